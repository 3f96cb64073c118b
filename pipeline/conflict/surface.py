"""Aircraft on the aerodrome surface in tracked data: separation minima apply between airborne aircraft, so
the conflicts job leaves pairs with an aircraft on the surface out of its losses and alerts (docs/conflict.md,
"Aircraft on the surface").

A track row is on the surface when the last report of its segment that said anything said so (the tracker's
`on_ground`: CAT021 GBS, CAT048 STAT, or a field monitor); when no report said anything, when its tracked
speed is below SURFACE_SPEED_KT. A report that says airborne is believed at any speed (helicopters fly
below 50 kt: 60 such plots on the real radar recording).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.track.noise import SURFACE_SPEED_KT


def on_surface(tracks: pd.DataFrame, surface_speed_kt: float = SURFACE_SPEED_KT
               ) -> tuple[np.ndarray, np.ndarray]:
    """Per track row (`speed_kt`, optional `on_ground`): whether the aircraft is on the surface, and whether
    that was decided by the speed alone (no report said)."""
    speed = tracks["speed_kt"].to_numpy(float)
    if "on_ground" in tracks.columns:
        said = tracks["on_ground"].astype("boolean")
        unknown = said.isna().to_numpy(bool)
        reported = said.fillna(False).to_numpy(bool)
    else:
        unknown = np.ones(len(tracks), bool)
        reported = np.zeros(len(tracks), bool)
    by_speed = unknown & (speed < surface_speed_kt)
    return reported | by_speed, by_speed


def surface_pairs(frame: pd.DataFrame, tracks: pd.DataFrame, column: str = "on_surface") -> np.ndarray:
    """Per row of a pair frame (`time, aircraft_a, aircraft_b`: pc or separations), whether either aircraft
    is on the surface at that time, by the tracks' boolean `on_surface` (a pair time without a track row
    counts as airborne); or flagged by another boolean `column` of the tracks."""
    flag = pd.Series(tracks[column].to_numpy(bool),
                     index=pd.MultiIndex.from_arrays([tracks["time"], tracks["aircraft_id"].astype(str)]))
    if flag.index.duplicated().any():
        flag = flag.groupby(level=[0, 1]).any()
    out = np.zeros(len(frame), bool)
    for side in ("aircraft_a", "aircraft_b"):
        at = pd.MultiIndex.from_arrays([frame["time"], frame[side].astype(str)])
        out |= flag.reindex(at).fillna(False).to_numpy(bool)
    return out
