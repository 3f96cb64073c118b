"""The one JSON writer and the one CSV writer of every output (pipeline/report/files.py), and write errors
naming the file."""

from __future__ import annotations

import errno
import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.report.files import named, write_csv, write_json

FIX = Path(__file__).resolve().parents[3] / "fixtures"


def _strict(text: str):
    """json.loads refusing NaN and infinities (Python's own reader accepts them)."""
    def refuse(name: str):
        raise ValueError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def test_the_json_writer_is_strict_utf8_indented_and_writes_one_time_format(tmp_path):
    doc = {"nan": float("nan"), "inf": np.inf, "nat": pd.NaT, "na": pd.NA, "n": np.int64(3),
           "ok": np.bool_(True), "naive": pd.Timestamp("2019-03-01 10:00:00.123456789"),
           "aware": pd.Timestamp("2019-03-01 12:00:00", tz="Europe/Paris"),
           "whole": np.datetime64("2019-03-01T10:00:00"), "name": "Zürich ✈", "rows": [{"x": math.nan}]}
    path = write_json(doc, tmp_path / "o.json")
    text = path.read_bytes().decode("utf-8")
    assert _strict(text) == {"nan": None, "inf": None, "nat": None, "na": None, "n": 3, "ok": True,
                             "naive": "2019-03-01T10:00:00.123Z", "aware": "2019-03-01T11:00:00.000Z",
                             "whole": "2019-03-01T10:00:00.000Z", "name": "Zürich ✈", "rows": [{"x": None}]}
    assert text.startswith('{\n  "nan": null,') and text.endswith("}\n")


def test_a_write_error_without_a_file_name_is_given_the_output(tmp_path):
    with pytest.raises(OSError) as raised, named(tmp_path / "t.parquet"):
        raise OSError("Error writing bytes to file. Detail: [errno 28] No space left on device")
    assert raised.value.filename == str(tmp_path / "t.parquet") and raised.value.errno == errno.ENOSPC
    assert raised.value.strerror == "No space left on device"
    with pytest.raises(OSError) as raised, named(tmp_path / "t.parquet"):
        raise OSError(errno.EACCES, "Permission denied", "/elsewhere/x")  # names its file already: kept
    assert raised.value.filename == "/elsewhere/x"


def test_the_csv_writer_guards_formula_like_text_and_writes_times_and_numbers_one_way(tmp_path):
    frame = pd.DataFrame({"callsign": ["=1+1", "MAS72", "-2", None],
                          "kind": pd.Categorical(["@x", "ok", "ok", "ok"]),
                          "time": pd.to_datetime(["2019-03-01 10:00:00.5"] * 4).tz_localize("UTC"),
                          "naive": pd.to_datetime(["2019-03-01 11:00:00"] * 4),
                          "lat": [-0.0, -0.00004481, 2.123456789, np.nan], "n": [1, 2, 3, 4]})
    path = write_csv(frame.iloc[:2], tmp_path / "t.csv", decimals={"lat": 7})
    write_csv(frame.iloc[2:], path, append=True, decimals={"lat": 7})
    assert path.read_text().splitlines() == [
        "callsign,kind,time,naive,lat,n",
        "'=1+1,'@x,2019-03-01T10:00:00.500000Z,2019-03-01T11:00:00.000000Z,0.0,1",
        "MAS72,ok,2019-03-01T10:00:00.500000Z,2019-03-01T11:00:00.000000Z,-0.0000448,2",  # a number: kept
        "'-2,ok,2019-03-01T10:00:00.500000Z,2019-03-01T11:00:00.000000Z,2.1234568,3",
        ",ok,2019-03-01T10:00:00.500000Z,2019-03-01T11:00:00.000000Z,,4"]


@pytest.fixture(scope="module")
def job_results(tmp_path_factory):
    """A track and a conflicts run on the fixtures (conflicts with alert events)."""
    from msdc.pipeline.jobs import conflicts, track

    fix = {"inputs": (str(FIX / "radar.ast"), str(FIX / "adsb.ast")), "sensors": str(FIX / "sensors.toml"),
           "date": pd.Timestamp("2019-03-01").date()}
    tracked = track.track_job(track.TrackOptions(**fix, callsign="MAS72"))
    out = str(tmp_path_factory.mktemp("conflicts") / "k.csv")
    found = conflicts.conflict_job(conflicts.ConflictOptions(**fix, output=out, step_s=5.0, radius_nm=40.0,
                                                             vertical_ft=30000.0, horizons_s="60"))
    return tracked, found


@pytest.mark.parametrize("job", ["track", "conflicts"])
def test_track_and_conflicts_csv_guard_formula_like_text(job_results, tmp_path, job):
    """A call sign or aircraft id that a spreadsheet would run (=, +, -, @) is written behind an apostrophe
    in the track table and the conflicts tables, as decode's CSV and every workbook do."""
    from dataclasses import replace

    from msdc.pipeline.jobs import conflicts, track

    tracked, found = job_results
    if job == "track":
        checked = replace(tracked.checked, output=tmp_path / "t.csv", json=None)
        result = replace(tracked, options=replace(tracked.options, figures=None), checked=checked,
                         tracks=tracked.tracks.assign(callsign="=HYPERLINK(\"http://x\")"))
        track.write_tracks(result)
        column = pd.read_csv(tmp_path / "t.csv")["callsign"]
    else:
        checked = replace(found.checked, output=tmp_path / "k.csv", json=None)
        result = replace(found, checked=checked, alerts=found.alerts.assign(aircraft_a="@SUM(A1)"),
                         options=replace(found.options, figures=None))
        conflicts.write_conflicts(result)
        column = pd.read_csv(tmp_path / "k.csv")["aircraft_a"]
    assert len(column) and set(column) == {"'=HYPERLINK(\"http://x\")" if job == "track" else "'@SUM(A1)"}
