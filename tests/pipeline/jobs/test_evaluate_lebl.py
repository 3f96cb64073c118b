"""msdc evaluate on the real LEBL hour (../shared/real), against what another method found: the six aircraft
whose ADS-B lags the multilateration by 0.8-1.2 s at speed were found by benchmarks/lebl_mlat_speed.py (the
median of along-track error over speed per aircraft against ADS-B interpolated by address, no evaluate code);
the timing notes of the manoeuvring-area p95 and false-report rows name the same six."""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import pytest
from asterix_bytes import SHARED

from msdc.pipeline.jobs.evaluate import EvaluateOptions, evaluate_job

REAL = SHARED / "real"
FILES = ("adsb_v023_160510-lebl-220001.ast", "mlat_160510-lebl-220001.ast", "smr_160510-lebl-220001.ast")
LATE_ADSB = {"343386", "3443D2", "344441", "3444CA", "3444CF", "344548"}  # benchmarks/lebl_mlat_speed.py
ROOT = Path(__file__).resolve().parents[3]
pytestmark = [pytest.mark.validation, pytest.mark.skipif(
    not all((REAL / f).exists() for f in FILES), reason=f"{REAL} lacks the LEBL hour: real case skipped")]


def _sensor_file(path: Path) -> Path:
    """The [[sensor]] tables of docs/methods/lebl-hour.md (the corrected reference points) written out."""
    text = (ROOT / "docs" / "methods" / "lebl-hour.md").read_text(encoding="utf-8")
    start = text.index("[[sensor]]")
    path.write_text(text[start:text.index("```", start)])
    return path


def test_the_late_adsb_aircraft_are_named_on_the_multilaterations_accuracy_row(tmp_path):
    # the options of benchmarks/evaluate_real.py
    result = evaluate_job(EvaluateOptions(
        inputs=tuple(str(REAL / f) for f in FILES), sensors=str(_sensor_file(tmp_path / "lebl.toml")),
        preset="ed117a", sectors=str(ROOT / "docs" / "examples" / "lebl-areas.geojson"),
        editions=("21=0.23",), date=dt.date(2016, 5, 10), adsb_sigma_m=5.0, reference="adsb"))
    card = result.scorecard
    (notes,) = card[(card["sector"] == "manoeuvring") & (card["requirement"] == "p95_m")]["notes"]
    (timing,) = re.findall(r"timing: [^;]*;[^)]*\)", notes)
    assert set(re.findall(r"\b(3[0-9A-F]{5}) [+-]\d", timing)) == LATE_ADSB
    # the false reports too: the benchmark found 119 of its 120 reports beyond 60 m on those six aircraft
    (notes,) = card[(card["sector"] == "manoeuvring") & (card["requirement"] == "false_reports")]["notes"]
    said = re.search(r"timing: ([\d,]+) of the ([\d,]+) false reports .*?\(([^:]*):", notes)
    near, false, named = said.groups()
    assert set(named.split(", ")) == LATE_ADSB
    assert int(near.replace(",", "")) >= 0.95 * int(false.replace(",", ""))
