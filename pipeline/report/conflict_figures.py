"""A PNG per alert event: both tracks around the event with their predicted positions and 95 % ellipses
at every horizon from the alert's start, and the pair's PC against time per horizon (bare Agg figures)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib.dates as mdates
import numpy as np
import pandas as pd
from matplotlib.patches import Ellipse

from msdc.pipeline.model.geodesy import M_PER_NM
from msdc.pipeline.report.canvas import FIGURE_PNG_COMPRESS_LEVEL, new_figure, save_png

CHI2_95_2D = 5.991464547107979  # 95 % quantile of chi-square with 2 degrees of freedom
KM_PER_NM = 1.852
COLORS = {"a": "#1f77b4", "b": "#d62728"}
HORIZON_STYLES = ("-", "--", ":", "-.")
BEFORE_S = 120.0  # track drawn from this long before the alert


def figure_name(index: int, alert: pd.Series) -> str:
    """alert_<n>_<a>_<b>_<horizon>s.png, n counting from 1 in the Alerts table's order."""
    def safe(v: object) -> str:
        return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(v)).strip("_") or "x"

    return f"alert_{index + 1:03d}_{safe(alert['aircraft_a'])}_{safe(alert['aircraft_b'])}_" \
           f"{alert['horizon_s']:g}s.png"


def aircraft_label(row: pd.Series, side: str) -> str:
    """One aircraft of a conflict table's row as an ATC reader names it: call sign, Mode 3/A code, address
    and flight level ("EZY12AB 7061 (4CA216) FL 95"), each part left out when the row lacks it."""
    def text(column: str) -> str:
        value = row.get(f"{column}_{side}")
        return "" if value is None or (not isinstance(value, str) and pd.isna(value)) else str(value)

    parts = [text("callsign"), text("mode3a"), f"({row[f'aircraft_{side}']})"]
    level = row.get(f"flight_level_{side}")
    if level is not None and pd.notna(level):
        parts.append(f"FL {float(level):.0f}")
    return " ".join(p for p in parts if p)


def place_label(row: pd.Series) -> str:
    """", at 41.297 N 2.078 E" from the row's latitude and longitude (the pair's midpoint); "" without."""
    lat, lon = row.get("latitude"), row.get("longitude")
    if lat is None or lon is None or pd.isna(lat) or pd.isna(lon):
        return ""
    return f", at {abs(lat):.3f} {'N' if lat >= 0 else 'S'} {abs(lon):.3f} {'E' if lon >= 0 else 'W'}"


def _nm(lat, lon, lat0: float, lon0: float) -> tuple[np.ndarray, np.ndarray]:
    """East and north in NM from (lat0, lon0), equirectangular (plenty for one event's picture)."""
    k = 6371.0088 * math.pi / 180.0 / KM_PER_NM
    dlon = (np.asarray(lon, float) - lon0 + 180.0) % 360.0 - 180.0
    return dlon * k * math.cos(math.radians(lat0)), (np.asarray(lat, float) - lat0) * k


def _ellipse(ax, e_nm: float, n_nm: float, var_e: float, cov_en: float, var_n: float, **style) -> None:
    """The 95 % ellipse of an east/north covariance (m^2) centred at (e_nm, n_nm)."""
    cov = np.array([[var_e, cov_en], [cov_en, var_n]], dtype=float)
    if not np.isfinite(cov).all() or not np.isfinite([e_nm, n_nm]).all():
        return
    vals, vecs = np.linalg.eigh(cov)
    width, height = 2.0 * np.sqrt(np.maximum(vals, 0.0) * CHI2_95_2D) / M_PER_NM
    angle = math.degrees(math.atan2(vecs[1, 0], vecs[0, 0]))
    ax.add_patch(Ellipse((e_nm, n_nm), width, height, angle=angle, fill=False, **style))


def pc_line(times: pd.Series, values, step_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Times (naive UTC) and values of one PC series with a NaN after each sample whose next one is more
    than step_s later: the line breaks where the pair has no PC sample (PC below eps, predicted levels
    apart, a track absent), as the alert events do, instead of joining across the gap."""
    t = pd.to_datetime(times).dt.tz_convert(None).to_numpy()
    v = np.asarray(values, dtype=float)
    gaps = np.flatnonzero(np.diff(t) / np.timedelta64(1, "s") > step_s * (1 + 1e-9)) + 1
    return np.insert(t, gaps, np.datetime64("NaT")), np.insert(v, gaps, np.nan)


def pc_window(sample_times: pd.Series, alert: pd.Series, step_s: float, t0: pd.Timestamp,
              t1: pd.Timestamp) -> tuple[pd.Timestamp, pd.Timestamp]:
    """The PC panel's time range: the pair's samples, the alert and its loss start, a step (or 5 %) either
    side, within [t0, t1]; not the whole window of the map, which may hold only a few seconds of PC."""
    marks = [alert["start"], alert["end"]]
    if "loss_start" in alert and pd.notna(alert.get("loss_start")):
        marks.append(pd.Timestamp(alert["loss_start"]))
    lo = min([sample_times.min(), *marks]) if len(sample_times) else min(marks)
    hi = max([sample_times.max(), *marks]) if len(sample_times) else max(marks)
    pad = pd.Timedelta(seconds=max(step_s, 0.05 * (hi - lo).total_seconds()))
    return max(lo - pad, t0), min(hi + pad, t1)


def _window(alert: pd.Series, horizons: list[float]) -> tuple[pd.Timestamp, pd.Timestamp]:
    """The times a figure draws: BEFORE_S before the alert's start to its end plus the longest horizon."""
    start = alert["start"]
    return (start - pd.Timedelta(seconds=BEFORE_S),
            max(alert["end"], start) + pd.Timedelta(seconds=float(max(horizons))))


def _origin(alert: pd.Series, tracks: pd.DataFrame) -> tuple[float, float]:
    """The map's origin: aircraft_a at the alert's start, else the tracks' median position."""
    at = tracks[(tracks["aircraft_id"] == alert["aircraft_a"]) & (tracks["time"] == alert["start"])]
    return (float(at["latitude"].iloc[0]), float(at["longitude"].iloc[0])) if len(at) else (
        float(tracks["latitude"].median()), float(tracks["longitude"].median()))


class AlertData:
    """alert_figure's arguments for each alert cut to what its figure draws (the pair's tracks and PC in
    the figure's window, their predictions from the alert's start), with the horizons and map origin taken
    from the whole frames: the same figure as from the whole frames, from a few kB to send to a worker.
    The frames are indexed once by aircraft and pair (rows kept in their order), so that each alert's cut
    costs its own rows, not a scan of the whole PC table."""

    def __init__(self, tracks: pd.DataFrame, predictions: pd.DataFrame, pc: pd.DataFrame):
        self.tracks, self.predictions, self.pc = tracks, predictions, pc
        self.horizons = sorted(predictions["horizon_s"].unique())
        self._tracks = tracks.groupby("aircraft_id", sort=False, observed=True).indices
        self._predictions = predictions.groupby("aircraft_id", sort=False, observed=True).indices
        self._pairs = pc.groupby(["aircraft_a", "aircraft_b"], sort=False, observed=True).indices
        self._median: tuple[float, float] | None = None

    def _rows(self, frame: pd.DataFrame, index: dict, keys: list) -> pd.DataFrame:
        """The rows of ``frame`` under these keys of its index, in the frame's order."""
        found = [index[k] for k in keys if k in index]
        return frame.iloc[np.sort(np.concatenate(found))] if found else frame.iloc[:0]

    def __call__(self, alert: pd.Series) -> dict:
        a, b = alert["aircraft_a"], alert["aircraft_b"]
        t0, t1 = _window(alert, self.horizons)
        tracks = self._rows(self.tracks, self._tracks, [a] if a == b else [a, b])
        pred = self._rows(self.predictions, self._predictions, [a] if a == b else [a, b])
        series = self._rows(self.pc, self._pairs, [(a, b)])
        at = tracks[(tracks["aircraft_id"] == a) & (tracks["time"] == alert["start"])]
        if len(at):
            origin = (float(at["latitude"].iloc[0]), float(at["longitude"].iloc[0]))
        else:  # the whole frame's median, as _origin takes it
            if self._median is None:
                lat, lon = self.tracks["latitude"].median(), self.tracks["longitude"].median()
                self._median = (float(lat), float(lon))
            origin = self._median
        return {"alert": alert, "tracks": tracks[(tracks["time"] >= t0) & (tracks["time"] <= t1)],
                "predictions": pred[pred["time"] == alert["start"]],
                "pc": series[(series["time"] >= t0) & (series["time"] <= t1)], "horizons": self.horizons,
                "origin": origin}


def alert_figure(alert: pd.Series, tracks: pd.DataFrame, predictions: pd.DataFrame, pc: pd.DataFrame,
                 threshold: float, path: str | Path, dpi: int = 110, step_s: float | None = None,
                 horizons: list[float] | None = None, origin: tuple[float, float] | None = None) -> Path:
    """One alert event: map (NM from aircraft_a at the alert's start) above PC against time (pc: the
    samples the alert events were found in; step_s: their step, default the smallest in the pair's;
    horizons and origin: the predictions' horizons and ``_origin``, default from these frames)."""
    a, b, start = alert["aircraft_a"], alert["aircraft_b"], alert["start"]
    horizons = sorted(predictions["horizon_s"].unique()) if horizons is None else horizons
    t0, t1 = _window(alert, horizons)
    fig = new_figure(7.5, 8.8, dpi=dpi)
    ax, ax_pc = fig.subplots(2, 1, height_ratios=(2.4, 1.0))
    lat0, lon0 = _origin(alert, tracks) if origin is None else origin
    for key, ident in (("a", a), ("b", b)):
        color = COLORS[key]
        tr = tracks[(tracks["aircraft_id"] == ident) & (tracks["time"] >= t0) & (tracks["time"] <= t1)]
        e, n = _nm(tr["latitude"], tr["longitude"], lat0, lon0)
        ax.plot(e, n, color=color, lw=1.2, label=f"{aircraft_label(alert, key)} track")
        now = (tr["time"] == start).to_numpy()
        if now.any():
            ax.plot(e[now], n[now], "o", color=color, ms=6, zorder=5)
        pred = predictions[(predictions["aircraft_id"] == ident) & (predictions["time"] == start)]
        for i, h in enumerate(horizons):
            row = pred[pred["horizon_s"] == h]
            if row.empty:
                continue
            row = row.iloc[0]
            pe, pn = _nm(row["latitude"], row["longitude"], lat0, lon0)
            ax.plot(pe, pn, "x", color=color, ms=6, zorder=5)
            _ellipse(ax, float(pe), float(pn), row["var_east_m2"], row["cov_east_north_m2"],
                     row["var_north_m2"], color=color, lw=1.4 if h == alert["horizon_s"] else 0.8,
                     ls=HORIZON_STYLES[i % len(HORIZON_STYLES)])
    for i, h in enumerate(horizons):
        ax.plot([], [], color="#555555", ls=HORIZON_STYLES[i % len(HORIZON_STYLES)],
                label=f"95 % ellipse of the prediction {h:g} s ahead")
    ax.plot([], [], "o", color="#555555", label="position at the alert's start")
    ax.plot([], [], "x", color="#555555", label="predicted positions (mean) from there")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"east (NM) of {a} at the alert's start ({lat0:.3f}, {lon0:.3f})")
    ax.set_ylabel("north (NM)")
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7, loc="best")
    cpa = ""
    if "cpa_horizontal_nm" in alert and pd.notna(alert.get("cpa_horizontal_nm")):
        cpa = (f"; predicted closest approach in {alert['time_to_cpa_s']:.0f} s: "
               f"{alert['cpa_horizontal_nm']:.2f} NM, {alert['cpa_vertical_ft']:.0f} ft")
    ax.set_title(f"{aircraft_label(alert, 'a')} / {aircraft_label(alert, 'b')}{place_label(alert)}\n"
                 f"PC > {threshold:g} at the {alert['horizon_s']:g} s horizon from "
                 f"{start:%H:%M:%S} to {alert['end']:%H:%M:%S} UTC, peak {alert['peak_pc']:.2f}{cpa}",
                 fontsize=8.5, wrap=True)
    series = pc[(pc["aircraft_a"] == a) & (pc["aircraft_b"] == b) & (pc["time"] >= t0) & (pc["time"] <= t1)]
    if step_s is None:
        gaps = np.diff(np.unique(series["time"].to_numpy())) / np.timedelta64(1, "s")
        step_s = float(gaps.min()) if len(gaps) else 1.0
    for i, h in enumerate(horizons):
        s = series[series["horizon_s"] == h].sort_values("time")
        ax_pc.plot(*pc_line(s["time"], s["pc"], step_s), ls=HORIZON_STYLES[i % len(HORIZON_STYLES)],
                   marker="o", ms=2.5, lw=1.3 if h == alert["horizon_s"] else 0.9, label=f"PC, {h:g} s ahead")
    ax_pc.axhline(threshold, color="#888888", lw=0.8, ls=":", label=f"threshold {threshold:g}")
    ax_pc.axvline(start.tz_convert(None), color="#111111", lw=0.8, label="alert start")
    if "loss_start" in alert and pd.notna(alert.get("loss_start")):
        ax_pc.axvline(pd.Timestamp(alert["loss_start"]).tz_convert(None), color="#d62728", lw=0.8,
                      ls="--", label="loss of separation starts")
    lo, hi = pc_window(series["time"], alert, step_s, t0, t1)
    ax_pc.set_xlim(lo.tz_convert(None), hi.tz_convert(None))
    ax_pc.set_ylim(-0.02, 1.02)
    ax_pc.xaxis.set_major_formatter(mdates.DateFormatter("%H:%M:%S"))
    ax_pc.set_xlabel("time of the prediction (UTC)\na gap in a line: no PC sample there, counted as 0 "
                     "(PC below 1e-6, predicted levels apart, an aircraft on the surface or untracked)",
                     fontsize=7.5)
    ax_pc.set_ylabel("probability of conflict")
    ax_pc.grid(True, lw=0.3)
    ax_pc.legend(fontsize=7, loc="upper left")
    return save_png(fig, path, compress_level=FIGURE_PNG_COMPRESS_LEVEL)
