"""Time offsets seen in position errors (evaluate.timing): the fitted lead against numpy's polyfit and its
standard error against the scatter of seeded draws; the note names the aircraft given a late reference by
construction, a common offset, and stays silent on an antenna offset that does not grow with speed."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.timing import fit_lead, timing_note


def _aircraft(name: str, lead_s: float, rng, offset_m: float = 0.0, noise_m: float = 3.0,
              speeds=(5.0, 80.0), n: int = 120) -> pd.DataFrame:
    """n reports 1 s apart of one aircraft accelerating through ``speeds``: along = offset + lead * speed
    + noise (independent draws), its horizontal error the along part and 2 m across."""
    speed = np.linspace(*speeds, n)
    along = offset_m + lead_s * speed + rng.normal(0.0, noise_m, n)
    return pd.DataFrame({"aircraft": name, "t_s": np.arange(n, dtype=float), "along_m": along,
                         "speed_mps": speed, "error_m": np.hypot(along, 2.0)})


def test_the_lead_is_the_slope_of_along_track_error_on_speed():
    rng = np.random.default_rng(1)
    e = _aircraft("A", 0.8, rng, offset_m=12.0)
    fit = fit_lead(e["along_m"].to_numpy(), e["speed_mps"].to_numpy(), e["t_s"].to_numpy())
    slope, _ = np.polyfit(e["speed_mps"], e["along_m"], 1)
    assert fit.lead_s == pytest.approx(slope, abs=1e-9) and fit.n == 120


def test_the_standard_error_matches_the_scatter_of_the_leads():
    """Over 400 seeded aircraft (12 blocks of 10 s each) the fitted leads scatter as their jackknife
    standard errors say (within 15 %), and three of them, the note's test, hold the true lead in 97 % or
    more of the aircraft."""
    rng = np.random.default_rng(2)
    fits = [fit_lead(e["along_m"].to_numpy(), e["speed_mps"].to_numpy(), e["t_s"].to_numpy())
            for e in (_aircraft("A", 0.5, rng) for _ in range(400))]
    leads, ses = np.array([f.lead_s for f in fits]), np.array([f.se_s for f in fits])
    assert np.std(leads) == pytest.approx(np.mean(ses), rel=0.15)
    assert np.mean(np.abs(leads - 0.5) <= 3.0 * ses) >= 0.97


def test_too_few_blocks_give_no_lead():
    e = _aircraft("A", 0.5, np.random.default_rng(3), n=40)  # 40 s: four 10 s blocks
    assert np.isnan(fit_lead(e["along_m"].to_numpy(), e["speed_mps"].to_numpy(), e["t_s"].to_numpy()).se_s)


def test_aircraft_with_a_late_reference_are_named_with_the_errors_they_hold():
    rng = np.random.default_rng(4)
    errors = pd.concat([_aircraft(f"OK{i}", 0.0, rng) for i in range(10)]
                       + [_aircraft("LATE1", 1.0, rng), _aircraft("LATE2", -1.2, rng)], ignore_index=True)
    beyond = errors["error_m"] > 12.0
    held = int((beyond & errors["aircraft"].str.startswith("LATE")).sum())
    note = timing_note(errors, 12.0)
    assert note.startswith("timing: 2 of 12 aircraft lead or lag the reference unlike the others")
    named = dict(re.findall(r"(\w+) ([+-]\d\.\d\d) s", note.split("; the others")[0]))
    assert named.keys() == {"LATE1", "LATE2"}
    assert float(named["LATE1"]) == pytest.approx(1.0, abs=0.1)
    assert float(named["LATE2"]) == pytest.approx(-1.2, abs=0.1)
    assert f"holding {held:,} of the {int(beyond.sum()):,} errors over 12 m" in note


def test_a_common_offset_is_said_without_blaming_either_side():
    rng = np.random.default_rng(5)
    errors = pd.concat([_aircraft(f"A{i}", 0.4, rng) for i in range(8)], ignore_index=True)
    note = timing_note(errors)
    assert note.startswith("timing: the reports lead the reference by 0.4")
    assert "which of the two the data cannot say" in note


@pytest.mark.parametrize("offsets_m", [(0.0,) * 10,
                                       (-15.0, -10.0, 0.0, 5.0, 12.0, 20.0, -8.0, 3.0, 9.0, 15.0)])
def test_no_note_without_a_clock(offsets_m):
    """No offset, or antennas 8-20 m apart along fuselages taxiing at 3-15 m/s (where a fit through the
    origin would read up to several seconds): the intercept takes them, no note."""
    rng = np.random.default_rng(6)
    errors = pd.concat([_aircraft(f"A{i}", 0.0, rng, offset_m=o, speeds=(3.0, 15.0))
                        for i, o in enumerate(offsets_m)], ignore_index=True)
    assert timing_note(errors, 12.0) == ""


def test_late_aircraft_holding_no_error_over_the_threshold_get_no_note():
    """A reference 1 s late on an aircraft taxiing at 3-12 m/s: its errors (12 m at most, with 0.5 m of
    noise) stay under a 20 m threshold, so the row has nothing to explain; without a threshold it is named."""
    rng = np.random.default_rng(9)
    errors = pd.concat([_aircraft(f"OK{i}", 0.0, rng, noise_m=0.5, speeds=(3.0, 12.0)) for i in range(6)]
                       + [_aircraft("LATE", 1.0, rng, noise_m=0.5, speeds=(3.0, 12.0))], ignore_index=True)
    assert errors.loc[errors["aircraft"] == "LATE", "error_m"].max() < 20.0
    assert timing_note(errors, 20.0) == ""
    named = re.search(r"\((LATE) ([+-]\d\.\d\d) s;", timing_note(errors))
    assert named is not None and float(named.group(2)) == pytest.approx(1.0, abs=0.05)
