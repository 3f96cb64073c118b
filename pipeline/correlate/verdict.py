"""A window's verdict: one line saying what its matched numbers (pipeline.correlate.matched) show.

It says only what they support: a mean offset along or across track is named when it stands more than
OFFSET_SE standard errors out of the noise (that of the window's own reports), with its size and, along
track, the seconds of flight it amounts to; not its cause, which one window cannot tell (a time-stamp
error and a range or azimuth bias both move plots along track; the bias fit of --quality, over every
aircraft, tells them apart: the verdict points there). Otherwise the window shows no systematic offset,
and the distance is the two sensors' noise together, unless its RMS is past NOISE_RMS_LIMIT_M, which no
sensor's noise reaches: then an error that changes along the flight (a wrong site, a bias seen from a
turning flight) is said instead. A window with fewer than MIN_MATCHED_REPORTS matched reports gets no
verdict, only the count.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from msdc.pipeline.correlate.matched import MIN_SPEED_MS

MIN_MATCHED_REPORTS = 10
CAUSES = "a time-stamp, range or azimuth error: the radar's biases (--quality) tell which"
# a multilateration system or surface radar under test: --quality fits no biases of its (CAT048 radars only)
OTHER_CAUSES = ("a time-stamp or position error of either sensor (--quality fits biases for CAT048 radars "
                "only)")
RADAR_PREFIX = "048:"  # the sensor ids of CAT048 radars
OFFSET_SE = 3.0  # a mean offset is named past this many standard errors (0.3 % of noise-only windows)
# an RMS distance past this is no sensor's noise: four times the loosest horizontal RMS a standard asks of a
# sensor (ESASSP Annex D R3, 500 m for 5 NM separation, primary radar)
NOISE_RMS_LIMIT_M = 2000.0
CHANGING = ("an error that changes along the flight, such as a wrong sensor site or a bias seen from a "
            "turning flight")


def _number(summary: Mapping[str, Any], key: str) -> float:
    value = summary.get(key)
    try:
        number = float(value)
    except (TypeError, ValueError):
        return math.nan
    return number


def _metres(value: float) -> str:
    return f"{value:,.0f} m"


def _stands_out(mean: float, se: float) -> bool:
    return math.isfinite(mean) and math.isfinite(se) and abs(mean) > OFFSET_SE * se


def window_verdict(summary: Mapping[str, Any], reference: str = "ADS-B", tested: str = RADAR_PREFIX) -> str:
    """The verdict of a window from its summary's matched keys; ``reference`` names the reference sensor
    in the text ("ADS-B", or the other radar's id), ``tested`` is the tested sensor's id (a CAT048 radar's
    offsets point to its bias fit; another kind's do not)."""
    radar = tested.startswith(RADAR_PREFIX)
    n = int(_number(summary, "matched_reports")) if math.isfinite(_number(summary, "matched_reports")) else 0
    if n < MIN_MATCHED_REPORTS:
        reports = f"report{'s' if n != 1 else ''}"
        who = f"radar {reports}" if radar else f"{reports} of {tested}"
        return (f"no verdict: {n} {who} matched to {reference} at their own time (at least "
                f"{MIN_MATCHED_REPORTS} needed)")
    along, along_se = _number(summary, "matched_along_mean_m"), _number(summary, "matched_along_se_m")
    cross, cross_se = _number(summary, "matched_cross_mean_m"), _number(summary, "matched_cross_se_m")
    offsets = []
    if _stands_out(along, along_se):
        where = "behind" if along < 0 else "ahead of"
        text = f"{_metres(abs(along))} {where} {reference} along track"
        offset_s = _number(summary, "matched_time_offset_s")
        if math.isfinite(offset_s):
            text += f" ({abs(offset_s):.1f} s of flight)"
        offsets.append(text)
    if _stands_out(cross, cross_se):
        offsets.append(f"{_metres(abs(cross))} {'right' if cross > 0 else 'left'} of the {reference} track")
    head = "systematic offset: " + "; ".join(offsets) if offsets else "no systematic offset beyond the noise"
    if not offsets and not (math.isfinite(along_se) or math.isfinite(cross_se)):  # nothing was tested
        head = (f"offsets not judged (too few reports moving faster than {MIN_SPEED_MS:g} m/s for a "
                "direction of travel)")
    rms = _number(summary, "matched_sep_rms_m")
    beyond = not offsets and math.isfinite(rms) and rms > NOISE_RMS_LIMIT_M
    if beyond and (math.isfinite(along_se) or math.isfinite(cross_se)):
        head = "no constant offset along or across track"
    text = f"{head}; {_metres(rms)} RMS from {reference} over {n} reports"
    if beyond:
        text += (f", far beyond any sensor's noise (past {_metres(NOISE_RMS_LIMIT_M)}): {CHANGING}; "
                 f"{'the radar' if radar else 'either sensor'}'s site and biases are to be checked"
                 f"{' (--quality fits the biases)' if radar else ''}")
    if offsets:
        text += f"; {CAUSES if radar else OTHER_CAUSES}"
    jumps = _number(summary, "adsb_jumps")
    if reference == "ADS-B" and math.isfinite(jumps) and jumps > 0:
        text += f"; {int(jumps):,} ADS-B position jump{'s' if jumps != 1 else ''} left out"
    return text


def mention_mixed(summaries: list[dict], mixed) -> int:
    """Append to the verdict of each window whose aircraft (its address, else ``CS:`` call sign) is, on one
    of the window's two sensors, in ``mixed`` (pairs of aircraft_id and sensor_id as text:
    pipeline.model.mixed.mixed_pairs) that two targets may share the identity there; in place. Returns how
    many were."""
    pairs = set(mixed)
    if not pairs:
        return 0
    said = 0
    for summary in summaries:
        ident = summary.get("address") or (f"CS:{summary['callsign']}" if summary.get("callsign") else None)
        sensors = [s for s in (summary.get("radar_sensor"), summary.get("reference_sensor"))
                   if (str(ident), str(s)) in pairs]
        if ident and sensors and summary.get("verdict"):
            where = " and ".join(map(str, sensors))
            summary["verdict"] += (f"; two targets may share this identity on {where} (its reports switch "
                                   "between two places): these numbers mix both")
            said += 1
    return said
