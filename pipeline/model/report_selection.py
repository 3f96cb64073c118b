"""Which reports a run reads: a time window (``--from``/``--to``), an area (``--area``: GeoJSON polygons or a
range/azimuth window of a sensor), a flight-level band (``--fl``) and a subset of sensors (``--sensor``).

Applied to the reports before anything is computed from them (``select_reports``, a pure function of a
frame of reports), by one rule per criterion; a report must meet every criterion given:

- time: the report's UTC ``time`` (radar I048/140, ADS-B time of applicability...) in [from, to): from
  inclusive, to exclusive, so consecutive windows share no report. A report without a time is left out.
- sensor: the report's sensor (``sensor_id``, "CCC:SAC/SIC") is one of those given; "SAC/SIC" names the
  sensors of every category with that pair, "CCC:SAC/SIC" one category, "010:SAC/SIC:mlat" one kind.
- flight level: the report's own ``flight_level`` (Mode C, I021/145...) within [min, max], both inclusive.
  A report without a flight level is left out: it is not shown to be in the band (a primary-only plot, a
  surface target's report without one).
- area: the report's WGS-84 position (for a radar plot, where its range and azimuth put it at its flight
  level) inside a polygon (``pipeline.model.polygons``), or, for a sensor window, its slant range and
  azimuth from that sensor's site within the window (both bounds inclusive; an azimuth window may wrap
  through north, 300-60deg). A plot of the window's own radar is judged by its decoded range and azimuth
  (I048/040) as they are; any other report by the slant range and azimuth of its position at its height
  (none known: at the site's height) from the site in the sensor file. A report without a position is
  left out.

Reports left out are counted per criterion (one report may fail several); the counts are recorded with the
run's parameters (``recorded``).

The jobs that build measurements (identity, coverage) build them from the reports within READING_MARGIN of
the time window only (``MarginCut``): which address a call sign or Mode 3/A code goes with, and each ADS-B
source's coverage, are settled over the window and its margin, not over whatever else the inputs hold, so a
window's results do not depend on how much of the day a recording or a dataset holds, and a dataset's read
stops at the margin. The reports cut are counted as left out, by every criterion they fail.
"""

from __future__ import annotations

import datetime as dt
import math
import re
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from msdc.pipeline.model.polygons import Polygons, inside
from msdc.pipeline.model.time import utc_text

SELECTION_INPUTS = ("time", "sensor_id", "sac", "sic", "latitude", "longitude", "height_m", "flight_level",
                    "rho_nm", "theta_deg")  # the measurement columns select_reports reads
FL_RANGE = (-20.0, 1000.0)  # below the lowest aerodrome to above any aircraft
RANGE_MAX_NM = 10_000.0
_SENSOR = re.compile(r"(?:(\d{1,3}):)?(\d{1,3})[/_](\d{1,3})(?::(mlat|smr))?")
_TIME_OF_DAY = re.compile(r"(\d{1,2}):(\d{2})(?::(\d{2}(?:\.\d+)?))?")
_NUMBER = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)"
_RANGE = re.compile(rf"({_NUMBER})-({_NUMBER})nm", re.IGNORECASE)
_AZIMUTH = re.compile(rf"({_NUMBER})-({_NUMBER})deg", re.IGNORECASE)
# How far beyond --from/--to the measurement jobs read (module docstring): a flight's address, call sign and
# Mode 3/A code are seen together within minutes (ADS-B sends them every few seconds, a Mode S radar every
# scan), while a code is reused by other flights over hours; the reach gate's farthest useful neighbour in
# time is well inside it (15 min at 1000 kt is 250 NM).
READING_MARGIN = pd.Timedelta(minutes=15)


class WindowError(ValueError):
    """--from or --to cannot be placed (no date), or the window holds no time; the message names the
    option."""


@dataclass(frozen=True)
class SensorRef:
    """A sensor as --sensor names it: SAC/SIC, with its category (None: any) and CAT010 kind (None: any)."""

    text: str
    sac: int
    sic: int
    category: int | None = None
    kind: str | None = None

    def matches(self, category: int, sac: int, sic: int, kind: str | None) -> bool:
        """Whether a sensor of this category, SAC/SIC and kind is the one named."""
        return (self.sac == sac and self.sic == sic and self.category in (None, category)
                and self.kind in (None, kind))


@dataclass(frozen=True)
class TimeBound:
    """--from or --to: an instant (UTC), or a time of day (s after midnight) on the recording's day."""

    text: str
    instant: pd.Timestamp | None = None
    time_of_day_s: float | None = None

    def on(self, day: dt.date | None, name: str) -> pd.Timestamp:
        """The instant on the recording's ``day`` (None: the inputs carry no date); ValueError naming the
        option when it cannot be placed."""
        if day is None:
            raise WindowError(f"{name} {self.text}: the inputs carry no date (their times are placed on "
                             "1970-01-01) and --date was not given: give --date YYYY-MM-DD")
        if self.instant is not None:
            return self.instant
        return pd.Timestamp(day, tz="UTC") + pd.Timedelta(seconds=self.time_of_day_s)


@dataclass(frozen=True)
class SensorWindow:
    """--area SENSOR:A-Bnm:C-Ddeg: slant range A..B NM and azimuth C..D deg (clockwise from north, wrapping
    through north when C > D) from the site of the named sensor."""

    text: str
    sensor: SensorRef
    range_nm: tuple[float, float]
    azimuth_deg: tuple[float, float]
    site: tuple[float, float, float] | None = None  # the sensor file's latitude, longitude (deg), height (m)

    def azimuth_inside(self, azimuth_deg: np.ndarray) -> np.ndarray:
        """Whether each azimuth (deg) lies in the window, both bounds inclusive."""
        lo, hi = self.azimuth_deg
        az = np.mod(azimuth_deg, 360.0)
        if hi - lo >= 360.0:
            return np.isfinite(az)
        lo, hi = lo % 360.0, hi % 360.0
        return (az >= lo) & (az <= hi) if lo <= hi else (az >= lo) | (az <= hi)


@dataclass(frozen=True)
class ReportSelection:
    """The reports a run reads (see the module docstring); an empty one keeps every report."""

    start: TimeBound | None = None
    end: TimeBound | None = None
    area: Polygons | SensorWindow | None = None
    area_text: str | None = None
    fl: tuple[float, float] | None = None
    fl_text: str | None = None
    sensors: tuple[SensorRef, ...] = field(default_factory=tuple)

    @property
    def active(self) -> bool:
        """Whether any criterion is given."""
        return any(v is not None for v in (self.start, self.end, self.area, self.fl)) or bool(self.sensors)

    def window(self, day: dt.date | None) -> tuple[pd.Timestamp | None, pd.Timestamp | None]:
        """--from and --to as instants on the recording's day; ValueError naming the option when a bound
        cannot be placed or the window is empty."""
        lo = self.start.on(day, "--from") if self.start is not None else None
        hi = self.end.on(day, "--to") if self.end is not None else None
        if lo is not None and hi is not None and not lo < hi:
            raise WindowError(f"--from {self.start.text} ({lo.isoformat()}) is not before --to "
                             f"{self.end.text} ({hi.isoformat()}): the window holds no time")
        return lo, hi

    @property
    def timed(self) -> bool:
        """Whether a time window (--from, --to or both) is given."""
        return self.start is not None or self.end is not None

    @property
    def placed(self) -> bool:
        """Whether every time bound given is an instant (placed without the recording's day)."""
        return all(b is None or b.instant is not None for b in (self.start, self.end))

    def reading_window(self, day: dt.date | None) -> tuple[pd.Timestamp | None, pd.Timestamp | None] | None:
        """What the measurement jobs read: the window widened by READING_MARGIN on each side (a side not
        given stays open); None when no time bound is given. WindowError as ``window``."""
        if not self.timed:
            return None
        lo, hi = self.window(day)
        return (None if lo is None else lo - READING_MARGIN, None if hi is None else hi + READING_MARGIN)

    def parameters(self, day: dt.date | None = None) -> dict:
        """The options as given; the flight-level band applied (an open bound as FL_RANGE's) and the window's
        instants (msdc's JSON time text) when the day is known."""
        out: dict = {"from": self.start.text if self.start else None,
                     "to": self.end.text if self.end else None, "area": self.area_text,
                     "fl": self.fl_text or (f"{self.fl[0]:g}:{self.fl[1]:g}" if self.fl else None),
                     "fl_bounds": list(self.fl) if self.fl else None,
                     "sensors": [s.text for s in self.sensors]}
        try:
            lo, hi = self.window(day)
        except ValueError:
            lo = hi = None
        if lo is not None or hi is not None:
            out["from_utc"] = utc_text(lo) if lo is not None else None
            out["to_utc"] = utc_text(hi) if hi is not None else None
        return out


# ---------------------------------------------------------------------------------------------------------
# Option texts


def check_order(start: TimeBound, end: TimeBound) -> None:
    """ValueError when --from is not before --to, both date-times or both times of day (a time of day and a
    date-time are compared once placed on the recording's day: ReportSelection.window)."""
    if start.instant is not None and end.instant is not None:
        empty = not start.instant < end.instant
    elif start.time_of_day_s is not None and end.time_of_day_s is not None:
        empty = not start.time_of_day_s < end.time_of_day_s
    else:
        return
    if empty:
        raise ValueError(f"--from {start.text} is not before --to {end.text}: the window holds no time")


MAX_WINDOWS = 100_000  # --window: more windows than this is a mistake (a month of 1-minute windows: 44,640)


def span_windows(selection: ReportSelection, minutes: float, name: str = "--window") -> list[ReportSelection]:
    """The selection's --from/--to span cut into consecutive windows of ``minutes`` (the last one shorter
    when the span is not a whole number of them), each the selection with that window's bounds, written as
    the span's are (date-times, every edge as 2026-11-28T13:30:00Z, or times of day); ValueError naming the
    option when the span is not given by both bounds of one kind."""
    start, end = selection.start, selection.end
    if start is None or end is None:
        raise ValueError(f"{name} {minutes:g}: cuts the span --from ... --to ... into windows; give both")
    step = float(minutes) * 60.0
    if start.instant is not None and end.instant is not None:
        lo, hi = start.instant, end.instant
        total = (hi - lo).total_seconds()

        def bound(s: float) -> TimeBound:
            t = lo + pd.Timedelta(seconds=s)
            return TimeBound(t.isoformat().replace("+00:00", "Z"), instant=t)
    elif start.time_of_day_s is not None and end.time_of_day_s is not None:
        lo_s = start.time_of_day_s
        total = end.time_of_day_s - lo_s

        def bound(s: float) -> TimeBound:
            t = lo_s + s
            h, rest = divmod(t, 3600.0)
            m, sec = divmod(rest, 60.0)
            text = f"{int(h):02d}:{int(m):02d}" + (f":{sec:06.3f}".rstrip("0").rstrip(".") if sec else "")
            return TimeBound(text, time_of_day_s=t)
    else:
        raise ValueError(f"{name} {minutes:g}: --from {start.text} and --to {end.text} must both be "
                         "date-times or both times of day for the span to be cut into windows")
    if not total > 0:
        raise ValueError(f"--from {start.text} is not before --to {end.text}: the window holds no time")
    count = math.ceil(total / step - 1e-9)
    if count > MAX_WINDOWS:
        raise ValueError(f"{name} {minutes:g}: the span from {start.text} to {end.text} would be {count:,} "
                         f"windows, more than {MAX_WINDOWS:,}; give longer windows")
    edges = [bound(k * step) for k in range(count)] + [end]
    if start.instant is None:  # times of day: the span's ends as the user wrote them
        edges[0] = start
    else:  # every edge's label in one form, the span's own bounds kept
        edges[0], edges[-1] = replace(start, text=edges[0].text), replace(end, text=bound(total).text)
    return [replace(selection, start=a, end=b) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def parse_time(text: str, name: str) -> TimeBound:
    """An ISO date-time in UTC (2023-05-02T08:10:00, ...Z or +00:00; a date alone is its midnight) or a
    time of day (08:10, 08:10:30.5) on the recording's day; ValueError naming the option, the value and
    what was refused."""
    raw = str(text).strip()
    m = _TIME_OF_DAY.fullmatch(raw)
    if m:
        h, mnt, sec = int(m.group(1)), int(m.group(2)), float(m.group(3) or 0.0)
        if h > 23 or mnt > 59 or sec >= 60.0:
            raise ValueError(f"{name} {text!r}: not a time of day (hours 0-23, minutes and seconds 0-59)")
        return TimeBound(raw, time_of_day_s=h * 3600.0 + mnt * 60.0 + sec)
    try:
        instant = pd.Timestamp(dt.datetime.fromisoformat(raw.replace("z", "Z")))
    except (ValueError, TypeError):
        raise ValueError(f"{name} {text!r}: not a UTC time: give an ISO date-time (2023-05-02T08:10:00, "
                         "optionally ending in Z) or a time of day (08:10 or 08:10:30.5) on the "
                         "recording's day") from None
    if instant.tzinfo is not None:
        if instant.utcoffset() != dt.timedelta(0):
            raise ValueError(f"{name} {text!r}: the time has a UTC offset of {instant.utcoffset()}: msdc "
                             "works in UTC; give the UTC time (ending in Z, +00:00 or nothing)")
        instant = instant.tz_convert("UTC")
    else:
        instant = instant.tz_localize("UTC")
    return TimeBound(raw, instant=instant)


def parse_fl(text: str, name: str = "--fl") -> tuple[float, float]:
    """'MIN:MAX' flight levels (either may be left empty: ':100', '245:'), MIN <= MAX, each within FL_RANGE;
    ValueError naming the option and value."""
    lo_text, sep, hi_text = str(text).partition(":")
    usage = f"{name} {text!r}: expected MIN:MAX in flight levels, e.g. 100:245 (or 245: and :100)"
    if not sep or not (lo_text.strip() or hi_text.strip()):
        raise ValueError(usage)
    try:
        lo = float(lo_text) if lo_text.strip() else FL_RANGE[0]
        hi = float(hi_text) if hi_text.strip() else FL_RANGE[1]
    except ValueError:
        raise ValueError(usage) from None
    for v in (lo, hi):
        if not (np.isfinite(v) and FL_RANGE[0] <= v <= FL_RANGE[1]):
            raise ValueError(f"{name} {text!r}: {v:g} is outside FL {FL_RANGE[0]:g} to {FL_RANGE[1]:g}")
    if lo > hi:
        raise ValueError(f"{name} {text!r}: MIN {lo:g} is above MAX {hi:g}")
    return lo, hi


def parse_sensor(text: str, name: str = "--sensor") -> SensorRef:
    """'SAC/SIC' (or SAC_SIC), 'CCC:SAC/SIC' or '010:SAC/SIC:mlat' (as the outputs' sensor_id shows it);
    ValueError naming the option and value."""
    raw = str(text).strip()
    m = _SENSOR.fullmatch(raw)
    if not m:
        raise ValueError(f"{name} {text!r}: not a sensor: give SAC/SIC (e.g. 20/129), CCC:SAC/SIC (e.g. "
                         "048:20/129) or 010:SAC/SIC:mlat as the outputs' sensor_id shows it")
    cat, sac, sic, kind = m.groups()
    for what, v in (("SAC", sac), ("SIC", sic), ("category", cat)):
        if v is not None and int(v) > 255:
            raise ValueError(f"{name} {text!r}: {what} {v} is above 255")
    if kind is not None and cat is not None and int(cat) != 10:
        raise ValueError(f"{name} {text!r}: a kind (:{kind}) is given only for CAT010 sensors")
    return SensorRef(raw, int(sac), int(sic), None if cat is None else int(cat), kind)


def parse_window(text: str, name: str = "--area") -> SensorWindow:
    """'SENSOR:A-Bnm:C-Ddeg' (e.g. 20/129:0-60nm:30-120deg); ValueError naming the option and value. The
    site is looked up later (``with_site``)."""
    parts = str(text).rsplit(":", 2)
    usage = (f"{name} {text!r}: expected a GeoJSON file (.geojson or .json) or SENSOR:RANGE:AZIMUTH, e.g. "
             "20/129:0-60nm:30-120deg")
    if len(parts) != 3:
        raise ValueError(usage)
    try:
        sensor = parse_sensor(parts[0], "SENSOR")
    except ValueError as exc:
        raise ValueError(f"{name} {text!r}: {exc}") from None
    rm, am = _RANGE.fullmatch(parts[1].strip()), _AZIMUTH.fullmatch(parts[2].strip())
    if rm is None or am is None:
        raise ValueError(usage + (" (range in NM: 0-60nm)" if rm is None else " (azimuth in degrees: "
                                  "30-120deg, clockwise from north)"))
    r_lo, r_hi, a_lo, a_hi = (float(v) for v in (*rm.groups(), *am.groups()))
    if not 0.0 <= r_lo < r_hi <= RANGE_MAX_NM:
        raise ValueError(f"{name} {text!r}: range {parts[1]} must run from a lower to a higher slant range "
                         f"within 0-{RANGE_MAX_NM:g} NM")
    same = a_lo % 360.0 == a_hi % 360.0 and a_hi - a_lo != 360.0  # 360-0deg as 0-0deg; 0-360deg is all
    if not (0.0 <= a_lo <= 360.0 and 0.0 <= a_hi <= 360.0) or same:
        raise ValueError(f"{name} {text!r}: azimuth {parts[2]} must be two different angles from 0 to 360 "
                         "deg (from C clockwise to D; 300-60deg wraps through north)")
    return SensorWindow(str(text).strip(), sensor, (r_lo, r_hi), (a_lo, a_hi))


def with_site(window: SensorWindow, sensors: pd.DataFrame, sensors_path: str | None) -> SensorWindow:
    """The window with its sensor's site from the sensor table; ValueError naming the option when the sensor
    file is missing, lacks the sensor or lists it twice."""
    ref = window.sensor
    if sensors_path is None:
        raise ValueError(f"--area {window.text}: a sensor window needs the sensor's site: give --sensors "
                         "S.toml")
    rows = sensors[(sensors["sac"] == ref.sac) & (sensors["sic"] == ref.sic)]
    if ref.category is not None and "category" in rows:
        rows = rows[rows["category"] == ref.category]
    if ref.kind is not None and "kind" in rows:
        rows = rows[rows["kind"] == ref.kind]
    if len(rows) == 0:
        raise ValueError(f"--area {window.text}: no sensor {ref.text} in {sensors_path}")
    if len(rows) > 1:
        raise ValueError(f"--area {window.text}: {sensors_path} lists SAC/SIC {ref.sac}/{ref.sic} "
                         f"{len(rows)} times (categories {', '.join(str(c) for c in rows['category'])}): "
                         "name one, e.g. 048:SAC/SIC")
    row = rows.iloc[0]
    site = (float(row["latitude"]), float(row["longitude"]), float(row["altitude_m"]))
    return SensorWindow(window.text, ref, window.range_nm, window.azimuth_deg, site)


# ---------------------------------------------------------------------------------------------------------
# The selection itself


def sensor_parts(sensor_ids) -> pd.DataFrame:
    """category, sac, sic and kind of each "CCC:SAC/SIC[:kind]" sensor id (-1 and None where unreadable),
    worked out once per distinct id."""
    codes, uniques = pd.factorize(pd.Series(sensor_ids))  # a categorical's codes: no text per row
    rows = []
    for u in [*uniques, None]:  # the last row: a missing id (code -1)
        m = _SENSOR.fullmatch(str(u)) if u is not None and not pd.isna(u) else None
        rows.append((int(m.group(1)), int(m.group(2)), int(m.group(3)), m.group(4)) if m and m.group(1)
                    else (-1, -1, -1, None))
    table = pd.DataFrame(rows, columns=["category", "sac", "sic", "kind"])
    return table.iloc[np.where(codes < 0, len(uniques), codes)].reset_index(drop=True)


def select_reports(reports: pd.DataFrame, selection: ReportSelection, day: dt.date | None
                   ) -> tuple[np.ndarray, dict[str, int]]:
    """Per report, whether the selection keeps it, and how many reports each criterion left out (keys
    ``time``, ``sensor``, ``flight_level``, ``area``; a report may be left out by more than one). Reads
    ``time`` (UTC), ``sensor_id``, ``flight_level``, ``latitude``, ``longitude``, ``height_m``, ``rho_nm``,
    ``theta_deg`` (the last five only with --area; a column missing is taken as unknown). ``day``: the
    recording's day, for times of day; ValueError naming the option when a bound cannot be placed."""
    n = len(reports)
    keep = np.ones(n, bool)
    counts: dict[str, int] = {}
    if selection.timed:
        lo, hi = selection.window(day)
        ns = pd.DatetimeIndex(pd.to_datetime(reports["time"], utc=True)).as_unit("ns").asi8
        known = ~pd.isna(pd.to_datetime(reports["time"], utc=True)).to_numpy(bool)
        ok = known.copy()
        if lo is not None:
            ok &= ns >= lo.as_unit("ns").value
        if hi is not None:
            ok &= ns < hi.as_unit("ns").value
        counts["time"] = int((~ok).sum())
        keep &= ok
    if selection.sensors:
        parts = sensor_parts(reports["sensor_id"])
        ok = np.zeros(n, bool)
        for ref in selection.sensors:
            ok |= ((parts["sac"].to_numpy() == ref.sac) & (parts["sic"].to_numpy() == ref.sic)
                   & ((parts["category"].to_numpy() == ref.category) if ref.category is not None else True)
                   & (parts["kind"].to_numpy(dtype=object) == ref.kind if ref.kind is not None else True))
        counts["sensor"] = int((~ok).sum())
        keep &= ok
    if selection.fl is not None:
        level = _floats(reports, "flight_level")
        ok = (level >= selection.fl[0]) & (level <= selection.fl[1])  # NaN: False
        counts["flight_level"] = int((~ok).sum())
        keep &= ok
    if selection.area is not None:
        ok = in_area(reports, selection.area)
        counts["area"] = int((~ok).sum())
        keep &= ok
    return keep, counts


def _floats(frame: pd.DataFrame, name: str) -> np.ndarray:
    """A column as float64 (NaN for <NA>), all NaN when the frame lacks it."""
    if name not in frame:
        return np.full(len(frame), np.nan)
    return pd.to_numeric(frame[name], errors="coerce").astype("float64").to_numpy(float, na_value=np.nan)


def in_area(reports: pd.DataFrame, area: Polygons | SensorWindow) -> np.ndarray:
    """Per report, whether its position lies in the area (module docstring); False without a position."""
    lat, lon = _floats(reports, "latitude"), _floats(reports, "longitude")
    if isinstance(area, Polygons):
        return inside(area, lat, lon)
    from msdc.pipeline.model.geodesy import slant_range_azimuth

    if area.site is None:
        raise ValueError(f"--area {area.text}: the sensor's site was not looked up (with_site)")
    site_lat, site_lon, site_alt = area.site
    height = _floats(reports, "height_m")
    height = np.where(np.isfinite(height), height, site_alt)
    rho, theta = np.full(len(reports), np.nan), np.full(len(reports), np.nan)
    placed = np.isfinite(lat) & np.isfinite(lon)
    if placed.any():
        rho[placed], theta[placed], _ = slant_range_azimuth(site_lat, site_lon, site_alt, lat[placed],
                                                            lon[placed], height[placed])
    if "sensor_id" in reports:  # the window's own radar plots: their decoded range and azimuth
        parts = sensor_parts(reports["sensor_id"])
        ref = area.sensor
        own = ((parts["sac"].to_numpy() == ref.sac) & (parts["sic"].to_numpy() == ref.sic)
               & (parts["category"].to_numpy() == 48) & (ref.category in (None, 48)))
        own_rho, own_theta = _floats(reports, "rho_nm"), _floats(reports, "theta_deg")
        own &= np.isfinite(own_rho) & np.isfinite(own_theta)
        rho[own], theta[own] = own_rho[own], own_theta[own]
    lo, hi = area.range_nm
    return (rho >= lo) & (rho <= hi) & area.azimuth_inside(theta)


@dataclass
class MarginCut:
    """Cuts the reports beyond READING_MARGIN of the window from measurement rows before the identity rule
    sees them (module docstring), counting them as ``select_reports`` would leave them out."""

    selection: ReportSelection
    day: dt.date | None  # the recording's day, for times of day
    reports: int = 0  # cut so far
    left_out: dict[str, int] = field(default_factory=dict)  # theirs, per criterion

    def __post_init__(self):
        self.span = self.selection.reading_window(self.day)

    def inside(self, times) -> np.ndarray:
        """Per UTC time, whether it lies within the margin (both ends included); False for a missing one."""
        ns = pd.DatetimeIndex(pd.to_datetime(times, utc=True)).as_unit("ns")
        inside = ~ns.isna()
        lo, hi = self.span if self.span is not None else (None, None)
        if lo is not None:
            inside &= ns >= lo
        if hi is not None:
            inside &= ns <= hi
        return np.asarray(inside, bool)

    def keep(self, rows: pd.DataFrame) -> pd.DataFrame:
        """The rows (measurement rows, by their UTC ``time``) within the margin; those cut are counted. A row
        without a time is cut: the window leaves it out."""
        if self.span is None or not len(rows):
            return rows
        inside = self.inside(rows["time"])
        if inside.all():
            return rows
        _, counts = select_reports(rows[~inside], self.selection, self.day)
        self.reports += int((~inside).sum())
        for k, v in counts.items():
            self.left_out[k] = self.left_out.get(k, 0) + v
        return rows[inside].reset_index(drop=True)


def recorded(selection: ReportSelection, day: dt.date | None, reports: int, kept: int,
             left_out: dict[str, int]) -> dict:
    """What a run's outputs record of its selection: the options as given, the window's instants, and the
    reports read, kept and left out per criterion."""
    return {**selection.parameters(day), "reports": int(reports), "kept": int(kept),
            "left_out": {k: int(v) for k, v in left_out.items()}}


def describe(record: dict) -> str:
    """One line for the terminal: what was given and how many reports were kept."""
    given = [f"--{k} {record[k]}" for k in ("from", "to", "area") if record.get(k)]
    if record.get("fl_bounds"):  # the band applied: "--fl 100:" reads as --fl 100:1000
        given.append(f"--fl {record['fl_bounds'][0]:g}:{record['fl_bounds'][1]:g}")
    given += [f"--sensor {s}" for s in record.get("sensors") or ()]
    why = ", ".join(f"{v} by {k.replace('_', ' ')}" for k, v in record.get("left_out", {}).items() if v)
    windows = record.get("windows")
    return (f"selection {' '.join(given)}: {record['kept']} of {record['reports']} reports kept"
            + (f" (left out: {why})" if why else "")
            + (f", read over {windows} windows, each with its margin" if windows else ""))


__all__ = ["FL_RANGE", "MAX_WINDOWS", "MarginCut", "READING_MARGIN", "ReportSelection", "SELECTION_INPUTS",
           "SensorRef", "SensorWindow", "TimeBound", "WindowError", "check_order", "describe", "in_area",
           "parse_fl", "parse_sensor", "parse_time", "parse_window", "recorded", "select_reports",
           "sensor_parts", "span_windows", "with_site"]
