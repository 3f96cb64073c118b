"""Table rows written straight into a write-only sheet's XML stream, the cells openpyxl would write.

openpyxl's write-only ``append`` binds every value to a cell object, tries and fails to bind each styled
cell passed in (an exception per cell) and writes it through a chain of per-cell calls: about a third of
its plain-cell rate for the formatted numbers of msdc's tables. ``install(ws)`` routes rows appended as
``RawRow`` through one function that writes plain numbers, booleans and text as the same ``<c>`` elements
(same coordinates, types, ``%.16g`` numbers, inline strings, the column's style id) and hands every other
cell (formula-like or illegal text, dates, cells built elsewhere) to openpyxl's own cell writer. It needs
two private openpyxl attributes (``WriteOnlyWorksheet._values_to_row`` and the sheet writer's
``write_row``); where they are missing ``install`` returns False and the caller appends as usual.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

from lxml.etree import XMLParser, fromstring
from openpyxl.cell import WriteOnlyCell
from openpyxl.cell.cell import ERROR_CODES, ILLEGAL_CHARACTERS_RE, Cell
from openpyxl.styles import Alignment
from openpyxl.utils import get_column_letter
from openpyxl.xml import LXML

_MAX_TEXT = 32_767
# Booleans carry this number format: LibreOffice shows an unstyled boolean cell as 0/1 or TRUE/FALSE
# depending on its neighbours (both in one Summary row); with it every one reads TRUE or FALSE, as Excel
# shows booleans whatever their format
BOOL_FORMAT = '"TRUE";"TRUE";"FALSE"'


class RawRow(list):
    """A row of plain values (None, int, float, bool, str, or cells) for a sheet set up by install()."""


class RowStyles:
    """Per column: the number format plain numbers take there (None: General) and its style id, looked up
    the first time the column writes a styled number, as openpyxl does when it writes the cell; and the
    alignment plain text takes there (``aligns``; None: none), its style id looked up the same way."""

    def __init__(self, ws, formats: Sequence[str | None], aligns: Sequence[Alignment | None] | None = None):
        self.ws, self.formats = ws, list(formats)
        self.aligns = [None] * len(self.formats) if aligns is None else list(aligns)
        self.ids: list[str | None] = [None] * len(self.formats)
        self.text_ids: list[str | None] = [None] * len(self.formats)
        self.letters = [get_column_letter(j + 1) for j in range(len(self.formats))]
        self._bool_id: str | None = None

    def bool_id(self) -> str:
        """The style id of BOOL_FORMAT, looked up once."""
        if self._bool_id is None:
            self._bool_id = f"{bool_cell(self.ws, True).style_id}"
        return self._bool_id

    def style_id(self, j: int) -> str:
        sid = self.ids[j]
        if sid is None:
            cell = WriteOnlyCell(self.ws, 0.0)
            cell.number_format = self.formats[j]
            sid = self.ids[j] = f"{cell.style_id}"
        return sid

    def text_style(self, j: int) -> str:
        """The ``s`` attribute of plain text in column j: its alignment's style id, or nothing."""
        if self.aligns[j] is None:
            return ""
        sid = self.text_ids[j]
        if sid is None:
            cell = WriteOnlyCell(self.ws, "")
            cell.alignment = self.aligns[j]
            sid = self.text_ids[j] = f' s="{cell.style_id}"'
        return sid

    def letter(self, j: int) -> str:
        while j >= len(self.letters):
            self.letters.append(get_column_letter(len(self.letters) + 1))
        return self.letters[j]


def install(ws, styles: RowStyles) -> bool:
    """Write this sheet's RawRow rows with ``styles``; False (nothing changed) where openpyxl's write-only
    internals are not the ones this was written for (the caller then appends ordinary rows)."""
    if not LXML:
        return False
    try:
        ws._get_writer()
        writer = ws._writer
        to_row, write_row = ws._values_to_row, writer.write_row
    except AttributeError:
        return False

    def values_to_row(values, row_idx):
        return values if values.__class__ in _RAW else to_row(values, row_idx)

    def raw_write_row(xf, row, row_idx):
        kind = row.__class__
        if kind is RawRow:
            _write(xf, ws, row, row_idx, styles, to_row, write_row)
        elif kind is RawRows:
            _write_many(xf, ws, row, row_idx, styles, to_row, write_row)
        elif kind is not _Skip:
            write_row(xf, row, row_idx)

    ws._values_to_row, writer.write_row = values_to_row, raw_write_row
    return True


class RawRows(list):
    """``count`` rows (RawRow, from ``rows``) appended as one, for a sheet set up by install(): written
    together, CHUNK_ROWS parsed at a time; append() it, then append SKIP count - 1 times, which only moves
    openpyxl's row counter on past them (append_rows does both)."""

    def __init__(self, rows: Iterable[RawRow], count: int):
        super().__init__()
        self.rows, self.count = rows, count


class _Skip(list):
    pass


SKIP = _Skip()
_RAW = (RawRow, RawRows, _Skip)
CHUNK_ROWS = 2048  # rows parsed in one go: one parse instead of one a row, a bounded string


def append_rows(ws, rows: Iterable[RawRow], count: int) -> None:
    """Append ``count`` rows to a sheet set up by install(): the same cells as appending each RawRow."""
    if count:
        ws.append(RawRows(rows, count))
        for _ in range(count - 1):
            ws.append(SKIP)


def _write_many(xf, ws, block: RawRows, row_idx: int, styles: RowStyles, to_row, write_row) -> None:
    """The rows of ``block`` from sheet row ``row_idx`` on, as _write writes each one, parsed CHUNK_ROWS at a
    time (a row that openpyxl writes goes between, in order)."""
    pending: list[str] = []

    def flush() -> None:
        if pending:
            for element in fromstring(f"<rows>{''.join(pending)}</rows>", _PARSER):
                xf.write(element)
            pending.clear()

    idx = row_idx
    for values in block.rows:
        text = None if ws.row_dimensions.get(idx) else _row_text(values, idx, styles)
        if text is None:
            flush()
            write_row(xf, to_row(openpyxl_values(ws, values, styles.formats, styles.aligns), idx), idx)
        else:
            pending.append(text)
            if len(pending) >= CHUNK_ROWS:
                flush()
        idx += 1
    flush()
    if idx - row_idx != block.count:
        raise ValueError(f"{idx - row_idx} rows given for {block.count}")


def _write(xf, ws, values: RawRow, row_idx: int, styles: RowStyles, to_row, write_row) -> None:
    """One row as one element, parsed from its text (cheaper than an element per cell); a row holding
    anything but finite numbers, booleans and plain text goes through openpyxl whole (formula-like
    text as cells made elsewhere, dates, illegal text: its own errors)."""
    dims = ws.row_dimensions.get(row_idx)
    text = None if dims else _row_text(values, row_idx, styles)
    if text is None:  # a row with its own height or style, or a cell only openpyxl writes: its own way
        write_row(xf, to_row(openpyxl_values(ws, values, styles.formats, styles.aligns), row_idx), row_idx)
        return
    xf.write(fromstring(text, _PARSER))


def _row_text(values: RawRow, row_idx: int, styles: RowStyles) -> str | None:
    """The row's XML as openpyxl writes it, or None when a cell needs openpyxl (not a finite number, a
    boolean or plain text)."""
    r = f"{row_idx}"
    formats = styles.formats
    parts = [f'<row r="{r}">']
    for j, value in enumerate(values):
        if value is None:
            continue
        kind = value.__class__
        if kind is int or (kind is float and value - value == 0.0):  # not NaN or infinite
            if formats[j] is None:
                parts.append(f'<c r="{styles.letter(j)}{r}" t="n"><v>{value:.16g}</v></c>')
            else:
                parts.append(f'<c r="{styles.letter(j)}{r}" s="{styles.style_id(j)}" t="n"><v>{value:.16g}'
                             '</v></c>')
        elif kind is bool:
            parts.append(f'<c r="{styles.letter(j)}{r}" s="{styles.bool_id()}" t="b"><v>{1 if value else 0}'
                         '</v></c>')
        elif kind is str and formats[j] is None and _plain_text(value):
            style = styles.text_style(j)
            if not value:  # openpyxl writes "" as an element without content
                parts.append(f'<c r="{styles.letter(j)}{r}"{style} t="inlineStr"/>')
            else:
                space = ' xml:space="preserve"' if value != value.strip() else ""
                parts.append(f'<c r="{styles.letter(j)}{r}"{style} t="inlineStr"><is><t{space}>'
                             f'{value.translate(_ESCAPE)}</t></is></c>')
        else:
            return None
    parts.append("</row>")
    return "".join(parts)


_ESCAPE = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;", "\r": "&#13;"})
_PARSER = XMLParser(resolve_entities=False, huge_tree=True, remove_blank_text=False)


def openpyxl_values(ws, values: Sequence[Any], formats: Sequence[str | None],
                    aligns: Sequence[Alignment | None] | None = None) -> list[Any]:
    """The row as openpyxl's append takes it: numbers under a column format as cells carrying it (the
    public path, one cell per value), text in an aligned column (``aligns``) as a cell so aligned,
    everything else as it is."""
    out = list(values)
    for j, value in enumerate(out):
        if value.__class__ is bool:
            out[j] = bool_cell(ws, value)
        elif value.__class__ is str and aligns is not None and aligns[j] is not None:
            cell = WriteOnlyCell(ws, value)
            cell.alignment = aligns[j]
            out[j] = cell
        elif formats[j] is not None and value is not None and not isinstance(value, Cell):
            cell = WriteOnlyCell(ws, value)
            cell.number_format = formats[j]
            out[j] = cell
    return out


def bool_cell(ws, value: bool) -> WriteOnlyCell:
    """A boolean cell that reads TRUE or FALSE in every spreadsheet (BOOL_FORMAT), aligned right as
    LibreOffice aligns it (Excel centres a boolean), under its header (aligned as numbers are)."""
    cell = WriteOnlyCell(ws, value)
    cell.number_format = BOOL_FORMAT
    cell.alignment = _RIGHT
    return cell


_RIGHT = Alignment(horizontal="right")


def _plain_text(value: str) -> bool:
    """Text openpyxl writes as a plain inline string: not a formula, not an error code, legal, not cut."""
    return not (value[:1] == "=" and len(value) > 1) and value not in ERROR_CODES \
        and len(value) <= _MAX_TEXT and ILLEGAL_CHARACTERS_RE.search(value) is None
