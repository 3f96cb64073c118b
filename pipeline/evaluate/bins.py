"""Where a sensor detects: the probability of detection per bin (range band, azimuth sector, flight-level
band, surface or airborne) and on grids (range x azimuth: the polar map; range x height: the vertical
coverage diagram), from the table of expected updates (detection.expected_updates).

Every bin gives its expected and detected updates, PD with its Clopper-Pearson 95 % interval, and whether
it holds enough expected updates to be shown as a value (``enough``)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.statistics import proportion
from msdc.pipeline.model.geodesy import M_PER_FT

RANGE_BAND_NM = 10.0
AZIMUTH_SECTOR_DEG = 30.0
FLIGHT_LEVEL_BAND = 50.0  # flight levels (5,000 ft)
MAP_AZIMUTH_DEG = 10.0  # the polar map's azimuth step
VERTICAL_RANGE_NM = 5.0  # the vertical coverage diagram's range step ...
VERTICAL_HEIGHT_FT = 2000.0  # ... and height step
# Below this many expected updates a bin is shown as "too few", not as a value: 20 of 20 detected still
# leaves the interval's lower end at 0.83, too wide to say anything of a radar meant to detect 0.97 or more
MIN_EXPECTED = 20
COUNT_COLUMNS = ["expected", "detected", "pd", "ci_low", "ci_high", "enough"]
CLASSES = ("airborne", "surface", "unknown")


def _bin_index(values: np.ndarray, edges: np.ndarray, what: str) -> np.ndarray:
    """Each value's bin [edges[i], edges[i+1]) as i, -1 outside the edges or NaN."""
    edges = np.asarray(edges, float)
    if edges.ndim != 1 or edges.size < 2 or not np.all(np.isfinite(edges)) or np.any(np.diff(edges) <= 0):
        raise ValueError(f"{what} edges must be at least two finite numbers, increasing, got {edges!r}")
    v = np.asarray(values, float)
    i = np.searchsorted(edges, v, side="right") - 1
    return np.where(np.isfinite(v) & (i >= 0) & (i < edges.size - 1), i, -1)


def _counts(index: np.ndarray, detected: np.ndarray, n_bins: int, min_expected: int) -> pd.DataFrame:
    """Expected and detected updates per bin number 0..n_bins-1 (index -1: in no bin), PD and interval."""
    keep = index >= 0
    expected = np.bincount(index[keep], minlength=n_bins)
    hit = np.bincount(index[keep], weights=detected[keep].astype(float), minlength=n_bins).astype(np.int64)
    p = proportion(hit, expected)
    return pd.DataFrame({"expected": expected, "detected": hit, "pd": p.value, "ci_low": p.ci_low,
                         "ci_high": p.ci_high, "enough": expected >= min_expected})


def _rows(table: pd.DataFrame, inside_coverage: bool) -> pd.DataFrame:
    """The expected updates counted: those inside coverage only, or all of them."""
    return table[table["in_coverage"].to_numpy(bool)] if inside_coverage else table


def flight_level(table: pd.DataFrame) -> np.ndarray:
    """The flight level (pressure altitude / 100 ft) of each expected update; NaN where the reference has
    none."""
    return table["altitude_ft"].to_numpy(float) / 100.0


def height_ft(table: pd.DataFrame) -> np.ndarray:
    """The height (ft above the WGS-84 ellipsoid: the reference's height_m, else its pressure altitude) of
    each expected update."""
    return table["height_m"].to_numpy(float) / M_PER_FT


def detection_by(table: pd.DataFrame, values: np.ndarray | str, edges, *, inside_coverage: bool = True,
                 min_expected: int = MIN_EXPECTED) -> pd.DataFrame:
    """PD per band [low, high) of ``values`` (an array aligned with ``table``, or one of its columns):
    columns low, high and COUNT_COLUMNS, one row per band, empty bands included. By default only the
    updates inside coverage count, as in the ``pd`` requirement the bands break down."""
    v = table[values].to_numpy(float) if isinstance(values, str) else np.asarray(values, float)
    keep = table["in_coverage"].to_numpy(bool) if inside_coverage else np.ones(len(table), bool)
    edges = np.asarray(edges, float)
    index = np.where(keep, _bin_index(v, edges, str(values) if isinstance(values, str) else "band"), -1)
    out = _counts(index, table["detected"].to_numpy(bool), edges.size - 1, min_expected)
    return pd.concat([pd.DataFrame({"low": edges[:-1], "high": edges[1:]}), out], axis=1)


def _edges(top: float, step: float) -> np.ndarray:
    """0, step, ... up to the first multiple of step above ``top`` (at least one band)."""
    n = max(int(np.floor(top / step)) + 1, 1) if np.isfinite(top) else 1
    return step * np.arange(n + 1)


def _finite(reduce, values) -> float:
    """``reduce`` (np.max or np.min) of the finite values and 0 (an edge of every grid), without the warning
    numpy's nan-functions give where every value is NaN."""
    v = np.asarray(values, float)
    return float(reduce(v[np.isfinite(v)], initial=0.0))


def azimuth_edges(step_deg: float) -> np.ndarray:
    """0, step, ... and 360 (a last narrower sector where step does not divide 360)."""
    return np.append(np.arange(0.0, 360.0 - 1e-9, step_deg), 360.0)


def surface_airborne(table: pd.DataFrame, reference: pd.DataFrame) -> np.ndarray:
    """Per expected update: 'surface' or 'airborne' from the reference's ``on_ground`` (its latest sample
    of that aircraft at or before the update's ``t_ref_s``; of samples at one time, the last in the
    reference's order: the scorecard's surface and airborne rows place them alike),
    'unknown' where the reference has no such column or value: a pressure altitude cannot tell (an
    airport's ground level is its elevation, and QNH moves it)."""
    out = np.full(len(table), "unknown", dtype=object)
    if "on_ground" not in reference.columns or table.empty:
        return out
    latest = _latest_sample(table["aircraft"], table["t_ref_s"].to_numpy(float), reference["aircraft"],
                            reference["t_s"].to_numpy(float))
    flag = reference["on_ground"].astype("boolean").array
    found = latest >= 0
    known = found & ~flag.isna()[np.where(found, latest, 0)]
    ground = flag.fillna(False).to_numpy(bool)[np.where(found, latest, 0)]
    out[known] = np.where(ground[known], "surface", "airborne")
    return out


def _latest_sample(aircraft, t_s: np.ndarray, ref_aircraft, ref_t_s: np.ndarray) -> np.ndarray:
    """Per (aircraft, t_s), the row of the reference's latest sample of that aircraft at or before t_s (of
    samples at one time, the last in the reference's order), -1 where none: a backward as-of join on the
    aircraft's integer codes, without sorting the reference's text (already in aircraft and time order
    when built by evaluate, sorted here otherwise)."""
    codes, names = pd.factorize(ref_aircraft)
    codes[np.isnan(ref_t_s)] = -1  # no time: never the latest
    n = len(names)
    if bool(np.all(np.diff(codes) >= 0)) and _times_ascend(codes, ref_t_s):
        order = None  # codes ascend by first appearance: already grouped, each group in time order
    else:
        order = np.lexsort((ref_t_s, codes))  # stable: equal times keep the reference's order
    sorted_codes = codes if order is None else codes[order]
    sorted_t = ref_t_s if order is None else ref_t_s[order]
    bounds = np.searchsorted(sorted_codes, np.arange(n + 1), side="left")
    wanted = pd.Index(names).get_indexer(pd.Index(aircraft))
    out = np.full(len(t_s), -1, dtype=np.int64)
    present = np.flatnonzero(wanted >= 0)
    by_group = np.argsort(wanted[present], kind="stable")
    rows = present[by_group]
    cuts = np.searchsorted(wanted[rows], np.arange(n + 1), side="left")
    for g in np.flatnonzero(np.diff(cuts)):
        mine = rows[cuts[g]:cuts[g + 1]]
        lo, hi = bounds[g], bounds[g + 1]
        i = lo + np.searchsorted(sorted_t[lo:hi], t_s[mine], side="right") - 1
        out[mine] = np.where((i >= lo) & ~np.isnan(t_s[mine]), i, -1)  # a missing time: none
    if order is not None:
        out = np.where(out >= 0, order[np.maximum(out, 0)], -1)
    return out


def _times_ascend(codes: np.ndarray, t_s: np.ndarray) -> bool:
    """Whether ``t_s`` ascends within each run of equal ``codes`` (a missing time's code is -1)."""
    same = codes[1:] == codes[:-1]
    with np.errstate(invalid="ignore"):
        return bool(np.all(~same | (t_s[1:] >= t_s[:-1]) | (codes[1:] < 0)))


def detection_bands(table: pd.DataFrame, reference: pd.DataFrame, *, range_step_nm: float = RANGE_BAND_NM,
                    sector_deg: float = AZIMUTH_SECTOR_DEG, fl_step: float = FLIGHT_LEVEL_BAND,
                    min_expected: int = MIN_EXPECTED) -> dict[str, pd.DataFrame]:
    """PD inside coverage per range band (NM), azimuth sector (deg), flight-level band and surface/airborne
    class, each a table of low, high (or ``class``) and COUNT_COLUMNS."""
    inside = _rows(table, True)
    fl = flight_level(inside)
    bands = {
        "range_nm": detection_by(table, "rho_nm", _edges(_finite(np.max, inside["rho_nm"]), range_step_nm),
                                 min_expected=min_expected),
        "azimuth_deg": detection_by(table, "azimuth_deg", azimuth_edges(sector_deg),
                                    min_expected=min_expected),
        "flight_level": detection_by(table, flight_level(table), _edges(
            _finite(np.max, fl), fl_step),
            min_expected=min_expected),
    }
    cls = surface_airborne(table, reference)
    keep = table["in_coverage"].to_numpy(bool)
    index = np.where(keep, pd.Categorical(cls, categories=CLASSES).codes, -1)
    bands["surface"] = pd.concat([pd.DataFrame({"class": CLASSES}), _counts(
        index, table["detected"].to_numpy(bool), len(CLASSES), min_expected)], axis=1)
    return bands


def detection_grid(table: pd.DataFrame, x: np.ndarray, x_edges, y: np.ndarray, y_edges, *,
                   inside_coverage: bool = False, min_expected: int = MIN_EXPECTED) -> pd.DataFrame:
    """PD on a grid of x bands by y bands (arrays aligned with ``table``): one row per cell, x_low, x_high,
    y_low, y_high and COUNT_COLUMNS, x varying slowest. By default every expected update counts, inside the
    coverage limits or not: the grid is a picture of where the sensor detects."""
    xe, ye = np.asarray(x_edges, float), np.asarray(y_edges, float)
    ix, iy = _bin_index(x, xe, "x"), _bin_index(y, ye, "y")
    keep = (ix >= 0) & (iy >= 0)
    if inside_coverage:
        keep &= table["in_coverage"].to_numpy(bool)
    ny = ye.size - 1
    index = np.where(keep, ix * ny + iy, -1)
    out = _counts(index, table["detected"].to_numpy(bool), (xe.size - 1) * ny, min_expected)
    cx, cy = np.divmod(np.arange(len(out)), ny)
    cells = pd.DataFrame({"x_low": xe[cx], "x_high": xe[cx + 1], "y_low": ye[cy], "y_high": ye[cy + 1]})
    return pd.concat([cells, out], axis=1)


def polar_grid(table: pd.DataFrame, range_edges_nm=None, azimuth_edges_deg=None, **kwargs) -> pd.DataFrame:
    """PD on slant range (x, NM) by azimuth (y, deg): the polar coverage map. Default: 10 NM by 10 deg out to
    the farthest expected update."""
    if range_edges_nm is None:
        range_edges_nm = _edges(_finite(np.max, table["rho_nm"]), RANGE_BAND_NM)
    if azimuth_edges_deg is None:
        azimuth_edges_deg = azimuth_edges(MAP_AZIMUTH_DEG)
    return detection_grid(table, table["rho_nm"].to_numpy(float), range_edges_nm,
                          table["azimuth_deg"].to_numpy(float), azimuth_edges_deg, **kwargs)


def vertical_grid(table: pd.DataFrame, range_edges_nm=None, height_edges_ft=None, **kwargs) -> pd.DataFrame:
    """PD on slant range (x, NM) by height (y, ft above the ellipsoid): the vertical coverage diagram, where
    the cone of silence is the empty wedge above the site. Default: 5 NM by 2,000 ft."""
    h = height_ft(table)
    if range_edges_nm is None:
        range_edges_nm = _edges(_finite(np.max, table["rho_nm"]), VERTICAL_RANGE_NM)
    if height_edges_ft is None:  # from 0, or lower where an aircraft is below the ellipsoid (the Dead Sea)
        lowest_ft = _finite(np.min, h)
        bottom = VERTICAL_HEIGHT_FT * min(float(np.floor(lowest_ft / VERTICAL_HEIGHT_FT)), 0.0)
        height_edges_ft = bottom + _edges(_finite(np.max, h) - bottom, VERTICAL_HEIGHT_FT)
    return detection_grid(table, table["rho_nm"].to_numpy(float), range_edges_nm, h, height_edges_ft,
                          **kwargs)
