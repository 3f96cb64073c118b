"""Conflict workbook: sheets Alerts, Losses, Warning times and Parameters (the shared write-only table
writer of `pipeline.report.excel`, written atomically)."""

from __future__ import annotations

import os

import pandas as pd

from pipeline.report.excel import write_tables


def write_conflict_workbook(alerts: pd.DataFrame, losses: pd.DataFrame, warnings: pd.DataFrame,
                            parameters: dict, path_xlsx: str | os.PathLike[str]) -> None:
    """One sheet per table (times as Excel date-times in UTC, headers even when a table is empty)."""
    write_tables({"Alerts": alerts, "Losses": losses, "Warning times": warnings}, path_xlsx,
                 parameters=parameters)
