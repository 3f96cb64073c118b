"""The real-data gap experiment: delete stretches of real ADS-B tracks, predict through them, score.

Shared by tests/test_track_validation.py (small) and benchmarks/track_validation.py (full)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd

from msdc.pipeline.track import Plane, TrackerConfig, nacp_covariance
from msdc.pipeline.track.noise import (
    KT_PER_M_S,
    MIN_AIRCRAFT_RESIDUALS,
    SURFACE_SPEED_KT,
    aircraft_tail,
    along_across,
    fit_timing,
    ground_velocity,
    plane_forms,
    plane_residuals,
    variance_ratio,
)
from msdc.pipeline.track.plane import estimate, filter_plane

# ../shared beside the checkout, as the other tests; MSDC_SHARED overrides it (worktrees elsewhere)
SHARED = Path(os.environ.get("MSDC_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))
REAL = SHARED / "real" / "adsb_v023_160510-lebl-220001.ast"
GAP_BINS = [(5, 15), (15, 30), (30, 45), (45, 60)]


def load_real_adsb(min_span_s: float = 600.0) -> list[dict] | None:
    """Airborne CAT021 tracks per address: t (s), plane e/n (m), isotropic variance from the 0.23 FOM
    position accuracy read as NACp, and the reported ground vector in the plane (ve, vn m/s; NaN where
    the report has none); None when the recording is absent."""
    if not REAL.exists():
        return None
    import msdc.asterix as asterix

    frame = asterix.read(REAL, editions={21: "0.23"}).frames[21]
    frame = frame[(frame["gbs"] == 0) & frame["latitude"].notna() & frame["address"].notna()]
    frame = frame.assign(t=frame["day"].astype(float) * 86400.0 + frame["time_of_day"].astype(float),
                         var=nacp_covariance(frame["fom_pa"].astype(float)))
    frame = frame[np.isfinite(frame["var"])]
    tracks = []
    for address, g in frame.groupby("address", observed=True):
        g = g.sort_values("t").drop_duplicates("t")
        if len(g) < 100 or g["t"].iloc[-1] - g["t"].iloc[0] < min_span_s:
            continue
        plane = Plane.around(g["latitude"].to_numpy(), g["longitude"].to_numpy())
        e, n = plane.forward(g["latitude"].to_numpy(), g["longitude"].to_numpy())
        t, var = g["t"].to_numpy(), g["var"].to_numpy()
        speed = g["ground_speed_kt"].to_numpy(float) / KT_PER_M_S
        angle = np.radians(g["track_angle_deg"].to_numpy(float))
        m = plane.local_to_plane(g["latitude"].to_numpy(), g["longitude"].to_numpy())
        v = np.einsum("nij,nj->ni", m, np.stack([speed * np.sin(angle), speed * np.cos(angle)], -1))
        near = np.hypot(e, n) < 1_000_000.0  # a few reports carry garbage positions far away
        t, e, n, var, v = t[near], e[near], n[near], var[near], v[near]
        # position jumps are not truth: drop what the tracker gates on the complete track
        run = filter_plane(TrackerConfig(), t, e, n, var, np.zeros(len(t)), var)
        ok = run.accepted & (run.segment == np.bincount(run.segment).argmax())
        tracks.append({"address": str(address), "t": t[ok], "e": e[ok], "n": n[ok], "var": var[ok],
                       "ve": v[ok, 0], "vn": v[ok, 1], "jumps": int((~run.accepted).sum())})
    return tracks


def _velocity(t, ve, vn) -> np.ndarray:
    """Each report's ground vector, else the last one at most VELOCITY_HOLD_S earlier, else zero
    (pipeline.track.noise.ground_velocity on one track's plane vectors)."""
    frame = pd.DataFrame({"time": pd.to_datetime(t, unit="s", utc=True), "sensor_id": "adsb",
                          "sensor_kind": "adsb", "aircraft_id": "a",
                          "ground_speed_kt": np.hypot(ve, vn) * KT_PER_M_S,
                          "heading_deg": np.degrees(np.arctan2(ve, vn))})
    return ground_velocity(frame)


def _covariances(var, var_t, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """cov_ee, cov_en, cov_nn of R = var I + var_t v v^T."""
    return var + var_t * v[:, 0] ** 2, var_t * v[:, 0] * v[:, 1], var + var_t * v[:, 1] ** 2


def gap_experiment(tracks, cfg: TrackerConfig, rng, repeats: int = 1, gaps_per_track: int = 6,
                   noise: str = "declared", passes: int = 6, timing: bool = False,
                   per_aircraft: bool = False) -> dict:
    """Mean (and `_median`) error (m) at the deleted reports, per gap-length bin: the IMM's forward
    prediction, its smoothed fill, holding the last report, and a straight line from the velocity over
    the last 10 s of reports. noise "estimate": before the scored pass, the ADS-B sigma is rescaled per
    declared (FOM) level, pooled over the tracks, from the residuals of the reports the tracker keeps
    (pipeline.track.noise.variance_ratio, `passes` passes); the deleted reports are never used. The
    factors per level are in the result under "scales". timing: also an along-track timing term per
    level (pipeline.track.noise.fit_timing, ground vectors as ground_velocity from the kept reports),
    its sigma_t (s) per level under "timing". per_aircraft (with "estimate", isotropic): then the
    per-aircraft gate-share guard of pipeline.track.noise per track (MIN_AIRCRAFT_RESIDUALS), its sigma
    factors under "raised"."""
    rows = []
    scales_out, timing_out, raised_out = [], [], []
    for _ in range(repeats):
        cut = []
        for tr in tracks:
            t = tr["t"]
            removed = np.zeros(len(t), bool)
            gaps = []
            for _ in range(gaps_per_track):
                length = rng.uniform(5.0, 60.0)
                start = rng.uniform(t[0] + 60.0, t[-1] - length - 10.0)
                inside = (t >= start) & (t < start + length)
                # keep gaps apart: at least 30 s of reports between two deleted stretches
                near = (t >= start - 30.0) & (t < start + length + 30.0)
                if removed[near].any() or inside.sum() == 0:
                    continue
                removed |= inside
                gaps.append((start, length, inside))
            keep = ~removed
            velocity = (_velocity(t[keep], tr["ve"][keep], tr["vn"][keep]) if timing
                        else np.zeros((keep.sum(), 2)))
            cut.append((tr, keep, gaps, velocity))
        levels = np.unique(np.concatenate([tr["var"] for tr in tracks]))
        scale = dict.fromkeys(levels.tolist(), 1.0)
        var_t = dict.fromkeys(levels.tolist(), 0.0)
        if noise == "estimate":
            timed = None
            for _ in range(passes):
                q, lv, res_uw, hph_uw, speed = [], [], [], [], []
                for tr, keep, _, vk in cut:
                    lk = tr["var"][keep]
                    var = lk * np.array([scale[v] for v in lk])
                    cov = _covariances(var, np.array([var_t[v] for v in lk]), vk)
                    run = filter_plane(cfg, tr["t"][keep], tr["e"][keep], tr["n"][keep], *cov)
                    res, hph = plane_residuals(run, tr["e"][keep], tr["n"][keep])
                    q.append(plane_forms(run, tr["e"][keep], tr["n"][keep], *cov))
                    rot = along_across(vk)
                    res_uw.append(np.einsum("nij,nj->ni", rot, res))
                    hph_uw.append(rot @ hph @ np.swapaxes(rot, 1, 2))
                    speed.append(np.hypot(vk[:, 0], vk[:, 1]))
                    lv.append(lk)
                q, lv, speed = np.concatenate(q), np.concatenate(lv), np.concatenate(speed)
                res_uw, hph_uw = np.concatenate(res_uw), np.concatenate(hph_uw)
                fast = speed * KT_PER_M_S >= SURFACE_SPEED_KT
                if timed is None:
                    timed = {v: timing and (fast & (lv == v) & np.isfinite(q)).sum() >= 30 for v in scale}
                for v in scale:
                    sel = (lv == v) & np.isfinite(q)
                    if timed[v]:
                        s2, var_t[v] = fit_timing(res_uw[sel], hph_uw[sel], speed[sel], scale[v] * v,
                                                  var_t[v])
                        scale[v] = s2 / v
                    elif sel.sum() >= 30:
                        scale[v] *= variance_ratio(q[sel], 2)
            scales_out.append({float(np.sqrt(v)): float(np.sqrt(s)) for v, s in scale.items()})
            timing_out.append({float(np.sqrt(v)): float(np.sqrt(s)) for v, s in var_t.items()})
        raised = np.ones(len(cut))
        if noise == "estimate" and per_aircraft and not timing:
            for _ in range(passes):
                moved = 0.0
                for i, (tr, keep, _, _) in enumerate(cut):
                    var = tr["var"][keep] * np.array([scale[v] for v in tr["var"][keep]]) * raised[i] ** 2
                    zeros = np.zeros(len(var))
                    run = filter_plane(cfg, tr["t"][keep], tr["e"][keep], tr["n"][keep], var, zeros, var)
                    q = plane_forms(run, tr["e"][keep], tr["n"][keep], var, zeros, var)
                    if np.isfinite(q).sum() >= MIN_AIRCRAFT_RESIDUALS:
                        new = max(raised[i], raised[i] * np.sqrt(aircraft_tail(q, 2)))
                        moved, raised[i] = max(moved, new / raised[i] - 1.0), new
                if moved <= 0.01:
                    break
            raised_out.append(raised.copy())
        for (tr, keep, gaps, vk), k in zip(cut, raised, strict=True):
            t, e, n = tr["t"], tr["e"], tr["n"]
            lk = tr["var"][keep]
            cov = _covariances(lk * np.array([scale[v] for v in lk]) * k**2, np.array([var_t[v] for v in lk]),
                               vk)
            run = filter_plane(cfg, t[keep], e[keep], n[keep], *cov)
            tk, ek, nk = t[keep], e[keep], n[keep]
            for _, length, inside in gaps:
                tm = t[inside]
                fwd = estimate(run, tm)
                smo = estimate(run, tm, smooth=True)
                k = np.searchsorted(tk, tm[0]) - 1
                j = np.searchsorted(tk, tk[k] - 10.0)
                dt = max(tk[k] - tk[j], 1e-9)
                v = (np.array([ek[k] - ek[j], nk[k] - nk[j]]) / dt) if k > j else np.zeros(2)
                for i, ti in enumerate(tm):
                    z = np.array([e[inside][i], n[inside][i]])
                    rows.append({"gap_s": length,
                                 "imm": np.hypot(*(fwd.x[i, [0, 3]] - z)),
                                 "smoothed": np.hypot(*(smo.x[i, [0, 3]] - z)),
                                 "hold": np.hypot(ek[k] - z[0], nk[k] - z[1]),
                                 "line": np.hypot(*(np.array([ek[k], nk[k]]) + v * (ti - tk[k]) - z))})
    df = pd.DataFrame(rows)
    out = {}
    for lo, hi in GAP_BINS:
        sel = df[(df.gap_s >= lo) & (df.gap_s < hi)]
        means = {c: sel[c].mean() for c in ("imm", "smoothed", "hold", "line")}
        medians = {f"{c}_median": sel[c].median() for c in ("imm", "smoothed", "hold", "line")}
        out[f"{lo}-{hi} s"] = {"n": len(sel), **means, **medians}
    if scales_out:
        out["scales"] = scales_out
    if timing_out and timing:
        out["timing"] = timing_out
    if raised_out:
        out["raised"] = raised_out
    return out
