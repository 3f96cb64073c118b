"""The measurement column on_ground: what a report says of the aircraft being on the surface (CAT021
I021/040 GBS, CAT048 I048/230 STAT by the spec's code table, RAB: a field monitor)."""

from pathlib import Path

import pandas as pd
import pytest

from msdc.pipeline.model.measurements import DECODED_COLUMNS, adsb_measurements, on_ground


def test_cat048_stat_codes_say_on_ground_as_the_spec_table():
    # I048/230 STAT (CAT048 1.27-1.32): 0 no alert/no SPI airborne, 1 ... on ground, 2 alert airborne,
    # 3 alert on ground, 4 and 5 "airborne or on ground", 7 unknown (6 unassigned)
    stat = pd.array([0, 1, 2, 3, 4, 5, 6, 7, None], dtype="Int8")
    said = on_ground(pd.DataFrame({"flight_status": stat}), 48)
    assert said.tolist() == [False, True, False, True, pd.NA, pd.NA, pd.NA, pd.NA, pd.NA]


def test_cat021_gbs_and_a_field_monitor_say_on_ground():
    frame = pd.DataFrame({"gbs": pd.array([0, 1, None, 0], dtype="Int8"),
                          "rab": pd.array([0, 0, 0, 1], dtype="Int8")})  # RAB 1: a fixed transponder
    assert on_ground(frame, 21).tolist() == [False, True, pd.NA, True]
    assert on_ground(pd.DataFrame({"gbs": [1]}), 48).isna().all()  # CAT048 has no GBS
    # a frame without the items: the measurement column is there, all <NA>
    frame = pd.DataFrame({"time_of_day": [1.0], "day": [0], "latitude": [1.0], "longitude": [100.0],
                          "sac": [0], "sic": [1]})
    out = adsb_measurements(frame)
    assert str(out["on_ground"].dtype) == "boolean" and out["on_ground"].isna().all()


REAL_RADAR = Path(__file__).resolve().parents[4] / "shared" / "real" / "230502-est-080001_BCN_60MN_08_09.ast"


@pytest.mark.skipif(not REAL_RADAR.exists(), reason="../shared/real (the real recordings) is not beside the "
                                                    "repository")
def test_the_real_radars_site_monitor_is_on_the_ground():
    # the Mode 3/A 7777 site monitor of the Barcelona radar (address 344045, 899 plots) replies STAT 1
    import msdc.asterix as asterix

    frame = asterix.read(REAL_RADAR, date="2023-05-02", columns=DECODED_COLUMNS).frames[48]
    said = on_ground(frame, 48)
    monitor = (frame["address"] == "344045").to_numpy(bool)
    assert monitor.sum() == 899 and said[monitor].all()
    assert said.isna().sum() == 772  # the plots without I048/230 (Mode A/C only)
