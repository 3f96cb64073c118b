"""Plot requirements: false reports (no reference aircraft near), split and multiple reports (more than one
report of one aircraft in one update)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.detection import update_interval, update_period
from msdc.pipeline.evaluate.outcome import Outcome, rate, share, withheld
from msdc.pipeline.evaluate.reference import DEFAULT_GATE_M, associated, parameter
from msdc.pipeline.evaluate.scans import update_numbers

SPLIT_PLOT_CODE = 3  # I048/030: split plot
_CODE_3 = rf"(?:^|,)\s*{SPLIT_PLOT_CODE}\s*(?:,|$)"


def _false(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None) -> np.ndarray:
    """Whether each report with a position has no reference aircraft within distance_m at its time."""
    distance = parameter(parameters, "distance_m", None)
    if distance is None:
        raise ValueError("false reports need the parameter distance_m")
    rep = associated(reports, reference, parameters)
    d = rep["ref_distance_m"].to_numpy(float)
    return ~np.isnan(d) & (d > float(distance))


# An external reference (--reference-file) lists the aircraft it was made for (a flight trial's GPS): a
# plot far from them may be any other aircraft's, so none is judged false (with the fixture's ADS-B as the
# file, the plots in its gaps were 8.5 % "false"; with one trial aircraft, 80 %)
EXTERNAL_NOT_ALL = ("an external reference lists the aircraft it was made for, not every aircraft in the "
                    "air: a report far from them may be another's, not false")


def _external(reference: pd.DataFrame) -> bool:
    """Whether the reference is an external file's (build_reference: ``built_by`` "external")."""
    return "built_by" in reference and len(reference) > 0 and \
        bool((reference["built_by"].astype(str) == "external").all())


def false_reports(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                  sensor: Sensor | None = None) -> Outcome:
    """``false_reports``: reports with a position and no reference aircraft within distance_m, of all
    reports with a position; withheld against an external reference (EXTERNAL_NOT_ALL)."""
    if _external(reference):
        return withheld("false_reports", EXTERNAL_NOT_ALL)
    rep = associated(reports, reference, parameters)
    positioned = ~np.isnan(rep["ref_distance_m"].to_numpy(float))
    false = _false(rep, reference, parameters)
    return share("false_reports", int(false.sum()), int(positioned.sum()),
                 _late_reference(rep, reference, parameters, false))


def _late_reference(rep: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                    false: np.ndarray) -> tuple[str, ...]:
    """A note when false reports lie near aircraft whose reference is early or late (evaluate.timing: their
    lead stands out from the other aircraft's), as a report ahead of a late reference looks false."""
    from msdc.pipeline.evaluate.accuracy import is_adsb, position_errors
    from msdc.pipeline.evaluate.timing import late_aircraft

    if not false.any() or is_adsb(rep):  # an ADS-B aircraft's own latency makes its reports wrong, not true
        return ()
    late = late_aircraft(position_errors(rep, reference, parameters))
    near = false & pd.Series(rep["ref_aircraft"], dtype=object).astype(str).isin(late).to_numpy(bool)
    if not near.any():
        return ()
    named = ", ".join(late[:6]) + (f" and {len(late) - 6} more" if len(late) > 6 else "")
    return (f"timing: {int(near.sum()):,} of the {int(false.sum()):,} false reports lie near an aircraft "
            f"whose reference leads or lags unlike the others' ({named}: see the accuracy rows); that "
            "reference is early or late, so these reports may be true",)


def false_reports_per_scan(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                           sensor: Sensor) -> Outcome:
    """``false_reports_per_scan``: false reports (as false_reports) per antenna scan, the scans being the
    span of the reports' times over the scan period; withheld against an external reference."""
    if _external(reference):
        return withheld("false_reports_per_scan", EXTERNAL_NOT_ALL)
    rep = associated(reports, reference, parameters)
    period, said = update_period(rep, sensor)
    if not math.isfinite(period):
        raise ValueError(f"sensor {sensor.name!r}: no scan period ({said})")
    t = rep["t_s"].to_numpy(float)
    scans = (np.nanmax(t) - np.nanmin(t)) / period if t.size else 0.0
    notes = (said, f"{scans:.1f} scans")
    if parameter(parameters, "distance_m", None) is None:  # the standard gives none: unassociated is false
        gate_m = float(parameter(parameters, "gate_m", DEFAULT_GATE_M))
        parameters = {**(parameters or {}), "distance_m": gate_m}
        notes = (*notes, f"false: no reference aircraft within {gate_m:g} m (the association gate; no "
                         "distance_m given)")
    return rate("false_reports_per_scan", int(_false(rep, reference, parameters).sum()), scans, notes)


def update_table(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                 sensor: Sensor) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """One row per update of a reference aircraft (its associated reports less than half an update interval
    apart, the interval being interval_s else the scan period): how many reports it holds, how many of
    them are exact repeats (same time and position as another), and whether one carries I048/030 code 3."""
    rep = associated(reports, reference, parameters)
    period, said = update_interval(rep, parameters, sensor)
    if not math.isfinite(period) or period <= 0:
        raise ValueError(f"sensor {sensor.name!r}: no update interval ({said})")
    mine = rep[rep["ref_index"].to_numpy() >= 0]
    code3 = (mine["warning_codes"].astype("string").str.contains(_CODE_3, regex=True, na=False).to_numpy(bool)
             if "warning_codes" in mine.columns else np.zeros(len(mine), bool))
    t = mine["t_s"].to_numpy(float)
    frame = pd.DataFrame({"update": update_numbers(mine["ref_index"].to_numpy(), t, period),
                          "ref": mine["ref_index"].to_numpy(), "t": t,
                          "lat": mine["latitude"].to_numpy(float), "lon": mine["longitude"].to_numpy(float),
                          "aircraft": mine["ref_aircraft"].to_numpy(object), "code3": code3})
    frame = frame.sort_values(["update", "t"], kind="stable")
    frame["repeat"] = frame.duplicated(["ref", "t", "lat", "lon"]).to_numpy()
    table = frame.groupby("update", sort=True).agg(
        aircraft=("aircraft", "first"), t_s=("t", "first"), reports=("repeat", "size"),
        repeats=("repeat", "sum"), code3=("code3", "any")).reset_index(drop=True)
    return table, (said,)


def split_reports(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                  sensor: Sensor) -> Outcome:
    """``split_reports``: updates of an aircraft holding a second report that is not an exact repeat of
    another (a split, not a duplicate), or a report marked split (I048/030 code 3), of all its updates."""
    table, notes = update_table(reports, reference, parameters, sensor)
    split = ((table["reports"] - table["repeats"]) > 1) | table["code3"].astype(bool)
    return share("split_reports", int(split.sum()), len(table), notes)


def multiple_reports(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None,
                     sensor: Sensor) -> Outcome:
    """``multiple_reports``: updates of an aircraft holding more than one report (repeats included), or a
    report marked split (I048/030 code 3), of all its updates."""
    table, notes = update_table(reports, reference, parameters, sensor)
    multiple = (table["reports"] > 1) | table["code3"].astype(bool)
    return share("multiple_reports", int(multiple.sum()), len(table), notes)
