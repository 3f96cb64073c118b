"""Time offsets between a sensor and its reference, seen in the position errors: a report stamped late or
early by dt lies speed * dt along the track. Fitted per aircraft, the offsets say whether an accuracy
figure measures the sensor's scatter or a clock: one sensor clock serves every aircraft, so offsets that
differ by aircraft are the reference's (an ADS-B transponder's latency), and one common offset belongs to
either side. The accuracy rows carry the finding as a note; it changes no value and no verdict."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.statistics import chi2_sf

MIN_MOVING_REPORTS = 20  # an aircraft's offset is fitted from this many moving reports or more
BLOCK_S = 10.0  # successive errors are correlated: the standard error treats each 10 s as one draw
MIN_BLOCKS = 5  # ... and needs this many blocks
MATERIAL_S = 0.5  # an aircraft's offset this far from the others' is worth a note
COMMON_MATERIAL_S = 0.2  # a common offset this large is worth a note
MIN_AIRCRAFT_COMMON = 5  # ... when this many aircraft show it
Z_SIGNIFICANT = 3.0  # ... when this many standard errors from zero (common) or from the others (aircraft)
HETEROGENEITY_P = 1e-3  # the aircraft's offsets differ when Cochran's Q has a p-value below this


@dataclass(frozen=True)
class Offset:
    """A least-squares time offset (s; positive: the report leads the reference along its track)."""

    lead_s: float
    se_s: float
    n: int


def _slope(n, sv, sa, svv, sva):
    """The least-squares slope of a on v from the sums of 1, v, a, v*v and v*a."""
    return (sva - sv * sa / n) / (svv - sv * sv / n)


def fit_lead(along_m: np.ndarray, speed_mps: np.ndarray, t_s: np.ndarray | None = None) -> Offset:
    """along = offset + lead * speed + noise, by least squares: the constant offset takes what does not grow
    with speed (the two antennas' places on the aircraft, a bias), the lead what does (a clock). Successive
    errors are correlated, so the standard error is a jackknife over blocks of BLOCK_S (each left out in
    turn); NaN with fewer than MIN_BLOCKS blocks or no spread of speed."""
    a, v = np.asarray(along_m, float), np.asarray(speed_mps, float)
    t = np.arange(a.size) * BLOCK_S if t_s is None else np.asarray(t_s, float)
    blocks = np.unique(np.floor(t / BLOCK_S), return_inverse=True)[1]
    g = int(blocks.max(initial=-1)) + 1
    if g < MIN_BLOCKS or float(np.ptp(v)) <= 0:
        return Offset(np.nan, np.nan, int(a.size))
    sums = np.stack([np.bincount(blocks, weights=w, minlength=g)
                     for w in (np.ones_like(a), v, a, v * v, v * a)])
    lead = float(_slope(*sums.sum(axis=1)))
    with np.errstate(divide="ignore", invalid="ignore"):
        left_out = _slope(*(sums.sum(axis=1, keepdims=True) - sums))
    if not np.isfinite(left_out).all():  # a block holding every spread of speed: no jackknife
        return Offset(lead, np.nan, int(a.size))
    return Offset(lead, float(np.sqrt((g - 1) / g * np.sum((left_out - left_out.mean()) ** 2))), int(a.size))


def aircraft_leads(errors: pd.DataFrame) -> pd.DataFrame:
    """Per aircraft with MIN_MOVING_REPORTS moving reports or more (``along_m`` and ``speed_mps`` finite):
    ``lead_s``, ``se_s``, ``n``; indexed by aircraft."""
    moving = errors[np.isfinite(errors["along_m"].to_numpy(float))
                    & np.isfinite(errors["speed_mps"].to_numpy(float))]
    rows = {}
    for aircraft, g in moving.groupby(moving["aircraft"].astype(str), sort=True):
        if len(g) >= MIN_MOVING_REPORTS:
            fit = fit_lead(g["along_m"].to_numpy(float), g["speed_mps"].to_numpy(float),
                           g["t_s"].to_numpy(float))
            if np.isfinite(fit.se_s) and fit.se_s > 0:
                rows[aircraft] = (fit.lead_s, fit.se_s, fit.n)
    return pd.DataFrame.from_dict(rows, orient="index", columns=["lead_s", "se_s", "n"])


def _weighted(leads: pd.DataFrame, tau2: float = 0.0) -> tuple[float, float]:
    """The inverse-variance mean of the aircraft's leads and its standard error (``tau2``: the variance of
    the leads between aircraft, added to each one's)."""
    w = 1.0 / (leads["se_s"].to_numpy(float) ** 2 + tau2)
    return float(np.sum(w * leads["lead_s"].to_numpy(float)) / w.sum()), float(np.sqrt(1.0 / w.sum()))


def _cochran_q(leads: pd.DataFrame) -> float:
    mean, _ = _weighted(leads)
    return float(np.sum(((leads["lead_s"] - mean) / leads["se_s"]) ** 2))


def common_lead(leads: pd.DataFrame) -> tuple[float, float]:
    """The aircraft's common lead and its standard error, random effects (DerSimonian-Laird): where the
    aircraft differ more than their errors say, the mean is as uncertain as their spread."""
    w = 1.0 / leads["se_s"].to_numpy(float) ** 2
    tau2 = max(0.0, (_cochran_q(leads) - (len(leads) - 1)) / (w.sum() - np.sum(w * w) / w.sum()))
    return _weighted(leads, tau2)


def outlying(leads: pd.DataFrame) -> list[str]:
    """Aircraft whose lead lies MATERIAL_S or more and Z_SIGNIFICANT standard errors from the others'
    consensus (from their median, then the mean of those not flagged, until stable), a minority of them;
    [] when the leads are alike (Cochran's Q, HETEROGENEITY_P) or no majority agrees."""
    if len(leads) < 3 or chi2_sf(_cochran_q(leads), len(leads) - 1) >= HETEROGENEITY_P:
        return []
    lead, se = leads["lead_s"].to_numpy(float), leads["se_s"].to_numpy(float)
    consensus, flagged = float(np.median(lead)), None
    for _ in range(10):
        apart = np.abs(lead - consensus)
        now = (apart >= MATERIAL_S) & (apart >= Z_SIGNIFICANT * se)
        if 2 * now.sum() >= len(lead):
            return []
        if flagged is not None and (now == flagged).all():
            break
        flagged = now
        consensus, _ = _weighted(leads[~flagged])
    return list(leads.index[flagged])


def late_aircraft(errors: pd.DataFrame) -> list[str]:
    """The aircraft of ``errors`` (accuracy.position_errors) whose lead stands out (outlying)."""
    leads = aircraft_leads(errors)
    return outlying(leads) if len(leads) else []


def timing_note(errors: pd.DataFrame, limit_m: float | None = None) -> str:
    """The accuracy rows' note on time offsets in ``errors`` (accuracy.position_errors), or '': aircraft
    whose offset stands out (how many of the errors beyond ``limit_m`` they hold), else a common offset."""
    leads = aircraft_leads(errors)
    if leads.empty:
        return ""
    late = outlying(leads)
    if late:
        mine = errors["aircraft"].astype(str).isin(late).to_numpy()
        held = ""
        if limit_m is not None and (beyond := errors["error_m"].to_numpy(float) > limit_m).any():
            held = (f", holding {int((beyond & mine).sum()):,} of the {int(beyond.sum()):,} errors over "
                    f"{limit_m:.3g} m")
        shown = ", ".join(f"{a} {leads.at[a, 'lead_s']:+.2f} s" for a in late[:6])
        more = f" and {len(late) - 6} more" if len(late) > 6 else ""
        rest, _ = _weighted(leads.drop(index=late))
        return (f"timing: {len(late)} of {len(leads)} aircraft lead or lag the reference unlike the others "
                f"({shown}{more}; the others {rest:+.2f} s){held}. One sensor clock serves every aircraft: "
                "their reference is early or late (an ADS-B latency), and so are their errors along the "
                "track at speed")
    if len(leads) < MIN_AIRCRAFT_COMMON:
        return ""
    common, se = common_lead(leads)
    if abs(common) >= COMMON_MATERIAL_S and abs(common) >= Z_SIGNIFICANT * se:
        return (f"timing: the reports {'lead' if common > 0 else 'lag'} the reference by {abs(common):.2f} s "
                f"(± {se:.2f} s, {len(leads)} aircraft) along the track: a time offset between sensor and "
                "reference, which of the two the data cannot say; the errors at speed hold it")
    return ""
