"""Decode speed and memory: records/s and peak RSS per category, and pyasteryx's rate when installed.

Run by hand (never a timed test): ``python benchmarks/decode.py [--records 1000000] [--categories 48,62]``.
Cases: CAT048 plots, CAT021 ADS-B, CAT010 multilateration reports, CAT020 WAM reports, CAT048 among other
categories, CAT062 system tracks, CAT063 sensor status messages; each rate is also given as a share of
CAT048's. Recordings are built with msdc's own encoder and cached in --work; the mixed case is the CAT048 one
with 30 % of its bytes in blocks of other categories (stepped over by framing). CAT001 (plots and tracks,
half each, with a CAT002 sector crossing of their radar before every 25 records: their times are made
whole from them) is decoded alone, categories=(1,), and CAT002 alone, categories=(2,). Each measurement
runs in a fresh process: one warm-up decode (numba's cached kernel loads, memory pages are touched once),
then the best of --repeat timed decodes, file in page cache to DataFrame.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

CALLSIGNS = np.array(["MAS72", "AXM123", "SIA305", "DLH65A", "BAW22", "EZS14ZH", "KLM1605", "UAE343"])


def cat048_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Typical Mode S monoradar plots: the items a radar sends on nearly every report."""
    ac = rng.integers(0, len(CALLSIGNS), n)
    return pd.DataFrame({
        "sac": 25, "sic": 201, "time_of_day": np.sort(rng.uniform(0, 86000, n)).round(7),
        "typ": 5, "sim": 0, "rdp": 0, "spi": 0, "rab": 0,
        "rho_nm": rng.uniform(5, 250, n), "theta_deg": rng.uniform(0, 359.9, n),
        "mode3a": pd.Series(rng.integers(0, 4096, n)).map(lambda v: f"{v:04o}"),
        "mode3a_v": 0, "mode3a_g": 0, "mode3a_l": 0,
        "flight_level": rng.integers(0, 1600, n) / 4, "flight_level_v": 0, "flight_level_g": 0,
        "ssr_runlength_deg": 0.703125, "ssr_replies": 12, "ssr_amplitude_dbm": -60.0,
        "address": pd.Series(0x750000 + ac).map(lambda v: f"{v:06X}"), "callsign": CALLSIGNS[ac],
        "bds_count": 1, "track_number": rng.integers(0, 4096, n),
        "ground_speed_kt": rng.uniform(100, 500, n), "heading_deg": rng.uniform(0, 359, n),
        "cnf": 0, "rad": 2, "dou": 0, "mah": 0, "cdm": 0, "com": 1, "flight_status": 0,
    })


def cat021_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Typical 1090ES ADS-B reports in the 2.x family."""
    ac = rng.integers(0, len(CALLSIGNS), n)
    tod = np.sort(rng.uniform(0, 86000, n))
    return pd.DataFrame({
        "sac": 0, "sic": 1, "time_applicability_position": tod, "time_applicability_velocity": tod,
        "time_reception_position": tod + 0.5, "time_reception_velocity": tod + 0.5,
        "time_report_transmission": tod + 0.6, "atp": 1, "arc": 1, "rc": 0, "rab": 0,
        "latitude": rng.uniform(-10, 10, n), "longitude": rng.uniform(95, 115, n),
        "address": pd.Series(0x750000 + ac).map(lambda v: f"{v:06X}"), "callsign": CALLSIGNS[ac],
        "mode3a": "2301", "flight_level": rng.integers(0, 1600, n) / 4,
        "geometric_height_ft": rng.integers(0, 6000, n) * 6.25,
        "ground_speed_kt": rng.uniform(100, 500, n), "track_angle_deg": rng.uniform(0, 359, n),
        "track_number": rng.integers(0, 4096, n), "nucp_nic": 8, "nucr_nacv": 2, "nacp": 9, "sil": 3,
        "nic_baro": 1, "mops_version": 2, "link_technology": 2, "emitter_category": 3,
        "geo_vertical_rate_ftmin": 0.0, "service_id": 1,
    })


def cat001_frame(n: int, rng: np.random.Generator) -> tuple[pd.DataFrame, np.ndarray]:
    """Monoradar plots and tracks (TYP 0 and 1 alternately) with the items an old radar sends, and their
    whole times of day."""
    tod = np.floor(np.sort(rng.uniform(0, 86000, n)) * 128) / 128  # on the 1/128 s grid: mod 512 fits
    track = (np.arange(n) % 2).astype(float)
    return pd.DataFrame({
        "sac": 25, "sic": 201, "typ": track, "ssr_psr": 3, "truncated_time_of_day": tod % 512,
        "rho_nm": rng.uniform(5, 250, n), "theta_deg": rng.uniform(0, 359.9, n),
        "mode3a": pd.Series(rng.integers(0, 4096, n)).map(lambda v: f"{v:04o}"), "mode3a_v": 0,
        "flight_level": rng.integers(0, 1600, n) / 4, "flight_level_v": 0,
        "track_number": np.where(track == 1, rng.integers(0, 4096, n), np.nan),
        "x_nm": np.where(track == 1, rng.uniform(-200, 200, n), np.nan),
        "y_nm": np.where(track == 1, rng.uniform(-200, 200, n), np.nan),
        "ground_speed_kt": np.where(track == 1, rng.uniform(100, 500, n), np.nan),
        "heading_deg": np.where(track == 1, rng.uniform(0, 359, n), np.nan),
        "con": np.where(track == 1, 0, np.nan), "rad": np.where(track == 1, 1, np.nan),
    }), tod


def cat002_frame(n: int, rng: np.random.Generator, tod: np.ndarray | None = None) -> pd.DataFrame:
    """Sector crossings (32 sectors a turn) with a north marker and its rotation period every 33rd."""
    tod = np.sort(rng.uniform(0, 86000, n)) if tod is None else tod
    north = np.arange(n) % 33 == 0
    return pd.DataFrame({
        "sac": 25, "sic": 201, "message_type": np.where(north, 1, 2), "time_of_day": tod,
        "sector_number": np.where(north, np.nan, (np.arange(n) % 33 - 1) * 8),
        "antenna_rotation_period_s": np.where(north, 4.0, np.nan),
    })


def cat062_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Typical system track messages of a multi-sensor tracker: the items it sends on nearly every update
    (position in both frames, velocity, Mode 3/A, identity, two octets of track status, update ages, flight
    levels, accuracies, Mode S selected altitude and heading)."""
    ac = rng.integers(0, len(CALLSIGNS), n)
    return pd.DataFrame({
        "sac": 25, "sic": 100, "service_id": 1, "time_of_day": np.sort(rng.uniform(0, 86000, n)).round(7),
        "latitude": rng.uniform(-10, 10, n), "longitude": rng.uniform(95, 115, n),
        "x_m": rng.uniform(-4e5, 4e5, n).round(), "y_m": rng.uniform(-4e5, 4e5, n).round(),
        "vx_ms": rng.uniform(-250, 250, n), "vy_ms": rng.uniform(-250, 250, n),
        "mode3a": pd.Series(rng.integers(0, 4096, n)).map(lambda v: f"{v:04o}"),
        "mode3a_v": 0, "mode3a_g": 0, "mode3a_changed": 0, "callsign": CALLSIGNS[ac],
        "address": pd.Series(0x750000 + ac).map(lambda v: f"{v:06X}"),
        "magnetic_heading_deg": rng.uniform(0, 359, n), "selected_altitude_ft": 35000.0,
        "track_number": rng.integers(0, 65536, n), "mon": 0, "spi": 0, "mrh": 0, "altitude_source": 0,
        "cnf": 0, "sim": 0, "tse": 0, "tsb": 0, "fpc": 1, "aff": 0, "stp": 0, "kos": 0,
        "track_age_s": 0.25, "ssr_age_s": 2.5, "mds_age_s": 2.5, "adsb_age_s": 0.5,
        "movement_transversal": 0, "movement_longitudinal": 0, "movement_vertical": 0,
        "altitude_discrepancy": 0, "flight_level_age_s": 2.5, "mode3a_age_s": 2.5,
        "flight_level": rng.integers(0, 1600, n) / 4, "barometric_altitude_fl": rng.integers(0, 1600, n) / 4,
        "barometric_altitude_qnh": 0, "vertical_rate_ftmin": 0.0,
        "accuracy_x_m": 50.0, "accuracy_y_m": 50.0, "accuracy_vx_ms": 2.0, "accuracy_vy_ms": 2.0,
    })


def cat063_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Sensor status messages of a tracker: one per sensor and period, with the sensor's biases."""
    return pd.DataFrame({
        "sac": 25, "sic": 100, "service_id": 1, "time_of_day": np.sort(rng.uniform(0, 86000, n)).round(7),
        "sensor_sac": 25, "sensor_sic": rng.integers(1, 40, n), "sensor_status": 0, "psr_nogo": 0,
        "ssr_nogo": 0, "mds_nogo": 0, "ads_nogo": 0, "mlt_nogo": 0, "time_stamping_bias_ms": 0.0,
        "ssr_range_bias_nm": rng.integers(-8, 8, n) / 128, "ssr_azimuth_bias_deg": 0.0,
    })


def cat010_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Airport Mode S multilateration target reports (as the real LEBL file: I010/042 x/y, I010/200, /202,
    /161, /170, /060, /220, /245, /090)."""
    ac = rng.integers(0, len(CALLSIGNS), n)
    return pd.DataFrame({
        "sac": 0, "sic": 107, "message_type": 1, "typ": 1, "time_of_day": np.sort(rng.uniform(0, 86000, n)),
        "x_m": rng.integers(-8000, 8000, n).astype(float), "y_m": rng.integers(-8000, 8000, n).astype(float),
        "ground_speed_kt": rng.uniform(0, 160, n), "track_angle_deg": rng.uniform(0, 359, n),
        "vx_ms": rng.integers(-300, 300, n) / 4, "vy_ms": rng.integers(-300, 300, n) / 4,
        "track_number": rng.integers(0, 4096, n), "cnf": 0, "tre": 0, "cst": 0, "mah": 0, "tcc": 1, "sth": 0,
        "mode3a": pd.Series(rng.integers(0, 4096, n)).map(lambda v: f"{v:04o}"),
        "address": pd.Series(0x340000 + ac).map(lambda v: f"{v:06X}"), "callsign": CALLSIGNS[ac],
        "flight_level": rng.integers(-4, 40, n) / 4,
    })


def cat020_frame(n: int, rng: np.random.Generator) -> pd.DataFrame:
    """Wide-area multilateration reports: WGS-84 and Cartesian position, track, codes, velocity, heights and
    the I020/500 standard deviations."""
    ac = rng.integers(0, len(CALLSIGNS), n)
    return pd.DataFrame({
        "sac": 25, "sic": 10, "tech_ssr": 1, "tech_ms": 0, "tech_hf": 1, "tech_vdl4": 1, "tech_uat": 1,
        "tech_dme": 1, "tech_ot": 1, "time_of_day": np.sort(rng.uniform(0, 86000, n)),
        "latitude": rng.uniform(40, 43, n), "longitude": rng.uniform(0, 4, n),
        "x_m": rng.uniform(-100_000, 100_000, n), "y_m": rng.uniform(-100_000, 100_000, n),
        "track_number": rng.integers(0, 4096, n), "cnf": 0, "tre": 0, "cst": 0, "cdm": 0, "mah": 0, "sth": 0,
        "mode3a": pd.Series(rng.integers(0, 4096, n)).map(lambda v: f"{v:04o}"),
        "vx_ms": rng.integers(-1000, 1000, n) / 4, "vy_ms": rng.integers(-1000, 1000, n) / 4,
        "flight_level": rng.integers(0, 1600, n) / 4,
        "address": pd.Series(0x340000 + ac).map(lambda v: f"{v:06X}"), "callsign": CALLSIGNS[ac],
        "geometric_height_ft": rng.integers(0, 6000, n) * 6.25,
        "sigma_x_m": rng.integers(4, 400, n) / 4, "sigma_y_m": rng.integers(4, 400, n) / 4,
        "com": 1, "flight_status": 0,
    })


FRAMES = {48: cat048_frame, 21: cat021_frame, 10: cat010_frame, 20: cat020_frame, 62: cat062_frame,
          63: cat063_frame, 2: cat002_frame}


def build(path: Path, category: int, n: int) -> None:
    """Encode n records of one category with msdc's encoder (cached on disk)."""
    from msdc.asterix.encode import encode_frame

    rng = np.random.default_rng(category)
    part = path.with_suffix(".part")  # renamed when whole: a failed build leaves no file to reuse
    with open(part, "wb") as fh:
        step = 200_000
        for lo in range(0, n, step):
            m = min(step, n - lo)
            if category == 1:  # each block of 25 records after a sector crossing of their radar
                frame, tod = cat001_frame(m, rng)
                plots = encode_frame(1, frame, records_per_block=25)
                sectors = encode_frame(2, cat002_frame(len(tod[::25]), rng, np.maximum(tod[::25] - 0.1, 0)),
                                       records_per_block=1)
                fh.write(_interleave(sectors, plots))
                continue
            make = FRAMES[category]
            fh.write(encode_frame(category, make(m, rng), records_per_block=25,
                                  prefer={"latitude": "130", "longitude": "130"} if category == 21 else None))
    part.rename(path)


def _blocks(data: bytes) -> list[bytes]:
    """The data blocks of a raw stream, by their LEN."""
    out, pos = [], 0
    while pos < len(data):
        n = int.from_bytes(data[pos + 1:pos + 3], "big")
        out.append(data[pos:pos + n])
        pos += n
    return out


def _interleave(first: bytes, second: bytes) -> bytes:
    """Blocks of two streams alternately (one of each in turn)."""
    a, b = _blocks(first), _blocks(second)
    return b"".join(x + y for x, y in zip(a, b, strict=True))


def build_mixed(path: Path, cat048_path: Path, other_share: float = 0.30) -> None:
    """The CAT048 recording with blocks of other categories (CAT001 plots, CAT002 sector messages; msdc
    decodes neither) after each CAT048 block, so that other_share of the bytes are other categories."""
    data = cat048_path.read_bytes()
    out = bytearray()
    owed = 0.0
    pos = 0
    i = 0
    while pos < len(data):
        n = int.from_bytes(data[pos + 1:pos + 3], "big")
        out += data[pos:pos + n]
        pos += n
        owed += n * other_share / (1 - other_share)
        while owed >= 200:
            i += 1
            if i % 2:  # CAT001: 40 records of FSPEC C0 (I001/010, I001/020), SAC/SIC, target descriptor
                body = bytes([0xC0, 25, 201, 0x22]) * 40
            else:  # CAT002: 40 sector crossings: FSPEC E0, I002/010, I002/000 = 2, I002/020 sector
                body = b"".join(bytes([0xE0, 25, 201, 2, k]) for k in range(40))
            blk = bytes([1 if i % 2 else 2]) + (len(body) + 3).to_bytes(2, "big") + body
            out += blk
            owed -= len(blk)
    path.write_bytes(bytes(out))


def _rss_mb() -> float:
    """This process's resident memory now (Linux /proc; 0 elsewhere)."""
    try:
        with open("/proc/self/status") as f:
            return next(int(line.split()[1]) for line in f if line.startswith("VmRSS")) / 1024
    except (OSError, StopIteration):
        return 0.0


def measure(path: Path, repeat: int, category: int, pin: str = "") -> dict:
    """In this (fresh) process: warm up on a prefix, then the peak-memory decode and best-of-repeat
    (``pin``: the category's edition pinned instead of its default)."""
    import gc
    import tempfile

    import msdc.asterix as asterix

    with tempfile.NamedTemporaryFile(suffix=".ast") as tiny:
        tiny.write(path.read_bytes()[:200_000])
        tiny.flush()
        kw = {"editions": {category: pin}} if pin else {}
        asterix.read(tiny.name, categories=[category], **kw)  # loads the cached kernel and pandas machinery
    base_rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    gc.collect()
    base_now_mb = _rss_mb()
    t0 = time.perf_counter()
    rec = asterix.read(path, categories=[category], **kw)
    first_s = time.perf_counter() - t0
    peak_rss_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    gc.collect()
    held_mb = _rss_mb() - base_now_mb  # what the frames really hold (absent columns share one array)
    n = sum(len(f) for f in rec.frames.values())
    frame_mb = sum(f.memory_usage(deep=True).sum() for f in rec.frames.values()) / 1e6
    values = sum(int(f.notna().to_numpy().sum()) for f in rec.frames.values())  # present cells
    del rec
    gc.collect()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        asterix.read(path, categories=[category], **kw)
        times.append(time.perf_counter() - t0)
    return {"records": n, "first_s": first_s, "best_s": min(times), "records_per_s": n / min(times),
            "peak_rss_mb": peak_rss_mb, "rss_before_mb": base_rss_mb, "frame_mb": frame_mb,
            "held_mb": held_mb, "values_per_record": values / max(n, 1),
            "file_mb": path.stat().st_size / 1e6}


def measure_pyasteryx(path: Path, max_records: int) -> dict | None:
    """pyasteryx's records/s on the first max_records records of the same file, if it is installed."""
    try:
        from pyasteryx import Decoder
    except ImportError:
        return None
    dec = Decoder()
    t0 = time.perf_counter()
    n = 0
    for _ in dec.iter_file(path):
        n += 1
        if n >= max_records:
            break
    dt = time.perf_counter() - t0
    return {"records": n, "seconds": dt, "records_per_s": n / dt}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--records", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--work", default="/tmp/msdc-bench")
    ap.add_argument("--pyasteryx-records", type=int, default=100_000)
    ap.add_argument("--categories", default="48,21,10,20,48+30% other,1,2,62,63",
                    help="the cases to run, comma-separated (default: all)")
    ap.add_argument("--measure", help=argparse.SUPPRESS)
    ap.add_argument("--category", type=int, default=48, help=argparse.SUPPRESS)
    ap.add_argument("--pin", default="", help=argparse.SUPPRESS)
    ap.add_argument("--measure-pyasteryx", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.measure:
        print(json.dumps(measure(Path(args.measure), args.repeat, args.category, args.pin)))
        return 0
    if args.measure_pyasteryx:
        print(json.dumps(measure_pyasteryx(Path(args.measure_pyasteryx), args.pyasteryx_records)))
        return 0
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    rates: dict[str, float] = {}
    value_rates: dict[str, float] = {}  # present values (non-empty cells) per second
    for cat in [c if "other" in c else int(c) for c in args.categories.split(",")]:
        if cat == "48+30% other":
            path = work / f"cat048_other30_{args.records}.ast"
            if not path.exists():
                build_mixed(path, work / f"cat048_{args.records}.ast")
                print(f"built {path} ({path.stat().st_size / 1e6:.1f} MB): CAT048 + 30 % CAT001/CAT002 bytes")
            cat = 48
            label = "CAT048+30% other"
        else:
            path = work / f"cat{cat:03d}_{args.records}.ast"
            label = f"CAT{cat:03d}"
        if not path.exists():
            t0 = time.perf_counter()
            build(path, cat, args.records)
            print(f"built {path} ({path.stat().st_size / 1e6:.1f} MB) in {time.perf_counter() - t0:.1f} s")
        run = [sys.executable, __file__, "--repeat", str(args.repeat)]
        m = json.loads(subprocess.run(run + ["--measure", str(path), "--category", str(cat)], check=True,
                                      capture_output=True, text=True).stdout)
        rates[label] = m["records_per_s"]
        value_rates[label] = m["records_per_s"] * m["values_per_record"]
        grow_mb = m["peak_rss_mb"] - m["rss_before_mb"]
        rates[label] = m["records_per_s"]
        versus = (f"; {m['records_per_s'] / rates['CAT048']:.0%} of CAT048's rate"
                  if label != "CAT048" and "CAT048" in rates else "")
        print(f"{label}: {m['records']:,} records in {m['best_s']:.3f} s = "
              f"{m['records_per_s']:,.0f} rec/s (first decode in a fresh process {m['first_s']:.3f} s)"
              f"{versus}")
        value_versus = (f"; {value_rates[label] / value_rates['CAT048']:.0%} of CAT048's"
                        if label != "CAT048" and "CAT048" in value_rates else "")
        print(f"{label}: {m['values_per_record']:.1f} present values a record, "
              f"{value_rates[label]:,.0f} values/s{value_versus}")
        print(f"{label}: peak RSS {m['peak_rss_mb']:.0f} MB, of which the decode added {grow_mb:.0f} MB"
              f" (imports and kernel before it: {m['rss_before_mb']:.0f} MB); frames {m['frame_mb']:.0f} MB"
              f" (columns summed; held after the decode: {m['held_mb']:.0f} MB),"
              f" file {m['file_mb']:.0f} MB;"
              f" added/(frames+file) = {grow_mb / (m['frame_mb'] + m['file_mb']):.2f}")
        if label == "CAT021":  # the cost of 'auto' (CAT021's default) against the edition it chooses
            argv = run + ["--measure", str(path), "--category", "21", "--pin", "2.7"]
            pinned = json.loads(subprocess.run(argv, check=True, capture_output=True, text=True).stdout)
            print(f"CAT021 with --edition 21=2.7: {pinned['best_s']:.3f} s; auto costs "
                  f"{m['best_s'] / pinned['best_s'] - 1:.1%} of decoding")
        p = json.loads(subprocess.run(run + ["--measure-pyasteryx", str(path), "--pyasteryx-records",
                                             str(args.pyasteryx_records)], check=True, capture_output=True,
                                      text=True).stdout)
        if p is None:
            print(f"{label}: pyasteryx not installed (pip install pyasteryx to compare)")
        else:
            ratio = m["records_per_s"] / p["records_per_s"]
            print(f"{label}: pyasteryx {p['records']:,} records in {p['seconds']:.2f} s = "
                  f"{p['records_per_s']:,.0f} rec/s; msdc / pyasteryx = {ratio:.0f}x")
    if "CAT062" in rates and "CAT048" in rates:  # the issue's bar: CAT062 at 80 % of CAT048's records/s
        print(f"CAT062 / CAT048 records/s = {rates['CAT062'] / rates['CAT048']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
