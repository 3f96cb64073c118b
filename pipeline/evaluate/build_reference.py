"""Building the reference the requirements judge against, from the measurements (pipeline.model's frame):
``leave_one_out`` (every sensor but the one under test, tracked and smoothed by the IMM of pipeline.track),
``adsb_reference`` (ADS-B reports alone), each after the quality gates (reference_gates), with the
self-reference fallback where no other sensor sees the aircraft. An external reference is read by
``external_reference.read_external_reference``.

Each reference row carries, besides reference.REFERENCE_REQUIRED and the pressure altitude and identity:
``sigma_m`` (the reference's 1-sigma position error along its ellipse's major axis), ``built_by`` (the
sensors whose reports updated the track stretch the row belongs to), ``self_reference`` (True where the
row comes from the sensor's own track: detection, codes and identity may use it, position accuracy not) and
``updated`` (True where a report updated the track at the row's time: the reference saw the aircraft then).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from msdc.pipeline.evaluate.reference import in_order
from msdc.pipeline.evaluate.reference_gates import Gates, gate_reports
from msdc.pipeline.model.identity import known_by_address
from msdc.pipeline.model.schema import equals_text

IDENTITY_COLUMNS = ("mode3a", "address", "callsign")
# the tracker's columns a reconstruction reads (reconstruct)
TRACK_INPUTS = ("aircraft_id", "segment", "time", "latitude", "longitude", "flight_level", "speed_kt",
                "sigma_major_m", "sources")
BUILT_COLUMNS = ("aircraft", "t_s", "latitude", "longitude", "altitude_ft", *IDENTITY_COLUMNS, "sigma_m",
                 "built_by", "self_reference", "updated", "on_ground")
BUILT_BY_SEPARATOR = " + "
# a segment of a sensor's own track is a self-reference when updated at least this often, or when its one
# update has another of the same aircraft within 30 s, or when its aircraft is known by its Mode S address:
# a lone report of a Mode 3/A code would judge itself (Barcelona's lone M3A:4445 plot, 39 NM from that
# code's aircraft, was associated to its own one-row track and never false). One-report segments beside
# others are kept: the tracker starts one at each plot its gate rejects, and where a reflection alternates
# with the aircraft's plots every plot is such a segment (dropping them made 36 of the aircraft's own plots
# false there). So are an addressed aircraft's: a parked aircraft a Mode S radar hears every 48-96 s is
# real, and without its own plots went to its neighbours on the apron as wrong addresses
MIN_OWN_UPDATES = 2


@dataclass
class BuiltReference:
    """The reference frame (BUILT_COLUMNS), how many ADS-B reports each gate removed (GATE_KEYS), the
    epoch its ``t_s`` counts from, and what was done, in words."""

    frame: pd.DataFrame
    gate_counts: dict[str, int]
    epoch: pd.Timestamp | None
    notes: list[str] = field(default_factory=list)


def _epoch(meas: pd.DataFrame, epoch: pd.Timestamp | None) -> pd.Timestamp | None:
    """The UTC midnight ``t_s`` counts from: the one given, else that of the earliest report (the day the
    decoder's ``day`` column counts from, so reference and radar_reports share a clock)."""
    from msdc.pipeline.track.tracker import utc_timestamp

    if epoch is not None:
        return utc_timestamp("epoch", epoch)
    return None if meas.empty else pd.Timestamp(meas["time"].min()).tz_convert("UTC").floor("D")


def _empty() -> pd.DataFrame:
    """A reference with no row, in BUILT_COLUMNS."""
    return pd.DataFrame({c: pd.Series(dtype=object if c in (*IDENTITY_COLUMNS, "aircraft", "built_by")
                                      else bool if c in ("self_reference", "updated")
                                      else "boolean" if c == "on_ground" else float) for c in BUILT_COLUMNS})


def _built_by(group: np.ndarray, n_groups: int, sources: np.ndarray) -> np.ndarray:
    """Per segment (``group``: each track row's segment among ``n_groups``; ``sources``: the rows'
    comma-joined sensors), the sensors whose reports updated it, sorted and joined."""
    sensors: list[set[str]] = [set() for _ in range(n_groups)]
    for g, text in set(zip(group.tolist(), sources.tolist(), strict=True)):
        sensors[g].update(p.strip() for p in text.split(",") if p.strip())
    return np.array([BUILT_BY_SEPARATOR.join(sorted(s)) for s in sensors] or [""], dtype=object)


def _segments(key: np.ndarray, segment: np.ndarray) -> tuple[np.ndarray, int]:
    """Per track row, a number for its (aircraft, segment) from the aircraft's code (``key``, from 0), and
    how many there are."""
    group, groups = pd.factorize(key.astype(np.int64) * (int(segment.max(initial=0)) + 1) + segment)
    return group, len(groups)


def _codes(right_key: np.ndarray, left_key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both sides' keys as integer codes of one numbering (integer keys from 0, as reconstruct numbers the
    aircraft, are their own codes)."""
    if (right_key.dtype.kind in "iu" and left_key.dtype.kind in "iu" and right_key.min() >= 0
            and (not len(left_key) or left_key.min() >= 0)):
        return right_key.astype(np.int64), left_key.astype(np.int64)
    codes, _ = pd.factorize(np.concatenate([right_key, left_key]))
    return codes[:len(right_key)].astype(np.int64), codes[len(right_key):].astype(np.int64)


def _combined(r_code: np.ndarray, right_t: np.ndarray, l_code: np.ndarray, left_t: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """(key, time) of both sides as one integer each, in the order of key then time: key * width + the
    time's offset from the earliest where the integer times allow it, else key * span + the time's rank."""
    times = np.concatenate([right_t, left_t])
    if times.dtype.kind == "i" and len(times):
        lo, hi = int(times.min()), int(times.max())
        width = hi - lo + 1
        top = int(max(r_code.max(initial=0), l_code.max(initial=0))) + 1
        if top * width < 2**62:
            return (r_code * width + (right_t.astype(np.int64) - lo),
                    l_code * width + (left_t.astype(np.int64) - lo))
    times = np.unique(times)
    span = len(times) + 1
    return r_code * span + np.searchsorted(times, right_t), l_code * span + np.searchsorted(times, left_t)


def _latest_at(left_key: np.ndarray, left_t: np.ndarray, right_key: np.ndarray, right_t: np.ndarray
               ) -> np.ndarray:
    """Per left row, the index into the right rows of the same key's latest row at or before the left
    row's time (of equal times, the last in the right's order), else that key's first; -1 for a key with
    no right row. The right rows must be sorted by key, then time (stably)."""
    if not len(right_key):
        return np.full(len(left_key), -1, np.int64)
    r_code, l_code = _codes(right_key, left_key)
    r_comb, l_comb = _combined(r_code, right_t, l_code, left_t)
    order = np.argsort(r_comb, kind="stable")  # the codes' order, equal (key, time) rows as given
    r_sorted, r_code_sorted = r_comb[order], r_code[order]
    at = np.searchsorted(r_sorted, l_comb, "right") - 1
    same = (at >= 0) & (r_code_sorted[np.maximum(at, 0)] == l_code)
    first = np.searchsorted(r_code_sorted, l_code, "left")  # before the key's first row: its first
    last = len(order) - 1
    has_key = (first <= last) & (r_code_sorted[np.minimum(first, last)] == l_code)
    return np.where(has_key, order[np.minimum(np.where(same, at, first), last)], -1)


def _keyed(aircraft: pd.Series, time: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """Aircraft ids as an object array and times as int64 nanoseconds (UTC)."""
    return (aircraft.astype(str).to_numpy(object), time.astype("datetime64[ns, UTC]").array.asi8)


def _identity(left_key: np.ndarray, left_t: np.ndarray, rep_key: np.ndarray, rep_t: np.ndarray,
              reports: pd.DataFrame, established: bool = False) -> dict[str, object]:
    """Per reference row (its aircraft's code and time in ns), each identity column taken from the reports
    that built it (their aircraft's codes, of the same numbering, and times): per aircraft, the latest value
    reported at or before the row's time (before the first, the first). With ``established`` (a sensor's own
    track judging that sensor's codes), only values the aircraft's previous report also gave count: otherwise
    each report's own code, wrong or garbled, would be its reference and never false. The values are
    worked on as integer codes of their texts and made text once, per column."""
    out: dict[str, object] = {}
    for col in IDENTITY_COLUMNS:
        if col not in reports.columns:
            out[col] = np.full(len(left_key), None, object)
            continue
        value, labels = _text_codes(reports[col])
        keep = value >= 0
        keep[keep] = labels[value[keep]] != ""  # an empty text says nothing
        value, key, t = value[keep], rep_key[keep], rep_t[keep]
        order = np.lexsort((t, key))  # by aircraft, then time; stable among equal times
        value, key, t = value[order], key[order], t[order]
        if established:  # the aircraft's previous report gave the same value
            same = np.zeros(len(value), bool)
            same[1:] = (key[1:] == key[:-1]) & (value[1:] == value[:-1])
            value, key, t = value[same], key[same], t[same]
        if not len(value):
            out[col] = np.full(len(left_key), None, object)
            continue
        at = _latest_at(left_key, left_t, key, t)
        out[col] = _text_column(labels, np.where(at >= 0, value[np.maximum(at, 0)], -1))
    return out


def _text_codes(values: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """A column's values as integer codes (-1: missing) into its distinct texts (``str`` of each value,
    equal texts one code), the texts an object array."""
    if isinstance(values.dtype, pd.CategoricalDtype):
        codes, labels = values.cat.codes.to_numpy(np.int64), values.cat.categories.to_numpy(object)
    else:
        codes, labels = pd.factorize(values)
        codes, labels = np.asarray(codes, np.int64), np.asarray(labels, object)
    texts, merged = np.unique(np.array([str(v) for v in labels], dtype=object), return_inverse=True)
    return np.where(codes >= 0, merged.reshape(-1)[np.maximum(codes, 0)] if len(labels) else -1, -1), texts


# the dtype pandas gives a column of texts with missing values (Arrow-backed "str" from pandas 3, else object)
_INFERRED_TEXT = pd.Series(np.array(["", np.nan], dtype=object)).dtype


def _text_column(labels: np.ndarray, codes: np.ndarray):
    """``labels[codes]`` (-1: missing, NaN) as the column a frame would make of that object array, built
    from the labels and codes without an object per row where pandas keeps text in Arrow."""
    if isinstance(_INFERRED_TEXT, np.dtype) or not (codes >= 0).any():
        out = np.full(len(codes), np.nan, object)
        out[codes >= 0] = labels[codes[codes >= 0]]
        return out
    import pyarrow as pa

    taken = pa.array(labels, type=pa.large_string()).take(pa.array(codes, mask=codes < 0))
    return pd.array(taken, dtype=_INFERRED_TEXT)


def _level_between_updates(level: np.ndarray, t: np.ndarray, upd: np.ndarray, group: np.ndarray
                           ) -> np.ndarray:
    """The tracks' flight level with the rows between two updates of a segment (``group``: the rows'
    segment) interpolated linearly in time between the levels filtered at those updates: the vertical
    filter is not smoothed, so between updates it flies the last vertical rate on and jumps at the next
    update (a descent begun in an ADS-B gap left the reference 350-1,650 ft above the aircraft in
    simulation). ``t``: the rows' times (any unit), ``upd``: the rows a report updated."""
    level = level.copy()
    order = np.argsort(group, kind="stable")
    bounds = np.flatnonzero(np.diff(group[order])) + 1
    for rows in np.split(order, bounds) if len(order) else []:
        known = rows[upd[rows] & np.isfinite(level[rows])]
        if known.size < 2:
            continue
        by_time = known[np.argsort(t[known], kind="stable")]
        inside = rows[(t[rows] > t[by_time[0]]) & (t[rows] < t[by_time[-1]]) & ~upd[rows]]
        level[inside] = np.interp(t[inside], t[by_time], level[by_time])
    return level


def _on_ground(key_ref: np.ndarray, t_ref: np.ndarray, key: np.ndarray, t: np.ndarray, reports: pd.DataFrame,
               speed_kt: np.ndarray) -> pd.api.extensions.ExtensionArray:
    """Per reference row (its aircraft's code and time in ns; the reports' of the same numbering), whether the
    aircraft is on the surface: its latest report's own say at or before the row's time (GBS, STAT, a field
    monitor's RAB; before the first report, the first's), else the row's tracked ``speed_kt`` below 50 kt,
    the rule of conflicts (a radar plot's reported speed of 0 at FL 180 made an airborne aircraft
    "surface"); unknown for an aircraft without reports."""
    from msdc.pipeline.quality.surface import SURFACE_SPEED_KT

    said = (reports["on_ground"].astype("boolean").to_numpy(dtype=object, na_value=None)
            if "on_ground" in reports else np.full(len(reports), None, object))
    order = np.lexsort((t, key))
    at = _latest_at(key_ref, t_ref, key[order], t[order])
    latest = said[order][np.maximum(at, 0)]
    slow = np.asarray(speed_kt, float) < SURFACE_SPEED_KT  # NaN: not slow
    flag = pd.array(np.where(pd.isna(latest), slow, latest).astype(bool), dtype="boolean")
    flag[at < 0] = pd.NA
    return flag


def _supported(key: np.ndarray, t_ns: np.ndarray, group: np.ndarray, updated: np.ndarray, n_groups: int,
               max_gap_s: float = 30.0) -> np.ndarray:
    """Per segment of a sensor's own track, whether it is a reference: updated at least MIN_OWN_UPDATES
    times, or its one update has another update of the same aircraft within max_gap_s."""
    counts = np.bincount(group[updated], minlength=n_groups)
    ok = counts >= MIN_OWN_UPDATES
    k, t, g = key[updated], t_ns[updated], group[updated]
    order = np.lexsort((t, k))
    k, t, g = k[order], t[order], g[order]
    near = np.zeros(len(t), bool)
    gap = max_gap_s * 1e9
    same_prev = np.r_[False, k[1:] == k[:-1]]
    near[1:] |= same_prev[1:] & (t[1:] - t[:-1] <= gap)
    near[:-1] |= same_prev[1:] & (t[1:] - t[:-1] <= gap)
    lone = counts[g] == 1
    ok[g[lone & near]] = True
    return ok


def reconstruct(reports: pd.DataFrame, epoch: pd.Timestamp, *, step_s: float = 1.0,
                max_coast_s: float = 60.0, self_reference: bool = False) -> pd.DataFrame:
    """The smoothed IMM reconstruction (pipeline.track.track, RTS) of these reports as reference rows:
    only rows the reports support (coasted rows after a segment's last update left out), with sigma_m,
    built_by, updated (a report updated the row) and the identity of the reports. The tracker runs each
    aircraft as its own task (pipeline.parallel: threads, or a cluster's workers); what follows is done
    for every aircraft at once, column by column."""
    from msdc.pipeline.track import track

    if reports.empty:
        return _empty()
    tr = track(reports, step_s=step_s, max_coast_s=max_coast_s, smooth=True, epoch=epoch,
               columns=TRACK_INPUTS, summaries=False).tracks  # what the reference rows are made of
    if tr.empty:
        return _empty()
    # per row as arrays, the texts made objects once: what follows is done for every aircraft at once
    aircraft = tr["aircraft_id"].to_numpy(object)
    sources = tr["sources"].to_numpy(object)
    t_ns = tr["time"].astype("datetime64[ns, UTC]").array.asi8
    # the ids as integer codes (one per id, the reports' too): grouping, sorting and matching compare
    # numbers, not texts
    rep_key, rep_t = _keyed(reports["aircraft_id"], reports["time"])
    codes, names = pd.factorize(np.concatenate([aircraft, rep_key]))
    key, rep_key = codes[:len(aircraft)], codes[len(aircraft):]
    group, n_groups = _segments(key, tr["segment"].to_numpy(np.int64))
    built_by = _built_by(group, n_groups, sources)  # per segment
    updated = sources != ""
    # a smoothed segment is supported between its first and last update; rows coasted beyond the last
    # update are a prediction, not a reconstruction
    first = np.full(n_groups, np.iinfo(np.int64).max)
    last = np.full(n_groups, np.iinfo(np.int64).min)  # a segment without an update keeps no row
    np.minimum.at(first, group, t_ns)
    np.maximum.at(last, group[updated], t_ns[updated])
    keep = (t_ns >= first[group]) & (t_ns <= last[group])
    if self_reference:  # a sensor's own segment of one report is that report judging itself: no reference
        addressed = known_by_address(names)
        segment_key = np.zeros(n_groups, np.int64)
        segment_key[group] = key  # a segment is one aircraft's
        keep &= (_supported(key, t_ns, group, updated, n_groups) | addressed[segment_key])[group]
    key, t_ns, group, updated = (v[keep] for v in (key, t_ns, group, updated))
    level = _level_between_updates(tr["flight_level"].to_numpy(float)[keep], t_ns.astype(float), updated,
                                   group)
    identity = _identity(key, t_ns, rep_key, rep_t, reports, established=self_reference)
    on_ground = _on_ground(key, t_ns, rep_key, rep_t, reports, tr["speed_kt"].to_numpy(float)[keep])
    out = pd.DataFrame({
        "aircraft": _text_column(np.asarray(names, object), key),
        "t_s": (tr["time"][keep] - epoch).dt.total_seconds().to_numpy(float),
        "latitude": tr["latitude"].to_numpy(float)[keep], "longitude": tr["longitude"].to_numpy(float)[keep],
        "altitude_ft": level * 100.0,
        **identity,
        "sigma_m": tr["sigma_major_m"].to_numpy(float)[keep], "built_by": _text_column(built_by, group),
        "self_reference": np.full(len(key), self_reference),
        "updated": updated,
        "on_ground": on_ground.to_numpy()})
    del tr
    if in_order(out["aircraft"], out["t_s"].to_numpy(float)):
        return out  # as the tracker gives them, most often: the sort would copy every column for nothing
    return out.sort_values(["aircraft", "t_s"], kind="stable", ignore_index=True)


def rows_of(frame: pd.DataFrame) -> dict:
    """Per aircraft of a reference (or probe) frame, its row numbers."""
    return frame.groupby(frame["aircraft"].astype(str).to_numpy(object), sort=False).indices


def _uncovered(own: pd.DataFrame, independent: pd.DataFrame, max_gap_s: float,
               ind_rows: dict | None = None) -> pd.DataFrame:
    """The rows of the sensor's own track at times no independent reference stretch of the same aircraft
    covers (stretches: runs of samples at most max_gap_s apart). ind_rows: ``rows_of(independent)``, when
    known (one reference serves ten radars)."""
    if own.empty or independent.empty:
        return own
    keep = np.ones(len(own), bool)
    ind_t = independent["t_s"].to_numpy(float)
    ind_rows = rows_of(independent) if ind_rows is None else ind_rows
    for aircraft, rows in rows_of(own).items():
        t_ind = ind_t[ind_rows[aircraft]] if aircraft in ind_rows else ind_t[:0]
        if not t_ind.size:
            continue
        t = own["t_s"].to_numpy(float)[rows]
        i = np.searchsorted(t_ind, t, side="right") - 1
        before = np.clip(i, 0, t_ind.size - 1)
        after = np.clip(i + 1, 0, t_ind.size - 1)
        bridged = t_ind[after] - t_ind[before] <= max_gap_s
        inside = (i >= 0) & (t <= t_ind[-1]) & ((t == t_ind[before]) | bridged)
        keep[rows] = ~inside
    return own[keep]


def _needing_fallback(own: pd.DataFrame, independent: pd.DataFrame, epoch: pd.Timestamp,
                      max_gap_s: float, ind_rows: dict | None = None) -> np.ndarray:
    """Per report of the sensor, whether its aircraft has a report the independent reference does not
    cover (_uncovered's rule at report times): only those aircraft need the sensor's own track, which is
    the costly part of a leave-one-out reference where ADS-B sees every aircraft."""
    if own.empty or independent.empty:
        return np.ones(len(own), bool)
    t_s = (own["time"].astype("datetime64[ns, UTC]").array.asi8 - epoch.value) / 1e9
    probe = pd.DataFrame({"aircraft": own["aircraft_id"].astype(str).to_numpy(object), "t_s": t_s})
    left = _uncovered(probe.sort_values(["aircraft", "t_s"], kind="stable"), independent, max_gap_s, ind_rows)
    return probe["aircraft"].isin(set(left["aircraft"])).to_numpy(bool)


def _reference(meas: pd.DataFrame, builders: np.ndarray, sensor_id: str | None, gates: Gates,
               epoch: pd.Timestamp | None, step_s: float, max_coast_s: float, fallback: bool,
               max_gap_s: float, cache: dict | None = None) -> BuiltReference:
    """The reference from the gated reports the mask ``builders`` selects (a mask over ``meas``), with the
    sensor's own track where no builder covers an aircraft when ``fallback``. ``cache`` (one per ``meas``)
    keeps the latest reconstruction by the sensors that built it: the ADS-B reference of ten radars in a
    row is built once."""
    epoch = _epoch(meas, epoch)
    notes = _shared_navigation(meas, builders, sensor_id)
    key = (frozenset(str(v) for v in meas.loc[builders, "sensor_id"].unique()), repr(gates), epoch, step_s,
           max_coast_s)
    if cache is not None and key in cache:
        built, counts, shared = cache[key]
    else:
        gated, counts = gate_reports(meas[builders], gates)
        built = (reconstruct(gated, epoch, step_s=step_s, max_coast_s=max_coast_s) if epoch is not None
                 else _empty())
        shared = {}  # what the sensors' fallbacks read of it: its rows per aircraft, once
        if cache is not None:  # the latest only: leave-one-out never builds the same twice
            cache.clear()
            cache[key] = (built, counts, shared)
    frames = [built]
    if fallback and sensor_id is not None and epoch is not None:
        own_reports = meas[equals_text(meas["sensor_id"], sensor_id)]
        if (own_reports["sensor_kind"] == "adsb").any():
            own_reports, _ = gate_reports(own_reports, gates)
        if "rows" not in shared and len(built):
            shared["rows"] = rows_of(built)
        ind_rows = shared.get("rows")
        own_reports = own_reports[_needing_fallback(own_reports, built, epoch, max_gap_s, ind_rows)]
        own = reconstruct(own_reports, epoch, step_s=step_s, max_coast_s=max_coast_s, self_reference=True)
        own = _uncovered(own, built, max_gap_s, ind_rows)
        if len(own):
            notes.append(f"{own['aircraft'].nunique()} aircraft judged in part or whole against "
                         f"{sensor_id}'s own track ({len(own)} self-reference rows): not for position "
                         "accuracy")
            frames.append(own)
    frames = [f for f in frames if len(f)]
    if len(frames) == 2 and _sorted(built, shared) and in_order(frames[1]["aircraft"],
                                                              frames[1]["t_s"].to_numpy(float)):
        frame = _merged(built, frames[1], _blocks(built, shared))
    else:
        frame = pd.concat(frames, ignore_index=True) if frames else _empty()
        if not in_order(frame["aircraft"], frame["t_s"].to_numpy(float)):
            frame = frame.sort_values(["aircraft", "t_s"], kind="stable", ignore_index=True)
    return BuiltReference(frame, counts, epoch, notes)


def _sorted(built: pd.DataFrame, shared: dict) -> bool:
    """Whether the reconstruction is in aircraft and time order (once per reconstruction)."""
    if "sorted" not in shared:
        shared["sorted"] = in_order(built["aircraft"], built["t_s"].to_numpy(float))
    return shared["sorted"]


def _blocks(built: pd.DataFrame, shared: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A reconstruction in aircraft and time order as its aircraft labels (ascending), the row where each
    one's samples start (and the end) and the sample times (once per reconstruction)."""
    if "blocks" not in shared:
        labels = built["aircraft"]
        codes, _ = pd.factorize(labels)  # ascending in a sorted frame: a new code where a label starts
        starts = np.flatnonzero(np.r_[True, codes[1:] != codes[:-1]])
        names = labels.iloc[starts].to_numpy(object)
        shared["blocks"] = (names, np.r_[starts, len(built)], built["t_s"].to_numpy(float))
    return shared["blocks"]


def _merged(built: pd.DataFrame, own: pd.DataFrame, blocks: tuple[np.ndarray, np.ndarray, np.ndarray]
            ) -> pd.DataFrame:
    """``built`` and ``own``, each in aircraft and time order, as one frame in that order, own's rows after
    built's of the same aircraft and time (what a stable sort of the two one after the other leaves): built
    cut where own's rows go in, not every row sorted and copied again for a few thousand of the sensor's
    own."""
    names, starts, t = blocks
    labels = own["aircraft"].to_numpy(object)
    own_t = own["t_s"].to_numpy(float)
    j = np.searchsorted(names, labels, side="left")
    found = (j < len(names)) & (names[np.minimum(j, len(names) - 1)] == labels)
    at = starts[j].copy()  # an aircraft built has none of: before the first label after it
    runs = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])  # own's rows come aircraft by aircraft
    for a, b in zip(runs, np.r_[runs[1:], len(own)], strict=True):
        if found[a]:
            lo, hi = starts[j[a]], starts[j[a] + 1]
            at[a:b] = lo + np.searchsorted(t[lo:hi], own_t[a:b], side="right")
    cuts = np.flatnonzero(np.r_[True, at[1:] != at[:-1]])
    pieces, done = [], 0
    for a, b in zip(cuts, np.r_[cuts[1:], len(own)], strict=True):
        pieces += [built.iloc[done:at[a]], own.iloc[a:b]]
        done = at[a]
    pieces.append(built.iloc[done:])
    columns = pd.concat([built.iloc[:0], own.iloc[:0]]).columns  # as the two one after the other
    return pd.concat([p for p in pieces if len(p)], ignore_index=True)[columns]


def _shared_navigation(meas: pd.DataFrame, builders: np.ndarray, sensor_id: str | None) -> list[str]:
    """A note when an ADS-B sensor under test is judged against other ADS-B ground stations: they relay
    the same aircraft's position, from the same navigation source, so their errors are not independent."""
    if sensor_id is None:
        return []
    adsb = equals_text(meas["sensor_kind"], "adsb")
    if not adsb[equals_text(meas["sensor_id"], sensor_id)].any():
        return []
    others = sorted(str(v) for v in meas.loc[builders & adsb, "sensor_id"].dropna().unique())
    if not others:
        return []
    return [f"the reference of ADS-B sensor {sensor_id} includes ADS-B from {', '.join(others)}: the same "
            "aircraft's navigation source, so its position errors are not independent of the sensor's"]


def _check_sensor(meas: pd.DataFrame, sensor_id: str) -> None:
    """Refuse a sensor under test that is not in the measurements, naming those present."""
    present = sorted(str(v) for v in meas["sensor_id"].dropna().unique())
    if sensor_id not in present:
        raise ValueError(f"sensor {sensor_id!r} is not in the measurements (present: {', '.join(present)})")


def leave_one_out(meas: pd.DataFrame, sensor_id: str, *, gates: Gates | None = None,
                  epoch: pd.Timestamp | None = None, step_s: float = 1.0, max_coast_s: float = 60.0,
                  fallback: bool = True, max_gap_s: float = 30.0, require_present: bool = True,
                  cache: dict | None = None) -> BuiltReference:
    """The reference for ``sensor_id``: per aircraft, the smoothed IMM track of every other sensor's
    reports (the ADS-B ones after the gates); where none covers an aircraft (no independent sample within
    max_gap_s), the sensor's own smoothed track, flagged ``self_reference`` (``fallback``). A sensor absent
    from ``meas`` is refused unless ``require_present`` is False (its reports may all be unidentified)."""
    if require_present:
        _check_sensor(meas, sensor_id)
    builders = ~equals_text(meas["sensor_id"], sensor_id)
    return _reference(meas, builders, sensor_id, gates or Gates(), epoch, step_s, max_coast_s, fallback,
                      max_gap_s, cache)


def adsb_reference(meas: pd.DataFrame, sensor_id: str | None = None, *, gates: Gates | None = None,
                   epoch: pd.Timestamp | None = None, step_s: float = 1.0, max_coast_s: float = 60.0,
                   fallback: bool = True, max_gap_s: float = 30.0, cache: dict | None = None
                   ) -> BuiltReference:
    """The reference from the ADS-B reports alone, after the gates, tracked and smoothed; an ADS-B sensor
    under test is left out of it. With ``sensor_id`` and ``fallback``, aircraft no ADS-B report covers get
    the sensor's own track, flagged ``self_reference``."""
    if sensor_id is not None:
        _check_sensor(meas, sensor_id)
    builders = ((meas["sensor_kind"] == "adsb").to_numpy(bool)
                & ~equals_text(meas["sensor_id"], sensor_id or ""))
    return _reference(meas, builders, sensor_id, gates or Gates(), epoch, step_s, max_coast_s, fallback,
                      max_gap_s, cache)
