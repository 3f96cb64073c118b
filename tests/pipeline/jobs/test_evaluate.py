"""msdc evaluate end to end on a recording written from the radar-effects simulator (a radar with known Pd,
code garble and error rates, false and split plots, CAT034 north markers) and its ADS-B: every injected rate
lies inside the scorecard's 95 % interval, verdicts follow the intervals, and bad options are refused
before anything is written."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fixtures.radar_effects import RadarEffects, expected_rates, simulate_effects
from msdc.asterix.encode import encode_frame
from msdc.pipeline.cli import main
from msdc.pipeline.jobs.evaluate import EvaluateOptions, evaluate_job, validate
from msdc.pipeline.jobs.options import OptionError

INJECTED = RadarEffects(pd=0.9, full_range_nm=140.0, max_range_nm=180.0, cone_elevation_deg=40.0,
                        mode3a_garble=0.03, mode3a_error=0.01, modec_garble=0.02, modec_error=0.015,
                        false_per_scan=2.0, split=0.03)
# one worker runs the module: the recording, its evaluation and the windows' are made once (split between
# the workers, each made them, and again whenever a worker came back to the module)
pytestmark = pytest.mark.xdist_group("evaluate_windows")
RADAR_ID = "048:25/201"
DATE = "2020-01-01"  # the simulator's recordings carry no date


def _requirement(ident: str, threshold: float, direction: str, params: dict) -> str:
    lines = ["[[requirement]]", f'id = "{ident}"', f"threshold = {threshold!r}", f'direction = "{direction}"',
             'stated = "test"', 'clause = "test clause"', "checked = true", 'source = "test"']
    if params:
        lines.append("parameters = { " + ", ".join(f"{k} = {v!r}" for k, v in params.items()) + " }")
    return "\n".join(lines) + "\n"


def _preset(sim) -> str:
    """Every simulated rate as a requirement whose threshold its truth clearly meets, and pd twice more:
    against a threshold far below the truth (pass) and far above it (fail)."""
    text = ('[preset]\nname = "test-radar"\ntitle = "test"\nstandard = "none"\nsensor_types = ["ssr"]\n'
            'source = "hand"\n\n')
    for ident, (truth, params) in expected_rates(sim.effects, sim.scan_period_s).items():
        if ident == "pd":
            continue
        if ident == "false_reports_per_scan":
            text += _requirement(ident, 100.0, "<=", params)
        else:
            text += _requirement(ident, 0.0 if truth > 0.5 else 1.0, ">=" if truth > 0.5 else "<=", params)
    text += _requirement("pd", 0.5, ">=", {}) + _requirement("pd", 0.99, ">=", {"scope": "global"})
    text += _requirement("false_reports", 0.9, "<=", {"distance_m": 2100.0})
    return text


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> tuple[object, Path]:
    sim = simulate_effects(effects=INJECTED, seed=2028)
    out = tmp_path_factory.mktemp("effects")
    (out / "radar.ast").write_bytes(encode_frame(48, sim.radar) + encode_frame(34, sim.north_markers))
    (out / "adsb.ast").write_bytes(encode_frame(21, sim.sim.adsb))
    (out / "sensors.toml").write_text(sim.sensors_toml(coverage=True))
    (out / "preset.toml").write_text(_preset(sim))
    return sim, out


def _options(folder: Path, **kw) -> EvaluateOptions:
    given = {"inputs": (str(folder / "radar.ast"), str(folder / "adsb.ast")),
             "sensors": str(folder / "sensors.toml"), "preset": str(folder / "preset.toml"),
             "date": pd.Timestamp(DATE).date()}
    return EvaluateOptions(**{**given, **kw})


@pytest.fixture(scope="module")
def evaluated(recording, every_kernel_compiled):
    sim, folder = recording
    return sim, evaluate_job(_options(folder))


def test_every_injected_rate_is_inside_its_interval(evaluated):
    sim, result = evaluated
    card = result.scorecard.set_index(["sensor", "sector", "requirement", "threshold"])
    truth = expected_rates(sim.effects, sim.scan_period_s)
    assert set(result.scorecard["sensor"]) == {RADAR_ID}  # ADS-B is not of the preset's types
    for ident, (value, _) in truth.items():
        threshold = 0.5 if ident == "pd" else 100.0 if ident == "false_reports_per_scan" else \
            0.0 if value > 0.5 else 1.0
        row = card.loc[(RADAR_ID, "global", ident, threshold)]
        assert row["ci_low"] <= value <= row["ci_high"], (ident, value, row.to_dict())
        assert row["n"] > 500, ident


def test_the_scan_period_comes_from_the_north_markers_and_coverage_from_the_sensor_file(evaluated):
    sim, result = evaluated
    pd_row = result.scorecard[(result.scorecard["requirement"] == "pd")].iloc[0]
    assert f"scan period {sim.scan_period_s:.4g} s from" in pd_row["notes"]
    assert "max_range_nm 140" in pd_row["notes"] and "max_elevation_deg 40" in pd_row["notes"]


def test_false_plots_are_counted_as_the_truth_has_them(evaluated):
    sim, result = evaluated
    row = result.scorecard[result.scorecard["requirement"] == "false_reports"].iloc[0]
    false_plots = int((sim.plots["kind"] == "false").sum())
    assert round(row["value"] * row["n"]) == false_plots
    assert row["n"] == len(sim.radar)  # every plot is a trial


def test_the_verdict_follows_the_interval(evaluated):
    _, result = evaluated
    card = result.scorecard[result.scorecard["sector"] == "global"]
    pd_rows = card[card["requirement"] == "pd"].set_index("threshold")
    assert pd_rows.loc[0.5, "verdict"] == "pass" and pd_rows.loc[0.99, "verdict"] == "fail"
    assert (card["verdict"] != "fail").sum() == len(card) - 1


def test_the_surface_target_has_rows_of_its_own(evaluated):
    """The simulated surface target (1.3 NM from the site, under 50 kt) is judged apart: its updates are the
    surface rows', every other aircraft's the airborne rows', together the global row's."""
    sim, result = evaluated
    card = result.scorecard
    pd_rows = card[(card["requirement"] == "pd") & (card["threshold"] == 0.5)].set_index("sector")
    assert set(pd_rows.index) == {"global", "surface", "airborne"}
    assert pd_rows.loc["surface", "n"] + pd_rows.loc["airborne", "n"] == pd_rows.loc["global", "n"]
    per = result.tables["Per aircraft"].set_index("aircraft")
    surface = per[per["surface_share"] > 0.5]
    assert len(surface) == 1
    (label,) = surface.index
    expected_surface = int(surface.loc[label, "expected_updates"])
    assert pd_rows.loc["surface", "n"] == expected_surface


def test_per_aircraft_and_per_band_tables(evaluated):
    sim, result = evaluated
    per = result.tables["Per aircraft"]
    # every simulated aircraft the radar saw is a row, with its plots counted
    seen = sim.plots[(sim.plots["row"] >= 0) & (sim.plots["kind"] != "false")]
    assert len(per) == seen["aircraft"].nunique()
    assert per["reports"].sum() == len(seen)
    band = result.tables["PD per range band"]
    inside = band[band["range_to_nm"] <= INJECTED.full_range_nm]
    total = inside["detected"].sum() / inside["expected"].sum()
    assert abs(total - INJECTED.pd) < 0.03


def test_coverage_from_the_scorecards_association_equals_associating_again(recording, monkeypatch):
    """The coverage bands and grids take the scorecard's associated reports when the association they need
    is the same (no field monitor, the preset's gate): the figures of associating the reports afresh."""
    import msdc.pipeline.jobs.evaluate as job
    from msdc.pipeline.evaluate import reference as ref_module

    _, folder = recording
    coverage, pairs = job._coverage, []
    calls = {"associate": 0}
    associate = ref_module.associate

    def counted(*args, **kwargs):
        calls["associate"] += 1
        return associate(*args, **kwargs)

    def both(reports, reference, sensor, preset, linked=None):
        before = calls["associate"]
        reused = coverage(reports, reference, sensor, preset, linked)
        pairs.append((reused, coverage(reports, reference, sensor, preset), calls["associate"] - before))
        return reused

    monkeypatch.setattr(ref_module, "associate", counted)
    monkeypatch.setattr(job, "_coverage", both)
    evaluate_job(_options(folder, test_sensors=(RADAR_ID,)))
    (reused, fresh, associations), = pairs
    assert associations == 1  # the fresh one only
    for name, band in fresh[0].items():
        pd.testing.assert_frame_equal(reused[0][name], band)
    assert fresh[0] and fresh[1] is not None and fresh[2] is not None
    for a, b in zip(reused[1:], fresh[1:], strict=True):
        pd.testing.assert_frame_equal(a, b)


def test_the_cli_writes_the_three_outputs(recording, tmp_path):
    sim, folder = recording
    out = tmp_path / "out"
    out.mkdir()
    args = [str(folder / "radar.ast"), str(folder / "adsb.ast"), "--sensors", str(folder / "sensors.toml"),
            "--preset", str(folder / "preset.toml"), "--date", DATE, "-o", str(out / "e.xlsx"),
            "--json", str(out / "e.json"), "--html", str(out / "e.html")]
    assert main(["evaluate", *args]) == 0
    doc = json.loads((out / "e.json").read_text())
    assert {r["requirement"] for r in doc["results"]} >= {"pd", "mode3a_valid", "split_reports"}
    assert "Per aircraft" in doc["tables"] and "map_points" not in doc  # the map is the HTML's
    assert "PD range x azimuth" in doc["tables"]
    assert not [t for t, rows in doc["tables"].items() if rows and "index" in rows[0]]  # no row labels
    assert (out / "e.xlsx").stat().st_size > 0 and "<table" in (out / "e.html").read_text()
    # every output says what it was made from and how: the inputs' SHA-256, the preset, the reference
    import hashlib
    import html

    import openpyxl

    digests = [hashlib.sha256((folder / n).read_bytes()).hexdigest() for n in ("radar.ast", "adsb.ast")]
    assert [i["sha256"] for i in doc["inputs"]] == digests
    assert [i["records"] for i in doc["inputs"]] == [{"34": len(sim.north_markers), "48": len(sim.radar)},
                                                     {"21": len(sim.sim.adsb)}]
    params = doc["parameters"]
    assert (params["preset"], params["reference"]) == ("test-radar", "leave-one-out")
    assert params["date"] == DATE and params["software"].startswith("msdc ")
    ws = openpyxl.load_workbook(out / "e.xlsx", read_only=True)["Parameters"]
    listed = [r for r in ws.iter_rows(values_only=True) if len(r) >= 3]
    rows = {(r[0], r[1]): r[2] for r in listed}
    assert rows[("input 1", "sha256")] == digests[0] and rows[("parameters", "preset")] == "test-radar"
    # the run's notes a row each, as the JSON lists them (not one cell of JSON text)
    assert params["notes"] and [r[2] for r in listed if r[:2] == ("parameters", "notes")] == params["notes"]
    page = (out / "e.html").read_text()
    assert '>Run</h2>' in page and all(d in page for d in digests)
    assert all(f"<td>{html.escape(note)}</td>" in page for note in params["notes"])


@pytest.mark.parametrize(("change", "message"), [
    ({"preset": "eurocontrol-1997"}, "--preset: unknown preset 'eurocontrol-1997' (did you mean "
                                     "'eurocontrol-1997-ssr'?)"),
    ({"output": "e.csv"}, "-o"),
    ({"reference_file": "nowhere.csv"}, "--reference-file nowhere.csv: no such file"),
    # the file was taken and --reference adsb dropped in silence
    ({"reference_file": "nowhere.csv", "reference": "adsb"},
     "--reference adsb and --reference-file nowhere.csv: give one"),
    ({"test_sensors": ("25-201",)}, "--test"),
])
def test_bad_options_are_refused_before_decoding(recording, change, message):
    _, folder = recording
    with pytest.raises(OptionError, match=None) as caught:
        validate(_options(folder, **change))
    assert message in str(caught.value)


def test_html_without_bokeh_is_refused_before_decoding(recording, tmp_path, capsys, monkeypatch):
    """Without the html extra the run decoded and evaluated, then ended in a traceback and wrote nothing;
    --html is refused first, naming the extra, and nothing is written."""
    import importlib.util

    _, folder = recording
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "bokeh" else
                        real(name, *a))
    html = tmp_path / "e.html"
    status = main(["evaluate", str(folder / "radar.ast"), "--sensors", str(folder / "sensors.toml"),
                   "--preset", str(folder / "preset.toml"), "--date", DATE, "-o", str(tmp_path / "e.xlsx"),
                   "--html", str(html)])
    assert status == 2
    assert capsys.readouterr().err.strip() == (f"msdc evaluate: --html {html}: the HTML report's map needs "
                                               "bokeh, which is not installed: pip install 'msdc[html]'")
    assert not list(tmp_path.iterdir())


def test_a_preset_for_other_sensors_is_refused_with_what_is_present(recording, tmp_path, capsys):
    _, folder = recording
    before = sorted(tmp_path.iterdir())
    status = main(["evaluate", str(folder / "radar.ast"), "--sensors", str(folder / "sensors.toml"),
                   "--preset", "ed117a", "--date", DATE, "--json", str(tmp_path / "e.json")])
    assert status == 1
    err = capsys.readouterr().err
    assert "no sensor in the inputs is of a kind the preset ed117a applies to (mlat)" in err
    assert f"{RADAR_ID} (radar)" in err
    assert sorted(tmp_path.iterdir()) == before


def test_a_radar_whose_site_is_wrong_gets_no_verdict(recording, tmp_path):
    """The sensor file puts the radar 0.5 degrees (55 km) north of its site: its plots lie far from ADS-B,
    so every row of it is inconclusive, saying why, where the right site gives passes and fails."""
    sim, folder = recording
    site = sim.declared_site
    moved = tmp_path / "moved.toml"
    moved.write_text(sim.sensors_toml().replace(f"latitude = {site.latitude!r}",
                                                f"latitude = {site.latitude + 0.5!r}"))
    assert moved.read_text() != sim.sensors_toml()
    result = evaluate_job(_options(folder, sensors=str(moved)))
    card = result.scorecard
    assert len(card) and set(card["verdict"]) == {"inconclusive"}
    assert card["notes"].str.startswith(f"no verdict: radar {RADAR_ID}: its plots lie a median").all()
    assert any("its plots lie a median" in w for w in result.warnings)


def test_a_radars_track_updates_without_a_plot_are_no_reports(recording, evaluated, tmp_path):
    """I048/020 TYP 0 ("no detection") records are the radar tracker's own updates, SIM 1 ones simulated
    plots: neither is a report. Each plot is copied a scan later (into the next scan, often a missed one),
    0.05 NM out and without codes, once as TYP 0 and once as SIM 1: the scorecard is the one without them,
    and every plot of the truth, no copy, is a trial of false_reports."""
    sim, result = evaluated
    _, original = recording
    folder = tmp_path
    later = sim.radar.assign(time_of_day=sim.radar["time_of_day"] + sim.scan_period_s,
                             rho_nm=sim.radar["rho_nm"] + 0.05, mode3a=None, flight_level=np.nan,
                             address=None, callsign=None, mode3a_v=pd.NA, mode3a_g=pd.NA,
                             flight_level_v=pd.NA, flight_level_g=pd.NA)
    tracker, simulated = later.assign(typ=0), later.assign(sim=1)
    radar = pd.concat([sim.radar.assign(sim=0), tracker, simulated]).sort_values("time_of_day", kind="stable")
    (folder / "radar.ast").write_bytes(encode_frame(48, radar.reset_index(drop=True))
                                       + encode_frame(34, sim.north_markers))
    for name in ("adsb.ast", "sensors.toml", "preset.toml"):
        (folder / name).write_bytes((original / name).read_bytes())
    again = evaluate_job(_options(folder))
    keys = ["sensor", "sector", "requirement", "threshold"]
    both = result.scorecard.merge(again.scorecard, on=keys, suffixes=("", "_again"))
    assert len(both) == len(result.scorecard) == len(again.scorecard)
    for column in ("value", "n", "ci_low", "ci_high", "verdict"):
        assert both[column].equals(both[f"{column}_again"]), column
    false_row = again.scorecard[again.scorecard["requirement"] == "false_reports"].iloc[0]
    assert false_row["n"] == len(sim.radar)
    said = [w for w in again.warnings if "left out of the measurements" in w]
    assert said == [f"radar.ast: {len(sim.radar):,} CAT048 records without a plot (I048/020 TYP 0, no "
                    f"detection: the radar tracker's own updates) and {len(sim.radar):,} CAT048 records "
                    "simulated (SIM 1) left out of the measurements: they are no plot of a real target"]
    assert said[0] in again.parameters["warnings"]  # the outputs record it (the JSON and Parameters sheet)


def test_a_fixed_7777_transponder_without_rab_is_a_field_monitor(recording, evaluated, tmp_path):
    """A transponder at 4 NM / 100 deg, Mode 3/A 7777 on each of 300 scans and RAB clear (as the real
    Barcelona hour's monitor): it gets the field monitors' rows, its 300 expected updates all detected, and
    the note names it; the traffic's global rows are the run's without it."""
    sim, result = evaluated
    _, original = recording
    scans = sim.north_markers["time_of_day"].to_numpy()[:300] + 1.0
    monitor = pd.DataFrame({"sac": 25, "sic": 201, "time_of_day": scans, "day": 0, "typ": 5, "rho_nm": 4.0,
                            "theta_deg": 100.0, "mode3a": "7777", "flight_level": 0.0, "address": "3C0FFE",
                            "callsign": None, "mode3a_v": 0, "mode3a_g": 0, "flight_level_v": 0,
                            "flight_level_g": 0})
    radar = pd.concat([sim.radar, monitor]).sort_values("time_of_day", kind="stable", ignore_index=True)
    (tmp_path / "radar.ast").write_bytes(encode_frame(48, radar) + encode_frame(34, sim.north_markers))
    for name in ("adsb.ast", "sensors.toml", "preset.toml"):
        (tmp_path / name).write_bytes((original / name).read_bytes())
    again = evaluate_job(_options(tmp_path))
    notes = again.parameters["notes"]
    assert any("3C0FFE (Mode 3/A 7777 on every report, 95 % within" in n for n in notes), notes
    card = again.scorecard
    monitor_pd = card[(card["sector"] == "field monitors") & (card["requirement"] == "pd")]
    assert len(monitor_pd) and (monitor_pd["value"] == 1.0).all()
    assert (monitor_pd["n"] >= 299).all() and (monitor_pd["n"] <= 300).all()  # the first scan may open it
    keys = ["sensor", "sector", "requirement", "threshold"]
    before = result.scorecard[result.scorecard["sector"] == "global"].set_index(keys)
    after = card[card["sector"] == "global"].set_index(keys).loc[before.index]
    assert after["n"].equals(before["n"]) and after["value"].equals(before["value"])


def test_an_unknown_test_sensor_is_refused(recording):
    _, folder = recording
    from msdc.pipeline.jobs.common import JobError

    with pytest.raises(JobError, match=r"--test 25/202: no sensor .* \(present: 021:0/1 \(adsb\), "
                                       r"048:25/201 \(radar\)\)"):
        evaluate_job(_options(folder, test_sensors=("25/202",)))


def test_leave_one_out_never_uses_the_sensor_under_test(evaluated):
    _, result = evaluated
    notes = " ".join(result.parameters["notes"])
    assert "self-reference rows" in notes  # aircraft without ADS-B fall back to the radar's own track
    rows = result.scorecard
    assert np.isfinite(rows["value"]).all()


def _square(lat: float, lon: float, half_deg: float) -> list:
    a, b, c, d = lon - half_deg, lon + half_deg, lat - half_deg, lat + half_deg
    return [[[a, c], [b, c], [b, d], [a, d], [a, c]]]


def test_sectors_cut_the_figures(recording, tmp_path):
    """A sector holding all the traffic gives the global figures exactly (as a sector and as a preset area),
    one holding none is withheld with the reason, and a flight-level band keeps fewer updates."""
    sim, folder = recording
    site = sim.declared_site
    everywhere = _square(site.latitude, site.longitude, 10.0)  # 600 NM across: all the traffic
    features = [{"type": "Feature", "properties": {"name": "all", "area": "everywhere"},
                 "geometry": {"type": "Polygon", "coordinates": everywhere}},
                {"type": "Feature", "properties": {"name": "high", "min_fl": 200},
                 "geometry": {"type": "Polygon", "coordinates": everywhere}},
                {"type": "Feature", "properties": {"name": "elsewhere"},
                 "geometry": {"type": "Polygon",
                              "coordinates": _square(-site.latitude, site.longitude - 90, 1)}}]
    sectors = tmp_path / "sectors.geojson"
    sectors.write_text(json.dumps({"type": "FeatureCollection", "features": features}))
    preset = tmp_path / "p.toml"
    preset.write_text('[preset]\nname = "sectors"\ntitle = "t"\nstandard = "none"\nsensor_types = ["ssr"]\n'
                      'source = "hand"\n\n[preset.areas]\neverywhere = "all of it"\n\n'
                      + _requirement("pd", 0.5, ">=", {}) + 'area = "everywhere"\n'
                      + _requirement("pd", 0.6, ">=", {}))
    result = evaluate_job(_options(folder, preset=str(preset), sectors=str(sectors)))
    card = result.scorecard.set_index(["sector", "threshold"])
    assert card.loc[("everywhere", 0.5), "n"] == card.loc[("global", 0.6), "n"]
    assert card.loc[("everywhere", 0.5), "value"] == card.loc[("global", 0.6), "value"]
    assert card.loc[("all", 0.6), "n"] == card.loc[("global", 0.6), "n"]
    assert 0 < card.loc[("high", 0.6), "n"] < card.loc[("global", 0.6), "n"]
    assert np.isnan(card.loc[("elsewhere", 0.6), "value"])
    assert "no expected update inside 'elsewhere'" in card.loc[("elsewhere", 0.6), "notes"]


TRACKER_NOISE_M = 50.0  # per axis: a horizontal RMS of 50 * sqrt(2) = 70.7 m


def _tracker_frame(sim, seed: int = 5) -> pd.DataFrame:
    """System tracks of every simulated aircraft every 4 s along its true path with 50 m of noise per axis;
    the first aircraft changes track number once, half way."""
    truth = sim.reference(step_s=4.0)
    rng = np.random.default_rng(seed)
    m_per_deg = 111_320.0
    lat = truth["latitude"].to_numpy() + rng.normal(0.0, TRACKER_NOISE_M, len(truth)) / m_per_deg
    lon = truth["longitude"].to_numpy() + rng.normal(0.0, TRACKER_NOISE_M, len(truth)) / (
        m_per_deg * np.cos(np.radians(truth["latitude"].to_numpy())))
    number = truth["aircraft"].to_numpy() * 10 + 1
    first = truth["aircraft"].to_numpy() == 0
    number[np.flatnonzero(first)[first.sum() // 2:]] += 1
    return pd.DataFrame({"sac": 25, "sic": 100, "time_of_day": truth["t_s"].to_numpy() % 86400.0,
                         "track_number": number, "latitude": lat, "longitude": lon,
                         "mode3a": truth["mode3a"], "address": truth["address"],
                         "callsign": truth["callsign"],
                         "flight_level": truth["altitude_ft"].to_numpy() / 100.0})


def test_a_tracker_is_judged_on_its_system_tracks(recording, tmp_path):
    """CAT062 tracks of every aircraft every 4 s: every 5 s interval holds an update (PD exactly 1), the one
    track number change is counted, and the RMS error is the tracks' 70.7 m plus the reference's own."""
    sim, folder = recording
    tracks = tmp_path / "tracks.ast"
    tracks.write_bytes(encode_frame(62, _tracker_frame(sim)))
    preset = tmp_path / "tracker.toml"
    preset.write_text('[preset]\nname = "tracks"\ntitle = "t"\nstandard = "none"\n'
                      'sensor_types = ["tracker"]\nsource = "hand"\n\n'
                      + _requirement("pd", 0.5, ">=", {"interval_s": 5.0})
                      + _requirement("track_continuity", 1.0, "<=", {})
                      + _requirement("rms_m", 1000.0, "<=", {}))
    result = evaluate_job(_options(folder, preset=str(preset),
                                   inputs=(str(folder / "radar.ast"), str(folder / "adsb.ast"), str(tracks))))
    card = result.scorecard[result.scorecard["sector"] == "global"].set_index("requirement")
    assert set(result.scorecard["sensor"]) == {"062:25/100"}
    row = card.loc["pd"]
    assert row["value"] == 1.0 and row["n"] > 500
    assert card.loc["track_continuity", "value"] * card.loc["track_continuity", "n"] == pytest.approx(1.0)
    assert 60.0 < card.loc["rms_m", "value"] < 90.0
    # error against range: the same judged reports, banded; the noise does not grow with range
    by_range = result.tables["Position error per range band"]
    assert by_range["reports"].sum() == card.loc["rms_m", "n"]
    full = by_range[by_range["reports"] >= 200]
    assert len(full) >= 3 and full["rms_m"].between(55.0, 95.0).all()


def test_a_window_keeps_the_north_markers_of_its_margin(recording):
    """With --from/--to the service messages are cut to the window's 15-minute margin, as the measurements
    are: the markers from 08:15 to 08:46 of the simulated hour for 08:30-08:31."""
    from msdc.pipeline.jobs.evaluate import within_margin
    from msdc.pipeline.model.load import Loaded
    from msdc.pipeline.model.report_selection import MarginCut, ReportSelection, parse_time

    sim, _ = recording
    day = pd.Timestamp(DATE).date()
    window = ReportSelection(start=parse_time("08:30", "--from"), end=parse_time("08:31", "--to"))
    markers = sim.north_markers
    loaded = Loaded({34: markers, 48: sim.radar}, [], date=day, cut=MarginCut(window, day))
    within_margin(loaded, (34, 62))
    tod = markers["time_of_day"].to_numpy(float)
    expected = markers[(tod >= 8.25 * 3600) & (tod <= 8.5 * 3600 + 60 + 900)]
    assert 100 < len(expected) < 0.6 * len(markers)  # 31 of the 60 minutes
    assert loaded.frames[34]["time_of_day"].tolist() == expected["time_of_day"].tolist()
    assert loaded.frames[48] is sim.radar  # the categories not named are left as they are


HALVES = (("08:00", "08:30"), ("08:30", "09:00"))


@pytest.fixture(scope="module")
def windowed(recording):
    """The simulated hour evaluated as two 30-minute windows pooled (--window 30), and each half alone
    (--from/--to), with the accuracy and bias requirements added to the preset."""
    sim, folder = recording
    preset = folder / "preset_windows.toml"
    preset.write_text(_preset(sim) + _requirement("rms_m", 1000.0, "<=", {})
                      + _requirement("p95_m", 1000.0, "<=", {}) + _requirement("max_m", 5000.0, "<=", {})
                      + _requirement("range_bias_m", 500.0, "<=", {}))
    span = evaluate_job(_options(folder, preset=str(preset), from_time="08:00", to_time="09:00",
                                 window_minutes=30.0))
    halves = [evaluate_job(_options(folder, preset=str(preset), from_time=a, to_time=b)) for a, b in HALVES]
    return span, halves


def _key(card: pd.DataFrame) -> pd.DataFrame:
    return card.set_index(["sector", "requirement", "parameters"])


def test_each_window_is_evaluated_as_its_own_from_and_to(windowed):
    span, halves = windowed
    per = span.tables["Scorecard per window"]
    for (a, b), half in zip(HALVES, halves, strict=True):
        rows = per[(per["window_from"] == a) & (per["window_to"] == b)].drop(columns=["window_from",
                                                                                      "window_to"])
        pd.testing.assert_frame_equal(rows.reset_index(drop=True), half.scorecard.reset_index(drop=True))
    assert span.parameters["windows"] == [{"from": a, "to": b, "kept": h.loaded.selection["kept"]}
                                          for (a, b), h in zip(HALVES, halves, strict=True)]
    from msdc.pipeline.model.report_selection import describe

    kept = sum(h.loaded.selection["kept"] for h in halves)
    assert describe(span.loaded.selection).startswith(f"selection --from 08:00 --to 09:00: {kept} of ")
    assert describe(span.loaded.selection).endswith(", read over 2 windows, each with its margin")
    # a note both windows gave is said as each window's
    assert "every window: not judged by test-radar: 021:0/1 (adsb) (they still build the reference)" \
        in span.parameters["notes"]


def test_the_span_pools_the_windows_counts_and_errors(windowed):
    """Worked out from the two halves' own outputs: successes and trials (value x n) added, the
    Clopper-Pearson interval from beta quantiles (of the effective trials where the span's note gives a
    design effect: split plots share their update's codes), the RMS from the halves' mean squares, the
    maximum the larger, a fitted bias the inverse-variance mean of the halves' (standard errors from their
    notes)."""
    import re

    from scipy import stats

    span, halves = windowed
    card = _key(span.scorecard[span.scorecard["sector"] == "global"])
    parts = [_key(h.scorecard[h.scorecard["sector"] == "global"]) for h in halves]
    effects = 0
    for key, row in card.iterrows():
        if key[1] not in ("mode3a_valid", "modec_correct", "split_reports", "pd", "false_reports"):
            continue
        n = [p.loc[key, "n"] for p in parts]
        k = [round(p.loc[key, "value"] * p.loc[key, "n"]) for p in parts]
        assert row["n"] == sum(n), key
        assert row["value"] == pytest.approx(sum(k) / sum(n)), key
        effect = re.search(r"design effect ([0-9.]+)\)", row["notes"])
        deff = float(effect.group(1)) if effect else 1.0  # printed to 3 decimals: the bound to 1e-4
        low = stats.beta.ppf(0.025, sum(k) / deff, (sum(n) - sum(k)) / deff + 1)
        assert row["ci_low"] == pytest.approx(low, abs=1e-4 if effect else 1e-9), key
        effects += bool(effect)
    assert effects == 2  # mode3a_valid and modec_correct: the test radar's split plots repeat its codes
    rms = card.xs("rms_m", level=1).iloc[0]
    halves_rms = [p.xs("rms_m", level=1).iloc[0] for p in parts]
    assert rms["n"] == sum(h["n"] for h in halves_rms)
    assert rms["value"] == pytest.approx(np.sqrt(sum(h["value"] ** 2 * h["n"] for h in halves_rms)
                                                 / rms["n"]), rel=1e-9)
    assert card.xs("max_m", level=1).iloc[0]["value"] == max(p.xs("max_m", level=1).iloc[0]["value"]
                                                             for p in parts)
    p95 = card.xs("p95_m", level=1).iloc[0]["value"]
    lo, hi = sorted(p.xs("p95_m", level=1).iloc[0]["value"] for p in parts)
    assert lo <= p95 <= hi
    bias = [p.xs("range_bias_m", level=1).iloc[0] for p in parts]
    assert all(np.isfinite(b["value"]) for b in bias), "each half fits a range bias"
    se = [float(re.search(r"standard error ([0-9.eE+-]+) m", b["notes"]).group(1)) for b in bias]
    w = 1 / np.square(se)
    pooled = card.xs("range_bias_m", level=1).iloc[0]
    assert pooled["value"] == pytest.approx(np.sum(w * [b["value"] for b in bias]) / np.sum(w), rel=2e-2)
    assert "combined by inverse variance" in pooled["notes"]


def test_the_span_is_the_hour_evaluated_at_once_but_at_the_windows_edge(windowed, evaluated):
    """The detection and code figures of the pooled halves equal those of the hour evaluated at once (the
    north markers fix the scan period; the reference is cut at 08:30 only); a gap across 08:30 is in
    neither half."""
    span, _ = windowed
    _, whole = evaluated
    card, one = _key(span.scorecard), _key(whole.scorecard)
    for req in ("pd", "mode3a_correct", "modec_correct", "split_reports"):
        for key in [k for k in one.index if k[1] == req and k[0] == "global"]:
            assert card.loc[key, "n"] == pytest.approx(one.loc[key, "n"], rel=0.01), key
            assert card.loc[key, "value"] == pytest.approx(one.loc[key, "value"], abs=0.01), key
    gaps = [k for k in one.index if k[1] == "long_gaps" and k[0] == "global"]
    assert gaps and all(card.loc[k, "n"] <= one.loc[k, "n"] for k in gaps)
    per = span.tables["Per aircraft"]
    assert per["reports"].sum() == whole.tables["Per aircraft"]["reports"].sum()
    assert set(per["windows"]) <= {1, 2} and (per["windows"] == 2).any()


@pytest.mark.parametrize(("change", "message"), [
    ({"window_minutes": 30.0}, "--window 30: cuts the span --from ... --to ... into windows; give both"),
    ({"window_minutes": 30.0, "from_time": "08:00", "to_time": "2020-01-01T09:00"},
     "must both be date-times or both times of day"),
    ({"window_minutes": 0.5, "from_time": "08:00", "to_time": "09:00"}, "--window"),
    ({"window_minutes": 1.0, "from_time": "2020-01-01", "to_time": "2020-12-01"}, "more than 100,000"),
])
def test_window_options_are_checked_before_decoding(recording, change, message):
    _, folder = recording
    with pytest.raises(OptionError) as caught:
        validate(_options(folder, **change))
    assert message in str(caught.value)


def test_every_column_of_the_evaluation_tables_has_a_workbook_header(windowed):
    """The tables a windowed run writes (every table of a run, and those per window): no column would
    print its snake_case name in the workbook."""
    from msdc.pipeline.report.headers import has_header

    span, _ = windowed
    assert len(span.tables) >= 10
    assert sorted({c for t in span.tables.values() for c in t.columns if not has_header(c)}) == []


def test_a_windowed_runs_outputs_hold_the_windows(windowed, tmp_path):
    """The workbook and the JSON hold every row per window; the HTML report the global ones."""
    import openpyxl

    from msdc.pipeline.jobs.evaluate import write_evaluation

    span, _ = windowed
    checked = replace(span.checked, output=tmp_path / "w.xlsx", json=tmp_path / "w.json",
                      html=tmp_path / "w.html")
    write_evaluation(replace(span, checked=checked))
    doc = json.loads((tmp_path / "w.json").read_text())
    per = span.tables["Scorecard per window"]
    assert len(doc["tables"]["Scorecard per window"]) == len(per) > 0
    assert doc["parameters"]["windows"][1]["from"] == "08:30"
    sheet = openpyxl.load_workbook(tmp_path / "w.xlsx")["Scorecard per window"]
    rows = [row for row in sheet.iter_rows() if row[1].value is not None]  # the notes below: column A only
    assert len(rows) == len(per) + 1  # with the header row
    head = [c.value for c in rows[0]]
    assert head[:5] == ["Window from", "Window to", "Sensor", "Sector", "Requirement"]
    # written as the scorecard is: a PD row's figures as percentages, "yes"/"no", the verdict coloured
    value, checked, verdict = (head.index(h) for h in ("Value", "Threshold checked against the standard",
                                                       "Verdict"))
    pd_rows = [r for r in rows[1:] if r[head.index("Requirement")].value == "pd"]
    assert pd_rows and all(r[value].number_format == "0.00%" for r in pd_rows)
    assert {r[checked].value for r in rows[1:]} <= {"yes", "no"}
    assert all(r[verdict].fill.fgColor.rgb.endswith(("C6EFCE", "FFC7CE", "FFEB9C")) for r in rows[1:])
    page = (tmp_path / "w.html").read_text()
    shown = re.split(r"<h2[^>]*>Scorecard per window, global rows", page)[1].split("</table>")[0]
    assert shown.count("<tr>") == (per["sector"] == "global").sum() + 1  # with the header row
    assert (per["sector"] != "global").any()


def test_windows_without_reports_are_named_and_the_others_pooled(recording, windowed):
    """07:00-08:30 in 30-minute windows: the recording starts at 08:00, so the first two windows hold no
    report and are named in the notes; the span's figures are the third window's, which is the first half
    evaluated alone. A span with no report in any window is refused, naming its windows."""
    from msdc.pipeline.jobs.common import JobError

    _, folder = recording
    span, halves = windowed
    preset = str(folder / "preset_windows.toml")
    late = evaluate_job(_options(folder, preset=preset, from_time="07:00", to_time="08:30",
                                 window_minutes=30.0))
    notes = late.parameters["notes"]
    refused = [n for n in notes if n.startswith("window ")]
    assert [n.split(": ")[0] for n in refused] == ["window 07:00 to 07:30", "window 07:30 to 08:00"]
    assert all("0 of" in n and n.endswith("no report is left to analyse") for n in refused)
    assert [w["from"] for w in late.parameters["windows"]] == ["08:00"]
    cols = ["sensor", "sector", "requirement", "value", "ci_low", "ci_high", "n", "verdict"]
    pd.testing.assert_frame_equal(late.scorecard[cols], halves[0].scorecard[cols])
    with pytest.raises(JobError, match=r"--window 30: no window of the span gave an evaluation \(window "
                                       r"06:00 to 06:30: selection .* no report is left to analyse; window "
                                       r"06:30 to 07:00: "):
        evaluate_job(_options(folder, preset=preset, from_time="06:00", to_time="07:00", window_minutes=30.0))


def test_the_spans_errors_per_range_band_pool_the_windows(windowed):
    """Per sensor and band, from the halves' own tables: the reports added, the RMS from their mean squares,
    the maximum the larger, the aircraft at least the most of either and at most both; the 95th percentile
    at least the lower half's and at most the larger maximum. Every band of a half is in the span's."""
    span, halves = windowed
    title = "Position error per range band"
    whole = span.tables[title].set_index(["sensor", "range_from_nm"])
    parts = [h.tables[title].set_index(["sensor", "range_from_nm"]) for h in halves]
    assert len(whole) > 3 and set().union(*(p.index for p in parts)) == set(whole.index)
    for key, row in whole.iterrows():
        given = [p.loc[key] for p in parts if key in p.index]
        assert row["reports"] == sum(g["reports"] for g in given), key
        assert row["rms_m"] == pytest.approx(np.sqrt(sum(g["rms_m"] ** 2 * g["reports"] for g in given)
                                                     / row["reports"]), rel=1e-9), key
        assert row["max_m"] == max(g["max_m"] for g in given), key
        assert max(g["aircraft"] for g in given) <= row["aircraft"] <= sum(g["aircraft"] for g in given)
        assert min(g["p95_m"] for g in given) <= row["p95_m"] <= row["max_m"], key


@pytest.fixture(scope="module")
def span_watched(recording, tmp_path_factory):
    """08:00 to 08:20 in 10-minute windows, with the p95 and maximum requirements added to the preset,
    evaluated once with the system's temporary folder moved to a folder of its own and the files under it
    listed when the pooling starts: the options, the run, the files seen (per folder) and that folder."""
    import tempfile

    import msdc.pipeline.jobs.evaluate as job

    sim, folder = recording
    preset = tmp_path_factory.mktemp("span") / "preset.toml"
    preset.write_text(_preset(sim) + _requirement("p95_m", 1000.0, "<=", {})
                      + _requirement("max_m", 5000.0, "<=", {}))
    temporary = tmp_path_factory.mktemp("tmp")
    seen: list[dict[str, list[str]]] = []
    pooled = job._pooled_sensor

    def watching(checked, sensor_id, span):
        files: dict[str, list[str]] = {}
        for p in sorted(temporary.glob("msdc-evaluate-*/sensor-*/*/*.parquet")):
            files.setdefault(p.parent.name, []).append(p.name)
        seen.append(files)
        return pooled(checked, sensor_id, span)

    options = _options(folder, preset=str(preset), from_time="08:00", to_time="08:20", window_minutes=10.0)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(tempfile, "tempdir", str(temporary))
        mp.setattr(job, "_pooled_sensor", watching)
        run = evaluate_job(options)
    return options, run, seen, temporary


def test_a_span_keeps_its_error_values_in_a_temporary_folder_it_removes(span_watched, tmp_path, monkeypatch):
    """The windows' judged errors by range and the values of a percentile or maximum wait for the pooling in
    files under the system's temporary folder (one a window, per sensor and requirement), which is gone
    after the run, and after a run that fails while pooling."""
    import tempfile

    import msdc.pipeline.jobs.evaluate as job

    options, run, seen, temporary = span_watched
    assert run.scorecard["sensor"].nunique() == 1
    two = ["0000000.parquet", "0000001.parquet"]  # two windows
    assert seen[0]["errors-by-range"] == two
    # the 95th percentile's values (a maximum keeps its largest only): global in both windows, surface and
    # airborne in the second only (the first has no aircraft on the surface: its airborne is its global)
    per = run.tables["Scorecard per window"]
    p95 = per[per["requirement"] == "p95_m"]
    assert sorted(p95[p95["window_from"] == "08:00"]["sector"]) == ["global"]
    assert sorted(p95[p95["window_from"] == "08:10"]["sector"]) == ["airborne", "global", "surface"]
    files = sorted(v for k, v in seen[0].items() if k.startswith("values-"))
    assert files == [["0000000.parquet"]] * 2 + [two]
    assert list(temporary.iterdir()) == []

    def failing(*_):
        raise RuntimeError("pooling failed")

    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    monkeypatch.setattr(job, "_pooled_sensor", failing)
    with pytest.raises(RuntimeError, match="pooling failed"):
        evaluate_job(options)
    assert list(temporary.iterdir()) == []


def test_a_span_pooled_from_disk_in_passes_gives_the_figures_of_its_values_read_back(span_watched,
                                                                                    monkeypatch):
    """A span's percentile, its interval and the error bands pooled in passes over the files (as when they
    hold more values than the span reads at once: here with that limit 0) are those of the values read back
    together, each figure; the bands' RMS to within the order of summation."""
    from msdc.pipeline.evaluate import windows

    options, together, _, _ = span_watched  # the values read back together
    monkeypatch.setattr(windows, "VALUES_HELD", 0)
    called: list[str] = []

    def spied(name):
        original = getattr(windows, name)

        def spy(*args, **kw):
            called.append(name)
            return original(*args, **kw)
        return spy

    for name in ("streamed_interval", "streamed_error_bands"):
        monkeypatch.setattr(windows, name, spied(name))
    passes = evaluate_job(options)
    assert called.count("streamed_error_bands") == 1 and called.count("streamed_interval") >= 1
    columns = ["sensor", "sector", "requirement", "value", "ci_low", "ci_high", "n", "verdict"]
    pd.testing.assert_frame_equal(passes.scorecard[columns], together.scorecard[columns], check_exact=True)
    p95 = together.scorecard[together.scorecard["requirement"] == "p95_m"]
    assert p95.set_index("sector").loc["global", ["ci_low", "ci_high"]].notna().all()
    title = "Position error per range band"
    a, b = passes.tables[title], together.tables[title]
    pd.testing.assert_frame_equal(a.drop(columns="rms_m"), b.drop(columns="rms_m"), check_exact=True)
    assert np.allclose(a["rms_m"], b["rms_m"], rtol=1e-13, atol=0.0) and len(a) > 3


def test_per_aircraft_rms_error_is_that_of_its_reports_errors():
    """The per-aircraft table's RMS position error, by hand: a reference aircraft standing at 50 N 4 E and
    two reports 30 m and 40 m north of it give sqrt((30^2 + 40^2) / 2) = 35.355 m over 2 errors; the other
    aircraft, 20 NM away, has no report (no RMS, 0 reports)."""
    from msdc.pipeline.jobs.evaluate import _per_aircraft

    # metres per degree of latitude at 50 N: the WGS-84 meridian radius of curvature a (1 - e2) / (1 - e2
    # sin^2)^1.5 = 6,373,784 m, so 111,244 m a degree
    a, e2 = 6378137.0, 0.00669437999014
    m_per_deg = np.radians(1.0) * a * (1 - e2) / (1 - e2 * np.sin(np.radians(50.0)) ** 2) ** 1.5
    t = np.arange(0.0, 101.0, 10.0)
    reference = pd.DataFrame({"aircraft": ["A"] * 11 + ["B"] * 11, "t_s": np.r_[t, t],
                              "latitude": np.r_[np.full(11, 50.0), np.full(11, 50.0 + 20 * 1852 / m_per_deg)],
                              "longitude": 4.0, "altitude_ft": 30000.0, "built_by": "021:0/1",
                              "self_reference": False, "on_ground": False})
    reports = pd.DataFrame({"t_s": [20.0, 50.0], "latitude": 50.0 + np.array([30.0, 40.0]) / m_per_deg,
                            "longitude": 4.0, "flight_level": 300.0})
    table = _per_aircraft("048:20/1", reports, reference, None, {}).set_index("aircraft")
    assert table.loc["A", "rms_error_m"] == pytest.approx(np.sqrt((30.0**2 + 40.0**2) / 2), rel=1e-4)
    assert table.loc["A", "errors_judged"] == 2 and table.loc["A", "reports"] == 2
    assert np.isnan(table.loc["B", "rms_error_m"]) and table.loc["B", "reports"] == 0


def test_a_field_monitors_surface_share_is_whole():
    """The per-aircraft table's surface share: a field monitor stands on the surface (1, not its code 2),
    an aircraft half on the surface 0.5."""
    from msdc.pipeline.jobs.evaluate import _per_aircraft

    t = np.arange(4.0)
    reference = pd.DataFrame({"aircraft": ["M"] * 4 + ["A"] * 4, "t_s": np.r_[t, t],
                              "latitude": 0.0, "longitude": np.r_[np.zeros(4), np.full(4, 0.1)],
                              "built_by": "x", "self_reference": False,
                              "on_ground": [True] * 4 + [True, True, False, False],
                              "field_monitor": [True] * 4 + [False] * 4})
    reports = pd.DataFrame({"t_s": [1.0], "latitude": [0.0], "longitude": [0.0]})
    table = _per_aircraft("R", reports, reference, None, {}).set_index("aircraft")
    assert table.loc["M", "surface_share"] == 1.0 and table.loc["A", "surface_share"] == 0.5
