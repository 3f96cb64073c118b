"""Audit findings on correlation: what the separation, lag and window numbers mean, checked against values
worked out by hand or with pyproj (never read back from the code under test)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from measurement_frames import meas_frame
from pyproj import Geod

from msdc.pipeline.correlate.correlation import correlate, separation_summary
from msdc.pipeline.report.headers import column_name

WGS84 = Geod(ellps="WGS84")


def _frame(kind: str, t, lat, lon, sic: int = 2) -> pd.DataFrame:
    n = len(t)
    return pd.DataFrame({
        "sensor": kind, "time_of_day": np.asarray(t, float), "latitude": np.asarray(lat, float),
        "longitude": np.asarray(lon, float), "flight_level": 350.0, "ground_speed_kt": 450.0,
        "heading_deg": 0.0, "callsign": pd.Series(["MAS72"] * n, dtype="str"),
        "address": pd.Series(["750123"] * n, dtype="str"),
        "sac": pd.array([1] * n, dtype="Int64"), "sic": pd.array([sic if kind == "radar" else 0] * n,
                                                                  dtype="Int64"),
    })


def test_separation_summary_by_hand():
    # slots 3, 4, 100, 5 m; the third slot's ADS-B position is a held one: left out of the statistics
    sep = np.array([3.0, 4.0, 100.0, 5.0])
    out = separation_summary(sep, np.zeros(4, bool), np.array([False, False, True, False]))
    assert out["sep_slots"] == 3
    assert out["sep_mean_m"] == pytest.approx(4.0) and out["sep_median_m"] == pytest.approx(4.0)
    assert out["sep_rms_m"] == pytest.approx(math.sqrt((9 + 16 + 25) / 3))
    assert out["sep_max_m"] == pytest.approx(5.0)
    assert out["sep_p95_m"] == pytest.approx(4.0 + 0.9 * 1.0)  # linear interpolation between 4 and 5
    assert out["sep_rms_all_m"] == pytest.approx(math.sqrt((9 + 16 + 10000 + 25) / 4))
    # no slot where both reported: no statistic, not a 0
    none = separation_summary(sep, np.ones(4, bool), np.zeros(4, bool))
    assert none["sep_slots"] == 0 and math.isnan(none["sep_rms_m"]) and math.isnan(none["sep_median_m"])


def test_separation_leaves_out_slots_holding_a_stale_position():
    # one report per 10 s slot at its start, flying north 0.01 deg a slot; ADS-B 0.001 deg east of the
    # radar, and silent in slots 5 and 6 (they hold slot 4's position, up to 2.2 km behind)
    t = np.arange(36000.0, 36200.0, 10.0)
    lat = 2.0 + 0.001 * (t - 36000.0)
    radar = _frame("radar", t, lat, np.full(t.size, 101.0))
    keep = ~np.isin(np.arange(t.size), [5, 6])
    adsb = _frame("adsb", t[keep], lat[keep], np.full(keep.sum(), 101.001))
    (w,) = correlate(meas_frame(pd.concat([radar, adsb], ignore_index=True), day="2019-03-01"),
                     callsign="MAS72").windows
    s = w.summary
    _, _, dist = WGS84.inv(np.full(t.size, 101.0), lat, np.full(t.size, 101.001), lat)
    assert s["slots"] == 20 and s["adsb_filled_slots"] == 2 and s["sep_slots"] == 18
    assert s["sep_rms_m"] == pytest.approx(math.sqrt(np.mean(dist[keep] ** 2)), abs=0.01)
    assert s["sep_max_m"] == pytest.approx(dist[keep].max(), abs=0.01)
    assert s["sep_median_m"] == pytest.approx(np.median(dist[keep]), abs=0.01)
    # every slot: the held slots 5 and 6 sit 0.01 and 0.02 deg behind the radar
    _, _, held = WGS84.inv([101.0, 101.0], lat[[5, 6]], [101.001, 101.001], lat[[4, 4]])
    all_slots = np.concatenate([dist[keep], held])
    assert s["sep_rms_all_m"] == pytest.approx(math.sqrt(np.mean(all_slots ** 2)), abs=0.01)
    assert s["sep_rms_all_m"] > 5 * s["sep_rms_m"]


def _two_radars_run():
    """MAS72 seen by radars 1/2 and 1/3 and ADS-B over the same 200 s, one ADS-B report 0.5 deg off (a jump:
    its windows get a note); --pairs all: three windows numbered 1, one per sensor pair."""
    t = np.arange(36000.0, 36200.0, 10.0)
    lat, lon = 2.0 + 0.001 * (t - 36000.0), np.full(t.size, 101.0)
    adsb_lon = lon.copy()
    adsb_lon[7] += 0.5
    frames = [_frame("radar", t, lat, lon, sic=2), _frame("radar", t, lat, lon + 0.0005, sic=3),
              _frame("adsb", t, lat, adsb_lon)]
    meas = meas_frame(pd.concat(frames, ignore_index=True), day="2019-03-01")
    return correlate(meas, callsign="MAS72", pairs="all")


def test_every_window_names_its_sensor_pair(tmp_path):
    from openpyxl import load_workbook

    from msdc.pipeline.report.excel import write_report
    from msdc.pipeline.report.summary import summary_table

    run = _two_radars_run()
    pairs = [(w.summary["radar_sensor"], w.summary["reference_sensor"], w.summary["window"])
             for w in run.windows]
    assert sorted(pairs) == [("048:1/2", "021:1/0", 1), ("048:1/2", "048:1/3", 1), ("048:1/3", "021:1/0", 1)]
    text = summary_table(run)
    notes = [line for line in text.splitlines() if line.startswith("Note:") and "jump" in line]
    assert [n.split(": 1 ADS-B position jump in this window")[0] for n in sorted(notes)] == [
        f"Note: MAS72 window 1 ({r} vs 021:1/0)" for r in ("048:1/2", "048:1/3")]
    write_report(run, tmp_path / "r.xlsx", tables="xlsx")
    wb = load_workbook(tmp_path / "r.xlsx")
    for sheet, per_window in (("Slots", 20), ("Correlation", 39)):
        rows = list(wb[sheet].iter_rows(values_only=True))
        head = [column_name(h) for h in rows[0]]
        body = [dict(zip(head, r, strict=True)) for r in rows[1:] if isinstance(r[0], int)]
        counts = pd.Series([(r["radar_sensor"], r["reference_sensor"]) for r in body]).value_counts()
        assert counts.to_dict() == {(r, ref): per_window for r, ref, _ in pairs}, sheet
    titles = [c.title.tx.rich.p[0].r[0].t for c in wb["Lag charts"]._charts]
    assert sorted(titles) == sorted(f"MAS72 window 1 ({r} vs {ref}), N = 20" for r, ref, _ in pairs)
    summary = list(wb["Summary"].iter_rows(values_only=True))
    header = next(i for i, r in enumerate(summary) if r[:3] == ("Aircraft", "Window", "Sensors"))
    assert sorted(r[2] for r in summary[header + 1: header + 4]) == sorted(f"{r} vs {ref}"
                                                                          for r, ref, _ in pairs)


def _weave(t):
    w = 2 * np.pi * (t - 36000.0)
    return (1.3 + 0.02 * np.sin(w / 2900.0) + 0.01 * np.sin(w / 1300.0 + 1.0),
            103.8 + 0.03 * np.cos(w / 3100.0) + 0.01 * np.sin(w / 1100.0))


def _delayed(delay_s: float, span_s: float = 200.0):
    """One window of span_s / 10 slots: ADS-B on the weave every 2 s, radar the same track delay_s late."""
    t = np.arange(36000.0, 36000.0 + span_s, 2.0)
    frames = [_frame("radar", t, *_weave(t - delay_s)), _frame("adsb", t, *_weave(t))]
    meas = meas_frame(pd.concat(frames, ignore_index=True), day="2019-03-01")
    (w,) = correlate(meas, callsign="MAS72").windows
    return w


def _scipy_pearson(w, axis: str) -> dict[int, float]:
    """Pearson of the slotted series at every lag with at least 2 pairs, by scipy on the overlap."""
    from scipy.stats import pearsonr

    x, y = w.slots[f"radar_{axis}"].to_numpy(), w.slots[f"adsb_{axis}"].to_numpy()
    n = x.size
    out = {}
    for d in range(-(n - 2), n - 1):
        xs, ys = (x[d:], y[:n - d]) if d >= 0 else (x[:n + d], y[-d:])
        out[d] = float(pearsonr(xs, ys).statistic)
    return out


def test_pearson_is_shown_only_where_ten_slots_overlap():
    # 20 slots: lags with fewer than 10 slot pairs (|lag| > 10) have no coefficient, not the +-1 of 2 pairs
    w = _delayed(30.0)
    ref = _scipy_pearson(w, "lat")
    assert abs(ref[18]) == pytest.approx(1.0)  # what a 2-pair overlap gives
    lags = w.lags.set_index("lag")["pearson_lat"]
    for d, r in ref.items():
        if abs(d) <= 10:
            assert lags[d] == pytest.approx(r, abs=1e-9), d
        else:
            assert np.isnan(lags[d]), d
    assert np.isnan(lags[19]) and np.isnan(lags[-19])
    # a 30 s delay = +3 slots, inside the search
    best = max((d for d in ref if abs(d) <= 10), key=lambda d: ref[d])
    assert w.summary["pearson_peak_lag_lat"] == best == 3
    assert w.summary["pearson_peak_at_limit_lat"] is False


def test_a_pearson_peak_at_the_search_limit_is_no_lag_estimate():
    # radar 150 s (15 slots) late in a 20-slot window: the search stops at
    # |lag| = min(20 // 2, 20 - 10) = 10, where scipy's coefficient is still the largest: flagged, no lag
    # given, and said in the note
    w = _delayed(150.0)
    ref = _scipy_pearson(w, "lat")
    assert max((d for d in ref if abs(d) <= 10), key=lambda d: ref[d]) == 10
    s = w.summary
    assert s["pearson_peak_lag_lat"] is None and s["pearson_peak_at_limit_lat"] is True
    from msdc.pipeline.report.summary import window_note

    assert "Pearson latitude" in window_note(s) and "edge of the lags searched |lag| = 10" in window_note(s)


def test_pearson_min_overlap_is_checked():
    from msdc.pipeline.correlate.correlation import pearson_by_lag

    for bad in (1, 2.5, True, "10"):
        with pytest.raises(ValueError, match="min_overlap"):
            pearson_by_lag([1.0, 2.0, 3.0], [1.0, 2.0, 4.0], bad)


def test_quality_figures_say_which_windows_they_cover(tmp_path, monkeypatch, capsys):
    """correlate --quality draws per-window figures for the first FIGURE_WINDOWS windows only: the Figures
    sheet and the terminal say so (here 1 of MAS72's 2 windows on the fixtures)."""
    from pathlib import Path

    from openpyxl import load_workbook

    from msdc.pipeline.cli import main
    from msdc.pipeline.jobs import correlate

    fix = Path(__file__).resolve().parents[3] / "fixtures"
    monkeypatch.setattr(correlate, "FIGURE_WINDOWS", 1)
    out = tmp_path / "c.xlsx"
    assert main(["correlate", str(fix / "radar.ast"), str(fix / "adsb.ast"), "--sensors",
                 str(fix / "sensors.toml"), "--callsign", "MAS72", "--quality", "-o", str(out), "--json",
                 str(tmp_path / "c.json")]) == 0
    err = capsys.readouterr().err
    # the lead carries the radar's errors in each window: the simulator's radar noise (range sigma 70 m,
    # azimuth sigma 0.08 deg: fixtures/truth.json) within 15 %, and the Radar biases sheet's fit
    import json

    lead = json.loads((tmp_path / "c.json").read_text())["summary"]
    assert len(lead["windows"]) == 2
    for w in lead["windows"]:
        assert w["quality_reports"] >= 0.9 * w["matched_reports"] > 50
        assert w["range_error_std_m"] == pytest.approx(70.0, rel=0.15)
        assert w["azimuth_error_std_deg"] == pytest.approx(0.08, rel=0.15)
    (radar,) = lead["radars"]
    biases = load_workbook(out)["Radar biases"]
    header = [column_name(c.value) for c in biases[1]]
    row = dict(zip(header, [c.value for c in biases[2]], strict=True))
    assert radar["radar_sensor"] == "048:25/201"
    assert radar["range_bias_m"] == pytest.approx(row["range_bias_m"])
    assert radar["time_bias_se_s"] == pytest.approx(row["time_bias_se_s"])
    assert "Figures: slotting and lag figures for the first 1 of 2 windows only" in err
    first = load_workbook(out)["Figures"]["A1"].value
    assert first.startswith("Slotting and lag figures for the first 1 of 2 windows only")
    drawn = [p.name for p in tmp_path.glob("c_*.png") if "_slotting_" in p.name or "_lags_" in p.name]
    assert sorted(drawn) == ["c_lags_1.png", "c_slotting_1.png"]


def _meas_one_window():
    t = np.arange(28800.0, 29000.0, 2.0)  # 08:00:00-08:03:18 UTC
    frames = [_frame("radar", t, *_weave(t)), _frame("adsb", t, *_weave(t))]
    return meas_frame(pd.concat(frames, ignore_index=True), day="2019-03-01")


def test_times_in_another_zone_are_taken_as_the_same_instants():
    meas = _meas_one_window()
    (utc,) = correlate(meas, callsign="MAS72").windows
    kl = meas.assign(time=meas["time"].dt.tz_convert("Asia/Kuala_Lumpur"))  # 16:00 local, UTC+8
    (local,) = correlate(kl, callsign="MAS72").windows
    assert utc.summary["start_tod"] == local.summary["start_tod"] == 28800.0  # 08:00:00 UTC
    assert local.summary["start"] == pd.Timestamp("2019-03-01T08:00:00", tz="UTC")
    us = meas.assign(time=meas["time"].dt.as_unit("us"))  # another resolution: the same seconds
    assert correlate(us, callsign="MAS72").windows[0].summary["end_tod"] == utc.summary["end_tod"]
    pd.testing.assert_frame_equal(local.slots, utc.slots)


def test_naive_times_and_contradicting_arguments_are_refused():
    meas = _meas_one_window()
    naive = meas.assign(time=meas["time"].dt.tz_localize(None))
    with pytest.raises(TypeError, match=r"meas: column 'time' must hold time-zone-aware UTC datetimes, got "
                                        r"naive datetimes: localise them, \.dt\.tz_localize\('UTC'\)"):
        correlate(naive, callsign="MAS72")
    with pytest.raises(TypeError, match=r"meas: column 'time' must hold time-zone-aware UTC datetimes, got "
                                        r"dtype float64"):
        correlate(meas.assign(time=1.0), callsign="MAS72")
    with pytest.raises(ValueError, match=r"all_aircraft=True .* not both \(got callsign='MAS72'\)"):
        correlate(meas, all_aircraft=True, callsign="MAS72")
    with pytest.raises(ValueError, match=r"not both \(got address='750123'\)"):
        correlate(meas, all_aircraft=True, address="750123")
    for name, value, wanted in (("slot_s", 0.0, "> 0"), ("slot_s", float("nan"), "> 0"),
                                ("gap_s", -1.0, ">= 0"), ("gap_s", float("inf"), ">= 0")):
        with pytest.raises(ValueError, match=f"{name} {value!r}: must be a finite number of seconds "
                                             f"{wanted}"):
            correlate(meas, callsign="MAS72", **{name: value})
    with pytest.raises(TypeError, match="slot_s '10': must be a number of seconds, not str"):
        correlate(meas, callsign="MAS72", slot_s="10")
    with pytest.raises(ValueError, match="pairs must be one of"):
        correlate(meas, callsign="MAS72", pairs="radar")


def test_a_run_whose_every_window_is_skipped_says_so(tmp_path, capsys):
    """--slot 3600 on MAS72 (windows of 344 s and 2771 s): nothing correlated. Exit 0 as for --all without
    overlap (the report lists the skipped windows and why), with a warning naming the cause."""
    from pathlib import Path

    from openpyxl import load_workbook

    from msdc.pipeline.cli import main

    fix = Path(__file__).resolve().parents[3] / "fixtures"
    out = tmp_path / "s.xlsx"
    assert main(["correlate", str(fix / "radar.ast"), str(fix / "adsb.ast"), "--sensors",
                 str(fix / "sensors.toml"), "--callsign", "MAS72", "--slot", "3600", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert ("warning: no window correlated, 2 skipped: every one is shorter than one slot (--slot 3600); "
            "use a shorter --slot") in captured.err
    assert "0 window(s) correlated, 2 skipped" in captured.out
    assert load_workbook(out)["Summary"]["A1"].value.startswith("Correlation summary: 0 window(s), 2 skipped")


def _visible_label_boxes(fig, ax):
    from matplotlib.text import Text

    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    shown = [t for t in ax.texts if t.get_visible() and t.get_text()]
    return shown, [Text.get_window_extent(t, renderer) for t in shown], ax.get_window_extent(renderer)


def test_map_labels_do_not_overlap_and_stay_inside():
    """Three sensor pairs of one aircraft start at one place with the same window number and time, beside a
    radar site: each text once, no two labels overlapping, all inside the axes."""
    from msdc.pipeline.report.figures import track_map

    run = _two_radars_run()
    sensors = pd.DataFrame({"name": ["Site A", "Site B"], "sac": [1, 1], "sic": [2, 3],
                            "latitude": [2.0, 2.01], "longitude": [101.0, 101.0]})
    fig = track_map(run, sensors)
    ax = fig.axes[0]
    shown, boxes, inside = _visible_label_boxes(fig, ax)
    texts = [t.get_text() for t in shown]
    assert texts.count("MAS72 #1 10:00") == 1 and {"Site A", "Site B"} <= set(texts)
    assert all(not a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1:]), texts
    assert all(inside.x0 <= b.x0 and b.x1 <= inside.x1 and inside.y0 <= b.y0 and b.y1 <= inside.y1
               for b in boxes), texts


def test_a_lag_peak_at_the_edge_keeps_its_label_inside(monkeypatch):
    from msdc.pipeline.report import figures

    w = _delayed(150.0)  # the latitude peak sits at the search limit, lag +10
    drawn = {}
    monkeypatch.setattr(figures, "save_png", lambda fig, path, *a: drawn.setdefault("fig", fig))
    figures.lag_figure(w, "unused.png")
    fig = drawn["fig"]
    ax = fig.axes[0]
    shown, boxes, inside = _visible_label_boxes(fig, ax)
    (edge,) = [(t, b) for t, b in zip(shown, boxes, strict=True) if "search limit" in t.get_text()]
    assert edge[0].get_text().startswith("+10") and inside.x0 <= edge[1].x0 and edge[1].x1 <= inside.x1


def test_summary_gives_each_note_its_own_row(tmp_path):
    """A window with a separation note and a Pearson note: two Summary rows, so no row runs far past the
    tables (LibreOffice fits the page to the widest row: the fixtures' Summary had shrunk to half size)."""
    from openpyxl import load_workbook

    from msdc.pipeline.report.excel import write_report
    from msdc.pipeline.report.summary import window_note, window_notes

    run = _two_radars_run()
    expected = [n for w in run.windows for n in window_notes(w.summary)]
    assert any("; " in (window_note(w.summary) or "").replace("; rerun", "") for w in run.windows)
    write_report(run, tmp_path / "r.xlsx", tables="xlsx")
    rows = list(load_workbook(tmp_path / "r.xlsx")["Summary"].iter_rows(values_only=True))
    start = next(i for i, r in enumerate(rows) if isinstance(r[0], str) and r[0].startswith("Notes on"))
    assert rows[start][0] == f"Notes on the thesis's measures ({len(expected)})"
    shown = [r[4] for r in rows[start + 1: start + 1 + len(expected)]]
    assert shown == expected and all(n.count("Pearson") <= 1 for n in shown)


def test_chart_titles_are_small_enough_for_one_line(tmp_path):
    """A window's chart title names its sensor pair: at 10 pt bold it stays on one line of the 12.6 cm
    chart (Excel's default 14 pt wrapped it onto three, squashing the plot)."""
    from openpyxl import load_workbook

    from msdc.pipeline.report.excel import write_report

    write_report(_two_radars_run(), tmp_path / "r.xlsx", tables="xlsx")
    wb = load_workbook(tmp_path / "r.xlsx")
    for sheet in ("Lag charts", "Slot charts"):
        for chart in wb[sheet]._charts:
            (paragraph,) = chart.title.tx.rich.p
            assert paragraph.pPr.defRPr.sz == 1000 and paragraph.pPr.defRPr.b
            assert len(paragraph.r[0].t) <= 55, paragraph.r[0].t  # ~6 pt a character: 330 pt of 357
