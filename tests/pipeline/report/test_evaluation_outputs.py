"""The evaluation's writers (XLSX, JSON, HTML) on a hand-made scorecard (tests/evaluation_sample.py): what
each writes is read back and compared with the values written there by hand; the HTML is opened in headless
Chromium with every network request refused."""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path

import pandas as pd
import pytest
from evaluation_sample import COLUMNS, ROWS, images, map_points, png, scorecard, tables
from openpyxl import load_workbook

from msdc.pipeline.evaluate.scorecard_schema import (
    SCORECARD_COLUMNS,
    schema_markdown,
    validate_map,
    validate_scorecard,
)
from msdc.pipeline.report.evaluation_html import evaluation_html, write_evaluation_html
from msdc.pipeline.report.evaluation_json import read_evaluation_json, write_evaluation_json
from msdc.pipeline.report.evaluation_xlsx import write_evaluation_xlsx

ROOT = Path(__file__).resolve().parents[3]
CHROMIUM = "/usr/bin/chromium"


# ------------------------------------------------------------------------------------------- schema

def test_the_schema_is_the_documented_one() -> None:
    """The columns the brief names, in order; the docs page shows the schema's own tables."""
    assert SCORECARD_COLUMNS == ("sensor", "sector", "requirement", "value", "ci_low", "ci_high", "n",
                                 "threshold", "verdict", "clause", "checked", "notes", "parameters")
    page = (ROOT / "docs" / "guide" / "evaluate-outputs.md").read_text(encoding="utf-8")
    assert schema_markdown() in page


@pytest.mark.parametrize(("change", "message"), [
    (lambda f: f.drop(columns="clause"), "scorecard: columns missing 'clause'"),
    (lambda f: f.assign(extra=1), "unknown 'extra'"),
    (lambda f: f.assign(verdict=["pass", "fail", "maybe", "pass", "pass"]),
     "column 'verdict', row 2: 'maybe' is not one of pass, fail, inconclusive"),
    (lambda f: f.assign(requirement=["pd", "pd_x", "pd", "rms_m", "p95_m"]),
     "column 'requirement', row 1: 'pd_x' is not a documented requirement id"),
    (lambda f: f.assign(ci_low=[0.98, 0.94, 0.955, 110.4, math.nan]), "column 'ci_low', row 0: 0.98 exceeds"),
    (lambda f: f.assign(ci_high=[0.9764, 0.96, 0.975, math.nan, math.nan]), "column 'ci_high', row 3"),
    (lambda f: f.assign(threshold=[0.97, 0.98, "0.96", 150.0, 50.0]),
     "column 'threshold', row 2: '0.96' is not a number"),
    (lambda f: f.assign(n=[50000, 2000, 3000, -1, 0]), "column 'n', row 3: -1 is negative"),
    (lambda f: f.assign(checked=[True, False, False, "yes", False]), "column 'checked', row 3: 'yes' is not"),
    (lambda f: pd.concat([f, f.iloc[[0]]]), "row 5: 'pd' repeats row 0"),
])
def test_a_bad_scorecard_is_refused_naming_column_row_and_value(change, message: str) -> None:
    with pytest.raises(ValueError, match=None) as caught:
        validate_scorecard(change(scorecard()))
    assert message in str(caught.value)


def test_bad_map_points_are_refused() -> None:
    bad = map_points().assign(source=["reference", "radar"] * 6)
    with pytest.raises(ValueError, match=r"map points: column 'source', row 1: 'radar' is not one of"):
        validate_map(bad)
    with pytest.raises(ValueError, match=r"column 'latitude', row 0: 91.0 is outside -90 to 90"):
        validate_map(map_points().assign(latitude=[91.0] * 12))


# --------------------------------------------------------------------------------------------- XLSX

@pytest.fixture(scope="module")
def workbook(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("evaluation") / "evaluation.xlsx"
    write_evaluation_xlsx(scorecard(), path, tables())
    return path


def test_the_workbook_opens_on_the_scorecard_then_the_tables(workbook: Path) -> None:
    wb = load_workbook(workbook)
    assert wb.sheetnames == ["Scorecard", "PD per aircraft", "PD per range band"]
    ws = wb["Scorecard"]
    header = [c.value for c in ws[1]]
    assert header == ["Sensor", "Sector", "Requirement", "Parameters", "Value", "95 % interval, low",
                      "95 % interval, high",
                      "Unit", "Threshold", "Verdict", "Sample size", "Clause",
                      "Threshold checked against the standard", "Notes"]
    rows = [[c.value for c in row] for row in ws.iter_rows(min_row=2, max_row=6)]
    for row, want in zip(rows, ROWS, strict=True):
        sensor, sector, req, value, low, high, n, threshold, verdict, clause, checked, notes = want
        assert row[:3] == [sensor, sector, req]
        got = [math.nan if v is None else v for v in (row[4], row[5], row[6], row[8])]
        assert got == pytest.approx([value, low, high, threshold], nan_ok=True)
        assert row[9:13] == [verdict, n, clause, "yes" if checked else "no"]
        assert (row[13] or "") == notes
    assert [r[3] for r in rows] == ["interval_s = 5", None, None, None, None]
    assert [r[7] for r in rows] == ["percent", "percent", "percent", "metres", "metres"]
    # the formula-like note stays text
    assert ws.cell(6, 14).data_type == "s"


def test_verdicts_are_coloured_and_unchecked_thresholds_marked(workbook: Path) -> None:
    ws = load_workbook(workbook)["Scorecard"]
    fills = {ws.cell(r, 10).value: ws.cell(r, 10).fill.fgColor.rgb[-6:] for r in range(2, 7)}
    assert fills == {"pass": "C6EFCE", "fail": "FFC7CE", "inconclusive": "FFEB9C"}
    marks = [(ws.cell(r, 13).value, ws.cell(r, 13).font.b, ws.cell(r, 9).font.i) for r in range(2, 7)]
    assert marks == [("yes", False, False), ("no", True, True), ("no", True, True), ("yes", False, False),
                     ("no", True, True)]
    # a proportion is shown as a percentage, a distance in metres with one decimal
    assert ws.cell(2, 5).number_format == "0.00%" and ws.cell(5, 5).number_format == "0.0"
    notes = " ".join(str(c.value) for row in ws.iter_rows(min_row=7) for c in row if c.value)
    assert "not checked against the standard's own text" in notes


@pytest.mark.parametrize("value, text, number_format", [
    (0.9832, "98.32 %", "0.00%"), (0.0001, "0.0100 %", "0.0000%"), (0.000146, "0.0146 %", "0.0000%"),
    (0.00397, "0.397 %", "0.000%"), (0.0, "0.00 %", "0.00%"), (1.0, "100.00 %", "0.00%"),
])
def test_a_small_proportion_keeps_three_significant_digits(value, text, number_format) -> None:
    """A false-report share of 0.0146 % beside its threshold of 0.01 % must not both read 0.01 %."""
    from msdc.pipeline.report.evaluation_formats import percent_format, unit_text

    assert unit_text(value, "fraction") == text and percent_format(value) == number_format


def test_a_small_proportion_in_the_workbook_keeps_its_digits(tmp_path: Path) -> None:
    card = scorecard()
    card.loc[1, ["requirement", "value", "ci_low", "ci_high", "threshold"]] = [
        "false_reports", 0.000146, 0.0000397, 0.000373, 0.0001]
    path = tmp_path / "small.xlsx"
    write_evaluation_xlsx(card, path, tables())
    ws = load_workbook(path)["Scorecard"]
    assert (ws.cell(3, 5).number_format, ws.cell(3, 9).number_format) == ("0.0000%", "0.0000%")
    assert ws.cell(2, 5).number_format == "0.00%"


def test_every_sheet_is_set_up_to_print(workbook: Path) -> None:
    for ws in load_workbook(workbook).worksheets:
        assert ws.page_setup.orientation == "landscape", ws.title
        assert ws.page_setup.fitToWidth == 1 and ws.sheet_properties.pageSetUpPr.fitToPage, ws.title
        assert ws.print_title_rows == "$1:$1", ws.title  # the header row repeated


def test_the_tables_sheets_hold_the_tables(workbook: Path) -> None:
    ws = load_workbook(workbook)["PD per range band"]
    assert [c.value for c in ws[1]] == ["Sensor", "Range from (NM)", "Range to (NM)", "Expected updates",
                                        "Detected updates", "Probability of detection"]
    assert [c.value for c in ws[2]] == ["SSR1", 0, 50, 150, 148, pytest.approx(148 / 150)]
    assert [c.value for c in ws[3]] == ["SSR1", 50, 100, 0, 0, None]  # NaN: an empty cell
    assert ws.cell(2, 6).number_format == "0.00%"  # a proportion as on the scorecard, not 0.986667


def test_the_coverage_sheet_holds_the_images_after_the_scorecard(tmp_path: Path) -> None:
    path = tmp_path / "e.xlsx"
    write_evaluation_xlsx(scorecard(), path, tables(), images())
    wb = load_workbook(path)
    assert wb.sheetnames == ["Scorecard", "Coverage", "PD per aircraft", "PD per range band"]
    ws = wb["Coverage"]
    assert [ws.cell(r, 1).value for r in range(1, ws.max_row + 1) if ws.cell(r, 1).value] == list(images())
    # each image whole (both fit a landscape page unscaled), its own pixels
    assert [(i.width, i.height) for i in ws._images] == [(400, 300), (320, 200)]
    assert ws.page_setup.orientation == "landscape" and ws.page_setup.fitToWidth == 1
    assert len(ws.row_breaks.brk) == 2  # one figure per printed page


@pytest.mark.parametrize(("bad", "message"), [
    ({"x": b"GIF89a"}, "images: 'x' is not a PNG image (no PNG signature; got 6 bytes)"),
    ({"x": "a.png"}, "images: 'x' is not a PNG image (no PNG signature; got str)"),
    ({" ": png(1, 1, (0, 0, 0))}, "images: title ' ' is not a non-empty text"),
    ([b"\x89PNG"], "images: must be a mapping of title -> PNG bytes, got list"),
])
def test_bad_images_are_refused(tmp_path: Path, bad, message: str) -> None:
    for write in (lambda: write_evaluation_xlsx(scorecard(), tmp_path / "e.xlsx", images=bad),
                  lambda: evaluation_html(scorecard(), images=bad)):
        with pytest.raises(ValueError) as caught:
            write()
        assert str(caught.value) == message
    assert not (tmp_path / "e.xlsx").exists()


# --------------------------------------------------------------------------------------------- JSON

def test_json_results_have_exactly_the_keys_and_nan_is_null(tmp_path: Path) -> None:
    path = write_evaluation_json(scorecard(), tmp_path / "e.json", tables(), map_points())
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert [list(r) for r in doc["results"]] == [[*COLUMNS, "parameters"]] * 5
    assert doc["results"][0] == {"sensor": "SSR1", "sector": "global", "requirement": "pd", "value": 0.975,
                                 "ci_low": 0.9736, "ci_high": 0.9764, "n": 50000, "threshold": 0.97,
                                 "verdict": "pass", "clause": "6.3.2.1", "checked": True, "notes": "",
                                 "parameters": "interval_s = 5"}
    withheld = doc["results"][4]
    ends = (withheld["value"], withheld["ci_low"], withheld["ci_high"], withheld["n"])
    assert ends == (None, None, None, 0)
    assert "NaN" not in path.read_text(encoding="utf-8")
    assert doc["tables"]["PD per range band"][1] == {"sensor": "SSR1", "range_from_nm": 50.0,
                                                     "range_to_nm": 100.0, "expected_updates": 0,
                                                     "detected_updates": 0, "pd": None}
    assert len(doc["map_points"]) == 12 and doc["map_points"][0]["source"] == "reference"


def test_json_round_trip(tmp_path: Path) -> None:
    path = write_evaluation_json(scorecard(), tmp_path / "e.json", tables())
    card, back = read_evaluation_json(path)
    pd.testing.assert_frame_equal(card, validate_scorecard(scorecard()))
    assert list(back) == list(tables())
    for name, frame in tables().items():
        pd.testing.assert_frame_equal(back[name], frame, check_dtype=False)


# --------------------------------------------------------------------------------------------- HTML

def test_the_html_holds_its_scripts_and_loads_nothing() -> None:
    """Self-contained: no <script src>, no <link> to a style sheet; the scorecard's text is escaped."""
    text = evaluation_html(scorecard(), tables(), map_points())
    assert "<script src" not in text.lower() and "<link" not in text.lower()
    assert "<script" in text and "Bokeh" in text
    bad = scorecard()
    bad.loc[0, "notes"] = "<img src=x onerror=alert(1)>"
    assert "<img src=x" not in evaluation_html(bad)
    with_images = evaluation_html(scorecard(), images={"<b>x</b>": png(2, 1, (0, 0, 0))})
    assert '<img src="data:image/png;base64,' in with_images and "<b>x</b>" not in with_images
    assert "Coverage" not in evaluation_html(scorecard())  # no figures, no section


def test_the_html_tables_show_numbers_as_the_workbook() -> None:
    """Proportions as the scorecard's percentages (148 / 150 = 98.67 %, not 0.986667), NM to 3 decimals,
    counts whole, NaN empty."""
    text = evaluation_html(scorecard(), tables())
    band = re.split(r"<h2[^>]*>PD per range band</h2>", text)[1]
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", band)
    assert cells == ["SSR1", "0.0", "50.0", "150", "148", "98.67 %",
                     "SSR1", "50.0", "100.0", "0", "0", ""]
    first = re.split(r"<h2[^>]*>PD per aircraft</h2>", text)[1].split("</table>")[0]
    aircraft = re.findall(r"<td[^>]*>([^<]*)</td>", first)
    assert aircraft == ["MAS72", "SSR1", "120", "118", "98.33 %", "IBE3150", "SSR1", "80", "80", "100.00 %"]


def _browser():
    """Playwright's sync API and Debian's Chromium, or a skip saying which is missing."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("playwright not installed (pip install playwright): the HTML report is opened in "
                    "headless Chromium through it")
    if shutil.which(CHROMIUM) is None:
        pytest.skip(f"{CHROMIUM} not installed (apt-get install chromium): the HTML report is opened in it")
    return sync_playwright


# every canvas, inside Bokeh's shadow roots too, and how many of its pixels are an aircraft's colour
_PAINTED = """([r, g, b]) => {
  const canvases = [];
  const walk = (root) => { for (const el of root.querySelectorAll('*')) {
    if (el.tagName === 'CANVAS') canvases.push(el); if (el.shadowRoot) walk(el.shadowRoot); } };
  walk(document);
  let painted = 0;
  for (const c of canvases) {
    if (!c.width || !c.height) continue;
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    for (let i = 0; i < d.length; i += 4)
      if (Math.abs(d[i] - r) < 40 && Math.abs(d[i + 1] - g) < 40 && Math.abs(d[i + 2] - b) < 40) painted++;
  }
  return painted;
}"""


@pytest.mark.slow  # Chromium's start and Bokeh's 1 MB script: about 3 s
def test_the_html_report_works_offline_in_chromium(tmp_path: Path) -> None:
    sync_playwright = _browser()
    path = write_evaluation_html(scorecard(), tmp_path / "e.html", tables(), map_points(), images=images())
    # the widest cells of the real LEBL ED-117A scorecard: it needed 1,193 px before the narrow layout
    wide = scorecard().assign(sensor="010:0/107:mlat", sector="manoeuvring", parameters="distance_m = 100",
                              clause="ED-117A Table 3-1")
    wide.loc[wide["n"] > 0, "n"] = 11_761
    wide_path = write_evaluation_html(wide, tmp_path / "wide.html", tables())
    url = path.as_uri()
    refused: list[str] = []
    messages: list[tuple[str, str]] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=[
            "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--no-first-run"])
        try:
            context = browser.new_context(offline=True)

            def route(request_route) -> None:
                if request_route.request.url in (url, wide_path.as_uri()):
                    request_route.continue_()
                else:
                    refused.append(request_route.request.url)
                    request_route.abort()

            context.route("**/*", route)
            page = context.new_page()
            page.on("console", lambda m: messages.append((m.type, m.text)))
            page.on("pageerror", lambda e: messages.append(("error", str(e))))
            page.goto(url)
            page.wait_for_selector("#map canvas", state="attached", timeout=30_000)
            page.wait_for_function("() => window.Bokeh && Bokeh.documents.length > 0", timeout=30_000)
            page.wait_for_timeout(300)  # the first paint after the document is idle
            # a body per result: its figures' row, then its notes' row (when it has notes)
            rows = page.eval_on_selector_all("#scorecard tbody", """bs => bs.map(b => [
                ...b.rows[0].cells].map(c => c.textContent).concat(
                b.rows.length > 1 ? [b.rows[1].cells[0].textContent] : [""]))""")
            verdict_colour = page.eval_on_selector(
                "#scorecard tbody:nth-of-type(2) td:nth-child(10)",
                "c => getComputedStyle(c).backgroundColor")
            notes_shown = page.eval_on_selector("#scorecard tbody:nth-of-type(3) tr.notes td", """c => [
                getComputedStyle(c, "::before").content, c.getBoundingClientRect().width,
                document.querySelector("#scorecard").getBoundingClientRect().width]""")
            scroll = page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
            figures = page.eval_on_selector_all(
                "#coverage img", "is => is.map(i => [i.alt, i.complete, i.naturalWidth, i.naturalHeight])")
            page_messages = list(messages)  # before the test's own pixel reads (Chromium warns of those)
            blue = page.evaluate(_PAINTED, [0x1F, 0x77, 0xB4])  # IBE3150, the first aircraft by name
            red = page.evaluate(_PAINTED, [0xD6, 0x27, 0x28])  # MAS72
            narrow = context.new_page()
            narrow.set_viewport_size({"width": 1024, "height": 768})
            narrow.goto(wide_path.as_uri())
            narrow_scroll = narrow.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
            clause_lines = narrow.eval_on_selector(  # the lines 'ED-117A Table 3-1' takes (their tops)
                "#scorecard tbody td:nth-child(12)", """c => { const r = document.createRange();
                r.selectNodeContents(c);
                return new Set([...r.getClientRects()].map(x => Math.round(x.top))).size; }""")
        finally:
            browser.close()
    assert rows == [
        ["SSR1", "global", "pd", "interval_s = 5", "97.50 %", "97.36 %", "97.64 %", "percent", "97.00 %",
         "pass", "50,000",
         "6.3.2.1", "yes", ""],
        ["SSR1", "global", "mode3a_correct", "", "95.00 %", "94.00 %", "96.00 %", "percent", "98.00 %",
         "fail", "2,000", "COMPASS Radar preset (no clause of the 1997 standard given)", "no", ""],
        ["SSR1", "FL 100-200", "modec_correct", "", "96.50 %", "95.50 %", "97.50 %", "percent", "96.00 %",
         "inconclusive", "3,000", "COMPASS Radar preset (no clause of the 1997 standard given)", "no",
         "interval [0.955, 0.975] straddles 0.96"],
        ["SSR1", "global", "rms_m", "", "120.5", "110.4", "131.0", "metres", "150.0", "pass", "4,000",
         "5.2.1", "yes", ""],
        ["ADSB1", "global", "p95_m", "", "", "", "", "metres", "50.0", "inconclusive", "0", "ED-129 3.2",
         "no", "=withheld: no report where the reference's sigma is below the tolerance"],
    ]
    assert verdict_colour == "rgb(255, 199, 206)"  # fail: #ffc7ce
    # the notes, headed so, across the whole table under their figures (not a last column, a word a line,
    # pushed out of view): the page does not scroll sideways at Playwright's 1,280 px
    label, notes_px, table_px = notes_shown
    assert label == '"Notes: "' and notes_px == pytest.approx(table_px, abs=2.0)
    assert scroll[0] <= scroll[1]
    assert narrow_scroll[0] <= narrow_scroll[1] == 1024  # nor in a 1,024 px window, with LEBL's widest cells
    assert clause_lines == 2
    # the coverage figures load from the page itself, at the sizes the sample's PNGs were written with
    assert figures == [["SSR1: polar map", True, 400, 300], ["SSR1: vertical coverage", True, 320, 200]]
    assert blue > 50 and red > 50, (blue, red)  # both aircraft's lines and dots drawn
    assert refused == []
    assert [m for m in page_messages if m[0] in ("error", "warning")] == []
    assert any("bokeh" in text.lower() for _, text in page_messages)  # the console was listened to


def test_the_html_opens_on_each_sensors_verdicts_and_links_its_failures() -> None:
    """The sample scorecard by hand: SSR1 passes pd and rms_m, fails mode3a_correct (global, its second
    row), is inconclusive on modec_correct (a value); ADSB1 is inconclusive on p95_m with no value (not
    measured). The failure links to its own row of the scorecard."""
    from lxml import html as lhtml

    page = lhtml.fromstring(evaluation_html(scorecard(), tables(), map_points(), images=images()))
    rows = [[c.text_content() for c in tr.xpath("./td")]
            for tr in page.xpath('//table[@id="verdicts"]/tbody/tr')]
    assert rows == [["SSR1", "2", "1", "1", "0", "mode3a_correct: global"],
                    ["ADSB1", "0", "0", "1", "1", "none"]]
    (link,) = page.xpath('//table[@id="verdicts"]//a')
    target = page.get_element_by_id(link.get("href").lstrip("#"))
    assert [c.text_content() for c in target.xpath("./tr[1]/td")][:3] == ["SSR1", "global", "mode3a_correct"]


def test_the_html_lists_its_sections_and_folds_long_tables() -> None:
    """A line of links under the title, one per section heading, each to that heading; a table of 61 rows
    folded under its heading ('61 rows: show them'), one of 60 shown as it is."""
    from lxml import html as lhtml

    frames = {"Sixty": pd.DataFrame({"bin": range(60)}), "Sixty-one": pd.DataFrame({"bin": range(61)})}
    page = lhtml.fromstring(evaluation_html(scorecard(), frames, map_points()))
    links = page.xpath('//nav[@id="contents"]/a')
    headings = page.xpath("//h2")
    assert [a.text_content() for a in links] == [h.text_content() for h in headings] == [
        "Verdicts", "Scorecard", "Map", "Sixty", "Sixty-one"]
    assert [a.get("href") for a in links] == ["#" + h.get("id") for h in headings]
    sixty, sixty_one = (h.getnext() for h in headings[3:])
    assert sixty.tag == "table" and len(sixty.xpath("./tbody/tr")) == 60
    assert sixty_one.tag == "details"
    assert sixty_one.xpath("./summary")[0].text_content() == "61 rows: show them"
    assert len(sixty_one.xpath("./table/tbody/tr")) == 61
