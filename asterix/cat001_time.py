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
from numba import njit

from . import kernel
from .layout import compile_layout

PLOT_CATEGORY, SERVICE_CATEGORY = 1, 2
WINDOW_S = 512.0  # I001/141 wraps every 512 s
DAY_S = 86400.0
# A plot follows the CAT002 message before it by less than an antenna rotation (4-12 s for surveillance
# radars, 16 s at the slowest); 32 s is two of the slowest rotations, and the chance that a reference
# stale by an unknown time dates a record a multiple of 512 s wrong before it is ended is 2 * 32 / 512.
MAX_FROM_REFERENCE_S = 32.0

# Why a record stays undated: codes of the walk, and their text in Recording.untimed
DATED, C_NO_TIME, C_NO_SOURCE, C_NO_REFERENCE, C_STALE, C_TOO_FAR = range(6)
NO_TIME = "no I001/141 truncated time of day"
NO_SOURCE = "no I001/010 SAC/SIC: its radar's CAT002 messages cannot be told"
NO_REFERENCE = "no CAT002 time of day (I002/030) of its radar before it"
TOO_FAR = f"more than {MAX_FROM_REFERENCE_S:g} s from its radar's last CAT002 time of day"
STALE = (f"its radar's last CAT002 time of day went stale (a record before it was more than "
         f"{MAX_FROM_REFERENCE_S:g} s from it)")
REASONS = {C_NO_TIME: NO_TIME, C_NO_SOURCE: NO_SOURCE, C_NO_REFERENCE: NO_REFERENCE, C_STALE: STALE,
           C_TOO_FAR: TOO_FAR}
UNTIMED_COLUMNS = ["offset", "category", "sac", "sic", "reason"]
N_RADARS = 1 << 16  # SAC * 256 + SIC


@dataclass
class SectorClock:
    """Each radar's (SAC * 256 + SIC) last CAT002 time of day (NaN: none yet) and whether it still dates
    records, carried from one chunk to the next by ``iter_read`` so that chunks date records as one
    ``read`` does."""

    tod_s: np.ndarray = field(default_factory=lambda: np.full(N_RADARS, np.nan))
    live: np.ndarray = field(default_factory=lambda: np.zeros(N_RADARS, np.uint8))


@njit(cache=True, nogil=True)
def _whole(tau: float, ref: float) -> tuple[float, float]:
    """One record's whole time of day and its signed distance from the reference (see whole_time)."""
    k_max = np.ceil((DAY_S - tau) / WINDOW_S) - 1  # the day's last window: tau + 512 k < 86400
    best_tod, best_d = np.nan, np.inf
    for day in (0.0, DAY_S, -DAY_S):
        k = min(max(np.rint((ref - day - tau) / WINDOW_S), 0.0), k_max)
        tod = tau + WINDOW_S * k
        d = tod + day - ref
        if abs(d) < abs(best_d):
            best_tod, best_d = tod, d
    return best_tod, best_d


@njit(cache=True, nogil=True)
def _whole_many(tau, ref, tod, d):
    for i in range(tau.shape[0]):
        tod[i], d[i] = _whole(tau[i], ref[i])


def whole_time(truncated_s: np.ndarray, reference_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The time of day (0-86400 s) whose value modulo 512 s is ``truncated_s`` nearest ``reference_s``,
    on the reference's day or the day after or before it, and its signed distance from the reference."""
    tau, ref = np.broadcast_arrays(np.asarray(truncated_s, float), np.asarray(reference_s, float))
    tod, d = np.empty(tau.shape), np.empty(tau.shape)
    _whole_many(np.ascontiguousarray(tau).ravel(), np.ascontiguousarray(ref).ravel(), tod.ravel(), d.ravel())
    return tod, d


@njit(cache=True, nogil=True)
def _date(offset, key, truncated, r_offset, r_key, r_tod, clock_tod, clock_live, limit, tod, code):
    """Walk the records and the references in file order (both come sorted by offset), dating each record
    from its radar's last reference (clock_*, updated in place); fill tod and code."""
    j = 0
    n_ref = r_offset.shape[0]
    for i in range(offset.shape[0]):
        while j < n_ref and r_offset[j] < offset[i]:
            k = r_key[j]
            if k >= 0 and 0.0 <= r_tod[j] < DAY_S:
                clock_tod[k] = r_tod[j]
                clock_live[k] = 1
            j += 1
        k = key[i]
        tod[i] = np.nan
        if np.isnan(truncated[i]):
            code[i] = C_NO_TIME
        elif k < 0:
            code[i] = C_NO_SOURCE
        elif np.isnan(clock_tod[k]):
            code[i] = C_NO_REFERENCE
        elif clock_live[k] == 0:
            code[i] = C_STALE
        else:
            t, d = _whole(truncated[i], clock_tod[k])
            if abs(d) <= limit:
                tod[i] = t
                code[i] = DATED
            else:
                code[i] = C_TOO_FAR
                clock_live[k] = 0  # stale until the radar's next CAT002 message
    while j < n_ref:
        k = r_key[j]
        if k >= 0 and 0.0 <= r_tod[j] < DAY_S:
            clock_tod[k] = r_tod[j]
            clock_live[k] = 1
        j += 1


def _keys(sac, sic) -> np.ndarray:
    """SAC * 256 + SIC, -1 where either is absent."""
    a = pd.array(sac, dtype="Int32").to_numpy(dtype=np.int64, na_value=-1)
    b = pd.array(sic, dtype="Int32").to_numpy(dtype=np.int64, na_value=-1)
    return np.where((a >= 0) & (b >= 0), a * 256 + b, -1)


def _in_file_order(offset: np.ndarray, *columns: np.ndarray) -> list[np.ndarray]:
    """The arrays sorted by offset (frames already are: then as they are)."""
    offset = np.ascontiguousarray(offset, np.int64)
    if len(offset) > 1 and not (np.diff(offset) > 0).all():
        order = np.argsort(offset, kind="stable")
        return [offset[order], *(np.ascontiguousarray(c)[order] for c in columns)]
    return [offset, *(np.ascontiguousarray(c) for c in columns)]


def date_records(offset: np.ndarray, key: np.ndarray, truncated_s: np.ndarray, ref_offset: np.ndarray,
                 ref_key: np.ndarray, ref_tod_s: np.ndarray, clock: SectorClock
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Whole times of day of CAT001 records (NaN where undated) and the code of each (DATED or why not),
    from the CAT002 times of the same data (``ref_*``) and those ``clock`` carries from before it;
    ``clock`` is updated with each radar's last reference."""
    offset = np.asarray(offset, np.int64)
    order = np.argsort(offset, kind="stable") if len(offset) > 1 and not (np.diff(offset) > 0).all() else None
    p = [offset, np.asarray(key, np.int64), np.asarray(truncated_s, float)]
    if order is not None:
        p = [a[order] for a in p]
    r_off, r_key, r_tod = _in_file_order(np.asarray(ref_offset, np.int64), np.asarray(ref_key, np.int64),
                                         np.asarray(ref_tod_s, float))
    tod, code = np.empty(len(offset)), np.empty(len(offset), np.int8)
    _date(*(np.ascontiguousarray(a) for a in p), r_off, r_key, r_tod, clock.tod_s, clock.live,
          MAX_FROM_REFERENCE_S, tod, code)
    if order is not None:  # back to the records' own order
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        tod, code = tod[back], code[back]
    return tod, code


def _service_times(buf: np.ndarray, starts: np.ndarray, lens: np.ndarray, edition: str | None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Offsets, radar keys and times of day of the CAT002 records in these blocks (those that walk), when
    CAT002 is not decoded itself: CAT001 needs them all the same."""
    lay = compile_layout(SERVICE_CATEGORY, edition, ("time_of_day",))
    cap = int(lens.sum()) // 2 + 1  # a record is at least 2 bytes (an FSPEC and a one-byte item)
    slots = max(lay.n_slots, 1)
    rel_off, rel_len = np.empty((cap, slots), np.uint16), np.zeros((cap, slots), np.uint16)
    rec_off, rec_blk = np.empty(cap, np.int64), np.empty(cap, np.int64)
    n = kernel.scan(buf, starts, lens, lay.parts, lay.n_frn, lay.n_slots, rel_off, rel_len, rec_off,
                    rec_blk, np.zeros(slots, np.uint8))[2]
    assert n >= 0, "record arrays sized for the smallest records"
    fl = np.full((len(lay.out_names_float), n), np.nan)
    it = np.full((len(lay.out_names_int), n), -1, np.int32)
    wd = np.full((len(lay.out_names_wide), n), -1, np.int64)
    fg = np.full((len(lay.out_names_flag), n), -1, np.int8)
    kernel.gather(buf, rec_off, rel_off, rel_len, lay.F, lay.f_mult, fl, it, wd, fg, 0, n, 0)
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
        edition = editions.get(SERVICE_CATEGORY)
        if edition == "auto":  # CAT002 is not decoded: nothing chose; its editions share one table
            edition = None
        r_off, r_key, r_tod = _service_times(buf, b_start[sel], b_len[sel], edition)
    plots = columns.get(PLOT_CATEGORY)
    if plots is None:
        date_records(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), r_off, r_key, r_tod, clock)
        return pd.DataFrame(columns=UNTIMED_COLUMNS)
    key = _keys(plots["sac"], plots["sic"])
    tod, code = date_records(plots["offset"], key, np.asarray(plots["truncated_time_of_day"], float),
                             r_off, r_key, r_tod, clock)
    plots["time_of_day"] = tod
    bad = np.flatnonzero(code != DATED)
    return pd.DataFrame({"offset": np.asarray(plots["offset"], np.int64)[bad],
                         "category": np.full(len(bad), PLOT_CATEGORY, np.int64),
                         "sac": pd.array(plots["sac"], dtype="Int32")[bad],
                         "sic": pd.array(plots["sic"], dtype="Int32")[bad],
                         "reason": pd.Categorical.from_codes(code[bad] - 1, [REASONS[c] for c in
                                                                             sorted(REASONS)])},
                        columns=UNTIMED_COLUMNS)


def untimed_advice(path: str, untimed: pd.DataFrame) -> list[str]:
    """One line per reason: how many CAT001 records have no time of day, and the first offsets."""
    out = []
    for why, g in untimed.groupby("reason", sort=False, observed=True):
        first = ", ".join(str(int(o)) for o in g["offset"].iloc[:3])
        out.append(f"{path}: {len(g)} CAT001 record(s) have no time of day: {why} (offsets {first}"
                   f"{', ...' if len(g) > 3 else ''}; Recording.untimed lists them)")
    return out
