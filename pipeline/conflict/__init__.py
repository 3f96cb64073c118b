"""Conflict analysis: probability of conflict, pair pre-filter, losses of separation and alert scoring."""

from msdc.pipeline.conflict.events import (
    alert_events,
    classify_alerts,
    losses_of_separation,
    separation,
    warning_times,
)
from msdc.pipeline.conflict.geometry import horizontal_distance_nm, surface_ecef_m
from msdc.pipeline.conflict.grid import grid_rows, on_grid
from msdc.pipeline.conflict.pairs import candidate_pairs, closing_margin_m, pairs_per_step
from msdc.pipeline.conflict.pairs_pc import pair_probabilities
from msdc.pipeline.conflict.probability import conflict_probability, pc_margin, pc_upper_bound

__all__ = ["alert_events", "candidate_pairs", "classify_alerts", "closing_margin_m", "conflict_probability",
           "grid_rows", "horizontal_distance_nm", "losses_of_separation", "on_grid", "pair_probabilities",
           "pairs_per_step", "pc_margin", "pc_upper_bound", "separation", "surface_ecef_m", "warning_times"]
