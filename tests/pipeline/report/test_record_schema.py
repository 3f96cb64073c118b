"""The one output schema per category (report.record_schema): every column the reader builds, for every
edition of every category, with the dtype the reader gives it, and back with that dtype from Parquet."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from asterix_bytes import decode_bytes

from msdc.asterix.categories import category
from msdc.asterix.columns import BY_CATEGORY
from msdc.asterix.encode import encode_frame
from msdc.asterix.tables import available
from msdc.pipeline.report.record_schema import SchemaMismatch, record_schema

EDITIONS = [(cat, ed) for cat in sorted(BY_CATEGORY) for ed in available()[cat]]


def decoded(cat: int, edition: str) -> pd.DataFrame:
    """The reader's frame of two records of ``cat`` in ``edition`` carrying only SAC/SIC: every column of the
    edition is built, most of them empty, in the reader's dtypes."""
    data = encode_frame(cat, pd.DataFrame({"sac": [1, 3], "sic": [2, 4]}), edition=edition)
    return decode_bytes(data, editions={cat: edition}, categories=[cat]).frames[cat]


@pytest.mark.parametrize("cat, edition", EDITIONS)
def test_every_column_the_reader_builds_is_in_the_schema_with_its_dtype(tmp_path, cat, edition):
    frame = decoded(cat, edition).assign(file=pd.Categorical(["x.ast"] * 2))
    schema = record_schema(cat)
    rows = schema.conform(frame)
    assert list(rows.columns) == schema.columns and set(frame.columns) <= set(schema.columns)
    for column in frame.columns:
        assert rows[column].dtype == frame[column].dtype, column
    path = tmp_path / "o.parquet"
    with pq.ParquetWriter(path, schema.arrow()) as writer:
        writer.write_table(pa.Table.from_pandas(rows, schema=writer.schema, preserve_index=False))
    back = pd.read_parquet(path)
    for column in frame.columns:
        want = frame[column].dtype
        if isinstance(want, pd.CategoricalDtype):
            assert isinstance(back[column].dtype, pd.CategoricalDtype), column
        else:
            assert back[column].dtype == want, column
    assert back["sac"].tolist() == [1, 3] and back["sic"].tolist() == [2, 4]


@pytest.mark.parametrize("cat", sorted(BY_CATEGORY))
def test_the_schema_keeps_the_reader_order_for_the_default_edition(cat):
    """Identity and time first, provenance last, as the reader orders a frame; decode's file at the end."""
    frame = decoded(cat, category(cat).default_edition)
    order = [c for c in record_schema(cat).columns if c in frame.columns]
    assert order == list(frame.columns)
    assert record_schema(cat).columns[-3:] == ["block", "offset", "file"]


def test_a_column_missing_from_a_frame_is_absent_in_its_dtype():
    """A 0.2x frame under the CAT021 schema: the 2.x-only columns empty (NaN, <NA>), typed as documented."""
    frame = decoded(21, "0.23")
    rows = record_schema(21).conform(frame)
    assert "nacp" not in frame and rows["nacp"].dtype == "Int32" and rows["nacp"].isna().all()
    assert rows["time_applicability_position"].dtype == np.float64
    assert rows["time_applicability_position"].isna().all()
    assert rows["rc"].dtype == "Int8" and rows["rc"].isna().all()


def test_a_column_no_documented_list_has_is_refused_not_dropped():
    frame = decoded(48, "1.32").assign(new_field=1.0)
    with pytest.raises(SchemaMismatch, match="CAT048 column.*'new_field'"):
        record_schema(48).conform(frame)
