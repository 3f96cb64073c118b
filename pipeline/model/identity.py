"""Aircraft identity, assigned once when measurements are built, and the normalisation of its parts.

Rule, per report, over all sensors of the run together:
1. the report's 24-bit address, when it has one;
2. else the address its call sign is seen with elsewhere in the run, when that address is unique;
3. else "CS:" + call sign;
4. else the address its Mode 3/A code is seen with, when unique; else "M3A:" + Mode 3/A code;
5. else <NA>: the report belongs to no aircraft (it still counts as a report of its sensor).
Correlation, quality, jump detection and everything after group by this ``aircraft_id`` only.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from pipeline.model.schema import coded_text, text_categorical


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
    unidentified). The rule reads a row's address, call sign and Mode 3/A code and which of them occur
    together anywhere in the run, so it is worked out once per distinct combination of the three."""
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
    ident = ident.fillna("CS:" + triples["callsign"])
    ident = ident.fillna(_unique_address(triples, "mode3a")).fillna("M3A:" + triples["mode3a"])
    return pd.Series(coded_text(row_combo, ident.to_numpy(dtype=object, na_value=None)), index=meas.index,
                     name="aircraft_id")


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
        out[column] = label.where(label.notna() & (label != ""), out["aircraft_id"].map(second)).fillna("")
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
