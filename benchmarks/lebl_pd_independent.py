"""An independent count of the LEBL multilateration's and surface radar's probability of update in 1 s
intervals inside the manoeuvring area, against ADS-B alone: the check of docs/methods/evaluate.md's LEBL
rows by another method than `msdc evaluate` (no reconstructed reference, no self-reference, no evaluate code).

The recordings are decoded with msdc.asterix; everything after is written out here:
- positions on a flat east/north plane (m) about the airport reference point (local radii of curvature:
  metres of error across the airport);
- the reference: each aircraft's ADS-B positions (by address, the six field monitors left out, a report
  more than 300 m/s from both neighbours dropped), cut where reports are more than 30 s apart;
- the expected updates: whole 1 s intervals from each stretch's first report, each in the area when the
  position interpolated at its middle lies in a manoeuvring polygon (even-odd rule, written here);
- detected: the multilateration reports the aircraft's address in the interval; a surface radar plot (no
  address) counts for the reference aircraft nearest it within 150 m at its time;
- PD with its Clopper-Pearson 95 % interval; ``bridged`` also counts as missed the intervals of an
  excursion out of the area shorter than 30 s between two stays in it (what a reference cut to the area
  and interpolated across such gaps does).

Run by hand: ``python benchmarks/lebl_pd_independent.py [../shared/real]``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import beta

import msdc.asterix as asterix

ROOT = Path(__file__).resolve().parents[1]

REFERENCE_POINT = (41.2969, 2.0785)  # LEBL aerodrome reference point (deg)
# the systems' origins as the sensor file of docs/methods/lebl-hour.md gives them: MLAT, SMR (deg)
ORIGINS = {107: (41.297074, 2.078480), 7: (41.295569, 2.095099)}
MONITORS = {"342383", "342384", "342385", "342386", "342387", "3433D5"}
GAP_S, JUMP_MPS, SMR_GATE_M, DAY = 30.0, 300.0, 150.0, "2016-05-10"
A_M, E2 = 6378137.0, 6.69437999014e-3  # WGS-84


def plane(lat, lon) -> tuple[np.ndarray, np.ndarray]:
    """East and north (m) of the reference point, on the local radii of curvature."""
    lat0 = np.radians(REFERENCE_POINT[0])
    w = np.sqrt(1.0 - E2 * np.sin(lat0) ** 2)
    north_m_per_rad, east_m_per_rad = A_M * (1.0 - E2) / w**3, A_M / w * np.cos(lat0)
    return (np.radians(np.asarray(lon, float) - REFERENCE_POINT[1]) * east_m_per_rad,
            np.radians(np.asarray(lat, float) - REFERENCE_POINT[0]) * north_m_per_rad)


def inside(x, y, rings: list[np.ndarray]) -> np.ndarray:
    """Even-odd rule: a ray towards +x crosses a ring's edges an odd number of times."""
    hit = np.zeros(np.shape(x), bool)
    for ring in rings:
        odd = np.zeros(np.shape(x), bool)
        for (x0, y0), (x1, y1) in zip(ring[:-1], ring[1:], strict=True):
            if y0 != y1:
                odd ^= ((y0 > y) != (y1 > y)) & (x < x0 + (y - y0) * (x1 - x0) / (y1 - y0))
        hit |= odd
    return hit


def manoeuvring(path: Path) -> list[np.ndarray]:
    rings = []
    for feature in json.loads(path.read_text())["features"]:
        if feature["properties"].get("area") == "manoeuvring":
            ring = np.asarray(feature["geometry"]["coordinates"][0], float)
            rings.append(np.column_stack(plane(ring[:, 1], ring[:, 0])))
    return rings


def seconds(frame: pd.DataFrame) -> np.ndarray:
    return (frame["timestamp"] - pd.Timestamp(DAY, tz="UTC")).dt.total_seconds().to_numpy(float)


def reference(adsb: pd.DataFrame) -> dict[str, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Per address, its stretches (t, east, north), jumps dropped."""
    adsb = adsb.dropna(subset=["latitude", "longitude", "address"])
    adsb = adsb[~adsb["address"].astype(str).isin(MONITORS)]
    x, y = plane(adsb["latitude"], adsb["longitude"])
    frame = pd.DataFrame({"a": adsb["address"].astype(str).to_numpy(), "t": seconds(adsb), "x": x, "y": y})
    out = {}
    for address, g in frame.sort_values(["a", "t"]).drop_duplicates(["a", "t"]).groupby("a"):
        t, x, y = g["t"].to_numpy(), g["x"].to_numpy(), g["y"].to_numpy()
        speed = np.hypot(np.diff(x), np.diff(y)) / np.maximum(np.diff(t), 0.5)
        fast = np.r_[False, speed > JUMP_MPS] & np.r_[speed > JUMP_MPS, False]
        t, x, y = t[~fast], x[~fast], y[~fast]
        cuts = np.flatnonzero(np.diff(t) > GAP_S) + 1
        out[address] = [(tt, xx, yy) for tt, xx, yy in zip(np.split(t, cuts), np.split(x, cuts),
                                                              np.split(y, cuts), strict=True) if tt.size > 1]
    return out


def intervals(ref, rings) -> pd.DataFrame:
    """Every whole 1 s interval of every stretch: address, start, middle position, in the area."""
    rows = []
    for address, stretches in ref.items():
        for t, x, y in stretches:
            start = t[0] + np.arange(int(np.floor(t[-1] - t[0])))
            mid = start + 0.5
            xm, ym = np.interp(mid, t, x), np.interp(mid, t, y)
            rows.append(pd.DataFrame({"address": address, "start": start, "x": xm, "y": ym,
                                      "area": inside(xm, ym, rings)}))
    return pd.concat(rows, ignore_index=True)


def bridged(table: pd.DataFrame) -> np.ndarray:
    """The out-of-area intervals of an excursion shorter than GAP_S between two in-area ones (same
    aircraft and stretch: consecutive starts 1 s apart)."""
    out = np.zeros(len(table), bool)
    for _, g in table.groupby("address", sort=False):
        area, start = g["area"].to_numpy(), g["start"].to_numpy()
        run_start = np.flatnonzero(np.r_[True, (area[1:] != area[:-1]) | (np.diff(start) != 1.0)])
        run_end = np.r_[run_start[1:], area.size]
        for k in range(1, len(run_start) - 1):
            a, b = run_start[k], run_end[k]
            if (not area[a] and area[a - 1] and area[b] and b - a < GAP_S
                    and start[a] - start[a - 1] == 1.0 and start[b] - start[b - 1] == 1.0):
                out[g.index[a:b]] = True
    return out


def detected(table: pd.DataFrame, address: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Whether the sensor reported the interval's aircraft in [start, start + 1)."""
    got = np.zeros(len(table), bool)
    by = pd.DataFrame({"a": address, "t": t}).sort_values("t").groupby("a")["t"].apply(np.asarray)
    for a, idx in table.groupby("address").groups.items():
        if a not in by.index:
            continue
        times, start = by[a], table.loc[idx, "start"].to_numpy()
        got[idx] = np.searchsorted(times, start + 1.0, "left") > np.searchsorted(times, start, "left")
    return got


def smr_owners(smr: pd.DataFrame, ref) -> tuple[np.ndarray, np.ndarray]:
    """Each surface radar plot's reference aircraft (the nearest within SMR_GATE_M at its time) and time."""
    ox, oy = plane(*ORIGINS[7])
    px, py, t = smr["x_m"].to_numpy(float) + ox, smr["y_m"].to_numpy(float) + oy, seconds(smr)
    best, owner = np.full(t.size, SMR_GATE_M), np.full(t.size, None, object)
    for address, stretches in ref.items():
        for tt, xx, yy in stretches:
            on = (t >= tt[0]) & (t <= tt[-1])
            d = np.hypot(px[on] - np.interp(t[on], tt, xx), py[on] - np.interp(t[on], tt, yy))
            rows = np.flatnonzero(on)[d < best[on]]
            best[rows], owner[rows] = d[d < best[on]], address
    keep = owner != None  # noqa: E711
    return owner[keep].astype(str), t[keep]


def share(k: int, n: int) -> str:
    lo = beta.ppf(0.025, k, n - k + 1) if k else 0.0
    hi = beta.ppf(0.975, k + 1, n - k) if k < n else 1.0
    return f"{k:,} of {n:,} = {100 * k / n:.2f} % ({100 * lo:.2f}-{100 * hi:.2f} %)"


def real_folder(doc: str) -> Path:
    """The folder of the real recordings, the command line's one argument (default ../shared/real)."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("real", nargs="?", type=Path, default=ROOT.parent / "shared" / "real")
    return ap.parse_args().real


def lebl_frames(real: Path) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """The LEBL hour decoded: ADS-B (CAT021 0.23), multilateration and surface radar (CAT010) frames."""
    adsb = asterix.read(real / "adsb_v023_160510-lebl-220001.ast", date=DAY, editions={21: "0.23"}).frames[21]
    mlat = asterix.read(real / "mlat_160510-lebl-220001.ast", date=DAY).frames[10]
    smr = asterix.read(real / "smr_160510-lebl-220001.ast", date=DAY).frames[10]
    return adsb, mlat, smr


def main() -> None:
    adsb, mlat, smr = lebl_frames(real_folder(__doc__))
    mlat = mlat[(mlat["typ"] == 1) & mlat["address"].notna()]
    smr = smr[smr["x_m"].notna()]
    ref = reference(adsb)
    table = intervals(ref, manoeuvring(ROOT / "docs" / "examples" / "lebl-areas.geojson"))
    extra = bridged(table)
    owners, t_smr = smr_owners(smr, ref)
    for name, got in (("MLAT", detected(table, mlat["address"].astype(str).to_numpy(), seconds(mlat))),
                      ("SMR", detected(table, owners, t_smr))):
        area = table["area"].to_numpy()
        k, n = int(got[area].sum()), int(area.sum())
        print(f"{name}: in the manoeuvring area {share(k, n)}; excursions under {GAP_S:g} s bridged as "
              f"missed: {share(k, n + int(extra.sum()))}")


if __name__ == "__main__":
    main()
