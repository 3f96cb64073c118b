"""Sensor data quality tables: counts, duplicates, update intervals, gaps, missing speeds, jumps, ADS-B NIC.

Rows are per aircraft (``aircraft_id``, pipeline.model.identity; "(all)" pools the aircraft in the air,
"(all surface)" those on the surface: pipeline.quality.surface) and per sensor (radar or ADS-B, with its
SAC/SIC). Everything after the duplicate count is computed on de-duplicated reports
(``pipeline.model.dedup``, per aircraft and sensor). Update intervals are the time differences
between consecutive reports of one aircraft from one sensor of at most ``gap_s`` (their count, min,
median, 95th percentile and ``interval_max_within_gap_s``; ``interval_max_s`` is the longest interval of
all, gaps included); longer ones are gaps (listed with their start and end;
"reappeared_after_1h" when longer than an hour). An aircraft known by its Mode 3/A code alone is
labelled with it ("M3A:7052"); reports of no aircraft (no address, call sign or Mode 3/A) get one row
per sensor labelled "(no identity)", counted but with no intervals or gaps: they are many targets, and
time between them measures nothing. ``two_targets`` marks an aircraft whose reports from that sensor switch
back and forth between two places (pipeline.model.mixed): its intervals and gaps mix two targets; a pooled
row is marked when one of its aircraft is.
Columns ending ``_utc`` (and the jumps' ``utc``) are instants, datetime64[ns, UTC], NaT when the
recording is undated (its ``*_tod`` columns then give the time of day); JSON writes them as ISO 8601.
Columns ending ``_tod`` are times of day in seconds since midnight UTC, like ``time_of_day``; the workbook
shows them as clock times (hh:mm:ss.000), hence no ``_s`` in their names.
"""

from __future__ import annotations

import itertools
from collections.abc import Collection, Iterator

import numpy as np
import pandas as pd

from msdc.pipeline.model.dedup import DEDUP_KEYS, deduplicate
from msdc.pipeline.model.identity import aircraft_labels
from msdc.pipeline.model.jumps import JUMP_FLAG_COLUMNS, JUMP_INPUTS, jump_table
from msdc.pipeline.model.time import UTC_DTYPE, dated_or_nat, with_clock
from msdc.pipeline.quality.checks import check_frame, check_options, check_seconds
from msdc.pipeline.quality.surface import SURFACE_ALL, SURFACE_INPUTS, mostly_surface, on_surface

ALL = "(all)"
UNIDENTIFIED = "?"  # the aircraft key of reports that belong to no aircraft (aircraft_id <NA>)
NO_IDENTITY = "(no identity)"  # their call-sign label: no address, call sign or Mode 3/A code
REAPPEARANCE_S = 3600.0
QUALITY_BIN_S = 600.0
NUCP_MIN = 5  # NUCp below this is low integrity (MOPS version 0)
NIC_MIN = 6  # NIC below this is low integrity (MOPS versions 1 and 2)
ADSB_INDICATORS = ["nucp_nic", "nacp", "nucr_nacv", "sil", "fom_pa"]  # fom_pa: the 0.2x figure of merit PA
SENSOR_KEYS = ["sensor", "sac", "sic"]
SHARE_COLUMNS = ["nucp_below_5_pct", "nic_below_6_pct", "low_integrity_pct"]
ID_KEYS = ["callsign", "address", *SENSOR_KEYS]

QUALITY_COLUMNS = [
    *ID_KEYS, "on_surface", "reports", "duplicates_removed", "reports_after_dedup", "first_tod", "last_tod",
    "first_utc", "last_utc", "intervals", "interval_min_s", "interval_median_s", "interval_p95_s",
    "interval_max_s", "interval_max_within_gap_s", "gaps", "longest_gap_s", "reappearances", "speed_missing",
    "speed_zero", "speed_missing_or_zero", "speed_missing_or_zero_pct", "jumps", "nucp_below_5_pct",
    "nic_below_6_pct", "low_integrity_pct", "mops_versions", "two_targets",
]
HISTOGRAM_COLUMNS = [*SENSOR_KEYS, "bin_start_s", "bin_end_s", "intervals"]
GAP_COLUMNS = [*ID_KEYS, "gap_start_tod", "gap_end_tod", "gap_start_utc", "gap_end_utc", "gap_duration_s",
               "reappeared_after_1h"]
JUMP_COLUMNS = [*ID_KEYS, "time_of_day", "utc", "latitude", "longitude", "fit_latitude", "fit_longitude",
                "jump_size_m"]
VALUE_COUNT_COLUMNS = [*ID_KEYS, "indicator", "value", "reports", "share_pct"]
# The measurement columns quality_tables reads, and the flags of pipeline.model.marks.mark_once it reuses
# when the frame carries them; every other column is left out of its working copies (a day holds a
# million reports)
QUALITY_INPUTS = list(dict.fromkeys([
    *DEDUP_KEYS, *JUMP_INPUTS, "sensor_id", "sensor_kind", "sac", "sic", "address", "callsign",
    *ADSB_INDICATORS, "mops_version", *SURFACE_INPUTS]))
QUALITY_FLAGS = ["duplicate", *JUMP_FLAG_COLUMNS]
DEDUP_COLUMNS = [*DEDUP_KEYS, "sensor_kind", "sensor_id", "duplicate"]  # what deduplicate reads
ADSB_UNREAD = ["sensor_kind", "sensor_id", "ground_speed_kt", "heading_deg", "duplicate"]  # once deduplicated


def histogram_edges_s(gap_s: float) -> np.ndarray:
    """Update-interval bin edges: 0.1 s up to 20 s (fine enough to show a radar's scan jitter and an ADS-B
    station's spread), then 30, 60, 120 s, closed by gap_s."""
    fine = np.round(np.arange(0.0, 20.0 + 1e-9, 0.1), 1)
    edges = np.concatenate([fine, [30.0, 60.0, 120.0]])
    return np.append(edges[edges < gap_s], gap_s)


def _aircraft_labels(meas: pd.DataFrame) -> pd.DataFrame:
    """Reports (their QUALITY_INPUTS and QUALITY_FLAGS) with the thesis clock, an ``aircraft`` key ("?" when
    unidentified), ``sensor`` (the kind) and each aircraft's call-sign/address labels in place of the
    per-report values."""
    both = with_clock(meas[[c for c in meas if c in QUALITY_INPUTS or c in QUALITY_FLAGS]])
    both["sensor"] = both["sensor_kind"].astype("object")
    both["aircraft"] = both["aircraft_id"].astype("object").fillna(UNIDENTIFIED)
    labels = aircraft_labels(meas).set_index("aircraft_id")
    codes, aircraft = pd.factorize(both["aircraft"])  # labels looked up once per aircraft, not per report
    per_aircraft = {column: pd.Series(aircraft).map(labels[column]).fillna("").astype("object").to_numpy()
                    for column in ("callsign", "address")}
    # an aircraft known by its Mode 3/A code alone shows it ("M3A:7052"); reports of no aircraft say so
    unlabelled = (per_aircraft["callsign"] == "") & (per_aircraft["address"] == "")
    keys = np.asarray(aircraft, dtype=object)
    per_aircraft["callsign"] = np.where(unlabelled, np.where(keys == UNIDENTIFIED, NO_IDENTITY, keys),
                                        per_aircraft["callsign"])
    for column, values in per_aircraft.items():
        both[column] = pd.Series(values[codes], index=both.index, dtype=object)
    return both


def _deduplicated_rows(frame: pd.DataFrame, by: list[str]) -> np.ndarray:
    """Positions in ``frame`` of the rows ``deduplicate`` keeps of each group of ``by`` (groups in order of
    first appearance, each in time order without repeats): the rows are then taken once, not copied per
    group and joined."""
    keys = frame[[c for c in DEDUP_COLUMNS if c in frame]]
    keys = keys.assign(_row=np.arange(len(frame)))
    groups = keys.groupby([frame[c] for c in by], dropna=False, sort=False)
    rows = [deduplicate(g)[0]["_row"].to_numpy() for _, g in groups]
    return np.concatenate(rows) if rows else np.zeros(0, np.int64)


MIN_P95_INTERVALS = 20  # the fewest intervals of which one in twenty can lie above a 95th percentile


def _interval_stats(intervals_s: np.ndarray, longest_s: float = np.nan) -> dict:
    """Count, min, median, 95th percentile and maximum of the intervals within the gap rule, and
    ``interval_max_s`` the longest interval between successive reports, gaps included (``longest_s``)."""
    if intervals_s.size == 0:
        return {"intervals": 0, "interval_min_s": np.nan, "interval_median_s": np.nan,
                "interval_p95_s": np.nan, "interval_max_s": longest_s, "interval_max_within_gap_s": np.nan}
    return {"intervals": int(intervals_s.size), "interval_min_s": float(intervals_s.min()),
            "interval_median_s": float(np.median(intervals_s)),
            # withheld below MIN_P95_INTERVALS: of fewer, a "95th percentile" is the largest ones interpolated
            "interval_p95_s": (float(np.percentile(intervals_s, 95)) if intervals_s.size >= MIN_P95_INTERVALS
                               else np.nan),
            "interval_max_s": float(np.fmax(intervals_s.max(), longest_s)),
            "interval_max_within_gap_s": float(intervals_s.max())}


def _speed_stats(gs_kt: pd.Series) -> dict:
    missing, zero = int(gs_kt.isna().sum()), int((gs_kt == 0).sum())
    n = len(gs_kt)
    return {"speed_missing": missing, "speed_zero": zero, "speed_missing_or_zero": missing + zero,
            "speed_missing_or_zero_pct": 100.0 * (missing + zero) / n if n else np.nan}


def integrity_shares(adsb: pd.DataFrame) -> dict:
    """Percent of reports with nucp_nic below 5 (read as NUCp) and below 6 (read as NIC), and the low-
    integrity percent choosing by mops_version per report (NaN without versions); versions seen."""
    v = pd.to_numeric(adsb["nucp_nic"], errors="coerce") if "nucp_nic" in adsb else pd.Series(
        np.nan, index=adsb.index)
    known = v.notna()
    n = int(known.sum())
    out = {"nucp_below_5_pct": 100.0 * float((v[known] < NUCP_MIN).sum()) / n if n else np.nan,
           "nic_below_6_pct": 100.0 * float((v[known] < NIC_MIN).sum()) / n if n else np.nan,
           "low_integrity_pct": np.nan, "mops_versions": ""}
    if "mops_version" in adsb:
        mops = pd.to_numeric(adsb["mops_version"], errors="coerce")
        both = known & mops.notna()
        if both.any():
            low = np.where(mops[both] == 0, v[both] < NUCP_MIN, v[both] < NIC_MIN)
            out["low_integrity_pct"] = 100.0 * float(low.sum()) / int(both.sum())
            out["mops_versions"] = ",".join(str(int(m)) for m in sorted(mops[both].unique()))
    return out


def _group_rows(group: pd.DataFrame, gap_s: float,
                jumps_by_aircraft: pd.Series) -> tuple[dict, np.ndarray, list[dict], pd.DataFrame]:
    """Summary row, within-track intervals, gap rows and de-duplicated reports of one aircraft and sensor."""
    ident = {k: group[k].iloc[0] for k in ID_KEYS}
    clean, dups = deduplicate(group)
    t = clean["time_of_day"].to_numpy(float)
    dt = np.diff(t)
    within, gap = dt[dt <= gap_s], np.flatnonzero(dt > gap_s)
    stamps = clean["timestamp"] if "timestamp" in clean else pd.Series(pd.NaT, index=clean.index)
    stamps = dated_or_nat(stamps)
    gaps = [{**ident, "gap_start_tod": t[i], "gap_end_tod": t[i + 1],
             "gap_start_utc": stamps.iloc[i], "gap_end_utc": stamps.iloc[i + 1],
             "gap_duration_s": t[i + 1] - t[i], "reappeared_after_1h": bool(t[i + 1] - t[i] > REAPPEARANCE_S)}
            for i in gap]
    # every report may repeat another aircraft's (a damaged address copies a relayed report): no times left
    ends = (t[0], t[-1], stamps.iloc[0], stamps.iloc[-1]) if t.size else (np.nan, np.nan, pd.NaT, pd.NaT)
    row = {**ident, "on_surface": mostly_surface(on_surface(clean)), "reports": len(group),
           "duplicates_removed": dups, "reports_after_dedup": len(clean),
           **dict(zip(("first_tod", "last_tod", "first_utc", "last_utc"), ends, strict=True)),
           **_interval_stats(within, float(dt.max()) if dt.size else np.nan),
           "gaps": len(gaps),
           "longest_gap_s": float(dt[gap].max()) if gap.size else np.nan,
           "reappearances": sum(g["reappeared_after_1h"] for g in gaps),
           **_speed_stats(clean["ground_speed_kt"])}
    if ident["sensor"] == "adsb":
        row["jumps"] = int(jumps_by_aircraft.get(group["aircraft"].iloc[0], 0))
        row |= integrity_shares(clean)
    return row, within, gaps, clean


def _aircraft_groups(narrow: pd.DataFrame) -> Iterator[tuple[tuple, pd.DataFrame]]:
    """Each aircraft's reports of each sensor with its key (the sensor's number, SENSOR_KEYS, call sign,
    address, aircraft), sorted and keyed as iterating a grouping over those gives them, each taken only
    when asked for: the grouping's sorted copy of every report is never made."""
    sensor = narrow.groupby(SENSOR_KEYS, dropna=False, sort=True).ngroup().to_numpy()  # sorted as the keys
    by = narrow.groupby([sensor, *SENSOR_KEYS, "callsign", "address", "aircraft"], dropna=False, sort=True)
    ids, keys = by.ngroup().to_numpy(), by.size().index
    order = np.argsort(ids, kind="stable")  # each group's rows in frame order, as the grouping takes them
    bounds = np.searchsorted(ids[order], np.arange(len(keys) + 1))
    del by, ids, sensor
    for i, key in enumerate(keys):
        yield key, narrow.take(order[bounds[i]:bounds[i + 1]])


def _pooled_row(rows: list[dict], intervals: list[np.ndarray], sensor_id: tuple,
                clean: list[pd.DataFrame], label: str = ALL) -> dict:
    """A pooled summary row of one sensor ("(all)" or "(all surface)": ``label``) from its per-aircraft
    rows, intervals and reports."""
    frame = pd.DataFrame(rows)
    row = {"callsign": label, "address": "", **dict(zip(SENSOR_KEYS, sensor_id, strict=True)),
           "on_surface": label == SURFACE_ALL}
    for c in ("reports", "duplicates_removed", "reports_after_dedup", "gaps", "reappearances",
              "speed_missing", "speed_zero", "speed_missing_or_zero"):
        row[c] = int(frame[c].sum())
    row["first_tod"], row["last_tod"] = frame["first_tod"].min(), frame["last_tod"].max()
    row["first_utc"] = row["last_utc"] = pd.NaT
    if frame["first_tod"].notna().any():  # else no aircraft kept a report past de-duplication
        first, last = frame["first_tod"].idxmin(), frame["last_tod"].idxmax()
        row["first_utc"], row["last_utc"] = frame.loc[first, "first_utc"], frame.loc[last, "last_utc"]
    row |= _interval_stats(np.concatenate(intervals) if intervals else np.array([]),
                           frame["interval_max_s"].max())
    row["longest_gap_s"] = frame["longest_gap_s"].max()
    row["speed_missing_or_zero_pct"] = (100.0 * row["speed_missing_or_zero"] / row["reports_after_dedup"]
                                        if row["reports_after_dedup"] else np.nan)
    if sensor_id[0] == "adsb":
        row["jumps"] = int(frame["jumps"].sum())
        row |= integrity_shares(pd.concat(clean, ignore_index=True))
    row["two_targets"] = bool(frame["two_targets"].any())
    return row


def _mixed_pairs(meas: pd.DataFrame) -> tuple[tuple[str, str], ...]:
    """The (aircraft_id, sensor_id) pairs of two targets under one identity among the reports that are no
    duplicates, as the jobs find them (pipeline.jobs.common.marked_measurements)."""
    from msdc.pipeline.model.mixed import mixed_identities, mixed_pairs

    kept = ~meas["duplicate"].to_numpy(bool) if "duplicate" in meas else slice(None)
    return mixed_pairs(mixed_identities(meas[kept]))


def _indicators(adsb: pd.DataFrame) -> list[str]:
    """The ADS-B quality indicators the data carries (a column with no value counts as absent)."""
    return [c for c in ADSB_INDICATORS if c in adsb and adsb[c].notna().any()]


def _first_rows(ids: np.ndarray, n: int) -> np.ndarray:
    """Each of the ``n`` groups' first row (in ``ids``, the group of each row)."""
    first = np.full(n, -1)
    first[ids[::-1]] = np.arange(len(ids))[::-1]
    return first


def _key_groups(adsb: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, pd.DataFrame]:
    """Each report's group of ID_KEYS (its aircraft and sensor) and its sensor's pooled ("(all)") group,
    numbered as a sorted grouping over ID_KEYS orders them (equal keys: one group), and the keys of every
    group (row g: group g). The reports are grouped once; the tables work on these numbers, not on texts."""
    own = adsb.groupby(ID_KEYS, dropna=False, sort=False).ngroup().to_numpy()
    first = _first_rows(own, int(own.max()) + 1)
    keys = adsb[ID_KEYS].iloc[first]
    keys = pd.concat([keys, keys.assign(callsign=ALL, address="")], ignore_index=True)
    rank = keys.groupby(ID_KEYS, dropna=False, sort=True).ngroup().to_numpy()
    table = keys.iloc[_first_rows(rank, int(rank.max()) + 1)].reset_index(drop=True)
    return rank[own], rank[own + len(first)], table


def _adsb_value_counts(adsb: pd.DataFrame) -> pd.DataFrame:
    """Value counts of each ADS-B quality indicator present, per aircraft and pooled per ADS-B sensor
    (counted on group numbers, each report once for its aircraft and once for its sensor without copying
    the reports, then keyed, summed and sorted as one grouping over the key columns)."""
    indicators = _indicators(adsb)
    if adsb.empty or not indicators:
        return pd.DataFrame(columns=VALUE_COUNT_COLUMNS)
    own, pooled, keys = _key_groups(adsb)
    parts = []
    for c in indicators:
        value = pd.to_numeric(adsb[c], errors="coerce").astype("Int64").array
        for group in (own, pooled):  # every report counts for its aircraft and for its sensor (summed below)
            size = pd.DataFrame({"group": group, "value": value}).groupby(["group", "value"], dropna=False,
                                                                          sort=False).size()
            parts.append(size.rename("reports").reset_index().assign(indicator=c))
    part = pd.concat(parts, ignore_index=True)
    counted = keys.iloc[part["group"].to_numpy()].reset_index(drop=True).assign(
        indicator=part["indicator"], value=part["value"], reports=part["reports"])
    keys = [*ID_KEYS, "indicator"]
    counts = counted.groupby([*keys, "value"], dropna=False, sort=True)["reports"].sum().reset_index()
    totals = counts.groupby(keys, dropna=False)["reports"].transform("sum")
    counts["share_pct"] = 100.0 * counts["reports"] / totals
    return counts[VALUE_COUNT_COLUMNS]


def _adsb_over_time(adsb: pd.DataFrame) -> pd.DataFrame:
    """Median of each indicator and the integrity shares per 10-minute bin, per aircraft and pooled
    (grouped once, on group numbers and bins, aggregated column by column: a day holds thousands of bins).
    Each report counts for its aircraft's group and its sensor's; the reports are not copied for that:
    each half is numbered and aggregated on its own (integer counts add up exactly, and an aircraft's
    group is never a pooled one, whose call sign "(all)" no decoded call sign can spell; if one were, that
    group's medians would be taken over both halves together, as one group)."""
    indicators = _indicators(adsb)
    columns = [*ID_KEYS, "bin_start_tod", "bin_start_utc", "reports", *[f"{c}_median" for c in indicators],
               *SHARE_COLUMNS]
    if adsb.empty:
        return pd.DataFrame(columns=columns)
    own, pooled, keys = _key_groups(adsb)
    rows = len(adsb)
    bin_start = np.floor(adsb["time_of_day"].to_numpy(float) / QUALITY_BIN_S) * QUALITY_BIN_S
    bins, bin_code = np.unique(bin_start, return_inverse=True)  # sorted, a missing time (NaN) last
    # (group, bin) numbered in sorted order, as a sorted grouping over both columns would: an aircraft's
    # row, then its sensor's
    halves = [own * len(bins) + bin_code, pooled * len(bins) + bin_code]
    del own, pooled, bin_code
    pairs = np.unique(np.concatenate(halves))
    ids = [np.searchsorted(pairs, h) for h in halves]
    del halves
    n = len(pairs)
    first = _first_rows(np.concatenate(ids), n) % rows  # each group's first report (aircraft rows first)
    group = pairs // len(bins)
    out = {k: keys[k].to_numpy()[group] for k in ID_KEYS}
    out["bin_start_tod"] = bins[pairs % len(bins)]
    del pairs, group
    tod0 = adsb["time_of_day"].to_numpy(float)[first]
    if "timestamp" in adsb:
        start = dated_or_nat(adsb["timestamp"].iloc[first].reset_index(drop=True)) - pd.to_timedelta(
            tod0 - out["bin_start_tod"], unit="s")
        out["bin_start_utc"] = start.array
    else:
        out["bin_start_utc"] = pd.array([pd.NaT] * n, dtype=UTC_DTYPE)
    out["reports"] = sum(np.bincount(i, minlength=n) for i in ids)
    apart = np.intersect1d(ids[0], ids[1]).size == 0  # no group in both halves
    for c in indicators:
        values = pd.to_numeric(adsb[c], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        median = np.full(n, np.nan)
        if apart:
            for i in ids:
                by = pd.Series(values).groupby(i).median()
                median[by.index.to_numpy()] = by.to_numpy()
        else:
            by = pd.Series(np.concatenate([values, values])).groupby(np.concatenate(ids)).median()
            median = by.reindex(range(n)).to_numpy()
        out[f"{c}_median"] = median
    out |= _integrity_shares_by(adsb, ids, n)
    return pd.DataFrame({c: out[c] for c in columns}, columns=columns)


def _integrity_shares_by(adsb: pd.DataFrame, ids: list[np.ndarray], n: int) -> dict[str, np.ndarray]:
    """SHARE_COLUMNS of integrity_shares() for every group at once; each report of ``adsb`` counts for its
    group in each array of ``ids``."""
    v = (pd.to_numeric(adsb["nucp_nic"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
         if "nucp_nic" in adsb else np.full(len(adsb), np.nan))
    known = ~np.isnan(v)

    def pct(hit: np.ndarray, of: np.ndarray) -> np.ndarray:
        total = sum(np.bincount(i, of.astype(float), minlength=n) for i in ids)  # whole numbers: exact sums
        count = sum(np.bincount(i, (hit & of).astype(float), minlength=n) for i in ids)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > 0, 100.0 * count / total, np.nan)

    out = {"nucp_below_5_pct": pct(v < NUCP_MIN, known), "nic_below_6_pct": pct(v < NIC_MIN, known),
           "low_integrity_pct": np.full(n, np.nan)}
    if "mops_version" in adsb:
        mops = pd.to_numeric(adsb["mops_version"], errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        both = known & ~np.isnan(mops)
        out["low_integrity_pct"] = pct(np.where(mops == 0, v < NUCP_MIN, v < NIC_MIN), both)
    return out


def _as_utc(frame: pd.DataFrame, columns: list[str]) -> pd.DataFrame:
    """``frame`` with ``columns`` as datetime64[ns, UTC] (an all-NaT column is built naive)."""
    return frame.assign(**{c: pd.to_datetime(frame[c], utc=True).astype(UTC_DTYPE) for c in columns})


NO_ADSB_NOTE = ("No ADS-B (CAT021) report in the input: position jumps and quality indicators are looked "
                "for in ADS-B only.")


def quality_tables(meas: pd.DataFrame, *, gap_s: float = 180.0, jump_kw: dict | None = None,
                   mixed: Collection[tuple[str, str]] | None = None) -> dict[str, pd.DataFrame]:
    """Sheets "Quality", "Update intervals", "Gaps", "Jumps", "ADS-B quality" and "ADS-B quality over time"
    (see the module docstring) of a measurement frame holding radar and/or ADS-B. ``mixed``: the (aircraft_id,
    sensor_id) pairs of two targets under one identity when already found (None: found here)."""
    check_frame("meas", meas, ("sensor_kind", "time"))
    check_seconds("gap_s", gap_s)
    check_options("jump_kw", jump_kw)
    mixed = set(_mixed_pairs(meas) if mixed is None else mixed)
    both = _aircraft_labels(meas)
    adsb_rows = both["sensor"] == "adsb"

    by = ["aircraft", "sac", "sic"]
    at = np.flatnonzero(adsb_rows.to_numpy(bool))
    at = at[_deduplicated_rows(both[[*by, *(c for c in DEDUP_COLUMNS if c in both)]].iloc[at], by)]
    adsb = both[[c for c in both if c not in ADSB_UNREAD]].iloc[at].reset_index(drop=True)  # taken once
    no_adsb = adsb.empty
    jumps = jump_table(adsb, **(jump_kw or {}))
    jump_rows = adsb.loc[jumps["row"].to_numpy()] if len(jumps) else adsb.iloc[:0]
    jumps_by_aircraft = jump_rows["aircraft"].value_counts()
    adsb_quality, adsb_over_time = _adsb_value_counts(adsb), _adsb_over_time(adsb)
    del adsb

    summary, gaps, hist = [], [], []
    edges = histogram_edges_s(gap_s)
    needed = [*ID_KEYS, "aircraft", "time", "time_of_day", "timestamp", "ground_speed_kt", "nucp_nic",
              "mops_version", "duplicate", "sensor_kind", "sensor_id", *DEDUP_KEYS, *SURFACE_INPUTS]
    narrow = both[[c for c in dict.fromkeys(needed) if c in both]]  # the groups are copied: keep them narrow
    del both
    for _, groups in itertools.groupby(_aircraft_groups(narrow), key=lambda group: group[0][0]):  # per sensor
        rows, intervals, clean = [], [], []
        for key, g in groups:
            sensor_id = key[1:1 + len(SENSOR_KEYS)]
            row, within, g_gaps, g_clean = _group_rows(g, gap_s, jumps_by_aircraft)
            sensors = g["sensor_id"].astype(str).unique() if "sensor_id" in g else ()
            row["two_targets"] = key[-1] != UNIDENTIFIED and any((str(key[-1]), s) in mixed for s in sensors)
            if key[-1] == UNIDENTIFIED:  # reports of many targets: no interval or gap between them means much
                within, g_gaps = within[:0], []
                row |= _interval_stats(within) | {"gaps": np.nan, "longest_gap_s": np.nan, "reappearances": 0}
            rows.append(row)
            intervals.append(within)
            clean.append(g_clean[[c for c in ("nucp_nic", "mops_version") if c in g_clean]])  # for the pool
            gaps += g_gaps
        pooled = []  # the aircraft in the air, then those on the surface (pipeline.quality.surface)
        for label, surface in ((ALL, False), (SURFACE_ALL, True)):
            at = [i for i, row in enumerate(rows) if row["on_surface"] == surface]
            if at:
                pooled.append(_pooled_row([rows[i] for i in at], [intervals[i] for i in at], sensor_id,
                                          [clean[i] for i in at], label))
        summary += [*pooled, *rows]
        counts, _ = np.histogram(np.concatenate(intervals), bins=edges)
        hist.append(pd.DataFrame({**dict(zip(SENSOR_KEYS, sensor_id, strict=True)), "bin_start_s": edges[:-1],
                                  "bin_end_s": edges[1:], "intervals": counts}))

    jump_stamps = jumps["timestamp"] if len(jumps) else pd.Series([], dtype=UTC_DTYPE)
    jump_sheet = pd.DataFrame({k: jump_rows[k].to_numpy() for k in ID_KEYS} | {
        "time_of_day": jumps["time_of_day"].to_numpy(float),
        "utc": dated_or_nat(jump_stamps.reset_index(drop=True)).array,
        **{c: jumps[c].to_numpy(float) for c in ("latitude", "longitude", "fit_latitude", "fit_longitude",
                                                  "jump_size_m")}}, columns=JUMP_COLUMNS)
    quality = _as_utc(pd.DataFrame(summary, columns=QUALITY_COLUMNS).astype({"jumps": "Int64"}),
                      ["first_utc", "last_utc"])
    if no_adsb:  # an empty sheet would read as none found: nothing was looked at
        for sheet in (jump_sheet, adsb_quality, adsb_over_time):
            sheet.attrs["note"] = NO_ADSB_NOTE
    return {
        "Quality": quality,
        "Update intervals": (pd.concat(hist, ignore_index=True) if hist
                             else pd.DataFrame(columns=HISTOGRAM_COLUMNS)),
        "Gaps": _as_utc(pd.DataFrame(gaps, columns=GAP_COLUMNS), ["gap_start_utc", "gap_end_utc"]),
        "Jumps": jump_sheet,
        "ADS-B quality": adsb_quality,
        "ADS-B quality over time": adsb_over_time,
    }


def workbook_sheets(sheets: dict[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
    """The quality sheets as a workbook prints them: "Update intervals" lists only the bins that hold
    intervals (every 0.1 s bin up to the longest interval printed 18 pages on the real radar), numbered
    afresh (a kept index would print as a column); the DataFrames and the JSON keep every bin."""
    bins = sheets.get("Update intervals")
    if bins is None or "intervals" not in bins:
        return dict(sheets)
    return {**sheets, "Update intervals": bins[bins["intervals"] > 0].reset_index(drop=True)}
