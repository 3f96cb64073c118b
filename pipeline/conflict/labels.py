"""What names the aircraft of a conflict table and where the pair was: each aircraft's call sign and Mode
3/A code as reported at the event's time, the pair's midpoint and each aircraft's flight level there. An
ATC reader knows aircraft by call sign and code, not by 24-bit address.

The table columns in order: the pair first (each address with its call sign and code), then what each
table says (`pipeline.conflict.events`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.conflict.pairs import time_key
from msdc.pipeline.model.selection import IDENTITY_COLUMNS, identity_at

PAIR_COLUMNS = ["aircraft_a", "callsign_a", "mode3a_a", "aircraft_b", "callsign_b", "mode3a_b"]
POSITION_COLUMNS = ["latitude", "longitude", "flight_level_a", "flight_level_b"]


def with_identities(frame: pd.DataFrame, time_column: str, timeline: pd.DataFrame) -> pd.DataFrame:
    """frame (`aircraft_a, aircraft_b`, time_column) with each aircraft's call sign and Mode 3/A code at
    that time (`pipeline.model.selection.identity_at`), placed after its address."""
    out = frame.copy()
    for side in ("a", "b"):
        found = identity_at(timeline, out[f"aircraft_{side}"].to_numpy(), out[time_column])
        for c in IDENTITY_COLUMNS:
            out[f"{c}_{side}"] = found[c].to_numpy(dtype=object) if len(out) else pd.Series(dtype=object)
    return _pair_first(out)


def with_position(frame: pd.DataFrame, time_column: str, samples: pd.DataFrame) -> pd.DataFrame:
    """frame with the pair's midpoint (`latitude, longitude`) and each aircraft's `flight_level_a`,
    `flight_level_b` at time_column, from the samples (`aircraft_id, time, latitude, longitude,
    flight_level`) at exactly that time; NaN where an aircraft has none."""
    out = frame.copy()
    pos = samples[["latitude", "longitude", "flight_level"]].set_axis(
        pd.MultiIndex.from_arrays([time_key(samples["time"]), samples["aircraft_id"].astype(str)]))
    pos = pos[~pos.index.duplicated()]
    at = time_key(out[time_column]) if len(out) else np.zeros(0, np.int64)
    ends = [pos.reindex(pd.MultiIndex.from_arrays([at, out[f"aircraft_{s}"].astype(str)])).to_numpy(float)
            for s in ("a", "b")]
    a, b = ends
    dlon = (b[:, 1] - a[:, 1] + 180.0) % 360.0 - 180.0
    out["latitude"] = (a[:, 0] + b[:, 0]) / 2.0
    out["longitude"] = (a[:, 1] + dlon / 2.0 + 180.0) % 360.0 - 180.0
    out["flight_level_a"], out["flight_level_b"] = a[:, 2], b[:, 2]
    return out


def ordered(frame: pd.DataFrame, after: str) -> pd.DataFrame:
    """frame with POSITION_COLUMNS moved to just after the column `after` (the time they are at)."""
    rest = [c for c in frame.columns if c not in POSITION_COLUMNS]
    at = rest.index(after) + 1
    return frame[rest[:at] + [c for c in POSITION_COLUMNS if c in frame.columns] + rest[at:]]


def _pair_first(frame: pd.DataFrame) -> pd.DataFrame:
    """PAIR_COLUMNS first, the others in their order."""
    return frame[PAIR_COLUMNS + [c for c in frame.columns if c not in PAIR_COLUMNS]]
