"""PNG figures of a CorrelationRun, drawn on bare Agg figures (no pyplot, no global state)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import matplotlib.dates as mdates
import numpy as np
import pandas as pd
from matplotlib import patheffects
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.text import Text

from msdc.pipeline.correlate.correlation import peak_lag, pearson_max_lag, pearson_search_limit
from msdc.pipeline.correlate.results import CorrelationRun, WindowResult
from msdc.pipeline.model.geodesy import M_PER_NM
from msdc.pipeline.report.canvas import new_figure, save_png  # noqa: F401 - importable here too
from msdc.pipeline.report.summary import aircraft_name, map_nouns, printable, slot_seconds, window_label

RADAR_COLOR = "#d62728"
ADSB_COLOR = "#ffd400"
ADSB_EDGE = "#3d3000"
_STYLE = {
    "radar": {"line": RADAR_COLOR, "face": RADAR_COLOR, "edge": "#7a0000", "lw": 1.1, "ms": 3.6, "z": 4},
    "adsb": {"line": ADSB_COLOR, "face": ADSB_COLOR, "edge": ADSB_EDGE, "lw": 1.6, "ms": 5.6, "z": 3},
}
_LABEL = {"radar": "Radar (CAT048)", "adsb": "ADS-B (CAT021)"}
# what the two roles of a correlation run are, by its --pairs (pipeline.correlate.correlation.PAIR_KINDS)
_PAIR_LABELS = {"mlat-adsb": {"radar": "Multilateration (CAT010/CAT020)", "adsb": "ADS-B (CAT021)"},
                "smr-mlat": {"radar": "Surface radar (CAT010)", "adsb": "Multilateration (CAT010/CAT020)"}}
_MAX_TITLE_CALLSIGNS = 6
_MAX_TRACK_LABELS = 30
MAX_MARKED_SLOTS = 20_000  # past this many slots the map shows lines only: markers would only overplot
# the map's PNG (1300 x 975) at zlib level 1: the same pixels as level 6 in 0.05 s instead of 0.08 (the 3 h
# run's critical path), 5 % more bytes
TRACK_PNG_COMPRESS_LEVEL = 1


def _text(value: object) -> str:
    """Printable label text that matplotlib will not parse as mathtext."""
    return printable(value).replace("$", r"\$")


def _floats(frame: pd.DataFrame, column: str) -> np.ndarray:
    if column not in frame.columns:
        return np.full(len(frame), np.nan)
    return pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float, na_value=np.nan)


def _flags(frame: pd.DataFrame, column: str) -> np.ndarray:
    if column not in frame.columns:
        return np.zeros(len(frame), dtype=bool)
    return frame[column].fillna(False).astype(bool).to_numpy()


def _time_axis(slots: pd.DataFrame) -> tuple[np.ndarray, bool]:
    """Slot times as naive-UTC datetime64 when every timestamp is known, else time_of_day seconds."""
    if "timestamp" in slots.columns and len(slots):
        stamps = pd.to_datetime(slots["timestamp"], utc=True, errors="coerce")
        if stamps.notna().all():
            return stamps.dt.tz_localize(None).to_numpy(), True
    return _floats(slots, "time_of_day"), False


def _draw_sensor(ax: Axes, x: np.ndarray, y: np.ndarray, filled: np.ndarray, sensor: str,
                 markers: bool = True) -> None:
    """One slotted track: a line through every slot, solid markers at measured slots, hollow at filled."""
    st = _STYLE[sensor]
    effects = [patheffects.Stroke(linewidth=st["lw"] + 1.6, foreground=ADSB_EDGE), patheffects.Normal()]
    ax.plot(x, y, color=st["line"], lw=st["lw"], zorder=st["z"],
            path_effects=effects if sensor == "adsb" else None)
    if not markers:
        return
    finite = np.isfinite(y)
    measured, held = finite & ~filled, finite & filled
    ax.plot(x[measured], y[measured], ls="none", marker="o", ms=st["ms"], mfc=st["face"], mec=st["edge"],
            mew=0.7, zorder=st["z"] + 0.1)
    ax.plot(x[held], y[held], ls="none", marker="o", ms=st["ms"], mfc="white", mec=st["edge"], mew=0.9,
            zorder=st["z"] + 0.1)


def _legend_handles(any_filled: bool, labels: dict[str, str] = _LABEL) -> list[Line2D]:
    handles = []
    for sensor in ("radar", "adsb"):
        st = _STYLE[sensor]
        effects = ([patheffects.Stroke(linewidth=st["lw"] + 1.6, foreground=ADSB_EDGE), patheffects.Normal()]
                   if sensor == "adsb" else None)
        handles.append(Line2D([], [], color=st["line"], lw=st["lw"], marker="o", ms=st["ms"], mfc=st["face"],
                              mec=st["edge"], mew=0.7, path_effects=effects, label=labels[sensor]))
    if any_filled:
        handles.append(Line2D([], [], ls="none", marker="o", ms=5, mfc="white", mec="0.3", mew=0.9,
                              label="filled slot (no report)"))
    return handles


def _window_label(window: WindowResult) -> str:
    return f"{_text(aircraft_name(window.summary))} #{_text(window.summary.get('window'))}"


def _callsign_title(windows: list[WindowResult]) -> str:
    names = list(dict.fromkeys(_text(aircraft_name(w.summary)) for w in windows))
    shown = ", ".join(names[:_MAX_TITLE_CALLSIGNS])
    more = len(names) - _MAX_TITLE_CALLSIGNS
    return shown + (f" +{more} more" if more > 0 else "")


# range rings: the smallest of these steps that rings the farthest slot in at most MAX_RINGS (an airport's
# tracks within 25 NM got one 50 NM ring, which set the map's scale: the traffic filled a quarter of it)
RING_STEPS_NM = (1.0, 2.0, 5.0, 10.0, 25.0, 50.0, 100.0)
MAX_RINGS = 5


def range_ring(lat: float, lon: float, radius_nm: float, points: int = 181) -> tuple[np.ndarray, np.ndarray]:
    """Longitudes and latitudes of a circle of ``radius_nm`` around a site on the WGS-84 ellipsoid."""
    from pyproj import Geod

    azimuths = np.linspace(0.0, 360.0, points)
    lons, lats, _ = Geod(ellps="WGS84").fwd(np.full(points, lon), np.full(points, lat), azimuths,
                                             np.full(points, radius_nm * M_PER_NM))
    return np.asarray(lons), np.asarray(lats)


_SPHERE_M = 6_371_008.8  # mean Earth radius
# a geodesic on WGS-84 is within 0.6 % of the great circle on the mean sphere: a point more than 2 % nearer
# on the sphere than the farthest one there cannot be the farthest on the ellipsoid
_FARTHEST_MARGIN = 0.02


def farthest_m(geod, lat: float, lon: float, lats: np.ndarray, lons: np.ndarray) -> float:
    """The longest WGS-84 geodesic distance (m) from (lat, lon) to the points (0 with none): exact, measured
    only for the points the great circle on the mean sphere (haversine) leaves in contention."""
    if not lats.size:
        return 0.0
    phi, phi0 = np.radians(lats), math.radians(lat)
    h = (np.sin((phi - phi0) / 2) ** 2
         + math.cos(phi0) * np.cos(phi) * np.sin(np.radians(lons - lon) / 2) ** 2)
    sphere_m = 2 * _SPHERE_M * np.arcsin(np.sqrt(np.clip(h, 0.0, 1.0)))
    near = sphere_m >= (1 - _FARTHEST_MARGIN) * sphere_m.max()
    n = int(near.sum())
    _, _, dist_m = geod.inv(np.full(n, lon), np.full(n, lat), lons[near], lats[near])
    return float(np.max(dist_m))


def _window_sites(sensors: pd.DataFrame | None, run: CorrelationRun) -> pd.DataFrame | None:
    """The sensor file's entries of the sensors the windows correlate (a CAT048 radar; a CAT010 entry by
    its kind): the LEBL multilateration's map drew the surface radar's point and rings too, not in the
    pair. Every entry when none of them is (a hand-made run)."""
    if sensors is None or sensors.empty or not run.windows:
        return sensors
    from msdc.pipeline.model.report_selection import sensor_parts

    ids = {str(w.summary.get(k)) for w in run.windows for k in ("radar_sensor", "reference_sensor")}
    wanted = {(int(c), int(a), int(b), k if c == 10 else None)
              for c, a, b, k in sensor_parts(sorted(ids)).itertuples(index=False) if c >= 0}
    kind = sensors["kind"] if "kind" in sensors else pd.Series(None, index=sensors.index)
    category = sensors["category"] if "category" in sensors else pd.Series(48, index=sensors.index)
    keys = [(int(c), int(a), int(b), k if c == 10 else None)
            for c, a, b, k in zip(category, sensors["sac"], sensors["sic"], kind, strict=True)]
    mine = sensors[[key in wanted for key in keys]]
    return mine if len(mine) else sensors


def ring_step_nm(far_nm: float) -> float:
    """The rings' step: the smallest of RING_STEPS_NM that reaches ``far_nm`` in at most MAX_RINGS rings."""
    return next((step for step in RING_STEPS_NM if far_nm <= MAX_RINGS * step), RING_STEPS_NM[-1])


def _draw_sites(ax: Axes, sensors: pd.DataFrame | None, lats: np.ndarray, lons: np.ndarray) -> float | None:
    """Radar sites (triangle and name) and range rings out to the farthest slot, every ring_step_nm of the
    farthest; the step (None without sites)."""
    if sensors is None or sensors.empty:
        return None
    from pyproj import Geod

    geod = Geod(ellps="WGS84")
    ok = np.isfinite(lats) & np.isfinite(lons)
    sites = [(float(row.latitude), float(row.longitude)) for row in sensors.itertuples(index=False)]
    far = [farthest_m(geod, lat, lon, lats[ok], lons[ok]) / M_PER_NM for lat, lon in sites]
    step = ring_step_nm(max(far))
    for (lat, lon), far_nm, row in zip(sites, far, sensors.itertuples(index=False), strict=True):
        for k in range(1, max(1, math.ceil(far_nm / step)) + 1):
            ring_lon, ring_lat = range_ring(lat, lon, k * step)
            ax.plot(ring_lon, ring_lat, color="0.55", lw=0.7, ls=":", zorder=1)
            _label(ax, f"{k * step:g} NM", (ring_lon[0], ring_lat[0]), fontsize=7, color="0.4",
                   zorder=2, gid=_RING_LABEL)
        ax.plot(lon, lat, marker="^", ms=10, color="black", mfc="#4d4d4d", ls="none", zorder=7)
        _label(ax, _text(getattr(row, "name", "radar")), (lon, lat), fontsize=8, fontweight="bold", zorder=7,
               gid=_SITE_LABEL)
    return step


def _clock_label(slots: pd.DataFrame, k: int) -> str:
    """HH:MM UTC of slot ``k`` (from the timestamp, else the time of day)."""
    x, is_time = _time_axis(slots)
    if is_time:
        return pd.Timestamp(x[k]).strftime("%H:%M")
    tod = float(x[k])
    return f"{int(tod // 3600) % 24:02d}:{int(tod % 3600 // 60):02d}" if math.isfinite(tod) else ""


def _direction_and_times(ax: Axes, window: WindowResult, label: bool) -> None:
    """Arrows along the ADS-B slotted track (direction of flight) and the start and end times."""
    s = window.slots
    lon, lat = _floats(s, "adsb_lon"), _floats(s, "adsb_lat")
    ok = np.flatnonzero(np.isfinite(lon) & np.isfinite(lat))
    if ok.size < 2:
        return
    for frac in (0.35, 0.7):
        i = ok[int(frac * (ok.size - 1))]
        j = ok[min(np.searchsorted(ok, i) + 2, ok.size - 1)]
        if i != j:
            ax.annotate("", xy=(lon[j], lat[j]), xytext=(lon[i], lat[i]), zorder=6,
                        arrowprops={"arrowstyle": "-|>", "color": "black", "lw": 1.0, "mutation_scale": 14})
    bbox = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.6", "alpha": 0.85}
    start = (f"{_window_label(window)} " if label else "") + _clock_label(s, ok[0])
    _label(ax, start, (lon[ok[0]], lat[ok[0]]), fontsize=7, zorder=6, bbox=bbox, gid=_START_LABEL,
           arrowprops={"arrowstyle": "-", "color": "0.35", "lw": 0.6, "shrinkA": 0, "shrinkB": 0})
    _label(ax, _clock_label(s, ok[-1]), (lon[ok[-1]], lat[ok[-1]]), fontsize=7, zorder=6, color="0.25",
           gid=_END_LABEL)


# Map labels, placed after everything else is drawn (place_labels) in this order: site names, window starts,
# window ends, ring distances; each takes the first of LABEL_OFFSETS_PT where it overlaps no label already
# placed and stays inside the axes, else it is left out (the same text at the same point only once)
_SITE_LABEL, _START_LABEL, _END_LABEL, _RING_LABEL = "site", "start", "end", "ring"
_LABEL_ORDER = (_SITE_LABEL, _START_LABEL, _END_LABEL, _RING_LABEL)
LABEL_OFFSETS_PT = ((5, 5), (5, -13), (-5, 5), (-5, -13), (5, 16), (-5, 16), (5, -24), (-5, -24), (14, -4),
                    (-14, -4), (5, 28), (-5, 28), (5, -36), (-5, -36), (30, 30), (-30, 30), (30, -40),
                    (-30, -40), (45, 0), (-45, 0), (10, 45), (-10, 45), (10, -55), (-10, -55), (60, 30),
                    (-60, 30), (60, -40), (-60, -40))


def _label(ax: Axes, text: str, xy: tuple[float, float], **style) -> None:
    """A map label at ``xy`` (data), its place chosen later by place_labels (``gid``: its kind)."""
    ann = ax.annotate(text, xy, xytext=LABEL_OFFSETS_PT[0], textcoords="offset points", **style)
    ann.set_in_layout(False)  # placing it never moves the layout the other labels were placed in


def place_labels(fig: Figure, ax: Axes) -> int:
    """Move each map label to the first offset where it overlaps no label placed before it (nor the legend)
    and stays inside the axes; hide it when none does, or when the same text at the same point is shown.
    Returns the number of window start labels left out for want of room."""
    labels = [a for a in ax.texts if a.get_gid() in _LABEL_ORDER]
    missed = 0
    if not any(a.get_gid() == _START_LABEL for a in labels):  # a long run's map (no window labels): sites
        return missed  # and rings as they are, without the extra draw of every track
    fig.draw_without_rendering()  # once: the layout and the legend's place are final
    renderer = fig.canvas.get_renderer()
    inside = ax.get_window_extent(renderer)
    legend = ax.get_legend()
    kept = [legend.get_window_extent(renderer)] if legend is not None else []
    seen: set[tuple] = set()
    for ann in sorted(labels, key=lambda a: _LABEL_ORDER.index(a.get_gid())):
        # a window start names its aircraft, number and time: one label, whichever sensor pair (numbers
        # restart per pair, and each pair's slots sit a little apart); other labels once per text and place
        where = () if ann.get_gid() == _START_LABEL else tuple(np.round(np.asarray(ann.xy, dtype=float), 2))
        key = (ann.get_gid(), ann.get_text(), *where)
        if key in seen:
            ann.set_visible(False)
            continue
        seen.add(key)
        for dx, dy in LABEL_OFFSETS_PT:
            ann.xyann = (dx, dy)
            ann.set_horizontalalignment("left" if dx >= 0 else "right")
            box = Text.get_window_extent(ann, renderer).padded(2)  # the text and its box, not the leader
            if (box.x0 >= inside.x0 and box.x1 <= inside.x1 and box.y0 >= inside.y0 and box.y1 <= inside.y1
                    and not any(box.overlaps(k) for k in kept)):
                kept.append(box)
                break
        else:
            ann.set_visible(False)
            missed += ann.get_gid() == _START_LABEL
    return missed


def track_figure(run: CorrelationRun, path_png: str | os.PathLike[str],
                 sensors: pd.DataFrame | None = None) -> Path:
    """Map of every window's slotted tracks (track_map) written as PNG; returns the path."""
    return save_png(track_map(run, sensors), path_png, TRACK_PNG_COMPRESS_LEVEL)


def track_map(run: CorrelationRun, sensors: pd.DataFrame | None = None) -> Figure:
    """Map of every window's slotted tracks (radar red over ADS-B yellow) with direction arrows and start
    and end times (UTC), labels placed apart (place_labels); with ``sensors``, the radar sites and range
    rings."""
    fig = new_figure(10, 7.5)
    ax = fig.add_subplot()
    lats: list[np.ndarray] = []
    lons: list[np.ndarray] = []
    any_filled = False
    # every window's track of one sensor kind in one line (NaN between windows breaks it) and one set of
    # markers: the same picture as one artist per window (z-order sets the layers), far fewer artists
    tracks: dict[str, list[np.ndarray]] = {"adsb": [], "radar": []}
    gap = np.array([np.nan])
    for w in run.windows:
        s = w.slots
        # a radar-radar window's reference is a radar: drawn as one, never as ADS-B
        second_radar = str(w.summary.get("reference_sensor") or "").startswith("048:")
        for sensor in ("adsb", "radar"):  # radar on top so both stay visible where they overlap
            lon, lat = _floats(s, f"{sensor}_lon"), _floats(s, f"{sensor}_lat")
            filled = _flags(s, f"{sensor}_filled")
            any_filled |= bool((filled & np.isfinite(lat)).any())
            kind = "radar" if second_radar else sensor
            tracks[kind].append(np.stack([np.concatenate([lon, gap]), np.concatenate([lat, gap]),
                                          np.concatenate([filled, [False]])]))
            lats.append(lat)
            lons.append(lon)
        if len(run.windows) <= _MAX_TRACK_LABELS:
            _direction_and_times(ax, w, label=len(run.windows) > 1)
    n_slots = sum(len(w.slots) for w in run.windows)
    markers = n_slots <= MAX_MARKED_SLOTS
    for sensor, parts in tracks.items():
        if parts:
            lon, lat, filled = np.concatenate(parts, axis=1)
            _draw_sensor(ax, lon, lat, filled.astype(bool), sensor, markers)
    all_lat = np.concatenate(lats) if lats else np.array([])
    all_lon = np.concatenate(lons) if lons else np.array([])
    sensors = _window_sites(sensors, run)
    step = _draw_sites(ax, sensors, all_lat, all_lon) if run.windows else None
    finite_lat = all_lat[np.isfinite(all_lat)]
    if finite_lat.size:
        coslat = math.cos(math.radians(float(np.mean(finite_lat))))
        if coslat > 0.01:
            ax.set_aspect(1.0 / coslat, adjustable="datalim")
        pairs = str(run.parameters.get("pairs", ""))
        handles = _legend_handles(any_filled, _PAIR_LABELS.get(pairs, _LABEL))
        if step is not None:
            handles.append(Line2D([], [], marker="^", ms=9, color="black", mfc="#4d4d4d", ls="none",
                                  label="reference point" if pairs in _PAIR_LABELS else "radar site"))
            handles.append(Line2D([], [], color="0.55", lw=0.7, ls=":",
                                  label=f"range ring every {step:g} NM"))
        handles.append(Line2D([], [], marker=r"$\rightarrow$", ms=10, color="black", ls="none",
                              label="direction of flight; times UTC"))
        # inside the axes wherever "best" puts it, so it cannot move the constrained layout: left out of
        # the layout's passes, which each searched every slot for its best place again
        ax.legend(handles=handles, loc="best", framealpha=0.9, fontsize=8).set_in_layout(False)
    else:
        ax.text(0.5, 0.5, "No correlated windows", ha="center", va="center", transform=ax.transAxes,
                fontsize=14, color="0.4")
    ax.ticklabel_format(useOffset=False)
    ax.margins(0.06)
    ax.grid(True, color="0.88", lw=0.6)
    ax.set_axisbelow(True)
    ax.set_xlabel("Longitude (deg, WGS-84)")
    ax.set_ylabel("Latitude (deg, WGS-84)")
    fig.suptitle(f"Slotted tracks: {_callsign_title(run.windows) or 'none'}", fontsize=13, fontweight="bold")
    unmarked = "" if markers else f"; {n_slots:,} slots: lines only, no slot markers"
    first, second = map_nouns(run.parameters.get("pairs"))  # the Map sheet's title says the same
    ax.set_title(f"{first} (red) over {second} (yellow), {len(run.windows)} window(s), equal-distance aspect"
                 f"{unmarked}", fontsize=9, color="0.35")
    missed = place_labels(fig, ax)
    if missed:  # said, not hidden silently
        ax.set_title(f"{ax.get_title()}; {missed} window label(s) left out for want of room", fontsize=9,
                     color="0.35")
    return fig


def figure_peak(lags, r, measure: str) -> tuple[int | None, bool]:
    """Index of the peak the lag figure marks, by the rule of the summary numbers (NCC over every lag,
    Pearson over |lag| <= pearson_search_limit), and whether it sits at the search limit (then no lag
    estimate: marked hollow); None when there is no finite value."""
    lags = np.asarray(lags)
    n_slots = (lags.size + 1) // 2
    if measure != "pearson":
        lag, at_limit = peak_lag(lags, r), False
    else:
        limit = pearson_search_limit(n_slots)
        lag = peak_lag(lags, r, limit) if limit >= 1 else None
        at_limit = lag is not None and abs(lag) == limit
    return (None if lag is None else int(np.flatnonzero(lags == lag)[0])), at_limit


def lag_figure(window: WindowResult, path: str | os.PathLike[str]) -> Path:
    """NCC and Pearson coefficient against lag for |lag| <= N/2 (latitude and longitude panels), the peak
    of each marked by the rule of the summary numbers; returns the path."""
    fig = new_figure(10, 4.2)
    lags = window.lags.sort_values("lag") if "lag" in window.lags.columns else window.lags
    x = _floats(lags, "lag")
    half = pearson_max_lag((x.size + 1) // 2)
    inside = np.abs(x) <= half
    peaks: list[tuple[Axes, Text, Line2D]] = []
    for i, axis in enumerate(("lat", "lon")):
        ax = fig.add_subplot(1, 2, i + 1)
        ax.axvline(0, color="0.6", lw=0.8, zorder=1)
        shown: list[np.ndarray] = []
        for measure, color, ls in (("ncc", "#1f77b4", "-"), ("pearson", "#2ca02c", "--")):
            y = _floats(lags, f"{measure}_{axis}")
            label = "NCC" if measure == "ncc" else "Pearson"
            ax.plot(x[inside], y[inside], color=color, ls=ls, lw=1.4, label=label, zorder=3)
            shown.append(y[inside])
            k, at_limit = figure_peak(x, y, measure)
            flat = measure == "pearson" and window.summary.get(f"pearson_lag_unidentified_{axis}") is True
            if k is not None and inside[k]:
                # the label on the side towards the middle, so a peak at the edge keeps it inside the axes
                right = x[k] <= 0
                if at_limit or flat:  # no lag estimate: a hollow mark, said in words
                    (mark,) = ax.plot(x[k], y[k], marker="o", ms=9, mfc="white", mec=color, mew=1.4,
                                      ls="none", zorder=4, clip_on=False)
                    why = "search limit" if at_limit else "straight leg, not identified"
                    text = f"{int(x[k]):+d}: {why}, no estimate"
                else:
                    (mark,) = ax.plot(x[k], y[k], marker="*", ms=12, color=color, mec="black", mew=0.6,
                                      ls="none", zorder=4, clip_on=False)
                    text = f"{int(x[k]):+d}"
                label = ax.annotate(text, (x[k], y[k]), xytext=(10 if right else -10, 6),
                                    textcoords="offset points", ha="left" if right else "right", fontsize=8,
                                    color=color, zorder=5)
                peaks.append((ax, label, mark))
        values = np.concatenate(shown) if shown else np.array([])
        values = values[np.isfinite(values)]
        if values.size:
            low, high = float(values.min()), float(values.max())
            pad = max(0.02, 0.08 * (high - low))
            ax.set_ylim(max(-1.05, low - pad), min(1.05, high + pad))
        if half > 0:  # a little room beyond the limits, so a mark there is drawn whole
            ax.set_xlim(-half - 0.03 * half - 0.5, half + 0.03 * half + 0.5)
        ax.set_title("Latitude" if axis == "lat" else "Longitude", fontsize=10)
        ax.set_xlabel(f"lag (slots), |lag| <= N/2 = {half}")
        ax.set_ylabel("coefficient")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, color="0.88", lw=0.6)
        ax.legend(fontsize=8, loc="lower center")
    step = slot_seconds(window)
    note = f", 1 slot = {step:g} s" if math.isfinite(step) else ""
    fig.suptitle(f"Correlation against lag: {window_label(window.summary)}{note}\n(star = peak, hollow = "
                 "peak at the search limit; wider lags, with less than half the slots overlapping, left out)",
                 fontsize=10)
    place_peak_labels(fig, peaks)
    return save_png(fig, path)


# where a peak's label may go, in points from the peak: beside it on the side towards the middle first,
# then below, above and on the other side; each clears the largest mark (a 12 pt star: 6 pt radius)
_PEAK_LABEL_OFFSETS_PT = [(10, 6), (10, -14), (0, 10), (0, -20), (-10, 6), (-10, -14), (16, -4), (-16, -4)]
LABEL_CLEARANCE_PX = 1.0


def place_peak_labels(fig: Figure, peaks: list[tuple[Axes, Text, Line2D]]) -> None:
    """Move each peak label (its axes, text, mark) to the first of _PEAK_LABEL_OFFSETS_PT (mirrored for a
    label on the left) where it covers no peak mark and no label placed before it and stays inside its
    axes; where none is free, the first. The NCC and Pearson peaks at one lag, and a label 7 pt beside a
    12 pt star, drew their labels over the marks."""
    if not peaks:
        return
    fig.draw_without_rendering()  # the layout settled: the marks' and labels' extents are final
    renderer = fig.canvas.get_renderer()
    marks = {id(ax): [m.get_window_extent(renderer) for a, _, m in peaks if a is ax] for ax, _, _ in peaks}
    placed = []
    for ax, label, _ in peaks:
        left = label.get_horizontalalignment() == "right"
        area = ax.get_window_extent(renderer)
        for n, (dx, dy) in enumerate(_PEAK_LABEL_OFFSETS_PT):
            dx = -dx if left else dx
            label.set_horizontalalignment("center" if dx == 0 else ("right" if dx < 0 else "left"))
            label.xyann = (dx, dy)
            box = label.get_window_extent(renderer).padded(LABEL_CLEARANCE_PX)
            clear = not any(box.overlaps(other) for other in [*marks[id(ax)], *placed])
            inside = area.x0 <= box.x0 and box.x1 <= area.x1 and area.y0 <= box.y0 and box.y1 <= area.y1
            if clear and inside:
                break
            if n == len(_PEAK_LABEL_OFFSETS_PT) - 1:  # nowhere free: the first place
                dx0, dy0 = _PEAK_LABEL_OFFSETS_PT[0]
                label.set_horizontalalignment("right" if left else "left")
                label.xyann = (-dx0 if left else dx0, dy0)
        placed.append(label.get_window_extent(renderer).padded(LABEL_CLEARANCE_PX))


def latlon_time_figure(window: WindowResult, path: str | os.PathLike[str]) -> Path:
    """Radar and ADS-B slotted latitude and longitude against time; returns the path."""
    fig = new_figure(10, 6)
    s = window.slots
    x, is_time = _time_axis(s)
    axes = fig.subplots(2, 1, sharex=True)
    for ax, axis, name in ((axes[0], "lat", "Latitude (deg)"), (axes[1], "lon", "Longitude (deg)")):
        for sensor in ("adsb", "radar"):
            _draw_sensor(ax, x, _floats(s, f"{sensor}_{axis}"), _flags(s, f"{sensor}_filled"), sensor)
        ax.set_ylabel(name)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, color="0.88", lw=0.6)
    any_filled = any(bool((_flags(s, f"{sensor}_filled") & np.isfinite(_floats(s, f"{sensor}_{axis}"))).any())
                     for sensor in ("radar", "adsb") for axis in ("lat", "lon"))
    axes[0].legend(handles=_legend_handles(any_filled), fontsize=8, loc="best")
    if is_time:
        locator = mdates.AutoDateLocator()
        axes[1].xaxis.set_major_locator(locator)
        axes[1].xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
        axes[1].set_xlabel("time (UTC)")
    else:
        axes[1].set_xlabel("time of day (s)")
    fig.suptitle(f"Latitude and longitude against time: {window_label(window.summary)}", fontsize=11)
    return save_png(fig, path)
