"""Aircraft identity, assigned once when measurements are built, and the normalisation of its parts.

Rule, per report, over all sensors of the run together (the reports the run builds measurements from: with a
time window, those within report_selection.READING_MARGIN of it):
1. the report's 24-bit address, when it has one;
2. else the address its call sign is seen with elsewhere in the run, when that address is unique;
3. else "CS:" + call sign;
4. else the address its Mode 3/A code is seen with, when unique, if the report lies within reach of that
   address's own reports (below); else "M3A:" + Mode 3/A code;
5. else <NA>: the report belongs to no aircraft (it still counts as a report of its sensor).
Correlation, quality, jump detection and everything after group by this ``aircraft_id`` only.

The reach gate of rule 4: a Mode 3/A code says little (4096 codes, reused over a day; false plots such as
reflections repeat a transponder's reply elsewhere), so a report joins the address only if it lies within
M3A_REACH_SPEED_KT x the time to, plus M3A_REACH_MARGIN_NM of, the address's addressed report just before or
just after it. The real Barcelona radar recording has a plot 38.7 NM from its aircraft's simultaneous plot.
Refused reports keep "M3A:" + code; ``identify`` lists them. Without time, latitude and longitude columns
the gate cannot apply.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from msdc.pipeline.model.geodesy import great_circle_nm
from msdc.pipeline.model.schema import coded_text, text_categorical
from msdc.pipeline.model.time import iso_utc

# the labels of aircraft known without a Mode S address (rules 3 and 4 above); any other id is an address
CALLSIGN_PREFIX, MODE_A_PREFIX = "CS:", "M3A:"


def known_by_address(ids) -> np.ndarray:
    """Per aircraft id, whether it is the aircraft's Mode S address (not a call-sign or Mode 3/A label)."""
    s = pd.Series(ids, dtype="string")
    return (s.notna() & ~s.str.startswith((CALLSIGN_PREFIX, MODE_A_PREFIX))).fillna(False).to_numpy(bool)

# Rule 4's reach gate: faster than any civil aircraft's ground speed (an airliner in the jet stream makes
# about 700 kt), and a margin for radar plot error (0.35 NM is 1 sigma of 0.08 deg at 250 NM) and site error
M3A_REACH_SPEED_KT = 1000.0
M3A_REACH_MARGIN_NM = 3.0
REFUSED_COLUMNS = ["row", "mode3a", "address", "distance_nm", "seconds", "limit_nm"]
_GATE_INPUTS = ("time", "latitude", "longitude")


def _per_label(s: pd.Series, normalise) -> pd.Series:
    """A categorical Series normalised once per distinct label (categorical out, labels merged)."""
    labels = normalise(pd.Series(s.cat.categories, dtype="string"))
    return pd.Series(coded_text(s.cat.codes.to_numpy(), labels.to_numpy(dtype=object, na_value=None)),
                     index=s.index, name=s.name)


def normalise_callsign(s):
    """Upper-case call sign with spaces removed ("mas 72" -> "MAS72"); Series in, Series out (categorical
    in, categorical out); NA kept."""
    if isinstance(s, pd.Series) and isinstance(s.dtype, pd.CategoricalDtype):
        return _per_label(s, normalise_callsign)
    if isinstance(s, pd.Series):
        out = s.astype("string").str.upper().str.replace(" ", "", regex=False)
        return out.where(out.str.len() > 0)
    if s is None or (not isinstance(s, str) and pd.isna(s)):
        return None
    text = str(s).upper().replace(" ", "")
    return text or None


def normalise_address(s):
    """Upper-case 6-hex-digit address ("0x76cd41" -> "76CD41"); Series in, Series out (categorical in,
    categorical out); NA kept."""
    if isinstance(s, pd.Series) and isinstance(s.dtype, pd.CategoricalDtype):
        return _per_label(s, normalise_address)
    if isinstance(s, pd.Series):
        out = s.astype("string").str.strip().str.upper().str.removeprefix("0X").str.zfill(6)
        return out.where(out.str.len() > 0)
    if s is None or (not isinstance(s, str) and pd.isna(s)):
        return None
    text = str(s).strip().upper().removeprefix("0X")
    return text.zfill(6) if text else None


def _unique_address(meas: pd.DataFrame, column: str) -> pd.Series:
    """Per row, the address its ``column`` value is seen with when that address is unique, else NA."""
    pairs = meas[[column, "address"]].dropna().drop_duplicates()
    counts = pairs[column].value_counts()
    unique = pairs[pairs[column].isin(counts.index[counts == 1])].set_index(column)["address"]
    return meas[column].map(unique).astype("string")


def assign_aircraft_id(meas: pd.DataFrame) -> pd.Series:
    """The ``aircraft_id`` of every row by the module's rule (the schema's categorical text, <NA> when
    unidentified); ``identify`` also lists the reports rule 4's reach gate kept apart."""
    return identify(meas)[0]


def identify(meas: pd.DataFrame) -> tuple[pd.Series, pd.DataFrame]:
    """The ``aircraft_id`` of every row by the module's rule, and the reports the reach gate kept from the
    address their Mode 3/A code is seen with (REFUSED_COLUMNS: row position, code, address, distance from
    the address's report nearest in time, the seconds between them, and the reach limit).
    The rule reads a row's address, call sign and Mode 3/A code and which of them occur together anywhere in
    the run, so it is worked out once per distinct combination of the three (the gate per row)."""
    parts = [text_categorical(meas[c]) for c in ("address", "callsign", "mode3a")]
    key = np.zeros(len(meas), np.int64)
    for part in parts:  # codes -1..n-1 of each column, packed into one integer per row (in place)
        key *= len(part.cat.categories) + 1
        key += part.cat.codes.to_numpy(np.int64)
        key += 1
    row_combo, _ = pd.factorize(key)  # combinations in order of first appearance (hashing: few of them)
    first = np.flatnonzero(~pd.Series(key).duplicated().to_numpy())  # the row where each first appears
    del key
    triples = pd.DataFrame({c: p.iloc[first].astype("string").reset_index(drop=True)
                            for c, p in zip(("address", "callsign", "mode3a"), parts, strict=True)})
    ident = triples["address"].fillna(_unique_address(triples, "callsign"))
    ident = ident.fillna(CALLSIGN_PREFIX + triples["callsign"])
    by_code = _unique_address(triples, "mode3a").where(ident.isna())
    ident = ident.fillna(by_code).fillna(MODE_A_PREFIX + triples["mode3a"])
    refused = _out_of_reach(meas, parts[0], row_combo, by_code)
    codes = row_combo.copy()
    codes[refused["row"].to_numpy(np.int64)] += len(triples)  # the refused rows take their own code's label
    labels = np.concatenate([ident.to_numpy(dtype=object, na_value=None),
                             (MODE_A_PREFIX + triples["mode3a"]).to_numpy(dtype=object, na_value=None)])
    ids = pd.Series(coded_text(codes, labels), index=meas.index, name="aircraft_id")
    refused["mode3a"] = triples["mode3a"].to_numpy(dtype=object)[row_combo[refused["row"].to_numpy(np.int64)]]
    return ids, refused[REFUSED_COLUMNS]


def _seconds(times: pd.Series) -> np.ndarray:
    """Seconds since 1970 (float, NaN for a missing time) of a datetime column."""
    stamps = pd.DatetimeIndex(times).as_unit("ns")  # pandas may keep any unit
    out = stamps.asi8.astype(np.float64) / 1e9
    out[stamps.isna()] = np.nan
    return out


def _anchors_before(anchor_key: np.ndarray, anchor_t: np.ndarray, key: np.ndarray,
                    t: np.ndarray) -> np.ndarray:
    """Per (key, t), how many anchors, sorted by (key, time), come before it: the position of the first
    anchor of its key at or after its time (anchors first on equal times)."""
    keys, times = np.concatenate([anchor_key, key]), np.concatenate([anchor_t, t])
    is_row = np.r_[np.zeros(len(anchor_key), bool), np.ones(len(key), bool)]
    order = np.lexsort((is_row, times, keys))
    before = np.cumsum(~is_row[order])  # anchors up to and including each merged position
    out = np.empty(len(key), np.int64)
    out[order[is_row[order]] - len(anchor_key)] = before[is_row[order]]
    return out


def _out_of_reach(meas: pd.DataFrame, address: pd.Series, row_combo: np.ndarray,
                  by_code: pd.Series) -> pd.DataFrame:
    """Rows that rule 4 would join to an address (``by_code`` per combination) but that lie beyond reach of
    the address's addressed report just before and just after them (row, address, distance_nm, seconds and
    limit_nm to the nearer in time); rows without a time or position, or whose address has none, pass."""
    empty = pd.DataFrame({"row": np.zeros(0, np.int64), "address": np.zeros(0, object),
                          "distance_nm": np.zeros(0), "seconds": np.zeros(0), "limit_nm": np.zeros(0)})
    if not set(_GATE_INPUTS) <= set(meas) or not by_code.notna().any():
        return empty
    target = address.cat.categories.get_indexer(by_code.to_numpy(dtype=object, na_value=None))
    target = np.where(by_code.notna().to_numpy(), target, -1)[row_combo]  # per row; -1: not joined by code
    t, lat, lon = _seconds(meas["time"]), meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    placed = np.isfinite(t) & np.isfinite(lat) & np.isfinite(lon)
    own = address.cat.codes.to_numpy(np.int64)
    anchors = np.flatnonzero(placed & (own >= 0) & np.isin(own, target[target >= 0]))
    anchors = anchors[np.lexsort((t[anchors], own[anchors]))]  # by address, then time
    rows = np.flatnonzero(placed & (target >= 0))
    start = np.searchsorted(own[anchors], target[rows], "left")
    stop = np.searchsorted(own[anchors], target[rows], "right")
    found = stop > start
    rows, start, stop = rows[found], start[found], stop[found]
    best = np.full((2, len(rows)), np.nan)  # distance, seconds to the nearer in time
    ok = np.zeros(len(rows), bool)
    after = _anchors_before(own[anchors], t[anchors], target[rows], t[rows])  # index of the anchor after
    for near in (np.clip(after - 1, start, stop - 1), np.clip(after, start, stop - 1)):
        at = anchors[near]
        d_nm = great_circle_nm(lat[at], lon[at], lat[rows], lon[rows])
        dt_s = np.abs(t[rows] - t[at])
        ok |= d_nm <= M3A_REACH_SPEED_KT * dt_s / 3600.0 + M3A_REACH_MARGIN_NM
        closer = ~(dt_s >= best[1])  # NaN (first pass) or nearer in time
        best[0][closer], best[1][closer] = d_nm[closer], dt_s[closer]
    bad = rows[~ok]
    if not len(bad):
        return empty
    seconds = best[1][~ok]
    return pd.DataFrame({"row": bad, "address": address.cat.categories.to_numpy(dtype=object)[own[anchors][
        start[~ok]]], "distance_nm": best[0][~ok], "seconds": seconds,
        "limit_nm": M3A_REACH_SPEED_KT * seconds / 3600.0 + M3A_REACH_MARGIN_NM})


def refused_warnings(refused: pd.DataFrame, meas: pd.DataFrame) -> list[str]:
    """One warning for the reports rule 4's reach gate kept apart (``identify``'s table, rows of ``meas``):
    how many, per code and address, and the first one with its file and offset when the frame has them."""
    if not len(refused):
        return []
    pairs = refused.groupby(["mode3a", "address"], sort=False).size()
    listed = ", ".join(f"{code} -> {addr} ({n})" for (code, addr), n in list(pairs.items())[:5])
    more = f" and {len(pairs) - 5} more" if len(pairs) > 5 else ""
    first = refused.iloc[0]
    row = meas.iloc[int(first["row"])]
    where = "".join(f"{label}{row[c]}, " for c, label in (("file", ""), ("offset", "offset "))
                    if c in meas and pd.notna(row[c]))
    sensor = f"{row['sensor_id']} " if "sensor_id" in meas else ""
    if "time" in meas and pd.notna(row["time"]):
        when = iso_utc(row["time"]) or pd.Timestamp(row["time"]).strftime("%H:%M:%S.%f")[:-3]
        where += f"at {when}, "
    reach = f"{M3A_REACH_SPEED_KT:.0f} kt from its nearest report in time, plus {M3A_REACH_MARGIN_NM:g} NM"
    return [f"{len(refused)} report(s) without an address were not joined to the aircraft their Mode 3/A "
            f"code is seen with, lying beyond its reach ({reach}): a false plot or a reused code; they are "
            f"labelled M3A:<code> (code -> address: {listed}{more}); the first: {sensor}{where}"
            f"{first['mode3a']}, {first['distance_nm']:.1f} NM from {first['address']}'s report "
            f"{first['seconds']:.1f} s apart (limit {first['limit_nm']:.1f} NM)"]


def aircraft_labels(meas: pd.DataFrame) -> pd.DataFrame:
    """Per aircraft_id, the labels shown in reports: the most frequent call sign and address (ADS-B first,
    as it always transmits identity; the smallest of equally frequent values), "" when none."""
    cols = meas[["aircraft_id", "sensor_kind", "callsign", "address"]]
    known = cols[cols["aircraft_id"].notna().to_numpy(bool)]
    out = pd.DataFrame({"aircraft_id": pd.Series(sorted(str(a) for a in known["aircraft_id"].unique()),
                                                 dtype=object)})
    adsb = known[(known["sensor_kind"] == "adsb").to_numpy(bool)]
    for column in ("callsign", "address"):
        first, second = _most_common_by(adsb, column), _most_common_by(known, column)
        label = out["aircraft_id"].map(first)
        label = label.where(label.notna() & (label != ""), out["aircraft_id"].map(second))
        out[column] = label.astype(object).fillna("")  # all missing is float64, which "" cannot fill
    columns = ["aircraft_id", "callsign", "address"]  # built from lists: the dtypes pandas infers for text
    return pd.DataFrame({c: out[c].tolist() for c in columns}, columns=columns)


def _most_common_by(meas: pd.DataFrame, column: str) -> pd.Series:
    """Per aircraft_id, its most frequent non-missing ``column`` value (the smallest on ties), as text."""
    ident, values = meas["aircraft_id"], meas[column]
    if isinstance(ident.dtype, pd.CategoricalDtype) and isinstance(values.dtype, pd.CategoricalDtype):
        return _most_common_codes(ident, values)
    pairs = meas[["aircraft_id", column]].dropna()
    if pairs.empty:
        return pd.Series(dtype=object)
    counts = pairs.groupby(["aircraft_id", column], sort=False, observed=True).size()
    counts = counts.rename("n").reset_index()
    counts = counts.sort_values(["aircraft_id", "n", column], ascending=[True, False, True], kind="stable")
    top = counts.drop_duplicates("aircraft_id")
    return pd.Series(top[column].map(str).to_numpy(dtype=object),
                     index=top["aircraft_id"].map(str).to_numpy())


def _most_common_codes(ident: pd.Series, values: pd.Series) -> pd.Series:
    """_most_common_by for categorical columns, on their codes (the smallest in category order on ties, as
    sorting the categorical does); no per-row object is made."""
    a, c = ident.cat.codes.to_numpy(np.int64), values.cat.codes.to_numpy(np.int64)
    both = (a >= 0) & (c >= 0)
    if not both.any():
        return pd.Series(dtype=object)
    n_values = len(values.cat.categories)
    pair, count = np.unique(a[both] * n_values + c[both], return_counts=True)
    pa, pc = pair // n_values, pair % n_values
    order = np.lexsort((pc, -count, pa))  # per aircraft: most frequent first, then the smallest code
    top = order[np.r_[True, pa[order][1:] != pa[order][:-1]]]
    return pd.Series([str(v) for v in values.cat.categories[pc[top]]],
                     index=[str(v) for v in ident.cat.categories[pa[top]]], dtype=object)
