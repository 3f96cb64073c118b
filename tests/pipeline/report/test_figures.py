"""The lag figure's peak labels, checked on the drawn canvas."""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.correlate.results import WindowResult
from msdc.pipeline.report import figures


def _window() -> WindowResult:
    """21 slots: NCC (a tent) and Pearson peak together at lag 0 in latitude, 0.01 apart (the two stars
    nearly coincide, as on the fixtures' MAS136 longitude); in longitude Pearson rises to the search
    limit, +10 (a hollow mark whose label is long)."""
    d = np.arange(-20, 21)
    lags = pd.DataFrame({"lag": d, "ncc_lat": 1.0 - np.abs(d) / 21.0, "ncc_lon": 1.0 - np.abs(d) / 21.0,
                         "pearson_lat": 0.99 - 0.0005 * d**2, "pearson_lon": 0.5 + 0.04 * d})
    return WindowResult({"callsign": "TST1", "window": 1, "slots": 21}, pd.DataFrame(), lags)


def test_peak_labels_cover_no_mark_and_no_other_label(tmp_path, monkeypatch):
    """A label 7 pt beside a 12 pt star sat on it, and the NCC and Pearson labels of one lag on each
    other: every label now clears every peak mark of its panel and every other label, and stays inside
    its panel."""
    captured = {}
    monkeypatch.setattr(figures, "save_png", lambda fig, path: captured.setdefault("fig", fig))
    figures.lag_figure(_window(), tmp_path / "lags.png")
    fig = captured["fig"]
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()
    labels = []
    for ax in fig.axes:
        marks = [line.get_window_extent(renderer) for line in ax.get_lines()
                 if line.get_marker() in ("*", "o")]
        texts = [t for t in ax.texts if t.get_visible() and t.get_text()]
        assert len(marks) == len(texts) == 2
        area = ax.get_window_extent(renderer)
        for text in texts:
            box = text.get_window_extent(renderer)
            assert not any(box.overlaps(m) for m in marks), text.get_text()
            assert area.x0 <= box.x0 and box.x1 <= area.x1 and area.y0 <= box.y0 and box.y1 <= area.y1
            labels.append(box)
    assert all(not a.overlaps(b) for i, a in enumerate(labels) for b in labels[i + 1:])
    assert {t.get_text() for ax in fig.axes for t in ax.texts} == {"+0", "+10: search limit, no estimate"}



def test_an_aircraft_without_a_call_sign_is_named_by_its_address():
    """Two surface vehicles without call signs (the LEBL hour's 4CA1C3 and 4CA548) were both '? #1' on the
    map and in its title; they are named as the terminal names them, by address."""
    from msdc.pipeline.report.summary import window_label

    def window(callsign, address, number):
        return WindowResult({"callsign": callsign, "address": address, "window": number}, pd.DataFrame(),
                            pd.DataFrame())

    windows = [window(None, "4CA1C3", 1), window(None, "4CA548", 1), window("AFL2513", "4242AA", 2),
               window(None, None, 3)]
    assert [figures._window_label(w) for w in windows] == ["4CA1C3 #1", "4CA548 #1", "AFL2513 #2", "? #3"]
    assert figures._callsign_title(windows) == "4CA1C3, 4CA548, AFL2513, ?"
    assert window_label(windows[0].summary) == "4CA1C3 window 1"


def test_the_map_draws_the_sites_of_the_sensors_its_windows_correlate():
    """A multilateration-against-ADS-B run with the LEBL sensor file (multilateration and surface radar,
    both CAT010 0/...): the surface radar's reference point is not in the pair, so not drawn; a radar-radar
    run draws both radars and no other; a run whose sensors the file lacks keeps every entry."""
    sensors = pd.DataFrame({"name": ["LEBL MLAT", "LEBL SMR", "R1", "R2", "R3"], "sac": [0, 0, 25, 25, 25],
                            "sic": [107, 7, 201, 202, 203], "latitude": 41.3, "longitude": 2.08,
                            "category": [10, 10, 48, 48, 48],
                            "kind": ["mlat", "smr", "radar", "radar", "radar"]})

    def run(radar, reference):
        from msdc.pipeline.correlate.results import CorrelationRun

        summary = {"radar_sensor": radar, "reference_sensor": reference, "window": 1}
        return CorrelationRun(windows=[WindowResult(summary, pd.DataFrame(), pd.DataFrame())])

    names = lambda r: list(figures._window_sites(sensors, r)["name"])  # noqa: E731
    assert names(run("010:0/107:mlat", "021:0/107")) == ["LEBL MLAT"]
    assert names(run("010:0/7:smr", "010:0/107:mlat")) == ["LEBL MLAT", "LEBL SMR"]
    assert names(run("048:25/201", "048:25/203")) == ["R1", "R3"]
    assert names(run("048:30/1", "021:0/1")) == ["LEBL MLAT", "LEBL SMR", "R1", "R2", "R3"]


def test_range_rings_step_to_ring_the_farthest_slot_in_five_at_most():
    """An airport's tracks within 22 NM got one 50 NM ring; the step is the smallest of 1, 2, 5, 10, 25, 50
    and 100 NM reaching the farthest slot in five rings: 22 NM -> 5 NM (5 rings), 150 NM -> 50 (3), 4.9 ->
    1 (5), 5.1 -> 2 (3), 600 -> 100 (6, the largest step)."""
    assert [figures.ring_step_nm(x) for x in (22.0, 150.0, 4.9, 5.1, 600.0)] == [5.0, 50.0, 1.0, 2.0, 100.0]
