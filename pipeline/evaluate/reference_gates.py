"""The reference's quality gates: ADS-B reports below the NACp/NIC/SIL minimums and position jumps kept out
of the reference (counted), and the sigma gate, which judges a report only where the reference's own
position sigma is well below the tolerance being tested (the exclusions counted)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.reference import (
    DEFAULT_REFERENCE_GAP_S,
    associated,
    checked_trajectories,
    parameter,
    rows_by_index,
)
from msdc.pipeline.model.identity import known_by_address
from msdc.pipeline.quality.checks import check_indicator
from msdc.pipeline.quality.filters import FILTER_KEYS, apply_filters

GATE_KEYS = (*FILTER_KEYS, "sil_below_min", "sil_missing_kept")
# a report is judged where the reference sigma is below this fraction of the tolerance tested: at a third,
# the reference adds at most 5.4 % to an RMS error at the tolerance (sqrt(1 + 1/9) = 1.054)
DEFAULT_SIGMA_FRACTION = 1.0 / 3.0
SIGMA_GATE_KEYS = ("reports", "judged", "no_reference", "self_reference", "sigma_unknown", "sigma_too_large")


@dataclass(frozen=True)
class Gates:
    """The minimums an ADS-B report must meet to enter the reference (None: not applied) and whether
    position jumps are dropped (pipeline.model.jumps)."""

    min_nacp: int | None = None
    min_nic: int | None = None
    min_sil: int | None = None
    drop_jumps: bool = False
    jump_kw: dict = field(default_factory=dict)


def gate_reports(meas: pd.DataFrame, gates: Gates) -> tuple[pd.DataFrame, dict[str, int]]:
    """The measurements with the ADS-B reports that fail the gates removed (jumps, then NIC, then NACp, as
    quality.filters.apply_filters, then SIL), and the count removed per key of GATE_KEYS (each report counted
    once, by the first gate that removes it; a report without the indicator is kept and counted)."""
    check_indicator("min_sil", gates.min_sil, high=3)
    kept, counts = apply_filters(meas, drop_jumps=gates.drop_jumps, min_nic=gates.min_nic,
                                 min_nacp=gates.min_nacp, jump_kw=gates.jump_kw or None)
    counts = {**counts, "sil_below_min": 0, "sil_missing_kept": 0}
    if gates.min_sil is None:
        return kept, counts
    adsb = (kept["sensor_kind"] == "adsb").to_numpy(bool)
    sil = (pd.to_numeric(kept["sil"], errors="coerce").to_numpy(float) if "sil" in kept
           else np.full(len(kept), np.nan))
    low = adsb & (sil < gates.min_sil)
    counts["sil_below_min"] = int(low.sum())
    counts["sil_missing_kept"] = int((adsb & np.isnan(sil)).sum())
    return kept[~low].reset_index(drop=True), counts


def reference_at(reports: pd.DataFrame, reference: pd.DataFrame, column: str,
                 parameters: Mapping | None) -> np.ndarray:
    """Per associated report (``ref_index`` as reference.associate gives it), a numeric reference column
    interpolated linearly at the report's time; NaN where not associated, outside the reference's stretches
    (the reference_max_gap_s rule) or where the reference lacks the column."""
    out = np.full(len(reports), np.nan)
    ref, trajs = checked_trajectories(reference)
    if column not in ref.columns:
        return out
    max_gap_s = float(parameter(parameters, "reference_max_gap_s", DEFAULT_REFERENCE_GAP_S))
    values = pd.to_numeric(ref[column], errors="coerce").to_numpy(float)
    t = reports["t_s"].to_numpy(float)
    idx = reports["ref_index"].to_numpy()
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if not rows.size:
            continue
        v = values[tr.rows]
        i = np.searchsorted(tr.t_s, t[rows], side="right") - 1
        j = np.clip(i, 0, max(tr.t_s.size - 2, 0))
        k1 = np.minimum(j + 1, tr.t_s.size - 1)
        span = tr.t_s[k1] - tr.t_s[j]
        w = np.where(span > 0, (t[rows] - tr.t_s[j]) / np.where(span > 0, span, 1.0), 0.0)
        exact = (i >= 0) & (t[rows] == tr.t_s[np.clip(i, 0, tr.t_s.size - 1)])
        ok = ((i >= 0) & (i < tr.t_s.size - 1) & (span <= max_gap_s)) | exact
        out[rows] = np.where(ok, v[j] + w * (v[k1] - v[j]), np.nan)
        out[rows[exact]] = v[np.clip(i, 0, tr.t_s.size - 1)][exact]
    return out


def self_referenced(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None) -> np.ndarray:
    """Per associated report, True where either reference sample around the report's time is a
    self-reference row (``self_reference`` True); False otherwise, and where the reference has no flag."""
    if "self_reference" not in reference.columns:
        return np.zeros(len(reports), bool)
    # the flag read as numbers by reference_at (True 1, False 0), on the reference's own trajectories:
    # a copy of the frame with the flag as floats was checked and cut again for every sensor
    with np.errstate(invalid="ignore"):
        return np.nan_to_num(reference_at(reports, reference, "self_reference", parameters), nan=0.0) > 0.0


SELF_REFERENCE = "self-reference"  # opens every note that counts what rests on the sensor's own track


def own_track_words(own: int, total: int, what: str = "trials") -> str:
    """The note of a row of which ``own`` of ``total`` trials were judged against the sensor's own track;
    '' when none."""
    if not own:
        return ""
    return (f"{SELF_REFERENCE}: {own:,} of {total:,} {what} judged against the sensor's own track (no other "
            "sensor saw their aircraft then)")


def own_by_address(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None) -> np.ndarray:
    """Per associated report, whether it lies on the sensor's own track of an aircraft known by its Mode S
    address: that track is keyed by the address the sensor reports, so its address cannot be judged there."""
    own = self_referenced(reports, reference, parameters)
    if not own.any() or "ref_aircraft" not in reports.columns:
        return own & False
    return own & known_by_address(reports["ref_aircraft"].to_numpy(object))


def independent_reference(reference: pd.DataFrame) -> pd.DataFrame:
    """The reference without its self-reference rows: what position accuracy may be judged against."""
    if "self_reference" not in reference.columns:
        return reference
    return reference[~reference["self_reference"].astype(bool).to_numpy()]


@dataclass(frozen=True)
class SigmaGate:
    """Which reports are judged (a boolean per report, in the reports' order) and the counts of
    SIGMA_GATE_KEYS: every report falls in exactly one of judged, no_reference, self_reference,
    sigma_unknown and sigma_too_large."""

    judged: np.ndarray
    counts: dict[str, int]


def sigma_gate(reports: pd.DataFrame, reference: pd.DataFrame, tolerance_m: float,
               parameters: Mapping | None = None, *, independent: bool = True) -> SigmaGate:
    """The reports a position requirement with this tolerance (m) may judge: associated with a reference
    aircraft, on an independent reference (not a self-reference row) when ``independent`` (position
    accuracy: a sensor never judges itself), and with the reference's ``sigma_m`` known and below
    ``sigma_fraction`` (parameter, default DEFAULT_SIGMA_FRACTION) of the tolerance."""
    if not np.isfinite(tolerance_m) or tolerance_m <= 0:
        raise ValueError(f"sigma gate: tolerance {tolerance_m!r} m must be a positive number")
    fraction = float(parameter(parameters, "sigma_fraction", DEFAULT_SIGMA_FRACTION))
    if not 0.0 < fraction:
        raise ValueError(f"sigma gate: sigma_fraction {fraction!r} must be above 0")
    rep = associated(reports, reference, parameters)
    n = len(rep)
    linked = rep["ref_index"].to_numpy() >= 0
    sigma = reference_at(rep, reference, "sigma_m", parameters)
    own = self_referenced(rep, reference, parameters) & linked if independent else np.zeros(n, bool)
    unknown = linked & ~own & np.isnan(sigma)
    with np.errstate(invalid="ignore"):
        large = linked & ~own & ~unknown & ~(sigma < fraction * tolerance_m)
    judged = linked & ~own & ~unknown & ~large
    counts = {"reports": n, "judged": int(judged.sum()), "no_reference": int((~linked).sum()),
              "self_reference": int(own.sum()), "sigma_unknown": int(unknown.sum()),
              "sigma_too_large": int(large.sum())}
    return SigmaGate(judged, counts)
