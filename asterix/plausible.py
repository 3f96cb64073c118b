"""Values no real report carries: a position off the Earth, a time of day outside 0-24 h.

Bytes that are not what they are read as (garbage framed as blocks, a wrong edition) decode into such
values far more often than real reports do; ``auto`` breaks ties with them, and the reader counts the
records that carry one.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# column -> (lowest, highest) plausible value; time of day: highest excluded (86400 s is the next day)
BOUNDS: dict[str, tuple[float, float]] = {
    "latitude": (-90.0, 90.0),
    "longitude": (-180.0, 180.0),
    "time_of_day": (0.0, 86400.0),
}
EXCLUSIVE_TOP = ("time_of_day",)
SHOWN_OFFSETS = 5  # offsets of implausible records a Recording keeps


class Implausible(NamedTuple):
    """Records of one category holding an implausible value: how many, and the first ones' offsets."""

    records: int
    offsets: tuple[int, ...]

    def __add__(self, other: Implausible) -> Implausible:  # type: ignore[override]
        return Implausible(self.records + other.records, (self.offsets + other.offsets)[:SHOWN_OFFSETS])


def implausible(columns: dict[str, np.ndarray]) -> np.ndarray:
    """True for each record one of whose bounded columns (``BOUNDS``, those present) holds a value outside
    its bounds; an absent value (NaN) is no evidence either way."""
    n = len(next(iter(columns.values()))) if columns else 0
    out = np.zeros(n, bool)
    for name, (lo, hi) in BOUNDS.items():
        values = columns.get(name)
        if values is None:
            continue
        values = np.asarray(values, np.float64)
        high = values >= hi if name in EXCLUSIVE_TOP else values > hi
        out |= (values < lo) | high  # NaN compares False: absent values pass
    return out


def count_implausible(columns: dict[str, np.ndarray], offsets: np.ndarray) -> Implausible:
    """The records of one category's decoded columns that hold an implausible value (``implausible``)."""
    bad = implausible({name: columns[name] for name in BOUNDS if name in columns})
    return Implausible(int(bad.sum()), tuple(int(o) for o in offsets[bad][:SHOWN_OFFSETS]))
