"""The areas of Barcelona El Prat (LEBL) in docs/examples/lebl-areas.geojson, and how well the real LEBL hour
(../shared/real: ADS-B, multilateration, surface radar) falls inside them.

Each area is a rough shape: a runway or a taxiway a rectangle of a given width about its centreline, an apron
a quadrilateral. Their corner points are the constants below (see docs/guide/sectors.md for how they were
drawn). Run by hand:

    python benchmarks/lebl_areas.py [../shared/real] [--write]

``--write`` rewrites the example file from the constants; the check reads the example file with
msdc.pipeline.evaluate.sectors and prints the shares of the recordings' reports inside the areas.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "docs" / "examples" / "lebl-areas.geojson"
M_PER_DEG_LAT = 111_132.0  # at 41.3 N (WGS-84 meridian arc per degree, rounded)
M_PER_DEG_LON = 83_760.0  # at 41.3 N (WGS-84 parallel per degree, rounded)
# (name, area, (lon, lat) of one end of the centreline, of the other end, width m): the centrelines fitted to
# the recording's moving ground reports (docs/guide/sectors.md says how), the runways' lengths as published
STRIPS = [
    ("RWY 06L/24R", "manoeuvring", (2.06353, 41.29444), (2.10216, 41.30768), 80.0),
    ("RWY 06R/24L", "manoeuvring", (2.07447, 41.28235), (2.10269, 41.29199), 80.0),
    ("RWY 02/20", "manoeuvring", (2.08470, 41.28753), (2.09456, 41.30903), 80.0),
    ("TWY north parallel", "manoeuvring", (2.06458, 41.29554), (2.09578, 41.30621), 60.0),
    ("TWY south parallel", "manoeuvring", (2.07375, 41.28399), (2.10022, 41.29300), 60.0),
    ("TWY 02/20 parallel", "manoeuvring", (2.08210, 41.28823), (2.09152, 41.30810), 60.0),
    ("TWY central", "manoeuvring", (2.07994, 41.30034), (2.08250, 41.29573), 60.0),
    ("TWY central south", "manoeuvring", (2.08248, 41.29586), (2.08460, 41.29233), 60.0),
]
# (name, area, corners (lon, lat)): rough outlines of the stands and their taxilanes
APRONS = [
    ("Apron T1", "apron", [(2.07400, 41.28500), (2.08350, 41.28800), (2.08245, 41.28813), (2.08175, 41.28831),
                           (2.08287, 41.29070), (2.08170, 41.29600), (2.07120, 41.29150)]),
    ("Apron T2", "apron", [(2.06500, 41.29610), (2.08938, 41.30442), (2.09005, 41.30585), (2.08880, 41.30900),
                           (2.06330, 41.30060)]),
]
# (the aprons stop about a metre short of the TWY 02/20 parallel strip: Apron T1 goes round its southern end
# and up its western edge, Apron T2's eastern corner, inside the strip, is replaced by the two points where
# its edges cross the western edge. A standard's areas do not overlap; until 2026-12-02 the aprons reached
# over the taxiway, and 3,473 reports were judged as both manoeuvring and apron)
MONITORS = {"342383", "342384", "342385", "342386", "342387"}  # fixed field transponders (lebl-hour.md)
RUNWAY_SPEED_KT = 50.0  # on the ground this fast: a take-off or landing roll
MOVING_KT = 5.0  # on the ground and this fast: taxiing (or a vehicle driving)
LEBL_HOUR = Path(__file__).resolve().parents[1] / "docs" / "methods" / "lebl-hour.md"


def sensors_toml() -> str:
    """The [[sensor]] tables of docs/methods/lebl-hour.md (its TOML block: the corrected reference points)."""
    text = LEBL_HOUR.read_text(encoding="utf-8")
    start = text.index("[[sensor]]")
    return text[start:text.index("```", start)]


def strip(a: tuple[float, float], b: tuple[float, float], width_m: float) -> list[list[float]]:
    """A rectangle width_m wide about the segment a-b (lon, lat), as a closed counter-clockwise ring, in a
    local flat approximation (good to well under a metre over 4 km)."""
    ax, ay = a[0] * M_PER_DEG_LON, a[1] * M_PER_DEG_LAT
    bx, by = b[0] * M_PER_DEG_LON, b[1] * M_PER_DEG_LAT
    ux, uy = bx - ax, by - ay
    norm = np.hypot(ux, uy)
    nx, ny = -uy / norm * width_m / 2, ux / norm * width_m / 2
    corners = [(ax - nx, ay - ny), (bx - nx, by - ny), (bx + nx, by + ny), (ax + nx, ay + ny)]
    ring = [[round(x / M_PER_DEG_LON, 6), round(y / M_PER_DEG_LAT, 6)] for x, y in corners]
    if (bx - ax) * (2 * ny) - (by - ay) * (2 * nx) < 0:  # keep counter-clockwise (RFC 7946 3.1.6)
        ring.reverse()
    return [*ring, ring[0]]


def collection() -> dict:
    """The example file's GeoJSON."""
    features = []
    for name, area, a, b, width in STRIPS:
        features.append({"type": "Feature", "properties": {"name": name, "area": area, "width_m": width},
                         "geometry": {"type": "Polygon", "coordinates": [strip(a, b, width)]}})
    for name, area, corners in APRONS:
        ring = [[lon, lat] for lon, lat in corners]
        features.append({"type": "Feature", "properties": {"name": name, "area": area},
                         "geometry": {"type": "Polygon", "coordinates": [[*ring, ring[0]]]}})
    return {"type": "FeatureCollection", "features": features}


def measurements(real: Path) -> pd.DataFrame:
    import msdc.asterix as asterix
    from msdc.pipeline.model.measurements import build_measurements
    from msdc.pipeline.model.sensors import read_sensors

    adsb = asterix.read(real / "adsb_v023_160510-lebl-220001.ast", editions={21: "0.23"}, date="2016-05-10")
    mlat = asterix.read(real / "mlat_160510-lebl-220001.ast", date="2016-05-10")
    smr = asterix.read(real / "smr_160510-lebl-220001.ast", date="2016-05-10")
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        path = Path(tmp) / "lebl.toml"
        path.write_text(sensors_toml())
        return build_measurements(None, adsb.frames[21], read_sensors(path), adsb_sigma_m=10.0,
                                  cat010=pd.concat([mlat.frames[10], smr.frames[10]], ignore_index=True),
                                  date="2016-05-10")


def check(meas: pd.DataFrame) -> None:
    """The shares of on-ground reports inside some area, per area, and of the fast ones on a runway."""
    from msdc.pipeline.evaluate.sectors import read_sectors, sector_mask

    sectors = read_sectors(EXAMPLE)
    lat, lon = meas["latitude"].to_numpy(float), meas["longitude"].to_numpy(float)
    masks = {s.name: sector_mask(s, lat, lon, meas["flight_level"].to_numpy(float)) for s in sectors}
    runway = np.logical_or.reduce([m for n, m in masks.items() if n.startswith("RWY")])
    taxiway = np.logical_or.reduce([m for n, m in masks.items() if n.startswith("TWY")])
    apron = np.logical_or.reduce([m for n, m in masks.items() if n.startswith("Apron")])
    anywhere = runway | taxiway | apron
    kind = meas["sensor_kind"].astype(str).to_numpy()
    ground = meas["on_ground"].astype("boolean").fillna(False).to_numpy(bool)
    monitor = meas["address"].isin(MONITORS).to_numpy(bool)
    speed = meas["ground_speed_kt"].to_numpy(float)
    rows = []
    for k in ("mlat", "adsb", "smr"):
        base = (kind == k) & ~monitor & np.isfinite(lat)
        on = base & ground if k != "smr" else base
        fast = on & (speed >= RUNWAY_SPEED_KT)
        moving = on & (speed > MOVING_KT)
        rows.append({"sensor": k, "reports": int(on.sum()), "in some area": anywhere[on].mean(),
                     f"moving (over {MOVING_KT:.0f} kt)": int(moving.sum()),
                     "of those in some area": anywhere[moving].mean() if moving.any() else np.nan,
                     "runway": runway[on].mean(), "taxiway": taxiway[on].mean(), "apron": apron[on].mean(),
                     f"at {RUNWAY_SPEED_KT:.0f} kt or more": int(fast.sum()),
                     "of those on a runway": runway[fast].mean() if fast.any() else np.nan})
    table = pd.DataFrame(rows)
    print("reports on the ground (multilateration, ADS-B: ground bit set; surface radar: every report; field "
          "monitors left out):")
    print(table.to_string(index=False, float_format=lambda v: f"{100 * v:.1f} %"))
    out = (kind == "mlat") & ~monitor & ground & np.isfinite(lat) & ~anywhere
    who = meas.loc[out].groupby("aircraft_id", observed=True).agg(
        reports=("latitude", "size"), callsign=("callsign", "first"), latitude=("latitude", "median"),
        longitude=("longitude", "median"), speed_kt=("ground_speed_kt", "median"))
    print("multilateration on-ground reports outside every area, by target (over 200 reports):")
    print(who[who["reports"] > 200].sort_values("reports", ascending=False).to_string())
    on = (kind == "mlat") & ~monitor & ground & np.isfinite(lat)
    fixed = who.index[who["speed_kt"].fillna(0.0) == 0.0].intersection(who.index[who["callsign"].isna()])
    vehicle = meas["callsign"].astype("string").str.fullmatch(r"F\d\d").fillna(False).to_numpy(bool)
    not_fixed = on & ~meas["aircraft_id"].astype(str).isin(fixed.astype(str)).to_numpy(bool)
    print(f"outside every area: fixed transponders without call sign ({', '.join(map(str, fixed))}) "
          f"{int((out & ~not_fixed).sum()):,}, vehicles (call signs F and two digits) "
          f"{int((out & vehicle).sum()):,} of their {int((on & vehicle).sum()):,}; in some area without the "
          "fixed transponders "
          f"{100 * anywhere[not_fixed].mean():.1f} %, without the vehicles too "
          f"{100 * anywhere[not_fixed & ~vehicle].mean():.1f} %")
    for k in ("mlat", "adsb"):
        on = (kind == k) & ~monitor & ground & np.isfinite(lat)
        per = {n: int(m[on].sum()) for n, m in masks.items()}
        print(f"{k}: on-ground reports per area: {per}")
    on = (kind == "adsb") & ground & (speed >= RUNWAY_SPEED_KT)
    off = on & ~runway
    if off.any():
        far = meas.loc[off, ["latitude", "longitude", "ground_speed_kt"]]
        print(f"fast ADS-B ground reports off every runway: {len(far)}; e.g.\n{far.head(5).to_string()}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("real", nargs="?", default=str(ROOT.parent / "shared" / "real"))
    ap.add_argument("--write", action="store_true", help=f"rewrite {EXAMPLE.relative_to(ROOT)}")
    args = ap.parse_args()
    if args.write:
        EXAMPLE.parent.mkdir(parents=True, exist_ok=True)
        text = re.sub(r"\[\s+(-?[\d.]+),\s+(-?[\d.]+)\s+\]", r"[\1, \2]", json.dumps(collection(), indent=1))
        EXAMPLE.write_text(text + "\n", encoding="utf-8")
        print(f"wrote {EXAMPLE}")
    real = Path(args.real)
    if not real.is_dir():
        print(f"{real}: no such folder; nothing checked", file=sys.stderr)
        return 1
    check(measurements(real))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
