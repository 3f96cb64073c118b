"""A raw recording's data blocks as ``msdc decode`` frames them (asterix.plan: the chain as it is, framed
carefully where it breaks), each block's time of day, and the bytes framing skipped with decode's reasons."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import PurePath

import numpy as np

from msdc.asterix.containers import Segments


@dataclass
class RawBlocks:
    """The blocks (offsets, in file order), each one's first time of day (NaN: none), the skipped bytes
    (offset, length, reason), and 'NAME is not ASTERIX...' when next to nothing of the file is."""

    start: np.ndarray
    stop: np.ndarray
    time_s: np.ndarray
    skipped: list[tuple[int, int, str]]
    not_asterix: str | None = None


def raw_blocks(path: str, buf: np.ndarray, seg: Segments) -> RawBlocks:
    """Frame and decode (time of day only) a raw recording held in ``buf`` (``seg``: read_segments'), as
    asterix.read does; ``path``: its name as the messages give it."""
    from msdc.asterix.categories import DECODABLE
    from msdc.asterix.containers import readonly
    from msdc.asterix.plan import plan_recording
    from msdc.asterix.reader import decode_framed, framing_reason, selected_columns
    from msdc.asterix.verdict import Tally, not_asterix_text

    buf = readonly(buf)
    plan = plan_recording(buf, seg, {}, DECODABLE)
    framed = plan.framer(buf).window()
    rec = decode_framed(buf, plan, framed, path=path, selected=selected_columns(["time_of_day"]))
    b_start, b_len = framed[0].astype(np.int64), framed[1].astype(np.int64)
    skipped = [(int(o), int(n), framing_reason(buf, seg, int(o), int(code)))
               for o, n, code in zip(framed[4].tolist(), framed[5].tolist(), framed[7].tolist(), strict=True)]
    account = Tally(path)
    account.add(rec)
    said = not_asterix_text(PurePath(path).name, account, bytes(buf[:256])) if account.not_asterix() else None
    return RawBlocks(b_start, b_start + b_len, _first_times(rec.frames, b_start), skipped, said)


def _first_times(frames: dict, b_start: np.ndarray) -> np.ndarray:
    """Per block, the time of day of its first record that has one (NaN when none); a record is placed in
    its block by its offset (a block is of one category: its records are in one frame)."""
    out = np.full(len(b_start), np.nan)
    for frame in frames.values():
        if not len(frame) or "time_of_day" not in frame:
            continue
        t = frame["time_of_day"].to_numpy(np.float64)
        off = frame["offset"].to_numpy(np.int64)
        ok = np.isfinite(t)
        order = np.argsort(off[ok], kind="stable")
        b = np.searchsorted(b_start, off[ok][order], side="right") - 1
        blocks, first = np.unique(b, return_index=True)  # each block's first record
        out[blocks] = t[ok][order][first]
    return out
