"""The radar site table: read ``[[sensor]]`` entries from TOML, and print the entry a missing radar needs."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pandas as pd

SENSOR_COLUMNS = ["name", "sac", "sic", "latitude", "longitude", "altitude_m"]
_TYPES = {"name": (str,), "sac": (int,), "sic": (int,), "latitude": (int, float),
          "longitude": (int, float), "altitude_m": (int, float)}
_RANGES = {"sac": (0, 255), "sic": (0, 255), "latitude": (-90.0, 90.0), "longitude": (-180.0, 180.0)}


def _check_entry(path: Path, i: int, entry: object) -> dict:
    where = f"{path}: [[sensor]] entry {i + 1}"
    if not isinstance(entry, dict):
        raise ValueError(f"{where} is not a table")
    missing = [k for k in SENSOR_COLUMNS if k not in entry]
    if missing:
        raise ValueError(f"{where} lacks {', '.join(missing)} (needs {', '.join(SENSOR_COLUMNS)})")
    for key, types in _TYPES.items():
        value = entry[key]
        if isinstance(value, bool) or not isinstance(value, types):
            kind = " or ".join("integer" if t is int else "float" if t is float else "string" for t in types)
            raise ValueError(f"{where}: {key} = {value!r} should be a {kind}")
    for key, (lo, hi) in _RANGES.items():
        if not lo <= entry[key] <= hi:
            raise ValueError(f"{where}: {key} = {entry[key]!r} is outside {lo}..{hi}")
    return {k: entry[k] for k in SENSOR_COLUMNS}


def read_sensors(path: str | Path) -> pd.DataFrame:
    """The sensor table (name, sac, sic, latitude, longitude, altitude_m) of a TOML file; ValueError if bad.

    Latitude/longitude are WGS-84 degrees, altitude_m the antenna height above the WGS-84 ellipsoid.
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            doc = tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: not valid TOML: {exc}") from exc
    entries = doc.get("sensor")
    if not isinstance(entries, list) or not entries:
        raise ValueError(f"{path}: no [[sensor]] tables found")
    rows = [_check_entry(path, i, e) for i, e in enumerate(entries)]
    seen: dict[tuple[int, int], str] = {}
    for row in rows:
        key = (row["sac"], row["sic"])
        if key in seen:
            raise ValueError(f"{path}: SAC {key[0]} SIC {key[1]} appears twice "
                             f"({seen[key]!r} and {row['name']!r})")
        seen[key] = row["name"]
    frame = pd.DataFrame(rows, columns=SENSOR_COLUMNS)
    frame = frame.astype({"sac": "int64", "sic": "int64", "latitude": "float64", "longitude": "float64",
                          "altitude_m": "float64"})
    return frame


def sensor_toml_snippet(sac: int, sic: int) -> str:
    """The ``[[sensor]]`` lines to add to the sensor file for a radar that is not in it."""
    return (
        "[[sensor]]\n"
        f'name = "radar SAC {sac} SIC {sic}"\n'
        f"sac = {sac}\n"
        f"sic = {sic}\n"
        "latitude = 0.0    # TODO: antenna latitude, degrees north (WGS-84)\n"
        "longitude = 0.0   # TODO: antenna longitude, degrees east (WGS-84)\n"
        "altitude_m = 0.0  # TODO: antenna height above the WGS-84 ellipsoid, metres\n"
    )
