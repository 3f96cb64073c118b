"""PNG figures of data quality and radar accuracy (thesis figures 6.7-6.18), on bare Agg figures.

Each function draws one figure and returns the PNG path. The coefficient-against-lag figure is
``pipeline.report.figures.lag_figure`` (not repeated here).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import rcParams
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.ticker import FuncFormatter, MultipleLocator, NullFormatter

from msdc.pipeline.correlate.results import WindowResult
from msdc.pipeline.correlate.windows import in_window
from msdc.pipeline.model.geodesy import M_PER_NM
from msdc.pipeline.model.measurements import matching_aircraft
from msdc.pipeline.model.time import midnight, with_clock
from msdc.pipeline.quality.accuracy import MAX_AZIMUTH_ELEVATION_DEG, elevation_deg
from msdc.pipeline.report.figures import new_figure, save_png
from msdc.pipeline.report.summary import side_words, window_label

RADAR_COLOR = "#d62728"
ADSB_COLOR = "#e6b800"
_SENSOR_LABEL = {"radar": "Radar (CAT048)", "adsb": "ADS-B (CAT021)", "mlat": "Multilateration",
                 "smr": "Surface radar (CAT010)"}
_TICK_STEPS_S = (10, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 14400)  # whole minutes from 60 s
MAX_ERROR_POINTS = 50_000  # reports drawn per radar error figure: more only overplot, and cost seconds
MAX_LEGEND_AIRCRAFT = 20  # aircraft named in the radar error legend; past it, colours only


def plt_cycle() -> list[str]:
    """The colours of matplotlib's default property cycle (C0, C1, ...)."""
    return rcParams["axes.prop_cycle"].by_key()["color"]


def _clock(seconds: float, _pos=None, *, with_seconds: bool = True) -> str:
    """HH:MM:SS (HH:MM without ``with_seconds``) of seconds since midnight (with +Nd past the first day)."""
    if not np.isfinite(seconds):
        return ""
    day, rem = divmod(int(round(seconds)), 86400)
    text = f"{rem // 3600:02d}:{rem % 3600 // 60:02d}" + (f":{rem % 60:02d}" if with_seconds else "")
    return f"+{day}d {text}" if day else text


CHAR_WIDTH_EM = 0.62  # a tick label digit's width in ems (DejaVu Sans, matplotlib's default: 0.636)
LABEL_GAP = 1.5  # a tick step holds at least this many label widths (a label and half a label's room)


def _time_axis(ax: Axes, t_s) -> None:
    """Clock-time ticks on round steps (10 s .. 4 h) for an axis of seconds since midnight: the shortest
    step whose labels fit the axis's width with room between them (HH:MM:SS labels at 30 s on a half-width
    panel ran into one string), as HH:MM where the step is whole minutes."""
    t = np.asarray(t_s, dtype=float)
    t = t[np.isfinite(t)]
    span = float(t.max() - t.min()) if t.size else 0.0
    fig = ax.get_figure()
    width_in = ax.get_position().width * fig.get_figwidth() * 0.9  # (the layout takes a little more)
    size_pt = FontProperties(size=rcParams["xtick.labelsize"]).get_size_in_points()
    longest = max((len(_clock(v)) for v in (t.min(), t.max())), default=8) if t.size else 8

    def fits(step: int) -> bool:
        chars = longest - (3 if step % 60 == 0 else 0)
        return (span / step + 1) * chars * CHAR_WIDTH_EM * size_pt / 72.0 * LABEL_GAP <= width_in

    step = next((s for s in _TICK_STEPS_S if fits(s)), _TICK_STEPS_S[-1])
    ax.xaxis.set_major_locator(MultipleLocator(step))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _pos=None: _clock(v, with_seconds=step % 60 != 0)))
    ax.set_xlabel("time (UTC)")


def _grid(ax: Axes) -> None:
    ax.grid(True, color="0.88", lw=0.6)
    ax.set_axisbelow(True)


def _empty(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="0.4", fontsize=12)


def histogram_range_s(histogram: pd.DataFrame, share: float = 0.999) -> float:
    """Upper end (s) of the bins holding ``share`` of one sensor's intervals: the linear axis shows the
    bulk of the distribution, rare long intervals are counted in a note instead."""
    counts = histogram["intervals"].to_numpy(float)
    total = counts.sum()
    if total <= 0:
        return float(histogram["bin_end_s"].max()) if len(histogram) else 1.0
    k = int(np.searchsorted(np.cumsum(counts), share * total))
    return float(histogram["bin_end_s"].to_numpy(float)[min(k, len(counts) - 1)])


def interval_histogram_figure(histogram: pd.DataFrame, path: str | os.PathLike[str]) -> Path:
    """interval_histogram written as PNG."""
    return save_png(interval_histogram(histogram), path)


BULK_SHARE = 0.99  # the left panel of an update-interval figure: the range holding this share of them


def interval_histogram(histogram: pd.DataFrame) -> Figure:
    """Update-interval histogram ("Update intervals" of quality_tables), one row per sensor: at the left
    the bulk (the range holding 99 % of the intervals, linear), at the right every interval on log-log
    axes as intervals per second of interval (the rare long ones, a few against tens of thousands, stay
    visible, and a 30 s wide bin of 5 is not drawn 300 times the height of a 0.1 s bin of 5); bars
    labelled by their counts where the labels leave room."""
    sensors = list(histogram.groupby(["sensor", "sac", "sic"], dropna=False, sort=True))
    fig = new_figure(11, 2.7 * max(len(sensors), 1))
    if not sensors:
        _empty(fig.add_subplot(), "No update intervals")
        return fig
    axes = fig.subplots(len(sensors), 2, squeeze=False, width_ratios=[3, 2])
    placed = []
    for (bulk_ax, all_ax), ((sensor, sac, sic), h) in zip(axes, sensors, strict=True):
        color = RADAR_COLOR if sensor == "radar" else ADSB_COLOR
        top = histogram_range_s(h, BULK_SHARE)
        shown = h[h["bin_start_s"] < top]
        hidden = int(h.loc[h["bin_start_s"] >= top, "intervals"].sum())
        placed.append(_bars(bulk_ax, shown, color))
        occupied = shown.loc[shown["intervals"] > 0, "bin_start_s"]
        low = float(occupied.min()) if len(occupied) else 0.0
        pad = max(0.15 * (top - low), 0.3)  # a radar's intervals sit in a few bins near its scan period
        bulk_ax.set_xlim(max(0.0, low - pad), top + 0.3 * pad)
        bulk_ax.set_ylim(0.0, float(shown["intervals"].max() or 1) * 1.18)
        total = int(h["intervals"].sum())
        beyond = f"; {hidden} longer than {top:g} s (right)" if hidden else ""
        label = _SENSOR_LABEL.get(sensor, sensor)
        bulk_ax.set_title(f"{label} SAC {sac} SIC {sic}: {total} intervals{beyond}", fontsize=10)
        bulk_ax.set_ylabel("intervals")
        bulk_ax.set_xlabel("update interval (s)")
        nonzero = h[h["intervals"] > 0]
        if len(nonzero):
            # 0.1 s bins at 10 s: edges only; bins 0.1 s to 60 s wide: heights per second of interval
            placed.append(_bars(all_ax, nonzero, color, lw=0.0, density=True))
            all_ax.set_xscale("log")  # 0.1 s bins near the bulk and the 30-180 s ones alike visible
            all_ax.set_yscale("log")
            first = float(nonzero["bin_start_s"].min())
            all_ax.set_xlim(max(first, 0.05) / 1.3, float(nonzero["bin_end_s"].max()) * 1.3)
            density = nonzero["intervals"] / (nonzero["bin_end_s"] - nonzero["bin_start_s"])
            all_ax.set_ylim(float(density.min()) / 10.0, float(density.max()) * 4.0)
            all_ax.set_ylabel("intervals per s of interval")
            plain = FuncFormatter(lambda v, _pos: f"{v:g}")  # 4, 5, 6 s, not 4 x 10^0
            all_ax.xaxis.set_major_formatter(plain)
            all_ax.xaxis.set_minor_formatter(plain if all_ax.get_xlim()[1] / all_ax.get_xlim()[0] < 20
                                             else NullFormatter())
        else:
            _empty(all_ax, "No update intervals")
        all_ax.set_title("every interval, per second of interval (log-log)", fontsize=10)
        all_ax.set_xlabel("update interval (s)")
        for ax in (bulk_ax, all_ax):
            _grid(ax)
    fig.suptitle("Update intervals after de-duplication (bins as in the Update intervals sheet)", fontsize=12)
    _drop_overlapping(fig, placed)
    return fig


def _bars(ax: Axes, bins: pd.DataFrame, color: str, lw: float = 0.5, density: bool = False) -> tuple:
    """The bins as bars labelled with their counts, as high as their counts or (``density``) as their
    counts per second of the bin's width; (labels, counts, bars) for _drop_overlapping."""
    width = bins["bin_end_s"] - bins["bin_start_s"]
    height = bins["intervals"] / width if density else bins["intervals"]
    bars = ax.bar(bins["bin_start_s"], height, width=width, align="edge", color=color,
                  edgecolor="0.25" if lw else color, lw=lw)
    labels = [f"{int(v)}" if v > 0 else "" for v in bins["intervals"]]
    return ax.bar_label(bars, labels=labels, fontsize=7, padding=1), bins["intervals"].to_numpy(), bars


LABEL_MARGIN_PX = 2.0  # room kept around a bar label


def _drop_overlapping(fig: Figure, placed: list[tuple]) -> None:
    """In each panel (its bar labels, counts and bars), hide the labels that would overlap the label of a
    larger count or a bar other than their own (a radar's few bins near its scan period, 0.1 s apart: their
    counts ran into one another, or sat on the taller bar beside); the sheet gives every count. The layout
    is settled once here and kept when saved unless a hidden label reached outside its panel (it took room
    there, which the layout gives back)."""
    renderer = fig.canvas.get_renderer()
    engine = fig.get_layout_engine()
    if engine is not None:
        engine.execute(fig)  # the panels placed: the labels' extents are final (no drawing needed)
    keeps_layout = True
    for texts, counts, bars in placed:
        edges = np.array([b.get_window_extent(renderer).extents for b in bars]).reshape(-1, 4)
        kept: list[np.ndarray] = []
        for i in np.argsort(-counts, kind="stable"):
            if not texts[i].get_text():
                continue
            extent = texts[i].get_window_extent(renderer)
            box = extent.extents + np.array([-1, -1, 1, 1]) * LABEL_MARGIN_PX
            on_bar = ((edges[:, 0] < box[2]) & (edges[:, 2] > box[0]) & (edges[:, 1] < box[3])
                      & (edges[:, 3] > box[1]))
            on_bar[i] = False
            on_label = any(k[0] < box[2] and k[2] > box[0] and k[1] < box[3] and k[3] > box[1] for k in kept)
            if on_label or on_bar.any():
                texts[i].set_visible(False)
                panel = texts[i].axes.get_window_extent(renderer)
                keeps_layout &= bool(panel.x0 <= extent.x0 and extent.x1 <= panel.x1
                                     and panel.y0 <= extent.y0 and extent.y1 <= panel.y1)
            else:
                kept.append(box)
    if engine is not None and keeps_layout:
        fig.set_layout_engine("none")  # what was hidden lay inside its panel: the same layout, not redone


def radar_error_figure(errors: pd.DataFrame, path: str | os.PathLike[str],
                       biases: pd.DataFrame | None = None) -> Path:
    """Range and azimuth error against slant range and against time (``radar_errors`` rows of one radar),
    coloured per aircraft; with ``biases`` (one row) the fitted range bias + gain and azimuth bias lines."""
    fig = new_figure(11, 7)
    axes = fig.subplots(2, 2, sharey="row")
    if errors.empty:
        for ax in axes.ravel():
            _empty(ax, "No matched reports")
        return save_png(fig, path)
    range_nm = errors["slant_range_m"].to_numpy(float) / M_PER_NM
    step = max(1, -(-len(errors) // MAX_ERROR_POINTS))  # every step-th report of each aircraft is drawn
    groups = list(errors.groupby(errors["callsign"].fillna(errors["address"]).fillna("?"), sort=True))
    labelled = len(groups) <= MAX_LEGEND_AIRCRAFT
    colours = len(plt_cycle())
    # aircraft i takes colour i of the cycle; past the legend's limit, aircraft sharing a colour are drawn
    # together (a day's hundreds of aircraft would otherwise cost one artist per aircraft and panel)
    sets = ([(i % colours, [g]) for i, g in enumerate(groups)] if labelled
            else [(c, groups[c::colours]) for c in range(min(colours, len(groups)))])
    for c, mine in sets:
        pos = np.concatenate([errors.index.get_indexer(g.index.to_numpy())[::step] for _, g in mine])
        label = str(mine[0][0]) if labelled else None
        for row, metric in enumerate(("range_error_m", "azimuth_error_deg")):
            y = errors[metric].to_numpy(float)[pos]
            axes[row, 0].plot(range_nm[pos], y, ".", ms=2.5, alpha=0.7, color=f"C{c}", label=label)
            axes[row, 1].plot(errors["time_of_day"].to_numpy(float)[pos], y, ".", ms=2.5, alpha=0.7,
                              color=f"C{c}")
    overhead = elevation_deg(errors) > MAX_AZIMUTH_ELEVATION_DEG
    if overhead.any():  # their azimuth is left out of the bias fit: marked, so that none is read as a bias
        for ax, x in ((axes[1, 0], range_nm), (axes[1, 1], errors["time_of_day"].to_numpy(float))):
            ax.plot(x[overhead], errors["azimuth_error_deg"].to_numpy(float)[overhead], "x", ms=4, color="k",
                    label=f"above {MAX_AZIMUTH_ELEVATION_DEG:g} deg elevation (not fitted)")
    if biases is not None and len(biases):
        b = biases.iloc[0]
        r = np.linspace(np.nanmin(range_nm), np.nanmax(range_nm), 50)
        axes[0, 0].plot(r, b["range_bias_m"] + b["range_gain_ppm"] * 1e-6 * r * M_PER_NM, "k-", lw=1.5,
                        label="bias + gain fit")
        axes[1, 0].axhline(b["azimuth_bias_deg"], color="k", lw=1.5, label="azimuth bias fit")
    for ax in axes.ravel():
        ax.axhline(0.0, color="0.5", lw=0.8)
        _grid(ax)
    axes[0, 0].set_ylabel("range error (m)")
    axes[1, 0].set_ylabel("azimuth error (deg)")
    axes[1, 0].set_xlabel("slant range (NM)")
    for ax in axes[:, 1]:
        _time_axis(ax, errors["time_of_day"])
    axes[0, 1].set_xlabel("")
    handles = {}  # outside the panels, so that it covers no point: aircraft, then the fitted lines
    for ax in (axes[0, 0], axes[1, 0]):
        handles |= dict(zip(*reversed(ax.get_legend_handles_labels()), strict=True))
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside right upper", fontsize=7,
                   markerscale=2)
    radars = ", ".join(str(r) for r in errors["radar"].dropna().unique()[:3])
    shown = f", 1 in {step} drawn" if step > 1 else ""
    who = "" if labelled else f", {len(groups)} aircraft (colours repeat)"
    fig.suptitle(f"Radar errors against ADS-B: {radars} ({len(errors)} reports{shown}{who})", fontsize=12)
    return save_png(fig, path)


def _none_if_blank(value) -> str | None:
    return None if value is None or (not isinstance(value, str) and pd.isna(value)) or value == "" else value


def _raw_in_window(window: WindowResult, frames: list[pd.DataFrame]) -> pd.DataFrame:
    """The window aircraft's raw reports of every sensor in ``frames`` inside the window."""
    s = window.summary
    cs, addr = _none_if_blank(s.get("callsign")), _none_if_blank(s.get("address"))
    if cs is None and addr is None:  # (a radar pair's aircraft known by neither): its slots alone
        return frames[0].iloc[:0].assign(time_of_day=np.array([], float))
    # select() over the frames joined, without joining them whole: the aircraft matched over all, then
    # only their rows joined
    ids = matching_aircraft(frames, cs, addr)
    chosen = [f[f["aircraft_id"].isin(ids).fillna(False).to_numpy(bool)] for f in frames]
    start = midnight(pd.concat([f["time"] for f in frames], ignore_index=True))
    rows = with_clock(pd.concat(chosen, ignore_index=True), start)
    return rows[in_window(rows["time_of_day"], s["start_tod"], s["end_tod"])]


def _side(rows: pd.DataFrame, sensors: str, kind: str) -> pd.DataFrame:
    """The rows of one side of a window: its sensor ``sensors`` (a sensor_id, ADS-B ground stations joined by
    "+"; with several radars, a window's pair is one radar against one reference), else (unknown) of
    ``kind``. By id, not by the frame a row came in: a surface radar's reference is multilateration."""
    if sensors and "sensor_id" in rows:
        return rows[rows["sensor_id"].astype(str).isin(sensors.split("+")).to_numpy(bool)]
    return rows[(rows["sensor_kind"] == kind).to_numpy(bool)]


def track_span(values: np.ndarray, pad: float = 0.08) -> tuple[float, float] | None:
    """y range of a coordinate panel: the radar reports' range, padded by ``pad`` of it (at least 0.01 deg);
    None when there is no finite value."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return None
    low, high = float(finite.min()), float(finite.max())
    margin = max(pad * (high - low), 0.01)
    return low - margin, high + margin


def slotting_figure(window: WindowResult, radar_meas: pd.DataFrame, adsb_meas: pd.DataFrame,
                    path: str | os.PathLike[str]) -> Path:
    """One window's slotting figure (``slotting``) saved as a PNG at ``path``."""
    return save_png(slotting(window, radar_meas, adsb_meas), path)


def slotting(window: WindowResult, radar_meas: pd.DataFrame, adsb_meas: pd.DataFrame) -> Figure:
    """Latitude and longitude against time of one window: raw reports (left) and 10 s slots (right); each
    side's reports are its sensors' (by id, whichever frame holds them), named by the kind they are."""
    fig = new_figure(12, 6.5)
    axes = fig.subplots(2, 2, sharex=True, sharey="row")
    s = window.summary
    ids = {"radar": str(s.get("radar_sensor") or ""), "adsb": str(s.get("reference_sensor") or "")}
    rows = _raw_in_window(window, [radar_meas, adsb_meas])
    raw = {side: _side(rows, ids[side], side) for side in ids}
    words = side_words(s)
    labels = {side: f"{words[side]} {ids[side]}" if ids[side] else _SENSOR_LABEL[side] for side in ids}
    slots = window.slots
    for row, (axis, name) in enumerate((("lat", "latitude"), ("lon", "longitude"))):
        for sensor, color in (("adsb", ADSB_COLOR), ("radar", RADAR_COLOR)):
            r = raw[sensor]
            axes[row, 0].plot(r["time_of_day"], r[name], ".", ms=3, color=color, label=labels[sensor])
            filled = slots[f"{sensor}_filled"].fillna(False).astype(bool).to_numpy()
            t, y = slots["time_of_day"].to_numpy(float), slots[f"{sensor}_{axis}"].to_numpy(float)
            axes[row, 1].plot(t, y, "-", color=color, lw=1.2)
            axes[row, 1].plot(t[~filled], y[~filled], "o", ms=4, color=color, mec="0.2", mew=0.5,
                              label=labels[sensor])
            axes[row, 1].plot(t[filled], y[filled], "o", ms=4, mfc="white", mec=color, mew=0.9)
        axes[row, 0].set_ylabel(f"{name} (deg)")
        if not len(rows):  # said, not an empty panel that reads as no report
            axes[row, 0].text(0.5, 0.5, "reports not drawn: the aircraft has no call sign or address\n"
                              "to find them by (its slots, right, are the window's)", ha="center",
                              va="center", transform=axes[row, 0].transAxes, fontsize=9, color="0.35")
        span = track_span(raw["radar"][name].to_numpy(float))
        if span is not None:  # ADS-B position jumps (up to degrees away) would flatten the track
            axes[row, 0].set_ylim(*span)
            y = raw["adsb"][name].to_numpy(float)
            outside = int(((y < span[0]) | (y > span[1])).sum())
            if outside:
                why = " (position jumps)" if words["adsb"] == "ADS-B" else ""
                axes[row, 0].text(0.01, 0.02, f"{outside} {words['adsb']} report(s) off the axis{why}",
                                  transform=axes[row, 0].transAxes, fontsize=8, color="0.3")
        for ax in axes[row]:
            ax.ticklabel_format(axis="y", useOffset=False)
            _grid(ax)
    axes[0, 0].set_title("before slotting (reports)", fontsize=10)
    axes[0, 1].set_title("after slotting (slot means; hollow = filled)", fontsize=10)
    axes[0, 0].legend(fontsize=8, markerscale=2)
    for ax in axes[1]:
        _time_axis(ax, slots["time_of_day"])
    fig.suptitle(f"Latitude and longitude before and after slotting: {window_label(s)}", fontsize=12)
    return fig
