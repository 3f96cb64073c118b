"""The verdicts per sensor of a scorecard, counted by hand."""

from __future__ import annotations

import math

import pandas as pd

from msdc.pipeline.evaluate.verdicts import sensor_verdicts, verdicts_text


def _card() -> pd.DataFrame:
    rows = [  # sensor, sector, requirement, value, verdict
        ("MLAT", "manoeuvring", "pd", 0.9998, "pass"),
        ("MLAT", "manoeuvring", "p95_m", 27.4, "fail"),
        ("SMR", "global", "pd", 0.80, "fail"),
        ("MLAT", "stands", "pd", math.nan, "inconclusive"),
        ("MLAT", "global", "callsign_correct", 0.85, "fail"),
        ("MLAT", "apron", "callsign_correct", 0.86, "fail"),
        ("MLAT", "apron", "p95_m", 16.2, "inconclusive"),
    ]
    return pd.DataFrame(rows, columns=["sensor", "sector", "requirement", "value", "verdict"],
                        index=[10, 11, 12, 13, 14, 15, 16])  # an index of its own: rows count from 0


def test_each_sensors_verdicts_counted_in_the_order_the_sensors_come() -> None:
    mlat, smr = sensor_verdicts(_card())
    assert (mlat.sensor, mlat.counts, mlat.not_measured) == (
        "MLAT", {"pass": 1, "fail": 3, "inconclusive": 2}, 1)
    assert mlat.failed == {"p95_m": [("manoeuvring", 1)], "callsign_correct": [("global", 4), ("apron", 5)]}
    assert (smr.counts, smr.not_measured, smr.failed) == (
        {"pass": 0, "fail": 1, "inconclusive": 0}, 0, {"pd": [("global", 2)]})


def test_the_terminal_lines() -> None:
    assert verdicts_text(_card()).splitlines() == [
        "Verdicts of MLAT: pass 1, fail 3, inconclusive 2 (1 of them not measured); failed: "
        "p95_m (manoeuvring); callsign_correct (global, apron)",
        "Verdicts of SMR: pass 0, fail 1, inconclusive 0 (0 of them not measured); failed: pd (global)"]
