"""An intact block stranded between two damages less than a block apart decodes (benchmarks/fuzz_reader.py
found 20 CAT021 records lost so on the ADS-B fixture, seeds 77 and 2026), when its own bytes are the
evidence no chain can give: it walks exactly, holds two records or more, and every record names one data
source already met in its category. Streams built by hand from the I048 layout of the spec (FSPEC 0x90:
I048/010 SAC, SIC; I048/040 RHO in 1/256 NM, THETA in 360/2^16 degrees)."""

from __future__ import annotations

import json
import warnings
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest
from reader_fuzz import account, check_chunks

import msdc.asterix as asterix

GAP = bytes(5)  # zeros: no byte of them starts a plausible block header


def block(sac: int, sic: int, plots: list[tuple[int, int]]) -> bytes:
    """A CAT048 block of one record per (raw RHO, raw THETA), each with I048/010 and I048/040."""
    body = b"".join(bytes([0x90, sac, sic]) + rho.to_bytes(2, "big") + theta.to_bytes(2, "big")
                    for rho, theta in plots)
    return bytes([48]) + (3 + len(body)).to_bytes(2, "big") + body


def real(k: int, first: int) -> list[bytes]:
    """k blocks of three plots of radar 1/2, plots numbered from ``first``."""
    return [block(1, 2, [(2560 + 3 * (first + i) + j, 1000 * (first + i) + j) for j in range(3)])
            for i in range(k)]


CUT = bytes([48, 0, 24, 0x90, 1, 2, 10]) + GAP + bytes(6)  # a block header whose body the damage cut short


def stream(stranded: bytes) -> tuple[bytes, int]:
    """Four real blocks, a gap, the stranded block, a cut block and a gap, four real blocks; and where
    the stranded block starts."""
    head = b"".join(real(4, 0)) + GAP
    return head + stranded + CUT + b"".join(real(4, 10)), len(head)


def _read(tmp_path: Path, data: bytes) -> asterix.Recording:
    path = tmp_path / "stream.ast"
    path.write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return asterix.read(path, categories=[48])


def test_a_stranded_block_of_a_met_source_decodes_with_its_values(tmp_path):
    plots = [(0x1234, 0x4000), (0x0A80, 0x8000), (0xFF00, 0xC000)]
    data, at = stream(block(1, 2, plots))
    rec = _read(tmp_path, data)
    got = rec.frames[48].set_index("offset")
    offsets = [at + 3 + 7 * j for j in range(3)]
    assert set(offsets) <= set(got.index), "the stranded block's records are lost"
    rows = got.loc[offsets]
    # RHO 0x1234 / 256 = 18.203125 NM, 0x0A80 / 256 = 10.5, 0xFF00 / 256 = 255.0; THETA a quarter turn each
    assert np.allclose(rows["rho_nm"], [18.203125, 10.5, 255.0])
    assert np.allclose(rows["theta_deg"], [90.0, 180.0, 270.0])
    assert (rows["sac"] == 1).all() and (rows["sic"] == 2).all()
    assert len(rec.frames[48]) == 8 * 3 + 3  # every real block's plots and the stranded one's, no other
    assert account(rec) == len(data)
    cut = at + len(block(1, 2, plots))
    assert rec.errors["offset"].tolist() == [at - len(GAP), cut]  # the gap, and the cut block to the next


@pytest.mark.parametrize("stranded, why", [
    (block(1, 9, [(2560, 0), (2561, 1), (2562, 2)]), "a data source never met in CAT048"),
    (block(1, 2, [(2560, 0)]), "one record: one chance match of a met source is not evidence enough"),
    (block(1, 2, [(2560, 0), (2561, 1)])[:-7] + block(1, 9, [(2561, 1)])[3:], "a record of another source"),
])
def test_a_stranded_block_without_the_evidence_is_left_with_the_damage(tmp_path, stranded, why):
    data, at = stream(stranded[:1] + (len(stranded)).to_bytes(2, "big") + stranded[3:])
    rec = _read(tmp_path, data)
    assert len(rec.frames[48]) == 8 * 3, why
    assert not (set(rec.frames[48]["offset"]) & set(range(at, at + len(stranded)))), why
    assert account(rec) == len(data)
    assert rec.errors["offset"].tolist()[0] == at - len(GAP)


@pytest.mark.parametrize("chunk", [17, 100, 1_000])
def test_a_stranded_block_reads_alike_in_any_chunks(tmp_path, chunk):
    data, _ = stream(block(1, 2, [(0x1234, 0x4000), (0x0A80, 0x8000)]))
    whole = _read(tmp_path, data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert check_chunks(tmp_path / "stream.ast", whole, chunk, categories=[48]) == []


def test_the_first_item_of_every_shipped_edition_is_its_data_source_identifier():
    """The stranded block's evidence reads FRN 1 as SAC/SIC in every category: true of every edition
    msdc ships (each category's item 010, two one-byte elements, first in its UAP, all UAPs of CAT001)."""
    tables = sorted(p for p in files("msdc.asterix.tables").iterdir() if p.name.endswith(".json"))
    assert len(tables) >= 13
    for path in tables:
        table = json.loads(path.read_text())
        uaps = table["uaps"].values() if "uaps" in table else [table["uap"]]
        for uap in uaps:
            first = uap[0]
            assert (first["frn"], first["id"], first["node"]["bits"]) == (1, "010", 16), path.name
            assert [e["name"] for e in first["node"]["items"]] == ["SAC", "SIC"], path.name
