"""Surface radar tracks joined to aircraft by position.

A primary surface radar's reports carry no address, call sign or Mode 3/A code, so the identity rule
(pipeline.model.identity) leaves them without an aircraft, and nothing could be correlated against them per
aircraft. Rule, applied after identity: the reports of one surface radar track (its sensor and track number,
split where the track is silent for more than TRACK_GAP_S) each vote for the aircraft whose identified report
of another sensor (multilateration, ADS-B, radar) lies nearest, within MATCH_WINDOW_S and MATCH_DISTANCE_M;
the track joins the aircraft with the most votes when it has at least MIN_VOTES of them, more than half
of the track's votes, and the aircraft's own reports do not deny it: where that aircraft has identified
reports bracketing a track report within MATCH_WINDOW_S either side, the report agrees when within
MATCH_DISTANCE_M of the aircraft's position interpolated between them and disagrees when beyond
CONTRARY_DISTANCE_M, and a track with disagreeing reports joins only when more of its reports agree (a
vehicle's track that passes an aircraft for a few reports, then drives on 500 m from it, gets that
aircraft's votes and nobody else's). Tracks of vehicles without a transponder, and those near no identified
report, stay unidentified. The gate limits which reports vote, not which reports join: every report of a
joined track joins, so its far reports still count in any comparison made afterwards.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.schema import text_categorical

PRIMARY_KINDS = ("smr",)  # sensor kinds whose reports carry no identity of their own
TRACK_GAP_S = 30.0  # a track number silent this long starts another track (numbers are reused)
MATCH_WINDOW_S = 1.0  # a vote's report and the aircraft's report at most this far apart in time
MATCH_DISTANCE_M = 50.0  # and in position (aircraft on the apron stand about 40-80 m apart)
MIN_VOTES = 3
CONTRARY_DISTANCE_M = 100.0  # a report this far from its aircraft's interpolated position disagrees (twice
# the gate: two sensors' time stamps a few tenths of a second apart on a fast aircraft, or a long one's echo
# centroid, put agreeing reports a few tens of metres off)
INPUTS = ("time", "latitude", "longitude", "sensor_kind", "sensor_id", "track_number", "aircraft_id")
_EARTH_M = 6371008.8


def _plane(lat: np.ndarray, lon: np.ndarray, lat0: float, lon0: float) -> np.ndarray:
    """East/north metres from (lat0, lon0) on a local equirectangular plane (airport scale: a few km,
    where it is within centimetres of the tangent plane)."""
    x = np.radians(lon - lon0) * np.cos(np.radians(lat0)) * _EARTH_M
    y = np.radians(lat - lat0) * _EARTH_M
    return np.stack([x, y], axis=1)


def _segments(meas: pd.DataFrame, rows: np.ndarray) -> np.ndarray:
    """Per primary report (``rows``), the number of its track segment: sensor and track number, split at
    silences over TRACK_GAP_S; a report without a track number is a segment of its own."""
    t = meas["time"].to_numpy("datetime64[ns]")[rows].astype("int64") / 1e9
    sensor = meas["sensor_id"].cat.codes.to_numpy()[rows].astype(np.int64)
    number = meas["track_number"].astype("Int64").fillna(-1).to_numpy(np.int64)[rows]
    order = np.lexsort((t, number, sensor))
    s, n, tt = sensor[order], number[order], t[order]
    new = np.ones(len(rows), bool)
    new[1:] = (s[1:] != s[:-1]) | (n[1:] != n[:-1]) | (np.diff(tt) > TRACK_GAP_S) | (n[1:] < 0)
    out = np.empty(len(rows), np.int64)
    out[order] = np.cumsum(new) - 1
    return out


def _distance_to_candidate(t_k: np.ndarray, xy_k: np.ndarray, code_k: np.ndarray, t_p: np.ndarray,
                           xy_p: np.ndarray, candidate: np.ndarray) -> np.ndarray:
    """Per primary report (time ``t_p``, plane position ``xy_p``), the distance (m) from its ``candidate``
    aircraft's position interpolated between the identified reports of that aircraft (``code_k``) before and
    after it, each within MATCH_WINDOW_S; NaN where it has no candidate or no such bracketing reports."""
    span = float(max(t_k.max(), t_p.max()) - min(t_k.min(), t_p.min())) + 10.0
    origin = float(min(t_k.min(), t_p.min()))
    key = code_k * span + (t_k - origin)  # sorted by aircraft, then time
    order = np.argsort(key, kind="stable")
    key, tk, xyk, ck = key[order], t_k[order], xy_k[order], code_k[order]
    after = np.searchsorted(key, np.maximum(candidate, 0) * span + (t_p - origin))
    nxt, prv = np.clip(after, 0, len(key) - 1), np.clip(after - 1, 0, len(key) - 1)
    ok = ((candidate >= 0) & (after > 0) & (after < len(key)) & (ck[prv] == candidate)
          & (ck[nxt] == candidate) & (t_p - tk[prv] <= MATCH_WINDOW_S) & (tk[nxt] - t_p <= MATCH_WINDOW_S))
    gap = tk[nxt] - tk[prv]
    w = np.where(gap > 0, (t_p - tk[prv]) / np.where(gap > 0, gap, 1.0), 0.0)
    at = xyk[prv] + w[:, None] * (xyk[nxt] - xyk[prv])
    return np.where(ok, np.hypot(*(xy_p - at).T), np.nan)


def join_primary_tracks(meas: pd.DataFrame) -> tuple[pd.Series, int]:
    """``meas``'s aircraft_id with the surface radar tracks joined to aircraft (see the module docstring),
    and how many reports were joined; unchanged when there is no unidentified primary report."""
    from scipy.spatial import cKDTree

    ident = meas["aircraft_id"]
    kind = meas["sensor_kind"].astype(str).to_numpy()
    primary = np.isin(kind, PRIMARY_KINDS) & ident.isna().to_numpy(bool)
    known = ~np.isin(kind, PRIMARY_KINDS) & ident.notna().to_numpy(bool)
    if not primary.any() or not known.any():
        return ident, 0
    p_rows, k_rows = np.flatnonzero(primary), np.flatnonzero(known)
    lat, lon = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    t = meas["time"].to_numpy("datetime64[ns]").astype("int64") / 1e9
    lat0, lon0 = float(np.median(lat[p_rows])), float(np.median(lon[p_rows]))
    t0 = float(t[p_rows].min())
    scale = MATCH_DISTANCE_M / MATCH_WINDOW_S  # a second of time counts as much as this many metres
    xy_k, xy_p = _plane(lat[k_rows], lon[k_rows], lat0, lon0), _plane(lat[p_rows], lon[p_rows], lat0, lon0)
    points = np.column_stack([xy_k, (t[k_rows] - t0) * scale])
    query = np.column_stack([xy_p, (t[p_rows] - t0) * scale])
    dist, at = cKDTree(points).query(query, k=4, distance_upper_bound=MATCH_DISTANCE_M * 2.0)
    found = at < len(k_rows)
    safe = np.where(found, at, 0)
    horiz = np.hypot(*(query[:, None, :2] - points[safe][..., :2]).transpose(2, 0, 1))
    near = found & (np.abs(query[:, None, 2] - points[safe][..., 2]) <= MATCH_DISTANCE_M) & (
        horiz <= MATCH_DISTANCE_M)
    horiz = np.where(near, horiz, np.inf)
    best = np.argmin(horiz, axis=1)
    voted = near[np.arange(len(p_rows)), best]
    codes = ident.cat.codes.to_numpy()
    vote = np.where(voted, codes[k_rows][safe[np.arange(len(p_rows)), best]], -1)
    segment = _segments(meas, p_rows)
    table = pd.DataFrame({"segment": segment, "vote": vote})
    votes = table[table["vote"] >= 0].groupby(["segment", "vote"]).size().rename("n").reset_index()
    cast = votes.groupby("segment")["n"].transform("sum")
    top = votes.sort_values(["segment", "n"], ascending=[True, False]).drop_duplicates("segment")
    top = top[(top["n"] >= MIN_VOTES) & (top["n"] * 2 > cast.loc[top.index])]
    candidate = pd.Series(segment).map(pd.Series(top["vote"].to_numpy(), index=top["segment"].to_numpy()))
    away = _distance_to_candidate(t[k_rows], xy_k, codes[k_rows].astype(np.int64), t[p_rows], xy_p,
                                  candidate.fillna(-1).to_numpy(np.int64))
    evidence = pd.DataFrame({"agree": away <= MATCH_DISTANCE_M, "against": away > CONTRARY_DISTANCE_M})
    said = evidence.groupby(segment).sum()
    denied = said.index[(said["against"] > 0) & (said["against"] >= said["agree"])]
    top = top[~top["segment"].isin(denied)]
    joined = pd.Series(top["vote"].to_numpy(), index=top["segment"].to_numpy())
    new_codes = pd.Series(segment).map(joined).fillna(-1).to_numpy(np.int64)
    out = codes.copy()
    out[p_rows] = np.where(new_codes >= 0, new_codes, codes[p_rows])
    result = pd.Series(pd.Categorical.from_codes(out, categories=ident.cat.categories), index=ident.index,
                       name=ident.name)
    return text_categorical(result), int((new_codes >= 0).sum())
