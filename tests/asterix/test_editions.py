"""Each edition walked by its own layout: one hand-built record per structural difference between
consecutive editions in ../shared/specs that changes how many bytes are walked (bytes worked out by hand)."""

from __future__ import annotations

import numpy as np
import pytest
from asterix_bytes import block, decode_bytes

from msdc.asterix import tables as asterix_tables
from msdc.asterix.layout import compile_layout

V2 = ["2.1", "2.2", "2.3", "2.4", "2.5", "2.6", "2.7"]

# CAT021 2.x record: FRN 1 (I021/010), FRN 37 (I021/271), FRN 41 (I021/400 receiver ID).
# FSPEC: FRN 1 -> octet 0 bit 0x80; FRN 37 -> (37-1) = 36 = 5*7 + 1 -> octet 5 bit 0x40;
# FRN 41 -> 40 = 5*7 + 5 -> octet 5 bit 0x04; FX on octets 0-4: 81 01 01 01 01 44.
FSPEC_271_400 = bytes.fromhex("810101010144")


def rec_271(second_octet: int) -> bytes:
    """I021/010 SAC 0 SIC 1, I021/271 (first octet 0x01: all flags 0, FX=1), I021/400 = 1."""
    return FSPEC_271_400 + bytes([0x00, 0x01]) + bytes([0x01, second_octet]) + bytes([0x01])


def test_271_second_octet_has_no_fx_in_2_1():
    # 2.1: second octet = spare(4) + LW(4), no FX. LW = 5 -> 0x05: odd, so its last bit is 1.
    # 2.1 walks 2 bytes of I021/271, then I021/400 = 0x01 -> receiver_id 1.
    data = block(21, rec_271(0x05), rec_271(0x05))
    rec = decode_bytes(data, editions={21: "2.1"})
    assert rec.errors.empty, rec.errors
    assert list(rec.frames[21].receiver_id) == [1, 1]
    # 2.2 and later: second octet = LW(4) + spare(3) + FX. 0x05 has FX = 1, so the item reads on into
    # I021/400's byte 0x01 (FX = 1 again) and the next record: the block does not walk.
    for ed in V2[1:]:
        bad = decode_bytes(data, editions={21: ed})
        assert 21 not in bad.frames or bad.frames[21].empty, ed
        assert len(bad.errors) == 1 and bad.errors.offset.iloc[0] == 0, ed


def test_271_even_second_octet_walks_two_bytes_in_every_2x_edition():
    # 0x50: in 2.1 spare 0101 + LW 0000; in 2.2+ LW 0101, spare 000, FX 0. Two bytes either way.
    for ed in V2:
        rec = decode_bytes(block(21, rec_271(0x50)), editions={21: ed})
        assert rec.errors.empty and list(rec.frames[21].receiver_id) == [1], ed


# 0.23 -> 0.24: I021/130 grows from 2 x 24 bits (180/2^23 deg) to 2 x 32 bits (180/2^25 deg).
# Record: FSPEC FRNs 1, 3, 4, 5 (010, 030, 130, 080) = 1011 1000 = 0xB8; 010 = 00 01;
# 030 = 00 00 80 (128/128 = 1 s); 080 = 3C 66 0C.
POS_023 = bytes.fromhex("B8" "0001" "000080" "200000E00000" "3C660C")  # 0x200000 = 2^21 -> 45 deg
POS_024 = bytes.fromhex("B8" "0001" "000080" "00800000FF800000" "3C660C")  # 2^23 * 180/2^25 = 45 deg


def test_130_six_bytes_in_0_23_eight_bytes_from_0_24():
    r = decode_bytes(block(21, POS_023), editions={21: "0.23"})
    assert r.errors.empty
    row = r.frames[21].iloc[0]
    assert (row.latitude, row.longitude, row.address, row.time_of_day) == (45.0, -45.0, "3C660C", 1.0)
    for ed in ("0.24", "0.25", "0.26"):
        r = decode_bytes(block(21, POS_024), editions={21: ed})
        assert r.errors.empty, ed
        row = r.frames[21].iloc[0]
        assert (row.latitude, row.longitude, row.address) == (45.0, -45.0, "3C660C"), ed
        # 0.23 bytes under 0.24+: I021/130 swallows 8 bytes (20 00 00 E0 00 00 3C 66), leaving one
        # byte (0C) for the 3-byte I021/080: past the end of the block.
        assert len(decode_bytes(block(21, POS_023), editions={21: ed}).errors) == 1, ed
    # 0.24 bytes under 0.23: I021/130 takes 6 bytes, I021/080 = 00 00 3C, then "66 0C" starts a record
    # whose FSPEC 0x66 announces FRNs 2, 3, 6: I021/040 needs 2 bytes, 1 is left -> the block fails.
    assert len(decode_bytes(block(21, POS_024), editions={21: "0.23"}).errors) == 1


def test_0_26_defines_frn_27_and_28():
    # FSPEC FRN 1 and FRN 27: octet 0 = 0x81, octets 1-2 = 0x01, FRN 27 -> 26 = 3*7 + 5 -> octet 3 bit 0x04.
    # I021/070 (0.26): V G L spare + 12-bit code; 7106 octal = 3654 = 0x0E46.
    data = block(21, bytes.fromhex("81010104" "0001" "0E46"))
    r = decode_bytes(data, editions={21: "0.26"})
    assert r.errors.empty and r.frames[21].mode3a.iloc[0] == "7106"
    for ed in ("0.23", "0.24", "0.25"):  # FRN 27 is a spare FRN there
        bad = decode_bytes(data, editions={21: ed})
        assert len(bad.errors) == 1 and "FRN the edition does not define" in bad.errors.reason.iloc[0], ed
    # FRN 28 (0.26 I021/131 signal amplitude, 1 byte): octet 3 bit 0x02; amplitude 0x4D = 77
    data = block(21, bytes.fromhex("81010102" "0001" "4D"))
    assert decode_bytes(data, editions={21: "0.26"}).frames[21].signal_amplitude.iloc[0] == 77
    assert len(decode_bytes(data, editions={21: "0.25"}).errors) == 1


@pytest.mark.parametrize("edition", V2)
def test_040_five_octets_walk_in_every_2x_edition(edition):
    # 2.6 adds I021/040 octets 4-5 (TBC, MBC), all ending with FX: every 2.x edition walks them by FX.
    # FSPEC FRNs 1, 2, 3 = 1110 0000 = 0xE0; 010 = 00 01; 040 = 01 01 01 8B 86 (FX 1,1,1,1,0);
    # I021/161: spare 4 + TRNUM 0xDEB = 3563 -> 0D EB
    data = block(21, bytes.fromhex("E0" "0001" "010101" "8B86" "0DEB"))
    r = decode_bytes(data, editions={21: edition})
    assert r.errors.empty and r.frames[21].track_number.iloc[0] == 3563


@pytest.mark.parametrize("edition", ["1.21", "1.27", "1.28", "1.29", "1.30", "1.31", "1.32"])
def test_048_020_six_octets_walk_in_every_edition(edition):
    # I048/020 grows 2 -> 3 (1.31) -> 6 octets (1.32), every octet ending with FX.
    # FSPEC FRNs 1, 3, 4 = 1011 0000 = 0xB0; 010 = 19 C9 (25/201);
    # 020: A5 (TYP 5, SPI 1, FX) 95 (FX) C1 (FX) 01 01 00; 040: RHO 0xC5AF = 50607/256 NM, THETA F1E0
    data = block(48, bytes.fromhex("B0" "19C9" "A595C1010100" "C5AFF1E0"))
    r = decode_bytes(data, editions={48: edition})
    assert r.errors.empty
    row = r.frames[48].iloc[0]
    assert (row.typ, row.spi, row.rho_nm) == (5, 1, 50607 / 256)


def test_048_1_27_to_1_30_walk_alike():
    # The printed 1.28-1.30 differ from 1.27 only in code-table texts and a title: same kernel arrays.
    ref = compile_layout(48, "1.27")
    for ed in ("1.28", "1.29", "1.30"):
        lay = compile_layout(48, ed)
        for name in ("kind", "size", "ext_sizes", "ext_fx", "sub_parts", "f_bit", "f_bits", "f_signed"):
            assert np.array_equal(getattr(lay, name), getattr(ref, name)), (ed, name)


def test_every_edition_has_its_own_table():
    from msdc.asterix.tables import available, resolve_edition

    tables = available()
    assert tables[21] == ["0.23", "0.24", "0.25", "0.26", *V2]
    assert tables[48] == ["1.27", "1.28", "1.29", "1.30", "1.31", "1.32"]
    assert resolve_edition(21, "2.2") == "2.2" and resolve_edition(48, "1.23") == "1.27"


def test_available_editions_are_in_version_order():
    """available_editions()[20] was ['1.10', '1.11', '1.9'] (text order); CAT020 1.9, 1.10 and 1.11 ship
    (docs/decoding/editions.md), and 1.9 is the oldest."""
    from msdc.asterix import available_editions

    assert available_editions()[20] == ["1.9", "1.10", "1.11"]
    with pytest.raises(ValueError, match=r"tables: 1\.9, 1\.10, 1\.11\)"):
        asterix_tables.resolve_edition(20, "1.8")


# --- editions={21: "auto"} chooses an edition, not a family ------------------------------------------

def plain_2x(i: int) -> bytes:
    """FSPEC FRNs 1, 3 (E0 would add 040; A0 = 1010 0000 = FRNs 1, 3): I021/010 00 01, I021/161 track i."""
    return bytes([0xA0, 0x00, 0x01]) + (i & 0xFFF).to_bytes(2, "big")


def test_auto_picks_2_1_from_a_block_with_odd_lw():
    blocks = [block(21, plain_2x(i), plain_2x(i + 1)) for i in range(0, 40, 2)]
    odd_at = sum(len(b) for b in blocks[:7])
    blocks.insert(7, block(21, rec_271(0x05)))  # walks only under 2.1 (see above)
    rec = decode_bytes(b"".join(blocks), editions={21: "auto"})
    assert rec.editions[21] == "2.1" and rec.errors.empty
    why = rec.edition_choice[21]
    assert "editions walking every sampled block: 2.1;" in why
    assert f"1 blocks told 2.1/2.2/2.3/2.4/2.5/2.6/2.7 apart: offset {odd_at} walks under 2.1)" in why
    assert rec.frames[21].receiver_id.dropna().tolist() == [1]


def test_auto_reports_when_no_edition_walks_every_block():
    # block B: I021/271 = 01 51 50. 2.2+: 0x51 ends with FX=1, 0x50 with FX=0 -> 3 bytes, then 400 = 01.
    # 2.1: 271 = 01 51 (no FX in octet 2), 400 = 0x50, then "01" starts a record whose FSPEC runs out.
    rec_b = FSPEC_271_400 + bytes([0x00, 0x01, 0x01, 0x51, 0x50, 0x01])
    data = block(21, rec_271(0x05)) + block(21, rec_b) + block(21, plain_2x(7))
    rec = decode_bytes(data, editions={21: "auto"})
    assert "no edition walks every sampled block" in rec.edition_choice[21]
    assert len(rec.errors) == 1  # one of the two blocks is reported, never silently misread
