"""Argument checks of the quality library calls: a clear ValueError/TypeError naming the argument, the value
and the reason, before any work (never a deep pandas traceback or a silently empty or wrong table)."""

from __future__ import annotations

import pandas as pd

from msdc.pipeline.meta import REFERENCES  # what radar accuracy is measured against
from msdc.pipeline.model.arguments import finite_number


def check_frame(name: str, value: object, columns: tuple[str, ...] = ()) -> None:
    """``value`` is a DataFrame holding ``columns``."""
    if not isinstance(value, pd.DataFrame):
        raise TypeError(f"{name}: expected a pandas DataFrame, got {type(value).__name__}")
    missing = [c for c in columns if c not in value]
    if missing:
        raise ValueError(f"{name}: lacks the column(s) {', '.join(missing)}")


def check_reference(reference: object) -> None:
    """``reference`` names a reference radar accuracy can be measured against."""
    if not isinstance(reference, str) or reference not in REFERENCES:
        raise ValueError(f"reference: {reference!r} is not one of {', '.join(map(repr, REFERENCES))}")


def check_seconds(name: str, value: object) -> None:
    """``value`` is a finite, positive number of seconds (model.arguments.finite_number)."""
    finite_number(name, value)


def check_options(name: str, value: object) -> None:
    """``value`` is None or a dict of keyword arguments."""
    if value is not None and not isinstance(value, dict):
        raise TypeError(f"{name}: expected a dict of keyword arguments or None, got {type(value).__name__}")


def check_indicator(name: str, value: object, high: int = 15) -> None:
    """``value`` is None or a whole number 0..high (an ADS-B quality indicator's minimum)."""
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{name}: expected a whole number 0 to {high} or None, got {value!r}")
    if not 0 <= value <= high:
        raise ValueError(f"{name}: {value} is outside 0 to {high}")


def check_sensors(sensors: object, meas: pd.DataFrame) -> None:
    """``sensors`` is the sensor table, or None when ``meas`` holds no radar report (ADS-B alone)."""
    if sensors is None and not (meas["sensor_kind"] == "radar").any():
        return
    if not isinstance(sensors, pd.DataFrame):
        raise TypeError(f"sensors: expected the sensor table (a DataFrame, pipeline.model.sensors) for the "
                        f"radar reports, got {type(sensors).__name__}")
