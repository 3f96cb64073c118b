"""Per-job column selection: a job builds only the measurement columns it reads (pipeline.model.schema
schema_columns / validate(frame, columns), pipeline.jobs.correlate.correlate_columns), and gets the same
results as from the whole frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from frames import assert_frame_equal

from msdc.pipeline.jobs import correlate
from msdc.pipeline.jobs import quality as quality_jobs
from msdc.pipeline.jobs.correlate import CorrelateOptions, correlate_columns
from msdc.pipeline.jobs.quality import QualityOptions, quality_columns
from msdc.pipeline.model.load import load_measurements
from msdc.pipeline.model.marks import mark_once
from msdc.pipeline.model.schema import MEASUREMENT_COLUMNS, SchemaError, column_names, validate
from msdc.pipeline.model.sensors import read_sensors
from msdc.pipeline.track.tracker import FILTER_INPUTS, REQUIRED

FIX = Path(__file__).resolve().parents[3] / "fixtures"
INPUTS = [FIX / "radar.ast", FIX / "adsb.ast"]


@pytest.fixture(scope="module")
def sensors() -> pd.DataFrame:
    return read_sensors(FIX / "sensors.toml")


def corr(**kw) -> CorrelateOptions:
    return CorrelateOptions(**({"inputs": tuple(map(str, INPUTS)), "sensors": str(FIX / "sensors.toml"),
                                "all_aircraft": True} | kw))


def test_column_names_are_checked_and_in_schema_order():
    assert column_names(["longitude", "time", "latitude"]) == ["time", "latitude", "longitude"]
    assert column_names(None) == MEASUREMENT_COLUMNS
    with pytest.raises(SchemaError, match="'speed' is not a measurement column"):
        column_names(["time", "speed"])


def test_a_narrow_frame_is_validated_on_its_own_columns(sensors):
    columns = ["time", "sensor_kind", "aircraft_id", "latitude", "longitude"]
    _, narrow = load_measurements(INPUTS, sensors, columns=columns)
    assert list(narrow.columns) == columns
    assert validate(narrow, columns) is narrow
    with pytest.raises(SchemaError, match="'sensor_id' is missing"):  # not the whole model
        validate(narrow)
    with pytest.raises(SchemaError, match="'latitude' is missing"):
        validate(narrow.drop(columns="latitude"), columns)
    with pytest.raises(SchemaError, match="'longitude' has values missing or outside"):  # still checked
        validate(narrow.assign(longitude=200.0), columns)
    with pytest.raises(SchemaError, match="'sensor_kind'.*allowed: radar, adsb"):
        validate(narrow.assign(sensor_kind=pd.Series("lidar", index=narrow.index, dtype="string")
                               .astype("category")), columns)


def test_narrow_measurements_are_the_full_ones_columns(sensors):
    """The identity rule reads address, call sign and Mode 3/A, and sigma_major_m the covariance: asked
    for alone, they come out as in the whole frame, without their inputs."""
    _, full = load_measurements(INPUTS, sensors)
    for columns in (["time", "aircraft_id", "sigma_major_m"], ["sensor_id", "rho_nm", "nacp"]):
        _, narrow = load_measurements(INPUTS, sensors, columns=columns, chunk=40_000)  # many chunks joined
        assert_frame_equal(narrow, full[columns])


@pytest.mark.parametrize("bounds", [("2024-01-01T08:40:00Z", "2024-01-01T09:00:00Z"), ("08:40", "09:00")],
                         ids=["instants", "times of day"])
def test_the_window_margin_is_the_same_in_chunks_whole_and_from_frames(sensors, bounds):
    """The rows within 15 minutes of --from/--to: cut chunk by chunk while decoding (instants), once all is
    read (times of day), or from the decoded frames (evaluate's path): the same measurements, the same
    reports cut; none beyond the margin, and the window's own rows all there."""
    from msdc.pipeline.model.load import load
    from msdc.pipeline.model.measurements import build_measurements
    from msdc.pipeline.model.report_selection import MarginCut, ReportSelection, parse_time

    day = "2024-01-01"
    window = ReportSelection(start=parse_time(bounds[0], "--from"), end=parse_time(bounds[1], "--to"))
    got = []
    for chunk in (40_000, 10**9):
        loaded, meas = load_measurements(INPUTS, sensors, date=day, chunk=chunk, selection=window)
        got.append((meas, loaded.cut.reports, loaded.cut.left_out))
    frames = load(INPUTS, date=day)
    cut = MarginCut(window, frames.date)
    meas = build_measurements(frames.frames[48], frames.frames[21], sensors, date=frames.date, cut=cut)
    got.append((meas, cut.reports, cut.left_out))
    _, whole = load_measurements(INPUTS, sensors, date=day)
    for meas, reports, left_out in got:
        assert_frame_equal(meas, got[0][0])
        assert (reports, left_out) == (got[0][1], got[0][2]) == (len(whole) - len(meas), {"time": reports})
    t = got[0][0]["time"]
    assert t.min() >= pd.Timestamp(f"{day}T08:25Z") and t.max() <= pd.Timestamp(f"{day}T09:15Z")
    lo, hi = pd.Timestamp(f"{day}T08:40Z"), pd.Timestamp(f"{day}T09:00Z")
    inside = (whole["time"] >= lo) & (whole["time"] < hi)
    assert ((t >= lo) & (t < hi)).sum() == inside.sum() > 1000


def test_correlate_columns_follow_the_options():
    plain = correlate_columns(corr())
    assert plain == column_names(plain) and "aircraft_id" in plain and "rho_nm" in plain
    assert not {"cov_ee_m2", "sigma_major_m", "nucp_nic", "nacp", "mode3a", "file"} & set(plain)
    assert {"nucp_nic", "nacp"} <= set(correlate_columns(corr(min_nic=5, min_nacp=7)))
    with_quality = set(correlate_columns(corr(quality=True)))  # what quality and its figures read too
    figures = set(correlate.SLOTTING_FIGURE_INPUTS)
    assert with_quality == set(plain) | set(quality_columns(quality())) | figures
    assert {"nacp", "mops_version", "theta_deg"} <= with_quality
    assert not {"cov_ee_m2", "sigma_major_m", "mode3a", "file"} & with_quality
    predict = set(correlate_columns(corr(fill="predict")))  # the tracker reads the covariance
    assert predict - set(plain) == {"cov_ee_m2", "cov_en_m2", "cov_nn_m2", "nucr_nacv", "flight_level"}


def _windows(run) -> list:
    return [(w.summary, w.slots, w.lags) for w in run.windows]


def _assert_same_windows(narrow, full) -> None:
    """The two runs have the same windows: summaries, slots and lags."""
    assert len(narrow.windows) == len(full.windows) > 0
    for (s_n, slots_n, lags_n), (s_f, slots_f, lags_f) in zip(_windows(narrow), _windows(full), strict=True):
        assert s_n == s_f
        assert_frame_equal(slots_n, slots_f)
        assert_frame_equal(lags_n, lags_f)


@pytest.mark.parametrize("kw", [{}, {"drop_jumps": True, "min_nic": 5, "min_nacp": 7},
                                {"pairs": "all", "split_adsb": True}, {"fill": "predict"}])
def test_correlation_on_the_narrow_frame_equals_the_full_frame(kw, monkeypatch):
    narrow = correlate.correlate_job(corr(**kw))
    assert ("cov_ee_m2" in narrow.measurements) == (kw.get("fill") == "predict")
    assert "fit_latitude" not in narrow.measurements and "mode3a" not in narrow.measurements
    monkeypatch.setattr(correlate, "correlate_columns", lambda options: None)
    full = correlate.correlate_job(corr(**kw))
    assert "cov_ee_m2" in full.measurements and "fit_latitude" in full.measurements
    _assert_same_windows(narrow.run, full.run)
    assert narrow.run.skipped == full.run.skipped and narrow.run.filters == full.run.filters
    if kw.get("drop_jumps"):
        assert narrow.run.filters["jumps"] > 0


def test_mark_once_with_the_jump_flag_alone(sensors):
    _, meas = load_measurements(INPUTS, sensors)
    full, flag = mark_once(meas), mark_once(meas, flags=["jump"])
    assert "jump" in flag and not {"jump_size_m", "fit_latitude", "fit_longitude"} & set(flag)
    assert np.array_equal(flag["jump"].to_numpy(), full["jump"].to_numpy()) and flag["jump"].any()
    assert_frame_equal(flag, full.drop(columns=["jump_size_m", "fit_latitude", "fit_longitude"]))


def quality(**kw) -> QualityOptions:
    return QualityOptions(**({"inputs": tuple(map(str, INPUTS)), "sensors": str(FIX / "sensors.toml"),
                              "all_aircraft": True} | kw))


def test_quality_columns_follow_the_reference():
    plain = quality_columns(quality())
    assert plain == column_names(plain) and {"aircraft_id", "rho_nm", "nacp", "mops_version"} <= set(plain)
    assert {"height_m", "height_source"} <= set(plain)  # the reference's geometric height, where reported
    assert not {"cov_ee_m2", "sigma_major_m", "mode3a", "track_number", "file"} & set(plain)
    track = quality_columns(quality(reference="track"))  # the tracker reads the covariance and NACv
    assert set(track) - set(plain) == {"cov_ee_m2", "cov_en_m2", "cov_nn_m2"}
    assert set(REQUIRED) | set(FILTER_INPUTS) | {"nacp"} <= set(track)
    assert not {"sigma_major_m", "mode3a", "track_number", "file"} & set(track)


@pytest.mark.parametrize("kw", [{}, {"all_aircraft": False, "callsign": "MAS72", "gap_s": 30.0},
                                {"reference": "track"}])
def test_quality_on_the_narrow_frame_equals_the_full_frame(kw, monkeypatch):
    seen = []
    measured = quality_jobs.quality_step

    def spy(meas, sensors, options, reference_meas=None):
        seen.append(set(meas.columns))
        return measured(meas, sensors, options, reference_meas)

    monkeypatch.setattr(quality_jobs, "quality_step", spy)
    narrow = quality_jobs.quality_job(quality(**kw))
    monkeypatch.setattr(quality_jobs, "quality_columns", lambda options: None)
    full = quality_jobs.quality_job(quality(**kw))
    track = kw.get("reference") == "track"
    assert ("cov_ee_m2" in seen[0]) == track and "rho_nm" in seen[0] and "mode3a" not in seen[0]
    assert "cov_ee_m2" in seen[1] and "mode3a" in seen[1]
    assert list(narrow.quality.sheets) == list(full.quality.sheets)
    for name, table in full.quality.sheets.items():
        assert_frame_equal(narrow.quality.sheets[name], table, check_exact=True)
    assert len(narrow.quality.errors) > 0 and len(narrow.quality.sheets["Jumps"]) > 0
    assert_frame_equal(narrow.quality.errors, full.quality.errors, check_exact=True)


def test_correlate_quality_on_the_narrow_frame_equals_the_full_frame(monkeypatch):
    """correlate --quality builds the columns correlate and quality read (and every jump column), not the
    whole frame: the same windows, quality sheets and radar errors."""
    narrow = correlate.correlate_job(corr(quality=True))
    assert "fit_latitude" in narrow.measurements and "nacp" in narrow.measurements
    assert "cov_ee_m2" not in narrow.measurements and "mode3a" not in narrow.measurements
    monkeypatch.setattr(correlate, "correlate_columns", lambda options: None)
    full = correlate.correlate_job(corr(quality=True))
    assert "cov_ee_m2" in full.measurements
    _assert_same_windows(narrow.run, full.run)
    assert list(narrow.quality.sheets) == list(full.quality.sheets) and "Jumps" in full.quality.sheets
    for name, table in full.quality.sheets.items():
        assert_frame_equal(narrow.quality.sheets[name], table, check_exact=True)
    assert len(narrow.quality.errors) > 0 and len(narrow.quality.sheets["Jumps"]) > 0
    assert_frame_equal(narrow.quality.errors, full.quality.errors, check_exact=True)
    assert narrow.run.extra_sheets.keys() == full.run.extra_sheets.keys()
