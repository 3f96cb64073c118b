"""Two targets under one identity: a sensor's reports of one aircraft that jump back and forth between places.

A transponder readdressed to another aircraft's address, two surface radar tracks of different vehicles
joined to one aircraft, two aircraft squawking one Mode 3/A code: one ``aircraft_id`` then holds two
targets, and every figure of it (accuracy, intervals, detection) mixes them. Per aircraft and sensor, in
time order, a report *switches* when it lies far from the report before it (over MIN_SEPARATION_M and
over SIGMAS_APART of their combined sigmas) but within a quarter of that distance of one of the two reports
before that: it went back to where the sequence was. One target does not: moving, its earlier reports lie
farther away than the last; with noise alone, the last is no farther than the rest. A parked target's
isolated position jump makes one switch (its return), a moving one's none; two interleaved targets make
one in every one to four reports.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import east_north_m

# Two places this far apart are not one aircraft's extent (the largest are ~80 m long: a surface radar's
# split echoes of one aircraft lie within that) nor a surface radar's or multilateration's noise
MIN_SEPARATION_M = 150.0
SIGMAS_APART = 6.0  # ...and this many of the two reports' combined major-axis sigmas
BACK_RATIO = 4.0  # a switch returns within 1/4 of the jump of one of the two reports before the last
WINDOW_S = 60.0  # the three reports compared lie within this span: after a gap the aircraft has moved
MIN_SWITCHES = 10  # fewer: isolated jumps, not two targets
MIN_SHARE = 0.1  # switches among the reports judged: interleaved targets give ~0.3-0.5, jumps ~0.01
# What it reads; sigma_major_m too where the frame has it (track, evaluate): correlate and quality do not
# build it (a row's bytes), and without it the real Barcelona hour's worst radar aircraft had 8 switches,
# 3.8 % of its plots (at most 3 with it)
MIXED_INPUTS = ["time", "aircraft_id", "sensor_id", "latitude", "longitude"]
MIXED_COLUMNS = ["aircraft_id", "sensor_id", "reports", "judged", "switches", "share", "separation_m"]


def mixed_identities(meas: pd.DataFrame) -> pd.DataFrame:
    """Per aircraft and sensor whose reports switch between two places (see the module docstring):
    aircraft_id, sensor_id, reports, judged (reports with two earlier ones within WINDOW_S), switches,
    share = switches / judged, separation_m (the median distance of a switch). Needs time, aircraft_id,
    sensor_id, latitude, longitude and sigma_major_m (0 where absent); unidentified rows are not judged."""
    if meas.empty or not {"aircraft_id", "sensor_id", "time", "latitude", "longitude"} <= set(meas.columns):
        return pd.DataFrame(columns=MIXED_COLUMNS)
    known = meas["aircraft_id"].notna().to_numpy(bool) & np.isfinite(meas["latitude"].to_numpy(float))
    m = meas.loc[known]
    aircraft, sensor = pd.factorize(m["aircraft_id"])[0], pd.factorize(m["sensor_id"])[0]
    ident = aircraft.astype(np.int64) * (int(sensor.max(initial=0)) + 1) + sensor
    t = (m["time"] - m["time"].min()).dt.total_seconds().to_numpy(float)
    order = np.lexsort((t, ident))
    ident, t = ident[order], t[order]
    lat, lon = m["latitude"].to_numpy(float)[order], m["longitude"].to_numpy(float)[order]
    sigma = (m["sigma_major_m"].to_numpy(float)[order] if "sigma_major_m" in m else np.zeros(len(m)))
    sigma = np.nan_to_num(sigma)
    n = len(t)
    switch = np.zeros(n, bool)
    judged = np.zeros(n, bool)
    jump = np.full(n, np.nan)
    if n >= 3:
        i = np.arange(2, n)
        same = (ident[i - 1] == ident[i]) & (ident[i - 2] == ident[i]) & (t[i] - t[i - 2] <= WINDOW_S)
        back3 = np.zeros(len(i), bool)
        ok3 = i >= 3
        back3[ok3] = (ident[i[ok3] - 3] == ident[i[ok3]]) & (t[i[ok3]] - t[i[ok3] - 3] <= WINDOW_S)

        def dist(a, b):
            return short_distance_m(lat[a], lon[a], lat[b], lon[b])

        d_last = dist(i, i - 1)
        d_back = dist(i, i - 2)
        d3 = np.full(len(i), np.inf)
        d3[back3] = dist(i[back3], i[back3] - 3)
        d_back = np.minimum(d_back, d3)
        apart = np.maximum(MIN_SEPARATION_M, SIGMAS_APART * np.hypot(sigma[i], sigma[i - 1]))
        judged[i] = same
        switch[i] = same & (d_last > apart) & (d_back * BACK_RATIO < d_last)
        jump[i] = np.where(switch[i], d_last, np.nan)
    frame = pd.DataFrame({"g": ident, "judged": judged, "switch": switch, "jump": jump})
    per = frame.groupby("g").agg(reports=("judged", "size"), judged=("judged", "sum"),
                                 switches=("switch", "sum"), separation_m=("jump", "median"))
    per["share"] = per["switches"] / per["judged"].where(per["judged"] > 0)
    hit = per[(per["switches"] >= MIN_SWITCHES) & (per["share"] >= MIN_SHARE)]
    if hit.empty:
        return pd.DataFrame(columns=MIXED_COLUMNS)
    first = pd.Series(np.arange(n)).groupby(ident).first()  # a row of each group, for its names
    rows = order[first.loc[hit.index].to_numpy()]
    out = hit.reset_index(drop=True).assign(aircraft_id=m["aircraft_id"].astype(str).to_numpy()[rows],
                                            sensor_id=m["sensor_id"].astype(str).to_numpy()[rows])
    return out[MIXED_COLUMNS].sort_values(["aircraft_id", "sensor_id"]).reset_index(drop=True)


def short_distance_m(lat1_deg, lon1_deg, lat2_deg, lon2_deg) -> np.ndarray:
    """Distance (m) between nearby points on the WGS-84 ellipsoid, flat about their mean latitude
    (geodesy.east_north_m): within 1e-6 of the geodesic up to 5 km, about thirty times faster than it (the
    comparisons here are of reports seconds apart)."""
    return np.hypot(*east_north_m(lat1_deg, lon1_deg, lat2_deg, lon2_deg))


def mixed_warnings(meas: pd.DataFrame, limit: int = 5) -> list[str]:
    """One warning naming the aircraft and sensors whose reports switch between two places (at most
    ``limit`` named): their figures mix two targets."""
    return mixed_text(mixed_identities(meas), limit)


def mixed_pairs(found: pd.DataFrame) -> tuple[tuple[str, str], ...]:
    """The (aircraft_id, sensor_id) of a mixed_identities table, as text: what a frame's attrs can carry
    (a table there would break pandas' attrs comparison in concat)."""
    return tuple(zip(found["aircraft_id"].astype(str), found["sensor_id"].astype(str), strict=True))


def mixed_text(found: pd.DataFrame, limit: int = 5) -> list[str]:
    """mixed_warnings of a mixed_identities table already made."""
    if found.empty:
        return []
    named = "; ".join(f"{r.aircraft_id} on {r.sensor_id} ({r.switches:,} of {r.judged:,} reports, "
                      f"{r.separation_m:,.0f} m apart)" for r in found.head(limit).itertuples())
    more = f" and {len(found) - limit} more" if len(found) > limit else ""
    return [f"{len(found)} aircraft's reports switch back and forth between two places: {named}{more}. Two "
            "targets may share the identity (a readdressed transponder, two tracks joined, a shared code): "
            "their figures mix both"]
