"""Detection requirements: probability of detection/update (``pd``) and long gaps (``long_gaps``), from the
updates the reference says the sensor should have made inside its coverage."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Protocol

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Coverage, Sensor, coverage
from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import (
    ASSOCIATION_COLUMNS,
    DEFAULT_REFERENCE_GAP_S,
    associated,
    association_gates,
    checked_trajectories,
    parameter,
    shared,
)
from msdc.pipeline.evaluate.scans import period_from_markers, period_from_plots
from msdc.pipeline.evaluate.statistics import proportion
from msdc.pipeline.evaluate.update_times import aircraft_updates

EXPECTED_COLUMNS = ["aircraft", "stretch", "t_s", "detected", "in_coverage", "rho_nm", "elevation_deg",
                    "azimuth_deg", "altitude_ft", "height_m", "t_ref_s"]

# with no minimum elevation declared, the expected updates inside coverage below the lowest elevation the
# sensor detected (all missed, perhaps below a radar's horizon) are said once they are this share or more
BELOW_DETECTIONS_SHARE = 0.01


class Within(Protocol):
    """A region the expected updates are counted in: its name, and per expected update (a table of
    EXPECTED_COLUMNS) whether it lies there."""

    name: str

    def __call__(self, table: pd.DataFrame) -> np.ndarray: ...


def update_period(reports: pd.DataFrame, sensor: Sensor) -> tuple[float, str]:
    """The sensor's scan period and where it came from: the one settled for the whole sensor when given
    (Sensor.scan_period), else its north markers, else the plots."""
    if sensor.scan_period is not None:
        return sensor.scan_period
    if sensor.north_markers_s is not None and len(sensor.north_markers_s) >= 2:
        period = period_from_markers(sensor.north_markers_s)
        if math.isfinite(period):
            return period, f"scan period {period:.4g} s from {len(sensor.north_markers_s)} north markers"
    mine = reports[reports["ref_index"] >= 0]
    period = period_from_plots(mine["t_s"].to_numpy(float), mine["ref_index"].to_numpy())
    return period, f"scan period {period:.4g} s estimated from the plots (no north markers)"


def update_interval(reports: pd.DataFrame, parameters: Mapping | None, sensor: Sensor | None
                    ) -> tuple[float, str]:
    """The interval that groups a sensor's reports into updates, and where it came from: ``interval_s``
    when given, else the scan period (update_period); NaN without either."""
    interval = parameter(parameters, "interval_s", None)
    if interval is not None:
        return float(interval), f"intervals of {float(interval):g} s"
    if sensor is None:
        return math.nan, "no sensor, so no scan period"
    return update_period(reports, sensor)


def expected_updates(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                     sensor: Sensor) -> tuple[pd.DataFrame, Coverage, tuple[str, ...]]:
    """Every update the sensor should have made of each reference aircraft, whether it did, and whether the
    aircraft was then inside coverage, where it then was (slant range, elevation, azimuth from the site; the
    reference's pressure altitude and height; ``t_ref_s``, the time that place was read at: the update's
    own, clipped into its stretch), with the coverage and notes on what was used. With ``interval_s`` the
    updates are whole intervals tiling each reference stretch; else one per scan period, the detected ones
    at their report times and the missed ones spread over the gaps."""
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    interval = parameter(parameters, "interval_s", None)
    # what the table depends on besides the frames: the association's gates only where it is made here
    gates = None if all(c in reports.columns for c in ASSOCIATION_COLUMNS) else association_gates(parameters)
    return shared(("expected_updates", id(reports), id(reference), id(sensor), max_gap_s, interval, gates),
                  (reports, reference, sensor),
                  lambda: _expected_updates(reports, reference, parameters, sensor, max_gap_s, interval))


def _expected_updates(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                      sensor: Sensor, max_gap_s: float, interval) -> tuple[pd.DataFrame, Coverage,
                                                                           tuple[str, ...]]:
    """`expected_updates`' work."""
    rep = associated(reports, reference, parameters)
    period, said = update_period(rep, sensor)
    if interval is not None:
        said = f"intervals of {float(interval):g} s"
    step = float(interval) if interval is not None else period
    if not math.isfinite(step) or step <= 0:
        raise ValueError(f"sensor {sensor.name!r}: no update interval ({said})")
    ref, trajs = checked_trajectories(reference)
    t_all, idx = rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy()
    names = ("aircraft", "stretch", "t_s", "detected", "lat", "lon", "height_m", "altitude_ft", "t_ref_s")
    cols: dict[str, list] = {c: [] for c in names}
    order = np.lexsort((t_all, idx))  # each reference aircraft's report times, sorted, one after the other
    t_sorted, idx_sorted = t_all[order], idx[order]
    bounds = np.searchsorted(idx_sorted, np.arange(len(trajs) + 1), "left")
    for k, tr in enumerate(trajs):  # the expected updates, stretch by stretch; where the sensor saw them
        mine = t_sorted[bounds[k]:bounds[k + 1]]
        stretch, t_exp, held, clipped = aircraft_updates(tr.t_s, mine, max_gap_s, step, interval is not None)
        lat, lon, h, alt = tr.at(clipped, max_gap_s)
        for c, v in (("aircraft", np.full(t_exp.size, tr.label, object)), ("stretch", stretch),
                     ("t_s", t_exp), ("detected", held), ("lat", lat), ("lon", lon), ("height_m", h),
                     ("altitude_ft", alt), ("t_ref_s", clipped)):
            cols[c].append(v)
    if cols["t_s"]:
        whole = {c: np.concatenate(v) for c, v in cols.items()}
        rho, az, el = sensor.polar_azimuth(whole.pop("lat"), whole.pop("lon"), whole["height_m"])
        table = pd.DataFrame({"aircraft": whole["aircraft"], "stretch": whole["stretch"], "t_s": whole["t_s"],
                              "detected": whole["detected"], "rho_nm": rho, "elevation_deg": el,
                              "azimuth_deg": az, "altitude_ft": whole["altitude_ft"],
                              "height_m": whole["height_m"], "t_ref_s": whole["t_ref_s"]})
    else:
        table = pd.DataFrame({c: [] for c in EXPECTED_COLUMNS if c != "in_coverage"})
    table = table.sort_values(["aircraft", "stretch", "t_s"], kind="stable", ignore_index=True)
    det = table["detected"].to_numpy(bool)
    cov = sensor.settled_coverage or coverage(sensor, table["rho_nm"].to_numpy(float)[det],
                                              table["elevation_deg"].to_numpy(float)[det])
    table["in_coverage"] = cov.inside(table["rho_nm"], table["elevation_deg"])
    below = _below_detections(table) if sensor.min_elevation_deg is None else None
    return table[EXPECTED_COLUMNS], cov, (said, cov.source, *([below] if below else []))


def _below_detections(table: pd.DataFrame) -> str | None:
    """A note when BELOW_DETECTIONS_SHARE or more of the expected updates inside coverage lie below the
    lowest elevation of the detected ones: a radar's horizon, undeclared, counts them all as missed."""
    inside = table["in_coverage"].to_numpy(bool)
    elevation = table["elevation_deg"].to_numpy(float)
    detected = inside & table["detected"].to_numpy(bool) & np.isfinite(elevation)
    if not detected.any():
        return None
    lowest = float(elevation[detected].min())
    below = int((inside & (elevation < lowest)).sum())
    share = below / int(inside.sum())
    if share < BELOW_DETECTIONS_SHARE:
        return None
    return (f"{below} expected updates inside coverage ({100 * share:.1f} %) lie below the lowest elevation "
            f"the sensor detected ({lowest:.2f} deg), all missed: no min_elevation_deg is declared; if that "
            "is the radar's horizon, declare it in the sensor file")


def _per_aircraft(table: pd.DataFrame) -> pd.DataFrame:
    """Per aircraft: expected updates inside coverage, detected ones, PD and its interval."""
    inside = table[table["in_coverage"]]
    g = inside.groupby("aircraft", sort=True)["detected"].agg(["sum", "size"])
    p = proportion(g["sum"].to_numpy(np.int64), g["size"].to_numpy(np.int64))
    return pd.DataFrame({"aircraft": g.index, "expected": g["size"].to_numpy(),
                         "detected": g["sum"].to_numpy(), "pd": p.value, "ci_low": p.ci_low,
                         "ci_high": p.ci_high})


def pd_requirement(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                   sensor: Sensor, within: Within | None = None) -> Outcome:
    """``pd``: detected expected updates inside coverage over all expected ones (``within``: only those in a
    region). Scope 'global' pools every update; 'per_target' gives the aircraft whose interval reaches lowest
    (every aircraft must meet it)."""
    table, _, notes = expected_updates(reports, reference, parameters, sensor)
    if within is not None:
        table = table[np.asarray(within(table), bool)]
        if table.empty:
            return withheld("pd", f"no expected update inside {within.name!r}")
    inside = table[table["in_coverage"]]
    per = _per_aircraft(table)
    if parameter(parameters, "scope", "global") == "per_target":
        return per_target(per, notes)
    return share("pd", int(inside["detected"].sum()), len(inside), notes, per)


def per_target(per: pd.DataFrame, notes: tuple[str, ...] = ()) -> Outcome:
    """A per-target PD from the per-aircraft table (aircraft, expected, detected, ci_high): the aircraft whose
    interval reaches lowest, every aircraft having to meet the threshold."""
    if per.empty:
        return withheld("pd", "no expected update inside coverage")
    worst = per.iloc[int(np.argmin(per["ci_high"].to_numpy()))]
    notes = (*notes, f"per target: the aircraft {worst['aircraft']!r} of {len(per):,} reaches lowest")
    return share("pd", int(worst["detected"]), int(worst["expected"]), notes, per)


def long_gaps(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
              sensor: Sensor, within: Within | None = None) -> Outcome:
    """``long_gaps``: of the intervals between successive updates of an aircraft in one reference stretch
    with every update between them expected inside coverage (and ``within`` a region: in it; scan updates,
    whatever interval_s says), the share with min_gap_s <= gap < max_gap_s."""
    lo = parameter(parameters, "min_gap_s", None)
    if lo is None:
        raise ValueError("long_gaps needs the parameter min_gap_s")
    hi = float(parameter(parameters, "max_gap_s", math.inf))
    scans = {k: v for k, v in (parameters or {}).items() if k != "interval_s"}
    table, _, notes = expected_updates(reports, reference, scans, sensor)
    counted = table["in_coverage"].to_numpy(bool)
    if within is not None:
        region = np.asarray(within(table), bool)
        if not region.any():
            return withheld("long_gaps", f"no expected update inside {within.name!r}")
        counted = counted & region
    # the table runs aircraft by aircraft, stretch by stretch, in time: successive detected updates of one
    # stretch with no update between them (both included) that is not counted
    aircraft, stretch = table["aircraft"].to_numpy(object), table["stretch"].to_numpy()
    group = np.cumsum(np.r_[True, (aircraft[1:] != aircraft[:-1]) | (stretch[1:] != stretch[:-1])])
    at = np.flatnonzero(table["detected"].to_numpy(bool))
    out_before = np.concatenate([[0], np.cumsum(~counted)])  # updates not counted before each row
    a, b = at[:-1], at[1:]
    ok = (group[a] == group[b]) & ((out_before[b + 1] - out_before[a]) == 0)
    t = table["t_s"].to_numpy(float)
    g = (t[b] - t[a])[ok]
    count = int(np.sum((g >= float(lo)) & (g < hi)))
    return share("long_gaps", count, g.size, (*notes, f"{g.size:,} gaps inside coverage"))
