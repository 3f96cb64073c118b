"""The report selection (pipeline.model.report_selection, pipeline.model.polygons): each criterion against
values worked out here by hand or by another method (matplotlib's point-in-polygon, the fixtures' own
WGS-84 geodesy for range and azimuth)."""

from __future__ import annotations

import datetime as dt
import json

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path as MplPath

from fixtures import geodesy as geo
from msdc.pipeline.model import report_selection as rs
from msdc.pipeline.model.polygons import inside, read_polygons

DAY = dt.date(2023, 5, 2)


def _reports(**columns) -> pd.DataFrame:
    n = len(next(iter(columns.values())))
    base = {"time": pd.Series([pd.Timestamp("2023-05-02T08:00:00Z")] * n),
            "sensor_id": ["048:20/129"] * n, "flight_level": [100.0] * n}
    return pd.DataFrame(base | columns)


# ---------------------------------------------------------------------------------------------------------
# Option texts


@pytest.mark.parametrize("text, expected", [
    ("2023-05-02T08:10:00", pd.Timestamp("2023-05-02T08:10:00Z")),
    ("2023-05-02T08:10:00Z", pd.Timestamp("2023-05-02T08:10:00Z")),
    ("2023-05-02 08:10:00.5+00:00", pd.Timestamp("2023-05-02T08:10:00.5Z")),
    ("2023-05-02", pd.Timestamp("2023-05-02T00:00:00Z")),
])
def test_iso_date_times_are_utc_instants(text, expected):
    assert rs.parse_time(text, "--from").on(DAY, "--from") == expected


@pytest.mark.parametrize("text, seconds", [("08:10", 29400.0), ("8:10:30.5", 29430.5), ("23:59:59", 86399.0),
                                           ("00:00", 0.0)])
def test_a_time_of_day_is_placed_on_the_recording_s_day(text, seconds):
    bound = rs.parse_time(text, "--to")
    assert bound.time_of_day_s == seconds
    assert bound.on(DAY, "--to") == pd.Timestamp("2023-05-02T00:00:00Z") + pd.Timedelta(seconds=seconds)


@pytest.mark.parametrize("text, said", [
    ("2023-05-02T10:10:00+02:00", "UTC offset of 2:00:00"),
    ("24:00", "hours 0-23"),
    ("08:61", "minutes and seconds 0-59"),
    ("yesterday", "not a UTC time"),
    ("2023-13-02T08:00", "not a UTC time"),
])
def test_times_refused_name_the_option_the_value_and_why(text, said):
    with pytest.raises(ValueError) as err:
        rs.parse_time(text, "--from")
    assert str(err.value).startswith(f"--from {text!r}") and said in str(err.value)


def test_a_time_of_day_without_the_recording_s_day_is_refused():
    with pytest.raises(ValueError, match=r"--from 08:10: the inputs carry no date.*--date"):
        rs.ReportSelection(start=rs.parse_time("08:10", "--from")).window(None)


def test_an_empty_window_is_refused():
    start, end = rs.parse_time("08:10", "--from"), rs.parse_time("08:10", "--to")
    with pytest.raises(ValueError, match="is not before --to 08:10"):
        rs.ReportSelection(start=start, end=end).window(DAY)
    with pytest.raises(ValueError, match="--from 08:10 is not before --to 08:10: the window holds no time"):
        rs.check_order(start, end)
    rs.check_order(start, rs.parse_time("2023-05-02T08:00", "--to"))  # one of each: judged once placed
    with pytest.raises(ValueError, match=r"--from 08:10 \(2023-05-02T08:10:00\+00:00\) is not before"):
        rs.ReportSelection(start=start, end=rs.parse_time("2023-05-02T08:00", "--to")).window(DAY)


@pytest.mark.parametrize("text, band", [("100:245", (100.0, 245.0)), ("245:", (245.0, 1000.0)),
                                        (":100", (-20.0, 100.0)), ("-10:0", (-10.0, 0.0))])
def test_flight_level_bands(text, band):
    assert rs.parse_fl(text) == band


@pytest.mark.parametrize("text, said", [("100", "expected MIN:MAX"), ("a:b", "expected MIN:MAX"),
                                        (":", "expected MIN:MAX"), ("300:200", "MIN 300 is above MAX 200"),
                                        ("0:2000", "2000 is outside FL -20 to 1000"),
                                        ("nan:100", "outside")])
def test_flight_level_bands_refused(text, said):
    with pytest.raises(ValueError) as err:
        rs.parse_fl(text)
    assert str(err.value).startswith(f"--fl {text!r}") and said in str(err.value)


@pytest.mark.parametrize("text, ref", [("20/129", (None, 20, 129, None)), ("20_129", (None, 20, 129, None)),
                                       ("048:20/129", (48, 20, 129, None)),
                                       ("010:0/107:mlat", (10, 0, 107, "mlat"))])
def test_sensor_names(text, ref):
    got = rs.parse_sensor(text)
    assert (got.category, got.sac, got.sic, got.kind) == ref


@pytest.mark.parametrize("text", ["radar", "20/300", "048:20/129:smr", "20/129/1", ""])
def test_sensor_names_refused(text):
    with pytest.raises(ValueError, match=f"--sensor {text!r}"):
        rs.parse_sensor(text)


@pytest.mark.parametrize("text", ["20/129:0-60:30-120deg", "20/129:60-0nm:30-120deg", "20/129:0-60nm",
                                  "20/129:0-60nm:30-400deg", "20/129:0-60nm:30-30deg", "x:0-60nm:0-90deg",
                                  "20/129:0-60nm:360-0deg"])
def test_sensor_windows_refused(text):
    with pytest.raises(ValueError, match=f"--area {text!r}"):
        rs.parse_window(text)


# ---------------------------------------------------------------------------------------------------------
# The criteria


def test_the_time_window_keeps_from_inclusive_to_exclusive_and_no_time_never():
    times = pd.Series(pd.to_datetime(["2023-05-02T08:09:59.999Z", "2023-05-02T08:10:00Z",
                                      "2023-05-02T08:14:59.999Z", "2023-05-02T08:15:00Z", None], utc=True,
                                     format="ISO8601"))
    sel = rs.ReportSelection(start=rs.parse_time("08:10", "--from"),
                             end=rs.parse_time("2023-05-02T08:15:00Z", "--to"))
    keep, counts = rs.select_reports(_reports(time=times), sel, DAY)
    assert keep.tolist() == [False, True, True, False, False] and counts == {"time": 3}


def test_sensors_by_pair_category_and_kind():
    ids = ["048:20/129", "021:20/129", "048:20/130", "010:0/107:mlat", "010:0/107:smr", None]
    frame = _reports(sensor_id=pd.Series(ids, dtype="category"))
    pick = {("20/129",): [1, 1, 0, 0, 0, 0], ("048:20/129",): [1, 0, 0, 0, 0, 0],
            ("010:0/107:mlat", "20/130"): [0, 0, 1, 1, 0, 0], ("0/107",): [0, 0, 0, 1, 1, 0]}
    for names, expected in pick.items():
        sel = rs.ReportSelection(sensors=tuple(rs.parse_sensor(n) for n in names))
        keep, counts = rs.select_reports(frame, sel, DAY)
        assert keep.astype(int).tolist() == expected, names
        assert counts == {"sensor": len(ids) - sum(expected)}


def test_the_flight_level_band_is_inclusive_and_leaves_out_reports_without_a_level():
    levels = [99.75, 100.0, 245.0, 245.25, np.nan, None]
    frame = _reports(flight_level=pd.array(levels, dtype="Float64"))
    keep, counts = rs.select_reports(frame, rs.ReportSelection(fl=(100.0, 245.0)), DAY)
    assert keep.tolist() == [False, True, True, False, False, False] and counts == {"flight_level": 4}


def test_every_criterion_counts_its_own_left_out():
    frame = _reports(time=pd.Series(pd.to_datetime(["2023-05-02T07:00Z", "2023-05-02T08:30Z"] * 2, utc=True)),
                     flight_level=[50.0, 50.0, 150.0, 150.0])
    sel = rs.ReportSelection(start=rs.parse_time("08:00", "--from"), fl=(100.0, 200.0))
    keep, counts = rs.select_reports(frame, sel, DAY)
    assert keep.tolist() == [False, False, False, True] and counts == {"time": 2, "flight_level": 2}


# ---------------------------------------------------------------------------------------------------------
# Polygons, against matplotlib's point-in-polygon


def _geojson(tmp_path, doc) -> str:
    path = tmp_path / "area.geojson"
    path.write_text(json.dumps(doc))
    return str(path)


def test_polygons_with_a_hole_and_a_multipolygon_agree_with_matplotlib(tmp_path):
    outer = [[1.0, 41.0], [3.0, 41.2], [2.6, 42.4], [1.8, 41.9], [1.2, 42.3], [1.0, 41.0]]  # concave
    hole = [[1.8, 41.3], [2.3, 41.3], [2.3, 41.7], [1.8, 41.7], [1.8, 41.3]]
    other = [[3.5, 40.0], [4.0, 40.0], [3.75, 40.5]]  # left open: the reader closes it
    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [outer, hole]}},
        {"type": "Feature", "properties": {}, "geometry": {"type": "MultiPolygon",
                                                            "coordinates": [[other]]}}]}
    polygons = read_polygons(_geojson(tmp_path, doc))
    rng = np.random.default_rng(7)
    lon, lat = rng.uniform(0.5, 4.5, 20_000), rng.uniform(39.5, 43.0, 20_000)
    xy = np.column_stack([lon, lat])
    expected = ((MplPath(outer).contains_points(xy) & ~MplPath(hole).contains_points(xy))
                | MplPath([*other, other[0]]).contains_points(xy))
    got = inside(polygons, lat, lon)
    assert 1000 < expected.sum() < 19_000
    assert (got == expected).all()
    keep, counts = rs.select_reports(_reports(latitude=lat, longitude=lon),
                                     rs.ReportSelection(area=polygons), DAY)
    assert (keep == expected).all() and counts == {"area": int((~expected).sum())}


def test_a_report_without_a_position_is_outside_any_area(tmp_path):
    square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]]
    polygons = read_polygons(_geojson(tmp_path, {"type": "Polygon", "coordinates": [square]}))
    assert inside(polygons, [0.5, np.nan, 0.5], [0.5, 0.5, np.nan]).tolist() == [True, False, False]


@pytest.mark.parametrize("doc, said", [
    ({"type": "Point", "coordinates": [1, 2]}, "is a Point, not a Polygon"),
    ({"type": "Polygon", "coordinates": [[[0, 0], [1, 0]]]}, "at least 3 finite positions"),
    ({"type": "Polygon", "coordinates": [[[0, 95], [1, 0], [1, 1]]]}, "off the Earth"),
    ({"type": "Polygon", "coordinates": [[[179, 0], [-179, 0], [-179, 1]]]}, "antimeridian"),
    ({"type": "FeatureCollection", "features": []}, "no Polygon or MultiPolygon"),
])
def test_bad_geojson_is_refused_naming_the_file(tmp_path, doc, said):
    path = _geojson(tmp_path, doc)
    with pytest.raises(ValueError) as err:
        read_polygons(path)
    assert str(err.value).startswith(path) and said in str(err.value)


def test_a_file_that_is_not_json_is_refused(tmp_path):
    path = tmp_path / "area.geojson"
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not a GeoJSON file .JSON error at line 1"):
        read_polygons(path)


# ---------------------------------------------------------------------------------------------------------
# A sensor's range/azimuth window, against the fixtures' geodesy


SITE = (41.2, 2.0, 120.0)  # latitude, longitude (deg), altitude (m)


def _window(text: str) -> rs.SensorWindow:
    sensors = pd.DataFrame({"sac": [20], "sic": [129], "category": [48], "kind": ["radar"],
                            "latitude": [SITE[0]], "longitude": [SITE[1]], "altitude_m": [SITE[2]]})
    return rs.with_site(rs.parse_window(text), sensors, "sensors.toml")


@pytest.mark.parametrize("text, az", [("20/129:10-60nm:30-120deg", (30.0, 120.0)),
                                      ("20_129:10-60nm:300-60deg", (300.0, 60.0))])
def test_the_window_keeps_positions_at_their_slant_range_and_azimuth(text, az):
    rng = np.random.default_rng(3)
    n = 5000
    lat = SITE[0] + rng.uniform(-1.3, 1.3, n)
    lon = SITE[1] + rng.uniform(-1.7, 1.7, n)
    h = rng.uniform(0.0, 12_000.0, n)
    enu = geo.ecef_to_enu(geo.geodetic_to_ecef(lat, lon, h), *SITE)
    e, nn, u = enu[..., 0], enu[..., 1], enu[..., 2]
    rho_nm = np.sqrt(e**2 + nn**2 + u**2) / geo.M_PER_NM
    azimuth = np.degrees(np.arctan2(e, nn)) % 360.0
    after, before = azimuth >= az[0], azimuth <= az[1]
    in_az = after & before if az[0] < az[1] else after | before
    expected = (rho_nm >= 10.0) & (rho_nm <= 60.0) & in_az
    frame = _reports(sensor_id=["021:0/1"] * n, latitude=lat, longitude=lon, height_m=h)
    keep, counts = rs.select_reports(frame, rs.ReportSelection(area=_window(text)), DAY)
    assert 200 < expected.sum() < n - 200
    assert (keep == expected).all() and counts == {"area": int((~expected).sum())}


def test_the_window_s_own_radar_plots_are_judged_by_their_decoded_range_and_azimuth():
    """The positions are far off on purpose: the plots of 048:20/129 go by rho and theta as decoded, another
    radar's plot with the same rho and theta by its position."""
    frame = _reports(sensor_id=["048:20/129", "048:20/129", "048:20/129", "048:20/130"],
                     rho_nm=[59.99, 60.01, 30.0, 30.0], theta_deg=[45.0, 45.0, 121.0, 45.0],
                     latitude=[0.0] * 4, longitude=[0.0] * 4, height_m=[0.0] * 4)
    keep, _ = rs.select_reports(frame, rs.ReportSelection(area=_window("20/129:0-60nm:30-120deg")), DAY)
    assert keep.tolist() == [True, False, False, False]


def test_a_window_needs_the_sensor_in_the_sensor_file():
    window = rs.parse_window("20/130:0-60nm:0-90deg")
    sensors = pd.DataFrame({"sac": [20], "sic": [129], "category": [48], "kind": ["radar"],
                            "latitude": [1.0], "longitude": [1.0], "altitude_m": [0.0]})
    with pytest.raises(ValueError, match="no sensor 20/130 in s.toml"):
        rs.with_site(window, sensors, "s.toml")
    with pytest.raises(ValueError, match="needs the sensor's site: give --sensors"):
        rs.with_site(window, sensors, None)


@settings(deadline=None)
@given(st.lists(st.integers(0, 86_399_999), min_size=1, max_size=60), st.integers(0, 86_399_999),
       st.integers(0, 86_399_999))
def test_consecutive_windows_split_the_reports_without_sharing_one(ms, a, b):
    """[from, b) and [b, to) keep disjoint reports whose union is [from, to)'s: no report counted twice at a
    boundary, none lost (times in milliseconds of the day, bounds as times of day)."""
    lo, hi = sorted((a, b))
    mid = (lo + hi) // 2
    frame = _reports(time=pd.Series(pd.Timestamp("2023-05-02", tz="UTC") + pd.to_timedelta(ms, unit="ms")))

    def kept(start: int, end: int) -> np.ndarray:
        clock = [f"{t // 3_600_000:02d}:{t // 60_000 % 60:02d}:{t % 60_000 / 1000:06.3f}"
                 for t in (start, end)]
        sel = rs.ReportSelection(start=rs.parse_time(clock[0], "--from"), end=rs.parse_time(clock[1], "--to"))
        return rs.select_reports(frame, sel, DAY)[0]

    if not lo < mid < hi:
        return
    first, second, whole = kept(lo, mid), kept(mid, hi), kept(lo, hi)
    assert not (first & second).any() and ((first | second) == whole).all()
    assert whole.tolist() == [lo <= t < hi for t in ms]


def test_a_span_is_cut_into_consecutive_windows_the_last_shorter():
    """65 minutes in windows of 20: 13:30, 13:50, 14:10, 14:30 and the last 5 minutes to 14:35; each
    window's end the next one's start (--to left out: no report in two windows)."""
    from msdc.pipeline.model.report_selection import ReportSelection, parse_time, span_windows

    span = ReportSelection(start=parse_time("2026-11-28T13:30", "--from"),
                           end=parse_time("2026-11-28T14:35Z", "--to"), fl=(100.0, 200.0), fl_text="100:200")
    windows = span_windows(span, 20)
    starts = [w.start.instant for w in windows]
    assert starts == [pd.Timestamp(f"2026-11-28T{t}", tz="UTC") for t in ("13:30", "13:50", "14:10", "14:30")]
    assert [w.end.instant for w in windows[:-1]] == starts[1:]
    assert windows[-1].end.instant == span.end.instant and windows[0].start.instant == span.start.instant
    # every edge labelled alike, the user's own "2026-11-28T13:30" included
    assert [(w.start.text, w.end.text) for w in windows] == [
        ("2026-11-28T13:30:00Z", "2026-11-28T13:50:00Z"), ("2026-11-28T13:50:00Z", "2026-11-28T14:10:00Z"),
        ("2026-11-28T14:10:00Z", "2026-11-28T14:30:00Z"), ("2026-11-28T14:30:00Z", "2026-11-28T14:35:00Z")]
    assert all(w.fl == (100.0, 200.0) for w in windows)  # the other criteria stay
    morning = ReportSelection(start=parse_time("08:00", "--from"), end=parse_time("08:25:30", "--to"))
    day = span_windows(morning, 10.5)
    assert [(w.start.text, w.end.text) for w in day] == [("08:00", "08:10:30"), ("08:10:30", "08:21"),
                                                          ("08:21", "08:25:30")]
    assert [w.start.time_of_day_s for w in day] == [28800.0, 29430.0, 30060.0]
    assert len(span_windows(span, 65)) == 1 and len(span_windows(span, 64.99)) == 2


# ---------------------------------------------------------------------------------------------------------
# What the outputs record


def test_the_record_holds_the_options_as_given_the_instants_and_the_band_applied():
    """--from 08:10 --to 08:40 --fl 100: on 2 May 2023: the texts as typed, the instants as msdc's JSON
    writes every time (ISO 8601 UTC to the millisecond, Z), and the open band's bounds (FL 100 to FL 1000,
    the highest --fl takes); the terminal line gives the band applied, as an option that selects alike."""
    sel = rs.ReportSelection(start=rs.parse_time("08:10", "--from"), end=rs.parse_time("08:40", "--to"),
                             fl=rs.parse_fl("100:"), fl_text="100:")
    record = rs.recorded(sel, DAY, 44, 11, {"time": 22, "flight_level": 23})
    assert {k: record[k] for k in ("from", "to", "fl", "fl_bounds", "from_utc", "to_utc")} == {
        "from": "08:10", "to": "08:40", "fl": "100:", "fl_bounds": [100.0, 1000.0],
        "from_utc": "2023-05-02T08:10:00.000Z", "to_utc": "2023-05-02T08:40:00.000Z"}
    line = rs.describe(record)
    assert line.startswith("selection --from 08:10 --to 08:40 --fl 100:1000: 11 of 44 reports kept")
