"""``identification_correct`` and ``identification_false``: a report's identity as a whole (its Mode S
address, call sign and validated Mode 3/A code, whichever it carries) against the reference's. On the
sensor's own track of an aircraft known by its address the address is not compared (the track is keyed by
it); the trials judged against the sensor's own track are counted in the row's note."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.codes import MODE3A, _present, _validated, unread_callsigns
from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import associated, reference_values
from msdc.pipeline.evaluate.reference_gates import own_by_address, own_track_words, self_referenced

IDENTITIES = ("address", "callsign", "mode3a")


def _same(a, b) -> bool:
    return str(a).strip().upper() == str(b).strip().upper()


def identity_table(reports: pd.DataFrame, reference: pd.DataFrame,
                   parameters: Mapping | None) -> pd.DataFrame:
    """Per associated report: how many of its identity items could be compared with a known reference value
    (a Mode 3/A code only when validated and ungarbled; an address not on the sensor's own address-keyed
    track), how many of those differ, and whether it lies on the sensor's own track (``own``)."""
    rep = associated(reports, reference, parameters)
    rep = rep[rep["ref_index"].to_numpy() >= 0].reset_index(drop=True)
    compared = np.zeros(len(rep), int)
    differ = np.zeros(len(rep), int)
    keyed = own_by_address(rep, reference, parameters)
    for column in IDENTITIES:
        if column not in rep.columns:
            continue
        truth = reference_values(rep, reference, column, parameters)
        used = _present(rep[column]) & _present(pd.Series(truth, dtype=object))
        if column == "mode3a":
            valid = _validated(rep, *MODE3A[2:])
            used &= True if valid is None else valid
        if column == "address":
            used &= ~keyed
        if column == "callsign":  # the reference's unread (a character outside the ICAO set): not compared
            used &= ~unread_callsigns(truth)
        got = rep[column].to_numpy(object)
        wrong = np.array([u and not _same(a, b) for u, a, b in zip(used, got, truth, strict=True)], bool)
        compared += used
        differ += wrong
    return pd.DataFrame({"ref_aircraft": rep["ref_aircraft"].to_numpy(object), "compared": compared,
                         "differ": differ, "own": self_referenced(rep, reference, parameters)})


def _identification(requirement: str, reports: pd.DataFrame, reference: pd.DataFrame,
                    parameters: Mapping | None) -> Outcome:
    table = identity_table(reports, reference, parameters)
    judged = table[table["compared"] > 0]
    if not len(judged):
        return withheld(requirement, "no associated report carries an identity the reference knows")
    wrong = judged["differ"].to_numpy() > 0
    count = int((~wrong).sum()) if requirement.endswith("_correct") else int(wrong.sum())
    note = own_track_words(int(judged["own"].sum()), len(judged))
    return share(requirement, count, len(judged), (note,) if note else ())


def identification_correct(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                           sensor=None) -> Outcome:
    """Of the reports with an identity item the reference knows, those whose every such item matches."""
    return _identification("identification_correct", reports, reference, parameters)


def identification_false(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
                         sensor=None) -> Outcome:
    """Of the same reports, those with an item that differs from the reference's."""
    return _identification("identification_false", reports, reference, parameters)
