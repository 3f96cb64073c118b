"""``identification_correct`` / ``identification_false`` on hand-built reports of two aircraft: a report
is judged on the identity items it carries that the reference knows (a Mode 3/A code only when validated
and ungarbled), and is false if any of them differs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from msdc.pipeline.evaluate.requirements import REQUIREMENTS

IDS = {"A": ("AAA001", "ABC1", "1234", 0.0), "B": ("BBB002", "XYZ9", "4321", 1.0)}


def _case() -> tuple[pd.DataFrame, pd.DataFrame]:
    t = np.arange(0.0, 30.0)
    reference = pd.concat([pd.DataFrame({"aircraft": ac, "t_s": t, "latitude": lat, "longitude": 0.01 * t,
                                         "address": a, "callsign": c, "mode3a": m})
                           for ac, (a, c, m, lat) in IDS.items()], ignore_index=True)
    rows = [dict(address="AAA001", callsign="ABC1", mode3a="1234") for _ in range(6)]
    rows += [dict(address="AAA001", callsign="ABC2", mode3a="1234"),  # wrong call sign: false
             dict(address="AAA001", callsign="ABC1", mode3a="7777", mode3a_g=1),  # garbled code not judged
             dict(address=None, callsign=None, mode3a=None),  # no identity: not judged
             dict(address=None, callsign=None, mode3a="1235")]  # wrong validated code: false
    reports = pd.DataFrame(rows).assign(t_s=np.arange(10.0) * 2, latitude=0.0)
    reports["longitude"] = 0.01 * reports["t_s"]
    reports["mode3a_g"] = reports.get("mode3a_g", pd.Series(0, index=reports.index)).fillna(0)
    reports["mode3a_v"] = 0
    b = pd.DataFrame({"t_s": [3.0, 7.0], "latitude": 1.0, "longitude": [0.03, 0.07], "address": "bbb002",
                      "callsign": None, "mode3a": None, "mode3a_g": 0, "mode3a_v": 0})
    return pd.concat([reports, b], ignore_index=True), reference


def test_identity_judged_on_the_items_carried_and_known():
    reports, reference = _case()
    right = REQUIREMENTS["identification_correct"](reports, reference, {})
    wrong = REQUIREMENTS["identification_false"](reports, reference, {})
    assert (right.count, right.n) == (9, 11)  # 12 reports, one with no identity
    assert (wrong.count, wrong.n) == (2, 11)
    assert right.value == pytest.approx(9 / 11) and wrong.value == pytest.approx(2 / 11)


def test_no_identity_the_reference_knows_is_withheld():
    reports, reference = _case()
    out = REQUIREMENTS["identification_correct"](reports, reference.drop(columns=["address", "callsign",
                                                                                 "mode3a"]), {})
    assert np.isnan(out.value) and "no associated report carries an identity" in out.notes[0]


def test_an_address_on_the_sensors_own_track_keyed_by_it_is_not_compared():
    """On the sensor's own track of AAA001 (keyed by its address) a wrong address is not compared (the
    track takes the address the sensor reports); the call sign and code still are. B's two reports and an
    added one on A with only a wrong address ('AAA009') carry nothing else: not judged. Left: A's six right,
    the wrong call sign, the garbled code's report (its call sign right) and the wrong validated code, 7 of
    9 right, all nine on the own track."""
    reports, reference = _case()
    reference = reference.assign(aircraft=reference["address"], self_reference=True)
    reports.loc[len(reports)] = dict(address="AAA009", callsign=None, mode3a=None, t_s=19.0, latitude=0.0,
                                     longitude=0.19, mode3a_g=0, mode3a_v=0)
    right = REQUIREMENTS["identification_correct"](reports, reference, {})
    assert (right.count, right.n) == (7, 9)
    assert any("self-reference: 9 of 9 trials" in n for n in right.notes)
