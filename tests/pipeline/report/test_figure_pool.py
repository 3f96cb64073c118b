"""Per-item figures drawn in parallel (report.figure_pool) and chosen by --figures-limit / --figures-only
(jobs.figures): the same PNGs as drawn in one process, a failing figure named, the figures left out
listed with commands that really draw them."""

from __future__ import annotations

import datetime as dt
import gc
import io
import json
import shlex
import subprocess
import sys
import weakref
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from PIL import Image

from msdc.pipeline.cli import build_parser, main
from msdc.pipeline.jobs import track
from msdc.pipeline.jobs.common import NOT_DRAWN, JobError, OptionError, choose
from msdc.pipeline.jobs.options import command_args, from_args
from msdc.pipeline.jobs.track import TrackOptions
from msdc.pipeline.progress import Progress
from msdc.pipeline.report import figure_pool
from msdc.pipeline.report.figure_pool import FigureError, FigureTask, render
from msdc.pipeline.report.track_figures import aircraft_figure, figure_names

FIX = Path(__file__).resolve().parents[3] / "fixtures"
BASE = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--sensors", str(FIX / "sensors.toml"), "--date",
        "2019-03-01"]
TRUTH = json.loads((FIX / "truth.json").read_text())["aircraft"]  # five aircraft, each tracked
TRUTH_AIRCRAFT = len(TRUTH)


def _pixels(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGBA"))


def _pngs(folder: Path) -> dict[str, np.ndarray]:
    return {p.name: _pixels(p) for p in sorted(folder.glob("*.png"))}


@pytest.fixture(scope="module")
def fixture_run():
    options = TrackOptions(inputs=tuple(BASE[:2]), sensors=BASE[3], all_aircraft=True,
                           date=dt.date(2019, 3, 1))
    return track.track_job(options)


def _write(result, folder: Path, workers: int, **figure_options) -> dict[str, Path]:
    options = replace(result.options, figures=str(folder), **figure_options)
    return track.write_tracks(replace(result, options=options), workers=workers)


def test_parallel_figures_are_the_serial_ones_pixel_for_pixel(fixture_run, tmp_path):
    # matplotlib's Agg output is deterministic: two worker processes draw the very pixels one process does
    serial = _write(fixture_run, tmp_path / "one", workers=1, figures_limit=3)
    parallel = _write(fixture_run, tmp_path / "two", workers=2, figures_limit=3)
    assert len([k for k in serial if k.startswith("figure ")]) == 3
    assert [p.name for p in serial.values()] == [p.name for p in parallel.values()]
    one, two = _pngs(tmp_path / "one"), _pngs(tmp_path / "two")
    assert list(one) == list(two) and len(one) == 3
    for name in one:
        assert one[name].shape == two[name].shape and one[name].shape[0] > 500, name
        assert np.array_equal(one[name], two[name]), name


def test_limit_draws_the_first_and_lists_the_rest_with_commands_that_draw_them(fixture_run, tmp_path):
    # the aircraft in the order of their ids (fixtures/truth.json's addresses), the first two drawn
    every = [name for name, _ in figure_names(fixture_run.tracks).values()]
    assert [name.rsplit("_", 1)[1] for name in every] == sorted(a["address"] + ".png" for a in TRUTH)
    _write(fixture_run, tmp_path / "two", workers=1, figures_limit=2)
    drawn = sorted(p.name for p in (tmp_path / "two").glob("*.png"))
    assert drawn == sorted(every[:2])
    lines = (tmp_path / "two" / NOT_DRAWN).read_text().splitlines()
    assert lines[0].startswith(f"# 3 of {TRUTH_AIRCRAFT} figures not drawn (--figures-limit 2)")
    listed = dict(line.split("\t") for line in lines if not line.startswith("#"))
    assert list(listed) == every[2:]
    # the listed command, run as it is: exactly that figure, the same pixels as this run draws it
    name = every[3]
    _write(fixture_run, tmp_path / "one", workers=1, figures_only=name)
    assert [p.name for p in (tmp_path / "one").iterdir()] == [name]  # no list: nothing was left out
    argv = shlex.split(listed[name])
    assert argv[:2] == ["msdc", "track"] and "--figures-only" in argv
    assert main(argv[1:]) == 0
    assert sorted(p.name for p in (tmp_path / "two").glob("*.png")) == sorted([*every[:2], name])
    assert np.array_equal(_pixels(tmp_path / "two" / name), _pixels(tmp_path / "one" / name))


def _straight(n: int = 60) -> pd.DataFrame:
    """A track table by hand: a straight 250 kt flight east along the equator, one row a second."""
    t0 = pd.Timestamp("2026-01-01", tz="UTC")
    return pd.DataFrame({
        "aircraft_id": "ABC123", "time": t0 + pd.to_timedelta(range(n), "s"),
        "latitude": 0.0, "longitude": np.arange(n) * 250 / 3600 / 60, "speed_kt": 250.0, "coasted": False,
        "segment": 0, "sigma_major_m": 20.0, "sigma_minor_m": 10.0, "mode_cv": 1.0})


def _tasks(folder: Path, frames: list[pd.DataFrame]) -> list[FigureTask]:
    reports = frames[0].iloc[:0].assign(sensor_id=[], sensor_kind=[])
    return [FigureTask(f"f{i}.png", aircraft_figure,
                       {"tracks": t, "reports": reports, "path": folder / f"f{i}.png"})
            for i, t in enumerate(frames)]


def test_a_figure_failing_in_a_worker_is_named_with_its_reason(tmp_path):
    good = _straight()
    with pytest.raises(FigureError, match=r"figure f1\.png could not be drawn: KeyError: 'latitude'"):
        render(_tasks(tmp_path, [good, good.drop(columns="latitude"), good]), 3, workers=2)


def test_an_os_error_in_a_worker_comes_back_as_it_is_naming_its_file(tmp_path):
    # a figure whose folder cannot be made (a file is in the way): the OSError, naming that path, as drawn
    # in one process (the output transaction then names the user's path)
    (tmp_path / "in_the_way").write_text("a file\n")
    tasks = _tasks(tmp_path, [_straight()] * 3)
    blocked = tmp_path / "in_the_way" / "f1.png"
    tasks[1] = FigureTask("f1.png", aircraft_figure, {**tasks[1].kwargs, "path": blocked})
    with pytest.raises(OSError) as raised:
        render(tasks, 3, workers=2)
    assert not isinstance(raised.value, FigureError) and str(tmp_path / "in_the_way") in str(raised.value)


def test_the_progress_bar_counts_figures_on_a_terminal(tmp_path):
    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    stream = Terminal()
    paths = render(_tasks(tmp_path, [_straight()] * 3), 3, workers=1, progress=Progress(stream))
    assert [p.name for p in paths] == ["f0.png", "f1.png", "f2.png"] and all(p.exists() for p in paths)
    bars = stream.getvalue().split("\r")[1:]
    assert [b.split("(")[1].split(",")[0] for b in bars] == ["1/3", "2/3", "3/3"] and bars[-1].endswith("\n")


def test_a_failing_figure_fails_the_run_naming_it_and_writes_nothing(fixture_run, tmp_path, monkeypatch):
    import msdc.pipeline.report.track_figures as tf

    def broken(**kwargs):
        raise ValueError("no room for the legend")

    monkeypatch.setattr(tf, "aircraft_figure", broken)  # reaches this process only: drawn serially
    with pytest.raises(JobError, match=r"figure track_\S+\.png could not be drawn: ValueError: no room"):
        _write(fixture_run, tmp_path / "figs", workers=1, figures_limit=0)
    assert list(tmp_path.iterdir()) == []


def test_choose_limit_and_only():
    names = ["a.png", "b.png", "c.png"]
    assert choose(names, 2, None).drawn == [0, 1] and choose(names, 2, None).not_drawn == ["c.png"]
    assert choose(names, 0, None).drawn == [0, 1, 2] and choose(names, 9, None).not_drawn == []
    assert choose(names, 1, "c,a.png").drawn == [0, 2]  # --figures-only: the limit does not apply
    with pytest.raises(OptionError, match=r"--figures-only d\.png: no such figure in this run"):
        choose(names, 1, "d")


def test_command_args_parse_back_to_the_same_options(tmp_path):
    argv = ["track", *BASE, "--all", "--figures", str(tmp_path / "f w"), "--figures-limit", "7", "--step",
            "0.125", "--tpm", "fixed:0.95", "--edition", "48=1.27", "--smooth"]
    options = from_args(TrackOptions, build_parser().parse_args(argv), smooth=True)
    again = from_args(TrackOptions, build_parser().parse_args(["track", *command_args(options)]), smooth=True)
    assert again == options


@pytest.mark.parametrize("extra", [["--figures-limit", "3"], ["--figures-only", "track_X"]])
def test_figure_choices_need_figures(extra, tmp_path, capsys):
    assert main(["track", *BASE, "--all", "-o", str(tmp_path / "t.csv"), *extra]) == 2
    err = capsys.readouterr().err
    assert f"{extra[0]} {extra[1]}: only with --figures DIR" in err and list(tmp_path.iterdir()) == []


class _Held:
    """An object a test can watch die (weakref) held in a reference cycle, as a figure's artists are."""


def _draw_a_cycle(path: Path, seen: list) -> Path:
    held = _Held()
    held.me = held
    seen.append(weakref.ref(held))
    return path


def test_a_worker_collects_each_figures_garbage_after_drawing_it(tmp_path):
    """A figure's artists refer to each other: freed only by the collector, whose oldest generation runs
    rarely; the worker collects after each figure so that its memory is one figure's (issue 26 item 5)."""
    seen: list = []
    task = FigureTask("cycle.png", _draw_a_cycle, {"path": tmp_path / "cycle.png", "seen": seen})
    gc.disable()  # only the worker's own collection may free it
    try:
        figure_pool._run(task)
        assert seen[-1]() is not None  # drawn alone, the cycle stays
        assert figure_pool._run_and_collect(task) == tmp_path / "cycle.png"
        assert seen[-1]() is None
    finally:
        gc.enable()


def test_the_fork_server_freezes_what_it_loaded_last():
    """figure_server, last of the fork server's preloads, moves the loaded objects out of the collector's
    reach (gc.freeze), so that workers' collections do not copy the pages they share with the server."""
    assert figure_pool.PRELOAD[-1] == "msdc.pipeline.report.figure_server"
    probe = ("import gc, importlib; before = gc.get_freeze_count(); "
             "importlib.import_module('msdc.pipeline.report.figure_server'); "
             "print(before, gc.get_freeze_count())")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    before, after = map(int, done.stdout.split())
    assert before == 0 and after > 1000  # the interpreter's own objects at least
