"""Sector layers from a GeoJSON file: hand-made polygons (a hole, a band, a MultiPolygon, one at the
antimeridian) and points worked out by hand to lie inside or outside; every refusal names the file, the
feature and the reason."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from msdc.pipeline.evaluate.presets import load_preset
from msdc.pipeline.evaluate.sectors import (
    Sector,
    area_overlaps,
    check_preset_areas,
    read_sectors,
    sector_mask,
    sectors_for_area,
)

ROOT = Path(__file__).resolve().parents[3]


def square(west, south, east, north):
    """A closed ring, counter-clockwise, [longitude, latitude]."""
    return [[west, south], [east, south], [east, north], [west, north], [west, south]]


def feature(name, rings, *, kind="Polygon", **properties):
    props = {} if name is None else {"name": name}
    props.update(properties)
    return {"type": "Feature", "properties": props, "geometry": {"type": kind, "coordinates": rings}}


# an apron 2.0-2.1 E, 41.0-41.1 N with a hole 2.04-2.06 E, 41.04-41.06 N; a TMA band FL 100 to 245 over
# 1-3 E, 40-42 N; two runway rectangles as one MultiPolygon; a box touching the antimeridian from the west
FEATURES = [
    feature("Apron T1", [square(2.0, 41.0, 2.1, 41.1), square(2.04, 41.04, 2.06, 41.06)], area="apron"),
    feature("TMA lower", [square(1.0, 40.0, 3.0, 42.0)], min_fl=100, max_fl=245),
    feature("Runways", [[square(2.07, 41.28, 2.10, 41.29)], [square(2.08, 41.30, 2.09, 41.33)]],
            kind="MultiPolygon", area="manoeuvring", stroke="#ff0000"),
    feature("Fiji box", [square(179.0, -17.0, 180.0, -16.0)], min_fl=0),
]


def write(tmp_path: Path, doc, name: str = "sectors.geojson") -> Path:
    path = tmp_path / name
    path.write_text(doc if isinstance(doc, str) else json.dumps(doc), encoding="utf-8")
    return path


def collection(*features):
    return {"type": "FeatureCollection", "features": list(features)}


@pytest.fixture()
def sectors(tmp_path: Path) -> list[Sector]:
    return read_sectors(write(tmp_path, collection(*FEATURES)))


def test_the_sectors_are_read_in_file_order_with_their_properties(sectors) -> None:
    got = [(s.name, s.area, s.min_fl, s.max_fl, len(s.polygons)) for s in sectors]
    assert got == [("Apron T1", "apron", None, None, 1), ("TMA lower", None, 100.0, 245.0, 1),
                   ("Runways", "manoeuvring", None, None, 2), ("Fiji box", None, 0.0, None, 1)]
    assert len(sectors[0].polygons[0]) == 2  # the outer ring and its hole
    assert [s.name for s in sectors_for_area(sectors, "apron")] == ["Apron T1"]
    assert sectors_for_area(sectors, "stands") == []
    # without an area property a sector belongs to the area of its own name
    assert [s.name for s in sectors_for_area(sectors, "TMA lower")] == ["TMA lower"]


def test_a_point_in_the_hole_is_outside(sectors) -> None:
    apron = sectors[0]
    # inside the outer ring / in the hole / east of the apron / on the hole's east side, still in the apron
    lat = [41.02, 41.05, 41.05, 41.05, math.nan]
    lon = [2.02, 2.05, 2.15, 2.08, 2.02]
    assert sector_mask(apron, lat, lon).tolist() == [True, False, False, True, False]
    # an unbanded sector does not ask for a flight level: a missing one leaves the point inside
    assert sector_mask(apron, lat, lon, [math.nan] * 5).tolist() == [True, False, False, True, False]


def test_the_band_holds_its_lower_level_and_not_its_upper(sectors) -> None:
    tma = sectors[1]
    lat, lon = [41.0] * 6 + [43.0], [2.0] * 6 + [2.0]
    fl = [99.9, 100.0, 200.0, 244.9, 245.0, math.nan, 200.0]
    assert sector_mask(tma, lat, lon, fl).tolist() == [False, True, True, True, False, False, False]
    # without flight levels nothing is inside a banded sector
    assert not sector_mask(tma, lat, lon).any()


def test_either_polygon_of_a_multipolygon_holds(sectors) -> None:
    runways = sectors[2]
    lat = [41.285, 41.315, 41.295, 41.315]
    lon = [2.085, 2.085, 2.085, 2.095]  # the first, the second, between them, east of the second
    assert sector_mask(runways, lat, lon).tolist() == [True, True, False, False]


def test_a_box_at_the_antimeridian_does_not_reach_across_it(sectors) -> None:
    fiji = sectors[3]  # min_fl 0 only: every level from 0 up
    lat, lon, fl = [-16.5, -16.5, -16.5], [179.5, -179.5, 179.5], [10.0, 10.0, -1.0]
    assert sector_mask(fiji, lat, lon, fl).tolist() == [True, False, False]


def test_a_flight_level_may_be_one_number_for_all(sectors) -> None:
    assert sector_mask(sectors[1], [41.0, 41.5], [2.0, 2.5], 150.0).tolist() == [True, True]


BAD = [
    ("not json", "{", "not a GeoJSON file (JSON error at line 1"),
    ("a geometry", {"type": "Polygon", "coordinates": [square(0, 0, 1, 1)]},
     "a sectors file is a GeoJSON FeatureCollection, this is a Polygon"),
    ("a list", [1, 2], "a sectors file is a GeoJSON FeatureCollection, this is not GeoJSON"),
    ("no features", collection(), "a FeatureCollection without features"),
    ("not a feature", collection(FEATURES[0], {"type": "Polygon"}), "feature 2: not a GeoJSON Feature"),
    ("no name", collection(FEATURES[0], feature(None, [square(0, 0, 1, 1)])),
     "feature 2: property 'name' must be a non-empty text, got missing"),
    ("blank name", collection(feature("  ", [square(0, 0, 1, 1)])),
     "feature 1: property 'name' must be a non-empty text, got '  ' (str)"),
    ("number name", collection(feature(7, [square(0, 0, 1, 1)])),
     "feature 1: property 'name' must be a non-empty text, got 7 (int)"),
    ("duplicate", collection(FEATURES[0], FEATURES[1], feature("Apron T1", [square(0, 0, 1, 1)])),
     "feature 3 ('Apron T1'): the name is already feature 1's; sector names must be unique"),
    ("area number", collection(feature("A", [square(0, 0, 1, 1)], area=3)),
     "feature 1 ('A'): property 'area' must be a non-empty text, got 3 (int)"),
    ("band text", collection(feature("A", [square(0, 0, 1, 1)], min_fl="100")),
     "feature 1 ('A'): property 'min_fl' must be a finite number (a flight level, e.g. 245), got '100'"),
    ("band bool", collection(feature("A", [square(0, 0, 1, 1)], max_fl=True)),
     "feature 1 ('A'): property 'max_fl' must be a finite number (a flight level, e.g. 245), got True"),
    ("band reversed", collection(feature("A", [square(0, 0, 1, 1)], min_fl=245, max_fl=100)),
     "feature 1 ('A'): min_fl 245 is not below max_fl 100"),
    ("misspelt band", collection(feature("A", [square(0, 0, 1, 1)], max_FL=100)),
     "feature 1 ('A'): property 'max_FL' is not one msdc reads (did you mean 'max_fl'?)"),
    ("properties list", collection({"type": "Feature", "properties": [1],
                                    "geometry": {"type": "Polygon", "coordinates": [square(0, 0, 1, 1)]}}),
     "feature 1: 'properties' must be an object, got [1]"),
    ("a point", collection(feature("P", [2.0, 41.0], kind="Point")),
     "feature 1 ('P'): its geometry is a Point, not a Polygon or MultiPolygon"),
    ("no geometry", collection({"type": "Feature", "properties": {"name": "G"}, "geometry": None}),
     "feature 1 ('G'): its geometry is a non-geometry, not a Polygon or MultiPolygon"),
    ("short ring", collection(feature("R", [[[0, 0], [1, 1]]])),
     "feature 1 ('R'), ring 1: a ring needs at least 3 finite positions"),
    ("bad position", collection(feature("R", [[[0, 0], [1, "x"], [1, 1]]])),
     "feature 1 ('R'), ring 1: positions must be [longitude, latitude] numbers"),
    ("latitude first", collection(feature("R", [square(41.0, 2.0, 41.1, 95.0)])),
     "feature 1 ('R'), ring 1: a position is off the Earth"),
    ("across 180", collection(feature("R", [[[179.5, 0], [-179.5, 0], [-179.5, 1], [179.5, 0]]])),
     "feature 1 ('R'), ring 1: an edge spans more than 180 degrees of longitude"),
    ("empty multipolygon", collection(feature("M", [], kind="MultiPolygon")),
     "feature 1 ('M') has no coordinates"),
    ("multipolygon ring", collection(feature("M", [[square(0, 0, 1, 1)], [[[0, 0]]]], kind="MultiPolygon")),
     "feature 1 ('M'), polygon 2, ring 1: a ring needs at least 3 finite positions"),
    ("text position", collection(feature("R", [[["0", "0"], ["1", "0"], ["1", "1"], ["0", "0"]]])),
     "feature 1 ('R'), ring 1: positions must be [longitude, latitude] numbers"),
    ("named global", collection(feature("global", [square(0, 0, 1, 1)])),
     "feature 1 ('global'): the name 'global' is the scorecard's own"),
    ("named surface", collection(feature("surface", [square(0, 0, 1, 1)])),
     "feature 1 ('surface'): the name 'surface' is the scorecard's own"),
    ("too deep", "[" * 100_000 + "]" * 100_000, "not a GeoJSON file (nested too deeply to read)"),
    ("flat ring", collection(feature("R", [[[0, 0], [1, 1], [0, 0]]])),
     "feature 1 ('R'), ring 1: a ring needs at least 3 different positions"),
    # read as two numbers, the altitude seemed to band the sector and did not
    ("altitude", collection(feature("R", [[[0, 0, 100.0], [1, 0, 100.0], [1, 1, 100.0], [0, 0, 100.0]]])),
     "feature 1 ('R'), ring 1: a position carries an altitude (100.0); msdc reads longitude and latitude"),
]


@pytest.mark.parametrize(("doc", "message"), [(d, m) for _, d, m in BAD], ids=[i for i, _, _ in BAD])
def test_bad_sector_files_are_refused_naming_file_feature_and_reason(tmp_path: Path, doc, message) -> None:
    path = write(tmp_path, doc)
    with pytest.raises(ValueError) as caught:
        read_sectors(path)
    assert str(caught.value).startswith(f"{path}: "), str(caught.value)
    assert message in str(caught.value)


def test_an_unreadable_file_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"missing.geojson: cannot be read"):
        read_sectors(tmp_path / "missing.geojson")
    path = tmp_path / "latin1.geojson"
    path.write_bytes(b'{"name": "\xe9"}')
    with pytest.raises(ValueError, match=r"latin1.geojson: not a GeoJSON file \(not UTF-8 text\)"):
        read_sectors(path)


def test_a_preset_area_no_sector_provides_is_reported(sectors) -> None:
    preset = load_preset("ed117a")
    warnings = check_preset_areas(preset, sectors)
    # ed117a.toml: manoeuvring (4 requirements) and apron are provided; stands has 4, approach-inner and
    # approach-outer 2 each, all left out
    missing = [w for w in warnings if w.startswith("preset ed117a: no sector has area")]
    assert [w.split("'")[1] for w in missing] == ["stands", "approach-inner", "approach-outer"]
    assert "its 4 requirements (" in missing[0] and missing[0].endswith("are not evaluated")
    assert not any("'apron'" in w or "'manoeuvring'" in w for w in missing)
    assert check_preset_areas(load_preset("ed87e"), sectors) == [
        "sector 'Apron T1': area 'apron' is not one of preset ed87e's areas (manoeuvring): no area "
        "requirement applies to it"]


def test_an_example_file_reads(tmp_path: Path) -> None:
    example = ROOT / "docs" / "examples" / "lebl-areas.geojson"
    if not example.exists():
        pytest.skip(f"{example} not written yet")
    sectors = read_sectors(example)
    assert {s.area for s in sectors} <= {"manoeuvring", "apron", "stands"}
    assert np.all([len(s.polygons) >= 1 for s in sectors])
    # its areas do not overlap: a 3 m grid over the airport falls in sectors of one area at most
    lon, lat = np.meshgrid(np.arange(2.055, 2.105, 3.0 / 83_760.0),
                           np.arange(41.280, 41.312, 3.0 / 111_132.0))
    lat, lon = lat.ravel(), lon.ravel()
    area_of_point = {}
    for s in sectors:
        for k in np.flatnonzero(sector_mask(s, lat, lon)):
            area_of_point.setdefault(int(k), set()).add(s.area)
    assert area_of_point and max(len(a) for a in area_of_point.values()) == 1


def test_sectors_of_two_areas_sharing_reports_are_noted() -> None:
    """Two squares of different areas overlapping by a quarter, a third of the same area as the first: of
    nine points, one lies in the overlap of the two areas, one only in the two same-area sectors."""
    x = np.array([0.5, 1.5, 2.5, 0.5, 1.5, 2.5, 0.5, 1.5, 2.5])
    y = np.array([0.5, 0.5, 0.5, 1.5, 1.5, 1.5, 2.5, 2.5, 2.5])
    a = (x < 2) & (y < 2)  # [0, 2) x [0, 2)
    b = (x > 1) & (y > 1)  # (1, 3] x (1, 3]: shares (1.5, 1.5) with a
    c = (x < 1) & (y < 1)  # inside a, same area
    note = area_overlaps([("A", "apron", a), ("B", "manoeuvring", b), ("C", "apron", c)], "reports")
    assert note == ("sectors of different areas overlap where 1 of the reports lie ('A' (apron) and 'B' "
                    "(manoeuvring): 1): those are judged under both areas' requirements; draw the areas "
                    "apart")
    assert area_overlaps([("A", "apron", a), ("C", "apron", c)]) == ""


def test_a_zero_altitude_as_map_editors_write_it_is_read(tmp_path: Path) -> None:
    ring = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 0, 0]]
    (sector,) = read_sectors(write(tmp_path, collection(feature("R", [ring]))))
    flat = read_sectors(write(tmp_path, collection(feature("R", [[q[:2] for q in ring]]))))[0]
    assert str(sector) == str(flat)
