"""A raw stream's day 0 is its first report's day: a daily recording started at midnight whose first plots
are stamped just before it is dated by --date from those plots, and every job says so."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED

from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.model.time import DayTally

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
    tally = DayTally()
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


@pytest.mark.parametrize(("tods", "first_day"), [
    ([86398.0, 86399.0, 0.5, 1.0, 2.0, 3.0], 0),  # a real midnight: the first plots are 2-4 s from the rest
    ([13665.7, 79201.7, 79202.0, 79203.0], 1),  # 79201.7 s less bit 23 (65536 s): a rise of 18 h after it
    ([79202.6, 28802.6, 28803.0, 28807.4], -1),  # 28802.6 s moved +14 h: a drop of 14 h after it
    ([79202.6, 79203.0, 28802.6, 28803.0, 28807.4, 28808.0, 28809.0], -1),  # two damaged
    ([79202.6, 28802.6], 0),  # two that disagree: no follower says which; the first is day 0, as always
    ([50000.0], 0), ([], 0)])
def test_first_report_day_by_hand(tods, first_day):
    """Day 0 is the day of the first report within 1 h (24 h clock) of most of the reports after it; the
    first report's day is counted back from it by the 12 h rule (a drop is a midnight, a rise a day back)."""
    from msdc.asterix.timeline import first_report_day

    assert first_report_day(np.array(tods)) == first_day


def _fixture_with_first_moved(tmp_path, hours: float, count: int = 1) -> str:
    import msdc.asterix as asterix

    frame = asterix.read("fixtures/radar.ast").frames[48]
    frame.iloc[:count, frame.columns.get_loc("time_of_day")] += hours * 3600.0
    path = tmp_path / "r.ast"
    path.write_bytes(encode_frame(48, frame))
    return str(path)


@pytest.mark.parametrize("count", [1, 2])
@pytest.mark.parametrize("chunk", [None, 1, 1000])
def test_a_damaged_first_time_of_day_redates_no_other_report(count, chunk, tmp_path):
    """The fixture (08:00-11:20 on 2019-03-01) with its first record(s)' I048/140 moved +14 h to 22:00:
    every other report was put on 2019-03-02 (day 1). Now each keeps 2019-03-01 plus its own time of day,
    read whole or in chunks (chunk 1: one data block a chunk, the first chunks alone cannot tell)."""
    import msdc.asterix as asterix

    good = asterix.read("fixtures/radar.ast").frames[48]["time_of_day"].to_numpy()
    path = _fixture_with_first_moved(tmp_path, 14.0, count)
    if chunk is None:
        got = asterix.read(path, date="2019-03-01").frames[48]
    else:
        got = pd.concat([r.frames[48] for r in asterix.iter_read(path, date="2019-03-01", chunk=chunk)
                         if 48 in r.frames], ignore_index=True)
    want = pd.Timestamp("2019-03-01", tz="UTC") + pd.to_timedelta(good[count:], "s")
    assert (got["day"].to_numpy()[count:] == 0).all()
    assert (got["timestamp"].iloc[count:].to_numpy() == want.to_numpy()).all()
    assert len(got) == len(good)


REAL_ADSB = SHARED / "real" / "adsb_v023_160510-lebl-220001.ast"


@pytest.mark.skipif(not REAL_ADSB.is_file(), reason=f"{REAL_ADSB} not present: the real-file case is skipped")
def test_one_bit_flip_in_the_real_first_time_of_day_redates_no_other_report(tmp_path):
    """LEBL ADS-B (2016-05-10 22:00:01 to 00:01:02): bit 7 of byte 10 is the top bit of the first record's
    I021/030, 79201.7 s becoming 13665.7 s (03:47). The 49,329 others went 24 h early; now none moves."""
    import msdc.asterix as asterix

    data = bytearray(REAL_ADSB.read_bytes())
    data[10] ^= 0x80
    path = tmp_path / "flip.ast"
    path.write_bytes(bytes(data))
    good = asterix.read(REAL_ADSB, editions={21: "0.23"}, date="2016-05-10").frames[21]
    got = asterix.read(path, editions={21: "0.23"}, date="2016-05-10").frames[21]
    assert got["time_of_day"].iloc[0] == pytest.approx(79201.6953125 - 65536.0)  # the damage, as said
    assert (got["timestamp"].iloc[1:].to_numpy() == good["timestamp"].iloc[1:].to_numpy()).all()
    others = got["timestamp"].iloc[1:]
    assert others.min().floor("s") == pd.Timestamp("2016-05-10 22:00:01", tz="UTC")
    assert others.max() == pd.Timestamp("2016-05-11 00:01:02.1484375", tz="UTC")
    chunks = pd.concat([r.frames[21] for r in asterix.iter_read(path, editions={21: "0.23"},
                                                                date="2016-05-10", chunk=20_000)])
    assert (chunks["timestamp"].to_numpy() == got["timestamp"].to_numpy()).all()
