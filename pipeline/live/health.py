"""The live monitor's figures and alarms, as pure functions of what the live state gives (the reports of a
recent window, the feeds' counters, the last status message per sensor) and the wall-clock time.

The probability of update and the Mode 3/A / Mode C validity are the evaluation's own requirement functions
(msdc.pipeline.evaluate) run on the window's reports. A live window has no reference trajectory, so each
sensor track is its own reference: its updates are expected one per measured update period from its first
to its last report in the window, and a gap of g holds round(g / T) - 1 missed updates. A figure whose
sample is too small is withheld (``value`` None and a ``note`` saying why), never printed as fact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.codes import CODE_REQUIREMENTS
from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.detection import pd_requirement
from msdc.pipeline.evaluate.outcome import Outcome, withheld
from msdc.pipeline.evaluate.scans import MIN_DIFFS, period_from_plots
from msdc.pipeline.live.monitor import Thresholds
from msdc.pipeline.live.state import waiting_datagrams
from msdc.pipeline.model.coverage import out_of_coverage
from msdc.pipeline.model.sources import kind_of_id

SCHEMA = "msdc-live-monitor/1"  # the JSON snapshot's version (docs/guide/live-monitor.md)
MIN_UPDATES = 10  # expected updates in the window below which the live probability of update is withheld
MIN_CODES = 10  # reports carrying a code in the window below which its validity is withheld
MIN_RATE_WINDOW_S = 1.0  # a report rate over less than this much wall-clock time is withheld
STALE_PERIODS = 3.0  # a target not updated for this many update periods is drawn as stale
DEFAULT_STALE_S = 15.0  # ... or for this long when its sensor's update period is not known
TRAIL_POINTS = 60  # the most positions kept per target trail (the latest ones)
MAX_TARGETS = 3000  # the most targets sent to the page (the most recently updated ones)
# A sensor's live figures (update interval, probability of update, code validity) are measured on the
# reports of at most this many of its window's reports: beyond it, on whole tracks taken in a fixed order
# (by a hash of their key, so a track stays in the sample while it is in the window) until the next would
# pass it. Keeps a snapshot under a second at a busy centre's rate (840,000 reports in a 120 s window).
MAX_FIGURE_REPORTS = 5000
# a figure measured on a sample of whole tracks: its interval treats the reports as independent, so no
# verdict and no alarm (a fixed sample of the LEBL surface radar's tracks read 95.4 % [94.8-96.0] and
# raised "degraded" where the whole window gave 96.95 % [96.56-97.30])
SAMPLE_NOTE = ("measured on {tracks} of {of_tracks} tracks ({reports:,} of {of_reports:,} reports): no "
               "verdict or alarm on a sample")
# categories of status messages (north markers, sector crossings, service status): their senders are not
# sensors of target reports, their times come through status_times
STATUS_CATEGORIES = frozenset({"002", "019", "023", "025", "034", "063", "065"})
# why an ADS-B sensor's probability of update is shown, not judged against min_pd
ADSB_PD_NOTE = ("ADS-B reports follow the squitters received, not periodic updates: the share of updates "
                "at the measured interval, not judged against the radar threshold (no ADS-B standard here "
                "sets one)")
# categories of reports whose records are counted and dated by arrival but make no measurement rows live
# (pipeline.live.decode.MEASURED), with what they are
COUNTED_ONLY = {"001": "monoradar plots and tracks: their time of day needs the radar's CAT002",
                "062": "system tracks, which msdc evaluate scores as tracks under test"}
# the validity figures: requirement id, the report's code column, its 'not validated' column, the live
# state's boolean 'valid' column, the threshold's field
VALIDITY = {
    "mode3a_valid": ("mode3a", "mode3a_v", "mode3a_valid", "min_mode3a_valid"),
    "modec_valid": ("flight_level", "flight_level_v", "modec_valid", "min_modec_valid"),
}


@dataclass
class Memory:
    """What the monitor carries from one snapshot to the next: when each sensor was last heard (it drops
    out of the recent window when it goes silent) and each feed's counters over the window."""

    last_heard_wall_s: dict[str, float] = field(default_factory=dict)
    feed_samples: dict[str, list[tuple[float, dict]]] = field(default_factory=dict)


# ------------------------------------------------------------------------------------ reports as tracks

def report_times_s(frame: pd.DataFrame) -> np.ndarray:
    """The reports' own times (their ``time`` column) as seconds since 1970, NaN where absent."""
    t = pd.to_datetime(frame["time"], utc=True)
    out = t.to_numpy("datetime64[ns]").astype("int64") / 1e9
    return np.where(t.isna().to_numpy(), np.nan, out)


def track_keys(frame: pd.DataFrame) -> np.ndarray:
    """Per report, the target it belongs to within its sensor: "A:<id>" from its aircraft identity (the
    Mode S address where it has one), else "T<n>" from the sensor's track number, else None (a plot that
    cannot be followed). A frame that carries them already (``_track_key``, set once by snapshot) gives
    those."""
    if "_track_key" in frame.columns:  # pandas may keep a missing key as NaN in a column of text
        keys = frame["_track_key"].to_numpy(object, copy=True)
        keys[pd.isna(keys)] = None
        return keys
    n = len(frame)
    out = np.full(n, None, dtype=object)
    if "track_number" in frame.columns:
        tn = pd.to_numeric(frame["track_number"], errors="coerce").round().astype("Int64")
        ok = tn.notna().to_numpy()
        out[ok] = ("T" + tn[ok].astype(str)).to_numpy(object)
    if "aircraft_id" in frame.columns:
        ac = frame["aircraft_id"].astype("string")
        ok = ac.notna().to_numpy()
        out[ok] = ("A:" + ac[ok]).to_numpy(object)
    return out


def _live_sensor(rows: pd.DataFrame, sensor_id: str) -> Sensor:
    """The evaluation's Sensor for a live window: every position inside coverage (the limits declared wide
    open, the site at the reports' centroid), since the window's own reports are the only reference."""
    return Sensor(float(np.nanmean(rows["latitude"])), float(np.nanmean(rows["longitude"])), 0.0,
                  name=sensor_id, min_range_nm=0.0, max_range_nm=1.0e6, min_elevation_deg=-90.0,
                  max_elevation_deg=90.0)


def self_reference(rows: pd.DataFrame, positions: bool = True) -> tuple[pd.DataFrame, pd.DataFrame]:
    """One sensor's reports with each track as its own reference: the reports with ``t_s`` and the
    association columns set (ref_index: the track's place among the sorted track keys), and the reference
    (aircraft, t_s, latitude, longitude). Reports without a time or track are left out, and without a
    position unless ``positions`` is False (the update interval and the codes' validity need none: a radar
    feed heard without --sensors has no positions)."""
    t = report_times_s(rows)
    key = track_keys(rows)
    lat = pd.to_numeric(rows["latitude"], errors="coerce").to_numpy(float)
    lon = pd.to_numeric(rows["longitude"], errors="coerce").to_numpy(float)
    ok = np.isfinite(t) & np.array([k is not None for k in key], bool)
    if positions:
        ok &= np.isfinite(lat) & np.isfinite(lon)
    rep = rows.loc[ok].reset_index(drop=True).copy()
    rep["t_s"] = t[ok]
    labels = np.array(sorted(set(key[ok])), dtype=object)
    index = np.searchsorted(labels, key[ok].astype(str)) if labels.size else np.zeros(0, np.int64)
    rep["ref_index"] = index.astype(np.int64)
    rep["ref_aircraft"] = pd.Series(key[ok], dtype=object)
    rep["ref_distance_m"] = 0.0
    reference = pd.DataFrame({"aircraft": key[ok].astype(str), "t_s": t[ok], "latitude": lat[ok],
                              "longitude": lon[ok]})
    return rep, reference


# -------------------------------------------------------------------------------------------- figures

def figure_sample(window: pd.DataFrame) -> tuple[pd.DataFrame, dict | None]:
    """The window's reports the figures are measured on: all of them up to MAX_FIGURE_REPORTS, else whole
    tracks in the order of a CRC-32 of their key, each that still fits (at least one); with what was sampled
    (None: all). A window without tracks (ADS-B 0.23 carries no track numbers) is measured whole: its
    figures that need tracks are withheld, the others are cheap."""
    if len(window) <= MAX_FIGURE_REPORTS:
        return window, None
    import zlib

    key = track_keys(window)
    codes, names = pd.factorize(pd.Series(key, dtype=object), use_na_sentinel=True)
    if not len(names):
        return window, None
    counts = np.bincount(codes[codes >= 0], minlength=len(names))
    order = np.argsort([zlib.crc32(str(n).encode()) for n in names], kind="stable")
    picked = np.zeros(len(names), bool)
    room = MAX_FIGURE_REPORTS
    for track in order:  # each track that fits, not only those before the first that does not
        if counts[track] <= room or not picked.any():
            picked[track] = True
            room -= counts[track]
    keep = (codes >= 0) & picked[np.maximum(codes, 0)]
    chosen = names[picked]
    sample = window.loc[keep]
    return sample, {"tracks": len(chosen), "of_tracks": int(len(names)), "reports": int(keep.sum()),
                    "of_reports": int(len(window))}


def update_interval_s(rows: pd.DataFrame) -> float:
    """The sensor's update period measured on the window (scans.period_from_plots over its tracks: the
    median interval between successive reports of a track, refined over whole periods); NaN with fewer
    than MIN_DIFFS intervals."""
    rep, _ = self_reference(rows, positions=False)
    if not len(rep):
        return math.nan
    return period_from_plots(rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy())


def live_pd(rows: pd.DataFrame, sensor_id: str, window_s: float) -> Outcome:
    """The probability of update over the window (the evaluation's ``pd``, scope global): every track its
    own reference, one update expected per measured update period between its first and last report."""
    if not len(rows):
        return withheld("pd", "no report in the window")
    rep, reference = self_reference(rows)
    if not len(rep):
        followed = len(self_reference(rows, positions=False)[0]) > 0  # timed and tracked, yet unplaced
        return withheld("pd", "the reports carry no position (a radar's plots are placed from its site: give "
                              "--sensors)" if followed else
                        "no report with a time, a position and a track number or identity")
    period = period_from_plots(rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy())
    if not math.isfinite(period):
        return withheld("pd", f"update period not measurable: fewer than {MIN_DIFFS} intervals between "
                              "successive reports of a track in the window")
    outcome = pd_requirement(rep, reference, {"reference_max_gap_s": 2.0 * window_s}, _live_sensor(rep,
                                                                                                sensor_id))
    if outcome.n < MIN_UPDATES:
        return withheld("pd", f"{int(outcome.n)} expected updates in the window (fewer than {MIN_UPDATES})")
    tracks = int(rep["ref_index"].nunique())
    return replace(outcome, notes=(f"update period {period:.4g} s measured on the window's {tracks} tracks; "
                                   "misses before a track's first or after its last report in the window "
                                   "are not counted",))


def _validity_frame(rep: pd.DataFrame, code: str, v_col: str, valid_col: str) -> pd.DataFrame | None:
    """The reports whose validity is known, with the 'not validated' bit the requirement reads: the feed's
    own bit when it gives it, else from its boolean 'valid' column; None when the feed says neither."""
    if v_col in rep.columns:
        known = pd.to_numeric(rep[v_col], errors="coerce").notna().to_numpy()
        return rep.loc[known]
    if valid_col not in rep.columns:
        return None
    valid = rep[valid_col].astype("boolean")
    known = valid.notna().to_numpy()
    out = rep.loc[known].copy()
    out[v_col] = (~valid[known].astype(bool)).astype(np.int8).to_numpy()
    return out


def live_validity(rows: pd.DataFrame, requirement: str) -> Outcome:
    """``mode3a_valid`` or ``modec_valid`` over the window (the evaluation's requirement): of the reports
    carrying the code whose validity the feed states, the share marked valid."""
    code, v_col, valid_col, _ = VALIDITY[requirement]
    if not len(rows):
        return withheld(requirement, "no report in the window")
    rep, reference = self_reference(rows, positions=False)
    rep = _validity_frame(rep, code, v_col, valid_col) if code in rep.columns else None
    if rep is None:
        return withheld(requirement, f"the reports do not say whether their {code} is validated")
    if not len(rep):
        return withheld(requirement, f"no report in the window states whether its {code} is validated")
    outcome = CODE_REQUIREMENTS[requirement](rep, reference, None)
    if outcome.n < MIN_CODES:
        return withheld(requirement, f"{int(outcome.n)} reports carry a {code} with a stated validity "
                                     f"(fewer than {MIN_CODES})")
    return outcome


def _number(v) -> float | None:
    """A finite float for JSON, None otherwise."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def judged(outcome: Outcome, threshold: float) -> dict:
    """A figure for the page: value and 95 % interval, the counts, the threshold, and its state: "withheld"
    (no value; ``note`` says why), "degraded" (the whole interval below the threshold: the alarm), "low"
    (the value below it but the interval reaching it: not shown by the data yet) or "ok"."""
    value = _number(outcome.value)
    out = {"value": value, "ci_low": _number(outcome.ci_low), "ci_high": _number(outcome.ci_high),
           "count": int(outcome.count), "n": int(outcome.n), "threshold": float(threshold),
           "note": "; ".join(outcome.notes)}
    if value is None:
        out["state"] = "withheld"
    elif out["ci_high"] is not None and out["ci_high"] < threshold:
        out["state"] = "degraded"
    elif value < threshold:
        out["state"] = "low"
    else:
        out["state"] = "ok"
    return out


def unjudged(figure: dict, why: str) -> dict:
    """A measured figure shown without a verdict (state "unjudged", no alarm), its note saying why."""
    return {**figure, "state": "unjudged", "note": "; ".join(n for n in (figure["note"], why) if n)}


# ------------------------------------------------------------------------------------------- snapshot

def lookback_s(thresholds: Thresholds) -> float:
    """How far back the monitor asks the state for reports: the window, or the silence threshold if longer
    (a sensor last heard inside it is then still seen)."""
    return max(thresholds.window_s, thresholds.silent_s)


def _cat010_status(sensor_id: str) -> bool:
    """A CAT010 id without a kind ("010:SAC/SIC"): its status messages and the reports of kinds not measured,
    which give the last status of its kinds' sensors ("010:SAC/SIC:mlat", ":smr"), no panel of their own."""
    return sensor_id.startswith("010:") and sensor_id.count(":") == 1


def _status_time(sensor_id: str, status_times: dict) -> float | None:
    """The last status message of a sensor, a CAT010 sensor's under its SAC/SIC without the kind."""
    if sensor_id in status_times:
        return status_times[sensor_id]
    if sensor_id.startswith("010:") and sensor_id.count(":") == 2:
        return status_times.get(sensor_id.rsplit(":", 1)[0])
    return None


def _kind(sensor_id: str, rows: pd.DataFrame) -> str | None:
    """The kind its latest report gives, else the one its id implies (no report in the lookback)."""
    if len(rows) and "sensor_kind" in rows.columns:
        k = rows["sensor_kind"].dropna()
        if len(k):
            return str(k.iloc[-1])
    return kind_of_id(sensor_id)


def _feeds_of(sensor_id: str, rows: pd.DataFrame, counters: dict) -> list[str]:
    feeds = {f for f, c in counters.items() if sensor_id in (c.get("records") or {})}
    if len(rows) and "feed" in rows.columns:
        feeds |= {str(f) for f in rows["feed"].dropna().unique()}
    return sorted(feeds)


def sensor_figures(sensor_id: str, rows: pd.DataFrame, window: pd.DataFrame, counters: dict,
                   status_times: dict, now_wall_s: float, rate_window_s: float,
                   last_heard_wall_s: float | None, thresholds: Thresholds) -> tuple[dict, list[dict]]:
    """One sensor's panel and alarms. ``rows``: its reports over the lookback, ``window``: those of the
    window; ``last_heard_wall_s``: when it was last heard (None: not in the lookback nor remembered)."""
    feeds = _feeds_of(sensor_id, rows, counters)
    total = sum(int((counters.get(f, {}).get("records") or {}).get(sensor_id, 0)) for f in feeds)
    measured, sampled = figure_sample(window)
    period = update_interval_s(measured) if len(measured) else math.nan
    status = _status_time(sensor_id, status_times)
    panel = {
        "sensor_id": sensor_id, "kind": _kind(sensor_id, rows), "feeds": feeds, "records_total": total,
        "reports_in_window": int(len(window)),
        "reports_per_s": (len(window) / rate_window_s) if rate_window_s >= MIN_RATE_WINDOW_S else None,
        "rate_window_s": round(rate_window_s, 2),
        "update_interval_s": _number(period),
        "update_interval_note": "" if math.isfinite(period) else
        f"fewer than {MIN_DIFFS} intervals between successive reports of a track in the window",
        "last_report_age_s": None if last_heard_wall_s is None else max(0.0, now_wall_s - last_heard_wall_s),
        "last_status_age_s": None if status is None else max(0.0, now_wall_s - float(status)),
        "decode_errors": sum(int(counters.get(f, {}).get("decode_errors", 0)) for f in feeds),
        "pd": judged(live_pd(measured, sensor_id, thresholds.window_s), thresholds.min_pd),
        "figures_sample": sampled,
    }
    if panel["kind"] == "adsb" and panel["pd"]["value"] is not None:
        panel["pd"] = unjudged(panel["pd"], ADSB_PD_NOTE)
    for req, (*_, threshold) in VALIDITY.items():
        panel[req] = judged(live_validity(measured, req), getattr(thresholds, threshold))
    if sampled is not None:  # whole tracks sampled: the interval, of independent reports, is too narrow
        for req in ("pd", *VALIDITY):
            if panel[req]["value"] is not None and panel[req]["state"] != "unjudged":
                panel[req] = unjudged(panel[req], SAMPLE_NOTE.format(**sampled))
    category = sensor_id.split(":", 1)[0]
    if category in COUNTED_ONLY:  # no report rows: say so, not "too few intervals"
        why = f"CAT{category} records are counted, not measured, live ({COUNTED_ONLY[category]})"
        panel["update_interval_note"] = why
        panel["reports_per_s"] = None  # its records arrive; none is a report of the map and the figures
        panel["pd"] = judged(withheld("pd", why), thresholds.min_pd)
        for req, (*_, threshold) in VALIDITY.items():
            panel[req] = judged(withheld(req, why), getattr(thresholds, threshold))
    alarms = []
    age = panel["last_report_age_s"]
    if age is None or age >= thresholds.silent_s:
        said = (f"no report for {age:.0f} s" if age is not None
                else f"no report in the last {lookback_s(thresholds):.0f} s")
        alarms.append({"level": "alarm", "kind": "silent", "sensor_id": sensor_id,
                       "message": f"{sensor_id} silent: {said} (threshold {thresholds.silent_s:g} s)"})
    names = {"pd": "probability of update", "mode3a_valid": "Mode 3/A validity",
             "modec_valid": "Mode C validity"}
    for req, name in names.items():
        f = panel[req]
        if f["state"] == "degraded":
            alarms.append({"level": "alarm", "kind": f"degraded_{req}", "sensor_id": sensor_id,
                           "message": f"{sensor_id} degraded: {name} {f['value']:.1%} (95 % interval up to "
                                      f"{f['ci_high']:.1%}) below {f['threshold']:.0%}"})
    panel["alarms"] = [a["kind"] for a in alarms]
    return panel, alarms


def feed_figures(feed: str, counter: dict, samples: list[tuple[float, dict]], now_wall_s: float,
                 window_s: float) -> tuple[dict, list[dict]]:
    """One feed's panel (its counters, packets per second and decode errors over the window, from the
    counters remembered at earlier snapshots, with the seconds they span: from the first snapshot in the
    window, less than the window while the monitor is younger; from the last one before it when none
    is in it) and its warnings."""
    kept = window_samples(samples, now_wall_s - window_s)
    inside = [(t, c) for t, c in kept if t >= now_wall_s - window_s] or kept[:1]
    first_t, first = inside[0] if inside else (now_wall_s, counter)
    span = now_wall_s - first_t
    last_packet = counter.get("last_packet_wall_s")
    panel = {"feed": feed, **{k: int(counter.get(k, 0)) for k in ("packets", "bytes", "framed", "unframed",
                                                                     "empty", "decode_errors", "dropped")},
             "packets_per_s": ((int(counter.get("packets", 0)) - int(first.get("packets", 0))) / span
                               if span >= MIN_RATE_WINDOW_S else None),
             "rate_window_s": round(span, 2),
             "last_packet_age_s": None if last_packet is None else max(0.0, now_wall_s - float(last_packet))}
    panel["waiting"] = waiting_datagrams(panel)
    warnings = []
    for key, what in (("decode_errors", "decode errors"), ("dropped", "datagrams dropped (queue full)"),
                      ("unframed", "datagrams that do not frame into data blocks")):
        new = int(counter.get(key, 0)) - int(first.get(key, 0))
        panel[f"{key}_in_window"] = new
        if new > 0:
            warnings.append({"level": "warning", "kind": key, "feed": feed,
                             "message": f"{feed}: {new} {what} in the last {span:.0f} s"})
    return panel, warnings


def window_samples(samples: list[tuple[float, dict]], start_wall_s: float) -> list[tuple[float, dict]]:
    """The counters remembered at or after ``start_wall_s``, led by the last one before it (kept for when
    none is inside: with snapshots as far apart as the window, --window 1, none fell inside it and the
    feed's rate and warnings were silent)."""
    before = [i for i, (t, _) in enumerate(samples) if t < start_wall_s]
    return samples[before[-1]:] if before else list(samples)


def arrival_period_s(wall_s: np.ndarray, key: np.ndarray) -> float:
    """The median interval between successive arrivals of a target's reports (any length: a replay may be
    faster than real time), NaN with fewer than MIN_DIFFS intervals."""
    order = np.lexsort((wall_s, key))
    t, k = wall_s[order], key[order]
    d = np.diff(t)[k[1:] == k[:-1]]
    d = d[d > 0]
    return float(np.median(d)) if d.size >= MIN_DIFFS else math.nan


def targets(window: pd.DataFrame, now_wall_s: float) -> list[dict]:
    """The targets of the window for the map: per sensor and track (or Mode S address, for reports without
    a track: the map follows them, the figures do not), its trail (latest TRAIL_POINTS positions, oldest
    first, as [latitude, longitude]; ADS-B positions outside their source's coverage left out, as the
    measurements leave them out), its latest call sign, Mode 3/A and flight level,
    its age and whether it is stale (not updated for STALE_PERIODS of its sensor's update periods, measured
    on arrival times: a replay faster than real time updates faster)."""
    if not len(window):
        return []
    key = track_keys(window).copy()
    if "address" in window.columns:  # a report without a track is drawn by its Mode S address (ADS-B 0.23)
        address = window["address"].astype("string")
        by_address = np.array([k is None for k in key], bool) & address.notna().to_numpy(bool)
        key[by_address] = ("A:" + address[by_address]).to_numpy(object)
    lat = pd.to_numeric(window["latitude"], errors="coerce").to_numpy(float)
    lon = pd.to_numeric(window["longitude"], errors="coerce").to_numpy(float)
    ok = np.isfinite(lat) & np.isfinite(lon) & np.array([k is not None for k in key], bool)
    far, _ = out_of_coverage(window)  # ADS-B positions no ground station receives (the measurements' rule)
    ok &= ~far
    if not ok.any():  # no report with a position and a track or address: no target (the split below fails)
        return []
    w = window.loc[ok, [c for c in ("sensor_id", "sensor_kind", "wall_s", "callsign", "mode3a",
                                    "flight_level") if c in window.columns]].copy()
    w["key"], w["lat"], w["lon"] = key[ok], lat[ok], lon[ok]
    w["sensor_id"] = w["sensor_id"].astype(str)
    w = w.sort_values("wall_s", kind="stable")
    periods_s = {s: arrival_period_s(g["wall_s"].to_numpy(float), g["key"].to_numpy(object).astype(str))
                 for s, g in w.groupby("sensor_id", sort=False, observed=True)}
    # per target (sensor, track), vectorised: its rows' group, the last row and the last non-null value of
    # each label column; the trail from the latest TRAIL_POINTS rows alone
    group = w.groupby(["sensor_id", "key"], sort=False, observed=True)
    last = group.tail(1)
    labels = {c: group[c].last() for c in ("callsign", "mode3a", "flight_level") if c in w.columns}
    gid = group.ngroup().to_numpy()
    inside = group.cumcount(ascending=False).to_numpy() < TRAIL_POINTS
    order = np.argsort(gid[inside], kind="stable")  # by target, in arrival order within each
    xy = np.column_stack([w["lat"].to_numpy(float), w["lon"].to_numpy(float)])[inside][order].round(5)
    cuts = np.flatnonzero(np.diff(gid[inside][order])) + 1
    by_gid = dict(zip(np.unique(gid[inside]), np.split(xy, cuts), strict=True))
    last_gid = gid[group.cumcount(ascending=False).to_numpy() == 0]
    trails = {key: by_gid[g].tolist() for key, g in zip(zip(last["sensor_id"], last["key"], strict=True),
                                                         last_gid, strict=True)}
    out = []
    for sid, k, wall in zip(last["sensor_id"], last["key"], last["wall_s"].to_numpy(float), strict=True):
        def latest(col: str, sid=sid, k=k):
            v = labels[col].get((sid, k)) if col in labels else None
            return None if v is None or pd.isna(v) else v

        fl = _number(latest("flight_level"))
        age = max(0.0, now_wall_s - float(wall))
        period = periods_s.get(sid, math.nan)
        stale_after = STALE_PERIODS * period if math.isfinite(period) else DEFAULT_STALE_S
        cs, m3a = latest("callsign"), latest("mode3a")
        out.append({"id": f"{sid}|{k}", "sensor_id": sid, "track": k,
                    "callsign": None if cs is None else str(cs), "mode3a": None if m3a is None else str(m3a),
                    "flight_level": None if fl is None else round(fl, 2), "age_s": round(age, 2),
                    "stale": bool(age > stale_after), "trail": trails[(sid, k)]})
    out.sort(key=lambda t: t["age_s"])
    return out[:MAX_TARGETS]


def _without_figures(sensor_id: str, rows: pd.DataFrame, window: pd.DataFrame, counters: dict,
                     status_times: dict, now_wall_s: float, rate_window_s: float,
                     last_heard_wall_s: float | None, thresholds: Thresholds, exc: Exception
                     ) -> tuple[dict, list[dict]]:
    """A sensor whose figures failed: its panel made from no report (figures withheld, its silence still
    judged), its reports still counted, and a warning naming the failure (the traceback in the log)."""
    import logging

    logging.getLogger("msdc.live").exception("figures of %s failed", sensor_id)
    why = f"figures not computed: {type(exc).__name__}: {exc}"
    panel, raised = sensor_figures(sensor_id, rows, window.iloc[:0], counters, status_times, now_wall_s,
                                   rate_window_s, last_heard_wall_s, thresholds)
    panel["reports_in_window"] = int(len(window))
    if panel["reports_per_s"] is not None:
        panel["reports_per_s"] = len(window) / rate_window_s
    for req in ("pd", *VALIDITY):
        panel[req] = {**panel[req], "note": why}
    panel["update_interval_note"] = why
    warning = {"level": "warning", "kind": "figures_failed", "sensor_id": sensor_id,
               "message": f"{sensor_id}: {why}"}
    panel["alarms"] = [*panel["alarms"], warning["kind"]]
    return panel, [*raised, warning]


def snapshot(frame: pd.DataFrame, counters: dict, status_times: dict, now_wall_s: float,
             started_wall_s: float, thresholds: Thresholds,
             memory: Memory | None = None) -> tuple[dict, Memory]:
    """The monitor's JSON snapshot (schema in docs/guide/live-monitor.md) and the memory for the next one.
    ``frame``: state.recent(lookback_s(thresholds)); ``counters``, ``status_times``: the state's."""
    memory = memory or Memory()
    if len(frame):
        frame = frame.assign(_track_key=track_keys(frame))  # once, for the figures and the map
    last_heard = dict(memory.last_heard_wall_s)
    window_start = now_wall_s - thresholds.window_s
    if len(frame):
        wall = frame["wall_s"].to_numpy(float)
        sid = frame["sensor_id"].astype(str).to_numpy(object)
        for s, t in pd.Series(wall).groupby(sid).max().items():
            last_heard[s] = max(float(t), last_heard.get(s, -math.inf))
        in_window = wall >= window_start
    else:
        sid, in_window = np.zeros(0, object), np.zeros(0, bool)
    for c in counters.values():  # records arrived, whether or not they make reports (CAT062 tracks)
        for s, t in (c.get("last_record_wall_s") or {}).items():
            last_heard[s] = max(float(t), last_heard.get(s, -math.inf))
    known = {s for s in set(last_heard) | {s for c in counters.values() for s in (c.get("records") or {})}
             if s.split(":", 1)[0] not in STATUS_CATEGORIES and not _cat010_status(s)}
    rate_window = min(thresholds.window_s, now_wall_s - started_wall_s)
    sensors, alarms = [], []
    for s in sorted(known):
        rows = frame.loc[sid == s] if len(frame) else frame
        window = frame.loc[(sid == s) & in_window] if len(frame) else frame
        try:
            panel, raised = sensor_figures(s, rows, window, counters, status_times, now_wall_s, rate_window,
                                           last_heard.get(s), thresholds)
        except Exception as exc:  # one sensor's data never stops the page: its figures withheld, it said
            panel, raised = _without_figures(s, rows, window, counters, status_times, now_wall_s, rate_window,
                                             last_heard.get(s), thresholds, exc)
        sensors.append(panel)
        alarms += raised
    feeds, samples = [], {}
    for f in sorted(counters):
        counter = {k: v for k, v in counters[f].items() if k not in ("records", "last_record_wall_s")}
        kept = window_samples(memory.feed_samples.get(f, []), window_start)
        panel, warned = feed_figures(f, counter, kept, now_wall_s, thresholds.window_s)
        feeds.append(panel)
        alarms += warned
        samples[f] = [*kept, (now_wall_s, counter)]
    shown = targets(frame.loc[in_window] if len(frame) else frame, now_wall_s)
    ends = np.array([t["trail"][-1] for t in shown], float).reshape(-1, 2)
    centre = ({"latitude": round(float(ends[:, 0].mean()), 5),
               "longitude": round(float(ends[:, 1].mean()), 5)} if len(ends) else None)
    snap = {"schema": SCHEMA, "now_wall_s": now_wall_s, "started_wall_s": started_wall_s,
            "uptime_s": max(0.0, now_wall_s - started_wall_s), "thresholds": thresholds.as_dict(),
            "alarms": alarms, "sensors": sensors, "feeds": feeds, "centre": centre, "targets": shown}
    return snap, Memory(last_heard, samples)
