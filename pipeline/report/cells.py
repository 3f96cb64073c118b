"""Cells, columns and page setup of msdc's write-only workbooks (shared by the report's sheets and charts).

Cell rules: times are real Excel date-times in UTC (clock times when the date is unknown, never seconds of
day), numbers are numbers (NaN -> empty cell) with the format of their unit (``pipeline.report.formats``),
one style per column, all text is stored as text (never as a formula). Pages: A4 landscape, fitted to the
page width, header rows repeated.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import re
import textwrap
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from itertools import islice
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from openpyxl.cell import WriteOnlyCell
from openpyxl.cell.cell import ILLEGAL_CHARACTERS_RE, Cell
from openpyxl.styles import DEFAULT_FONT, Alignment, Border, Font, PatternFill, Side
from openpyxl.utils import get_column_letter
from openpyxl.worksheet._write_only import WriteOnlyWorksheet
from openpyxl.xml import LXML

from msdc.pipeline.model.sources import escaped
from msdc.pipeline.report.formats import UNITS, column_unit, excel_format
from msdc.pipeline.report.headers import workbook_header
from msdc.pipeline.report.rows import RawRow, RowStyles, append_rows, bool_cell, install
from msdc.pipeline.report.summary import (
    is_missing,
    json_value,
    utc_naive,
)
from msdc.pipeline.report.textguard import FORMULA_START

if not LXML:  # pragma: no cover - lxml is a dependency; OPENPYXL_LXML=False would halve the write speed
    import warnings

    warnings.warn("openpyxl is not using lxml (is OPENPYXL_LXML set?): workbooks will be written slowly",
                  stacklevel=1)

DATETIME_FORMAT = "yyyy-mm-dd hh:mm:ss.000"
SUMMARY_DATETIME_FORMAT = 'yyyy-mm-dd hh:mm:ss "UTC"'  # a window's start/end: an Excel date, labelled
DATE_FORMAT = "yyyy-mm-dd"
TIME_FORMAT = "hh:mm:ss.000"
CLOCK_FORMAT = UNITS["tod"].excel  # seconds of day shown as a clock time ([hh] runs past 24 h)
MAX_CORRELATION_CHARTS = 20
MAX_SLOT_CHART_WINDOWS = 10
EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_TEXT = 32_767
MIN_WIDTH, MAX_WIDTH = 6.0, 66.0
# A column is as wide as its widest content with a character's gap either side (GAP_CHARS). A text column
# right of a numeric one is indented one level: a number flush with its column's right edge would otherwise
# touch the text flush with the next column's left edge (1.6 | 2 printed as "1.62"); the indent, about 1.5
# characters in LibreOffice (1 in Excel), is that column's gap on its left
GAP_CHARS, INDENT_CHARS = 1.0, 1.5
# A header is bold, and a bold word is wider than its letters: 'Maximum' 8.8 characters, which LibreOffice
# broke as 'Maximu|m' in a column of 9. Per character, its width in the unit of column widths (the digit
# of the body font): the wider of DejaVu Sans Bold and DejaVu Serif Bold (LibreOffice's headers where
# Calibri is missing) against DejaVu Sans's digit, rounded up to 0.05 (Calibri Bold against Calibri's digit
# is within that); any other character 1.25
_BOLD_WIDTHS = {char: width for width, chars in {
    0.5: "'", 0.55: " ", 0.6: "ijl,./\\|", 0.65: ":;", 0.7: "f-", 0.75: "IJ!()[]", 0.8: "t_`\u00b0",
    0.85: 'r"*', 0.95: "sz?", 1.0: "c", 1.05: "vxy", 1.1: "0123456789aeko$", 1.15: "bdghnpquFLSYZ{}",
    1.2: "EPT\u00b5", 1.25: "AVX", 1.3: "C", 1.35: "BGR#+<=>^~\u00b1", 1.4: "DKOQU", 1.45: "N&", 1.5: "wH",
    1.6: "%@", 1.7: "m", 1.75: "M", 1.8: "W"}.items() for char in chars}
# The same for the body's regular text: the wider of DejaVu Sans Book (LibreOffice's face where Calibri is
# missing) and Carlito (Calibri's metrics), each against its own digit, rounded up to 0.05; any other
# character 1.25. Wrapped text's lines are counted with these: counted as characters, a line of a
# scorecard's notes held 54 where 43 were counted, and its rows printed half again too tall
_REGULAR_WIDTHS = {char: width for width, chars in {
    0.45: "'", 0.5: "ijlI,. ", 0.55: ":;", 0.65: "fJ!()-[]", 0.7: "rt", 0.8: '"/\\`\u00b0', 0.85: "sz",
    0.9: "cL", 0.95: "kvxyF?|", 1.0: "aegESTY0123456789$*_{}\u2013", 1.05: "bdhnopquKP",
    1.1: "BCRXZ\u00b5", 1.15: "AV", 1.25: "DGH", 1.3: "NU", 1.35: "OQ#&+<=>^~\u00b1", 1.45: "w", 1.5: "%",
    1.6: "m", 1.7: "M", 1.8: "W@"}.items() for char in chars}
_WIDTH_SAMPLE_ROWS = 5000
FAST_ROWS = True  # table rows through pipeline.report.rows (False: openpyxl's append, cell by cell)
_ISO_DATE = re.compile(r"\d{4}-\d{2}-\d{2}\Z")
_ISO_DATETIME = re.compile(r"\d{4}-\d{2}-\d{2}[T ]\d{2}:\d{2}(:\d{2}(\.\d{1,9})?)?(Z|[+-]\d{2}:?\d{2})?\Z")
_DATETIME_HEADERS = {"time_utc", "start", "end", "timestamp", "run_time"}
_DATE_CODES = re.compile(r"yy|hh")  # a number format showing a date or a time
_FORMAT_SYNTAX = re.compile(r'[\[\]"]')  # what a number format has that its text does not

# every font named as the body's (openpyxl's default, Calibri): a font without a name printed in LibreOffice's
# default serif face, so headers, titles and notes did not match the cells under them
BODY_FONT = DEFAULT_FONT.name
BOLD = Font(name=BODY_FONT, bold=True)
TITLE_FONT = Font(name=BODY_FONT, bold=True, size=12)
NOTE_FONT = Font(name=BODY_FONT, italic=True, color="595959")
HEADER_FILL = PatternFill("solid", fgColor="D9E1F2")
_BLOCK_FILLS = ["EDEDED", "E2EFDA", "DDEBF7", "FCE4D6"]
_HEADER_BORDER = Border(bottom=Side(style="thin", color="808080"))
# a header's alignment by (right, indented): aligned as its column's values (aligned_right, indented)
_HEADER_ALIGN = {(right, indent): Alignment(horizontal="right" if right else "left", indent=int(indent),
                                            vertical="center", wrap_text=True)
                 for right in (False, True) for indent in (False, True)}
INDENTED = Alignment(horizontal="left", indent=1)  # an indented column's text (INDENT_CHARS)

# A4 landscape, margins, fixed row height: the page grid charts and figures are placed on
PAPER_A4 = 9
MARGIN_IN = 0.4
ROW_HEIGHT_PT = 15.0


# ----------------------------------------------------------------------------------------------- values

def excel_value(value: Any) -> Any:
    """A value openpyxl stores natively: None for missing, naive-UTC datetime, int, float, bool or text."""
    if is_missing(value):
        return None
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, pd.Timestamp | dt.datetime | np.datetime64):
        return utc_naive(value)
    if isinstance(value, dt.date | dt.time):
        return value
    if isinstance(value, pd.Timedelta | dt.timedelta | np.timedelta64):  # before Integral: timedelta64 is one
        return pd.Timedelta(value).total_seconds()
    if isinstance(value, Integral):
        return int(value)
    if isinstance(value, Real):
        number = float(value)
        return number if math.isfinite(number) else ("inf" if number > 0 else "-inf")
    if isinstance(value, str):
        return clean_text(value)
    if isinstance(value, Path):
        return clean_text(str(value))
    if isinstance(value, Mapping | list | tuple | set | frozenset | np.ndarray):
        return clean_text(json.dumps(json_value(value), ensure_ascii=False))
    return clean_text(str(value))


def iso_time(text: str) -> dt.datetime | dt.date | None:
    """A naive-UTC datetime (or a date) when ``text`` is an ISO 8601 date-time (or date), else None. Only for
    the Parameters sheet, whose values arrive as the JSON's text (``run_utc``, ``date``); tables carry
    datetimes and their text is never parsed."""
    if not (10 <= len(text) <= 40 and text[:1].isdigit()):
        return None
    try:
        if _ISO_DATE.match(text):
            return dt.date.fromisoformat(text)
        if _ISO_DATETIME.match(text):
            return utc_naive(pd.Timestamp(text))
    except ValueError:
        pass
    return None


def clean_text(text: str) -> str:
    """Text Excel can hold: XML-illegal control characters replaced, a lone surrogate (a file name's bytes
    that are not UTF-8) as its escape, cut at Excel's cell limit."""
    return escaped(ILLEGAL_CHARACTERS_RE.sub("\ufffd", text))[:EXCEL_MAX_TEXT]


def text_cell(ws: WriteOnlyWorksheet, text: str, *, font: Font | None = None,
              fill: PatternFill | None = None) -> WriteOnlyCell:
    """A string cell that can never become a formula (type "s"; quote prefix on formula-like text)."""
    cell = WriteOnlyCell(ws, text)
    cell.data_type = "s"
    if text.startswith(FORMULA_START):
        cell.quotePrefix = True
    if font is not None:
        cell.font = font
    if fill is not None:
        cell.fill = fill
    return cell


def is_number(value: Any) -> bool:
    """A real int or float (not a bool): the values a numeric cell format applies to."""
    return isinstance(value, int | float) and not isinstance(value, bool)


def cell_for(ws: WriteOnlyWorksheet, value: Any, number_format: str | None) -> Any:
    """The cell (or plain value) for an excel_value() result under a column number format; a boolean reads
    TRUE or FALSE (rows.BOOL_FORMAT)."""
    if value is None:
        return value
    if isinstance(value, bool):
        return bool_cell(ws, value)
    if isinstance(value, str):
        return text_cell(ws, value)
    if isinstance(value, dt.datetime):
        number_format = DATETIME_FORMAT
    elif isinstance(value, dt.date):
        number_format = DATE_FORMAT
    elif isinstance(value, dt.time):
        number_format = TIME_FORMAT
    elif number_format is None or (isinstance(value, int) and number_format == "0"):
        return value
    elif number_format == CLOCK_FORMAT:
        value = value / 86400.0
    cell = WriteOnlyCell(ws, value)
    cell.number_format = number_format
    return cell


# ------------------------------------------------------------------------------------ column writing

@dataclass
class Column:
    """One output column: its header, cell values (already Excel-ready) and, for numbers that need it, a
    template cell carrying the column's number format, reused for every value (styling by column)."""

    header: str
    values: list[Any]
    number_format: str | None
    styled: WriteOnlyCell | None = None
    text: bool = False  # values may hold text, which must be checked for formula-like starts
    bools: bool = False  # values may hold booleans, written with rows.BOOL_FORMAT
    wrap: int | None = None  # text longer than this many characters wraps inside its cell (write_table)
    indent: bool = False  # its text indented one level (INDENT_CHARS: a text column right of a numeric one)


def _datetime_serials(series: pd.Series) -> list[Any]:
    """Excel serial days (UTC wall clock) of a datetime column, None where missing."""
    stamps = series.dt.tz_convert("UTC").dt.tz_localize(None) if series.dt.tz is not None else series
    days = (stamps - pd.Timestamp("1899-12-30")) / pd.Timedelta(days=1)
    return [None if v != v else v for v in days.round(11).to_numpy(dtype=float, na_value=np.nan).tolist()]


def column_values(series: pd.Series) -> list[Any]:
    """excel_value() of every entry, with fast paths for plain float, integer and bool columns."""
    dtype = series.dtype
    if dtype.kind == "f" and isinstance(dtype, np.dtype):
        values = series.to_numpy()
        if np.isinf(values).any():
            return [excel_value(v) for v in values.tolist()]
        return [None if v != v else v for v in values.tolist()]  # v != v: NaN
    if dtype.kind in "iub" and isinstance(dtype, np.dtype):
        return series.to_numpy().tolist()
    return memo_values(series.tolist())


def memo_values(values: list[Any]) -> list[Any]:
    """excel_value() of every entry, worked out once per distinct value (identity columns repeat a few
    values over thousands of rows); keyed by type and value, so 1, 1.0 and True stay apart."""
    try:
        keys = list(zip(map(type, values), values, strict=True))
        memo = {key: excel_value(key[1]) for key in set(keys)}
    except TypeError:  # an unhashable value (a list or a dict): one at a time
        return [excel_value(v) for v in values]
    return [memo[key] for key in keys]


def _fallback_format(values: Iterable[Any]) -> str | None:
    numbers = [v for v in values if is_number(v)]
    if not numbers or all(float(v).is_integer() for v in numbers):
        return None
    return "0.000000" if max(abs(v) for v in numbers) < 1 else "0.000"


def number_format_for(name: str, values: Iterable[Any]) -> str | None:
    """Number format of a column: from the unit table by name, else from sample values (None = General)."""
    return excel_format(name) or _fallback_format(values)


def make_column(ws: WriteOnlyWorksheet, header: str, data: pd.Series | list[Any], *,
                general: bool = False) -> Column:
    """A Column from a pandas Series (fast paths for numbers and datetimes) or a list of raw values.

    Seconds-of-day columns become clock times; datetimes become Excel date-times; numbers take the format
    of their unit. ``general`` keeps numbers in General format (columns mixing unrelated values)."""
    series = data if isinstance(data, pd.Series) else pd.Series(list(data), dtype=object)
    unit = None if general else column_unit(header)
    if isinstance(series.dtype, pd.DatetimeTZDtype) or series.dtype.kind == "M":
        column = Column(header, _datetime_serials(series), DATETIME_FORMAT)
    else:
        values = column_values(series)
        if unit == "tod" and all(v is None or is_number(v) for v in values):
            values = [None if v is None else v / 86400.0 for v in values]
            column = Column(header, values, CLOCK_FORMAT)
        else:
            kinds = {type(v) for v in values[:_WIDTH_SAMPLE_ROWS] if v is not None}
            mixed = bool(kinds - {int, float, bool})
            fmt = None if general else number_format_for(header, values[:_WIDTH_SAMPLE_ROWS])
            if mixed:  # text, dates, mixed types: one cell at a time
                return Column(header, values, fmt, text=True)
            if fmt == "0" and kinds <= {int, bool}:
                fmt = None  # integers read the same in General
            column = Column(header, values, fmt, bools=bool in kinds)
    if column.number_format is not None:
        column.styled = WriteOnlyCell(ws, 0.0)
        column.styled.number_format = column.number_format
    return column


def table_rows(ws: WriteOnlyWorksheet, columns: list[Column], start: int = 0,
          stop: int | None = None) -> Iterator[list[Any]]:
    """Rows of cells for ws.append: plain values where General will do, the column's styled cell (value
    swapped in) for formatted numbers, text cells for text."""
    styled = [(j, c.styled) for j, c in enumerate(columns) if c.styled is not None and not c.text]
    texts = [(j, c.number_format) for j, c in enumerate(columns) if c.text]
    flags = [j for j, c in enumerate(columns) if c.bools and not c.text]
    wraps = _wraps(columns)
    indents = [j for j, c in enumerate(columns) if c.indent]
    for row in islice(zip(*(c.values for c in columns), strict=True), start, stop):
        out = list(row)
        for j, cell in styled:
            value = out[j]
            if value is not None and value.__class__ is not bool:
                cell.value = value
                out[j] = cell
        for j in flags:
            if out[j].__class__ is bool:
                out[j] = bool_cell(ws, out[j])
        for j, fmt in texts:
            value = out[j]
            if value is not None and not (value.__class__ is str and not value.startswith(FORMULA_START)):
                out[j] = cell_for(ws, value, fmt)
        if wraps:
            _wrap_long(ws, out, wraps)
        for j in indents:
            _indent(ws, out, j)
        yield out


_WRAPPED = {False: Alignment(wrap_text=True),  # bottom-aligned, as the row's other cells
            True: Alignment(horizontal="left", indent=1, wrap_text=True)}  # and indented (Column.indent)


def _wraps(columns: list[Column]) -> list[tuple[int, int, bool]]:
    """(index, characters, indented) of the text columns whose long text wraps."""
    return [(j, c.wrap, c.indent) for j, c in enumerate(columns) if c.text and c.wrap]


def _wrap_long(ws: WriteOnlyWorksheet, row: list[Any], wraps: list[tuple[int, int, bool]]) -> None:
    """Text longer than its column's ``wrap`` as a cell that wraps (cleaned as text_cell does): it would
    otherwise run on to the right, and the printed page, fitted to the widest row, would shrink to it."""
    for j, chars, indent in wraps:
        value = row[j]
        if value.__class__ is str and len(value) > chars:
            cell = text_cell(ws, clean_text(value))
            cell.alignment = _WRAPPED[indent]
            row[j] = cell


def _indent(ws: WriteOnlyWorksheet, row: list[Any], j: int) -> None:
    """The text of an indented column (Column.indent) as an indented cell, a text cell made elsewhere
    (formula-like text, wrapped text) indented as it is; numbers and dates stay right-aligned."""
    value = row[j]
    if value.__class__ is str:
        cell = WriteOnlyCell(ws, value)
        cell.alignment = INDENTED
        row[j] = cell
    elif isinstance(value, Cell) and value.data_type == "s" and not value.alignment.indent:
        value.alignment = INDENTED


def raw_rows(ws: WriteOnlyWorksheet, columns: list[Column], start: int = 0,
             stop: int | None = None) -> Iterator[RawRow]:
    """Rows for a sheet set up by rows.install: values as they are (the writer gives numbers their
    column's style), text columns' formula-like text and other values as cells, as table_rows does."""
    texts = [(j, c.number_format) for j, c in enumerate(columns) if c.text]
    wraps = _wraps(columns)
    for row in islice(zip(*(c.values for c in columns), strict=True), start, stop):
        out = RawRow(row)
        for j, fmt in texts:
            value = out[j]
            if value is not None and not (value.__class__ is str and not value.startswith(FORMULA_START)):
                out[j] = cell_for(ws, value, fmt)
                if columns[j].indent:  # plain text the writer indents itself (RowStyles.aligns)
                    _indent(ws, out, j)
        if wraps:
            _wrap_long(ws, out, wraps)
        yield out


def display_len(value: Any, number_format: str | None) -> int:
    """Characters the value takes shown under number_format: what a column's width must hold."""
    if value is None:
        return len(SUMMARY_DATETIME_FORMAT) if number_format == SUMMARY_DATETIME_FORMAT else 0
    if isinstance(value, str):
        return max(len(line) for line in value.split("\n"))
    if isinstance(value, bool):
        return 5
    if number_format == SUMMARY_DATETIME_FORMAT:
        return len(SUMMARY_DATETIME_FORMAT)
    if isinstance(value, dt.datetime) or number_format == DATETIME_FORMAT:
        return len(DATETIME_FORMAT)
    if isinstance(value, dt.date | dt.time) or number_format == CLOCK_FORMAT:
        return 12
    if number_format and _DATE_CODES.search(number_format):  # another date format ("UTC"-labelled ones)
        return len(_FORMAT_SYNTAX.sub("", number_format))
    if number_format and "." in number_format:
        return len(f"{value:,.{number_format.count('0', number_format.index('.'))}f}")
    if number_format and number_format.startswith("#,"):
        return len(f"{value:,.0f}")
    if isinstance(value, float) and not number_format:
        return min(len(repr(value)), 12)
    return len(f"{value:.0f}") if isinstance(value, float) else len(str(value))


def _widest(values: Iterable[Any], number_format: str | None) -> list[Any]:
    """The values among ``values`` whose display_len() can be the longest: every distinct value, except
    that of the ints, and of the floats under a number format, only the largest and the most negative
    (their text grows with the magnitude, a minus sign included, -0.0's too): a column's width costs a
    few format calls instead of one per cell."""
    ints, floats, rest = [], [], {}
    for value in values:
        kind = value.__class__
        if kind is int:
            ints.append(value)
        elif kind is float and number_format is not None:
            floats.append(value)
        else:
            try:
                rest[(kind, value)] = value
            except TypeError:  # unhashable: kept as it is
                rest[(kind, id(value))] = value
    widest = list(rest.values())
    if ints:
        widest += [max(ints), min(ints)]
    if floats:
        array = np.asarray(floats, dtype=float)
        negative, nan = np.signbit(array), np.isnan(array)
        for part in (array[~negative & ~nan], array[negative & ~nan]):
            if part.size:
                widest += [float(part.max()), float(part.min())]
        if nan.any():
            widest.append(math.nan)
    return widest


def column_width(header: str, values: Iterable[Any], number_format: str | None,
                 label: str | None = None, indent: bool = False) -> float:
    """Column width (characters) fitting the longest word of the header printed (``label``, else
    ``header``) and the widest values, GAP_CHARS either side, the left one INDENT_CHARS for an ``indent``
    (Column.indent), within limits; a header word also as printed in bold (bold_width) with GAP_CHARS to
    spare, after the indent."""
    words = (label or header).split(" ")
    longest = max([max(len(word) for word in words),
                   *(display_len(v, number_format) for v in _widest(values, number_format))])
    if header in _DATETIME_HEADERS:
        longest = max(longest, display_len(None, number_format) or len(DATETIME_FORMAT))
    bold = max(bold_width(word) for word in words) + (INDENT_CHARS if indent else 0.0) + GAP_CHARS
    return min(MAX_WIDTH, max(MIN_WIDTH, left_space(indent) + longest + GAP_CHARS, bold))


def bold_width(text: str) -> float:
    """Printed width of bold header text in characters of column width (_BOLD_WIDTHS)."""
    return text_width(text, bold=True)


def text_width(text: str, bold: bool = False) -> float:
    """Printed width of text in characters of column width (_REGULAR_WIDTHS, or _BOLD_WIDTHS when bold)."""
    widths = _BOLD_WIDTHS if bold else _REGULAR_WIDTHS
    return sum(widths.get(char, 1.25) for char in text)


def wrapped_lines(text: str, width: float, bold: bool = False) -> int:
    """The lines a cell shows of ``text`` wrapped at its spaces and line breaks into ``width`` characters of
    column width (text_width); a word wider than the line is broken where it reaches the edge."""
    space = text_width(" ", bold)
    width = max(width, 1.0)
    lines = 0
    for paragraph in text.split("\n"):
        lines, line = lines + 1, 0.0
        for word in paragraph.split(" "):
            size = text_width(word, bold)
            if line and line + space + size > width:
                lines, line = lines + 1, 0.0
            line += (space if line else 0.0) + size
            while line > width:  # a word longer than a line runs on to the next
                lines, line = lines + 1, line - width
    return lines


def left_space(indent: bool) -> float:
    """The space left of a column's content: its indent (INDENT_CHARS) or the gap (GAP_CHARS)."""
    return INDENT_CHARS if indent else GAP_CHARS


def set_widths(ws: WriteOnlyWorksheet, widths: list[float]) -> None:
    """Set the sheet's column widths in order (before any row is written, as write-only sheets need)."""
    for i, width in enumerate(widths, start=1):
        ws.column_dimensions[get_column_letter(i)].width = round(width, 1)


def aligned_right(values: Iterable[Any], number_format: str | None = None) -> bool:
    """Whether a column's cells print right-aligned: every value a number, a date or time (a number to a
    spreadsheet) or a boolean; any text makes it a text column, aligned left. A column without values: by
    its number format (a numeric column's)."""
    seen = False
    for value in values:
        if isinstance(value, str):
            return False
        seen = seen or value is not None
    return seen or number_format is not None


def indented(right: list[bool]) -> list[bool]:
    """Per column, whether it is indented (INDENT_CHARS): a left-aligned column right of a right-aligned
    one (``right``: aligned_right per column)."""
    return [j > 0 and right[j - 1] and not r for j, r in enumerate(right)]


def header_cells(ws: WriteOnlyWorksheet, headers: list[str], fill: PatternFill = HEADER_FILL,
                 right: list[bool] | None = None) -> list[Any]:
    """Bold, filled, bordered and wrapped header cells, each aligned as its column's values (``right``:
    aligned_right per column; None: all text), a numeric column's header right (a number prints under its
    own header, not nearer the next column's), an indented column's indented (indented)."""
    right = right or [False] * len(headers)
    cells = []
    for j, (header, indent) in enumerate(zip(headers, indented(right), strict=True)):
        cell = text_cell(ws, clean_text(str(header)), font=BOLD, fill=fill)
        cell.border = _HEADER_BORDER
        cell.alignment = _HEADER_ALIGN[right[j], indent]
        cells.append(cell)
    return cells


def header_height(headers: list[str], widths: list[float], right: list[bool] | None = None) -> float:
    """Height (points) of a header row whose headers wrap at their spaces into columns of ``widths``
    characters (less an indented column's indent: ``right``, aligned_right per column): the lines of the
    longest, as many as its letters or its bold words (bold_width) take, whichever is more, set explicitly
    (spreadsheet programs do not all fit it)."""
    indents = indented(right) if right else [False] * len(headers)
    lines = [max(len(textwrap.wrap(h, width=max(1, int(w) - 1), break_long_words=False) or [h]),
                 wrapped_lines(h, w - (INDENT_CHARS if indent else 0.0), bold=True))
             for h, w, indent in zip(headers, widths, indents, strict=False)]
    return max([1, *lines]) * ROW_HEIGHT_PT


def note_text_cell(ws: WriteOnlyWorksheet, text: str) -> WriteOnlyCell:
    """A note's cell: its text cleaned for Excel, in the note font."""
    return text_cell(ws, clean_text(text), font=NOTE_FONT)


def page_setup(ws: WriteOnlyWorksheet, title_rows: str | None = "1:1", *, fit_height: int = 0) -> None:
    """A4 landscape, fitted to one page wide (``fit_height`` pages tall, 0 = as many as needed), narrow
    margins, header rows repeated on every page, sheet name and page number in the footer."""
    ws.page_setup.orientation = "landscape"
    ws.page_setup.paperSize = PAPER_A4
    ws.page_setup.fitToWidth = 1
    ws.page_setup.fitToHeight = fit_height
    ws.sheet_properties.pageSetUpPr.fitToPage = True
    for side in ("left", "right"):
        setattr(ws.page_margins, side, MARGIN_IN)
    ws.page_margins.top = ws.page_margins.bottom = 0.5
    ws.page_margins.header = ws.page_margins.footer = 0.25
    if title_rows:
        ws.print_title_rows = title_rows
    ws.oddFooter.center.text = "&A, page &P of &N"


PAGE_WIDTH_CHARS = 170  # characters of column width a landscape page shows legibly
# a short table (a page tall or less) up to this wide prints on one page, smaller (down to about half size),
# rather than across pages that each hold a few columns of a row or two (wider: 2-3 pages, as a long one)
PAGE_SLACK = 0.1  # a table up to this much of a page wider than a whole number of pages is fitted to it
SHORT_TABLE_ROWS, SHORT_TABLE_MAX_CHARS = 40, 1.5 * PAGE_WIDTH_CHARS


def wide_pages(ws: WriteOnlyWorksheet, widths: list[float], text: list[bool], rows: int | None = None) -> int:
    """For a table wider than one legible landscape page: fit it to 2 or 3 pages wide instead of 1 and
    repeat its leading text columns (identity: call sign, address, sensor) on every page; a short one
    (``rows``, page_count) stays one page wide. Returns the number of pages wide."""
    pages = page_count(widths, rows)
    if pages > 1:
        ws.page_setup.fitToWidth = pages
        ws.page_setup.pageOrder = "overThenDown"  # a band of rows on consecutive pages, then the next
        lead = lead_columns(text)
        if lead:
            ws.print_title_cols = f"A:{get_column_letter(lead)}"
    return pages


def page_count(widths: list[float], rows: int | None = None) -> int:
    """How many landscape pages wide a table of these column widths prints (1 to 3): one for a short table
    (at most SHORT_TABLE_ROWS ``rows``) up to SHORT_TABLE_MAX_CHARS wide."""
    if rows is not None and rows <= SHORT_TABLE_ROWS and sum(widths) <= SHORT_TABLE_MAX_CHARS:
        return 1
    return max(1, min(3, math.ceil(sum(widths) / PAGE_WIDTH_CHARS - PAGE_SLACK))) if widths else 1


def lead_columns(text: list[bool]) -> int:
    """The leading text columns (up to 3) a table wider than a page repeats on every page."""
    lead = 0
    while lead < min(3, len(text)) and text[lead]:
        lead += 1
    return lead


def fixed_rows(ws: WriteOnlyWorksheet) -> None:
    """Every row ROW_HEIGHT_PT high in Excel and LibreOffice alike (their defaults differ), so a grid of
    charts or images lands on the same pages in both."""
    ws.sheet_format.defaultRowHeight = ROW_HEIGHT_PT
    ws.sheet_format.customHeight = True


def write_table(ws: WriteOnlyWorksheet, columns: list[Column], *, freeze: str = "A2",
                 note: str = "") -> int:
    """Header row, the rows and an optional note under them; returns the number of rows kept."""
    n_rows = len(columns[0].values) if columns else 0
    sample = [c.values[:_WIDTH_SAMPLE_ROWS] for c in columns]
    labels = [workbook_header(c.header) for c in columns]
    right = [aligned_right(v, c.number_format) for c, v in zip(columns, sample, strict=True)]
    for c, indent in zip(columns, indented(right), strict=True):
        c.indent = indent
    widths = [column_width(c.header, v, c.number_format, label, c.indent)
              for c, v, label in zip(columns, sample, labels, strict=True)]
    for c, width in zip(columns, widths, strict=True):
        if c.text and width >= MAX_WIDTH:
            c.wrap = int(width - left_space(c.indent) - GAP_CHARS)
    _wrapped_heights(ws, columns, min(n_rows, EXCEL_MAX_ROWS - 1))
    set_widths(ws, widths)
    ws.freeze_panes = freeze
    page_setup(ws)
    wide_pages(ws, widths, [c.text for c in columns], n_rows)
    kept = min(n_rows, EXCEL_MAX_ROWS - 1)
    if kept < n_rows:
        note = f"{note} Rows cut at Excel's limit: {kept} of {n_rows} written.".strip()
    ws.row_dimensions[1].height = header_height(labels, widths, right)
    ws.append(header_cells(ws, labels, right=right))
    styles = RowStyles(ws, [None if c.styled is None or c.text else c.number_format for c in columns],
                       [INDENTED if c.indent else None for c in columns])
    if FAST_ROWS and install(ws, styles):
        append_rows(ws, raw_rows(ws, columns, 0, kept), kept)
    else:  # openpyxl's public path: a styled cell per formatted number
        for row in table_rows(ws, columns, 0, kept):
            ws.append(row)
    if note:  # below the table, so the printed width stays the table's
        ws.append([])
        lead, lines = note_lines(note, widths, [c.text for c in columns], n_rows)
        for line in lines:
            ws.append([None] * lead + [note_text_cell(ws, line)])
    return kept


def _wrapped_heights(ws: WriteOnlyWorksheet, columns: list[Column], kept: int) -> None:
    """Rows holding wrapped text (Column.wrap) made tall enough for its lines, set before any row is
    written (spreadsheet programs do not all fit a row to its text on opening)."""
    heights: dict[int, int] = {}
    for c in columns:
        if not c.wrap:
            continue
        for i, value in enumerate(c.values[:kept]):
            if value.__class__ is str and len(value) > c.wrap:
                lines = wrapped_lines(value, c.wrap)
                heights[i + 2] = max(heights.get(i + 2, 1), lines)
    for row, lines in heights.items():
        ws.row_dimensions[row].height = lines * ROW_HEIGHT_PT


def note_lines(note: str, widths: list[float], text: list[bool],
               rows: int | None = None) -> tuple[int, list[str]]:
    """Where a table's note starts (the first column after those repeated on every page, where a table
    prints wider than a page) and the note cut at spaces into lines that fit the rest of the first page,
    so that no page shows a line cut off."""
    pages = page_count(widths, rows)
    lead = lead_columns(text) if pages > 1 else 0
    lead_w = sum(widths[:lead])
    page_w = (sum(widths) + (pages - 1) * lead_w) / pages if pages > 1 else max(sum(widths), 100.0)
    return lead, textwrap.wrap(note, width=int(max(40.0, 0.85 * (page_w - lead_w)))) or [note]


