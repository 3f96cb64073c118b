"""--adsb-sigma: a declared accuracy for ADS-B reports without NACp (CAT021 0.2x), on track and conflicts.

The references are the simulator's: the per-axis sigma it injected, and the declared value itself (the
covariance must be exactly sigma^2). The recording is encoded in CAT021 edition 0.23, which has no
NACp, as the real recording; its figure of merit is never read as NACp."""

from __future__ import annotations

import datetime
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fixtures.real_track_data import REAL
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.jobs import common
from msdc.pipeline.jobs.conflicts import ConflictOptions, conflict_job
from msdc.pipeline.jobs.track import TrackOptions, summary, track_job

INJECTED_M = 20.0  # the simulator's ADS-B position sigma per axis for this recording
DECLARED_M = 50.0
# what CAT021 0.23 can carry of the simulator's columns (no I021/090 quality indicators: no NACp)
V023 = ["sac", "sic", "time_of_day", "latitude", "longitude", "address", "callsign", "flight_level",
        "ground_speed_kt", "track_angle_deg"]
DATE = "2019-03-01"
DAY = datetime.date(2019, 3, 1)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """Two aircraft, ADS-B only, 20 m per axis, no low-quality episode; as 0.23 (no NACp) and as the
    current edition with NACp 0 on every report."""
    from fixtures.scenario import default_scenario
    from fixtures.simulate import sensors_toml, simulate

    sc = replace(default_scenario(), adsb_sigma_position_m=INJECTED_M, adsb_low_quality_episodes=0)
    sc = replace(sc, aircraft=sc.aircraft[:2])
    sim = simulate(sc, seed=5)
    d = tmp_path_factory.mktemp("adsb_sigma")
    (d / "v023.ast").write_bytes(encode_frame(21, sim.adsb[V023], edition="0.23"))
    (d / "nacp0.ast").write_bytes(encode_frame(21, sim.adsb.assign(nacp=0)))
    (d / "s.toml").write_text(sensors_toml(sc.radar))
    return d


def _track(d, **kw):
    return track_job(TrackOptions(inputs=(str(d / "v023.ast"),), editions=("21=0.23",), date=DAY,
                                  sensors=str(d / "s.toml"), all_aircraft=True, output=str(d / "t.csv"),
                                  **kw))


def test_declared_noise_uses_exactly_the_declared_sigma(recording):
    r = _track(recording, adsb_sigma_m=DECLARED_M, noise="declared")
    m = r.measurements
    assert len(m) > 1000 and (m["sensor_kind"] == "adsb").all() and m["nacp"].isna().all()
    np.testing.assert_array_equal(m["cov_ee_m2"], DECLARED_M**2)  # 2500 m^2 per axis
    np.testing.assert_array_equal(m["cov_nn_m2"], DECLARED_M**2)
    np.testing.assert_array_equal(m["cov_en_m2"], 0.0)
    assert r.tracks["aircraft_id"].nunique() == 2
    assert r.parameters["adsb_sigma_m"] == DECLARED_M and r.parameters["noise"] == "declared"


def test_estimate_recovers_the_injected_sigma_from_the_declared_one(recording):
    for noise in ("estimate", "timing"):
        r = _track(recording, adsb_sigma_m=DECLARED_M, noise=noise)
        rows = r.noise[r.noise["sensor_kind"] == "adsb"].set_index("component")
        row = rows.loc["position"]
        assert row["declared_from"] == "declared" and bool(row["estimated"])
        assert row["declared_sigma"] == DECLARED_M
        # ~5900 reports: the sample sigma is within ~1 % of 20 m; 5 % is the residual method's bound against
        # the sample's RMS in test_track_noise (19.87 m on 2026-11-22), the injected jumps cut as gross errors
        assert row["estimated_sigma"] == pytest.approx(INJECTED_M, rel=0.05)
        m = r.measurements
        if noise == "estimate":
            assert "timing" not in rows.index
            np.testing.assert_allclose(m["cov_ee_m2"], row["estimated_sigma"] ** 2, rtol=1e-9)
        else:
            # no time-stamp jitter injected (times quantised to 1/128 s: 2.3 ms RMS, 0.5 m at 200 m/s,
            # nothing against 20 m): the timing term stays near 0 and the covariance near 20^2 I
            assert rows.loc["timing", "unit"] == "s" and 0.0 <= rows.loc["timing", "estimated_sigma"] < 0.05
            np.testing.assert_allclose(m["cov_ee_m2"], row["estimated_sigma"] ** 2, rtol=0.05)
            np.testing.assert_allclose(m["cov_nn_m2"], row["estimated_sigma"] ** 2, rtol=0.05)


def test_noise_classes_keep_declared_apart_from_the_same_nacp_sigma():
    """A declared sigma equal to a NACp level's (NACp 9: 30 / 2.4477 m) is still its own class."""
    import pandas as pd

    from msdc.pipeline.model.measurements import nacp_sigma_m
    from msdc.pipeline.track.noise import _classes

    var = float(nacp_sigma_m([9])[0]) ** 2
    meas = pd.DataFrame({"sensor_id": ["021:0/1"] * 3, "sensor_kind": ["adsb"] * 3,
                         "cov_ee_m2": [var] * 3, "nacp": pd.array([9, pd.NA, 9], dtype="Int64")})
    codes, keys = _classes(meas, np.full((3, 2), np.nan), np.array(["airborne"] * 3))
    assert codes[0] == codes[2] != codes[1]
    assert sorted(k[4] for k in keys) == ["declared", "nacp"]
    # the same report on the surface is a class of its own too
    codes, keys = _classes(meas, np.full((3, 2), np.nan), np.array(["airborne", "airborne", "surface"]))
    assert len(set(codes)) == 3 and sorted(k[5] for k in keys) == ["airborne", "airborne", "surface"]


def test_nacp_0_is_not_given_the_declared_sigma(recording, capsys):
    """NACp 0 says "unknown or >= 10 NM": a statement of poor accuracy, not a missing one."""
    d = recording
    code = main(["track", str(d / "nacp0.ast"), "--sensors", str(d / "s.toml"), "--all", "--adsb-sigma", "50",
                 "-o", str(d / "n.csv")])
    err = capsys.readouterr().err
    assert code == 1 and "no aircraft could be tracked" in err and "have NACp 0" in err
    assert not (d / "n.csv").exists()


def test_without_the_option_the_message_suggests_it(recording, capsys):
    d = recording
    code = main(["track", str(d / "v023.ast"), "--edition", "21=0.23", "--date", DATE, "--sensors",
                 str(d / "s.toml"), "--all", "-o", str(d / "m.csv")])
    err = capsys.readouterr().err
    assert code == 1 and "carry no NACp" in err and "--adsb-sigma" in err
    assert len([line for line in err.splitlines() if line.startswith("msdc track:")]) == 1
    assert not (d / "m.csv").exists()


def test_conflicts_record_declared_noise_and_the_sigma(recording):
    d = recording
    base = {"inputs": (str(d / "v023.ast"),), "editions": ("21=0.23",), "date": DAY,
            "sensors": str(d / "s.toml"), "output": str(d / "c.csv"), "adsb_sigma_m": DECLARED_M}
    declared = conflict_job(ConflictOptions(**base))
    assert declared.parameters["noise"] == "declared" and declared.noise is None
    assert declared.parameters["adsb_sigma_m"] == DECLARED_M and declared.counts["aircraft"] == 2
    estimated = conflict_job(ConflictOptions(**base, noise="estimate"))
    row = estimated.noise[estimated.noise["sensor_kind"] == "adsb"]
    assert estimated.parameters["noise"] == "estimate"
    assert row["estimated_sigma"].iloc[0] == pytest.approx(INJECTED_M, rel=0.05)


TRACK = ["track", "{A}", "--sensors", "{S}", "--all", "-o", "{O}/t.csv"]
CONFLICTS = ["conflicts", "{A}", "--sensors", "{S}", "-o", "{O}/c.csv"]
# (id, argv, words the one-line message must contain)
BAD = [
    (f"{cmd[0]}-{name}", cmd + extra, words)
    for cmd in (TRACK, CONFLICTS)
    for name, extra, words in [
        ("zero", ["--adsb-sigma", "0"], ["--adsb-sigma 0.0", "0.5 to 20000 m"]),
        ("small", ["--adsb-sigma", "0.4"], ["--adsb-sigma 0.4", "0.5 to 20000 m"]),
        ("negative", ["--adsb-sigma", "-30"], ["--adsb-sigma -30.0", "0.5 to 20000 m"]),
        ("huge", ["--adsb-sigma", "20001"], ["--adsb-sigma 20001.0", "0.5 to 20000 m"]),
        ("nan", ["--adsb-sigma", "nan"], ["--adsb-sigma nan", "finite"]),
        ("inf", ["--adsb-sigma", "inf"], ["--adsb-sigma inf", "finite"]),
        ("text", ["--adsb-sigma", "thirty"], ["--adsb-sigma", "float"]),
    ]
] + [("conflicts-noise", CONFLICTS + ["--noise", "guess"], ["--noise 'guess'", "declared, estimate"])]


@pytest.mark.parametrize(("argv", "words"), [pytest.param(a, w, id=i) for i, a, w in BAD])
def test_bad_options_refused_before_decoding(argv, words, recording, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(common, "load", lambda *a, **k: pytest.fail("decoded before validating"))
    subst = {"{A}": str(recording / "v023.ast"), "{S}": str(recording / "s.toml"), "{O}": str(tmp_path)}
    argv = [subst.get(a, a.replace("{O}", str(tmp_path))) for a in argv]
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse: not a number
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and all(w in err for w in words), err
    assert "Traceback" not in err and (len(err.splitlines()) == 1 or "usage:" in err)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not REAL.exists(), reason=f"real recording {REAL} not present (../shared/real)")
def test_real_v023_recording_is_tracked_with_a_declared_sigma(tmp_path):
    sensors = str(Path(__file__).resolve().parents[3] / "fixtures" / "sensors.toml")
    r = track_job(TrackOptions(inputs=(str(REAL),), editions=("21=0.23",), sensors=sensors, all_aircraft=True,
                               output=str(tmp_path / "t.csv"), adsb_sigma_m=30.0, noise="estimate"))
    assert r.tracks["aircraft_id"].nunique() >= 40  # 47 on 2026-11-22; 0 without --adsb-sigma
    rows = r.noise[r.noise["sensor_kind"] == "adsb"].set_index("motion")
    assert sorted(rows.index) == ["airborne", "surface"] and (rows["declared_from"] == "declared").all()
    # Airborne and surface reports are separate classes. The mean of the airborne residuals alone gives
    # 10.9 m (2026-11-23), near the last session's 11.2-11.7 m per FOM level on the 22 airborne tracks
    # (the decoded ground bit; benchmarks track_validation real); its heavy tail (time stamps 0.5-0.9 s
    # late) then put 2 % of the reports beyond the 99.9 % gate, so the sigma is raised until 1 % is:
    # above 10.9 m, and well below the declared 30 m (which would mean the residuals were not used).
    # 19.4 m on 2026-11-23. Pooled with the surface reports it was 6.3 m.
    airborne, surface = rows.loc["airborne"], rows.loc["surface"]
    assert 10.9 < airborne["estimated_sigma"] < 25.0 and airborne["residuals"] > 25_000
    # taxiing and parked aircraft: residuals of a metre or two (2.8 m on 2026-11-23), far below airborne
    assert surface["estimated_sigma"] < airborne["estimated_sigma"] / 3 and surface["residuals"] > 15_000
    # the pooled estimate gated 1,339 reports and broke the tracks into 365 segments, VLG7821's smooth
    # 1 Hz approach into 112 (--noise declared, 30 m: 194 and 106); 556 and 195 on 2026-11-23, VLG7821 4
    ac = r.result.aircraft.set_index("aircraft_id")
    assert ac["gated"].sum() < 700 and ac["segments"].sum() < 250 and ac.loc["344282", "segments"] <= 10
    # VLG7782 (344441) taxis with positions that jump 15-17 m back and forth (0.6 % of the surface class's
    # reports): at the class's 2.8 m its track broke into 33 segments, 155 reports gated (2026-11-23). The
    # per-aircraft guard raises its surface sigma alone (5.7 m on 2026-11-23): 1 segment, 1 gated report
    raised = pd.DataFrame(r.noise.attrs["aircraft"])
    assert raised["aircraft_id"].tolist() == ["344441"] and raised["motion"].tolist() == ["surface"]
    assert surface["estimated_sigma"] < raised["estimated_sigma_m"].iloc[0] < airborne["estimated_sigma"]
    assert ac.loc["344441", "segments"] <= 3 and ac.loc["344441", "gated"] <= 20
    assert [a["aircraft_id"] for a in summary(r)["noise"]["aircraft_raised"]] == ["344441"]
    assert math.isfinite(r.parameters["adsb_sigma_m"]) and r.parameters["adsb_sigma_m"] == 30.0


@pytest.mark.skipif(not REAL.exists(), reason=f"real recording {REAL} not present (../shared/real)")
def test_real_v023_timing_term_splits_the_airborne_scatter(tmp_path):
    sensors = str(Path(__file__).resolve().parents[3] / "fixtures" / "sensors.toml")
    r = track_job(TrackOptions(inputs=(str(REAL),), editions=("21=0.23",), sensors=sensors, all_aircraft=True,
                               output=str(tmp_path / "t.csv"), adsb_sigma_m=30.0, noise="timing"))
    adsb = r.noise[r.noise["sensor_kind"] == "adsb"]
    rows = adsb[adsb["component"] == "position"].set_index("motion")
    timing = adsb[adsb["component"] == "timing"].set_index("motion")
    assert sorted(rows.index) == sorted(timing.index) == ["airborne", "surface"]
    # Across track the airborne residuals are ~2 m at every speed, along track they grow with speed
    # (time stamps off by ~0.05 s robustly, with a tail 0.5-0.9 s late). With the timing term the
    # airborne position sigma is the across-track scatter's (3.5 m on 2026-11-23, where one isotropic
    # sigma is raised to 19.4 m) and sigma_t lies between the robust jitter and the late tail (0.24 s,
    # raised by the gate-share guard from the mean's 0.12 s)
    airborne, surface = rows.loc["airborne"], rows.loc["surface"]
    assert 1.0 < airborne["estimated_sigma"] < 10.0 and airborne["residuals"] > 25_000
    assert timing.loc["airborne", "unit"] == "s" and 0.05 < timing.loc["airborne", "estimated_sigma"] < 0.5
    # taxiing and parked aircraft (2.6 m on 2026-11-23) are too slow for a timing term (under 26 m/s,
    # 0.1 s is under 3 m): kept at 0 and said so
    assert surface["estimated_sigma"] < 5.0 and surface["residuals"] > 15_000
    assert timing.loc["surface", "estimated_sigma"] == 0.0 and not timing.loc["surface", "estimated"]
    # isotropic per class: 556 gated reports, 195 segments, VLG7821 4; with the timing term 424, 150 and
    # 3 on 2026-11-23
    ac = r.result.aircraft.set_index("aircraft_id")
    assert ac["gated"].sum() < 500 and ac["segments"].sum() < 180 and ac.loc["344282", "segments"] <= 4
