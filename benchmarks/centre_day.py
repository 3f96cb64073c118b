"""A day of a surveillance centre, simulated and ingested: 10 radars (4-12 s scans, CAT048 plots and CAT034
north markers) and 2 ADS-B ground stations (CAT021, each aircraft at 1-2 Hz), over a traffic that peaks at
``--peak`` aircraft in the air; then ``msdc ingest`` of it with 1 and 2 workers (issue 29).

Run by hand (never a timed test):

    python benchmarks/centre_day.py --hours 1 --out /work/bench-data      # generate (cached), then ingest
    python benchmarks/centre_day.py --hours 6 --out /work/bench-data --generate-only
    python benchmarks/centre_day.py --hours 6 --out /work/bench-data --datasets /tmp/ds   # datasets elsewhere
    python benchmarks/centre_day.py --days 7 --out /work/bench-data --workers 2   # a week into one dataset

The recordings go to ``OUT/centre-{hours}h-seed{seed}/``: one raw file per sensor (``radar_20_01.ast`` ...,
``adsb_0_1.ast``), written hour by hour in time order, the radars' ``sensors.toml`` and ``scenario.json``
(the parameters, the date to give ``--date``, the records per file). A rerun with the same parameters
reuses them. The window is centred on the traffic peak (14:00 UTC): 1 h is 13:30-14:30, 6 h 11:00-17:00,
24 h the whole day, so a shorter window is a part of the same day's traffic.

The traffic is the simulator's (fixtures/): each flight is ``fixtures.flight.plan_flight``'s random
waypoint flight around the centre, flown by its exact segment kinematics, evaluated for all the flights of
an hour at once; positions go to WGS-84 and to each sensor's slant range and azimuth with
``fixtures.geodesy``, values are quantised to the ASTERIX LSBs as ``fixtures.simulate`` does, and the frames
are encoded with ``msdc.asterix.encode``. A radar reports an aircraft once per scan, when its beam crosses
it (with 70 m / 0.08 deg noise, 97 % detection, within its range and above -1 deg of elevation, both
declared in the sensor file); each aircraft sends its ADS-B position every 0.5-1 s and each ground station
relays the messages of the aircraft within 250 NM of it, so where the two stations overlap they relay the
same messages, as real ground stations do (before generator 3 each station drew its own 1-2 Hz, as if an
aircraft seen by both sent 2-4 positions a second).

The ingest measurements are those of ``benchmarks/ingest.py`` (a fresh process per run into an empty
dataset; peak RSS of the main process and of the largest worker; CPU of the process tree).
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from fixtures import geodesy as geo  # noqa: E402
from fixtures.flight import Flight, _kinematics, plan_flight  # noqa: E402
from fixtures.scenario import RadarSite  # noqa: E402
from fixtures.simulate import (  # noqa: E402
    FL_LSB,
    HEIGHT_LSB_FT,
    LATLON_LSB_DEG,
    RADAR_TYP_MODE_S_ROLL_CALL,
    RHO_LSB_NM,
    TOD_LSB_S,
    _q,
    _q_angle,
    _q_lon,
    _q_speed_kt,
    sensors_toml,
)

DATE = "2026-11-28"
CENTRE = (46.0, 2.5)  # latitude, longitude of the flights' tangent plane
HOUR_S = 3600.0
DAY_S = 86400.0
PEAK_TOD_S = 14 * HOUR_S
FLIGHT_S = (2400.0, 5400.0)  # flight durations: 40-90 min
FLIGHT_RANGE_NM = (20.0, 330.0)  # flights stay this far from the centre
ADSB_INTERVAL_S = (0.5, 1.0)  # 1-2 Hz
ADSB_RANGE_NM = 250.0
ADSB_SIGMA_M = 5.0
DETECTION = 0.97
MIN_ELEVATION_DEG = -1.0  # a radar sees no aircraft below this elevation from its site (the Earth's bulge)
SIGMA_RANGE_M, SIGMA_AZIMUTH_DEG = 70.0, 0.08
RECORDS_PER_BLOCK = 25
GENERATOR = 3  # recordings made by an earlier version are made again (2: one plot per crossing; 3: the
# ground stations relay the same ADS-B messages, 1-2 Hz an aircraft, not 1-2 Hz each drawn apart)
# (east NM, north NM of the centre, scan period s, range NM): approach radars turn fast and see less
RADARS = [(-200, -100, 10.0, 250.0), (-200, 100, 12.0, 250.0), (-70, -180, 8.0, 200.0), (-40, 10, 4.0, 80.0),
          (-70, 180, 8.0, 200.0), (70, -180, 6.0, 200.0), (50, -20, 5.0, 100.0), (70, 180, 10.0, 250.0),
          (200, -100, 12.0, 250.0), (200, 100, 6.0, 200.0)]
STATIONS = [(-100, 0), (100, 0)]  # ADS-B ground stations, east and north NM of the centre


@dataclass(frozen=True)
class Radar:
    """A radar of the centre: its site, scan period, range and the time its beam points north."""

    site: RadarSite
    period_s: float
    range_nm: float
    north_s: float


def _site(name: str, sac: int, sic: int, east_nm: float, north_nm: float, altitude_m: float) -> RadarSite:
    lat, lon = geo.plane_to_geodetic(east_nm * geo.M_PER_NM, north_nm * geo.M_PER_NM, *CENTRE)
    return RadarSite(name=name, sac=sac, sic=sic, latitude=round(float(lat), 6),
                     longitude=round(float(lon), 6), altitude_m=altitude_m)


def sensors(seed: int) -> tuple[list[Radar], list[RadarSite]]:
    """The 10 radars (SAC 20, SIC 1-10) and 2 ADS-B stations (SAC 0, SIC 1-2)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))
    radars = [Radar(_site(f"Radar {k + 1}", 20, k + 1, e, n, 100.0), p, r, float(rng.uniform(0.0, p)))
              for k, (e, n, p, r) in enumerate(RADARS)]
    stations = [_site(f"ADS-B {k + 1}", 0, k + 1, e, n, 50.0) for k, (e, n) in enumerate(STATIONS)]
    return radars, stations


def airborne_target(tod_s: np.ndarray, peak: int) -> np.ndarray:
    """Aircraft in the air wanted at each time of day: 20 % of the peak at night, rising from 05:00 to the
    peak at 14:00 and back by 23:00."""
    w = np.clip((tod_s - 5 * HOUR_S) / (18 * HOUR_S), 0.0, 1.0)
    return peak * (0.2 + 0.8 * np.sin(np.pi * w) ** 2)


def schedule(peak: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Every flight of the day: start times (s; from 90 min before midnight, so the night starts with
    aircraft in the air) and durations, drawn so that the airborne count follows airborne_target."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0]))
    grid = np.arange(-FLIGHT_S[1], DAY_S, 60.0)
    rate = airborne_target(np.mod(grid, DAY_S), peak) / np.mean(FLIGHT_S)  # flights started per second
    cum = np.concatenate([[0.0], np.cumsum(rate * 60.0)])
    n = int(rng.poisson(cum[-1]))
    start = np.sort(np.interp(rng.uniform(0.0, cum[-1], n), cum, np.append(grid, DAY_S)))
    return start, rng.uniform(*FLIGHT_S, n)


class Fleet:
    """Flights evaluated all at once: their segment tables laid end to end (a flight's segments sorted by
    start time, the flights by index), so one searchsorted finds the segment of every (flight, time)."""

    def __init__(self, flights: list[Flight], ids: np.ndarray) -> None:
        tabs = [f._table() for f in flights]
        counts = np.array([len(t["t0"]) for t in tabs])
        self.ids = ids
        self.first = np.concatenate([[0], np.cumsum(counts)[:-1]])
        self.tab = {k: np.concatenate([t[k] for t in tabs]) for k in tabs[0]}
        self.key = np.repeat(np.arange(len(flights)) * 1e6, counts) + self.tab["t0"]
        self.start = np.array([f.start_s for f in flights])
        self.end = np.array([f.end_s for f in flights])

    def state(self, k: np.ndarray, t: np.ndarray) -> dict[str, np.ndarray]:
        """Latitude, longitude, pressure altitude (ft), height (m), plane speed (kt) and track of flights
        ``k`` (positions in this fleet) at times ``t``."""
        i = np.maximum(np.searchsorted(self.key, k * 1e6 + t, side="right") - 1, self.first[k])
        tab = self.tab
        dt = t - tab["t0"][i]
        e, n, trk, v = _kinematics(tab["e0"][i], tab["n0"][i], tab["trk0"][i], tab["v0"][i], dt,
                                   tab["rate"][i], tab["acc"][i])
        alt_ft = tab["alt0"][i] + tab["vr"][i] * dt / 60.0
        lat, lon = geo.plane_to_geodetic(e, n, *CENTRE)
        return {"latitude": lat, "longitude": lon, "alt_ft": alt_ft, "height_m": alt_ft * geo.M_PER_FT,
                "speed_kt": v / geo.KT_TO_MS, "track_deg": trk}


def fleet_of(starts: np.ndarray, durations: np.ndarray, ids: np.ndarray, seed: int,
             cache: dict[int, Flight]) -> Fleet:
    """The flights ``ids`` planned (each from its own random stream, so any window of the day flies the
    same flights), kept in ``cache`` across hours."""
    for i in ids:
        if i not in cache:
            rng = np.random.default_rng(np.random.SeedSequence([seed, 2, int(i)]))
            cache[int(i)] = plan_flight(rng, float(starts[i]), float(durations[i]), range_nm=FLIGHT_RANGE_NM)
    return Fleet([cache[int(i)] for i in ids], ids)


def _identity(ids: np.ndarray) -> dict[str, np.ndarray]:
    """Address, callsign and Mode 3/A of flights ``ids`` (one aircraft per flight), each formatted once per
    flight."""
    flights, rows = np.unique(ids, return_inverse=True)
    return {"address": np.array([f"{0x400000 + i:06X}" for i in flights], dtype=object)[rows],
            "callsign": np.array([f"CTR{i:05d}" for i in flights], dtype=object)[rows],
            "mode3a": np.array([f"{i % 4096:04o}" for i in flights], dtype=object)[rows]}


@dataclass
class AdsbMessages:
    """The fleet's ADS-B position messages in a time span, as every ground station in range receives them:
    flight index k, time t (s of the day), the true state and the reported (noisy) position."""

    k: np.ndarray
    t: np.ndarray
    state: dict[str, np.ndarray]
    latitude: np.ndarray
    longitude: np.ndarray


def adsb_messages(fleet: Fleet, t0: float, t1: float, rng: np.random.Generator) -> AdsbMessages:
    """Each flight's ADS-B position messages in [t0, t1): one every 0.5-1 s (1-2 Hz), its position with the
    aircraft's navigation error drawn once per message (every station that receives it relays the same)."""
    lo = np.maximum(fleet.start, t0)
    hi = np.minimum(fleet.end, t1)
    room = np.maximum(hi - lo, 0.0)
    counts = np.ceil(room / ADSB_INTERVAL_S[0]).astype(np.int64) + 1
    k = np.repeat(np.arange(len(lo)), counts)
    step = rng.uniform(*ADSB_INTERVAL_S, len(k))
    step[np.concatenate([[0], np.cumsum(counts)[:-1]])] = rng.uniform(0.0, ADSB_INTERVAL_S[1], len(lo))
    t = np.cumsum(step)
    t -= np.repeat(np.concatenate([[0.0], t[np.cumsum(counts)[:-1] - 1]]), counts)  # restart per flight
    t = _q(lo[k] + t, TOD_LSB_S)
    keep = t < hi[k]
    k, t = k[keep], t[keep]
    order = np.lexsort((k, t))
    k, t = k[order], t[order]
    st = fleet.state(k, t)
    n = len(t)
    lat, lon = geo.offset_geodetic(st["latitude"], st["longitude"], st["height_m"],
                                   rng.normal(0.0, ADSB_SIGMA_M, n), rng.normal(0.0, ADSB_SIGMA_M, n))
    return AdsbMessages(k, t, st, lat, lon)


def adsb_frame(fleet: Fleet, messages: AdsbMessages, station: RadarSite) -> pd.DataFrame:
    """CAT021 reports of the station: the messages of the flights within 250 NM of it."""
    st = messages.state
    slant_m, _, _ = geo.polar_from_site(st["latitude"], st["longitude"], st["height_m"], station.latitude,
                                        station.longitude, station.altitude_m)
    seen = slant_m <= ADSB_RANGE_NM * geo.M_PER_NM
    k, t, st = messages.k[seen], messages.t[seen], {c: v[seen] for c, v in st.items()}
    lat, lon = messages.latitude[seen], messages.longitude[seen]
    n = len(t)
    ident = _identity(fleet.ids[k])
    return pd.DataFrame({
        "sac": np.full(n, station.sac), "sic": np.full(n, station.sic), "time_of_day": t,
        "latitude": _q(lat, LATLON_LSB_DEG), "longitude": _q_lon(lon), **ident,
        "flight_level": _q(st["alt_ft"] / 100.0, FL_LSB),
        "geometric_height_ft": _q(st["height_m"] / geo.M_PER_FT, HEIGHT_LSB_FT),
        "ground_speed_kt": _q_speed_kt(st["speed_kt"]), "track_angle_deg": _q_angle(st["track_deg"]),
        "track_number": fleet.ids[k] % 4000 + 1, "nucp_nic": np.full(n, 8), "nucr_nacv": np.full(n, 2),
        "nacp": np.full(n, 9), "sil": np.full(n, 3), "nic_baro": np.full(n, 1),
        "mops_version": np.full(n, 2)})


def radar_frame(fleet: Fleet, radar: Radar, t0: float, t1: float, rng: np.random.Generator) -> pd.DataFrame:
    """CAT048 plots of the radar in [t0, t1): one per scan per flight within range, at the time the beam
    crosses the aircraft (solved by fixed-point iteration on its azimuth)."""
    site, period = radar.site, radar.period_s
    first = int(np.floor((t0 - radar.north_s) / period)) - 1
    last = int(np.ceil((t1 - radar.north_s) / period)) + 1
    active = np.flatnonzero((fleet.start < t1) & (fleet.end > t0))
    scans = np.arange(first, last + 1)
    k = np.repeat(active, len(scans))
    scan = np.tile(scans, len(active))
    north = radar.north_s + scan * period
    inside = (north + period > fleet.start[k]) & (north < fleet.end[k])
    k, north = k[inside], north[inside]

    def azimuth(t: np.ndarray) -> tuple[np.ndarray, ...]:
        st = fleet.state(k, t)
        slant, az, el = geo.polar_from_site(st["latitude"], st["longitude"], st["height_m"], site.latitude,
                                            site.longitude, site.altitude_m)
        return az, slant, el, st

    az = azimuth(north)[0]
    for _ in range(3):  # the beam turns 360 deg a scan, the aircraft's azimuth a fraction of a degree
        t = north + period * az / 360.0
        new = azimuth(t)[0]
        az = az + (new - az + 180.0) % 360.0 - 180.0
    t = north + period * az / 360.0
    az, slant, el, st = azimuth(t)
    # a crossing belongs to the scan whose turn it falls in: an aircraft on the north azimuth solves to the
    # end of one scan and the start of the next, the same crossing twice
    keep = ((t >= t0) & (t < t1) & (t >= fleet.start[k]) & (t <= fleet.end[k]) & (el > MIN_ELEVATION_DEG)
            & (t >= north) & (t < north + period)
            & (slant <= radar.range_nm * geo.M_PER_NM) & (rng.uniform(size=len(t)) < DETECTION))
    k, t, az, slant = k[keep], t[keep], az[keep], slant[keep]
    st = {c: v[keep] for c, v in st.items()}
    n = len(t)
    t_rep = _q(t, TOD_LSB_S)
    order = np.lexsort((k, t_rep))
    k, t_rep, az, slant = k[order], t_rep[order], az[order], slant[order]
    st = {c: v[order] for c, v in st.items()}
    rho = _q((slant + rng.normal(0.0, SIGMA_RANGE_M, n)) / geo.M_PER_NM, RHO_LSB_NM)
    theta = _q_angle(az + rng.normal(0.0, SIGMA_AZIMUTH_DEG, n))
    ident = _identity(fleet.ids[k])
    return pd.DataFrame({
        "sac": np.full(n, site.sac), "sic": np.full(n, site.sic), "time_of_day": t_rep,
        "typ": np.full(n, RADAR_TYP_MODE_S_ROLL_CALL), "rho_nm": np.minimum(rho, 255.99), "theta_deg": theta,
        "mode3a": ident["mode3a"], "flight_level": _q(st["alt_ft"] / 100.0, FL_LSB),
        "address": ident["address"], "callsign": ident["callsign"],
        "track_number": fleet.ids[k] % 4000 + 1, "ground_speed_kt": _q_speed_kt(st["speed_kt"]),
        "heading_deg": _q_angle(st["track_deg"])})


def _fixed_records(category: int, frame: pd.DataFrame) -> np.ndarray:
    """The frame's records as rows of bytes (every record of these frames has the same items, so the same
    length: checked)."""
    from msdc.asterix.encode import encode_frame

    if not len(frame):
        return np.zeros((0, 0), np.uint8)
    raw = np.frombuffer(encode_frame(category, frame, records_per_block=1), np.uint8)
    size = int(raw[1]) << 8 | int(raw[2])
    if len(raw) != size * len(frame):
        raise ValueError(f"CAT{category:03d} records of unequal lengths: cannot cut them apart")
    return raw.reshape(len(frame), size)[:, 3:]


def radar_bytes(frame: pd.DataFrame, radar: Radar, t0: float, t1: float) -> bytes:
    """The radar's hour in time order: each scan's CAT034 north marker, then that scan's CAT048 plots in
    data blocks of at most RECORDS_PER_BLOCK (a block never spans a north marker)."""
    period = radar.period_s
    scans = np.arange(np.ceil((t0 - radar.north_s) / period), np.ceil((t1 - radar.north_s) / period))
    north_tod = _q(radar.north_s + scans * period, TOD_LSB_S)
    north_tod = north_tod[(north_tod >= t0) & (north_tod < t1)]
    markers = _fixed_records(34, pd.DataFrame({
        "sac": np.full(len(north_tod), radar.site.sac), "sic": np.full(len(north_tod), radar.site.sic),
        "message_type": np.full(len(north_tod), 1), "time_of_day": np.mod(north_tod, DAY_S),
        "antenna_rotation_period_s": np.full(len(north_tod), period)}))
    plots = _fixed_records(48, frame.assign(time_of_day=np.mod(frame["time_of_day"], DAY_S)))
    cut = np.searchsorted(frame["time_of_day"].to_numpy(), north_tod, side="left")
    bounds = np.concatenate([[0], cut, [len(frame)]])
    out = []
    for j in range(len(bounds) - 1):
        if j > 0:
            out.append(bytes([34, 0, 3 + markers.shape[1]]) + markers[j - 1].tobytes())
        for a in range(int(bounds[j]), int(bounds[j + 1]), RECORDS_PER_BLOCK):
            b = min(a + RECORDS_PER_BLOCK, int(bounds[j + 1]))
            size = 3 + (b - a) * plots.shape[1]
            out.append(bytes([48, size >> 8, size & 0xFF]) + plots[a:b].tobytes())
    return b"".join(out)


def window(hours: int) -> tuple[float, float]:
    """The simulated window: ``hours`` centred on the traffic peak, within the day."""
    if hours >= 24:
        return 0.0, DAY_S
    t0 = min(max(PEAK_TOD_S - hours * HOUR_S / 2, 0.0), DAY_S - hours * HOUR_S)
    return t0, t0 + hours * HOUR_S


def generate(out: Path, hours: int, peak: int, seed: int, date: str = DATE) -> dict:
    """Write the recordings of the window into ``out`` (made anew) and return scenario.json's content
    (``date``: the day they are said to be of; the traffic is the seed's whatever the date)."""
    from msdc.asterix.encode import encode_frame

    radars, stations = sensors(seed)
    starts, durations = schedule(peak, seed)
    t0, t1 = window(hours)
    tmp = out.with_name(out.name + ".part")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    names = {**{r.site.sic: f"radar_{r.site.sac}_{r.site.sic:02d}.ast" for r in radars}}
    files = {f"r{r.site.sic}": open(tmp / names[r.site.sic], "wb") for r in radars}  # noqa: SIM115
    files |= {f"a{s.sic}": open(tmp / f"adsb_{s.sac}_{s.sic}.ast", "wb") for s in stations}  # noqa: SIM115
    counts: dict[str, int] = {}
    cache: dict[int, Flight] = {}
    peak_seen = 0
    began = time.perf_counter()
    try:
        for h0 in np.arange(t0, t1, HOUR_S):
            h1 = min(h0 + HOUR_S, t1)
            ids = np.flatnonzero((starts < h1) & (starts + durations > h0))
            mids = np.arange(h0, h1, 60.0)
            flying = max(((starts <= m) & (starts + durations > m)).sum() for m in mids)
            peak_seen = max(peak_seen, int(flying))
            fleet = fleet_of(starts, durations, ids, seed, cache)
            for i in [i for i in cache if starts[i] + durations[i] <= h0]:
                del cache[i]
            rng = np.random.default_rng(np.random.SeedSequence([seed, 3, int(h0)]))
            messages = adsb_messages(fleet, h0, h1, rng)
            for s in stations:
                frame = adsb_frame(fleet, messages, s)
                tod = np.mod(frame["time_of_day"], DAY_S)
                files[f"a{s.sic}"].write(encode_frame(21, frame.assign(time_of_day=tod),
                                                      records_per_block=RECORDS_PER_BLOCK))
                counts[f"adsb_{s.sac}_{s.sic}.ast"] = counts.get(f"adsb_{s.sac}_{s.sic}.ast", 0) + len(frame)
            for r in radars:
                frame = radar_frame(fleet, r, h0, h1, rng)
                files[f"r{r.site.sic}"].write(radar_bytes(frame, r, h0, h1))
                counts[names[r.site.sic]] = counts.get(names[r.site.sic], 0) + len(frame)
            done = sum(counts.values()) / 1e6
            print(f"  {h0 / HOUR_S:05.2f} h: {len(ids)} flights, {done:.1f} M records so far"
                  f" ({time.perf_counter() - began:.0f} s)", flush=True)
    finally:
        for fh in files.values():
            fh.close()
    (tmp / "sensors.toml").write_text(sensors_text(radars))
    meta = {"generator": GENERATOR, "hours": hours, "peak": peak, "seed": seed, "date": date,
            "from_tod_s": t0, "to_tod_s": t1,
            "airborne_peak_seen": peak_seen,
            "flights": int(((starts < t1) & (starts + durations > t0)).sum()),
            "records": counts, "records_total": sum(counts.values()),
            "radars": [{"sac": r.site.sac, "sic": r.site.sic, "scan_period_s": r.period_s,
                        "max_range_nm": r.range_nm} for r in radars],
            "generated_s": round(time.perf_counter() - began, 1)}
    (tmp / "scenario.json").write_text(json.dumps(meta, indent=1) + "\n")
    shutil.rmtree(out, ignore_errors=True)
    tmp.rename(out)
    return meta


def sensors_text(radars: list[Radar]) -> str:
    """The sensor file of the radars: site, noise and coverage as simulated (range and lowest elevation)."""
    return "".join(sensors_toml(r.site) + f"sigma_range_m = {SIGMA_RANGE_M!r}\n"
                   f"sigma_azimuth_deg = {SIGMA_AZIMUTH_DEG!r}\nmax_range_nm = {r.range_nm!r}\n"
                   f"min_elevation_deg = {MIN_ELEVATION_DEG!r}\n\n" for r in radars)


def recordings(base: Path, hours: int, peak: int, seed: int, date: str = DATE) -> tuple[Path, dict]:
    """The window's folder and scenario, generated unless a previous run left them for these parameters
    (their sensor file written again: it describes the simulation, whichever version wrote the folder)."""
    name = f"centre-{hours}h-seed{seed}" if peak == 450 else f"centre-{hours}h-peak{peak}-seed{seed}"
    out = base / (name if date == DATE else f"{name}-{date}")
    meta_path = out / "scenario.json"
    if meta_path.exists():
        meta = json.loads(meta_path.read_text())
        wanted = (GENERATOR, hours, peak, seed, date)
        if (meta.get("generator"), meta["hours"], meta["peak"], meta["seed"], meta["date"]) == wanted:
            (out / "sensors.toml").write_text(sensors_text(sensors(seed)[0]))
            return out, meta
    print(f"generating {out} ...", flush=True)
    return out, generate(out, hours, peak, seed, date)


def days(args) -> None:
    """--days N: N whole days (day k: seed + k, dated DATE + k days) ingested one after the other into one
    dataset with the last of --workers, each day's figures as the dataset grows; then the same inputs
    again, which must do nothing."""
    from ingest import MEASURE, read_through

    workers = args.workers[-1]
    root = (args.datasets or args.out) / f"dataset-{args.days}d-w{workers}"
    shutil.rmtree(root, ignore_errors=True)
    made = []
    for k in range(args.days):
        date = str(pd.Timestamp(DATE).date() + pd.Timedelta(days=k))
        made.append(recordings(args.out, 24, args.peak, args.seed + k, date))
    if args.generate_only:
        return
    total_records = total_s = 0.0
    for again in (False, True):
        for folder, meta in made:
            inputs = sorted(folder.glob("*.ast"))
            for p in inputs:
                read_through(p)
            done = subprocess.run([sys.executable, "-c", MEASURE, json.dumps([str(p) for p in inputs]),
                                   str(root), str(workers), str(args.chunk_mb), meta["date"]],
                                  capture_output=True, text=True)
            if done.returncode:
                print(done.stderr[-3000:])
                raise SystemExit(f"ingest of {meta['date']} failed")
            m = json.loads(done.stdout.strip().splitlines()[-1])
            parts = sum(1 for _ in root.rglob("*.parquet"))
            if again:
                print(f"{meta['date']} again: {m['records']} records ingested in {m['seconds']:.1f} s "
                      f"(nothing to do), peak RSS main {m['main_rss_mb']:.0f} MB", flush=True)
                continue
            total_records += m["records"]
            total_s += m["seconds"]
            print(f"{meta['date']}: {m['records']} records in {m['seconds']:.1f} s = "
                  f"{m['records'] / m['seconds'] / 1e6:.2f} M records/s; dataset now {parts} parts, "
                  f"{m['dataset_mb']:.0f} MB; peak RSS main {m['main_rss_mb']:.0f} MB, largest worker "
                  f"{m['worker_rss_mb']:.0f} MB; CPU {m['cpu_s']:.1f} s", flush=True)
    print(f"{args.days} days: {total_records / 1e6:.1f} M records in {total_s:.0f} s = "
          f"{total_records / total_s / 1e6:.2f} M records/s with {workers} workers", flush=True)


def main() -> None:
    from ingest import MEASURE, read_through

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=int, choices=(1, 6, 24), default=1)
    parser.add_argument("--out", type=Path, default=Path("/work/bench-data"))
    parser.add_argument("--peak", type=int, default=450, help="aircraft in the air at the peak (300-600)")
    parser.add_argument("--seed", type=int, default=29)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--chunk-mb", type=float, default=16.0)
    parser.add_argument("--generate-only", action="store_true")
    parser.add_argument("--datasets", type=Path, default=None,
                        help="where the ingests write their datasets (default: --out)")
    parser.add_argument("--days", type=int, default=None,
                        help="N whole days into one dataset (day k: seed + k, dated DATE + k days)")
    args = parser.parse_args()
    if args.days:
        days(args)
        return
    t = time.perf_counter()
    folder, meta = recordings(args.out, args.hours, args.peak, args.seed)
    inputs = sorted(folder.glob("*.ast"))
    size = sum(p.stat().st_size for p in inputs)
    print(f"{folder}: {len(inputs)} files, {size / 1e9:.2f} GB, {meta['records_total'] / 1e6:.1f} M records "
          f"({', '.join(f'{k}: {v}' for k, v in sorted(meta['records'].items()))}); {meta['flights']} "
          f"flights, "
          f"{meta['airborne_peak_seen']} in the air at the most; ready in {time.perf_counter() - t:.0f} s "
          f"(generated in {meta['generated_s']} s)", flush=True)
    if args.generate_only:
        return
    for p in inputs:
        read_through(p)  # in the page cache, as far as it fits
    base = None
    for workers in args.workers:
        root = (args.datasets or args.out) / f"dataset-{args.hours}h-w{workers}"
        shutil.rmtree(root, ignore_errors=True)
        load = __import__("os").getloadavg()[0]
        done = subprocess.run([sys.executable, "-c", MEASURE, json.dumps([str(p) for p in inputs]), str(root),
                               str(workers), str(args.chunk_mb), meta["date"]],
                              capture_output=True, text=True)
        if done.returncode:
            print(done.stderr[-3000:])
            raise SystemExit(f"ingest with {workers} worker(s) failed")
        m = json.loads(done.stdout.strip().splitlines()[-1])
        rate = m["records"] / m["seconds"]
        base = base or rate
        print(f"workers {workers}: {m['records']} records in {m['seconds']:.1f} s = {rate / 1e6:.2f} M "
              f"records/s (x{rate / base:.2f}), {m['parts']} parts, {m['dataset_mb']:.0f} MB; peak RSS main "
              f"{m['main_rss_mb']:.0f} MB, largest worker {m['worker_rss_mb']:.0f} MB; "
              f"CPU {m['cpu_s']:.1f} s = {m['records'] / m['cpu_s'] / 1e6:.2f} M records per CPU-second "
              f"(load {load:.1f} before)",
              flush=True)
        if workers != args.workers[-1]:
            shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
