"""The sql job (``msdc sql``): a DuckDB query over a dataset (``msdc ingest``), each category a view
(``cat048``, ``cat021``...) over the parts its manifest lists, printed as a table or written whole to CSV
or Parquet (all or nothing: report.transaction)."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from msdc.pipeline.jobs.common import JobError, OptionError, nonempty_path, output_path, spare_dataset
from msdc.pipeline.jobs.options import SqlOptions, check_declared
from msdc.pipeline.report.transaction import OutputTransaction, staged

CSV_BATCH_ROWS = 100_000  # rows fetched and written at a time to a CSV output
# the views a query names (cat048...): only they are made, their parts checked before it runs; a name in a
# string counts too (query_table('cat048') reads the view): one it does not read costs a check, never a miss
VIEW_NAMED = re.compile(r"cat(\d{3})", re.IGNORECASE)
DAMAGED_SHOWN = 5  # damaged parts named in the error, at most


@dataclass
class SqlResult:
    """The first rows (as many as --limit, for the terminal) or the file written, and the views there were."""

    views: list[str]
    head: pd.DataFrame | None = None
    more: bool = False  # rows beyond the head
    output: Path | None = None
    rows_written: int | None = None
    notes: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)  # said on stderr before the rows


def validate(options: SqlOptions) -> tuple[str, Path, Path | None]:
    """The query, the dataset folder and -o, checked; OptionError if bad."""
    check_declared(options)
    query = " ".join(options.query).strip().rstrip(";").strip()
    if not query:
        raise OptionError("no query given: msdc sql --dataset DIR \"SELECT ...\"")
    if options.dataset is None:
        raise OptionError("--dataset is required")
    nonempty_path("--dataset", options.dataset)
    out = output_path("-o", options.output, (".csv", ".parquet"))
    spare_dataset(options.dataset, [(f"-o {out}", out)])
    return query, Path(options.dataset), out


def sql_job(options: SqlOptions, *, tx: OutputTransaction | None = None) -> SqlResult:
    """Run the query; JobError when DuckDB is missing or refuses the query (its message, and the views)."""
    from msdc.pipeline.dataset.manifest import ManifestError
    from msdc.pipeline.dataset.reader import NotADataset, duckdb_views, open_manifest, view_name

    query, root, out = validate(options)
    try:
        import duckdb
    except ImportError:
        raise JobError("msdc sql needs DuckDB: pip install 'msdc[dataset]' (or pip install duckdb)",
                       2) from None
    try:
        manifest = open_manifest(root)
        categories = _categories(manifest, query)
        warnings = _checked_parts(root, manifest, categories)  # before DuckDB reads a part
        con, _ = duckdb_views(root, manifest=manifest, categories=categories)
        views = [view_name(c) for c in sorted(_held(manifest))]
    except NotADataset as exc:
        raise OptionError(f"--dataset {exc}") from None
    except ManifestError as exc:
        raise JobError(str(exc), 2) from None
    except duckdb.Error as exc:
        raise JobError(f"--dataset {root}: its parts cannot be read: {str(exc).splitlines()[0]}", 2) from None
    shown = ", ".join(views) or "none: the dataset holds no record"
    try:
        if out is None:
            cursor = con.execute(query)
            if cursor.description is None:
                return SqlResult(views, None, warnings=warnings)
            names = [d[0] for d in cursor.description]
            rows = cursor.fetchmany(options.limit + 1)
            head = pd.DataFrame.from_records(rows[:options.limit], columns=names)
            return SqlResult(views, head, more=len(rows) > options.limit, warnings=warnings)
        with staged(tx) as stage:
            target = stage.path(out)
            if out.suffix.lower() == ".parquet":
                quoted = str(target).replace("'", "''")
                n = con.execute(f"COPY ({query}) TO '{quoted}' (FORMAT PARQUET)").fetchone()[0]  # rows copied
            else:
                n = _csv(con.sql(query), target)
        return SqlResult(views, output=out, rows_written=int(n), warnings=warnings)
    except duckdb.Error as exc:
        raise JobError(f"the query failed: {str(exc).splitlines()[0]} (views: {shown})", 2) from None
    finally:
        con.close()


def _categories(manifest, query: str) -> set[int]:
    """The categories whose views the query names (every one when it names none): the views made, and the
    parts checked; a view the query reads without naming it does not exist, so no part is read unchecked."""
    return (_held(manifest) & {int(c) for c in VIEW_NAMED.findall(query)}) or _held(manifest)


def _held(manifest) -> set[int]:
    """The categories the dataset's parts hold (a view each)."""
    return {int(p["category"]) for rec in manifest.inputs.values() for p in rec["parts"]}


def _checked_parts(root: Path, manifest, categories: set[int]) -> list[str]:
    """Check the parts of ``categories`` (dataset.integrity): JobError naming the damaged ones, the query
    not run; else the warnings (parts ingested without a checksum)."""
    from msdc.pipeline.dataset.integrity import check_parts

    checked = check_parts(root, list(manifest.inputs.values()), categories)
    if checked.damaged:
        said = [f"{p['path']} ({p['rows']:,} CAT{int(p['category']):03d} records of {p['input']}): {why}"
                for p, why in checked.damaged[:DAMAGED_SHOWN]]
        more = len(checked.damaged) - DAMAGED_SHOWN
        raise JobError(f"--dataset {root}: {len(checked.damaged)} damaged part(s) cannot be read as ingest "
                       "wrote them, the query was not run: " + "; ".join(said)
                       + (f"; and {more} more" if more > 0 else "") + " (restore the part(s) from a backup, "
                       "or ingest their inputs again into a new dataset)", 2)
    if not checked.unverified:
        return []
    return [f"{checked.unverified} part(s) the query may read carry no checksum (ingested before msdc "
            "recorded them): read unchecked, a damaged one would go unnoticed"]


def _csv(relation, target: Path) -> int:
    """The query's rows written to ``target`` batch by batch through report.files.write_csv, so that they
    follow every CSV output's rules (formula-like text guarded, times ISO 8601 UTC with a Z), which DuckDB's
    own CSV writer does not; the number of rows."""
    from msdc.pipeline.report.files import write_csv

    if relation is None:
        raise JobError("the query returns no rows to write (it is not a SELECT)", 2)
    relation = _nested_as_text(relation)
    batches = getattr(relation, "to_arrow_reader", None) or relation.fetch_arrow_reader  # DuckDB 2, else 1
    reader = batches(CSV_BATCH_ROWS)
    n = 0
    for batch in reader:
        write_csv(batch.to_pandas(), target, append=n > 0)
        n += batch.num_rows
    if n == 0:
        write_csv(reader.schema.empty_table().to_pandas(), target)
    return n


def _nested_as_text(relation):
    """The relation with its LIST, ARRAY, STRUCT, MAP and UNION columns as DuckDB's text of them ("[AXM123,
    MAS72]", as the terminal's table shows them): pandas wrote numpy's form ("['AXM123' 'MAS72']")."""
    columns, nested = [], False
    for name, kind in zip(relation.columns, relation.types, strict=True):
        quoted = '"' + name.replace('"', '""') + '"'
        text = str(kind)
        if text.endswith("]") or text.startswith(("STRUCT", "MAP", "UNION")):
            columns.append(f"CAST({quoted} AS VARCHAR) AS {quoted}")
            nested = True
        else:
            columns.append(quoted)
    return relation.project(", ".join(columns)) if nested else relation


__all__ = ["SqlOptions", "SqlResult", "sql_job", "validate"]
