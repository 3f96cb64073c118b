"""What a requirement function returns: the counts, the value with its 95 % interval, and what it rests on."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.statistics import (
    ClusterSums,
    ShareClusters,
    design_effect,
    effective_proportion,
    poisson_rate,
)


@dataclass(frozen=True)
class ErrorEvidence:
    """What an error statistic rests on, kept so that the windows of a span pool exactly: each aircraft's
    sums (an RMS, mean or SD), or every value with its aircraft (a percentile), or the largest value (the
    maximum; its count is the outcome's ``n``)."""

    statistic: str
    seed: int = 0
    sums: ClusterSums | None = None
    values: np.ndarray | None = None
    clusters: pd.Categorical | None = None  # each value's aircraft: codes, not a text per value


@dataclass(frozen=True)
class FitEvidence:
    """A fitted radar bias of one window: value and standard error (its unit), the plots and aircraft it
    rests on; the windows of a span combine their fits by inverse variance."""

    value: float
    se: float
    unit: str
    n_reports: int
    aircraft: int


@dataclass(frozen=True)
class Outcome:
    """One requirement measured on one sensor: ``count`` of ``n`` (successes of trials, or events per
    exposure for a rate), the value and its interval, notes on what it used (scan period, coverage), and
    the per-aircraft table where the requirement has one."""

    requirement: str
    value: float
    ci_low: float
    ci_high: float
    n: float
    count: int
    notes: tuple[str, ...] = ()
    per_aircraft: pd.DataFrame | None = field(default=None, compare=False)
    evidence: ErrorEvidence | FitEvidence | ShareClusters | None = field(default=None, compare=False)


def share(requirement: str, count: int, n: int, notes: tuple[str, ...] = (),
          per_aircraft: pd.DataFrame | None = None, clusters: ShareClusters | None = None) -> Outcome:
    """A proportion count / n with its Clopper-Pearson interval (NaN when n is 0); with ``clusters`` (trials
    that are not independent, grouped) the interval is that of the effective sample, n over the design
    effect, and a note says so where the effect is over 1 (kept as the outcome's evidence, to pool)."""
    deff = design_effect(int(count), int(n), clusters) if clusters is not None else 1.0
    p = effective_proportion(int(count), int(n), deff)
    if deff > 1.0:
        notes = (*notes, f"interval of {int(n) / deff:,.0f} effective trials: {int(n):,} in "
                         f"{clusters.clusters:,} groups that are not independent (design effect {deff:.3f})")
    return Outcome(requirement, p.value, p.ci_low, p.ci_high, int(n), int(count), notes, per_aircraft,
                   clusters)


def rate(requirement: str, events: int, exposure: float, notes: tuple[str, ...] = ()) -> Outcome:
    """Events per unit of exposure with the exact Poisson interval (NaN when the exposure is 0)."""
    r = poisson_rate(int(events), float(exposure))
    return Outcome(requirement, r.value, r.ci_low, r.ci_high, float(exposure), int(events), notes)


def withheld(requirement: str, reason: str) -> Outcome:
    """No figure: the data cannot support one; the reason says why."""
    return Outcome(requirement, math.nan, math.nan, math.nan, 0, 0, (reason,))
