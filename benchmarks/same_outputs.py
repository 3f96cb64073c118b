"""Same outputs: run every msdc command on two checkouts and prove that they write the same files.

Written for the package-layout refactor (top-level ``asterix`` and ``pipeline`` becoming ``msdc.asterix`` and
``msdc.pipeline``), which must not change any output: every command, run on each side in a fresh interpreter
from the checkout itself (nothing installed), must exit with the same status, print the same stdout and stderr
and write the same files, byte for byte (PNG: pixel for pixel).

    python benchmarks/same_outputs.py --baseline 88b6dc3~1   # before the msdc layout, against this checkout
    python benchmarks/same_outputs.py --baseline main --candidate ../wt-rename --work /tmp/same
    python benchmarks/same_outputs.py --baseline HEAD --only track-3h-one,stats-fixtures   # HEAD against HEAD
    python benchmarks/same_outputs.py --list                    # the cases and their command lines

Baseline: ``git worktree add --detach`` of REV into the work folder (reused when present). Candidate: a
checkout directory, by default the repository this script lives in. A checkout whose root holds an
``__init__.py`` is loaded as package ``msdc`` (``msdc.pipeline.cli.main``), any other as top-level packages
(``pipeline.cli.main``); the checkout is also first on ``sys.path`` (the simulator, ``fixtures``, imports from
there) and is the working directory, so ``fixtures/radar.ast`` means each side's own copy of the bundled
fixtures. A side that imports msdc modules from anywhere but its checkout (the editable install of another
checkout, or top-level ``asterix``/``pipeline`` modules in the ``msdc`` layout) fails its case.

Inputs: the bundled fixtures (``fixtures/radar.ast``, ``fixtures/adsb.ast``, ``fixtures/sensors.toml``,
dated 2019-03-01) and the 3 h benchmark recording (3 h, 16 aircraft, 2 radars, seed 2019:
``benchmarks/pipeline.py``'s default scenario), built once by the candidate's ``benchmarks/pipeline.py``
``build()`` into ``WORK/recording-3h`` and reused while its ``scenario.txt`` names the same scenario. Both
sides read the same recording files by the same absolute path.

Outputs: each run writes into ``WORK/stage/CASE``, the same folder for both sides, so the output paths that
a command echoes (on stdout and stderr, in the JSON ``command`` and the workbooks' Parameters sheet) are the
same on both sides and need no normalisation; the folder is then moved to ``WORK/runs/SIDE/CASE/out``, beside
the run's ``stdout.txt``, ``stderr.txt``, ``exit_code`` and ``child.json`` (the modules the side loaded). The
two sides of a case run one after the other, never at the same time. numba caches its compiled kernels in
``WORK/numba-cache/SIDE-LAYOUT``, not in the checkouts: a kernel cached by the other layout of the same file
would import its module by the old name (``asterix.kernel``) and fail the case. A side's first runs in a new
work folder therefore include numba's compilation (30-50 s in all).

Comparison: the same relative file names on both sides, then every file's bytes. Where the bytes differ:

- PNG: the decoded images are compared (mode, size, pixels).
- xlsx: the zip members are compared by name and order, compression method and content (a PNG member by
  pixels if its bytes differ), after the normalisations below; the members' zip timestamps are not compared.
- Parquet, CSV and any other file: no normalisation; the report says what differs.

Normalisations, the only ones: each replaces a value that differs between two runs of the same code on the
same inputs, never anything else (HEAD against HEAD needs 1-3; nothing else varied from run to run: PNG,
Parquet and CSV files came out byte-identical, with Python's hash seed drawn afresh in every run):

1. JSON files: the values of the keys ``"run_utc"`` (the run's wall-clock time, to the second) and
   ``"run_time_s"`` (its elapsed seconds), wherever they occur; the rest of the text compares as it is.
2. xlsx worksheets: the value cell that follows a key cell reading ``run_utc`` or ``run_time_s`` (the same two
   values, on the Parameters sheet).
3. xlsx ``docProps/core.xml``: the ``dcterms:created`` and ``dcterms:modified`` timestamps (openpyxl stamps
   the time the workbook was made and saved). The zip entries' own timestamps (the time of writing) are not
   compared at all (see xlsx above).
4. stdout and stderr: each side's checkout directory is replaced by ``<checkout>`` (the sides run from
   different directories; the fixtures are given relative to it, so it rarely appears).

Every accepted normalisation that changed something is listed under the table. The script exits 1 when any
case differs (or a side loaded foreign modules), 0 when every case is identical.

On the 2-core machine under other work (load 2-5, 2026-11-28), one side's 37 cases took 120-190 s with
numba's cache warm and up to 260 s in a new work folder. a042c8b (before the msdc layout) against 029af14,
and 029af14 against itself: 37 of 37 identical.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

SCRIPT = Path(__file__).resolve()
ROOT = SCRIPT.parents[1]
DATE = "2019-03-01"
HOURS, AIRCRAFT, RADARS, SEED = 3.0, 16, 2, 2019  # benchmarks/pipeline.py's default scenario
RECORDING_KEY = f"{HOURS:g} h, {AIRCRAFT} aircraft, {RADARS} radars, seed {SEED}"  # its scenario.txt
RECORDING_FILES = ("radar1.ast", "radar2.ast", "adsb.ast")
MSDC_TOPS = ("msdc", "asterix", "pipeline", "fixtures")
WORK = Path(tempfile.gettempdir()) / "msdc-same-outputs"

FIX = ("fixtures/radar.ast", "fixtures/adsb.ast", "--sensors", "fixtures/sensors.toml", "--date", DATE)
COMMANDS = ("decode", "stats", "correlate", "quality", "track", "conflicts")
REC = ("{rec}/radar1.ast", "{rec}/radar2.ast", "{rec}/adsb.ast", "--sensors", "{rec}/sensors.toml",
       "--date", DATE)


@dataclass(frozen=True)
class Case:
    """One command line; ``{out}`` stands for the run's output folder, ``{rec}`` for the 3 h recording's."""

    name: str
    argv: tuple[str, ...]

    @property
    def recording(self) -> bool:
        """Whether the case reads the 3 h recording."""
        return any("{rec}" in a for a in self.argv)


def _case(name: str, *argv: str) -> Case:
    """A case from its name and command line."""
    return Case(name, argv)


CASES: tuple[Case, ...] = (
    _case("version", "--version"),
    _case("help", "--help"),
    *(_case(f"help-{command}", command, "--help") for command in COMMANDS),
    # decode
    _case("decode-csv-two-categories", "decode", "fixtures/radar.ast", "fixtures/adsb.ast", "--date", DATE,
          "-o", "{out}/decoded.csv"),
    _case("decode-parquet-two-categories", "decode", "fixtures/radar.ast", "fixtures/adsb.ast",
          "--date", DATE, "-o", "{out}/decoded.parquet"),
    _case("decode-csv-cat48-undated", "decode", "fixtures/radar.ast", "fixtures/adsb.ast", "--category", "48",
          "-o", "{out}/radar.csv"),
    _case("decode-parquet-edition-pins", "decode", "fixtures/radar.ast", "fixtures/adsb.ast", "--edition",
          "48=1.27", "--edition", "21=2.4", "--strict", "--chunk-mb", "1", "--date", DATE,
          "-o", "{out}/pinned.parquet"),
    _case("decode-edition-auto", "decode", "fixtures/adsb.ast", "--edition", "21=auto",
          "-o", "{out}/adsb.csv"),
    _case("decode-no-output", "decode", "fixtures/radar.ast", "fixtures/adsb.ast"),
    _case("decode-wrong-edition", "decode", "fixtures/adsb.ast", "--edition", "21=0.26", "-o", "{out}/x.csv"),
    _case("decode-missing-input", "decode", "fixtures/missing.ast", "-o", "{out}/x.csv"),
    # stats
    _case("stats-fixtures", "stats", "fixtures/radar.ast", "fixtures/adsb.ast", "--date", DATE),
    _case("stats-undated-chunks", "stats", "fixtures/radar.ast", "fixtures/adsb.ast", "--chunk-mb", "1"),
    # correlate
    _case("correlate-callsign", "correlate", *FIX, "--callsign", "MAS72", "-o", "{out}/report.xlsx",
          "--json", "{out}/summary.json"),
    _case("correlate-all-quality", "correlate", *FIX, "--all", "--quality", "-o", "{out}/report.xlsx",
          "--json", "{out}/summary.json"),
    _case("correlate-filters-parquet", "correlate", *FIX, "--all", "--drop-jumps", "--min-nacp", "8",
          "--slot", "5", "--gap", "120", "--tables", "parquet", "-o", "{out}/report.xlsx",
          "--json", "{out}/summary.json"),
    _case("correlate-address-predict", "correlate", *FIX, "--address", "750312", "--fill", "predict",
          "--json", "{out}/summary.json"),
    # quality
    _case("quality-all", "quality", *FIX, "--all", "-o", "{out}/quality.xlsx", "--json", "{out}/q.json"),
    _case("quality-reference-track", "quality", *FIX, "--callsign", "MAS72", "--reference", "track",
          "--gap", "60", "-o", "{out}/quality.xlsx", "--json", "{out}/q.json"),
    _case("quality-adsb-only", "quality", "fixtures/adsb.ast", "--date", DATE, "--all",
          "--json", "{out}/q.json"),
    # track
    _case("track-callsign-figures", "track", *FIX, "--callsign", "SIA305", "-o", "{out}/tracks.parquet",
          "--json", "{out}/tracks.json", "--figures", "{out}/figs"),
    _case("track-all-smooth-csv", "track", *FIX, "--all", "--noise", "estimate", "--smooth", "--step", "5",
          "-o", "{out}/tracks.csv", "--json", "{out}/tracks.json"),
    _case("track-declared-imm-smoother", "track", *FIX, "--address", "750B1E", "--noise", "declared",
          "--smoother", "imm", "--tpm", "dynamic", "-o", "{out}/tracks.parquet"),
    _case("track-adsb-timing", "track", *FIX, "--all", "--sources", "adsb", "--noise", "timing",
          "--step", "10", "--json", "{out}/tracks.json"),
    # conflicts
    _case("conflicts-csv", "conflicts", *FIX, "--step", "5", "-o", "{out}/conflicts.csv",
          "--json", "{out}/conflicts.json"),
    _case("conflicts-xlsx-figures", "conflicts", *FIX, "--step", "5", "--radius-nm", "40", "--vertical-ft",
          "30000", "--horizon", "60", "-o", "{out}/conflicts.xlsx", "--json", "{out}/conflicts.json",
          "--figures", "{out}/figs"),
    _case("conflicts-csv-alerts-gaussian", "conflicts", *FIX, "--step", "5", "--radius-nm", "40",
          "--vertical-ft", "30000", "--horizon", "20,120", "--vertical", "gaussian", "--method", "midpoint",
          "--surface", "include", "-o", "{out}/conflicts.csv"),
    # the 3 h benchmark recording
    _case("stats-3h", "stats", *REC[:3], "--date", DATE),
    _case("correlate-3h-all", "correlate", *REC, "--all", "-o", "{out}/report.xlsx", "--json",
          "{out}/summary.json"),
    _case("correlate-3h-pairs-all", "correlate", *REC, "--all", "--pairs", "all",
          "--json", "{out}/summary.json"),
    _case("quality-3h-all", "quality", *REC, "--all", "-o", "{out}/quality.xlsx", "--json", "{out}/q.json"),
    _case("track-3h-one", "track", *REC, "--callsign", "TST0003", "-o", "{out}/tracks.parquet", "--json",
          "{out}/tracks.json", "--figures", "{out}/figs"),
)


# ---------------------------------------------------------------------------------------------------------
# The child: one command in a fresh interpreter, from a checkout, nothing installed


def _layout(checkout: Path) -> str:
    """``msdc`` when the checkout root is the package (it has an ``__init__.py``), ``flat`` otherwise."""
    return "msdc" if (checkout / "__init__.py").exists() else "flat"


def _import_checkout(checkout: Path) -> str:
    """Make the checkout importable: first on sys.path, and package ``msdc`` loaded from its root in that
    layout. Returns the layout."""
    sys.path.insert(0, str(checkout))
    layout = _layout(checkout)
    if layout == "msdc":
        spec = importlib.util.spec_from_file_location("msdc", checkout / "__init__.py",
                                                      submodule_search_locations=[str(checkout)])
        assert spec is not None and spec.loader is not None
        package = importlib.util.module_from_spec(spec)
        sys.modules["msdc"] = package
        spec.loader.exec_module(package)
    return layout


def _foreign_modules(checkout: Path, layout: str) -> list[str]:
    """msdc modules loaded from outside the checkout, and top-level ``asterix``/``pipeline`` modules in the
    msdc layout (which an installed ``msdc`` would not have)."""
    found = []
    for name, module in sorted(sys.modules.items()):
        top = name.split(".")[0]
        if top not in MSDC_TOPS:
            continue
        file = getattr(module, "__file__", None)
        if layout == "msdc" and top in ("asterix", "pipeline"):
            found.append(f"{name} (top-level import in the msdc layout, from {file})")
        elif file and not Path(file).resolve().is_relative_to(checkout):
            found.append(f"{name} from {file}")
    return found


def child_run(checkout: Path, sidecar: Path, argv: list[str]) -> None:
    """Run ``main(argv)`` of the checkout's CLI and exit with its status; write what was loaded to sidecar."""
    layout = _import_checkout(checkout)
    status: int | str | None = "no status (exception)"
    cli: ModuleType | None = None
    try:
        cli = importlib.import_module("msdc.pipeline.cli" if layout == "msdc" else "pipeline.cli")
        sys.argv = ["msdc", *argv]  # the jobs record " ".join(sys.argv[1:]) as the command
        status = cli.main(argv)
    except SystemExit as exc:  # argparse: --help, --version, usage errors
        status = exc.code
        raise
    finally:
        sidecar.write_text(json.dumps({"layout": layout, "cli": getattr(cli, "__file__", None),
                                       "status": status, "foreign": _foreign_modules(checkout, layout)},
                                      indent=1))
    sys.stdout.flush()
    sys.stderr.flush()
    raise SystemExit(status)


def child_build(checkout: Path, out: Path) -> None:
    """Write the 3 h recording into ``out`` with the checkout's own ``benchmarks/pipeline.py`` build()."""
    _import_checkout(checkout)
    path = checkout / "benchmarks" / "pipeline.py"
    spec = importlib.util.spec_from_file_location("msdc_bench_pipeline", path)
    assert spec is not None and spec.loader is not None
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    bench.build(out, HOURS, AIRCRAFT, RADARS, SEED)


# ---------------------------------------------------------------------------------------------------------
# Running the sides


@dataclass(frozen=True)
class Side:
    """A checkout under test: ``baseline`` or ``candidate``."""

    name: str
    checkout: Path


@dataclass
class Run:
    """What one side's run of one case left behind."""

    folder: Path
    status: int
    stdout: bytes
    stderr: bytes
    wall_s: float
    foreign: list[str] = field(default_factory=list)

    @property
    def out(self) -> Path:
        """The folder holding the files the command wrote."""
        return self.folder / "out"


def _child_env(work: Path, tag: str) -> dict[str, str]:
    """The environment of a side's interpreter: ours without PYTHONPATH (the checkout decides the imports),
    numba's cache in ``WORK/numba-cache/TAG`` (see the docstring)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["NUMBA_CACHE_DIR"] = str(work / "numba-cache" / tag)
    return env


def _git(*args: str, cwd: Path = ROOT) -> str:
    """``git ARGS`` in ``cwd``: its stdout, stripped; CalledProcessError when it fails."""
    return subprocess.run(["git", *args], cwd=cwd, check=True, capture_output=True, text=True).stdout.strip()


def _describe(checkout: Path) -> str:
    """The checkout's commit, with ``+changes`` when its working tree differs from it."""
    try:
        head = _git("rev-parse", "--short", "HEAD", cwd=checkout)
        dirty = _git("status", "--porcelain", "--untracked-files=no", cwd=checkout)
    except (subprocess.CalledProcessError, OSError):
        return "not a git checkout"
    return head + (" +changes" if dirty else "")


def baseline_checkout(rev: str, work: Path) -> Path:
    """A detached worktree of ``rev`` in the work folder, added once and reused."""
    sha = _git("rev-parse", "--verify", f"{rev}^{{commit}}")
    path = work / f"baseline-{sha[:12]}"
    if path.exists():
        if _git("rev-parse", "HEAD", cwd=path) != sha:
            raise SystemExit(f"{path} exists but is not a checkout of {sha}: remove it (git worktree remove)")
        return path
    _git("worktree", "add", "--detach", str(path), sha)
    return path


def recording(candidate: Path, work: Path) -> Path:
    """The 3 h benchmark recording, built by the candidate's benchmarks/pipeline.py once and cached."""
    out = work / "recording-3h"
    tag = out / "scenario.txt"
    if tag.exists() and tag.read_text() == RECORDING_KEY and all((out / n).exists() for n in RECORDING_FILES):
        return out
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-P", str(SCRIPT), "--child", "build", str(candidate), str(out)],
                   cwd=candidate, env=_child_env(work, f"recording-{_layout(candidate)}"), check=True)
    tag.write_text(RECORDING_KEY)
    print(f"built the 3 h recording ({RECORDING_KEY}) in {out}: {time.perf_counter() - t0:.1f} s", flush=True)
    return out


def run_case(case: Case, side: Side, work: Path, rec: Path | None) -> Run:
    """Run the case on one side in a fresh interpreter; move its outputs to WORK/runs/SIDE/CASE/out."""
    stage = work / "stage" / case.name
    folder = work / "runs" / side.name / case.name
    for path in (stage, folder):
        shutil.rmtree(path, ignore_errors=True)
        path.mkdir(parents=True)
    argv = [a.replace("{out}", str(stage)).replace("{rec}", str(rec)) for a in case.argv]
    sidecar = folder / "child.json"
    cmd = [sys.executable, "-P", str(SCRIPT), "--child", "run", str(side.checkout), str(sidecar), "--", *argv]
    t0 = time.perf_counter()
    env = _child_env(work, f"{side.name}-{_layout(side.checkout)}")
    done = subprocess.run(cmd, cwd=side.checkout, env=env, capture_output=True)
    wall = time.perf_counter() - t0
    shutil.move(stage, folder / "out")
    (folder / "stdout.txt").write_bytes(done.stdout)
    (folder / "stderr.txt").write_bytes(done.stderr)
    (folder / "exit_code").write_text(f"{done.returncode}\n")
    foreign = json.loads(sidecar.read_text())["foreign"] if sidecar.exists() else ["(no child record)"]
    return Run(folder, done.returncode, done.stdout, done.stderr, wall, foreign)


# ---------------------------------------------------------------------------------------------------------
# Comparing


@dataclass
class Verdict:
    """One case's comparison: files compared, what differs (the first entry is the one reported)."""

    files: int = 0
    problems: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def identical(self) -> bool:
        """No difference was found."""
        return not self.problems


def _first_line_diff(a: bytes, b: bytes) -> str:
    """Where two texts first differ: line and column, and both lines from a little before that column."""
    la, lb = a.splitlines(), b.splitlines()
    for i, (x, y) in enumerate(zip(la, lb, strict=False), 1):
        if x != y:
            col = next((k for k, (p, q) in enumerate(zip(x, y, strict=False)) if p != q), min(len(x), len(y)))
            start = max(0, col - 20)
            return f"line {i} col {col + 1}: {_short(x[start:])} vs {_short(y[start:])}"
    return f"{len(la)} vs {len(lb)} lines" if len(la) != len(lb) else "line endings differ"


def _short(raw: bytes, width: int = 60) -> str:
    """A line as text, cut at ``width`` characters, quoted."""
    text = raw.decode("utf-8", "replace")
    return repr(text if len(text) <= width else text[:width] + "...")


def same_pixels(a: bytes, b: bytes) -> str | None:
    """None when two PNGs decode to the same image, else how they differ (pixels that differ, their box)."""
    import numpy as np
    from PIL import Image

    ia, ib = Image.open(io.BytesIO(a)), Image.open(io.BytesIO(b))
    if (ia.mode, ia.size) != (ib.mode, ib.size):
        return f"image {ia.mode} {ia.size} vs {ib.mode} {ib.size}"
    if ia.tobytes() == ib.tobytes():
        return None
    pa, pb = np.asarray(ia), np.asarray(ib)
    differ = (pa != pb).reshape(pa.shape[0], pa.shape[1], -1).any(axis=2)
    rows, cols = np.nonzero(differ)
    return (f"{differ.sum()} of {differ.size} pixels differ, in x {cols.min()}-{cols.max()}, "
            f"y {rows.min()}-{rows.max()}")


JSON_RUN_KEYS = re.compile(rb'("(?:run_utc|run_time_s)":\s*)("[^"]*"|[-+0-9.eE]+|null)')
SHEET_RUN_CELLS = re.compile(
    rb'(<c r="[A-Z]+[0-9]+"[^>]*><is><t>(?:run_utc|run_time_s)</t></is></c><c r="[A-Z]+[0-9]+"[^>]*>)'
    rb'(<v>[^<]*</v>|<is><t[^>]*>[^<]*</t></is>)(?=</c>)')
TAG_BREAK = b">\n<"
CORE_TIMES = re.compile(rb"(<dcterms:(created|modified)[^>]*>)[^<]*(</dcterms:\2>)")


def normalise_json(text: bytes) -> bytes:
    """The values of "run_utc" and "run_time_s" replaced (normalisation 1)."""
    return JSON_RUN_KEYS.sub(rb'\1"<run-dependent>"', text)


def normalise_member(name: str, data: bytes) -> bytes:
    """An xlsx member with its run-dependent values replaced (normalisations 2 and 3); others unchanged."""
    if name == "docProps/core.xml":
        return CORE_TIMES.sub(rb"\1<run-dependent>\3", data)
    if name.startswith("xl/worksheets/") and name.endswith(".xml"):
        return SHEET_RUN_CELLS.sub(rb"\1<v>run-dependent</v>", data)
    return data


def compare_xlsx(a: bytes, b: bytes) -> tuple[str | None, list[str]]:
    """Compare two workbooks member by member: (the first difference or None, normalisations that applied)."""
    za, zb = zipfile.ZipFile(io.BytesIO(a)), zipfile.ZipFile(io.BytesIO(b))
    na, nb = za.namelist(), zb.namelist()
    if na != nb:
        only = sorted(set(na) ^ set(nb))
        return (f"zip members differ: {only[:3]}" if only else "zip member order differs"), []
    notes = []
    for name in na:
        ia, ib = za.getinfo(name), zb.getinfo(name)
        if ia.compress_type != ib.compress_type:
            return f"{name}: compression {ia.compress_type} vs {ib.compress_type}", []
        da, db = za.read(name), zb.read(name)
        if da == db:
            continue
        if name.lower().endswith(".png"):
            why = same_pixels(da, db)
            if why:
                return f"{name}: {why}", []
            notes.append(f"{name}: PNG bytes differ, pixels identical")
            continue
        ma, mb = normalise_member(name, da), normalise_member(name, db)
        if ma != mb:  # XML parts are one line: break them between elements to say where
            return f"{name}: {_first_line_diff(*(m.replace(b'><', TAG_BREAK) for m in (ma, mb)))}", []
        notes.append(f"{name}: run-dependent values normalised")
    return None, notes


def compare_parquet(a: Path, b: Path) -> str:
    """How two Parquet files with different bytes differ (schema, metadata or data); never accepted."""
    import pyarrow.parquet as pq

    ta, tb = pq.read_table(a), pq.read_table(b)
    if ta.schema.metadata != tb.schema.metadata:
        keys = sorted(k.decode() for k in set(ta.schema.metadata or {}) | set(tb.schema.metadata or {})
                      if (ta.schema.metadata or {}).get(k) != (tb.schema.metadata or {}).get(k))
        return f"Parquet key-value metadata differs: {keys}"
    if not ta.schema.equals(tb.schema):
        return "Parquet schema differs"
    for column in ta.column_names:
        if not ta[column].equals(tb[column]):
            return f"Parquet column {column!r} differs"
    return "Parquet bytes differ (same schema, metadata and data: row groups or encoding)"


def compare_file(rel: str, a: Path, b: Path) -> tuple[str | None, list[str]]:
    """Compare one output file of both sides: (the difference or None, normalisations that applied)."""
    da, db = a.read_bytes(), b.read_bytes()
    if da == db:
        return None, []
    suffix = a.suffix.lower()
    if suffix == ".png":
        why = same_pixels(da, db)
        return (f"{rel}: {why}", []) if why else (None, [f"{rel}: PNG bytes differ, pixels identical"])
    if suffix == ".xlsx":
        why, notes = compare_xlsx(da, db)
        return (f"{rel}: {why}", []) if why else (None, [f"{rel}: {n}" for n in notes])
    if suffix == ".json":
        na, nb = normalise_json(da), normalise_json(db)
        if na == nb:
            return None, [f"{rel}: run_utc/run_time_s normalised"]
        return f"{rel}: {_first_line_diff(na, nb)}", []
    if suffix == ".parquet":
        return f"{rel}: {compare_parquet(a, b)}", []
    return f"{rel}: {_first_line_diff(da, db)}", []


def _files(folder: Path) -> set[str]:
    """Every file under ``folder``, as a relative POSIX path."""
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}


def _stream(raw: bytes, side: Side) -> bytes:
    """stdout or stderr with the side's checkout directory replaced (normalisation 4)."""
    return raw.replace(str(side.checkout).encode(), b"<checkout>")


def compare(base: Run, cand: Run, sides: tuple[Side, Side]) -> Verdict:
    """Compare both sides' runs of a case: modules loaded, exit status, stdout, stderr, then every file."""
    verdict = Verdict()
    for side, run in zip(sides, (base, cand), strict=True):
        if run.foreign:
            verdict.problems.append(f"{side.name} loaded {len(run.foreign)} module(s) it should not: "
                                    f"{run.foreign[0]}" + (", ..." if len(run.foreign) > 1 else ""))
    if base.status != cand.status:
        verdict.problems.append(f"exit status {base.status} vs {cand.status}")
    for stream in ("stdout", "stderr"):
        sa, sb = _stream(getattr(base, stream), sides[0]), _stream(getattr(cand, stream), sides[1])
        if sa != sb:
            verdict.problems.append(f"{stream}: {_first_line_diff(sa, sb)}")
        elif sa != getattr(base, stream) or sb != getattr(cand, stream):
            verdict.notes.append(f"{stream}: checkout directory replaced")
    fa, fb = _files(base.out), _files(cand.out)
    if fa != fb:
        verdict.problems.append(f"files only in baseline {sorted(fa - fb)[:3]}, only in candidate "
                                f"{sorted(fb - fa)[:3]}")
    verdict.files = len(fa & fb)
    for rel in sorted(fa & fb):
        why, notes = compare_file(rel, base.out / rel, cand.out / rel)
        if why:
            verdict.problems.append(why)
        verdict.notes.extend(notes)
    return verdict


# ---------------------------------------------------------------------------------------------------------
# Main


def _selected(only: str | None) -> list[Case]:
    """The cases named by --only (all when None); an unknown name is refused."""
    if not only:
        return list(CASES)
    names = [n.strip() for n in only.split(",") if n.strip()]
    known = {c.name: c for c in CASES}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise SystemExit(f"--only: unknown case(s) {unknown}; --list shows them")
    return [known[n] for n in names]


def _table(rows: list[tuple[Case, Run, Run, Verdict]]) -> str:
    """The result table: case, files compared, wall time of each side, identical or the first difference."""
    width = max(len(c.name) for c, *_ in rows)
    lines = [f"{'case':{width}s}  files  baseline  candidate  result", "-" * (width + 60)]
    for case, base, cand, verdict in rows:
        result = "identical" if verdict.identical else f"DIFFERS: {verdict.problems[0]}"
        result = result if len(result) <= 100 else result[:97] + "..."
        more = f" (+{len(verdict.problems) - 1} more)" if len(verdict.problems) > 1 else ""
        lines.append(f"{case.name:{width}s}  {verdict.files:5d}  {base.wall_s:7.1f}s  {cand.wall_s:8.1f}s  "
                     f"{result}{more}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Run the selected cases on both sides, one side at a time, print the table; 1 if any case differs."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", metavar="REV", help="git revision to compare against (a detached worktree)")
    ap.add_argument("--candidate", type=Path, default=ROOT, metavar="DIR",
                    help=f"checkout under test (default: this repository, {ROOT})")
    ap.add_argument("--work", type=Path, default=WORK, metavar="DIR",
                    help="work folder: baseline worktree, 3 h recording, runs (default: %(default)s)")
    ap.add_argument("--only", metavar="NAME,...", help="run only these cases")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    args = ap.parse_args(argv)
    cases = _selected(args.only)
    if args.list:
        for case in cases:
            print(f"{case.name:32s} msdc {' '.join(case.argv)}")
        return 0
    if not args.baseline:
        ap.error("--baseline REV is required")
    work = args.work.resolve()
    work.mkdir(parents=True, exist_ok=True)
    candidate = args.candidate.resolve()
    sides = (Side("baseline", baseline_checkout(args.baseline, work)), Side("candidate", candidate))
    for side in sides:
        print(f"{side.name}: {side.checkout} ({_layout(side.checkout)} layout, {_describe(side.checkout)})",
              flush=True)
    rec = recording(candidate, work) if any(c.recording for c in cases) else None
    rows = []
    for case in cases:
        runs = [run_case(case, side, work, rec) for side in sides]
        verdict = compare(runs[0], runs[1], sides)
        print(f"{case.name:32s} baseline {runs[0].wall_s:6.1f} s (exit {runs[0].status})  candidate "
              f"{runs[1].wall_s:6.1f} s (exit {runs[1].status})  {verdict.files} files  "
              f"{'identical' if verdict.identical else 'DIFFERS'}", flush=True)
        rows.append((case, runs[0], runs[1], verdict))
    print()
    print(_table(rows))
    total = [sum(r[i].wall_s for r in rows) for i in (1, 2)]
    print(f"\nwall time: baseline {total[0]:.1f} s, candidate {total[1]:.1f} s, {len(rows)} cases; runs in "
          f"{work / 'runs'}")
    notes = [(c.name, n) for c, _, _, v in rows for n in v.notes]
    if notes:
        print("\nnormalised (run-dependent values, see the docstring):")
        for name, note in notes:
            print(f"  {name}: {note}")
    failed = [r for r in rows if not r[3].identical]
    for case, _, _, verdict in failed:
        print(f"\n{case.name} differs:\n  " + "\n  ".join(verdict.problems))
    print(f"\n{len(rows) - len(failed)} of {len(rows)} cases identical" + (", some DIFFER" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--child"]:
        if sys.argv[2] == "run":
            child_run(Path(sys.argv[3]), Path(sys.argv[4]), sys.argv[6:])
        else:
            child_build(Path(sys.argv[3]), Path(sys.argv[4]))
    else:
        sys.exit(main())
