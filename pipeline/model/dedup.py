"""Removal of repeated measurements (same time, position, speed and heading)."""

from __future__ import annotations

import pandas as pd

DEDUP_KEYS = ["time_of_day", "latitude", "longitude", "ground_speed_kt", "heading_deg"]


def sort_by_time(meas: pd.DataFrame) -> pd.DataFrame:
    """Measurements in stable time order, index reset."""
    return meas.sort_values("time_of_day", kind="stable").reset_index(drop=True)


def duplicate_mask(meas: pd.DataFrame) -> pd.Series:
    """True for rows equal to an earlier row in time, position, speed and heading (NaN equals NaN).

    The ``sensor`` column, when present, is part of the key so radar never duplicates ADS-B.
    """
    keys = [k for k in ["sensor", *DEDUP_KEYS] if k in meas]
    return meas.duplicated(subset=keys, keep="first")


def deduplicate(meas: pd.DataFrame) -> tuple[pd.DataFrame, int]:
    """Time-sorted measurements without repeats, and how many repeats were dropped."""
    ordered = sort_by_time(meas)
    dup = duplicate_mask(ordered)
    return ordered[~dup].reset_index(drop=True), int(dup.sum())
