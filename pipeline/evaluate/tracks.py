"""Tracker requirements over test tracks (CAT062 or any report carrying ``track_number``), judged per
reference aircraft: ``extra_tracks`` (more than one test track of one aircraft at a time) and
``track_continuity`` (track number changes per aircraft)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.outcome import Outcome, rate, share, withheld
from msdc.pipeline.evaluate.reference import associated, parameter

DEFAULT_INTERVAL_S = 5.0  # the time bins "at a time" means: a tracker's update period is 1-5 s


def _binned(reports: pd.DataFrame, reference: pd.DataFrame,
            parameters: Mapping | None) -> pd.DataFrame | None:
    """Per reference aircraft and time bin of interval_s: the distinct test track numbers in it and the one
    holding most of its reports (ties: the lowest number); None when no report has a track number."""
    if "track_number" not in reports.columns:
        return None
    rep = associated(reports, reference, parameters)
    rep = rep[(rep["ref_index"].to_numpy() >= 0) & rep["track_number"].notna().to_numpy()]
    if not len(rep):
        return None
    interval = float(parameter(parameters, "interval_s", DEFAULT_INTERVAL_S))
    frame = pd.DataFrame({"aircraft": rep["ref_aircraft"].to_numpy(object),
                          "bin": np.floor(rep["t_s"].to_numpy(float) / interval).astype(np.int64),
                          "track": pd.to_numeric(rep["track_number"]).to_numpy(np.int64)})
    counts = frame.groupby(["aircraft", "bin", "track"], sort=True).size().rename("reports").reset_index()
    counts = counts.sort_values(["aircraft", "bin", "reports", "track"], ascending=[True, True, False, True])
    per_bin = counts.groupby(["aircraft", "bin"], sort=True).agg(tracks=("track", "size"),
                                                                 main=("track", "first"))
    return per_bin.reset_index()


def extra_tracks(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                 sensor=None) -> Outcome:
    """Of the (aircraft, interval) pairs holding a test track, those holding more than one track number."""
    bins = _binned(reports, reference, parameters)
    if bins is None:
        return withheld("extra_tracks", "no associated report carries a track number")
    per = bins.groupby("aircraft").agg(intervals=("tracks", "size"),
                                       extra=("tracks", lambda s: int((s > 1).sum())))
    return share("extra_tracks", int((bins["tracks"] > 1).sum()), len(bins), per_aircraft=per.reset_index())


def track_continuity(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                     sensor=None) -> Outcome:
    """Changes of an aircraft's main track number (the one holding most of its reports in an interval) from
    one interval to the next, per aircraft tracked (a Poisson rate)."""
    bins = _binned(reports, reference, parameters)
    if bins is None:
        return withheld("track_continuity", "no associated report carries a track number")
    changes = bins.groupby("aircraft")["main"].agg(
        lambda s: int((s.to_numpy()[1:] != s.to_numpy()[:-1]).sum()))
    out = rate("track_continuity", int(changes.sum()), float(len(changes)),
               (f"{len(changes)} aircraft tracked",))
    per = pd.DataFrame({"aircraft": changes.index.astype(str), "changes": changes.to_numpy(np.int64)})
    return replace(out, per_aircraft=per)  # the windows of a span count an aircraft in several once
