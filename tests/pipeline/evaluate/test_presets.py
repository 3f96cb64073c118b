"""Presets as data: every shipped preset loads; its figures agree with ../shared/standards.md, read from that
file's tables here (not copied from the presets); bad user presets are refused naming file, requirement and
key."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from asterix_bytes import SHARED

from msdc.pipeline.evaluate.catalogue import CATALOGUE
from msdc.pipeline.evaluate.presets import available_presets, load_preset
from msdc.pipeline.evaluate.presets_doc import PAGE, page_with_tables

REPO = Path(__file__).resolve().parents[3]

STANDARDS = SHARED / "standards.md"
needs_standards = pytest.mark.skipif(not STANDARDS.is_file(),
                                     reason=f"{STANDARDS} absent (reference material beside the repository)")
SHIPPED = {"eurocontrol-1997-ssr", "eurocontrol-1997-psr", "esassp-psr-5nm", "esassp-psr-3nm", "ed117a",
           "ed87e", "ed116", "ed142-5nm", "ed142-3nm", "adsb-nra"}
CHECKED_PRESETS = {"eurocontrol-1997-psr", "esassp-psr-5nm", "esassp-psr-3nm"}


def _table_rows() -> list[list[str]]:
    """Every markdown table row of standards.md as its cells (header and rule rows included)."""
    return [[c.strip() for c in line.strip().strip("|").split("|")]
            for line in STANDARDS.read_text().splitlines() if line.startswith("|")]


def _prose() -> str:
    """standards.md with its line breaks and runs of spaces made single spaces (sentences span lines)."""
    return " ".join(STANDARDS.read_text().split())


def _row(first: str, *, column: int = 0, nth: int | None = None) -> list[str]:
    """The table row whose cell `column` starts with `first`: the only one, or the nth (from 0) of them."""
    found = [r for r in _table_rows() if len(r) > column and r[column].startswith(first)]
    assert len(found) == 1 or (nth is not None and len(found) > nth), (first, found)
    return found[nth or 0]


def _figure(text: str) -> tuple[str, float]:
    """('>', 0.97) from '> 97 %'; a figure without a sign is a limit not to exceed ('<=')."""
    match = re.search(r"(>=|<=|>|<)?\s*([\d.]+(?:e-?\d+)?)\s*(%?)", text)
    sign, number, percent = match.groups()
    return sign or "<=", float(number) / (100.0 if percent else 1.0)


def _find(preset, ident: str, area: str | None = None, **params):
    """The one requirement with this id, area and these parameters."""
    found = [r for r in preset.requirements if r.id == ident and r.area == area
             and all(r.parameters.get(k) == v for k, v in params.items())]
    assert len(found) == 1, (preset.name, ident, area, params, found)
    return found[0]


def test_every_shipped_preset_loads():
    assert set(available_presets()) == SHIPPED
    for name in SHIPPED:
        preset = load_preset(name)
        assert preset.name == name and preset.requirements
        assert all(r.id in CATALOGUE and r.clause and r.source and r.stated for r in preset.requirements)
        # a figure is "checked" only where standards.md says it was checked against the standard's text
        if name not in CHECKED_PRESETS | {"eurocontrol-1997-ssr"}:
            assert not any(r.checked for r in preset.requirements), name


@needs_standards
def test_1997_radar_standard_against_standards_md():
    ssr, psr = load_preset("eurocontrol-1997-ssr"), load_preset("eurocontrol-1997-psr")
    assert ssr.min_sample == psr.min_sample == int(re.search(r"at least ([\d,]+) samples",
                                                             _prose()).group(1).replace(",", ""))
    for quantity, preset, ident in [("SSR overall probability of detection", ssr, "pd"),
                                    ("PSR probability of target position detection", psr, "pd"),
                                    ("PSR false target reports", psr, "false_reports_per_scan"),
                                    ("PSR/SSR combination: probability of association", psr,
                                     "psr_ssr_association")]:
        _, figure, clause = _row(quantity)
        req = _find(preset, ident) if ident != "pd" else _find(preset, "pd", interval_s=None)
        direction, threshold = _figure(figure)
        assert (req.threshold, req.clause, req.checked) == (pytest.approx(threshold), clause, True)
        assert req.direction == (direction if direction != "<=" else ">=" if ident.endswith("association")
                                 else "<=")
    # "slant range bias 100 m, azimuth bias 0.1 deg, range gain 1 m/NM, time stamp 100 ms", then the SDs
    ids = {"slant range bias": ("range_bias_m", 1.0), "azimuth bias": ("azimuth_bias_deg", 1.0),
           "range gain": ("range_gain_ppm", 1e6 / 1852.0), "time stamp": ("time_bias_s", 1e-3),
           "range": ("range_sd_m", 1.0), "azimuth": ("azimuth_sd_deg", 1.0)}
    for quantity in ("PSR systematic errors", "PSR random errors (SD)"):
        _, figures, clause = _row(quantity)
        for part in figures.split(","):
            name, number = re.fullmatch(r"\s*([a-z ]+?) ([\d.]+) .*", part).groups()
            ident, scale = ids[name]
            req = _find(psr, ident)
            assert req.threshold == pytest.approx(float(number) * scale) and req.direction == "<="
            assert req.clause == clause and req.checked


@needs_standards
def test_compass_radar_additions_are_flagged_unchecked():
    prose = _prose()
    line = prose[prose.index("COMPASS's \"Radar\" preset adds"):][:300]  # the sentence (figures hold dots)
    ssr = load_preset("eurocontrol-1997-ssr")
    mode_a = float(re.search(r"Mode A correct >= ([\d.]+) %", line).group(1)) / 100
    mode_c, tolerance = re.search(r"Mode C correct \(within (\d+) ft\) >= ([\d.]+) %", line).groups()[::-1]
    assert _find(ssr, "mode3a_correct").threshold == pytest.approx(mode_a)
    req = _find(ssr, "modec_correct", tolerance_ft=float(tolerance))
    assert req.threshold == pytest.approx(float(mode_c) / 100)
    interval, pd = re.search(r"PD over (\d+) s >= ([\d.]+) %", line).groups()
    assert _find(ssr, "pd", interval_s=float(interval)).threshold == pytest.approx(float(pd) / 100)
    assert not any(r.checked for r in ssr.requirements if r.id != "pd" or r.parameters.get("interval_s"))


@needs_standards
def test_esassp_annex_d_against_standards_md():
    for column, name in ((1, "esassp-psr-5nm"), (2, "esassp-psr-3nm")):
        preset = load_preset(name)
        interval = _figure(_row("R1 measurement interval")[column])[1]
        direction, pd = _figure(_row("R2 probability of update")[column])
        req = _find(preset, "pd", interval_s=interval)
        assert (req.threshold, req.direction, req.checked) == (pytest.approx(pd), direction, True)
        direction, rms = _figure(_row("R3 horizontal position RMS")[column])
        req = _find(preset, "rms_m")
        assert (req.threshold, req.direction, req.checked) == (rms, direction, True)


def _split(cell: str) -> list[tuple[str, float]]:
    """'>= 95 % / >= 70 % / >= 90 %' -> the figures in order."""
    return [_figure(part) for part in cell.split(" / ")]


@needs_standards
def test_ed117a_against_standards_md():
    preset = load_preset("ed117a")
    areas = ("manoeuvring", "apron", "stands")
    label, figures = _row("probability of target report (1 s", column=2)[2:4]
    intervals = [float(s) for s in re.findall(r"(\d+) s", label)]
    for area, interval, (direction, pd) in zip(areas, intervals, _split(figures), strict=True):
        req = _find(preset, "pd", area, interval_s=interval)
        assert (req.threshold, req.direction) == (pytest.approx(pd), direction)
    for area, (_, metres) in zip(areas, _split(_row("reported position accuracy, 95 %", column=2, nth=0)[3]),
                                 strict=True):
        assert _find(preset, "p95_m", area).threshold == metres
    label, figure = _row("false target report beyond", column=2)[2:4]
    for area, metres in zip(areas, re.findall(r"\d+", label), strict=True):
        assert _find(preset, "false_reports", area, distance_m=float(metres)).threshold == _figure(figure)[1]
    shares = _split(_row("probability of identification: Mode S", column=2)[3])
    idents = ("address_correct", "callsign_correct", "mode3a_correct")
    for ident, (_, share) in zip(idents, shares, strict=True):
        assert _find(preset, ident).threshold == pytest.approx(share)
    assert not any(r.checked for r in preset.requirements)


@needs_standards
def test_ed142_against_standards_md():
    rms = _split(_row("horizontal position RMS", column=2)[3])
    label, figure = _row("false position (beyond", column=2)[2:4]
    for i, name in enumerate(("ed142-5nm", "ed142-3nm")):
        preset = load_preset(name)
        assert _find(preset, "rms_m").threshold == rms[i][1] and _find(preset, "rms_m").direction == "<="
        distance = float(re.findall(r"(\d+) m", label)[i])
        share = _figure(figure)[1]
        assert _find(preset, "false_reports", distance_m=distance).threshold == pytest.approx(share)
        assert _find(preset, "pd").parameters["scope"] == "per_target"  # "for every target"


@needs_standards
def test_adsb_nra_against_standards_md():
    text = _prose()
    latency = float(re.search(r"horizontal position latency ([\d.]+) s \(95 %\)", text).group(1))
    accuracy = float(re.search(r"position source accuracy (\d+) m \(95 %\)", text).group(1))
    preset = load_preset("adsb-nra")
    assert _find(preset, "latency_p95_s").threshold == latency
    assert _find(preset, "p95_m").threshold == accuracy


GOOD = """
[preset]
name = "mine"
title = "My radar"
standard = "local"
sensor_types = ["ssr"]
source = "our contract"

[preset.areas]
tma = "the TMA"

[[requirement]]
id = "pd"
threshold = 0.97
direction = ">="
parameters = { interval_s = 5 }
stated = ">= 97 %"
clause = "4.2"
checked = true
source = "contract"
area = "tma"

[[requirement]]
id = "rms_m"
threshold = 150
direction = "<="
stated = "150 m"
clause = "4.3"
checked = false
source = "contract"
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "mine.toml"
    path.write_text(text)
    return path


def test_a_user_preset_loads_by_path(tmp_path):
    preset = load_preset(_write(tmp_path, GOOD))
    assert preset.name == "mine" and preset.areas == {"tma": "the TMA"} and preset.min_sample is None
    pd, rms = preset.requirements
    assert pd.parameters == {"interval_s": 5.0} and pd.area == "tma" and rms.threshold == 150.0


@pytest.mark.parametrize("old, new, message", [
    ('threshold = 0.97', 'treshold = 0.97',
     "requirement 1 (pd): unknown key 'treshold' (did you mean 'threshold'?)"),
    ('threshold = 150', 'threshold = "150 m"', "requirement 2 (rms_m): key 'threshold' must be a number"),
    ('id = "rms_m"', 'id = "rms"', "requirement 2: unknown requirement id 'rms' (did you mean 'rms_m'?)"),
    ('direction = "<="', 'direction = "=<"', "requirement 2 (rms_m): key 'direction' must be one of"),
    ('checked = false', 'checked = "no"', "requirement 2 (rms_m): key 'checked' must be true or false"),
    ('interval_s = 5', 'intervals = 5',
     "requirement 1 (pd) parameters: unknown key 'intervals' (did you mean 'interval_s'?)"),
    ('interval_s = 5', 'interval_s = -5', "requirement 1 (pd) parameters: key 'interval_s' must be > 0"),
    ('{ interval_s = 5 }', '{ interval_s = 5, scope = "pertarget" }', "key 'scope' must be one of 'global', "
     "'per_target', got 'pertarget' (did you mean 'per_target'?)"),
    ('threshold = 0.97', 'threshold = 97', "key 'threshold' is a fraction between 0 and 1 for pd"),
    ('area = "tma"', 'area = "TMA"', "key 'area' names 'TMA', not among the preset's [areas] (tma)"),
    ('clause = "4.3"\n', '', "requirement 2 (rms_m): missing key 'clause'"),
    ('sensor_types = ["ssr"]', 'sensor_types = ["sr"]', "[preset]: key 'sensor_types' holds 'sr'"),
    ('title = "My radar"', 'titel = "My radar"', "[preset]: unknown key 'titel' (did you mean 'title'?)"),
    ('[[requirement]]\nid = "rms_m"', '[[requirements]]\nid = "rms_m"',
     "unknown key 'requirements' (did you mean 'requirement'?)"),
    ('threshold = 150', 'threshold = 150\nmin_sample = 0', "key 'min_sample' must be a whole number >= 1"),
    ('stated = "150 m"', 'stated = "150 m"\nstated = "x"', "not valid TOML"),
    ('threshold = 150', 'threshold = 0',
     "requirement 2 (rms_m): key 'threshold' must be a positive number of m"),
    ('interval_s = 5', 'interval_s = 1e-9',
     "requirement 1 (pd) parameters: key 'interval_s' must be at least 0.1 s"),
    ('id = "rms_m"\nthreshold = 150', 'id = "long_gaps"\nthreshold = 0.01\nparameters = { min_gap_s = 10, '
     'max_gap_s = 5 }', "requirement 2 (long_gaps) parameters: min_gap_s 10.0 must be below max_gap_s 5.0"),
    ('tma = "the TMA"', 'global = "everywhere"',
     "[preset.areas]: the area name 'global' is the scorecard's own"),
    ('sensor_types = ["ssr"]', 'sensor_types = []', "[preset]: key 'sensor_types' names no sensor type"),
])
def test_bad_presets_are_refused_naming_file_requirement_and_key(tmp_path, old, new, message):
    assert old in GOOD
    path = _write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(ValueError) as refused:
        load_preset(path)
    assert str(refused.value).startswith(str(path)) and message in str(refused.value)


def test_a_byte_order_mark_is_read_and_an_empty_name_refused(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD.encode())
    assert load_preset(path).name == "mine"
    with pytest.raises(ValueError, match="the preset is empty"):
        load_preset("")


def test_a_repeated_requirement_is_refused(tmp_path):
    repeated = GOOD + GOOD[GOOD.index('[[requirement]]\nid = "rms_m"'):]
    with pytest.raises(ValueError, match=r"requirement 3 \(rms_m\): repeats requirement 2"):
        load_preset(_write(tmp_path, repeated))


def test_a_required_parameter_is_asked_for(tmp_path):
    text = GOOD.replace('id = "rms_m"', 'id = "modec_correct"').replace("threshold = 150", "threshold = 0.9")
    with pytest.raises(ValueError,
                       match=r"requirement 2 \(modec_correct\) parameters: missing key 'tolerance_ft'"):
        load_preset(_write(tmp_path, text))


def test_unknown_preset_name_and_missing_file(tmp_path):
    with pytest.raises(ValueError, match=r"unknown preset 'ed117'.*did you mean 'ed117a'.*shipped presets"):
        load_preset("ed117")
    with pytest.raises(ValueError, match=r"preset file .*nothere.toml: no such file"):
        load_preset(tmp_path / "nothere.toml")
    with pytest.raises(ValueError, match=r"ed116.toml: no such file \(the shipped preset is named 'ed116'"):
        load_preset("ed116.toml")
    with pytest.raises(ValueError, match=r"preset file .*: not a file"):
        load_preset(tmp_path)


def test_the_docs_show_the_shipped_presets_and_ids():
    """docs/methods/evaluate.md holds the tables made from the catalogue and the TOML files."""
    text = (REPO / PAGE).read_text()
    assert text == page_with_tables(text), "python -m msdc.pipeline.evaluate.presets_doc --write-docs"
    assert all(f"#### `{name}`" in text for name in SHIPPED) and "| `rms_m` |" in text


def test_a_preset_gate_must_be_a_positive_distance(tmp_path):
    from msdc.pipeline.evaluate.presets import load_preset

    text = load_preset("ed116").path  # the shipped text, with its gate changed
    from importlib import resources

    shipped = resources.files("msdc.pipeline.evaluate").joinpath("presets/ed116.toml").read_text()
    assert text == "preset ed116" and "gate_m = 150.0" in shipped
    assert load_preset("ed116").association() == {"gate_m": 150.0}
    bad = tmp_path / "bad.toml"
    bad.write_text(shipped.replace("gate_m = 150.0", "gate_m = -1.0"))
    with pytest.raises(ValueError, match=r"\[preset\]: key 'gate_m' must be a positive number of metres"):
        load_preset(bad)
