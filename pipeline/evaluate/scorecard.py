"""One sensor evaluated against a preset: each requirement measured (globally, per sector of the sector file,
and on its preset area) and judged into the scorecard's rows (scorecard_schema.SCORECARD) with its verdict.

Sectors are regions: a name, an optional preset area and a mask function of (latitude, longitude, flight
level, on ground: 1, 0 or NaN unknown). Besides the sector file's, "surface" and "airborne" are regions of
their own when the reference has aircraft on the surface. A report belongs to a region where its reference
aircraft is inside it at the report's time (an unassociated report: where the report itself is), and so
does an expected update (pd, long_gaps) at its time; the other requirements read the reference cut to its
samples inside the region. The scan period and coverage are the sensor's, from all of its plots."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.accuracy import THRESHOLD_PARAMETER
from msdc.pipeline.evaluate.catalogue import CATALOGUE, ERROR, PROPORTION, RATE, SIGNED
from msdc.pipeline.evaluate.codes import CODE_REQUIREMENTS
from msdc.pipeline.evaluate.coverage import Sensor, coverage_of
from msdc.pipeline.evaluate.detection import Within, update_period
from msdc.pipeline.evaluate.outcome import Outcome, withheld
from msdc.pipeline.evaluate.presets import RESERVED_SECTORS, Preset, Requirement
from msdc.pipeline.evaluate.reference import (
    DEFAULT_REFERENCE_GAP_S,
    associate,
    associated,
    checked_trajectories,
    rows_by_index,
    shared,
    shared_references,
)
from msdc.pipeline.evaluate.reference_gates import self_referenced, sigma_gate
from msdc.pipeline.evaluate.requirements import REQUIREMENTS
from msdc.pipeline.evaluate.statistics import magnitude_interval, verdict

GLOBAL, SURFACE, AIRBORNE, MONITORS = RESERVED_SECTORS
MONITOR_CODE = 2.0  # the on-ground channel's value for a field monitor
# (lat deg, lon deg, FL, on ground 1/0/NaN) -> inside
Mask = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
# measured per region on the sensor's expected updates, each placed where its reference aircraft then was,
# not on frames cut to the region: a cut reference would bridge an aircraft's short excursions out of the
# region (its stretches), and a cut of the plots would estimate coverage limits of its own
REGIONAL = ("pd", "long_gaps")
# proportions whose own notes count their trials on the sensor's own track (velocity: judged on an independent
# reference only, the own-track reports left out and counted; codes and identity: the own-track trials among
# theirs), so the region's count of associated reports would mislead on them
OWN_NOTE = frozenset({"velocity_correct", "identification_correct", "identification_false",
                      *CODE_REQUIREMENTS})
# the sigma gate's counts of reports left out (reference_gates.SIGMA_GATE_KEYS), in words
GATE_WORDS = {"no_reference": "with no reference aircraft", "self_reference": "on the sensor's own track",
              "sigma_unknown": "where the reference's sigma is unknown",
              "sigma_too_large": "where the reference's sigma is too large for the tolerance"}


@dataclass(frozen=True)
class Region:
    """Where figures are cut: a name (the scorecard's ``sector``), the preset area it belongs to (None: any
    requirement without an area is also given per region) and its mask."""

    name: str
    mask: Mask
    area: str | None = None


@dataclass
class SensorScore:
    """The scorecard rows of one sensor, the outcomes they came from (per region name and requirement) and
    the notes on what was done."""

    sensor: str
    rows: list[dict] = field(default_factory=list)
    outcomes: dict[tuple[str, str, int], Outcome] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    reports: pd.DataFrame | None = field(default=None, compare=False)  # associated with the whole reference


def _is_position(requirement: Requirement) -> bool:
    """Whether the requirement judges positions against a tolerance in metres (the sigma gate applies)."""
    kind = CATALOGUE[requirement.id]
    return kind.kind == ERROR and kind.unit == "m" and requirement.id not in ("range_sd_m",)


def measure(requirement: Requirement, reports: pd.DataFrame, reference: pd.DataFrame,
            sensor: Sensor, within: Within | None = None) -> Outcome:
    """The requirement's outcome; a position requirement judges only the reports the sigma gate passes (its
    counts in the notes); a requirement the data cannot support is withheld with the reason. ``within``
    (the REGIONAL requirements, on the whole frames): only the expected updates in a region count."""
    function = REQUIREMENTS.get(requirement.id)
    if function is None:
        return withheld(requirement.id, "not measured by this version of msdc")
    params = dict(requirement.parameters)
    notes: tuple[str, ...] = ()
    rep = reports
    if _is_position(requirement) and len(reports) and len(reference):
        gate = sigma_gate(reports, reference, requirement.threshold, params)
        c = gate.counts
        rep = reports[gate.judged].reset_index(drop=True)
        left = {k: v for k, v in c.items() if k not in ("reports", "judged") and v}
        notes = (f"sigma gate at {requirement.threshold:g} m: {c['judged']:,} of {c['reports']:,} reports "
                 "judged"
                 + (" (left out: " + ", ".join(f"{v:,} {GATE_WORDS.get(k, k.replace('_', ' '))}"
                                               for k, v in left.items()) + ")" if left else ""),)
        params[THRESHOLD_PARAMETER] = requirement.threshold  # the timing note counts the errors over it
    elif "distance_m" in params and len(reports) and len(reference):
        rep, notes = _gate_false(reports, reference, float(params["distance_m"]), params)
    try:
        out = (function(rep, reference, params, sensor) if within is None
               else function(rep, reference, params, sensor, within=within))
    except ValueError as exc:
        return withheld(requirement.id, str(exc))
    return Outcome(out.requirement, out.value, out.ci_low, out.ci_high, out.n, out.count,
                   (*notes, *out.notes), out.per_aircraft, out.evidence)


def _gate_false(reports: pd.DataFrame, reference: pd.DataFrame, distance_m: float,
                params: dict) -> tuple[pd.DataFrame, tuple[str, ...]]:
    """The reports a false-report count may judge: those no reference aircraft is near (false whatever the
    reference's accuracy), and those near one whose reference sigma is well below distance_m (a reference
    as uncertain as the distance would make true reports look false); the count left out in a note."""
    rep = associated(reports, reference, params)
    gate = sigma_gate(rep, reference, distance_m, params, independent=False)
    keep = (rep["ref_index"].to_numpy() < 0) | gate.judged
    dropped = int((~keep).sum())
    note = (f"sigma gate at {distance_m:g} m: {dropped:,} of {len(rep):,} reports left out, near an aircraft "
            "whose reference sigma is unknown or too large") if dropped else ""
    return rep[keep].reset_index(drop=True), (note,) if note else ()


def self_reference_note(reports: pd.DataFrame, reference: pd.DataFrame, sensor_id: str) -> str:
    """How many of a region's associated reports were judged against the sensor's own track (their aircraft
    seen by no other sensor then): said on every detection, code, identity and count row; '' when none."""
    linked = reports[reports["ref_index"].to_numpy() >= 0]
    own = int(self_referenced(linked, reference, None).sum()) if len(linked) else 0
    if not own:
        return ""
    return (f"self-reference: {own:,} of {len(linked):,} associated reports judged against {sensor_id}'s own "
            "track (no other sensor saw their aircraft then)")


def parameters_text(requirement: Requirement) -> str:
    """The requirement's parameters as the preset gives them: 'interval_s = 5, scope = global'."""
    return ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                     for k, v in requirement.parameters.items())


def judge(outcome: Outcome, requirement: Requirement, preset: Preset, sensor_id: str, sector: str) -> dict:
    """The scorecard row of one outcome: the verdict from its interval (a signed bias by its magnitude)
    against the threshold, with the preset's minimum sample."""
    low, high = outcome.ci_low, outcome.ci_high
    notes = list(outcome.notes)
    if CATALOGUE[requirement.id].kind == SIGNED and not math.isnan(low):
        low, high = magnitude_interval(low, high)
        notes.append(f"judged by its magnitude, in [{low:.4g}, {high:.4g}]")
    n = outcome.n
    if CATALOGUE[requirement.id].statistic == "max" and math.isfinite(outcome.value):
        # the largest error judged bounds the true maximum from below: [value, inf) holds it for sure
        low, high = float(outcome.value), math.inf
    v = verdict(low, high, requirement.threshold, requirement.direction,
                int(n) if math.isfinite(n) else None, preset.minimum_sample(requirement))
    if v.reason and (not math.isnan(outcome.value) or not notes):
        notes.append(v.reason)
    if not requirement.checked:
        notes.append("threshold not checked against the standard's text")
    return {"sensor": sensor_id, "sector": sector, "requirement": requirement.id,
            "parameters": parameters_text(requirement), "value": float(outcome.value),
            "ci_low": float(outcome.ci_low), "ci_high": float(outcome.ci_high),
            "n": float(n) if math.isfinite(n) else 0.0, "threshold": float(requirement.threshold),
            "verdict": v.verdict, "clause": requirement.clause, "checked": bool(requirement.checked),
            "notes": "; ".join(dict.fromkeys(x for x in notes if x))}


def reference_positions(reports: pd.DataFrame, reference: pd.DataFrame,
                        max_gap_s: float = DEFAULT_REFERENCE_GAP_S
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per associated report, its reference aircraft's latitude, longitude and flight level at the report's
    time (interpolated), and its on-ground flag (ground_flags) of the latest sample at or before it, as the
    bins' surface and airborne classes take it (NaN where not associated or the reference does not know)."""
    n = len(reports)
    lat, lon, fl, ground = (np.full(n, np.nan) for _ in range(4))
    t, idx = reports["t_s"].to_numpy(float), reports["ref_index"].to_numpy()
    ref, trajs = checked_trajectories(reference)
    flags = (ground_flags(ref) if "on_ground" in ref.columns or "field_monitor" in ref.columns
             else None)
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if rows.size:
            a, b, _, alt = tr.at(t[rows], max_gap_s)
            lat[rows], lon[rows], fl[rows] = a, b, alt / 100.0
            if flags is not None:
                latest = np.searchsorted(tr.t_s, t[rows], side="right") - 1  # the last of equal times
                known = latest >= 0
                ground[rows[known]] = flags[tr.rows[latest[known]]]
    return lat, lon, fl, ground


def ground_flags(frame: pd.DataFrame) -> np.ndarray:
    """Per row, 1.0 on the surface, 0.0 airborne, NaN unknown (the ``on_ground`` column) and MONITOR_CODE
    for a field monitor (the ``field_monitor`` column: a fixed transponder, not traffic)."""
    out = (frame["on_ground"].astype("boolean").astype("Float64").to_numpy(float, na_value=np.nan)
           if "on_ground" in frame.columns else np.full(len(frame), np.nan))
    if "field_monitor" in frame.columns:
        out[frame["field_monitor"].fillna(False).to_numpy(bool)] = MONITOR_CODE
    return out


def _report_fl(reports: pd.DataFrame) -> np.ndarray:
    """The reports' own flight levels (NaN where absent)."""
    if "flight_level" not in reports.columns:
        return np.full(len(reports), np.nan)
    return pd.to_numeric(reports["flight_level"], errors="coerce").to_numpy(float)


def cut(reports: pd.DataFrame, reference: pd.DataFrame, masks: Sequence[Mask],
        where: tuple[np.ndarray, ...]) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The associated reports and the reference inside the union of ``masks``: reports by ``where`` (their
    reference position, else their own), the reference by its samples with each one's neighbours (so that a
    report inside near the edge is interpolated between the samples it lies between, not across the time
    its aircraft spent outside); each report's ``ref_index`` renumbered to the cut reference's aircraft (a
    report whose aircraft has no sample inside is left out)."""
    ref = checked_trajectories(reference)[0]
    alt = ref["altitude_ft"].to_numpy(float) / 100.0 if "altitude_ft" in ref else np.full(len(ref), np.nan)
    lat, lon = ref["latitude"].to_numpy(float), ref["longitude"].to_numpy(float)
    samples = union(masks, lat, lon, alt, ground_flags(ref))
    same = shared(("same aircraft", id(ref)), (ref,), lambda: same_aircraft(ref["aircraft"]))
    ref_in = ref[with_neighbours(samples, same)]
    ref_in = ref_in.reset_index(drop=True)
    rep_in = reports[union(masks, *where)]
    labels = np.array(sorted(ref_in["aircraft"].unique()), dtype=object)
    linked = rep_in["ref_index"].to_numpy() >= 0
    names = rep_in["ref_aircraft"].to_numpy(object)
    pos = np.full(len(rep_in), -1, np.int64)
    if labels.size and linked.any():
        found = np.searchsorted(labels, names[linked])
        found = np.clip(found, 0, labels.size - 1)
        pos[linked] = np.where(labels[found] == names[linked], found, -2)
    rep_in = rep_in.assign(ref_index=pos)
    rep_in = rep_in[pos != -2].reset_index(drop=True)
    return rep_in, ref_in


def union(masks: Sequence[Mask], lat, lon, fl, ground) -> np.ndarray:
    """Whether each place (latitude, longitude, flight level, on-ground flag) lies in any of ``masks``."""
    keep = np.zeros(len(lat), bool)
    for m in masks:
        keep |= np.asarray(m(lat, lon, fl, ground), bool)
    return keep


def same_aircraft(aircraft: pd.Series) -> np.ndarray:
    """Per row, whether it is of the previous row's aircraft (the first row: False)."""
    ids = aircraft.to_numpy(object)
    same = np.zeros(ids.size, bool)
    same[1:] = ids[1:] == ids[:-1]
    return same


def with_neighbours(keep: np.ndarray, same: np.ndarray) -> np.ndarray:
    """``keep`` widened by one row either side within each aircraft (rows sorted by aircraft, then time;
    ``same``: same_aircraft of them)."""
    keep = np.asarray(keep, bool)
    out = keep.copy()
    out[1:] |= keep[:-1] & same[1:]   # the row after a kept one
    out[:-1] |= keep[1:] & same[1:]   # the row before one
    return out


@dataclass(frozen=True, eq=False)
class Placed:
    """A region's expected updates (detection.Within): those whose reference aircraft was in the union of
    ``masks`` at the update (``t_ref_s``), by the rule that places the reports (reference_positions)."""

    name: str
    masks: Sequence[Mask]
    reference: pd.DataFrame = field(repr=False)
    max_gap_s: float = DEFAULT_REFERENCE_GAP_S

    def __call__(self, table: pd.DataFrame) -> np.ndarray:
        lat, lon, fl, ground = shared(("update places", id(table), id(self.reference), self.max_gap_s),
                                      (table, self.reference),
                                      lambda: update_places(table, self.reference, self.max_gap_s))
        return union(self.masks, lat, lon, fl, ground)


def update_places(table: pd.DataFrame, reference: pd.DataFrame, max_gap_s: float = DEFAULT_REFERENCE_GAP_S
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per expected update (detection.EXPECTED_COLUMNS), its reference aircraft's latitude, longitude,
    flight level and on-ground flag at ``t_ref_s``, as reference_positions gives a report's."""
    labels = pd.Index([tr.label for tr in checked_trajectories(reference)[1]])
    at = pd.DataFrame({"t_s": table["t_ref_s"].to_numpy(float),
                       "ref_index": labels.get_indexer(pd.Index(table["aircraft"]))})
    return reference_positions(at, reference, max_gap_s)


def surface_regions(reference: pd.DataFrame) -> list[Region]:
    """"surface" and "airborne" as regions, when the reference has aircraft on the surface (else the
    airborne row would repeat the global one), and "field monitors" when it has any (fixed transponders:
    judged apart from the traffic, and left out of every other region)."""
    flags = ground_flags(reference)
    out = []
    if (flags == 1.0).any():
        out += [Region(SURFACE, lambda lat, lon, fl, ground: ground == 1.0),
                Region(AIRBORNE, lambda lat, lon, fl, ground: ground == 0.0)]
    if (flags == MONITOR_CODE).any():
        out.append(Region(MONITORS, lambda lat, lon, fl, ground: ground == MONITOR_CODE))
    return out


def traffic(mask: Mask) -> Mask:
    """The mask without the field monitors."""
    def inside(lat, lon, fl, ground) -> np.ndarray:
        return np.asarray(mask(lat, lon, fl, ground), bool) & (ground != MONITOR_CODE)
    return inside


def _everywhere(lat, lon, fl, ground) -> np.ndarray:
    return np.ones(len(lat), bool)


def _regions_for(requirement: Requirement, regions: Sequence[Region], monitors: bool = False
                 ) -> list[tuple[str, list[Mask]]]:
    """The (sector name, masks) a requirement is measured on: its preset area (the union of the regions of
    that area) when it has one; else global and every region."""
    if requirement.area is not None:
        masks = [traffic(r.mask) if monitors else r.mask for r in regions if r.area == requirement.area]
        return [(requirement.area, masks)] if masks else []
    if monitors:
        return [(GLOBAL, [traffic(_everywhere)])] + [(r.name, [r.mask if r.name == MONITORS else
                                                              traffic(r.mask)]) for r in regions]
    return [(GLOBAL, [])] + [(r.name, [r.mask]) for r in regions]


def score_sensor(preset: Preset, sensor_id: str, reports: pd.DataFrame, reference: pd.DataFrame,
                 sensor: Sensor, regions: Sequence[Region] = ()) -> SensorScore:
    """Every requirement of the preset measured on the sensor's reports against the reference, globally and
    per region, judged into scorecard rows (each reference frame's trajectories cut once)."""
    with shared_references():
        return _score(preset, sensor_id, reports, reference, sensor, regions)


def _score(preset: Preset, sensor_id: str, reports: pd.DataFrame, reference: pd.DataFrame,
           sensor: Sensor, regions: Sequence[Region]) -> SensorScore:
    """`score_sensor`'s work."""
    score = SensorScore(sensor_id)
    regions = [*surface_regions(reference), *regions]
    monitors = any(r.name == MONITORS for r in regions)
    rep = associate(reports, reference, preset.association()) if len(reference) else reports.assign(
        ref_index=-1, ref_aircraft=None, ref_distance_m=np.inf)
    score.reports = rep
    if sensor.scan_period is None:  # one scan period for every region: a sector's plots estimate none
        sensor = replace(sensor, scan_period=update_period(rep, sensor))
    if sensor.settled_coverage is None and len(reference):  # and one coverage for every requirement
        sensor = replace(sensor, settled_coverage=coverage_of(sensor, rep[rep["ref_index"] >= 0], reference))
    cuts: dict[str, tuple[pd.DataFrame, pd.DataFrame]] = {} if monitors else {GLOBAL: (rep, reference)}
    where: tuple[np.ndarray, ...] | None = None
    marks: dict[str, str] = {}

    def places() -> tuple[np.ndarray, ...]:
        """Where each report is: its reference aircraft's place at its time, else its own, on the surface or
        airborne as it says itself (GBS, STAT: a false report has no aircraft to say it) (made once)."""
        nonlocal where
        if where is None:
            lat, lon, fl, ground = reference_positions(rep, reference)
            own = ~np.isfinite(lat)
            where = (np.where(own, rep["latitude"].to_numpy(float), lat),
                     np.where(own, rep["longitude"].to_numpy(float), lon),
                     np.where(own, _report_fl(rep), fl), np.where(own, ground_flags(rep), ground))
        return where

    def unplaced(name: str, req: Requirement) -> str:
        """On a surface or airborne row of a false-report count: the reports of no aircraft that say
        neither, so lie in neither row (only in the global one)."""
        if name not in (SURFACE, AIRBORNE) or "distance_m" not in req.parameters:
            return ""
        n = int(((rep["ref_index"].to_numpy() < 0) & np.isnan(places()[3])).sum())
        return (f"{n:,} reports of no reference aircraft that do not say whether they are on the surface "
                "are in neither the surface nor the airborne row (only in the global one)") if n else ""

    def region(name: str, masks: list[Mask]) -> tuple[pd.DataFrame, pd.DataFrame]:
        """The reports and reference of a region, cut once."""
        if name not in cuts:
            cuts[name] = cut(rep, reference, masks, places())
        return cuts[name]

    def mark(name: str, masks: list[Mask]) -> str:
        """The region's self-reference note, from its reports against the whole reference (made once)."""
        if name not in marks:
            inside = union(masks, *places()) if masks else np.ones(len(rep), bool)
            marks[name] = self_reference_note(rep[inside], reference, sensor_id)
        return marks[name]

    for i, req in enumerate(preset.requirements):
        spots = _regions_for(req, regions, monitors)
        if not spots:  # a row all the same: a requirement of the preset is never silently absent
            what = f"{req.id} ({parameters_text(req)})" if req.parameters else req.id
            why = f"on area {req.area!r}: no sector of that area in the sector file, not measured"
            score.notes.append(f"{what} {why}")
            outcome = withheld(req.id, f"not measured {why.removesuffix(', not measured')}")
            score.outcomes[(str(req.area), req.id, i)] = outcome
            score.rows.append(judge(outcome, req, preset, sensor_id, str(req.area)))
            continue
        for name, masks in spots:
            if req.id in REGIONAL and masks:
                gap_s = float(req.parameters.get("reference_max_gap_s") or DEFAULT_REFERENCE_GAP_S)
                outcome = measure(req, rep, reference, sensor, Placed(name, masks, reference, gap_s))
            else:
                r, ref = region(name, masks)
                outcome = (withheld(req.id, f"no report and no reference inside {name!r}") if r.empty and
                           ref.empty else measure(req, r, ref, sensor))
            if (CATALOGUE[req.id].kind in (PROPORTION, RATE) and req.id not in OWN_NOTE
                    and mark(name, masks)):  # never position figures
                outcome = replace(outcome, notes=(*outcome.notes, marks[name]))
            if said := unplaced(name, req):
                outcome = replace(outcome, notes=(*outcome.notes, said))
            score.outcomes[(name, req.id, i)] = outcome
            score.rows.append(judge(outcome, req, preset, sensor_id, name))
    return score
