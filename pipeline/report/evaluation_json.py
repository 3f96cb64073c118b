"""The evaluation's JSON: a ``results`` list with one object per scorecard row (exactly the scorecard's
columns as keys), the named tables as lists of row objects, and the map points when given; NaN as null."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from msdc.pipeline.evaluate.scorecard_schema import (
    SCORECARD_COLUMNS,
    validate_map,
    validate_scorecard,
    validate_tables,
)
from msdc.pipeline.report.files import write_json
from msdc.pipeline.report.summary import table_records

FORMAT = "msdc-evaluation"
VERSION = 1


def evaluation_document(scorecard: pd.DataFrame, tables: Mapping[str, pd.DataFrame] | None = None,
                        map_points: pd.DataFrame | None = None, run: Mapping[str, Any] | None = None
                        ) -> dict[str, Any]:
    """The JSON document of an evaluation (validated by scorecard_schema): format, version, columns,
    results, tables (name -> rows) and, when given, map_points, and the run's ``inputs`` and
    ``parameters`` (``run``: what was read, with SHA-256, and how: software, preset, reference, gates,
    report selection, notes)."""
    card = validate_scorecard(scorecard)
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION, "columns": list(SCORECARD_COLUMNS),
                           "results": table_records(card)}
    if run is not None:
        doc["inputs"] = list(run.get("inputs", []))
        doc["parameters"] = dict(run.get("parameters", {}))
    for row in doc["results"]:
        row["n"] = int(row["n"]) if float(row["n"]).is_integer() else row["n"]  # a count reads as one
    frames = validate_tables(tables)
    doc["tables"] = {name: table_records(frame.reset_index() if not isinstance(frame.index, pd.RangeIndex)
                                         else frame) for name, frame in frames.items()}
    points = validate_map(map_points)
    if points is not None:
        doc["map_points"] = table_records(points)
    return doc


def write_evaluation_json(scorecard: pd.DataFrame, path: str | os.PathLike[str],
                          tables: Mapping[str, pd.DataFrame] | None = None,
                          map_points: pd.DataFrame | None = None, run: Mapping[str, Any] | None = None
                          ) -> Path:
    """evaluation_document written as strict JSON to ``path`` (an error names it); returns ``path``."""
    return write_json(evaluation_document(scorecard, tables, map_points, run), path)


def read_evaluation_json(path: str | os.PathLike[str]) -> tuple[pd.DataFrame, dict[str, pd.DataFrame]]:
    """The scorecard (validated, null as NaN) and the tables read back from an evaluation JSON."""
    import json

    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise ValueError(f"{path}: not an msdc evaluation JSON (no \"format\": \"{FORMAT}\")")
    card = pd.DataFrame(doc["results"], columns=list(SCORECARD_COLUMNS))
    for name in ("value", "ci_low", "ci_high", "n", "threshold"):
        card[name] = pd.to_numeric(card[name]).astype(float)
    tables = {name: pd.DataFrame(rows) for name, rows in doc.get("tables", {}).items()}
    return validate_scorecard(card), tables
