"""Sensor table reading, decoded frames to measurement frames, call sign handling and aircraft selection."""

import datetime as dt
import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame

from msdc.pipeline.model.measurements import (
    UnknownRadar,
    adsb_measurements,
    normalise_callsign,
    radar_measurements,
    select,
)
from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS
from msdc.pipeline.model.sensors import read_sensors, sensor_toml_snippet
from msdc.pipeline.model.time import UNDATED_DAY, seconds_since

A = 6378137.0
GOOD = """
[[sensor]]
name = "Equator"
sac = 1
sic = 2
latitude = 0.0
longitude = 10
altitude_m = 0.0

[[sensor]]
name = "Changi"
sac = 1
sic = 3
latitude = 1.35
longitude = 103.99
altitude_m = 20
"""


def write(tmp_path, text):
    path = tmp_path / "sensors.toml"
    path.write_text(text)
    return path


def test_read_sensors(tmp_path):
    table = read_sensors(write(tmp_path, GOOD))
    assert list(table.columns) == ["name", "sac", "sic", "latitude", "longitude", "altitude_m",
                                   "sigma_range_m", "sigma_azimuth_deg", "category", "kind", "sigma_m",
                                   "min_range_nm", "max_range_nm", "min_elevation_deg", "max_elevation_deg"]
    limits = ["min_range_nm", "max_range_nm", "min_elevation_deg", "max_elevation_deg"]
    assert table[limits].isna().all().all()  # coverage not declared
    assert table["category"].tolist() == [48, 48] and table["kind"].tolist() == ["radar", "radar"]
    assert table["sigma_m"].isna().all()  # a radar's noise is its range and azimuth sigmas
    assert table["name"].tolist() == ["Equator", "Changi"]
    assert table.loc[1, "altitude_m"] == 20.0 and table["altitude_m"].dtype == np.float64
    # optional noise: defaults 70 m and 0.08 deg, or per radar
    assert table["sigma_range_m"].tolist() == [70.0, 70.0]
    assert table["sigma_azimuth_deg"].tolist() == [0.08, 0.08]
    text = GOOD.replace("altitude_m = 20", "altitude_m = 20\nsigma_range_m = 30\nsigma_azimuth_deg = 0.05")
    noisy = read_sensors(write(tmp_path, text))
    assert noisy["sigma_range_m"].tolist() == [70.0, 30.0]
    assert noisy["sigma_azimuth_deg"].tolist() == [0.08, 0.05]


@pytest.mark.parametrize(("text", "words"), [
    (GOOD.replace("altitude_m = 20\n", ""), ["entry 2", "altitude_m"]),
    (GOOD.replace("sac = 1\nsic = 3", 'sac = "1"\nsic = 3'), ["sac", "'1'", "integer"]),
    (GOOD.replace("latitude = 1.35", "latitude = true"), ["latitude = true should be"]),  # TOML's spelling
    # a blank name labelled the radar's rows with nothing
    (GOOD.replace('name = "Changi"', 'name = " "'), ["entry 2", "SAC 1 SIC 3", "name is empty"]),
    (GOOD.replace("sic = 3", "sic = 2"), ["SAC 1 SIC 2", "twice"]),
    (GOOD.replace("latitude = 1.35", "latitude = 91.0"), ["latitude", "outside"]),
    (GOOD.replace("altitude_m = 20", "altitude_m = 20\nsigma_range_m = 0"), ["sigma_range_m", "outside"]),
    (GOOD.replace("altitude_m = 20", "altitude_m = 20\nsigma_azimuth_deg = 'x'"),
     ["sigma_azimuth_deg", "float"]),
    (GOOD.replace("longitude = 10\n", "longitude = 0.0\n", 1),
     ["entry 1", "'Equator'", "SAC 1 SIC 2", "latitude 0", "longitude 0", "no radar site", "template"]),
    ("[[sensor]\n", ["not valid TOML"]),
    ("title = 'x'\n", ["no [[sensor]]"]),
])
def test_read_sensors_errors_name_the_file(tmp_path, text, words):
    path = write(tmp_path, text)
    with pytest.raises(ValueError) as info:
        read_sensors(path)
    message = str(info.value)
    assert str(path) in message
    for word in words:
        assert word in message


def test_sensor_snippet_is_valid_toml():
    doc = tomllib.loads(sensor_toml_snippet(25, 7))
    (entry,) = doc["sensor"]
    assert (entry["sac"], entry["sic"]) == (25, 7)
    assert {"name", "latitude", "longitude", "altitude_m"} <= set(entry)


def test_normalise_callsign():
    assert normalise_callsign("mas 72") == "MAS72"
    assert normalise_callsign(" sia321 ") == "SIA321"
    assert normalise_callsign(None) is None
    assert normalise_callsign(pd.NA) is None
    out = normalise_callsign(pd.Series(pd.Categorical(["mas 72", None, "  "])))
    assert out.iloc[0] == "MAS72" and out.iloc[1:].isna().all()


def cat048(**cols):
    n = len(cols["time_of_day"])
    base = {
        "sac": pd.array([1] * n, dtype="Int32"), "sic": pd.array([2] * n, dtype="Int32"),
        "day": np.zeros(n, np.int64),
        "timestamp": pd.Series(pd.NaT, index=range(n), dtype="datetime64[ns, UTC]"),
        "rho_nm": np.full(n, np.nan), "theta_deg": np.full(n, np.nan), "x_nm": np.full(n, np.nan),
        "y_nm": np.full(n, np.nan), "flight_level": np.full(n, np.nan),
        "address": pd.Categorical(["750123"] * n), "callsign": pd.Categorical(["MAS72  "] * n),
        "ground_speed_kt": np.full(n, 400.0), "heading_deg": np.full(n, 90.0),
    }
    base.update(cols)
    return pd.DataFrame(base)


def test_radar_measurements_positions_and_schema(tmp_path):
    sensors = read_sensors(write(tmp_path, GOOD))
    frame = cat048(
        time_of_day=np.array([86399.0, 5.0, 6.0, np.nan]),
        day=np.array([0, 1, 1, 1]),
        rho_nm=np.array([100.0, np.nan, np.nan, 10.0]), theta_deg=np.array([90.0, np.nan, np.nan, 0.0]),
        x_nm=np.array([np.nan, 0.0, np.nan, np.nan]), y_nm=np.array([np.nan, 0.0, np.nan, np.nan]),
        flight_level=np.array([0.0, 100.0, 50.0, 50.0]),
    )
    meas = radar_measurements(frame, sensors)
    assert list(meas.columns) == MEASUREMENT_COLUMNS
    # row 3 has no position, row 4 no time: both dropped; undated, day 1 continues past 86400
    assert seconds_since(meas["time"], UNDATED_DAY).tolist() == [86399.0, 86405.0]
    assert (meas["sensor_kind"] == "radar").all() and (meas["sensor_id"] == "048:1/2").all()
    assert (meas["aircraft_id"] == "750123").all()
    # polar, site (0, 10, 0), due east, 100 NM, FL 0: chord of the equator, lon = 10 + 2 asin(185200 / 2a)
    assert meas.loc[0, "latitude"] == pytest.approx(0.0, abs=1e-9)
    assert meas.loc[0, "longitude"] == pytest.approx(10 + math.degrees(2 * math.asin(185200 / (2 * A))),
                                                     abs=1e-8)
    # cartesian (0, 0): straight above the site
    assert (meas.loc[1, "latitude"], meas.loc[1, "longitude"]) == pytest.approx((0.0, 10.0), abs=1e-9)
    assert meas["position_item"].tolist() == ["040", "042"]
    assert meas["callsign"].tolist() == ["MAS72", "MAS72"]


def test_radar_measurements_unknown_radar(tmp_path):
    sensors = read_sensors(write(tmp_path, GOOD))
    frame = cat048(time_of_day=np.array([1.0, 2.0, 3.0]), rho_nm=np.full(3, 50.0), theta_deg=np.full(3, 10.0),
                   sac=pd.array([7, 1, 7], dtype="Int32"), sic=pd.array([9, 2, 9], dtype="Int32"))
    with pytest.raises(UnknownRadar) as info:
        radar_measurements(frame, sensors)
    assert info.value.missing == [(7, 9)]
    assert "SAC 7 SIC 9" in str(info.value) and "[[sensor]]" in str(info.value)


def test_radar_measurements_flags_missing_height(tmp_path):
    sensors = read_sensors(write(tmp_path, GOOD))
    frame = cat048(time_of_day=np.array([1.0, 2.0]), rho_nm=np.full(2, 50.0), theta_deg=np.full(2, 10.0),
                   flight_level=np.array([np.nan, 300.0]))
    meas = radar_measurements(frame, sensors)
    assert meas["height_source"].tolist() == ["none", "flight_level"]
    assert np.isnan(meas["height_m"].iloc[0]) and meas["height_m"].iloc[1] == pytest.approx(300 * 30.48)


def test_adsb_measurements():
    n = 3
    frame = pd.DataFrame({
        "sac": pd.array([0] * n, dtype="Int32"), "sic": pd.array([9] * n, dtype="Int32"),
        "time_of_day": [10.0, 11.0, 12.0], "day": np.zeros(n, np.int64),
        "timestamp": pd.Series(pd.NaT, index=range(n), dtype="datetime64[ns, UTC]"),
        "latitude": [1.0, np.nan, 1.2], "longitude": [103.0, 103.1, 103.2],
        "address": pd.Categorical(["750123"] * n), "callsign": pd.Categorical(["mas72"] * n),
        "flight_level": [350.0] * n, "ground_speed_kt": [450.0] * n, "track_angle_deg": [45.0, 46.0, 47.0],
        "nucp_nic": pd.array([7] * n, dtype="Int32"), "nacp": pd.array([9] * n, dtype="Int32"),
    })
    meas = adsb_measurements(frame, date=dt.date(2019, 3, 1))
    assert meas["time"].tolist() == [pd.Timestamp("2019-03-01 00:00:10", tz="UTC"),
                                     pd.Timestamp("2019-03-01 00:00:12", tz="UTC")]
    assert meas["heading_deg"].tolist() == [45.0, 47.0]
    assert meas["callsign"].tolist() == ["MAS72", "MAS72"]
    assert (meas["sensor_kind"] == "adsb").all() and (meas["sensor_id"] == "021:0/9").all()
    # NACp 9: 95 % within 30 m, so sigma = 30 / 2.4477 per axis, isotropic (the 95th percentile of the
    # radius of a circular 2-D Gaussian: the Rayleigh distribution's, by scipy)
    from scipy.stats import rayleigh

    k95 = rayleigh.ppf(0.95)
    assert meas["cov_ee_m2"].tolist() == pytest.approx([(30 / k95) ** 2] * 2)
    assert meas["cov_nn_m2"].tolist() == meas["cov_ee_m2"].tolist() and (meas["cov_en_m2"] == 0).all()
    assert meas["sigma_major_m"].tolist() == pytest.approx([30 / k95] * 2)
    assert meas["height_source"].tolist() == ["flight_level"] * 2


def frame_ids(callsigns, addresses):
    n = len(callsigns)
    return meas_frame(pd.DataFrame({"callsign": callsigns, "address": addresses, "i": range(n),
                                    "time_of_day": np.arange(n, dtype=float), "latitude": 0.0,
                                    "longitude": 0.0, "sensor": "adsb"}))


def test_select_by_callsign_and_address():
    meas = frame_ids(["MAS72", None, "SIA1", None, "MAS72"], ["750123", "750123", "76CD01", None, "750124"])
    # case/space-insensitive; the row without call sign belongs to its address's aircraft
    assert select(meas, callsign="mas 72")["i"].tolist() == [0, 1, 4]
    assert select(meas, address="0x750123")["i"].tolist() == [0, 1]
    assert select(meas, callsign="MAS72", address="750124")["i"].tolist() == [4]
    # a radar plot without address joins the aircraft its call sign is seen with (identity over all sensors)
    both = frame_ids(["SIA1", "SIA1"], ["ABCDEF", None])
    assert both["aircraft_id"].tolist() == ["ABCDEF", "ABCDEF"]
    assert select(both, address="abcdef")["i"].tolist() == [0, 1]


def test_adsb_0_2x_figure_of_merit_is_not_nucp():
    # 0.2x frames have no nucp_nic column; I021/090 PA (fom_pa) is a figure of merit of its own whose scale
    # no spec gives as NUCp's, NIC's or NACp's: it is carried as fom_pa and fills none of them
    from msdc.pipeline.model.measurements import adsb_measurements

    frame = pd.DataFrame({"time_of_day": [1.0, 2.0], "day": [0, 0], "latitude": [1.0, 1.1],
                          "longitude": [100.0, 100.1], "sac": [0, 0], "sic": [1, 1],
                          "fom_pa": pd.array([7, pd.NA], dtype="Int64")})
    out = adsb_measurements(frame)
    assert out["nucp_nic"].isna().all() and out["nacp"].isna().all()
    assert out["fom_pa"].iloc[0] == 7 and pd.isna(out["fom_pa"].iloc[1])


def test_unknown_radar_without_sac_or_sic_gets_no_invalid_toml(tmp_path):
    """A record missing its SAC cannot be declared: the message explains that instead of offering the
    non-TOML line ``sac = <NA>``; a complete unknown pair still gets its [[sensor]] lines."""
    import tomllib

    sensors = read_sensors(write(tmp_path, GOOD))
    frame = cat048(time_of_day=np.array([1.0, 2.0]), rho_nm=np.full(2, 50.0), theta_deg=np.full(2, 10.0),
                   sac=pd.array([None, 7], dtype="Int32"), sic=pd.array([3, 9], dtype="Int32"))
    with pytest.raises(UnknownRadar) as info:
        radar_measurements(frame, sensors)
    text = str(info.value)
    assert "<NA>\n" not in text and "sac = <NA>" not in text
    assert "SAC <NA> SIC 3: records without a complete data source identifier (I048/010)" in text
    snippet = text[text.index("add:\n") + len("add:\n"):]
    assert tomllib.loads(snippet)["sensor"] == [{"name": "radar SAC 7 SIC 9", "sac": 7, "sic": 9,
                                                "latitude": 0.0, "longitude": 0.0, "altitude_m": 0.0}]


def test_radar_offsets_match_the_same_aircraft_within_a_second():
    """30 plots each 0.4 s from an ADS-B report of the same address 0.01 deg of latitude north (1112 m on
    WGS-84 at 41 deg: Geod), and another aircraft's report at the very instant 0.1 deg away: the median
    offset is 1112 m; reports 2 s away are not matched, so 19 plots (below 20) give no row."""
    from pyproj import Geod

    from msdc.pipeline.model.site_check import radar_offsets

    t0 = pd.Timestamp("2019-03-01T08:00:00Z")
    n = 30
    times = t0 + pd.to_timedelta(10.0 * np.arange(n), unit="s")
    plots = pd.DataFrame({"time": times, "sensor_kind": "radar", "sensor_id": "048:25/201",
                          "address": "750123", "latitude": 41.0, "longitude": 2.0,
                          "rho_nm": np.linspace(10.0, 40.0, n)})
    mine = pd.DataFrame({"time": times + pd.Timedelta(seconds=0.4), "sensor_kind": "adsb",
                         "sensor_id": "021:0/107", "address": "750123", "latitude": 41.01, "longitude": 2.0,
                         "rho_nm": np.nan})
    other = mine.assign(time=times, address="4CA5F7", latitude=41.1)
    got = radar_offsets(pd.concat([plots, mine, other], ignore_index=True))
    expected_m = Geod(ellps="WGS84").inv(2.0, 41.0, 2.0, 41.01)[2]
    assert list(got["sensor_id"]) == ["048:25/201"] and int(got["matched_plots"].iloc[0]) == n
    assert abs(float(got["offset_median_m"].iloc[0]) - expected_m) < 0.5
    late = mine.assign(time=np.where(np.arange(n) < 11, times + pd.Timedelta(seconds=2), mine["time"]))
    assert radar_offsets(pd.concat([plots, late, other], ignore_index=True)).empty


def test_sensor_ids_stay_whole_numbers_when_some_report_lacks_its_sac_or_sic():
    """A missing SAC or SIC shows as "?" in its own report's id; the other reports' ids stay "021:1/2" (a
    missing value once turned every pair into floats: "021:1.0/2.0")."""
    from msdc.pipeline.model.measurements import sensor_id

    sac = pd.Series([1, None, 1, 7], dtype="Int64")
    ids = sensor_id(21, sac, pd.Series([2, 2, None, 129], dtype="Int64"))
    assert ids.astype(str).tolist() == ["021:1/2", "021:?/2", "021:1/?", "021:7/129"]
    # a value no SAC byte holds stays itself, not taken for a missing one
    odd = sensor_id(21, pd.Series([-1, None], dtype="Int64"), pd.Series([2, 2], dtype="Int64"))
    assert odd.astype(str).tolist() == ["021:-1/2", "021:?/2"]


def test_records_that_are_no_plot_of_a_real_target_are_left_out_and_said(tmp_path):
    """I048/020 TYP 0 (no detection: the radar tracker's own update), SIM 1 in I048/020 or I021/040
    (a simulated report): no measurement, whichever way the frames are read, each counted once per file.
    TYP 0 with SIM 1 is counted as TYP 0."""
    import warnings

    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame
    from msdc.pipeline.model.load import load_measurements
    from msdc.pipeline.model.measurements import LeftOutWarning, build_measurements

    fix = Path(__file__).resolve().parents[3] / "fixtures"
    sensors = read_sensors(fix / "sensors.toml")
    radar = asterix.read(fix / "radar.ast").frames[48].drop(columns=["file"], errors="ignore")
    adsb = asterix.read(fix / "adsb.ast").frames[21].drop(columns=["file"], errors="ignore")
    radar_path, adsb_path = tmp_path / "r.ast", tmp_path / "a.ast"
    typ = radar["typ"].astype("Int64").to_numpy().copy()
    sim = radar["sim"].astype("Int64").to_numpy().copy()
    typ[[0, 5, 9]] = 0
    sim[[5, 20]] = 1
    marked = radar.assign(typ=pd.array(typ, dtype="Int8"), sim=pd.array(sim, dtype="Int8"))
    adsb_sim = adsb["sim"].astype("Int64").to_numpy().copy()
    adsb_sim[[3]] = 1
    radar_path.write_bytes(encode_frame(48, marked))
    adsb_path.write_bytes(encode_frame(21, adsb.assign(sim=pd.array(adsb_sim, dtype="Int8"))))
    kept_radar = np.ones(len(radar), bool)
    kept_radar[[0, 5, 9, 20]] = False
    kept_adsb = np.ones(len(adsb), bool)
    kept_adsb[3] = False

    loaded, meas = load_measurements([radar_path, adsb_path], sensors, date="2019-03-01")
    plain_loaded, plain = load_measurements([fix / "radar.ast", fix / "adsb.ast"], sensors, date="2019-03-01")
    by_kind = meas["sensor_kind"].astype(str)
    plain_kind = plain["sensor_kind"].astype(str)
    for kind, kept in (("radar", kept_radar), ("adsb", kept_adsb)):  # the same reports bar those marked
        for column in ("time", "latitude", "longitude"):
            assert meas.loc[by_kind == kind, column].tolist() == \
                plain.loc[plain_kind == kind, column].to_numpy()[kept].tolist(), (kind, column)
    said = [w for w in loaded.warnings if "left out of the measurements" in w]
    tail = " left out of the measurements: they are no plot of a real target"
    assert said == ["r.ast: 3 CAT048 records without a plot (I048/020 TYP 0, no detection: the radar "
                    "tracker's own updates) and 1 CAT048 record simulated (SIM 1)" + tail,
                    "a.ast: 1 CAT021 record simulated (SIM 1)" + tail]
    assert not [w for w in plain_loaded.warnings if "left out of the measurements" in w]

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        built = build_measurements(asterix.read(radar_path).frames[48], asterix.read(adsb_path).frames[21],
                                   sensors, date="2019-03-01")
    assert len(built) == len(meas)
    texts = [str(w.message) for w in caught if issubclass(w.category, LeftOutWarning)]
    assert texts == ["the inputs: 1 CAT021 record simulated (SIM 1) and 3 CAT048 records without a plot "
                     "(I048/020 TYP 0, no detection: the radar tracker's own updates) and 1 CAT048 record "
                     "simulated (SIM 1)" + tail]
