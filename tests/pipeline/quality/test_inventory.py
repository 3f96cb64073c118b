"""msdc stats streams: tables folded chunk by chunk equal the whole-file tables, and hand-counted values."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

import msdc.asterix as asterix
from msdc.pipeline.jobs import stats
from msdc.pipeline.jobs.common import OptionError
from msdc.pipeline.quality.inventory import StatsAccumulator, stats_tables
from tests.asterix_bytes import block, fspec

ROOT = Path(__file__).resolve().parents[3]
RADAR, ADSB = str(ROOT / "fixtures" / "radar.ast"), str(ROOT / "fixtures" / "adsb.ast")
GARBAGE = b"\xee" * 7


def _callsign(text: str) -> bytes:
    """I048/240: 8 characters of 6 bits (A-Z 1-26, space 32, digits 48-57), left-aligned, space-padded."""
    bits = 0
    for ch in text.ljust(8):
        bits = bits << 6 | (ord(ch) - 64 if ch.isalpha() else ord(ch) if ch.isdigit() else 32)
    return bits.to_bytes(6, "big")


def _plot(sic: int, tod_s: float, address: int | None, callsign: str | None) -> bytes:
    """One CAT048 block of one record: I048/010 (SAC 25), /140, and /220, /240 when given."""
    frns = [1, 2] + ([8] if address is not None else []) + ([9] if callsign is not None else [])
    body = fspec(*frns) + bytes([25, sic]) + round(tod_s * 128).to_bytes(3, "big")
    if address is not None:
        body += address.to_bytes(3, "big")
    if callsign is not None:
        body += _callsign(callsign)
    return block(48, body)


def _hand_built() -> tuple[bytes, int]:
    """Radar 25/201: call-sign-only CS9 twice, a plot with no identity, address 4840D6 (KLM1) twice before
    and twice after midnight; radar 25/202: 4840D6 once. Seven garbage bytes after the third block."""
    blocks = [_plot(201, 86000.0, None, "CS9"), _plot(201, 86100.0, None, "CS9"),
              _plot(201, 86200.0, None, None),
              _plot(201, 86390.0, 0x4840D6, "KLM1"), _plot(202, 86391.0, 0x4840D6, "KLM1"),
              _plot(201, 86395.0, 0x4840D6, "KLM1"), _plot(201, 5.0, 0x4840D6, "KLM1"),
              _plot(201, 10.0, 0x4840D6, "KLM1")]
    head = b"".join(blocks[:3])
    return head + GARBAGE + b"".join(blocks[3:]), len(head)


def _streamed(path, chunk: int, **kw) -> dict[str, pd.DataFrame]:
    acc = StatsAccumulator()
    n = 0
    for rec in asterix.iter_read(path, chunk=chunk, **kw):
        acc.add(rec.frames, rec.errors, rec.ignored)
        n += 1
    assert n >= 3  # several chunks really were folded
    return acc.tables()


def _assert_tables_equal(a: dict[str, pd.DataFrame], b: dict[str, pd.DataFrame]) -> None:
    assert a.keys() == b.keys()
    for name in a:
        pd.testing.assert_frame_equal(a[name].reset_index(drop=True), b[name].reset_index(drop=True),
                                      check_dtype=False, obj=name)


def test_hand_built_recording_counted_by_hand(tmp_path):
    data, garbage_at = _hand_built()
    path = tmp_path / "hand.ast"
    path.write_bytes(data)
    tables = _streamed(path, chunk=1, date="2019-03-01")  # every block its own chunk
    cats = tables["categories"].set_index("category")
    assert cats.loc[48, "records"] == 8
    assert (cats.loc[48, "start"], cats.loc[48, "end"]) == ("2019-03-01 23:53:20", "2019-03-02 00:00:10")
    assert cats.loc[48, "duration_min"] == round((86410 - 86000) / 60, 1)
    assert (cats.loc[48, "addresses"], cats.loc[48, "callsigns"]) == (1, 2)
    src = tables["sources"]
    assert src[["sac", "sic", "records", "addresses", "callsigns"]].values.tolist() == [[25, 201, 7, 1, 2],
                                                                                      [25, 202, 1, 1, 1]]
    assert src[["start", "end"]].values.tolist() == [["2019-03-01 23:53:20", "2019-03-02 00:00:10"],
                                                     ["2019-03-01 23:59:51", "23:59:51"]]
    ac = tables["aircraft"]  # the plot with neither address nor call sign is no aircraft: its own last row
    assert ac[["sic", "address", "callsign", "records", "start", "end", "duration_min"]].values.tolist() == [
        [201, "4840D6", "KLM1", 4, "2019-03-01 23:59:50", "2019-03-02 00:00:10", round(20 / 60, 1)],
        [201, "-", "CS9", 2, "2019-03-01 23:53:20", "23:55:00", round(100 / 60, 1)],
        [201, "(none)", "-", 1, "2019-03-01 23:56:40", "23:56:40", 0.0],
        [202, "4840D6", "KLM1", 1, "2019-03-01 23:59:51", "23:59:51", 0.0]]
    skipped = tables["skipped"]
    assert skipped[["blocks", "bytes", "first_offset"]].values.tolist() == [[1, len(GARBAGE), garbage_at]]
    # undated: clock times, "+1d" past midnight
    undated = _streamed(path, chunk=1)["aircraft"]
    assert undated[["start", "end"]].values.tolist()[0] == ["23:59:50", "+1d 00:00:10"]
    # the same tables from the whole file at once
    _assert_tables_equal(tables, stats_tables(*_whole(path, date="2019-03-01")))


def _whole(path, **kw):
    rec = asterix.read(path, **kw)
    return rec.frames, rec.errors, rec.ignored


@pytest.mark.parametrize("path, chunk", [(RADAR, 20_000), (ADSB, 100_000)])
def test_streamed_tables_equal_whole_file_tables(path, chunk):
    dated = stats_tables(*_whole(path, date="2019-03-01"))
    _assert_tables_equal(_streamed(path, chunk, date="2019-03-01"), dated)
    _assert_tables_equal(_streamed(path, chunk), stats_tables(*_whole(path)))


def test_stats_job_streams_with_its_chunk_size():
    small = stats.stats_job(stats.StatsOptions(inputs=(RADAR, ADSB), chunk_mb=0.1))
    whole = stats.stats_job(stats.StatsOptions(inputs=(RADAR, ADSB), chunk_mb=64.0))
    _assert_tables_equal(small.tables, whole.tables)
    truth = json.loads((ROOT / "fixtures" / "truth.json").read_text())  # the simulator's row counts
    n48, n21 = truth["radar"]["rows"], truth["adsb"]["rows"]
    assert [i["records"] for i in small.inputs] == [{48: n48}, {21: n21}]
    assert small.records == n48 + n21
    assert small.tables["categories"]["records"].tolist() == [n21, n48]
    with pytest.raises(OptionError, match="--chunk-mb"):
        stats.stats_job(stats.StatsOptions(inputs=(RADAR,), chunk_mb=0.0))


def test_category_whose_every_block_is_skipped(tmp_path, capsys):
    """A CAT048 block whose only record is cut short (I048/140 needs 3 bytes, 1 is left) decodes no record:
    stats lists no category and the skipped block, says nothing could be decoded, and never traces back.
    A good block of the same category in another chunk is counted as usual."""
    from msdc.pipeline.cli import main

    bad = block(48, fspec(1, 2) + bytes([25, 201, 0]))
    path = tmp_path / "bad.ast"
    path.write_bytes(bad)
    with pytest.warns(asterix.ContentWarning, match="bad.ast is not ASTERIX"):
        assert len(asterix.read(path).frames[48]) == 0  # the category is there, with no record
    assert main(["stats", str(path)]) == 1
    captured = capsys.readouterr()
    assert "Records per category:\n  none" in captured.out and "Records per SAC/SIC:\n  none" in captured.out
    assert "nothing could be decoded" in captured.err and "Traceback" not in captured.err
    tables = _streamed_any(path)
    assert tables["categories"].empty
    assert tables["skipped"][["blocks", "bytes"]].values.tolist() == [[1, len(bad)]]
    good = _plot(201, 100.0, 0x4840D6, "KLM1")
    path.write_bytes(bad + good)
    tables = _streamed_any(path, chunk=1)
    assert tables["categories"][["category", "records"]].values.tolist() == [[48, 1]]


def _streamed_any(path, chunk: int = 1 << 20) -> dict[str, pd.DataFrame]:
    acc = StatsAccumulator()
    for rec in asterix.iter_read(path, chunk=chunk):
        acc.add(rec.frames, rec.errors, rec.ignored)
    return acc.tables()


def _every_category_stream() -> bytes:
    """Blocks written by hand: CAT048 from radar 25/201 (two blocks), CAT062 system tracks from tracker
    9/1 (one block of two tracks: I062/010, /070 at 100 s and 101 s, /040, /380 ADR 4840D6 on the first),
    a CAT063 sensor status (tracker 9/1 about 25/201, time 99 s), a CAT065 end of batch (9/1, 102 s) and
    two blocks of CAT008, which msdc does not decode (FSPEC 0x80, I008/010 SAC SIC)."""
    track1 = (fspec(1, 4, 11, 12) + bytes([9, 1]) + (100 * 128).to_bytes(3, "big")
              + bytes.fromhex("80" "4840D6") + b"\x00\x05")
    track2 = fspec(1, 4, 12) + bytes([9, 1]) + (101 * 128).to_bytes(3, "big") + b"\x00\x06"
    status63 = fspec(1, 3, 4) + bytes([9, 1]) + (99 * 128).to_bytes(3, "big") + bytes([25, 201])
    batch65 = fspec(1, 2, 4) + bytes([9, 1, 2]) + (102 * 128).to_bytes(3, "big")
    cat008 = block(8, bytes([0x80, 9, 2]))
    return (_plot(201, 98.0, 0x4840D6, "KLM1") + cat008 + block(62, track1, track2) + block(63, status63)
            + cat008 + block(65, batch65) + _plot(201, 103.0, 0x4840D6, "KLM1"))


def test_every_category_listed_per_sac_sic(tmp_path, capsys):
    """stats decodes every category msdc decodes (tracks and status messages per SAC/SIC; addresses and call
    signs only where the category has them) and lists those it does not decode with their blocks."""
    from msdc.pipeline.cli import main

    path = tmp_path / "every.ast"
    path.write_bytes(_every_category_stream())
    result = stats.stats_job(stats.StatsOptions(inputs=(str(path),), date=pd.Timestamp("2019-03-01").date()))
    cats = result.tables["categories"]
    assert cats["category"].tolist() == [8, 48, 62, 63, 65]
    assert cats["decoded"].tolist() == ["no", "yes", "yes", "yes", "yes"]
    assert cats["blocks"].tolist() == [2, 2, 1, 1, 1]
    assert cats["records"].tolist()[1:] == [2, 2, 1, 1] and pd.isna(cats["records"].iloc[0])
    assert cats.set_index("category").loc[62, ["start", "end"]].tolist() == ["2019-03-01 00:01:40",
                                                                            "00:01:41"]
    assert cats["addresses"].tolist()[1:3] == [1, 1] and cats["addresses"].iloc[3:].isna().all()
    src = result.tables["sources"]
    assert src[["category", "sac", "sic", "records"]].values.tolist() == [[48, 25, 201, 2], [62, 9, 1, 2],
                                                                         [63, 9, 1, 1], [65, 9, 1, 1]]
    ac = result.tables["aircraft"]
    assert ac[["category", "address", "records"]].values.tolist() == [[48, "4840D6", 2], [62, "4840D6", 1],
                                                                     [62, "(none)", 1]]
    assert result.inputs[0]["records"] == {48: 2, 62: 2, 63: 1, 65: 1}
    assert main(["stats", str(path)]) == 0
    text = capsys.readouterr().out.split("Records per SAC/SIC")[0]
    row8 = next(line.split() for line in text.splitlines() if line.split()[:1] == ["8"])
    assert row8[:4] == ["8", "no", "2", "-"]
    # with the measurement categories alone (asterix.read's default), the others are listed as not decoded
    rec = asterix.read(path)
    listed = stats_tables(rec.frames, rec.errors, rec.ignored)["categories"].set_index("category")
    assert listed["decoded"].to_dict() == {8: "no", 48: "yes", 62: "no", 63: "no", 65: "no"}
    assert listed.loc[62, "blocks"] == 1
