"""Which aircraft to correlate: one named by call sign / address, or every aircraft both sensors saw."""

from __future__ import annotations

import difflib
from dataclasses import dataclass

import pandas as pd

from pipeline.model.measurements import normalise_address, normalise_callsign, select


class NoSuchAircraft(LookupError):
    """The requested aircraft is not in the radar and/or ADS-B data; lists the closest ones present."""

    def __init__(self, wanted: str, missing_in: list[str], closest: list[str], message: str | None = None):
        self.wanted, self.missing_in, self.closest = wanted, missing_in, closest
        hint = f"closest present in both: {', '.join(closest)}" if closest else "nothing similar is present"
        super().__init__(message or f"{wanted} not seen by {' or '.join(missing_in)}; {hint}")


@dataclass
class Aircraft:
    """One aircraft's measurements from each sensor, with the labels used in reports ("" if unknown)."""

    callsign: str
    address: str
    radar: pd.DataFrame
    adsb: pd.DataFrame


def _most_common(values: pd.Series) -> str:
    counts = values.dropna().value_counts(sort=True)
    return str(counts.index[0]) if len(counts) else ""


def _label(radar: pd.DataFrame, adsb: pd.DataFrame, column: str) -> str:
    """The most frequent value of a column, ADS-B first (it always transmits identity)."""
    return _most_common(adsb[column]) or _most_common(radar[column])


def _closest(wanted: str, radar: pd.DataFrame, adsb: pd.DataFrame, column: str) -> list[str]:
    both = sorted(set(radar[column].dropna()) & set(adsb[column].dropna()))
    return difflib.get_close_matches(wanted, both, n=5, cutoff=0.5)


def one_aircraft(radar: pd.DataFrame, adsb: pd.DataFrame, callsign: str | None = None,
                 address: str | None = None) -> Aircraft:
    """The aircraft with this call sign and/or address; NoSuchAircraft if either sensor lacks it."""
    if callsign is None and address is None:
        raise ValueError("give a call sign or an address (or ask for all aircraft)")
    r = select(radar, callsign, address, link_with=adsb)
    a = select(adsb, callsign, address, link_with=radar)
    missing = [name for name, f in (("radar", r), ("ADS-B", a)) if f.empty]
    if missing:
        if callsign is not None:
            wanted = normalise_callsign(callsign)
            closest = _closest(wanted or "", radar, adsb, "callsign")
            what = f"call sign {wanted}"
        else:
            wanted = normalise_address(address)
            closest = _closest(wanted or "", radar, adsb, "address")
            what = f"address {wanted}"
        if callsign is not None and address is not None:
            what += f" with address {normalise_address(address)}"
        raise NoSuchAircraft(what, missing, closest)
    cs = normalise_callsign(callsign) if callsign is not None else _label(r, a, "callsign")
    addr = normalise_address(address) if address is not None else _label(r, a, "address")
    return Aircraft(cs or "", addr or "", r, a)


def _keys(meas: pd.DataFrame, by_callsign: dict[str, str]) -> pd.Series:
    """Aircraft key per row: "A:" + address, else the address the call sign maps to, else "C:" + call sign."""
    from_cs = meas["callsign"].map(by_callsign)
    key = ("A:" + meas["address"]).fillna("A:" + from_cs).fillna("C:" + meas["callsign"])
    return key


def all_aircraft(radar: pd.DataFrame, adsb: pd.DataFrame) -> list[Aircraft]:
    """Every aircraft seen by both sensors, matched by address where present, else by call sign.

    A row without an address takes the address its call sign is seen with, when that is unique.
    Sorted by call sign, then address.
    """
    pairs = pd.concat([radar[["callsign", "address"]], adsb[["callsign", "address"]]]).dropna()
    per_cs = pairs.drop_duplicates().groupby("callsign")["address"]
    by_callsign = {cs: addrs.iloc[0] for cs, addrs in per_cs if len(addrs) == 1}
    r_key, a_key = _keys(radar, by_callsign), _keys(adsb, by_callsign)
    out = []
    for key in sorted(set(r_key.dropna()) & set(a_key.dropna())):
        r = radar[(r_key == key).to_numpy()].reset_index(drop=True)
        a = adsb[(a_key == key).to_numpy()].reset_index(drop=True)
        addr = key[2:] if key.startswith("A:") else ""
        out.append(Aircraft(_label(r, a, "callsign"), addr, r, a))
    return sorted(out, key=lambda ac: (ac.callsign, ac.address))
