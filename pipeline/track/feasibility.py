"""What a tracking run can be asked before it starts, and why it found nothing: an upper bound on the rows
it would put out (``track_rows``, refused past MAX_TRACK_ROWS by ``check_track_rows``) and the reason no
aircraft could be tracked (``untrackable``)."""

from __future__ import annotations

import numpy as np
import pandas as pd

# Rows the tracker may put out (grid samples plus report times) in one run: each costs about 570 bytes
# through estimation and the table (measured: fixtures --all, 33 k rows at --step 1 against 177 k at 0.1:
# +82 MB), so 4 M rows hold about 2.3 GB; 300 aircraft for an hour at 1 s make 1.1 M. --step alone cannot
# bound this (the same step is harmless on one aircraft and huge on a day of traffic), so it is counted
# after decoding, before tracking.
MAX_TRACK_ROWS = 4_000_000


class TooManyRows(ValueError):
    """The run would put out more than MAX_TRACK_ROWS rows: the message says how many, for how many
    aircraft (the command adds the option to change)."""


def track_rows(meas: pd.DataFrame, step_s: float, max_coast_s: float, *, grid_only: bool = False) -> int:
    """An upper bound on the rows ``track`` will put out: per aircraft, the grid of step_s over the time its
    reports cover (each gap up to max_coast_s, and max_coast_s after the last), plus one row per report
    (grid_only: the grid rows alone)."""
    if meas.empty:
        return 0
    t = meas["time"].dt.as_unit("ns").astype("int64").to_numpy() / 1e9
    ids = pd.factorize(meas["aircraft_id"])[0]
    order = np.lexsort((t, ids))
    t, ids = t[order], ids[order]
    gap = np.diff(t)
    same = ids[1:] == ids[:-1]
    covered = float(np.minimum(gap[same], max_coast_s).sum()) + max_coast_s * (int(ids.max()) + 1)
    return int(covered / step_s) + 2 * (int(ids.max()) + 1) + (0 if grid_only else len(meas))


def check_track_rows(meas: pd.DataFrame, step_s: float, max_coast_s: float, per_row: int = 1, what: str = "",
                     *, grid_only: bool = False) -> None:
    """TooManyRows when the run would put out more than MAX_TRACK_ROWS rows (``per_row`` rows for each
    track row, e.g. one prediction per horizon, named ``what``; grid_only: for each grid row)."""
    rows = track_rows(meas, float(step_s), float(max_coast_s), grid_only=grid_only) * per_row
    if rows > MAX_TRACK_ROWS:
        raise TooManyRows(f"the tracks of these {meas['aircraft_id'].nunique()} aircraft would need about "
                          f"{rows:,} {what or 'output rows'}, more than {MAX_TRACK_ROWS:,}")


def _unusable(meas: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Per report, whether it has no usable position or covariance, and its sensor kind."""
    cov = meas[["latitude", "longitude", "cov_ee_m2", "cov_en_m2", "cov_nn_m2"]].to_numpy(dtype=float)
    return ~np.isfinite(cov).all(axis=1), meas["sensor_kind"].astype(str).to_numpy()


def _adsb_unusable(meas: pd.DataFrame, bad: np.ndarray, kind: np.ndarray) -> str:
    """The ADS-B reports without a usable accuracy and why, '' when none."""
    n_adsb = int((bad & (kind == "adsb")).sum())
    if not n_adsb:
        return ""
    nacp = meas["nacp"].isna().to_numpy() if "nacp" in meas else np.zeros(len(meas), bool)
    no_nacp = int((bad & (kind == "adsb") & nacp).sum())
    why = [f"{no_nacp} carry no NACp, as in CAT021 0.2x, whose figure of merit msdc does not turn into "
           "a sigma: declare their accuracy with --adsb-sigma M (1-sigma metres per axis)"] if no_nacp else []
    if n_adsb > no_nacp:
        why.append(f"{n_adsb - no_nacp} have NACp 0 (unknown) or no position")
    return (f"{n_adsb} of {int((kind == 'adsb').sum())} ADS-B reports have no usable accuracy "
            f"({'; '.join(why)})")


def unused_adsb(meas: pd.DataFrame) -> list[str]:
    """The warning for ADS-B reports the tracker leaves out for want of an accuracy, when the others could
    be tracked: LEBL's 49,296 CAT021 0.23 reports went unused, the tracks made of the rest, without a word."""
    bad, kind = _unusable(meas)
    said = _adsb_unusable(meas, bad, kind)
    return [f"{said}: not used in the tracks"] if said else []


def untrackable(meas: pd.DataFrame) -> str:
    """Why no aircraft could be tracked: the reports without a usable position or covariance, by kind."""
    bad, kind = _unusable(meas)
    parts = []
    n_radar = int((bad & (kind == "radar")).sum())
    if said := _adsb_unusable(meas, bad, kind):
        parts.append(said)
    if n_radar:
        parts.append(f"{n_radar} of {int((kind == 'radar').sum())} radar plots have no position or "
                     "covariance (no range/azimuth, no flight level, or almost overhead)")
    detail = "; ".join(parts) if parts else f"{len(meas)} reports, none long enough to start a track"
    return f"no aircraft could be tracked: {detail}"


INTERVAL_SAMPLE_AIRCRAFT = 200  # aircraft whose reports measure the sensors' update intervals (a day has
# thousands: the intervals are the sensors', alike on every aircraft, and a sample keeps the check cheap)


def update_intervals(meas: pd.DataFrame, max_aircraft: int = INTERVAL_SAMPLE_AIRCRAFT) -> pd.Series:
    """Each sensor's median update interval (s): the median over its intervals between consecutive reports
    of one aircraft (repeated times left out), over the first ``max_aircraft`` aircraft; indexed by
    sensor_id, in ascending order of interval. Empty when no sensor reports an aircraft twice."""
    if meas.empty:
        return pd.Series(dtype=float)
    aircraft = pd.factorize(meas["aircraft_id"])[0]
    sample = (aircraft >= 0) & (aircraft < max_aircraft)  # only the three columns read, not every one copied
    sensor, names = pd.factorize(meas["sensor_id"].to_numpy()[sample])
    ids = aircraft[sample].astype(np.int64) * (len(names) + 1) + sensor
    t = meas["time"].dt.as_unit("ns").astype("int64").to_numpy()[sample] / 1e9
    order = np.lexsort((t, ids))
    t, ids, sensor = t[order], ids[order], sensor[order]
    gap = np.diff(t)
    keep = (ids[1:] == ids[:-1]) & (gap > 0)
    if not keep.any():
        return pd.Series(dtype=float)
    medians = pd.Series(gap[keep]).groupby(sensor[1:][keep]).median()
    return pd.Series(medians.to_numpy(), index=names[medians.index]).sort_values()
