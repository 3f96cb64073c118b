"""msdc ingest: the partition layout and schema, rows equal to asterix.read's, days across midnight, a second
ingest doing nothing, a SIGKILLed ingest resuming to the same dataset, --workers 2 equal to one, and failed
runs leaving the dataset as it was."""

from __future__ import annotations

import datetime as dt
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from dataset_data import (
    ADSB,
    DAY,
    FIX,
    RADAR,
    category_rows,
    listed_parts,
    manifest,
    midnight_recording,
    on_disk,
    same_dataset,
    same_rows,
)

import msdc.asterix as asterix
from msdc.pipeline.cli import main
from msdc.pipeline.report.record_schema import record_schema

# one worker runs the module: the fixtures' dataset made once, not on each worker
pytestmark = pytest.mark.xdist_group("ingest")

TRUTH = json.loads((FIX / "truth.json").read_text())


def ingest(*args: str) -> int:
    return main(["ingest", *map(str, args)])


@pytest.fixture(scope="module")
def fixtures_dataset(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("ds") / "data"
    assert ingest(RADAR, ADSB, "--dataset", root, "--date", DAY) == 0
    return root


def test_partitions_are_day_category_sensor(fixtures_dataset):
    radar, adsb = TRUTH["radar"], TRUTH["adsb"]
    assert listed_parts(fixtures_dataset) == on_disk(fixtures_dataset)  # nothing beside the parts
    folders = sorted(p.rsplit("/", 1)[0] for p in listed_parts(fixtures_dataset))
    assert folders == [f"date={DAY}/category=021/sensor={adsb['sac']}_{adsb['sic']}",
                       f"date={DAY}/category=048/sensor={radar['sac']}_{radar['sic']}"]
    doc = manifest(fixtures_dataset)
    rows = {rec["file"]: rec["rows"] for rec in doc["inputs"]}
    assert rows == {"radar.ast": {"048": radar["rows"]}, "adsb.ast": {"021": adsb["rows"]}}
    import hashlib

    first = doc["inputs"][0]
    assert first["sha256"] == hashlib.sha256(RADAR.read_bytes()).hexdigest()
    assert first["size_bytes"] == RADAR.stat().st_size and first["format"] == "raw" and first["date"] == DAY
    assert set(first["editions"]) == {"048"} and doc["msdc"]
    assert [p["rows"] for p in first["parts"]] == [radar["rows"]]


def test_each_part_has_its_categorys_documented_schema(fixtures_dataset):
    for rel in listed_parts(fixtures_dataset):
        cat = int(rel.split("/")[1].split("=")[1])
        schema = pq.read_schema(fixtures_dataset / rel)
        assert schema.names == record_schema(cat).columns
        assert schema.names[-3:] == ["block", "offset", "file"]


def test_parts_are_zstd_with_dictionaries_for_text_only(fixtures_dataset):
    # the encodings docs/guide/large-recordings.md states (they change the bytes, not the values read back)
    for rel in listed_parts(fixtures_dataset):
        meta = pq.ParquetFile(fixtures_dataset / rel).metadata
        schema = pq.read_schema(fixtures_dataset / rel)
        for g in range(meta.num_row_groups):
            for c in range(meta.num_columns):
                chunk = meta.row_group(g).column(c)
                field = schema.field(chunk.path_in_schema)
                assert chunk.compression == "ZSTD", chunk.path_in_schema
                text = str(field.type).startswith("dictionary")
                assert chunk.has_dictionary_page == text, chunk.path_in_schema
                if str(field.type) == "double":
                    assert "BYTE_STREAM_SPLIT" in chunk.encodings, chunk.path_in_schema


@pytest.mark.parametrize("path,cat", [(RADAR, 48), (ADSB, 21)])
def test_rows_equal_asterix_read(fixtures_dataset, path, cat):
    frame = asterix.read(path, date=DAY).frames[cat]  # the whole file at once: no chunk, no dataset
    rows = category_rows(fixtures_dataset, cat)
    rows = rows[rows["file"] == path.name].reset_index(drop=True)
    assert len(rows) == len(frame)
    assert (rows["date"] == DAY).all()
    for col in frame.columns:
        got, want = rows[col], frame[col].reset_index(drop=True)
        if isinstance(want.dtype, pd.CategoricalDtype):
            got, want = got.astype(object), want.astype(object)
        pd.testing.assert_series_equal(got, want, check_dtype=False, check_names=False,
                                       check_categorical=False, obj=col)


def test_days_across_midnight_go_to_their_dates(tmp_path):
    rec = tmp_path / "midnight.ast"
    a, b = midnight_recording(rec)
    root = tmp_path / "ds"
    assert ingest(rec, "--dataset", root, "--date", DAY, "--chunk-mb", "0.1") == 0
    rows = category_rows(root, 48)
    next_day = (dt.date.fromisoformat(DAY) + dt.timedelta(days=1)).isoformat()
    for f, sensor in ((a, "20_129"), (b, "20_130")):
        tod = f["time_of_day"].to_numpy()
        before = int(np.flatnonzero(np.diff(tod) < 0)[0]) + 1  # the plots before the clock wraps
        got = rows[rows["sensor"] == sensor]
        assert len(got) == len(f)
        assert (got["date"].iloc[:before] == DAY).all() and (got["date"].iloc[before:] == next_day).all()
        want = pd.Timestamp(DAY, tz="UTC") + pd.to_timedelta(np.where(np.arange(len(f)) < before, 0, 86400)
                                                               + tod, unit="s")
        assert (got["timestamp"].to_numpy() == want.to_numpy()).all()
    parts = sorted(p.rsplit("/", 1)[0] for p in listed_parts(root))
    assert parts == [f"date={d}/category=048/sensor={s}" for d in (DAY, next_day)
                     for s in ("20_129", "20_130")]


def test_ingesting_the_same_input_again_does_nothing(fixtures_dataset, tmp_path, capsys):
    root = tmp_path / "copy"
    shutil.copytree(fixtures_dataset, root)
    before = {p: p.read_bytes() for p in root.rglob("*") if p.is_file()}
    capsys.readouterr()
    copy = tmp_path / "renamed.ast"  # the same bytes under another name: the same input
    shutil.copy(RADAR, copy)
    assert ingest(RADAR, copy, ADSB, "--dataset", root, "--date", DAY) == 0
    out = capsys.readouterr().out
    assert out.count("already in the dataset") == 2 and "nothing to do" in out
    assert {p: p.read_bytes() for p in root.rglob("*") if p.is_file()} == before
    assert "its rows keep the options" not in out  # the same options: nothing more to say


def test_an_input_skipped_as_ingested_says_the_options_it_was_not_given(fixtures_dataset, tmp_path, capsys):
    """Ingested again with another --date, the input was skipped with 'nothing to do' alone: the new --date
    was silently not applied."""
    root = tmp_path / "copy"
    shutil.copytree(fixtures_dataset, root)
    before = {p: p.read_bytes() for p in root.rglob("*") if p.is_file()}
    capsys.readouterr()
    assert ingest(RADAR, "--dataset", root, "--date", "2020-01-02") == 0
    out = capsys.readouterr().out
    assert (f"nothing to do; its rows keep the options it was ingested with (--date 2020-01-02 now, {DAY} "
            "then): to apply these, ingest it into another dataset") in out
    assert {p: p.read_bytes() for p in root.rglob("*") if p.is_file()} == before


def test_workers_2_on_one_input_write_the_rows_workers_1_writes(tmp_path):
    """One input, two workers: each window of the raw stream written by a pool process (parts of their
    own): the same rows, in the same order, in every partition, across midnight (the clocks settled before
    the windows decode)."""
    rec = tmp_path / "midnight.ast"
    midnight_recording(rec, 12000)  # about 190 kB: chunks of 0.1 MB, midnight in the middle one
    one, two = tmp_path / "one", tmp_path / "two"
    args = (rec, "--date", DAY, "--chunk-mb", "0.1")
    assert ingest(*args, "--dataset", one) == 0
    assert ingest(*args, "--dataset", two, "--workers", "2") == 0
    assert len({p.split("/")[0] for p in listed_parts(one)}) == 2  # both days
    assert len(listed_parts(two)) > len(listed_parts(one))  # the windows' parts
    same_rows(one, two)
    again = tmp_path / "again"
    assert ingest(*args, "--dataset", again, "--workers", "2") == 0
    same_dataset(two, again)  # and the same parts for the same command


def _several_inputs(tmp_path: Path) -> list[Path]:
    """Inputs whose ingests end in another order than theirs: the ADS-B station's (the largest, six times
    the others: it ends last), a radar's, a copy of it (the same bytes: skipped), an input of another
    content under the radar's name (its label the resolved path)."""
    copy, other = tmp_path / "copy.ast", tmp_path / "other" / "radar.ast"
    shutil.copy(RADAR, copy)
    other.parent.mkdir()
    midnight_recording(other, 3000)
    return [ADSB, RADAR, copy, other]


def test_workers_2_on_several_inputs_write_the_dataset_workers_1_writes(tmp_path, capsys):
    """Inputs at least as many as workers: each ingested whole by a pool process, streamed as one process
    streams it, so the same parts (names and rows), the same manifest (inputs in input order, labels and
    skips as one process assigns them) and the same lines said, whatever order the inputs end in."""
    inputs = _several_inputs(tmp_path)
    one, two = tmp_path / "one", tmp_path / "two"
    said = {}
    for root, workers in ((one, "1"), (two, "2")):
        assert ingest(*inputs, "--dataset", root, "--date", DAY, "--chunk-mb", "0.1", "--workers", workers
                      ) == 0
        said[workers] = capsys.readouterr()
    same_dataset(one, two)
    assert [r["file"] for r in manifest(two)["inputs"]] == ["adsb.ast", "radar.ast", str(inputs[3].resolve())]
    assert said["2"].out.replace(str(two), str(one)) == said["1"].out
    assert f"{inputs[2]}: same content as {RADAR} (SHA-256); skipped" in said["2"].err
    assert said["2"].err == said["1"].err


def test_workers_2_warnings_and_progress(tmp_path):
    """The warnings of inputs ingested in parallel come in input order, as one process says them; the
    progress bar moves over all the inputs' bytes to its end."""
    from msdc.pipeline.jobs.ingest import ingest_job
    from msdc.pipeline.jobs.options import IngestOptions

    rec = tmp_path / "midnight.ast"
    midnight_recording(rec, 3000)
    inputs = (str(RADAR), str(ADSB), str(rec))  # CAT021 only: the two radars' inputs have no record of it
    got = {}
    calls: list[tuple[int, int, str]] = []
    for workers in (1, 2):
        options = IngestOptions(inputs=inputs, dataset=str(tmp_path / f"ds{workers}"), workers=workers,
                                date=dt.date.fromisoformat(DAY), categories=(21,), chunk_mb=0.1)
        got[workers] = ingest_job(options, on_chunk=(lambda *a: calls.append(a)) if workers == 2 else None)
    no_record = [w for w in got[2].warnings if "no record of CAT021 decoded" in w]
    assert [w.split(":")[0] for w in no_record] == [str(RADAR), str(rec)]
    assert got[2].warnings == got[1].warnings
    total = RADAR.stat().st_size + ADSB.stat().st_size + rec.stat().st_size
    assert calls and calls[-1][:2] == (total, total)
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)  # never back


def test_workers_2_a_failed_input_leaves_the_dataset_one_process_leaves(tmp_path, capsys):
    """Inputs ingested in parallel, one of them failing (a raw stream without --date, between two dated
    pcap files, the largest after it): the input before it committed, nothing of it nor of the input after
    it, the error one process says, the same exit status."""
    from container_bytes import pcap_file, udp_frame
    from live_bytes import raw_blocks

    def pcap_of(raw: Path, out: Path) -> Path:
        start_s = int(dt.datetime.fromisoformat(f"{DAY}T08:00:00+00:00").timestamp())
        blocks = raw_blocks(raw.read_bytes())
        out.write_bytes(pcap_file([(start_s + k, 0, udp_frame(b)) for k, b in enumerate(blocks)])[0])
        return out

    first, last = pcap_of(RADAR, tmp_path / "radar.pcap"), pcap_of(ADSB, tmp_path / "adsb.pcap")
    assert last.stat().st_size > first.stat().st_size > RADAR.stat().st_size
    err = {}
    for workers in ("1", "2"):
        root = tmp_path / f"ds{workers}"
        assert ingest(first, RADAR, last, "--dataset", root, "--workers", workers) == 1
        err[workers] = capsys.readouterr().err
        assert [r["file"] for r in manifest(root)["inputs"]] == ["radar.pcap"]
        assert on_disk(root) == listed_parts(root)
    assert f"{RADAR}: a raw recording carries no date: give --date" in err["2"]
    assert "Traceback" not in err["2"]
    assert err["2"] == err["1"]
    same_dataset(tmp_path / "ds1", tmp_path / "ds2")


def _run(args: list[str]) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "msdc.pipeline.cli", "ingest", *args],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _started(root: Path, proc: subprocess.Popen) -> float:
    """When the ingest made its dataset folder (its work starts: the start-up before is no interest)."""
    while not root.exists() and proc.poll() is None:
        time.sleep(0.002)
    return time.monotonic()


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    """The kill tests' command (a recording across midnight, the radar's and the ADS-B fixtures) run whole
    in a subprocess, once per --workers asked: its arguments but --dataset, its dataset, and how long its
    work took (from its dataset folder made to its end)."""
    folder = tmp_path_factory.mktemp("uninterrupted")
    rec = folder / "midnight.ast"
    midnight_recording(rec, 12000)
    runs: dict[str, tuple[list[str], Path, float]] = {}

    def run(workers: str) -> tuple[list[str], Path, float]:
        if workers not in runs:
            inputs = [str(rec), str(RADAR), str(ADSB), "--date", DAY, "--chunk-mb", "0.1", "--workers",
                      workers]
            reference = folder / f"reference{workers}"
            proc = _run([*inputs, "--dataset", str(reference)])
            start = _started(reference, proc)
            assert proc.wait(timeout=120) == 0
            runs[workers] = inputs, reference, time.monotonic() - start
        return runs[workers]

    return run


def test_a_resumed_ingest_cuts_its_inputs_as_the_whole_command_did(uninterrupted, tmp_path):
    """Three inputs on two workers are each ingested whole (one part per partition); a rerun of the same
    command after a kill that left only the last input to do writes it whole too, not in windows as a
    command of that one input would: the dataset of the uninterrupted run (seen once in the kill test below,
    when a kill fell after the first two inputs' commits)."""
    from msdc.pipeline.dataset import manifest as mf

    inputs, reference, _ = uninterrupted("2")
    resumed = tmp_path / "resumed"
    shutil.copytree(reference, resumed)
    manifest = mf.load(resumed)
    last = next(d for d, r in manifest.inputs.items() if Path(r["path"]).name == ADSB.name)
    for part in manifest.inputs.pop(last)["parts"]:  # as if killed before the last input's commit
        (resumed / part["path"]).unlink()
    mf.save(resumed, manifest)
    assert ingest(*inputs, "--dataset", str(resumed)) == 0
    same_dataset(reference, resumed)


# a kill in each third of the work for each --workers; the default run kills once per --workers, in the
# middle third with one worker and the last with two (the first third: -m validation), 4.5 s a kill here
KILLS = [pytest.param(workers, third, marks=() if (workers, third) in (("1", 1), ("2", 2))
                      else pytest.mark.validation, id=f"{workers}-third{third}")
         for workers in ("1", "2") for third in range(3)]


@pytest.mark.parametrize(("workers", "third"), KILLS)
def test_an_ingest_killed_at_any_moment_resumes_to_the_same_dataset(uninterrupted, tmp_path, workers, third):
    """SIGKILL at a random moment of the work (seeded, within the given third of it), then the same command
    again: the dataset of a run never killed, part by part and row by row, nothing else left. With two
    workers each input is ingested whole by a pool process (three inputs), and the pool's processes die
    with the main one: none goes on writing parts the rerun writes again."""
    inputs, reference, work_s = uninterrupted(workers)
    root = tmp_path / "killed"
    proc = _run([*inputs, "--dataset", str(root)])
    _started(root, proc)
    try:
        proc.wait(timeout=(third + random.Random(third).random()) / 3 * work_s)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    assert ingest(*inputs, "--dataset", root) == 0
    same_dataset(reference, root)


def test_ctrl_c_ends_a_pooled_ingest_without_a_traceback(tmp_path):
    """Ctrl-C reaches the terminal's whole process group: each pool process ended by its KeyboardInterrupt
    printed multiprocessing's traceback ("Process ForkServerProcess-2: Traceback ...", at some moments)
    and the new dataset folder was left with its lock file and partition folders. The pool's processes
    leave it to the main one (they stop at their next chunk): status 130, no traceback, no folder."""
    big = tmp_path / "big.ast"
    big.write_bytes(ADSB.read_bytes() * 20)  # long enough to be decoding when the signal comes
    root = tmp_path / "ds"
    proc = subprocess.Popen([sys.executable, "-m", "msdc.pipeline.cli", "ingest", str(big), str(RADAR),
                             "--dataset", str(root), "--date", DAY, "--chunk-mb", "0.5", "--workers", "2"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 60
        while not list(root.glob("date=*/category=*/sensor=*/.part-*.tmp")) and proc.poll() is None \
                and time.monotonic() < deadline:  # a pool process is writing
            time.sleep(0.005)
        assert proc.poll() is None, "the ingest ended before a pool process wrote"
        os.killpg(proc.pid, signal.SIGINT)  # as the terminal sends it
        out, _ = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, out
    assert "Traceback" not in out, out
    assert not root.exists(), sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def test_what_an_interrupted_ingest_left_is_removed(fixtures_dataset, tmp_path, capsys):
    """Every state a kill can leave, made by hand: a part renamed but its input not in the manifest, a part
    still under its temporary name, a temporary manifest."""
    root = tmp_path / "ds"
    shutil.copytree(fixtures_dataset, root)
    doc = manifest(root)
    adsb = doc["inputs"].pop()
    (root / "manifest.json").write_text(json.dumps(doc))  # the ADS-B input's record never written
    part = root / adsb["parts"][0]["path"]
    shutil.copy(part, part.with_name(".part-d37f30c9f33a4be7-00001.tmp"))
    stray = root / f"date={DAY}/category=048/sensor=25_201/.part-0123456789abcdef-00000.tmp"
    stray.write_bytes(b"PAR1")
    (root / ".manifest.json.tmp").write_text("{")
    capsys.readouterr()
    assert ingest(RADAR, ADSB, "--dataset", root, "--date", DAY) == 0
    assert "removed 4 file(s) an interrupted ingest left" in capsys.readouterr().err
    same_dataset(fixtures_dataset, root)


def test_an_undated_input_is_refused_and_the_inputs_before_it_stay(tmp_path, capsys):
    root = tmp_path / "ds"
    assert ingest(RADAR, "--dataset", root) == 1  # a raw stream carries no date
    err = capsys.readouterr().err
    assert f"{RADAR}: a raw recording carries no date: give --date" in err and "Traceback" not in err
    assert not root.exists()  # the folder this run made is gone: as it was
    assert ingest(RADAR, "--dataset", root, "--date", DAY) == 0
    before = on_disk(root)
    assert ingest(ADSB, "--dataset", root) == 1
    assert on_disk(root) == before == listed_parts(root)  # the radar input stays, nothing of the ADS-B one


@pytest.mark.parametrize("args,says", [
    (["--dataset", "{file}"], "is a file, not a folder"),
    (["--dataset", "{tmp}/no/such/ds"], "does not exist"),
    (["--dataset", "{tmp}/ds", "--workers", "0"], "--workers"),
])
def test_bad_options_exit_2_with_a_message(tmp_path, capsys, args, says):
    file = tmp_path / "f.txt"
    file.write_text("x")
    argv = [RADAR, "--date", DAY] + [a.format(file=file, tmp=tmp_path) for a in args]
    assert ingest(*argv) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err


def test_an_input_that_is_not_asterix_writes_nothing(tmp_path, capsys):
    junk = tmp_path / "notes.ast"
    junk.write_text("these are not data blocks at all, " * 200)
    root = tmp_path / "ds"
    assert ingest(RADAR, junk, "--dataset", root, "--date", DAY) == 1
    assert "nothing ingested" in capsys.readouterr().err
    assert not root.exists()


def test_a_stop_before_the_first_part_leaves_no_folder(tmp_path, monkeypatch):
    """An ingest stopped after it made a partition folder but before any part file was in it left the new
    dataset folder behind, with its lock and the empty partition folders (the pooled Ctrl-C test, 1 run in
    ~10 under load): the folder it made, holding no file, is removed, as when nothing was made at all."""
    import msdc.pipeline.dataset.ingest_input as step
    from msdc.pipeline.jobs import ingest

    root = tmp_path / "ds"

    def stopped(*args, **kwargs):
        (root / "date=2019-03-01" / "category=048" / "sensor=25_201").mkdir(parents=True)
        raise KeyboardInterrupt

    monkeypatch.setattr(step, "ingest_input", stopped)  # the job imports it when it runs
    with pytest.raises(KeyboardInterrupt):
        ingest.ingest_job(ingest.IngestOptions(inputs=(str(RADAR),), dataset=str(root), date=DAY))
    assert not root.exists()


def _damaged_radar(path: Path, every: int, count: int) -> list[tuple[int, int]]:
    """The radar fixture with ``count`` data blocks (every ``every``-th from the 10th) made undecodable: their
    bodies all 0xFF, an FSPEC that never ends; the (offset, length) of each, found by walking the blocks' LEN
    fields."""
    data = bytearray(RADAR.read_bytes())
    blocks, offset = [], 0
    while offset < len(data):
        length = int.from_bytes(data[offset + 1:offset + 3], "big")
        blocks.append((offset, length))
        offset += length
    damaged = blocks[10::every][:count]
    for start, length in damaged:
        data[start + 3:start + length] = b"\xff" * (length - 3)
    path.write_bytes(bytes(data))
    return damaged


@pytest.mark.parametrize("workers", ["1", "2"])
def test_blocks_skipped_as_damaged_are_said_on_stderr(tmp_path, capsys, workers):
    """Each skipped block of a damaged recording is said as msdc decode says it (file, offset, reason), the
    first 20, then how many more, their count and bytes; the manifest counts the same. Said nothing before."""
    path = tmp_path / "radar.ast"
    damaged = _damaged_radar(path, 3, 23)
    assert ingest(path, "--dataset", tmp_path / "ds", "--date", DAY, "--workers", workers, "--chunk-mb",
                  "0.1") == 0
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if line.startswith(f"msdc ingest: {path}: ")]
    reason = "an FSPEC or item runs past the end of its data block"
    assert said == [*(f"msdc ingest: {path}: offset {start}: {reason} (record at offset {start + 3})"
                      for start, _ in damaged[:20]),
                    f"msdc ingest: {path}: 3 more skipped block(s) ('msdc stats' groups them by reason)",
                    f"msdc ingest: {path}: 23 block(s) skipped ({sum(n for _, n in damaged)} bytes): their "
                    "records are not in the dataset"]
    assert manifest(tmp_path / "ds")["inputs"][0]["skipped_blocks"] == 23


def test_a_damaged_input_with_a_name_not_utf8_is_said_escaped(tmp_path, capsys):
    path = Path(os.fsdecode(tmp_path / "radar") + os.fsdecode(b"\xff.ast"))
    (start, length), = _damaged_radar(path, 1, 1)
    assert ingest(path, "--dataset", tmp_path / "ds", "--date", DAY) == 0
    err = capsys.readouterr().err
    assert f"msdc ingest: {tmp_path}/radar\\xff.ast: offset {start}: " in err
    assert f"msdc ingest: {tmp_path}/radar\\xff.ast: 1 block(s) skipped ({length} bytes)" in err
