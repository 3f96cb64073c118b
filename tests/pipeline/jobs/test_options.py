"""Each option declared once (pipeline.jobs.options): the argparse parser, the options objects a command line
makes, the declared range and choice checks and the docs tables all come from the options dataclasses.
Checked against expectations written out here, not derived from the declarations."""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import math
import subprocess
import sys
from pathlib import Path

import pytest

from msdc.pipeline.cli import build_parser
from msdc.pipeline.jobs import options as opts
from msdc.pipeline.jobs.options import (
    COMMAND_OPTIONS,
    ConflictOptions,
    CorrelateOptions,
    DecodeOptions,
    OptionError,
    QualityOptions,
    StatsOptions,
    TrackOptions,
    check_declared,
    declared,
    from_args,
)

ROOT = Path(__file__).resolve().parents[3]
# the report selection every command takes (pipeline.model.report_selection)
READING = {"--edition": "editions", "--date": "date", "--format": "format", "--from": "from_time",
           "--to": "to_time", "--area": "area", "--fl": "fl", "--sensor": "sensor_ids"}
SELECTION = {"--sensors": "sensors", "--callsign": "callsign", "--address": "address",
             "--all": "all_aircraft"}
# the commands that read a dataset instead of INPUT files, and run their work on a Dask cluster
DATASET = {"--dataset": "dataset", "--scheduler": "scheduler", "--workers": "workers"}
TRACKING = {"--figures": "figures", "--figures-limit": "figures_limit", "--figures-only": "figures_only",
            "--step": "step_s", "--max-coast": "max_coast_s", "--tpm": "tpm",
            "--sources": "sources", "--noise": "noise"}

# every option of each command: flag -> the options field it fills ("INPUT": the positional argument)
EXPECTED = {
    "decode": {"INPUT": "inputs", "--output": "output", "--category": "categories", "--strict": "strict",
               "--lenient": "lenient",
               "--chunk-mb": "chunk_mb", "--sensors": "sensors", **READING},
    "stats": {"INPUT": "inputs", "--chunk-mb": "chunk_mb", "--sensors": "sensors", **READING, **DATASET},
    "correlate": {"INPUT": "inputs", **SELECTION, "--output": "output", "--json": "json", "--slot": "slot_s",
                  "--gap": "gap_s", "--pairs": "pairs", "--split-adsb": "split_adsb", "--quality": "quality",
                  "--drop-jumps": "drop_jumps", "--min-nic": "min_nic", "--min-nacp": "min_nacp",
                  "--fill": "fill", "--tables": "tables", "--adsb-sigma": "adsb_sigma_m",
                  **READING, **DATASET},
    "quality": {"INPUT": "inputs", **SELECTION, "--output": "output", "--json": "json", "--gap": "gap_s",
                "--reference": "reference", "--drop-jumps": "drop_jumps", "--min-nic": "min_nic",
                "--min-nacp": "min_nacp", "--adsb-sigma": "adsb_sigma_m", **READING, **DATASET},
    "track": {"INPUT": "inputs", **SELECTION, "--output": "output", "--json": "json", **TRACKING,
              "--smooth": "smooth", "--smoother": "smoother", "--adsb-sigma": "adsb_sigma_m",
              **READING, **DATASET},
    "conflicts": {"INPUT": "inputs", "--sensors": "sensors", "--output": "output", "--json": "json",
                  "--horizon": "horizons_s", "--radius-nm": "radius_nm", "--vertical-ft": "vertical_ft",
                  "--vertical-tolerance-ft": "vertical_tolerance_ft", "--threshold": "threshold",
                  "--method": "method", "--vertical": "vertical", "--surface": "surface", **TRACKING,
                  "--adsb-sigma": "adsb_sigma_m", "--max-report-gap": "max_report_gap_s",
                  "--min-fl": "min_fl", "--exclude-mode-a-only": "exclude_mode_a_only",
                  "--exclude-codes": "exclude_codes",
                  **READING, **DATASET},
    "evaluate": {"INPUT": "inputs", "--sensors": "sensors", "--preset": "preset", "--sectors": "sectors",
                 "--reference": "reference", "--reference-file": "reference_file", "--test": "test_sensors",
                 "--drop-jumps": "drop_jumps", "--min-nic": "min_nic", "--min-nacp": "min_nacp",
                 "--min-sil": "min_sil", "--output": "output", "--json": "json", "--html": "html",
                 "--window": "window_minutes",
                 "--adsb-sigma": "adsb_sigma_m", **READING, **DATASET},
    "ingest": {"INPUT": "inputs", "--dataset": "dataset", "--workers": "workers", "--category": "categories",
               "--lenient": "lenient", "--chunk-mb": "chunk_mb", "--edition": "editions", "--date": "date",
               "--format": "format"},
    "sql": {"SQL": "query", "--dataset": "dataset", "--output": "output", "--limit": "limit"},
    "listen": {"--udp": "udp", "--iface": "iface", "--sensors": "sensors", "--record": "record",
               "--rotate": "rotate", "--http": "http", "--alarm-silent": "alarm_silent_s",
               "--alarm-min-pd": "alarm_min_pd", "--alarm-min-mode3a-valid": "alarm_min_mode3a_valid",
               "--alarm-min-modec-valid": "alarm_min_modec_valid", "--window": "window_s", "--queue": "queue",
               "--duration": "duration_s", "--edition": "editions", "--dataset": "dataset"},
    "replay": {"RECORDING": "inputs", "--to": "to", "--iface": "iface", "--ttl": "ttl", "--speed": "speed",
               "--loop": "loop", "--duration": "duration_s", "--format": "format"},
}
PAGES = {"listen": "live", "replay": "live"}  # the guide page of a command not on COMMAND.md


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def _parser_options(parser: argparse.ArgumentParser) -> dict[str, str]:
    """flag (the long one; the metavar of a positional) -> the namespace name it fills, but -h."""
    out = {}
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        name = action.option_strings[-1] if action.option_strings else action.metavar
        out[name] = action.dest
    return out


def test_every_command_is_declared():
    assert list(_subparsers()) == list(COMMAND_OPTIONS) == list(EXPECTED)


@pytest.mark.parametrize("command", list(EXPECTED))
def test_the_parser_has_each_declared_option_and_no_other(command):
    """Each argparse option fills the field of its name; each declared field is an option of its command."""
    parser = _subparsers()[command]
    assert _parser_options(parser) == EXPECTED[command]
    fields = {spec.name or "INPUT": f.name for f, spec, _ in declared(COMMAND_OPTIONS[command])}
    assert fields == EXPECTED[command]


def test_inherited_options_are_redeclared_where_they_differ():
    """correlate requires --sensors, quality does not; conflicts' --noise defaults to declared, track's to
    estimate; conflicts keeps track's --max-coast as declared there."""
    sensors = {cmd: [a for a in _subparsers()[cmd]._actions if a.dest == "sensors"] for cmd in EXPECTED}
    assert sensors["correlate"][0].required and not sensors["quality"][0].required
    assert "needed when radar plots are used" in sensors["quality"][0].help
    for cmd in ("decode", "stats"):  # only --area reads it there
        assert not sensors[cmd][0].required and "--area" in sensors[cmd][0].help
    assert TrackOptions().noise == "estimate" and ConflictOptions().noise == "declared"
    assert ConflictOptions().all_aircraft and not TrackOptions().all_aircraft
    assert TrackOptions.__dataclass_fields__["max_coast_s"] is ConflictOptions.__dataclass_fields__[
        "max_coast_s"]
    # the ADS-B filters are declared once, for correlate and quality alike
    for name in ("drop_jumps", "min_nic", "min_nacp"):
        assert CorrelateOptions.__dataclass_fields__[name] is QualityOptions.__dataclass_fields__[name]


def test_the_aircraft_selection_is_one_required_group():
    parser = _subparsers()["quality"]
    (group,) = parser._mutually_exclusive_groups
    assert group.required and [a.option_strings for a in group._group_actions] == [
        ["--callsign"], ["--address"], ["--all"]]
    assert not _subparsers()["conflicts"]._mutually_exclusive_groups


def test_help_reads_as_declared():
    """The usage names options by their flags (not by the field names), lists argparse's choices and keeps
    the job-checked ones free text."""
    usage = _subparsers()["track"].format_usage()
    assert "[--step STEP]" in usage and "[--max-coast MAX_COAST]" in usage
    assert "[--smoother {rts,imm}]" in usage
    assert "[--noise NOISE]" in usage and "[--adsb-sigma M]" in usage and "[--edition CAT=ED]" in usage
    assert "(--callsign CALLSIGN | --address ADDRESS | --all)" in usage
    assert "[INPUT ...]" in usage  # or --dataset
    assert "INPUT [INPUT ...]" in _subparsers()["decode"].format_usage()  # no --dataset there
    assert "[--category {1,2,10,19,20,21,23,25,34,48,62,63,65}]" in _subparsers()["decode"].format_usage()


# ---------------------------------------------------------------------------------------------------------
# from_args


def _args(*argv: str) -> argparse.Namespace:
    return build_parser().parse_args(list(argv))


def test_a_command_line_makes_the_options_it_says():
    args = _args("correlate", "r.ast", "a.ast", "--sensors", "s.toml", "--all", "--slot", "5", "--gap", "30",
                 "--edition", "21=0.26", "--edition", "48 = 1.27", "--date", "2019-03-01", "--min-nic", "3",
                 "--fill", "predict", "--split-adsb", "-o", "r.xlsx", "--adsb-sigma", "50")
    assert from_args(CorrelateOptions, args) == CorrelateOptions(
        inputs=("r.ast", "a.ast"), sensors="s.toml", all_aircraft=True, slot_s=5.0, gap_s=30.0,
        editions=("21=0.26", "48=1.27"), date=dt.date(2019, 3, 1), min_nic=3, fill="predict", split_adsb=True,
        output="r.xlsx", adsb_sigma_m=50.0)


def test_options_left_out_take_the_dataclass_defaults():
    assert from_args(ConflictOptions, _args("conflicts", "r.ast", "-o", "c.csv")) == ConflictOptions(
        inputs=("r.ast",), output="c.csv")
    options = from_args(ConflictOptions, _args("conflicts", "r.ast", "-o", "c.csv"))
    assert options.horizons_s == (20.0, 60.0, 120.0) and options.sources == ("radar", "adsb")
    assert options.noise == "declared" and options.all_aircraft
    assert from_args(DecodeOptions, _args("decode", "r.ast")) == DecodeOptions(inputs=("r.ast",))
    assert from_args(StatsOptions, _args("stats", "r.ast", "--chunk-mb", "2")) == StatsOptions(
        inputs=("r.ast",), chunk_mb=2.0)


def test_repeated_and_text_options():
    options = from_args(DecodeOptions, _args("decode", "r.ast", "--category", "48", "--category", "21"))
    assert options.categories == (48, 21)
    options = from_args(ConflictOptions, _args("conflicts", "r.ast", "-o", "c.csv", "--horizon", "30,90",
                                               "--sources", "adsb", "--method", "blocks"))
    assert (options.horizons_s, options.sources, options.method) == ("30,90", "adsb", "blocks")


def test_extra_values_override_the_command_line():
    """msdc track: --smoother implies --smooth (its command passes smooth)."""
    args = _args("track", "r.ast", "--all", "--json", "t.json", "--smoother", "imm")
    options = from_args(TrackOptions, args, smooth=args.smooth or args.smoother is not None)
    assert options.smooth and options.smoother == "imm"
    assert not from_args(TrackOptions, _args("track", "r.ast", "--all", "--json", "t.json")).smooth


# ---------------------------------------------------------------------------------------------------------
# check_declared


DECLARED_ERRORS = [
    (CorrelateOptions(slot_s=0.0), "--slot 0.0: must be a finite number from 0.1 to 3600 s"),
    (CorrelateOptions(slot_s=math.inf), "--slot inf: must be a finite number from 0.1 to 3600 s"),
    (CorrelateOptions(gap_s=math.nan), "--gap nan: must be a finite number from 0.1 to 86400 s"),
    (CorrelateOptions(min_nic=12), "--min-nic 12: must be an integer from 0 to 11"),
    (CorrelateOptions(min_nacp=5.5), "--min-nacp 5.5: must be an integer from 0 to 11"),
    (CorrelateOptions(pairs="radar"),
     "--pairs 'radar': must be one of radar-adsb, radar-radar, mlat-adsb, smr-mlat, all"),
    (CorrelateOptions(fill="zero"), "--fill 'zero': must be hold or predict"),
    (CorrelateOptions(tables="csv"), "--tables 'csv': must be one of auto, xlsx, parquet"),
    (CorrelateOptions(adsb_sigma_m=0.1), "--adsb-sigma 0.1: must be a finite number from 0.5 to 20000 m"),
    (CorrelateOptions(format="zip"), "--format 'zip': must be one of raw, pcap, pcapng, final, gps, oradis"),
    (QualityOptions(reference="smooth"), "--reference 'smooth': must be adsb or track"),
    (QualityOptions(gap_s=-5.0), "--gap -5.0: must be a finite number from 0.1 to 86400 s"),
    (DecodeOptions(chunk_mb=0.0), "--chunk-mb 0.0: must be a finite number from 0.1 to 4096 MB"),
    (DecodeOptions(categories=(48, 8)),
     "--category 8: must be one of 1, 2, 10, 19, 20, 21, 23, 25, 34, 48, 62, 63, 65"),
    (StatsOptions(chunk_mb=1e6), "--chunk-mb 1000000.0: must be a finite number from 0.1 to 4096 MB"),
    (TrackOptions(noise="nacp"), "--noise 'nacp': must be one of declared, estimate, timing"),
    (TrackOptions(step_s=7200.0), "--step 7200.0: must be a finite number from 0.001 to 3600 s"),
    (TrackOptions(adsb_sigma_m=1e9),
     "--adsb-sigma 1000000000.0: must be a finite number from 0.5 to 20000 m"),
    (ConflictOptions(horizons_s=(20.0, 0.5)), "--horizon 0.5: must be a finite number from 1 to 3600 s"),
    (ConflictOptions(radius_nm=0.0), "--radius-nm 0.0: must be a finite number from 0.01 to 100 NM"),
    (ConflictOptions(vertical_ft=math.nan), "--vertical-ft nan: must be a finite number from 1 to 100000 ft"),
    (ConflictOptions(vertical_tolerance_ft=-1.0),
     "--vertical-tolerance-ft -1.0: must be a finite number from 0 to 500 ft"),
    (TrackOptions(smoother="two-filter"), "--smoother 'two-filter': must be rts or imm"),
    (ConflictOptions(vertical="probable"), "--vertical 'probable': must be gate or gaussian"),
    (ConflictOptions(surface="maybe"), "--surface 'maybe': must be exclude or include"),
    (ConflictOptions(method="montecarlo"), "--method 'montecarlo': must be one of exact, one-block, blocks, "
                                           "midpoint"),
]


@pytest.mark.parametrize(("options", "message"), DECLARED_ERRORS,
                         ids=[m.split(":")[0] for _, m in DECLARED_ERRORS])
def test_a_declared_range_or_choice_is_checked(options, message):
    with pytest.raises(OptionError) as info:
        check_declared(options)
    assert str(info.value) == message and info.value.status == 2


@pytest.mark.parametrize("options_cls", list(COMMAND_OPTIONS.values()))
def test_the_defaults_and_unset_options_pass(options_cls):
    check_declared(options_cls())


@pytest.mark.parametrize("options_cls", list(COMMAND_OPTIONS.values()))
def test_every_declared_range_is_checked_at_its_bounds(options_cls):
    """Each range option: its bounds pass, a little beyond them fails naming the option."""
    for f, spec, kind in declared(options_cls):
        if spec.range is None:
            continue
        lo, hi = spec.range
        step = 1 if kind is int else (hi - lo) * 1e-6
        for good in (lo, hi):
            check_declared(dataclasses.replace(options_cls(), **{f.name: kind(good)}))
        for bad in (lo - step, hi + step):
            with pytest.raises(OptionError, match=f"^{spec.name} "):
                check_declared(dataclasses.replace(options_cls(), **{f.name: kind(bad)}))


@pytest.mark.parametrize(("command", "options", "flag"), [
    ("decode", DecodeOptions(chunk_mb=0.0), "--chunk-mb"), ("stats", StatsOptions(format="zip"), "--format"),
    ("correlate", CorrelateOptions(callsign="MAS72", slot_s=0.0), "--slot"),
    ("quality", QualityOptions(all_aircraft=True, reference="x"), "--reference"),
    ("track", TrackOptions(all_aircraft=True, json="t.json", adsb_sigma_m=0.1), "--adsb-sigma"),
    ("conflicts", ConflictOptions(output="c.csv", radius_nm=0.0), "--radius-nm")])
def test_a_declared_option_is_checked_before_the_inputs_are_read(command, options, flag, monkeypatch):
    """Each job checks the declared ranges and choices first: a bad one is said before any input is hashed
    (a day's recording takes seconds), by the library as by the command line."""
    import importlib

    from msdc.pipeline.jobs import common

    monkeypatch.setattr(common, "sha256", lambda path: pytest.fail(f"{path} hashed before the options"))
    job = importlib.import_module(f"msdc.pipeline.jobs.{command}")
    with pytest.raises(OptionError, match=f"^{flag} "):
        job.validate(dataclasses.replace(options, inputs=(str(ROOT / "fixtures" / "radar.ast"),)))


def test_what_relates_options_is_not_declared():
    """--max-coast's lower bound is --step and --threshold is strictly inside (0, 1): the jobs check them."""
    fields = {f.name: spec for f, spec, _ in declared(ConflictOptions)}
    assert fields["max_coast_s"].range is None and fields["threshold"].range is None
    check_declared(ConflictOptions(max_coast_s=-1.0, threshold=1.0))


def test_option_declarations_are_checked():
    with pytest.raises(TypeError, match="immutable"):
        opts.option([], "--x", help="x")
    with pytest.raises(ValueError, match="section 'middle'"):
        opts.option(None, "--x", help="x", section="middle")


# ---------------------------------------------------------------------------------------------------------
# --help stays light


def test_the_options_import_no_heavy_library():
    """build_parser's module and the category registry it reads import no numpy, pandas or numba."""
    code = ("import sys, msdc.pipeline.jobs.options; "
            "print(','.join(m for m in ('numpy', 'pandas', 'numba', 'scipy') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.strip() == "", done.stdout + done.stderr


# ---------------------------------------------------------------------------------------------------------
# The guide's options tables


@pytest.mark.parametrize("command", list(EXPECTED))
def test_the_guide_shows_the_declared_options(command):
    """docs/guide/COMMAND.md holds the table options_table makes, between its markers (rewrite them with
    ``python -m msdc.pipeline.jobs.options --write-docs``), one row per option of the command."""
    text = (ROOT / "docs" / "guide" / f"{PAGES.get(command, command)}.md").read_text()
    table = text.partition(f"<!-- options: {command} -->\n")[2].partition("<!-- /options -->")[0]
    assert table == opts.options_table(COMMAND_OPTIONS[command]), "python -m msdc.pipeline.jobs.options " \
                                                                  "--write-docs rewrites it"
    rows = [row.split(" | ")[0].removeprefix("| ") for row in table.splitlines()[2:] if row.startswith("| ")]
    assert sorted(rows) == sorted("`-o`, `--output`" if flag == "--output" else f"`{flag}`"
                                  for flag in EXPECTED[command])


def test_a_table_row_says_what_the_option_takes():
    from msdc.pipeline.jobs.options import ListenOptions

    # an integer's bounds in digits: "1 to 1e+07" was refused as written ("invalid int value: '1e7'")
    assert any(row.startswith("| `--queue` | 1 to 10000000 |") for row in opts.options_table(ListenOptions)
               .splitlines())
    table = opts.options_table(CorrelateOptions).splitlines()
    assert "| `--slot` | 0.1 to 3600 s | `10` | slot width D in seconds |" in table
    assert "| `--sensors` | SENSORS | required | the radars' positions ([the sensor file](sensors.md)) |" \
        in table
    assert "| `--min-nic` | 0 to 11 |  | drop ADS-B reports with NUCp/NIC below N " \
           "([filters](quality.md#filters)) |" in table
    assert "| `--split-adsb` | flag |  | keep ADS-B ground stations apart (default: one ADS-B source per " \
           "aircraft after deduplication) |" in table
    assert table[-1] == "Exactly one of `--callsign`, `--address` and `--all` is required."
    rows = opts.options_table(ConflictOptions).splitlines()
    assert "| `--horizon` | 1 to 3600 s | `20,60,120` | look-aheads in seconds, comma-separated, whole " \
           "multiples of `--step` |" in rows
    assert any(row.startswith("| `--max-coast` | number (s) | `60` |") for row in rows)
    assert any(row.startswith("| `--threshold` | number | `0.2` |") for row in rows)
    assert any(row.startswith("| `--edition` | CAT=ED, repeatable |  |") for row in rows)
    assert any(row.startswith("| `INPUT` | one or more, or none with `--dataset` |  | the recordings |")
               for row in rows)
    decode = opts.options_table(opts.DecodeOptions).splitlines()
    assert any(row.startswith("| `INPUT` | one or more |  | the recordings") for row in decode)


def test_a_stale_table_is_found_and_rewritten(tmp_path):
    for command in COMMAND_OPTIONS:
        page = f"{PAGES.get(command, command)}.md"
        (tmp_path / page).write_text((ROOT / "docs" / "guide" / page).read_text())
    page = tmp_path / "track.md"
    page.write_text(page.read_text().replace("| `--smooth` | flag |", "| `--smooth` | switch |"))
    assert opts.write_docs(tmp_path, check=True) == [page] and "switch" in page.read_text()
    assert opts.write_docs(tmp_path) == [page] and "switch" not in page.read_text()
    assert opts.write_docs(tmp_path, check=True) == []
    with pytest.raises(ValueError, match="no <!-- options: track --> ... <!-- /options --> markers"):
        opts.page_with_table("# msdc track\n", "track")
