"""--from, --to, --area, --fl and --sensor on every command: the reports kept against counts worked out here
from the decoded fixture recordings (their times, flight levels, positions, decoded range and azimuth), the
selection recorded in each command's outputs, and the refusals (status 2, the option and value named, no
traceback, the output folder as it was)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED
from matplotlib.path import Path as MplPath

import msdc.asterix as asterix
from msdc.pipeline.cli import main

ROOT = Path(__file__).resolve().parents[3]
FIX = ROOT / "fixtures"
INPUTS = [str(FIX / "radar.ast"), str(FIX / "adsb.ast")]
SENSORS = ["--sensors", str(FIX / "sensors.toml")]
DAY = "2024-01-01"  # the fixtures are raw recordings: undated
WINDOW = ["--date", DAY, "--from", "08:10", "--to", f"{DAY}T08:16:00Z", "--fl", "100:300",
          "--sensor", "25/201", "--sensor", "021:0/1"]


@pytest.fixture(scope="module")
def decoded() -> dict[int, pd.DataFrame]:
    """The fixtures' CAT048 and CAT021 records, with their UTC instants."""
    frames = {}
    for path in INPUTS:
        for cat, frame in asterix.read(path).frames.items():
            t = pd.Timestamp(DAY, tz="UTC") + pd.to_timedelta(
                frame["day"].to_numpy(float) * 86400.0 + frame["time_of_day"].to_numpy(float), unit="s")
            frames[cat] = frame.assign(t=t)
    return frames


def _expected_window(decoded) -> tuple[int, int]:
    """Records in [08:10, 08:16) at FL 100-300 of the two sensors (all the fixtures have), and all records."""
    kept = 0
    for frame in decoded.values():
        t, fl = frame["t"], frame["flight_level"].astype(float)
        inside = ((t >= pd.Timestamp(f"{DAY}T08:10Z")) & (t < pd.Timestamp(f"{DAY}T08:16Z"))
                  & fl.between(100, 300))
        kept += int(inside.sum())
    return kept, sum(len(f) for f in decoded.values())


COMMANDS = {
    "decode": ["-o", "{d}/out.csv"],
    "stats": [],
    "correlate": [*SENSORS, "--all", "-o", "{d}/c.xlsx", "--json", "{d}/c.json"],
    "quality": [*SENSORS, "--all", "-o", "{d}/q.xlsx", "--json", "{d}/q.json"],
    "track": [*SENSORS, "--all", "-o", "{d}/t.csv", "--json", "{d}/t.json", "--step", "4"],
    "conflicts": [*SENSORS, "-o", "{d}/k.xlsx", "--json", "{d}/k.json", "--step", "4"],
}


def _recorded(command: str, d: Path, out: str) -> dict:
    """The selection a command's outputs record (JSON parameters; decode's side file; stats' terminal)."""
    if command == "stats":
        line = next(x for x in out.splitlines() if x.startswith("selection "))
        kept, total = (int(v) for v in line.split(": ", 1)[1].split(" records")[0].split(" of "))
        return {"kept": kept, "reports": total}
    if command == "decode":
        return json.loads((d / "out_selection.json").read_text())["report_selection"]
    name = {"correlate": "c", "quality": "q", "track": "t", "conflicts": "k"}[command]
    return json.loads((d / f"{name}.json").read_text())["parameters"]["report_selection"]


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_command_reads_only_the_selected_reports(command, tmp_path, capsys, decoded):
    argv = [command, *INPUTS, *WINDOW, *(a.format(d=tmp_path) for a in COMMANDS[command])]
    assert main(argv) == 0, capsys.readouterr().err
    out, err = capsys.readouterr()
    record = _recorded(command, tmp_path, out)
    kept, total = _expected_window(decoded)
    assert 500 < kept < total / 2
    assert (record["kept"], record["reports"]) == (kept, total)
    said = out if command in ("decode", "stats") else err  # the terminal says it too
    assert f": {kept} of {total} re" in next(x for x in said.splitlines() if "selection --from 08:10" in x)
    if command != "stats":
        assert record["from_utc"] == f"{DAY}T08:10:00.000Z" and record["to_utc"] == f"{DAY}T08:16:00.000Z"
        assert record["fl"] == "100:300" and record["fl_bounds"] == [100.0, 300.0]
        assert record["sensors"] == ["25/201", "021:0/1"]
    if command == "track":  # tracked from the selected reports only: no row before 08:10, none past the last
        times = pd.to_datetime(pd.read_csv(tmp_path / "t.csv")["time"], utc=True)  # report's coast (60 s)
        assert times.min() >= pd.Timestamp(f"{DAY}T08:10Z")
        assert pd.Timestamp(f"{DAY}T08:15:30Z") < times.max() <= pd.Timestamp(f"{DAY}T08:17Z")
    if command == "quality":  # the workbook's Parameters sheet records it too
        import openpyxl

        ws = openpyxl.load_workbook(tmp_path / "q.xlsx", read_only=True)["Parameters"]
        rows = {(r[0], r[1]): r[2] for r in ws.iter_rows(values_only=True) if len(r) >= 3}
        assert rows[("report_selection", "kept")] == kept and rows[("report_selection", "from")] == "08:10"


def test_decode_writes_only_the_selected_records(tmp_path, capsys, decoded):
    assert main(["decode", *INPUTS, *WINDOW, "-o", str(tmp_path / "out.csv")]) == 0
    written = {cat: pd.read_csv(tmp_path / f"out_cat{cat:03d}.csv") for cat in (21, 48)}
    for cat, frame in decoded.items():
        t, fl = frame["t"], frame["flight_level"].astype(float)
        inside = ((t >= pd.Timestamp(f"{DAY}T08:10Z")) & (t < pd.Timestamp(f"{DAY}T08:16Z"))
                  & fl.between(100, 300))
        assert written[cat]["offset"].tolist() == frame.loc[inside, "offset"].tolist()


def test_decode_s_selection_file_is_json_as_every_output_s(tmp_path, capsys):
    """Indented by 2 as the guide says every JSON output is, its times ISO 8601 UTC to the millisecond
    with Z."""
    assert main(["decode", *INPUTS, *WINDOW, "-o", str(tmp_path / "out.csv")]) == 0
    text = (tmp_path / "out_selection.json").read_text(encoding="utf-8")
    assert text.startswith('{\n  "software": "msdc ') and text.endswith("\n}\n")
    assert f'\n    "from_utc": "{DAY}T08:10:00.000Z",\n' in text


def test_decode_lists_its_selection_file_as_its_data_file(tmp_path, capsys, monkeypatch):
    """-o out.csv given relative: the selection file is listed relative too, saying what it is."""
    monkeypatch.chdir(tmp_path)
    assert main(["decode", *INPUTS, *WINDOW, "--category", "48", "-o", "out.csv"]) == 0
    assert capsys.readouterr().err.endswith("msdc decode: 2 file(s) written:\n  out.csv (CAT048 records)\n"
                                            "  out_selection.json (selection record)\n")


def test_a_polygon_keeps_the_adsb_reports_inside_it(tmp_path, capsys, decoded):
    """A triangle over part of the traffic; the CAT021 positions inside it by matplotlib's test."""
    adsb = decoded[21]
    lat, lon = adsb["latitude"].to_numpy(float), adsb["longitude"].to_numpy(float)
    mid_lat, mid_lon = np.nanmedian(lat), np.nanmedian(lon)
    ring = [[mid_lon - 1.0, mid_lat - 1.0], [mid_lon + 0.3, mid_lat - 0.8], [mid_lon, mid_lat + 0.6]]
    area = tmp_path / "area.geojson"
    area.write_text(json.dumps({"type": "Polygon", "coordinates": [[*ring, ring[0]]]}))
    expected = MplPath([*ring, ring[0]]).contains_points(np.column_stack([lon, lat]))
    assert 100 < expected.sum() < len(adsb) - 100
    assert main(["stats", *INPUTS, "--area", str(area), "--sensor", "021:0/1", "--date", DAY]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.startswith("selection "))
    assert f": {int(expected.sum())} of {len(adsb) + len(decoded[48])} records kept" in line


def test_a_radar_window_keeps_the_radar_s_plots_by_their_decoded_range_and_azimuth(tmp_path, capsys, decoded):
    radar = decoded[48]
    rho, theta = radar["rho_nm"].to_numpy(float), radar["theta_deg"].to_numpy(float)
    expected = (rho >= 60.0) & (rho <= 110.0) & ((theta >= 350.0) | (theta <= 170.0))
    assert 100 < expected.sum() < len(radar) - 100
    assert main(["decode", *INPUTS, *SENSORS, "--area", "25_201:60-110nm:350-170deg", "--sensor",
                 "048:25/201", "-o", str(tmp_path / "out.csv")]) == 0
    assert pd.read_csv(tmp_path / "out.csv")["offset"].tolist() == radar.loc[expected, "offset"].tolist()


# ---------------------------------------------------------------------------------------------------------
# Refusals


REFUSED = [
    ("decode", ["--from", "08:10+02:00"], "--from '08:10+02:00': not a UTC time"),
    ("stats", ["--from", "2024-01-01T10:00:00+02:00"], "UTC offset of 2:00:00"),
    ("correlate", ["--from", "08:20", "--to", "08:10"],
     "--from 08:20 is not before --to 08:10: the window holds no time"),
    ("quality", ["--fl", "300:100"], "--fl '300:100': MIN 300 is above MAX 100"),
    ("track", ["--sensor", "radar"], "--sensor 'radar': not a sensor"),
    ("conflicts", ["--area", "25/201:0-60nm"], "--area '25/201:0-60nm': expected a GeoJSON file"),
    ("quality", ["--area", "9/9:0-60nm:0-90deg"], "--area 9/9:0-60nm:0-90deg: no sensor 9/9 in"),
    ("decode", ["--area", "nowhere.geojson"], "--area nowhere.geojson: --area file does not exist"),
    ("decode", ["--area", "25/201:0-60nm:0-90deg"], "needs the sensor's site: give --sensors"),
    # placed on the recording's day only after decoding: refused then, nothing written
    ("track", ["--from", "08:10"], "--from 08:10: the inputs carry no date"),
    ("decode", ["--from", "2024-01-01T08:10:00"], "the inputs carry no date"),
]


@pytest.mark.parametrize("command, args, said", REFUSED)
def test_bad_selections_are_refused_leaving_the_folder_as_it_was(command, args, said, tmp_path, capsys):
    (tmp_path / "kept.txt").write_text("as it was")
    before = sorted(p.name for p in tmp_path.iterdir())
    sensors = SENSORS if command not in ("decode", "stats") or "9/9" in args[-1] else []
    argv = [command, *INPUTS, *sensors, *args, *(a.format(d=tmp_path) for a in COMMANDS[command]
                                                 if a not in SENSORS)]
    if command in ("correlate", "quality", "track") and "--all" not in argv:
        argv.append("--all")
    status = main(argv)
    err = capsys.readouterr().err
    assert status == 2 and said in err and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert (tmp_path / "kept.txt").read_text() == "as it was"


def test_a_selection_that_leaves_nothing_says_so(tmp_path, capsys, decoded):
    """No fixture aircraft flies above FL 900: every report is left out, and the run says so."""
    status = main(["quality", *INPUTS, *SENSORS, "--all", "--fl", "900:1000", "-o", str(tmp_path / "q.xlsx")])
    err = capsys.readouterr().err
    total = sum(len(f) for f in decoded.values())
    assert status == 1 and f"--fl 900:1000: 0 of {total} reports kept" in err and "no report is left" in err
    assert not list(tmp_path.iterdir())


def test_a_selection_that_keeps_no_adsb_says_what_is_left_empty(tmp_path, capsys, decoded):
    assert main(["quality", *INPUTS, *SENSORS, "--all", "--sensor", "048:25/201",
                 "--json", str(tmp_path / "q.json")]) == 0
    err = capsys.readouterr().err
    assert (f"the report selection keeps no ADS-B (CAT021) report of the {len(decoded[21])} in the inputs"
            in err)
    record = json.loads((tmp_path / "q.json").read_text())["parameters"]["report_selection"]
    assert record["kept"] == len(decoded[48]) and record["left_out"] == {"sensor": len(decoded[21])}


REAL_RADAR = SHARED / "real" / "230502-est-080001_BCN_60MN_08_09.ast"


@pytest.mark.skipif(not REAL_RADAR.exists(), reason="../shared/real (the real recordings) is not beside the "
                    "repository")
def test_the_real_radar_hour_against_the_independent_decoders_values(tmp_path, capsys):
    """08:15 to 08:45 at FL 100 and above within 40 NM of the radar, azimuth 300 through north to 120 deg:
    counted from the values two independent decoders agree on (expected.csv.gz), not from msdc's."""
    agreed = pd.read_csv(REAL_RADAR.with_name(REAL_RADAR.name + ".expected.csv.gz"))
    t, theta = agreed["time_of_day"], agreed["theta_deg"]
    expected = ((t >= 8.25 * 3600) & (t < 8.75 * 3600) & (agreed["flight_level"] >= 100)
                & (agreed["rho_nm"] <= 40) & ((theta >= 300) | (theta <= 120)))
    assert 1000 < expected.sum() < len(agreed) / 4
    site = tmp_path / "bcn.toml"  # the site matters only for other sensors' reports: there are none
    site.write_text('[[sensor]]\nname = "BCN"\nsac = 20\nsic = 129\nlatitude = 41.297\nlongitude = 2.078\n'
                    'altitude_m = 0.0\n')
    assert main(["decode", str(REAL_RADAR), "--sensors", str(site), "--date", "2023-05-02", "--from", "08:15",
                 "--to", "2023-05-02T08:45Z", "--fl", "100:", "--area", "20/129:0-40nm:300-120deg",
                 "-o", str(tmp_path / "out.csv")]) == 0
    assert pd.read_csv(tmp_path / "out.csv")["offset"].tolist() == agreed.loc[expected, "offset"].tolist()


def test_an_aircraft_not_seen_names_the_selection_as_a_possible_cause(capsys):
    """SIA305's ADS-B reports are all left out by --sensor: 'not seen by ADS-B' says the selection ran."""
    status = main(["correlate", *INPUTS, *SENSORS, "--callsign", "SIA305", "--sensor", "048:25/201"])
    err = capsys.readouterr().err
    assert status == 1 and "SIA305 not seen by ADS-B" in err
    assert "(among the reports the selection keeps: --sensor)" in err
