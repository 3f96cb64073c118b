"""The jobs layer: options checked before any decoding (one-line messages naming the option or file), the
jobs' results, and work done once per job."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from msdc.pipeline.jobs import common, correlate, decode, quality, stats
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.jobs.correlate import CorrelateOptions
from msdc.pipeline.jobs.decode import DecodeOptions
from msdc.pipeline.jobs.quality import QualityOptions
from msdc.pipeline.jobs.stats import StatsOptions

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB, SENSORS = str(FIX / "radar.ast"), str(FIX / "adsb.ast"), str(FIX / "sensors.toml")


def corr(**kw) -> CorrelateOptions:
    base = {"inputs": (RADAR, ADSB), "sensors": SENSORS, "callsign": "MAS72"}
    return CorrelateOptions(**(base | kw))


CASES = [
    (corr(slot_s=0.0), "--slot 0.0"),
    (corr(slot_s=math.nan), "--slot nan"),
    (corr(slot_s=math.inf), "--slot inf"),
    (corr(slot_s=1e-9), "--slot 1e-09"),
    (corr(gap_s=-1.0), "--gap -1.0"),
    (corr(gap_s=math.nan), "--gap nan"),
    (corr(gap_s=0.0), "--gap 0.0"),
    (corr(min_nacp=-3), "--min-nacp -3"),
    (corr(min_nic=99), "--min-nic 99"),
    (corr(pairs="adsb-adsb"), "--pairs 'adsb-adsb'"),
    (corr(callsign=None, address="XYZ"), "--address 'XYZ'"),
    (corr(callsign=None), "exactly one of --callsign, --address or --all"),
    (corr(all_aircraft=True), "exactly one of"),
    (corr(editions=("21=9.9",)), "--edition 21=9.9"),
    (corr(editions=("62=1.0",)), "--edition 62=1.0"),
    (corr(output="report.txt"), "-o report.txt: must end in .xlsx"),
    (corr(output="/nonexistent/dir/r.xlsx"), "does not exist"),
    (corr(json="x.csv"), "--json x.csv: must end in .json"),
    (corr(sensors="/nonexistent/s.toml"), "--sensors /nonexistent/s.toml"),
    (corr(inputs=("/nonexistent/x.ast",)), "/nonexistent/x.ast: input file does not exist"),
    (corr(inputs=(str(FIX),)), "is a directory"),
    (corr(format="zip"), "--format 'zip'"),
    (QualityOptions(inputs=(RADAR,), sensors=SENSORS, all_aircraft=True, gap_s=-5.0), "--gap -5.0"),
    (DecodeOptions(inputs=(RADAR,), chunk_mb=0.0), "--chunk-mb 0.0"),
    (DecodeOptions(inputs=(RADAR,), output="out.txt"), "-o out.txt: must end in .csv or .parquet"),
    (StatsOptions(inputs=(RADAR,), editions=("48=abc",)), "--edition 48=abc"),
]


@pytest.mark.parametrize(("options", "words"), CASES)
def test_bad_options_are_refused_before_decoding(options, words, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(common, "load", lambda *a, **k: pytest.fail("decoded before validating"))
    validate = {CorrelateOptions: correlate.validate, QualityOptions: quality.validate,
                DecodeOptions: decode.validate, StatsOptions: stats.validate}[type(options)]
    with pytest.raises(OptionError) as info:
        validate(options)
    message = str(info.value)
    assert words in message and "\n" not in message
    assert info.value.status == 2


def test_output_directory_and_unwritable(tmp_path):
    (tmp_path / "d.xlsx").mkdir()
    with pytest.raises(OptionError, match="is a directory"):
        correlate.validate(corr(output=str(tmp_path / "d.xlsx")))
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if not __import__("os").access(locked, __import__("os").W_OK):  # root can write anyway
            with pytest.raises(OptionError, match="not writable"):
                correlate.validate(corr(output=str(locked / "r.xlsx")))
    finally:
        locked.chmod(0o700)


def test_bad_sensor_file_is_reported_once_before_decoding(tmp_path):
    bad = tmp_path / "s.toml"
    bad.write_text("[[sensor]]\nname = 'x'\n")
    with pytest.raises(OptionError) as info:
        correlate.validate(corr(sensors=str(bad)))
    assert str(info.value).count(str(bad)) == 1 and "lacks" in str(info.value)


def test_duplicate_inputs_are_skipped_with_a_warning(tmp_path):
    copy = tmp_path / "copy.ast"
    copy.write_bytes(Path(RADAR).read_bytes())
    checked = correlate.validate(corr(inputs=(RADAR, ADSB, str(copy))))
    assert [p.name for p in checked.inputs] == ["radar.ast", "adsb.ast"]
    (warning,) = checked.warnings
    assert "copy.ast" in warning and "SHA-256" in warning


def test_a_job_returns_its_warnings_and_an_error_carries_them(tmp_path):
    """The result holds every warning of the run, validation's first; an error leaving a job (or a step of
    one) carries those collected before it, earliest first, for the command to print ahead of the error."""
    copy = tmp_path / "copy.ast"
    copy.write_bytes(Path(RADAR).read_bytes())
    options = QualityOptions(inputs=(RADAR, ADSB, str(copy)), sensors=SENSORS, callsign="MAS72")
    checked = quality.validate(options)
    result = quality.quality_job(options, checked=checked)
    assert result.warnings[:1] == checked.warnings and "SHA-256" in checked.warnings[0]
    with pytest.raises(common.JobError) as info, common.carrying(["job"]), common.carrying(["step"]) as said:
        said.append("then")
        raise common.JobError("no such aircraft")
    assert info.value.job_warnings == ["job", "step", "then"]


def test_correlate_job_returns_results_and_writes_only_when_asked(tmp_path):
    result = correlate.correlate_job(corr(date=None, quality=True, drop_jumps=True))
    assert [w.summary["window"] for w in result.run.windows] == [1, 2]
    assert {w.summary["radar_sensor"] for w in result.run.windows} == {"048:25/201"}
    assert result.quality is not None and "Radar biases" in result.run.extra_sheets
    # jumps were detected once and reused: the filter removed exactly the flagged reports
    assert result.run.filters["jumps"] > 0 and "jump" in result.measurements
    assert correlate.write_correlation(result) == {}
    out = tmp_path / "r.xlsx"
    written = correlate.write_correlation(correlate.correlate_job(corr(output=str(out))))
    assert written["report"] == out and out.exists() and written["figure"].exists()


def test_stats_and_quality_jobs():
    inventory = stats.stats_job(StatsOptions(inputs=(RADAR, ADSB)))
    assert set(inventory.tables["categories"]["category"]) == {21, 48}
    q = quality.quality_job(QualityOptions(inputs=(RADAR, ADSB), sensors=SENSORS, callsign="MAS72"))
    assert set(q.quality.sheets["Quality"]["callsign"]) >= {"MAS72"}


def test_warnings_implausible_site_height_and_time_running_backwards(tmp_path):
    sensors = tmp_path / "s.toml"
    sensors.write_text(Path(SENSORS).read_text().replace("altitude_m = 40.0", "altitude_m = -99999.0"))
    checked = correlate.validate(corr(sensors=str(sensors)))
    assert any("altitude_m = -99999" in w for w in checked.warnings)
    # the second half of the radar recording given first: CAT048 runs backwards between the inputs
    import msdc.asterix as asterix
    from msdc.asterix.encode import encode_frame

    frame = asterix.read(RADAR).frames[48]
    early, late = tmp_path / "early.ast", tmp_path / "late.ast"
    early.write_bytes(encode_frame(48, frame.iloc[: len(frame) // 2]))
    late.write_bytes(encode_frame(48, frame.iloc[len(frame) // 2:]))
    result = correlate.correlate_job(corr(inputs=(str(late), str(early), ADSB)))
    assert any("runs backwards" in w or "run backwards" in w for w in result.warnings)
    ordered = correlate.correlate_job(corr(inputs=(str(early), str(late), ADSB)))
    assert not any("backwards" in w for w in ordered.warnings)


def test_order_warning_is_per_data_source():
    """Two radars recorded side by side overlap in time and say nothing; one radar's later file given first
    does. Spans are worked out per SAC/SIC from hand-made records (10:00-11:00 and 09:00-10:30 UTC)."""
    import datetime as dt

    import pandas as pd

    from msdc.pipeline.model.load import time_spans

    def frame(sic: int, start_h: float, end_h: float) -> dict[int, pd.DataFrame]:
        return {48: pd.DataFrame({"sac": [25, 25], "sic": [sic, sic], "day": [0, 0],
                                  "time_of_day": [start_h * 3600, end_h * 3600]})}

    day = dt.date(2019, 3, 1)
    first, other_radar = time_spans(frame(201, 10, 11), day), time_spans(frame(202, 9, 10.5), day)
    assert first == {"048:25/201": (pd.Timestamp("2019-03-01 10:00", tz="UTC"),
                                    pd.Timestamp("2019-03-01 11:00", tz="UTC"))}
    assert common.order_warnings([Path("a.ast"), Path("b.ast")], [first, other_radar]) == []
    same_radar = time_spans(frame(201, 9, 10.5), day)
    (warning,) = common.order_warnings([Path("a.ast"), Path("b.ast")], [first, same_radar])
    assert warning.startswith("b.ast: 048:25/201 starts at 2019-03-01 09:00:00+00:00, before the end of its "
                              "records in a.ast (2019-03-01 11:00:00+00:00)")


def test_time_spans_sources_without_sac_or_sic():
    """Records missing SAC or SIC form sources of their own, shown with "?" as sensor_id shows them."""
    import datetime as dt

    import pandas as pd

    from msdc.pipeline.model.load import time_spans

    frame = pd.DataFrame({"sac": pd.array([25, None, 25, 25], "Int64"),
                          "sic": pd.array([None, 7, 201, 201], "Int64"),
                          "time_of_day": [3600.0, 7200.0, 10800.0, 14400.0], "day": [0, 0, 0, 0]})
    spans = time_spans({21: frame}, dt.date(2019, 3, 1))
    at = {h: pd.Timestamp(f"2019-03-01 {h:02d}:00", tz="UTC") for h in (1, 2, 3, 4)}
    assert spans == {"021:25/?": (at[1], at[1]), "021:?/7": (at[2], at[2]), "021:25/201": (at[3], at[4])}


def test_decode_progress_ends_at_the_file_size(tmp_path):
    """The bar is fed byte offsets, one bar per pass over a file (label "FILE: what"): its last call for a
    file must be the file's size, or it stops short of 100 % and never ends its line (the last record's
    offset is a record length before the end); within a pass the offsets only grow."""
    calls = []
    decode.decode_job(DecodeOptions(inputs=(RADAR, ADSB), output=str(tmp_path / "d.csv"), chunk_mb=0.1),
                      on_chunk=lambda done, size, label: calls.append((label, done, size)))
    for path in (RADAR, ADSB):
        name, size = Path(path).name, Path(path).stat().st_size
        mine = [c for c in calls if c[0].startswith(f"{name}: ")]
        assert len(mine) >= 2 and mine[-1] == (f"{name}: decoding", size, size)
        assert all(done <= total == size for _, done, total in mine)
        for label in {c[0] for c in mine}:
            done = [c[1] for c in mine if c[0] == label]
            assert done == sorted(done), label
