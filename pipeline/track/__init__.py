"""Multi-sensor IMM tracking: fused, gap-filled, optionally smoothed tracks per aircraft.

`track(measurements)` runs one horizontal IMM (CV and coordinated turns, optionally CA) and a vertical
filter per aircraft over every sensor's reports in time order; `predict(state, horizon_s)` propagates an
IMM state without measurements; `radar_covariance` and `nacp_covariance` build measurement covariances.
The input schema is in `pipeline.track.tracker`.
"""

from .config import Mode, TrackerConfig, check_tpm, default_modes, parse_tpm
from .covariance import nacp_covariance, radar_covariance
from .frame import Plane
from .predict import predict
from .tracker import ImmState, TrackResult, track

__all__ = ["ImmState", "Mode", "Plane", "TrackResult", "TrackerConfig", "check_tpm", "default_modes",
           "nacp_covariance", "parse_tpm", "predict", "radar_covariance", "track"]
