"""Plain-data views of a CorrelationRun: the JSON summary and the fixed-width stdout table."""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Mapping
from numbers import Real
from typing import Any

import numpy as np
import pandas as pd

from msdc.pipeline.correlate.correlation import PAIR_KINDS, ROLE_NOUNS, pearson_search_limit
from msdc.pipeline.correlate.results import (
    MATCHED_KEYS,
    RADAR_KEYS,
    SUMMARY_KEYS,
    WINDOW_QUALITY_KEYS,
    CorrelationRun,
    WindowResult,
)
from msdc.pipeline.model.sources import kind_of_id
from msdc.pipeline.model.time import iso_utc
from msdc.pipeline.report.files import is_missing, json_value
from msdc.pipeline.report.formats import decimals

SKIPPED_KEYS = ["callsign", "address", "radar_sensor", "reference_sensor", "start_tod", "end_tod", "reason"]
# Parameter names (top level or under "options") that may hold the slot length in seconds
_SLOT_PARAMETER_KEYS = ("slot_s", "slot_seconds", "slot_duration_s", "slot_length_s", "slot_size_s")


def utc_naive(value: pd.Timestamp | dt.datetime | np.datetime64 | str) -> dt.datetime | None:
    """A UTC wall-clock datetime without tzinfo (naive input is taken as UTC); None when missing."""
    if is_missing(value):
        return None
    ts = pd.Timestamp(value)
    if ts.tzinfo is not None:
        ts = ts.tz_convert("UTC").tz_localize(None)
    return ts.round("us").to_pydatetime()


def table_records(frame: pd.DataFrame) -> list[dict[str, Any]]:
    """A table's rows as JSON values; datetime columns as ISO 8601 UTC to the millisecond (``iso_utc``,
    None where undated), as every time in the JSON."""
    times = {c for c, dtype in frame.dtypes.items() if dtype.kind == "M"}  # naive or tz-aware datetimes
    rows = frame.to_dict("records")
    for row in rows:
        for key, value in row.items():
            row[key] = iso_utc(value) if key in times else json_value(value)
    return rows


def window_summary(window: WindowResult) -> dict[str, Any]:
    """The window's summary restricted to SUMMARY_KEYS, in order, as JSON values (absent keys -> None),
    then ``note`` (``window_note``, None when there is nothing to say)."""
    summary = {key: json_value(window.summary.get(key)) for key in SUMMARY_KEYS}
    for key in ("start", "end"):  # ISO 8601 UTC to the millisecond, as every time in the JSON
        value = window.summary.get(key)
        if isinstance(value, pd.Timestamp | dt.datetime):
            summary[key] = iso_utc(value)
    summary["note"] = window_note(window.summary)
    return summary


# What a report leads with, and the thesis's measures that follow with their limits, one sentence each: the
# same words in the workbook's Summary, on the terminal and in the JSON's "summary"
LEAD_TITLE = "What each window shows"
LEAD_TEXT = ("every radar report against the reference's position at the report's own time (interpolated "
             "between the reference reports on either side), over the slots where both sensors reported, "
             "ADS-B position jumps left out: no slot mean and no filled slot is read")


KIND_WORDS = {kind: noun[:1].upper() + noun[1:] for kind, noun in ROLE_NOUNS.items()}  # "Surface radar"


def side_words(summary: Mapping[str, Any]) -> dict[str, str]:
    """What a window's two sides are, by the kind their sensor ids imply ("radar": the sensor correlated,
    "adsb": its reference; ADS-B ground stations joined by "+"): "Surface radar" and "Multilateration" for
    --pairs smr-mlat, "Radar" for a second radar; the role's own word where the ids do not say."""
    words = {}
    for side, key in (("radar", "radar_sensor"), ("adsb", "reference_sensor")):
        ids = str(summary.get(key) or "")
        kinds = {kind_of_id(s) for s in ids.split("+")} if ids else set()
        kind = kinds.pop() if len(kinds) == 1 and None not in kinds else side
        words[side] = KIND_WORDS[kind]
    return words


def pair_nouns(pairs: str | None) -> tuple[str, str]:
    """The sensor correlated and its reference in words, by --pairs (radar against ADS-B by default; with a
    second radar as reference, both named)."""
    if pairs in ("radar-radar", "all"):
        return "radar", "the reference (ADS-B or the second radar)"
    tested, reference = PAIR_KINDS.get(pairs or "radar-adsb", ("radar", "adsb"))
    return ROLE_NOUNS[tested], ROLE_NOUNS[reference]


def map_nouns(pairs: str | None) -> tuple[str, str]:
    """The sensor drawn red on the map and the one drawn yellow: pair_nouns for --pairs mlat-adsb and
    smr-mlat; else radar and ADS-B (a radar-radar pair's second radar is red too)."""
    return pair_nouns(pairs) if pairs in ("mlat-adsb", "smr-mlat") else ("radar", "ADS-B")


def lead_text(run: CorrelationRun) -> str:
    """LEAD_TEXT in the words of the run's --pairs: "every multilateration report", and no ADS-B jumps
    where the reference is not ADS-B (a surface radar's is multilateration)."""
    tested, reference = PAIR_KINDS.get(run.parameters.get("pairs") or "radar-adsb", ("radar", "adsb"))
    text = LEAD_TEXT.replace("every radar report", f"every {ROLE_NOUNS[tested]} report")
    return text if reference == "adsb" else text.replace(", ADS-B position jumps left out", "")
RADARS_TITLE = "Radars against ADS-B over the run"
RADARS_TEXT = ("--quality: each radar's accuracy (RMS distance, range and azimuth error SD) and the biases "
               "fitted over every aircraft, with their standard errors (the Radar biases sheet)")
THESIS_TITLE = "The thesis's measures"
THESIS_TEXT = "kept as the thesis computes them; each with its limit"
THESIS_LIMITS: dict[str, tuple[str, str]] = {
    "counts": ("Thesis table 6.1: reports in the window before slotting, slots after",
               "'after' counts every slot, filled ones included: the window's length, not its reports"),
    "coefficients": ("Thesis table 6.2: r(0) by NCC, with Pearson and the peak lags",
                     "NCC keeps the mean, so r(0) is near 1 for any two nearby tracks, even kilometres "
                     "apart, and peaks at lag 0 whatever the clock; a Pearson peak lag is an estimate only "
                     "on a window that turns (withheld at the search limit or on a near-straight leg)"),
    "separation": ("Separation between the slot means, over the slots both sensors reported",
                   "it holds the slotting (two slot means describe the aircraft at different moments of a "
                   "slot: hundreds of metres between unbiased sensors) and, unless --drop-jumps, ADS-B "
                   "position jumps"),
}
LEAD_WINDOW_KEYS = ["callsign", "address", "window", "radar_sensor", "reference_sensor", "start", "end",
                    *MATCHED_KEYS, *WINDOW_QUALITY_KEYS, "verdict"]


def has_quality(run: CorrelationRun) -> bool:
    """Whether the run carries the quality step's numbers (--quality): its radars, or a window's."""
    return bool(run.radars) or any(not is_missing(w.summary.get("quality_reports")) for w in run.windows)


def lead_json(run: CorrelationRun) -> dict[str, Any]:
    """The JSON's "summary": what each window shows (LEAD_WINDOW_KEYS; without --quality its quality keys
    are left out), the radars' accuracy and biases (--quality), and the thesis's measures' limits."""
    summaries = [window_summary(w) for w in run.windows]
    keys = [k for k in LEAD_WINDOW_KEYS if k not in WINDOW_QUALITY_KEYS or has_quality(run)]
    return {"about": f"{LEAD_TITLE}: {lead_text(run)}",
            "windows": [{k: s.get(k) for k in keys} for s in summaries],
            "radars": [{k: json_value(r.get(k)) for k in RADAR_KEYS} for r in run.radars],
            "thesis_measures": {name: f"{title}: {limit}" for name, (title, limit) in THESIS_LIMITS.items()}}


def run_to_json(run: CorrelationRun) -> dict[str, Any]:
    """The run as a JSON-ready dict: the summary it leads with (lead_json), then windows, skipped windows,
    parameters, inputs and filters."""
    return {
        "summary": lead_json(run),
        "windows": [window_summary(w) for w in run.windows],
        "skipped": [{key: json_value(getattr(s, key)) for key in SKIPPED_KEYS} for s in run.skipped],
        "parameters": json_value(run.parameters),
        "inputs": json_value(run.inputs),
        "filters": json_value(run.filters),
    }


def slot_seconds(window: WindowResult, parameters: Mapping[str, Any] | None = None) -> float:
    """Slot length in seconds: from the slots' time_of_day spacing, else from the parameters, else NaN."""
    slots = window.slots
    if {"slot", "time_of_day"} <= set(slots.columns) and len(slots) > 1:
        slot = pd.to_numeric(slots["slot"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        tod = pd.to_numeric(slots["time_of_day"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        ok = np.isfinite(slot) & np.isfinite(tod)
        dslot, dtod = np.diff(slot[ok]), np.diff(tod[ok])
        step = dtod[dslot != 0] / dslot[dslot != 0]
        step = step[np.isfinite(step) & (step > 0)]
        if step.size:
            return float(np.median(step))
    for source in (parameters or {}, (parameters or {}).get("options") or {}):
        for key in _SLOT_PARAMETER_KEYS:
            value = source.get(key) if isinstance(source, Mapping) else None
            if isinstance(value, Real) and not isinstance(value, bool) and value > 0:
                return float(value)
    return math.nan


def printable(text: Any) -> str:
    """``text`` as one printable line: control characters escaped, missing values empty."""
    if is_missing(text):
        return ""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in str(text))


def aircraft_name(summary: Mapping[str, Any], none: str = "?") -> str:
    """Who a window or skipped window is of, as people name it: its call sign, else its address."""
    return printable(summary.get("callsign")) or printable(summary.get("address")) or none


def sensor_pair(summary: Mapping[str, Any]) -> str:
    """A window's sensors as "radar vs reference" (``048:25/201 vs 021:0/1``); "" when it names none."""
    radar, reference = printable(summary.get("radar_sensor")), printable(summary.get("reference_sensor"))
    return f"{radar or '-'} vs {reference or '-'}" if radar or reference else ""


def window_label(summary: Mapping[str, Any]) -> str:
    """A window as people read it: call sign (else address), number and sensor pair, e.g. ``TST0000 window 1
    (048:25/201 vs 021:0/1)``: window numbers restart for every sensor pair of an aircraft."""
    who = aircraft_name(summary)
    pair = sensor_pair(summary)
    return f"{who} window {printable(summary.get('window'))}" + (f" ({pair})" if pair else "")


SEP_SLOTS_TEXT = "sep: separations over the slots where both sensors reported (filled slots left out)"
SEP_DOMINATED_RATIO = 3.0  # sep_rms above this many times the median separation: a few slots dominate it


def window_note(summary: Mapping[str, Any]) -> str | None:
    """Plain-language notes on a window, "; "-joined, else None: its RMS separation is dominated by a few
    slots (``sep_rms_m > SEP_DOMINATED_RATIO * sep_median_m``; the ADS-B jumps found, the usual cause, and
    the option that removes them), a Pearson peak at the search limit or not identified (no lag estimate:
    correlation.lag_identifiable), or Pearson peak lags read in a window with ADS-B jumps (a jump leaving
    the overlap moves the peak)."""
    notes = window_notes(summary)
    return "; ".join(notes) if notes else None


def window_notes(summary: Mapping[str, Any]) -> list[str]:
    """window_note's notes one by one (the Summary sheet gives each its own row)."""
    return [n for n in (_separation_note(summary), *_pearson_notes(summary)) if n]


def _jumps(summary: Mapping[str, Any]) -> int:
    jumps = summary.get("adsb_jumps")
    return 0 if is_missing(jumps) else int(jumps)


def _separation_note(summary: Mapping[str, Any]) -> str | None:
    rms, median = summary.get("sep_rms_m"), summary.get("sep_median_m")
    if is_missing(rms) or is_missing(median) or not rms > SEP_DOMINATED_RATIO * median:
        return None
    head = f"sep RMS {float(rms):.1f} m > {SEP_DOMINATED_RATIO:g} x median {float(median):.1f} m"
    jumps = _jumps(summary)
    if jumps > 0:
        plural = "s" if jumps != 1 else ""
        return f"{jumps} ADS-B position jump{plural} in this window; rerun with --drop-jumps ({head})"
    return f"a few slots dominate the separation ({head}); see sep_m in the Slots sheet"


def _pearson_notes(summary: Mapping[str, Any]) -> list[str]:
    at_limit = [name for axis, name in (("lat", "latitude"), ("lon", "longitude"))
                if summary.get(f"pearson_peak_at_limit_{axis}") is True]
    notes = []
    if at_limit:
        slots = summary.get("slots")
        edge = f" |lag| = {pearson_search_limit(int(slots))}" if isinstance(slots, Real) else ""
        notes.append(f"Pearson {' and '.join(at_limit)} peak at the edge of the lags searched{edge}: "
                     "no lag estimate")
    flat = [name for axis, name in (("lat", "latitude"), ("lon", "longitude"))
            if summary.get(f"pearson_lag_unidentified_{axis}") is True]
    if flat:
        notes.append(f"Pearson {' and '.join(flat)} peak lag not identified: the window is too close to a "
                     "straight, constant-speed leg, where a time shift is a constant offset that Pearson "
                     "removes (no lag estimate)")
    lags = [(axis, summary.get(f"pearson_peak_lag_{axis}")) for axis in ("lat", "lon")]
    moved = [f"{axis} {int(lag):+d}" for axis, lag in lags if not is_missing(lag) and int(lag) != 0]
    if moved and _jumps(summary) > 0:
        notes.append(f"Pearson peak lags ({', '.join(moved)}) in a window with ADS-B position jumps: read "
                     "them after --drop-jumps")
    return notes


def clock_text(timestamp: Any, tod: Any, *, date: bool = True) -> str:
    """A window time for text output: UTC date-time (to the second) when the timestamp is known, else
    HH:MM:SS from the time of day (+Nd past the first day); "-" when neither is known."""
    try:
        moment = utc_naive(timestamp) if isinstance(timestamp, str | pd.Timestamp | dt.datetime) else None
    except (TypeError, ValueError):
        moment = None
    if moment is not None:
        return moment.strftime("%Y-%m-%d %H:%M:%S" if date else "%H:%M:%S")
    if is_missing(tod) or not isinstance(tod, Real) or not math.isfinite(float(tod)):
        return "-"
    days, rem = divmod(int(float(tod) // 1), 86400)
    text = f"{rem // 3600:02d}:{rem % 3600 // 60:02d}:{rem % 60:02d}"
    return text + (f"+{days}d" if days else "")


def _num(value: Any, key: str) -> str:
    if is_missing(value) or not isinstance(value, Real) or not math.isfinite(float(value)):
        return "-"
    return f"{float(value):.{decimals(key)}f}"


def _count(value: Any) -> str:
    return "-" if is_missing(value) or not isinstance(value, Real) else f"{int(value)}"


# (header, summary key or None for a computed cell, right-aligned)
_TABLE = [("call sign", "callsign", False), ("win", "window", True),
          ("sensors", "sensors", False), ("start (UTC)", "start", False),
          ("end", "end", False), ("slots", "slots", True), ("radar", "radar_before", True),
          ("ADS-B", "adsb_before", True), ("filled r/a", None, True), ("jumps", "adsb_jumps", True),
          ("NCC(0) lat", "ncc0_lat", True), ("NCC(0) lon", "ncc0_lon", True),
          ("Pearson(0) lat", "pearson0_lat", True), ("Pearson(0) lon", "pearson0_lon", True),
          ("sep median m", "sep_median_m", True), ("sep RMS m", "sep_rms_m", True)]


def _table_row(s: Mapping[str, Any]) -> list[str]:
    start = clock_text(s.get("start"), s.get("start_tod"))
    end_full = clock_text(s.get("end"), s.get("end_tod"))
    same_day = start[:10] == end_full[:10] and len(start) > 10 and len(end_full) > 10
    end = clock_text(s.get("end"), s.get("end_tod"), date=not same_day)
    cells = []
    for _, key, _ in _TABLE:
        if key is None:
            cells.append(f"{_count(s.get('radar_filled_slots'))}/{_count(s.get('adsb_filled_slots'))}")
        elif key == "callsign":
            cells.append(aircraft_name(s, "-"))
        elif key == "sensors":
            cells.append(sensor_pair(s) or "- vs -")
        elif key == "start":
            cells.append(start)
        elif key == "end":
            cells.append(end)
        elif decimals(key, 0) == 0:
            cells.append(_count(s.get(key)))
        else:
            cells.append(_num(s.get(key), key))
    return cells


def frame_text(frame: pd.DataFrame) -> str:
    """A DataFrame as terminal text, each number to the decimals of its unit (``formats.decimals``)."""
    shown = frame.copy()
    for name in shown.columns:
        column = shown[name]
        if pd.api.types.is_float_dtype(column.dtype):
            places = decimals(str(name))
            shown[name] = [("-" if is_missing(v) else f"{v:.{places}f}") for v in column.tolist()]
        elif column.isna().any():
            shown[name] = ["-" if is_missing(v) else v for v in column.tolist()]
    return shown.to_string(index=False)


def _fixed_width(header: list[str], rows: list[list[str]], right: list[bool]) -> list[str]:
    """A header, a rule and the rows, each column as wide as its widest cell."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(cells: list[str]) -> str:
        padded = (c.rjust(n) if r else c.ljust(n) for c, n, r in zip(cells, widths, right, strict=True))
        return "  ".join(padded)

    return [line(header), "  ".join("-" * n for n in widths), *(line(r) for r in rows)]


def _plus_minus(s: Mapping[str, Any], key: str, se_key: str) -> str:
    """A mean with its standard error, "-27.6 +- 19.8" ("-" when the mean is missing)."""
    mean = _num(s.get(key), key)
    se = _num(s.get(se_key), se_key)
    return mean if mean == "-" or se == "-" else f"{mean} +- {se}"


# the lead table: (header, cell of a window summary, right-aligned); with --quality the _QUALITY_TABLE too
_LEAD_TABLE = [
    ("call sign", lambda s: aircraft_name(s, "-"), False),
    ("win", lambda s: _count(s.get("window")), True),
    ("sensors", lambda s: sensor_pair(s) or "- vs -", False),
    ("start (UTC)", lambda s: clock_text(s.get("start"), s.get("start_tod")), False),
    ("reports", lambda s: _count(s.get("matched_reports")), True),
    ("median m", lambda s: _num(s.get("matched_sep_median_m"), "matched_sep_median_m"), True),
    ("RMS m", lambda s: _num(s.get("matched_sep_rms_m"), "matched_sep_rms_m"), True),
    ("p95 m", lambda s: _num(s.get("matched_sep_p95_m"), "matched_sep_p95_m"), True),
    ("along m (+- SE)", lambda s: _plus_minus(s, "matched_along_mean_m", "matched_along_se_m"), True),
    ("cross m (+- SE)", lambda s: _plus_minus(s, "matched_cross_mean_m", "matched_cross_se_m"), True),
    ("time offset s", lambda s: _num(s.get("matched_time_offset_s"), "matched_time_offset_s"), True),
]
_QUALITY_TABLE = [
    ("range error m", lambda s: _num(s.get("range_error_mean_m"), "range_error_mean_m"), True),
    ("range SD m", lambda s: _num(s.get("range_error_std_m"), "range_error_std_m"), True),
    ("azimuth error deg", lambda s: _num(s.get("azimuth_error_mean_deg"), "azimuth_error_mean_deg"), True),
    ("azimuth SD deg", lambda s: _num(s.get("azimuth_error_std_deg"), "azimuth_error_std_deg"), True),
]
_RADAR_TABLE = [
    ("radar", lambda r: printable(r.get("radar")) or "-", False),
    ("sensor", lambda r: printable(r.get("radar_sensor")) or "-", False),
    ("reports", lambda r: _count(r.get("n_reports")), True),
    ("RMS m", lambda r: _num(r.get("horizontal_error_rms_m"), "horizontal_error_rms_m"), True),
    ("range SD m", lambda r: _num(r.get("range_error_std_m"), "range_error_std_m"), True),
    ("azimuth SD deg", lambda r: _num(r.get("azimuth_error_std_deg"), "azimuth_error_std_deg"), True),
    ("range bias m", lambda r: _plus_minus(r, "range_bias_m", "range_bias_se_m"), True),
    ("gain ppm", lambda r: _plus_minus(r, "range_gain_ppm", "range_gain_se_ppm"), True),
    ("azimuth bias deg", lambda r: _plus_minus(r, "azimuth_bias_deg", "azimuth_bias_se_deg"), True),
    ("time bias s", lambda r: _plus_minus(r, "time_bias_s", "time_bias_se_s"), True),
]


def lead_table(run: CorrelationRun) -> list[str]:
    """The lines a run's terminal output leads with: what each window shows (with --quality the radar's
    errors in it), each window's verdict, and with --quality the radars' accuracy and biases."""
    if not run.windows:
        return []
    spec = _LEAD_TABLE + (_QUALITY_TABLE if has_quality(run) else [])
    lines = [f"{LEAD_TITLE}: {lead_text(run)}"]
    lines += _fixed_width([h for h, _, _ in spec], [[cell(w.summary) for _, cell, _ in spec]
                                                     for w in run.windows], [r for _, _, r in spec])
    lines += [f"Verdict: {window_label(w.summary)}: {printable(w.summary.get('verdict')) or '-'}"
              for w in run.windows]
    if run.radars:
        lines += ["", f"{RADARS_TITLE} ({RADARS_TEXT}):"]
        lines += _fixed_width([h for h, _, _ in _RADAR_TABLE], [[cell(r) for _, cell, _ in _RADAR_TABLE]
                                                                 for r in run.radars],
                              [r for _, _, r in _RADAR_TABLE])
        lines += [f"Note: {printable(r.get('radar'))}: {printable(r.get('note'))}" for r in run.radars
                  if printable(r.get("note"))]
    return [*lines, ""]


def thesis_limits() -> list[str]:
    """One line per thesis measure: what it is and its limit."""
    return [f"  {title}: {limit}" for title, limit in THESIS_LIMITS.values()]


def summary_table(run: CorrelationRun) -> str:
    """The run for the terminal: the lead (lead_table), then the thesis's measures as a fixed-width table,
    one line per window, their limits, the skipped windows and the windows' notes."""
    header = [h for h, _, _ in _TABLE]
    right = [r for _, _, r in _TABLE]
    rows = [_table_row(w.summary) for w in run.windows]
    lines = lead_table(run)
    if run.windows:
        lines.append(f"{THESIS_TITLE} ({THESIS_TEXT}):")
    lines += _fixed_width(header, rows, right)
    if run.windows:
        lines += thesis_limits()
    lines.append(f"{len(run.windows)} window(s) correlated, {len(run.skipped)} skipped")
    for skipped in run.skipped:
        who = aircraft_name(vars(skipped))
        pair = sensor_pair(vars(skipped))
        span = f"{clock_text(None, skipped.start_tod)}-{clock_text(None, skipped.end_tod)}"
        lines.append(f"  skipped {who}{f' ({pair})' if pair else ''} {span}: {printable(skipped.reason)}")
    if run.windows:
        lines.append(SEP_SLOTS_TEXT)
    notes = [(w, window_note(w.summary)) for w in run.windows]
    for w, note in notes:
        if note:
            lines.append(f"Note: {window_label(w.summary)}: {note}")
    return "\n".join(text.rstrip() for text in lines)
