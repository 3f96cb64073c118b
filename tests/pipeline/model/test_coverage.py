"""ADS-B reports outside any ground station's reach are left out of the measurements, with a warning."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
from asterix_bytes import decode_bytes
from pyproj import Geod

import msdc.asterix as asterix
from fixtures.real_track_data import REAL
from msdc.asterix.encode import encode_frame
from msdc.pipeline.model.coverage import out_of_coverage
from msdc.pipeline.model.jumps import detect_jumps
from msdc.pipeline.model.measurements import OutOfCoverageWarning, build_measurements

GEOD = Geod(ellps="WGS84")
SITE = (41.30, 2.08)


def _around(rng, n, lat0, lon0, max_nm):
    """n positions at uniform bearings and distances up to max_nm from (lat0, lon0), by pyproj."""
    lon, lat, _ = GEOD.fwd(np.full(n, lon0), np.full(n, lat0), rng.uniform(0, 360, n),
                           rng.uniform(0, max_nm, n) * 1852.0)
    return lat, lon


def _cat021(lat, lon, address, sic=7, t0=30000.0):
    n = len(lat)
    return pd.DataFrame({"sac": 0, "sic": sic, "time_of_day": t0 + np.arange(n) * 1.0, "latitude": lat,
                         "longitude": lon, "address": address, "flight_level": 300.0, "nacp": 8})


def _measure(frames):
    data = b"".join(encode_frame(21, f) for f in frames)
    return build_measurements(None, decode_bytes(data).frames[21], date="2019-03-01")


def test_reports_beyond_reach_are_left_out_and_said():
    rng = np.random.default_rng(5)
    lat, lon = _around(rng, 400, *SITE, 150.0)
    near = _cat021(lat, lon, [f"4CA{i % 8:03d}" for i in range(400)])
    # one aircraft: three reports 1200 NM away (a wrong CPR zone), then three near the station
    lon_far, lat_far, _ = GEOD.fwd([SITE[1]] * 3, [SITE[0]] * 3, [200.0] * 3, [1200 * 1852.0] * 3)
    lat_ok, lon_ok = _around(rng, 3, *SITE, 60.0)
    odd = _cat021(np.r_[lat_far, lat_ok], np.r_[lon_far, lon_ok], "06414F", t0=31000.0)
    with pytest.warns(OutOfCoverageWarning, match="3 report"):
        meas = _measure([near, odd])
    assert len(meas) == 403  # 406 less the 3 far ones
    kept = meas[meas["address"] == "06414F"]
    np.testing.assert_allclose(kept["latitude"], lat_ok, atol=1e-4)
    (text,) = meas.attrs["coverage_warnings"]
    # the median of the 400 near reports is within a few NM of the station: 1200 NM give or take them
    found = re.match(r"ADS-B 021:0/7: 3 report\(s\) of 1 aircraft lie (\d+)(?:-(\d+))? NM .*beyond 500 NM",
                     text)
    assert found and all(1180 <= int(v) <= 1220 for v in found.groups() if v)


def test_a_network_source_keeps_its_whole_coverage():
    # one source spread over 1500 NM (a network fed as one SAC/SIC): its 99th percentile spreads the limit
    rng = np.random.default_rng(6)
    lat, lon = _around(rng, 500, -25.0, 134.0, 1500.0)
    meas = _measure([_cat021(lat, lon, [f"7C{i % 20:04d}" for i in range(500)], sic=9)])
    assert len(meas) == 500 and "coverage_warnings" not in meas.attrs
    far, table = out_of_coverage(meas)
    assert not far.any() and table.empty


@pytest.mark.skipif(not REAL.exists(), reason="../shared/real is not beside the checkout")
def test_real_recording_far_positions_and_jumps():
    cat021 = asterix.read(REAL, editions={21: "0.23"}, date="2016-05-10").frames[21]
    # independently: distances from the median position with pyproj
    lat0, lon0 = np.median(cat021["latitude"]), np.median(cat021["longitude"])
    _, _, d = GEOD.inv(np.full(len(cat021), lon0), np.full(len(cat021), lat0), cat021["longitude"],
                       cat021["latitude"])
    expected_far = int((d / 1852.0 > 500.0).sum())
    with pytest.warns(OutOfCoverageWarning):
        meas = build_measurements(None, cat021, adsb_sigma_m=30.0)
    assert expected_far == 30 and len(meas) == len(cat021) - expected_far
    # ARA102 (06414F): 6 reports about 1066 NM away, then 5 about 75 NM from the station: the 5 are kept and
    # none is a jump any more (before, the far six were taken as the track and the good five as jumps)
    ara = meas[meas["address"] == "06414F"]
    assert len(ara) == 5 and ara["latitude"].between(41.0, 41.3).all()
    assert not detect_jumps(meas)[ara.index].any()


def test_a_job_that_builds_some_columns_names_the_file_and_offset(tmp_path):
    # quality builds only quality.quality_columns (no file, no offset); its warning still names the first far
    # report's file and byte offset, as one built with every column does, and the two columns go after it
    from msdc.pipeline.jobs import quality
    from msdc.pipeline.model.load import load_measurements

    rng = np.random.default_rng(5)
    lat, lon = _around(rng, 400, *SITE, 150.0)
    near = _cat021(lat, lon, [f"4CA{i % 8:03d}" for i in range(400)])
    lon_far, lat_far, _ = GEOD.fwd([SITE[1]] * 3, [SITE[0]] * 3, [200.0] * 3, [1200 * 1852.0] * 3)
    odd = _cat021(lat_far, lon_far, "06414F", t0=31000.0)
    data = b"".join(encode_frame(21, f) for f in (near, odd))
    path = tmp_path / "far.ast"
    path.write_bytes(data)
    first_far = int(decode_bytes(data).frames[21]["offset"].iloc[400])  # the decoder's own byte offset
    columns = quality.quality_columns(quality.QualityOptions(inputs=(str(path),), all_aircraft=True))
    assert not {"file", "offset"} & set(columns)
    _, meas = load_measurements([path], None, date="2019-03-01", columns=columns, either=True)  # job warns
    (text,) = meas.attrs["coverage_warnings"]
    assert f"the first: far.ast, offset {first_far}, latitude" in text
    assert list(meas.columns) == columns and len(meas) == 400
