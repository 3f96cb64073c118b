"""Mode S BDS registers carried in I048/250 (Comm-B MB fields) decoded into columns, as data.

I048/250 is a one-byte count then 8-byte groups: 56 bits of MB data, BDS1 (4 bits), BDS2 (4 bits). The
radar's declared BDS1/BDS2 says which register a group holds (never inferred from the content). Register
layouts are ICAO Doc 9871 (Technical Provisions for Mode S Services and Extended Squitter), MB bits
numbered 1-56 from the most significant. A field whose status bit is 0 is absent (NaN), never 0. When a
record carries one register twice, its first group is read.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BdsField:
    """One register field: status bit, first value bit and width (MB bits 1-56), two's complement or
    not (the sign bit is the first value bit), LSB, offset added after scaling, and angles wrapped to
    [0, 360)."""

    status: int
    start: int
    bits: int
    signed: bool = False
    lsb: float = 1.0
    offset: float = 0.0
    wrap360: bool = False


# register (BDS1 * 16 + BDS2, written as the column path's "BDSxy") -> field name -> layout (Doc 9871)
REGISTERS: dict[str, dict[str, BdsField]] = {
    "BDS40": {  # selected vertical intention
        "MCP_ALT": BdsField(status=1, start=2, bits=12, lsb=16.0),  # MCP/FCU selected altitude, ft
        "FMS_ALT": BdsField(status=14, start=15, bits=12, lsb=16.0),  # FMS selected altitude, ft
        "BARO": BdsField(status=27, start=28, bits=12, lsb=0.1, offset=800.0),  # baro setting - 800 mb
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
    present = np.flatnonzero(rel_off != 0xFFFF)
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


def decode(buf: np.ndarray, rec_off: np.ndarray, rel_off: np.ndarray, rel_len: np.ndarray,
           wanted: dict[str, tuple[str, ...]]) -> dict[str, np.ndarray]:
    """Float columns (NaN where absent) of the register fields ``wanted`` (column name -> path such as
    ('BDS50', 'ROLL')), from the I048/250 slot of every record: one vectorised pass per register."""
    n = rec_off.shape[0]
    out = {name: np.full(n, np.nan) for name in wanted}
    rec, mb, code = groups(buf, rec_off, rel_off, rel_len)
    for reg in sorted({path[0] for path in wanted.values()}):
        sel = np.flatnonzero(code == register_code(reg))
        _, first = np.unique(rec[sel], return_index=True)  # the first group of the register per record
        sel = sel[first]
        rows, words = rec[sel], mb[sel]
        for name, path in wanted.items():
            if path[0] != reg:
                continue
            _, f = field_of(path)
            valid = ((words >> np.uint64(56 - f.status)) & np.uint64(1)).astype(bool)
            last = f.start + f.bits - 1
            raw = ((words >> np.uint64(56 - last)) & np.uint64((1 << f.bits) - 1)).astype(np.int64)
            if f.signed:
                raw = np.where(raw >= 1 << (f.bits - 1), raw - (1 << f.bits), raw)
            value = raw * f.lsb + f.offset
            if f.wrap360:
                value = np.mod(value, 360.0)
            out[name][rows[valid]] = value[valid]
    return out
