"""Surface or airborne: which pooled row of the quality and accuracy sheets an aircraft's reports go to.

A report is on the surface when it says so (``on_ground``: CAT021 GBS, CAT048 I048/230 STAT on ground, or
either's RAB, a field monitor: a fixed transponder) and airborne when it says that; when it says nothing,
on the surface below SURFACE_SPEED_KT of ground speed (a report without speed counts as airborne). The
rule of ``msdc conflicts`` (pipeline.conflict.surface) applied per report. An aircraft's reports of one
sensor go to the "(all surface)" row when more than half of them are on the surface, else to "(all)": a
site monitor or a parked aircraft is not pooled with the traffic the radar tracks in the air, and an
aircraft that taxies and takes off stays in one row, by where it spent most of its reports.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

# msdc conflicts' threshold (pipeline.track.noise.SURFACE_SPEED_KT; a test holds them equal), kept here so
# that the quality sheets do not import the tracker and scipy with it
SURFACE_SPEED_KT = 50.0
SURFACE_ALL = "(all surface)"  # the pooled row of aircraft on the surface
SURFACE_INPUTS = ["on_ground", "ground_speed_kt"]  # the measurement columns the rule reads


def on_surface(reports: pd.DataFrame) -> np.ndarray:
    """Per report, whether it is on the surface by the module's rule."""
    n = len(reports)
    speed = (pd.to_numeric(reports["ground_speed_kt"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
             if "ground_speed_kt" in reports else np.full(n, np.nan))
    slow = speed < SURFACE_SPEED_KT  # NaN: not slow
    if "on_ground" not in reports:
        return slow
    said = reports["on_ground"].astype("boolean")
    return np.where(said.isna().to_numpy(bool), slow, said.fillna(False).to_numpy(bool))


def mostly_surface(flags: np.ndarray) -> bool:
    """Whether more than half of an aircraft's reports of one sensor are on the surface."""
    return bool(flags.size) and 2 * int(np.count_nonzero(flags)) > flags.size
