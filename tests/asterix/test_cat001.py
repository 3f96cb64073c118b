"""CAT001 monoradar plots and tracks: records written by hand from the 1.2-1.4 layouts, values worked by hand.

The record's I001/020 TYP chooses its UAP. Plot UAP: FRN 1 I001/010, 2 I001/020, 3 I001/040, 4 I001/070,
5 I001/090, 6 I001/130, 7 I001/141, 8 I001/050, 9 I001/120, 10 I001/131, 11 I001/080, 12 I001/100,
13 I001/060, 14 I001/030, 15 I001/150, 16-19 spare, 20 SP, 21 RFS. Track UAP: 1 I001/010, 2 I001/020,
3 I001/161, 4 I001/040, 5 I001/042, 6 I001/200, 7 I001/070, 8 I001/090, 9 I001/141, 10 I001/130,
11 I001/131, 12 I001/120, 13 I001/170, 14 I001/210, 15 I001/050, 16 I001/080, 17 I001/100, 18 I001/060,
19 I001/030, 20 SP, 21 RFS, 22 I001/150. The three editions print the same UAPs and items.
"""

from __future__ import annotations

import json

import pandas as pd
import pytest
from asterix_bytes import SHARED, block, decode_bytes, fspec, mutate
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from msdc.asterix.encode import encode_frame, encode_record

EDITIONS = ["1.2", "1.3", "1.4"]

# A sector crossing of the same radar (CAT002 FRN 1 I002/010, 2 I002/000, 4 I002/030) dating the records:
# 36000 s * 128 = 4608000 = 0x465000
SECTOR = fspec(1, 2, 4) + bytes([25, 201, 2]) + bytes.fromhex("465000")

# Plot, SAC 25 SIC 201, FRNs 1-10, 14, 15:
# I001/020 0x35 = 0 0 11 0 1 0 1: TYP 0 plot, SIM 0, SSRPSR 3 combined, ANT 0, SPI 1, RAB 0, FX
#          0xC8 = 1 10 0 1 00 0: TST 1, DS1DS2 2 (7600), ME 0, MI 1
# I001/040 RHO 0x3240 = 12864 / 128 = 100.5 NM; THETA 0x4000 = 16384 * 360 / 65536 = 90 deg
# I001/070 0x2F40: V 0, G 0, L 1, code 0o7500 = 3904 = 0xF40
# I001/090 0x7FFB: V 0, G 1, HGT 14 bits 0x3FFB = -5 -> -1.25 FL
# I001/130 0x03 0x04: two 7-bit indicators (FX set on the first)
# I001/141 0x42C0 = 17088 / 128 = 133.5 s; 36000 = 70 * 512 + 160, so nearest 36000: 35840 + 133.5
# I001/050 0x829C: V 1, G 0, L 0, code 0o1234 = 668 = 0x29C
# I001/120 0xFE = -2 * 2^-8 NM/s = -0.0078125 NM/s = -28.125 kt
# I001/131 0xBA = 186 - 256 = -70 dBm
# I001/030 0x05 0x08: codes 2 (reflection, FX) and 4 (split plot)
# I001/150 0xA0 = 1 0 1 00 0 00: XA 1, XC 1, X2 0
PLOT = (bytes.fromhex("FFE380") + bytes([25, 201]) + bytes.fromhex("35C8") + bytes.fromhex("32404000")
        + bytes.fromhex("2F40") + bytes.fromhex("7FFB") + bytes.fromhex("0304") + bytes.fromhex("42C0")
        + bytes.fromhex("829C") + b"\xfe" + b"\xba" + bytes.fromhex("0508") + b"\xa0")

# Track, SAC 25 SIC 201, FRNs 1-9, 13, 19, 22: FSPEC FF (1-7, FX) C5 (8, 9, 13, FX) 09 (19, FX) 80 (22)
# I001/020 0xE8 = 1 1 10 1 0 0 0: TYP 1 track, SIM 1, SSRPSR 2 sole secondary, ANT 1, SPI 0, RAB 0, no FX
# I001/161 0x0123 = 291
# I001/040 RHO 0x0080 = 1.0 NM; THETA 0xC000 = 49152 * 360 / 65536 = 270 deg
# I001/042 X 0xFFA0 = -96 / 64 = -1.5 NM; Y 0x0090 = 144 / 64 = 2.25 NM
# I001/200 GSP 0x0800 = 2048 * 2^-14 = 0.125 NM/s = 450 kt; HDG 0x2000 = 45 deg
# I001/070 0x8280: V 1, code 0o1200 = 640 = 0x280
# I001/090 0x0578 = 1400 / 4 = FL 350
# I001/141 0x0001 = 1/128 s; nearest 36000 s: 36352 + 0.0078125 (-352 s) or 35840 + 0.0078125 (-159.99 s):
#          the nearest is 35840.0078125, 159.99 s before the sector crossing: beyond 32 s, undated
# I001/170 0xD3 = 1 1 0 1 0 0 1 1: CON 1, RAD 1, MAN 0, DOU 1, RDPC 0, spare, GHO 1, FX; 0x80: TRE 1
# I001/030 0x07 0x80: codes 3 (sidelobe, FX) and 64
# I001/150 0x04 = 0 0 0 00 1 00: X2 1
TRACK = (bytes.fromhex("FFC50980") + bytes([25, 201]) + b"\xe8" + bytes.fromhex("0123")
         + bytes.fromhex("0080C000") + bytes.fromhex("FFA00090") + bytes.fromhex("08002000")
         + bytes.fromhex("8280") + bytes.fromhex("0578") + bytes.fromhex("0001") + bytes.fromhex("D380")
         + bytes.fromhex("0780") + b"\x04")


def decode1(*records: bytes, sector: bool = True, **kw) -> pd.DataFrame:
    """The CAT001 frame of one block of these records, after one CAT002 sector crossing of their radar."""
    data = (block(2, SECTOR) if sector else b"") + block(1, *records)
    rec = decode_bytes(data, categories=kw.pop("categories", [1]), **kw)
    assert rec.errors.empty, rec.errors.to_dict("records")
    return rec.frames[1]


def test_fspecs_worked_by_hand() -> None:
    assert fspec(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 14, 15) == bytes.fromhex("FFE380")
    assert fspec(1, 2, 3, 4, 5, 6, 7, 8, 9, 13, 19, 22) == bytes.fromhex("FFC50980")


@pytest.mark.parametrize("edition", EDITIONS)
def test_plot(edition: str) -> None:
    r = decode1(PLOT, editions={1: edition}).iloc[0]
    assert (r.sac, r.sic, r.typ, r.sim, r.ssr_psr, r.ant, r.spi, r.rab) == (25, 201, 0, 0, 3, 0, 1, 0)
    assert (r.tst, r.ds1ds2, r.me, r.mi) == (1, 2, 0, 1)
    assert (r.rho_nm, r.theta_deg) == (100.5, 90.0)
    assert (r.mode3a, r.mode3a_v, r.mode3a_g, r.mode3a_l) == ("7500", 0, 0, 1)
    assert (r.flight_level, r.flight_level_v, r.flight_level_g) == (-1.25, 0, 1)
    assert r.truncated_time_of_day == 133.5 and r.time_of_day == 35973.5
    assert r.mode2 == "1234"
    assert r.doppler_speed_kt == -28.125 and r.received_power_dbm == -70.0
    assert r.warning_codes == "2,4"
    assert (r.xa, r.xc, r.x2) == (1, 1, 0)
    # track items are absent on a plot
    assert pd.isna(r.track_number) and pd.isna(r.x_nm) and pd.isna(r.ground_speed_kt) and pd.isna(r.con)


@pytest.mark.parametrize("edition", EDITIONS)
def test_track(edition: str) -> None:
    rec = decode_bytes(block(2, SECTOR) + block(1, TRACK), categories=[1], editions={1: edition})
    assert rec.errors.empty and rec.editions == {1: "1.4"}  # 1.2 and 1.3 are read with the 1.4 table
    r = rec.frames[1].iloc[0]
    assert (r.typ, r.sim, r.ssr_psr, r.ant, r.spi, r.rab) == (1, 1, 2, 1, 0, 0)
    assert pd.isna(r.tst) and pd.isna(r.ds1ds2)  # no second octet of I001/020
    assert r.track_number == 291
    assert (r.rho_nm, r.theta_deg, r.x_nm, r.y_nm) == (1.0, 270.0, -1.5, 2.25)
    assert (r.ground_speed_kt, r.heading_deg) == (450.0, 45.0)
    assert (r.mode3a, r.mode3a_v) == ("1200", 1) and r.flight_level == 350.0
    assert r.truncated_time_of_day == 0.0078125
    assert (r.con, r.rad, r.man, r.dou, r.rdpc, r.gho, r.tre) == (1, 1, 0, 1, 0, 1, 1)
    assert r.warning_codes == "3,64" and (r.xa, r.xc, r.x2) == (0, 0, 1)
    assert pd.isna(r.time_of_day)  # 159.99 s from the sector crossing: undated
    assert rec.untimed.reason.tolist() == ["more than 32 s from its radar's last CAT002 time of day"]


def test_plot_and_track_in_one_block_keep_file_order() -> None:
    f = decode1(PLOT, TRACK, PLOT)
    assert f.typ.tolist() == [0, 1, 0]
    assert f.rho_nm.tolist() == [100.5, 1.0, 100.5]
    assert f.track_number.isna().tolist() == [True, False, True]


def test_typ_chooses_how_the_same_fspec_is_walked() -> None:
    # FRN 3 is I001/040 (4 bytes) in a plot and I001/161 (2 bytes) in a track
    plot = fspec(1, 2, 3) + bytes([1, 2, 0x00]) + bytes.fromhex("01000800")  # RHO 2 NM, THETA 11.25 deg
    track = fspec(1, 2, 3) + bytes([1, 2, 0x80]) + bytes.fromhex("0100")  # track number 256
    f = decode1(plot, track, sector=False)
    assert f.rho_nm.iloc[0] == 2.0 and f.theta_deg.iloc[0] == 11.25 and pd.isna(f.track_number.iloc[0])
    assert f.track_number.iloc[1] == 256 and pd.isna(f.rho_nm.iloc[1])
    # the same item bytes under the other TYP do not walk: the block is reported, not misread
    swapped = fspec(1, 2, 3) + bytes([1, 2, 0x80]) + bytes.fromhex("01000800")
    rec = decode_bytes(block(1, swapped), categories=[1])
    assert 1 not in rec.frames or rec.frames[1].empty
    assert rec.errors.reason.str.contains("FRN|past the end|record").all() and len(rec.errors) == 1


def test_frn_22_is_a_track_item_only() -> None:
    x_pulse = bytes([0x04])
    track = fspec(1, 2, 22) + bytes([1, 2, 0x80]) + x_pulse
    assert decode1(track, sector=False).x2.iloc[0] == 1
    plot = fspec(1, 2, 22) + bytes([1, 2, 0x00]) + x_pulse
    rec = decode_bytes(block(1, plot), categories=[1])
    assert rec.errors.reason.iloc[0].startswith("the FSPEC sets an FRN the edition does not define")


@pytest.mark.parametrize("typ", [0x00, 0x80])
def test_rfs_is_reported_not_walked(typ: int) -> None:
    rec = decode_bytes(block(1, fspec(1, 2, 21) + bytes([1, 2, typ, 1, 3, 0, 0])), categories=[1])
    assert len(rec.errors) == 1 and "Random Field Sequencing (RFS)" in rec.errors.reason.iloc[0]


def test_items_after_the_selector_without_it_are_reported() -> None:
    rec = decode_bytes(block(1, fspec(1, 3) + bytes([1, 2]) + bytes(4)), categories=[1])
    assert "without that item" in rec.errors.reason.iloc[0] and rec.errors.offset.iloc[0] == 0
    # a record with I001/010 alone needs no UAP
    f = decode1(fspec(1) + bytes([1, 2]), sector=False)
    assert (f.sac.iloc[0], f.sic.iloc[0]) == (1, 2) and pd.isna(f.typ.iloc[0])


def test_second_octet_of_020_does_not_change_the_uap() -> None:
    # TYP is in the first octet; a second octet (FX) is walked by its FX bit
    plot = fspec(1, 2, 7) + bytes([1, 2, 0x01, 0x80]) + bytes.fromhex("0100")
    f = decode1(plot, sector=False)
    assert (f.typ.iloc[0], f.tst.iloc[0], f.truncated_time_of_day.iloc[0]) == (0, 1, 2.0)


def test_not_decoded_unless_asked() -> None:
    data = block(2, SECTOR) + block(1, PLOT, TRACK)
    rec = decode_bytes(data)
    assert rec.frames == {} and rec.errors.empty and rec.untimed.empty
    assert rec.ignored_blocks == {1: 1, 2: 1} and rec.ignored_bytes == len(data)


@pytest.mark.parametrize("edition", EDITIONS)
def test_encoder_writes_the_hand_bytes(edition: str) -> None:
    plot = encode_record(1, {
        "sac": 25, "sic": 201, "typ": 0, "sim": 0, "ssr_psr": 3, "ant": 0, "spi": 1, "rab": 0, "tst": 1,
        "ds1ds2": 2, "me": 0, "mi": 1, "rho_nm": 100.5, "theta_deg": 90.0, "mode3a": "7500", "mode3a_v": 0,
        "mode3a_g": 0, "mode3a_l": 1, "flight_level": -1.25, "flight_level_v": 0, "flight_level_g": 1,
        "truncated_time_of_day": 133.5, "mode2": "1234", "doppler_speed_kt": -28.125,
        "received_power_dbm": -70.0, "warning_codes": "2,4", "xa": 1, "xc": 1, "x2": 0},
        edition=edition, extra={"130": bytes.fromhex("0304"), "050": bytes.fromhex("829C")})
    assert plot == PLOT
    track = encode_record(1, {
        "sac": 25, "sic": 201, "typ": 1, "sim": 1, "ssr_psr": 2, "ant": 1, "spi": 0, "rab": 0,
        "track_number": 291, "rho_nm": 1.0, "theta_deg": 270.0, "x_nm": -1.5, "y_nm": 2.25,
        "ground_speed_kt": 450.0, "heading_deg": 45.0, "mode3a": "1200", "mode3a_v": 1, "flight_level": 350.0,
        "truncated_time_of_day": 0.0078125, "con": 1, "rad": 1, "man": 0, "dou": 1, "rdpc": 0, "gho": 1,
        "tre": 1, "warning_codes": "3,64", "x2": 1}, edition=edition)
    assert track == TRACK


def test_encoder_refuses_what_the_uap_cannot_hold() -> None:
    with pytest.raises(ValueError, match="choose their UAP .*plot or track.* give 'typ'"):
        encode_record(1, {"sac": 1, "rho_nm": 3.0})
    with pytest.raises(ValueError, match="I001/161 is not an item of the record's UAP \\(plot\\)"):
        encode_record(1, {"typ": 0, "track_number": 3})
    with pytest.raises(ValueError, match="row 1: I001/161 is not an item of its UAP \\(plot\\)"):
        encode_frame(1, pd.DataFrame({"typ": [1, 0], "track_number": [3, 4]}))
    with pytest.raises(ValueError, match="derived on decoding"):
        encode_record(1, {"typ": 0, "time_of_day": 10.0})
    # frames of both UAPs: each row by its own UAP, in row order
    frame = pd.DataFrame({"sac": [25, 25], "sic": [201, 201], "typ": [0, 1], "rho_nm": [100.5, 1.0],
                          "track_number": [None, 291]})
    data = encode_frame(1, frame)
    first = encode_record(1, {"sac": 25, "sic": 201, "typ": 0, "rho_nm": 100.5})
    second = encode_record(1, {"sac": 25, "sic": 201, "typ": 1, "rho_nm": 1.0, "track_number": 291})
    assert data == block(1, first, second)


# ---------------------------------------------------------------------------------------------------------
# The printed editions and the tables built from them

SPECS = SHARED / "specs"
needs_specs = pytest.mark.skipif(not (SPECS / "Cat_001_1_4.txt").is_file(),
                                 reason="../shared/specs (the printed layouts) is not beside the repository")


@needs_specs
@pytest.mark.parametrize(("category", "editions", "table"), [
    (1, ["1_2", "1_3", "1_4"], "cat001_1.4.json"), (2, ["1_0", "1_1", "1_2"], "cat002_1.2.json")])
def test_printed_editions_parse_to_the_shipped_table(category: int, editions: list[str], table: str) -> None:
    from pathlib import Path

    from msdc.asterix.tables.build import apply_errata, parse_spec

    shipped = json.loads((Path(__file__).resolve().parents[2] / "asterix" / "tables" / table).read_text())
    for ed in editions:
        parsed = apply_errata(parse_spec((SPECS / f"Cat_{category:03d}_{ed}.txt").read_text()))
        assert {k: v for k, v in parsed.items() if k != "edition"} == \
               {k: v for k, v in shipped.items() if k != "edition"}, ed


def test_table_holds_both_uaps_and_the_selector() -> None:
    from msdc.asterix.tables import load_table

    t = load_table(1, "1.2")
    assert t["selector"] == {"item": "020", "field": ["TYP"], "values": {"0": "plot", "1": "track"}}
    plot = [u["id"] if u else None for u in t["uaps"]["plot"]]
    track = [u["id"] if u else None for u in t["uaps"]["track"]]
    assert plot == ["010", "020", "040", "070", "090", "130", "141", "050", "120", "131", "080", "100",
                    "060", "030", "150", None, None, None, None, "SP", "RFS"]
    assert track == ["010", "020", "161", "040", "042", "200", "070", "090", "141", "130", "131", "120",
                     "170", "210", "050", "080", "100", "060", "030", "SP", "RFS", "150"]


def test_build_refuses_an_alias_whose_layout_differs(tmp_path) -> None:
    from msdc.asterix.tables import build

    one = "# Cat_002_1_{e}  category 2 edition (1, {e})\nFRN 1: I002/010: Data Source Identifier\n" \
          "  group 16 bits\n    SAC: System Area Code\n      element 8 bits: raw\n" \
          "    SIC: System Identification Code\n      element {b} bits: raw\n"
    (tmp_path / "Cat_002_1_1.txt").write_text(one.format(e=1, b=8))
    (tmp_path / "Cat_002_1_2.txt").write_text(one.format(e=2, b=7))
    with pytest.raises(ValueError, match="alias of 1.2, but its layout differs"):
        build.main(["build", str(tmp_path), "2"])


# ---------------------------------------------------------------------------------------------------------
# Bytes: no crash, an exact account, no silent wrong walk (with CAT001 and CAT002 decoded)


def accounted(rec) -> int:
    return rec.decoded_bytes + int(rec.errors["length"].sum()) + rec.container_bytes + rec.ignored_bytes


def radar_stream(rounds: int = 4) -> tuple[bytes, list[tuple[int, int, list[int]]]]:
    """Sector crossings and blocks of plots and tracks: (start, category, track numbers) per block."""
    out, blocks, n = b"", [], 1
    for r in range(rounds):
        sector = fspec(1, 2, 3, 4) + bytes([25, 201, 2, 16 * r]) + (128 * (100 + r)).to_bytes(3, "big")
        # tracks: FRN 3 I001/161, FRN 9 I001/141; the plot: FRN 3 I001/040, FRN 7 I001/141 = 0 (undated)
        tracks = [fspec(1, 2, 3, 9) + bytes([25, 201, 0x80]) + (n + k).to_bytes(2, "big")
                  + (128 * (100 + r) % 65536).to_bytes(2, "big") for k in range(2)]
        plot = fspec(1, 2, 3, 7) + bytes([25, 201, 0x00]) + bytes.fromhex("0A000100") + bytes(2)
        for cat, body, numbers in ((2, sector, []), (1, b"".join(tracks) + plot, [n, n + 1])):
            blocks.append((len(out), cat, numbers))
            out += block(cat, body)
        n += 2
    return out, blocks


def test_radar_stream_decodes_whole() -> None:
    data, _ = radar_stream()
    rec = decode_bytes(data, categories=[1, 2])
    assert rec.errors.empty and accounted(rec) == len(data) and rec.decoded_bytes == len(data)
    f = rec.frames[1]
    assert f.track_number.dropna().tolist() == list(range(1, 9))
    assert f.time_of_day[f.typ == 1].tolist() == [100.0, 100.0, 101.0, 101.0, 102.0, 102.0, 103.0, 103.0]


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=600))
def test_random_bytes_never_crash_and_are_accounted(data: bytes) -> None:
    rec = decode_bytes(data, categories=[1, 2])
    assert accounted(rec) == len(data)
    decoded = set(rec.frames[1].offset) if 1 in rec.frames else set()
    assert set(rec.untimed.offset) <= decoded  # only decoded CAT001 records are undated


@pytest.mark.fuzz
@settings(max_examples=examples(300), deadline=None)
@given(st.data())
def test_mutated_radar_stream_accounted_and_far_blocks_survive(data) -> None:
    stream, blocks = radar_stream(5)
    buf = bytearray(stream)
    pos, action = mutate(buf, data)
    rec = decode_bytes(bytes(buf), categories=[1, 2])
    assert accounted(rec) == len(buf)
    starts = [s for s, _, _ in blocks]
    hit = max(i for i, s in enumerate(starts) if s <= pos)
    numbers = set(rec.frames[1].track_number.dropna()) if 1 in rec.frames else set()
    first_lost = hit - 1 if pos - starts[hit] < 3 else hit  # damage in a header: the block before may go
    assert {t for _, _, ts in blocks[:max(first_lost, 0)] for t in ts} <= numbers
    if action != "truncate":
        assert {t for _, _, ts in blocks[hit + 2:] for t in ts} <= numbers
    for frame in rec.frames.values():
        assert frame["offset"].between(0, len(buf) - 1).all()
    # every record is read by its own UAP: a track number only ever from a track
    if 1 in rec.frames:
        f = rec.frames[1]
        assert (f.track_number.isna() | (f.typ == 1)).all()
