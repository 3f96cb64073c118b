"""Calibration of the IMM prediction on the real ADS-B recording: predict each airborne track from many
start times to 20, 60 and 120 s ahead and score the predicted 95 % ellipse against what the aircraft
then reported.

Shared by tests/test_conflict_calibration.py (a few tracks) and benchmarks/conflict_calibration.py (all).
The tracker is run as `msdc conflicts` runs it (`track(...)` with the default configuration on the
measurement frame of the airborne CAT021 reports); the prediction is `propagate_state` of
pipeline/conflict/predict.py from the posterior after the last update at or before the start time, in
1 s cycles (the job's default step). The outcome is the aircraft's own accepted reports (the ones the
tracker did not gate as jumps), interpolated at exactly start + horizon.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import replace

import numpy as np
import pandas as pd
from real_track_data import REAL

from msdc.pipeline.conflict.calibration import chi2_2_ppf, interpolate_reports, mahalanobis2
from msdc.pipeline.conflict.predict import propagate_state
from msdc.pipeline.track import ImmState, track
from msdc.pipeline.track.tracker import MAX_RANGE_M

HORIZONS_S = (20.0, 60.0, 120.0)
D2_95 = chi2_2_ppf(0.95)  # 5.991


def load_real_tracks(max_aircraft: int | None = None, min_reports: int = 300, sigma_m: float | None = None):
    """Track the airborne CAT021 reports of the real recording as the conflict job does; returns
    (TrackResult with states, measurements) or None when the recording is absent. max_aircraft keeps
    the aircraft with the most airborne reports; sigma_m replaces every report's sigma per axis (m)."""
    if not REAL.exists():
        return None
    import msdc.asterix as asterix
    from msdc.pipeline.model.measurements import adsb_measurements, nacp_sigma_m

    frame = asterix.read(REAL, editions={21: "0.23"}).frames[21]
    frame = frame[(frame["gbs"] == 0) & frame["latitude"].notna() & frame["address"].notna()]
    meas = adsb_measurements(frame, date=dt.date(2016, 5, 10))
    # edition 0.23 carries no NACp: msdc gives such reports no covariance, so `msdc track` drops them.
    # As tests/real_track_data.py does, read the 0.23 figure of merit (PA, fom_pa) as NACp.
    var = nacp_sigma_m(meas["fom_pa"]) ** 2
    missing = ~np.isfinite(meas["cov_ee_m2"].to_numpy(float))
    meas.loc[missing, "cov_ee_m2"] = var[missing]
    meas.loc[missing, "cov_nn_m2"] = var[missing]
    meas.loc[missing, "cov_en_m2"] = np.where(np.isfinite(var[missing]), 0.0, np.nan)
    if sigma_m is not None:
        meas = meas.assign(cov_ee_m2=sigma_m**2, cov_en_m2=0.0, cov_nn_m2=sigma_m**2)
    finite = np.isfinite(meas[["cov_ee_m2", "cov_nn_m2"]].to_numpy(float)).all(axis=1)
    meas = meas[finite].drop_duplicates(["aircraft_id", "time"]).reset_index(drop=True)
    counts = meas["aircraft_id"].astype(str).value_counts()
    keep = counts[counts >= min_reports].index
    if max_aircraft is not None:
        keep = keep[:max_aircraft]
    meas = meas[meas["aircraft_id"].astype(str).isin(keep)].reset_index(drop=True)
    return track(meas, keep_states=True), meas


def _accepted_reports(result, meas: pd.DataFrame, aircraft_id: str):
    """(t, east, north) in the aircraft's plane of the reports its filter accepted, and the run."""
    own, run, epoch = result.runs[aircraft_id]
    g = meas[meas["aircraft_id"].astype(str) == aircraft_id]
    g = g.assign(_t=(g["time"] - epoch).dt.total_seconds().to_numpy()).sort_values(
        ["_t", "sensor_id"], kind="stable")
    e, n = own.forward(g["latitude"].to_numpy(float), g["longitude"].to_numpy(float))
    near = np.isfinite(e) & np.isfinite(n) & (np.hypot(e, n) < MAX_RANGE_M)
    t, e, n = g["_t"].to_numpy(float)[near], e[near], n[near]
    if len(t) != len(run.t) or not np.allclose(t, run.t):
        raise AssertionError(f"aircraft {aircraft_id}: reports do not line up with the filter run")
    ok = run.accepted
    return t[ok], e[ok], n[ok], run.segment[ok], run, own, epoch


def prediction_errors(result, meas: pd.DataFrame, *, every_s: float = 10.0, warmup_s: float = 60.0,
                      horizons_s=HORIZONS_S, args_for=None, max_gap_s: float = 5.0) -> pd.DataFrame:
    """One row per (aircraft, start time, horizon): the error of the predicted mean against the
    interpolated report (m), the predicted covariance, d2 (squared Mahalanobis distance), and the
    age of the posterior (s since the last update), and the change of the reported course over the
    horizon (deg: what the aircraft did). Start times: every every_s seconds, from warmup_s
    after the start of the track segment, at most max_coast_s after its last update. args_for(config)
    -> kernel args for the prediction (default: the tracker's own, `config.kernel_args()`)."""
    horizons = np.asarray(sorted(horizons_s), float)
    rows = []
    for aircraft_id in sorted(result.runs):
        t, e, n, seg, run, own, epoch = _accepted_reports(result, meas, aircraft_id)
        if len(t) < 2:
            continue
        args = run.config.kernel_args() if args_for is None else args_for(run.config)
        upd = np.flatnonzero(run.accepted)
        starts = np.arange(np.ceil((t[0] + warmup_s) / every_s) * every_s, t[-1] - horizons[0], every_s)
        for s in starts:
            i = upd[np.searchsorted(run.t[upd], s + 1e-9, side="right") - 1]
            # as the job: no track (so no prediction) beyond max_coast_s after the last update; none in
            # a segment's first warmup_s; outcomes only from the same segment (a restart after a jump
            # or a long gap is not the predicted aircraft's continuation)
            same = seg == run.segment[i]
            if s - run.t[i] > run.config.max_coast_s or s - t[same][0] < warmup_s:
                continue
            truth = interpolate_reports(t[same], e[same], n[same], s + horizons, max_gap_s)
            have = np.isfinite(truth[:, 0])
            if not have.any():
                continue
            state = ImmState(aircraft_id, None, own, run.config, run.mu[i], run.x[i], run.P[i])
            m, c = propagate_state(state, s - run.t[i] + horizons[have], 1.0, args=args)
            err = m[:, [0, 3]] - truth[have]
            cov = c[:, [[0, 0], [3, 3]], [[0, 3], [0, 3]]]
            d2 = mahalanobis2(err, cov)
            turn = _course_change(t[same], e[same], n[same], s, s + horizons[have], max_gap_s)
            for k, h in enumerate(horizons[have]):
                rows.append((aircraft_id, s, h, err[k, 0], err[k, 1], cov[k, 0, 0], cov[k, 0, 1],
                             cov[k, 1, 1], d2[k], s - run.t[i], turn[k]))
    return pd.DataFrame(rows, columns=["aircraft_id", "start_s", "horizon_s", "error_east_m", "error_north_m",
                                       "var_east_m2", "cov_east_north_m2", "var_north_m2", "d2", "age_s",
                                       "course_change_deg"])


def _course_change(t, e, n, start_s: float, ends_s: np.ndarray, max_gap_s: float, base_s: float = 5.0):
    """Absolute change (deg) of the reported course from start_s to each of ends_s, each course from the
    reports interpolated base_s apart (NaN where they cannot be)."""
    times = np.concatenate([[start_s - base_s, start_s], np.ravel([[x - base_s, x] for x in ends_s])])
    p = interpolate_reports(t, e, n, times, max_gap_s)
    d = p[1::2] - p[0::2]
    course = np.degrees(np.arctan2(d[:, 0], d[:, 1]))
    return np.abs((course[1:] - course[0] + 180.0) % 360.0 - 180.0)


def coverage_table(errors: pd.DataFrame) -> pd.DataFrame:
    """Per horizon: predictions, aircraft, share inside the 95 % ellipse, the median d2 (1.386 when
    calibrated), the RMS error and the RMS predicted 1-sigma radius (sqrt of the trace / 2), and the
    lowest and highest per-aircraft share."""
    out = []
    for h, g in errors.groupby("horizon_s"):
        inside = g["d2"] <= D2_95
        per = inside.groupby(g["aircraft_id"]).mean()
        out.append({"horizon_s": h, "n": len(g), "aircraft": g["aircraft_id"].nunique(),
                    "inside_95": inside.mean(), "median_d2": g["d2"].median(),
                    "rms_error_m": float(np.sqrt((g["error_east_m"] ** 2 + g["error_north_m"] ** 2).mean())),
                    "rms_sigma_m": float(np.sqrt(((g["var_east_m2"] + g["var_north_m2"]) / 2.0).mean())),
                    "per_aircraft_min": per.min(), "per_aircraft_max": per.max()})
    return pd.DataFrame(out)


def scaled_args(q_scale: float = 1.0, tpm: str | None = None):
    """args_for: the tracker's kernel args with every mode's process-noise variance times q_scale and,
    when given, another TPM for the prediction only."""
    def args_for(config):
        cfg = config if tpm is None else replace(config, tpm=tpm)
        args = cfg.kernel_args()
        args["qs"] = args["qs"] * q_scale
        return args
    return args_for
