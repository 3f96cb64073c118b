"""A PNG per tracked aircraft: the fused track with its 2-sigma ellipses at intervals, every sensor's raw
reports, coasted parts dashed, and the mode probabilities against time (bare Agg figures)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib.dates as mdates
import numpy as np
import pandas as pd
from matplotlib.patches import Ellipse

from pipeline.report.figures import new_figure, save_png

_SENSOR_COLORS = ("#d62728", "#1f77b4", "#9467bd", "#8c564b", "#e377c2", "#17becf")
ADSB_COLOR = "#e6b800"
TRACK_COLOR = "#111111"
ELLIPSE_SIGMA = 2.0  # drawn ellipses hold about 86 % of the 2-D position error
ELLIPSE_EVERY = 12  # about this many ellipses per aircraft


def _local_km(lat: np.ndarray, lon: np.ndarray, lat0: float, lon0: float) -> tuple[np.ndarray, np.ndarray]:
    """East and north in km from (lat0, lon0), equirectangular: plenty for a picture of one flight."""
    k = 6371.0088 * math.pi / 180.0
    dlon = (np.asarray(lon, float) - lon0 + 180.0) % 360.0 - 180.0
    return dlon * k * math.cos(math.radians(lat0)), (np.asarray(lat, float) - lat0) * k


def aircraft_figure(tracks: pd.DataFrame, reports: pd.DataFrame, path: str | Path, title: str = "",
                    dpi: int = 130) -> Path:
    """One aircraft: map (km from the track's median position) above mode probabilities against time.
    tracks: the tracker's rows of this aircraft; reports: its measurements (sensor_id, sensor_kind, time,
    latitude, longitude)."""
    fig = new_figure(8.0, 8.6, dpi=dpi)
    ax, ax_mode = fig.subplots(2, 1, height_ratios=(3.0, 1.0))
    lat0, lon0 = float(tracks["latitude"].median()), float(tracks["longitude"].median())
    e_t, n_t = _local_km(tracks["latitude"].to_numpy(), tracks["longitude"].to_numpy(), lat0, lon0)
    colors = iter(_SENSOR_COLORS)
    for sid, g in reports.groupby("sensor_id", sort=True, observed=True):
        e, n = _local_km(g["latitude"].to_numpy(), g["longitude"].to_numpy(), lat0, lon0)
        kind = str(g["sensor_kind"].iloc[0])
        color = ADSB_COLOR if kind == "adsb" else next(colors, "#7f7f7f")
        ax.plot(e, n, ls="none", marker="." if kind == "adsb" else "+", ms=3 if kind == "adsb" else 5,
                color=color, label=f"{sid} ({kind}, {len(g)} reports)", zorder=2)
    coasted = tracks["coasted"].to_numpy(bool)
    seg = tracks["segment"].to_numpy()
    # a coasted stretch is drawn dashed from the last update into it; updated stretches solid
    for s in np.unique(seg):
        sel = np.flatnonzero(seg == s)
        ee, nn, cc = e_t[sel], n_t[sel], coasted[sel]
        solid = np.where(cc, np.nan, ee), np.where(cc, np.nan, nn)
        ax.plot(*solid, color=TRACK_COLOR, lw=1.0, zorder=4)
        dash_mask = cc | np.r_[cc[1:], False]
        ax.plot(np.where(dash_mask, ee, np.nan), np.where(dash_mask, nn, np.nan), color=TRACK_COLOR, lw=1.0,
                ls=(0, (3, 2)), zorder=4)
    ax.plot([], [], color=TRACK_COLOR, lw=1.0, label="fused track")
    ax.plot([], [], color=TRACK_COLOR, lw=1.0, ls=(0, (3, 2)), label="coasted (no report)")
    # the map shows the track (gated garbage reports far away would shrink it to a dot)
    span = max(float(np.nanmax(e_t) - np.nanmin(e_t)), float(np.nanmax(n_t) - np.nanmin(n_t)), 1.0)
    pad = 0.08 * span
    ax.set_xlim(np.nanmin(e_t) - pad, np.nanmax(e_t) + pad)
    ax.set_ylim(np.nanmin(n_t) - pad, np.nanmax(n_t) + pad)
    # ellipses magnified by a round factor so that the median one is about 2 % of the map
    every = max(len(tracks) // ELLIPSE_EVERY, 1)
    picks = np.arange(every // 2, len(tracks), every)
    median_km = float(np.nanmedian(tracks["sigma_major_m"].to_numpy(float)[picks])) * ELLIPSE_SIGMA / 1000.0
    scale = max(1.0, 10.0 ** math.floor(math.log10(0.02 * span / median_km))) if median_km > 0 else 1.0
    for i in picks:
        row = tracks.iloc[i]
        k = 2 * ELLIPSE_SIGMA * scale / 1000.0
        ax.add_patch(Ellipse((e_t[i], n_t[i]), k * row["sigma_minor_m"], k * row["sigma_major_m"],
                             angle=-float(row.get("ellipse_orientation_deg", 0.0)), fill=False,
                             color="#2ca02c", lw=1.0, zorder=5))
    ax.plot([], [], color="#2ca02c", lw=1.0,
            label=f"{ELLIPSE_SIGMA:g}-sigma position ellipse, drawn x{scale:g}")
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"east (km) of {lat0:.3f}, {lon0:.3f}")
    ax.set_ylabel("north (km)")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7, loc="best")
    ax.set_title(title or str(tracks["aircraft_id"].iloc[0]), fontsize=10)
    t = tracks["time"].dt.tz_convert(None)
    for col, label, color in (("mode_cv", "CV", "#444444"), ("mode_turn_left", "turn left", "#1f77b4"),
                              ("mode_turn_right", "turn right", "#d62728"), ("mode_ca", "CA", "#2ca02c")):
        if col in tracks:
            ax_mode.plot(t, tracks[col].to_numpy(float), color=color, lw=0.9, label=label)
    ax_mode.xaxis.set_major_formatter(mdates.DateFormatter("%H:%M"))
    ax_mode.set_ylim(-0.02, 1.02)
    ax_mode.set_ylabel("mode probability")
    ax_mode.set_xlabel("time (UTC)")
    ax_mode.grid(True, lw=0.3)
    ax_mode.legend(fontsize=7, loc="upper right", ncols=4)
    return save_png(fig, path)


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "aircraft"


def track_figures(result, directory: str | Path) -> dict[str, Path]:
    """One PNG per aircraft of a track job's result (``track_<callsign or id>.png``) in directory."""
    d = Path(directory)
    out: dict[str, Path] = {}
    tracks, meas = result.tracks, result.measurements
    for ident, g in tracks.groupby("aircraft_id", sort=True, observed=True):
        cs = str(g["callsign"].iloc[0] or "")
        title = f"{cs} ({ident})" if cs else str(ident)
        reports = meas[(meas["aircraft_id"] == ident).to_numpy(bool)]
        name = _safe(f"{cs}_{ident}" if cs else str(ident))
        out[str(ident)] = aircraft_figure(g.reset_index(drop=True), reports, d / f"track_{name}.png", title)
    return out
