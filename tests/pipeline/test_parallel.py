"""Per-aircraft threads: results in order, lazily taken, errors raised; the tracker, the noise estimate and
the conflict predictions give the same numbers, bit for bit, on one thread and on two."""

from __future__ import annotations

import threading
import time
from dataclasses import asdict

import numpy as np
import pandas as pd
import pytest

import fixtures.track_e2e_data as d
import msdc.pipeline.parallel as parallel
from msdc.pipeline.conflict.predict import predict_tracks
from msdc.pipeline.parallel import map_ordered
from msdc.pipeline.track import track
from msdc.pipeline.track.noise import estimate_noise


def test_results_come_in_order_from_several_threads():
    names = set()

    def slow(i: int) -> int:
        names.add(threading.current_thread().name)
        time.sleep(0.002 * ((7 * i) % 5))  # later items often finish first
        return i * i

    assert list(map_ordered(slow, range(40), threads=4)) == [i * i for i in range(40)]
    assert len(names) > 1 and all(n.startswith("msdc") for n in names)
    assert list(map_ordered(slow, range(5), threads=1)) == [0, 1, 4, 9, 16]


def test_items_are_taken_at_most_two_per_thread_ahead():
    taken = []

    def items():
        for i in range(100):
            taken.append(i)
            yield i

    results = map_ordered(lambda i: i, items(), threads=3)
    assert next(results) == 0
    assert len(taken) <= 2 * 3 + 1


def test_an_error_in_one_item_is_raised_in_order():
    def fail_at_7(i: int) -> int:
        if i == 7:
            raise ValueError("item 7")
        return i

    got = []
    with pytest.raises(ValueError, match="item 7"):
        for r in map_ordered(fail_at_7, range(20), threads=4):
            got.append(r)
    assert got == list(range(7))


def test_work_mapped_from_a_pool_thread_stays_in_that_thread():
    def inner(i: int) -> tuple[int, int]:
        return i, threading.get_ident()

    def outer(i: int) -> tuple[int, list[tuple[int, int]]]:
        return threading.get_ident(), list(map_ordered(inner, range(3), threads=4))

    results = list(map_ordered(outer, range(6), threads=2))
    assert len(results) == 6
    for ident, rows in results:
        assert [k for k, _ in rows] == [0, 1, 2]
        assert {i for _, i in rows} == {ident}  # no pool inside the pool: the outer item's own thread


@pytest.fixture(scope="module")
def measurements(tmp_path_factory):
    return d.build(d.small_scenario(), tmp=tmp_path_factory.mktemp("par")).measurements


def test_tracker_noise_estimate_and_predictions_are_the_same_on_two_threads(measurements, monkeypatch):
    def run(n: int):
        monkeypatch.setattr(parallel, "thread_count", lambda: n)
        est = estimate_noise(measurements, sites=d.SITES)
        res = track(est.measurements, smooth=True, keep_states=True)
        return est, res, predict_tracks(res, [30.0, 90.0], step_s=5.0, sigma_alt=True)

    est1, one, pred1 = run(1)
    estn, many, predn = run(2)
    assert measurements["aircraft_id"].nunique() == 2  # both threads have an aircraft to do
    pd.testing.assert_frame_equal(est1.sensors, estn.sensors, check_exact=True)
    np.testing.assert_array_equal(est1.measurements[["cov_ee_m2", "cov_en_m2", "cov_nn_m2"]].to_numpy(),
                                  estn.measurements[["cov_ee_m2", "cov_en_m2", "cov_nn_m2"]].to_numpy())
    pd.testing.assert_frame_equal(one.tracks, many.tracks, check_exact=True)
    pd.testing.assert_frame_equal(one.sensors, many.sensors, check_exact=True)
    pd.testing.assert_frame_equal(one.rejected, many.rejected, check_exact=True)
    assert len(pred1) > 1000
    pd.testing.assert_frame_equal(pred1, predn, check_exact=True)


def test_radar_errors_against_the_track_are_the_same_on_two_threads(monkeypatch):
    from bias_fleet import FLEET

    from fixtures.scenario import Scenario
    from fixtures.simulate import simulate
    from msdc.pipeline.model.measurements import build_measurements
    from msdc.pipeline.model.sensors import REQUIRED_COLUMNS
    from msdc.pipeline.quality.accuracy import radar_errors

    sc = Scenario(name="threads", aircraft=FLEET[:4])
    sim = simulate(sc, seed=7)
    sensors = pd.DataFrame([asdict(sc.radar)])[REQUIRED_COLUMNS]
    meas = build_measurements(sim.radar, sim.adsb, sensors)
    errors = []
    for n in (1, 2):
        monkeypatch.setattr(parallel, "thread_count", lambda n=n: n)
        errors.append(radar_errors(meas, sensors, reference="track"))
    assert errors[0]["callsign"].nunique() >= 2 and len(errors[0]) > 100
    pd.testing.assert_frame_equal(errors[0], errors[1], check_exact=True)


def test_fill_predict_is_the_same_on_two_threads(measurements, monkeypatch):
    """correlate --fill predict builds each aircraft's predictors on the threads: every window's slots,
    lags and summary equal those of one thread, bit for bit, in the same order."""
    from msdc.pipeline.correlate.correlation import correlate

    def run(n: int):
        monkeypatch.setattr(parallel, "thread_count", lambda: n)
        return correlate(measurements, all_aircraft=True, fill="predict")

    one, two = run(1), run(2)
    assert len({w.summary["address"] for w in one.windows}) == 2  # both threads had an aircraft
    assert [w.summary for w in one.windows] == [w.summary for w in two.windows]
    for a, b in zip(one.windows, two.windows, strict=True):
        pd.testing.assert_frame_equal(a.slots, b.slots, check_exact=True)
        pd.testing.assert_frame_equal(a.lags, b.lags, check_exact=True)
    assert [s.reason for s in one.skipped] == [s.reason for s in two.skipped]
