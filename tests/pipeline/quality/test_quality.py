"""Quality tables against what the simulator emitted: counts, duplicates, intervals, gaps, speeds, NIC."""

from __future__ import annotations

import datetime as dt
from dataclasses import asdict

import numpy as np
import pandas as pd
import pytest

from fixtures.scenario import midnight_scenario
from fixtures.simulate import GAP_RULE_S, simulate
from msdc.pipeline.correlate.correlation import correlate
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import REQUIRED_COLUMNS as SENSOR_COLUMNS
from msdc.pipeline.quality.tables import (
    GAP_COLUMNS,
    HISTOGRAM_COLUMNS,
    QUALITY_COLUMNS,
    VALUE_COUNT_COLUMNS,
    histogram_edges_s,
    integrity_shares,
    quality_tables,
)
from msdc.pipeline.report.headers import column_name
from msdc.pipeline.report.quality_figures import interval_histogram_figure, slotting_figure

# one worker runs the module: the simulation and its tables made once, not on each worker
pytestmark = pytest.mark.xdist_group("quality")

DAY0 = pd.Timestamp("2019-06-14", tz="UTC")


def measurements(sim, radar=None) -> pd.DataFrame:
    """The measurement frame of a simulation, dated DAY0."""
    sensors = pd.DataFrame([asdict(sim.scenario.radar)])[SENSOR_COLUMNS]
    meas = build_measurements(sim.radar if radar is None else radar, sim.adsb, sensors, date=DAY0.date())
    assert (meas["sensor_kind"] == "adsb").sum() == len(sim.adsb)  # every simulated report has a position
    return meas


@pytest.fixture(scope="module")
def sim():
    return simulate(seed=2019)


@pytest.fixture(scope="module")
def frames(sim):
    return measurements(sim)


@pytest.fixture(scope="module")
def tables(frames):
    return quality_tables(frames)


def row_of(table: pd.DataFrame, callsign: str, sensor: str) -> pd.Series:
    hit = table[(table["callsign"] == callsign) & (table["sensor"] == sensor)]
    assert len(hit) == 1, (callsign, sensor)
    return hit.iloc[0]


def emitted(sim, sensor: str, callsign: str | None = None) -> pd.DataFrame:
    """The simulator's truth rows of one sensor (and aircraft), originals only (no duplicate copies)."""
    tt = sim.truth_tracks.query("sensor == @sensor and not duplicate")
    return tt if callsign is None else tt[tt["callsign"] == callsign]


def expected_intervals(sim, sensor: str, callsign: str) -> np.ndarray:
    dt = np.diff(np.sort(emitted(sim, sensor, callsign)["t_s"].to_numpy()))
    return dt[dt <= GAP_RULE_S]


def test_sheets_and_columns(tables):
    assert list(tables) == ["Quality", "Update intervals", "Gaps", "Jumps", "ADS-B quality",
                            "ADS-B quality over time"]
    assert list(tables["Quality"].columns) == QUALITY_COLUMNS
    assert list(tables["Update intervals"].columns) == HISTOGRAM_COLUMNS
    assert list(tables["Gaps"].columns) == GAP_COLUMNS
    assert list(tables["ADS-B quality"].columns) == VALUE_COUNT_COLUMNS


@pytest.mark.parametrize("sensor", ["radar", "adsb"])
def test_counts_duplicates_and_update_intervals_equal_the_emitted_reports(sim, tables, sensor):
    q = tables["Quality"]
    for ac in sim.aircraft:
        cs = ac.spec.callsign
        row = row_of(q, cs, sensor)
        originals = emitted(sim, sensor, cs)
        assert row["address"] == ac.spec.address_hex
        assert row["reports_after_dedup"] == len(originals)
        assert row["duplicates_removed"] == sim.truth["duplicates"][sensor]["by_aircraft"][cs]["count"]
        assert row["reports"] == len(originals) + row["duplicates_removed"]
        dt = expected_intervals(sim, sensor, cs)
        assert row["intervals"] == dt.size
        assert row["interval_min_s"] == dt.min() and row["interval_max_within_gap_s"] == dt.max()
        # the true maximum: the longest of every interval between successive emitted reports, gaps included
        every_dt = np.diff(np.sort(originals["t_s"].to_numpy()))
        assert row["interval_max_s"] == every_dt.max()
        assert row["interval_max_s"] > GAP_RULE_S or row["interval_max_s"] == row["interval_max_within_gap_s"]
        assert row["interval_median_s"] == pytest.approx(np.median(dt))
        assert row["interval_p95_s"] == pytest.approx(np.percentile(dt, 95))
        assert row["first_tod"] == originals["t_s"].min() and row["last_tod"] == originals["t_s"].max()
        assert row["first_utc"] == DAY0 + pd.to_timedelta(originals["t_s"].min(), unit="s")
        assert row["last_utc"] == DAY0 + pd.to_timedelta(originals["t_s"].max(), unit="s")
    pooled = row_of(q, "(all)", sensor)
    every = np.concatenate([expected_intervals(sim, sensor, a.spec.callsign) for a in sim.aircraft])
    assert pooled["reports_after_dedup"] == len(emitted(sim, sensor))
    assert pooled["duplicates_removed"] == sim.truth["duplicates"][sensor]["total"]
    assert pooled["interval_median_s"] == pytest.approx(np.median(every))
    assert pooled["interval_p95_s"] == pytest.approx(np.percentile(every, 95))
    hist = tables["Update intervals"].query("sensor == @sensor")
    counts, _ = np.histogram(every, bins=histogram_edges_s(GAP_RULE_S))
    np.testing.assert_array_equal(hist["intervals"], counts)
    assert hist["bin_end_s"].iloc[-1] == GAP_RULE_S
    if sensor == "radar":  # one report per scan: the scan period
        assert pooled["interval_median_s"] == pytest.approx(sim.scenario.scan_period_s, abs=0.05)
    else:
        lo, hi = sim.scenario.adsb_interval_s
        assert lo - 0.01 <= pooled["interval_min_s"]
        assert row_of(q, "MAS72", "adsb")["interval_p95_s"] <= hi + 0.01


def test_missing_and_zero_radar_speeds_equal_the_injected_flags(sim, tables):
    q = tables["Quality"]
    for cs, flags in sim.truth["radar_speed_flags"].items():
        row = row_of(q, cs, "radar")
        assert row["speed_missing"] == flags["missing_reports"]
        assert row["speed_zero"] == flags["zero_reports"]
        n = len(emitted(sim, "radar", cs))
        assert row["speed_missing_or_zero_pct"] == pytest.approx(
            100.0 * (flags["missing_reports"] + flags["zero_reports"]) / n)
    flags = emitted(sim, "radar")["speed_flag"]
    pooled = row_of(q, "(all)", "radar")
    assert pooled["speed_missing"] == (flags == "missing").sum()
    assert pooled["speed_zero"] == (flags == "zero").sum()
    assert row_of(q, "(all)", "adsb")["speed_missing_or_zero"] == 0


def test_gaps_and_reappearance(sim, tables):
    gaps = tables["Gaps"]
    for sensor, key in (("adsb", "adsb_gaps"), ("radar", "radar_gaps")):
        got = gaps[gaps["sensor"] == sensor].sort_values(["callsign", "gap_start_tod"])
        want = pd.DataFrame(sim.truth[key]).sort_values(["callsign", "start_s"])
        assert got["callsign"].tolist() == want["callsign"].tolist()
        np.testing.assert_array_equal(got["gap_start_tod"], want["start_s"])
        np.testing.assert_array_equal(got["gap_end_tod"], want["end_s"])
        np.testing.assert_allclose(got["gap_duration_s"], want["duration_s"])
        assert got["reappeared_after_1h"].tolist() == (want["duration_s"] > 3600).tolist()
    back = gaps[gaps["reappeared_after_1h"]]
    assert set(back["callsign"]) == {"MAS136"} and set(back["sensor"]) == {"radar", "adsb"}
    assert str(gaps["gap_start_utc"].dtype) == str(gaps["gap_end_utc"].dtype) == "datetime64[ns, UTC]"
    want = pd.DataFrame(sim.truth["radar_gaps"]).query("callsign == 'MAS136'").sort_values("start_s").iloc[0]
    got = back[back["sensor"] == "radar"].sort_values("gap_start_tod").iloc[0]
    assert got["gap_start_utc"] == DAY0 + pd.to_timedelta(want["start_s"], unit="s")
    assert got["gap_end_utc"] == DAY0 + pd.to_timedelta(want["end_s"], unit="s")
    q = tables["Quality"]
    assert row_of(q, "MAS136", "radar")["reappearances"] == 1
    assert row_of(q, "(all)", "adsb")["gaps"] == len(sim.truth["adsb_gaps"])


def test_jumps_per_aircraft(sim, tables):
    injected = pd.DataFrame(sim.truth["jumps"])
    q = tables["Quality"]
    for cs, n in injected["callsign"].value_counts().items():
        assert row_of(q, cs, "adsb")["jumps"] == n
    assert row_of(q, "(all)", "adsb")["jumps"] == len(injected)
    jumps = tables["Jumps"]
    np.testing.assert_array_equal(np.sort(jumps["time_of_day"]), np.sort(injected["t_s"]))
    assert (jumps["jump_size_m"] > 10_000).all()
    assert str(jumps["utc"].dtype) == "datetime64[ns, UTC]"
    want = (DAY0 + pd.to_timedelta(np.sort(injected["t_s"].to_numpy()), unit="s")).tolist()
    assert sorted(jumps["utc"]) == want


def test_adsb_quality_indicators(sim, tables):
    copy = sim.truth_tracks.query("sensor == 'adsb'").sort_values("row")["duplicate"].to_numpy()
    originals = sim.adsb[~copy]
    counts = tables["ADS-B quality"]
    pooled = counts[counts["callsign"] == "(all)"]
    for indicator in ("nucp_nic", "nacp", "nucr_nacv", "sil"):
        got = pooled[pooled["indicator"] == indicator].set_index("value")["reports"]
        want = originals[indicator].value_counts()
        assert got.sort_index().tolist() == want.sort_index().tolist(), indicator
        assert got.index.tolist() == sorted(want.index.tolist())
    shares = pooled[pooled["indicator"] == "nacp"]["share_pct"]
    assert shares.sum() == pytest.approx(100.0)
    low = sim.truth_tracks.query("sensor == 'adsb' and not duplicate")["low_quality"]
    q = row_of(tables["Quality"], "(all)", "adsb")
    assert q["nic_below_6_pct"] == pytest.approx(100.0 * low.mean())
    assert q["low_integrity_pct"] == pytest.approx(100.0 * low.mean())  # MOPS 2: NIC < 6
    assert q["nucp_below_5_pct"] == pytest.approx(  # episodes carry NIC 4 or 5
        100.0 * (originals["nucp_nic"] < 5).mean())
    assert q["mops_versions"] == "2"
    over_time = tables["ADS-B quality over time"]
    whole = over_time[over_time["callsign"] == "(all)"]
    assert whole["reports"].sum() == len(originals)
    assert (whole["bin_start_tod"] % 600 == 0).all()
    starts = DAY0 + pd.to_timedelta(np.floor(originals["time_of_day"] / 600) * 600, unit="s")
    assert str(whole["bin_start_utc"].dtype) == "datetime64[ns, UTC]"  # the bin start, within float rounding
    starts = pd.Series(starts.drop_duplicates().sort_values().array)
    error = whole["bin_start_utc"].reset_index(drop=True) - starts
    assert error.abs().max() <= pd.Timedelta(1, "us")
    assert set(whole["nacp_median"]) <= {8.0, 8.5, 9.0}


def test_integrity_shares_follow_the_mops_version():
    frame = pd.DataFrame({"nucp_nic": [4, 5, 5, 6, 7, 9], "mops_version": [0, 0, 2, 2, 1, 2]})
    s = integrity_shares(frame)
    assert s["nucp_below_5_pct"] == pytest.approx(100 / 6) and s["nic_below_6_pct"] == pytest.approx(50.0)
    # MOPS 0: NUCp 4 low, NUCp 5 fine; MOPS 1/2: NIC 5 low
    assert s["low_integrity_pct"] == pytest.approx(100 * 2 / 6)
    assert s["mops_versions"] == "0,1,2"
    s = integrity_shares(frame.drop(columns="mops_version"))
    assert np.isnan(s["low_integrity_pct"]) and s["nic_below_6_pct"] == pytest.approx(50.0)


def test_without_timestamps_identities_or_optional_columns(sim):
    sensors = pd.DataFrame([asdict(sim.scenario.radar)])[SENSOR_COLUMNS]
    radar = sim.radar.copy()
    for c in ("callsign", "address", "mode3a"):  # plots with no identity at all
        radar[c] = radar[c].astype(object)
        radar.loc[radar.index[:50], c] = None
    # and plots known by a Mode 3/A code alone, one no other report carries
    radar.loc[radar.index[50:60], ["callsign", "address"]] = None
    radar.loc[radar.index[50:60], "mode3a"] = "7777"
    # no nucr_nacv / sil / mops_version, no date
    meas = build_measurements(radar, sim.adsb.drop(columns=["nucr_nacv", "sil", "mops_version"],
                                                   errors="ignore"), sensors)
    t = quality_tables(meas)
    q = t["Quality"]
    anon = q[(q["callsign"] == "(no identity)") & (q["address"] == "")]
    assert len(anon) == 1 and anon["reports"].iloc[0] == 50
    assert row_of(q, "M3A:7777", "radar")["reports"] == 10  # labelled with its code, not left blank
    # many targets: no intervals or gaps of theirs, here or in the pooled row and histogram
    assert anon["intervals"].iloc[0] == 0 and np.isnan(anon["gaps"].iloc[0])
    radar_rows = q[(q["sensor"] == "radar") & (q["callsign"] != "(all)")]
    assert row_of(q, "(all)", "radar")["intervals"] == radar_rows["intervals"].sum()
    hist = t["Update intervals"]
    assert hist.loc[hist["sensor"] == "radar", "intervals"].sum() == radar_rows["intervals"].sum()
    assert q["first_utc"].isna().all() and t["Gaps"]["gap_start_utc"].isna().all()
    assert str(q["first_utc"].dtype) == str(t["Gaps"]["gap_end_utc"].dtype) == "datetime64[ns, UTC]"
    assert t["Jumps"]["utc"].isna().all() and t["ADS-B quality over time"]["bin_start_utc"].isna().all()
    assert set(t["ADS-B quality"]["indicator"]) == {"nucp_nic", "nacp"}
    assert np.isnan(row_of(q, "(all)", "adsb")["low_integrity_pct"])
    assert row_of(q, "(all)", "radar")["reports"] == len(radar)
    empty = quality_tables(meas.iloc[:0])
    assert all(v.empty for v in empty.values())


def test_intervals_across_midnight():
    sim = simulate(midnight_scenario(), seed=5)
    q = quality_tables(measurements(sim))["Quality"]
    for sensor in ("radar", "adsb"):
        row = row_of(q, "(all)", sensor)
        assert row["first_tod"] < 86400.0 < row["last_tod"]
        assert row["interval_max_within_gap_s"] <= GAP_RULE_S
        longest = max(g["duration_s"] for g in sim.truth[f"{sensor}_gaps"])
        assert row["interval_max_s"] == pytest.approx(longest)
        assert row["gaps"] == len(sim.truth[f"{sensor}_gaps"])
    last = row_of(q, "(all)", "radar")
    assert last["last_utc"].date() == dt.date(2019, 6, 15) and last["last_utc"].hour == 0  # the next day
    assert last["last_utc"] == DAY0 + pd.to_timedelta(last["last_tod"], unit="s")


def test_quality_figures(sim, frames, tables, tmp_path):
    radar, adsb = frames[frames["sensor_kind"] == "radar"], frames[frames["sensor_kind"] == "adsb"]
    png = interval_histogram_figure(tables["Update intervals"], tmp_path / "intervals.png")
    assert png.read_bytes()[:4] == b"\x89PNG"
    run = correlate(frames, callsign="MAS72")
    png = slotting_figure(run.windows[0], radar, adsb, tmp_path / "slots.png")
    assert png.exists() and png.stat().st_size > 10_000
    empty = interval_histogram_figure(tables["Update intervals"].iloc[:0], tmp_path / "none.png")
    assert empty.exists()


def test_interval_labels_never_overlap_and_the_largest_count_is_labelled():
    """A radar's intervals fill 30 neighbouring 0.1 s bins near its 4 s scan (real CAT048: the counts ran
    into one another): the labels left visible do not overlap on the canvas, the largest count is one of
    them, and a lone bin far away keeps its own."""
    from msdc.pipeline.quality.tables import histogram_edges_s
    from msdc.pipeline.report.quality_figures import interval_histogram

    edges = histogram_edges_s(180.0)
    counts = np.zeros(len(edges) - 1, np.int64)
    near = (edges[:-1] >= 3.0) & (edges[:-1] < 6.0)
    counts[near] = np.arange(1, near.sum() + 1) * 37
    counts[np.flatnonzero(np.isclose(edges[:-1], 15.0))] = 300
    hist = pd.DataFrame({"sensor": "radar", "sac": 20, "sic": 129, "bin_start_s": edges[:-1],
                         "bin_end_s": edges[1:], "intervals": counts})
    fig = interval_histogram(hist)
    renderer = fig.canvas.get_renderer()
    shown = [t for t in fig.axes[0].texts if t.get_visible() and t.get_text()]
    boxes = [t.get_window_extent(renderer) for t in shown]
    assert all(not a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
    texts = {t.get_text() for t in shown}
    # a label beside a taller neighbour would sit on its bar: on this rising ramp only the top one stays
    assert str(counts.max()) in texts and "300" in texts and 2 <= len(shown) < near.sum()


def test_slotting_figure_rows_equal_a_selection_over_both_sensors_joined(frames):
    """The figure's raw reports are found without joining both sensors' frames: the same rows, values and
    clock as select() over the two joined (also with one sensor empty)."""
    from msdc.pipeline.correlate.windows import in_window
    from msdc.pipeline.model.measurements import select
    from msdc.pipeline.model.time import midnight, with_clock
    from msdc.pipeline.report.quality_figures import _raw_in_window

    radar, adsb = frames[frames["sensor_kind"] == "radar"], frames[frames["sensor_kind"] == "adsb"]
    window = correlate(frames, callsign="MAS72").windows[0]
    s = window.summary
    for meas, other in ((radar, adsb), (adsb, radar), (radar.iloc[:0], adsb)):
        both = pd.concat([meas, other], ignore_index=True)
        want = with_clock(select(both, s["callsign"], s["address"]), midnight(both["time"]))
        want = want[in_window(want["time_of_day"], s["start_tod"], s["end_tod"])]
        got = _raw_in_window(window, [meas, other])
        assert len(got) > 0
        pd.testing.assert_frame_equal(got, want, check_exact=True)


def test_slotting_figure_of_a_surface_radar_draws_its_multilateration_reference(frames):
    """--pairs smr-mlat: both sides' reports drawn and named by their kind. The radar and ADS-B reports of
    MAS72 relabelled as a surface radar and a multilateration, with the ADS-B left beside them and first
    in the frame: the figure drew no reference reports and called the multilateration "ADS-B"."""
    from msdc.pipeline.report.quality_figures import slotting

    def relabelled(rows: pd.DataFrame, kind: str, sensor: str) -> pd.DataFrame:
        return rows.assign(sensor_kind=kind, sensor_id=sensor)

    radar, adsb = frames[frames["sensor_kind"] == "radar"], frames[frames["sensor_kind"] == "adsb"]
    smr, mlat = relabelled(radar, "smr", "010:0/7:smr"), relabelled(adsb, "mlat", "010:0/107:mlat")
    others = pd.concat([adsb, smr, mlat], ignore_index=True)  # the job's non-radar frame, ADS-B first
    others = others.astype({"sensor_kind": "category", "sensor_id": "category"})
    window = correlate(others, callsign="MAS72", pairs="smr-mlat").windows[0]
    s = window.summary
    assert (s["radar_sensor"], s["reference_sensor"]) == ("010:0/7:smr", "010:0/107:mlat")
    fig = slotting(window, others.iloc[:0], others)
    drawn = {line.get_label(): len(line.get_xdata()) for line in fig.axes[0].get_lines()}
    for rows, label in ((smr, "Surface radar 010:0/7:smr"), (mlat, "Multilateration 010:0/107:mlat")):
        ours = rows[(rows["callsign"] == "MAS72") & rows["time"].between(s["start"], s["end"])]
        assert drawn[label] == len(ours) > 0


def _sheet(ws) -> pd.DataFrame:
    """A workbook sheet read back by openpyxl: header row (as snake_case names), then the cells' values as
    openpyxl reads them."""
    rows = list(ws.iter_rows(values_only=True))
    return pd.DataFrame(rows[1:], columns=[column_name(h) for h in rows[0]], dtype=object)


def _formats(ws, header: str) -> set[str]:
    col = [column_name(c.value) for c in ws[1]].index(header)
    return {row[col].number_format for row in ws.iter_rows(min_row=2) if row[col].value is not None}


def test_workbook_times_are_excel_dates_of_the_truth(sim, tables, tmp_path):
    """Gap and jump instants read back by openpyxl are datetimes at the simulator's emission times on DAY0
    (openpyxl reads to the millisecond: within half of one), formatted as UTC date-times."""
    import openpyxl

    from msdc.pipeline.report.excel import write_tables
    write_tables(tables, tmp_path / "q.xlsx")
    wb = openpyxl.load_workbook(tmp_path / "q.xlsx")
    half_ms = dt.timedelta(microseconds=500)
    day0 = dt.datetime(2019, 6, 14)  # Excel dates carry no zone: the UTC wall clock
    gaps = _sheet(wb["Gaps"])
    want = pd.DataFrame(sim.truth["radar_gaps"] + sim.truth["adsb_gaps"])
    assert len(gaps) == len(want)
    got = sorted(zip(gaps["callsign"], gaps["gap_start_utc"], gaps["gap_end_utc"], strict=True))
    want = want.sort_values(["callsign", "start_s"])
    for (cs, start, end), (_, w) in zip(got, want.iterrows(), strict=True):
        assert cs == w["callsign"]
        assert abs(start - (day0 + dt.timedelta(seconds=w["start_s"]))) <= half_ms
        assert abs(end - (day0 + dt.timedelta(seconds=w["end_s"]))) <= half_ms
    assert all(isinstance(v, dt.datetime) for v in gaps["gap_start_utc"])
    assert _formats(wb["Gaps"], "gap_start_utc") == {"yyyy-mm-dd hh:mm:ss.000"}
    jumps = sorted(_sheet(wb["Jumps"])["utc"])
    injected = sorted(day0 + dt.timedelta(seconds=s) for s in pd.DataFrame(sim.truth["jumps"])["t_s"])
    assert len(jumps) == len(injected)
    assert all(abs(a - b) <= half_ms for a, b in zip(jumps, injected, strict=True))
    quality = _sheet(wb["Quality"])
    first = quality[(quality["callsign"] == "MAS72") & (quality["sensor"] == "adsb")]["first_utc"].iloc[0]
    t0 = emitted(sim, "adsb", "MAS72")["t_s"].min()
    assert isinstance(first, dt.datetime) and abs(first - (day0 + dt.timedelta(seconds=t0))) <= half_ms
    bins = _sheet(wb["ADS-B quality over time"])["bin_start_utc"]
    assert bins.map(lambda v: v.minute % 10 == 0 and v.second == 0 and v.microsecond == 0).all()


def test_undated_workbook_shows_time_of_day_only(sim, tmp_path):
    """Without a date the instants are empty cells and the time of day is a clock time, as before."""
    import openpyxl

    from msdc.pipeline.report.excel import write_tables
    sensors = pd.DataFrame([asdict(sim.scenario.radar)])[SENSOR_COLUMNS]
    t = quality_tables(build_measurements(sim.radar, sim.adsb, sensors))
    write_tables(t, tmp_path / "u.xlsx")
    wb = openpyxl.load_workbook(tmp_path / "u.xlsx")
    for sheet, clock, instant in (("Quality", "first_tod", "first_utc"), ("Gaps", "gap_start_tod",
                                  "gap_start_utc"), ("Jumps", "time_of_day", "utc")):
        frame = _sheet(wb[sheet])
        assert frame[instant].isna().all(), sheet
        assert _formats(wb[sheet], clock) == {"[hh]:mm:ss.000"}
    gaps = _sheet(wb["Gaps"])
    want = sorted(pd.DataFrame(sim.truth["radar_gaps"] + sim.truth["adsb_gaps"])["start_s"])
    got = sorted(v.total_seconds() for v in gaps["gap_start_tod"])  # a clock time reads as a timedelta
    np.testing.assert_allclose(got, want, atol=5e-4)


def test_json_times_are_iso_text_to_the_millisecond(sim, tables):
    """The JSON rows keep ISO 8601 UTC text, cut to the millisecond, worked out here from the truth times."""
    from msdc.pipeline.report.summary import table_records

    def iso(seconds: float) -> str:
        ms = int(np.floor(seconds * 1000 + 1e-6))
        h, rest = divmod(ms, 3_600_000)
        return f"2019-06-14T{h:02d}:{rest // 60_000:02d}:{rest // 1000 % 60:02d}.{ms % 1000:03d}Z"

    gaps = table_records(tables["Gaps"])
    want = pd.DataFrame(sim.truth["radar_gaps"] + sim.truth["adsb_gaps"])
    assert sorted((g["callsign"], g["gap_start_utc"], g["gap_end_utc"]) for g in gaps) == sorted(
        (w["callsign"], iso(w["start_s"]), iso(w["end_s"])) for _, w in want.iterrows())
    jumps = table_records(tables["Jumps"])
    assert sorted(j["utc"] for j in jumps) == sorted(iso(s) for s in pd.DataFrame(sim.truth["jumps"])["t_s"])
    assert all(isinstance(j["time_of_day"], float) for j in jumps)
    bins = table_records(tables["ADS-B quality over time"])
    assert all(b["bin_start_utc"] == iso(b["bin_start_tod"]) for b in bins)
    undated = table_records(pd.DataFrame({"t_utc": pd.Series([pd.NaT, pd.Timestamp("1970-01-01 08:00",
                                                                                   tz="UTC")])}))
    assert undated == [{"t_utc": None}, {"t_utc": None}]


def test_0_2x_figure_of_merit_is_its_own_indicator():
    # CAT021 0.23 reports with PA 0, 6, 7, 7 (I021/090) and no NUCp/NIC: the ADS-B quality sheets count PA as
    # fom_pa, and the NUCp/NIC shares are unknown, not PA's
    from msdc.pipeline.model.measurements import adsb_measurements

    frame = pd.DataFrame({"time_of_day": [1.0, 2.0, 3.0, 4.0], "day": 0,
                          "latitude": [1.0, 1.001, 1.002, 1.003], "longitude": 100.0, "sac": 0, "sic": 1,
                          "address": "ABC123", "callsign": "ABC1",
                          "fom_pa": pd.array([0, 6, 7, 7], dtype="Int64")})
    t = quality_tables(adsb_measurements(frame, date=DAY0.date()))
    counts = t["ADS-B quality"]
    pooled = counts[counts["callsign"] == "(all)"]
    assert set(pooled["indicator"]) == {"fom_pa"}
    assert dict(zip(pooled["value"], pooled["reports"], strict=True)) == {0: 1, 6: 1, 7: 2}
    q = t["Quality"]
    assert q[["nucp_below_5_pct", "nic_below_6_pct"]].isna().all().all()
    over_time = t["ADS-B quality over time"]
    assert "fom_pa_median" in over_time and "nucp_nic_median" not in over_time


@pytest.mark.parametrize(("gap_s", "error"), [(-1.0, ValueError), (0, ValueError), (float("inf"), ValueError),
                                              (None, TypeError)])
def test_quality_tables_reject_a_bad_gap(gap_s, error):
    with pytest.raises(error, match=f"gap_s {gap_s!r}: must be a "):
        quality_tables(pd.DataFrame({"sensor_kind": [], "time": []}), gap_s=gap_s)


def test_workbook_headers_say_the_unit_the_cells_show(tables, tmp_path):
    """A column shown as a clock time (hh:mm:ss) is not named in seconds (first_tod_s showed 08:00:00)."""
    import openpyxl

    from msdc.pipeline.report.excel import write_tables
    write_tables(tables, tmp_path / "q.xlsx")
    wb = openpyxl.load_workbook(tmp_path / "q.xlsx")
    clocks = {(ws.title, h) for ws in wb.worksheets for h in (c.value for c in ws[1]) if h and ws.max_row > 1
              and "[hh]:mm:ss.000" in _formats(ws, column_name(h))}
    names = {(title, column_name(h)) for title, h in clocks}
    assert ("Quality", "first_tod") in names and ("Gaps", "gap_start_tod") in names
    assert ("ADS-B quality over time", "bin_start_tod") in names
    assert not [h for _, h in names if h.endswith("_s")]
    assert all(h.endswith(" (UTC)") for _, h in clocks), clocks  # the printed header: a UTC clock time


def test_a_wide_sheet_note_is_printed_whole(tmp_path):
    """A note under a table wider than a page is cut into lines that fit the first page beside the columns
    every page repeats (one cell in column A ran across the page edge: "ADS-B is the r")."""
    import openpyxl

    from msdc.pipeline.quality.accuracy import LIMITATION_NOTE
    from msdc.pipeline.report.cells import PAGE_WIDTH_CHARS
    from msdc.pipeline.report.excel import write_tables

    frame = pd.DataFrame({"radar": ["KLIA MSSR"], **{f"quantity_number_{i:02d}_m": [1.0] for i in range(24)}})
    frame.attrs["note"] = LIMITATION_NOTE
    write_tables({"Wide": frame}, tmp_path / "w.xlsx")
    ws = openpyxl.load_workbook(tmp_path / "w.xlsx")["Wide"]
    pages = ws.page_setup.fitToWidth
    assert pages in (2, 3) and ws.print_title_cols == "$A:$A"
    rows = [r for r in ws.iter_rows(min_row=3, values_only=True) if any(v is not None for v in r)]
    assert all(r[0] is None and r[1] for r in rows)  # not in the repeated column A
    assert " ".join(r[1] for r in rows) == LIMITATION_NOTE
    widths = [ws.column_dimensions[openpyxl.utils.get_column_letter(i)].width for i in range(1, 26)]
    # one printed page holds the repeated column A and a pages-th of the rest, about PAGE_WIDTH_CHARS
    room = sum(widths[1:]) / pages
    assert len(rows) > 1 and max(len(r[1]) for r in rows) <= min(room, PAGE_WIDTH_CHARS)


def _real_like_adsb_histogram() -> pd.DataFrame:
    """The real 0.23 ADS-B station's shape: 17410 and 20306 intervals in the 0.4 and 0.5 s bins, 2621 beside
    1031 near 1 s, a few hundred spread to 30 s (99 % end by 1.2 s here, worked out by hand below)."""
    from msdc.pipeline.quality.tables import histogram_edges_s

    edges = histogram_edges_s(180.0)
    counts = np.zeros(len(edges) - 1, np.int64)
    at = {0.4: 17410, 0.5: 20306, 0.3: 2400, 0.9: 1031, 1.0: 2621, 1.1: 600, 2.0: 146, 5.0: 198, 20.0: 26}
    for start, n in at.items():
        counts[np.flatnonzero(np.isclose(edges[:-1], start))] = n
    return pd.DataFrame({"sensor": "adsb", "sac": 0, "sic": 107, "bin_start_s": edges[:-1],
                         "bin_end_s": edges[1:], "intervals": counts})


def test_interval_figure_shows_the_bulk_wide_and_the_tail_on_log_axes():
    from msdc.pipeline.report.quality_figures import interval_histogram

    hist = _real_like_adsb_histogram()
    # 44738 intervals; 99 % = 44290.6: the bins 0.3-1.2 s hold 44368, so the bulk panel ends at 1.2 s and
    # 146 + 198 + 26 = 370 are longer
    fig = interval_histogram(hist)
    bulk, every = fig.axes[0], fig.axes[1]
    assert bulk.get_xlim()[1] < 1.6 and every.get_xscale() == every.get_yscale() == "log"
    assert every.get_xlim()[1] >= 30.0  # the 20-30 s bin is shown
    renderer = fig.canvas.get_renderer()
    width_px = bulk.get_window_extent(renderer).width
    assert 0.1 / np.diff(bulk.get_xlim())[0] * width_px > 20  # a 0.1 s bar is tens of pixels, not one
    assert "370 longer than 1.2 s" in bulk.get_title()


def test_the_log_log_panel_draws_intervals_per_second_of_interval():
    """Bins 0.1 s wide near the bulk, 10 s wide from 20 s: on the log-log panel a bar is as high as its
    count per second of its width (17410 in 0.4-0.5 s: 174,100 per s; 26 in 20-30 s: 2.6 per s), so the
    26 long intervals are not drawn 100 times higher than they would be in 0.1 s bins; its label still
    gives the count."""
    from msdc.pipeline.report.quality_figures import interval_histogram

    fig = interval_histogram(_real_like_adsb_histogram())
    every = fig.axes[1]
    bars = {round(p.get_x(), 6): p for p in every.patches}
    assert bars[0.4].get_height() == pytest.approx(174_100.0) and bars[0.4].get_width() == pytest.approx(0.1)
    assert bars[20.0].get_height() == pytest.approx(2.6) and bars[20.0].get_width() == pytest.approx(10.0)
    assert every.get_ylim()[0] < 2.6 and "per s" in every.get_ylabel()
    assert "26" in {t.get_text() for t in every.texts}


def test_interval_labels_sit_on_no_other_bar():
    """17410 beside 20306 was drawn over the taller bar; 2621 over 1031: a visible label overlaps no other
    visible label and no bar but its own (checked on the canvas, with the bars' own extents)."""
    from msdc.pipeline.report.quality_figures import interval_histogram

    fig = interval_histogram(_real_like_adsb_histogram())
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        bars = [p for p in ax.patches if p.get_height() > 0]
        labels = [t for t in ax.texts if t.get_visible() and t.get_text()]
        assert labels
        boxes = [t.get_window_extent(renderer) for t in labels]
        assert all(not a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:])
        for text, box in zip(labels, boxes, strict=True):
            middle = (box.x0 + box.x1) / 2  # bar_label centres a label over its bar
            own = [b for b in bars if b.get_window_extent(renderer).x0 <= middle
                   <= b.get_window_extent(renderer).x1]
            others = [b for b in bars if b not in own]
            assert not any(box.overlaps(b.get_window_extent(renderer)) for b in others), text.get_text()
        assert "20306" in {t.get_text() for t in labels}


def test_radar_error_legend_covers_no_panel(tmp_path, monkeypatch):
    from msdc.pipeline.quality.accuracy import estimate_biases
    from msdc.pipeline.report import quality_figures

    errors = pd.DataFrame({"radar": "R", "sac": 1, "sic": 2, "callsign": [f"AC{i % 6}" for i in range(600)],
                           "address": None, "time_of_day": np.arange(600.0) * 5,
                           "slant_range_m": np.linspace(20e3, 300e3, 600), "range_rate_ms": 0.0,
                           "tangential_speed_ms": 0.0, "adsb_nacp": 9,
                           "range_error_m": np.sin(np.arange(600)) * 100, "azimuth_error_deg": 0.0})
    errors["ground_range_m"] = errors["slant_range_m"] * 0.99
    captured = {}
    monkeypatch.setattr(quality_figures, "save_png", lambda fig, path: captured.setdefault("fig", fig))
    quality_figures.radar_error_figure(errors, tmp_path / "e.png", estimate_biases(errors))
    fig = captured["fig"]
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    assert not any(ax.get_legend() for ax in fig.axes) and len(fig.legends) == 1
    legend = fig.legends[0].get_window_extent(renderer)
    assert not any(legend.overlaps(ax.get_window_extent(renderer)) for ax in fig.axes)


def test_an_aircraft_whose_every_report_repeats_another_is_counted_not_fatal(sim):
    """One ADS-B report relayed by a second ground station with its address damaged: the job marks it a
    repeat (ADS-B is one source whatever the station), so its aircraft, and that station, keep no report
    past de-duplication. quality_tables raised IndexError; the rows count it, with no times."""
    from msdc.pipeline.model.marks import mark_once

    sensors = pd.DataFrame([asdict(sim.scenario.radar)])[SENSOR_COLUMNS]
    relayed = sim.adsb.iloc[[100]].assign(address="ABCDEF", callsign="DAMAGED",
                                           sic=int(sim.adsb["sic"].max()) + 1)
    meas = mark_once(build_measurements(sim.radar, pd.concat([sim.adsb, relayed], ignore_index=True),
                                        sensors, date=DAY0.date()))
    q = quality_tables(meas)["Quality"]
    from msdc.pipeline.model.dedup import repeated_aircraft

    assert "every report of ABCDEF (1 report) repeats" in repeated_aircraft(meas, meas["duplicate"])[0]
    station = q[(q["sensor"] == "adsb") & (q["sic"] == relayed["sic"].iloc[0])]
    for callsign in ("DAMAGED", "(all)"):
        row = station[station["callsign"] == callsign].iloc[0]
        assert (row["reports"], row["duplicates_removed"], row["reports_after_dedup"]) == (1, 1, 0)
        assert np.isnan(row["first_tod"]) and pd.isna(row["first_utc"]) and row["intervals"] == 0
    # the first copy is kept: the first station's rows are those of the recording without the relay
    before = quality_tables(mark_once(build_measurements(sim.radar, sim.adsb, sensors, date=DAY0.date())))
    pd.testing.assert_frame_equal(q[q["sic"] != relayed["sic"].iloc[0]].reset_index(drop=True),
                                  before["Quality"])


def test_slotting_figure_of_an_aircraft_without_identity_says_why_it_draws_no_report(frames):
    """--pairs radar-radar --quality on a radar hour: a window of an aircraft with neither call sign nor
    address (a Mode A/C target) raised KeyError 'time_of_day' (a traceback from msdc correlate)."""
    from msdc.pipeline.report.quality_figures import slotting

    mas72 = frames[(frames["sensor_kind"] == "radar") & (frames["callsign"] == "MAS72")]
    second = mas72.assign(sensor_id="048:25/202", sic=202)
    two = pd.concat([mas72, second], ignore_index=True).assign(callsign=None, address=None)
    two = two.astype({"sensor_id": "category"})
    window = correlate(two, all_aircraft=True, pairs="radar-radar").windows[0]
    assert not window.summary["callsign"] and not window.summary["address"]  # blank: no identity
    fig = slotting(window, two, two.iloc[:0])
    said = [t.get_text() for t in fig.axes[0].texts]
    assert said and said[0].startswith("reports not drawn: the aircraft has no call sign or address")
    assert all(len(line.get_xdata()) == 0 for line in fig.axes[0].get_lines())


def test_a_95th_percentile_needs_twenty_intervals():
    """quality --from 22:02:00 --to 22:02:01 printed a 95th percentile of one interval (0.398 s, its
    median too). With 19 intervals none can lie above a 95th percentile: withheld; with 20 it is numpy's
    (19 ones and a 3: 1 + 0.05 x 2 = 1.1 s, interpolated between the 19th and 20th values)."""
    from msdc.pipeline.quality.tables import _interval_stats

    assert np.isnan(_interval_stats(np.array([0.398]))["interval_p95_s"])
    assert np.isnan(_interval_stats(np.ones(19))["interval_p95_s"])
    assert _interval_stats(np.r_[np.ones(19), 3.0])["interval_p95_s"] == pytest.approx(1.1)
    assert _interval_stats(np.array([0.398]))["interval_median_s"] == pytest.approx(0.398)
