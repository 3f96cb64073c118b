"""Which aircraft samples an analysis counts: a minimum flight level, no Mode-A-only targets, no listed
Mode 3/A codes (VFR conspicuity codes, say). Declared once as command-line options (`jobs.options.
SelectionOptions`); `msdc conflicts` applies them to its losses and alerts, and an analysis of sensors or
tracks can apply the same ones.

A sample is one aircraft at one time (a track row). Its Mode 3/A code and call sign are those of the
aircraft's last report at or before that time that carried one (`identity_timeline`, `identity_at`):
codes change in flight, a VFR flight squawks 7000 until it is given a code. An aircraft is Mode-A-only
when no report gave it an address or a call sign (its `aircraft_id` is "M3A:" and its code,
`pipeline.model.identity`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.pipeline.model.identity import MODE_A_PREFIX

MODE_A_ONLY_PREFIX = MODE_A_PREFIX
IDENTITY_COLUMNS = ("callsign", "mode3a")
_CODE = re.compile(r"[0-7]{4}")


@dataclass(frozen=True)
class Selection:
    """The samples to count: at or above min_fl (a sample without a level is then left out), not of a
    Mode-A-only target, not squawking one of exclude_codes (four octal digits each)."""

    min_fl: float | None = None
    exclude_mode_a_only: bool = False
    exclude_codes: tuple[str, ...] = ()

    @property
    def active(self) -> bool:
        """Whether anything is left out."""
        return self.min_fl is not None or self.exclude_mode_a_only or bool(self.exclude_codes)

    def parameters(self) -> dict:
        """The selection as recorded with a run's parameters."""
        return {"min_fl": self.min_fl, "exclude_mode_a_only": self.exclude_mode_a_only,
                "exclude_codes": list(self.exclude_codes)}


def parse_codes(value, name: str = "--exclude-codes") -> tuple[str, ...]:
    """'7000,2000' (or a sequence of codes) -> ('2000', '7000'): four octal digits each; ValueError naming
    the option and the bad item."""
    items = value.split(",") if isinstance(value, str) else [str(v) for v in (value or ())]
    codes = []
    for i, item in enumerate(items):
        code = item.strip()
        if not _CODE.fullmatch(code):
            which = f"item {i + 1} " if len(items) > 1 else ""
            raise ValueError(f"{name} {value!r}: {which}{code!r} is not a Mode 3/A code (four octal digits "
                             "0-7, e.g. 7000)")
        codes.append(code)
    return tuple(sorted(set(codes)))


def is_mode_a_only(aircraft_ids) -> np.ndarray:
    """Per aircraft_id, whether it is a Mode-A-only target (no address and no call sign in any report)."""
    ids = pd.Series(np.asarray(aircraft_ids, dtype=object))
    return ids.astype("string").str.startswith(MODE_A_ONLY_PREFIX).fillna(False).to_numpy(bool)


def identity_timeline(meas: pd.DataFrame) -> pd.DataFrame:
    """`aircraft_id, time, callsign, mode3a` at each report where either changes (the first report of an
    aircraft included), each the last value reported up to then, or before any, the first one reported
    ("" when never): what `identity_at` looks up. Small: a row per change, not per report."""
    cols = ["aircraft_id", "time", *IDENTITY_COLUMNS]
    frame = meas.loc[meas["aircraft_id"].notna().to_numpy(bool), cols]
    frame = pd.DataFrame({"aircraft_id": frame["aircraft_id"].astype(str).to_numpy(dtype=object),
                          "time": pd.to_datetime(frame["time"], utc=True).array,
                          **{c: frame[c].astype("string").to_numpy(dtype=object, na_value=None)
                             for c in IDENTITY_COLUMNS}})
    frame = frame.sort_values(["aircraft_id", "time"], kind="stable").reset_index(drop=True)
    by = frame.groupby("aircraft_id", sort=False)
    for c in IDENTITY_COLUMNS:
        frame[c] = by[c].ffill()
        frame[c] = frame.groupby("aircraft_id", sort=False)[c].bfill().fillna("")
    new = frame["aircraft_id"].ne(frame["aircraft_id"].shift())
    for c in IDENTITY_COLUMNS:
        new |= frame[c].ne(frame[c].shift())
    return frame[new.to_numpy(bool)].reset_index(drop=True)


def identity_at(timeline: pd.DataFrame, aircraft_ids, times) -> pd.DataFrame:
    """`callsign, mode3a` of each aircraft at each time (one row per pair of them, in their order), from
    `identity_timeline`: the last values reported at or before the time, before the first report the first
    ones; "" for an aircraft the timeline does not have."""
    query = pd.DataFrame({"aircraft_id": pd.Series(np.asarray(aircraft_ids, dtype=object)).astype(str),
                          "time": pd.to_datetime(pd.Series(times), utc=True).array,
                          "row": np.arange(len(aircraft_ids))})
    empty = pd.DataFrame({c: [""] * len(query) for c in IDENTITY_COLUMNS})
    if not len(query) or not len(timeline):
        return empty
    query = query.dropna(subset=["time"]).sort_values("time", kind="stable")
    timeline = timeline.sort_values("time", kind="stable")
    out = empty.copy()
    for direction in ("forward", "backward"):  # backward last: it wins where both found one
        found = pd.merge_asof(query, timeline, on="time", by="aircraft_id", direction=direction)
        hit = found[IDENTITY_COLUMNS[0]].notna().to_numpy(bool)
        rows = found["row"].to_numpy()[hit]
        for c in IDENTITY_COLUMNS:
            out.loc[rows, c] = found.loc[hit, c].to_numpy(dtype=object)
    return out


def selected_samples(samples: pd.DataFrame, selection: Selection, timeline: pd.DataFrame | None = None
                     ) -> tuple[np.ndarray, dict[str, int]]:
    """Per sample (`aircraft_id, time, flight_level`), whether the selection keeps it, and how many
    samples each rule left out (a sample may be left out by more than one)."""
    keep = np.ones(len(samples), bool)
    counts: dict[str, int] = {}
    if selection.min_fl is not None:
        level = samples["flight_level"].to_numpy(float)
        low = ~(level >= selection.min_fl)  # no level: not shown to be above
        counts["below_min_fl"] = int(low.sum())
        keep &= ~low
    if selection.exclude_mode_a_only:
        mode_a = is_mode_a_only(samples["aircraft_id"])
        counts["mode_a_only"] = int(mode_a.sum())
        keep &= ~mode_a
    if selection.exclude_codes:
        if timeline is None:
            raise ValueError("selected_samples: excluding codes needs the identity timeline")
        code = identity_at(timeline, samples["aircraft_id"].to_numpy(), samples["time"])["mode3a"]
        listed = code.isin(selection.exclude_codes).to_numpy(bool)
        counts["excluded_codes"] = int(listed.sum())
        keep &= ~listed
    return keep, counts
