"""Peak memory of ``msdc stats`` and ``msdc decode -o`` against the recording's size, and the speed at which
bytes that are not ASTERIX are skipped (issue 27, items 6 and 7).

Builds raw recordings of the sizes asked by repeating one unit (the real CAT048 recording of ../shared/real
with the CAT021 and CAT048 fixtures, or the fixtures alone), and non-ASTERIX files (zeros, random bytes),
then runs each command in a fresh interpreter under ``/usr/bin/time`` at a fixed ``--chunk-mb`` and prints
wall time, CPU time (user + system: steadier than wall time on a shared machine), peak RSS and MB/s of
CPU. The files are deleted afterwards (check ``df`` first: the sizes add up).

    python benchmarks/reader_memory.py                                   # 100, 500, 1000 MB at --chunk-mb 8
    python benchmarks/reader_memory.py --sizes 100,500,1000,2000,4000 --work /tmp/msdc-mem
    python benchmarks/reader_memory.py --sizes 100 --garbage zeros:1000,random:100 --only stats
"""

from __future__ import annotations

import argparse
import os
import shutil
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REAL = ROOT.parent / "shared" / "real"
UNIT_FILES = [REAL / "230502-est-080001_BCN_60MN_08_09.ast", ROOT / "fixtures" / "adsb.ast",
              ROOT / "fixtures" / "radar.ast"]


def unit_bytes() -> bytes:
    """One repeat of the benchmark recording: whole raw files end to end (those that exist)."""
    return b"".join(p.read_bytes() for p in UNIT_FILES if p.is_file())


def pcap_packets(unit: bytes, first_s: int) -> bytes:
    """The unit's data blocks in UDP datagrams of up to 1,400 bytes (Ethernet/IPv4/UDP, little-endian
    microsecond pcap records 10 ms apart from ``first_s``), without the pcap file header."""
    blocks, q = [], 0
    while q < len(unit):
        n = int.from_bytes(unit[q + 1:q + 3], "big")
        blocks.append(unit[q:q + n])
        q += n
    out, datagram, k = [], b"", 0
    for block in [*blocks, b""]:
        if datagram and (not block or len(datagram) + len(block) > 1400):
            udp = struct.pack(">HHHH", 40000, 8600, 8 + len(datagram), 0) + datagram
            ip = struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(udp), 7, 0x4000, 64, 17, 0,
                             bytes([192, 168, 1, 10]), bytes([239, 1, 1, 1]))
            frame = b"\x01\x00\x5e\x01\x01\x01\x00\x11\x22\x33\x44\x55\x08\x00" + ip + udp
            t_us = first_s * 1_000_000 + k * 10_000
            record = struct.pack("<IIII", t_us // 1_000_000, t_us % 1_000_000, len(frame), len(frame))
            out.append(record + frame)
            datagram, k = b"", k + 1
        datagram += block
    return b"".join(out)


def build(path: Path, size_mb: float, kind: str) -> Path:
    """A file of about ``size_mb`` MB: the unit repeated (kind 'asterix'), the unit in UDP datagrams of a
    pcap (kind 'pcap'), zeros, or random bytes."""
    size = int(size_mb * 1e6)
    with path.open("wb") as fh:
        if kind == "asterix":
            unit = unit_bytes()
            for _ in range(max(size // len(unit), 1)):
                fh.write(unit)
        elif kind == "pcap":
            fh.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
            first_s, done = 1_551_398_400, 24  # 2019-03-01 00:00 UTC
            while done < size:
                packets = pcap_packets(unit_bytes(), first_s)
                fh.write(packets)
                done += len(packets)
                first_s += 3600
        else:
            rng = np.random.default_rng(27)  # the same random bytes every run
            done = 0
            while done < size:
                n = min(1 << 20, size - done)
                fh.write(bytes(n) if kind == "zeros" else rng.integers(0, 256, n, np.uint8).tobytes())
                done += n
    return path


def timed(label: str, argv: list[str], size: int) -> dict:
    """Run ``msdc ARGV`` in a fresh interpreter; print and return wall, CPU, peak RSS and MB/s of CPU."""
    cmd = ["/usr/bin/time", "-f", "%e %M %U %S", sys.executable, "-m", "msdc.pipeline.cli", *argv]
    load = os.getloadavg()[0]
    done = subprocess.run(cmd, capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    wall_s, rss_kb, user_s, sys_s = lines[-1].split()
    why = f": {lines[-2]}" if done.returncode and len(lines) > 1 else ""
    cpu_s = float(user_s) + float(sys_s)
    row = {"label": label, "wall_s": float(wall_s), "cpu_s": cpu_s, "rss_mb": int(rss_kb) / 1024,
           "mb_per_cpu_s": size / 1e6 / max(cpu_s, 1e-9), "load": load, "status": done.returncode}
    print(f"{label:40s} {row['wall_s']:8.1f} s  CPU {cpu_s:7.1f} s ({row['mb_per_cpu_s']:6.1f} MB/s)  "
          f"peak RSS {row['rss_mb']:6.0f} MB  (load {load:.1f}; exit {done.returncode}{why})", flush=True)
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="100,500,1000", help="recording sizes, MB (comma-separated)")
    ap.add_argument("--chunk-mb", type=float, default=8.0)
    ap.add_argument("--garbage", default="zeros:1000,random:100",
                    help="non-ASTERIX files as KIND:MB (zeros, random), comma-separated; '' for none")
    ap.add_argument("--pcap", default="", help="pcap sizes, MB (comma-separated): the unit in UDP datagrams")
    ap.add_argument("--only", default="stats,decode", help="commands to run (stats, decode)")
    ap.add_argument("--edition", default="", help="an --edition for every run (e.g. 21=auto)")
    ap.add_argument("--work", type=Path, help="directory for the files (default: a temporary one)")
    args = ap.parse_args()
    only = set(args.only.split(","))
    extra = ["--edition", args.edition] if args.edition else []
    print(f"unit: {', '.join(p.name for p in UNIT_FILES if p.is_file())} ({len(unit_bytes()):,} bytes); "
          f"--chunk-mb {args.chunk_mb:g}")
    work = Path(tempfile.mkdtemp(dir=args.work)) if args.work else Path(tempfile.mkdtemp())
    try:
        cases = [("asterix", float(s)) for s in args.sizes.split(",") if s]
        cases += [("pcap", float(s)) for s in args.pcap.split(",") if s]
        cases += [(k, float(mb)) for k, mb in (g.split(":") for g in args.garbage.split(",") if g)]
        for kind, size_mb in cases:
            path = build(work / f"{kind}{size_mb:g}.{'pcap' if kind == 'pcap' else 'ast'}", size_mb, kind)
            size = path.stat().st_size
            name = f"{kind} {size / 1e6:,.0f} MB"
            if "stats" in only:
                timed(f"stats {name}", ["stats", str(path), "--chunk-mb", f"{args.chunk_mb:g}", *extra], size)
            if "decode" in only:
                out = work / "out.parquet"
                timed(f"decode -o {name}", ["decode", str(path), "-o", str(out), "--chunk-mb",
                                            f"{args.chunk_mb:g}", *extra], size)
                for p in work.glob("out*.parquet"):
                    p.unlink()
            path.unlink()
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
