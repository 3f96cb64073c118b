"""A hand-made evaluation (scorecard, tables, map points) for the writers' tests: every value written here
by hand, one row per verdict and per edge (a withheld figure, an unchecked threshold, formula-like text)."""

from __future__ import annotations

import math

import pandas as pd

NAN = math.nan
# sensor, sector, requirement, value, ci_low, ci_high, n, threshold, verdict, clause, checked, notes
ROWS = [
    ("SSR1", "global", "pd", 0.975, 0.9736, 0.9764, 50000, 0.97, "pass", "6.3.2.1", True, ""),
    ("SSR1", "global", "mode3a_correct", 0.95, 0.94, 0.96, 2000, 0.98, "fail",
     "COMPASS Radar preset (no clause of the 1997 standard given)", False, ""),
    ("SSR1", "FL 100-200", "modec_correct", 0.965, 0.955, 0.975, 3000, 0.96, "inconclusive",
     "COMPASS Radar preset (no clause of the 1997 standard given)", False,
     "interval [0.955, 0.975] straddles 0.96"),
    ("SSR1", "global", "rms_m", 120.5, 110.4, 131.0, 4000, 150.0, "pass", "5.2.1", True, ""),
    ("ADSB1", "global", "p95_m", NAN, NAN, NAN, 0, 50.0, "inconclusive", "ED-129 3.2", False,
     "=withheld: no report where the reference's sigma is below the tolerance"),
]
COLUMNS = ["sensor", "sector", "requirement", "value", "ci_low", "ci_high", "n", "threshold", "verdict",
           "clause", "checked", "notes"]


def scorecard() -> pd.DataFrame:
    """The hand-made scorecard (no row with parameters but the first: pd over 5 s)."""
    frame = pd.DataFrame(ROWS, columns=COLUMNS)
    return frame.assign(parameters=["interval_s = 5"] + [""] * (len(frame) - 1))


def tables() -> dict[str, pd.DataFrame]:
    """A per-aircraft and a per-bin table, by hand (one NaN to be written as null / an empty cell)."""
    per_aircraft = pd.DataFrame({"aircraft": ["MAS72", "IBE3150"], "sensor": ["SSR1", "SSR1"],
                                 "expected_updates": [120, 80], "detected_updates": [118, 80],
                                 "pd": [118 / 120, 1.0]})
    per_bin = pd.DataFrame({"sensor": ["SSR1", "SSR1"], "range_from_nm": [0.0, 50.0],
                            "range_to_nm": [50.0, 100.0], "expected_updates": [150, 0],
                            "detected_updates": [148, 0], "pd": [148 / 150, NAN]})
    return {"PD per aircraft": per_aircraft, "PD per range band": per_bin}


def map_points() -> pd.DataFrame:
    """Two aircraft near Barcelona: three reports and three reference points each."""
    rows = []
    for name, lat0, lon0 in (("MAS72", 41.30, 2.08), ("IBE3150", 41.50, 2.30)):
        for i in range(3):
            rows.append((name, "reference", "reference", lat0 + 0.01 * i, lon0 + 0.02 * i))
            rows.append((name, "report", "SSR1", lat0 + 0.01 * i + 0.001, lon0 + 0.02 * i - 0.001))
    return pd.DataFrame(rows, columns=["aircraft", "source", "sensor", "latitude", "longitude"])


def png(width: int, height: int, rgb: tuple[int, int, int]) -> bytes:
    """A one-colour PNG written from the PNG specification (signature; IHDR: 8-bit truecolour; one IDAT of
    zlib-compressed scanlines, each after filter byte 0; IEND), so a reader's width and height can be
    checked against the numbers given here."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    rows = b"".join(b"\x00" + bytes(rgb) * width for _ in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def images() -> dict[str, bytes]:
    """Two coverage figures stand-ins: 400 x 300 blue and 320 x 200 green."""
    return {"SSR1: polar map": png(400, 300, (31, 119, 180)),
            "SSR1: vertical coverage": png(320, 200, (44, 160, 44))}
