"""Encode -> decode round trip over every edition table: every column comes back within one LSB.

Which columns exist in an edition, their widths, signedness and LSBs are read here from the edition tables
by a walker of this file (and checked against the compiled decoder layout); values are drawn in engineering
units over each field's whole range, encoded with ``encode_frame`` and decoded with ``decode_buffer``.

Absence is drawn per *presence unit*: an item, a compound subitem, or an octet group of an extended item.
A unit that is not written decodes as missing (NaN / <NA>), never 0. A column left out of a unit that is
written is zero-filled on the wire, so it decodes as 0; an extended item's octet groups before a written one
are sent too (zero-filled).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED
from budget import examples
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from msdc.asterix import decode_buffer
from msdc.asterix.columns import BDS_KINDS, Column, columns_for
from msdc.asterix.containers import read_segments
from msdc.asterix.encode import encode_frame, encode_record
from msdc.asterix.frames import icao_text
from msdc.asterix.layout import compile_layout
from msdc.asterix.tables import load_table

EDITIONS = [(48, "1.27"), (48, "1.31"), (48, "1.32"),
            (21, "0.23"), (21, "0.24"), (21, "0.25"), (21, "0.26"),
            (21, "2.1"), (21, "2.4"), (21, "2.6"), (21, "2.7"),
            (10, "1.1"), (20, "1.9"), (20, "1.10"), (20, "1.11")]
V2 = [(c, e) for c, e in EDITIONS if c == 21 and e.startswith("2.")]
# service messages (no call sign nor Mode 3/A): only the generic tests
CAT034 = [(34, "1.27"), (34, "1.28"), (34, "1.29"), (2, "1.2")]
REAL = SHARED / "real"  # ../shared/real beside the repository root
SERVICE = (2, 34)  # I0xx/020 feeds two columns: sector_number and sector_azimuth_deg
CAT062 = [(62, f"1.{m}") for m in range(16, 22)]
STATUS = [(19, "1.3"), (23, "1.3"), (25, "1.5"), (63, "1.6"), (65, "1.5")]
GENERIC = EDITIONS + CAT034 + CAT062 + STATUS
# CAT062 fields later editions add (I062/060 V, G in 1.17; I062/080 SFC, IDD, IEC in 1.18, MLAT in 1.20,
# M5I in 1.21): columns the earlier editions lack
CAT062_ADDED = {"1.17": {"mode3a_v", "mode3a_g"}, "1.18": {"sfc", "idd", "iec"}, "1.20": {"cst_mlat"},
                "1.21": {"cst_m5"}}
PREFER_130 = {"latitude": "130", "longitude": "130"}
ICAO_CHARS = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 "
DAY_S = 86400.0
# columns fed by a time-of-day item: kept within one day
TOD_COLUMNS = {"time_of_day", "time_applicability_position", "time_reception_position"}
# 2.x: time_of_day is I021/071, else I021/073 (derived below, not drawn)
V2_DERIVED = {"time_of_day"}
# CAT034, CAT002: I0xx/020 feeds two columns; the azimuth is the sector number times 360/256 deg (not drawn)
SECTOR_DEG = 360 / 256
TYP = {"plot": 0, "track": 1}  # CAT001: the I001/020 TYP of each UAP


@dataclass(frozen=True)
class Spec:
    """Where a column's value lies in an edition (from the table) and what it may hold."""

    name: str
    kind: str
    item: str
    unit: tuple  # presence unit: (item,), (item, subitem), or either + (octet group,) for extended items
    group: int | None  # octet group index inside an extended node
    bits: int
    signed: bool
    step: float  # LSB * column scale (1 for non-float kinds)

    @property
    def lo(self) -> float:
        raw = -(1 << (self.bits - 1)) if self.signed and self.kind == "float" else 0
        return raw * self.step

    @property
    def hi(self) -> float:
        raw = (1 << (self.bits - 1)) - 1 if self.signed and self.kind == "float" else (1 << self.bits) - 1
        top = raw * self.step
        return min(top, DAY_S - self.step) if self.name in TOD_COLUMNS else top


def _locate(node: dict, path: tuple[str, ...]) -> tuple[dict, int] | None:
    """(element node, octet group) of a named field inside a fixed or extended node."""
    kind = node["kind"]
    if not path:
        return (node, 0) if kind == "element" else None
    if kind == "group":
        children = [(c, 0) for c in node["items"]]
    elif kind == "extended":
        children = [(c, g) for g, grp in enumerate(node["groups"]) for c in grp]
    else:
        return None
    for child, g in children:
        if child.get("name") == path[0]:
            if child["kind"] == "element":
                return (child, g) if len(path) == 1 else None
            found = _locate(child, path[1:])
            return None if found is None else (found[0], g)
    return None


def _uap(category: int, edition: str, uap: str = "") -> list:
    """One UAP of an edition table ("uap", or one of "uaps": CAT001 "plot" and "track")."""
    table = load_table(category, edition)
    return table["uaps"][uap] if "uaps" in table else table["uap"]


def _resolve(category: int, edition: str, col: Column, only_item: str | None = None,
             uap: str = "") -> Spec | None:
    """The first source of a column that exists in the edition's UAP (or the source in only_item)."""
    items = {u["id"]: u["node"] for u in _uap(category, edition, uap) if u}
    for item, path in col.sources:
        if item not in items or (only_item is not None and item != only_item):
            continue
        node, unit = items[item], (item,)
        if col.kind in ("count", "codes"):
            if node["kind"] == "repetitive":
                bits = 8 if col.kind == "count" else int(node["item"]["bits"])  # codes: each repetition's
                return Spec(col.name, col.kind, item, unit, None, bits, False, 1.0)
            continue
        if node["kind"] == "compound":
            sub = next((s for s in node["subitems"] if s and path and s["name"] == path[0]), None)
            if sub is None:
                continue
            node, path, unit = sub["node"], path[1:], (item, path[0])
            if node["kind"] == "element" and len(path) == 1:  # a bare element subitem, named like it
                path = ()
        found = _locate(node, path)
        if found is None:
            continue
        elem, g = found
        group = g if node["kind"] == "extended" else None
        step = float(elem.get("lsb", 1.0)) * col.scale if col.kind == "float" else 1.0
        return Spec(col.name, col.kind, item, unit + ((group,) if group is not None else ()), group,
                    int(elem["bits"]), bool(elem.get("signed", False)), step)
    return None


def specs_for(category: int, edition: str, prefer130: bool = False, uap: str = "") -> dict[str, Spec]:
    out = {}
    for col in columns_for(category, edition):
        only = PREFER_130.get(col.name) if prefer130 else None
        spec = _resolve(category, edition, col, only, uap)
        if spec is not None:
            out[col.name] = spec
    return out


@pytest.mark.parametrize(("category", "edition"), GENERIC)
def test_table_walk_agrees_with_layout(category: int, edition: str) -> None:
    specs = specs_for(category, edition)
    items = set(compile_layout(category, edition).item_frn)
    assert {s.item for s in specs.values()} <= items
    # a column exists in an edition when one of its sources resolves there
    # (but for a field that is a spare bit in that edition: I021/200 ME, spare in 2.1; I020/020 CF, an
    # octet-group 1.9 does not define)
    spare = {"me"} if (category, edition) == (21, "2.1") else {"cf"} if (category, edition) == (20, "1.9") \
        else set()
    if category == 62:  # spare bits (or an octet group not yet defined) in the earlier editions
        spare = set().union(*(cols for ed, cols in CAT062_ADDED.items() if _version(ed) > _version(edition)))
    # Mode S register fields (kind "bds", I048/250 contents) are read by asterix/bds.py, not the table walk
    registers = {c.name for c in columns_for(category, edition) if c.kind in BDS_KINDS}
    for col in columns_for(category, edition):
        if col.name not in specs and col.name not in spare | registers:
            assert not any(item in items for item, _ in col.sources), col.name
    missing = {c.name for c in columns_for(category, edition)} - set(specs) - registers
    if category == 20:  # no message type item in CAT020 (I020/020 CF, from 1.10 on, is in spare)
        assert missing == {"message_type"} | spare
    elif category in (*SERVICE, 10, 48, 62, 19, 23, 25, 63, 65) or edition.startswith("2.") \
            or edition == "0.26":
        assert missing == spare
    else:
        assert missing == {"mode3a", "signal_amplitude"}  # no I021/070 nor I021/131 before 0.26


# ---------------------------------------------------------------------------------------------------------
# Values


def _zero(spec: Spec):
    return {"float": 0.0, "octal": "0000"}.get(spec.kind, 0)


def _value(spec: Spec) -> st.SearchStrategy:
    """An engineering value over the whole field range, extremes favoured."""
    if spec.kind == "float":
        lo, hi = spec.lo, spec.hi
        edges = [lo, hi, spec.step, min(max(0.0, lo), hi)]
        if spec.signed:
            edges += [-spec.step, lo + spec.step]
        return st.one_of(st.sampled_from(edges), st.floats(lo, hi, allow_nan=False))
    if spec.kind in ("int", "flag"):
        return st.integers(0, (1 << spec.bits) - 1)
    if spec.kind == "count":
        return st.integers(0, 255)
    if spec.kind == "codes":  # one to five codes of the repeated element, joined by ','
        return st.lists(st.integers(0, (1 << spec.bits) - 1), min_size=1, max_size=5).map(
            lambda codes: ",".join(map(str, codes)))
    if spec.kind == "octal":
        return st.integers(0, 0o7777).map(lambda v: f"{v:04o}")
    if spec.kind == "hex":
        return st.integers(0, (1 << 24) - 1).map(lambda v: f"{v:06X}")
    if spec.kind == "icao":
        return st.text(ICAO_CHARS, min_size=1, max_size=8).filter(lambda s: s.strip() != "")
    raise AssertionError(spec.kind)


def _expected_text(spec: Spec, value):
    return value.rstrip() if spec.kind == "icao" else value


@st.composite
def rows(draw, category: int, edition: str, prefer130: bool, uap: str = "") -> tuple[dict, dict]:
    """(input row for encode_frame, expected decoded row); CAT001 rows of one UAP (``typ`` fixed)."""
    specs = specs_for(category, edition, prefer130, uap)
    v2 = category == 21 and edition.startswith("2.")
    drawn = {n: s for n, s in specs.items()
             if not (v2 and n in V2_DERIVED) and not (category in SERVICE and n == "sector_azimuth_deg")
             and not (uap and n == "typ")}
    units: dict[tuple, list[Spec]] = {}
    for s in drawn.values():
        units.setdefault(s.unit, []).append(s)
    present = {u for u in units if draw(st.booleans())}
    if not present:
        present = {drawn["sac"].unit}
    if uap:  # the octet of TYP is always written: it chooses the UAP
        present.add(specs["typ"].unit)
    # octet groups of an extended node before a written one are written too (zero-filled)
    emitted = set(present)
    for u in units:
        if len(u) and isinstance(u[-1], int) and any(
                p[:-1] == u[:-1] and isinstance(p[-1], int) and p[-1] > u[-1] for p in present):
            emitted.add(u)
    given_row: dict = {}
    expected: dict = {}
    for u, members in units.items():
        if u not in present:
            for s in members:
                given_row[s.name] = None
                expected[s.name] = _zero(s) if u in emitted else None
            continue
        # a unit is written when at least one of its columns has a value; the others are zero-filled
        droppable = [s for s in members if s.kind in ("float", "int", "flag", "octal")]
        keep = draw(st.sampled_from(members))
        for s in members:
            if s is not keep and s in droppable and draw(st.integers(0, 4)) == 0:
                given_row[s.name] = None
                expected[s.name] = _zero(s)
            else:
                v = draw(_value(s))
                given_row[s.name] = v
                expected[s.name] = _expected_text(s, v)
    if uap:
        given_row["typ"] = expected["typ"] = TYP[uap]
    if category in SERVICE and "sector_azimuth_deg" in specs:
        number = expected["sector_number"]
        expected["sector_azimuth_deg"] = None if number is None else number * SECTOR_DEG
        given_row["sector_azimuth_deg"] = None
    if v2:
        t071, t073 = expected["time_applicability_position"], expected["time_reception_position"]
        tod = t071 if t071 is not None else t073
        expected["time_of_day"] = tod
        given_row["time_of_day"] = tod if tod is not None and draw(st.booleans()) else None
        step = drawn["time_applicability_position"].step
        same = t073 is not None and math.floor(t071 / step + 0.5) == math.floor(t073 / step + 0.5) \
            if t071 is not None else True
        if not same and given_row["time_applicability_position"] is not None and draw(st.booleans()):
            # I021/071 written through time_of_day alone (the encoder would leave time_of_day in I021/073
            # when that already holds the same value)
            given_row["time_of_day"] = t071
            given_row["time_applicability_position"] = None
    return given_row, expected


# ---------------------------------------------------------------------------------------------------------
# Round trip


def round_trip(category: int, edition: str, frame: pd.DataFrame, prefer: dict | None = None,
               records_per_block: int = 20) -> pd.DataFrame:
    data = encode_frame(category, frame, edition=edition, prefer=prefer, records_per_block=records_per_block)
    buf = np.frombuffer(data, np.uint8)
    rec = decode_buffer(buf, read_segments(buf, "raw"), path="<round trip>", editions={category: edition},
                        categories=[category])
    assert rec.errors.empty, rec.errors.to_dict("records")
    assert rec.decoded_bytes == len(data)
    assert list(rec.frames) == [category]
    out = rec.frames[category]
    assert len(out) == len(frame)
    return out


def assert_row(decoded: pd.DataFrame, i: int, expected: dict, specs: dict[str, Spec]) -> None:
    for name, want in expected.items():
        got = decoded[name].iloc[i]
        where = f"row {i} column {name!r}: expected {want!r}, decoded {got!r}"
        if want is None:
            assert pd.isna(got), where
            continue
        assert not pd.isna(got), where
        spec = specs[name]
        if spec.kind == "float":
            tol = spec.step / 2 + 1e-9 * max(1.0, abs(want))
            assert abs(float(got) - float(want)) <= tol, where
        elif spec.kind in ("int", "flag", "count"):
            assert int(got) == int(want), where
        else:
            assert str(got) == want, where


def check(category: int, edition: str, given_rows: list[dict], expected: list[dict], prefer130: bool = False,
          records_per_block: int = 20) -> pd.DataFrame:
    frame = pd.DataFrame(given_rows)
    decoded = round_trip(category, edition, frame, PREFER_130 if prefer130 else None, records_per_block)
    specs = specs_for(category, edition, prefer130)
    if category == 21 and edition.startswith("2."):
        specs["time_of_day"] = specs["time_applicability_position"]
    for i, row in enumerate(expected):
        assert_row(decoded, i, row, specs)
    # columns the edition does not have are all-missing
    for col in columns_for(category, edition):
        if col.name not in specs:
            assert decoded[col.name].isna().all(), col.name
    return decoded


@pytest.mark.parametrize(("category", "edition"), GENERIC)
@settings(max_examples=examples(30), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_round_trip_every_edition(category: int, edition: str, data: st.DataObject) -> None:
    prefer130 = category == 21 and edition.startswith("2.") and data.draw(st.booleans(), label="prefer 130")
    n = data.draw(st.integers(1, 7), label="rows")
    drawn = [data.draw(rows(category, edition, prefer130), label=f"row {i}") for i in range(n)]
    per_block = data.draw(st.integers(1, 5), label="records per block")
    check(category, edition, [g for g, _ in drawn], [e for _, e in drawn], prefer130, per_block)


def _full_row(specs: dict[str, Spec], pick) -> dict:
    return {n: pick(s) for n, s in specs.items()}


@pytest.mark.parametrize(("category", "edition", "prefer130"),
                         [(c, e, False) for c, e in GENERIC] + [(c, e, True) for c, e in V2])
def test_every_field_at_its_extremes(category: int, edition: str, prefer130: bool) -> None:
    specs = specs_for(category, edition, prefer130)
    if category == 21 and edition.startswith("2."):
        del specs["time_of_day"]

    def lowest(s: Spec):
        return {"float": s.lo, "octal": "0000", "hex": "000000", "icao": "0", "codes": "0"}.get(s.kind, 0)

    def highest(s: Spec):
        return {"float": s.hi, "octal": "7777", "hex": "FFFFFF", "icao": "ZZZZZZZZ", "count": 3,
                "codes": "127,0,127"}.get(
            s.kind, (1 << s.bits) - 1)

    def one_step(s: Spec):
        return {"float": -s.step if s.signed else s.step, "octal": "0001", "hex": "000001",
                "icao": "A 1", "count": 1, "codes": "1"}.get(s.kind, 1)

    given_rows = [_full_row(specs, lowest), _full_row(specs, highest), _full_row(specs, one_step)]
    expected = [dict(r) for r in given_rows]
    if category == 21 and edition.startswith("2."):
        for r in expected:
            r["time_of_day"] = r["time_applicability_position"]
    decoded = check(category, edition, given_rows, expected, prefer130)
    for name, s in specs.items():
        if s.kind == "float" and s.signed:  # signed minimum: exactly -2^(bits-1) LSBs, sign bit only
            assert decoded[name].iloc[0] == pytest.approx(-(2.0 ** (s.bits - 1)) * s.step, rel=1e-12)
            assert decoded[name].iloc[0] < 0 < decoded[name].iloc[1]


# ---------------------------------------------------------------------------------------------------------
# Named edge cases


@pytest.mark.parametrize("edition", ["1.27", "1.31", "1.32"])
def test_cat048_flight_level_signed_extremes(edition: str) -> None:
    fls = [-2048.0, 2047.75, -0.25, 0.0, -1200.5, 330.0]
    decoded = round_trip(48, edition, pd.DataFrame({"sac": 1, "sic": 2, "flight_level": fls}))
    assert decoded.flight_level.tolist() == fls


@pytest.mark.parametrize("edition", ["0.23", "0.26", "2.1", "2.7"])
def test_cat021_flight_level_signed_extremes(edition: str) -> None:
    fls = [-8192.0, 8191.75, -2048.0, -0.25, 0.0]  # I021/145: 16-bit two's complement, 1/4 FL
    decoded = round_trip(21, edition, pd.DataFrame({"sac": 1, "sic": 2, "flight_level": fls}))
    assert decoded.flight_level.tolist() == fls


CALLSIGNS = ["AB 12 C", "1 2 3 4", "A1B2C3D4", "  X9", "DLH65A", "0", "Z 9", "12345678", "EZY 4 Y"]


@pytest.mark.parametrize(("category", "edition"), EDITIONS)
def test_callsigns_with_digits_and_spaces(category: int, edition: str) -> None:
    frame = pd.DataFrame({"sac": 1, "sic": 2, "callsign": CALLSIGNS + [None]})
    decoded = round_trip(category, edition, frame)
    assert decoded.callsign.tolist()[:-1] == [c.rstrip() for c in CALLSIGNS]
    assert pd.isna(decoded.callsign.iloc[-1])


# An identification of all zeros (code 0 is no character) or all spaces (the 6-bit IA-5 code of a space is
# 0b100000: 100000 x 8 = 0x820820820820) decodes to no text; callsign_hex keeps its bits, and the encoder
# writes them back (it left the item out, or wrote zeros for spaces).
ALL_ZERO, ALL_SPACE = "000000000000", "820820820820"


def test_identification_bits_are_written_from_callsign_hex() -> None:
    """Worked by hand from the specs (Cat_021_0_23.txt FRN 18 I021/170: 48 bits; Cat_010_1_1.txt FRN 14
    I010/245: STI 2 bits, spare 6, CHR 48 bits). CAT021 0.23, FRNs 1 and 18: FSPEC 81 01 10, SAC/SIC 01 02,
    then the six bytes; CAT010 1.1, FRNs 1 and 14: FSPEC 81 02, 01 02, STI byte 00, then the six bytes."""
    adsb = pd.DataFrame({"sac": [1, 1], "sic": [2, 2], "callsign": [None, "MAS72"],
                         "callsign_hex": [ALL_ZERO, None]})
    data = encode_frame(21, adsb, edition="0.23", records_per_block=1)
    assert data[:14] == bytes.fromhex("15000e" "810110" "0102" + ALL_ZERO)  # LEN 3 + 3 + 2 + 6 = 14
    mlat = pd.DataFrame({"sac": [1], "sic": [2], "callsign_hex": [ALL_SPACE]})  # no callsign column at all
    assert encode_frame(10, mlat, edition="1.1") == bytes.fromhex(
        "0a000e" "8102" "0102" "00" + ALL_SPACE)  # LEN 3 + 2 + 2 + 7 = 14
    for category, edition, frame in ((21, "0.23", adsb), (10, "1.1", mlat)):
        back = round_trip(category, edition, frame)
        assert back.callsign_hex.tolist()[:1] == frame.callsign_hex.tolist()[:1]
        assert pd.isna(back.callsign.iloc[0])
    assert back_text(round_trip(21, "0.23", adsb)) == [None, "MAS72"]  # no hex: written from the text
    assert encode_record(21, {"sac": 1, "sic": 2, "callsign_hex": ALL_ZERO}, edition="0.23") == bytes.fromhex(
        "810110" "0102" + ALL_ZERO)


def back_text(frame: pd.DataFrame) -> list:
    return frame.callsign.astype(object).where(frame.callsign.notna(), None).tolist()


def test_a_callsign_and_its_hex_that_disagree_are_refused() -> None:
    """An edited callsign is not overwritten by the hex decoding left beside it, silently."""
    frame = pd.DataFrame({"sac": [1, 1], "sic": [2, 2], "callsign": ["MAS72", "ABC"],
                          "callsign_hex": ["3414F7CA0820", ALL_ZERO]})
    # M 001101 A 000001 S 010011 7 110111 2 110010, then 3 spaces 100000: 0x3414F7CA0820, the first row agrees
    assert icao_text(0x3414F7CA0820) == "MAS72"
    with pytest.raises(ValueError, match=r"^row 1: callsign 'ABC' and callsign_hex '000000000000' \(which "
                                         r"reads ''\) disagree: drop callsign_hex to write the text"):
        encode_frame(21, frame, edition="0.23")
    # a removed call sign beside the hex of MAS72: refused too (the hex would put MAS72 back); beside the
    # all-zero hex, no text agrees
    removed = frame.assign(callsign=[None, None])
    words = (r"^row 0: callsign absent and callsign_hex '3414F7CA0820' \(which reads 'MAS72'\) disagree: "
             r"drop callsign_hex to leave the item out")
    with pytest.raises(ValueError, match=words):
        encode_frame(21, removed, edition="0.23")
    assert encode_frame(21, removed.iloc[[1]], edition="0.23")
    with pytest.raises(ValueError, match=r"^column 'callsign_hex' row 0: '0000' is not 12 hex digits"):
        encode_frame(21, pd.DataFrame({"sac": [1], "callsign_hex": ["0000"]}), edition="0.23")


@pytest.mark.skipif(not REAL.is_dir(), reason=f"{REAL} not present: real-recording round trip skipped")
@pytest.mark.parametrize(("name", "category", "edition", "blank"), [
    ("adsb_v023_160510-lebl-220001.ast", 21, "0.23", {ALL_ZERO: 5891}),
    ("mlat_160510-lebl-220001.ast", 10, "1.1", {ALL_SPACE: 9})])
def test_a_real_recording_keeps_every_identification(name, category, edition, blank) -> None:
    """The real LEBL ADS-B (CAT021 0.23) has 5,891 records whose I021/170 is all zeros, the MLAT 9 whose
    I010/245 is all spaces: decode -> encode -> decode gave them no item (ADS-B) or zeros (MLAT)."""
    frame = decode_buffer(*_mapped_raw(REAL / name), editions={category: edition},
                          categories=[category]).frames[category]
    hexes = frame.callsign_hex.astype(object).where(frame.callsign_hex.notna(), None)
    assert {h: int((hexes == h).sum()) for h in blank} == blank
    back = round_trip(category, edition, frame, records_per_block=100)
    for column in ("callsign_hex", "callsign"):
        before = frame[column].astype(object).where(frame[column].notna(), None).tolist()
        after = back[column].astype(object).where(back[column].notna(), None).tolist()
        assert after == before, column


def _mapped_raw(path) -> tuple:
    buf = np.frombuffer(path.read_bytes(), np.uint8)
    return buf, read_segments(buf, "raw")


@pytest.mark.parametrize(("category", "edition"), [(c, e) for c, e in EDITIONS if (c, e) not in
                                                    {(21, "0.23"), (21, "0.24"), (21, "0.25")}])
def test_octal_codes_0000_and_7777(category: int, edition: str) -> None:
    codes = ["0000", "7777", "0001", "7000", "1200", None]
    decoded = round_trip(category, edition, pd.DataFrame({"sac": 1, "sic": 2, "mode3a": codes}))
    assert decoded.mode3a.tolist()[:-1] == codes[:-1]
    assert pd.isna(decoded.mode3a.iloc[-1])


def test_no_mode3a_before_0_26() -> None:
    with pytest.raises(ValueError, match="mode3a"):
        encode_frame(21, pd.DataFrame({"mode3a": ["7777"]}), edition="0.23")


def fspec_frns(record: bytes) -> set[int]:
    """FRNs set in the FSPEC at the start of a record, read bit by bit."""
    out, i = set(), 0
    while True:
        for bit in range(7):
            if record[i] & (0x80 >> bit):
                out.add(7 * i + bit + 1)
        if not record[i] & 1:
            return out
        i += 1


@pytest.mark.parametrize(("edition", "prefer130"), [
    ("0.23", False), ("0.24", False), ("0.25", False), ("0.26", False),
    *((e, p) for _, e in V2 for p in (False, True))])
def test_positions_near_the_poles_and_antimeridian(edition: str, prefer130: bool) -> None:
    spec = specs_for(21, edition, prefer130)["longitude"]
    step = spec.step
    assert spec.item == ("131" if edition.startswith("2.") and not prefer130 else "130")
    assert spec.bits == (24 if edition == "0.23" or prefer130 else 32)
    # +180 fits unless the field stops one LSB short of it (24-bit I021/130: 2^23 LSBs = 180 exactly)
    lon_max = min(180.0, spec.hi)
    lats = [90.0, -90.0, 90.0 - step, -90.0 + step, 0.0, 45.123456]
    lons = [lon_max, -180.0, -180.0 + step, 179.0, 0.0, -0.000001]
    frame = pd.DataFrame({"sac": 1, "sic": 2, "latitude": lats, "longitude": lons})
    prefer = PREFER_130 if prefer130 else None
    data = encode_frame(21, frame, edition=edition, prefer=prefer)
    buf = np.frombuffer(data, np.uint8)
    rec = decode_buffer(buf, read_segments(buf, "raw"), editions={21: edition})
    out = rec.frames[21]
    assert rec.errors.empty and len(out) == len(lats)
    assert np.all(np.abs(out.latitude.to_numpy() - lats) <= step / 2 + 1e-12)
    assert np.all(np.abs(out.longitude.to_numpy() - lons) <= step / 2 + 1e-12)
    assert out.latitude.iloc[1] == -90.0 and out.longitude.iloc[1] == -180.0
    frns = fspec_frns(data[3:])  # first record, after the block header
    lay = compile_layout(21, edition)
    assert lay.item_frn[spec.item] in frns
    assert "131" not in lay.item_frn or spec.item == "131" or lay.item_frn["131"] not in frns
    if lon_max < 180.0:
        assert spec.bits == 24
        with pytest.raises(ValueError, match="range"):
            encode_frame(21, pd.DataFrame({"latitude": [0.0], "longitude": [180.0]}), edition=edition,
                         prefer=prefer)


@pytest.mark.parametrize(("category", "edition"), GENERIC)
def test_time_of_day_near_midnight(category: int, edition: str) -> None:
    tods = [0.0, 0.0078125, 0.004, 86399.99, 86399.9921875, 43200.0]
    decoded = round_trip(category, edition, pd.DataFrame({"sac": 1, "sic": 2, "time_of_day": tods}))
    assert np.all(np.abs(decoded.time_of_day.to_numpy() - tods) <= 1 / 256 + 1e-9)
    assert decoded.time_of_day.iloc[-2] == 86399.9921875 and decoded.time_of_day.iloc[0] == 0.0
    assert decoded.timestamp.isna().all()  # no date given
    assert math.isclose(decoded.time_of_day.max(), 86399.9921875)


# ---------------------------------------------------------------------------------------------------------
# CAT001: each UAP, and the whole time of day from a CAT002 message before each record


@pytest.mark.parametrize("uap", ["plot", "track"])
@settings(max_examples=examples(30), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_round_trip_cat001(uap: str, data: st.DataObject) -> None:
    n = data.draw(st.integers(1, 7), label="rows")
    drawn = [data.draw(rows(1, "1.4", False, uap), label=f"row {i}") for i in range(n)]
    given_rows, expected = [g for g, _ in drawn], [e for _, e in drawn]
    # each record's whole time, its I001/141 (the time modulo 512 s) and a CAT002 message of its radar
    # before it, within 32 s of it
    blocks, times = [], []
    for i, (g, e) in enumerate(drawn):
        true = data.draw(st.integers(0, 86400 * 128 - 1), label=f"time {i}") / 128
        ahead = data.draw(st.integers(-32 * 128, 32 * 128), label=f"ahead {i}") / 128
        if g.get("truncated_time_of_day") is not None or e.get("truncated_time_of_day") is not None:
            g["truncated_time_of_day"] = e["truncated_time_of_day"] = true % 512
        sector = pd.DataFrame([{"sac": e["sac"] or 0, "sic": e["sic"] or 0, "message_type": 2,
                                "time_of_day": (true - ahead) % 86400}])
        blocks.append(encode_frame(2, sector))
        dated = e["sac"] is not None and e["truncated_time_of_day"] is not None
        times.append(true if dated else np.nan)
    plots = encode_frame(1, pd.DataFrame(given_rows), edition="1.4", records_per_block=1)
    starts = [0]
    while starts[-1] < len(plots):
        starts.append(starts[-1] + int.from_bytes(plots[starts[-1] + 1:starts[-1] + 3], "big"))
    stream = b"".join(s + plots[a:b] for s, a, b in zip(blocks, starts[:-1], starts[1:], strict=True))
    buf = np.frombuffer(stream, np.uint8)
    rec = decode_buffer(buf, read_segments(buf, "raw"), path="<round trip>", categories=[1, 2])
    assert rec.errors.empty, rec.errors.to_dict("records")
    assert rec.decoded_bytes == len(stream)
    decoded = rec.frames[1]
    specs = specs_for(1, "1.4", uap=uap)
    for i, row in enumerate(expected):
        assert_row(decoded, i, row, specs)
    np.testing.assert_array_equal(decoded.time_of_day.to_numpy(), times)
    for col in columns_for(1, "1.4"):  # the other UAP's items are absent
        if col.name not in specs and col.name != "time_of_day":
            assert decoded[col.name].isna().all(), col.name


def _version(edition: str) -> tuple[int, ...]:
    """'1.20' -> (1, 20): editions compare as numbers, not as decimals (1.20 after 1.3)."""
    return tuple(int(x) for x in edition.split("."))
