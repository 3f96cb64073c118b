"""Small, seeded versions of the tracker validations (the full Monte Carlo is benchmarks/track_validation.py).

Every figure is scored against the simulator's truth or against reports withheld from the tracker."""

import numpy as np
import pytest

import fixtures.track_scenarios as sc
from fixtures.real_track_data import REAL, gap_experiment, load_real_adsb
from msdc.pipeline.track import Mode, TrackerConfig, default_modes
from msdc.pipeline.track.plane import estimate, filter_plane

PAPER_MODES = default_modes(3.0, sigma_cv_mps2=0.1, sigma_ct_mps2=0.5)


def _run(cfg, p):
    return filter_plane(cfg, p.t, p.e, p.n, p.ree, p.ren, p.rnn)


def _rms(cfg, plots, truth, after=30.0):
    sq = []
    for p in plots:
        est = estimate(_run(cfg, p), p.t)
        e, n = truth.at(p.t)
        sq.append(((est.x[:, 0] - e) ** 2 + (est.x[:, 3] - n) ** 2)[p.t > after])
    return np.sqrt(np.mean(np.concatenate(sq)))


def test_optimal_p_falls_as_the_scan_period_grows():
    # dynamic-TPM paper (a), radar A alone: the RMS-optimal fixed p is lower for a 12 s scan than a 2 s one
    rng = np.random.default_rng(11)
    truth = sc.tpm_paper_truth()
    site, _, phase, _ = sc.TPM_PAPER_RADARS[0]
    ps = [0.85, 0.9, 0.95, 0.98, 0.99]
    best = {}
    for period in (2.0, 12.0):
        plots = [sc.rotating_radar(truth, site, period, phase, 1.0, 70.0, 0.08, rng) for _ in range(8)]
        rms = [_rms(TrackerConfig(modes=PAPER_MODES, tpm=f"fixed:{p}", gate_probability=1.0), plots, truth)
               for p in ps]
        best[period] = ps[int(np.argmin(rms))]
        miss = np.concatenate([np.subtract(truth.at(p.t), (p.e, p.n)) for p in plots], axis=1)
        raw = np.sqrt(2.0 * np.mean(miss**2))
        assert min(rms) < 0.9 * raw
    assert best[12.0] < best[2.0]


def test_three_radars_default_tpm_not_worse_than_fixed():
    # dynamic-TPM paper (b) in small: the default (expm) at most 2 % above the best of fixed 0.90/0.95/0.98
    rng = np.random.default_rng(12)
    truth = sc.tpm_paper_truth()
    radars = sc.TPM_PAPER_RADARS
    plots = [sc.merge(*[sc.rotating_radar(truth, site, period, phase, pd, 70.0, 0.08, rng, sensor=i)
                        for i, (site, period, phase, pd) in enumerate(radars)]) for _ in range(8)]
    fixed = min(_rms(TrackerConfig(modes=PAPER_MODES, tpm=f"fixed:{p}", gate_probability=1.0), plots, truth)
                for p in (0.9, 0.95, 0.98))
    default = _rms(TrackerConfig(modes=PAPER_MODES, gate_probability=1.0), plots, truth)
    assert default <= 1.02 * fixed


def _binned_sq_errors(tpm, plots, truth, n_bins):
    """Per run: squared position errors of the filtered estimate at the plots after 30 s, summed per 1 s bin
    (the benchmark's Monte Carlo RMS curve before pooling), and the plot count per bin."""
    sq, count = np.zeros((len(plots), n_bins)), np.zeros((len(plots), n_bins))
    cfg = TrackerConfig(modes=PAPER_MODES, tpm=tpm, gate_probability=1.0)
    for k, p in enumerate(plots):
        est = estimate(_run(cfg, p), p.t)
        keep = p.t >= 30.0
        e, n = truth.at(p.t[keep])
        idx = np.round(p.t[keep] - 30.0).astype(int)
        np.add.at(sq[k], idx, (est.x[keep, 0] - e) ** 2 + (est.x[keep, 3] - n) ** 2)
        np.add.at(count[k], idx, 1.0)
    return sq, count


def _overall_and_peaks(weights, sq, count, windows):
    """Per row of run weights: overall RMS and the maximum of the pooled RMS curve in each window."""
    s, c = weights @ sq, weights @ count
    curve = np.sqrt(np.where(c > 0, s / np.maximum(c, 1e-12), np.nan))
    return np.column_stack([np.sqrt(s.sum(1) / c.sum(1))] + [np.nanmax(curve[:, w], axis=1) for w in windows])


def test_three_radars_expm_ties_fixed_095_at_every_manoeuvre_peak():
    # dynamic-TPM paper (b) at the peaks, in small (40 runs, the paper's filter, no gate): expm:82,45 (chosen
    # on the benchmark's seeds 1 and 2) is within 2 paired-bootstrap SEs of fixed 0.95 (the best fixed p
    # overall) at the peak of every manoeuvre, and within 1 % overall (benchmark, 400 runs: +0.13 +- 0.03 m,
    # a real 0.2 % loss; its SE here is about 0.1 m). The paper's law and fixed 0.98, which switch into a turn
    # less often, lose the 840 s peak by more than 2 SE (benchmark: +24 m); so does the default expm:150,20
    # (here +10.9 m against 2 SE = 5.3 m; benchmark +12.9 m), which is why it is not the law tested here
    rng = np.random.default_rng(17)
    truth = sc.tpm_paper_truth()
    runs, n_bins = 40, int(truth.t[-1] - 30.0) + 1
    radars = sc.TPM_PAPER_RADARS
    plots = [sc.merge(*[sc.rotating_radar(truth, site, period, phase, pd, 70.0, 0.08, rng, sensor=i)
                        for i, (site, period, phase, pd) in enumerate(radars)]) for _ in range(runs)]
    bins = 30.0 + np.arange(n_bins)
    windows = [(bins >= a) & (bins <= b + 30) for a, b in sc.TPM_PAPER_MANOEUVRES_S]
    resample = rng.multinomial(runs, np.full(runs, 1.0 / runs), size=400).astype(float)
    every = np.ones((1, runs))
    ref = _binned_sq_errors("fixed:0.95", plots, truth, n_bins)
    ref_value = _overall_and_peaks(every, *ref, windows)[0]
    ref_boot = _overall_and_peaks(resample, *ref, windows)

    def minus_ref(tpm):
        data = _binned_sq_errors(tpm, plots, truth, n_bins)
        diff = _overall_and_peaks(every, *data, windows)[0] - ref_value
        return diff, (_overall_and_peaks(resample, *data, windows) - ref_boot).std(axis=0)

    diff, se = minus_ref("expm:82,45")
    assert diff[0] <= 0.01 * ref_value[0]
    assert (diff[1:] <= 2 * se[1:]).all(), (diff, se)
    for slow in ("dynamic", "fixed:0.98"):
        diff, se = minus_ref(slow)
        assert diff[4] > 2 * se[4], (slow, diff, se)


def _robust_case():
    """The robust-IMM paper's ADS-B leg sequence at 90 m/s (1 m/s^2, 3 deg/s), 1 Hz for 100 s, and its
    filter (the default modes plus CA): (truth, sample times, tracker configuration)."""
    legs = [(10, 0, 0), (10, 0, 1), (10, 0, -1), (10, 3, 0), (10, 0, 1), (10, 0, -1), (10, -3, 0),
            (10, 0, 0), (10, 0, 1), (10, 0, -1)]
    return (sc.fly((0.0, 0.0), 90.0, 90.0, legs), np.arange(0.0, 100.0, 1.0),
            TrackerConfig(modes=default_modes(with_ca=True)))


def test_robust_imm_filters_and_coasts():
    # robust-IMM paper: 1 Hz ADS-B-like sensor (error magnitude 30.21 +- 6.4 m), filtered error 10-45 % lower
    rng = np.random.default_rng(13)
    truth, t, cfg = _robust_case()
    raw, filt, coast, hold = [], [], [], []
    for _ in range(10):
        p = sc.position_sensor(truth, t, 30.21, 6.4, rng)
        e, n = truth.at(p.t)
        est = estimate(_run(cfg, p), p.t)
        raw.append(np.hypot(p.e - e, p.n - n).mean())
        filt.append(np.hypot(est.x[:, 0] - e, est.x[:, 3] - n).mean())
        # a 6 s loss: coasted estimates against holding the last report
        keep = (t < 40) | (t > 45)
        q = sc.position_sensor(truth, t[keep], 30.21, 6.4, rng)
        gap = np.arange(40.0, 46.0)
        est = estimate(_run(cfg, q), gap)
        ge, gn = truth.at(gap)
        last = np.flatnonzero(q.t < 40)[-1]
        coast.append(np.hypot(est.x[:, 0] - ge, est.x[:, 3] - gn))
        hold.append(np.hypot(q.e[last] - ge, q.n[last] - gn))
    improvement = 1 - np.mean(filt) / np.mean(raw)
    assert 0.10 < improvement < 0.45
    assert (np.mean(coast, axis=0) < np.mean(hold, axis=0)).all()


def test_robust_imm_gain_grows_with_the_sensors_noise():
    # why MLAT near the airport cannot gain the most with one filter: same kinematics and filter, the
    # relative improvement rises with the error (benchmark: 16.5 % at 2 m ... 50.3 % at 100 m)
    rng = np.random.default_rng(16)
    truth, t, cfg = _robust_case()
    gain = []
    for mean in (4.3, 48.18):  # MLAT near the airport, WAM (tracking.md Table 2)
        raw, filt = [], []
        for _ in range(10):
            p = sc.position_sensor(truth, t, mean, 0.1 * mean, rng)
            e, n = truth.at(p.t)
            est = estimate(_run(cfg, p), p.t)
            raw.append(np.hypot(p.e - e, p.n - n).mean())
            filt.append(np.hypot(est.x[:, 0] - e, est.x[:, 3] - n).mean())
        gain.append(1 - np.mean(filt) / np.mean(raw))
    assert 0.1 < gain[0] < gain[1] - 0.1


def test_robust_imm_coasting_beats_hold_at_taxi_speed():
    # robust-IMM paper, second half of the target: under Poisson loss the coasted estimate beats holding
    # the last report at every time since it. Hardest case of the benchmark: MLAT near the airport (4.3 +-
    # 1.5 m) on scenario 2 at taxi speed (10 m/s, 0.5 m/s^2, 3 deg/s), where the aircraft moves least.
    # Benchmark (100 runs): 4.2/11.7 m at 1 s, 5.7/22.5 at 2 s, 12.3/55.4 at 5 s; here (20 runs, 43-72
    # samples per age) the margin is 14-22 times the standard error of the per-sample difference
    rng = np.random.default_rng(17)
    legs = [(10, 0, 0.5), (10, 0, -0.5), (10, 3, 0), (10, 0, 0), (10, -3, 0), (10, 0, 0)]
    truth = sc.fly((0.0, 0.0), 90.0, 10.0, legs)
    t = np.arange(0.0, 61.0, 1.0)
    cfg = TrackerConfig(modes=default_modes(with_ca=True))
    by_age = {}
    for _ in range(20):
        lost = np.zeros(len(t), bool)
        start = rng.exponential(10.0)
        while start < t[-1]:  # losses start at 0.1/s, each 1-10 s
            lost[(t >= start) & (t < start + rng.integers(1, 11))] = True
            start += rng.exponential(10.0)
        lost[:3] = False
        p = sc.position_sensor(truth, t[~lost], 4.3, 1.5, rng)
        est = estimate(_run(cfg, p), t[lost])
        e, n = truth.at(t[lost])
        k = np.searchsorted(p.t, t[lost]) - 1
        hold = np.hypot(p.e[k] - e, p.n[k] - n)
        coast = np.hypot(est.x[:, 0] - e, est.x[:, 3] - n)
        for age, c, h in zip(np.rint(t[lost] - p.t[k]).astype(int), coast, hold, strict=True):
            by_age.setdefault(age, []).append((c, h))
    for age in range(1, 6):
        assert len(by_age[age]) >= 30
        c, h = np.mean(by_age[age], axis=0)
        assert c < h, (age, c, h)


def test_vts_ranking():
    # VTS paper: CV Kalman loses the target in the turn (gated reports), CA Kalman holds it but is noisier
    # on straight legs, the IMM(CV, CA) is close to the best on both
    rng = np.random.default_rng(14)
    legs = [(200, 0, 0), (20, 4.0, 0), (40, 0, 1.0), (20, -4.0, 0), (120, 0, 0)]
    truth = sc.fly((-20000.0, 25000.0), 90.0, 120.0, legs)
    filters = {"cv": TrackerConfig(modes=(Mode("cv", "cv", 0.5),)),
               "ca": TrackerConfig(modes=(Mode("ca", "ca", 3.0),)),
               "imm": TrackerConfig(modes=(Mode("cv", "cv", 0.1), Mode("ca", "ca", 3.0)), tpm="expm:200")}
    straight = {k: [] for k in filters}
    manoeuvre = {k: [] for k in filters}
    gated = dict.fromkeys(filters, 0)
    for _ in range(10):
        p = sc.rotating_radar(truth, (0.0, 0.0), 4.0, 0.0, 1.0, 70.0, 0.08, rng)
        e, n = truth.at(p.t)
        for k, cfg in filters.items():
            run = _run(cfg, p)
            est = estimate(run, p.t)
            err2 = (est.x[:, 0] - e) ** 2 + (est.x[:, 3] - n) ** 2
            straight[k].append(err2[(p.t > 60) & (p.t < 200)])
            manoeuvre[k].append(err2[(p.t >= 200) & (p.t < 340)])
            gated[k] += int((run.status == 0).sum())

    def rms(d, k):
        return np.sqrt(np.mean(np.concatenate(d[k])))

    assert gated["cv"] > 10 * max(gated["imm"], 1)
    assert rms(manoeuvre, "cv") > 2 * rms(manoeuvre, "imm")
    assert rms(straight, "ca") > 1.2 * rms(straight, "cv")
    assert rms(straight, "imm") < 1.1 * rms(straight, "cv")
    assert rms(manoeuvre, "imm") < 1.1 * rms(manoeuvre, "ca")


@pytest.mark.skipif(not REAL.exists(), reason=f"real recording {REAL} not present (../shared/real)")
def test_real_adsb_gaps_filled_better_than_holding():
    tracks = load_real_adsb()[:8]
    res = gap_experiment(tracks, TrackerConfig(), np.random.default_rng(15))
    for label, row in res.items():
        if row["n"] == 0:
            continue
        assert row["imm"] < row["hold"] and row["smoothed"] < row["hold"]
        if not label.startswith("5-"):  # beyond 15 s the smoothed fill also beats the straight line
            assert row["smoothed"] < row["line"]
