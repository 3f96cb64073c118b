"""The simulated fleet and injected radar biases shared by the bias-recovery tests: 12 aircraft for 40 min
at random ranges, azimuths, turns and levels."""

from __future__ import annotations

from fixtures.scenario import AircraftSpec

INJECTED = {"range_bias_m": 150.0, "range_gain_ppm": 200.0, "azimuth_bias_deg": 0.1, "time_bias_s": 1.0}
TOLERANCE = {"range_bias_m": 15.0, "range_gain_ppm": 50.0, "azimuth_bias_deg": 0.01, "time_bias_s": 0.1}
FLEET = tuple(AircraftSpec(f"TST{i}", 0x710000 + i, f"{i + 1:04o}", ((0.0, 2400.0),)) for i in range(12))
CASES = {"none": (), "range": ("range_bias_m",), "gain": ("range_gain_ppm",),
         "azimuth": ("azimuth_bias_deg",), "time": ("time_bias_s",), "all": tuple(INJECTED)}


def se_name(key: str) -> str:
    """The standard-error column of a bias column: range_bias_m -> range_bias_se_m."""
    stem, unit = key.rsplit("_", 1)
    return f"{stem}_se_{unit}"
