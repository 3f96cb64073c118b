"""The workbook writer's shortcuts give what the cell-by-cell rules give: a column's width from its widest
candidates equals the widest of every cell, and memoised cell values equal excel_value() of each."""

from __future__ import annotations

import datetime as dt
import math

from budget import examples
from hypothesis import given, settings
from hypothesis import strategies as st

from msdc.pipeline.report.cells import (
    CLOCK_FORMAT,
    DATETIME_FORMAT,
    SUMMARY_DATETIME_FORMAT,
    column_width,
    display_len,
    excel_value,
    memo_values,
)
from msdc.pipeline.report.headers import column_name

FORMATS = [None, "0", "0.0", "0.0000", "0.000000", "#,##0", "#,##0.0", CLOCK_FORMAT, DATETIME_FORMAT,
           SUMMARY_DATETIME_FORMAT]
VALUES = st.one_of(st.none(), st.booleans(), st.integers(-10**12, 10**12),
                   st.floats(allow_infinity=False, width=64), st.sampled_from([0.0, -0.0, -1e-9, 0.5, -0.5]),
                   st.text(max_size=12), st.datetimes(min_value=dt.datetime(1990, 1, 1)))


def _naive_width(header: str, values: list, fmt: str | None) -> float:
    """The width rule applied to every cell (what column_width did before it took candidates)."""
    longest = max([max(len(word) for word in header.split(" ")), *(display_len(v, fmt) for v in values)])
    return min(66.0, max(6.0, longest + 2.0))


@settings(max_examples=examples(300), deadline=None)
@given(st.lists(VALUES, max_size=40), st.sampled_from(FORMATS))
def test_width_from_candidates_equals_width_from_every_cell(values, fmt):
    values = [v for v in values if not (isinstance(v, str) and fmt is not None)]  # a column is one kind
    values = [v for v in values if not (isinstance(v, float) and math.isnan(v))]  # NaN is an empty cell
    assert column_width("lat", values, fmt) == _naive_width("lat", values, fmt)


def test_width_sees_negative_zero_and_the_most_negative_value():
    # by hand: "-0.0000" is 7 characters, "0.0000" 6; "-12,345.0" 9
    assert column_width("x", [0.0, -0.0, 1.0], "0.0000") == max(6.0, 7 + 2.0)
    assert column_width("x", [3.0, -12345.0, -1.0], "#,##0.0") == 9 + 2.0


@given(st.lists(st.one_of(VALUES, st.just(math.nan), st.just(float("inf")), st.just("=1+1")), max_size=30))
def test_memo_values_equal_excel_value_of_each(values):
    expected = [excel_value(v) for v in values]
    got = memo_values(values)
    assert [(type(v), v) for v in got] == [(type(v), v) for v in expected]


def test_memo_values_keep_one_true_and_one_point_zero_apart_and_take_lists():
    assert [(type(v), v) for v in memo_values([1, True, 1.0, None])] == \
        [(int, 1), (bool, True), (float, 1.0), (type(None), None)]
    assert memo_values([[1, 2], "a"]) == ["[1, 2]", "a"]


# pipeline.report.rows: table rows written straight to the sheet's XML give the cells openpyxl writes

TRICKY = {
    "n": [1, -2, 0, 10**17 + 1, None, 7, 3, 0, 1, 2, 5],
    "lat": [0.1, -0.0, 1e-300, -123456.789, None, float("inf"), 2.5, 0.5, -1.0, 3.0, 1 / 3],
    "flag": [True, False, None, True, False, True, None, False, True, False, True],
    "callsign": ["MAS72", "", " lead", "a&b<c>d", "x\r\ny", "=1+1", "#N/A", "-3", "@x", None,
                 dt.datetime(2019, 3, 1, 8, 0, 1)],
}


def _workbook(tmp_path, name: str, fast: bool, monkeypatch) -> list[list[tuple]]:
    import openpyxl
    import pandas as pd
    from openpyxl import Workbook

    from msdc.pipeline.report import cells

    monkeypatch.setattr(cells, "FAST_ROWS", fast)
    wb = Workbook(write_only=True)
    ws = wb.create_sheet("T")
    frame = pd.DataFrame({k: pd.Series(v, dtype=object if k == "callsign" else None)
                          for k, v in TRICKY.items()})
    columns = [cells.make_column(ws, h, frame[h]) for h in frame.columns]
    cells.write_table(ws, columns, note="a note")
    wb.save(tmp_path / name)
    book = openpyxl.load_workbook(tmp_path / name)
    return [[(c.value, c.data_type, c.number_format, c.quotePrefix, c.alignment.horizontal,
              c.alignment.indent) for c in row] for row in book["T"].iter_rows()]


def test_raw_rows_write_the_cells_openpyxl_writes(tmp_path, monkeypatch):
    fast = _workbook(tmp_path, "fast.xlsx", True, monkeypatch)
    slow = _workbook(tmp_path, "slow.xlsx", False, monkeypatch)
    assert fast == slow
    # by hand, from the cell rules: text as text (formula-like with a quote prefix), numbers formatted
    by_header = dict(zip([column_name(c[0]) for c in slow[0]], zip(*slow[1:12], strict=True), strict=True))
    # call sign follows a column of booleans (aligned right): its text indented, formula-like text too
    assert by_header["callsign"][0] == ("MAS72", "s", "General", False, "left", 1)
    assert by_header["callsign"][3] == ("a&b<c>d", "s", "General", False, "left", 1)
    assert by_header["callsign"][5] == ("=1+1", "s", "General", True, "left", 1)
    assert by_header["lat"][1][0] == 0.0 and by_header["lat"][1][2] == "0.0000"
    assert by_header["lat"][5][0] == "inf"
    assert by_header["flag"][0][:2] == (True, "b")


def _sheet_xml(tmp_path, name: str, monkeypatch, many: bool) -> bytes:
    """The T sheet's XML with the TRICKY rows appended at once (RawRows, 3 rows parsed a time) or one by one
    (RawRow), row 5 given its own height (openpyxl writes it)."""
    import zipfile

    import pandas as pd
    from openpyxl import Workbook

    from msdc.pipeline.report import cells, rows

    monkeypatch.setattr(rows, "CHUNK_ROWS", 3)
    wb = Workbook(write_only=True)
    ws = wb.create_sheet("T")
    ws.row_dimensions[5].height = 30
    frame = pd.DataFrame({k: pd.Series(v, dtype=object if k == "callsign" else None)
                          for k, v in TRICKY.items()})
    columns = [cells.make_column(ws, h, frame[h]) for h in frame.columns]
    styles = rows.RowStyles(ws, [None if c.styled is None or c.text else c.number_format for c in columns])
    assert rows.install(ws, styles)
    ws.append(["header"])
    if many:
        rows.append_rows(ws, cells.raw_rows(ws, columns), len(frame))
    else:
        for row in cells.raw_rows(ws, columns):
            ws.append(row)
    ws.append(["after"])
    wb.save(tmp_path / name)
    return zipfile.ZipFile(tmp_path / name).read("xl/worksheets/sheet1.xml")


def test_rows_appended_at_once_are_the_rows_appended_one_by_one(tmp_path, monkeypatch):
    """Rows written together, parsed in chunks, with rows openpyxl writes among them (formula-like text,
    a date, infinity, a row with its own height), make the same sheet, byte for byte, row numbers
    included."""
    import re

    together = _sheet_xml(tmp_path, "many.xlsx", monkeypatch, True)
    one_by_one = _sheet_xml(tmp_path, "one.xlsx", monkeypatch, False)
    assert together == one_by_one
    numbers = [int(n) for n in re.findall(rb'<row r="(\d+)"', together)]
    assert numbers == list(range(1, len(TRICKY["n"]) + 3))  # header, 11 rows, the row after
    assert b'<row r="5" ht="30" customHeight="1">' in together


def test_install_declines_a_sheet_without_the_expected_internals():
    from msdc.pipeline.report.rows import RowStyles, install

    class Other:  # what a future openpyxl's sheet might look like: no _get_writer/_writer
        row_dimensions: dict = {}

    assert install(Other(), RowStyles(None, [])) is False


def test_install_takes_this_openpyxl_write_only_sheet():
    """With the openpyxl msdc is built against, the fast path is the one taken (so the comparison above
    compares two paths)."""
    from openpyxl import Workbook

    from msdc.pipeline.report.rows import RowStyles, install

    ws = Workbook(write_only=True).create_sheet("T")
    assert install(ws, RowStyles(ws, [None])) is True
    ws.close()
