"""The commands take multilateration and surface radar recordings: CAT010 and CAT021 files encoded here
(positions made with pyproj's geodesic), correlated, assessed and tracked from the command line."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from pyproj import Geod

from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main

GEOD = Geod(ellps="WGS84")
REF = (45.0, 5.0)
T = np.arange(0.0, 300.0, 1.0)
NORTH = 5.0 * T - 750.0  # one aircraft due north at 5 m/s (about 10 kt), on the surface
SENSORS = f"""
[[sensor]]
name = "MLAT"
category = 10
kind = "mlat"
sac = 0
sic = 107
latitude = {REF[0]}
longitude = {REF[1]}
altitude_m = 0.0

[[sensor]]
name = "SMR"
category = 10
kind = "smr"
sac = 0
sic = 7
latitude = {REF[0]}
longitude = {REF[1]}
altitude_m = 0.0
"""


def _run(argv, capsys) -> tuple[int, str, str]:
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def files(tmp_path):
    """ADS-B (CAT021 2.7) of aircraft 4CA1B2, the multilateration's reports of it 20 m east (CAT010, x/y
    from the reference point, TYP 1), and the surface radar's 12 m north of those (TYP 3, no identity,
    track 5), with a status message per second; and the sensor file."""
    lon, lat, _ = GEOD.fwd(np.full(T.size, REF[1]), np.full(T.size, REF[0]), np.where(NORTH >= 0, 0.0, 180.0),
                           np.abs(NORTH))
    adsb = pd.DataFrame({"sac": 0, "sic": 107, "time_of_day": T, "latitude": lat, "longitude": lon,
                         "address": "4CA1B2", "callsign": "RYR1AB", "nacp": 10, "ground_speed_kt": 9.7})
    mlat = pd.DataFrame({"sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": T, "x_m": 20.0,
                         "y_m": np.round(NORTH), "address": "4CA1B2", "callsign": "RYR1AB", "track_number": 9,
                         "vx_ms": 0.0, "vy_ms": 5.0})
    status = pd.DataFrame({"sac": 0, "sic": 107, "message_type": 2, "time_of_day": T + 0.5})
    smr = pd.DataFrame({"sac": 0, "sic": 7, "message_type": 1, "typ": 3, "time_of_day": T, "x_m": 20.0,
                        "y_m": np.round(NORTH) + 12.0, "track_number": 5, "vx_ms": 0.0, "vy_ms": 5.0})
    paths = {name: tmp_path / f"{name}.ast" for name in ("adsb", "mlat", "smr")}
    paths["adsb"].write_bytes(encode_frame(21, adsb, edition="2.7"))
    paths["mlat"].write_bytes(encode_frame(10, pd.concat([mlat, status], ignore_index=True)))
    paths["smr"].write_bytes(encode_frame(10, smr))
    paths["sensors"] = tmp_path / "sensors.toml"
    paths["sensors"].write_text(SENSORS)
    return paths


@pytest.mark.parametrize(("pairs", "inputs", "tested", "reference", "sep_m"), [
    ("mlat-adsb", ("adsb", "mlat"), "010:0/107:mlat", "021:0/107", 20.0),
    ("smr-mlat", ("smr", "mlat"), "010:0/7:smr", "010:0/107:mlat", 12.0),
])
def test_correlate_pairs(files, tmp_path, capsys, pairs, inputs, tested, reference, sep_m):
    out = tmp_path / "c.json"
    status, _, err = _run(["correlate", *(files[i] for i in inputs), "--sensors", files["sensors"], "--all",
                           "--pairs", pairs, "--date", "2016-05-10", "--json", out], capsys)
    assert status == 0, err
    (window,) = json.loads(out.read_text())["windows"]
    assert (window["radar_sensor"], window["reference_sensor"]) == (tested, reference)
    # x/y rounded to the metre: the separation is the offset within 0.5 m
    assert window["sep_median_m"] == pytest.approx(sep_m, abs=0.5)


def test_a_missing_reference_point_stops_the_run_with_its_lines(files, tmp_path, capsys):
    files["sensors"].write_text("[[sensor]]" + SENSORS.split("[[sensor]]")[2])  # the surface radar's alone
    out = tmp_path / "c.json"
    status, _, err = _run(["correlate", files["adsb"], files["mlat"], "--sensors", files["sensors"], "--all",
                           "--pairs", "mlat-adsb", "--json", out], capsys)
    assert status == 1 and not out.exists()
    assert "CAT010 multilateration SAC/SIC 0/107" in err and f"not in {files['sensors']}" in err
    assert 'kind = "mlat"' in err and "sic = 107" in err


def test_a_missing_category_is_named(files, tmp_path, capsys):
    status, _, err = _run(["correlate", files["adsb"], "--sensors", files["sensors"], "--all", "--pairs",
                           "mlat-adsb", "--json", tmp_path / "c.json"], capsys)
    assert status == 1 and "no multilateration (CAT010 or CAT020) records in the inputs" in err


def test_quality_measures_the_reference_points(files, tmp_path, capsys):
    out = tmp_path / "q.json"
    status, text, err = _run(["quality", files["adsb"], files["mlat"], files["smr"], "--sensors",
                              files["sensors"], "--all", "--date", "2016-05-10", "--json", out], capsys)
    assert status == 0, err
    tables = json.loads(out.read_text())["tables"]
    rows = {r["sensor_id"]: r for r in tables["Reference points"]}
    assert rows["010:0/107:mlat"]["reference"] == "adsb"
    assert rows["010:0/107:mlat"]["east_offset_m"] == pytest.approx(20.0, abs=0.5)
    assert rows["010:0/7:smr"]["north_offset_m"] == pytest.approx(12.0, abs=0.5)
    # the aircraft taxies at about 10 kt: pooled with the aircraft on the surface, but by the
    # multilateration, whose reports here say airborne (I010/020 GBS clear), and a report is believed
    pooled = {(r["callsign"], r["sensor"], r["sic"]) for r in tables["Quality"]
              if r["callsign"].startswith("(")}
    assert pooled == {("(all surface)", "adsb", 107), ("(all)", "mlat", 107), ("(all surface)", "smr", 7)}
    assert "Reference points" in text


def test_track_fuses_the_kinds_asked_for(files, tmp_path, capsys):
    out = tmp_path / "t.json"
    status, _, err = _run(["track", files["mlat"], files["smr"], "--sensors", files["sensors"], "--all",
                           "--sources", "mlat", "--date", "2016-05-10", "--json", out], capsys)
    assert status == 0, err
    (aircraft,) = json.loads(out.read_text())["aircraft"]
    sensors = {row["sensor_id"] for row in aircraft["sensors"]}
    assert sensors == {"010:0/107:mlat"}  # the surface radar's reports are CAT010 too, not asked for


def test_quality_of_one_aircraft_no_radar_saw(files, tmp_path, capsys):
    out = tmp_path / "q.json"
    both = ["quality", files["adsb"], files["mlat"], "--sensors", files["sensors"]]
    status, _, err = _run([*both, "--callsign", "RYR1AB", "--date", "2016-05-10", "--json", out], capsys)
    assert status == 0, err
    quality = json.loads(out.read_text())["tables"]["Quality"]
    assert {(r["callsign"], r["sensor"]) for r in quality} == {  # pooled as in the test above
        ("RYR1AB", "adsb"), ("RYR1AB", "mlat"), ("(all surface)", "adsb"), ("(all)", "mlat")}
    status, _, err = _run([*both, "--callsign", "XYZ99", "--json", tmp_path / "n.json"], capsys)
    assert status == 1 and "XYZ99" in err


def test_evaluate_reads_a_multilaterations_validity_bits(files, tmp_path, capsys):
    """The multilateration's CAT010 I010/060 'not validated' bits reach mode3a_correct: 40 of its 300 codes
    flagged not validated fail the row (260 of 300 correct), where before its reports were said to carry
    no bits and every code was taken as validated."""
    lon, lat, _ = GEOD.fwd(np.full(T.size, REF[1]), np.full(T.size, REF[0]), np.where(NORTH >= 0, 0.0, 180.0),
                           np.abs(NORTH))
    files["adsb"].write_bytes(encode_frame(21, pd.DataFrame(
        {"sac": 0, "sic": 107, "time_of_day": T, "latitude": lat, "longitude": lon, "address": "4CA1B2",
         "callsign": "RYR1AB", "mode3a": "1234", "nacp": 10, "ground_speed_kt": 9.7}), edition="2.7"))
    files["mlat"].write_bytes(encode_frame(10, pd.DataFrame(
        {"sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": T, "x_m": 20.0,
         "y_m": np.round(NORTH), "address": "4CA1B2", "callsign": "RYR1AB", "track_number": 9,
         "mode3a": "1234", "mode3a_v": (np.arange(T.size) < 40).astype(int), "mode3a_g": 0,
         "vx_ms": 0.0, "vy_ms": 5.0})))
    out = tmp_path / "e.json"
    status, _, err = _run(["evaluate", files["adsb"], files["mlat"], "--sensors", files["sensors"],
                           "--preset", "ed117a", "--date", "2016-05-10", "--json", out], capsys)
    assert status == 0, err
    (row,) = [r for r in json.loads(out.read_text())["results"]
              if r["requirement"] == "mode3a_correct" and r["sector"] == "global"]
    assert (row["n"], row["value"]) == (300, pytest.approx(260 / 300))
    assert "of the 40 misses: 40 carry a code not validated or garbled" in row["notes"]
    assert "no mode3a_v" not in row["notes"]


def test_a_quality_workbook_without_adsb_says_so_and_gives_reference_points_to_the_centimetre(
        files, tmp_path, capsys):
    """The Reference points sheet printed snake_case headers, its corrected point as a correlation
    coefficient ("corrected" read as "corr") and the sensor-file point to 0.0001 deg (11 m); with no ADS-B
    in the input the ADS-B sheets were empty with nothing to say nothing was looked at."""
    from openpyxl import load_workbook

    out = tmp_path / "q.xlsx"
    status, _, err = _run(["quality", files["mlat"], files["smr"], "--sensors", files["sensors"], "--all",
                           "--date", "2016-05-10", "-o", out], capsys)
    assert status == 0, err
    wb = load_workbook(out)
    ws = wb["Reference points"]
    header = {c.value: c.column for c in ws[1]}
    (smr,) = [r for r in range(2, ws.max_row + 1) if ws.cell(r, 1).value == "010:0/7:smr"]  # measured
    for name in ("Sensor-file point latitude (deg)", "Sensor-file point longitude (deg)",
                 "Corrected point latitude (deg)", "Corrected point longitude (deg)"):
        assert ws.cell(smr, header[name]).number_format == "0.0000000", name
    assert {"Sensor id", "Measured against", "Report pairs", "East offset (m)", "North offset (m)"} <= set(
        header)
    for sheet in ("Jumps", "ADS-B quality", "ADS-B quality over time"):
        texts = [c.value for row in wb[sheet].iter_rows() for c in row if isinstance(c.value, str)]
        assert any(t.startswith("No ADS-B (CAT021) report in the input") for t in texts), sheet


def test_quality_of_status_messages_only_says_no_report(files, tmp_path, capsys):
    """A CAT010 file of one status message (I010/000 type 2: no position) printed pandas' 'Empty DataFrame /
    Columns: [...] / Index: []' as its Quality table."""
    time = bytes.fromhex("465040")  # I010/140: 36000.5 s x 128
    # FSPEC D1 01 04: I010/010, /000, /140 | | /550; SAC 0 SIC 107; message type 2; a status octet
    record = bytes.fromhex("D10104") + bytes([0, 107]) + b"\x02" + time + b"\x68"
    status_only = tmp_path / "status.ast"
    status_only.write_bytes(bytes([10]) + (len(record) + 3).to_bytes(2, "big") + record)
    status, text, err = _run(["quality", status_only, "--sensors", files["sensors"], "--all", "--date",
                              "2016-05-10"], capsys)
    assert status == 0, err
    assert "Quality:\n  none: no report with a position in the inputs" in text
    assert "Empty DataFrame" not in text
