"""Workbook write speed: a synthetic correlation run written by ``write_report``, in cells per second.

Also times openpyxl's write-only mode on plain numbers (no styles) as the ceiling to compare with.
Run from the repository root: ``python benchmarks/workbook.py [--windows 60] [--slots 500]``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from msdc.pipeline.correlate.results import SLOT_COLUMNS, SUMMARY_KEYS, CorrelationRun, WindowResult  # noqa: E402


def synthetic_run(n_windows: int, n_slots: int, seed: int = 1) -> CorrelationRun:
    """``n_windows`` windows of ``n_slots`` slots each, with plausible values in every column."""
    rng = np.random.default_rng(seed)
    windows = []
    t0 = pd.Timestamp("2019-03-01 08:00", tz="UTC")
    for w in range(n_windows):
        k = np.arange(n_slots)
        tod = 28800.0 + 600.0 * w + 10.0 * k
        lat = 2.5 + 0.01 * k + rng.normal(0, 1e-4, n_slots)
        lon = 101.5 + 0.01 * k + rng.normal(0, 1e-4, n_slots)
        slots = pd.DataFrame({
            "slot": k, "time_of_day": tod, "timestamp": t0 + pd.to_timedelta(tod - 28800.0, unit="s"),
            "radar_lat": lat, "radar_lon": lon, "adsb_lat": lat + 1e-4, "adsb_lon": lon - 1e-4,
            "radar_count": rng.integers(1, 4, n_slots), "adsb_count": rng.integers(5, 12, n_slots),
            "radar_filled": rng.random(n_slots) < 0.05, "adsb_filled": rng.random(n_slots) < 0.02,
            "sep_m": rng.gamma(2.0, 150.0, n_slots)})[SLOT_COLUMNS]
        lags = np.arange(-(n_slots - 1), n_slots)
        lag_frame = pd.DataFrame({"lag": lags, "ncc_lat": 1 - 1e-6 * np.abs(lags),
                                  "ncc_lon": 1 - 2e-6 * np.abs(lags), "pearson_lat": np.cos(lags / n_slots),
                                  "pearson_lon": np.cos(lags / n_slots) - 0.01})
        summary = dict.fromkeys(SUMMARY_KEYS, 1.0)
        summary.update(callsign=f"TST{w:03d}", address=f"{w:06X}", window=1, slots=n_slots,
                       start=t0 + pd.Timedelta(seconds=600 * w),
                       end=t0 + pd.Timedelta(seconds=600 * w + 10 * n_slots))
        windows.append(WindowResult(summary=summary, slots=slots, lags=lag_frame))
    return CorrelationRun(windows=windows, parameters={"slot_s": 10.0, "date": "2019-03-01"})


def plain_cells_per_s(n_rows: int = 40_000, n_cols: int = 10) -> float:
    """openpyxl write-only mode, plain floats, no styles: the ceiling."""
    from openpyxl import Workbook

    values = np.random.default_rng(0).random((n_rows, n_cols)).tolist()
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        wb = Workbook(write_only=True)
        ws = wb.create_sheet("x")
        for row in values:
            ws.append(row)
        wb.save(Path(tmp) / "plain.xlsx")
        return n_rows * n_cols / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--windows", type=int, default=60)
    parser.add_argument("--slots", type=int, default=500)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    from openpyxl.xml import LXML

    from msdc.pipeline.report.excel import write_report

    run = synthetic_run(args.windows, args.slots)
    slot_cells = sum(len(w.slots) for w in run.windows) * (len(SLOT_COLUMNS) + 3)
    lag_cells = sum(len(w.lags) for w in run.windows) * 10
    cells = slot_cells + lag_cells
    print(f"openpyxl uses lxml: {LXML}")
    ceiling = plain_cells_per_s()
    print(f"plain write-only ceiling: {ceiling:,.0f} cells/s")
    best = float("inf")
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(args.repeat):
            start = time.perf_counter()
            write_report(run, Path(tmp) / "bench.xlsx")
            best = min(best, time.perf_counter() - start)
        size = (Path(tmp) / "bench.xlsx").stat().st_size
    print(f"write_report: {args.windows} windows x {args.slots} slots, ~{cells:,} table cells, "
          f"{size / 1e6:.1f} MB: best {best:.2f} s = {cells / best:,.0f} cells/s "
          f"({cells / best / ceiling:.0%} of the plain ceiling)")


if __name__ == "__main__":
    main()
