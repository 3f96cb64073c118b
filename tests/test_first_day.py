"""A raw stream's day 0 is its first report's day: a daily recording started at midnight whose first plots
are stamped just before it is dated by --date from those plots, and every job says so."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pytest

from asterix.encode import encode_frame
from pipeline.cli import main
from pipeline.model.time import FirstDayTally

SENSORS = "fixtures/sensors.toml"  # radar 25/201


def _daily(path, first_tods, n_after: int = 300) -> str:
    tods = np.r_[first_tods, 0.5 + np.arange(n_after)]
    n = len(tods)
    frame = pd.DataFrame({"sac": 25, "sic": 201, "time_of_day": tods, "rho_nm": np.linspace(10, 20, n),
                          "theta_deg": 10.0, "flight_level": 300.0, "track_number": 7, "callsign": "MAS72",
                          "address": "750312"})
    path.write_bytes(encode_frame(48, frame, records_per_block=4))
    return str(path)


def test_tally_by_hand():
    tally = FirstDayTally()
    tally.add({48: pd.DataFrame({"day": [0, 0, 1, 1, 1], "time_of_day": [86399.5, 86398.0, 0.1, 1.0, 2.0]})})
    tally.add({21: pd.DataFrame({"day": [-1, 1], "time_of_day": [86397.0, 3.0]})})
    assert (tally.before, tally.after, tally.earliest_tod_s) == (3, 4, 86397.0)
    # 3 of 7 is above 1 %: a real first day, no warning
    assert tally.warning("x.ast", dt.date(2019, 3, 2), "raw") == []
    tally.after = 400  # 3 of 403: below 1 %, all within 300 s of midnight
    (text,) = tally.warning("x.ast", dt.date(2019, 3, 2), "raw")
    assert "x.ast: its first 3 report(s) are stamped from 23:59:57 to midnight" in text
    assert "the rest are on 2019-03-03" in text and "give --date 2019-03-01" in text
    assert tally.warning("x.ast", None, "raw") == []  # undated: nothing named
    assert tally.warning("x.ast", dt.date(2019, 3, 2), "pcap") == []  # dated by its capture times
    tally.earliest_tod_s = 86400.0 - 301.0  # one plot more than 5 min before midnight: a real first day
    assert tally.warning("x.ast", dt.date(2019, 3, 2), "raw") == []


@pytest.mark.parametrize("job", [["stats"], ["track", "--all", "-o", "{tmp}/t.csv", "--sensors", SENSORS],
                                 ["decode", "-o", "{tmp}/d.csv"]])
def test_jobs_warn_of_a_first_day_of_late_plots(tmp_path, capsys, job):
    path = _daily(tmp_path / "daily.ast", [86399.0, 86399.5])
    args = [a.replace("{tmp}", str(tmp_path)) for a in job]
    assert main([args[0], path, *args[1:], "--date", "2019-03-02"]) == 0
    err = capsys.readouterr().err
    assert "daily.ast: its first 2 report(s) are stamped from 23:59:59 to midnight and the other 300" in err
    assert "give --date 2019-03-01" in err


def test_no_warning_for_a_recording_that_crosses_midnight(tmp_path, capsys):
    # 400 plots in the 400 s before midnight: day 0 is a real part of the recording
    path = _daily(tmp_path / "crossing.ast", 86000.0 + np.arange(400))
    assert main(["stats", path, "--date", "2019-03-02"]) == 0
    assert "to midnight" not in capsys.readouterr().err
