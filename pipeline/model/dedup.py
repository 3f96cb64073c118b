"""Removal of repeated measurements (same kind of sensor, time, position, speed and heading)."""

from __future__ import annotations

import numpy as np
import pandas as pd

DEDUP_KEYS = ["time", "latitude", "longitude", "ground_speed_kt", "heading_deg"]
DEDUP_BLOCK_ROWS = 500_000  # rows hashed at once by duplicate_mask (whole time values per block)


def sort_by_time(meas: pd.DataFrame) -> pd.DataFrame:
    """Measurements in stable time order, index reset."""
    return meas.sort_values("time", kind="stable").reset_index(drop=True)


def duplicate_mask(meas: pd.DataFrame, *, split_adsb: bool = False) -> pd.Series:
    """True for rows equal to an earlier row in time, position, speed and heading (NaN equals NaN).

    The source is part of the key: each radar (``sensor_id``) on its own, ADS-B as one source whatever
    the ground station (so a report relayed by two stations counts once) unless ``split_adsb``. A
    ``duplicate`` column, when present, was computed once for the job (pipeline.model.marks.mark_once) and is
    returned as it is.
    """
    if "duplicate" in meas:
        return meas["duplicate"].astype(bool)
    keys = [k for k in DEDUP_KEYS if k in meas]
    if "sensor_kind" in meas:  # the source as an integer: its kind, or its sensor id (-1: missing)
        kind, kinds = pd.factorize(meas["sensor_kind"])
        source = kind
        if "sensor_id" in meas:  # radars are told apart; ADS-B ground stations are one source
            apart = (meas["sensor_kind"] != "adsb").to_numpy(bool) | split_adsb
            sid = pd.factorize(meas["sensor_id"])[0]
            source = np.where(apart, np.where(sid >= 0, sid + len(kinds), -1), kind)
        meas = meas[keys].assign(_source=source)
        keys = ["_source", *keys]
    if "time" not in keys or len(meas) <= DEDUP_BLOCK_ROWS:
        return pd.Series(_duplicated(meas, keys), index=meas.index)
    # rows at different times are never repeats: look for them among blocks of whole time values, so
    # the hashing works on one block at a time (bounded memory), each block in frame order
    t = pd.DatetimeIndex(meas["time"]).asi8
    by_time = np.argsort(t, kind="stable")
    t_sorted = t[by_time]
    cuts = [0]
    while cuts[-1] + DEDUP_BLOCK_ROWS < len(t):
        cuts.append(int(np.searchsorted(t_sorted, t_sorted[cuts[-1] + DEDUP_BLOCK_ROWS], side="right")))
    cuts.append(len(t))
    dup = np.zeros(len(meas), bool)
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        if b > a:
            rows = np.sort(by_time[a:b])
            dup[rows] = _duplicated(meas.iloc[rows], keys)
    return pd.Series(dup, index=meas.index)


def _duplicated(meas: pd.DataFrame, keys: list[str]) -> np.ndarray:
    """pandas' duplicated (first kept) over ``keys``, hashing only the rows that share their time and
    latitude with another row: a repeat shares every key, and most rows share neither."""
    rows = shared_rows(meas)
    dup = np.zeros(len(meas), bool)
    if rows is None:
        return meas.duplicated(subset=keys, keep="first").to_numpy(bool)
    if rows.size:
        dup[rows] = meas.iloc[rows].duplicated(subset=keys, keep="first").to_numpy(bool)
    return dup


def shared_rows(meas: pd.DataFrame, rows: np.ndarray | None = None) -> np.ndarray | None:
    """Positions (ascending; among ``rows`` when given, counted in the frame) of the rows whose time and
    latitude both equal those of another of these rows (NaN equals NaN, NaT equals NaT, -0.0 equals 0.0):
    the only rows that can repeat or be repeated. None when the frame lacks either column."""
    if "time" not in meas or "latitude" not in meas:
        return None
    try:
        t, lat = (_bits(_key_array(meas[c]) if rows is None else _key_array(meas[c])[rows])
                  for c in ("time", "latitude"))
    except (TypeError, ValueError):  # not numbers or times: every row is hashed
        return None
    key = pd.Series(t * np.int64(-7046029254386353131) ^ lat)  # rows equal in both: equal key
    shared = np.flatnonzero(key.duplicated(keep=False).to_numpy(bool))
    return shared if rows is None else rows[shared]


def deduplicate(meas: pd.DataFrame) -> tuple[pd.DataFrame, int]:
    """Time-sorted measurements without repeats, and how many repeats were dropped."""
    ordered = sort_by_time(meas)
    dup = duplicate_mask(ordered)
    return ordered[~dup].reset_index(drop=True), int(dup.sum())


def _key_array(column: pd.Series) -> np.ndarray:
    """A column as numbers that compare like the dedup key: datetimes as int64 ns (NaT one value),
    everything else as float with NaN for missing (NaN is made equal to NaN by the caller)."""
    if isinstance(column.dtype, pd.DatetimeTZDtype) or column.dtype.kind == "M":
        return pd.DatetimeIndex(column).asi8
    return column.to_numpy(dtype=float, na_value=np.nan)


def _bits(values: np.ndarray) -> np.ndarray:
    """int64 numbers equal exactly when the values are equal as keys: floats by their bits, with one NaN
    and -0.0 made 0.0; datetimes (int64 ns) as they are."""
    if values.dtype.kind == "f":
        values = np.where(np.isnan(values), np.nan, values.astype(float) + 0.0).view(np.int64)
    return values.astype(np.int64, copy=False)


def repeat_groups(meas: pd.DataFrame, keys: list[str], rows: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Rows in key order and the group number of each of them: rows equal in every key column (NaN equals
    NaN, -0.0 equals 0.0) share a group; within a group rows keep their frame order (stable sort).
    Numeric and datetime key columns only (what ``DEDUP_KEYS`` holds). ``rows``: only these positions
    (the result then counts positions within ``rows``), without copying the frame first."""
    arrays = [_key_array(meas[k]) if rows is None else _key_array(meas[k])[rows] for k in keys]
    order = np.lexsort(arrays[::-1]) if arrays else np.arange(len(meas) if rows is None else len(rows))
    new = np.zeros(order.size, dtype=bool)
    if order.size:
        new[0] = True
    for a in arrays:
        s = a[order]
        same = s[1:] == s[:-1]
        if s.dtype.kind == "f":
            same |= np.isnan(s[1:]) & np.isnan(s[:-1])
        new[1:] |= ~same
    return order, np.cumsum(new) - 1


def repeated_aircraft(meas: pd.DataFrame, dup: np.ndarray, limit: int = 5) -> list[str]:
    """A warning naming the aircraft every one of whose reports repeats another's (same source kind, time,
    position, speed and heading) and so is left out whole: the repeats are of another aircraft (an address
    damaged in a relayed copy), since an aircraft's own first report is never a repeat. [] if none."""
    if not len(meas) or "aircraft_id" not in meas:
        return []
    ids = meas["aircraft_id"]  # counted on its codes (a job's millions of rows: no object copy, no grouping)
    if isinstance(ids.dtype, pd.CategoricalDtype):
        codes, names = ids.cat.codes.to_numpy(), ids.cat.categories
    else:
        codes, names = pd.factorize(ids, sort=True)
    known = codes >= 0
    size = np.bincount(codes[known], minlength=len(names))
    repeats = np.bincount(codes[known], weights=np.asarray(dup, bool)[known], minlength=len(names))
    whole = [(str(names[i]), int(size[i])) for i in np.flatnonzero((size > 0) & (repeats == size))]
    if not whole:
        return []
    whole.sort()
    named = ", ".join(f"{a} ({n} report{'s' if n > 1 else ''})" for a, n in whole[:limit])
    more = f" and {len(whole) - limit} more" if len(whole) > limit else ""
    return [f"{len(whole)} aircraft left out whole: every report of {named}{more} repeats another aircraft's "
            "(same time, position, speed and heading): a damaged identity in a copied report, most likely"]
