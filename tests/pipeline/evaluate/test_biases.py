"""Radar biases and random errors (pipeline/evaluate/biases.py) against the simulator's injected biases and
plot noise, the trust checks on an exact and a 1 km-off site, and a hand-placed plot's errors;
psr_ssr_association and coasting_correct on hand-built frames."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from fixtures.radar_effects import RadarEffects, effects_scenario, simulate_effects
from msdc.pipeline.evaluate.biases import bias_errors
from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.reference import associate
from msdc.pipeline.evaluate.requirements import REQUIREMENTS, radar_reports
from msdc.pipeline.model.geodesy import polar_to_geodetic

GEOD = Geod(ellps="WGS84")
INJECTED = {"range_bias_m": 150.0, "range_gain_ppm": 100.0, "azimuth_bias_deg": 0.12, "time_bias_s": 0.5}
SIX = ("range_bias_m", "range_gain_ppm", "azimuth_bias_deg", "time_bias_s", "range_sd_m", "azimuth_sd_deg")
SEED = 7


def _evaluate(offset_m: float, declare_sigmas: bool = True, self_reference: bool = False):
    """The six ids on the effects traffic with the four biases injected, the radar declared offset_m east
    of its true site."""
    sc = replace(effects_scenario(), **INJECTED)
    sim = simulate_effects(sc, RadarEffects(site_offset_m=(offset_m, 0.0)), seed=SEED)
    site = sim.declared_site
    sigmas = {"sigma_range_m": sc.sigma_range_m, "sigma_azimuth_deg": sc.sigma_azimuth_deg} \
        if declare_sigmas else {}
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m, **sigmas)
    ref = sim.reference().assign(self_reference=self_reference)
    rep = associate(radar_reports(sim.radar, sensor), ref)
    return sc, {rid: REQUIREMENTS[rid](rep, ref, {}, sensor) for rid in SIX}


@pytest.fixture(scope="module")
def exact():
    return _evaluate(0.0)


def test_injected_biases_and_noise_recovered_inside_their_intervals(exact):
    sc, out = exact
    truth = {**INJECTED, "range_sd_m": sc.sigma_range_m, "azimuth_sd_deg": sc.sigma_azimuth_deg}
    for rid, want in truth.items():
        o = out[rid]
        assert o.ci_low <= want <= o.ci_high, (rid, o)
        assert o.n > 3000 and o.ci_low < o.value < o.ci_high
    # seven aircraft: the signed intervals use Student t with 6 degrees of freedom, not 1.96
    assert any("Student t, 6 degrees of freedom" in n for n in out["range_bias_m"].notes)


def test_exact_site_is_trusted_and_not_flagged(exact):
    _, out = exact
    for rid in SIX:
        notes = " ".join(out[rid].notes)
        assert np.isfinite(out[rid].value), rid
        assert ": not flagged" in notes and "not to be trusted" not in notes and "unchecked" not in notes


def test_a_site_1_km_off_is_flagged_and_every_figure_withheld():
    _, out = _evaluate(1000.0)
    for rid in SIX:
        o = out[rid]
        assert np.isnan(o.value) and np.isnan(o.ci_low) and o.n == 0, rid
        assert "not to be trusted" in o.notes[0] and "from its declared site" in o.notes[0]
    assert "the fit gave range bias" in out["range_bias_m"].notes[0]


def test_no_declared_sigmas_leave_the_fit_unchecked_but_given():
    _, out = _evaluate(0.0, declare_sigmas=False)
    o = out["range_bias_m"]
    assert o.ci_low <= INJECTED["range_bias_m"] <= o.ci_high
    assert any("goodness of fit unchecked" in n for n in o.notes)


def test_a_self_reference_never_judges_biases():
    _, out = _evaluate(0.0, self_reference=True)
    for rid in SIX:
        assert np.isnan(out[rid].value) and "0 plots judged" in out[rid].notes[0], rid


def test_one_plot_placed_by_hand():
    """A reference aircraft flying north at 200 m/s, 50 km north of a site at (0, 0, 0) at t = 10 s, both
    on the ellipsoid; a plot 40 m beyond in range and 0.2 deg clockwise. Its slant range is the chord of
    pyproj's geodesic (< 0.2 m from it at 50 km), its range rate 200 m/s, its tangential speed 0."""
    t = np.arange(0.0, 21.0)
    lon, lat, _ = GEOD.fwd(np.zeros(t.size), np.zeros(t.size), np.zeros(t.size), 48_000.0 + 200.0 * t)
    ref = pd.DataFrame({"aircraft": "A", "t_s": t, "latitude": lat, "longitude": lon, "height_m": 0.0})
    plat, plon, _ = polar_to_geodetic(0.0, 0.0, 0.0, 50_040.0 / 1852.0, 0.2, 0.0)
    rep = pd.DataFrame({"t_s": [10.0], "latitude": plat, "longitude": plon, "rho_nm": [50_040.0 / 1852.0],
                        "theta_deg": [0.2]})
    e = bias_errors(rep, ref, {}, Sensor(0.0, 0.0, 0.0, sigma_range_m=50.0, sigma_azimuth_deg=0.1))
    row = e.iloc[0]
    assert row["range_error_m"] == pytest.approx(40.0, abs=0.3)
    assert row["azimuth_error_deg"] == pytest.approx(0.2, abs=1e-6)
    assert row["range_rate_ms"] == pytest.approx(200.0, rel=1e-3)
    assert row["tangential_speed_ms"] == pytest.approx(0.0, abs=0.01)
    assert row["azimuth_deg"] == pytest.approx(0.0, abs=1e-9) or row["azimuth_deg"] == pytest.approx(360.0)
    assert (row["sigma_range_m"], row["sigma_azimuth_deg"]) == (50.0, 0.1)  # the reference has no sigma_m
    out = REQUIREMENTS["range_bias_m"](rep, ref, {}, Sensor(0.0, 0.0, 0.0))
    assert np.isnan(out.value) and "1 plots" in out.notes[0] and "fewer than 20" in out.notes[0]


# ---------------------------------------------------------------------------------------------------------
# PSR/SSR association

MARKERS = -2.0 + 4.0 * np.arange(40)  # north markers every 4 s
SITE = Sensor(0.0, 0.0, 0.0, north_markers_s=MARKERS)


def _track(label: str, azimuth_deg: float, t_end: float = 80.0) -> pd.DataFrame:
    """A reference aircraft flying out along an azimuth from 30 NM at 0.1 NM/s, sampled every second."""
    t = np.arange(0.0, t_end + 0.5)
    lat, lon, _ = polar_to_geodetic(0.0, 0.0, 0.0, 30.0 + 0.1 * t, azimuth_deg, 0.0)
    return pd.DataFrame({"aircraft": label, "t_s": t, "latitude": lat, "longitude": lon, "height_m": 0.0})


def _plots(azimuth_deg: float, times, **columns) -> pd.DataFrame:
    """Plots on the aircraft's path at the given times."""
    t = np.asarray(times, float)
    lat, lon, _ = polar_to_geodetic(0.0, 0.0, 0.0, 30.0 + 0.1 * t, azimuth_deg, 0.0)
    return pd.DataFrame({"t_s": t, "latitude": lat, "longitude": lon, **columns})


def test_psr_ssr_association_counts_the_updates_both_saw():
    ref = pd.concat([_track("A", 0.0), _track("B", 90.0)], ignore_index=True)
    scans = 4.0 * np.arange(10)
    # A: 8 scans with a combined plot (TYP 7), 2 with a separate PSR-only (1) and SSR-only (5) plot, one scan
    # with an extra PSR-only plot beside its combined one (still associated), and a PSR-only scan alone
    a = [_plots(0.0, scans[:8], typ=7), _plots(0.0, scans[8:], typ=1), _plots(0.0, scans[8:] + 0.01, typ=5),
         _plots(0.0, [0.02], typ=1), _plots(0.0, [44.0], typ=1)]
    # B: Mode S roll-call only: its PSR never saw it, so nothing of it is judged
    b = [_plots(90.0, scans + 1.0, typ=5)]
    rep = pd.concat(a + b, ignore_index=True).sort_values("t_s", ignore_index=True)
    out = REQUIREMENTS["psr_ssr_association"](rep, ref, {}, SITE)
    assert (out.count, out.n) == (8, 10)
    assert out.value == pytest.approx(0.8)
    table = out.per_aircraft.set_index("aircraft")
    assert table.loc["A", "updates_both"] == 10 and table.loc["B", "updates_both"] == 0


def test_psr_ssr_association_withheld_without_the_bits_or_a_psr():
    ref = _track("A", 0.0)
    no_typ = REQUIREMENTS["psr_ssr_association"](_plots(0.0, [0.0, 4.0]), ref, {}, SITE)
    assert np.isnan(no_typ.value) and "I048/020 TYP" in no_typ.notes[0]
    clutter = _plots(180.0, [2.0], typ=1)  # a single PSR plot 60 NM from aircraft A: nobody's
    ssr = pd.concat([_plots(0.0, [0.0, 4.0], typ=5), clutter], ignore_index=True)
    ssr = REQUIREMENTS["psr_ssr_association"](ssr, ref, {}, SITE)
    assert np.isnan(ssr.value) and "no PSR detection" in ssr.notes[0]
    # combined plots only, as in the real Barcelona hour (TYP 7, 5, 3, 2; no TYP 1 in 44,085 records): a
    # PSR detection the radar failed to associate would be a TYP 1 plot, and none could be seen
    only = REQUIREMENTS["psr_ssr_association"](_plots(0.0, [0.0, 4.0], typ=7), ref, {}, SITE)
    assert np.isnan(only.value) and "no single PSR plot" in only.notes[0]


# ---------------------------------------------------------------------------------------------------------
# Coasting


def test_coasting_flag_against_the_reference_updates():
    """The reference was updated at 0-20 s and again from 50 s: a track report at 25 s is 5 s after an
    update (not coasting), at 35 and 45 s 15 and 25 s after (coasting, window 10 s), at 55 s 5 s after."""
    ref = _track("A", 0.0).assign(updated=lambda f: (f["t_s"] <= 20.0) | (f["t_s"] >= 50.0))
    times = [25.0, 35.0, 45.0, 55.0]
    right = REQUIREMENTS["coasting_correct"](_plots(0.0, times, cst=[0, 1, 1, 0]), ref, {}, None)
    assert (right.count, right.n) == (4, 4)
    wrong = REQUIREMENTS["coasting_correct"](_plots(0.0, times, cst=[1, 0, 1, 1]), ref, {"window_s": 10.0})
    assert (wrong.count, wrong.n) == (1, 4)
    wide = REQUIREMENTS["coasting_correct"](_plots(0.0, times, cst=[0, 1, 1, 0]), ref, {"window_s": 20.0})
    assert (wide.count, wide.n) == (3, 4)  # 35 s is 15 s after an update: not coasting within 20 s
    own = ref.assign(self_reference=True)  # the sensor's own track cannot say when it was detected
    none = REQUIREMENTS["coasting_correct"](_plots(0.0, times, cst=[1, 1, 1, 1]), own, {})
    assert (none.count, none.n) == (4, 4)


def test_coasting_withheld_without_the_flag_or_the_reference_updates():
    ref = _track("A", 0.0)
    out = REQUIREMENTS["coasting_correct"](_plots(0.0, [25.0], cst=[0]), ref, {})
    assert np.isnan(out.value) and "'updated'" in out.notes[0]
    out = REQUIREMENTS["coasting_correct"](_plots(0.0, [25.0]), ref.assign(updated=True), {})
    assert np.isnan(out.value) and "I062/080 CST" in out.notes[0]
