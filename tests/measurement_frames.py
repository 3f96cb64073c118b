"""Hand-made measurement frames for tests: old-style columns (seconds in ``time_of_day``) to the schema."""

from __future__ import annotations

import pandas as pd

from msdc.pipeline.model.identity import assign_aircraft_id
from msdc.pipeline.model.measurements import sensor_id
from msdc.pipeline.model.schema import conform, validate
from msdc.pipeline.model.time import UNDATED_DAY


def meas_frame(frame: pd.DataFrame, kind: str | None = None, day: str | None = None) -> pd.DataFrame:
    """A valid measurement frame from ``frame`` (``time_of_day`` seconds after ``day``, undated if None;
    ``sensor`` or ``kind`` the sensor kind); the input's other columns are kept after the schema's."""
    f = frame.reset_index(drop=True)
    if "time" not in f:
        base = UNDATED_DAY if day is None else pd.Timestamp(day, tz="UTC")
        f = f.assign(time=base + pd.to_timedelta(f["time_of_day"].to_numpy(float), unit="s"))
    if "sensor_kind" not in f:
        f = f.assign(sensor_kind=f["sensor"] if "sensor" in f else kind)
    if "sensor_id" not in f:
        cat = f["sensor_kind"].map({"radar": 48, "adsb": 21})
        sac = f["sac"] if "sac" in f else pd.Series(0, index=f.index)
        sic = f["sic"] if "sic" in f else pd.Series(0, index=f.index)
        ids = pd.Series(None, index=f.index, dtype=object)
        for c in cat.dropna().unique():  # one call per category: per row it took 7 s for 2,000 reports
            rows = (cat == c).to_numpy(bool)
            ids[rows] = sensor_id(int(c), sac[rows].to_numpy(), sic[rows].to_numpy()).astype(str).to_numpy()
        f = f.assign(sensor_id=ids)
    out = conform(f)
    out["aircraft_id"] = assign_aircraft_id(out)
    extra = f[[c for c in f.columns if c not in out.columns]]
    return validate(pd.concat([out, extra], axis=1))
