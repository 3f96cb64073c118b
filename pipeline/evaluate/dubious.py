"""``dubious``: test reports that are physically implausible against the aircraft's report before them (the
limits of ../shared/standards.md: 1333 kt, 29 m/s^2, 30 deg/s, 1000 ft/s; each a parameter)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import associated, parameter
from msdc.pipeline.model.geodesy import A_M, M_PER_S_PER_KT

LIMITS = {"max_speed_kt": 1333.0, "max_accel_mps2": 29.0, "max_turn_dps": 30.0, "max_vertical_ftps": 1000.0}
# reports of one aircraft closer in time than this are not compared (split plots of one scan, repeats)
MIN_INTERVAL_S = 1.0


def _distance_m(lat1, lon1, lat2, lon2) -> np.ndarray:
    """Great-circle distance on a sphere of the WGS-84 semi-major axis (enough against a 1333 kt limit)."""
    p1, p2 = np.radians(lat1), np.radians(lat2)
    dlat, dlon = p2 - p1, np.radians(lon2 - lon1)
    h = np.sin(dlat / 2) ** 2 + np.cos(p1) * np.cos(p2) * np.sin(dlon / 2) ** 2
    return 2 * A_M * np.arcsin(np.sqrt(np.clip(h, 0.0, 1.0)))


def dubious_flags(reports: pd.DataFrame, parameters: Mapping | None = None) -> pd.DataFrame:
    """Per report with a report of the same aircraft (``ref_aircraft``) at least MIN_INTERVAL_S before it:
    which limit it breaks against that report. Speed from the two positions; vertical rate from the two
    flight levels; acceleration and turn rate from the reported ground speed and heading (the radar's own
    smoothed velocity: differencing positions would flag plain measurement noise at 29 m/s^2)."""
    limits = {k: float(parameter(parameters, k, v)) for k, v in LIMITS.items()}
    rep = reports.sort_values(["ref_aircraft", "t_s"], kind="stable")
    same = rep["ref_aircraft"].to_numpy(object)
    t = rep["t_s"].to_numpy(float)
    compared = np.zeros(len(rep), bool)
    prev = np.full(len(rep), -1)
    last_by: dict[object, int] = {}
    for i, (ac, ti) in enumerate(zip(same, t, strict=True)):
        j = last_by.get(ac)
        if j is not None and ti - t[j] >= MIN_INTERVAL_S:
            prev[i], compared[i] = j, True
        if j is None or ti - t[j] >= MIN_INTERVAL_S:
            last_by[ac] = i
    i = np.flatnonzero(compared)
    j = prev[i]
    dt = t[i] - t[j]

    def col(name: str) -> np.ndarray:
        return pd.to_numeric(rep[name], errors="coerce").to_numpy(float) if name in rep else np.full(len(rep),
                                                                                                     np.nan)

    lat, lon = col("latitude"), col("longitude")
    speed = _distance_m(lat[j], lon[j], lat[i], lon[i]) / dt
    fl = col("flight_level")
    vertical = np.abs(fl[i] - fl[j]) * 100.0 / dt
    gs = col("ground_speed_kt") * M_PER_S_PER_KT
    accel = np.abs(gs[i] - gs[j]) / dt
    hdg = col("heading_deg")
    turn = np.abs((hdg[i] - hdg[j] + 180.0) % 360.0 - 180.0) / dt
    with np.errstate(invalid="ignore"):
        out = pd.DataFrame({
            "index": rep.index.to_numpy()[i], "ref_aircraft": same[i], "t_s": t[i], "interval_s": dt,
            "speed_kt": speed / M_PER_S_PER_KT, "accel_mps2": accel, "turn_dps": turn,
            "vertical_ftps": vertical,
            "too_fast": speed > limits["max_speed_kt"] * M_PER_S_PER_KT,
            "too_sudden": accel > limits["max_accel_mps2"], "turns_too_fast": turn > limits["max_turn_dps"],
            "climbs_too_fast": vertical > limits["max_vertical_ftps"]})
    out["dubious"] = out[["too_fast", "too_sudden", "turns_too_fast", "climbs_too_fast"]].any(axis=1)
    return out


def dubious(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
            sensor=None) -> Outcome:
    """Share of the associated reports, each compared with its aircraft's report before it, that break a
    limit; the per-aircraft table gives each aircraft's compared and dubious reports."""
    rep = associated(reports, reference, parameters)
    rep = rep[rep["ref_index"].to_numpy() >= 0]
    if not len(rep):
        return withheld("dubious", "no report is associated with a reference aircraft")
    flags = dubious_flags(rep, parameters)
    if not len(flags):
        return withheld("dubious", f"no aircraft has two reports at least {MIN_INTERVAL_S:g} s apart")
    per = flags.groupby("ref_aircraft", sort=True).agg(compared=("dubious", "size"),
                                                       dubious=("dubious", "sum"))
    notes = tuple(f"{int(flags[c].sum())} {c.replace('_', ' ')}" for c in
                  ("too_fast", "too_sudden", "turns_too_fast", "climbs_too_fast") if flags[c].any())
    if not ({"ground_speed_kt", "heading_deg"} <= set(rep.columns)):
        notes += ("no reported ground speed and heading: acceleration and turn rate not judged",)
    return share("dubious", int(flags["dubious"].sum()), len(flags), notes, per.reset_index())
