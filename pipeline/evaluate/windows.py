"""A span evaluated window by window, combined: each requirement's figure over the span from the windows'
outcomes, exactly where it is a sum (successes and trials, events and exposure, each aircraft's error sums,
every value of a percentile), and by inverse variance where it is a fit (a radar's biases, fitted per
window); the per-aircraft and per-bin tables by summing their counts.

A window is evaluated as ``--from``/``--to`` of that window alone would evaluate it (its reference built from
its reports), so the span's figures are those of its windows pooled: they differ from one evaluation of the
whole span only where a reference track or a scan estimate is cut at a window's edge (docs/guide/
evaluate.md, "A long span, window by window")."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
from pandas.api.types import union_categoricals

from msdc.pipeline.evaluate.accuracy import ERROR_RANGE_BAND_NM, error_bands, error_notes
from msdc.pipeline.evaluate.catalogue import CATALOGUE, ERROR, PROPORTION, RATE, SIGNED
from msdc.pipeline.evaluate.count_fold import GRID_KEYS, CountFold
from msdc.pipeline.evaluate.detection import per_target
from msdc.pipeline.evaluate.outcome import ErrorEvidence, FitEvidence, Outcome, rate, share, withheld
from msdc.pipeline.evaluate.presets import Requirement
from msdc.pipeline.evaluate.spill import SpilledFrames
from msdc.pipeline.evaluate.statistics import (
    Z975,
    ShareClusters,
    chi2_sf,
    clustered_interval,
    interval_from_sums,
    inverse_variance,
    pooled_sums,
    proportion,
)
from msdc.pipeline.evaluate.streamed import streamed_error_bands, streamed_interval

# below this p-value the windows' fits of one bias disagree beyond their standard errors
DRIFT_P = 0.01
# a spilled span pools a percentile, or its error bands, from more values than this in passes over the files
# (streamed: the same figures, memory bounded by a window's values) instead of reading them back together
VALUES_HELD = 5_000_000


def combine_outcomes(requirement: Requirement, outcomes: Sequence[Outcome]) -> Outcome:
    """The requirement's outcome over the span from its windows' outcomes (a window without a figure adds
    nothing; the notes say how many and why); withheld when no window gave one."""
    rid = requirement.id
    given = [o for o in outcomes if not (math.isnan(o.value) and o.n == 0)]
    if not given:
        reasons = list(dict.fromkeys(n for o in outcomes for n in o.notes))
        return withheld(rid, "no window gave a figure: " + "; ".join(reasons) if reasons
                        else "no window gave a figure")
    kind = CATALOGUE[rid].kind
    if len(given) == 1:  # one window's figure is its own
        out = given[0]
    elif kind == PROPORTION:
        out = _proportion(requirement, given)
    elif kind == RATE:
        out = _rate(rid, given)
    elif kind == ERROR:
        out = _error(rid, given)
    elif kind == SIGNED:
        out = _fits(rid, given)
    else:  # pragma: no cover - the catalogue has these four kinds
        raise ValueError(f"{rid}: no rule to combine a {kind} over windows")
    return Outcome(out.requirement, out.value, out.ci_low, out.ci_high, out.n, out.count,
                   (*out.notes, *_window_notes(outcomes, given)), out.per_aircraft, out.evidence)


def _window_notes(outcomes: Sequence[Outcome], given: Sequence[Outcome]) -> tuple[str, ...]:
    """How many windows the figure pools, the notes every one of them gave (marked as each window's: "6
    aircraft" in every window is not 6 over the span), and the windows without a figure."""
    out = [f"pooled over {len(given)} window{'s' if len(given) != 1 else ''}"]
    if len(given) > 1:
        common = [n for n in given[0].notes if all(n in o.notes for o in given[1:])]
        out += [f"every window: {n}" for n in common]
        if any(set(o.notes) - set(common) for o in given):
            out.append("notes that differ between windows are in the scorecard per window")
    figured = {id(o) for o in given}
    empty = [o for o in outcomes if id(o) not in figured]
    if empty:
        reasons = "; ".join(dict.fromkeys(n for o in empty for n in o.notes))
        out.append(f"{len(empty)} window{'s' if len(empty) != 1 else ''} without a figure"
                   + (f" ({reasons})" if reasons else ""))
    return tuple(out)


def _proportion(requirement: Requirement, given: Sequence[Outcome]) -> Outcome:
    """Successes over trials, summed; a per-target PD from each aircraft's updates summed over windows."""
    rid = requirement.id
    if rid == "pd" and requirement.parameters.get("scope") == "per_target":
        return per_target(combine_counts([o.per_aircraft for o in given if o.per_aircraft is not None],
                                         ["aircraft"]))
    per = [o.per_aircraft for o in given if o.per_aircraft is not None] if rid == "pd" else []
    table = combine_counts(per, ["aircraft"]) if per and len(per) == len(given) else None
    grouped = [o.evidence for o in given]  # the windows' cluster sums, where every window's trials had them
    clusters = sum(grouped[1:], grouped[0]) if all(isinstance(e, ShareClusters) for e in grouped) else None
    return share(rid, sum(o.count for o in given), int(sum(o.n for o in given)), (), table, clusters)


def _rate(rid: str, given: Sequence[Outcome]) -> Outcome:
    """Events and exposure added; a rate per aircraft (its outcomes' per-aircraft tables of ``changes``)
    takes as exposure the aircraft of every window, each once."""
    events = sum(o.count for o in given)
    tables = [o.per_aircraft for o in given if o.per_aircraft is not None and "changes" in o.per_aircraft]
    if len(tables) == len(given):
        aircraft = pd.concat(tables, ignore_index=True)["aircraft"].nunique()
        return rate(rid, events, float(aircraft), (f"{aircraft} aircraft tracked",))
    return rate(rid, events, float(sum(o.n for o in given)))


def _error(rid: str, given: Sequence[Outcome]) -> Outcome:
    """An error statistic from the windows' evidence pooled: aircraft sums, every value, or the largest."""
    evidence = [o.evidence for o in given]
    if all(isinstance(e, SpilledValues) for e in evidence):
        ci = streamed_interval(lambda: (e.part() for e in evidence), evidence[0].statistic,
                               seed=evidence[0].seed)
        return Outcome(rid, ci.value, ci.ci_low, ci.ci_high, ci.n, ci.n, error_notes(ci))
    if not all(isinstance(e, ErrorEvidence) for e in evidence):
        return withheld(rid, "a window kept no evidence to pool (this requirement is not combined over "
                             "windows by this version of msdc)")
    statistic, seed = evidence[0].statistic, evidence[0].seed
    n = int(sum(o.n for o in given))
    if statistic == "max":
        top = float(max(float(np.max(e.values)) for e in evidence))
        return Outcome(rid, top, math.nan, math.nan, n, n, ("a maximum has no interval",),
                       evidence=ErrorEvidence(statistic, seed, values=np.array([top])))
    if evidence[0].sums is not None:
        sums = pooled_sums([e.sums for e in evidence])
        ci = interval_from_sums(sums, statistic, seed=seed)
        kept = ErrorEvidence(statistic, seed, sums=sums)
    else:
        values = np.concatenate([e.values for e in evidence])
        # the aircraft of every window as one categorical, its labels sorted: their codes then order the
        # aircraft as the labels themselves would (the bootstrap draws whole aircraft in that order)
        clusters = union_categoricals([pd.Categorical(e.clusters) for e in evidence], sort_categories=True)
        ci = clustered_interval(values, clusters.codes, statistic, seed=seed)
        kept = ErrorEvidence(statistic, seed, values=values, clusters=clusters)
    return Outcome(rid, ci.value, ci.ci_low, ci.ci_high, ci.n, ci.n, error_notes(ci), evidence=kept)


def _fits(rid: str, given: Sequence[Outcome]) -> Outcome:
    """A fitted bias over the span: the windows' fits weighted by their inverse variance, its standard error
    1 / sqrt(sum of weights), and Cochran's Q of their agreement (a drift shows as disagreement)."""
    fits = [o.evidence for o in given]
    if not all(isinstance(f, FitEvidence) and f.se > 0 and math.isfinite(f.se) for f in fits):
        return withheld(rid, "a window's fit kept no standard error to combine")
    v = np.array([f.value for f in fits])
    value, se, q = inverse_variance(v, [f.se for f in fits])
    p = chi2_sf(q, len(fits) - 1)
    unit = fits[0].unit
    n = int(sum(f.n_reports for f in fits))
    notes = [f"the {len(fits)} windows' fits combined by inverse variance (a fit over the whole span may "
             f"differ): standard error {se:.3g} {unit}",
             f"the windows' fits range from {v.min():.4g} to {v.max():.4g} {unit}; Cochran's Q {q:.3g} on "
             f"{len(fits) - 1} degrees of freedom (p = {p:.2g})"]
    if p < DRIFT_P:
        notes.append(f"the windows' fits disagree beyond their standard errors (p < {DRIFT_P:g}): the bias "
                     "changed over the span, or a window's fit is off; see the scorecard per window")
    return Outcome(rid, value, value - Z975 * se, value + Z975 * se, n, n, tuple(notes),
                   evidence=FitEvidence(value, se, unit, n, max(f.aircraft for f in fits)))


def combine_counts(frames: Sequence[pd.DataFrame], keys: list[str]) -> pd.DataFrame:
    """Tables of ``expected`` and ``detected`` updates per key (aircraft, band, class) summed over windows, PD
    and its Clopper-Pearson interval worked out again (and ``enough`` where the tables have it, from
    bins.MIN_EXPECTED). Key order: first seen, bands by their lower end (count_fold.CountFold)."""
    fold = CountFold(keys)
    for frame in frames:
        fold.add(frame)
    return fold.table()


def combine_grid(frames: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """PD grids (bins.detection_grid) of several windows as one: every cell of any window's grid, on the
    whole rectangle their bands make (a cell no window reached: nothing expected), x varying slowest."""
    fold = CountFold(GRID_KEYS, grid=True)
    for frame in frames:
        fold.add(frame)
    return fold.table()


def _joined_builders(group: np.ndarray, built_by: np.ndarray, n: int) -> list[str]:
    """Per group (numbered 0..n-1), the sensors that built its reference in any of its rows, sorted and
    joined with " | ": one pass over the rows (a day's table is folded window by window, and a pandas
    aggregation per aircraft cost 0.2 ms each, every window again)."""
    parts: list[set[str]] = [set() for _ in range(n)]
    keyed = group >= 0  # NaN: a row in no group (a missing key)
    for k, v in zip(group[keyed].astype(np.int64).tolist(), built_by[keyed].tolist(), strict=True):
        if not pd.isna(v):
            parts[k].update(p for p in str(v).split(" | ") if p)
    return [" | ".join(sorted(p)) for p in parts]


def combine_per_aircraft(frames: Sequence[pd.DataFrame]) -> pd.DataFrame:
    """The evaluation's per-aircraft tables of one sensor's windows as one: counts summed, PD and interval
    again, the RMS error from the windows' mean squares, the reference shares weighted by its samples and the
    builders joined; ``windows`` counts the windows an aircraft is in."""
    frames = [f for f in frames if f is not None and len(f)]
    if not frames:
        return pd.DataFrame()
    whole = pd.concat(frames, ignore_index=True)
    keys = ["sensor", "aircraft"]
    # a window's own table counts as one window; a table pooled before says how many it holds
    whole = whole.assign(windows=whole["windows"].fillna(1).astype(np.int64) if "windows" in whole.columns
                         else 1)
    g = whole.groupby(keys, sort=False)
    out = g["windows"].sum().to_frame()
    out["built_by"] = _joined_builders(g.ngroup().to_numpy(), whole["built_by"].to_numpy(object), len(out))
    samples = whole["reference_samples"].to_numpy(float)
    for col in ("self_reference_share", "surface_share"):
        weighted = pd.Series(whole[col].to_numpy(float) * samples, index=whole.index)
        out[col] = (weighted.groupby([whole[k] for k in keys], sort=False).sum(min_count=1)
                    / g["reference_samples"].sum()).to_numpy()
    out["reference_samples"] = g["reference_samples"].sum()
    out["reports"] = g["reports"].sum()
    if "expected_updates" in whole.columns:
        out["expected_updates"] = g["expected_updates"].sum(min_count=1)
        out["detected_updates"] = g["detected_updates"].sum(min_count=1)
        known = out["expected_updates"].notna().to_numpy()
        e = out["expected_updates"].fillna(0).to_numpy(np.int64)
        d = out["detected_updates"].fillna(0).to_numpy(np.int64)
        p = proportion(d, e)
        for col, v in (("pd", p.value), ("ci_low", p.ci_low), ("ci_high", p.ci_high)):
            out[col] = np.where(known, v, np.nan)
    if "rms_error_m" in whole.columns:
        n = whole["errors_judged"].fillna(0).to_numpy(float)
        squares = pd.Series(np.square(whole["rms_error_m"].fillna(0).to_numpy(float)) * n, index=whole.index)
        total = g["errors_judged"].sum(min_count=1)
        out["errors_judged"] = total
        out["rms_error_m"] = np.sqrt(squares.groupby([whole[k] for k in keys], sort=False).sum().to_numpy()
                                     / total.to_numpy(float))
    out = out.reset_index()
    return out[[*(c for c in whole.columns if c in out.columns and c != "windows"), "windows"]]


@dataclass(frozen=True)
class SpilledValues:
    """A window's error values with their aircraft (a percentile's ErrorEvidence) as written to disk: the
    ``k``-th frame of ``frames``."""

    statistic: str
    seed: int
    frames: SpilledFrames
    k: int

    def load(self) -> ErrorEvidence:
        values, clusters = self.part()
        return ErrorEvidence(self.statistic, self.seed, values=values, clusters=clusters)

    def part(self) -> tuple[np.ndarray, pd.Categorical]:
        """The values and their aircraft, read back."""
        frame = self.frames.frame(self.k)
        return frame["value"].to_numpy(float), pd.Categorical(frame["aircraft"])


@dataclass(frozen=True)
class SpilledTable:
    """A window outcome's per-aircraft table as written to disk: the ``k``-th frame of ``frames``."""

    frames: SpilledFrames
    k: int

    def load(self) -> pd.DataFrame:
        return self.frames.frame(self.k)


def _loaded(outcome: Outcome, values: bool = True) -> Outcome:
    """The outcome with what its window wrote to disk read back (its error values only if ``values``)."""
    if values and isinstance(outcome.evidence, SpilledValues):
        outcome = replace(outcome, evidence=outcome.evidence.load())
    if isinstance(outcome.per_aircraft, SpilledTable):
        outcome = replace(outcome, per_aircraft=outcome.per_aircraft.load())
    return outcome


@dataclass
class SensorSpan:
    """One sensor's windows, folded as they come: its tables summed so far (fixed in size whatever the span),
    each window's outcomes and notes, the judged errors by range and the thinned map points. With ``spill``
    (a folder of its own) the judged errors by range, a percentile's values and an outcome's per-aircraft
    table (a PD's) wait there, read back when pooled, one requirement at a time: what the main process
    holds is then small whatever the span."""

    kind: str
    site: object = None
    spill: Path | None = None
    labels: list[tuple[str, str]] = field(default_factory=list)
    outcomes: list[dict] = field(default_factory=list)
    notes: list[list[str]] = field(default_factory=list)
    per_aircraft: pd.DataFrame = field(default_factory=pd.DataFrame)  # folded so far: per_aircraft_table()
    pending: list[pd.DataFrame] = field(default_factory=list, repr=False)  # windows' tables not folded yet
    bands: dict[str, CountFold] = field(default_factory=dict)
    polar: CountFold = field(default_factory=lambda: CountFold(GRID_KEYS, grid=True))
    vertical: CountFold = field(default_factory=lambda: CountFold(GRID_KEYS, grid=True))
    range_errors: list[pd.DataFrame] | SpilledFrames = field(default_factory=list)
    map_points: list[pd.DataFrame] = field(default_factory=list)
    values: dict[tuple, SpilledFrames] = field(default_factory=dict, repr=False)  # with spill, per outcome
    tables: dict[tuple, SpilledFrames] = field(default_factory=dict, repr=False)  # with spill, per outcome

    def __post_init__(self) -> None:
        if self.spill is not None:
            self.range_errors = SpilledFrames(self.spill / "errors-by-range")

    def add(self, label: tuple[str, str], outcomes: dict, notes: list[str], per_aircraft: pd.DataFrame,
            bands: dict[str, pd.DataFrame], polar: pd.DataFrame | None, vertical: pd.DataFrame | None,
            range_errors: pd.DataFrame | None, map_points: pd.DataFrame) -> None:
        """Fold one window in."""
        self.labels.append(label)
        self.outcomes.append(self._written(outcomes) if self.spill is not None else outcomes)
        self.notes.append(list(notes))
        self.pending.append(per_aircraft)
        if sum(len(t) for t in self.pending) >= len(self.per_aircraft):  # each row folded a few times at most
            self.per_aircraft_table()
        for key, table in bands.items():
            if key == "error_range":
                continue
            if key not in self.bands:
                self.bands[key] = CountFold(["class"] if key == "surface" else ["low", "high"])
            self.bands[key].add(table)
        self.polar.add(polar)
        self.vertical.add(vertical)
        if range_errors is not None:
            self.range_errors.append(range_errors)
        if len(map_points):
            self.map_points.append(map_points)

    def per_aircraft_table(self) -> pd.DataFrame:
        """The per-aircraft table over the windows so far (combine_per_aircraft of them all). The windows'
        tables are folded in once they hold as many rows as the table folded before them, not one by one:
        folding a table of every aircraft seen so far at every window cost time growing with the span's
        square (144 windows of 450 aircraft: 2.0 CPU-s a sensor, 576 windows 21.8 CPU-s)."""
        if self.pending:
            self.per_aircraft = combine_per_aircraft([self.per_aircraft, *self.pending])
            self.pending.clear()
        return self.per_aircraft

    def band_tables(self) -> dict[str, pd.DataFrame]:
        """Each detection band's table over the span (as combine_counts of every window's)."""
        return {key: fold.table() for key, fold in self.bands.items()}

    def grids(self) -> tuple[pd.DataFrame | None, pd.DataFrame | None]:
        """The polar and vertical PD grids over the span (as combine_grid of every window's; None when no
        window gave one)."""
        return tuple(fold.table() if fold.sums else None for fold in (self.polar, self.vertical))

    def judged_errors(self) -> pd.DataFrame | None:
        """Every window's judged errors by range as one frame (None when no window gave any)."""
        if not len(self.range_errors):
            return None
        if isinstance(self.range_errors, SpilledFrames):
            return self.range_errors.concat()
        return pd.concat(self.range_errors, ignore_index=True)

    def error_bands(self) -> pd.DataFrame | None:
        """The error-by-range table of every window's judged errors (None when no window gave any), from
        the files in passes when they hold more than VALUES_HELD errors."""
        if not len(self.range_errors):
            return None
        if isinstance(self.range_errors, SpilledFrames) and self.range_errors.rows > VALUES_HELD:
            return streamed_error_bands(self.range_errors.parts, ERROR_RANGE_BAND_NM)
        return error_bands(self.judged_errors())

    def _written(self, outcomes: dict) -> dict:
        """The window's outcomes, each one's error values and per-aircraft table written to disk
        (SpilledValues and SpilledTable in their place)."""
        out = {}
        for key, o in outcomes.items():
            e = o.evidence
            if isinstance(e, ErrorEvidence) and e.values is not None and e.clusters is not None:
                frame = pd.DataFrame({"value": e.values, "aircraft": e.clusters})
                written = self._write("values", key, frame)
                o = replace(o, evidence=SpilledValues(e.statistic, e.seed, *written))
            if o.per_aircraft is not None and len(o.per_aircraft):
                o = replace(o, per_aircraft=SpilledTable(*self._write("tables", key, o.per_aircraft)))
            out[key] = o
        return out

    def _write(self, kind: str, key: tuple, frame: pd.DataFrame) -> tuple[SpilledFrames, int]:
        """``frame`` written after the earlier windows' of the same kind and outcome key (a folder each):
        where, and its number there."""
        stores = getattr(self, kind)
        frames = stores.setdefault(key, SpilledFrames(self.spill / f"{kind}-{len(stores)}"))
        frames.append(frame)
        return frames, len(frames) - 1

    def pooled(self, requirements: Sequence[Requirement]) -> dict[tuple, Outcome]:
        """Every (sector, requirement id, index) any window gave, pooled over the windows; with ``spill``,
        one requirement's values read back at a time, and the pooled outcomes keep none."""
        out = {}
        for key in dict.fromkeys(k for o in self.outcomes for k in o):
            given = [o for o in (window_outcome(w, key) for w in self.outcomes) if o is not None]
            many = sum(o.n for o in given if isinstance(o.evidence, SpilledValues)) > VALUES_HELD
            given = [_loaded(o, values=not many) for o in given]
            pooled = combine_outcomes(requirements[key[2]], given)
            del given
            if self.spill is not None and isinstance(pooled.evidence, ErrorEvidence | SpilledValues):
                pooled = replace(pooled, evidence=None)
            out[key] = pooled
        return out

    def common_notes(self) -> tuple[list[str], list[tuple[tuple[str, str], str]]]:
        """The notes every window gave, and the others with their window."""
        return common_notes(list(zip(self.labels, self.notes, strict=True)))


def window_outcome(outcomes: dict, key: tuple) -> Outcome | None:
    """A window's outcome of (sector, requirement id, index): where the window had no aircraft on the surface
    its airborne figure is its global one (scorecard.surface_regions gives no airborne row then); a sector
    the window has no row of (no surface aircraft, no field monitor) adds nothing."""
    from msdc.pipeline.evaluate.scorecard import AIRBORNE, GLOBAL, SURFACE

    if key in outcomes:
        return outcomes[key]
    name, rid, index = key
    if name == AIRBORNE and (SURFACE, rid, index) not in outcomes:
        return outcomes.get((GLOBAL, rid, index))
    return None


def common_notes(labelled: Sequence[tuple[tuple[str, str], list[str]]]
                 ) -> tuple[list[str], list[tuple[tuple[str, str], str]]]:
    """The notes every window gave (in the first one's order; of several windows, written as every
    window's) and, with their window, the others."""
    if not labelled:
        return [], []
    common = [n for n in dict.fromkeys(labelled[0][1]) if all(n in notes for _, notes in labelled[1:])]
    rest = [(label, n) for label, notes in labelled for n in dict.fromkeys(notes) if n not in common]
    return ([f"every window: {n}" for n in common] if len(labelled) > 1 else common), rest


__all__ = ["DRIFT_P", "SensorSpan", "SpilledTable", "SpilledValues", "combine_counts", "combine_grid",
           "combine_outcomes", "combine_per_aircraft", "common_notes", "window_outcome"]
