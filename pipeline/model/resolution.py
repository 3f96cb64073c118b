"""How finely each report's horizontal position is written: the step of the item it came from, in metres.

A position rounded to a step s has a rounding error uniform over the step: its standard deviation is
s / sqrt(12) per axis, so no estimate of a sensor's noise can honestly be smaller (a multilateration
system repeats a parked transponder's I010/042 position to the metre, and its residuals are then zero).
The steps come from the decoder's item tables (asterix.layout.column_resolution), not written here twice.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pandas as pd

from msdc.asterix.layout import column_resolution
from msdc.asterix.tables import available
from msdc.pipeline.model.geodesy import M_PER_NM

# Metres per degree of latitude (the mean meridian degree, 111.13-111.69 km from the equator to the poles):
# a step's size to well under 1 %, which is all a floor needs
M_PER_DEG_LATITUDE = 111_320.0
# (category, position_item) -> the column whose step the position has and that column's metres per unit.
# Polar radar plots (I048/040) have none: their step lies along range and azimuth (7.2 m and
# 360/2^16 deg), not the same in every direction, and far below any radar's noise.
_STEP_COLUMNS = {(10, "042"): ("x_m", 1.0), (20, "042"): ("x_m", 1.0), (48, "042"): ("x_nm", M_PER_NM),
                 (10, "041"): ("latitude", M_PER_DEG_LATITUDE), (20, "041"): ("latitude", M_PER_DEG_LATITUDE)}


@cache
def item_step_m(category: int, position_item: str) -> float:
    """The coarsest step (m) of a position of this category written in this item, over every edition msdc
    decodes (the frame does not say which one; they agree today); NaN where the pair has no single step
    (polar plots, ADS-B, unknown items)."""
    column = _STEP_COLUMNS.get((category, position_item))
    if column is None:
        return math.nan
    steps = [s for edition in available().get(category, [])
             for s in column_resolution(category, column[0], edition)]
    return max(steps) * column[1] if steps else math.nan


def position_step_m(meas: pd.DataFrame) -> np.ndarray:
    """Per row of a measurement frame (pipeline.model.schema), the step (m) its horizontal position was
    written with, from its sensor's category (sensor_id "CCC:...") and position_item; NaN where unknown
    (ADS-B, whose I021/130 and /131 the frame does not tell apart; polar radar plots)."""
    out = np.full(len(meas), np.nan)
    if not len(meas) or "position_item" not in meas:
        return out
    category = meas["sensor_id"].astype(str).str[:3]
    item = meas["position_item"].astype(object).fillna("").astype(str)
    key = pd.Series(category.to_numpy(object) + "|" + item.to_numpy(object))
    for value in key.unique():
        cat, item = value.split("|")
        if cat.isdigit() and item:
            out[(key == value).to_numpy()] = item_step_m(int(cat), item)
    return out
