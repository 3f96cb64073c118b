"""The reference the requirements judge against (positions and identities per aircraft over time), its
minimum schema, its interpolation at report times, and the association of each test report with the
nearest reference aircraft."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.candidates import candidate_pairs, latitude_reach_deg
from msdc.pipeline.evaluate.interpolation import interpolate
from msdc.pipeline.model.geodesy import A_M, E2, M_PER_FT

REFERENCE_REQUIRED = ("aircraft", "t_s", "latitude", "longitude")
REFERENCE_OPTIONAL = ("altitude_ft", "height_m", "mode3a", "address", "callsign")
REPORTS_REQUIRED = ("t_s", "latitude", "longitude")
T = TypeVar("T")
DEFAULT_GATE_M = 3704.0  # 2 NM: a report further than this from every reference aircraft is not associated
DEFAULT_REFERENCE_GAP_S = 30.0  # reference samples further apart than this leave the aircraft unknown between
# a report's Mode C this far from an aircraft's altitude prefers another aircraft within the gate, if any:
# aircraft crossing at different levels keep their own plots (a Mode C error is 400 ft and up, a garbled
# one anything, so only a gross one with another aircraft in the gate at that level can mislead it)
DEFAULT_VERTICAL_GATE_FT = 3000.0
ASSOCIATION_COLUMNS = ("ref_index", "ref_aircraft", "ref_distance_m")
FAR_BATCH_AIRCRAFT = 32  # aircraft tried at once beyond the gate, the nearest found so far updated between


def _check_columns(frame: pd.DataFrame, required: tuple[str, ...], what: str) -> None:
    """Refuse a frame that lacks a required column, naming them all."""
    missing = [c for c in required if c not in frame.columns]
    if missing:
        raise ValueError(f"missing column(s) in {what}: {', '.join(missing)} "
                         f"(required: {', '.join(required)})")


def check_reference(reference: pd.DataFrame) -> pd.DataFrame:
    """The reference sorted by aircraft and time, rows without a position or time dropped; refused with a
    message when a required column is missing."""
    _check_columns(reference, REFERENCE_REQUIRED, "the reference")
    ref = reference.dropna(subset=["t_s", "latitude", "longitude"])
    if in_order(ref["aircraft"], ref["t_s"].to_numpy(float)):
        return ref.reset_index(drop=True)  # a reconstruction's order: sorting its text ids costs seconds
    return ref.sort_values(["aircraft", "t_s"], kind="stable", ignore_index=True)


def in_order(aircraft: pd.Series, t_s: np.ndarray) -> bool:
    """Whether rows are sorted by aircraft (text, none missing), then time (what a stable sort by both would
    leave as it is); times without NaN. Arrow-backed text is compared by pyarrow, with no object per row."""
    if len(aircraft) < 2:
        return True
    values = aircraft.array
    if hasattr(values, "__arrow_array__") and not isinstance(values, pd.Categorical):
        import pyarrow as pa
        import pyarrow.compute as pc

        ids = pa.array(values)
        a, b = ids.slice(0, len(ids) - 1), ids.slice(1)
        after = pc.greater(b, a).fill_null(False).to_numpy(zero_copy_only=False)
        same = pc.equal(b, a).fill_null(False).to_numpy(zero_copy_only=False)
    else:
        ids = aircraft.to_numpy(object)
        after, same = ids[1:] > ids[:-1], ids[1:] == ids[:-1]
    return bool(np.all(after | (same & (t_s[1:] >= t_s[:-1]))))


def parameter(parameters: Mapping | None, name: str, default):
    """A parameter's value, or its default when absent."""
    return default if not parameters or parameters.get(name) is None else parameters[name]


@dataclass(frozen=True)
class Trajectory:
    """One reference aircraft's samples as arrays, sorted by time."""

    label: object
    t_s: np.ndarray
    latitude: np.ndarray
    longitude: np.ndarray
    height_m: np.ndarray
    altitude_ft: np.ndarray
    rows: np.ndarray  # row numbers in the checked reference, for its identity columns

    @property
    def box(self) -> tuple[float, float, float, float] | None:
        """South, north, west and east bounds (deg) of the samples, which hold every interpolated position;
        None when the samples span 180 deg of longitude or more (across the antimeridian: interpolation
        between them wraps)."""
        west, east = float(np.nanmin(self.longitude)), float(np.nanmax(self.longitude))
        if not east - west < 180.0:
            return None
        return float(np.nanmin(self.latitude)), float(np.nanmax(self.latitude)), west, east

    def at(self, t_s: np.ndarray, max_gap_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Latitude, longitude, height (m) and pressure altitude (ft) interpolated linearly at t_s; NaN
        before the first sample, after the last, and between samples more than max_gap_s apart."""
        out = interpolate(self.t_s, self.latitude, self.longitude, self.height_m, self.altitude_ft,
                          np.asarray(t_s, dtype=float), float(max_gap_s))
        return out[0], out[1], out[2], out[3]

    def stretches(self, max_gap_s: float) -> list[tuple[float, float]]:
        """Spans (first, last sample time) of the reference, cut where samples are more than max_gap_s
        apart: the aircraft is known only inside them."""
        cut = np.flatnonzero(np.diff(self.t_s) > max_gap_s)
        starts = np.concatenate([[0], cut + 1])
        ends = np.concatenate([cut, [self.t_s.size - 1]])
        return [(float(self.t_s[a]), float(self.t_s[b])) for a, b in zip(starts, ends, strict=True)]


def trajectories(reference: pd.DataFrame) -> list[Trajectory]:
    """Per reference aircraft, its samples (the reference as check_reference returns it). Height comes from
    height_m, else the pressure altitude, else 0; the pressure altitude is NaN when absent."""
    n = len(reference)
    alt = reference["altitude_ft"].to_numpy(float) if "altitude_ft" in reference else np.full(n, np.nan)
    if "height_m" in reference:
        h = reference["height_m"].to_numpy(float)
    else:
        h = np.nan_to_num(alt * M_PER_FT, nan=0.0)
    t = reference["t_s"].to_numpy(float)
    lat, lon = reference["latitude"].to_numpy(float), reference["longitude"].to_numpy(float)
    codes, labels = pd.factorize(reference["aircraft"], sort=True)  # -1: no label, in no trajectory
    if len(codes) and bool(np.all(np.diff(codes) >= 0)):  # sorted by aircraft (a checked reference)
        starts = np.searchsorted(codes, np.arange(len(labels) + 1), side="left")
        return [Trajectory(label, t[a:b], lat[a:b], lon[a:b], h[a:b], alt[a:b], np.arange(a, b))
                for label, a, b in zip(labels, starts[:-1], starts[1:], strict=True)]  # views, not copies
    order = np.argsort(codes, kind="stable")
    starts = np.searchsorted(codes[order], np.arange(len(labels) + 1), side="left")
    out = []
    for label, a, b in zip(labels, starts[:-1], starts[1:], strict=True):
        rows = order[a:b]
        out.append(Trajectory(label, t[rows], lat[rows], lon[rows], h[rows], alt[rows], rows))
    return out


# within `shared_references`: per key, the objects its ids name (kept, so that no id is reused) and the value
_SHARED: ContextVar[dict[tuple, tuple[tuple, object]] | None] = ContextVar("msdc_shared_references",
                                                                           default=None)


@contextmanager
def shared_references() -> Iterator[None]:
    """Within it, a reference frame is checked and cut into trajectories once however many requirements
    read it (a sensor's scorecard reads one frame some fifteen times), and `shared` values are computed
    once. The frames must not change in place inside it: the requirements are pure functions of them."""
    if _SHARED.get() is not None:  # inside another: its memo serves both
        yield
        return
    token = _SHARED.set({})
    try:
        yield
    finally:
        _SHARED.reset(token)


def shared(key: tuple, objects: tuple, compute: Callable[[], T]) -> T:
    """``compute()``, once per key inside `shared_references` (every call outside it); key holds the ids of
    ``objects`` (the frames it is computed from) and the values that change the result. The value is shared:
    read, never written."""
    memo = _SHARED.get()
    if memo is None:
        return compute()
    hit = memo.get(key)
    if hit is not None and all(a is b for a, b in zip(hit[0], objects, strict=True)):
        return hit[1]  # type: ignore[return-value]
    value = compute()
    memo[key] = (objects, value)
    return value


def checked_trajectories(reference: pd.DataFrame) -> tuple[pd.DataFrame, list[Trajectory]]:
    """``check_reference(reference)`` and its ``trajectories`` (the arrays are shared: read, never
    written); inside `shared_references`, computed once per frame."""
    def cut() -> tuple[pd.DataFrame, list[Trajectory]]:
        ref = check_reference(reference)
        return ref, trajectories(ref)

    return shared(("trajectories", id(reference)), (reference,), cut)


def rows_by_index(idx: np.ndarray, n: int) -> list[np.ndarray]:
    """Per k in range(n), the rows where idx == k, ascending: ``np.flatnonzero(idx == k)`` for every
    aircraft of a reference from one sort, instead of a pass over every report per aircraft."""
    idx = np.asarray(idx)
    order = np.argsort(idx, kind="stable")
    bounds = np.searchsorted(idx[order], np.arange(n + 1), side="left")
    return [order[bounds[k]:bounds[k + 1]] for k in range(n)]


def local_distance_m(lat1_deg, lon1_deg, lat2_deg, lon2_deg) -> np.ndarray:
    """Horizontal distance (m) between nearby points on the WGS-84 ellipsoid's local radii of curvature:
    within 0.1 % of the geodesic below 20 km, which is all an association gate needs."""
    lat1, lat2 = np.asarray(lat1_deg, float), np.asarray(lat2_deg, float)
    s = np.sin(np.radians(0.5 * (lat1 + lat2)))
    w = np.sqrt(1.0 - E2 * s**2)
    meridian, normal = A_M * (1.0 - E2) / w**3, A_M / w
    dn = np.radians(lat2 - lat1) * meridian
    dlon = (np.asarray(lon2_deg, float) - np.asarray(lon1_deg, float) + 180.0) % 360.0 - 180.0
    de = np.radians(dlon) * normal * np.cos(np.radians(0.5 * (lat1 + lat2)))
    return np.hypot(de, dn)


def associate(reports: pd.DataFrame, reference: pd.DataFrame,
              parameters: Mapping | None = None) -> pd.DataFrame:
    """The reports with ``ref_index`` (the nearest reference aircraft's position in the sorted list of
    aircraft, -1 when none is within gate_m), ``ref_aircraft`` (its label, None when -1) and
    ``ref_distance_m`` (distance to the nearest reference aircraft at the report's time, inf when none is
    known then). Association is by horizontal position; where two aircraft are within the gate, one whose
    altitude is within vertical_gate_ft of the report's Mode C is preferred, so aircraft crossing at
    different levels keep their plots. Codes are judged apart from it: a wrong Mode C with a single
    aircraft in the gate still goes to that aircraft."""
    _check_columns(reports, REPORTS_REQUIRED, "the test reports")
    gate_m, vertical_ft, max_gap_s = association_gates(parameters)
    _, trajs = checked_trajectories(reference)
    t = reports["t_s"].to_numpy(float)
    lat, lon = reports["latitude"].to_numpy(float), reports["longitude"].to_numpy(float)
    mode_c_ft = (pd.to_numeric(reports["flight_level"], errors="coerce").to_numpy(float) * 100.0
                 if "flight_level" in reports.columns else np.full(t.size, np.nan))
    t_first = np.array([tr.t_s[0] for tr in trajs], dtype=float)
    t_last = np.array([tr.t_s[-1] for tr in trajs], dtype=float)
    boxes = [tr.box for tr in trajs]
    bounded = np.array([b is not None for b in boxes], dtype=bool)
    boxes = np.array([b if b is not None else (0.0, 0.0, 0.0, 0.0) for b in boxes], float).reshape(-1, 4)

    def pairs(aircraft: np.ndarray, order: np.ndarray, first: np.ndarray, stop: np.ndarray,
              limit_m: np.ndarray) -> tuple[np.ndarray, ...]:
        """The (aircraft, report) pairs the boxes may hold within limit_m, of the reports order[first[k]:
        stop[k]] per aircraft k: aircraft, row, distance (inf where the reference is not known then) and
        the reference's altitude."""
        ks, rows = candidate_pairs(aircraft, order, first, stop, t_first, t_last, boxes, bounded, t, lat,
                                   lon, limit_m)
        r_lat, r_lon, r_alt = (np.empty(ks.size) for _ in range(3))
        cuts = np.flatnonzero(np.diff(ks)) + 1
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, ks.size], strict=True):
            if b > a:
                r_lat[a:b], r_lon[a:b], _, r_alt[a:b] = trajs[ks[a]].at(t[rows[a:b]], max_gap_s)
        d = np.nan_to_num(local_distance_m(lat[rows], lon[rows], r_lat, r_lon), nan=np.inf)
        return ks, rows, d, r_alt

    # Per report, the nearest aircraft (and the nearest within the vertical gate), the smallest k on equal
    # distances. An aircraft is measured only against the reports its box of samples may hold nearer
    # (candidates.candidate_pairs): first every aircraft against the reports it may hold within the gate,
    # those of its latitudes (so the association within the gate is whole); then the reports left with
    # none within the gate, for the distance to the nearest aircraft beyond it, against each batch of
    # aircraft that may hold them nearer than the nearest found so far. An aircraft left out is farther
    # than the nearest found, so the nearest and its k are those of every aircraft measured against every
    # report.
    best, level_best = np.full(t.size, np.inf), np.full(t.size, np.inf)
    index, level_index = np.full(t.size, -1, dtype=np.int64), np.full(t.size, -1, dtype=np.int64)
    every = np.arange(len(trajs), dtype=np.int64)
    by_lat = np.argsort(lat, kind="stable")
    lats = lat[by_lat]
    reach = latitude_reach_deg(gate_m)
    first = np.where(bounded, np.searchsorted(lats, boxes[:, 0] - reach, "left"), 0).astype(np.int64)
    stop = np.where(bounded, np.searchsorted(lats, boxes[:, 1] + reach, "right"), t.size).astype(np.int64)
    ks, rows, d, r_alt = pairs(every, by_lat, first, stop, np.full(t.size, gate_m))
    _nearer(best, index, ks, rows, d)
    with np.errstate(invalid="ignore"):
        apart = np.abs(mode_c_ft[rows] - r_alt) > vertical_ft  # False where either is unknown
    _nearer(level_best, level_index, ks[~apart], rows[~apart], d[~apart])
    beyond = np.flatnonzero(~(best <= gate_m))  # within it, no aircraft beyond the gate can be nearer
    if beyond.size:
        by_time = beyond[np.argsort(t[beyond], kind="stable")]
        ts = t[by_time]
        first = np.searchsorted(ts, t_first, "left").astype(np.int64)
        stop = np.searchsorted(ts, t_last, "right").astype(np.int64)
        for batch in np.array_split(every, max(1, len(trajs) // FAR_BATCH_AIRCRAFT)):
            ks, rows, d, _ = pairs(batch, by_time, first, stop, best)
            _nearer(best, index, ks, rows, d)
    out = reports.copy()
    out["ref_distance_m"] = np.where(np.isfinite(lat) & np.isfinite(lon), best, np.nan)
    index = np.where(level_best <= gate_m, level_index, np.where(best <= gate_m, index, -1))
    out["ref_index"] = index
    labels = np.array([tr.label for tr in trajs] + [None], dtype=object)
    out["ref_aircraft"] = pd.Series(labels[index], index=out.index, dtype=object)
    return out


def _nearer(best: np.ndarray, index: np.ndarray, ks: np.ndarray, rows: np.ndarray, d: np.ndarray) -> None:
    """Per row of the pairs, its nearest aircraft among them (the smallest k of equal distances) where it is
    nearer than ``best`` (or as near with a smaller k than ``index``): best and index updated in place."""
    finite = np.isfinite(d)  # an unknown distance never makes an aircraft the nearest
    ks, rows, d = ks[finite], rows[finite], d[finite]
    order = np.lexsort((ks, d, rows))
    rows, d, ks = rows[order], d[order], ks[order]
    head = np.r_[True, rows[1:] != rows[:-1]] if rows.size else np.zeros(0, bool)
    rows, d, ks = rows[head], d[head], ks[head]
    closer = (d < best[rows]) | ((d == best[rows]) & (ks < index[rows]))
    best[rows[closer]] = d[closer]
    index[rows[closer]] = ks[closer]


def association_gates(parameters: Mapping | None) -> tuple[float, float, float]:
    """What associate takes from the parameters: gate_m, vertical_gate_ft and reference_max_gap_s (their
    defaults where absent); two parameter sets with the same gates associate alike."""
    return (float(parameter(parameters, "gate_m", DEFAULT_GATE_M)),
            float(parameter(parameters, "vertical_gate_ft", DEFAULT_VERTICAL_GATE_FT)),
            float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S)))


def associated(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None) -> pd.DataFrame:
    """The reports as associate returns them, reusing the association when the frame already carries it."""
    if all(c in reports.columns for c in ASSOCIATION_COLUMNS):
        return reports
    return associate(reports, reference, parameters)


def reference_values(reports: pd.DataFrame, reference: pd.DataFrame, column: str,
                     parameters: Mapping | None) -> np.ndarray:
    """Per associated report, the reference's value of an identity column (mode3a, address, callsign) at the
    report's time: the latest reference sample at or before it (else the first); None where the report is
    not associated or the reference lacks the column."""
    out = np.full(len(reports), None, dtype=object)
    if column not in reference.columns:
        return out
    ref, trajs = checked_trajectories(reference)
    t = reports["t_s"].to_numpy(float)
    idx = reports["ref_index"].to_numpy()
    groups = rows_by_index(idx, len(trajs))
    at = np.full(len(reports), -1, np.int64)  # per report, the reference row whose value it takes
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if rows.size:
            i = np.clip(np.searchsorted(tr.t_s, t[rows], side="right") - 1, 0, tr.t_s.size - 1)
            at[rows] = tr.rows[i]
    taken = at >= 0  # only those rows' values made objects, not the whole reference's column
    out[taken] = ref[column].iloc[at[taken]].to_numpy(object)
    out[pd.isna(out)] = None  # a missing value of any kind (NaN, <NA>) is None
    return out


def reference_altitude_ft(reports: pd.DataFrame, reference: pd.DataFrame,
                          parameters: Mapping | None) -> np.ndarray:
    """Per associated report, the reference's pressure altitude (ft) interpolated at the report's time."""
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    out = np.full(len(reports), np.nan)
    t = reports["t_s"].to_numpy(float)
    idx = reports["ref_index"].to_numpy()
    trajs = checked_trajectories(reference)[1]
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if rows.size:
            out[rows] = tr.at(t[rows], max_gap_s)[3]
    return out
