"""Why radar accuracy and biases are empty: said in the sheets' note, the terminal and the run's notes,
never an empty table without a reason (no radar, no ADS-B or none left after the filters, no overlap in
time, no aircraft seen by both, no radar report inside an ADS-B segment short enough to interpolate)."""

from __future__ import annotations

import pandas as pd

from msdc.pipeline.model.time import utc_text

NEEDS_REFERENCE = ("the Radar accuracy and Radar biases sheets need a reference (ADS-B) and are empty; the "
                   "Quality, Update intervals and Gaps sheets come from the radar's own reports")


def _span(times: pd.Series) -> str:
    """First and last instant of a sensor's reports, as UTC text."""
    return f"{utc_text(times.min())} to {utc_text(times.max())}"


def no_comparison_reason(meas: pd.DataFrame, reference: pd.DataFrame, *, filtered: bool = False,
                         max_gap_s: float = 10.0) -> str:
    """Why no radar report of ``meas`` was compared with the ADS-B of ``reference`` (the same reports with
    the filters applied; ``filtered``: some filter was asked for); assumes none was."""
    kind = meas["sensor_kind"].astype(str).to_numpy()
    radar = meas[kind == "radar"]
    if radar.empty:
        return "no radar (CAT048) report to compare"
    is_adsb = (reference["sensor_kind"].astype(str) == "adsb").to_numpy(bool)
    adsb = reference[is_adsb]
    if adsb.empty:
        if filtered and (kind == "adsb").any():
            return f"the ADS-B filters removed every ADS-B report: {NEEDS_REFERENCE}"
        return f"no ADS-B report: {NEEDS_REFERENCE}"
    if radar["time"].max() < adsb["time"].min() or adsb["time"].max() < radar["time"].min():
        return (f"radar ({_span(radar['time'])}) and ADS-B ({_span(adsb['time'])}) never overlap in time: "
                f"{NEEDS_REFERENCE}")
    if "aircraft_id" in meas:
        both = set(radar["aircraft_id"].dropna()) & set(adsb["aircraft_id"].dropna())
        if not both:
            return f"no aircraft is seen by both radar and ADS-B: {NEEDS_REFERENCE}"
    return (f"no radar report falls between two ADS-B reports of its aircraft at most {max_gap_s:g} s apart "
            f"(ADS-B jumps and duplicates left out): {NEEDS_REFERENCE}")
