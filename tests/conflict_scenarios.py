"""Simulated encounters for the conflict job: real losses of separation (converging, overtaking, climbing
and descending through a level) and near misses that keep separation (6 NM crossing, 6 NM head-on,
levelling off 1000 ft below), each flown by the project's simulator (radar + ADS-B recordings) and run
through decode -> track -> predict -> PC -> events by `conflict_job`.

Each scenario carries its loss window worked out by hand from the straight-line geometry (closed forms
in the comments); times are seconds after midnight (the flights start at 0 s). Speeds in NM/s are
kt / 3600. Shared by tests/test_conflict_scenarios.py and benchmarks/conflict_scenarios.py.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, replace
from pathlib import Path

from fixtures.flight import Flight, Segment
from fixtures.scenario import AircraftSpec, default_scenario
from fixtures.simulate import sensors_toml, simulate
from msdc.asterix.encode import encode_frame

DATE = dt.date(2019, 3, 1)
RADIUS_NM = 5.0
T_C = 400.0  # the encounter's reference time (s): closest point of the horizontal geometry
# where the encounters happen, NM east and north of the radar: away from the radar's overhead cone
# (a plot whose slant range is below the aircraft's height gets a degenerate covariance, see the notes)
CENTRE_NM = (30.0, 20.0)


@dataclass(frozen=True)
class Encounter:
    """Two aircraft and what the geometry says: the loss window (start, end) in s, or None."""

    name: str
    a: Flight
    b: Flight
    loss_s: tuple[float, float] | None
    note: str


def _start(point_nm, track_deg: float, speed_kt: float, at_s: float) -> tuple[float, float]:
    """Where a straight flight must start (east, north NM of the radar at 0 s) to pass point_nm (NM from
    CENTRE_NM) at at_s."""
    d = speed_kt / 3600.0 * at_s
    psi = math.radians(track_deg)
    return (CENTRE_NM[0] + point_nm[0] - d * math.sin(psi), CENTRE_NM[1] + point_nm[1] - d * math.cos(psi))


def _straight(point_nm, track_deg, speed_kt, alt_ft, duration_s=600.0, segments=None) -> Flight:
    e, n = _start(point_nm, track_deg, speed_kt, T_C)
    return Flight(0.0, e, n, alt_ft, speed_kt, track_deg, segments or (Segment(duration_s),))


def encounters() -> list[Encounter]:
    out = []
    # converging at 30 deg, both 450 kt, meeting at the origin at T_C: |r| = |dv| |t - T_C| with
    # |dv| = 2 * 450 sin(15 deg) kt, so the loss is T_C -+ 5 / |dv|
    dv = 2 * 450.0 * math.sin(math.radians(15.0)) / 3600.0
    out.append(Encounter("converging 30 deg", _straight((0, 0), 90.0, 450.0, 35000.0),
                         _straight((0, 0), 60.0, 450.0, 35000.0), (T_C - 5 / dv, T_C + 5 / dv),
                         "FL350, 450 kt each, tracks 090 and 060, same point at 400 s"))
    # overtaking: both track 090 at FL350, A 480 kt from (-30, 0), B 400 kt from (-20, 2) NM from the
    # centre: r = (10 - dv t, 2) with dv = 80 kt, |r| < 5 while |10 - dv t| < sqrt(21)
    dv = 80.0 / 3600.0
    out.append(Encounter("overtaking 2 NM abeam",
                         Flight(0.0, CENTRE_NM[0] - 30.0, CENTRE_NM[1], 35000.0, 480.0, 90.0,
                                (Segment(720.0),)),
                         Flight(0.0, CENTRE_NM[0] - 20.0, CENTRE_NM[1] + 2.0, 35000.0, 400.0, 90.0,
                                (Segment(720.0),)),
                         ((10 - math.sqrt(21)) / dv, (10 + math.sqrt(21)) / dv),
                         "FL350, 480 kt overtaking 400 kt, 2 NM abeam"))
    # 90 deg crossing at 420 kt over the origin at T_C: horizontal |r| = sqrt(2) 420 |t - T_C| < 5 NM for
    # |t - T_C| < 30.3 s. B climbs (descends) at 2000 fpm from 330 s: closer than 1000 ft less the
    # 25 ft tolerance to A's FL350 from 330 + (3000 - 975) / (2000 / 60) = 390.75 s to 449.25 s; the
    # loss is (390.75, T_C + 30.3)
    half = 5.0 / (math.sqrt(2) * 420.0 / 3600.0)
    for name, alt0, rate in (("climbing through FL350", 32000.0, 2000.0),
                             ("descending through FL350", 38000.0, -2000.0)):
        b = _straight((0, 0), 0.0, 420.0, alt0,
                      segments=(Segment(330.0), Segment(120.0, vertical_rate_fpm=rate), Segment(150.0)))
        out.append(Encounter(name, _straight((0, 0), 90.0, 420.0, 35000.0), b, (390.75, T_C + half),
                             "90 deg crossing at 420 kt over the same point at 400 s; "
                             f"B from FL{alt0 / 100:.0f} at {rate:+.0f} fpm from 330 s"))
    # near misses. 90 deg crossing, B passing 6 NM from A at T_C: at T_C, r = B - A is perpendicular to
    # the relative velocity (-1, 1), i.e. along (1, 1) / sqrt(2), 6 NM long
    off = 6.0 / math.sqrt(2)
    out.append(Encounter("crossing, 6 NM miss", _straight((0, 0), 90.0, 420.0, 35000.0),
                         _straight((off, off), 0.0, 420.0, 35000.0), None,
                         "FL350, 420 kt, 90 deg, closest 6.0 NM at 400 s"))
    out.append(Encounter("head-on, 6 NM abeam", _straight((0, 0), 90.0, 450.0, 35000.0),
                         _straight((0, 6.0), 270.0, 450.0, 35000.0), None,
                         "FL350, 450 kt each, opposite tracks 6 NM apart, abeam at 400 s"))
    # B climbs from FL320 at 2000 fpm from 300 s and levels at FL340 at 360 s, 1000 ft below A (1000 ft
    # apart is separated), then crosses under A at T_C
    b = _straight((0, 0), 0.0, 420.0, 32000.0,
                  segments=(Segment(300.0), Segment(60.0, vertical_rate_fpm=2000.0), Segment(240.0)))
    out.append(Encounter("levelling off 1000 ft below", _straight((0, 0), 90.0, 420.0, 35000.0), b, None,
                         "90 deg crossing over the same point at 400 s; B climbs FL320 -> FL340 "
                         "(300-360 s), A at FL350"))
    return out


def shifted(enc: Encounter, east_nm: float, north_nm: float) -> Encounter:
    """The same encounter moved east_nm, north_nm (the geometry, so the loss window, is unchanged)."""
    def move(f: Flight) -> Flight:
        return replace(f, east_nm=f.east_nm + east_nm, north_nm=f.north_nm + north_nm)
    return replace(enc, a=move(enc.a), b=move(enc.b))


def write_encounter(enc: Encounter, directory: Path, seed: int = 11) -> dict[str, str]:
    """Simulate the encounter (radar + ADS-B, no dropouts, jumps or low-quality episodes, so that the
    encounter itself is what is scored) and write r.ast, a.ast and s.toml; returns their paths."""
    specs = (AircraftSpec("ENCA", 0x720001, "2001", flights=(enc.a,)),
             AircraftSpec("ENCB", 0x720002, "2002", flights=(enc.b,)))
    sc = replace(default_scenario(), name=enc.name, aircraft=specs, adsb_jump_fraction=0.0,
                 adsb_long_dropouts=0, adsb_short_dropouts_per_hour=0.0, adsb_low_quality_episodes=0,
                 radar_long_dropouts=0)
    sim = simulate(sc, seed=seed)
    directory.mkdir(parents=True, exist_ok=True)
    paths = {"radar": directory / "r.ast", "adsb": directory / "a.ast", "sensors": directory / "s.toml"}
    paths["radar"].write_bytes(encode_frame(48, sim.radar))
    paths["adsb"].write_bytes(encode_frame(21, sim.adsb))
    paths["sensors"].write_text(sensors_toml(sc.radar))
    return {k: str(v) for k, v in paths.items()}


def run_encounter(enc: Encounter, directory: Path, seed: int = 11, horizons_s=(20.0, 60.0, 120.0), **options):
    """Simulate, then `conflict_job` on the recordings (nothing written); returns the job result."""
    from msdc.pipeline.jobs.conflicts import ConflictOptions, conflict_job

    p = write_encounter(enc, directory, seed)
    opts = ConflictOptions(inputs=(p["radar"], p["adsb"]), sensors=p["sensors"], date=DATE,
                           output=str(directory / "c.csv"), horizons_s=tuple(horizons_s), **options)
    return conflict_job(opts)
