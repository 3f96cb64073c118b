"""Every workbook msdc writes prints readably (issue 26 item 6): human headers with units, landscape pages
fitted to the width, no short table spread across pages, no column cut, no value too wide for its column.

The commands run once on the fixtures (correlate with --quality, quality, conflicts with alerts); their
workbooks are rendered to PDF by LibreOffice in one call (the test skips, saying so, where LibreOffice or
poppler's pdftotext is absent) and read back page by page."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
from pathlib import Path

import evaluation_sample
import pytest
from openpyxl import load_workbook

from msdc.pipeline.cli import main
from msdc.pipeline.report import cells, excel
from msdc.pipeline.report.evaluation_xlsx import write_evaluation_xlsx
from msdc.pipeline.report.headers import LABELS, column_name, has_header, header_unit, workbook_header

pytestmark = pytest.mark.xdist_group("print_workbooks")  # one worker renders the workbooks once

ROOT = Path(__file__).resolve().parents[3]
FIX = ROOT / "fixtures"
AIRCRAFT = [str(FIX / "radar.ast"), str(FIX / "adsb.ast"), "--date", "2019-03-01", "--sensors",
            str(FIX / "sensors.toml")]
RUNS = {
    "correlate.xlsx": ["correlate", *AIRCRAFT, "--callsign", "MAS72", "--quality"],
    "quality.xlsx": ["quality", *AIRCRAFT, "--all"],
    "conflicts.xlsx": ["conflicts", *AIRCRAFT, "--step", "5", "--radius-nm", "40", "--vertical-ft", "30000",
                       "--horizon", "60"],
}
# A4 landscape in points, less the top and bottom margins (0.5 in each) and a footer line
PAGE_W_PT, PAGE_H_PT = 841.89, 595.28
ROWS_HEIGHT_PT = PAGE_H_PT - 72.0 - 18.0


@pytest.fixture(scope="module")
def workbooks(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, set[str]]:
    """The fixtures' workbooks, and every column name a workbook writer asked a header for."""
    out = tmp_path_factory.mktemp("print")
    asked: set[str] = set()

    def spy(name: str) -> str:
        asked.add(name)
        return workbook_header(name)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(cells, "workbook_header", spy)
        mp.setattr(excel, "workbook_header", spy)
        for name, argv in RUNS.items():
            assert main([*argv, "-o", str(out / name)]) == 0, name
        # the evaluation's workbook, on the hand-made scorecard (its command comes later)
        sample = evaluation_sample
        write_evaluation_xlsx(sample.scorecard(), out / "evaluation.xlsx", sample.tables(), sample.images())
    return out, asked


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_every_column_a_workbook_writes_has_a_header_of_its_own(workbooks) -> None:
    """A column without an entry in headers.LABELS would print its snake_case name: none does."""
    _, asked = workbooks
    assert len(asked) > 100
    assert sorted(n for n in asked if not has_header(n)) == []


def test_the_column_lists_of_the_tables_have_headers() -> None:
    """The declared columns of every table a workbook shows, beyond those the fixtures' runs write."""
    from msdc.pipeline.conflict.events import ALERT_COLUMNS, LOSS_COLUMNS, WARNING_COLUMNS
    from msdc.pipeline.correlate.results import MATCHED_KEYS, RADAR_KEYS, SUMMARY_KEYS, WINDOW_QUALITY_KEYS
    from msdc.pipeline.quality.accuracy import BIAS_COLUMNS
    from msdc.pipeline.quality.reference_offset import OFFSET_COLUMNS
    from msdc.pipeline.quality.tables import (
        ADSB_INDICATORS,
        GAP_COLUMNS,
        HISTOGRAM_COLUMNS,
        JUMP_COLUMNS,
        QUALITY_COLUMNS,
        VALUE_COUNT_COLUMNS,
    )
    from msdc.pipeline.report.charts import CORRELATION_HEADERS, SLOTS_HEADERS
    from msdc.pipeline.report.excel import SKIPPED_HEADERS, SUMMARY_BLOCKS

    shown_elsewhere = {"start_tod", "end_tod", "verdict"}  # the Summary shows them as start/end and rows
    lists = [ALERT_COLUMNS, LOSS_COLUMNS, WARNING_COLUMNS, MATCHED_KEYS, RADAR_KEYS, WINDOW_QUALITY_KEYS,
             [k for k in SUMMARY_KEYS if k not in shown_elsewhere], BIAS_COLUMNS, GAP_COLUMNS,
             HISTOGRAM_COLUMNS, JUMP_COLUMNS, QUALITY_COLUMNS, VALUE_COUNT_COLUMNS, CORRELATION_HEADERS,
             SLOTS_HEADERS, SKIPPED_HEADERS, OFFSET_COLUMNS, [f"{c}_median" for c in ADSB_INDICATORS],
             *(keys for _, keys in SUMMARY_BLOCKS)]
    assert sorted({c for names in lists for c in names if not has_header(c)}) == []


def test_the_summary_block_titles_name_columns_by_their_headers() -> None:
    """A Summary block's title reads as its headers do: no column's snake_case name in it, with or without
    its underscores ("sep rms all m: every slot" named the header "Slot separation RMS, every slot (m)")."""
    from msdc.pipeline.report.excel import SUMMARY_BLOCKS

    for title, keys in SUMMARY_BLOCKS:
        for name in keys:
            if "_" in name:
                assert name not in title and name.replace("_", " ") not in title.lower(), (title, name)


def test_headers_are_distinct_and_read_back_to_their_names() -> None:
    """No two columns print the same header (a reader could not tell them apart), so column_name inverts
    workbook_header; a name without a label is its own header."""
    assert len({workbook_header(n) for n in LABELS}) == len(LABELS)
    assert all(column_name(workbook_header(n)) == n for n in LABELS)
    assert workbook_header("score") == column_name("score") == "score"


@pytest.mark.parametrize(("name", "header"), [
    ("sep_m", "Separation (m)"), ("range_gain_ppm", "Range gain (ppm)"), ("lag", "Lag (slots)"),
    ("lag_s", "Lag (s)"), ("cpa_horizontal_nm", "CPA horizontal (NM)"), ("gap_start_tod",
    "Gap start time of day (UTC)"), ("gap_start_utc", "Gap start (UTC)"), ("ncc_lat", "NCC latitude"),
    ("share_pct", "Share (%)"), ("flight_level_a", "Flight level A (FL)"), ("window", "Window")])
def test_a_header_names_the_unit_its_cells_are_in(name: str, header: str) -> None:
    """By hand: metres, ppm, lags in slots and seconds, NM, clock times and date-times in UTC, percent,
    flight levels; coefficients and counts have no unit."""
    assert workbook_header(name) == header


def test_header_units_agree_with_the_documented_decoded_columns() -> None:
    """A label that is also a decoded record's column (asterix.columns: latitude, sac...) shows the unit
    its documentation gives; a time of day documented in s prints as a UTC clock time."""
    from msdc.asterix.columns import columns_for
    from msdc.pipeline.report.record_schema import _editions

    documented = {c.name: c.unit for cat in (1, 2, 21, 34, 48, 62) for ed in _editions(cat)
                  for c in columns_for(cat, ed)}
    shared = sorted(set(documented) & set(LABELS))
    assert {"latitude", "longitude", "sac", "sic", "callsign", "address", "time_of_day"} <= set(shared)
    for name in shared:
        want = "UTC" if name == "time_of_day" else documented[name]
        assert header_unit(name) == want, name


# ------------------------------------------------------------------------------------------ rendered


def _tools() -> None:
    missing = [t for t in ("soffice", "pdftotext", "pdfinfo") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed: workbooks are rendered to PDF with LibreOffice "
                    "and read with poppler-utils")


@pytest.fixture(scope="module")
def pdfs(workbooks, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Every workbook rendered to PDF by LibreOffice in one call (a private profile: no clash with another
    LibreOffice running)."""
    _tools()
    folder, _ = workbooks
    out = tmp_path_factory.mktemp("pdf")
    profile = tmp_path_factory.mktemp("lo-profile")
    books = sorted(folder.glob("*.xlsx"))
    done = subprocess.run(["soffice", f"-env:UserInstallation={profile.as_uri()}", "--headless",
                           "--convert-to", "pdf", "--outdir", str(out), *map(str, books)],
                          capture_output=True, text=True, timeout=600)
    pdfs = {b.name: out / f"{b.stem}.pdf" for b in books}
    if not all(p.exists() for p in pdfs.values()):
        pytest.fail(f"LibreOffice wrote no PDF of some workbooks: {done.stdout} {done.stderr}")
    return pdfs


_FOOTER = re.compile(r"^\s*(.+?), page (\d+) of (\d+)\s*$", re.M)


def _pages(pdf: Path) -> list[tuple[str, str]]:
    """Each page's sheet (read from its footer, "Sheet, page P of N") and text, laid out as printed."""
    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True, text=True,
                          check=True).stdout
    pages = []
    for page in text.split("\f")[:-1]:
        footer = _FOOTER.findall(page)
        assert footer, page[-300:]
        pages.append((footer[-1][0], page))
    return pages


def _page_sizes(pdf: Path) -> list[tuple[float, float]]:
    info = subprocess.run(["pdfinfo", "-f", "1", "-l", "100000", str(pdf)], capture_output=True, text=True,
                          check=True).stdout
    return [(float(w), float(h)) for w, h in re.findall(r"Page\s+\d+ size:\s+([\d.]+) x ([\d.]+)", info)]


def _row_heights_pt(ws) -> float:
    """The printed height of a sheet's rows at 100 %: the heights set, 15 pt for the others."""
    return sum(ws.row_dimensions[r].height or 15.0 for r in range(1, ws.max_row + 1))


def _page_bound(ws) -> int:
    """Pages a sheet may print on: its fitted width (pages across) times the pages its rows fill at 100 %,
    header rows repeated on each (fitting to the width only ever shrinks, never grows, the rows)."""
    wide = max(1, ws.page_setup.fitToWidth or 1)
    if ws.page_setup.fitToHeight:
        return wide * ws.page_setup.fitToHeight
    titles = 15.0 * (2 if ws.print_title_rows and ":$2" in ws.print_title_rows else 1)
    tall = math.ceil(_row_heights_pt(ws) / (ROWS_HEIGHT_PT - titles))
    return wide * max(1, tall)


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_every_page_is_landscape_and_every_sheet_within_its_page_bound(workbooks, pdfs) -> None:
    folder, _ = workbooks
    for name, pdf in pdfs.items():
        sizes = _page_sizes(pdf)
        assert sizes and all(w > h for w, h in sizes), name
        assert all(abs(w - PAGE_W_PT) < 1 and abs(h - PAGE_H_PT) < 1 for w, h in sizes), name  # A4
        printed: dict[str, int] = {}
        for sheet, _ in _pages(pdf):
            printed[sheet] = printed.get(sheet, 0) + 1
        wb = load_workbook(folder / name)
        assert list(printed) == wb.sheetnames, name  # every sheet printed, in order
        for ws in wb.worksheets:
            assert printed[ws.title] <= _page_bound(ws), (name, ws.title, printed[ws.title], _page_bound(ws))


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_a_short_table_prints_on_one_page(workbooks, pdfs) -> None:
    """No one-row table across pages: every table of at most 40 rows up to 1.5 legible pages wide
    (cells.SHORT_TABLE_*) prints one page wide, and on one page when its rows fit one."""
    folder, _ = workbooks
    short = []
    for name, pdf in pdfs.items():
        counts: dict[str, int] = {}
        for sheet, _ in _pages(pdf):
            counts[sheet] = counts.get(sheet, 0) + 1
        wb = load_workbook(folder / name)
        for ws in wb.worksheets:
            widths = [d.width for d in ws.column_dimensions.values() if d.width]
            if ws.max_row <= 20 and not ws._charts and not ws._images and sum(widths) <= 1.5 * 170:
                short.append((name, ws.title))
                assert ws.page_setup.fitToWidth == 1, (name, ws.title)
                assert counts[ws.title] == 1, (name, ws.title, counts[ws.title])
    # the one-row Radar biases, the Gaps, the Losses and the Warning times among them
    assert {("quality.xlsx", "Radar biases"), ("quality.xlsx", "Gaps"), ("conflicts.xlsx", "Losses"),
            ("conflicts.xlsx", "Warning times"), ("evaluation.xlsx", "Scorecard"),
            ("evaluation.xlsx", "PD per range band")} <= set(short)


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_the_evaluation_scorecard_prints_every_row_and_its_marks(pdfs) -> None:
    """The Scorecard's page holds each hand-made row's requirement and verdict, the percentages as
    written by hand, and the note on unchecked thresholds."""
    pages = [text for sheet, text in _pages(pdfs["evaluation.xlsx"]) if sheet == "Scorecard"]
    assert len(pages) == 1
    text = " ".join(pages[0].split())
    for row in evaluation_sample.ROWS:
        assert row[2] in text and row[8] in text, row
    assert "97.50% 97.36% 97.64% percent 97.00% pass 50,000" in text
    assert "120.5 110.4 131.0 metres 150.0 pass 4,000" in text
    assert "not checked against the standard's own text" in text


def _words(text: str) -> set[str]:
    """The words of a text, a hyphenated one as its parts (a cell may wrap a header after its hyphen)."""
    return {w for w in re.split(r"\s+|(?<=-)", text) if w}


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_no_column_is_cut_and_no_value_overflows_its_cell(workbooks, pdfs) -> None:
    """Every header of every table prints, each of its words on the sheet's first pages across (its fitted
    width), so no column is cut off the page; no cell prints ### (a number or date wider than its
    column)."""
    folder, _ = workbooks
    checked = 0
    for name, pdf in pdfs.items():
        pages = _pages(pdf)
        assert not [sheet for sheet, text in pages if "###" in text], name
        wb = load_workbook(folder / name)
        for ws in wb.worksheets:
            headers = [c.value for c in ws[1] if isinstance(c.value, str)]
            if len(headers) < 2 or ws._charts or ws._images:  # a chart sheet's or a note sheet's heading
                continue
            wide = max(1, ws.page_setup.fitToWidth or 1)
            first = [text for sheet, text in pages if sheet == ws.title][:wide]
            printed = _words(" ".join(first))
            missing = [h for h in headers if not _words(h) <= printed]
            assert not missing, (name, ws.title, missing)
            checked += 1
    assert checked >= 10


@pytest.mark.slow  # the commands on the fixtures (about 20 s), LibreOffice (about 15 s)
def test_the_evaluation_coverage_figures_print_one_per_page(pdfs) -> None:
    pages = [text for sheet, text in _pages(pdfs["evaluation.xlsx"]) if sheet == "Coverage"]
    captions = [" ".join(p.split()).split(" Coverage, page")[0] for p in pages]
    assert captions == list(evaluation_sample.images())  # each figure on a page of its own, under its title
