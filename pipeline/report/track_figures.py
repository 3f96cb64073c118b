"""A PNG per tracked aircraft: the fused track with its 2-sigma ellipses at intervals, every sensor's raw
reports, coasted parts dashed, surface movements zoomed in panels of their own, and the mode probabilities
against time (bare Agg figures)."""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterator
from pathlib import Path

import matplotlib.dates as mdates
import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse, Rectangle

from msdc.pipeline.model.coasting import MISSED_UPDATE_FACTOR, coasted_time
from msdc.pipeline.report.canvas import FIGURE_PNG_COMPRESS_LEVEL, new_figure, save_png
from msdc.pipeline.report.figure_pool import FigureTask, render

_SENSOR_COLORS = ("#d62728", "#1f77b4", "#9467bd", "#8c564b", "#e377c2", "#17becf")
ADSB_COLOR = "#e6b800"
TRACK_COLOR = "#111111"
ZOOM_COLOR = "#ff7f0e"
ELLIPSE_SIGMA = 2.0  # drawn ellipses hold about 86 % of the 2-D position error
ELLIPSE_EVERY = 12  # about this many ellipses per aircraft
# Surface movements: the tracker's speed below the noise estimate's surface class limit (taxi speeds stay
# under ~30 kt, nothing flies below ~100 kt). A surface part spanning less than ZOOM_SHARE of the map (a
# taxi before a 60 km climb-out is a dot) gets a zoomed panel; parts farther apart than ZOOM_APART_KM are
# different aerodromes, at most MAX_ZOOMS panels (departure and arrival), each (and the map) at least
# MIN_ZOOM_KM wide.
SURFACE_SPEED_KT = 50.0
ZOOM_SHARE = 0.1
ZOOM_APART_KM = 5.0
MAX_ZOOMS = 2
MIN_ZOOM_UPDATES = 10  # a part's reports needed for a zoom (a lone report coasted at 0 kt is no taxi)
MIN_ZOOM_KM = 0.3
MAP_WIDTH_IN, ZOOM_WIDTH_IN, MODE_HEIGHT_IN = 8.0, 3.6, 2.2
# the figure's own layout (inches): margins left, right, top, bottom for tick labels, axis labels and the
# title; the gap between rows (the map's x label and the mode panel's legend above it), between the map and
# the zoom panels (their tick labels), and the mode panel's axes
MARGINS_IN = (0.85, 0.3, 0.45, 0.6)
ROW_GAP_IN, COLUMN_GAP_IN, MODE_AXES_IN = 0.95, 0.6, MODE_HEIGHT_IN - 0.6
MAP_ASPECT = (0.45, 1.2)  # the map's height over width lies within these


def _local_km(lat: np.ndarray, lon: np.ndarray, lat0: float, lon0: float) -> tuple[np.ndarray, np.ndarray]:
    """East and north in km from (lat0, lon0), equirectangular: plenty for a picture of one flight."""
    k = 6371.0088 * math.pi / 180.0
    dlon = (np.asarray(lon, float) - lon0 + 180.0) % 360.0 - 180.0
    return dlon * k * math.cos(math.radians(lat0)), (np.asarray(lat, float) - lat0) * k


def _box(e: np.ndarray, n: np.ndarray, pad_share: float, min_span: float) -> tuple[float, ...]:
    """(east min, east max, north min, north max) around the points: each side at least min_span, padded by
    pad_share of the larger side."""
    e0, e1, n0, n1 = np.nanmin(e), np.nanmax(e), np.nanmin(n), np.nanmax(n)
    pad = pad_share * max(e1 - e0, n1 - n0, min_span)
    grow_e, grow_n = max(min_span - (e1 - e0), 0.0) / 2, max(min_span - (n1 - n0), 0.0) / 2
    return e0 - pad - grow_e, e1 + pad + grow_e, n0 - pad - grow_n, n1 + pad + grow_n


def _square(e0: float, e1: float, n0: float, n1: float) -> tuple[float, float, float, float]:
    """The box grown on its shorter side to a square around the same centre."""
    half = max(e1 - e0, n1 - n0) / 2
    ce, cn = (e0 + e1) / 2, (n0 + n1) / 2
    return ce - half, ce + half, cn - half, cn + half


def _zoom_box(e: np.ndarray, n: np.ndarray) -> tuple[float, float, float, float]:
    """A surface part's square zoom box (east min, east max, north min, north max), km."""
    return _square(*_box(e, n, 0.1, MIN_ZOOM_KM))


def surface_parts(speed_kt: np.ndarray, coasted: np.ndarray, e: np.ndarray, n: np.ndarray,
                  span_km: float) -> list[np.ndarray]:
    """Row indices of the surface movements worth a zoomed panel, in time order: runs of rows slower than
    SURFACE_SPEED_KT, merged while within ZOOM_APART_KM, kept with MIN_ZOOM_UPDATES updates when their zoom
    box is under ZOOM_SHARE of the map's span (span_km)."""
    slow = np.asarray(speed_kt, float) < SURFACE_SPEED_KT
    edges = np.flatnonzero(np.diff(np.r_[False, slow, False].astype(np.int8)))
    parts: list[np.ndarray] = []
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        run = np.arange(start, stop)
        for k, part in enumerate(parts):
            apart_km = math.hypot(np.mean(e[part]) - np.mean(e[run]), np.mean(n[part]) - np.mean(n[run]))
            if apart_km < ZOOM_APART_KM:
                parts[k] = np.r_[part, run]
                break
        else:
            parts.append(run)
    small = [p for p in parts if np.count_nonzero(~coasted[p]) >= MIN_ZOOM_UPDATES
             and np.subtract(*_zoom_box(e[p], n[p])[1::-1]) < ZOOM_SHARE * span_km]
    return sorted(sorted(small, key=len, reverse=True)[:MAX_ZOOMS], key=lambda p: p[0])


def _draw_reports(ax: Axes, reports: pd.DataFrame, lat0: float, lon0: float, *, big: bool = False) -> None:
    """Every sensor's raw reports: ADS-B as dots, each radar as crosses of its own colour."""
    colors = iter(_SENSOR_COLORS)
    for sid, g in reports.groupby("sensor_id", sort=True, observed=True):
        e, n = _local_km(g["latitude"].to_numpy(), g["longitude"].to_numpy(), lat0, lon0)
        adsb = str(g["sensor_kind"].iloc[0]) == "adsb"
        ax.plot(e, n, ls="none", marker="." if adsb else "+", ms=(3 if adsb else 5) * (1.6 if big else 1.0),
                color=ADSB_COLOR if adsb else next(colors, "#7f7f7f"),
                label=f"{sid} ({g['sensor_kind'].iloc[0]}, {len(g)} reports)", zorder=2)


def coasting(tracks: pd.DataFrame) -> np.ndarray:
    """The rows drawn as coasted: more than MISSED_UPDATE_FACTOR expected update intervals after the last
    update (``age_s``; the interval that of the slowest sensor, pipeline.model.coasting.coasted_time, as the
    summary's coasted_s counts it). On a 1 s grid most rows fall between two reports (``coasted``: no
    report at that time), and dashing them drew every reported stretch as coasted; without ``age_s``
    (a table of other origin) the ``coasted`` flags."""
    coasted = tracks["coasted"].to_numpy(bool)
    if "age_s" not in tracks:
        return coasted
    update = ~coasted
    t = tracks["time_of_day"].to_numpy(float) if "time_of_day" in tracks else (
        (tracks["time"] - tracks["time"].min()).dt.total_seconds().to_numpy())
    seg = tracks["segment"].to_numpy()
    sources = (tracks["sources"].astype(str).to_numpy() if "sources" in tracks
               else np.full(len(tracks), "", dtype=object))
    rows = [(t[i], seg[i], s) for i in np.flatnonzero(update) for s in (str(sources[i]).split(",") or [""])]
    if not rows:
        return coasted
    ut, useg, usensor = (np.array(v) for v in zip(*rows, strict=True))
    order = np.lexsort((ut, useg))
    interval, _ = coasted_time(ut[order], useg[order], usensor[order])
    if not np.isfinite(interval):
        return coasted
    return tracks["age_s"].to_numpy(float) > MISSED_UPDATE_FACTOR * interval


def _draw_track(ax: Axes, e: np.ndarray, n: np.ndarray, coasted: np.ndarray, seg: np.ndarray) -> None:
    """Each segment of the fused track: updated stretches solid, coasted ones (``coasting``) dashed from
    the last update."""
    for s in np.unique(seg):
        sel = np.flatnonzero(seg == s)
        ee, nn, cc = e[sel], n[sel], coasted[sel]
        ax.plot(np.where(cc, np.nan, ee), np.where(cc, np.nan, nn), color=TRACK_COLOR, lw=1.0, zorder=4)
        dash = cc | np.r_[cc[1:], False]
        ax.plot(np.where(dash, ee, np.nan), np.where(dash, nn, np.nan), color=TRACK_COLOR, lw=1.0,
                ls=(0, (3, 2)), zorder=4)


def _draw_ellipses(ax: Axes, tracks: pd.DataFrame, e: np.ndarray, n: np.ndarray, span_km: float) -> None:
    """ELLIPSE_SIGMA ellipses at about ELLIPSE_EVERY rows, magnified by a round factor so that the median
    one is about 2 % of the map."""
    every = max(len(tracks) // ELLIPSE_EVERY, 1)
    picks = np.arange(every // 2, len(tracks), every)
    median_km = float(np.nanmedian(tracks["sigma_major_m"].to_numpy(float)[picks])) * ELLIPSE_SIGMA / 1000.0
    scale = max(1.0, 10.0 ** math.floor(math.log10(0.02 * span_km / median_km))) if median_km > 0 else 1.0
    k = 2 * ELLIPSE_SIGMA * scale / 1000.0
    minor, major = tracks["sigma_minor_m"].to_numpy(float), tracks["sigma_major_m"].to_numpy(float)
    angle = (tracks["ellipse_orientation_deg"].to_numpy(float) if "ellipse_orientation_deg" in tracks
             else np.zeros(len(tracks)))
    for i in picks:
        ax.add_patch(Ellipse((e[i], n[i]), k * minor[i], k * major[i], angle=-float(angle[i]), fill=False,
                             color="#2ca02c", lw=1.0, zorder=5))
    ax.plot([], [], color="#2ca02c", lw=1.0,
            label=f"{ELLIPSE_SIGMA:g}-sigma position ellipse, drawn x{scale:g}")


def _layout(span_e: float, span_n: float, zooms: int) -> tuple[Figure, Axes, list[Axes], Axes]:
    """The figure: the map (its height following its shape), up to MAX_ZOOMS zoom panels to its right,
    and the mode probabilities below across the width."""
    left, right, top, bottom = MARGINS_IN
    map_w = MAP_WIDTH_IN - left - (0.0 if zooms else right)
    map_h = map_w * span_n / span_e
    width = MAP_WIDTH_IN + (ZOOM_WIDTH_IN if zooms else 0.0)
    rows = max(zooms, 1)
    height = top + map_h + ROW_GAP_IN + MODE_AXES_IN + bottom
    fig = new_figure(width, height, layout=None)  # placed here: the same margins on every figure
    zoom_w = width - left - map_w - COLUMN_GAP_IN - right
    row_h = (map_h - ROW_GAP_IN * (rows - 1)) / rows
    gs = fig.add_gridspec(rows + 1, 2 if zooms else 1, height_ratios=[row_h] * rows + [MODE_AXES_IN],
                          width_ratios=[map_w, zoom_w] if zooms else None,
                          left=left / width, right=1 - right / width, top=1 - top / height,
                          bottom=bottom / height, hspace=ROW_GAP_IN / ((map_h - ROW_GAP_IN * (rows - 1)
                                                                         + MODE_AXES_IN) / (rows + 1)),
                          wspace=COLUMN_GAP_IN / ((map_w + zoom_w) / 2) if zooms else 0.0)
    ax = fig.add_subplot(gs[:rows, 0])
    zoom_axes = [fig.add_subplot(gs[i, 1]) for i in range(zooms)]
    return fig, ax, zoom_axes, fig.add_subplot(gs[rows, :])


def track_figure(tracks: pd.DataFrame, reports: pd.DataFrame, title: str = "",
                 end: pd.Timestamp | None = None) -> Figure:
    """One aircraft's figure (see ``aircraft_figure``), not yet saved; rows after ``end`` (the recording's
    last report: the tracker coasts on past it) are not drawn."""
    if end is not None:
        tracks = tracks[(tracks["time"] <= end).to_numpy(bool)].reset_index(drop=True)
    lat0, lon0 = float(tracks["latitude"].median()), float(tracks["longitude"].median())
    e_t, n_t = _local_km(tracks["latitude"].to_numpy(), tracks["longitude"].to_numpy(), lat0, lon0)
    coasted, seg = tracks["coasted"].to_numpy(bool), tracks["segment"].to_numpy()
    dashed = coasting(tracks)
    # the map shows the track (gated garbage reports far away would shrink it to a dot)
    span = max(float(np.nanmax(e_t) - np.nanmin(e_t)), float(np.nanmax(n_t) - np.nanmin(n_t)), MIN_ZOOM_KM)
    e0, e1, n0, n1 = _box(e_t, n_t, 0.08, MIN_ZOOM_KM)
    # a map between MAP_ASPECT's height/width shapes: a straight flight is not drawn as a hairline strip
    grow_n = max(MAP_ASPECT[0] * (e1 - e0) - (n1 - n0), 0.0) / 2
    grow_e = max((n1 - n0) / MAP_ASPECT[1] - (e1 - e0), 0.0) / 2
    e0, e1, n0, n1 = e0 - grow_e, e1 + grow_e, n0 - grow_n, n1 + grow_n
    parts = surface_parts(tracks["speed_kt"].to_numpy(float), coasted, e_t, n_t, span)
    fig, ax, zoom_axes, ax_mode = _layout(e1 - e0, n1 - n0, len(parts))
    _draw_reports(ax, reports, lat0, lon0)
    _draw_track(ax, e_t, n_t, dashed, seg)
    ax.plot([], [], color=TRACK_COLOR, lw=1.0, label="fused track")
    ax.plot([], [], color=TRACK_COLOR, lw=1.0, ls=(0, (3, 2)),
            label=f"coasted (no report for over {MISSED_UPDATE_FACTOR:g} update intervals)")
    ax.set_xlim(e0, e1)
    ax.set_ylim(n0, n1)
    _draw_ellipses(ax, tracks, e_t, n_t, span)
    t = tracks["time"].dt.tz_convert(None)
    if parts:  # the reports' map positions, once for every panel
        re_, rn = _local_km(reports["latitude"].to_numpy(), reports["longitude"].to_numpy(), lat0, lon0)
    for k, (part, zax) in enumerate(zip(parts, zoom_axes, strict=True), start=1):
        z0, z1, w0, w1 = _zoom_box(e_t[part], n_t[part])
        inside = (re_ >= z0) & (re_ <= z1) & (rn >= w0) & (rn <= w1)
        _draw_reports(zax, reports[inside], lat0, lon0, big=True)
        _draw_track(zax, e_t, n_t, dashed, seg)
        zax.set_xlim(z0, z1)
        zax.set_ylim(w0, w1)
        zax.set_aspect("equal", adjustable="box")
        zax.grid(True, lw=0.3)
        zax.tick_params(labelsize=7)
        first, last = t.iloc[part[0]], t.iloc[part[-1]]
        zax.set_title(f"{k}: surface, {first:%H:%M:%S}-{last:%H:%M:%S} (km)", fontsize=8)
        for side in zax.spines.values():
            side.set_edgecolor(ZOOM_COLOR)
        ax.add_patch(Rectangle((z0, w0), z1 - z0, w1 - w0, fill=False, color=ZOOM_COLOR, lw=1.2, zorder=6))
        ax.annotate(str(k), (z1, w1), xytext=(3, 3), textcoords="offset points", color=ZOOM_COLOR,
                    fontsize=8, fontweight="bold", zorder=6)
    if parts:
        ax.plot([], [], color=ZOOM_COLOR, lw=1.2, label="surface movement, zoomed at right")
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"east (km) of {lat0:.3f}, {lon0:.3f}")
    ax.set_ylabel("north (km)")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title(title or str(tracks["aircraft_id"].iloc[0]), fontsize=10)
    # one line per track segment: the mode probabilities are not drawn across the time between segments
    bounds = [*np.flatnonzero(np.r_[True, seg[1:] != seg[:-1]]), len(seg)]
    for col, label, color in (("mode_cv", "CV", "#444444"), ("mode_turn_left", "turn left", "#1f77b4"),
                              ("mode_turn_right", "turn right", "#d62728"), ("mode_ca", "CA", "#2ca02c")):
        if col in tracks:
            y = tracks[col].to_numpy(float)
            for k, (a, b) in enumerate(itertools.pairwise(bounds)):
                ax_mode.plot(t.iloc[a:b], y[a:b], color=color, lw=0.9, label=label if k == 0 else None)
    # minutes, or seconds where the ticks are less than a minute apart (a short track's minutes repeat)
    locator = mdates.AutoDateLocator()
    ticks = mdates.AutoDateFormatter(locator)
    ticks.scaled = {1.0: "%m-%d %H:%M", 1 / 24: "%H:%M", 1 / 1440: "%H:%M", 1 / 86400: "%H:%M:%S"}
    ax_mode.xaxis.set_major_locator(locator)
    ax_mode.xaxis.set_major_formatter(ticks)
    ax_mode.set_ylim(-0.02, 1.02)
    ax_mode.set_ylabel("mode probability")
    ax_mode.set_xlabel("time (UTC)")
    ax_mode.grid(True, lw=0.3)
    ax_mode.legend(fontsize=7, loc="lower right", bbox_to_anchor=(1.0, 1.0), ncols=4, frameon=False)
    return fig


def aircraft_figure(tracks: pd.DataFrame, reports: pd.DataFrame, path: str | Path, title: str = "",
                    dpi: int = 130, end: pd.Timestamp | None = None) -> Path:
    """One aircraft: map (km from the track's median position), surface movements zoomed at its right, above
    mode probabilities against time. tracks: the tracker's rows of this aircraft; reports: its measurements
    (sensor_id, sensor_kind, time, latitude, longitude); end: the recording's last report (rows after it
    are left out)."""
    fig = track_figure(tracks, reports, title, end)
    fig.set_dpi(dpi)
    return save_png(fig, path, compress_level=FIGURE_PNG_COMPRESS_LEVEL)
def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "aircraft"


def figure_names(tracks: pd.DataFrame) -> dict[object, tuple[str, str]]:
    """Per aircraft id, in drawing order (the ids sorted): its figure's file name
    (``track_<callsign>_<id>.png`` or ``track_<id>.png``) and title."""
    names = {}
    for ident, g in tracks[["aircraft_id", "callsign"]].groupby("aircraft_id", sort=True, observed=True):
        cs = str(g["callsign"].iloc[0] or "")
        names[ident] = (f"track_{_safe(f'{cs}_{ident}' if cs else str(ident))}.png",
                        f"{cs} ({ident})" if cs else str(ident))
    return names


def figure_tasks(result, directory: str | Path, chosen: list[object]) -> Iterator[FigureTask]:
    """One task per chosen aircraft id (figure_names' keys), made when the pool takes it: that aircraft's
    track rows and reports only."""
    d = Path(directory)
    names = figure_names(result.tracks)
    end = recording_end(result)
    tracks = result.tracks.groupby("aircraft_id", sort=True, observed=True)
    meas = result.measurements
    reports = meas.groupby("aircraft_id", sort=False, observed=True).indices
    for ident in chosen:
        name, title = names[ident]
        rows = reports.get(ident)
        mine = meas.iloc[rows] if rows is not None else meas.iloc[:0]
        yield FigureTask(name, aircraft_figure, {
            "tracks": tracks.get_group(ident).reset_index(drop=True), "reports": mine, "path": d / name,
            "title": title, "end": end})


def track_figures(result, directory: str | Path, workers: int | None = 1) -> dict[str, Path]:
    """One PNG per aircraft of a track job's result (``track_<callsign or id>.png``) in directory, drawn on
    ``workers`` processes (None: every core)."""
    names = figure_names(result.tracks)
    paths = render(figure_tasks(result, directory, list(names)), len(names), workers=workers)
    return {str(ident): path for ident, path in zip(names, paths, strict=True)}


def recording_end(result) -> pd.Timestamp | None:
    """The last report of the inputs (every data source's, Loaded.spans), else of the measurements tracked;
    None when neither is known."""
    spans = getattr(getattr(result, "loaded", None), "spans", None) or []
    ends = [hi for by_source in spans for _, hi in by_source.values() if not pd.isna(hi)]
    if not ends and len(result.measurements):
        ends = [result.measurements["time"].max()]
    return max(ends) if ends else None
