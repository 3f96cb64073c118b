"""Code and identity requirements: Mode 3/A and Mode C present, valid, correct and false; Mode S address and
call sign correct and false; each over the test reports associated with a reference aircraft."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.coverage import Sensor
from msdc.pipeline.evaluate.detection import update_interval
from msdc.pipeline.evaluate.outcome import Outcome, share, withheld
from msdc.pipeline.evaluate.reference import (
    associated,
    parameter,
    reference_altitude_ft,
    reference_values,
)
from msdc.pipeline.evaluate.reference_gates import own_by_address, own_track_words, self_referenced
from msdc.pipeline.evaluate.scans import update_numbers
from msdc.pipeline.evaluate.statistics import share_clusters

# per code: the report's column, the reference's, and the report's 'not validated' and 'garbled' bits
MODE3A = ("mode3a", "mode3a", "mode3a_v", "mode3a_g")
MODEC = ("flight_level", "altitude_ft", "flight_level_v", "flight_level_g")


def _present(values: pd.Series) -> np.ndarray:
    """Whether each report carries the value (not NA, not empty text)."""
    v = values.to_numpy(object)
    return np.array([x is not None and x is not pd.NA and not (isinstance(x, float) and np.isnan(x))
                     and x != "" for x in v], dtype=bool)


def _validated(rep: pd.DataFrame, v_col: str, g_col: str) -> np.ndarray | None:
    """1 where the report's code is validated and not garbled, 0 where either bit is set, None when the
    reports carry neither bit (then validity cannot be judged); a missing bit counts as not set."""
    if v_col not in rep.columns and g_col not in rep.columns:
        return None
    bad = np.zeros(len(rep), dtype=bool)
    for col in (v_col, g_col):
        if col in rep.columns:
            bad |= pd.to_numeric(rep[col], errors="coerce").fillna(0).to_numpy() != 0
    return ~bad


def _mine(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None) -> pd.DataFrame:
    """The reports associated with a reference aircraft."""
    rep = associated(reports, reference, parameters)
    return rep[rep["ref_index"].to_numpy() >= 0].reset_index(drop=True)


def _update_keys(rep: pd.DataFrame, parameters: Mapping | None, sensor: Sensor | None) -> np.ndarray | None:
    """Each associated report's aircraft update (a plot and its split share their replies, so their codes
    are not independent trials: scans.update_numbers); None without an update interval."""
    period, _ = update_interval(rep, parameters, sensor)
    if not math.isfinite(period) or period <= 0:
        return None
    return update_numbers(rep["ref_index"].to_numpy(), rep["t_s"].to_numpy(float), period)


def _share(requirement: str, success: np.ndarray, trial: np.ndarray, keys: np.ndarray | None,
           notes: tuple[str, ...] = (), own: np.ndarray | None = None) -> Outcome:
    """The share of successes among the trials (bool masks over the associated reports), its interval over
    their aircraft updates when ``keys`` gives them; ``own`` (the reports on the sensor's own track) counted
    among the trials in a note."""
    clusters = share_clusters(success[trial], keys[trial]) if keys is not None else None
    if own is not None:
        notes = (*notes, own_track_words(int((own & trial).sum()), int(trial.sum())))
    return share(requirement, int((success & trial).sum()), int(trial.sum()), tuple(n for n in notes if n),
                 clusters=clusters)


def _misses(known: np.ndarray, have: np.ndarray, valid: np.ndarray, used: np.ndarray, equal: np.ndarray,
            what: str, differ: str = "") -> str:
    """The note splitting a ``*_correct`` row's misses by why: no {what} in the report, one not validated or
    garbled, or one that differs from the reference's (``differ``: how, in words); '' when none missed."""
    missed = known & ~(used & equal)
    if not missed.any():
        return ""
    parts = [(int((missed & ~have).sum()), f"no {what}"),
             (int((missed & have & ~valid).sum()), f"a {what} not validated or garbled"),
             (int((missed & used & ~equal).sum()), differ or f"a different {what}")]
    said = "; ".join(f"{n:,} {'carries' if n == 1 else 'carry'} {words}" for n, words in parts if n)
    return f"of the {int(missed.sum()):,} misses: {said}"


def _code_outcome(requirement: str, reports: pd.DataFrame, reference: pd.DataFrame,
                  parameters: Mapping | None, code: tuple[str, str, str, str], sensor: Sensor | None
                  ) -> Outcome:
    """Present / valid / correct / false of Mode 3/A or Mode C, by the rule the docs give."""
    col, ref_col, v_col, g_col = code
    what = requirement.rsplit("_", 1)[1]
    rep = _mine(reports, reference, parameters)
    keys = _update_keys(rep, parameters, sensor)
    own = self_referenced(rep, reference, parameters)
    every = np.ones(len(rep), bool)
    have = _present(rep[col]) if col in rep.columns else np.zeros(len(rep), bool)
    if what == "present":
        return _share(requirement, have, every, keys, own=own)
    valid = _validated(rep, v_col, g_col)
    if what == "valid":
        if valid is None:
            return withheld(requirement, f"the reports carry no {v_col}/{g_col} bits")
        return _share(requirement, valid, have, keys, own=own)
    valid = np.ones(len(rep), bool) if valid is None else valid
    notes = () if v_col in rep.columns or g_col in rep.columns else (
        f"no {v_col}/{g_col} bits: every code taken as validated",)
    if col == "flight_level":
        tol = parameter(parameters, "tolerance_ft", None)
        if tol is None:
            raise ValueError(f"{requirement} needs the parameter tolerance_ft")
        truth = reference_altitude_ft(rep, reference, parameters)
        known = np.isfinite(truth)
        alt = (pd.to_numeric(rep[col], errors="coerce").to_numpy(float) * 100.0 if col in rep.columns
               else np.full(len(rep), np.nan))
        with np.errstate(invalid="ignore"):
            equal = np.abs(alt - truth) <= float(tol)
    else:
        truth = reference_values(rep, reference, ref_col, parameters)
        known = _present(pd.Series(truth, dtype=object))
        equal = np.array([str(a) == str(b) for a, b in zip(rep[col].to_numpy(object), truth, strict=True)]) \
            if col in rep.columns else np.zeros(len(rep), bool)
    if not known.any():
        return withheld(requirement, f"the reference gives no {ref_col} for the associated reports")
    used = have & valid & known
    if what == "correct":
        notes = (*notes, _misses(known, have, valid, used, equal, "code", "a different code")
                 if col == "mode3a" else _misses(known, have, valid, used, equal, "Mode C",
                                                 "a Mode C outside the tolerance"))
        return _share(requirement, used & equal, known, keys, notes, own)
    return _share(requirement, ~equal, used, keys, notes, own)


def unread_callsigns(values) -> np.ndarray:
    """Where a call sign holds a character outside the ICAO set (decoded as "?"): unread, not a call sign
    to compare a report's with."""
    return np.array([isinstance(v, str) and "?" in v for v in values], dtype=bool)


def _identity_outcome(requirement: str, reports: pd.DataFrame, reference: pd.DataFrame,
                      parameters: Mapping | None, column: str, sensor: Sensor | None) -> Outcome:
    """Correct / false Mode S address or call sign: as Mode 3/A, without validity bits. An address is not
    judged on the sensor's own track of an aircraft known by its address (that track is keyed by the very
    address judged: it could fail only by association); those reports are counted in a note."""
    rep = _mine(reports, reference, parameters)
    keys = _update_keys(rep, parameters, sensor)
    own = self_referenced(rep, reference, parameters)
    truth = reference_values(rep, reference, column, parameters)
    known = _present(pd.Series(truth, dtype=object))
    notes: tuple[str, ...] = ()
    if column == "address" and (keyed := own_by_address(rep, reference, parameters) & known).any():
        n_keyed = int(keyed.sum())
        they = "they report" if n_keyed > 1 else "it reports"
        notes = (f"{n_keyed:,} report{'s' if n_keyed > 1 else ''} on the sensor's own track, which is keyed "
                 f"by the address {they}, not judged",)
        known &= ~keyed
        if not known.any():
            return withheld(requirement, "every report lies on the sensor's own track, keyed by the address "
                            "it reports: an address is judged only against another sensor's track")
    if column == "callsign":  # a character outside the ICAO set ("?" as decoded): the reference's is unread
        unread = known & unread_callsigns(truth)
        if unread.any():
            n_unread = int(unread.sum())
            notes = (*notes, f"{n_unread:,} report{'s' if n_unread > 1 else ''} whose reference call sign "
                             "holds a character outside the ICAO set (shown '?'), not judged")
            known &= ~unread
    if not known.any():
        return withheld(requirement, f"the reference gives no {column} for the associated reports")
    have = _present(rep[column]) if column in rep.columns else np.zeros(len(rep), bool)
    got = rep[column].to_numpy(object) if column in rep.columns else np.full(len(rep), None, object)
    equal = np.array([str(a).strip().upper() == str(b).strip().upper()
                      for a, b in zip(got, truth, strict=True)], dtype=bool)
    used = have & known
    if requirement.endswith("_correct"):
        what = "address" if column == "address" else "call sign"
        notes = (*notes, _misses(known, have, have, used, equal, what))
        return _share(requirement, used & equal, known, keys, notes, own)
    return _share(requirement, ~equal, used, keys, notes, own)


def _code(requirement: str, code: tuple[str, str, str, str]):
    """The requirement function of one Mode 3/A or Mode C id."""
    def fn(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
           sensor=None) -> Outcome:
        return _code_outcome(requirement, reports, reference, parameters, code, sensor)
    fn.__name__ = requirement
    fn.__doc__ = f"``{requirement}`` (rule: docs/methods/evaluate.md)."
    return fn


def _identity(requirement: str, column: str):
    """The requirement function of one address or call sign id."""
    def fn(reports: pd.DataFrame, reference: pd.DataFrame, parameters: Mapping | None = None,
           sensor=None) -> Outcome:
        return _identity_outcome(requirement, reports, reference, parameters, column, sensor)
    fn.__name__ = requirement
    fn.__doc__ = f"``{requirement}`` (rule: docs/methods/evaluate.md)."
    return fn


CODE_REQUIREMENTS = {
    **{f"mode3a_{w}": _code(f"mode3a_{w}", MODE3A) for w in ("present", "valid", "correct", "false")},
    **{f"modec_{w}": _code(f"modec_{w}", MODEC) for w in ("present", "valid", "correct", "false")},
    **{f"address_{w}": _identity(f"address_{w}", "address") for w in ("correct", "false")},
    **{f"callsign_{w}": _identity(f"callsign_{w}", "callsign") for w in ("correct", "false")},
}
