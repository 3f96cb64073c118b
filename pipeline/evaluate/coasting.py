"""``coasting_correct``: a tracker's coasting flag (I062/080 CST) against whether the sensors that built the
reference detected the aircraft shortly before: a track flagged coasting should have had no detection in
the last ``window_s``, a track not flagged should have had one."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import (
    associated,
    checked_trajectories,
    parameter,
    rows_by_index,
)

DEFAULT_WINDOW_S = 10.0  # about two scans of a 4-5 s radar: a track older than this is coasting
UPDATED = "updated"  # reference column: True where a reference sensor's report updated it at that time


def coasting_correct(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                     sensor=None) -> Outcome:
    """Of the associated track reports carrying CST (``cst`` 0 or 1) judged against an independent reference
    that says when it was updated (column ``updated``), those whose flag agrees: CST 1 with no reference
    update in [t - window_s, t], CST 0 with one."""
    rid = "coasting_correct"
    if "cst" not in reports.columns:
        return withheld(rid, "the test reports carry no coasting flag (I062/080 CST)")
    if UPDATED not in reference.columns:
        return withheld(rid, "the reference does not say when its sensors detected each aircraft (no "
                             f"'{UPDATED}' column): coasting cannot be judged against it")
    window_s = float(parameter(parameters, "window_s", DEFAULT_WINDOW_S))
    if not window_s > 0:
        raise ValueError(f"coasting_correct: window_s {window_s!r} must be a positive number of seconds")
    rep = associated(reports, reference, parameters)
    cst = pd.to_numeric(rep["cst"], errors="coerce").to_numpy(float)
    judged = (rep["ref_index"].to_numpy() >= 0) & np.isfinite(cst)
    rep, cst = rep[judged], cst[judged]
    ref, trajs = checked_trajectories(reference)
    own = (ref["self_reference"].astype(bool).to_numpy() if "self_reference" in ref
           else np.zeros(len(ref), bool))
    updated = ref[UPDATED].astype(bool).to_numpy() & ~own  # a sensor cannot vouch for its own detections
    t, idx = rep["t_s"].to_numpy(float), rep["ref_index"].to_numpy()
    seen = np.zeros(len(rep), bool)
    groups = rows_by_index(idx, len(trajs))
    for k, tr in enumerate(trajs):
        rows = groups[k]
        if not rows.size:
            continue
        t_upd = tr.t_s[updated[tr.rows]]
        if not t_upd.size:
            continue
        last = np.searchsorted(t_upd, t[rows], side="right") - 1
        seen[rows] = (last >= 0) & (t[rows] - t_upd[np.maximum(last, 0)] <= window_s)
    if not len(rep):
        return withheld(rid, "no associated track report carries a coasting flag")
    correct = (cst == 1.0) != seen
    return share(rid, int(correct.sum()), len(rep),
                 (f"window {window_s:g} s; {int((cst == 1).sum()):,} reports flagged coasting",))
