"""PNG figures of where a sensor detects, from the evaluation's PD grids (msdc.pipeline.evaluate.bins): the
polar PD map (range x azimuth) and the vertical coverage diagram (range x height), on bare Agg figures.

A cell with too few expected updates to give a value (``enough`` false) is drawn grey, not coloured; a cell
where nothing was expected is left white."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib import colormaps
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import FuncFormatter

from msdc.pipeline.model.geodesy import M_PER_FT, M_PER_NM
from msdc.pipeline.report.canvas import new_figure, save_png

PD_CMAP = "RdYlGn"  # red (none detected) to green (all): a fixed 0-1 scale, so maps compare
# its bands: finer near 1, where the standards set their thresholds (a 95 % cell and a 99 % one differ)
PD_BANDS = (0.0, 0.5, 0.8, 0.9, 0.95, 0.97, 0.99, 1.0)
TOO_FEW_COLOR = "0.78"
GRID_COLUMNS = ("x_low", "x_high", "y_low", "y_high", "expected", "pd", "enough")


def grid_arrays(grid: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The x edges, y edges, PD (NaN where a cell has too few expected updates) and a too-few mask (cells with
    some but too few expected updates), the last two shaped (x cells, y cells)."""
    missing = [c for c in GRID_COLUMNS if c not in grid.columns]
    if missing:
        raise ValueError(f"a PD grid needs the columns {', '.join(GRID_COLUMNS)}; missing "
                         f"{', '.join(missing)}")
    xe = np.append(np.unique(grid["x_low"].to_numpy(float)), grid["x_high"].max())
    ye = np.append(np.unique(grid["y_low"].to_numpy(float)), grid["y_high"].max())
    nx, ny = xe.size - 1, ye.size - 1
    if len(grid) != nx * ny:
        raise ValueError(f"a PD grid of {nx} x {ny} cells has {len(grid)} rows")
    ix = np.searchsorted(xe, grid["x_low"].to_numpy(float))
    iy = np.searchsorted(ye, grid["y_low"].to_numpy(float))
    enough = grid["enough"].to_numpy(bool)
    value = np.full((nx, ny), np.nan)
    value[ix, iy] = np.where(enough, grid["pd"].to_numpy(float), np.nan)
    few = np.zeros((nx, ny), bool)
    few[ix, iy] = ~enough & (grid["expected"].to_numpy() > 0)
    return xe, ye, value, few


def _pd_scale() -> tuple[ListedColormap, BoundaryNorm]:
    """The PD colour scale: one colour per band of PD_BANDS, 1 itself in the top band."""
    cmap = colormaps[PD_CMAP].resampled(len(PD_BANDS) - 1)
    cmap = cmap.with_extremes(over=cmap(cmap.N - 1))
    return cmap, BoundaryNorm(PD_BANDS, cmap.N)


def _pd_colorbar(fig, mesh, ax, **kw) -> None:
    """The colour bar of the PD bands, ticked at their edges in percent."""
    bar = fig.colorbar(mesh, ax=ax, ticks=PD_BANDS, label="probability of detection", **kw)
    bar.ax.set_yticklabels([f"{100 * b:g} %" for b in PD_BANDS])


def _legend_too_few(ax, min_expected: int | None, below: float = -0.08) -> None:
    """The legend of the grey and white cells (and of the lines drawn), below the plot, off the data."""
    what = f"fewer than {min_expected} expected updates" if min_expected else "too few expected updates"
    handles = [*ax.get_legend_handles_labels()[0],
               Patch(facecolor=TOO_FEW_COLOR, edgecolor="0.5", label=what),
               Patch(facecolor="white", edgecolor="0.5", label="none expected")]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, below), fontsize=8, frameon=False,
              ncol=2)


def polar_pd_map(grid: pd.DataFrame, title: str = "", min_expected: int | None = None) -> Figure:
    """The polar PD map of a range (x, NM) x azimuth (y, deg) grid: north up, azimuth clockwise."""
    r_edges, az_edges, value, few = grid_arrays(grid)
    fig = new_figure(7.5, 7.5)
    ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    theta = np.radians(az_edges)
    cmap, norm = _pd_scale()
    mesh = ax.pcolormesh(theta, r_edges, np.ma.masked_invalid(value), cmap=cmap, norm=norm, shading="flat")
    ax.pcolormesh(theta, r_edges, np.ma.masked_where(~few, np.ones_like(value)),
                  cmap=ListedColormap([TOO_FEW_COLOR]), vmin=0.0, vmax=1.0, shading="flat")
    ax.set_ylim(0.0, float(r_edges[-1]))
    ax.set_rlabel_position(22.5)
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g} NM"))
    ax.grid(True, color="0.5", lw=0.4, alpha=0.6)
    ax.set_title(title or "Probability of detection by range (NM) and azimuth", fontsize=10)
    _pd_colorbar(fig, mesh, ax, shrink=0.7, pad=0.08)
    _legend_too_few(ax, min_expected)
    return fig


def vertical_coverage(grid: pd.DataFrame, title: str = "", min_expected: int | None = None,
                      cone_elevation_deg: float | None = None, site_altitude_m: float = 0.0,
                      max_range_nm: float | None = None) -> Figure:
    """The vertical coverage diagram of a range (x, NM) x height (y, ft) grid, with the declared or estimated
    cone of silence (elevation limit, drawn from the site's height) and maximum range when given."""
    x_edges, y_edges, value, few = grid_arrays(grid)
    fig = new_figure(10, 5.5)
    ax = fig.add_subplot()
    cmap, norm = _pd_scale()
    mesh = ax.pcolormesh(x_edges, y_edges, np.ma.masked_invalid(value).T, cmap=cmap, norm=norm,
                         shading="flat")
    ax.pcolormesh(x_edges, y_edges, np.ma.masked_where(~few, np.ones_like(value)).T,
                  cmap=ListedColormap([TOO_FEW_COLOR]), vmin=0.0, vmax=1.0, shading="flat")
    if cone_elevation_deg is not None and np.isfinite(cone_elevation_deg):
        rho = np.linspace(0.0, float(x_edges[-1]), 200)
        h_ft = (site_altitude_m + rho * M_PER_NM * np.sin(np.radians(cone_elevation_deg))) / M_PER_FT
        ax.plot(rho, h_ft, color="black", lw=1.0, ls="--",
                label=f"elevation limit {cone_elevation_deg:.3g} deg (cone of silence above)")
    if max_range_nm is not None and np.isfinite(max_range_nm):
        ax.axvline(max_range_nm, color="black", lw=1.0, ls=":", label=f"maximum range {max_range_nm:.4g} NM")
    ax.set_xlim(float(x_edges[0]), float(x_edges[-1]))
    ax.set_ylim(float(y_edges[0]), float(y_edges[-1]))
    ax.set_xlabel("slant range (NM)")
    ax.set_ylabel("height (ft): above the WGS-84 ellipsoid,\n"
                  "or the pressure altitude without a geometric one")
    ax.set_title(title or "Vertical coverage: probability of detection by range and height", fontsize=10)
    _pd_colorbar(fig, mesh, ax)
    _legend_too_few(ax, min_expected, below=-0.12)
    return fig


def polar_pd_figure(grid: pd.DataFrame, path: str | os.PathLike[str], title: str = "",
                    min_expected: int | None = None) -> Path:
    """Write the polar PD map as PNG; returns the path."""
    return save_png(polar_pd_map(grid, title, min_expected), path)


def vertical_coverage_figure(grid: pd.DataFrame, path: str | os.PathLike[str], title: str = "",
                             **kwargs) -> Path:
    """Write the vertical coverage diagram as PNG; returns the path."""
    return save_png(vertical_coverage(grid, title, **kwargs), path)


def png_bytes(fig: Figure) -> bytes:
    """The figure as PNG bytes; its artists are released afterwards (no pyplot: nothing else holds it)."""
    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", facecolor="white")
    finally:
        fig.clear()
    return buffer.getvalue()


def coverage_images(polar_grid: pd.DataFrame | None, vertical_grid: pd.DataFrame | None, title: str,
                    min_expected: int | None = None, **vertical) -> dict[str, bytes]:
    """The polar PD map and the vertical coverage diagram as PNG bytes, keyed by their titles (for the HTML
    report and the workbook's Coverage sheet); a grid that is None or empty is left out. ``vertical`` goes
    to vertical_coverage (cone_elevation_deg, site_altitude_m, max_range_nm)."""
    out: dict[str, bytes] = {}
    if polar_grid is not None and not polar_grid.empty:
        name = f"{title}: probability of detection by range and azimuth"
        out[name] = png_bytes(polar_pd_map(polar_grid, name, min_expected))
    if vertical_grid is not None and not vertical_grid.empty:
        name = f"{title}: vertical coverage (probability of detection by range and height)"
        out[name] = png_bytes(vertical_coverage(vertical_grid, name, min_expected, **vertical))
    return out
