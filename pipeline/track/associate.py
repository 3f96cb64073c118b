"""Radar plots without an identity joined to an aircraft by their radar track number.

A plot whose ``aircraft_id`` is missing, or only a Mode 3/A label ("M3A:...", a code not uniquely seen
with an address), takes the identity of the nearest-in-time plot of the same radar and track number that
has one, when that plot is at most ``max_gap_s`` away (radars reuse track numbers). The tracker's gate
then accepts or rejects the joined plot like any other report: a wrong join is gated, not fused.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.identity import MODE_A_PREFIX


def join_by_track_number(meas: pd.DataFrame, max_gap_s: float = 60.0) -> tuple[pd.DataFrame, int]:
    """The measurements with radar plots joined by (sensor_id, track_number); and how many were joined."""
    ident = meas["aircraft_id"].astype("string")
    weak = (ident.isna() | ident.str.startswith(MODE_A_PREFIX).fillna(False)).to_numpy(bool)
    radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
    has_tn = (meas["track_number"].notna().to_numpy(bool) if "track_number" in meas
              else np.zeros(len(meas), bool))
    candidates = radar & has_tn
    if not (candidates & weak).any():
        return meas, 0
    t = (meas["time"] - meas["time"].min()).dt.total_seconds().to_numpy(float)
    out = ident.to_numpy(dtype=object).copy()
    joined = 0
    pos = np.flatnonzero(candidates)
    sub = meas.iloc[pos]
    codes, _ = pd.factorize(sub["sensor_id"].astype(str) + "|" + sub["track_number"].astype(str))
    order = np.argsort(codes, kind="stable")
    bounds = np.flatnonzero(np.diff(codes[order])) + 1
    for group in np.split(order, bounds):
        idx = pos[group]
        strong = idx[~weak[idx]]
        todo = idx[weak[idx]]
        if not len(strong) or not len(todo):
            continue
        strong = strong[np.argsort(t[strong], kind="stable")]
        ts = t[strong]
        k = np.clip(np.searchsorted(ts, t[todo]), 0, len(ts) - 1)
        k_prev = np.clip(k - 1, 0, len(ts) - 1)
        nearest = np.where(np.abs(ts[k_prev] - t[todo]) <= np.abs(ts[k] - t[todo]), k_prev, k)
        ok = np.abs(ts[nearest] - t[todo]) <= max_gap_s
        out[todo[ok]] = ident.to_numpy(dtype=object)[strong[nearest[ok]]]
        joined += int(ok.sum())
    if not joined:
        return meas, 0
    return meas.assign(aircraft_id=pd.array(out, dtype="string")), joined
