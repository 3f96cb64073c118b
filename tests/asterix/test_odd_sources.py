"""Records naming another data source than the rest of their data block (damage inside a block that still
walks): counted by the reader, said by decode and stats (failing decode when they are 10 % or more), left
out of the measurements with a warning.

Offsets are worked out here from the bytes written; the damage case compares with the undamaged decode."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, decode_bytes, fspec

import msdc.asterix as asterix
from msdc.asterix.encode import encode_frame
from msdc.asterix.plausible import Implausible, odd_sources
from msdc.pipeline.cli import main
from msdc.pipeline.dataset.inputs import open_inputs
from msdc.pipeline.model.load import load

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"
RECORD_BYTES = 12  # FSPEC 1, I021/010 2, I021/030 3, I021/130 6 (edition 0.23)
BLOCK_RECORDS = 4
BLOCK_BYTES = 3 + BLOCK_RECORDS * RECORD_BYTES


def r021(sac: int, sic: int, tod_s: float) -> bytes:
    """CAT021 0.23 record: FRN 1 (I021/010), 3 (I021/030, 1/128 s), 4 (I021/130: 41.3 N 2.1 E, 180/2^23
    deg)."""
    lat, lon = (round(v / (180 / 2**23)) for v in (41.3, 2.1))
    return (fspec(1, 3, 4) + bytes([sac, sic]) + round(tod_s * 128).to_bytes(3, "big")
            + lat.to_bytes(3, "big") + lon.to_bytes(3, "big"))


def stream(odd: dict[tuple[int, int], tuple[int, int]], blocks: int = 10) -> tuple[bytes, list[int]]:
    """``blocks`` blocks of 4 records of SAC/SIC 0/1, but record (block, index) of ``odd`` naming its own
    source; returns the bytes and the odd records' offsets (block start + 3 + 12 per record before it)."""
    data, offsets = [], []
    for b in range(blocks):
        records = []
        for r in range(BLOCK_RECORDS):
            sac, sic = odd.get((b, r), (0, 1))
            records.append(r021(sac, sic, 30_000.0 + b + r / 10))
            if (b, r) in odd:
                offsets.append(b * BLOCK_BYTES + 3 + r * RECORD_BYTES)
        data.append(block(21, *records))
    assert all(len(d) == BLOCK_BYTES for d in data)
    return b"".join(data), offsets


def test_a_record_unlike_its_blocks_majority_is_odd():
    # block 0: 25/1 25/1 9/9 25/1 -> the third; block 1: 3/3 then 4/4 (a tie: the first met stands) -> the
    # second; block 2: no source beside two of 5/5 -> the first (every category's FRN 1 is its data
    # source); block 3: one record -> none; block 4: no source in any record -> none
    sac = pd.array([25, 25, 9, 25, 3, 4, None, 5, 5, 7, None, None], dtype="Int64")
    sic = pd.array([1, 1, 9, 1, 3, 4, None, 5, 5, 7, None, None], dtype="Int64")
    blocks = np.array([0, 0, 0, 0, 1, 1, 2, 2, 2, 3, 4, 4])
    assert np.flatnonzero(odd_sources(sac, sic, blocks)).tolist() == [2, 5, 6]


def test_a_feed_mixing_sensors_in_its_blocks_is_not_odd():
    # A feed putting several sensors' records in one block names each of them as some block's most common
    # source: 1/1 (blocks 0 and 2), 2/2 (block 1). A made-up 9/9 in block 3 is no block's.
    sac = pd.array([1, 1, 2, 2, 2, 1, 1, 2, 1, 1, 9], dtype="Int64")
    sic = pd.array([1, 1, 2, 2, 2, 1, 1, 2, 1, 1, 9], dtype="Int64")
    blocks = np.array([0, 0, 0, 1, 1, 1, 2, 2, 3, 3, 3])
    assert np.flatnonzero(odd_sources(sac, sic, blocks)).tolist() == [10]


def test_the_encoder_writes_a_block_per_data_source():
    # rows of 1/1, 1/1, 2/1, 2/1, 2/1, 1/1: three blocks of 2, 3 and 1 records (FSPEC, I048/010 and
    # I048/140: 6 bytes a record), each naming one sensor
    frame = pd.DataFrame({"sac": [1, 1, 2, 2, 2, 1], "sic": [1] * 6, "time_of_day": [1.0, 2, 3, 4, 5, 6]})
    data = encode_frame(48, frame)
    assert data[1:3] == (3 + 2 * 6).to_bytes(2, "big") and data[16:18] == (3 + 3 * 6).to_bytes(2, "big")
    assert data[36:39] == bytes([48]) + (3 + 6).to_bytes(2, "big") and len(data) == 45
    rec = decode_bytes(data)
    assert not rec.odd_sources and rec.frames[48].sac.tolist() == [1, 1, 2, 2, 2, 1]


def test_a_record_naming_another_source_is_counted_and_said(tmp_path, capsys):
    data, odd = stream({(3, 2): (7, 9)})  # 1 of 40 records: under 10 %
    path = tmp_path / "odd.ast"
    path.write_bytes(data)
    said = (f"odd.ast: 1 of its 40 CAT021 records name another data source (SAC/SIC) than most records of "
            f"their data block, or none, which no real recording's block does (offsets {odd[0]}): likely "
            "damaged; kept as the bytes say")
    with pytest.warns(asterix.ContentWarning, match=said.replace("(", r"\(").replace(")", r"\)")):
        rec = asterix.read(path, editions={21: "0.23"})
    assert rec.odd_sources == {21: Implausible(1, (odd[0],))}
    out = tmp_path / "o.csv"
    assert main(["decode", str(path), "-o", str(out), "--edition", "21=0.23"]) == 0  # said, not failing
    assert said in capsys.readouterr().err
    written = pd.read_csv(out)
    assert len(written) == 40
    assert written.loc[written.offset == odd[0], ["sac", "sic"]].values.tolist() == [[7, 9]]
    assert main(["stats", str(path), "--edition", "21=0.23"]) == 0
    assert said in capsys.readouterr().err
    dataset = tmp_path / "ds"
    assert main(["ingest", "--dataset", str(dataset), str(path), "--edition", "21=0.23", "--date",
                 "2019-03-01"]) == 0
    assert said in capsys.readouterr().err
    # a dataset's read puts an input's records back in file order, its block numbers with them
    loaded = load([], dataset=open_inputs(dataset))
    assert len(loaded.frames[21]) == 38 and any("left out of the measurements" in w for w in loaded.warnings)


def test_many_records_naming_other_sources_fail_decode(tmp_path, capsys):
    data, odd = stream({(0, 1): (7, 9), (2, 3): (7, 9), (5, 0): (8, 1), (9, 2): (7, 9)})  # 4 of 40: 10 %
    path = tmp_path / "odd.ast"
    path.write_bytes(data)
    out = tmp_path / "o.csv"
    assert main(["decode", str(path), "-o", str(out), "--edition", "21=0.23"]) == 1
    err = capsys.readouterr().err
    assert (f"odd.ast: 4 of its 40 CAT021 records (10%) name another data source (SAC/SIC) than most records "
            "of their data block, or none, which no real recording's block does (offsets "
            f"{', '.join(map(str, odd))}): bytes that are not what they are read as") in err
    assert not out.exists()


def test_the_measurements_leave_them_out_with_the_rest_of_their_block(tmp_path):
    data, odd = stream({(3, 2): (7, 9)})  # block 3's records 2 and 3 left out: 38 of 40 kept
    path = tmp_path / "odd.ast"
    path.write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", asterix.ContentWarning)
        loaded = load([path], editions={21: "0.23"})
    frame = loaded.frames[21]
    assert len(frame) == 38
    assert not {odd[0], odd[0] + RECORD_BYTES} & set(frame["offset"])
    assert set(zip(frame.sac, frame.sic, strict=True)) == {(0, 1)}
    assert ("odd.ast: 2 CAT021 record(s) name another data source than most records of their data block, or "
            f"none, or follow such a record in it (first at offset {odd[0]}: SAC/SIC 7/9): damaged data, "
            "left out of the measurements") in loaded.warnings


def test_damage_that_still_walks_is_caught_by_its_made_up_sources():
    """Bytes overwritten inside a block of the bundled ADS-B fixture (20 records a block): where the block
    still walks to its end into another number of records than it holds, the records made of the bytes
    after the damage name made-up data sources."""
    data = (FIXTURES / "adsb.ast").read_bytes()
    starts, q = [], 0
    while q < len(data):
        starts.append(q)
        q += int.from_bytes(data[q + 1:q + 3], "big")
    rng = np.random.default_rng(7)
    walked = by_source = 0
    for _ in range(150):
        q = starts[rng.integers(len(starts))]
        n = int.from_bytes(data[q + 1:q + 3], "big")
        blk = bytearray(data[q:q + n])
        k = int(rng.integers(4, 33))
        at = 3 + int(rng.integers(n - 3 - k))
        blk[at:at + k] = rng.integers(0, 256, k, dtype=np.uint8).tobytes()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", asterix.ContentWarning)
            good = decode_bytes(data[q:q + n])
            bad = decode_bytes(bytes(blk), editions=dict(good.editions))
        if len(bad.errors) or len(bad.frames[21]) == len(good.frames[21]):
            continue  # refused, or the same records with other values (no check can tell)
        walked += 1
        said = [bad.odd_sources.get(21, Implausible(0, ())), bad.implausible.get(21, Implausible(0, ()))]
        assert sum(odd.records for odd in said) >= 1
        by_source += said[0].records >= 1
    assert walked >= 5  # damage that walks into other records was met (about 1 in 10 such overwrites)
    assert by_source == walked  # the data source alone tells every one (14 of 14 with this seed)


def test_sound_recordings_have_none():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("radar.ast", "adsb.ast"):
            assert not asterix.read(FIXTURES / name).odd_sources
