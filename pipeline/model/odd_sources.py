"""Records naming another data source than the rest of their data block: left out of the measurements.

A real recording's data block holds one sensor's records; damage inside a block that still walks to its
end makes records out of the bytes after it, naming made-up sensors (asterix.plausible.odd_sources).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.asterix.plausible import odd_sources

COLUMNS = ["category", "file", "offset", "sac", "sic"]


def odd_source_mask(frame: pd.DataFrame) -> np.ndarray:
    """True for each record of a decoded frame naming another data source than most of its block, and for
    the records after it in its block (the walk past damage is misaligned until the block ends); none for
    a frame without the ``block`` column, such as a dataset's."""
    if not len(frame) or not {"sac", "sic", "block"} <= set(frame.columns):
        return np.zeros(len(frame), bool)
    block = frame["block"].to_numpy()
    odd = odd_sources(frame["sac"].array, frame["sic"].array, block)
    if odd.any():
        rank = np.arange(len(frame))
        first = pd.Series(np.where(odd, rank, len(frame))).groupby(block).transform("min").to_numpy()
        odd = rank >= first
    return odd


def drop_odd_sources(frames: dict[int, pd.DataFrame], name: str, left_out: list[pd.DataFrame]) -> None:
    """Leave the records of ``odd_source_mask`` out of ``frames`` (in place), their rows (COLUMNS) added to
    ``left_out``."""
    for cat, frame in frames.items():
        odd = odd_source_mask(frame)
        if odd.any():
            rows = frame.loc[odd, [c for c in COLUMNS[2:] if c in frame]].assign(category=int(cat), file=name)
            left_out.append(rows.reindex(columns=COLUMNS))
            frames[cat] = frame[~odd]


def odd_source_texts(rows: pd.DataFrame | None) -> list[str]:
    """One warning per input file with records left out by ``drop_odd_sources``: how many, of which
    categories, and the first one's offset and data source."""
    if rows is None or not len(rows):
        return []
    out = []
    for name, group in rows.groupby(rows["file"].astype(str).to_numpy(), sort=False):
        first = group.iloc[0]
        cats = ", ".join(f"CAT{int(c):03d}" for c in sorted(set(group["category"])))
        source = "no data source" if pd.isna(first["sac"]) else f"SAC/SIC {first['sac']}/{first['sic']}"
        out.append(f"{name}: {len(group)} {cats} record(s) name another data source than most records of "
                   "their data block, or none, or follow such a record in it (first at offset "
                   f"{int(first['offset'])}: {source}): damaged data, left out of the measurements")
    return out
