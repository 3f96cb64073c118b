"""The layout rules every workbook table shares (pipeline.report.cells), read back with openpyxl: a header
is aligned as its column's values, so that a number prints under its own header; a text column right of a
numeric one is indented, so that a number flush with its column's right edge never touches the text that
starts the next column."""

from __future__ import annotations

import math
from pathlib import Path

import evaluation_sample
import pandas as pd
import pytest
from openpyxl import Workbook, load_workbook

from msdc.pipeline.correlate.results import CorrelationRun, WindowResult
from msdc.pipeline.report import cells
from msdc.pipeline.report.evaluation_xlsx import write_evaluation_xlsx
from msdc.pipeline.report.excel import write_report
from msdc.pipeline.report.headers import column_name

# the Quality sheet's last columns as msdc quality writes them: percentages, then the MOPS versions as text
QUALITY = pd.DataFrame({
    "callsign": ["(all)", "AXM123", "MAS136"], "sensor": ["adsb", "adsb", "radar"],
    "on_surface": [False, False, True], "reports": [14986, 3124, 641],
    "low_integrity_pct": [1.6, 0.0, 2.9], "mops_versions": ["2", "2", None],
})
RADAR = {"radar": "KLIA MSSR", "radar_sensor": "048:25/201", "n_reports": 2922,
         "horizontal_error_rms_m": 275.3, "range_error_std_m": 70.4, "azimuth_error_std_deg": 0.079,
         "range_bias_m": 6.3, "range_bias_se_m": 4.3, "range_gain_ppm": -27.0, "range_gain_se_ppm": 22.4,
         "azimuth_bias_deg": 0.0036, "azimuth_bias_se_deg": 0.0015, "time_bias_s": -0.019,
         "time_bias_se_s": 0.015}


def _table(tmp_path: Path, frame: pd.DataFrame):
    """``frame`` written by write_table, read back."""
    wb = Workbook(write_only=True)
    ws = wb.create_sheet("T")
    cells.write_table(ws, [cells.make_column(ws, str(h), frame[h]) for h in frame.columns])
    wb.save(tmp_path / "t.xlsx")
    return load_workbook(tmp_path / "t.xlsx")["T"]


def _indents(row) -> dict[str, int]:
    """Indent level by column name of a header row."""
    return {column_name(c.value): int(c.alignment.indent) for c in row if c.value is not None}


@pytest.mark.parametrize("fast", [True, False])
def test_text_right_of_a_number_is_indented_and_its_column_wider(tmp_path: Path, monkeypatch, fast) -> None:
    """By hand: the MOPS versions (text) follow the low-integrity percentages (numbers flush right): header
    and cells indented one level, the column 8 characters ('versions') plus the indent (1.5) plus a
    character's gap wide; call sign (first) and sensor (after text) are not indented. Both row writers."""
    monkeypatch.setattr(cells, "FAST_ROWS", fast)
    ws = _table(tmp_path, QUALITY)
    assert _indents(ws[1]) == {"callsign": 0, "sensor": 0, "on_surface": 0, "reports": 0,
                               "low_integrity_pct": 0, "mops_versions": 1}
    assert [c.value for c in ws["F"][1:]] == ["2", "2", None]
    assert ws["F2"].alignment.indent == ws["F3"].alignment.indent == 1
    assert ws["A2"].alignment.indent == ws["B2"].alignment.indent == 0
    assert ws.column_dimensions["F"].width >= len("versions") + 1.5 + 1
    assert ws.column_dimensions["E"].width == len("integrity") + 2  # a numeric column: a character each side


def test_long_and_formula_like_text_of_an_indented_column_is_indented(tmp_path: Path) -> None:
    """Text the writer makes a cell of its own (formula-like, quote-prefixed; too long, wrapped) is
    indented as the column's plain text."""
    long = "x " * 60
    ws = _table(tmp_path, pd.DataFrame({"reports": [1, 2, 3], "note": ["=1+1", long, "plain"]}))
    assert [c.alignment.indent for c in ws["B"]] == [1, 1, 1, 1]
    assert ws["B2"].quotePrefix and ws["B3"].alignment.wrap_text


def test_summary_blocks_indent_the_text_right_of_a_number(tmp_path: Path) -> None:
    """The Summary's blocks share their columns: in the radar block 'Radar sensor' follows 'Radar' (text)
    and is not indented; in a window block 'Sensors' follows 'Window' (a number) and is."""
    t0 = pd.Timestamp("2019-03-01 08:05:02", tz="UTC")
    summary = {"callsign": "AXM123", "address": "75008A", "window": 1, "start": t0,
               "end": t0 + pd.Timedelta(minutes=12), "start_tod": 29102.0, "end_tod": 29822.0,
               "radar_sensor": "048:25/201", "reference_sensor": "021:0/1", "matched_reports": 151,
               "matched_sep_rms_m": 250.7}
    run = CorrelationRun(windows=[WindowResult(summary, pd.DataFrame(), pd.DataFrame())],
                         parameters={"date": "2019-03-01"}, radars=[RADAR])
    write_report(run, tmp_path / "r.xlsx")
    ws = load_workbook(tmp_path / "r.xlsx")["Summary"]
    radar = next(c.row for c in ws["A"] if c.value == "Radar")
    assert _indents(ws[radar])["radar_sensor"] == 0
    assert ws.cell(radar + 1, 2).value == "048:25/201" and ws.cell(radar + 1, 2).alignment.indent == 0
    window = next(c.row for c in ws["A"] if c.value == "Aircraft")
    indents = _indents(ws[window])
    assert indents["sensors"] == 1 and indents["aircraft"] == indents["window"] == 0
    pair = ws.cell(window + 1, 3)
    assert pair.value == "048:25/201 vs 021:0/1" and pair.alignment.indent == 1
    assert ws.cell(window + 1, 1).value == "AXM123" and ws.cell(window + 1, 1).alignment.indent == 0


def test_the_scorecard_indents_its_text_right_of_a_number(tmp_path: Path) -> None:
    """The scorecard: Unit follows the interval's high end, Verdict the threshold, Clause the sample size:
    indented, header and cells; Sensor, Requirement and Notes (after text) are not."""
    sample = evaluation_sample
    write_evaluation_xlsx(sample.scorecard(), tmp_path / "e.xlsx", sample.tables())
    ws = load_workbook(tmp_path / "e.xlsx")["Scorecard"]
    header = {c.value: c for c in ws[1]}
    indented = {h for h, c in header.items() if c.alignment.indent}
    assert indented == {"Unit", "Verdict", "Clause"}
    verdict = header["Verdict"].column_letter
    assert all(c.alignment.indent == 1 for c in ws[verdict][1:len(sample.ROWS) + 1])


def _alignment(cell) -> str:
    return cell.alignment.horizontal or "general"


def test_a_numeric_header_is_aligned_right_as_its_values(tmp_path: Path) -> None:
    """By hand: the percentages, counts and booleans print right-aligned, so do their headers; call sign,
    sensor and the MOPS versions (text) are left-aligned, headers and cells."""
    ws = _table(tmp_path, QUALITY)
    header = {column_name(c.value): _alignment(c) for c in ws[1]}
    assert header == {"callsign": "left", "sensor": "left", "on_surface": "right", "reports": "right",
                      "low_integrity_pct": "right", "mops_versions": "left"}
    # a boolean is aligned right in every spreadsheet (Excel would centre it), as its header
    assert ws["C2"].value is False and _alignment(ws["C2"]) == "right"


def test_summary_headers_are_aligned_as_their_block_s_values(tmp_path: Path) -> None:
    """The Summary's blocks share their columns: the radar block's 'Reports compared' (a count) sits in the
    windows' Sensors column (text), its 'Radar sensor' (text) in their Window column (numbers). Each
    header is aligned as the values under it in its own block."""
    t0 = pd.Timestamp("2019-03-01 08:05:02", tz="UTC")
    summary = {"callsign": "AXM123", "address": "75008A", "window": 1, "start": t0,
               "end": t0 + pd.Timedelta(minutes=12), "start_tod": 29102.0, "end_tod": 29822.0,
               "radar_sensor": "048:25/201", "reference_sensor": "021:0/1", "matched_reports": 151}
    run = CorrelationRun(windows=[WindowResult(summary, pd.DataFrame(), pd.DataFrame())],
                         parameters={"date": "2019-03-01"}, radars=[RADAR])
    write_report(run, tmp_path / "r.xlsx")
    ws = load_workbook(tmp_path / "r.xlsx")["Summary"]
    radar = next(c.row for c in ws["A"] if c.value == "Radar")
    header = {column_name(c.value): _alignment(c) for c in ws[radar] if c.value is not None}
    assert header["radar"] == header["radar_sensor"] == "left"
    assert header["n_reports"] == header["horizontal_error_rms_m"] == header["time_bias_se_s"] == "right"
    assert ws.cell(radar, 3).value == "Reports compared" and ws.cell(radar + 1, 3).value == 2922
    window = next(c.row for c in ws["A"] if c.value == "Aircraft")
    header = {column_name(c.value): _alignment(c) for c in ws[window] if c.value is not None}
    assert header["aircraft"] == header["sensors"] == "left"
    assert header["window"] == header["matched_reports"] == header["start"] == "right"


def test_every_header_of_a_correlation_workbook_is_aligned_as_its_cells(tmp_path: Path) -> None:
    """Generally: in every table sheet (header in row 1) a header is right-aligned exactly when no cell
    under it holds text, as read back (numbers, dates and booleans print right-aligned)."""
    stamps = pd.to_datetime(["2019-03-01 08:05:02", "2019-03-01 08:05:06"], utc=True)
    slots = pd.DataFrame({"slot": [0, 1], "time_of_day": [29102.0, 29106.0], "timestamp": stamps,
                          "radar_lat": [3.1, 3.2], "radar_lon": [101.6, 101.7], "adsb_lat": [3.1, 3.2],
                          "adsb_lon": [101.6, 101.7], "radar_count": [1, 1], "adsb_count": [2, 2],
                          "radar_filled": [False, True], "adsb_filled": [False, False],
                          "sep_m": [40.0, math.nan]})
    lags = pd.DataFrame({"lag": [-1, 0, 1], "ncc_lat": [0.9, 1.0, 0.9], "ncc_lon": [0.9, 1.0, 0.9],
                         "pearson_lat": [0.5, 0.9, 0.5], "pearson_lon": [0.5, 0.9, 0.5]})
    summary = {"callsign": "AXM123", "address": "75008A", "window": 1, "start_tod": 29102.0,
               "end_tod": 29106.0, "slots": 2}
    run = CorrelationRun(windows=[WindowResult(summary, slots, lags)], parameters={"date": "2019-03-01"},
                         extra_sheets={"Quality": QUALITY})
    write_report(run, tmp_path / "r.xlsx")
    checked = 0
    for ws in load_workbook(tmp_path / "r.xlsx").worksheets:
        if ws.title in ("Summary", "Lag charts", "Slot charts"):
            continue
        for col in ws.iter_cols(min_row=1, max_row=_last_row(ws)):
            header, values = col[0], [c for c in col[1:] if c.value is not None]
            if header.value is None or not values:
                continue
            text = any(c.data_type == "s" for c in values)
            assert _alignment(header) == ("left" if text else "right"), (ws.title, header.value)
            checked += 1
    assert checked >= 20


def _last_row(ws) -> int:
    """A table's last row: the row before the blank row that parts it from its note (or the last row)."""
    for row in range(2, ws.max_row + 1):
        if all(c.value is None for c in ws[row]):
            return row - 1
    return ws.max_row


def _printed_bold(word: str) -> float:
    """A header word's printed width in characters of column width, measured from the fonts matplotlib
    ships: the wider of DejaVu Sans Bold and DejaVu Serif Bold (LibreOffice's header fonts where Calibri
    is missing) at 11 pt, against the digit 0 of DejaVu Sans at 11 pt (the unit of column widths)."""
    import os

    import matplotlib
    from PIL import ImageFont

    fonts = os.path.join(matplotlib.get_data_path(), "fonts", "ttf")

    def font(name: str):
        return ImageFont.truetype(os.path.join(fonts, name), 1100)

    digit = font("DejaVuSans.ttf").getlength("0")
    return max(font(name).getlength(word) for name in ("DejaVuSans-Bold.ttf", "DejaVuSerif-Bold.ttf")) / digit


def test_every_header_word_fits_its_column_printed_in_bold() -> None:
    """Every word of every header the workbooks print fits its column as printed in bold, with a
    character to spare (LibreOffice broke 'Maximum' as 'Maximu|m' in a column of 9: 8.8 characters bold,
    and a cell's margins), and after the indent in an indented column."""
    from msdc.pipeline.report.headers import LABELS, workbook_header

    short = []
    for name in LABELS:
        header = workbook_header(name)
        for indent in (False, True):
            width = cells.column_width(name, [], None, header, indent)
            for word in header.split(" "):
                if width < _printed_bold(word) + 1.0 + (cells.INDENT_CHARS if indent else 0.0):
                    short.append((header, word, indent, width))
    assert short == []


def test_the_position_error_table_prints_maximum_whole(tmp_path: Path) -> None:
    """The evaluation's position error per range band (its last column 'Maximum error (m)', values of 5
    characters): the column holds 'Maximum' in bold, a character to spare, not only its 7 letters."""
    frame = pd.DataFrame({"sensor": ["010:0/107:mlat"] * 2, "range_from_nm": [0.0, 10.0],
                          "range_to_nm": [10.0, 20.0], "reports": [17624, 1571], "aircraft": [27, 16],
                          "rms_m": [34.4, 78.7], "p95_m": [84.0, 132.4], "max_m": [149.8, 149.6]})
    ws = _table(tmp_path, frame)
    assert ws["H1"].value == "Maximum error (m)"
    assert ws.column_dimensions["H"].width >= _printed_bold("Maximum") + 1.0 > len("Maximum") + 2


def test_a_header_row_is_as_tall_as_its_bold_lines() -> None:
    """'MMMM WWW' is 8 letters, one line of a 10-character column by its letters, two in bold (M and W
    print about 1.7 characters wide): the row is two lines tall."""
    assert len("MMMM WWW") <= 10 - 2 and _printed_bold("MMMM WWW") > 10.0
    assert cells.header_height(["MMMM WWW"], [10.0]) == 2 * cells.ROW_HEIGHT_PT


CARLITO = Path("/usr/share/fonts/truetype/crosextra/Carlito-Regular.ttf")  # Debian's fonts-crosextra-carlito


def _printed_regular(text: str, face: str) -> float:
    """Body text's printed width in characters of column width, at 11 pt against the face's own digit 0:
    DejaVu Sans as matplotlib ships it (LibreOffice's body font where Calibri is missing), or Carlito
    (metric-compatible with Calibri, Excel's body font)."""
    import os

    import matplotlib
    from PIL import ImageFont

    if face == "carlito":
        if not CARLITO.exists():
            pytest.skip(f"{CARLITO} not installed (apt-get install fonts-crosextra-carlito): Calibri's "
                        "widths are checked through it")
        path = str(CARLITO)
    else:
        path = os.path.join(matplotlib.get_data_path(), "fonts", "ttf", "DejaVuSans.ttf")
    font = ImageFont.truetype(path, 1100)
    return font.getlength(text) / font.getlength("0")


NOTES = [  # a scorecard's notes as msdc writes them, every printable ASCII letter and the units' signs
    "sigma gate at 12 m: 5,906 of 11,761 reports judged (left out: 5,851 on the sensor's own track, 4 where "
    "the "
    "reference's sigma is too large for the tolerance); 25 aircraft",
    "timing: 116 of the 116 false reports lie near an aircraft whose reference leads or lags (343386, 3443D2",
    "interval [0.983297, 1] straddles 0.99; threshold not checked against the standard's text",
    "ABCDEFGHIJKLMNOPQRSTUVWXYZ abcdefghijklmnopqrstuvwxyz 0123456789 !\"#$%&'()*+,-./:;<=>?@[\\]^_`{|}~",
    "\u00b1 0.5 \u00b0 \u00b5s \u2013 at 1.3 NM",
]


@pytest.mark.parametrize("face", ["dejavu", "carlito"])
def test_body_text_is_never_counted_narrower_than_it_prints(face: str) -> None:
    """A wrapped cell's lines are counted from cells.text_width: never narrower than the text prints in
    either face (a row too short cuts its last line off), and in DejaVu Sans, where LibreOffice prints
    Calibri's text here, within 12 % of it (counted by letters, rows printed half again too tall)."""
    for text in [*NOTES, "MMMM //// ____ |||| ****"]:  # the last: Carlito's widest against DejaVu's
        printed = _printed_regular(text, face)
        assert printed <= cells.text_width(text), text
        if face == "dejavu" and text in NOTES:
            assert cells.text_width(text) <= 1.12 * printed, text


def test_wrapped_lines_by_hand() -> None:
    """The faces' widths (the test above measures them): a, e, g, S 1.0 each, space 0.5, m 1.6; lines counted
    by hand."""
    assert cells.wrapped_lines("aegS aegS", 8.5) == 1  # 4 + 0.5 + 4
    assert cells.wrapped_lines("aegS aegS", 8.4) == 2
    assert cells.wrapped_lines("aegS aegS aegS", 8.5) == 2
    assert cells.wrapped_lines("m" * 10, 5.0) == 4  # 16 wide: broken at the edge, 5 + 5 + 5 + 1
    assert cells.wrapped_lines("ab\ncd", 40.0) == 2
    assert cells.wrapped_lines("", 10.0) == 1
