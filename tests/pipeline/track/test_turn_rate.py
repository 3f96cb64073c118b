"""The turn_rate_dps output against known turn rates: by hand for the track-angle slope, and against the
simulator's true turn rate (fixtures: SIA305's 1.47 deg/s turn, MXD1202's and MAS72's turns)."""

from __future__ import annotations

import numpy as np
import pytest

import fixtures.track_e2e_data as d
from msdc.pipeline.track import track
from msdc.pipeline.track.tracker import track_angle_rate

# one worker runs the module: the turning simulation made once, not on each worker
pytestmark = pytest.mark.xdist_group("turn_rate")


def test_track_angle_rate_by_hand():
    t = np.arange(0.0, 30.0, 1.0)
    psi = (350.0 + 2.0 * t) % 360.0  # 2 deg/s to the right, across north
    seg = np.zeros(len(t), int)
    np.testing.assert_allclose(track_angle_rate(t, psi, seg, 8.0, centred=True), 2.0, atol=1e-9)
    np.testing.assert_allclose(track_angle_rate(t, psi, seg, 8.0, centred=False)[1:], 2.0, atol=1e-9)
    assert np.isnan(track_angle_rate(t, psi, seg, 8.0, centred=False)[0])  # one row in the window
    # a left turn of -1 deg/s in a second segment is not mixed with the first one
    seg2 = (t >= 15).astype(int)
    psi2 = np.where(t < 15, psi, 100.0 - (t - 15.0))
    rate = track_angle_rate(t, psi2, seg2, 8.0, centred=True)
    np.testing.assert_allclose(rate[t < 15], 2.0, atol=1e-9)
    np.testing.assert_allclose(rate[t >= 15], -1.0, atol=1e-9)


@pytest.fixture(scope="module")
def turning(tmp_path_factory):
    e = d.build(tmp=tmp_path_factory.mktemp("turn"))
    keep = e.measurements["aircraft_id"].astype(str).isin(["76CDA3", "750B1E", "750312"]).to_numpy()
    meas = e.measurements[keep]
    out = {}
    for smooth in (False, True):
        tr = track(meas, smooth=smooth).tracks
        tod = (tr["time"] - d.MIDNIGHT).dt.total_seconds().to_numpy(float)
        truth = np.full(len(tr), np.nan)
        ident = tr["aircraft_id"].astype(str).to_numpy()
        for ac in e.sim.sim.aircraft:
            sel = ident == ac.spec.address_hex
            if sel.any():  # the simulator's track angle, differentiated over 1 s (+ = right turn)
                a, b = ac.truth(tod[sel] - 0.5).track_deg, ac.truth(tod[sel] + 0.5).track_deg
                truth[sel] = (b - a + 180.0) % 360.0 - 180.0
        out[smooth] = (tr, truth)
    return out


def test_smoothed_turn_rate_follows_the_true_turns(turning):
    tr, truth = turning[True]
    rate = tr["turn_rate_dps"].to_numpy()
    ok = np.isfinite(truth)
    turn = ok & (np.abs(truth) > 1.0)
    straight = ok & (np.abs(truth) < 0.05)
    assert turn.sum() > 200
    # the mean over the turns is within 10 % of the truth, errors small in turns and on straight legs
    ratio = np.mean(rate[turn] * np.sign(truth[turn])) / np.mean(np.abs(truth[turn]))
    assert ratio == pytest.approx(1.0, abs=0.1)
    assert np.sqrt(np.mean((rate[turn] - truth[turn]) ** 2)) < 0.5
    assert np.sqrt(np.mean(rate[straight] ** 2)) < 0.1
    # SIA305's 1.47 deg/s right turn: its steady part (truth within 0.05 of 1.47) averages 1.3-1.6
    sia = (tr["aircraft_id"].astype(str) == "76CDA3").to_numpy() & (np.abs(truth + 1.47) < 0.05)
    assert sia.sum() > 30
    assert -1.6 < rate[sia].mean() < -1.3


def test_forward_turn_rate_is_the_mode_mixture_and_reads_low(turning):
    # the forward (real-time) output keeps the mode-probability-weighted rate: between 0 and 3 deg/s,
    # under the truth on average in turns of 1.5-3 deg/s, and worse than the smoothed one
    fwd, truth = turning[False]
    smo, _ = turning[True]
    ok = np.isfinite(truth) & (np.abs(truth) > 1.0)
    f, s = fwd["turn_rate_dps"].to_numpy(), smo["turn_rate_dps"].to_numpy()
    assert np.all(np.abs(f) <= 3.0 + 1e-9)
    assert np.mean(f[ok] * np.sign(truth[ok])) < 0.9 * np.mean(np.abs(truth[ok]))
    assert np.sqrt(np.mean((s[ok] - truth[ok]) ** 2)) < 0.5 * np.sqrt(np.mean((f[ok] - truth[ok]) ** 2))
