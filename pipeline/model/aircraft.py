"""Which aircraft to correlate: one named by call sign / address, or every aircraft both kinds of sensor saw.

Aircraft are told apart by ``aircraft_id`` only (assigned once, pipeline.model.identity).
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pandas as pd

from msdc.pipeline.model.identity import aircraft_labels, normalise_address, normalise_callsign
from msdc.pipeline.model.measurements import select


class NoSuchAircraft(LookupError):
    """The requested aircraft is not in the radar and/or ADS-B data; lists the closest ones present."""

    def __init__(self, wanted: str, missing_in: list[str], closest: list[str], message: str | None = None):
        self.wanted, self.missing_in, self.closest = wanted, missing_in, closest
        hint = f"closest present: {', '.join(closest)}" if closest else "nothing similar is present"
        super().__init__(message or f"{wanted} not seen by {' or '.join(missing_in)}; {hint}")


@dataclass
class Aircraft:
    """One aircraft's measurements from each kind of sensor, with the labels used in reports ("" if none)."""

    callsign: str
    address: str
    radar: pd.DataFrame
    adsb: pd.DataFrame
    aircraft_id: str = ""


def _split(meas: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The radar rows and the ADS-B rows (the other kinds, multilateration and surface radar, in neither:
    pipeline.correlate names them radar and ADS-B by their role in a pair)."""
    kind = meas["sensor_kind"]
    radar, adsb = (kind == "radar").to_numpy(bool), (kind == "adsb").to_numpy(bool)
    return meas[radar].reset_index(drop=True), meas[adsb].reset_index(drop=True)


def _closest(wanted: str, meas: pd.DataFrame, column: str) -> list[str]:
    """The names (call signs or addresses) closest to ``wanted`` seen by any sensor, as msdc track
    suggests them; one seen by a single kind of sensor says which ("VLG1306 (ADS-B only)"), since
    correlating it needs both."""
    radar, adsb = _split(meas)
    in_radar, in_adsb = set(radar[column].dropna()), set(adsb[column].dropna())
    close = difflib.get_close_matches(wanted, sorted(in_radar | in_adsb), n=5, cutoff=0.5)
    return [name if name in in_radar and name in in_adsb else
            f"{name} ({'radar' if name in in_radar else 'ADS-B'} only)" for name in close]


def one_aircraft(meas: pd.DataFrame, callsign: str | None = None, address: str | None = None, *,
                 need_adsb: bool = True) -> Aircraft:
    """The aircraft with this call sign and/or address; NoSuchAircraft if radar (or, when ``need_adsb``,
    ADS-B) lacks it."""
    if callsign is None and address is None:
        raise ValueError("give a call sign or an address (or ask for all aircraft)")
    r, a = _split(select(meas, callsign, address))
    missing = [name for name, f in (("radar", r), ("ADS-B", a))
               if f.empty and (need_adsb or name == "radar")]
    if missing:
        if callsign is not None:
            wanted = normalise_callsign(callsign)
            closest = _closest(wanted or "", meas, "callsign")
            what = f"call sign {wanted}"
        else:
            wanted = normalise_address(address)
            closest = _closest(wanted or "", meas, "address")
            what = f"address {wanted}"
        if callsign is not None and address is not None:
            what += f" with address {normalise_address(address)}"
        raise NoSuchAircraft(what, missing, closest)
    labels = aircraft_labels(pd.concat([r, a], ignore_index=True) if len(a) else r)
    cs = normalise_callsign(callsign) if callsign is not None else labels["callsign"].iloc[0]
    addr = normalise_address(address) if address is not None else labels["address"].iloc[0]
    ident = r["aircraft_id"].iloc[0] if r["aircraft_id"].nunique() == 1 else ""
    return Aircraft(cs or "", addr or "", r, a, ident)


def all_aircraft(meas: pd.DataFrame, *, need_adsb: bool = True) -> list[Aircraft]:
    """Every aircraft seen by radar and (when ``need_adsb``) ADS-B, sorted by call sign, then address."""
    return list(iter_aircraft(meas, need_adsb=need_adsb))


def iter_aircraft(meas: pd.DataFrame, *, need_adsb: bool = True) -> Iterator[Aircraft]:
    """``all_aircraft`` one at a time: each aircraft's rows are copied out of ``meas`` only when it comes,
    so the whole run is never held twice."""
    for callsign, address, ident, radar, other in aircraft_rows(meas, need_adsb=need_adsb):
        yield Aircraft(callsign, address, meas.iloc[radar].reset_index(drop=True),
                       meas.iloc[other].reset_index(drop=True), ident)


def aircraft_rows(meas: pd.DataFrame, *, need_adsb: bool = True
                  ) -> Iterator[tuple[str, str, str, np.ndarray, np.ndarray]]:
    """Per aircraft, in ``all_aircraft`` order: its call sign and address labels, its ``aircraft_id``, and the
    positions in ``meas`` (ascending) of its radar rows and of its ADS-B rows; no row is copied (rows of
    the other kinds, multilateration and surface radar, are in neither)."""
    radar = (meas["sensor_kind"] == "radar").to_numpy(bool)
    adsb = (meas["sensor_kind"] == "adsb").to_numpy(bool)
    ident = meas["aircraft_id"]
    rows = {kind: ident[mask].groupby(ident[mask], sort=False, observed=True).indices  # positions in mask
            for kind, mask in (("radar", radar), ("adsb", adsb))}
    at = {"radar": np.flatnonzero(radar), "adsb": np.flatnonzero(adsb)}  # mask position -> row
    labels = aircraft_labels(meas).set_index("aircraft_id")
    ids = set(rows["radar"])
    chosen = sorted(ids & set(rows["adsb"]) if need_adsb else ids)
    for ident in sorted(chosen, key=lambda i: (labels.at[i, "callsign"], labels.at[i, "address"])):
        yield (labels.at[ident, "callsign"], labels.at[ident, "address"], ident,
               at["radar"][rows["radar"][ident]], at["adsb"][rows["adsb"].get(ident, np.zeros(0, np.int64))])
