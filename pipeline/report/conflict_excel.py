"""Conflict workbook: sheets Alerts, Losses, Warning times and Parameters (the shared cell and table rules
of `pipeline.report.cells`).

Times are Excel date-times in UTC, each labelled "UTC" by its number format (the CSV and JSON write them
with a Z); horizons, warnings and durations, whole multiples of the step, in General format (120, 2.5, -5,
not 120.000); an empty table fits one page wide."""

from __future__ import annotations

import os

import pandas as pd
from openpyxl import Workbook

from msdc.pipeline.correlate.results import CorrelationRun
from msdc.pipeline.report.cells import make_column, write_table
from msdc.pipeline.report.excel import write_parameters
from msdc.pipeline.report.saving import save

UTC_FORMAT = 'yyyy-mm-dd hh:mm:ss "UTC"'
UTC_FRACTION_FORMAT = 'yyyy-mm-dd hh:mm:ss.000 "UTC"'  # when a time has a fraction of a second
GENERAL_COLUMNS = {"horizon_s", "warning_s", "duration_s"}
TIME_TO_CPA_FORMAT = "0.0"


def write_conflict_workbook(alerts: pd.DataFrame, losses: pd.DataFrame, warnings: pd.DataFrame,
                            parameters: dict, path_xlsx: str | os.PathLike[str]) -> None:
    """One sheet per table (headers even when a table is empty) and the Parameters sheet."""
    wb = Workbook(write_only=True)
    for name, frame in (("Alerts", alerts), ("Losses", losses), ("Warning times", warnings)):
        ws = wb.create_sheet(name)
        write_table(ws, [_column(ws, str(c), frame[c]) for c in frame.columns])
        if frame.empty:  # a header row alone: one page, not the width the data would need
            ws.page_setup.fitToWidth = 1
            ws.print_title_cols = None
    write_parameters(wb, CorrelationRun(parameters=parameters), windows=False)
    save(wb, path_xlsx)


def _column(ws, header: str, series: pd.Series):
    """A table column: times labelled UTC, the step-multiple seconds in General format."""
    column = make_column(ws, header, series, general=header in GENERAL_COLUMNS)
    fmt = None
    if isinstance(series.dtype, pd.DatetimeTZDtype) or series.dtype.kind == "M":
        whole = series.dropna().dt.microsecond.eq(0).all() and series.dropna().dt.nanosecond.eq(0).all()
        fmt = UTC_FORMAT if whole else UTC_FRACTION_FORMAT
    elif header == "time_to_cpa_s":
        fmt = TIME_TO_CPA_FORMAT
    if fmt is not None:
        column.number_format = fmt
        if column.styled is not None:
            column.styled.number_format = fmt
    return column
