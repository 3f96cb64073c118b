"""Data sources: a sensor's SAC/SIC pair as one integer code, its id as the measurements show it (and the
kind it implies), and an input file's label."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd

# the sensor kind of the measured categories' reports (CAT010's is in its sensor id: "010:0/7:smr"), as the
# measurement rows give it (msdc.pipeline.model.schema.SENSOR_KINDS)
MEASURED_KINDS = {"048": "radar", "021": "adsb", "020": "mlat"}


def file_labels(paths) -> list[str]:
    """Each input's label in the ``file`` column and in messages: its name, or its path as given where two
    inputs share a name (so that ``file`` and ``offset`` always identify a record), as text every output
    can hold (path_text)."""
    names = [Path(p).name for p in paths]
    shared = {n for n, k in Counter(names).items() if k > 1}
    return [path_text(p if n in shared else n) for p, n in zip(paths, names, strict=True)]


def path_text(path) -> str:
    """A path as valid UTF-8 text: bytes of a name that are not UTF-8 (Python holds them as lone
    surrogates, which no CSV, Parquet or JSON writer takes) shown as \\xNN escapes."""
    return escaped(str(path))


_SURROGATE = re.compile("[\ud800-\udfff]")


def escaped(text: str, backslash: str = "\\") -> str:
    """``text`` with each lone surrogate as an escape: ``backslash`` then xNN for a byte that was not UTF-8
    (surrogateescape's U+DC80-U+DCFF), else uNNNN; ``backslash`` is two characters inside JSON text."""
    if text.isascii() or not _SURROGATE.search(text):  # isascii: a flag, no scan
        return text
    return _SURROGATE.sub(lambda m: backslash + (f"x{ord(m[0]) - 0xDC00:02x}" if 0xDC80 <= ord(m[0]) <= 0xDCFF
                                                 else f"u{ord(m[0]):04x}"), text)


def pair_codes(sac, sic) -> np.ndarray:
    """One integer per SAC/SIC pair (each one byte; a missing one counts as -1): pair_of turns it back."""
    sac, sic = (pd.Series(v).astype("Int64").fillna(-1).to_numpy(np.int64) for v in (sac, sic))
    return (sac + 1) * 65536 + sic + 1


def pair_of(code: int) -> tuple[int | None, int | None]:
    """The SAC and SIC of a pair_codes code (None where missing)."""
    sac, sic = (v - 1 for v in divmod(int(code), 65536))
    return (sac if sac >= 0 else None), (sic if sic >= 0 else None)


def source_id(category: int, sac, sic) -> str:
    """"CCC:SAC/SIC" (e.g. "048:25/201"), "?" for a missing SAC or SIC: the measurements' sensor_id."""
    sac, sic = ("?" if v is None or pd.isna(v) else v for v in (sac, sic))
    return f"{category:03d}:{sac}/{sic}"


def kind_of_id(sensor_id: str) -> str | None:
    """The measurements' sensor kind a sensor id implies ("048:..." radar, "021:..." adsb, "020:..." mlat,
    "010:SAC/SIC:smr" smr): a sensor gone silent keeps its kind with no report left to say it."""
    category, _, rest = sensor_id.partition(":")
    if category == "010":
        kind = rest.partition(":")[2]
        return kind if kind in ("mlat", "smr") else None
    return MEASURED_KINDS.get(category)
