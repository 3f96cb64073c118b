"""Tracker validations against the published scenarios (../shared/tracking.md), full Monte Carlo.

    python benchmarks/track_validation.py [tpm-sweep] [tpm-radars] [robust] [vts] [real] [smoothing]
        [tpm-real] [--runs 100] [--seed 2026]

tpm-sweep: dynamic-TPM paper (a), radar A alone, scan T 2..12 s, fixed p swept, optimal p vs T fitted.
tpm-radars: (b), radars A, B, C, the paper's filter and the default one; fixed 0.90/0.95/0.98 against
dynamic and expm, overall, at the manoeuvre peaks (maximum of the Monte Carlo RMS curve) and over each
manoeuvre, and each law minus fixed 0.95 with its paired bootstrap standard error. robust: robust-IMM
paper's six cases under four readings of what it leaves open (ROBUST_READINGS), raw vs filtered with
and without Poisson data loss, then coasted estimate vs holding the last report by time since it.
vts: CV Kalman, CA Kalman, IMM(CV, CV)
and IMM(CV, CA) on a radar-only manoeuvring track. real: the real CAT021 recording, random 5-60 s
stretches deleted and predicted through (ADS-B noise declared, estimated isotropic, estimated with the
along-track timing term). smoothing: the forward filter, the RTS pass on the combined
estimate and the IMM (two-filter) smoother on the 3-radar scenario and the VTS track. tpm-real: the real
recording's gap experiment for a few transition laws.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import fixtures.track_scenarios as sc  # noqa: E402
from msdc.pipeline.track import Mode, TrackerConfig, default_modes  # noqa: E402
from msdc.pipeline.track.plane import estimate, filter_plane  # noqa: E402

WARMUP_S = 30.0
PAPER_MODES = default_modes(3.0, sigma_cv_mps2=0.1, sigma_ct_mps2=0.5)  # the dynamic-TPM paper's filter


def _run(cfg, p):
    return filter_plane(cfg, p.t, p.e, p.n, p.ree, p.ren, p.rnn)


def tpm_sweep(runs: int, rng) -> None:
    truth = sc.tpm_paper_truth()
    site, _, phase, _ = sc.TPM_PAPER_RADARS[0]
    ps = np.round(np.arange(0.80, 0.9951, 0.005), 3)
    optima = []
    print("\n(a) radar A alone, scan period T, fixed p swept; time-averaged RMS position error (m), "
          f"{runs} runs, no gate (as in the paper)")
    for period in (2.0, 4.0, 6.0, 8.0, 10.0, 12.0):
        plots = [sc.rotating_radar(truth, site, period, phase, 1.0, 70.0, 0.08, rng) for _ in range(runs)]
        rms = []
        for p in ps:
            cfg = TrackerConfig(modes=PAPER_MODES, tpm=f"fixed:{p}", gate_probability=1.0)
            sq = []
            for pl in plots:
                est = estimate(_run(cfg, pl), pl.t)
                e, n = truth.at(pl.t)
                keep = pl.t > WARMUP_S
                sq.append(((est.x[:, 0] - e) ** 2 + (est.x[:, 3] - n) ** 2)[keep])
            rms.append(np.sqrt(np.mean(np.concatenate(sq))))
        rms = np.array(rms)
        best = ps[np.argmin(rms)]
        optima.append(best)
        show = {p: r for p, r in zip(ps, rms, strict=True) if p in (0.8, 0.9, 0.95, 0.98, 0.99, 0.995)}
        print(f"  T={period:4.1f} s: optimal p={best:.3f} (RMS {rms.min():.1f} m); "
              + ", ".join(f"p={p}: {r:.1f}" for p, r in show.items()))
    periods = np.array([2.0, 4.0, 6.0, 8.0, 10.0, 12.0])
    slope, intercept = np.polyfit(periods, optima, 1)
    print(f"  line fitted to the optima: p(T) = {intercept:.4f} {slope:+.4f} T  (paper: 1.0019 - 0.0050 T; "
          "target slope -0.008..-0.002)")


# fixed p, the paper's law and our fit of (a), and expm: expm:86 and expm:42 switch as often as fixed 0.95 and
# 0.90 at the mean plot interval (exp(-4.4/86) = 0.95), so they isolate the effect of the time dependence;
# dynamic:1.0,0.012, expm:82,45 and expm:82,20 were chosen on seeds 1 and 2 (docs/tracker.md), not on the
# seeds reported
TPM_SPECS = ["fixed:0.9", "fixed:0.95", "fixed:0.98", "dynamic", "dynamic:0.9937,0.0067", "dynamic:1.0,0.012",
             "expm:200", "expm:86", "expm:42", "expm:150,20", "expm:82,45", "expm:82,20"]
TPM_REFERENCE = "fixed:0.95"  # the best fixed p overall (of 0.90, 0.95, 0.98) on every seed tried
TPM_FILTERS = {"the paper's filter (CV 0.1, CT 0.5 m/s^2)": PAPER_MODES,
               "the default filter (CV 0.5, CT 1.0 m/s^2)": default_modes()}
BOOTSTRAP = 1000


def _tpm_summary(sq: np.ndarray, counts: np.ndarray, windows: list[np.ndarray]):
    """sq (B, bins) squared-error sums and counts (B, bins), one row per (resampled) set of runs -> overall
    RMS (B,), peak (B, manoeuvres: maximum of the RMS curve in the window) and RMS over each window."""
    curve = np.sqrt(np.where(counts > 0, sq / np.maximum(counts, 1e-12), np.nan))
    overall = np.sqrt(sq.sum(1) / counts.sum(1))
    peaks = np.stack([np.nanmax(curve[:, w], axis=1) for w in windows], 1)
    spans = np.stack([np.sqrt(sq[:, w].sum(1) / counts[:, w].sum(1)) for w in windows], 1)
    return overall, peaks, spans


def tpm_radars(runs: int, rng) -> None:
    """(b): per filter and tpm, the Monte Carlo RMS curve against time (squared errors of every run pooled per
    1 s bin), its mean over the run (overall), its maximum in each manoeuvre (+30 s: the paper's Fig. 5
    peaks) and the RMS over each manoeuvre (+30 s); then each tpm's difference from TPM_REFERENCE with the
    standard error of a paired bootstrap over the runs (every tpm filters the same plots)."""
    truth = sc.tpm_paper_truth()
    grid = np.arange(WARMUP_S, truth.t[-1], 1.0)
    nb = len(grid)
    radars = sc.TPM_PAPER_RADARS
    plots = [sc.merge(*[sc.rotating_radar(truth, site, period, phase, pd, 70.0, 0.08, rng, sensor=i)
                        for i, (site, period, phase, pd) in enumerate(radars)]) for _ in range(runs)]
    resample = rng.multinomial(runs, np.full(runs, 1.0 / runs), size=BOOTSTRAP).astype(float)
    windows = [(grid >= a) & (grid <= b + 30) for a, b in sc.TPM_PAPER_MANOEUVRES_S]
    spans_s = " ".join(f"{a:>4d}-{b}s" for a, b in sc.TPM_PAPER_MANOEUVRES_S)
    e_g, n_g = truth.at(grid)
    for filter_label, modes in TPM_FILTERS.items():
        sums = {label: {s: np.zeros((runs, nb)) for s in TPM_SPECS} for label in ("plots", "grid")}
        counts = {"plots": np.zeros((runs, nb)), "grid": np.ones((runs, nb))}
        for k, p in enumerate(plots):
            keep = p.t >= WARMUP_S
            idx = np.clip(np.round(p.t[keep] - WARMUP_S).astype(int), 0, nb - 1)
            np.add.at(counts["plots"][k], idx, 1.0)
            ep, np_ = truth.at(p.t[keep])
            for s in TPM_SPECS:
                run = _run(TrackerConfig(modes=modes, tpm=s, gate_probability=1.0), p)
                est = estimate(run, grid)
                sums["grid"][s][k] = (est.x[:, 0] - e_g) ** 2 + (est.x[:, 3] - n_g) ** 2
                est = estimate(run, p.t[keep])
                np.add.at(sums["plots"][s][k], idx, (est.x[:, 0] - ep) ** 2 + (est.x[:, 3] - np_) ** 2)
        for label, title in (("plots", "filtered, at the plots"),
                             ("grid", "on a 1 s grid, predicted between plots")):
            c = counts[label]
            print(f"\n(b) radars A, B, C (mean plot interval 4.4 s), {filter_label}, {runs} runs, RMS "
                  f"position error (m) {title}:\n  overall | peak = max of the RMS curve in each manoeuvre "
                  "(+30 s) | RMS over each manoeuvre (+30 s)")
            print(f"  tpm                   overall | {spans_s} | {spans_s}")
            ref = {}
            for s in TPM_SPECS:
                d = sums[label][s]
                o, pk, sp = _tpm_summary(d.sum(0, keepdims=True), c.sum(0, keepdims=True), windows)
                ref[s] = (np.concatenate([o, pk[0]]),
                          np.column_stack(_tpm_summary(resample @ d, resample @ c, windows)[:2]))
                print(f"  {s:21s} {o[0]:7.1f} | " + " ".join(f"{v:9.1f}" for v in pk[0])
                      + " | " + " ".join(f"{v:9.1f}" for v in sp[0]))
            print(f"  minus {TPM_REFERENCE} (overall | peaks), +- paired bootstrap SE over the runs; "
                  "'=' marks a tie (|difference| <= 2 SE)")
            base, base_b = ref[TPM_REFERENCE]
            for s in TPM_SPECS:
                if s == TPM_REFERENCE:
                    continue
                diff = ref[s][0] - base
                se = (ref[s][1] - base_b).std(axis=0)
                cells = [f"{v:+6.1f}+-{e:3.1f}{'=' if abs(v) <= 2 * e else ' '}"
                         for v, e in zip(diff, se, strict=True)]
                print(f"  {s:21s} {cells[0]} | " + " ".join(cells[1:]))


VTS_LEGS = [(300, 0, 0), (20, 4.0, 0), (40, 0, 1.0), (20, -4.0, 0), (200, 0, 0)]
VTS_MANOEUVRE_S = (300, 380)


def vts_truth():
    """The radar-only aircraft version of the VTS protocol (tracking.md 5.3 V3); our kinematics."""
    return sc.fly((-20000.0, 25000.0), 90.0, 120.0, VTS_LEGS, dt=0.01)


def smoothing(runs: int, rng) -> None:
    """Forward filter, RTS on the combined estimate and the IMM (two-filter) smoother, on the 3-radar
    scenario and the VTS track (1 s grid), RMS straight / in the manoeuvres (+30 s) and the worst second."""
    cases = {
        "radars A, B, C, default tracker": (sc.tpm_paper_truth(), sc.TPM_PAPER_MANOEUVRES_S, TrackerConfig(),
                                            lambda truth: sc.merge(*[
                                                sc.rotating_radar(truth, site, period, phase, pd, 70.0, 0.08,
                                                                  rng, sensor=i)
                                                for i, (site, period, phase, pd) in
                                                enumerate(sc.TPM_PAPER_RADARS)])),
        "radars A, B, C, paper's filter (CV 0.1, CT 0.5)": (
            sc.tpm_paper_truth(), sc.TPM_PAPER_MANOEUVRES_S, TrackerConfig(modes=PAPER_MODES), None),
        "VTS track, IMM(CV 0.1, CA 3.0)": (
            vts_truth(), [VTS_MANOEUVRE_S],
            TrackerConfig(modes=(Mode("cv", "cv", 0.1), Mode("ca", "ca", 3.0)), tpm="expm:200"),
            lambda truth: sc.rotating_radar(truth, (0.0, 0.0), 4.0, 0.0, 1.0, 70.0, 0.08, rng)),
        "VTS track, default tracker": (vts_truth(), [VTS_MANOEUVRE_S], TrackerConfig(), None),
    }
    print(f"\nsmoothing, {runs} runs per case: RMS position error (m) on a 1 s grid, straight legs / "
          "manoeuvres (+30 s) / worst second of the RMS curve")
    last_plots = None
    for label, (truth, manoeuvres, cfg, make) in cases.items():
        grid = np.arange(WARMUP_S, truth.t[-1] - 30.0, 1.0)
        man = np.zeros(len(grid), bool)
        for a, b in manoeuvres:
            man |= (grid >= a) & (grid <= b + 30)
        e, n = truth.at(grid)
        out = {"forward": [], "RTS": [], "IMM": []}
        plots = [make(truth) for _ in range(runs)] if make is not None else last_plots
        last_plots = plots
        for p in plots:
            run = _run(cfg, p)
            for name, kw in (("forward", {}), ("RTS", {"smooth": True}),
                             ("IMM", {"smooth": True, "smoother": "imm"})):
                est = estimate(run, grid, **kw)
                out[name].append((est.x[:, 0] - e) ** 2 + (est.x[:, 3] - n) ** 2)
        print(f"  {label}")
        for name, data in out.items():
            d = np.array(data)
            print(f"    {name:10s} straight {np.sqrt(d[:, ~man].mean()):7.1f}  manoeuvre "
                  f"{np.sqrt(d[:, man].mean()):7.1f}  worst {np.sqrt(d.mean(axis=0)).max():7.1f}")


# kinematics (speed m/s, along-track acceleration m/s^2, turn rate deg/s): ours, the paper gives none
KIN_AIRPORT = (40.0, 1.0, 3.0)
KIN_10NM = (90.0, 1.0, 3.0)
KIN_ENROUTE = (220.0, 0.5, 1.5)  # rate one at 430 kt needs ~50 deg of bank; at 25-30 deg: 1.2-1.5 deg/s
KIN_TAXI = (10.0, 0.5, 3.0)  # 20 kt straight taxi; +0.5 m/s^2 for 10 s ends at 29 kt, still a taxi speed


def _robust_truth(kind: str, kin: tuple[float, float, float]):
    """The robust-IMM paper's leg sequences (10 s legs, 1 Hz): scenario 1 (ADS-B) or 2/3 (MLAT, WAM),
    flown at kin = (speed m/s, along-track acceleration m/s^2, turn rate deg/s)."""
    speed, accel, rate = kin
    if kind == "adsb":
        legs = [(10, 0, 0), (10, 0, accel), (10, 0, -accel), (10, rate, 0), (10, 0, accel),
                (10, 0, -accel), (10, -rate, 0), (10, 0, 0), (10, 0, accel), (10, 0, -accel)]
    else:
        legs = [(10, 0, accel), (10, 0, -accel), (10, rate, 0), (10, 0, 0), (10, -rate, 0), (10, 0, 0)]
    return sc.fly((0.0, 0.0), 90.0, speed, legs, dt=0.01)


def _losses(t, rate, max_len_s, rng):
    """Samples lost to a Poisson process: losses start at `rate` per second, each 1..max_len_s samples long;
    the first three samples are kept (the track must start)."""
    lost = np.zeros(len(t), bool)
    s = rng.exponential(1.0 / rate)
    while s < t[-1]:
        lost[(t >= s) & (t < s + rng.integers(1, max_len_s + 1))] = True
        s += rng.exponential(1.0 / rate)
    lost[:3] = False
    return lost


ROBUST_CASES = [("ADS-B near airport", "adsb", "airport", 27.39, 1.8, 29.41, 12.58),
                ("ADS-B ~10 NM", "adsb", "10nm", 28.74, 4.0, 30.21, 13.80),
                ("ADS-B en route", "adsb", "enroute", 30.21, 6.4, 31.75, 14.58),
                ("MLAT near airport", "mlat", "airport", 4.30, 1.5, 4.30, 38.37),
                ("MLAT ~10 NM", "mlat", "10nm", 10.16, 2.0, 10.16, 20.86),
                ("WAM en route", "mlat", "enroute", 48.18, 7.5, 48.18, 15.06)]

# Readings of the paper's experiment: the kinematics of each case. Fixed in every reading (from the paper
# as summarised in tracking.md 2.2-2.4): 1 Hz; the leg sequences; error magnitude ~ N(Table 2 mean, std),
# uniform direction, white in time (randn added to the truth); CV, CA and turn models (our default modes +
# CA, process noise not tuned); R isotropic with the error's second moment (what --noise estimate tends
# to); improvement = (raw - filtered) / raw on the mean Euclidean error. The reasons were written down
# before any reading was run.
ROBUST_READINGS = [
    ("A", "regions are flight phases shared by every sensor (the benchmark's original reading): near the "
     "airport slow, 10 NM terminal, en route fast",
     {"ADS-B near airport": KIN_AIRPORT, "ADS-B ~10 NM": KIN_10NM, "ADS-B en route": KIN_ENROUTE,
      "MLAT near airport": KIN_AIRPORT, "MLAT ~10 NM": KIN_10NM, "WAM en route": KIN_ENROUTE}, False),
    ("B", "literal: the paper defines its scenarios by sensor (1 ADS-B, 2 MLAT, 3 WAM) and a region only "
     "picks Table 2's error; Table 3's ADS-B gains rise with the error (12.58 < 13.80 < 14.58), as one "
     "trajectory and one filter make them. Scenarios 1 and 2 in the terminal area (where ADS-B and both "
     "MLAT rows operate), scenario 3 en route (WAM at 200 km). Stated before running: by the gain-vs-noise "
     "property MLAT near (4.3 m) must gain less than MLAT 10 NM (10.16 m) on one trajectory",
     {"ADS-B near airport": KIN_10NM, "ADS-B ~10 NM": KIN_10NM, "ADS-B en route": KIN_10NM,
      "MLAT near airport": KIN_10NM, "MLAT ~10 NM": KIN_10NM, "WAM en route": KIN_ENROUTE}, False),
    ("C", "MLAT near the airport is surface movement: its 3-6 m is surface multilateration's accuracy "
     "(A-SMGCS, ED-117: 7.5 m on the manoeuvring area), 10-13 m at 20 km approach/wide-area MLAT; so "
     "scenario 2 near the airport is a taxiing aircraft (20 kt, 0.5 m/s^2 keeps it at taxi speed, turns "
     "3 deg/s kept); ADS-B near the airport stays airborne (27 m is not a surface accuracy); the rest as A",
     {"ADS-B near airport": KIN_AIRPORT, "ADS-B ~10 NM": KIN_10NM, "ADS-B en route": KIN_ENROUTE,
      "MLAT near airport": KIN_TAXI, "MLAT ~10 NM": KIN_10NM, "WAM en route": KIN_ENROUTE}, False),
    ("D", "the filter's R from Table 2's Std column (sigma = std per axis, e.g. 1.8 m for ADS-B near the "
     "airport): the paper gives each case a mean and a std and a Kalman filter takes a sigma, the only one "
     "it gives; no gate (the paper has none; the 99.9 % gate would reject most reports at this R). "
     "Kinematics of B (the literal reading). Noticed before running: Table 3's gain falls as mean/std "
     "rises (MLAT near 2.9: 38 %; ADS-B near 15: 12.6 %), so this reading was chosen from the paper's "
     "table, not only from its text",
     {"ADS-B near airport": KIN_10NM, "ADS-B ~10 NM": KIN_10NM, "ADS-B en route": KIN_10NM,
      "MLAT near airport": KIN_10NM, "MLAT ~10 NM": KIN_10NM, "WAM en route": KIN_ENROUTE}, True),
    ("D'", "D with A's kinematics (does D hinge on the trajectory?)",
     {"ADS-B near airport": KIN_AIRPORT, "ADS-B ~10 NM": KIN_10NM, "ADS-B en route": KIN_ENROUTE,
      "MLAT near airport": KIN_AIRPORT, "MLAT ~10 NM": KIN_10NM, "WAM en route": KIN_ENROUTE}, True),
]
ROBUST_LOSS_RATE, ROBUST_LOSS_MAX_S = 0.05, 5  # Table 3 under Poisson loss (tracking.md V2: 0.05-0.1/s)
HOLD_LOSS_RATE, HOLD_LOSS_MAX_S = 0.1, 10  # for coasted vs hold by time since the last report


def robust_config(r_from_std: bool = False):
    """The default tracker plus a CA mode (the paper's CV, CA and turn models); without the gate when R
    comes from Table 2's std (reading D)."""
    return TrackerConfig(modes=default_modes(with_ca=True), gate_probability=1.0 if r_from_std else 0.999)


def _sensor(truth, times, mean, std, rng, r_from_std: bool):
    """The paper's sensor; its declared covariance std^2 per axis when r_from_std (reading D)."""
    p = sc.position_sensor(truth, times, mean, std, rng)
    if r_from_std:
        p.ree[:] = std**2
        p.rnn[:] = std**2
    return p


def _robust_case(cfg, kind, kin, mean, std, runs, rng, r_from_std=False) -> dict:
    """Mean Euclidean errors (m) of one case: without loss (raw, filt); under Poisson loss at the received
    reports (raw_rx, filt_rx) and at every 1 Hz cycle (filt_all: coasted where lost; hold_all: the
    received report, or the last one held where lost)."""
    truth = _robust_truth(kind, kin)
    t = np.arange(0.0, truth.t[-1] + 1e-9, 1.0)
    e, n = truth.at(t)
    acc = {k: [] for k in ("raw", "filt", "raw_rx", "filt_rx", "filt_all", "hold_all")}
    for _ in range(runs):
        p = _sensor(truth, t, mean, std, rng, r_from_std)
        est = estimate(_run(cfg, p), t)
        acc["raw"].append(np.hypot(p.e - e, p.n - n))
        acc["filt"].append(np.hypot(est.x[:, 0] - e, est.x[:, 3] - n))
        lost = _losses(t, ROBUST_LOSS_RATE, ROBUST_LOSS_MAX_S, rng)
        q = _sensor(truth, t[~lost], mean, std, rng, r_from_std)
        est = estimate(_run(cfg, q), t)
        err = np.hypot(est.x[:, 0] - e, est.x[:, 3] - n)
        k = np.searchsorted(q.t, t, side="right") - 1
        hold = np.hypot(q.e[k] - e, q.n[k] - n)
        acc["raw_rx"].append(hold[~lost])
        acc["filt_rx"].append(err[~lost])
        acc["filt_all"].append(err)
        acc["hold_all"].append(hold)
    return {k: float(np.mean(np.concatenate(v))) for k, v in acc.items()}


def _coast_vs_hold(cfg, kind, kin, mean, std, runs, rng, r_from_std=False) -> dict:
    """Error at lost samples (Poisson losses), coasted IMM vs the last report held, by whole seconds since
    the last report: {age: (coasted mean, hold mean, samples)}."""
    truth = _robust_truth(kind, kin)
    t = np.arange(0.0, truth.t[-1] + 1e-9, 1.0)
    by_age: dict[int, list] = {}
    for _ in range(runs):
        lost = _losses(t, HOLD_LOSS_RATE, HOLD_LOSS_MAX_S, rng)
        p = _sensor(truth, t[~lost], mean, std, rng, r_from_std)
        tm = t[lost]
        est = estimate(_run(cfg, p), tm)
        e, n = truth.at(tm)
        k = np.searchsorted(p.t, tm) - 1
        hold = np.hypot(p.e[k] - e, p.n[k] - n)
        coast = np.hypot(est.x[:, 0] - e, est.x[:, 3] - n)
        for age, c, h in zip(np.rint(tm - p.t[k]).astype(int), coast, hold, strict=True):
            by_age.setdefault(int(age), []).append((c, h))
    return {a: (*np.mean(v, axis=0), len(v)) for a, v in sorted(by_age.items())}


def robust(runs: int, rng) -> None:
    cfg = robust_config()
    seed = int(rng.integers(2**62))  # every reading draws the same noise and losses (common random numbers)
    print(f"\nrobust IMM cases, {runs} runs each, 1 Hz, mean Euclidean position error (m); default modes "
          f"+ CA;\nunder loss: Poisson losses start at {ROBUST_LOSS_RATE}/s, each 1-{ROBUST_LOSS_MAX_S} s "
          "(the paper gives neither); rx = at the received reports; all = every 1 Hz cycle, coasted where "
          "lost,\nagainst the received reports' raw error (vs rx) and against raw with the last report held "
          "where lost (vs hold)")
    for label, reason, kins, r_from_std in ROBUST_READINGS:
        print(f"\n  reading {label}: {reason}")
        print("  case                kinematics       raw  filtered  improv. | loss: raw_rx filt_rx "
              "improv. | filt_all vs rx  hold_all vs hold | paper")
        gains = {}
        case_rng = np.random.default_rng(seed)
        for name, kind, _, mean, std, paper_raw, paper_imp in ROBUST_CASES:
            kin = kins[name]
            m = _robust_case(robust_config(r_from_std), kind, kin, mean, std, runs, case_rng, r_from_std)
            gains[name] = 100 * (m["raw"] - m["filt"]) / m["raw"]
            print(f"  {name:19s} {kin[0]:3.0f}/{kin[1]:.1f}/{kin[2]:.1f}  {m['raw']:6.2f}  {m['filt']:6.2f}  "
                  f"{gains[name]:6.2f} % | {m['raw_rx']:6.2f}  {m['filt_rx']:6.2f}  "
                  f"{100 * (m['raw_rx'] - m['filt_rx']) / m['raw_rx']:6.2f} % | {m['filt_all']:6.2f} "
                  f"{100 * (m['raw_rx'] - m['filt_all']) / m['raw_rx']:6.2f} %  {m['hold_all']:7.2f} "
                  f"{100 * (m['hold_all'] - m['filt_all']) / m['hold_all']:6.2f} % | "
                  f"{paper_raw}, {paper_imp} %")
        inside = all(10.0 <= g <= 40.0 for g in gains.values())
        top = max(gains, key=gains.get)
        print(f"    no loss: every case in 10-40 %: {'yes' if inside else 'no'}; largest: {top}")
    print("\n  ceiling with no manoeuvre: the same filter on a straight 60 s leg at constant speed (10 m/s), "
          "improvement %")
    case_rng = np.random.default_rng(seed)
    straight = sc.fly((0.0, 0.0), 90.0, 10.0, [(60, 0, 0)], dt=0.01)
    t = np.arange(0.0, 60.0 + 1e-9, 1.0)
    e, n = straight.at(t)
    cells = []
    for name, _, _, mean, std, _, _ in ROBUST_CASES:
        raw, filt = [], []
        for _ in range(runs):
            p = sc.position_sensor(straight, t, mean, std, case_rng)
            est = estimate(_run(cfg, p), t)
            raw.append(np.hypot(p.e - e, p.n - n))
            filt.append(np.hypot(est.x[:, 0] - e, est.x[:, 3] - n))
        cells.append(f"{name} ({mean:g} m) {100 * (1 - np.mean(filt) / np.mean(raw)):.1f}")
    print("    " + ", ".join(cells))
    print("\n  improvement against the sensor's error alone: ADS-B legs at 90 m/s (the 10 NM kinematics), "
          "the same filter,\n  error magnitude ~ N(mean, (0.1 mean)^2)")
    truth = _robust_truth("adsb", KIN_10NM)
    t = np.arange(0.0, truth.t[-1] + 1e-9, 1.0)
    cells = []
    for mean in (2.0, 4.3, 10.0, 20.0, 30.0, 48.0, 100.0):
        raw, filt = [], []
        for _ in range(runs):
            p = sc.position_sensor(truth, t, mean, 0.1 * mean, rng)
            est = estimate(_run(cfg, p), p.t)
            e, n = truth.at(p.t)
            raw.append(np.hypot(p.e - e, p.n - n))
            filt.append(np.hypot(est.x[:, 0] - e, est.x[:, 3] - n))
        cells.append(f"{mean:g} m: {100 * (1 - np.mean(filt) / np.mean(raw)):.1f} %")
    print("    " + ", ".join(cells))
    print(f"\n  Poisson data loss (losses start at {HOLD_LOSS_RATE}/s, each 1-{HOLD_LOSS_MAX_S} s), {runs} "
          "runs per case: error at the lost samples (m), coasted IMM / holding the last report,\n  by "
          "seconds since the last report; every case of every reading")
    seen = set()
    for label, _, kins, r_from_std in ROBUST_READINGS:
        for name, kind, _, mean, std, _, _ in ROBUST_CASES:
            if (name, kins[name], r_from_std) in seen:
                continue
            seen.add((name, kins[name], r_from_std))
            by_age = _coast_vs_hold(robust_config(r_from_std), kind, kins[name], mean, std, runs,
                                    np.random.default_rng(seed), r_from_std)
            worst = min((h - c, a) for a, (c, h, _) in by_age.items() if a >= 2)
            cells = "  ".join(f"{a} s {c:.1f}/{h:.1f}" for a, (c, h, _) in by_age.items()
                              if a in (1, 2, 3, 5, 10))
            print(f"    {label} {name:19s} {cells}  | coasted < hold at every age 2-{max(by_age)} s: "
                  f"{'yes' if worst[0] > 0 else 'no'} (closest at {worst[1]} s: {worst[0]:.1f} m; "
                  f"{sum(v[2] for v in by_age.values())} samples)")


def vts(runs: int, rng) -> None:
    truth = vts_truth()
    filters = {
        "CV Kalman": TrackerConfig(modes=(Mode("cv", "cv", 0.5),)),
        "CA Kalman": TrackerConfig(modes=(Mode("ca", "ca", 3.0),)),
        "IMM(CV,CV)": TrackerConfig(modes=(Mode("cv", "cv", 0.1), Mode("cv_high", "cv", 5.0)),
                                    tpm="expm:200"),
        "IMM(CV,CA)": TrackerConfig(modes=(Mode("cv", "cv", 0.1), Mode("ca", "ca", 3.0)), tpm="expm:200"),
    }
    man = VTS_MANOEUVRE_S
    stats = {k: {"straight": [], "man": [], "gated": 0, "restarts": 0} for k in filters}
    for _ in range(runs):
        p = sc.rotating_radar(truth, (0.0, 0.0), 4.0, 0.0, 1.0, 70.0, 0.08, rng)
        e, n = truth.at(p.t)
        for name, cfg in filters.items():
            run = _run(cfg, p)
            est = estimate(run, p.t)
            err2 = (est.x[:, 0] - e) ** 2 + (est.x[:, 3] - n) ** 2
            straight = (p.t > 60) & ((p.t < man[0]) | (p.t > man[1] + 60))
            stats[name]["straight"].append(err2[straight])
            stats[name]["man"].append(err2[(p.t >= man[0]) & (p.t <= man[1] + 60)])
            stats[name]["gated"] += int((run.status == 0).sum())
            stats[name]["restarts"] += int(run.segment.max())
    print(f"\nVTS comparison, radar-only aircraft (4 s scan, 70 m / 0.08 deg, 120 m/s, turn 4 deg/s, "
          f"1 m/s^2), {runs} runs; RMS position error (m)")
    print("  filter        straight  manoeuvre(+60 s)  gated reports  track restarts")
    for name, s in stats.items():
        print(f"  {name:12s} {np.sqrt(np.mean(np.concatenate(s['straight']))):9.1f} "
              f"{np.sqrt(np.mean(np.concatenate(s['man']))):16.1f} {s['gated']:14d} {s['restarts']:15d}")


def _gap_rows(res: dict) -> None:
    """One line per gap-length bin of a gap_experiment result."""
    for label, row in res.items():
        cells = "  ".join(f"{row[c]:7.1f} ({row[c + '_median']:6.1f})"
                          for c in ("imm", "smoothed", "hold", "line"))
        print(f"  {label:10s} {row['n']:8d}   {cells}")


def real(runs: int, rng) -> None:
    from fixtures.real_track_data import gap_experiment, load_real_adsb

    tracks = load_real_adsb()
    if tracks is None:
        print("\nreal: ../shared/real/adsb_v023_160510-lebl-220001.ast not found, skipped")
        return
    print(f"\nreal CAT021 (0.23) recording: {len(tracks)} airborne tracks; random 5-60 s stretches deleted, "
          "predicted through, scored against the deleted reports (m)")
    seed = int(rng.integers(2**32))
    for noise, timing, per_aircraft in (("declared", False, False), ("estimate", False, False),
                                        ("estimate", True, False), ("estimate", False, True)):
        # the same deleted stretches for each (the noise estimate draws no random numbers)
        res = gap_experiment(tracks, TrackerConfig(), np.random.default_rng(seed), repeats=runs // 10 + 1,
                             noise=noise, timing=timing, per_aircraft=per_aircraft)
        scales = res.pop("scales", None)
        sigma_t = res.pop("timing", None)
        raised = res.pop("raised", None)
        if raised is not None:  # the default guards surface classes only: these tracks are airborne
            lo = min((r[r > 1].min() for r in raised if (r > 1).any()), default=1.0)
            print("  noise estimate with the per-aircraft guard on these airborne tracks too: sigma raised "
                  "for " + ", ".join(f"{int((r > 1).sum())}" for r in raised) + " tracks per repeat, by x"
                  + f"{lo:.2f}-{max(r.max() for r in raised):.2f}")
            print("  gap length   reports   mean (median): IMM predicted   IMM smoothed     hold last        "
                  "straight line")
            _gap_rows(res)
            continue
        print(f"  noise {noise}" + (" with the timing term" if timing else "") + (
            "" if scales is None else ": declared sigma (m) -> estimated, per repeat: "
            + "; ".join(", ".join(f"{s:.1f} -> {s * k:.1f}" + (f" m, {t[s]:.3f} s" if t else "")
                                  for s, k in d.items())
                        for d, t in zip(scales, sigma_t or [None] * len(scales), strict=True))))
        print("  gap length   reports   mean (median): IMM predicted   IMM smoothed     hold last        "
              "straight line")
        _gap_rows(res)
    print("  fixed ADS-B sigma instead (same stretches), IMM predicted mean (median):")
    for sigma in (3.0, 7.5, 15.0, 30.0):
        fixed = [dict(tr, var=np.full(len(tr["var"]), sigma**2)) for tr in tracks]
        res = gap_experiment(fixed, TrackerConfig(), np.random.default_rng(seed), repeats=runs // 10 + 1)
        print(f"    {sigma:4.1f} m: " + "  ".join(f"{label} {row['imm']:6.1f} ({row['imm_median']:5.1f})"
                                             for label, row in res.items()))


TPM_REAL_SPECS = ["expm:150,20", "expm:82,45", "expm:82,20", "expm:86", "fixed:0.95"]


def tpm_real(runs: int, rng) -> None:
    """The real-data gap experiment (noise estimate) per transition law: what a law tuned on (b) does to
    predictions through 5-60 s gaps of 1 Hz ADS-B (the same deleted stretches for every law)."""
    from fixtures.real_track_data import gap_experiment, load_real_adsb

    tracks = load_real_adsb()
    if tracks is None:
        print("\ntpm-real: ../shared/real/adsb_v023_160510-lebl-220001.ast not found, skipped")
        return
    repeats = runs // 10 + 1
    print(f"\nreal CAT021 recording per tpm (default filter, noise estimate), {repeats} repeats: error (m) "
          "at the deleted reports, IMM predicted mean (median) | IMM smoothed mean")
    seed = int(rng.integers(2**32))
    for spec in TPM_REAL_SPECS:
        res = gap_experiment(tracks, TrackerConfig(tpm=spec), np.random.default_rng(seed), repeats=repeats,
                             noise="estimate")
        res.pop("scales", None)
        print(f"  {spec:13s} " + "  ".join(f"{label} {row['imm']:6.1f} ({row['imm_median']:5.1f}) | "
                                           f"{row['smoothed']:5.1f}" for label, row in res.items()))
    # the baselines do not depend on the law (the same deleted stretches)
    print("  straight line " + "  ".join(f"{label} {row['line']:6.1f} ({row['line_median']:5.1f}) |      "
                                          for label, row in res.items()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("parts", nargs="*",
                        default=["tpm-sweep", "tpm-radars", "robust", "vts", "real", "smoothing", "tpm-real"])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    # new parts go last: a part's random stream is its index in this order
    parts = {"tpm-sweep": tpm_sweep, "tpm-radars": tpm_radars, "robust": robust, "vts": vts, "real": real,
             "smoothing": smoothing, "tpm-real": tpm_real}
    names = list(parts)
    for part in args.parts:
        # each part its own stream, so a part's figures do not depend on which parts ran before it
        parts[part](args.runs, np.random.default_rng([args.seed, names.index(part)]))


if __name__ == "__main__":
    main()
