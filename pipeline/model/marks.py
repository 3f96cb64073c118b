"""Flags computed once per job: the ``duplicate`` flag and the ADS-B jump columns, which deduplication,
the filters, quality and accuracy then reuse instead of recomputing (``mark_once``)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.dedup import DEDUP_KEYS, duplicate_mask, repeat_groups, shared_rows
from msdc.pipeline.model.heap import release_free_memory
from msdc.pipeline.model.jumps import JUMP_FLAG_COLUMNS, JUMP_INPUTS, jump_flags


def mark_once(meas: pd.DataFrame, *, split_adsb: bool = False, jumps: bool = True,
              flags: list[str] | None = None) -> pd.DataFrame:
    """The measurements with the ``duplicate`` flag and the ADS-B jump columns (``jump``, ``jump_size_m``,
    ``fit_latitude``, ``fit_longitude``) computed once for the whole job; deduplication, filters, quality
    and accuracy reuse them instead of recomputing. ``jumps=False`` skips the jump search (a job that
    neither filters jumps nor assesses quality does not need it); ``flags``: only these jump columns
    (``["jump"]`` for a job that counts or drops jumps but never reads the fit)."""
    meas = meas.drop(columns=[c for c in ("duplicate", *JUMP_FLAG_COLUMNS) if c in meas])
    judged_columns = JUMP_FLAG_COLUMNS if flags is None else [c for c in JUMP_FLAG_COLUMNS if c in flags]
    keys = [k for k in DEDUP_KEYS if k in meas]
    # rows equal in every key have the same time, so the first in time order is the first in frame order:
    # no sorted copy is needed. Only the columns each step reads are selected, never the whole frame.
    narrow = meas[[*keys, *(c for c in ("sensor_kind", "sensor_id") if c in meas and c not in keys)]]
    dup = duplicate_mask(narrow, split_adsb=split_adsb)
    del narrow
    if not jumps:
        return meas.assign(duplicate=dup.to_numpy(bool))
    dup = dup.to_numpy(bool)
    adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
    judged = jump_flags(meas[[c for c in JUMP_INPUTS if c in meas]][adsb & ~dup],  # judged without repeats
                        columns=judged_columns)
    release_free_memory()  # the search's batches leave freed heap pages behind
    # a repeated report shares the verdict of the report it repeats: per group of ADS-B rows equal in
    # every dedup key, each column takes its first non-missing value in frame order. Only rows sharing
    # their time and latitude with another ADS-B row can be in a group of several; the others keep their own
    rows = np.flatnonzero(adsb)
    shared = shared_rows(meas, rows)
    alone = np.zeros(0, np.int64) if shared is None else np.setdiff1d(rows, shared, assume_unique=True)
    rows = rows if shared is None else shared
    order, group = repeat_groups(meas, keys, rows)
    at = np.full(len(meas), -1)  # position of each judged row within the judged frame
    at[np.flatnonzero(adsb & ~dup)] = np.arange(len(judged))
    in_key_order = rows[order]
    pos_all = at[in_key_order]  # judged position of each ADS-B row, in key order
    alone_pos = at[alone]  # (never repeats: judged themselves)
    del at, rows
    out = {}
    for c in judged_columns:
        values = judged[c].to_numpy(dtype=bool if c == "jump" else float)
        pos = pos_all
        known = pos >= 0
        if values.dtype.kind == "f":
            known[known] = ~np.isnan(values[pos[known]])
        first = np.full(int(group[-1]) + 1 if group.size else 0, -1)
        first_rows = np.flatnonzero(known)
        g = group[first_rows]
        lead = np.concatenate([[True], g[1:] != g[:-1]]) if g.size else np.zeros(0, bool)
        first[g[lead]] = pos[first_rows[lead]]
        src = first[group]
        del first, first_rows, g, lead, known
        column = np.zeros(len(meas), bool) if c == "jump" else np.full(len(meas), np.nan)
        has = src >= 0
        column[in_key_order[has]] = values[src[has]]
        column[alone] = values[alone_pos]
        out[c] = column
        del src, has, values
    return meas.assign(duplicate=dup, **out)

