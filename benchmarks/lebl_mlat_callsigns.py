"""The LEBL multilateration's reports without a call sign, against what the same aircraft's ADS-B sent
around them: whether an identification was there to relay (the check of docs/methods/evaluate.md's
call-sign paragraph by another method than `msdc evaluate`: no reference, no association, by address).

Run by hand: ``python benchmarks/lebl_mlat_callsigns.py [../shared/real]``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from lebl_pd_independent import lebl_frames, real_folder, seconds

WINDOWS_S = (15.0, 30.0)


def named(frame: pd.DataFrame) -> pd.DataFrame:
    """Address, time (s of the day) and whether a non-blank call sign is carried."""
    frame = frame[frame["address"].notna()]
    call = frame["callsign"].astype("string").str.strip()
    return pd.DataFrame({"address": frame["address"].astype(str).to_numpy(), "t": seconds(frame),
                         "has": (call.notna() & (call != "")).to_numpy(bool)})


def main() -> None:
    adsb, mlat, _ = lebl_frames(real_folder(__doc__))
    adsb, mlat = named(adsb), named(mlat[mlat["typ"] == 1])
    missing = mlat[~mlat["has"]]
    seen = missing["address"].isin(set(adsb["address"]))
    print(f"multilateration target reports with an address: {len(mlat):,}; without a call sign: "
          f"{len(missing):,}, of which {int((~seen).sum()):,} of aircraft or vehicles with no ADS-B at all "
          f"and {int(seen.sum()):,} of aircraft with ADS-B")
    called = adsb[adsb["has"]].groupby("address")["t"].apply(np.sort)
    for w in WINDOWS_S:
        none = 0
        for address, g in missing[seen].groupby("address"):
            times = called.get(address, np.empty(0))
            t = g["t"].to_numpy()
            none += int((np.searchsorted(times, t + w) == np.searchsorted(times, t - w)).sum())
        print(f"  of those {int(seen.sum()):,}: {none:,} ({100 * none / seen.sum():.0f} %) with no ADS-B "
              f"call sign of the aircraft within {w:g} s either")


if __name__ == "__main__":
    main()
