"""Two aircraft under one address (one's reports re-encoded with the other's address and call sign): every
kind of job says so (pipeline.model.mixed), naming the address and the sensor."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main

FIX = Path(__file__).resolve().parents[3] / "fixtures"
SAID = "1 aircraft's reports switch back and forth between two places: 750312 on 021:0/1 ("


@pytest.fixture(scope="module")
def readdressed(tmp_path_factory) -> Path:
    """The fixture's ADS-B with AXM123 (75008A, 08:05-09:00) sent as MAS72 (750312, 08:00-09:00)."""
    frame = asterix.read(FIX / "adsb.ast").frames[21].copy()
    axm = frame["address"] == "75008A"
    frame.loc[axm, "address"], frame.loc[axm, "callsign"] = "750312", "MAS72"
    path = tmp_path_factory.mktemp("mixed") / "adsb.ast"
    path.write_bytes(encode_frame(21, frame.drop(columns="callsign_hex")))  # the call sign from its text
    return path


def test_track_quality_and_evaluate_say_two_targets_share_an_address(readdressed, tmp_path, capsys):
    assert main(["track", str(readdressed), "--all", "-o", str(tmp_path / "t.csv")]) == 0
    assert SAID in capsys.readouterr().err
    inputs = [str(FIX / "radar.ast"), str(readdressed), "--sensors", str(FIX / "sensors.toml")]
    assert main(["quality", *inputs, "--all", "--json", str(tmp_path / "q.json")]) == 0
    assert SAID in capsys.readouterr().err
    _quality_rows_marked(json.loads((tmp_path / "q.json").read_text())["tables"]["Quality"])
    assert main(["evaluate", *inputs, "--preset", "eurocontrol-1997-ssr",
                 "--json", str(tmp_path / "e.json")]) == 0
    assert SAID in capsys.readouterr().err
    doc = json.loads((tmp_path / "e.json").read_text())
    assert any(SAID in w for w in doc["parameters"]["warnings"])
    _two_targets_marked(doc)


def _two_targets_marked(doc: dict) -> None:
    """The radar's per-aircraft rows: 750312's reference was built with the ADS-B that holds both targets
    (marked so), every other aircraft's row unmarked."""
    rows = {r["aircraft"]: r for r in doc["tables"]["Per aircraft"] if r["sensor"] == "048:25/201"}
    assert "021:0/1" in rows["750312"]["built_by"] and rows["750312"]["two_targets_on"] == "021:0/1"
    assert len(rows) > 1 and all(r["two_targets_on"] == "" for a, r in rows.items() if a != "750312")


def _quality_rows_marked(rows: list[dict]) -> None:
    """MAS72's ADS-B row and the ADS-B's pooled row marked; the radar's MAS72 (one target) and every other
    row not."""
    marked = {(r["callsign"], r["sensor"]) for r in rows if r["two_targets"]}
    assert marked == {("MAS72", "adsb"), ("(all)", "adsb")}
    assert {("MAS72", "radar"), ("MXD1202", "adsb")} <= {(r["callsign"], r["sensor"]) for r in rows}


def test_correlate_with_quality_marks_the_quality_rows(readdressed):
    from msdc.pipeline.jobs.correlate import correlate_job
    from msdc.pipeline.jobs.options import CorrelateOptions

    options = CorrelateOptions(inputs=(str(FIX / "radar.ast"), str(readdressed)),
                               sensors=str(FIX / "sensors.toml"), callsign="MAS72", quality=True)
    result = correlate_job(options)
    rows = result.quality.sheets["Quality"].to_dict("records")
    marked = {(r["callsign"], r["sensor"]) for r in rows if r["two_targets"]}
    assert marked == {("MAS72", "adsb"), ("(all)", "adsb")}  # --callsign: MAS72's rows alone


def test_a_windowed_evaluation_marks_the_aircraft_too(readdressed, tmp_path, capsys):
    """--window: the windows' findings pooled with the span's per-aircraft table."""
    span = ["--date", "2019-03-01", "--from", "08:00", "--to", "09:00", "--window", "30"]
    assert main(["evaluate", str(FIX / "radar.ast"), str(readdressed), "--sensors", str(FIX / "sensors.toml"),
                 "--preset", "eurocontrol-1997-ssr", *span, "--json", str(tmp_path / "e.json")]) == 0
    assert SAID in capsys.readouterr().err
    _two_targets_marked(json.loads((tmp_path / "e.json").read_text()))


def test_correlate_says_it_in_that_aircrafts_window_verdicts_alone(readdressed, tmp_path, capsys):
    out = tmp_path / "c.json"
    assert main(["correlate", str(FIX / "radar.ast"), str(readdressed), "--sensors",
                 str(FIX / "sensors.toml"), "--all", "--json", str(out)]) == 0
    assert SAID in capsys.readouterr().err
    windows = json.loads(out.read_text())["windows"]
    said = {w["address"] for w in windows if "two targets may share this identity on 021:0/1" in w["verdict"]}
    assert said == {"750312"} and len({w["address"] for w in windows}) > 1


def test_the_unaltered_fixtures_say_nothing_of_it(tmp_path, capsys):
    assert main(["track", str(FIX / "adsb.ast"), "--all", "-o", str(tmp_path / "t.csv")]) == 0
    assert "switch back and forth" not in capsys.readouterr().err


def test_a_row_is_marked_by_the_sensors_it_involves_alone():
    """By hand: A's reports mix on S1 (its reference's builder) and S9 (no part of the row), B's on the
    sensor under test; C is not mixed anywhere."""
    import pandas as pd

    from msdc.pipeline.jobs.evaluate import mark_two_targets

    table = pd.DataFrame({"sensor": ["T", "T", "T"], "aircraft": ["A", "B", "C"],
                          "built_by": ["S1 | S2", "S1", "S1 | S2"]})
    marked = mark_two_targets(table, {("A", "S1"), ("A", "S9"), ("B", "T"), ("D", "S1")})
    assert marked["two_targets_on"].tolist() == ["S1", "T", ""]
    assert mark_two_targets(table, frozenset())["two_targets_on"].tolist() == ["", "", ""]
