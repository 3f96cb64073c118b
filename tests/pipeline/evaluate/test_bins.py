"""Where a sensor detects: PD per bin and on grids, counted exactly on hand-worked frames, and on a simulated
radar whose PD falls off beyond a range and is zero in a cone of silence, against the simulator's truth."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fixtures.radar_effects import RadarEffects, simulate_effects
from msdc.pipeline.evaluate import bins
from msdc.pipeline.evaluate.coverage import Sensor, sensor_from_entry
from msdc.pipeline.evaluate.detection import EXPECTED_COLUMNS, expected_updates
from msdc.pipeline.evaluate.reference import associate
from msdc.pipeline.evaluate.requirements import REQUIREMENTS, radar_reports
from msdc.pipeline.evaluate.statistics import proportion
from msdc.pipeline.model.geodesy import M_PER_FT, M_PER_NM
from msdc.pipeline.model.sensors import read_sensors
from tests.pipeline.evaluate.test_requirements import NEAR, reference, reports


def hand_table(rows: list[tuple]) -> pd.DataFrame:
    """Expected updates written out: (aircraft, detected, in_coverage, rho_nm, azimuth_deg, altitude_ft)."""
    frame = pd.DataFrame(rows, columns=["aircraft", "detected", "in_coverage", "rho_nm", "azimuth_deg",
                                        "altitude_ft"])
    n = len(frame)
    t = np.arange(n, dtype=float)
    return frame.assign(stretch=0, t_s=t, t_ref_s=t, elevation_deg=1.0,
                        height_m=frame["altitude_ft"] * M_PER_FT)[EXPECTED_COLUMNS]


HAND = hand_table([
    ("A", True, True, 5.0, 0.0, 1000.0),      # range band 0-10 (its lower edge), sector 0-90
    ("A", False, True, 9.99, 89.99, 1000.0),  # band 0-10, sector 0-90
    ("A", True, True, 10.0, 90.0, 5000.0),    # on the edge: band 10-20, sector 90-180
    ("B", True, False, 15.0, 359.9, 9000.0),  # outside the coverage limits: counted only when asked
    ("B", False, True, 25.0, 270.0, np.nan),  # no altitude: in no flight-level band
    ("B", True, True, 30.0, 180.0, 1000.0),   # beyond the last range edge (30 is not below 30)
])


def test_bands_are_half_open_and_count_inside_coverage_by_default():
    out = bins.detection_by(HAND, "rho_nm", [0.0, 10.0, 20.0, 30.0], min_expected=2)
    assert out[["low", "high"]].to_numpy().tolist() == [[0, 10], [10, 20], [20, 30]]
    assert out["expected"].tolist() == [2, 1, 1] and out["detected"].tolist() == [1, 1, 0]
    assert out["enough"].tolist() == [True, False, False]
    # Clopper-Pearson by hand: 1 of 2 is [0.01258, 0.98742] (beta(1, 2) and beta(2, 1) at 2.5 %: 1 - sqrt
    # 0.975 and sqrt 0.975); 1 of 1 is [0.025, 1]; 0 of 1 is [0, 0.975]
    assert out["pd"].tolist() == [0.5, 1.0, 0.0]
    assert out["ci_low"].to_numpy() == pytest.approx([1 - math.sqrt(0.975), 0.025, 0.0])
    assert out["ci_high"].to_numpy() == pytest.approx([math.sqrt(0.975), 1.0, 0.975])
    every = bins.detection_by(HAND, "rho_nm", [0.0, 10.0, 20.0, 30.0], inside_coverage=False)
    assert every["expected"].tolist() == [2, 2, 1] and every["detected"].tolist() == [1, 2, 0]


def test_an_empty_band_has_no_value():
    out = bins.detection_by(HAND, "rho_nm", [100.0, 200.0])
    assert out["expected"].tolist() == [0] and math.isnan(out["pd"].iloc[0]) and not out["enough"].iloc[0]


def test_sectors_and_flight_levels():
    sectors = bins.detection_by(HAND, "azimuth_deg", bins.azimuth_edges(90.0), inside_coverage=False)
    assert sectors["expected"].tolist() == [2, 1, 1, 2] and sectors["detected"].tolist() == [1, 1, 1, 1]
    fl = bins.detection_by(HAND, bins.flight_level(HAND), [0.0, 50.0, 100.0])
    # inside coverage: FL10 three times (two detected); FL50, on the edge, in the upper band; no altitude:
    # in none
    assert fl["expected"].tolist() == [3, 1] and fl["detected"].tolist() == [2, 1]
    assert bins.azimuth_edges(50.0).tolist() == [0, 50, 100, 150, 200, 250, 300, 350, 360]


def test_bad_edges_are_refused():
    for edges in ([1.0], [0.0, 0.0], [0.0, np.nan], [2.0, 1.0]):
        with pytest.raises(ValueError, match="edges must be"):
            bins.detection_by(HAND, "rho_nm", edges)


def test_a_grid_counts_each_cell_and_x_varies_slowest():
    grid = bins.detection_grid(HAND, HAND["rho_nm"].to_numpy(), [0.0, 10.0, 20.0],
                               HAND["azimuth_deg"].to_numpy(), [0.0, 180.0, 360.0], min_expected=1)
    assert grid[["x_low", "y_low"]].to_numpy().tolist() == [[0, 0], [0, 180], [10, 0], [10, 180]]
    # every expected update by default, inside the limits or not:
    # (5, 0) (9.99, 89.99) | none | (10, 90) | (15, 359.9)
    assert grid["expected"].tolist() == [2, 0, 1, 1] and grid["detected"].tolist() == [1, 0, 1, 1]
    assert grid["enough"].tolist() == [True, False, True, True]
    inside = bins.detection_grid(HAND, HAND["rho_nm"].to_numpy(), [0.0, 10.0, 20.0],
                                 HAND["azimuth_deg"].to_numpy(), [0.0, 180.0, 360.0], inside_coverage=True)
    assert inside["expected"].tolist() == [2, 0, 1, 0]


def test_surface_and_airborne_from_a_reference_out_of_order_with_repeated_and_missing_times():
    ref = pd.DataFrame({"aircraft": ["B", "A", "A", "A", "B", "B"],
                        "t_s": [4.0, 1.0, 0.0, 1.0, np.nan, 3.5],
                        "on_ground": [True, False, True, True, False, False]})
    # A at 0: its sample at 0; at 1 and 2: of its two samples at 1 the later row (on the ground); B at 3:
    # no sample at or before it (the one without a time counts for none); at 4 and 5: its sample at 4
    assert bins.surface_airborne(HAND, ref).tolist() == ["surface", "surface", "surface", "unknown",
                                                         "surface", "surface"]


def test_surface_and_airborne_from_the_reference_flag():
    ref = pd.DataFrame({"aircraft": ["A", "A", "B"], "t_s": [0.0, 2.5, 0.0],
                        "on_ground": [True, False, None]})
    # A on the ground until 2.5 s (updates at 0, 1, 2), airborne after; B's flag unknown
    cls = bins.surface_airborne(HAND, ref)
    assert cls.tolist() == ["surface", "surface", "surface", "unknown", "unknown", "unknown"]
    ref.loc[1, "t_s"] = 1.5
    assert bins.surface_airborne(HAND, ref).tolist()[:3] == ["surface", "surface", "airborne"]
    assert set(bins.surface_airborne(HAND, ref.drop(columns="on_ground"))) == {"unknown"}
    bands = bins.detection_bands(HAND, ref, range_step_nm=10.0, sector_deg=90.0, min_expected=1)
    surface = bands["surface"].set_index("class")
    assert surface.loc["surface", ["expected", "detected"]].tolist() == [2, 1]
    assert surface.loc["airborne", ["expected", "detected"]].tolist() == [1, 1]
    assert surface.loc["unknown", ["expected", "detected"]].tolist() == [2, 1]  # B out of coverage left out
    assert bands["range_nm"]["high"].iloc[-1] == 40.0  # bands out past the farthest update inside coverage


def test_expected_updates_by_range_band_worked_by_hand():
    # 30 NM out at 0.1 NM/s on azimuth 90, scans every 4 s from 0 to 40 s: updates at 30.0, 30.4, ... 34.0
    # NM; reports missing at 16 s, 28 s, 32 s and 40 s
    times = [0, 4, 8, 12, 20, 24, 36]
    table, _, _ = expected_updates(reports(times, azimuth_deg=90.0), reference(40.0, azimuth_deg=90.0), {},
                                   NEAR)
    assert table["t_s"].tolist() == [0, 4, 8, 12, 16, 20, 24, 28, 32, 36, 40]
    assert table["azimuth_deg"].to_numpy() == pytest.approx(90.0, abs=1e-6)
    assert table["height_m"].tolist() == [0.0] * 11
    out = bins.detection_by(table, "rho_nm", [29.9, 31.1, 32.3, 33.5, 34.7])
    assert out["expected"].tolist() == [3, 3, 3, 2]
    assert out["detected"].tolist() == [3, 2, 1, 1]


# ---------------------------------------------------------------------------------------------------------
# A simulated radar: PD 0.9 out to 60 NM, falling linearly to 0 at 100 NM, none above 30 deg elevation

EFFECTS = RadarEffects(pd=0.9, full_range_nm=60.0, max_range_nm=100.0, cone_elevation_deg=30.0)
WIDE = 0.999  # per-band intervals: a dozen bands at 95 % would miss the truth somewhere one run in two


@pytest.fixture(scope="module")
def simulated():
    sim = simulate_effects(effects=EFFECTS, seed=2028)
    site, m = sim.declared_site, sim.north_markers
    sensor = Sensor(site.latitude, site.longitude, site.altitude_m,
                    north_markers_s=(m["day"] * 86400.0 + m["time_of_day"]).to_numpy())
    ref = sim.reference()
    rep = associate(radar_reports(sim.radar, sensor), ref)
    table, _, _ = expected_updates(rep, ref, {}, sensor)
    return sim, table


def test_pd_per_range_band_falls_where_the_injected_falloff_says(simulated):
    sim, table = simulated
    edges = np.arange(0.0, 190.0, 10.0)
    out = bins.detection_by(table, "rho_nm", edges, inside_coverage=False, min_expected=30)
    crossings = sim.plots[sim.plots["kind"].isin(["target", "missed"])]
    band = np.digitize(crossings["rho_true_nm"], edges) - 1
    # the injected probability averaged over each band's crossings: 0.9 from 10 to 60 NM, falling beyond,
    # and less than 0.9 from 0 to 10 NM, where the overflight's crossings in the cone of silence are
    truth = crossings.groupby(band)["pd"].mean()
    assert truth[1:6].to_numpy() == pytest.approx(EFFECTS.pd) and truth[0] < EFFECTS.pd
    checked = 0
    for i, row in out.iterrows():
        if not row["enough"]:
            continue
        wide = proportion(int(row["detected"]), int(row["expected"]), WIDE)
        assert wide.ci_low <= truth[i] <= wide.ci_high, (row, truth[i])
        if row["low"] >= EFFECTS.max_range_nm:
            assert row["detected"] == 0, row  # beyond the falloff: nothing
        checked += 1
    assert checked >= 12
    # the falloff shows: 60-70 NM well above 90-100 NM, and both below the full 0.9
    by = out.set_index("low")["pd"]
    assert by[60.0] > by[90.0] + 0.3 and by[90.0] < 0.25
    # every detection in the bands is one the truth detected (counted at the true range, to within the
    # few that the reference's interpolation moves across a band edge)
    detected = crossings[crossings["detected"]]
    per_band = np.bincount(np.digitize(detected["rho_true_nm"], edges) - 1, minlength=edges.size - 1)
    assert np.abs(out["detected"].to_numpy() - per_band[: edges.size - 1]).max() <= 2
    assert out["detected"].sum() == len(detected)


def test_the_cone_of_silence_shows_on_the_vertical_diagram(simulated):
    sim, table = simulated
    grid = bins.vertical_grid(table, np.arange(0.0, 41.0, 1.0), np.arange(0.0, 40001.0, 1000.0),
                              min_expected=1)
    site_m = sim.true_site.altitude_m
    # a cell is wholly inside the cone where even its lowest, farthest corner is above 30 deg (+1 deg for the
    # earth's curvature and the site's offset, negligible at these ranges)
    low_corner = np.degrees(np.arcsin(np.clip((grid["y_low"] * M_PER_FT - site_m)
                                              / (grid["x_high"] * M_PER_NM), -1, 1)))
    cone = grid[(low_corner > EFFECTS.cone_elevation_deg + 1.0) & (grid["expected"] > 0)]
    assert len(cone) >= 3 and cone["expected"].sum() >= 10  # the overflight's updates in the cone ...
    assert cone["detected"].sum() == 0  # ... none detected
    # beside the cone at the same heights, out to 60 NM, the radar detects at its full PD
    high_corner = np.degrees(np.arcsin(np.clip((grid["y_high"] * M_PER_FT - site_m)
                                               / (grid["x_low"].clip(lower=0.1) * M_PER_NM), -1, 1)))
    clear = grid[(high_corner < EFFECTS.cone_elevation_deg - 1.0) & (grid["x_high"] <= 60.0)
                 & (grid["y_low"] >= 25000.0)]
    p = clear["detected"].sum() / clear["expected"].sum()
    assert clear["expected"].sum() >= 100 and abs(p - EFFECTS.pd) < 0.06


def test_the_polar_map_counts_every_expected_update_once(simulated):
    _, table = simulated
    grid = bins.polar_grid(table)
    assert grid["expected"].sum() == len(table) and grid["detected"].sum() == table["detected"].sum()
    assert grid["y_high"].max() == 360.0 and (grid["y_high"] - grid["y_low"]).max() == 10.0


def test_pd_takes_its_coverage_from_the_sensor_file(simulated, tmp_path):
    sim, _ = simulated
    path = tmp_path / "sensors.toml"
    path.write_text(sim.sensors_toml(coverage=True))
    m = sim.north_markers
    markers = (m["day"] * 86400.0 + m["time_of_day"]).to_numpy()
    sensor = sensor_from_entry(read_sensors(path).iloc[0], markers)
    ref = sim.reference()
    rep = associate(radar_reports(sim.radar, sensor), ref)
    out = REQUIREMENTS["pd"](rep, ref, {}, sensor)
    assert "declared: max_range_nm 60, max_elevation_deg 30" in out.notes[1]
    # inside the declared 60 NM and 30 deg the injected PD is 0.9 everywhere
    assert out.ci_low <= EFFECTS.pd <= out.ci_high and out.n > 300
    crossings = sim.plots[sim.plots["kind"].isin(["target", "missed"])]
    inside = crossings[(crossings["rho_true_nm"] <= 60.0) & (crossings["elevation_deg"] <= 30.0)]
    assert abs(out.count - int(inside["detected"].sum())) <= 2


def test_default_vertical_edges_reach_below_the_ellipsoid():
    low = HAND.assign(height_m=HAND["height_m"] - 2500.0 * M_PER_FT)  # 1,000 ft lowest: now -1,500 ft
    grid = bins.vertical_grid(low, min_expected=1)
    assert grid["y_low"].min() == -2000.0 and grid["y_high"].max() == 8000.0  # highest 6,500 ft
    assert grid["expected"].sum() == len(HAND) - 1  # every update but the one without a height
    assert grid.loc[grid["y_low"] == -2000.0, "expected"].sum() == 3
