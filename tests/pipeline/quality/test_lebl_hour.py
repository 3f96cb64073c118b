"""The real LEBL hour (../shared/real): the multilateration's reference point offset measured by
reference_offsets (histogram peak of paired reports) against a different method written here (ADS-B
interpolated linearly to each multilateration report of the same address, the median difference), and the
surface radar's origin far from the airport reference point (docs/methods/lebl-hour.md)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import SHARED

import msdc.asterix as asterix
from msdc.pipeline.model.geodesy import ecef_to_enu, geodetic_to_ecef
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.quality.reference_offset import reference_offsets

REAL = SHARED / "real"
ARP = (41.2969, 2.0785)
pytestmark = [pytest.mark.validation, pytest.mark.skipif(
    not REAL.is_dir(), reason=f"{REAL} not present: real-recording cases skipped")]


def _sensors() -> pd.DataFrame:
    return pd.DataFrame({"name": ["MLAT", "SMR"], "sac": [0, 0], "sic": [107, 7], "latitude": [ARP[0]] * 2,
                         "longitude": [ARP[1]] * 2, "altitude_m": [53.0, 53.0], "category": [10, 10],
                         "kind": ["mlat", "smr"], "sigma_m": [3.0, 3.0], "sigma_range_m": np.nan,
                         "sigma_azimuth_deg": np.nan})


def _interpolated_offset(meas: pd.DataFrame) -> tuple[float, float]:
    """Median (east, north) of multilateration minus ADS-B interpolated to its time (ADS-B reports at most
    2 s apart around it), same address, below 50 kt."""
    def enu(f):
        e, n, _ = ecef_to_enu(*geodetic_to_ecef(f["latitude"].to_numpy(), f["longitude"].to_numpy(), 53.0),
                              ARP[0], ARP[1], 53.0)
        return e, n

    kinds = meas["sensor_kind"].astype(str)
    d_e, d_n = [], []
    for address, m in meas[(kinds == "mlat").to_numpy() & (meas["ground_speed_kt"] < 50).to_numpy()].groupby(
            meas["address"].astype(str), observed=True):
        a = meas[(kinds == "adsb").to_numpy() & (meas["address"].astype(str) == address).to_numpy()]
        a = a.sort_values("time")
        if len(a) < 2:
            continue
        ta, tm = a["time"].astype("int64").to_numpy() / 1e9, m["time"].astype("int64").to_numpy() / 1e9
        j = np.clip(np.searchsorted(ta, tm), 1, len(ta) - 1)
        ok = (tm >= ta[j - 1]) & (tm <= ta[j]) & (ta[j] - ta[j - 1] <= 2.0)
        w = (tm - ta[j - 1]) / np.maximum(ta[j] - ta[j - 1], 1e-9)
        ae, an = enu(a)
        me, mn = enu(m)
        d_e.append((me - (ae[j - 1] + w * (ae[j] - ae[j - 1])))[ok])
        d_n.append((mn - (an[j - 1] + w * (an[j] - an[j - 1])))[ok])
    return float(np.median(np.concatenate(d_e))), float(np.median(np.concatenate(d_n)))


def test_reference_points_of_the_real_hour():
    adsb = asterix.read(REAL / "adsb_v023_160510-lebl-220001.ast", editions={21: "0.23"}).frames[21]
    cat010 = pd.concat([asterix.read(REAL / n).frames[10] for n in ("mlat_160510-lebl-220001.ast",
                                                                    "smr_160510-lebl-220001.ast")],
                       ignore_index=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the 30 ADS-B positions off any station's reach
        meas = build_measurements(None, adsb, _sensors(), adsb_sigma_m=10.0, cat010=cat010, date="2016-05-10")
    table = reference_offsets(meas, _sensors()).set_index("sensor_id")
    mlat = table.loc["010:0/107:mlat"]
    east, north = _interpolated_offset(meas)
    assert (east, north) == pytest.approx((1.7, -19.3), abs=0.5)  # docs/methods/lebl-hour.md
    assert (mlat["east_offset_m"], mlat["north_offset_m"]) == pytest.approx((east, north), abs=0.5)
    smr = table.loc["010:0/7:smr"]
    # x/y from its own antenna, 1.39 km east of the airport reference point: its reports lie that far west
    assert smr["reference"] == "mlat" and smr["pairs"] > 5000
    assert np.hypot(smr["east_offset_m"], smr["north_offset_m"]) == pytest.approx(1400.0, abs=30.0)
