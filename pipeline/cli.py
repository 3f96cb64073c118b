"""The ``msdc`` command: decode, stats, correlate and quality, each a thin layer over library calls."""

from __future__ import annotations

import argparse
import datetime as dt
import sys
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import pandas as pd

import asterix
from asterix.errors import AsterixError, DecodeError, UnreadableInput
from asterix.reader import categories_in

from .aircraft import NoSuchAircraft
from .correlation import NoOverlap, correlate
from .filters import apply_filters
from .load import Loaded, load
from .measurements import UnknownRadar, adsb_measurements, radar_measurements
from .progress import Progress
from .quality_figures import slotting_figure
from .quality_run import quality_figures, quality_run
from .sensors import read_sensors, sensor_toml_snippet
from .stats import format_stats, stats_tables

FORMATS = ["raw", "pcap", "pcapng", "final", "gps", "oradis"]


def software_version() -> str:
    try:
        return version("msdc")
    except PackageNotFoundError:
        return "unknown"


class CliError(Exception):
    """A user-facing failure: printed without a traceback, exit status 1 (2 for unreadable input)."""

    def __init__(self, message: str, status: int = 1):
        super().__init__(message)
        self.status = status


def _date(text: str) -> dt.date:
    try:
        return dt.date.fromisoformat(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(f"not a date (YYYY-MM-DD): {text!r}") from exc


def _edition(text: str) -> str:
    cat, sep, ed = text.partition("=")
    if not sep or not cat.strip().isdigit() or not ed:
        raise argparse.ArgumentTypeError(f"expected CAT=EDITION (e.g. 21=0.26 or 21=auto), got {text!r}")
    return f"{int(cat)}={ed.strip()}"


def _decoding_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--edition", action="append", type=_edition, default=[], metavar="CAT=ED",
                   help="pin a category edition, e.g. 21=0.26, 48=1.27, or 21=auto (repeatable)")
    p.add_argument("--date", type=_date, help="UTC date of a raw or final recording (YYYY-MM-DD)")
    p.add_argument("--format", choices=FORMATS, help="container format (default: detected)")


def _aircraft_options(p: argparse.ArgumentParser, all_help: str) -> None:
    """Inputs, the sensor file and the aircraft selection shared by correlate and quality."""
    p.add_argument("inputs", nargs="+", metavar="INPUT")
    p.add_argument("--sensors", required=True, help="sensor positions (TOML [[sensor]] tables)")
    who = p.add_mutually_exclusive_group(required=True)
    who.add_argument("--callsign", help="call sign (case and spaces ignored)")
    who.add_argument("--address", help="24-bit aircraft address in hex")
    who.add_argument("--all", action="store_true", help=all_help)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="msdc", description="Multi-Sensor Data Correlator: ASTERIX "
                                     "CAT048/CAT021 decoding and radar/ADS-B correlation.")
    parser.add_argument("--version", action="version", version=f"msdc {software_version()}")
    sub = parser.add_subparsers(dest="command", required=True)

    d = sub.add_parser("decode", help="decode recordings to CSV or Parquet")
    d.add_argument("inputs", nargs="+", metavar="INPUT")
    d.add_argument("-o", "--output", help="OUT.csv or OUT.parquet (one file per category: stem_cat048...)")
    d.add_argument("--category", type=int, action="append", choices=[21, 48], help="only this category")
    d.add_argument("--strict", action="store_true", help="stop at the first bad block")
    d.add_argument("--chunk-mb", type=float, default=64.0, help="streaming chunk size (MB)")
    _decoding_options(d)

    s = sub.add_parser("stats", help="what the recordings hold")
    s.add_argument("inputs", nargs="+", metavar="INPUT")
    _decoding_options(s)

    c = sub.add_parser("correlate", help="correlate radar against ADS-B per aircraft (thesis algorithm)")
    _aircraft_options(c, "every aircraft seen by both sensors")
    c.add_argument("-o", "--output", help="Excel report (.xlsx); the track figure is written beside it")
    c.add_argument("--json", help="window summary as JSON")
    c.add_argument("--slot", type=float, default=10.0, help="slot width D in seconds (default 10)")
    c.add_argument("--gap", type=float, default=180.0, help="gap G in seconds that ends a period (180)")
    c.add_argument("--quality", action="store_true", help="add the Quality and Radar accuracy sheets")
    c.add_argument("--drop-jumps", action="store_true", help="remove detected ADS-B position jumps first")
    c.add_argument("--min-nic", type=int, help="drop ADS-B reports with NUCp/NIC below N")
    c.add_argument("--min-nacp", type=int, help="drop ADS-B reports with NACp below N")
    _decoding_options(c)

    q = sub.add_parser("quality", help="sensor data quality and radar accuracy against ADS-B")
    _aircraft_options(q, "every aircraft")
    q.add_argument("-o", "--output", help="Excel workbook (.xlsx); figures are written beside it")
    q.add_argument("--json", help="the tables as JSON")
    q.add_argument("--gap", type=float, default=180.0, help="gap in seconds reported as discontinuity")
    _decoding_options(q)
    return parser


def _load(args, progress: Progress, categories=None) -> Loaded:
    progress.stage("Processing data files")
    try:
        return load(args.inputs, editions=args.edition, date=args.date, format=args.format,
                    categories=categories, progress=progress)
    except UnreadableInput as exc:
        raise CliError(str(exc), 2) from exc


def _report_skipped(loaded_errors: pd.DataFrame) -> None:
    if len(loaded_errors):
        print(f"msdc: {len(loaded_errors)} block(s) skipped ({int(loaded_errors['length'].sum())} bytes); "
              "'msdc stats' lists them", file=sys.stderr)


def cmd_decode(args) -> int:
    progress = Progress()
    outputs: dict[int, Path] = {}
    writers: dict[int, object] = {}
    total_records = 0
    skipped = 0
    out = Path(args.output) if args.output else None
    if out is not None and out.suffix.lower() not in (".csv", ".parquet"):
        raise CliError(f"{out}: output must end in .csv or .parquet")
    counts: dict[int, int] = {}
    try:
        present: set[int] = set()
        for path in args.inputs:
            present |= set(categories_in(path, format=args.format)) & {21, 48}
        several = len(present & set(args.category or present)) > 1
        for path in args.inputs:
            size = Path(path).stat().st_size if Path(path).exists() else 0
            chunk = max(int(args.chunk_mb * 1e6), 1)
            for rec in asterix.iter_read(path, chunk=chunk, editions=args.edition, date=args.date,
                                         format=args.format, categories=args.category, strict=args.strict):
                skipped += len(rec.errors)
                for err in rec.errors.itertuples():
                    print(f"msdc: {path}: offset {err.offset}: {err.reason}", file=sys.stderr)
                for cat, frame in rec.frames.items():
                    counts[cat] = counts.get(cat, 0) + len(frame)
                    total_records += len(frame)
                    if out is not None:
                        frame = frame.assign(file=Path(path).name)
                        _write_chunk(out, cat, frame, outputs, writers, several=several)
                done = max((int(f["offset"].max()) for f in rec.frames.values() if len(f)), default=0)
                progress.bar(done, size, Path(path).name)
    except UnreadableInput as exc:
        raise CliError(str(exc), 2) from exc
    except DecodeError as exc:
        raise CliError(f"strict: {exc}") from exc
    finally:
        for w in writers.values():
            if hasattr(w, "close"):
                w.close()
    if out is None:
        for cat, n in sorted(counts.items()):
            print(f"CAT{cat:03d}: {n} records")
    else:
        for cat, p in sorted(outputs.items()):
            print(f"CAT{cat:03d}: {counts.get(cat, 0)} records -> {p}")
    if skipped:
        print(f"msdc: {skipped} block(s) skipped", file=sys.stderr)
    if total_records == 0:
        print("msdc: nothing could be decoded", file=sys.stderr)
        return 1
    return 0


def _write_chunk(out: Path, cat: int, frame: pd.DataFrame, outputs: dict, writers: dict,
                 several: bool) -> None:
    """Append one chunk of a category to its output (CSV or Parquet), opening it on first use."""
    if cat not in outputs:
        outputs[cat] = out.with_name(f"{out.stem}_cat{cat:03d}{out.suffix}") if several else out
        if several:
            print(f"msdc: several categories: writing {outputs[cat]}", file=sys.stderr)
    path = outputs[cat]
    frame = frame.assign(timestamp=frame["timestamp"].dt.strftime("%Y-%m-%dT%H:%M:%S.%fZ")) \
        if path.suffix.lower() == ".csv" else frame
    if path.suffix.lower() == ".csv":
        frame.to_csv(path, mode="a" if cat in writers else "w", header=cat not in writers, index=False)
        writers[cat] = True
    else:
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pa.Table.from_pandas(frame, preserve_index=False)
        if cat not in writers:
            writers[cat] = pq.ParquetWriter(path, table.schema)
        writers[cat].write_table(table.cast(writers[cat].schema))


def cmd_stats(args) -> int:
    loaded = _load(args, Progress())
    print(format_stats(stats_tables(loaded.frames, loaded.errors)), end="")
    for rec in loaded.recordings:
        for cat, why in rec.edition_choice.items():
            print(f"{rec.path}: CAT{cat:03d} edition {why}")
    if not any(len(f) for f in loaded.frames.values()):
        print("msdc: nothing could be decoded", file=sys.stderr)
        return 1
    return 0


def _sensors(sensors_path: str) -> pd.DataFrame:
    try:
        return read_sensors(sensors_path)
    except (OSError, ValueError) as exc:
        raise CliError(f"{sensors_path}: {exc}", 2 if isinstance(exc, OSError) else 1) from exc


def _measurements(loaded: Loaded, sensors: pd.DataFrame,
                  sensors_path: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Radar and ADS-B measurements, with the user-facing errors for missing data and sensors."""
    if 48 not in loaded.frames or loaded.frames[48].empty:
        raise CliError("no radar (CAT048) records in the inputs")
    if 21 not in loaded.frames or loaded.frames[21].empty:
        raise CliError("no ADS-B (CAT021) records in the inputs")
    try:
        radar = radar_measurements(loaded.frames[48], sensors)
    except UnknownRadar as exc:
        lines = "\n\n".join(sensor_toml_snippet(sac, sic) for sac, sic in exc.missing)
        raise CliError(f"radar SAC/SIC {', '.join(f'{a}/{b}' for a, b in exc.missing)} not in {sensors_path};"
                       f" add its position:\n\n{lines}") from exc
    return radar, adsb_measurements(loaded.frames[21])


def _parameters(args, loaded: Loaded, started: float) -> dict:
    return {"software": f"msdc {software_version()}", "command": " ".join(sys.argv[1:]) or "correlate",
            "run_utc": dt.datetime.now(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "run_time_s": round(time.monotonic() - started, 3), "editions": {
                f"CAT{c:03d}": e for c, e in sorted(loaded.editions.items())},
            "sensors": str(args.sensors), "date": loaded.date.isoformat() if loaded.date else None}


def _prepare(args, progress: Progress):
    """Load the inputs and the sensor file and build both sensors' measurements."""
    loaded = _load(args, progress)
    _report_skipped(loaded.errors)
    progress.stage("Pre-processing data")
    sensors = _sensors(args.sensors)
    radar, adsb = _measurements(loaded, sensors, args.sensors)
    return loaded, sensors, radar, adsb


def cmd_correlate(args) -> int:
    started = time.monotonic()
    progress = Progress()
    loaded, sensors, radar, adsb = _prepare(args, progress)
    adsb_all = adsb
    adsb, removed = apply_filters(adsb, drop_jumps=args.drop_jumps, min_nic=args.min_nic,
                                  min_nacp=args.min_nacp)
    progress.stage("Slotting data")
    progress.stage("Correlating data")
    try:
        run = correlate(radar, adsb, callsign=args.callsign, address=args.address, all_aircraft=args.all,
                        slot_s=args.slot, gap_s=args.gap, date=loaded.date)
    except (NoSuchAircraft, NoOverlap) as exc:
        raise CliError(str(exc)) from exc
    run.inputs = loaded.inputs
    run.filters = {k: v for k, v in removed.items() if _filter_on(args, k)}
    run.parameters = {**run.parameters, **_parameters(args, loaded, started),
                      "filters": {"drop_jumps": args.drop_jumps, "min_nic": args.min_nic,
                                  "min_nacp": args.min_nacp, "removed": run.filters}}
    for name, n in run.filters.items():
        print(f"filter {name}: {n} of the input's ADS-B reports", file=sys.stderr)
    images = None
    if args.quality:
        progress.stage("Analysing data quality")
        result = _quality(radar, adsb_all, sensors, args)
        run.extra_sheets.update(result.sheets)
        if args.output:
            images = _correlation_images(run, radar, adsb, result, Path(args.output))
    _write_outputs(run, args, progress, images)
    return 0


def _filter_on(args, key: str) -> bool:
    """Whether a filter's count belongs in the report (only the filters that were asked for)."""
    return {"jumps": args.drop_jumps, "nic_below_min": args.min_nic is not None,
            "nic_missing_kept": args.min_nic is not None, "nacp_below_min": args.min_nacp is not None,
            "nacp_missing_kept": args.min_nacp is not None}.get(key, True)


def _quality(radar, adsb, sensors, args):
    try:
        return quality_run(radar, adsb, sensors, callsign=args.callsign, address=args.address,
                           gap_s=args.gap)
    except NoSuchAircraft as exc:
        raise CliError(str(exc)) from exc


def _correlation_images(run, radar, adsb, result, out: Path, max_windows: int = 6) -> dict[str, Path]:
    """Quality figures plus, for the first windows, lat/lon before and after slotting and NCC by lag."""
    from .figures import lag_figure

    images = dict(quality_figures(result, out.parent, out.stem))
    for i, w in enumerate(run.windows[:max_windows]):
        label = f"{w.summary['callsign'] or w.summary['address']} window {w.summary['window']}"
        images[f"{label}: latitude and longitude before and after slotting"] = slotting_figure(
            w, radar, adsb, out.with_name(f"{out.stem}_slotting_{i + 1}.png"))
        images[f"{label}: coefficient against lag"] = lag_figure(
            w, out.with_name(f"{out.stem}_lags_{i + 1}.png"))
    return images


def cmd_quality(args) -> int:
    started = time.monotonic()
    progress = Progress()
    loaded, sensors, radar, adsb = _prepare(args, progress)
    progress.stage("Analysing data quality")
    result = _quality(radar, adsb, sensors, args)
    print(_quality_text(result))
    params = {**_parameters(args, loaded, started), "callsign": args.callsign, "address": args.address,
              "gap_s": args.gap}
    if args.json:
        _write_quality_json(result, params, loaded.inputs, args.json)
        print(f"JSON: {args.json}", file=sys.stderr)
    if args.output:
        from .report import write_tables

        progress.stage("Writing report")
        out = Path(args.output)
        images = quality_figures(result, out.parent, out.stem)
        write_tables(result.sheets, out, images=images, parameters={**params, "inputs": loaded.inputs})
        print(f"Report: {out}", file=sys.stderr)
    return 0


def _quality_text(result) -> str:
    """The per-sensor summary and the bias estimates, for the terminal."""
    q = result.sheets["Quality"]
    b = result.sheets["Radar biases"]
    keep = [c for c in ("callsign", "address", "sensor", "sac", "sic", "reports", "duplicates_removed",
                        "interval_median_s",
                        "interval_p95_s", "speed_missing_or_zero_pct", "gaps", "jumps") if c in q]
    bias_cols = [c for c in ("radar", "n_reports", "range_bias_m", "range_gain_ppm", "azimuth_bias_deg",
                             "time_bias_s") if c in b]
    text = "Quality:\n" + q[keep].to_string(index=False) + "\n\nRadar biases:\n"
    text += b[bias_cols].to_string(index=False) if len(b) else "  no radar report matched to ADS-B"
    note = b.attrs.get("note")
    return text + (f"\n\nNote: {note}" if note else "")


def _write_quality_json(result, params: dict, inputs: list, path: str) -> None:
    import json

    from .summary import json_value

    doc = {"parameters": params, "inputs": inputs,
           "tables": {name: [{k: json_value(v) for k, v in row.items()} for row in t.to_dict("records")]
                      for name, t in result.sheets.items()}}
    Path(path).write_text(json.dumps(doc, indent=1, default=str))


def _write_outputs(run, args, progress: Progress, images: dict | None = None) -> None:
    from .figures import track_figure
    from .report import write_report
    from .summary import summary_table, write_json

    print(summary_table(run))
    if args.json:
        write_json(run, args.json)
        print(f"JSON summary: {args.json}", file=sys.stderr)
    if args.output:
        progress.stage("Writing report")
        out = Path(args.output)
        png = out.with_name(out.stem + "_tracks.png")
        track_figure(run, png)
        write_report(run, out, figure_png=png, images=images)
        print(f"Report: {out}\nTrack figure: {png}", file=sys.stderr)


COMMANDS = {"decode": cmd_decode, "stats": cmd_stats, "correlate": cmd_correlate, "quality": cmd_quality}


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return COMMANDS[args.command](args)
    except CliError as exc:
        print(f"msdc {args.command}: {exc}", file=sys.stderr)
        return exc.status
    except AsterixError as exc:
        print(f"msdc {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
