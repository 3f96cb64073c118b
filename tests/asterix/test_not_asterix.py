"""What-is-this-file (issue #25 item 3, #27 item 4): a file that is not ASTERIX is said to be so, with what
was found where; most bytes skipped, or records with values no real report carries, are warned of with the
share and the offsets by every command, and decode fails unless --lenient.

Expected shares and offsets are worked out here from the bytes written (block by block, by hand)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import block, fspec

import msdc.asterix as asterix
from msdc.asterix.verdict import sniff
from msdc.pipeline.cli import main

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"
README = Path(__file__).resolve().parents[2] / "README.md"


def write(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


def random_bytes(n: int, seed: int = 25) -> bytes:
    return np.random.default_rng(seed).integers(0, 256, n, dtype=np.uint8).tobytes()


def test_random_bytes_are_not_asterix(tmp_path, capsys):
    """1 MB of random bytes decoded to a hundred CAT021 'records' (latitude 99, longitude 196), exit 0.
    Now: not ASTERIX, said at once with the share and offsets; decode writes nothing (exit 1), nor with
    --lenient, for none of it decodes: a chance block that walks is evidence only when every record names
    one data source (I0xx/010, mandatory in every category); stats says it and decodes nothing from it."""
    path = write(tmp_path, "random.bin", random_bytes(1_000_000))
    with pytest.warns(asterix.ContentWarning, match="random.bin is not ASTERIX: read as raw, 100% of its "
                                                    "1000000 bytes frame into no data block that decodes"):
        rec = asterix.read(path)
    assert rec.frames == {}
    out = tmp_path / "r.csv"
    assert main(["decode", str(path), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "random.bin is not ASTERIX" in err and "nothing written" in err and not out.exists()
    assert main(["decode", str(path), "-o", str(out), "--lenient"]) == 1
    err = capsys.readouterr().err
    assert "warning: random.bin is not ASTERIX" in err and "nothing could be decoded" in err
    assert list(tmp_path.glob("r*.csv")) == []
    assert main(["stats", str(path)]) == 1
    assert "warning: random.bin is not ASTERIX" in capsys.readouterr().err


def test_a_text_file_is_not_asterix_and_says_what_its_bytes_are(tmp_path, capsys):
    """'msdc decode README.md' said it 'holds CAT035, CAT101, CAT104'. Its first byte '#' (0x23 = 35) and
    the next two (the LEN a header would have) are named, and that it is text."""
    data = README.read_bytes()
    assert main(["decode", str(README), "-o", str(tmp_path / "x.csv")]) == 1
    err = capsys.readouterr().err
    assert "README.md is not ASTERIX: read as raw, 100% of its" in err
    assert f"it starts with bytes {data[:8].hex(' ')}" in err and ": text)" in err
    assert f"category {data[0]} with LEN {int.from_bytes(data[1:3], 'big')}" in err
    assert "CAT035" not in err and list(tmp_path.iterdir()) == []


def test_sniff_judges_a_large_file_by_its_head_middle_and_tail(tmp_path):
    """A 3.5 MB file of random bytes is said to be not ASTERIX from 3 windows of 1 MB (at once: the rest is
    not decoded); the radar fixture laid between two 1.2 MB runs of random bytes is ASTERIX in its middle."""
    path = write(tmp_path, "big.bin", random_bytes(3_500_000))
    said = sniff(path)
    assert said.startswith("big.bin is not ASTERIX: read as raw, of ")
    assert "read at its start, middle and end" in said
    radar = (FIXTURES / "radar.ast").read_bytes() * 12  # 1.2 MB
    middle = random_bytes(1_200_000) + radar + random_bytes(1_200_000, 7)
    assert sniff(write(tmp_path, "mid.bin", middle)) is None
    assert sniff(FIXTURES / "radar.ast") is None and sniff(FIXTURES / "adsb.ast") is None


def test_most_bytes_skipped_warn_with_the_share_and_offsets(tmp_path, capsys):
    """The radar fixture (101,446 bytes) after 150,000 bytes that are no blocks (0x00: no category 0): 60 %
    skipped, at offset 0; every radar record still decodes. decode fails unless --lenient; 50,000 such
    bytes (33 %) are only listed as skipped."""
    radar = (FIXTURES / "radar.ast").read_bytes()
    path = write(tmp_path, "zeros.ast", bytes(150_000) + radar)
    share = 150_000 / (150_000 + len(radar))
    with pytest.warns(asterix.ContentWarning) as caught:
        rec = asterix.read(path)
    assert len(rec.frames[48]) == len(asterix.read(FIXTURES / "radar.ast").frames[48])
    assert [str(w.message) for w in caught] == [
        f"zeros.ast: {share:.0%} of its {150_000 + len(radar)} bytes did not decode (150000 bytes skipped in "
        "1 run, at offset 0): most of it is not ASTERIX"]
    assert main(["decode", str(path), "-o", str(tmp_path / "z.csv")]) == 1
    assert "most of it is not ASTERIX; nothing written" in capsys.readouterr().err
    assert main(["decode", str(path), "-o", str(tmp_path / "z.csv"), "--lenient"]) == 0
    fewer = write(tmp_path, "fewer.ast", bytes(50_000) + radar)
    with warnings.catch_warnings():
        warnings.simplefilter("error", asterix.ContentWarning)
        assert len(asterix.read(fewer).errors) == 1


def r021_023(lat_deg: float, tod_s: float) -> bytes:
    """CAT021 0.23 record: FRN 1 (I021/010 0/1), 3 (I021/030, 1/128 s), 4 (I021/130: 2 x 24 bits at
    180/2^23 deg)."""
    lat = round(lat_deg / (180 / 2**23)) & 0xFFFFFF
    lon = round(2.0 / (180 / 2**23))
    return fspec(1, 3, 4) + bytes([0, 1]) + round(tod_s * 128).to_bytes(3, "big") + lat.to_bytes(3, "big") \
        + lon.to_bytes(3, "big")


def implausible_stream() -> tuple[bytes, list[int]]:
    """40 one-record 0.23 blocks (15 bytes each: header 3, FSPEC 1, 010 2, 030 3, 130 6); blocks 5, 12 and 30
    carry latitude 99 deg, block 20 a time of day of 25 h: 4 of 40 records (10 %). Returns the bytes and
    those records' offsets (block + 3)."""
    blocks, odd = [], []
    for i in range(40):
        lat, tod = (99.0 if i in (5, 12, 30) else 41.3), (90_000.0 if i == 20 else 30_000.0 + i)
        if i in (5, 12, 20, 30):
            odd.append(15 * i + 3)
        blocks.append(block(21, r021_023(lat, tod)))
    assert all(len(b) == 15 for b in blocks)
    return b"".join(blocks), odd


@pytest.mark.parametrize("command", ["stats", "decode", "track"])
def test_implausible_records_are_said_by_every_command(tmp_path, capsys, command):
    data, odd = implausible_stream()
    path = write(tmp_path, "odd.ast", data)
    said = (f"odd.ast: 4 of its 40 CAT021 records (10%) hold a position off the Earth or a time of day "
            f"outside 0-24 h, which no real report does (offsets {', '.join(map(str, odd))})")
    with pytest.warns(asterix.ContentWarning, match=said.replace("(", r"\(").replace(")", r"\)")):
        rec = asterix.read(path, editions={21: "0.23"})
    assert sorted(rec.implausible[21].offsets) == odd
    argv = {"stats": ["stats", str(path)], "decode": ["decode", str(path), "-o", str(tmp_path / "o.csv")],
            "track": ["track", str(path), "--all", "-o", str(tmp_path / "t.parquet")]}[command]
    status = main([*argv, "--edition", "21=0.23"])
    err = capsys.readouterr().err
    assert said in err
    assert status == (1 if command == "decode" else status)  # decode fails; the others warn and go on
    if command == "decode":
        assert not (tmp_path / "o.csv").exists()
        assert main([*argv, "--edition", "21=0.23", "--lenient"]) == 0
        assert len(pd.read_csv(tmp_path / "o.csv")) == 40


def test_sound_recordings_say_nothing():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("radar.ast", "adsb.ast"):
            rec = asterix.read(FIXTURES / name)
            assert not rec.implausible and rec.oversized_bytes == 0


def test_gzip_input_is_said_to_be_compressed(tmp_path, capsys):
    """A gzip-compressed recording was 'not ASTERIX ... starts with bytes 1f 8b' with --lenient suggested,
    which cannot help: it is said to be gzip-compressed, to decompress first, and --lenient is not offered."""
    import gzip

    path = write(tmp_path, "radar.ast.gz", gzip.compress((FIXTURES / "radar.ast").read_bytes()))
    out = tmp_path / "r.csv"
    assert main(["decode", str(path), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "radar.ast.gz is not ASTERIX but gzip-compressed: decompress it first (gunzip)" in err
    assert "--lenient" not in err and not out.exists()
    with pytest.warns(asterix.ContentWarning, match="gzip-compressed: decompress it first"):
        asterix.read(path)
