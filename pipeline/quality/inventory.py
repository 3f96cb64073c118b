"""What a recording holds: records per category and SAC/SIC, time spans, aircraft per sensor, skipped blocks.

Times are UTC date-times when the recording's date is known (timestamps present), HH:MM:SS otherwise
(``+Nd`` past the first day); never seconds of day. ``StatsAccumulator`` folds the tables chunk by chunk
(``asterix.iter_read``), so memory is bounded by the chunk size, not the file; ``stats_tables`` is the
same fold over one whole decoded recording.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd

from msdc.pipeline.model.sources import file_labels, path_text
from msdc.pipeline.model.time import clock

# "(record at offset 1234)", "at offset 0x1f": the place, not the reason; "(LEN 40, 36 bytes past the
# end)": a bad data block LEN's numbers; "(capture time 1989-04-23 02:22:56)": a damaged capture time's value
_OFFSET = re.compile(r"\s*\((?:record )?at offset (?:0x[0-9a-fA-F]+|\d+)\)"
                     r"|\s*\bat offset (?:0x[0-9a-fA-F]+|\d+)"
                     r"|\s*\(LEN \d+(?:, \d+ bytes? past the end)?\)"
                     r"|\s*\(capture time [^()]*\)")

NO_IDENTITY = "(none)"  # the aircraft table's address for records with neither address nor call sign
NONE_KEY = "~"  # their aircraft key: text (a chunk of them alone merges with others), sorted after the rest
STATS_COLUMNS = ("address", "callsign")  # decoded columns the tables need besides SAC/SIC and times
# The groupings of the tables: key columns, and whether rows with a missing key are left out
_LEVELS = {"categories": ["category"], "sources": ["category", "sac", "sic"],
           "aircraft": ["category", "sac", "sic", "key"]}  # aircraft: rows without SAC/SIC or key left out
_SPAN = ["t_min", "stamp_min", "t_max", "stamp_max"]
_SKIPPED = ["file", "category", "reason", "blocks", "bytes", "first_offset"]


def reason_kind(reason: str) -> str:
    """A skipped block's reason without the offset or LEN numbers embedded in it, so equal reasons group
    together."""
    return _OFFSET.sub("", str(reason)).strip()


def _span_text(t_min: float, stamp_min, t_max: float, stamp_max) -> tuple[str, str, float]:
    """Start and end as text (UTC date-time when both timestamps are known, else HH:MM:SS), duration (s)."""
    if not np.isfinite(t_min):
        return "-", "-", float("nan")
    duration = float(t_max - t_min)
    if pd.notna(stamp_min) and pd.notna(stamp_max):
        fmt = "%Y-%m-%d %H:%M:%S"
        end_text = stamp_max.strftime("%H:%M:%S" if stamp_max.date() == stamp_min.date() else fmt)
        return stamp_min.strftime(fmt), end_text, duration
    return clock(t_min), clock(t_max), duration


def _codes(column: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """Integer codes (-1 where missing) and the labels of a text column (categorical or not)."""
    if isinstance(column.dtype, pd.CategoricalDtype):
        return column.cat.codes.to_numpy(np.int64), np.asarray(column.cat.categories, object)
    codes, labels = pd.factorize(column.astype(object))
    return codes.astype(np.int64), np.asarray(labels, object)


def _first_rows(ids: np.ndarray, n_groups: int, rows: np.ndarray) -> np.ndarray:
    """For each group, the first of ``rows`` (ascending row numbers) that belongs to it; -1 if none."""
    out = np.full(n_groups, -1, np.int64)
    found, first = np.unique(ids[rows], return_index=True)
    out[found] = rows[first]
    return out


def _group_spans(stamps, t: np.ndarray, ids: np.ndarray, n_groups: int, keys: dict) -> pd.DataFrame:
    """Records and the first earliest / first latest record (as a whole-file argmin/argmax finds them)
    per group of one frame; ``ids`` numbers the groups (-1: left out), ``keys`` gives their key columns."""
    finite = np.flatnonzero((ids >= 0) & np.isfinite(t))
    t_min, t_max = np.full(n_groups, np.inf), np.full(n_groups, -np.inf)
    np.minimum.at(t_min, ids[finite], t[finite])
    np.maximum.at(t_max, ids[finite], t[finite])
    at_min = _first_rows(ids, n_groups, finite[t[finite] == t_min[ids[finite]]])
    at_max = _first_rows(ids, n_groups, finite[t[finite] == t_max[ids[finite]]])
    out = pd.DataFrame(keys)
    out["records"] = np.bincount(ids[ids >= 0], minlength=n_groups)
    out["t_min"] = np.where(at_min >= 0, t_min, np.nan)
    out["stamp_min"] = stamps.take(at_min, allow_fill=True)
    out["t_max"] = np.where(at_max >= 0, t_max, np.nan)
    out["stamp_max"] = stamps.take(at_max, allow_fill=True)
    return out


def _chunk_tables(cat: int, frame: pd.DataFrame) -> dict[str, tuple[pd.DataFrame, dict[str, pd.DataFrame]]]:
    """One decoded frame's partial tables per level: spans per group, and the distinct addresses and call
    signs per group. Grouping works on integer codes, so a chunk of millions of records stays cheap."""
    n = len(frame)
    t = frame["day"].to_numpy(dtype=float, na_value=np.nan) * 86400.0
    t = t + frame["time_of_day"].to_numpy(dtype=float, na_value=np.nan)
    stamps = (frame["timestamp"].array if "timestamp" in frame.columns
              else pd.array(np.full(n, np.datetime64("NaT", "ns"))).tz_localize("UTC"))
    addr, addr_labels = _codes(_identity(frame, "address"))
    cs, cs_labels = _codes(_identity(frame, "callsign"))
    sac = frame["sac"].to_numpy(np.int64, na_value=-1)
    sic = frame["sic"].to_numpy(np.int64, na_value=-1)
    # the aircraft key: its address, else its call sign (numbered after the addresses), else NO_IDENTITY
    # (numbered last: the records of no aircraft, one row per sensor, so that the table accounts for all)
    none = len(addr_labels) + len(cs_labels)
    key = np.where(addr >= 0, addr, np.where(cs >= 0, len(addr_labels) + cs, none))
    key_labels = np.array([*addr_labels, *("cs:" + str(c) for c in cs_labels), NONE_KEY], object)
    source = (sac + 1) * (1 << 32) + (sic + 1)  # every SAC/SIC pair, a missing one (-1) included
    aircraft = np.where((sac >= 0) & (sic >= 0), source * (len(key_labels) + 1) + key, -1)
    out = {}
    levels = [("categories", np.zeros(n, np.int64)), ("sources", source)]
    if "address" in frame.columns or "callsign" in frame.columns:  # status messages name no aircraft
        levels.append(("aircraft", aircraft))
    for level, combined in levels:
        keep = np.flatnonzero(combined >= 0)
        ids = np.full(n, -1, np.int64)
        ids[keep], uniques = pd.factorize(combined[keep])
        groups = len(uniques)
        first = _first_rows(ids, groups, keep)
        keys: dict[str, object] = {"category": np.full(groups, cat, np.int64)}
        if level != "categories":
            keys["sac"], keys["sic"] = frame["sac"].array.take(first), frame["sic"].array.take(first)
        if level == "aircraft":
            keys["key"] = key_labels[key[first]]
        distinct = {}
        for value, codes, labels in (("address", addr, addr_labels), ("callsign", cs, cs_labels)):
            rows = keep[codes[keep] >= 0]
            group, code = np.divmod(np.unique(ids[rows] * (len(labels) + 1) + codes[rows]), len(labels) + 1)
            found = pd.DataFrame({k: v.take(group) for k, v in keys.items()})
            found[value] = labels[code]
            distinct[value] = found
        out[level] = (_group_spans(stamps, t, ids, groups, keys), distinct)
    return out


def _identity(frame: pd.DataFrame, name: str) -> pd.Series:
    """An identity column (address, callsign), or an all-missing one for a category without it."""
    if name in frame.columns:
        return frame[name]
    empty = pd.Index([], dtype=object)
    return pd.Series(pd.Categorical.from_codes(np.full(len(frame), -1), categories=empty))


def _extremes(rows: pd.DataFrame, keys: list[str], how: str) -> pd.DataFrame:
    """Per group, the first row (in row order) with the smallest (``how="min"``) or largest finite time,
    with its timestamp."""
    t, stamp = f"t_{how}", f"stamp_{how}"
    finite = rows[np.isfinite(rows[t].to_numpy(float))]
    grouped = finite.groupby(keys, dropna=False, sort=False)[t]
    at = grouped.idxmin() if how == "min" else grouped.idxmax()
    return finite.loc[at.to_numpy(), [*keys, t, stamp]]


def _fold(rows: pd.DataFrame, keys: list[str]) -> pd.DataFrame:
    """Partial spans of successive chunks (earlier chunks first) folded into one row per group."""
    counts = rows.groupby(keys, dropna=False, sort=False)["records"].sum().reset_index()
    return (counts.merge(_extremes(rows, keys, "min"), on=keys, how="left")
            .merge(_extremes(rows, keys, "max"), on=keys, how="left"))


class StatsAccumulator:
    """The stats tables folded chunk by chunk: per group only the record count, the earliest and latest
    record and the distinct addresses and call signs are kept, so memory does not grow with the file."""

    def __init__(self) -> None:
        self.categories: set[int] = set()
        self._spans: dict[str, pd.DataFrame] = {}
        self._distinct: dict[tuple[str, str], pd.DataFrame] = {}
        self._skipped: pd.DataFrame | None = None
        self._files: dict[str, int] = {}  # files with skipped blocks, in the order met
        self._other: pd.DataFrame | None = None
        self._blocks: dict[int, int] = {}  # data blocks whose records decoded, per category
        self._identity: dict[int, set[str]] = {}  # the identity columns (address, callsign) per category

    def add(self, frames: dict[int, pd.DataFrame], errors: pd.DataFrame | None = None,
            ignored: pd.DataFrame | list[pd.DataFrame] | None = None) -> None:
        """Fold in one chunk: decoded frames by category, its skipped-bytes account, its ignored blocks."""
        self.categories |= {cat for cat, frame in frames.items() if len(frame)}  # no record: not listed
        for cat, frame in sorted(frames.items()):
            if len(frame):  # a chunk holds whole blocks: their numbers are distinct from other chunks'
                self._blocks[cat] = self._blocks.get(cat, 0) + int(frame["block"].nunique())
                self._identity.setdefault(cat, set()).update(c for c in ("address", "callsign") if c in frame)
            for level, (new, distinct) in _chunk_tables(cat, frame).items():
                old = self._spans.get(level)
                self._spans[level] = new if old is None else _fold(pd.concat([old, new], ignore_index=True),
                                                                   _LEVELS[level])
                for value, seen in distinct.items():
                    prev = self._distinct.get((level, value))
                    if prev is not None:
                        seen = pd.concat([prev, seen], ignore_index=True).drop_duplicates(ignore_index=True)
                    self._distinct[(level, value)] = seen
        if errors is not None and len(errors):
            kinds = errors.assign(reason=errors["reason"].map(reason_kind),
                                  file=errors["file"].map(path_text).astype(str) if "file" in errors else "")
            for name in kinds["file"].unique():  # input order, for the rows of one reason
                self._files.setdefault(name, len(self._files))
            new = (kinds.groupby(["file", "category", "reason"], dropna=False)
                   .agg(blocks=("offset", "size"), bytes=("length", "sum"), first_offset=("offset", "min"))
                   .reset_index())
            if self._skipped is not None:
                new = (pd.concat([self._skipped, new], ignore_index=True)
                       .groupby(["file", "category", "reason"], dropna=False)
                       .agg(blocks=("blocks", "sum"), bytes=("bytes", "sum"),
                            first_offset=("first_offset", "min")).reset_index())
            self._skipped = new
        other = [f for f in (ignored if isinstance(ignored, list) else [ignored]) if f is not None and len(f)]
        if other:
            if self._other is not None:
                other.insert(0, self._other)
            self._other = pd.concat(other).groupby("category", as_index=False)[["blocks", "bytes"]].sum()

    def merge(self, other: StatsAccumulator) -> None:
        """Fold in another accumulator's records (a dataset partition's: pipeline.dataset.partition_stats);
        its block counts are added as they are (a caller whose parts may share a block sets ``blocks``)."""
        self.categories |= other.categories
        for level, new in other._spans.items():
            old = self._spans.get(level)
            self._spans[level] = new if old is None else _fold(pd.concat([old, new], ignore_index=True),
                                                               _LEVELS[level])
        for key, seen in other._distinct.items():
            prev = self._distinct.get(key)
            self._distinct[key] = seen if prev is None else pd.concat(
                [prev, seen], ignore_index=True).drop_duplicates(ignore_index=True)
        for cat, n in other._blocks.items():
            self._blocks[cat] = self._blocks.get(cat, 0) + n
        for cat, names in other._identity.items():
            self._identity.setdefault(cat, set()).update(names)

    def set_blocks(self, blocks: dict[int, int]) -> None:
        """The data blocks per category, counted by the caller (distinct over a dataset's partitions)."""
        self._blocks = dict(blocks)

    def _table(self, level: str) -> pd.DataFrame:
        """A level's groups in key order (missing keys last), with their distinct addresses and call signs:
        counted, or for aircraft the call signs (stripped) listed."""
        keys = _LEVELS[level]
        spans = self._spans[level].sort_values(keys, na_position="last", kind="stable", ignore_index=True)
        for value in ("address", "callsign"):
            seen = self._distinct[(level, value)]
            if level == "aircraft":
                text = seen.assign(**{value: seen[value].map(lambda c: str(c).strip())}).drop_duplicates()
                found = text.groupby(keys, dropna=False, sort=False)[value].agg(
                    lambda v: ", ".join(sorted(v)))
            else:
                found = seen.groupby(keys, dropna=False, sort=False)[value].nunique()
            spans = spans.merge(found.rename(f"seen_{value}").reset_index(), on=keys, how="left")
        return spans

    def _seen(self, cat: int, value: str, count) -> object:
        """A distinct count of addresses or call signs, <NA> for a category without that column."""
        return _count(count) if value in self._identity.get(cat, ()) else pd.NA

    def tables(self) -> dict[str, pd.DataFrame]:
        """Tables: per category (every one present: those not decoded with their blocks, and said so), per
        category and SAC/SIC, aircraft per sensor, skipped blocks by reason, and blocks of categories not
        decoded."""
        per_cat, per_src, aircraft = [], [], []
        other = self._other if self._other is not None else pd.DataFrame(columns=["category", "blocks",
                                                                                   "bytes"])
        if self._spans:
            cats = self._table("categories").set_index("category")
            for cat in sorted(self.categories):
                r = cats.loc[cat]
                start, end, duration = _span_text(r.t_min, r.stamp_min, r.t_max, r.stamp_max)
                per_cat.append({"category": cat, "decoded": "yes", "blocks": self._blocks.get(cat, 0),
                                "records": int(r.records), "start": start, "end": end,
                                "duration_min": round(duration / 60.0, 1),
                                "addresses": self._seen(cat, "address", r.seen_address),
                                "callsigns": self._seen(cat, "callsign", r.seen_callsign)})
            for r in self._table("sources").itertuples(index=False):
                start, end, _ = _span_text(r.t_min, r.stamp_min, r.t_max, r.stamp_max)
                per_src.append({"category": r.category, "sac": r.sac, "sic": r.sic, "records": int(r.records),
                                "start": start, "end": end,
                                "addresses": self._seen(r.category, "address", r.seen_address),
                                "callsigns": self._seen(r.category, "callsign", r.seen_callsign)})
        # categories whose blocks were stepped over: the blocks framing counted, no record walked
        for r in other.itertuples(index=False):
            if int(r.category) not in self.categories:
                per_cat.append({"category": int(r.category), "decoded": "no", "blocks": int(r.blocks),
                                "records": pd.NA, "start": "-", "end": "-", "duration_min": float("nan"),
                                "addresses": pd.NA, "callsigns": pd.NA})
        per_cat.sort(key=lambda row: row["category"])
        if "aircraft" in self._spans:
            for r in self._table("aircraft").itertuples(index=False):
                start, end, duration = _span_text(r.t_min, r.stamp_min, r.t_max, r.stamp_max)
                callsigns = r.seen_callsign if isinstance(r.seen_callsign, str) and r.seen_callsign else "-"
                address = NO_IDENTITY if r.key == NONE_KEY else "-" if r.key.startswith("cs:") else r.key
                aircraft.append({"category": r.category, "sac": r.sac, "sic": r.sic, "address": address,
                                 "callsign": callsigns,
                                 "records": int(r.records), "start": start, "end": end,
                                 "duration_min": round(duration / 60.0, 1)})
        if self._skipped is not None:
            skipped = _by_reason(self._skipped, self._files)
        else:
            skipped = pd.DataFrame(columns=_SKIPPED)
        return {"categories": _integers(pd.DataFrame(per_cat), ["records", "addresses", "callsigns"]),
                "sources": _integers(pd.DataFrame(per_src), ["addresses", "callsigns"]),
                "aircraft": pd.DataFrame(aircraft), "skipped": skipped, "other": other}


def _by_reason(skipped: pd.DataFrame, files: dict[str, int]) -> pd.DataFrame:
    """The skipped blocks per file, category and reason, grouped by reason: the reasons with the most
    blocks over every file first (then the earliest), each reason's files in input order; a file shown by
    its name, or by its path where two inputs share a name."""
    key = ["category", "reason"]
    groups = skipped.groupby(key, dropna=False)
    order = pd.DataFrame({"total": -groups["blocks"].transform("sum"),
                          "first": groups["first_offset"].transform("min"),
                          "category": skipped["category"], "reason": skipped["reason"],
                          "file": skipped["file"].map(files)})
    skipped = skipped.loc[order.sort_values(["total", "first", "category", "reason", "file"],
                                            kind="stable").index]
    labels = dict(zip(files, file_labels(list(files)), strict=True))
    skipped = skipped.assign(file=skipped["file"].map(labels))
    return skipped[_SKIPPED].reset_index(drop=True)


def _integers(table: pd.DataFrame, columns: list[str]) -> pd.DataFrame:
    """The count columns as nullable integers (<NA>: not decoded, or a category without that column)."""
    for name in columns:
        if name in table:
            table[name] = pd.array(table[name].tolist(), dtype="Int64")
    return table


def _count(value) -> int:
    """A distinct count from a left merge: NaN (no value seen) is 0."""
    return 0 if pd.isna(value) else int(value)


def stats_tables(frames: dict[int, pd.DataFrame], errors: pd.DataFrame,
                 ignored: pd.DataFrame | list[pd.DataFrame] | None = None) -> dict[str, pd.DataFrame]:
    """Tables of whole decoded frames (one chunk of ``StatsAccumulator``): per category, per category and
    SAC/SIC, aircraft per sensor, skipped blocks by reason, and blocks of categories not decoded
    (``Recording.ignored``, one frame or one per input)."""
    acc = StatsAccumulator()
    acc.add(frames, errors, ignored)
    return acc.tables()


def format_stats(tables: dict[str, pd.DataFrame]) -> str:
    """The tables as plain text for the terminal."""
    parts = []
    for title, key in (("Records per category", "categories"), ("Records per SAC/SIC", "sources"),
                       ("Aircraft per sensor (address, call signs, time span)", "aircraft"),
                       ("Skipped blocks by reason", "skipped"),
                       ("Blocks of categories not decoded", "other")):
        if key not in tables:
            continue
        t = tables[key]
        if "category" in t:  # bytes that name no category (garbage) show '-', not <NA>
            t = t.assign(category=t["category"].astype(object).where(t["category"].notna(), "-"))
        if key in ("categories", "sources"):  # what a category not decoded, or without the column, lacks
            t = t.assign(**{c: t[c].astype(object).where(t[c].notna(), "-")
                            for c in ("records", "duration_min", "addresses", "callsigns") if c in t})
        # ASTERIX times are UTC, dated or not (HH:MM:SS is the UTC time of day)
        t = t.rename(columns={"start": "start (UTC)", "end": "end (UTC)"})
        parts.append(f"{title}:\n" + ("  none" if t.empty else t.to_string(index=False)))
    return "\n\n".join(parts) + "\n"
