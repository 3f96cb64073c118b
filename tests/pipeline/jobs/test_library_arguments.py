"""The library's arguments (asterix.read/iter_read, load, build_measurements, the job options): a date is
a UTC calendar day under one rule everywhere, one path is one input, type mistakes and nonsense values are
refused with a message naming the argument, and what is left out is said. Expected values come from the
fixture's own time-of-day column and the simulator's setup (08:00 UTC start), never from the code under
test."""

from __future__ import annotations

import datetime as dt
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from container_bytes import pcap_file, udp_frame

import msdc.asterix as asterix
from msdc.pipeline.jobs import common, correlate, quality, track
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.jobs.track import TrackOptions
from msdc.pipeline.model import schema
from msdc.pipeline.model.load import load
from msdc.pipeline.model.measurements import OffEarthWarning, build_measurements
from msdc.pipeline.model.sensors import read_sensors

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB, SENSORS = str(FIX / "radar.ast"), str(FIX / "adsb.ast"), str(FIX / "sensors.toml")
DAY = pd.Timestamp("2019-03-01", tz="UTC")


@pytest.fixture(scope="module")
def adsb() -> pd.DataFrame:
    return asterix.read(ADSB).frames[21]


@pytest.fixture(scope="module")
def radar() -> pd.DataFrame:
    return asterix.read(RADAR).frames[48]


def _first_expected(frame: pd.DataFrame) -> pd.Timestamp:
    """The first record's instant on 2019-03-01: midnight plus its own time of day (I021/073 etc.)."""
    return DAY + pd.to_timedelta(float(frame["time_of_day"].iloc[0]), "s")


MIDNIGHTS = [pd.Timestamp("2019-03-01"), pd.Timestamp("2019-03-01", tz="UTC"), dt.datetime(2019, 3, 1),
             dt.datetime(2019, 3, 1, tzinfo=dt.UTC), np.datetime64("2019-03-01"), "2019-03-01T00:00",
             " 2019-03-01 ", dt.date(2019, 3, 1)]
SHIFTED = [(pd.Timestamp("2019-03-01 12:00"), "time of day (12:00:00)"),
           (dt.datetime(2019, 3, 1, 12), "time of day (12:00:00)"),
           ("2019-03-01T12:00", "time of day (12:00:00)"),
           (pd.Timestamp("2019-03-01", tz="Asia/Kuala_Lumpur"), "not a UTC calendar day"),
           ("01/03/2019", "'01/03/2019': not a date"), (pd.NaT, "not a date")]
NOT_DATES = [(20190301, "an integer says neither YYYYMMDD nor nanoseconds"),
             (1.5, "float is not a date type"), (True, "integer")]


@pytest.mark.parametrize("date", MIDNIGHTS, ids=repr)
def test_a_midnight_is_its_day_everywhere(date, adsb):
    """A midnight datetime or Timestamp (naive or UTC) and an ISO text name the day: read, iter_read and
    build_measurements put the first report at 08:00:00.13 of it (the simulator starts at 08:00 UTC)."""
    want = _first_expected(adsb)
    assert want.strftime("%H:%M") == "08:00"
    assert asterix.read(ADSB, date=date).frames[21]["timestamp"].iloc[0] == want
    assert next(asterix.iter_read(ADSB, date=date)).frames[21]["timestamp"].iloc[0] == want
    undated = adsb.drop(columns="timestamp")
    assert build_measurements(None, undated, date=date)["time"].iloc[0] == want


# datetime64[ns] holds 1677-09-21 00:12:43 .. 2262-04-11 23:47:16 (pandas' Timestamp.min/max): a day
# outside it, or so near its ends that the day before or after does not fit, wrapped every timestamp
OUT_OF_RANGE = ["9999-12-31", "1000-01-01", "0001-01-01", "2262-04-12", "2262-04-11", "1677-09-21",
                "1677-09-22", dt.date(2300, 1, 1), pd.Timestamp("1677-12-31")]


@pytest.mark.parametrize("date", OUT_OF_RANGE, ids=str)
def test_a_date_outside_the_nanosecond_span_is_refused_everywhere(date, adsb, tmp_path):
    """9999-12-31 put the first report in 1816 and 1000-01-01 in 2169 (int64 wrap), silently."""
    undated = adsb.drop(columns="timestamp")
    calls = [lambda: asterix.read(ADSB, date=date), lambda: list(asterix.iter_read(ADSB, date=date)),
             lambda: load([ADSB], date=date), lambda: build_measurements(None, undated, date=date)]
    day = pd.Timestamp(date).date().isoformat()
    for call in calls:
        with pytest.raises(ValueError) as info:
            call()
        text = str(info.value)
        assert text.startswith(f"date {day}: outside the days") and "1678-01-01 to 2261-12-31" in text
    with pytest.raises(OptionError) as info:
        track.validate(TrackOptions(inputs=(ADSB,), callsign="MAS72", date=date,
                                         output=str(tmp_path / "t.csv")))
    assert str(info.value).startswith(f"--date {day}: outside the days")


@pytest.mark.parametrize("date", ["1678-01-01", "2261-12-31"])
def test_the_first_and_last_day_allowed_keep_exact_timestamps(date, adsb):
    """The range's ends: their neighbour days fit datetime64[ns] (checked against pandas' own limits) and
    the first report is that day plus its own time of day."""
    day = pd.Timestamp(date, tz="UTC")
    assert pd.Timestamp.min.tz_localize("UTC") < day - pd.Timedelta(days=1)
    assert day + pd.Timedelta(days=2) < pd.Timestamp.max.tz_localize("UTC")
    want = day + pd.to_timedelta(float(adsb["time_of_day"].iloc[0]), "s")
    assert asterix.read(ADSB, date=date).frames[21]["timestamp"].iloc[0] == want


@pytest.mark.parametrize(("date", "words"), SHIFTED + NOT_DATES, ids=repr)
def test_a_date_that_would_shift_the_times_is_refused_everywhere(date, words, adsb, tmp_path):
    """A time of day or another zone would move every timestamp (12:00 put the first report at 20:00, and
    +08:00 at 00:00); an integer read as nanoseconds put it in 1970. One rule for every entry point."""
    undated = adsb.drop(columns="timestamp")
    calls = [lambda: asterix.read(ADSB, date=date), lambda: list(asterix.iter_read(ADSB, date=date)),
             lambda: load([ADSB], date=date), lambda: build_measurements(None, undated, date=date)]
    for call in calls:
        with pytest.raises((ValueError, TypeError)) as info:
            call()
        assert str(info.value).startswith("date ") and words in str(info.value)
    with pytest.raises(OptionError) as info:  # the job options: the same rule, named as the option
        track.validate(TrackOptions(inputs=(ADSB,), callsign="MAS72", date=date,
                                         output=str(tmp_path / "t.csv")))
    assert str(info.value).startswith("--date ") and words in str(info.value)


def test_the_job_options_take_what_read_takes(tmp_path):
    """The ISO text read takes as a date, and the {category: edition} dict, are accepted by the options
    (they were refused with messages naming the format given, or an empty edition)."""
    checked = track.validate(TrackOptions(inputs=ADSB, callsign="MAS72", date="2019-03-01",
                                               editions={21: "2.7"}))
    assert checked.inputs == [Path(ADSB)] and checked.editions == {21: "2.7"}
    checked = correlate.validate(correlate.CorrelateOptions(inputs=(RADAR, ADSB), sensors=SENSORS,
                                                            callsign="MAS72", editions="21=0.26"))
    assert checked.editions == {21: "0.26"}
    with pytest.raises(OptionError, match=r"--edition 21=9\.9"):
        track.validate(TrackOptions(inputs=ADSB, callsign="MAS72", editions={21: "9.9"}))


@pytest.mark.parametrize(("changed", "words"), [
    ({"smooth": "no"}, "--smooth 'no': must be True or False, not str"),  # "no" was taken as true
    ({"all_aircraft": 1, "callsign": None}, "--all 1: must be True or False, not int"),
    # the next failed in os.fspath with a TypeError naming no option
    ({"sensors": 5}, "--sensors 5: expected text (a path, a name or a value), not int"),
    ({"address": 0x750312}, "--address 7668498: expected text"),
])
def test_job_options_of_the_wrong_type_are_named(changed, words):
    options = TrackOptions(**{"inputs": ADSB, "callsign": "MAS72", **changed})
    with pytest.raises(OptionError, match="^" + words.replace("(", r"\(").replace(")", r"\)")):
        track.validate(options)


def test_a_time_window_as_datetimes_is_still_taken():
    """The text check is for numbers given where text belongs: --from/--to also take datetimes."""
    window = dict(from_time=dt.datetime(2019, 3, 1, 8, 10, tzinfo=dt.UTC),
                  to_time=pd.Timestamp("2019-03-01T08:20Z"))
    checked = track.validate(TrackOptions(inputs=ADSB, callsign="MAS72", date="2019-03-01", **window))
    assert checked.selection.start.instant == pd.Timestamp("2019-03-01T08:10Z")
    assert checked.selection.end.instant == pd.Timestamp("2019-03-01T08:20Z")


def test_track_job_returns_the_table_without_an_output(adsb, tmp_path):
    """The guide's notebook use (docs/guide/python.md): track_job returns the table; only the command needs
    an output."""
    from msdc.asterix.encode import encode_frame

    columns = ["sac", "sic", "time_of_day", "latitude", "longitude", "address", "callsign", "flight_level"]
    few = adsb.loc[adsb["callsign"] == "MAS72", columns].iloc[:120]
    path = tmp_path / "mas72.ast"
    path.write_bytes(encode_frame(21, few, edition="2.7"))
    result = track.track_job(TrackOptions(inputs=str(path), callsign="MAS72", date="2019-03-01",
                                                adsb_sigma_m=30.0))
    assert result.tracks["time"].min() == _first_expected(few)
    with pytest.raises(OptionError, match="give at least one output"):
        track.validate(TrackOptions(inputs=str(path), callsign="MAS72"), require_output=True)


def test_missing_columns_are_refused_not_dropped(radar, adsb):
    """Frames swapped, or decoded without a position, gave 0 rows without a word: every row was dropped."""
    sensors = read_sensors(SENSORS)
    with pytest.raises(ValueError, match="cat048: the frame lacks rho_nm/theta_deg or x_nm/y_nm"):
        build_measurements(adsb, radar, sensors)
    narrow = asterix.read(RADAR, columns=("address",)).frames[48]
    with pytest.raises(ValueError, match="cat048: the frame lacks"):
        build_measurements(narrow, None, sensors)
    with pytest.raises(ValueError, match="cat021: the frame lacks latitude/longitude"):
        build_measurements(None, asterix.read(ADSB, columns=("address",)).frames[21])
    with pytest.raises(TypeError, match="cat021: a list, not a decoded CAT021 frame"):
        build_measurements(None, [1, 2])


def test_a_position_off_the_earth_is_said(adsb):
    """One report put at latitude 95 deg is left out, and a warning says so with its offset."""
    bad = adsb.copy()
    bad.loc[bad.index[7], "latitude"] = 95.0
    with pytest.warns(OffEarthWarning) as caught:
        meas = build_measurements(None, bad)
    assert len(meas) == len(adsb) - 1  # every fixture report has a position and a time
    (text,) = [str(w.message) for w in caught]
    assert f"1 CAT021 report(s) with a position off the Earth (first at offset {bad['offset'].iloc[7]}:" \
           " latitude 95.0000" in text


@pytest.mark.parametrize(("sigma", "error"), [(-5, ValueError), (0, ValueError), (0.4, ValueError),
                                              (1e9, ValueError), (float("nan"), ValueError),
                                              ("5", TypeError), (True, TypeError)])
def test_adsb_sigma_is_range_checked(sigma, error, adsb):
    """-5 m gave a covariance of 25 m^2 and 0 a zero covariance: the command's range (0.5-20,000 m)."""
    with pytest.raises(error, match=r"^adsb_sigma_m "):
        build_measurements(None, adsb, adsb_sigma_m=sigma)


def test_the_library_and_the_command_take_the_same_adsb_sigma():
    from msdc.pipeline.model.measurements import ADSB_SIGMA_RANGE_M

    assert ADSB_SIGMA_RANGE_M == common.ADSB_SIGMA_RANGE_M == (0.5, 20000.0)


def test_a_declared_adsb_sigma_is_the_covariance(adsb):
    """Reports without NACp get sigma^2 per axis: 0.5 m gives 0.25 m^2 (the lower bound is allowed)."""
    no_nacp = adsb.drop(columns=[c for c in ("nacp",) if c in adsb])
    meas = build_measurements(None, no_nacp, adsb_sigma_m=0.5)
    assert (meas["cov_ee_m2"] == 0.25).all() and (meas["cov_en_m2"] == 0.0).all()


def test_one_path_is_one_input(tmp_path):
    """A str where a sequence is expected was read character by character ('/: cannot read')."""
    one = load(ADSB)
    assert [i["path"] for i in one.inputs] == [ADSB] and len(one.frames[21]) == len(load([ADSB]).frames[21])
    assert load(Path(ADSB)).inputs[0]["path"] == ADSB
    options = TrackOptions(inputs=RADAR, callsign="MAS72", output=str(tmp_path / "t.csv"))
    checked = track.validate(options)
    assert checked.inputs == [Path(RADAR)]
    with pytest.raises(TypeError, match="paths 5"):
        load(5)


def test_one_column_name_is_one_column(adsb):
    meas = build_measurements(None, adsb)
    assert schema.validate(meas, "latitude") is meas
    assert schema.column_names("latitude") == ["latitude"]


def test_the_same_recording_twice_is_refused(tmp_path):
    """load([p, p]) doubled every record (29,972 rows): the same content twice is refused, naming both."""
    copy = tmp_path / "copy.ast"
    copy.write_bytes(Path(ADSB).read_bytes())
    for paths in ([ADSB, ADSB], [ADSB, copy]):
        with pytest.raises(ValueError, match=r"has the same content as .*adsb\.ast \(SHA-256\)"):
            load(paths)


@pytest.mark.parametrize(("categories", "error", "words"), [
    ((8,), ValueError, "msdc does not decode CAT008; it decodes CAT001, CAT002, CAT010, CAT019, CAT020, "
                       "CAT021, CAT023, CAT025, CAT034, CAT048, CAT062"),
    ((21, 999), ValueError, "CAT999"), ("21", TypeError, "a category number or a sequence"),
    ((21.0,), TypeError, "21.0 is not a category number"),
    (2.5, TypeError, "a category number or a sequence")])
def test_categories_are_checked(categories, error, words):
    for call in (lambda: asterix.read(ADSB, categories=categories),
                 lambda: list(asterix.iter_read(ADSB, categories=categories))):
        with pytest.raises(error) as info:
            call()
        assert str(info.value).startswith("categories ") and words in str(info.value)


@pytest.mark.parametrize("strict", ["False", 0, 1, None], ids=repr)
def test_strict_is_a_bool(strict, tmp_path):
    """strict="False" turned strict mode on (a non-empty text is true): a truncated recording then raised
    at its cut block instead of decoding the blocks before it."""
    cut = tmp_path / "cut.ast"
    cut.write_bytes(Path(RADAR).read_bytes()[:100_000])
    for call in (lambda: asterix.read(cut, strict=strict),
                 lambda: next(asterix.iter_read(cut, strict=strict))):
        with pytest.raises(TypeError, match=rf"^strict {re.escape(repr(strict))}: must be True or False "
                                            rf"\(a bool\), not {type(strict).__name__}$"):
            call()
    # a numpy bool is a bool: the 3200 records of the whole blocks (docs/decoding/bad-input.md), the cut
    # block reported
    rec = asterix.read(cut, strict=np.False_)
    assert len(rec.frames[48]) == 3200 and len(rec.errors) == 1


@pytest.mark.parametrize(("columns", "words"), [
    ([1], "columns [1]: 1 is not a column name (a str; see docs/columns.md)"),
    (("address", b"callsign"), "b'callsign' is not a column name"),
    (5, "columns 5: give a column name or a sequence of them")])
def test_columns_are_names(columns, words):
    """columns=[1] failed with AttributeError 'int' object has no attribute 'endswith'."""
    for call in (lambda: asterix.read(ADSB, columns=columns),
                 lambda: next(asterix.iter_read(ADSB, columns=columns))):
        with pytest.raises(TypeError) as info:
            call()
        assert words in str(info.value)


@pytest.mark.parametrize(("editions", "error", "words"), [
    # 2.7 is a table, but a float: refused as one, not 'not supported'; 1.30 is read as 1.3
    ({21: 2.7}, TypeError, "editions {21: 2.7}: CAT021 edition 2.7 is a float; give it as text"),
    ({48: 1.30}, TypeError, "editions {48: 1.3}: CAT048 edition 1.3 is a float; give it as text, as the "
                            "tables name it ('1.30': a float cannot hold 1.30; tables: 1.27, 1.28, 1.29, "
                            "1.30"),
    ([21], TypeError, "editions [21]: 21 is not a 'CAT=EDITION' text; give a mapping such as {21: '0.26'}"),
    (21, TypeError, "editions 21: give a mapping such as {21: '0.26'} or 'CAT=EDITION' texts"),
    (["21"], ValueError, "editions ['21']: '21' is not 'CAT=EDITION' text such as '21=0.26'"),
    ({21.0: "2.7"}, TypeError, "editions {21.0: '2.7'}: category 21.0 is not a category number")])
def test_editions_are_a_mapping_or_texts_of_text_editions(editions, error, words):
    """editions={48: 1.30} said "edition '1.3' is not supported", {21: 2.7} was taken, and editions=[21]
    said "CAT021 edition '' is not supported"."""
    for call in (lambda: asterix.read(RADAR, editions=editions),
                 lambda: next(asterix.iter_read(RADAR, editions=editions))):
        with pytest.raises(error) as info:
            call()
        assert str(info.value).startswith(words)


def test_every_form_of_editions_pins_the_edition():
    """The forms read documents, a category key given as text, and spaces after '=' ('48= 1.30' was
    'edition \' 1.30\' is not supported'); a job's options refuse a float edition as read does (they said
    {21: 2.7} was 'not supported')."""
    for editions in ({48: "1.30"}, {"48": "1.30"}, ["48=1.30"], "48=1.30", ("48= 1.30",)):
        assert asterix.read(RADAR, editions=editions).editions == {48: "1.30"}, editions
    with pytest.raises(OptionError, match=r"^--edition 21=2\.7: a float; give the edition as text"):
        track.validate(TrackOptions(inputs=ADSB, callsign="MAS72", editions={21: 2.7}))


def test_a_negative_category_is_named_as_given():
    """categories=-1 said 'msdc does not decode CAT-01'."""
    with pytest.raises(ValueError, match=r"^categories -1: msdc does not decode category -1; it decodes "
                                         r"CAT001"):
        asterix.read(ADSB, categories=-1)


def radar_pcap(tmp_path: Path) -> Path:
    """The radar fixture's first 10 data blocks (CAT, then a 2-byte LEN counting the header) in UDP packets
    captured on 2019-03-01 at 08:00 UTC: 17956 days after 1970-01-01 (1551398400 s) + 28800 s."""
    data, blocks, at = Path(RADAR).read_bytes(), [], 0
    while len(blocks) < 10:
        n = int.from_bytes(data[at + 1:at + 3], "big")
        blocks.append(data[at:at + n])
        at += n
    pcap, _ = pcap_file([(1_551_398_400 + 28_800 + i, 0, udp_frame(b)) for i, b in enumerate(blocks)])
    path = tmp_path / "radar.pcap"
    path.write_bytes(pcap)
    return path


def test_a_date_a_pcap_capture_overrides_is_said(tmp_path):
    """read(pcap, date="2020-01-01") dated the records by the capture time and said nothing of the date
    given (the command warns '--date ignored'); said now, naming the file and both days."""
    path = radar_pcap(tmp_path)
    with pytest.warns(UserWarning) as said:
        rec = asterix.read(path, date="2020-01-01")
    assert [str(w.message) for w in said] == [
        f"{path}: date=2020-01-01 ignored, the capture time dates a pcap file (day 0 2019-03-01)"]
    assert rec.date == dt.date(2019, 3, 1)
    assert (rec.frames[48].timestamp.dt.date == dt.date(2019, 3, 1)).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        asterix.read(path)  # no date given: nothing to say
        asterix.read(path, date="2019-03-01")  # the capture day itself: nothing ignored


def test_one_category_is_a_category(adsb):
    rec = asterix.read(RADAR, categories=48)
    assert list(rec.frames) == [48] and 21 not in rec.frames
    assert len(asterix.read(ADSB, categories=np.int64(21)).frames[21]) == len(adsb)


@pytest.mark.parametrize(("chunk", "error"), [("64", TypeError), (64.0, TypeError), (0, ValueError),
                                              (-5, ValueError), (True, TypeError), (2**70, ValueError)])
def test_iter_read_chunk_is_checked(chunk, error):
    """chunk="64" failed deep in numpy; 0 and -5 ran one block per chunk with an empty first one; 2**70 failed
    with OverflowError 'int too big to convert'."""
    with pytest.raises(error, match=r"^chunk "):
        next(asterix.iter_read(ADSB, chunk=chunk))


def test_iter_read_chunk_bounds_are_named_and_the_largest_reads_the_file_at_once():
    with pytest.raises(ValueError, match=r"^chunk 1180591620717411303424: must be a positive number of "
                                         r"bytes, at most 4611686018427387904 \(2\*\*62"):
        asterix.iter_read(ADSB, chunk=2**70)
    chunks = list(asterix.iter_read(RADAR, chunk=2**62))
    assert len(chunks) == 1 and len(chunks[0].frames[48]) == len(asterix.read(RADAR).frames[48])


@pytest.mark.parametrize(("changed", "error", "words"), [
    ({"progress": 5}, TypeError, "progress 5: must be a function progress(done, total, what) or None, "
                                 "not int"),
    ({"pool": 5}, TypeError, "pool 5: must be a concurrent.futures.Executor (a ProcessPoolExecutor) or None, "
                             "not int"),
    ({"chunk": 0}, ValueError, "chunk 0: must be a positive number of bytes"),
    ({"categories": 8}, ValueError, "categories 8: msdc does not decode CAT008"),
    ({"strict": "no"}, TypeError, "strict 'no': must be True or False"),
    ({"format": "pcapx"}, asterix.UnreadableInput, "unknown container format 'pcapx'"),
    ({"path": "no/such.ast"}, asterix.UnreadableInput,
     "no/such.ast: cannot read: No such file or directory")])
def test_iter_read_checks_its_arguments_when_called(changed, error, words):
    """progress=5 failed with "'int' object is not callable" and pool=5 with AttributeError 'submit', both
    at the first chunk, as every argument error and a missing file did: now each is refused, named, by the
    call itself, before anything is read."""
    kw = {"path": ADSB, **changed}
    with pytest.raises(error) as info:
        asterix.iter_read(kw.pop("path"), **kw)
    assert words in str(info.value)


def test_a_dataset_argument_that_is_not_one_is_named():
    """load(dataset=5) failed with AttributeError 'int' object has no attribute 'records'."""
    from msdc.pipeline.model.load import load_measurements

    with pytest.raises(TypeError, match=r"^dataset 5: not a dataset's inputs \(int\); give "):
        load([ADSB], dataset=5)
    with pytest.raises(TypeError, match=r"^dataset 'data': not a dataset's inputs \(str\)"):
        load_measurements([ADSB], read_sensors(SENSORS), dataset="data")


def test_the_sensor_table_or_its_path(radar):
    """A path is read with read_sensors; a dict is refused naming the argument (it failed on .duplicated)."""
    by_path = build_measurements(radar, None, SENSORS)
    by_table = build_measurements(radar, None, read_sensors(SENSORS))
    pd.testing.assert_frame_equal(by_path, by_table)
    with pytest.raises(TypeError, match="sensors: a dict, not the sensor table"):
        build_measurements(radar, None, {"sac": 25})
    with pytest.raises(ValueError, match="sensors: the table lacks latitude"):
        build_measurements(radar, None, pd.DataFrame({"sac": [25], "sic": [201]}))
    # a site the file reader would refuse: it failed as the measurement schema's "latitude" column
    table = read_sensors(SENSORS)
    for column, value, want in (("latitude", float("nan"), "latitude nan"),
                                ("longitude", 200.0, "longitude 200.0"),
                                ("altitude_m", float("inf"), "altitude_m inf")):
        bad = table.assign(**{column: value})
        row = r"^sensors: row 0 \('KLIA MSSR', SAC 25 SIC 201\) "
        with pytest.raises(ValueError, match=row + want + ": expected "):
            build_measurements(radar, None, bad)


@pytest.fixture(scope="module")
def adsb_0_23(tmp_path_factory, adsb) -> Path:
    """100 fixture ADS-B reports written as edition 0.23, one a block: I021/130 is 6 bytes in 0.23 and 8
    from 0.24 (specs), so 2.7 walks none of them and 0.23 alone walks every one."""
    from msdc.asterix.encode import encode_frame

    columns = ["sac", "sic", "time_of_day", "latitude", "longitude", "address", "callsign", "flight_level"]
    path = tmp_path_factory.mktemp("e023") / "adsb023.ast"
    path.write_bytes(encode_frame(21, adsb[columns].iloc[:100], edition="0.23", records_per_block=1))
    return path


def test_a_wrong_edition_is_a_python_warning(adsb_0_23):
    """read under a wrong pin (2.7) returned an empty frame with no warning: now asterix.EditionWarning says
    how many blocks failed and the edition to pin, in read's own terms; load passes it on. Unpinned, auto
    reads the recording as 0.23, with nothing to say."""
    advice = ("100 CAT021 block(s) could not be decoded under edition 2.7; every one sampled decodes under "
              "0.23: pin it with editions={21: '0.23'}")
    with pytest.warns(asterix.EditionWarning) as caught:
        rec = asterix.read(adsb_0_23, editions={21: "2.7"})
    assert len(rec.frames[21]) == 0 and [str(w.message) for w in caught] == [f"{adsb_0_23}: {advice}"]
    with pytest.warns(asterix.EditionWarning, match="pin it with editions="):
        load(adsb_0_23, editions={21: "2.7"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # pinned right, or chosen: nothing to say
        assert len(asterix.read(adsb_0_23, editions={21: "0.23"}).frames[21]) == 100
        assert len(asterix.read(adsb_0_23).frames[21]) == 100


def test_the_jobs_say_a_wrong_edition_once_in_their_terms(adsb_0_23):
    """The jobs name --edition; the library's Python warning does not reach the command's stderr."""
    options = quality.QualityOptions(inputs=(str(adsb_0_23),), all_aircraft=True, editions=("21=2.7",))
    checked = quality.validate(options)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _, said = common.load_inputs(options, checked, None)
    assert not [w for w in caught if issubclass(w.category, asterix.EditionWarning)]
    assert sum("pin it with --edition 21=0.23" in w for w in said) == 1


def test_output_under_a_file_says_it_is_a_file(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(OptionError) as info:
        common.output_path("-o", afile / "r.xlsx", (".xlsx",))
    assert str(info.value) == f"-o {afile / 'r.xlsx'}: {afile} is a file, not a directory"


def test_max_coast_names_its_real_bounds(tmp_path):
    """0 is refused by the --step bound, so 'from 0 to 86400 s' misled."""
    base = {"inputs": (ADSB,), "callsign": "MAS72", "output": str(tmp_path / "t.csv")}
    for coast in (1e12, 0.0):
        with pytest.raises(OptionError) as info:
            track.validate(TrackOptions(**base, max_coast_s=coast))
        assert "from 0 " not in str(info.value) and "--step (1)" in str(info.value)


def test_stats_times_are_labelled_utc():
    from msdc.pipeline.quality.inventory import format_stats, stats_tables

    rec = asterix.read(ADSB, date="2019-03-01")
    text = format_stats(stats_tables(rec.frames, rec.errors))
    header = text.splitlines()[1]
    assert "start (UTC)" in header and "end (UTC)" in header


def test_sensor_type_message_grammar(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[[sensor]]\nname = "r"\nsac = "25"\nsic = 1\nlatitude = 0.0\nlongitude = 0.0\n'
                    "altitude_m = 0.0\n")
    with pytest.raises(ValueError, match="sac = '25' should be an integer$"):
        read_sensors(path)


def test_the_column_docs_mark_cat021_track_number_as_2x(adsb_0_23):
    """0.2x editions have no I021/161: their frames have no track_number, and the Columns page says so."""
    assert "track_number" not in asterix.read(adsb_0_23, editions={21: "0.23"}).frames[21]
    assert "track_number" in asterix.read(ADSB).frames[21]  # the fixture is 2.x
    page = (Path(__file__).resolve().parents[3] / "docs" / "decoding" / "columns.md").read_text()
    row = [line for line in page.splitlines() if line.startswith("| identity |")][0]  # CAT048/021/034
    cat021 = row.split("|")[3]
    assert "`track_number` (2.x)" in cat021


def test_an_output_that_is_the_one_input_is_refused(tmp_path):
    """inputs given as one path: the check that an output is not an input read it letter by letter, so
    -o naming the input itself was let through (writing it would destroy the recording)."""
    rec = tmp_path / "t.csv"
    rec.write_bytes(Path(ADSB).read_bytes())
    with pytest.raises(OptionError, match="is the input"):
        track.validate(TrackOptions(inputs=str(rec), callsign="MAS72", output=str(rec)))


def test_one_value_of_a_repeatable_option_is_that_value(tmp_path):
    """A string given to a repeatable or positional option is one value, as ``inputs`` takes it (the query,
    the feed, the recording and the sensor under test were read letter by letter: "--udp '1'", "--test
    '0'", "f: input file does not exist", a query "S E L E C T"); a number is one value; None or a list is
    the default or the list's tuple; a comma-separated option (--sources) keeps its text."""
    from msdc.pipeline.jobs import conflicts, decode, evaluate, ingest, listen, replay, sql

    dataset = tmp_path / "ds"
    dataset.mkdir()
    assert sql.validate(sql.SqlOptions(query="SELECT 1", dataset=str(dataset)))[0] == "SELECT 1"
    assert listen.ListenOptions(udp="127.0.0.1:50998").udp == ("127.0.0.1:50998",)
    assert listen.validate(listen.ListenOptions(udp="127.0.0.1:50998", duration_s=1))
    assert replay.ReplayOptions(inputs=RADAR).inputs == (RADAR,)
    assert replay.validate(replay.ReplayOptions(inputs=RADAR, to="127.0.0.1:50999"))
    assert evaluate.EvaluateOptions(test_sensors="048:25/201").test_sensors == ("048:25/201",)
    assert decode.DecodeOptions(inputs=RADAR, categories=48).categories == (48,)
    assert ingest.IngestOptions(inputs=Path(RADAR), categories=[48, 21]).categories == (48, 21)
    assert ingest.IngestOptions(inputs=Path(RADAR)).inputs == (Path(RADAR),)
    assert decode.DecodeOptions(inputs=None, categories=None, editions=None).editions == ()
    assert conflicts.ConflictOptions(horizons_s=60).horizons_s == (60,)
    assert conflicts.ConflictOptions(sources="radar,adsb").sources == "radar,adsb"
    assert decode.DecodeOptions(editions={21: "0.26"}).editions == {21: "0.26"}


def test_none_for_an_option_that_cannot_be_unset_is_named():
    """chunk_mb=None failed as "unsupported operand type(s) for *: 'NoneType' and 'float'"."""
    from msdc.pipeline.jobs import decode, ingest

    with pytest.raises(OptionError, match=r"^--chunk-mb None: must be given a value \(leave it out for the "
                                          r"default 8\)"):
        ingest.validate(ingest.IngestOptions(inputs=RADAR, dataset="ds", date="2019-03-01", chunk_mb=None))
    with pytest.raises(OptionError, match=r"^--chunk-mb None"):
        decode.validate(decode.DecodeOptions(inputs=RADAR, chunk_mb=None))


def test_conflicts_from_python_refuses_an_aircraft_selection_and_needs_no_table(tmp_path):
    """ConflictOptions inherits callsign/address/all_aircraft, which the job ignored (every aircraft was
    tracked, said nowhere): refused. Without -o (the command requires it) the job validates, and
    write_conflicts writes only what is given."""
    from msdc.pipeline.jobs import conflicts

    base = dict(inputs=(RADAR, ADSB), sensors=SENSORS, date="2019-03-01")
    for changed in ({"callsign": "MAS72", "all_aircraft": False},
                    {"address": "750312", "all_aircraft": False}, {"all_aircraft": False}):
        with pytest.raises(OptionError, match="^callsign, address, all_aircraft: msdc conflicts tracks"):
            conflicts.validate(conflicts.ConflictOptions(**base, json=str(tmp_path / "c.json"), **changed))
    checked = conflicts.validate(conflicts.ConflictOptions(**base, json=str(tmp_path / "c.json")))
    assert checked.output is None and checked.json == tmp_path / "c.json"


@pytest.mark.parametrize("command", ["decode", "stats"])
def test_a_cat010_kind_is_refused_where_records_have_none_yet(command):
    """decode and stats read CAT010 records before their kind (mlat, smr) is worked out: --sensor
    010:0/107:mlat kept none of the real multilateration hour's 84,453 records, said only as "the selection
    left no record". Refused, naming the form to give; without the kind it is taken."""
    from msdc.pipeline.jobs import decode, stats

    module = {"decode": decode, "stats": stats}[command]
    options_cls = {"decode": decode.DecodeOptions, "stats": stats.StatsOptions}[command]
    words = (rf"^--sensor 010:0/107:mlat: {command} reads CAT010 records before their kind \(mlat\).*name "
             r"the sensor without it, --sensor 010:0/107$")
    with pytest.raises(OptionError, match=words):
        module.validate(options_cls(inputs=RADAR, sensor_ids="010:0/107:mlat"))
    assert module.validate(options_cls(inputs=RADAR, sensor_ids="010:0/107")).selection.active


def test_evaluate_s_library_only_options_are_checked_first():
    """EvaluateOptions without a preset said "unknown preset 'None'"; max_coast_s=-1 (no flag: the reference
    tracker's) failed after decoding, from the tracker: both OptionErrors before anything is read."""
    from msdc.pipeline.jobs import evaluate

    base = dict(inputs=(RADAR, ADSB), sensors=SENSORS, date="2019-03-01")
    with pytest.raises(OptionError, match="^--preset is required"):
        evaluate.validate(evaluate.EvaluateOptions(**base))
    with pytest.raises(OptionError, match=r"^max_coast_s -1: must be a finite number of seconds > 0 and >= "
                                          r"the reference's step \(1\)"):
        evaluate.validate(evaluate.EvaluateOptions(**base, preset="eurocontrol-1997-ssr", max_coast_s=-1))
