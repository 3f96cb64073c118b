"""The requirement functions by catalogue id, each f(reports, reference, parameters, sensor) -> Outcome, and
the test reports of a radar in the schema they take."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.accuracy import ACCURACY_REQUIREMENTS
from msdc.pipeline.evaluate.biases import BIAS_REQUIREMENTS
from msdc.pipeline.evaluate.coasting import coasting_correct
from msdc.pipeline.evaluate.codes import CODE_REQUIREMENTS
from msdc.pipeline.evaluate.combination import psr_ssr_association
from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.detection import long_gaps, pd_requirement
from msdc.pipeline.evaluate.dubious import dubious
from msdc.pipeline.evaluate.identification import identification_correct, identification_false
from msdc.pipeline.evaluate.plots import (
    false_reports,
    false_reports_per_scan,
    multiple_reports,
    split_reports,
)
from msdc.pipeline.evaluate.tracks import extra_tracks, track_continuity
from msdc.pipeline.evaluate.velocity import velocity_correct
from msdc.pipeline.model.geodesy import flight_level_to_m, polar_to_geodetic

DAY_S = 86400.0

REQUIREMENTS = {
    "pd": pd_requirement,
    "long_gaps": long_gaps,
    **CODE_REQUIREMENTS,
    "false_reports": false_reports,
    "false_reports_per_scan": false_reports_per_scan,
    "split_reports": split_reports,
    "multiple_reports": multiple_reports,
    "dubious": dubious,
    "identification_correct": identification_correct,
    "identification_false": identification_false,
    "velocity_correct": velocity_correct,
    "extra_tracks": extra_tracks,
    "track_continuity": track_continuity,
    **ACCURACY_REQUIREMENTS,
    **BIAS_REQUIREMENTS,
    "psr_ssr_association": psr_ssr_association,
    "coasting_correct": coasting_correct,
}


def radar_reports(frame: pd.DataFrame, sensor: Sensor) -> pd.DataFrame:
    """A CAT048 frame as test reports: ``t_s`` (day * 86400 + time_of_day when the frame has a day column,
    else time_of_day) and the plot's latitude and longitude from slant range, azimuth and Mode C height
    (on the site's horizontal plane where there is none), seen from the sensor's declared site."""
    for col in ("time_of_day", "rho_nm", "theta_deg"):
        if col not in frame.columns:
            raise ValueError(f"the radar frame lacks the column {col}")
    out = frame.copy()
    day = out["day"].to_numpy(float) if "day" in out.columns else 0.0
    out["t_s"] = out["time_of_day"].to_numpy(float) + DAY_S * day
    fl = pd.to_numeric(out["flight_level"], errors="coerce").to_numpy(float) if "flight_level" in out \
        else np.full(len(out), np.nan)
    lat, lon, _ = polar_to_geodetic(sensor.latitude, sensor.longitude, sensor.altitude_m,
                                    out["rho_nm"].to_numpy(float), out["theta_deg"].to_numpy(float),
                                    flight_level_to_m(fl))
    out["latitude"], out["longitude"] = lat, lon
    return out
