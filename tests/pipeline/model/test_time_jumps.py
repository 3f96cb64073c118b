"""A raw stream's time line that jumps (a long silence, or parts laid out of order) is said with where it
jumps and the other reading the day rule cannot tell it from: the times here are made by hand."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main

SENSORS = "fixtures/sensors.toml"  # radar 25/201


def _raw(path, tods) -> str:
    """A CAT048 raw recording of one aircraft's plots at these times of day, in this order."""
    n = len(tods)
    frame = pd.DataFrame({"sac": 25, "sic": 201, "time_of_day": np.asarray(tods, float),
                          "rho_nm": np.linspace(10, 20, n), "theta_deg": 10.0, "flight_level": 300.0,
                          "track_number": 7, "callsign": "MAS72", "address": "750312"})
    path.write_bytes(encode_frame(48, frame, records_per_block=4))
    return str(path)


def _run(job: list[str], path: str, tmp_path, capsys) -> str:
    """The job's standard error on ``path`` (``{tmp}`` in its options: the test's folder)."""
    args = [a.replace("{tmp}", str(tmp_path)) for a in job[1:]]
    code = main([job[0], path, *args, "--date", "2019-03-01"])
    err = capsys.readouterr().err
    assert code == 0, err
    return err


JOBS = [["stats"], ["decode", "-o", "{tmp}/d.csv"],
        ["track", "--all", "-o", "{tmp}/t.csv", "--sensors", SENSORS]]


@pytest.mark.parametrize("job", JOBS, ids=lambda j: j[0])
def test_a_silence_of_ten_hours_is_said(tmp_path, capsys, job):
    """300 plots from 20:00:00 (4 s apart, to 20:19:56), then 300 from 06:00:00: the day rule reads the
    drop of 14 h as a midnight, a silence of 9.7 h, which a silence of 33.7 h would read alike. Said from
    every 64th plot's time, each the median of five in a row: plot 256's 20:17:04 (73,024 s), then plot
    320's 06:01:20 (108,080 s), 9.74 h later."""
    tods = np.r_[72000.0 + 4 * np.arange(300), 21600.0 + 4 * np.arange(300)]
    err = _run(job, _raw(tmp_path / "r.ast", tods), tmp_path, capsys)
    assert ("r.ast: the time of day of its CAT048 reports jumps from about 20:17 to about 06:01 near byte"
            in err)
    assert "read as about 9.7 h later (a silence)" in err and "or the silence been about 33.7 h" in err


def test_parts_laid_out_of_order_are_said(tmp_path, capsys):
    """300 plots from 10:00:00 (to 10:19:56), then 300 from 09:00:00: read as 1.3 h back on the same day.
    Every 64th plot: 10:00:00, 10:04:16, 10:08:32, 10:12:48, 10:17:04, then 09:01:20, 09:05:36, 09:09:52,
    ...; of five in a row (the first reflected), 10:08:32 (36,512 s) then 09:09:52 (32,992 s): 0.98 h
    back."""
    tods = np.r_[36000.0 + 4 * np.arange(300), 32400.0 + 4 * np.arange(300)]
    err = _run(["stats"], _raw(tmp_path / "r.ast", tods), tmp_path, capsys)
    assert "jumps from about 10:08 to about 09:09" in err
    assert "read as about 1.0 h earlier (reports laid out of order)" in err and "about 23.0 h instead" in err


@pytest.mark.parametrize("tods", [
    86100.0 + 4 * np.arange(150),  # across midnight (23:55 to 00:04:56): a drop of 24 h is a midnight
    np.r_[36000.0 + 4 * np.arange(300), 36000.0 + 4 * 300 + 5 * 3600 + 4 * np.arange(300)],  # 5 h silence
], ids=["midnight", "five-hours"])
def test_no_jump_is_said_of_a_midnight_or_a_shorter_silence(tmp_path, capsys, tods):
    tods = np.asarray(tods) % 86400.0
    assert "jumps" not in _run(["stats"], _raw(tmp_path / "r.ast", tods), tmp_path, capsys)


def test_damaged_times_inside_a_recording_are_no_jump(tmp_path, capsys):
    """Ten plots of 600 stamped 12 h off, one every 60 (the first among them, also the first kept for the
    time line): each stands alone among plots that agree."""
    tods = 36000.0 + 4 * np.arange(600)
    tods[::60] = (tods[::60] + 43000.0) % 86400.0
    assert "jumps" not in _run(["stats"], _raw(tmp_path / "r.ast", tods), tmp_path, capsys)


def test_chunks_in_any_order_find_the_same_jump():
    """The tally keeps groups of reports by byte offset: chunks added in reverse say what one chunk says."""
    from msdc.pipeline.model.time import DayTally

    day = np.r_[np.zeros(640), np.ones(640)].astype(int)
    tod = np.r_[72000.0 + np.arange(640), 21600.0 + np.arange(640)]
    frame = pd.DataFrame({"day": day, "time_of_day": tod, "offset": 12 * np.arange(1280)})
    whole, parts = DayTally(), DayTally()
    whole.add({48: frame})
    for lo in range(1280 - 128, -1, -128):
        parts.add({48: frame.iloc[lo:lo + 128]})
    assert whole.jumps()["offset"].tolist() == parts.jumps()["offset"].tolist() == [640 * 12]  # 10th kept
    assert whole.jump_warnings("x", "pcap") == []  # a container's capture times date its reports


def test_each_categorys_time_line_is_its_own(tmp_path, capsys):
    """One hour's CAT048 plots (10:00:00-10:19:56), then the same hour's CAT021 reports: the file's times go
    back 20 min where the CAT021 reports begin, yet neither category's own line jumps (a recording written
    a category after the other). Then a second CAT048 part from 09:00:00 after the first: CAT048's line
    goes back 0.98 h (as in test_parts_laid_out_of_order_are_said) and is said, naming the category."""
    tods = 36000.0 + 4 * np.arange(300)
    adsb = pd.DataFrame({"sac": 0, "sic": 1, "time_of_day": tods, "latitude": 2.7, "longitude": 101.7,
                         "address": "750312", "callsign": "MAS72", "flight_level": 300.0})
    path = tmp_path / "r.ast"
    path.write_bytes(open(_raw(tmp_path / "a.ast", tods), "rb").read() + encode_frame(21, adsb))
    assert "jumps" not in _run(["stats"], str(path), tmp_path, capsys)
    both = np.r_[tods, 32400.0 + 4 * np.arange(300)]
    path.write_bytes(open(_raw(tmp_path / "a.ast", both), "rb").read() + encode_frame(21, adsb))
    err = _run(["stats"], str(path), tmp_path, capsys)
    assert "r.ast: the time of day of its CAT048 reports jumps from about 10:08 to about 09:09" in err
    assert "CAT021 reports jumps" not in err


def test_a_chunk_without_a_time_has_no_jump():
    """Reports whose times were all unreadable leave empty samples: no jump, not a failed concatenation."""
    from msdc.pipeline.model.time import DayTally

    tally = DayTally()
    tally.add({48: pd.DataFrame({"day": np.zeros(3, int), "time_of_day": np.full(3, np.nan),
                                 "offset": [0, 12, 24]})})
    assert tally.jumps().empty and tally.jump_warnings("x", "raw") == []
