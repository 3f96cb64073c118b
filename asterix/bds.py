"""Mode S BDS registers carried in I048/250 (Comm-B MB fields) decoded into columns, as data.

I048/250 is a one-byte count then 8-byte groups: 56 bits of MB data, BDS1 (4 bits), BDS2 (4 bits). The
radar's declared BDS1/BDS2 says which register a group holds (never inferred from the content). Register
layouts are ICAO Doc 9871 (Technical Provisions for Mode S Services and Extended Squitter) and, for BDS
3,0, Annex 10 Vol IV 4.3.8.4.2.2 (the MV field's subfields, MB bit = message bit - 32), MB bits numbered
1-56 from the most significant. A field whose status bit is 0 is absent, never 0; a register that repeats
its own code in MB bits 1-8 (1,0, 2,0, 3,0) is read only when they hold it. When a record carries one
register twice, its first group is read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BdsField:
    """One register field: status bit (0: the field has none), first value bit and width (MB bits 1-56),
    two's complement or not (the sign bit is the first value bit), LSB, offset added after scaling,
    angles wrapped to [0, 360), what it decodes to (``kind``: float, int, flag, chars (ICAO 6-bit text),
    address (24-bit hex), registers (the 1,7 capability bits as register names)) and a condition on
    another field of the register (``when``: name, value) without which it is absent."""

    status: int
    start: int
    bits: int
    signed: bool = False
    lsb: float = 1.0
    offset: float = 0.0
    wrap360: bool = False
    kind: str = "float"
    when: tuple[str, int] | None = None


# register (BDS1 * 16 + BDS2, written as the column path's "BDSxy") -> field name -> layout (Doc 9871)
REGISTERS: dict[str, dict[str, BdsField]] = {
    "BDS10": {  # data link capability report (MB 1-8 hold 0001 0000)
        "SUBNETWORK": BdsField(status=0, start=17, bits=7, kind="int"),  # Mode S subnetwork version
        "LEVEL5": BdsField(status=0, start=24, bits=1, kind="flag"),  # enhanced protocol: level 5
        "SPECIFIC_SERVICES": BdsField(status=0, start=25, bits=1, kind="flag"),
        "IDENTIFICATION": BdsField(status=0, start=33, bits=1, kind="flag"),  # aircraft id capability
        "SQUITTER": BdsField(status=0, start=34, bits=1, kind="flag"),  # squitter capability subfield
        "SURVEILLANCE_ID": BdsField(status=0, start=35, bits=1, kind="flag"),  # SI code capability
    },
    "BDS17": {  # common usage GICB capability report: bits 1-24 one register each (GICB_BITS)
        "CAPABILITY": BdsField(status=0, start=1, bits=24, kind="registers"),
    },
    "BDS20": {  # aircraft identification (MB 1-8 hold 0010 0000): 8 ICAO 6-bit characters
        "IDENT": BdsField(status=0, start=9, bits=48, kind="chars"),
    },
    "BDS30": {  # ACAS active resolution advisory (MB 1-8 hold 0011 0000)
        "ARA": BdsField(status=0, start=9, bits=14, kind="int"),  # active RAs, bit 9 first
        "RAC": BdsField(status=0, start=23, bits=4, kind="int"),  # RA complements
        "RAT": BdsField(status=0, start=27, bits=1, kind="flag"),  # RA terminated
        "MTE": BdsField(status=0, start=28, bits=1, kind="flag"),  # multiple threat encounter
        "TTI": BdsField(status=0, start=29, bits=2, kind="int"),  # threat type: 1 Mode S address
        "THREAT_ADDRESS": BdsField(status=0, start=31, bits=24, kind="address", when=("TTI", 1)),
    },
    "BDS40": {  # selected vertical intention
        "MCP_ALT": BdsField(status=1, start=2, bits=12, lsb=16.0),  # MCP/FCU selected altitude, ft
        "FMS_ALT": BdsField(status=14, start=15, bits=12, lsb=16.0),  # FMS selected altitude, ft
        "BARO": BdsField(status=27, start=28, bits=12, lsb=0.1, offset=800.0),  # baro setting - 800 mb
        # bit 48 status of the MCP/FCU mode bits 49 VNAV, 50 ALT HOLD, 51 APPROACH; 52-53 reserved
        "VNAV": BdsField(status=48, start=49, bits=1, kind="flag"),
        "ALT_HOLD": BdsField(status=48, start=50, bits=1, kind="flag"),
        "APPROACH": BdsField(status=48, start=51, bits=1, kind="flag"),
        # bit 54 status of the target altitude source, 55-56: 0 unknown, 1 aircraft altitude, 2 FCU/MCP
        # selected altitude, 3 FMS selected altitude
        "TARGET_SOURCE": BdsField(status=54, start=55, bits=2, kind="int"),
    },
    "BDS50": {  # track and turn report
        "ROLL": BdsField(status=1, start=2, bits=10, signed=True, lsb=45.0 / 256),  # deg
        "TRK": BdsField(status=12, start=13, bits=11, signed=True, lsb=90.0 / 512, wrap360=True),  # deg
        "GS": BdsField(status=24, start=25, bits=10, lsb=2.0),  # kt (1024/512)
        "TAR": BdsField(status=35, start=36, bits=10, signed=True, lsb=8.0 / 256),  # deg/s
        "TAS": BdsField(status=46, start=47, bits=10, lsb=2.0),  # kt
    },
    "BDS60": {  # heading and speed report
        "HDG": BdsField(status=1, start=2, bits=11, signed=True, lsb=90.0 / 512, wrap360=True),  # deg
        "IAS": BdsField(status=13, start=14, bits=10, lsb=1.0),  # kt
        "MACH": BdsField(status=24, start=25, bits=10, lsb=2.048 / 512),  # Mach
        "BAR": BdsField(status=35, start=36, bits=10, signed=True, lsb=8192.0 / 256),  # ft/min
        "IVV": BdsField(status=46, start=47, bits=10, signed=True, lsb=8192.0 / 256),  # ft/min
    },
}

GROUP_BYTES = 8  # one I048/250 repetition: MB data (7 bytes), BDS1 and BDS2 (one byte)
# registers whose MB bits 1-8 repeat their own code (Doc 9871): a group that does not is not read
SELF_CODED = ("BDS10", "BDS20", "BDS30")
# BDS 1,7 bits 1-24: the register each says the aircraft can give (Doc 9871 Table A-2-23)
GICB_BITS = ("05", "06", "07", "08", "09", "0A", "20", "21", "40", "41", "42", "43", "44", "45", "48",
             "50", "51", "52", "53", "54", "55", "56", "5F", "60")
# what each field kind decodes to, and the column kind that must name it (asterix/columns)
COLUMN_KIND = {"float": "bds", "int": "bdsint", "flag": "bdsflag", "chars": "bdstext", "address": "bdstext",
               "registers": "bdstext"}


def register_code(name: str) -> int:
    """The BDS1/BDS2 byte of a register name: 'BDS50' -> 0x50."""
    return int(name.removeprefix("BDS"), 16)


def field_of(path: tuple[str, ...]) -> tuple[str, BdsField]:
    """The register and field a column's path ('BDS50', 'ROLL') names; ValueError if there is none."""
    if len(path) != 2 or path[0] not in REGISTERS or path[1] not in REGISTERS[path[0]]:
        raise ValueError(f"I048/250 path {'/'.join(path)!r} names no register field of asterix/bds.py")
    return path[0], REGISTERS[path[0]][path[1]]


def groups(buf: np.ndarray, rec_off: np.ndarray, rel_off: np.ndarray, rel_len: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every repetition of the item in every record, in wire order: record index, 56-bit MB (uint64) and
    BDS1/BDS2 byte. The walker has checked the item's length (1 + 8 x count) against the record."""
    present = np.flatnonzero(rel_len != 0)
    start = rec_off[present].astype(np.int64) + rel_off[present].astype(np.int64)
    count = (rel_len[present].astype(np.int64) - 1) // GROUP_BYTES
    rec = np.repeat(present, count)
    first = np.repeat(np.cumsum(count) - count, count)
    k = np.arange(len(rec)) - first  # repetition number inside its record
    at = np.repeat(start, count) + 1 + GROUP_BYTES * k
    raw = np.zeros(len(rec), np.uint64)
    for b in range(GROUP_BYTES):
        raw = (raw << np.uint64(8)) | buf[at + b].astype(np.uint64)
    return rec, raw >> np.uint64(8), (raw & np.uint64(0xFF)).astype(np.int64)


def _raw(words: np.ndarray, f: BdsField) -> np.ndarray:
    """The field's bits of each 56-bit MB word, as int64 (two's complement applied when signed)."""
    last = f.start + f.bits - 1
    raw = ((words >> np.uint64(56 - last)) & np.uint64((1 << f.bits) - 1)).astype(np.int64)
    if f.signed:
        raw = np.where(raw >= 1 << (f.bits - 1), raw - (1 << f.bits), raw)
    return raw


def _gicb_text(raw: int) -> str:
    """The registers a BDS 1,7 word's bits 1-24 name ('20,40,50,60'); '' when none."""
    return ",".join(reg for i, reg in enumerate(GICB_BITS) if raw >> (23 - i) & 1)


def _typed(kind: str, n: int, rows: np.ndarray, raw: np.ndarray):
    """A column of n records from the raw values of a non-float field at ``rows`` (absent elsewhere)."""
    import pandas as pd

    from .frames import icao_text

    if kind in ("int", "flag"):
        values = np.zeros(n, np.int8 if kind == "flag" else np.int16)
        mask = np.ones(n, bool)
        values[rows], mask[rows] = raw, False
        return pd.arrays.IntegerArray(values, mask)
    fmt = {"chars": icao_text, "address": lambda v: f"{v:06X}", "registers": _gicb_text}[kind]
    uniques, inverse = np.unique(raw, return_inverse=True)
    labels = [fmt(int(u)) for u in uniques]
    cats = sorted({lab for lab in labels if lab})
    where = {lab: i for i, lab in enumerate(cats)}
    codes = np.full(n, -1, np.int32)
    codes[rows] = np.array([where.get(lab, -1) for lab in labels], np.int32)[inverse] if len(raw) else -1
    return pd.Categorical.from_codes(codes, categories=pd.Index(cats, dtype=object))


def decode(buf: np.ndarray, rec_off: np.ndarray, rel_off: np.ndarray, rel_len: np.ndarray,
           wanted: dict[str, tuple[str, ...]]) -> dict[str, object]:
    """Columns of the register fields ``wanted`` (column name -> path such as ('BDS50', 'ROLL')) from the
    I048/250 slot of every record, one vectorised pass per register: floats with NaN where absent,
    nullable ints and categorical text (``BdsField.kind``) with <NA>."""
    n = rec_off.shape[0]
    out: dict[str, object] = {}
    rec, mb, code = groups(buf, rec_off, rel_off, rel_len)
    for reg in sorted({path[0] for path in wanted.values()}):
        sel = np.flatnonzero(code == register_code(reg))
        _, first = np.unique(rec[sel], return_index=True)  # the first group of the register per record
        sel = sel[first]
        rows, words = rec[sel], mb[sel]
        if reg in SELF_CODED:  # bits 1-8 not its own code: not this register's content, not read
            own = (words >> np.uint64(48)) == np.uint64(register_code(reg))
            rows, words = rows[own], words[own]
        for name, path in wanted.items():
            if path[0] != reg:
                continue
            _, f = field_of(path)
            valid = np.ones(len(words), bool) if f.status == 0 else \
                ((words >> np.uint64(56 - f.status)) & np.uint64(1)).astype(bool)
            if f.when is not None:
                valid &= _raw(words, REGISTERS[reg][f.when[0]]) == f.when[1]
            raw = _raw(words, f)
            if f.kind != "float":
                out[name] = _typed(f.kind, n, rows[valid], raw[valid])
                continue
            value = raw * f.lsb + f.offset
            if f.wrap360:
                value = np.mod(value, 360.0)
            column = np.full(n, np.nan)
            column[rows[valid]] = value[valid]
            out[name] = column
    return out
