"""The ADS-B quality sheets count and aggregate on integer group numbers (pipeline.quality.tables
_key_groups) instead of grouping the report texts: checked against a direct pandas grouping over the key
texts, with call signs that sort before, among and after the pooled "(all)" rows, a missing SAC/SIC and
missing indicator values."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.quality.tables import ALL, ID_KEYS, QUALITY_BIN_S, _adsb_over_time, _adsb_value_counts

CALLSIGNS = ["", "#1", "(AA", "ZZ9", "AB12", "ab"]  # "" and "#1" sort before "(all)", the rest after


def _reports(n: int = 3000, seed: int = 7) -> pd.DataFrame:
    """ADS-B reports as quality_tables hands them on: text labels, two stations, indicators with gaps."""
    rng = np.random.default_rng(seed)
    aircraft = rng.integers(0, len(CALLSIGNS), n)
    station = rng.integers(0, 3, n)  # station 2 has no SAC/SIC

    def indicator(hi: int) -> pd.Series:
        values = pd.array(rng.integers(0, hi, n), dtype="Int8")
        values[rng.random(n) < 0.1] = pd.NA
        return pd.Series(values)

    tod = np.sort(rng.uniform(0.0, 4 * QUALITY_BIN_S, n))
    sic = pd.array(station + 1, dtype="Int16")
    sic[station == 2] = pd.NA
    return pd.DataFrame({
        "callsign": pd.Series([CALLSIGNS[a] for a in aircraft], dtype=object),
        "address": pd.Series([f"7000{a:02X}" for a in aircraft], dtype=object),
        "sensor": pd.Series(["adsb"] * n, dtype=object),
        "sac": pd.array(np.zeros(n, np.int64), dtype="Int16"), "sic": sic,
        "time_of_day": tod,
        "timestamp": pd.Timestamp("2019-03-01", tz="UTC") + pd.to_timedelta(tod, unit="s"),
        "nucp_nic": indicator(12), "nacp": indicator(12), "nucr_nacv": indicator(5), "sil": indicator(4),
        "mops_version": indicator(3),
    })


def _with_pooled(adsb: pd.DataFrame) -> pd.DataFrame:
    return pd.concat([adsb, adsb.assign(callsign=ALL, address="")], ignore_index=True)


@pytest.mark.parametrize("spelled_all", [False, True])
def test_value_counts_equal_a_grouping_over_the_key_texts(spelled_all):
    """Counted once per aircraft and once per sensor, then summed: an aircraft spelling a pooled group's
    keys adds to its counts."""
    adsb = _reports()
    if spelled_all:
        adsb.loc[adsb.index[::50], ["callsign", "address"]] = [ALL, ""]
    got = _adsb_value_counts(adsb)
    long = _with_pooled(adsb).melt(id_vars=ID_KEYS, value_vars=["nucp_nic", "nacp", "nucr_nacv", "sil"],
                                   var_name="indicator", value_name="value")
    long["value"] = long["value"].astype("Int64")
    want = long.groupby([*ID_KEYS, "indicator", "value"], dropna=False, sort=True).size()
    assert got["callsign"].iloc[0] == "" and ALL in set(got["callsign"]) and got["sic"].isna().any()
    assert len(got) == len(want) and got["reports"].tolist() == want.tolist()
    keys = got[[*ID_KEYS, "indicator", "value"]].astype(object).where(got.notna(), None)
    expected = [tuple(None if pd.isna(v) else v for v in k) for k in want.index]
    assert [tuple(k) for k in keys.itertuples(index=False)] == expected
    totals = got.groupby([*ID_KEYS, "indicator"], dropna=False)["reports"].transform("sum")
    assert np.allclose(got["share_pct"], 100.0 * got["reports"] / totals)


@pytest.mark.parametrize("spelled_all", [False, True])
def test_over_time_equals_a_grouping_over_the_key_texts_and_bins(spelled_all):
    """Each report counts for its aircraft and its sensor, the two halves numbered apart; an aircraft
    whose keys spell a pooled group's (not decodable, but possible in a frame) joins that group."""
    adsb = _reports()
    if spelled_all:
        adsb.loc[adsb.index[::50], ["callsign", "address"]] = [ALL, ""]
    got = _adsb_over_time(adsb)
    frame = _with_pooled(adsb).assign(
        bin_start_tod=lambda f: np.floor(f["time_of_day"] / QUALITY_BIN_S) * QUALITY_BIN_S)
    groups = frame.groupby([*ID_KEYS, "bin_start_tod"], dropna=False, sort=True)
    want = groups.agg(reports=("nacp", "size"), first_tod=("time_of_day", "first"),
                      nacp_median=("nacp", lambda v: v.astype(float).median()),
                      sil_median=("sil", lambda v: v.astype(float).median()))
    assert len(got) == len(want) and got["reports"].tolist() == want["reports"].tolist()
    assert got["bin_start_tod"].tolist() == [k[-1] for k in want.index]
    assert got["callsign"].tolist() == [k[0] for k in want.index]
    assert got["sic"].isna().tolist() == [pd.isna(k[4]) for k in want.index]
    assert (got["callsign"] == ALL).sum() == 3 * 4  # pooled: two stations and one without SAC/SIC, 4 bins
    np.testing.assert_array_equal(got["nacp_median"], want["nacp_median"])  # medians of whole numbers
    np.testing.assert_array_equal(got["sil_median"], want["sil_median"])
    start = (got["bin_start_utc"] - pd.Timestamp("2019-03-01", tz="UTC")).dt.total_seconds()
    np.testing.assert_allclose(start, got["bin_start_tod"], atol=1e-6)
