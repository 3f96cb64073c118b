"""msdc decode's outputs: one file per category whenever records of several categories decode (a broken
block chain included), nothing left behind by a failed or interrupted run, the ``block`` index whatever
the chunk size, and the message for a data block cut short by the end of the data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.jobs import stats

FIX = Path(__file__).resolve().parents[3] / "fixtures"
RADAR, ADSB = FIX / "radar.ast", FIX / "adsb.ast"
REAL = SHARED / "real"


def chain(data: bytes) -> list[tuple[int, int, int]]:
    """(offset, category, LEN) of each data block, by following the LEN bytes from the first byte until a
    header is incomplete or a LEN runs past the end (written from the ASTERIX rules, not the decoder's)."""
    out, q = [], 0
    while q + 3 <= len(data):
        n = int.from_bytes(data[q + 1:q + 3], "big")
        if n < 3 or q + n > len(data):
            break
        out.append((q, data[q], n))
        q += n
    return out


def radar_frame(n: int = 40) -> pd.DataFrame:
    """CAT048 plots of radar 25/201, 4 s apart, one address each (times exact in 1/128 s)."""
    return pd.DataFrame({"sac": 25, "sic": 201, "time_of_day": 28800.0 + 4.0 * np.arange(n),
                         "address": [f"{0x750000 + i:06X}" for i in range(n)]})


def adsb_frame(n: int = 30) -> pd.DataFrame:
    """CAT021 2.7 reports of ground station 0/107, 1 s apart."""
    return pd.DataFrame({"sac": 0, "sic": 107, "time_of_day": 28800.5 + np.arange(n),
                         "latitude": 2.5 + 0.001 * np.arange(n), "longitude": np.full(n, 101.7),
                         "address": [f"{0x880000 + i:06X}" for i in range(n)]})


def broken_then_adsb() -> tuple[bytes, int, int]:
    """40 CAT048 records (5 a block) cut 4 bytes into their 7th block, then 30 CAT021 records (6 a block)
    and 5 zero bytes of padding: the CAT048 chain breaks where the ADS-B stream starts, and the ADS-B
    chain does not reach the end (framing without walking records finds no CAT021 block: the pre-scan
    that decided on one output file did not). Returns the bytes, the CAT048 records in complete blocks
    (6 x 5) and the CAT021 records."""
    radar = encode_frame(48, radar_frame(), records_per_block=5)
    blocks = chain(radar)
    assert [c for _, c, _ in blocks] == [48] * 8
    cut = blocks[6][0] + 4
    return radar[:cut] + encode_frame(21, adsb_frame(), records_per_block=6) + bytes(5), 30, 30


def _files(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir())


# ---------------------------------------------------------------------------------------------------------
# 1. one file per category, decided from what decodes


@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_a_broken_chain_with_two_categories_writes_one_file_each(tmp_path, capsys, suffix):
    data, n48, n21 = broken_then_adsb()
    path = tmp_path / "m1.ast"
    path.write_bytes(data)
    out = tmp_path / f"m1{suffix}"
    assert main(["decode", str(path), "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert _files(tmp_path) == sorted(["m1.ast", f"m1_cat021{suffix}", f"m1_cat048{suffix}"])
    assert f"CAT021: {n21} records -> {tmp_path / f'm1_cat021{suffix}'}" in captured.out
    assert f"CAT048: {n48} records -> {tmp_path / f'm1_cat048{suffix}'}" in captured.out
    assert f"several categories: writing {tmp_path / f'm1_cat048{suffix}'}" in captured.err
    read = pd.read_csv if suffix == ".csv" else pd.read_parquet
    radar, adsb = read(tmp_path / f"m1_cat048{suffix}"), read(tmp_path / f"m1_cat021{suffix}")
    assert radar["time_of_day"].tolist() == radar_frame()["time_of_day"][:n48].tolist()
    assert radar["address"].astype(str).tolist() == radar_frame()["address"][:n48].tolist()
    assert adsb["time_of_day"].tolist() == adsb_frame()["time_of_day"].tolist()
    assert adsb["address"].astype(str).tolist() == adsb_frame()["address"].tolist()
    # the ADS-B stream starts 4 bytes after the last complete CAT048 block
    start = chain(data)[5][0] + chain(data)[5][2] + 4
    assert adsb["offset"].min() > start and radar["offset"].max() < start


def test_one_category_decoding_writes_the_output_itself(tmp_path, capsys):
    data, n48, _ = broken_then_adsb()
    path = tmp_path / "m1.ast"
    path.write_bytes(data)
    # the ADS-B blocks after the break are not walked (not decoded): skipped, most of the file, so
    # decode fails unless told to write what decodes
    assert main(["decode", str(path), "--category", "48", "-o", str(tmp_path / "r.csv")]) == 1
    assert "most of it is not ASTERIX" in capsys.readouterr().err and _files(tmp_path) == ["m1.ast"]
    assert main(["decode", str(path), "--category", "48", "-o", str(tmp_path / "r.csv"), "--lenient"]) == 0
    assert _files(tmp_path) == ["m1.ast", "r.csv"]
    assert len(pd.read_csv(tmp_path / "r.csv")) == n48
    assert "several categories" not in capsys.readouterr().err


# ---------------------------------------------------------------------------------------------------------
# 2. a failed or interrupted run writes nothing


def test_strict_failure_in_a_later_chunk_writes_nothing(tmp_path, capsys):
    """The radar fixture (101 kB) cut inside its last block: with 0.1 MB chunks the first chunk decodes
    and is written before strict mode meets the cut block."""
    data = RADAR.read_bytes()
    last = chain(data)[-1]
    assert last[0] + last[2] == len(data) and last[0] > 100_000  # the cut block is past the first chunk
    path = tmp_path / "cut.ast"
    path.write_bytes(data[:last[0] + 5])
    out = tmp_path / "strict.csv"
    out.write_text("an earlier run's output\n")
    assert main(["decode", str(path), "--strict", "--chunk-mb", "0.1", "-o", str(out)]) == 1
    assert f"offset {last[0]}" in capsys.readouterr().err
    assert _files(tmp_path) == ["cut.ast", "strict.csv"]
    assert out.read_text() == "an earlier run's output\n"  # kept as it was


def test_a_category_output_that_is_a_directory_is_refused_before_decoding(tmp_path, capsys, monkeypatch):
    def decoded(*args, **kwargs):
        raise AssertionError("decoded before the outputs were checked")

    monkeypatch.setattr(asterix, "iter_read", decoded)
    (tmp_path / "o_cat048.csv").mkdir()
    status = main(["decode", str(RADAR), str(ADSB), "-o", str(tmp_path / "o.csv")])
    err = capsys.readouterr().err
    assert status == 2
    o, each = tmp_path / "o.csv", tmp_path / "o_cat048.csv"
    assert err.strip() == f"msdc decode: -o {o}: its CAT048 file {each} is a directory"
    assert _files(tmp_path) == ["o_cat048.csv"]
    # one category asked for: only o.csv can be written, and the run goes on
    monkeypatch.undo()
    assert main(["decode", str(RADAR), "--category", "48", "-o", str(tmp_path / "o.csv")]) == 0
    assert _files(tmp_path) == ["o.csv", "o_cat048.csv"]


def _ctrl_c_in_numba():
    """What numba raises when Ctrl-C lands while it loads a cached kernel: a SystemError during the
    handling of the KeyboardInterrupt."""
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt:
        raise SystemError("<built-in function ...> returned a result with an exception set")  # noqa: B904


@pytest.mark.parametrize("failure", [KeyboardInterrupt, OSError, SystemError])
def test_an_interrupted_or_failing_run_leaves_no_file(tmp_path, capsys, monkeypatch, failure):
    """The second input's first chunk is interrupted (Ctrl-C, also as numba's SystemError, or a write that
    fails): the first input's records were already written to their temporary file, which goes too."""
    real = asterix.iter_read

    def iter_read(path, **kw):
        if Path(path) == ADSB:
            if failure is SystemError:
                _ctrl_c_in_numba()
            raise failure(28, "No space left on device") if failure is OSError else failure()
        yield from real(path, **kw)

    monkeypatch.setattr(asterix, "iter_read", iter_read)
    status = main(["decode", str(RADAR), str(ADSB), "-o", str(tmp_path / "o.parquet")])
    assert status == (1 if failure is OSError else 130)
    assert "Traceback" not in capsys.readouterr().err
    assert _files(tmp_path) == []


# ---------------------------------------------------------------------------------------------------------
# 3. the block index in the file, whatever the chunk size


def interleaved() -> tuple[bytes, pd.DataFrame, pd.DataFrame]:
    """20 CAT048 blocks of 3 records, each followed by a CAT021 block of 2 records: block 2k is CAT048,
    2k+1 CAT021, so CAT048 record i is in block 2 (i // 3) and CAT021 record j in block 2 (j // 2) + 1."""
    radar, adsb = radar_frame(60), adsb_frame(40)
    parts = [encode_frame(48, radar.iloc[3 * k:3 * k + 3], records_per_block=3)
             + encode_frame(21, adsb.iloc[2 * k:2 * k + 2], records_per_block=2) for k in range(20)]
    return b"".join(parts), radar, adsb


def test_block_is_the_index_in_the_file_for_any_chunk(tmp_path):
    data, radar, adsb = interleaved()
    path = tmp_path / "mixed.ast"
    path.write_bytes(data)
    blocks = chain(data)
    assert [c for _, c, _ in blocks] == [48, 21] * 20
    whole = asterix.read(path)
    for chunk in (1, 150, 1000, len(data)):
        parts = list(asterix.iter_read(path, chunk=chunk))
        assert (len(parts) > 1) == (chunk < len(data))
        for cat, expected in ((48, 2 * (np.arange(60) // 3)), (21, 2 * (np.arange(40) // 2) + 1)):
            got = pd.concat([p.frames[cat] for p in parts if cat in p.frames], ignore_index=True)
            assert got["block"].tolist() == expected.tolist(), chunk
            # each record lies in its block: the block's offset + 3 <= record offset < the block's end
            starts = np.array([blocks[b][0] for b in expected])
            ends = starts + np.array([blocks[b][2] for b in expected])
            assert ((starts + 3 <= got["offset"]) & (got["offset"] < ends)).all()
            pd.testing.assert_series_equal(got["block"], whole.frames[cat]["block"])


def test_decode_output_is_the_same_for_any_chunk_size(tmp_path):
    """The ADS-B fixture (632 kB) in 0.1 MB chunks and in one: every column equal, offset and block too."""
    small, one = tmp_path / "small.parquet", tmp_path / "one.parquet"
    assert main(["decode", str(ADSB), "--chunk-mb", "0.1", "-o", str(small)]) == 0
    assert main(["decode", str(ADSB), "-o", str(one)]) == 0
    a, b = pd.read_parquet(small), pd.read_parquet(one)
    for frame in (a, b):  # categoricals: each chunk has its own dictionary; compare the values
        for c in frame.columns:
            if isinstance(frame[c].dtype, pd.CategoricalDtype):
                frame[c] = frame[c].astype(object)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    blocks = chain(ADSB.read_bytes())
    assert a["block"].max() == len(blocks) - 1 and a["block"].is_monotonic_increasing
    starts = np.array([o for o, _, _ in blocks])
    assert (np.searchsorted(starts, a["offset"].to_numpy(), side="right") - 1 == a["block"]).all()


# ---------------------------------------------------------------------------------------------------------
# 5. a data block cut short by the end of the data


def test_a_truncated_final_block_says_how_far_it_runs_past_the_end(tmp_path, capsys):
    data = ADSB.read_bytes()
    blocks = chain(data)
    offset, _, n = blocks[100]
    path = tmp_path / "cut.ast"
    path.write_bytes(data[:offset + 7])  # the header and 4 bytes of block 100
    whole = asterix.read(ADSB)
    rec = asterix.read(path)
    reason = f"data block runs past the end of the data (LEN {n}, {n - 7} bytes past the end)"
    assert rec.errors[["offset", "length", "reason"]].values.tolist() == [[offset, 7, reason]]
    # decoded and accounted as before: the records of the 100 complete blocks, every byte accounted
    kept = whole.frames[21][whole.frames[21]["offset"] < offset]
    assert rec.frames[21]["offset"].tolist() == kept["offset"].tolist()
    assert rec.decoded_bytes == offset and rec.decoded_bytes + 7 == rec.size_bytes
    assert main(["decode", str(path)]) == 0
    assert f"msdc decode: {path}: offset {offset}: {reason}" in capsys.readouterr().err


def test_a_len_below_3_is_named_with_its_value(tmp_path):
    data = RADAR.read_bytes()
    bad = bytes([48, 0, 2])
    path = tmp_path / "low.ast"
    path.write_bytes(data + bad + data[:chain(data)[0][2]])  # LEN 2, then one good block
    rec = asterix.read(path)
    assert rec.errors[["offset", "reason"]].values.tolist() == [[len(data), "data block LEN below 3 (LEN 2)"]]


@pytest.mark.skipif(not REAL.is_dir(), reason=f"{REAL} not present: the real-recording case is skipped")
def test_the_real_adsb_recording_cut_short(tmp_path):
    data = (REAL / "adsb_v023_160510-lebl-220001.ast").read_bytes()[:700_001]
    last = chain(data)[-1]
    offset = last[0] + last[2]  # the first block that does not fit
    n = int.from_bytes(data[offset + 1:offset + 3], "big")
    assert (offset, n) == (699_997, 40)  # from the bytes: 700,001 - 699,997 = 4 of its 40 bytes are there
    path = tmp_path / "atrunc.ast"
    path.write_bytes(data)
    rec = asterix.read(path, editions={21: "0.23"})
    assert rec.errors["reason"].tolist() == [
        "data block runs past the end of the data (LEN 40, 36 bytes past the end)"]


# ---------------------------------------------------------------------------------------------------------
# 4. stats: skipped blocks by reason, with the file


def test_stats_names_the_file_of_each_skipped_block(tmp_path, capsys):
    """Two truncated copies of the radar fixture and one of the ADS-B fixture: the CAT048 reason has two
    rows, one per file (in input order), listed before the CAT021 reason's one row (fewer blocks)."""
    r, a = RADAR.read_bytes(), ADSB.read_bytes()
    (r50, _, _), (r30, _, _), (a200, _, _) = chain(r)[50], chain(r)[30], chain(a)[200]
    (tmp_path / "r_late.ast").write_bytes(r[:r50 + 10])
    (tmp_path / "r_early.ast").write_bytes(r[:r30 + 5])
    (tmp_path / "a_cut.ast").write_bytes(a[:a200 + 20])
    names = ["a_cut.ast", "r_late.ast", "r_early.ast"]
    result = stats.stats_job(stats.StatsOptions(inputs=tuple(str(tmp_path / n) for n in names)))
    reason = "data block runs past the end of the data"
    assert result.tables["skipped"].astype(object).values.tolist() == [
        ["r_late.ast", 48, reason, 1, 10, r50], ["r_early.ast", 48, reason, 1, 5, r30],
        ["a_cut.ast", 21, reason, 1, 20, a200]]
    assert main(["stats", *(str(tmp_path / n) for n in names)]) == 0
    out = capsys.readouterr().out
    table = out[out.index("Skipped blocks by reason"):out.index("Blocks of categories not decoded")]
    lines = table.strip().splitlines()
    assert lines[1].split()[:3] == ["file", "category", "reason"]
    assert [line.split()[:2] for line in lines[2:]] == [["r_late.ast", "48"], ["r_early.ast", "48"],
                                                         ["a_cut.ast", "21"]]
    # a name two inputs share is shown as the path given
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "r_late.ast").write_bytes(r[:r30 + 5])
    both = (str(tmp_path / "r_late.ast"), str(tmp_path / "b" / "r_late.ast"))
    skipped = stats.stats_job(stats.StatsOptions(inputs=both)).tables["skipped"]
    assert skipped[["file", "first_offset"]].values.tolist() == [[both[0], r50], [both[1], r30]]


def test_an_error_that_is_no_interrupt_still_surfaces(monkeypatch):
    """Only an exception raised while a KeyboardInterrupt was being handled counts as Ctrl-C: a plain
    SystemError is a defect and must not be hidden as exit 130."""
    def iter_read(path, **kw):
        raise SystemError("a defect")
        yield

    monkeypatch.setattr(asterix, "iter_read", iter_read)
    with pytest.raises(SystemError, match="a defect"):
        main(["decode", str(RADAR)])


def _same_name_inputs(tmp_path: Path) -> tuple[Path, Path]:
    """Two different CAT048 recordings both named x.ast, in folders a/ and b/: the fixture's 3266 plots,
    and its first 10 plots written again."""
    a, b = tmp_path / "a" / "x.ast", tmp_path / "b" / "x.ast"
    a.parent.mkdir()
    b.parent.mkdir()
    a.write_bytes(RADAR.read_bytes())
    b.write_bytes(encode_frame(48, asterix.read(RADAR).frames[48].head(10)))
    return a, b


def test_file_column_names_the_path_when_two_inputs_share_a_name(tmp_path):
    """The `file` column held the base name only, so (file, offset) named two records; stats already
    shows a shared name by its path, and the `file` column follows that rule."""
    from msdc.pipeline.model.load import load_measurements
    from msdc.pipeline.model.sensors import read_sensors
    from msdc.pipeline.model.sources import file_labels

    assert file_labels(["a/x.ast", "b/x.ast", "c/y.ast"]) == ["a/x.ast", "b/x.ast", "y.ast"]
    a, b = _same_name_inputs(tmp_path)
    out = tmp_path / "d.csv"
    assert main(["decode", str(a), str(b), "-o", str(out)]) == 0
    decoded = pd.read_csv(out, usecols=["file", "offset"])
    assert decoded["file"].value_counts().to_dict() == {str(a): 3266, str(b): 10}
    assert not decoded.duplicated().any()
    _, meas = load_measurements([a, b], read_sensors(FIX / "sensors.toml"), either=True)
    files = meas["file"].astype(str)
    assert set(files) == {str(a), str(b)} and (files == str(b)).sum() == 10
    assert not meas[["file", "offset"]].duplicated().any()
    # a name no other input shares stays the bare name
    _, meas = load_measurements([a, ADSB], read_sensors(FIX / "sensors.toml"))
    assert set(meas["file"].astype(str)) == {"x.ast", "adsb.ast"}


def test_category_picks_any_decodable_category(tmp_path, capsys):
    """--category takes every category msdc decodes (it offered only the measurement categories): north
    markers (CAT034) and sensor status (CAT063) beside the radar, each written to its own file with the
    values encoded; without --category only the measurement categories are decoded."""
    north = pd.DataFrame({"sac": 25, "sic": 201, "message_type": 1, "time_of_day": [28800.0, 28804.75]})
    status = pd.DataFrame({"sac": 25, "sic": 100, "time_of_day": [28801.5], "sensor_sac": 25,
                           "sensor_sic": 201})
    path = tmp_path / "mixed.ast"
    path.write_bytes(RADAR.read_bytes() + encode_frame(34, north) + encode_frame(63, status))
    out = tmp_path / "o.csv"
    assert main(["decode", str(path), "--category", "34", "--category", "63", "-o", str(out)]) == 0
    cat034 = pd.read_csv(tmp_path / "o_cat034.csv")
    cat063 = pd.read_csv(tmp_path / "o_cat063.csv")
    assert cat034.time_of_day.tolist() == [28800.0, 28804.75] and set(cat034.message_type) == {1}
    assert (cat063.sensor_sac.tolist(), cat063.sensor_sic.tolist()) == ([25], [201])
    assert not (tmp_path / "o_cat048.csv").exists()
    capsys.readouterr()
    assert main(["decode", str(path), "-o", str(tmp_path / "d.csv")]) == 0
    assert "CAT034" not in capsys.readouterr().out and (tmp_path / "d.csv").exists()
