"""evaluate with an external reference (--reference-file) under a report selection: the selection cuts the
reference as it cuts the reports. Checked against cutting the reference file by hand: the same figures."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

import msdc.asterix as asterix
from msdc.pipeline.cli import main

FIX = Path(__file__).resolve().parents[3] / "fixtures"
DAY = "2019-03-01"


def _reference_csv(path: Path, start: str | None = None, end: str | None = None) -> Path:
    """The ADS-B fixture's positions as a reference file (one sample per aircraft and second: the file
    wants increasing times), its times within [start, end) when given."""
    frame = asterix.read(FIX / "adsb.ast", date=DAY).frames[21]
    ref = pd.DataFrame({"aircraft": frame["address"].astype(str), "time": frame["timestamp"],
                        "latitude": frame["latitude"], "longitude": frame["longitude"],
                        "altitude_ft": frame["flight_level"] * 100.0, "sigma_m": 10.0}).dropna()
    ref = ref.sort_values(["aircraft", "time"]).drop_duplicates(["aircraft", "time"])
    if start is not None:
        lo, hi = pd.Timestamp(start, tz="UTC"), pd.Timestamp(end, tz="UTC")
        ref = ref[(ref["time"] >= lo) & (ref["time"] < hi)]
    ref["time"] = ref["time"].dt.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    ref.to_csv(path, index=False)
    return path


def _pd(tmp_path: Path, reference: Path, name: str, *extra: str) -> tuple[float, int]:
    out = tmp_path / f"{name}.json"
    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml")]
    assert main(["evaluate", *inputs, "--date", DAY, "--preset", "eurocontrol-1997-ssr", "--reference-file",
                 str(reference), *extra, "--json", str(out)]) == 0
    row = next(r for r in json.loads(out.read_text())["results"]
               if r["requirement"] == "pd" and r["sector"] == "global")
    return row["value"], row["n"]


@pytest.mark.parametrize("extra", [[], ["--window", "15"]], ids=["span", "windows"])
def test_a_time_window_cuts_the_external_reference_too(tmp_path, extra):
    """Kept whole, the reference's samples outside --from/--to made updates expected of a radar whose plots
    there were cut, every one a miss (PD 44 % where the cut reference gives 97 %), and each --window counted
    the whole file again."""
    window = ["--from", "08:30", "--to", "09:00"]
    whole = _reference_csv(tmp_path / "whole.csv")
    cut = _reference_csv(tmp_path / "cut.csv", f"{DAY}T08:30", f"{DAY}T09:00")
    assert _pd(tmp_path, whole, "whole", *window, *extra) == _pd(tmp_path, cut, "cut", *window, *extra)


def test_false_reports_are_withheld_against_an_external_reference(tmp_path):
    """An external reference lists the aircraft it was made for: the radar's plots in the ADS-B file's gaps
    (or of any aircraft a trial file leaves out) were counted false, 8.5 % here, 100 % without sigma_m.
    Withheld, with the reason."""
    preset = (FIX.parent / "pipeline" / "evaluate" / "presets" / "eurocontrol-1997-ssr.toml").read_text()
    preset += ('\n[[requirement]]\nid = "false_reports"\nthreshold = 0.1\ndirection = "<"\n'
               'stated = "< 0.1 %"\nclause = "test"\nchecked = false\nsource = "this test"\n'
               'parameters = { distance_m = 1852.0 }\n')
    (tmp_path / "p.toml").write_text(preset)
    out = tmp_path / "e.json"
    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml")]
    assert main(["evaluate", *inputs, "--date", DAY, "--preset", str(tmp_path / "p.toml"), "--reference-file",
                 str(_reference_csv(tmp_path / "ref.csv")), "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    row = next(r for r in doc["results"] if r["requirement"] == "false_reports" and r["sector"] == "global")
    assert row["value"] is None and row["verdict"] != "fail"
    assert "an external reference lists the aircraft it was made for" in row["notes"]
    # the ADS-B the preset does not judge was said to "still build the reference": the file is it
    assert ("not judged by eurocontrol-1997-ssr: 021:0/1 (adsb) (none builds the reference: it is the "
            "external file)") in doc["parameters"]["notes"]


def test_a_reference_of_another_day_is_said(tmp_path, capsys):
    """The fixture's ADS-B as a reference dated a day late: every figure was withheld with no word why."""
    ref = _reference_csv(tmp_path / "ref.csv")
    ref.write_text(ref.read_text().replace(f"{DAY}T", "2019-03-02T"))
    inputs = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml")]
    assert main(["evaluate", *inputs, "--date", DAY, "--preset", "eurocontrol-1997-ssr", "--reference-file",
                 str(ref), "--json", str(tmp_path / "e.json")]) == 0
    err = capsys.readouterr().err
    assert (f"--reference-file {ref}: no sample within the reports' time (2019-03-01 08:00:00 to "
            "2019-03-01 11:19:5") in err and "lie from 2019-03-02 08:00:0" in err
