"""Editions chosen for the user (issue #25 item 2, #27 item 5): a category whose editions walk differently
(CAT021) is read with 'auto' unless pinned, the same choice whole or in chunks; stretches of another edition
family laid after a recording are withheld and named with their offsets.

Expected values come from the specifications' layout changes (docs/decoding/editions.md, each with its
hand-built test in test_editions.py), from the block chain hopped here by LEN independently of msdc, and
from the real 0.23 recording pinned (whose values the independent decoders agree on)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED, block, decode_bytes
from budget import examples
from hypothesis import given, settings
from hypothesis import strategies as st

import msdc.asterix as asterix
from msdc.asterix import sampling
from msdc.asterix.families import edition_families, reading_default
from msdc.asterix.reader import _walk_flags
from msdc.asterix.stretches import Stretch, foreign_spans
from msdc.pipeline.cli import main

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures"
REAL_023 = SHARED / "real" / "adsb_v023_160510-lebl-220001.ast"
real = pytest.mark.skipif(not REAL_023.is_file(),
                          reason=f"{REAL_023} not present: real-recording case skipped")
V2 = ("2.1", "2.2", "2.3", "2.4", "2.5", "2.6", "2.7")
V2_WALK = ("2.2", "2.3", "2.4", "2.5", "2.6", "2.7")  # I021/271 octet 2 ends with an FX bit from 2.2 on


def hop(data: bytes) -> list[int]:
    """Block starts of a raw stream, hopped by LEN (CAT, 2-byte big-endian LEN) with no decoder."""
    at, out = 0, []
    while at < len(data):
        out.append(at)
        at += int.from_bytes(data[at + 1:at + 3], "big")
    assert at == len(data)
    return out


def write(tmp_path: Path, name: str, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


# ---------------------------------------------------------------------------------------------------------
# families and the reading default


def test_families_are_the_layout_changes_of_the_specs():
    """CAT021 changes the bytes walked 0.23 -> 0.24 (I021/130 6 -> 8 bytes), 0.25 -> 0.26 (FRN 27, 28
    defined), 0.26 -> 2.1 (a new UAP) and 2.1 -> 2.2 (I021/271 octet 2 gains an FX bit); CAT048 1.27-1.32
    and CAT034 1.27-1.29 only gain FX-walked octets or texts: one family each."""
    assert edition_families(21) == (("0.23",), ("0.24", "0.25"), ("0.26",), ("2.1",), V2_WALK)
    assert edition_families(48) == (("1.27", "1.28", "1.29", "1.30", "1.31", "1.32"),)
    assert edition_families(34) == (("1.27", "1.28", "1.29"),)
    assert (reading_default(21), reading_default(48), reading_default(34)) == ("auto", "1.32", "1.29")


@settings(max_examples=examples(40), deadline=None)
@given(st.data())
def test_editions_of_a_family_walk_every_damaged_block_alike(data):
    """The fixtures' blocks, a few bits flipped each, walk under every edition of a family alike (and
    one family's verdicts are not all another's: the grouping is not too coarse)."""
    adsb, radar = (FIXTURES / "adsb.ast").read_bytes(), (FIXTURES / "radar.ast").read_bytes()
    for cat, raw in ((21, adsb), (48, radar)):
        buf = np.frombuffer(bytearray(raw), np.uint8).copy()
        starts = np.array(hop(raw), np.int64)
        lens = np.array([int.from_bytes(raw[s + 1:s + 3], "big") for s in starts], np.int64)
        for _ in range(data.draw(st.integers(5, 60))):
            j = data.draw(st.integers(0, len(starts) - 1))
            at = int(starts[j]) + data.draw(st.integers(3, int(lens[j]) - 1))
            buf[at] ^= 1 << data.draw(st.integers(0, 7))
        verdicts = {}
        for family in edition_families(cat):
            flags = [_walk_flags(buf, starts, lens, cat, ed) for ed in family]
            assert all(np.array_equal(f, flags[0]) for f in flags), family
            verdicts[family] = flags[0]
        if cat == 21:
            assert not np.array_equal(verdicts[("0.23",)], verdicts[V2_WALK])


def test_auto_on_cat048_reads_as_the_default():
    """editions={48: 'auto'} raised KeyError 'latitude' (the tie-break looked for position columns CAT048
    has not): its editions tie, and auto reads as the default table."""
    path = FIXTURES / "radar.ast"
    rec = asterix.read(path, editions={48: "auto"})
    assert rec.editions == {48: "1.32"} and "newest 1.32" in rec.edition_choice[48]
    pd.testing.assert_frame_equal(rec.frames[48], asterix.read(path).frames[48])


def test_cli_takes_auto_for_any_category(capsys):
    assert main(["stats", str(FIXTURES / "radar.ast"), "--edition", "48=auto"]) == 0
    assert "CAT048 edition auto chose 1.32" in capsys.readouterr().out


# ---------------------------------------------------------------------------------------------------------
# the sample


@pytest.mark.parametrize("window", [8 << 20, 1000, 7])
def test_sample_is_every_block_or_the_first_at_each_spread_offset(monkeypatch, window):
    """A chain of 300 blocks of categories 21 and 48: the sample of CAT021 is all of them when there are
    no more than asked, else the first CAT021 block at or after each offset spread over the stream; the
    chain followed by sample_starts, framed starts given to sample_of, and a plain loop agree, whatever the
    window the chain is walked by (pages are released behind each: the windows must not change the
    sample), and each byte walked is released once, in order."""
    monkeypatch.setattr(sampling, "WINDOW_BYTES", window)
    blocks = [block(21 if i % 3 else 48, bytes([0x80, 0, i % 256])) for i in range(300)]
    data = b"".join(blocks)
    buf = np.frombuffer(data, np.uint8)
    starts = hop(data)
    of21 = np.array([s for s in starts if data[s] == 21], np.int64)
    got, total = sampling.sample_starts(buf, np.array([0]), np.array([len(data)]), 21, 500)
    assert total == 200 and np.array_equal(got, of21)
    got, total = sampling.sample_starts(buf, np.array([0]), np.array([len(data)]), 21, 30)
    targets = np.unique(np.linspace(0, len(data) - 1, 30).astype(np.int64))
    by_hand = sorted({next(s for s in of21 if s >= t) for t in targets if t <= of21[-1]})
    assert total == 200 and got.tolist() == by_hand
    assert sampling.sample_of(of21, 0, len(data), 30).tolist() == by_hand
    released = []
    assert sampling.all_chains_hold(buf, np.array([0]), np.array([len(data)]),
                                    lambda a, b: released.append((a, b)))
    assert released[0][0] == 0 and released[-1][1] == len(data)
    assert all(a[1] == b[0] for a, b in zip(released, released[1:], strict=False))
    # payloads of a container (many small ones, as pcap packets): batched, the same sample as one chain
    cut = [0, *starts[50:300:50], len(data)]
    got, total = sampling.sample_starts(buf, np.array(cut[:-1]), np.array(cut[1:]), 21, 30)
    assert total == 200 and got.tolist() == by_hand
    broken = buf.copy()
    broken[starts[120] + 1:starts[120] + 3] = 0  # a LEN of 0 in the middle: the chain does not hold
    assert not sampling.all_chains_hold(broken, np.array([0]), np.array([len(data)]))
    # at most about max_bytes of blocks: each block is 6 bytes (header, FSPEC, 2 bytes): 10 of the 200 in 60,
    # the 1st, 23rd, 45th, ... (floor of 10 positions spread evenly over 0..199)
    got, total = sampling.sample_starts(buf, np.array([0]), np.array([len(data)]), 21, 500, max_bytes=60)
    assert total == 200 and got.tolist() == of21[[0, 22, 44, 66, 88, 110, 132, 154, 176, 199]].tolist()


@real
@pytest.mark.parametrize("chunk", [150_000, 400_000])
def test_read_and_iter_read_choose_alike(tmp_path, chunk):
    """The edition and the words of its choice are the same whole and in chunks: the sample is taken over
    the whole recording before it is decoded (the first chunk decided alone before)."""
    adsb = (FIXTURES / "adsb.ast").read_bytes()
    for name, data in (("fixture", adsb), ("real", REAL_023.read_bytes()),
                       ("mixed", adsb + REAL_023.read_bytes())):
        path = write(tmp_path, f"{name}.ast", data)
        whole = asterix.read(path) if name != "mixed" else _quiet(path)
        parts = list(asterix.iter_read(path, chunk=chunk))
        assert len(parts) > 1
        assert {p.editions[21] for p in parts if 21 in p.editions} == {whole.editions[21]}, name
        assert all(p.edition_choice == whole.edition_choice for p in parts), name
        assert sum(len(p.frames.get(21, ())) for p in parts) == len(whole.frames[21])


def _quiet(path: Path) -> asterix.Recording:
    with pytest.warns(asterix.EditionWarning):
        return asterix.read(path)


# ---------------------------------------------------------------------------------------------------------
# stretches of another edition family


@pytest.mark.parametrize(("walks", "spans", "used"), [
    # U: walks under the edition used only, F: under the other family only, B: both, N: neither
    ("UUUUFFFF", [(4, 8)], 4),
    ("UUUBFFFBUUU", [(3, 8)], 6),  # blocks walking under both at the edges go with the stretch
    ("UUUFFUUUU", [], 7),  # a run of 2 against (< 3): damage that walks by chance
    ("FFFFUFFFF", [(0, 9)], 0),  # a run of 1 for: set aside, one stretch
    ("FFFNFFUUUNUUFF", [(0, 6)], 5),
    ("FFFFFF", [(0, 6)], 0),
])
def test_stretches_worked_by_hand(walks, spans, used):
    used_flags = np.array([c in "UB" for c in walks])
    other_flags = np.array([c in "FB" for c in walks])
    assert foreign_spans(used_flags, other_flags, 3) == (spans, used)


@real
def test_a_2x_recording_laid_before_a_0_23_one(tmp_path, capsys):
    """fixtures/adsb.ast (2.7, 750 blocks) then the real 0.23 recording: unpinned, auto decodes the 0.23
    part exactly as the real file alone (shifted), the 2.x stretch is withheld and named with its offsets,
    editions and how to decode it; pinned to 2.7, the reverse. Whole, in chunks and from the command line
    alike ('nothing could be decoded' before: the wrong-edition rule withheld every block)."""
    adsb, real_bytes = (FIXTURES / "adsb.ast").read_bytes(), REAL_023.read_bytes()
    path = write(tmp_path, "mixed.ast", adsb + real_bytes)
    n2x = len(hop(adsb))
    with pytest.warns(asterix.EditionWarning, match=f"offsets 0-{len(adsb) - 1} \\({n2x} blocks\\) walk "
                                                    "under 2.1-2.7 and not under 0.23"):
        rec = asterix.read(path)
    alone = asterix.read(REAL_023, editions={21: "0.23"}).frames[21]
    got = rec.frames[21]
    assert rec.editions == {21: "0.23"} and len(got) == len(alone)
    assert (got["offset"].to_numpy() == alone["offset"].to_numpy() + len(adsb)).all()
    for col in ("latitude", "longitude", "time_of_day", "address", "flight_level"):
        pd.testing.assert_series_equal(got[col], alone[col])
    assert rec.edition_stretches == {21: [Stretch(0, len(adsb), n2x, V2, "0.23", True, False)]}
    assert sorted(rec.errors.offset) == hop(adsb) and rec.errors.reason.str.contains("another edition").all()

    with pytest.warns(asterix.EditionWarning, match=f"offsets {len(adsb)}-{len(adsb) + len(real_bytes) - 1}"):
        pinned = asterix.read(path, editions={21: "2.7"})
    fixture = asterix.read(FIXTURES / "adsb.ast").frames[21]
    pd.testing.assert_frame_equal(pinned.frames[21].drop(columns="block"), fixture.drop(columns="block"))
    assert pinned.edition_stretches[21][0].editions == ("0.23",)

    # the stretch told once, joined across chunk boundaries, by every job
    assert main(["stats", str(path), "--chunk-mb", "0.2"]) == 0
    err = capsys.readouterr().err
    assert err.count("walk under 2.1-2.7") == 1
    assert f"offsets 0-{len(adsb) - 1} ({n2x} blocks) walk under 2.1-2.7 and not under 0.23" in err
    assert f"tail -c +1 mixed.ast | head -c {len(adsb)} > part.ast" in err
    out = tmp_path / "m.csv"
    assert main(["decode", str(path), "--chunk-mb", "0.3", "-o", str(out)]) == 0
    assert len(pd.read_csv(out)) == len(alone)


def test_a_damaged_stream_chooses_without_framing_every_family(tmp_path):
    """A raw stream whose chain breaks: the edition is chosen from the blocks before the break and windows
    framed under it (framing the whole stream under every family cost several times the decoding); the
    choice says so and both parts decode."""
    adsb = (FIXTURES / "adsb.ast").read_bytes()
    path = write(tmp_path, "broken.ast", adsb + b"\x15\x00\x07" + adsb)
    rec = asterix.read(path)
    assert rec.editions == {21: "2.7"}
    assert "sampled from the chain before its first break" in rec.edition_choice[21]
    assert len(rec.frames[21]) == 2 * len(asterix.read(FIXTURES / "adsb.ast").frames[21])


def test_pinning_still_overrides():
    data = (FIXTURES / "adsb.ast").read_bytes()[:20_000]
    rec = decode_bytes(data, editions={21: "2.1"})
    assert rec.editions == {21: "2.1"} and not rec.edition_choice
