"""The one schema of a category's decoded records in an output file, fixed before any record is read.

Built from the documented columns (``asterix.columns``): every column of every edition family of the
category (CAT021 2.x and 0.2x alike), in the frames' order, each with the dtype its kind documents
(``KIND_DTYPES``), then the columns every frame has and decode's ``file``. Every chunk of every input is
written under it: a column the record's edition lacks stays empty, never shifted under another header,
and a text column's dictionary index is 32-bit whatever the number of distinct values (a chunk's own
schema would give int8 below 128 call signs, which the next chunk overflows). A category added to the
column registry gets its schema from its column lists, with no change here.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import pandas as pd

# the columns every frame has beside the documented ones (docs/columns.md), and decode's input label
FRAME_COLUMNS = {"day": "int64", "timestamp": "timestamp", "block": "int64", "offset": "int64"}
LABEL_COLUMNS = {"file": "text"}
TRAILING = ("block", "offset", "file")  # provenance last, as the frames put it
_WORDS = ("float64", "Int8", "Int16", "Int32", "Int64", "int64", "timestamp", "text")


class SchemaMismatch(ValueError):
    """A decoded frame holds a column its category's documented columns lack (a column list not updated
    beside the decoder): nothing is written rather than the column dropped."""


@dataclass(frozen=True)
class RecordSchema:
    """The output columns of one category, in order, each with its dtype word (``float64``, ``Int8``...
    ``Int32``, ``int64``, ``timestamp`` or ``text``: categorical in pandas, dictionary<int32, string> in
    Arrow)."""

    category: int
    dtypes: dict[str, str]

    @property
    def columns(self) -> list[str]:
        """The column names, in file order."""
        return list(self.dtypes)

    def conform(self, frame: pd.DataFrame) -> pd.DataFrame:
        """``frame`` with exactly the schema's columns in its order (columns it lacks all absent, in their
        dtype), no column copied; SchemaMismatch naming a column the schema lacks."""
        extra = [c for c in frame.columns if c not in self.dtypes]
        if extra:
            raise SchemaMismatch(f"CAT{self.category:03d} column(s) {', '.join(map(repr, extra))} are in no "
                                 "documented column list of the category (asterix.columns)")
        n = len(frame)
        return pd.DataFrame({name: frame[name] if name in frame.columns else absent(kind, n)
                             for name, kind in self.dtypes.items()}, index=frame.index, copy=False)

    def arrow(self):
        """The Arrow schema (with pandas' metadata: nullable integers and categories read back as such),
        made once per process: it takes about 0.2 s, which every input written and every window read
        of a dataset paid."""
        return _arrow_schema(self.category, tuple(self.dtypes.items()))


@cache
def _arrow_schema(category: int, dtypes: tuple[tuple[str, str], ...]):
    """RecordSchema.arrow of the schema of these columns (an Arrow schema is immutable: shared)."""
    import pyarrow as pa

    words = dict(dtypes)
    template = RecordSchema(category, words).conform(pd.DataFrame(index=pd.RangeIndex(0)))
    schema = pa.Schema.from_pandas(template, preserve_index=False)
    for name, kind in words.items():
        i = schema.get_field_index(name)
        if kind == "text":
            schema = schema.set(i, pa.field(name, pa.dictionary(pa.int32(), pa.string())))
        elif kind == "timestamp":
            schema = schema.set(i, pa.field(name, pa.timestamp("ns", tz="UTC")))
    return schema


def absent(kind: str, n: int):
    """An all-absent column of ``n`` rows in the dtype word ``kind`` (``int64``, never absent in a frame,
    as nullable Int64 when rows need it)."""
    if kind == "text":
        return pd.Categorical.from_codes(np.full(n, -1), categories=pd.Index([], dtype=object))
    if kind == "float64":
        return np.full(n, np.nan)
    if kind == "timestamp":
        return pd.Series(np.full(n, np.datetime64("NaT"), "datetime64[ns]")).dt.tz_localize("UTC").array
    if kind == "int64" and n == 0:
        return np.zeros(0, np.int64)
    dtype = np.dtype(kind.lower())
    return pd.arrays.IntegerArray(np.zeros(n, dtype), np.ones(n, bool))


def dtype_word(kind: str) -> str:
    """The dtype word of a column kind, read from its documentation (KIND_DTYPES: ``Int32``, ``float64
    (NaN if absent)``, ``text (categorical)``); ValueError for a kind documented in none of them."""
    from msdc.asterix.columns import KIND_DTYPES

    try:
        word = KIND_DTYPES[kind].split()[0]
    except KeyError:
        raise ValueError(f"column kind {kind!r} has no documented dtype (asterix.columns.KIND_DTYPES)"
                         ) from None
    if word not in _WORDS:
        raise ValueError(f"column kind {kind!r}: documented dtype {KIND_DTYPES[kind]!r} is not one an output "
                         f"file can hold ({', '.join(_WORDS)})")
    return word


def _editions(category: int) -> list[str]:
    """The shipped editions of ``category``: its default first, then the others newest first."""
    from msdc.asterix.categories import category as registered
    from msdc.asterix.tables import available

    default = registered(category).default_edition
    def version(ed: str) -> tuple:
        return tuple(int(p) if p.isdigit() else p for p in ed.split("."))

    others = sorted((e for e in available().get(category, []) if e != default), key=version, reverse=True)
    return [default, *others]


@cache
def record_schema(category: int) -> RecordSchema:
    """The output schema of ``category``: the union of its editions' documented columns (an ``icao`` column
    followed by its ``_hex`` twin) in frame order, the identity and time first and the provenance last;
    ValueError when two editions give one column name two dtypes."""
    from msdc.asterix.columns import columns_for
    from msdc.asterix.reader import LEADING

    documented: dict[str, str] = {}
    for edition in _editions(category):
        for col in columns_for(category, edition):
            named = [(col.name, dtype_word(col.kind))] + ([(f"{col.name}_hex", "text")] if col.kind == "icao"
                                                          else [])
            for name, word in named:
                if documented.setdefault(name, word) != word:
                    raise ValueError(f"CAT{category:03d} column {name!r} is {documented[name]} in one "
                                     f"edition and {word} in another: one output file cannot hold both")
    every = {**documented, **FRAME_COLUMNS, **LABEL_COLUMNS}
    leading = [c for c in LEADING if c in every]
    middle = [c for c in every if c not in leading and c not in TRAILING]
    return RecordSchema(category, {c: every[c] for c in [*leading, *middle, *TRAILING]})


__all__ = ["FRAME_COLUMNS", "RecordSchema", "SchemaMismatch", "absent", "dtype_word", "record_schema"]
