"""--dataset as the jobs' input: quality, track and evaluate on a dataset ingested from the fixtures give the
JSON the recordings give (exactly, but for the run's clock and the inputs' paths, which the manifest holds
resolved); the recordings are moved away first, so only the dataset can be read. --sensor and --from/--to
prune partitions (a corrupted part outside them is never opened); bad --dataset values exit 2."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest
from dataset_data import ADSB, DAY, FIX, RADAR, midnight_recording

from msdc.pipeline.cli import main
from msdc.pipeline.dataset.inputs import Pruning, open_inputs

pytestmark = pytest.mark.xdist_group("dask")  # one Dask cluster for these tests

SENSORS = FIX / "sensors.toml"
TRUTH = json.loads((FIX / "truth.json").read_text())
VOLATILE = {"run_utc", "run_time_s", "path"}  # the run's clock; the manifest keeps the resolved input path


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    """A dataset ingested from copies of the fixtures, the copies then moved away (unreadable by path)."""
    work = tmp_path_factory.mktemp("dsin")
    copies = [shutil.copy(p, work / p.name) for p in (RADAR, ADSB)]
    root = work / "data"
    assert main(["ingest", *map(str, copies), "--dataset", str(root), "--date", DAY]) == 0
    gone = work / "gone"
    gone.mkdir()
    for c in copies:
        Path(c).rename(gone / Path(c).name)
    return root


def _without_volatile(doc):
    if isinstance(doc, dict):
        return {k: _without_volatile(v) for k, v in doc.items() if k not in VOLATILE}
    if isinstance(doc, list):
        return [_without_volatile(v) for v in doc]
    return doc


def _json(tmp_path: Path, name: str, args: list[str]) -> dict:
    out = tmp_path / f"{name}.json"
    assert main([*args, "--json", str(out)]) == 0
    return _without_volatile(json.loads(out.read_text()))


def _file_and_dataset(tmp_path, dataset, command: list[str], scheduler: str) -> tuple[dict, dict]:
    files = _json(tmp_path, "files", [command[0], str(RADAR), str(ADSB), "--date", DAY, *command[1:]])
    on_dataset = _json(tmp_path, "dataset", [command[0], "--dataset", str(dataset), *command[1:],
                                             "--scheduler", scheduler])
    return files, on_dataset


@pytest.mark.parametrize("command", [
    ["quality", "--sensors", str(SENSORS), "--all"],
    ["track", "--sensors", str(SENSORS), "--all"],
    ["evaluate", "--sensors", str(SENSORS), "--preset", "eurocontrol-1997-ssr"],
], ids=["quality", "track", "evaluate"])
def test_dataset_gives_the_recordings_results(tmp_path, dataset, command, dask_scheduler, capsys):
    """On the dataset the per-aircraft work runs as tasks on a 2-process Dask cluster; the recordings run
    it on threads in the test's process: the results are equal exactly (each aircraft's own work, combined
    in the same order)."""
    files, on_dataset = _file_and_dataset(tmp_path, dataset, command, dask_scheduler)
    assert on_dataset == files  # exactly: the same records in the same order give the same sums
    err = capsys.readouterr().err
    if command[0] != "quality":  # quality's reference interpolation is no per-aircraft task
        assert f"task(s) on the Dask scheduler at {dask_scheduler}, none failed" in err
        assert "not used" not in err  # the run that used the cluster was said not to (closed before asked)


WINDOW = ("08:40:00", "09:00:00")


def _records_within(start: str, end: str) -> list[dict[str, int]]:
    """Per fixture and category, its records whose time lies from ``start`` to ``end`` (times of day on
    DAY), inclusive."""
    import msdc.asterix as asterix

    lo, hi = (pd.Timedelta(t).total_seconds() for t in (start, end))
    out = []
    for path in (RADAR, ADSB):
        out.append({})
        for cat, frame in asterix.read(path).frames.items():
            tod = frame["day"].to_numpy(float) * 86400.0 + frame["time_of_day"].to_numpy(float)
            out[-1][str(cat)] = int(((tod >= lo) & (tod <= hi)).sum())
    return out


@pytest.mark.parametrize("command", [
    ["track", "--sensors", str(SENSORS), "--all"],
    ["evaluate", "--sensors", str(SENSORS), "--preset", "eurocontrol-1997-ssr"],
], ids=["track", "evaluate"])
def test_a_window_reads_only_its_margin_of_the_dataset(tmp_path, dataset, command, dask_scheduler):
    """--from/--to given as instants: the dataset's read stops 15 minutes beyond the window (its margin: a
    report's time is its record's timestamp), the recordings are read whole and cut at 15 minutes; the
    results are the same, and only the counts of what was read differ, by the records beyond 15 minutes."""
    window = ["--from", f"{DAY}T{WINDOW[0]}Z", "--to", f"{DAY}T{WINDOW[1]}Z"]
    files, on_dataset = _file_and_dataset(tmp_path, dataset, [*command, *window], dask_scheduler)
    read = [[i.pop("records") for i in doc["inputs"]] for doc in (files, on_dataset)]
    assert read == [_records_within("00:00:00", "23:59:59"), _records_within("08:25:00", "09:15:00")]
    reports = [doc["parameters"]["report_selection"].pop("reports") for doc in (files, on_dataset)]
    time_cut = [doc["parameters"]["report_selection"]["left_out"].pop("time") for doc in (files, on_dataset)]
    assert on_dataset == files
    never_read = sum(n for by_cat in read[0] for n in by_cat.values()) - sum(
        n for by_cat in read[1] for n in by_cat.values())
    assert never_read > 5_000 and reports[0] - reports[1] == never_read == time_cut[0] - time_cut[1]


def test_windows_on_a_cluster_are_the_windows_one_after_the_other(tmp_path, dataset, dask_scheduler, capsys):
    """--window on a cluster: each window is one task, evaluated on a worker (which reads the dataset around
    it); the recordings' windows run one after the other in the test's process. The JSON is the same
    exactly: each window is evaluated by the same code on the same records, pooled in the windows' order."""
    command = ["evaluate", "--sensors", str(SENSORS), "--preset", "eurocontrol-1997-ssr",
               "--from", f"{DAY}T08:40:00Z", "--to", f"{DAY}T09:00:00Z", "--window", "10"]
    files, on_dataset = _file_and_dataset(tmp_path, dataset, command, dask_scheduler)
    for doc in (files, on_dataset):  # what was read differs: the recordings whole, the dataset around each
        for info in doc["inputs"]:
            info.pop("records")
        doc["parameters"]["report_selection"].pop("reports")
        doc["parameters"]["report_selection"]["left_out"].pop("time")
    assert len(files["parameters"]["windows"]) == 2
    assert on_dataset == files
    err = capsys.readouterr().err
    assert "Evaluating 2 windows, each a task on the cluster" in err
    assert f"2 task(s) on the Dask scheduler at {dask_scheduler}, none failed" in err  # windows, not aircraft
    assert "not used" not in err


@pytest.mark.filterwarnings("error::pytest.PytestUnraisableExceptionWarning")  # tasks left behind
def test_a_bad_option_found_in_a_window_task_is_said_as_without_a_cluster(tmp_path, dataset, dask_scheduler,
                                                                         capsys):
    """A reference file is read by each window's task (on its worker): a bad line in it ends the run with
    exit status 2 and the file and line named, as without a cluster, and writes nothing; the other windows'
    tasks are cancelled while the cluster is there (no error is left for the garbage collector to print)."""
    bad = tmp_path / "ref.csv"
    bad.write_text("aircraft,time,latitude,longitude,altitude_ft\n,2020-01-01T08:41:00Z,3.0,101.0,10000\n")
    out = tmp_path / "e.json"
    for engine in (["--scheduler", dask_scheduler], ["--scheduler", "none"]):
        assert main(["evaluate", "--dataset", str(dataset), "--sensors", str(SENSORS), "--preset",
                     "eurocontrol-1997-ssr", "--from", f"{DAY}T08:40:00Z", "--to", f"{DAY}T09:00:00Z",
                     "--window", "10", "--reference-file", str(bad), "--json", str(out), *engine]) == 2
        err = capsys.readouterr().err
        assert f"--reference-file: {bad}:2: aircraft is empty" in err and "Traceback" not in err
        assert not out.exists()


def _corrupt(root: Path, category: int) -> Path:
    part = next(root.glob(f"date=*/category={category:03d}/sensor=*/part-*.parquet"))
    saved = part.with_name("saved")
    shutil.copy(part, saved)
    part.write_bytes(b"not parquet")
    return saved


def test_sensor_prunes_partitions(tmp_path, dataset, capsys):
    adsb = f"{TRUTH['adsb']['sac']}/{TRUTH['adsb']['sic']}"
    root = tmp_path / "data"
    shutil.copytree(dataset, root)
    _corrupt(root, 48)  # the radar's part: read, it would fail
    args = ["quality", "--dataset", str(root), "--sensors", str(SENSORS), "--all", "--sensor", adsb]
    assert main([*args, "--json", str(tmp_path / "q.json")]) == 0
    assert "radar.ast: no CAT021 or CAT048 record" not in capsys.readouterr().err  # pruned, not empty
    assert main(["quality", "--dataset", str(root), "--sensors", str(SENSORS), "--all"]) == 2  # it is read
    assert "part-" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["stats"], ["sql", "SELECT count(*) FROM cat048"]])
def test_a_damaged_part_is_said_by_every_command_with_status_2(tmp_path, dataset, capsys, command):
    """msdc stats printed a traceback (UnreadablePart) where quality said the part cannot be read, exit 2
    (docs/guide/large-recordings.md); sql exited 1 with DuckDB's three-line message."""
    root = tmp_path / "data"
    shutil.copytree(dataset, root)
    _corrupt(root, 48)
    assert main([command[0], "--dataset", str(root), *command[1:]]) == 2
    err = capsys.readouterr().err
    assert f"msdc {command[0]}: " in err and "cannot be read" in err and "Traceback" not in err
    assert len([line for line in err.splitlines() if line.startswith("msdc ")]) == 1
    assert len(err.strip().splitlines()) <= 2  # "Processing data files..." and the message


def test_bytes_damaged_inside_a_page_are_refused_not_read_as_other_values(tmp_path, dataset):
    """16 zero bytes in the middle of the CAT048 part's rho_nm column chunk (placed from the part's own
    footer) decoded into other ranges without a word; ingest writes each page's CRC-32 and the read checks
    it: the read is refused, naming the part."""
    import pyarrow.parquet as pq

    from msdc.pipeline.dataset.inputs import UnreadablePart

    root = tmp_path / "data"
    shutil.copytree(dataset, root)
    part, = root.glob("date=*/category=048/sensor=*/part-*.parquet")
    groups = pq.ParquetFile(part).metadata
    chunks = [groups.row_group(g).column(c) for g in range(groups.num_row_groups)
              for c in range(groups.num_columns) if groups.row_group(g).column(c).path_in_schema == "rho_nm"]
    chunk = max(chunks, key=lambda c: c.total_compressed_size)
    data = bytearray(part.read_bytes())
    at = chunk.data_page_offset + chunk.total_compressed_size // 2
    data[at:at + 16] = bytes(16)
    part.write_bytes(data)
    src = open_inputs(root)
    radar = next(i for i in range(2) if src.records[i]["rows"].get("048"))
    said = rf"cannot be read \({part}\): .*CRC checksum verification failed"
    with pytest.raises(UnreadablePart, match=said):
        src.read(radar)


def test_days_and_sensors_prune_the_parts_read(dataset):
    import datetime as dt

    src = open_inputs(dataset)
    radar = f"{TRUTH['radar']['sac']}_{TRUTH['radar']['sic']}"
    day = dt.date.fromisoformat(DAY)
    src.pruning = Pruning(first=day + dt.timedelta(days=1))
    assert all(not src.read(i).frames for i in range(2)) and src.read_parts == []
    src.pruning = Pruning(first=day, last=day, sensors=((48, radar),))
    frames = [src.read(i).frames for i in range(2)]
    assert [list(f) for f in frames] == [[48], []]
    assert [p.parts[-3:-1] for p in src.read_parts] == [("category=048", f"sensor={radar}")]


def test_window_prunes_days_and_keeps_the_margin():
    from msdc.pipeline.model.report_selection import ReportSelection, parse_time

    sel = ReportSelection(start=parse_time("2026-11-28T00:02:00", "--from"),
                          end=parse_time("2026-11-29T12:00:00", "--to"))
    from msdc.pipeline.dataset.inputs import pruning

    p = pruning(sel)
    assert (p.first.isoformat(), p.last.isoformat()) == ("2026-11-27", "2026-11-29")  # 5 min before 00:02
    assert pruning(ReportSelection(start=parse_time("08:10", "--from"))).first is None  # day not yet known
    # a measurement job reads the records within 15 minutes (its identity margin), and only those
    from msdc.pipeline.dataset.inputs import reading_pruning

    read = reading_pruning(p, sel)
    assert (read.first.isoformat(), read.last.isoformat()) == ("2026-11-27", "2026-11-29")
    assert (read.since, read.until) == (pd.Timestamp("2026-11-27T23:47Z"), pd.Timestamp("2026-11-29T12:15Z"))
    tod = ReportSelection(start=parse_time("08:10", "--from"))
    assert reading_pruning(pruning(tod), tod) == pruning(tod)  # a time of day: placed once read


def test_refusals(tmp_path, dataset, capsys):
    assert main(["quality", str(RADAR), "--dataset", str(dataset), "--sensors", str(SENSORS), "--all"]) == 2
    assert "both given" in capsys.readouterr().err
    assert main(["quality", "--dataset", str(tmp_path), "--sensors", str(SENSORS), "--all"]) == 2
    err = capsys.readouterr().err
    assert str(tmp_path) in err and "manifest.json" in err
    assert main(["track", "--dataset", str(tmp_path / "nope"), "--sensors", str(SENSORS), "--all"]) == 2
    assert "no such folder" in capsys.readouterr().err
    (tmp_path / "file").write_text("")
    for command in (["track", "--sensors", str(SENSORS), "--all"], ["stats"], ["sql", "SELECT 1"]):
        assert main([command[0], "--dataset", str(tmp_path / "file"), *command[1:]]) == 2
        assert f"{tmp_path / 'file'}: is a file, not a folder" in capsys.readouterr().err  # not "no such"
    assert main(["track", "--dataset", str(dataset), "--sensors", str(SENSORS), "--all", "--date", DAY]) == 2
    assert "with --date" in capsys.readouterr().err  # the ingest decoded it
    assert main(["quality", "--sensors", str(SENSORS), "--all"]) == 2  # neither INPUT nor --dataset


def _stats_lines(capsys, args: list[str], said: list[str] | None = None) -> list[str]:
    """The lines stats prints (its stderr appended to ``said``)."""
    assert main(["stats", *args]) == 0
    out, err = capsys.readouterr()
    if said is not None:
        said.append(err)
    return [line for line in out.splitlines() if "edition auto" not in line]  # the ingest chose it, said so


@pytest.mark.parametrize("selection", [[], ["--sensor", f"{TRUTH['adsb']['sac']}/{TRUTH['adsb']['sic']}",
                                            "--from", f"{DAY}T08:10:00", "--to", f"{DAY}T08:40:00"]],
                         ids=["all", "selected"])
def test_stats_on_a_dataset_are_the_recordings(dataset, capsys, dask_scheduler, selection):
    """Each partition's stats a task on the cluster, folded per input: the tables printed are the
    recordings' (records, blocks, spans, distinct addresses and call signs per sensor and aircraft)."""
    files = _stats_lines(capsys, [str(RADAR), str(ADSB), "--date", DAY, *selection])
    err = []
    on_dataset = _stats_lines(capsys, ["--dataset", str(dataset), "--scheduler", dask_scheduler, *selection],
                              err)
    # the partitions ran as tasks there (stats ran them on threads, whatever --scheduler said)
    assert f"task(s) on the Dask scheduler at {dask_scheduler}, none failed" in err[0]
    assert "not used" not in err[0]
    if selection:  # the radar's partition is never read: its records are not counted as left out
        import re

        said = [re.search(r"(\d+) of (\d+) records kept", lines[0]).groups() for lines in (files, on_dataset)]
        radar = re.search(r"(\d+) by sensor", files[0]).group(1)
        assert said[1] == (said[0][0], str(int(said[0][1]) - int(radar)))
        files, on_dataset = files[1:], on_dataset[1:]
    assert on_dataset == files and len(files) > 5  # tables, not a message


def test_stats_count_a_block_split_at_midnight_once(tmp_path, capsys):
    """Blocks of 5 plots 4 s apart across midnight: the block holding midnight is split over two day
    partitions; the dataset's block counts are the recording's (each block once)."""
    rec = tmp_path / "midnight.ast"
    midnight_recording(rec, n=600 * 5 + 100)  # plot 3000 of radar 20/129 at 00:00:00, inside a block
    root = tmp_path / "data"
    assert main(["ingest", str(rec), "--dataset", str(root), "--date", DAY]) == 0
    capsys.readouterr()
    days = sorted(p.name for p in root.glob("date=*"))
    assert len(days) == 2  # both days hold parts
    files = _stats_lines(capsys, [str(rec), "--date", DAY])
    assert _stats_lines(capsys, ["--dataset", str(root), "--scheduler", "none"]) == files


def test_a_run_lists_and_dates_only_the_inputs_it_reads(tmp_path):
    """A dataset holding the fixtures on DAY and another radar's recording on an earlier day: a run of a
    window on DAY reads only the fixtures, so its outputs list those two inputs and give DAY as the run's
    date (not the dataset's first day); a run over both days lists all three, dated the earlier day."""
    rec = tmp_path / "earlier.ast"
    midnight_recording(rec, n=600)  # radar 20/129, the 40 minutes before midnight
    work = tmp_path / "work"
    work.mkdir()
    copies = [shutil.copy(p, work / p.name) for p in (RADAR, ADSB)]
    root = tmp_path / "data"
    assert main(["ingest", str(rec), "--dataset", str(root), "--date", "2026-11-20"]) == 0
    assert main(["ingest", *map(str, copies), "--dataset", str(root), "--date", DAY]) == 0
    command = ["track", "--sensors", str(SENSORS), "--all", "--dataset", str(root), "--scheduler", "none"]
    window = _json(tmp_path, "window", [*command, "--from", f"{DAY}T08:40Z", "--to", f"{DAY}T09:00Z"])
    import hashlib

    fixtures = [hashlib.sha256(p.read_bytes()).hexdigest() for p in (RADAR, ADSB)]
    assert [i["sha256"] for i in window["inputs"]] == fixtures
    assert window["parameters"]["date"] == DAY
    both = _json(tmp_path, "both", [*command, "--from", "2026-11-20T23:00Z", "--to", f"{DAY}T09:00Z"])
    earlier = hashlib.sha256(rec.read_bytes()).hexdigest()
    assert [i["sha256"] for i in both["inputs"]] == [earlier, *fixtures]
    assert both["parameters"]["date"] == "2026-11-20"
    # quality and correlate decode in chunks (load.load_measurements): they listed the input of the other
    # day, or the ADS-B with --sensor of the radar, as read with 0 bytes
    quality = ["quality", "--sensors", str(SENSORS), "--all", "--dataset", str(root)]
    window = _json(tmp_path, "q-window", [*quality, "--from", f"{DAY}T08:40Z", "--to", f"{DAY}T09:00Z"])
    assert [i["sha256"] for i in window["inputs"]] == fixtures
    assert [i["bytes"] for i in window["inputs"]] == [RADAR.stat().st_size, ADSB.stat().st_size]
    radar = _json(tmp_path, "q-radar", [*quality, "--sensor", "048:25/201"])
    assert [(i["sha256"], i["bytes"]) for i in radar["inputs"]] == [(fixtures[0], RADAR.stat().st_size)]


def test_a_default_ingest_keeps_the_north_markers_evaluate_reads(tmp_path):
    """A radar recording with CAT034 north markers, ingested with no --category: the dataset holds them, and
    evaluate on it takes the scan period from them and gives the recordings' JSON (with only the measurement
    categories ingested, the period was estimated from the plots, another figure)."""
    from fixtures.radar_effects import RadarEffects, simulate_effects
    from msdc.asterix.encode import encode_frame

    sim = simulate_effects(effects=RadarEffects(pd=0.9), seed=3)
    radar, adsb, sensors = tmp_path / "radar.ast", tmp_path / "adsb.ast", tmp_path / "sensors.toml"
    radar.write_bytes(encode_frame(48, sim.radar) + encode_frame(34, sim.north_markers))
    adsb.write_bytes(encode_frame(21, sim.sim.adsb))
    sensors.write_text(sim.sensors_toml(coverage=True))
    root = tmp_path / "data"
    assert main(["ingest", str(radar), str(adsb), "--dataset", str(root), "--date", "2020-01-01"]) == 0
    stored = {p.name for p in (root / "date=2020-01-01").iterdir()}
    assert stored == {"category=021", "category=034", "category=048"}
    command = ["--sensors", str(sensors), "--preset", "eurocontrol-1997-ssr"]
    files = _json(tmp_path, "files", ["evaluate", str(radar), str(adsb), "--date", "2020-01-01", *command])
    on_dataset = _json(tmp_path, "dataset", ["evaluate", "--dataset", str(root), *command,
                                             "--scheduler", "none"])
    pd_notes = [r["notes"] for r in on_dataset["results"] if r["requirement"] == "pd"]
    assert any(" north markers; " in n for n in pd_notes)  # the per-scan pd row (the other: 5 s intervals)
    # the CAT034 markers laid after every plot: the file's times go back to its start there, but neither
    # category's own time line jumps, so neither run warns of it
    assert files["parameters"]["warnings"] == on_dataset["parameters"]["warnings"] == []
    assert on_dataset == files


def _files(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


@pytest.mark.parametrize("command", [
    ["track", "--sensors", str(SENSORS), "--all", "--json", "{manifest}"],
    ["track", "--sensors", str(SENSORS), "--all", "-o", "{part}"],
    ["track", "--sensors", str(SENSORS), "--all", "-o", "{outside}/t.csv", "--figures", "{root}/figs"],
    ["quality", "--sensors", str(SENSORS), "--all", "-o", "{root}/q.xlsx"],
    ["evaluate", "--sensors", str(SENSORS), "--preset", "eurocontrol-1997-ssr", "--json", "{link}/e.json"],
    ["conflicts", "--sensors", str(SENSORS), "-o", "{root}/k.csv"],
    ["correlate", "--sensors", str(SENSORS), "--all", "--json", "{root}/c.json"],
    ["sql", "-o", "{part}", "SELECT 1 AS x"],
], ids=["manifest", "part", "figures", "quality", "link", "conflicts", "correlate", "sql"])
def test_an_output_inside_the_dataset_is_refused(tmp_path, dataset, command, capsys):
    """An output inside the dataset's folder, by any path or link, overwrote its manifest or a part (a track
    table in place of the CAT048 part, read afterwards as radar plots): refused before anything is read,
    the dataset left byte for byte."""
    link = tmp_path / "link"
    link.symlink_to(dataset)
    part = next(dataset.rglob("*.parquet"))
    names = {"manifest": dataset / "manifest.json", "part": part, "root": dataset, "link": link,
             "outside": tmp_path}
    argv = [command[0], "--dataset", str(dataset), *(a.format(**names) for a in command[1:])]
    before = _files(dataset)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"is inside the dataset {dataset}; writing there would change the dataset" in err
    assert _files(dataset) == before


@pytest.mark.parametrize("damage, said", [
    (lambda rec, part: rec.update(date="2019-13-45"), "date '2019-13-45' is no date (YYYY-MM-DD)"),
    (lambda rec, part: part.update(date="xx"), "date 'xx' is no date (YYYY-MM-DD)"),
    (lambda rec, part: part.update(category=999), "category 999 is none msdc decodes"),
    (lambda rec, part: part.update(category="48"), "category '48' is none msdc decodes"),
    (lambda rec, part: part.update(rows=-1), "rows -1 is no count"),
    (lambda rec, part: part.update(sensor=None), "sensor None is no SAC_SIC text"),
    (lambda rec, part: part.update(path="../elsewhere.parquet"), "no path inside the dataset"),
], ids=["input-date", "part-date", "category", "category-text", "rows", "sensor", "path"])
@pytest.mark.parametrize("command", [["track", "--sensors", str(SENSORS), "--all", "--json", "{out}"],
                                     ["stats"]], ids=["track", "stats"])
def test_a_manifest_value_no_reader_can_use_is_said_by_name(tmp_path, dataset, damage, said, command, capsys):
    """A date, category, sensor, row count or path in the manifest that no reader can use ended in a
    traceback (ValueError, KeyError) once the job read it: now status 2 naming the manifest and the value."""
    copy = tmp_path / "copy"
    shutil.copytree(dataset, copy)
    doc = json.loads((copy / "manifest.json").read_text())
    damage(doc["inputs"][0], doc["inputs"][0]["parts"][0])
    (copy / "manifest.json").write_text(json.dumps(doc))
    argv = [command[0], "--dataset", str(copy), *(a.format(out=tmp_path / "t.json") for a in command[1:])]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and f"{copy / 'manifest.json'}: the input " in err and said in err, err
    assert not (tmp_path / "t.json").exists()


@pytest.mark.parametrize("change, said", [
    ("remove", "a part of CAT048 is missing (the manifest lists it): "),
    ("swap", "a part of CAT048 holds {adsb:,} rows where the manifest lists {radar:,} (changed since the "
             "ingest): "),
], ids=["missing", "swapped"])
@pytest.mark.parametrize("command", [["track", "--sensors", str(SENSORS), "--all", "--json", "{out}"],
                                     ["stats"]], ids=["track", "stats"])
def test_a_part_removed_or_replaced_since_the_ingest_is_said(tmp_path, dataset, change, said, command,
                                                            capsys):
    """A removed part was said "cannot be read" and its path, no reason; the ADS-B part copied over the
    radar's was read as radar plots (stats counted 14,986 CAT048 records; track asked for radar 0/1 in the
    sensor file): the rows each part holds are the manifest's, else status 2 naming the part."""
    copy = tmp_path / "copy"
    shutil.copytree(dataset, copy)
    radar = next(copy.glob("date=*/category=048/sensor=*/part-*.parquet"))
    if change == "remove":
        radar.unlink()
    else:
        shutil.copy(next(copy.glob("date=*/category=021/sensor=*/part-*.parquet")), radar)
    argv = [command[0], "--dataset", str(copy), "--scheduler", "none",
            *(a.format(out=tmp_path / "t.json") for a in command[1:])]
    assert main(argv) == 2
    err = capsys.readouterr().err
    expected = said.format(adsb=TRUTH["adsb"]["rows"], radar=TRUTH["radar"]["rows"])
    assert f"{copy}: {expected}" in err and radar.name in err and "Traceback" not in err, err
    assert not (tmp_path / "t.json").exists()


def test_partitions_the_selection_prunes_away_are_said_not_the_inputs(dataset, tmp_path, capsys):
    """--from/--to or --sensor keeping no partition with the records a job needs: the error said "no ...
    records in the inputs", which the dataset holds (the recordings' run says the selection kept none)."""
    adsb, radar = TRUTH["adsb"]["rows"], TRUTH["radar"]["rows"]
    early = ["--from", f"{DAY}T05:00", "--to", f"{DAY}T06:00"]
    base = ["--dataset", str(dataset), "--sensors", str(SENSORS), "--all", "--scheduler", "none"]
    assert main(["track", *base, *early, "-o", str(tmp_path / "t.csv")]) == 1
    assert ("no radar (CAT048) or ADS-B (CAT021) records in the dataset's partitions the report selection "
            f"keeps (--from, --to; it holds {adsb + radar:,})") in capsys.readouterr().err
    assert main(["correlate", *base, "--sensor", "048:25/201", "--json", str(tmp_path / "c.json")]) == 1
    assert ("no ADS-B (CAT021) records in the dataset's partitions the report selection keeps (--sensor; it "
            f"holds {adsb:,})") in capsys.readouterr().err


def test_a_dataset_without_the_categories_a_job_needs_says_so_of_itself(tmp_path, capsys):
    """The fixtures ingested with --category 62 alone: the jobs said of each recording "no CAT021 or CAT048
    record in it" and stats "nothing could be decoded from" it, though each holds thousands: it is the
    dataset that holds none."""
    root = tmp_path / "only62"
    assert main(["ingest", str(RADAR), str(ADSB), "--dataset", str(root), "--date", DAY,
                 "--category", "62"]) == 0
    capsys.readouterr()
    assert main(["track", "--dataset", str(root), "--sensors", str(SENSORS), "--all", "--scheduler", "none",
                 "-o", str(tmp_path / "t.csv")]) == 1
    err = capsys.readouterr().err
    assert f"{RADAR}: the dataset holds no CAT021 or CAT048 record of it (its ingest kept CAT062)" in err
    assert "no radar (CAT048) or ADS-B (CAT021) records in the dataset" in err and "in it" not in err
    assert main(["stats", "--dataset", str(root), "--scheduler", "none"]) == 1
    assert f"msdc stats: --dataset {root} holds no record of {RADAR} (" in capsys.readouterr().err
