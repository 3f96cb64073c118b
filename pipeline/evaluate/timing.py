"""Time offsets between a sensor and its reference, seen in the position errors: a report stamped late or
early by dt lies speed * dt along the track. Fitted per aircraft, the offsets say whether an accuracy
figure measures the sensor's scatter or a clock: one sensor clock serves every aircraft, so offsets that
differ by aircraft are the reference's (an ADS-B transponder's latency), and one common offset belongs to
either side. The accuracy rows carry the finding as a note; it changes no value and no verdict."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.statistics import chi2_sf, inverse_variance

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


def _block_fits(group: np.ndarray, along_m: np.ndarray, speed_mps: np.ndarray, t_s: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per group (codes 0..k-1): the lead, its jackknife standard error over BLOCK_S blocks, the reports
    and the blocks, all groups at once (sums per block, each block left out of its group's in turn)."""
    k = int(group.max(initial=-1)) + 1
    number = np.floor(t_s / BLOCK_S).astype(np.int64)  # blocks on the clock's 10 s, whatever the row
    pair = group.astype(np.int64) * (1 << 32) + (number - (number.min() if number.size else 0))
    keys, block = np.unique(pair, return_inverse=True)
    owner = (keys >> 32).astype(np.int64)  # each block's group
    a, v = along_m, speed_mps
    sums = np.stack([np.bincount(block, weights=w, minlength=keys.size)
                     for w in (np.ones_like(a), v, a, v * v, v * a)])
    totals = np.stack([np.bincount(owner, weights=row, minlength=k) for row in sums])
    blocks = np.bincount(owner, minlength=k).astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        lead = _slope(*totals)
        left_out = _slope(*(totals[:, owner] - sums))
        finite = np.where(np.isfinite(left_out), left_out, 0.0)
        mean = np.bincount(owner, weights=finite, minlength=k) / blocks
        squares = np.bincount(owner, weights=(left_out - mean[owner]) ** 2, minlength=k)
        se = np.sqrt((blocks - 1) / blocks * squares)  # NaN where a left-out fit had no spread of speed
    few = blocks < MIN_BLOCKS
    return np.where(few, np.nan, lead), np.where(few, np.nan, se), totals[0], blocks


def fit_lead(along_m: np.ndarray, speed_mps: np.ndarray, t_s: np.ndarray | None = None) -> Offset:
    """along = offset + lead * speed + noise, by least squares: the constant offset takes what does not grow
    with speed (the two antennas' places on the aircraft, a bias), the lead what does (a clock). Successive
    errors are correlated, so the standard error is a jackknife over blocks of BLOCK_S (each left out in
    turn); NaN with fewer than MIN_BLOCKS blocks or no spread of speed."""
    a, v = np.asarray(along_m, float), np.asarray(speed_mps, float)
    t = np.arange(a.size) * BLOCK_S if t_s is None else np.asarray(t_s, float)
    lead, se, n, _ = _block_fits(np.zeros(a.size, np.int64), a, v, t)
    return Offset(float(lead[0]), float(se[0]), int(n[0]))


def aircraft_leads(errors: pd.DataFrame) -> pd.DataFrame:
    """Per aircraft with MIN_MOVING_REPORTS moving reports or more (``along_m`` and ``speed_mps`` finite) and
    a finite standard error: ``lead_s``, ``se_s``, ``n``; indexed by aircraft."""
    along, speed = errors["along_m"].to_numpy(float), errors["speed_mps"].to_numpy(float)
    moving = np.isfinite(along) & np.isfinite(speed)
    codes, names = pd.factorize(errors["aircraft"].astype(str).to_numpy()[moving], sort=True)
    lead, se, n, _ = _block_fits(codes, along[moving], speed[moving], errors["t_s"].to_numpy(float)[moving])
    keep = (n >= MIN_MOVING_REPORTS) & np.isfinite(se) & (se > 0)
    return pd.DataFrame({"lead_s": lead[keep], "se_s": se[keep], "n": n[keep].astype(int)},
                        index=pd.Index(np.asarray(names)[keep], dtype=object))


def _weighted(leads: pd.DataFrame, tau2: float = 0.0) -> tuple[float, float]:
    """The inverse-variance mean of the aircraft's leads and its standard error (``tau2``: the variance of
    the leads between aircraft, added to each one's)."""
    mean, se, _ = inverse_variance(leads["lead_s"], leads["se_s"], tau2)
    return mean, se


def _cochran_q(leads: pd.DataFrame) -> float:
    return inverse_variance(leads["lead_s"], leads["se_s"])[2]


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


def timing_note(errors: pd.DataFrame, limit_m: float | None = None, adsb: bool = False) -> str:
    """The accuracy rows' note on time offsets in ``errors`` (accuracy.position_errors), or '': aircraft
    whose offset stands out (how many of the errors beyond ``limit_m`` they hold; none: no note), else a
    common offset. With ``adsb`` (the sensor under test is ADS-B: a clock per aircraft) the outlying
    aircraft's offsets are the sensor's own, not the reference's."""
    leads = aircraft_leads(errors)
    if leads.empty:
        return ""
    late = outlying(leads)
    if late:
        mine = errors["aircraft"].astype(str).isin(late).to_numpy()
        held = ""
        if limit_m is not None:
            beyond = errors["error_m"].to_numpy(float) > limit_m
            if not (beyond & mine).any():  # they hold no error over the threshold: nothing to explain
                return ""
            held = (f", holding {int((beyond & mine).sum()):,} of the {int(beyond.sum()):,} errors over "
                    f"{limit_m:.3g} m")
        shown = ", ".join(f"{a} {leads.at[a, 'lead_s']:+.2f} s" for a in late[:6])
        more = f" and {len(late) - 6} more" if len(late) > 6 else ""
        rest, _ = _weighted(leads.drop(index=late))
        why = ("ADS-B under test: each aircraft's transponder has a latency of its own, so these are its "
               "reports' own errors" if adsb else "One sensor clock serves every aircraft: their reference "
               "is early or late (an ADS-B latency), and so are their errors along the track at speed")
        return (f"timing: {len(late)} of {len(leads)} aircraft lead or lag the reference unlike the others "
                f"({shown}{more}; the others {rest:+.2f} s){held}. {why}")
    if len(leads) < MIN_AIRCRAFT_COMMON:
        return ""
    common, se = common_lead(leads)
    if abs(common) >= COMMON_MATERIAL_S and abs(common) >= Z_SIGNIFICANT * se:
        return (f"timing: the reports {'lead' if common > 0 else 'lag'} the reference by {abs(common):.2f} s "
                f"(± {se:.2f} s, {len(leads)} aircraft) along the track: a time offset between sensor and "
                "reference, which of the two the data cannot say; the errors at speed hold it")
    return ""
