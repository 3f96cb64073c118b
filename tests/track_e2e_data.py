"""End-to-end tracking against the project's simulator: two radars plus ADS-B, and the true position of
every aircraft at any instant (``SimAircraft.truth``). Shared by tests/test_track_integration.py (small
scenario) and benchmarks/track_e2e.py (the full default scenario)."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from pyproj import Geod

from fixtures.multiradar import TwoRadarSimulation, simulate_two_radars
from fixtures.scenario import DEFAULT_AIRCRAFT, Scenario, default_scenario
from msdc.pipeline.model.dedup import duplicate_mask
from msdc.pipeline.model.measurements import build_measurements
from msdc.pipeline.model.sensors import read_sensors

DATE = dt.date(2019, 3, 1)
MIDNIGHT = pd.Timestamp(DATE, tz="UTC")
R1, R2, ADSB = "048:25/201", "048:25/202", "021:0/1"
SITES = {R1: (2.7456, 101.7099), R2: (3.7754, 103.2094)}  # the two radars' sites (fixtures.multiradar)
_GEOD = Geod(ellps="WGS84")


def small_scenario() -> Scenario:
    """Two aircraft for 20 minutes, one ADS-B dropout of 200-300 s, radar 1 never drops out."""
    ac = tuple(replace(a, appearances=((0.0, 1200.0),)) for a in DEFAULT_AIRCRAFT[:2])
    return replace(default_scenario(), name="small", aircraft=ac, adsb_long_dropouts=1,
                   adsb_long_dropout_s=(200.0, 300.0), radar_long_dropouts=0,
                   adsb_low_quality_episodes=1, adsb_short_dropouts_per_hour=3.0)


@dataclass
class E2E:
    sim: TwoRadarSimulation
    measurements: pd.DataFrame  # measurement model, repeats dropped
    jump: np.ndarray  # per measurement row: an injected ADS-B position jump

    def truth_error_m(self, frame: pd.DataFrame) -> np.ndarray:
        """Horizontal distance (m, WGS-84 geodesic) of each row's latitude/longitude from the true position
        of its aircraft at its time; NaN where the aircraft is not flying."""
        tod = (frame["time"] - MIDNIGHT).dt.total_seconds().to_numpy(float)
        ident = frame["aircraft_id"].astype(str).to_numpy()
        out = np.full(len(frame), np.nan)
        for ac in self.sim.sim.aircraft:
            sel = ident == ac.spec.address_hex
            if sel.any():
                st = ac.truth(tod[sel])
                ok = np.isfinite(st.latitude)
                d = np.full(int(sel.sum()), np.nan)
                d[ok] = _GEOD.inv(frame["longitude"].to_numpy(float)[sel][ok], frame["latitude"].to_numpy(
                    float)[sel][ok], st.longitude[ok], st.latitude[ok])[2]
                out[sel] = d
        return out


def build(scenario: Scenario | None = None, seed: int = 2019, tmp: Path | None = None) -> E2E:
    """Simulate, and build the measurement model from the frames with the two radars' sensor file."""
    m = simulate_two_radars(scenario, seed=seed)
    path = (tmp or Path("/tmp")) / f"e2e_sensors_{seed}.toml"
    path.write_text(m.sensors_toml())
    radar = pd.concat([m.sim.radar, m.radar2], ignore_index=True)
    meas = build_measurements(radar, m.sim.adsb, read_sensors(path), date=DATE)
    dup = duplicate_mask(meas.sort_values("time", kind="stable")).reindex(meas.index).to_numpy(bool)
    meas = meas[~dup].reset_index(drop=True)
    # injected jumps: ADS-B reports whose position is more than 0.05 deg from the truth (jumps are 0.1-6 deg)
    e = E2E(m, meas, np.zeros(len(meas), bool))
    err = e.truth_error_m(meas)
    e.jump = (meas["sensor_kind"] == "adsb").to_numpy() & (err > 5000.0)
    return e


def rms(x: np.ndarray) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x**2))) if len(x) else float("nan")


def figures(e: E2E, smooth: bool = False) -> dict:
    """RMS errors (m) of each sensor's reports and of the tracks built from several source sets; the
    two-radar comparison is made on each single-radar track's own output times."""
    from msdc.pipeline.track import track

    meas = e.measurements
    err = e.truth_error_m(meas)
    sensor = meas["sensor_id"].to_numpy(str)
    out: dict = {"reports": {}, "tracks": {}}
    for sid in (ADSB, R1, R2):
        sel = sensor == sid
        out["reports"][sid] = rms(err[sel & ~e.jump])
    out["reports"]["adsb_with_jumps"] = rms(err[sensor == ADSB])
    tracks = {}
    for name, keep in (("fused", np.ones(len(meas), bool)), ("radars", sensor != ADSB),
                       ("radar1", sensor == R1), ("radar2", sensor == R2)):
        tr = track(meas[keep], smooth=smooth).tracks
        tr = tr.assign(error_m=e.truth_error_m(tr))
        tracks[name] = tr
        out["tracks"][name] = rms(tr["error_m"])
    fused = tracks["fused"]
    for sid in (ADSB, R1, R2):  # the fused track at the instants this sensor reported (apples to apples)
        at = fused["sources"].str.split(",").apply(lambda s, sid=sid: sid in s).to_numpy(bool)
        out["tracks"][f"fused_at_{sid}"] = rms(fused.loc[at, "error_m"])
    for single in ("radar1", "radar2"):
        both = tracks["radars"].set_index(["aircraft_id", "time"])["error_m"]
        one = tracks[single].set_index(["aircraft_id", "time"])["error_m"]
        common = one.index.intersection(both.index)
        out["tracks"][f"radars_on_{single}_times"] = rms(both.loc[common].to_numpy())
        out["tracks"][f"{single}_on_common_times"] = rms(one.loc[common].to_numpy())
    out["_tracks"] = tracks
    return out
