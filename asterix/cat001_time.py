"""CAT001's whole time of day: its truncated I001/141 made whole from the same radar's CAT002 messages.

I001/141 is the time of day modulo 512 s (1/128 s). A radar sending CAT001 sends CAT002 north-marker and
sector-crossing messages with the whole time of day (I002/030) as its antenna turns; a plot is reported
after the sector that holds it, within an antenna rotation of the last of them. The rule:

- a record's reference is the time of day of the last CAT002 message of the same SAC/SIC before it in
  the file (any message type with an I002/030 in 0-86400 s), carried across ``iter_read`` chunks;
- its whole time is the time whose value modulo 512 s is I001/141 nearest that reference, on the
  reference's day or, across midnight, the next or the previous one (86400 s is not a multiple of 512);
- it is kept when within ``MAX_FROM_REFERENCE_S`` of the reference; further, it is undated and the
  reference goes stale: later records of that radar stay undated until its next CAT002 message.

A reference that is not refreshed (CAT002 filtered out, a radar that stopped sending them) drifts away
from the plots' times; the first record beyond the limit ends it, before a wrap of 512 s could date
records a multiple of 512 s wrong. Undated records keep NaN and are listed, with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from . import kernel
from .layout import compile_layout

PLOT_CATEGORY, SERVICE_CATEGORY = 1, 2
WINDOW_S = 512.0  # I001/141 wraps every 512 s
DAY_S = 86400.0
# A plot follows the CAT002 message before it by less than an antenna rotation (4-12 s for surveillance
# radars, 16 s at the slowest); 32 s is two of the slowest rotations, and the chance that a reference
# stale by an unknown time dates a record a multiple of 512 s wrong before it is ended is 2 * 32 / 512.
MAX_FROM_REFERENCE_S = 32.0

NO_TIME = "no I001/141 truncated time of day"
NO_SOURCE = "no I001/010 SAC/SIC: its radar's CAT002 messages cannot be told"
NO_REFERENCE = "no CAT002 time of day (I002/030) of its radar before it"
TOO_FAR = f"more than {MAX_FROM_REFERENCE_S:g} s from its radar's last CAT002 time of day"
STALE = (f"its radar's last CAT002 time of day went stale (a record before it was more than "
         f"{MAX_FROM_REFERENCE_S:g} s from it)")
UNTIMED_COLUMNS = ["offset", "category", "sac", "sic", "reason"]


@dataclass
class SectorClock:
    """Each radar's (SAC * 256 + SIC) last CAT002 time of day and whether it still dates records, carried
    from one chunk to the next by ``iter_read`` so that chunks date records as one ``read`` does."""

    last: dict[int, tuple[float, bool]] = field(default_factory=dict)


def whole_time(truncated_s: np.ndarray, reference_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The time of day (0-86400 s) whose value modulo 512 s is ``truncated_s`` nearest ``reference_s``,
    on the reference's day or the day after or before it, and its signed distance from the reference."""
    tau = np.asarray(truncated_s, float)
    ref = np.asarray(reference_s, float)
    k_max = np.ceil((DAY_S - tau) / WINDOW_S) - 1  # the last window of a day: tau + 512 k < 86400
    best_tod = np.full(np.broadcast(tau, ref).shape, np.nan)
    best_d = np.full(best_tod.shape, np.inf)
    for day in (0.0, DAY_S, -DAY_S):
        k = np.clip(np.rint((ref - day - tau) / WINDOW_S), 0, k_max)
        tod = tau + WINDOW_S * k
        d = tod + day - ref
        better = np.abs(d) < np.abs(best_d)
        best_tod = np.where(better, tod, best_tod)
        best_d = np.where(better, d, best_d)
    return best_tod, best_d


def _keys(sac, sic) -> np.ndarray:
    """SAC * 256 + SIC, -1 where either is absent."""
    a = pd.array(sac, dtype="Int32").to_numpy(dtype=np.int64, na_value=-1)
    b = pd.array(sic, dtype="Int32").to_numpy(dtype=np.int64, na_value=-1)
    return np.where((a >= 0) & (b >= 0), a * 256 + b, -1)


def date_records(offset: np.ndarray, key: np.ndarray, truncated_s: np.ndarray, ref_offset: np.ndarray,
                 ref_key: np.ndarray, ref_tod_s: np.ndarray, clock: SectorClock
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Whole times of day of CAT001 records (NaN where undated) and the reason of each undated one ("" for
    the dated), from the CAT002 times of the same data (``ref_*``) and those ``clock`` carries from before
    it; ``clock`` is updated with each radar's last reference."""
    offset, key = np.asarray(offset, np.int64), np.asarray(key, np.int64)
    truncated_s = np.asarray(truncated_s, float)
    good = (ref_key >= 0) & (ref_tod_s >= 0) & (ref_tod_s < DAY_S)
    # references: a sentinel of no radar (key -2: the arrays are never empty), the carried ones (offset
    # -1: before the data), and those of the data
    carried = np.array(sorted(clock.last), np.int64)
    r_key = np.concatenate([[-2], carried, np.asarray(ref_key, np.int64)[good]]).astype(np.int64)
    r_off = np.concatenate([np.full(len(carried) + 1, -1, np.int64), np.asarray(ref_offset, np.int64)[good]])
    r_tod = np.concatenate([[np.nan], [clock.last[k][0] for k in carried],
                            np.asarray(ref_tod_s, float)[good]])
    r_live = np.concatenate([[False], [clock.last[k][1] for k in carried], np.ones(good.sum(), bool)]
                            ).astype(bool)
    order = np.lexsort((r_off, r_key))
    r_key, r_off, r_tod, r_live = r_key[order], r_off[order], r_tod[order], r_live[order]
    r_comp = (r_key << 41) | (r_off + 1)  # offsets below 2^40; ordering by radar, then file order

    n = len(offset)
    ref = np.searchsorted(r_comp, (key << 41) | (offset + 1)) - 1
    has_ref = (key >= 0) & (ref >= 0) & (r_key[np.maximum(ref, 0)] == key)
    ref = np.where(has_ref, ref, -1)
    has_time = np.isfinite(truncated_s)
    use = has_ref & has_time
    tod, d = whole_time(np.where(use, truncated_s, 0.0), np.where(use, r_tod[np.maximum(ref, 0)], 0.0))
    near = use & (np.abs(d) <= MAX_FROM_REFERENCE_S)
    # a reference goes stale at its first record beyond the limit: count those before each record
    far = (use & ~near).astype(np.int64)
    seq = np.lexsort((offset, ref))
    run = ref[seq]
    cum = np.cumsum(far[seq]) - far[seq]  # far records before each, in (reference, file) order
    start = np.r_[True, run[1:] != run[:-1]] if n else np.zeros(0, bool)
    first = np.maximum.accumulate(np.where(start, np.arange(n), 0)) if n else np.zeros(0, np.int64)
    before = np.empty(n, np.int64)
    before[seq] = cum - cum[first]
    stale = use & ((before > 0) | ~r_live[np.maximum(ref, 0)])
    dated = near & ~stale
    reason = np.full(n, "", dtype=object)
    reason[~dated & use] = TOO_FAR
    reason[stale] = STALE
    reason[has_time & ~has_ref] = NO_REFERENCE
    reason[has_time & (key < 0)] = NO_SOURCE
    reason[~has_time] = NO_TIME
    # each radar's last reference, and whether a record beyond the limit ended it
    fars = np.bincount(ref[ref >= 0], weights=far[ref >= 0], minlength=len(r_key))
    for j in np.flatnonzero(np.r_[r_key[1:] != r_key[:-1], True] & (r_key >= 0)):
        clock.last[int(r_key[j])] = (float(r_tod[j]), bool(r_live[j] and fars[j] == 0))
    return np.where(dated, tod, np.nan), reason


def _service_times(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, edition: str | None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets, radar keys and times of day of the CAT002 records in these blocks (those that walk), when
    CAT002 is not decoded itself: CAT001 needs them all the same."""
    lay = compile_layout(SERVICE_CATEGORY, edition, ("time_of_day",))
    cap = int(lens.sum()) // 2 + 1  # a record is at least 2 bytes (an FSPEC and a one-byte item)
    slots = max(lay.n_slots, 1)
    rel_off = np.full((cap, slots), 0xFFFF, np.uint16)
    rel_len = np.zeros((cap, slots), np.uint16)
    rec_off, rec_blk = np.empty(cap, np.int64), np.empty(cap, np.int64)
    n = kernel.scan(buf, starts, lens, lay.parts, lay.n_frn, lay.n_slots, rel_off, rel_len, rec_off,
                    rec_blk)[2]
    assert n >= 0, "record arrays sized for the smallest records"
    fl = np.full((len(lay.out_names_float), n), np.nan)
    it = np.full((len(lay.out_names_int), n), -1, np.int32)
    wd = np.full((len(lay.out_names_wide), n), -1, np.int64)
    kernel.gather(buf, rec_off[:n], rel_off[:n], rel_len[:n], lay.F, lay.f_mult, fl, it, wd)
    sac, sic = it[lay.out_names_int.index("sac")], it[lay.out_names_int.index("sic")]
    key = np.where((sac >= 0) & (sic >= 0), sac.astype(np.int64) * 256 + sic, -1)
    return rec_off[:n].copy(), key, fl[lay.out_names_float.index("time_of_day")]


def time_cat001(columns: dict[int, dict], buf: np.ndarray, framed, editions: dict,
                clock: SectorClock) -> pd.DataFrame:
    """Fill CAT001's ``time_of_day`` (decoded columns by category, as the reader builds them) from the
    CAT002 records of the framed blocks, decoded or not; return the undated records (UNTIMED_COLUMNS)."""
    if SERVICE_CATEGORY in columns:
        f = columns[SERVICE_CATEGORY]
        r_off, r_key, r_tod = f["offset"], _keys(f["sac"], f["sic"]), np.asarray(f["time_of_day"], float)
    else:
        b_start, b_len, b_cat = framed[:3]
        sel = b_cat == SERVICE_CATEGORY
        r_off, r_key, r_tod = _service_times(buf, b_start[sel], b_len[sel], editions.get(SERVICE_CATEGORY))
    plots = columns.get(PLOT_CATEGORY)
    if plots is None:
        date_records(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), r_off, r_key, r_tod, clock)
        return pd.DataFrame(columns=UNTIMED_COLUMNS)
    key = _keys(plots["sac"], plots["sic"])
    tod, reason = date_records(plots["offset"], key, np.asarray(plots["truncated_time_of_day"], float),
                               r_off, r_key, r_tod, clock)
    plots["time_of_day"] = tod
    bad = np.flatnonzero(reason != "")
    return pd.DataFrame({"offset": np.asarray(plots["offset"], np.int64)[bad],
                         "category": np.full(len(bad), PLOT_CATEGORY, np.int64),
                         "sac": pd.array(plots["sac"], dtype="Int32")[bad],
                         "sic": pd.array(plots["sic"], dtype="Int32")[bad],
                         "reason": reason[bad]}, columns=UNTIMED_COLUMNS)


def untimed_advice(path: str, untimed: pd.DataFrame) -> list[str]:
    """One line per reason: how many CAT001 records have no time of day, and the first offsets."""
    out = []
    for why, g in untimed.groupby("reason", sort=False):
        first = ", ".join(str(int(o)) for o in g["offset"].iloc[:3])
        out.append(f"{path}: {len(g)} CAT001 record(s) have no time of day: {why} (offsets {first}"
                   f"{', ...' if len(g) > 3 else ''}; Recording.untimed lists them)")
    return out
