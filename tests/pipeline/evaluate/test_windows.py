"""Pooling the windows of a span: each rule against arithmetic done here by hand or with scipy and numpy
directly (Clopper-Pearson from beta quantiles, Garwood from chi-square ones, inverse-variance weights,
percentiles of the values put together)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from msdc.pipeline.evaluate.outcome import ErrorEvidence, FitEvidence, Outcome, rate, share, withheld
from msdc.pipeline.evaluate.presets import Requirement
from msdc.pipeline.evaluate.statistics import cluster_sums, clustered_interval
from msdc.pipeline.evaluate.windows import (
    combine_counts,
    combine_grid,
    combine_outcomes,
    combine_per_aircraft,
)


def _req(ident: str, **parameters) -> Requirement:
    return Requirement(ident, 0.5, ">=", "clause", True, "test", "test", parameters=parameters)


def test_a_proportion_pools_successes_and_trials_with_the_exact_interval():
    windows = [share("mode3a_valid", 90, 100), share("mode3a_valid", 45, 50),
               withheld("mode3a_valid", "no report")]
    out = combine_outcomes(_req("mode3a_valid"), windows)
    assert (out.count, out.n) == (135, 150)
    assert out.value == pytest.approx(0.9)
    assert out.ci_low == pytest.approx(stats.beta.ppf(0.025, 135, 16))
    assert out.ci_high == pytest.approx(stats.beta.ppf(0.975, 136, 15))
    assert "pooled over 2 windows" in out.notes
    assert any(n.startswith("1 window without a figure (no report)") for n in out.notes)


def test_a_rate_pools_events_and_exposure_with_the_garwood_interval():
    out = combine_outcomes(_req("false_reports_per_scan"), [rate("false_reports_per_scan", 7, 100.0),
                                                            rate("false_reports_per_scan", 3, 50.0)])
    assert (out.count, out.n, out.value) == (10, 150.0, pytest.approx(10 / 150))
    assert out.ci_low == pytest.approx(stats.chi2.ppf(0.025, 20) / 2 / 150)
    assert out.ci_high == pytest.approx(stats.chi2.ppf(0.975, 22) / 2 / 150)


def test_no_window_with_a_figure_is_withheld_with_their_reasons():
    out = combine_outcomes(_req("pd"), [withheld("pd", "no update interval"), withheld("pd", "no report")])
    assert math.isnan(out.value) and out.n == 0
    assert out.notes == ("no window gave a figure: no update interval; no report",)


def test_a_per_target_pd_sums_each_aircraft_over_windows_then_takes_the_lowest():
    """A: 9 of 10 then 1 of 10 (10 of 20 pooled); B: 5 of 10 twice (10 of 20); C: 10 of 10. A's and B's
    pooled PD are equal; the lowest upper bound picks the first of them in order of appearance."""
    def per(rows):
        return pd.DataFrame(rows, columns=["aircraft", "expected", "detected"])

    w1 = share("pd", 5, 10, (), per([("A", 10, 9), ("B", 10, 5), ("C", 10, 10)]))
    w2 = share("pd", 1, 10, (), per([("A", 10, 1), ("B", 10, 5)]))
    out = combine_outcomes(_req("pd", scope="per_target"), [w1, w2])
    table = out.per_aircraft.set_index("aircraft")
    assert table.loc["A", "expected"] == 20 and table.loc["A", "detected"] == 10
    assert table.loc["C", "detected"] == 10 and table.loc["C", "pd"] == 1.0
    assert (out.count, out.n) == (10, 20)
    assert "per target: the aircraft 'A' of 3 reaches lowest" in out.notes


def _errors(values, aircraft, statistic, ident="rms_m") -> Outcome:
    values = np.asarray(values, float)
    evidence = (ErrorEvidence(statistic, 0, sums=cluster_sums(values, aircraft))
                if statistic in ("rms", "mean", "sd")
                else ErrorEvidence(statistic, 0, values=values, clusters=np.asarray(aircraft, str)))
    return Outcome(ident, math.nan, math.nan, math.nan, values.size, values.size, (), evidence=evidence)


@pytest.mark.parametrize("statistic,ident", [("rms", "rms_m"), ("mean", "mean_m"), ("p95", "p95_m")])
def test_an_error_statistic_is_that_of_the_windows_values_together(statistic, ident):
    rng = np.random.default_rng(11)
    a, b = rng.gamma(2.0, 40.0, 300), rng.gamma(3.0, 30.0, 200)
    ac_a, ac_b = rng.choice(list("ABCD"), 300), rng.choice(list("CDEF"), 200)
    windows = [_errors(a, ac_a, statistic, ident), _errors(b, ac_b, statistic, ident)]
    out = combine_outcomes(_req(ident), windows)
    both = np.concatenate([a, b])
    direct = {"rms": np.sqrt(np.mean(both**2)), "mean": np.mean(both),
              "p95": np.percentile(both, 95, method="inverted_cdf")}[statistic]
    assert out.value == pytest.approx(direct, rel=1e-12)
    assert out.n == 500 and "6 aircraft" in out.notes
    assert out.ci_low <= out.value <= out.ci_high


def test_a_pooled_percentiles_interval_is_that_of_the_windows_values_and_aircraft_together():
    """The windows keep each value's aircraft as codes; pooled, the bootstrap over aircraft must draw them as
    over the aircraft's names themselves (statistics.clustered_interval on the texts): the windows meet
    their aircraft in another order than the names sort in."""
    rng = np.random.default_rng(5)
    a, b = rng.gamma(2.0, 40.0, 240), rng.gamma(3.0, 30.0, 160)
    ac_a, ac_b = rng.choice(["Z9", "K2", "M1", "B7"], 240), rng.choice(["Q4", "B7", "A0", "Z9"], 160)
    windows = [_errors(a, ac_a, "p95", "p95_m"), _errors(b, ac_b, "p95", "p95_m")]
    out = combine_outcomes(_req("p95_m"), windows)
    direct = clustered_interval(np.concatenate([a, b]), np.concatenate([ac_a, ac_b]).astype(object), "p95")
    assert (out.value, out.ci_low, out.ci_high) == (direct.value, direct.ci_low, direct.ci_high)
    assert math.isfinite(out.ci_low) and "6 aircraft" in out.notes


@pytest.mark.parametrize("held", [None, 0], ids=["read-back", "in-passes"])
def test_a_span_that_keeps_its_values_on_disk_pools_them_as_together(tmp_path, monkeypatch, held):
    """A sensor's span with a spill folder: each window's percentile values written there as they come (the
    span holds none), the pooled percentile and interval those of the values and aircraft together
    (statistics.clustered_interval on the texts), the judged errors by range read back whole, in order, and
    their bands those of one frame (accuracy.error_bands); read back together, or in passes when they are
    more than the span reads at once (none here)."""
    from msdc.pipeline.evaluate import windows
    from msdc.pipeline.evaluate.accuracy import error_bands
    from msdc.pipeline.evaluate.windows import SensorSpan, SpilledValues

    if held is not None:
        monkeypatch.setattr(windows, "VALUES_HELD", held)

    rng = np.random.default_rng(8)
    a, b = rng.gamma(2.0, 40.0, 180), rng.gamma(3.0, 30.0, 120)
    ac_a, ac_b = rng.choice(["Z9", "K2", "B7"], 180), rng.choice(["Q4", "B7", "A0"], 120)
    span = SensorSpan("radar", spill=tmp_path / "sensor-0")
    for k, (v, ac) in enumerate(((a, ac_a), (b, ac_b))):
        errors = pd.DataFrame({"range_nm": v / 10.0, "aircraft": pd.Categorical(ac), "error_m": v})
        span.add((f"0{k}:00", f"0{k + 1}:00"), {("global", "p95_m", 0): _errors(v, ac, "p95", "p95_m")}, [],
                 pd.DataFrame(), {}, None, None, errors, pd.DataFrame())
    assert all(isinstance(o[("global", "p95_m", 0)].evidence, SpilledValues) for o in span.outcomes)
    assert len(list((tmp_path / "sensor-0").glob("values-0/*.parquet"))) == 2
    out = span.pooled([_req("p95_m")])[("global", "p95_m", 0)]
    direct = clustered_interval(np.concatenate([a, b]), np.concatenate([ac_a, ac_b]).astype(object), "p95")
    assert (out.value, out.ci_low, out.ci_high, out.n) == (direct.value, direct.ci_low, direct.ci_high, 300)
    assert out.evidence is None  # the pooled span keeps no values
    whole = span.judged_errors()
    assert whole["error_m"].tolist() == [*a, *b] and whole["aircraft"].astype(str).tolist() == [*ac_a, *ac_b]
    frame = pd.DataFrame({"range_nm": np.concatenate([a, b]) / 10.0,
                          "aircraft": np.concatenate([ac_a, ac_b]), "error_m": np.concatenate([a, b])})
    bands, direct = span.error_bands(), error_bands(frame)
    pd.testing.assert_frame_equal(bands.drop(columns="rms_m"), direct.drop(columns="rms_m"), check_exact=True)
    assert np.allclose(bands["rms_m"], direct["rms_m"], rtol=1e-13, atol=0.0) and len(bands) == 3


def test_a_span_that_keeps_its_tables_on_disk_sums_each_aircraft_as_together(tmp_path):
    """The per-target PD of test_a_per_target_pd_sums_each_aircraft_over_windows_then_takes_the_lowest,
    through a span with a spill folder: each window's per-aircraft table written there (the span holds a
    SpilledTable), the pooled table and the lowest aircraft as worked out there by hand."""
    from msdc.pipeline.evaluate.windows import SensorSpan, SpilledTable

    def per(rows):
        return pd.DataFrame(rows, columns=["aircraft", "expected", "detected"])

    span = SensorSpan("radar", spill=tmp_path / "sensor-0")
    for k, rows in enumerate(([("A", 10, 9), ("B", 10, 5), ("C", 10, 10)], [("A", 10, 1), ("B", 10, 5)])):
        span.add((f"0{k}:00", f"0{k + 1}:00"), {("global", "pd", 0): share("pd", 5, 10, (), per(rows))}, [],
                 pd.DataFrame(), {}, None, None, None, pd.DataFrame())
    assert all(isinstance(o[("global", "pd", 0)].per_aircraft, SpilledTable) for o in span.outcomes)
    out = span.pooled([_req("pd", scope="per_target")])[("global", "pd", 0)]
    table = out.per_aircraft.set_index("aircraft")
    assert (table.loc["A", "expected"], table.loc["A", "detected"]) == (20, 10)
    assert (table.loc["B", "expected"], table.loc["B", "detected"]) == (20, 10)
    assert (table.loc["C", "expected"], table.loc["C", "detected"], table.loc["C", "pd"]) == (10, 10, 1.0)
    assert (out.count, out.n) == (10, 20)
    assert "per target: the aircraft 'A' of 3 reaches lowest" in out.notes


def test_a_maximum_is_the_largest_of_the_windows():
    def top(v, n):
        return Outcome("max_m", v, math.nan, math.nan, n, n, (),
                       evidence=ErrorEvidence("max", 0, values=np.array([v])))

    out = combine_outcomes(_req("max_m"), [top(120.0, 40), top(310.5, 25), top(99.0, 3)])
    assert (out.value, out.n) == (310.5, 68) and math.isnan(out.ci_low)


def test_fitted_biases_combine_by_inverse_variance_with_cochrans_q():
    """10 m (SE 2) and 14 m (SE 4): weights 1/4 and 1/16, mean 10.8 m, SE 1/sqrt(0.3125) = 1.789 m,
    Q = 0.25 * 0.8^2 + 0.0625 * 3.2^2 = 0.8 on 1 degree of freedom."""
    def fit(v, se):
        return Outcome("range_bias_m", v, v - 2 * se, v + 2 * se, 100, 100, (),
                       evidence=FitEvidence(v, se, "m", 100, 12))

    out = combine_outcomes(_req("range_bias_m"), [fit(10.0, 2.0), fit(14.0, 4.0)])
    assert out.value == pytest.approx(10.8)
    se = 1 / math.sqrt(0.3125)
    assert out.ci_low == pytest.approx(10.8 - 1.959964 * se, rel=1e-6)
    assert out.ci_high == pytest.approx(10.8 + 1.959964 * se, rel=1e-6)
    assert out.n == 200
    assert any(f"Q 0.8 on 1 degrees of freedom (p = {stats.chi2.sf(0.8, 1):.2g})" in n for n in out.notes)
    assert not any("disagree" in n for n in out.notes)
    drift = combine_outcomes(_req("range_bias_m"), [fit(10.0, 0.5), fit(20.0, 0.5)])
    assert any("disagree beyond their standard errors" in n for n in drift.notes)


def test_grids_of_windows_cover_the_whole_rectangle_their_bands_make():
    """Window 1 reaches 0-20 NM up to 2,000 ft, window 2 0-10 NM up to 4,000 ft: the pooled grid holds the
    four cells, the one no window reached with nothing expected."""
    def grid(rows):
        cells = pd.DataFrame(rows, columns=["x_low", "x_high", "y_low", "y_high", "expected", "detected"])
        return cells.assign(pd=np.nan, ci_low=np.nan, ci_high=np.nan, enough=False)

    one = grid([(0, 10, 0, 2000, 30, 27), (10, 20, 0, 2000, 10, 5)])
    two = grid([(0, 10, 0, 2000, 20, 20), (0, 10, 2000, 4000, 25, 24)])
    out = combine_grid([one, two]).set_index(["x_low", "y_low"])
    assert len(out) == 4
    assert out.loc[(0, 0), "expected"] == 50 and out.loc[(0, 0), "detected"] == 47
    assert out.loc[(10, 2000), "expected"] == 0 and math.isnan(out.loc[(10, 2000), "pd"])
    assert out.loc[(0, 0), "ci_low"] == pytest.approx(stats.beta.ppf(0.025, 47, 4))
    assert bool(out.loc[(0, 0), "enough"]) and not bool(out.loc[(10, 0), "enough"])


def test_a_spans_bands_and_grids_folded_window_by_window_are_every_windows_combined():
    """The span's folds (evaluate.count_fold.CountFold: sums per key, a table at the end; combine_counts
    and combine_grid fold with it): counts by hand, PD and interval worked out again, a grid on the whole
    rectangle of its windows' bands, bands by their lower end, classes as first seen."""
    from msdc.pipeline.evaluate.count_fold import GRID_KEYS, CountFold

    def grid(rows):
        cells = pd.DataFrame(rows, columns=[*GRID_KEYS, "expected", "detected"])
        return cells.assign(pd=np.nan, ci_low=np.nan, ci_high=np.nan, enough=False)

    windows = [grid([(0, 10, 0, 2000, 30, 27), (10, 20, 0, 2000, 10, 5)]),
               grid([(0, 10, 0, 2000, 20, 20), (0, 10, 2000, 4000, 25, 24)]),
               grid([(0, 10, 0, 2000, 1, 0), (0, 10, 2000, 4000, 0, 0), (10, 20, 0, 2000, 4, 4),
                     (10, 20, 2000, 4000, 3, 1)])]
    fold = CountFold(GRID_KEYS, grid=True)
    for w in windows:
        fold.add(w)
    folded = fold.table()
    assert folded[["x_low", "y_low"]].to_numpy().tolist() == [[0, 0], [0, 2000], [10, 0], [10, 2000]]
    assert folded["expected"].tolist() == [51, 25, 14, 3] and folded["detected"].tolist() == [47, 24, 9, 1]
    assert folded["ci_low"].iloc[0] == pytest.approx(stats.beta.ppf(0.025, 47, 5))
    assert folded["enough"].tolist() == [True, True, False, False]
    with np.errstate(invalid="ignore", divide="ignore"):  # PD is detected over expected, NaN of none
        np.testing.assert_array_equal(folded["pd"], np.array([47 / 51, 24 / 25, 9 / 14, 1 / 3]))
    stepwise = None  # the pooled grid fed back with each next window: the same
    for w in windows:
        stepwise = combine_grid([stepwise, w])
    pd.testing.assert_frame_equal(folded, stepwise, check_exact=True)

    def band(lows, counts):
        return pd.DataFrame({"low": np.array(lows, float), "high": np.array(lows, float) + 10.0,
                             "expected": [c[0] for c in counts], "detected": [c[1] for c in counts],
                             "pd": np.nan, "ci_low": np.nan, "ci_high": np.nan, "enough": False})

    bands = [band([10, 20], [(30, 27), (3, 1)]), band([0, 10], [(1, 1), (40, 39)]), band([20], [(5, 5)])]
    fold = CountFold(["low", "high"])
    for b in bands:
        fold.add(b)
    folded = fold.table()
    assert folded["low"].tolist() == [0, 10, 20] and folded["expected"].tolist() == [1, 70, 8]
    assert folded["detected"].tolist() == [1, 66, 6] and folded["enough"].tolist() == [False, True, False]
    assert list(folded.columns) == list(bands[0].columns)
    classes = [pd.DataFrame({"class": ["airborne", "surface", "unknown"], "expected": [3, 4, 5],
                             "detected": [1, 2, 3]}), pd.DataFrame({"class": ["unknown", "airborne"],
                                                                    "expected": [2, 2], "detected": [2, 0]})]
    fold = CountFold(["class"])
    for c in classes:
        fold.add(c)
    classes_table = fold.table()
    assert classes_table["class"].tolist() == ["airborne", "surface", "unknown"]  # as first seen
    assert classes_table["expected"].tolist() == [5, 4, 7] and classes_table["detected"].tolist() == [1, 2, 5]
    assert list(classes_table.columns) == ["class", "expected", "detected", "pd", "ci_low", "ci_high"]
    pd.testing.assert_frame_equal(combine_counts(classes, ["class"]), classes_table, check_exact=True)


def test_per_aircraft_rows_of_windows_add_up():
    """An aircraft in two windows: 30 + 10 reports, 40 + 20 expected updates with 36 + 10 detected, RMS
    100 m over 30 errors and 200 m over 10 (pooled: sqrt((30 * 100^2 + 10 * 200^2) / 40) = 132.29 m), self
    reference 0.5 of 100 samples and 0 of 300 (pooled 50 / 400)."""
    columns = ["sensor", "aircraft", "built_by", "self_reference_share", "surface_share", "reference_samples",
               "reports", "expected_updates", "detected_updates", "pd", "ci_low", "ci_high", "rms_error_m",
               "errors_judged"]
    w1 = pd.DataFrame([("s", "A", "021:0/1", 0.5, 0.0, 100, 30, 40, 36, 0.9, 0, 1, 100.0, 30)],
                      columns=columns)
    w2 = pd.DataFrame([("s", "A", "048:1/2 | 021:0/1", 0.0, 0.0, 300, 10, 20, 10, 0.5, 0, 1, 200.0, 10),
                       ("s", "B", "021:0/1", 0.0, 1.0, 50, 5, 6, 6, 1.0, 0, 1, np.nan, np.nan)],
                      columns=columns)
    out = combine_per_aircraft([w1, w2]).set_index("aircraft")
    a = out.loc["A"]
    assert (a["reports"], a["expected_updates"], a["detected_updates"], a["windows"]) == (40, 60, 46, 2)
    assert a["pd"] == pytest.approx(46 / 60)
    assert a["ci_low"] == pytest.approx(stats.beta.ppf(0.025, 46, 15))
    assert a["rms_error_m"] == pytest.approx(math.sqrt((30 * 100**2 + 10 * 200**2) / 40))
    assert a["self_reference_share"] == pytest.approx(50 / 400)
    assert a["built_by"] == "021:0/1 | 048:1/2"
    assert math.isnan(out.loc["B", "rms_error_m"]) and out.loc["B", "surface_share"] == 1.0


def test_per_aircraft_tables_folded_window_by_window_equal_them_pooled_at_once():
    """Folding a third window into the pooled table of two gives the table of the three at once (a span's
    tables are folded as its windows come)."""
    columns = ["sensor", "aircraft", "built_by", "self_reference_share", "surface_share", "reference_samples",
               "reports", "expected_updates", "detected_updates", "pd", "ci_low", "ci_high", "rms_error_m",
               "errors_judged"]
    rows = [("s", "A", "021:0/1", 0.5, 0.0, 100, 30, 40, 36, 0.9, 0, 1, 100.0, 30),
            ("s", "A", "048:1/2", 0.0, 0.25, 300, 10, 20, 10, 0.5, 0, 1, 200.0, 10),
            ("s", "A", "021:0/1", 0.1, 0.0, 50, 5, 6, 6, 1.0, 0, 1, 50.0, 5)]
    windows = [pd.DataFrame([r], columns=columns) for r in rows]
    at_once = combine_per_aircraft(windows)
    folded = combine_per_aircraft([combine_per_aircraft([pd.DataFrame(), windows[0]]), windows[1]])
    folded = combine_per_aircraft([folded, windows[2]])
    pd.testing.assert_frame_equal(folded, at_once)
    assert at_once.loc[0, "windows"] == 3 and at_once.loc[0, "reference_samples"] == 450
    assert at_once.loc[0, "surface_share"] == pytest.approx(75 / 450)


def test_a_span_folds_its_windows_per_aircraft_tables_in_batches_equal_to_them_pooled_at_once(monkeypatch):
    """120 windows of 20 aircraft each (2 new a window, the others seen before) added to a span: its table
    is every window's pooled at once (counts exactly, shares and RMS to rounding), and the windows are
    folded in batches as large as the table before them (a few dozen folds, not one per window: each fold
    reads the whole table, so one per window costs time growing with the span's square)."""
    import msdc.pipeline.evaluate.windows as windows_module
    from msdc.pipeline.evaluate.windows import SensorSpan

    rng = np.random.default_rng(8)
    tables = []
    for w in range(120):
        n = 20
        tables.append(pd.DataFrame({
            "sensor": "s", "aircraft": [f"A{(2 * w + k) % 400:03d}" for k in range(n)], "built_by": "021:0/1",
            "self_reference_share": rng.random(n), "surface_share": rng.random(n),
            "reference_samples": rng.integers(1, 600, n), "reports": rng.integers(0, 60, n),
            "expected_updates": rng.integers(1, 60, n), "detected_updates": rng.integers(0, 2, n),
            "pd": 0.0, "ci_low": 0.0, "ci_high": 1.0, "rms_error_m": rng.random(n) * 100,
            "errors_judged": rng.integers(1, 50, n)}))
    folds = []
    combine = windows_module.combine_per_aircraft
    monkeypatch.setattr(windows_module, "combine_per_aircraft",
                        lambda frames: folds.append(1) or combine(frames))
    span = SensorSpan("radar")
    for w, table in enumerate(tables):
        span.add((str(w), str(w + 1)), {}, [], table, {}, None, None, None, pd.DataFrame())
    out = span.per_aircraft_table()
    at_once = combine(tables)
    pd.testing.assert_frame_equal(out, at_once, check_exact=False, rtol=1e-12)
    exact = ["sensor", "aircraft", "built_by", "reference_samples", "reports", "expected_updates",
             "detected_updates", "errors_judged", "windows"]
    pd.testing.assert_frame_equal(out[exact], at_once[exact], check_exact=True)
    assert len(out) == 258 and out["windows"].sum() == 120 * 20
    assert len(folds) <= 30, len(folds)


def test_the_builders_of_each_aircraft_are_every_windows_sensors_sorted_and_joined():
    """The pooled ``built_by`` of each aircraft, against the rule written as a pandas aggregation per group
    (every window's sensors split at " | ", blanks and missing ones left out, sorted and joined), on random
    tables whose aircraft come in no order, with missing builders and multi-sensor ones."""
    rng = np.random.default_rng(4)
    names = np.array(["021:0/1", "021:0/2", "048:20/1 + 021:0/1", "048:1/2 | 021:0/2", "", None], object)
    n = 300
    aircraft = rng.choice(list("QWERTYUIOP"), n)
    whole = pd.DataFrame({"sensor": rng.choice(["s1", "s2"], n), "aircraft": aircraft,
                          "built_by": names[rng.integers(0, len(names), n)], "self_reference_share": 0.0,
                          "surface_share": 0.0, "reference_samples": 10, "reports": 1})
    out = combine_per_aircraft([whole.iloc[:150], whole.iloc[150:]])
    rule = whole.groupby(["sensor", "aircraft"], sort=False)["built_by"].agg(
        lambda s: " | ".join(sorted({p for v in s.dropna() for p in str(v).split(" | ") if p})))
    assert list(zip(out["sensor"], out["aircraft"], strict=True)) == list(rule.index)  # first seen first
    assert list(out["built_by"]) == list(rule)
    assert out["built_by"].str.contains("048:1/2").any() and (out["built_by"] != "").all()


def test_a_note_every_window_gave_is_marked_as_each_windows_and_one_window_is_its_own_figure():
    """Two windows of 2 aircraft each ("2 aircraft" in both), 3 aircraft together: the pooled row says 3,
    and the windows' "2 aircraft" only as every window's. One window's outcome is its own, notes and all."""
    from dataclasses import replace

    a = replace(_errors([1.0, 2.0, 3.0], ["A", "B", "B"], "rms"), notes=("2 aircraft", "scan period 5 s"))
    b = replace(_errors([4.0, 5.0], ["B", "C"], "rms"), notes=("2 aircraft", "scan period 5 s"))
    out = combine_outcomes(_req("rms_m"), [a, b])
    assert "3 aircraft" in out.notes and "2 aircraft" not in out.notes
    assert "every window: 2 aircraft" in out.notes and "every window: scan period 5 s" in out.notes
    assert out.value == pytest.approx(math.sqrt((1 + 4 + 9 + 16 + 25) / 5))
    alone = combine_outcomes(_req("rms_m"), [a, withheld("rms_m", "no report")])
    assert alone.n == 3 and alone.evidence is a.evidence
    assert alone.notes == ("2 aircraft", "scan period 5 s", "pooled over 1 window",
                           "1 window without a figure (no report)")
