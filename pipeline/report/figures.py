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
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from pipeline.correlate.results import CorrelationRun, WindowResult
from pipeline.report.summary import printable, slot_seconds

RADAR_COLOR = "#d62728"
ADSB_COLOR = "#ffd400"
ADSB_EDGE = "#3d3000"
_STYLE = {
    "radar": {"line": RADAR_COLOR, "face": RADAR_COLOR, "edge": "#7a0000", "lw": 1.1, "ms": 3.6, "z": 4},
    "adsb": {"line": ADSB_COLOR, "face": ADSB_COLOR, "edge": ADSB_EDGE, "lw": 1.6, "ms": 5.6, "z": 3},
}
_LABEL = {"radar": "Radar (CAT048)", "adsb": "ADS-B (CAT021)"}
_MAX_TITLE_CALLSIGNS = 6
_MAX_TRACK_LABELS = 30


def new_figure(width: float, height: float, dpi: int = 130) -> Figure:
    """A white, constrained-layout Figure on its own Agg canvas (no pyplot state)."""
    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained", facecolor="white")
    FigureCanvasAgg(fig)
    return fig


def save_png(fig: Figure, path: str | os.PathLike[str]) -> Path:
    """Write the figure as PNG, creating the folder; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, format="png", facecolor="white")
    return path


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


def _draw_sensor(ax: Axes, x: np.ndarray, y: np.ndarray, filled: np.ndarray, sensor: str) -> None:
    """One slotted track: a line through every slot, solid markers at measured slots, hollow at filled."""
    st = _STYLE[sensor]
    effects = [patheffects.Stroke(linewidth=st["lw"] + 1.6, foreground=ADSB_EDGE), patheffects.Normal()]
    ax.plot(x, y, color=st["line"], lw=st["lw"], zorder=st["z"],
            path_effects=effects if sensor == "adsb" else None)
    finite = np.isfinite(y)
    measured, held = finite & ~filled, finite & filled
    ax.plot(x[measured], y[measured], ls="none", marker="o", ms=st["ms"], mfc=st["face"], mec=st["edge"],
            mew=0.7, zorder=st["z"] + 0.1)
    ax.plot(x[held], y[held], ls="none", marker="o", ms=st["ms"], mfc="white", mec=st["edge"], mew=0.9,
            zorder=st["z"] + 0.1)


def _legend_handles(any_filled: bool) -> list[Line2D]:
    handles = []
    for sensor in ("radar", "adsb"):
        st = _STYLE[sensor]
        effects = ([patheffects.Stroke(linewidth=st["lw"] + 1.6, foreground=ADSB_EDGE), patheffects.Normal()]
                   if sensor == "adsb" else None)
        handles.append(Line2D([], [], color=st["line"], lw=st["lw"], marker="o", ms=st["ms"], mfc=st["face"],
                              mec=st["edge"], mew=0.7, path_effects=effects, label=_LABEL[sensor]))
    if any_filled:
        handles.append(Line2D([], [], ls="none", marker="o", ms=5, mfc="white", mec="0.3", mew=0.9,
                              label="filled slot (no report)"))
    return handles


def _window_label(window: WindowResult) -> str:
    return f"{_text(window.summary.get('callsign')) or '?'} #{_text(window.summary.get('window'))}"


def _callsign_title(windows: list[WindowResult]) -> str:
    names = list(dict.fromkeys(_text(w.summary.get("callsign")) or "?" for w in windows))
    shown = ", ".join(names[:_MAX_TITLE_CALLSIGNS])
    more = len(names) - _MAX_TITLE_CALLSIGNS
    return shown + (f" +{more} more" if more > 0 else "")


def track_figure(run: CorrelationRun, path_png: str | os.PathLike[str]) -> Path:
    """Map of every window's slotted tracks: lon on x, lat on y, radar red, ADS-B yellow; returns the path."""
    fig = new_figure(10, 7.5)
    ax = fig.add_subplot()
    lats: list[np.ndarray] = []
    any_filled = False
    for w in run.windows:
        s = w.slots
        for sensor in ("adsb", "radar"):  # radar on top so both stay visible where they overlap
            lon, lat = _floats(s, f"{sensor}_lon"), _floats(s, f"{sensor}_lat")
            filled = _flags(s, f"{sensor}_filled")
            any_filled |= bool((filled & np.isfinite(lat)).any())
            _draw_sensor(ax, lon, lat, filled, sensor)
            lats.append(lat)
        if len(run.windows) > 1 and len(run.windows) <= _MAX_TRACK_LABELS:
            lon, lat = _floats(s, "adsb_lon"), _floats(s, "adsb_lat")
            ok = np.flatnonzero(np.isfinite(lon) & np.isfinite(lat))
            if ok.size:
                ax.annotate(_window_label(w), (lon[ok[0]], lat[ok[0]]), xytext=(5, 5),
                            textcoords="offset points", fontsize=7.5, zorder=6,
                            bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.6", "alpha": 0.85})
    all_lat = np.concatenate(lats) if lats else np.array([])
    all_lat = all_lat[np.isfinite(all_lat)]
    if all_lat.size:
        coslat = math.cos(math.radians(float(np.mean(all_lat))))
        if coslat > 0.01:
            ax.set_aspect(1.0 / coslat, adjustable="datalim")
        ax.legend(handles=_legend_handles(any_filled), loc="best", framealpha=0.9, fontsize=9)
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
    ax.set_title(f"radar (red) vs ADS-B (yellow), {len(run.windows)} window(s), equal-distance aspect",
                 fontsize=9, color="0.35")
    return save_png(fig, path_png)


def lag_figure(window: WindowResult, path: str | os.PathLike[str]) -> Path:
    """NCC and Pearson coefficient against lag, latitude and longitude panels; returns the path."""
    fig = new_figure(10, 4.2)
    lags = window.lags.sort_values("lag") if "lag" in window.lags.columns else window.lags
    x = _floats(lags, "lag")
    for i, axis in enumerate(("lat", "lon")):
        ax = fig.add_subplot(1, 2, i + 1)
        ax.axvline(0, color="0.6", lw=0.8, zorder=1)
        for measure, color, ls, marker in (("ncc", "#1f77b4", "-", "o"), ("pearson", "#2ca02c", "--", "s")):
            y = _floats(lags, f"{measure}_{axis}")
            label = "NCC" if measure == "ncc" else "Pearson"
            ax.plot(x, y, color=color, ls=ls, marker=marker, ms=3.5, lw=1.3, label=label, zorder=3)
            if np.isfinite(y).any():
                k = int(np.nanargmax(y))
                ax.plot(x[k], y[k], marker="*", ms=11, color=color, mec="black", mew=0.6, ls="none", zorder=4)
        ax.set_title("Latitude" if axis == "lat" else "Longitude", fontsize=10)
        ax.set_xlabel("lag (slots)")
        ax.set_ylabel("coefficient")
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.grid(True, color="0.88", lw=0.6)
        ax.legend(fontsize=8, loc="best")
    step = slot_seconds(window)
    note = f", 1 slot = {step:g} s" if math.isfinite(step) else ""
    fig.suptitle(f"Correlation against lag: {_window_label(window)}{note} (star = peak)", fontsize=11)
    return save_png(fig, path)


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
    fig.suptitle(f"Latitude and longitude against time: {_window_label(window)}", fontsize=11)
    return save_png(fig, path)
