"""ADS-B reports outside any ground station's reach: positions thousands of NM from the rest of their source's
reports (a wrongly decoded CPR position at the station; the real LEBL recording has 30 such, up to 7300 NM
away). They are left out of the measurements before identity and jump detection see them: an aircraft whose
first reports lie 2000 km away would otherwise make its good reports look like the jumps.

The rule is deliberately loose, so that it cannot cut a real network's coverage: per ADS-B source, the
reports farther from the source's median position than COVERAGE_FACTOR times the 99th percentile of those
distances, and farther than COVERAGE_MIN_NM. A ground station hears to its radio horizon, about 250 NM at
FL450; a network fed as one source spreads its 99th percentile with its coverage.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import great_circle_nm
from msdc.pipeline.model.schema import equals_text

COVERAGE_MIN_NM = 500.0  # twice a ground station's radio horizon at FL450
COVERAGE_FACTOR = 3.0  # times the source's 99th percentile distance from its median position
COVERAGE_COLUMNS = ["sensor_id", "file", "offset", "address", "callsign", "latitude", "longitude",
                    "distance_nm", "limit_nm"]


def out_of_coverage(meas: pd.DataFrame) -> tuple[np.ndarray, pd.DataFrame]:
    """Which rows are ADS-B reports outside their source's coverage (see the module docstring), and those
    rows as a table (COVERAGE_COLUMNS; distance_nm from the source's median position, limit_nm the rule's)."""
    far = np.zeros(len(meas), bool)
    if not len(meas) or not {"sensor_kind", "sensor_id", "latitude", "longitude"} <= set(meas):
        return far, pd.DataFrame(columns=COVERAGE_COLUMNS)
    adsb = equals_text(meas["sensor_kind"], "adsb")  # by codes: no text per row (2.5 M rows a window)
    lat = meas["latitude"].to_numpy(float)
    lon = meas["longitude"].to_numpy(float)
    dist_nm = np.full(len(meas), np.nan)
    limit_nm = np.full(len(meas), np.nan)
    sources, _ = pd.factorize(meas["sensor_id"])
    for source in np.unique(sources[adsb & (sources >= 0)]):
        rows = np.flatnonzero(adsb & (sources == source) & np.isfinite(lat) & np.isfinite(lon))
        if not len(rows):
            continue
        d = great_circle_nm(np.median(lat[rows]), np.median(lon[rows]), lat[rows], lon[rows])
        limit = max(COVERAGE_MIN_NM, COVERAGE_FACTOR * float(np.percentile(d, 99)))
        dist_nm[rows], limit_nm[rows] = d, limit
        far[rows[d > limit]] = True
    table = meas.loc[far, [c for c in COVERAGE_COLUMNS[:-2] if c in meas]].copy()
    table["distance_nm"], table["limit_nm"] = dist_nm[far], limit_nm[far]
    return far, table.reset_index(drop=True)


def coverage_warnings(table: pd.DataFrame | None) -> list[str]:
    """One warning per ADS-B source with reports left out as outside its coverage: how many, of how many
    aircraft, and the first one."""
    if table is None or not len(table):
        return []
    out = []
    for source, rows in table.groupby(table["sensor_id"].astype(str), sort=False):
        first = rows.iloc[0]
        places = (("file", ""), ("offset", "offset "))
        where = "".join(f"{label}{first[c]}, " for c, label in places if c in rows and pd.notna(first[c]))
        aircraft = rows["address"].dropna().astype(str).nunique() if "address" in rows else 0
        lo, hi = f"{rows['distance_nm'].min():.0f}", f"{rows['distance_nm'].max():.0f}"
        span = lo if lo == hi else f"{lo}-{hi}"
        out.append(f"ADS-B {source}: {len(rows)} report(s) of {aircraft} aircraft lie {span} NM "
                   f"from the median position of the source's reports (beyond "
                   f"{first['limit_nm']:.0f} NM, out of any ground station's reach: a position the "
                   f"ground station or the aircraft got wrong, as the bytes say), left out of the "
                   f"measurements; the first: {where}latitude "
                   f"{first['latitude']:.4f}, longitude {first['longitude']:.4f}")
    return out
