"""Compare two datasets written by ``msdc ingest`` row by row: the same partitions, and in each the same
rows (in file order: sorted by file and offset), columns, Arrow types and values (NaN equal to NaN, null
to null); part files, row groups and compression may differ. Prints what differs; exit 1 if anything does.

    python benchmarks/compare_datasets.py DATASET_A DATASET_B

Used to check that a change to the writer leaves a dataset's content as it was (issue 29).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq


def partitions(root: Path) -> dict[str, list[Path]]:
    """Each partition folder (relative) and its part files."""
    out: dict[str, list[Path]] = {}
    for part in sorted(root.glob("date=*/category=*/sensor=*/part-*.parquet")):
        out.setdefault(part.parent.relative_to(root).as_posix(), []).append(part)
    return out


def read(parts: list[Path]) -> pa.Table:
    """A partition's rows in file order (by file label, then offset), schema metadata dropped."""
    table = pa.concat_tables([pq.read_table(p) for p in parts])
    keys = pa.table({"file": table.column("file").cast(pa.string()), "offset": table.column("offset")})
    table = table.take(pc.sort_indices(keys, [("file", "ascending"), ("offset", "ascending")]))
    return table.replace_schema_metadata(None)


def differences(a: pa.Table, b: pa.Table) -> list[str]:
    """What differs between two partitions' tables."""
    if a.schema != b.schema:
        return [f"schemas differ:\n{a.schema}\n---\n{b.schema}"]
    if a.num_rows != b.num_rows:
        return [f"{a.num_rows} rows against {b.num_rows}"]
    out = []
    for name in a.column_names:
        x, y = a.column(name).combine_chunks(), b.column(name).combine_chunks()
        if pa.types.is_dictionary(x.type):
            x, y = x.cast(x.type.value_type), y.cast(y.type.value_type)
        if x.null_count != y.null_count or not pc.all(pc.equal(x.is_null(), y.is_null())).as_py():
            out.append(f"{name}: nulls differ")
            continue
        if pa.types.is_floating(x.type):
            same = pc.or_(pc.equal(x, y), pc.and_(pc.is_nan(x), pc.is_nan(y)))
        else:
            same = pc.equal(x, y)
        if not pc.all(pc.fill_null(same, True)).as_py():
            out.append(f"{name}: values differ")
    return out


def main() -> int:
    a, b = (Path(p) for p in sys.argv[1:3])
    pa_, pb = partitions(a), partitions(b)
    bad = 0
    for key in sorted(set(pa_) | set(pb)):
        if key not in pa_ or key not in pb:
            print(f"{key}: only in {a if key in pa_ else b}")
            bad += 1
            continue
        diff = differences(read(pa_[key]), read(pb[key]))
        for line in diff:
            print(f"{key}: {line}")
        bad += bool(diff)
    rows = sum(pq.ParquetFile(p).metadata.num_rows for parts in pa_.values() for p in parts)
    size_a = sum(p.stat().st_size for parts in pa_.values() for p in parts)
    size_b = sum(p.stat().st_size for parts in pb.values() for p in parts)
    print(f"{len(pa_)} partitions, {rows} rows; {'identical content' if not bad else f'{bad} differ'}; "
          f"files {size_a / 1e6:.1f} MB against {size_b / 1e6:.1f} MB")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
