"""pipeline.model.resolution: the step each report's position was written with (values from the specs)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.model.resolution import position_step_m


def test_each_row_gets_its_items_step_in_metres():
    meas = pd.DataFrame({
        "sensor_id": ["010:0/107:mlat", "020:25/10", "020:25/10", "048:25/201", "048:25/201", "021:0/107",
                      "010:0/7:smr"],
        "position_item": pd.array(["042", "042", "041", "042", "040", pd.NA, "041"], dtype="string")})
    step = position_step_m(meas)
    want = [1.0,  # I010/042 LSB 1 m
            0.5,  # I020/042 LSB 0.5 m
            180.0 / 2**25 * 111_320.0,  # I020/041 latitude LSB, ~0.60 m
            1852.0 / 128,  # I048/042 LSB 1/128 NM
            np.nan,  # polar: no single step
            np.nan,  # ADS-B: /130 or /131 not known from the frame
            180.0 / 2**31 * 111_320.0]  # I010/041, ~0.009 m
    np.testing.assert_allclose(step, want, rtol=1e-9)


def test_a_frame_without_position_items_has_no_steps():
    meas = pd.DataFrame({"sensor_id": ["010:0/107:mlat"]})
    assert np.isnan(position_step_m(meas)).all()
    assert position_step_m(meas.iloc[:0]).shape == (0,)
    assert pytest.approx(1.0) == position_step_m(meas.assign(position_item=["042"]))[0]
