"""Live load (issue 30): replay the 3 h benchmark recording (benchmarks/pipeline.py's scenario: 3 h, 16
aircraft, 2 radars and ADS-B) in a loop at increasing speeds to ``msdc listen`` on the loopback interface,
and report for each speed the records a second sent, received and lost, and the CPU ``listen`` used per
10,000 records a second; the highest speed with no record lost is the ceiling.

    python benchmarks/live_load.py                        # 127.0.0.1 unicast, 4 s per speed
    python benchmarks/live_load.py --keep /tmp/bench3h    # reuse the recordings benchmarks/pipeline.py kept
    python benchmarks/live_load.py --record               # listen also records (pcapng in a temporary folder)
    python benchmarks/live_load.py --http                 # listen also serves the monitor (one page open)

Target: 20 times a busy centre's real-time rate (2,000 plots + 5,000 ADS-B reports a second x 20 = 140,000
records a second) without loss on a 2-core machine. Loopback only (127.0.0.1): nothing leaves the machine.
Losses are counted three ways: records listen decoded against the records of the datagrams sent (each
datagram's records counted by msdc.asterix.read on the files), msdc's own queue drops (listen's
``dropped``), and the kernel's UDP receive-buffer errors (/proc/net/snmp, for the whole machine).
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import numpy as np  # noqa: E402

BUSY_CENTRE_RECORDS_S = 2_000 + 5_000
TARGET_RECORDS_S = 20 * BUSY_CENTRE_RECORDS_S
NAMES = ("radar1.ast", "radar2.ast", "adsb.ast")
TICKS = os.sysconf("SC_CLK_TCK")


def recordings(keep: Path | None) -> list[Path]:
    """The 3 h scenario's recordings (benchmarks/pipeline.py's build), reused when ``keep`` has them."""
    from pipeline import build

    out = keep or Path(tempfile.mkdtemp(prefix="live_load_"))
    out.mkdir(parents=True, exist_ok=True)
    tag = out / "scenario.txt"
    key = "3 h, 16 aircraft, 2 radars, seed 2019"
    if not (tag.exists() and tag.read_text() == key and all((out / n).exists() for n in NAMES)):
        build(out, 3.0, 16, 2, 2019)
        tag.write_text(key)
    return [out / n for n in NAMES]


def records_per_datagram(sched, paths: list[Path]) -> np.ndarray:
    """Records in each datagram of the schedule (raw files: one block each), counted by msdc.asterix.read
    per block: by the file reader, not by listen's batch decoder."""
    import msdc.asterix as asterix
    from msdc.asterix.categories import DECODABLE

    per_block: dict[bytes, int] = {}
    for p in paths:
        rec = asterix.read(p, categories=DECODABLE, columns=["time_of_day"])
        counts = np.zeros(rec.blocks, np.int64)
        for frame in rec.frames.values():
            counts += np.bincount(frame["block"].to_numpy(np.int64), minlength=rec.blocks)
        data = p.read_bytes()
        pos = 0
        for n in counts:
            length = int.from_bytes(data[pos + 1:pos + 3], "big")
            per_block[data[pos:pos + length]] = int(n)
            pos += length
    return np.array([per_block[d] for d in sched.data], np.int64)


def udp_rcvbuf_errors() -> int:
    """The kernel's UDP receive-buffer errors since boot (every socket of the machine)."""
    text = Path("/proc/net/snmp").read_text()
    lines = [line.split() for line in text.splitlines() if line.startswith("Udp:")]
    return int(dict(zip(lines[0][1:], lines[1][1:], strict=True))["RcvbufErrors"])


def cpu_s(pid: int) -> float:
    """User + system CPU seconds of a process so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _open_page(port: int, stop) -> None:
    """A page's event stream held open (the monitor then computes a snapshot a second), read until stop."""
    import urllib.request

    for _ in range(100):
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/events", timeout=5) as stream:
                while not stop.is_set():
                    stream.readline()
            return
        except OSError:
            time.sleep(0.1)


def run_speed(sched, per_dgram: np.ndarray, speed: float, seconds: float, record: Path | None,
              sensors: Path | None = None) -> dict:
    """listen in a fresh process, the schedule looped at ``speed`` for ``seconds``, then Ctrl-C: the
    figures of that run. With ``sensors``, listen serves the monitor (--http) and one page follows it."""
    import threading

    from msdc.pipeline.live.receive import Endpoint
    from msdc.pipeline.live.replay import send, sending_socket

    port = free_port()
    argv = [sys.executable, "-m", "msdc.pipeline.cli", "listen", "--udp", f"127.0.0.1:{port}"]
    if record is not None:
        argv += ["--record", str(record)]
    http = free_port() if sensors is not None else None
    if http is not None:
        argv += ["--http", f"127.0.0.1:{http}", "--sensors", str(sensors)]
    page_stop = threading.Event()
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stderr.readline()
        assert "receiving" in line, line + proc.stderr.read()
        if http is not None:
            threading.Thread(target=_open_page, args=(http, page_stop), daemon=True).start()
        time.sleep(0.5)
        cpu0, buf0 = cpu_s(proc.pid), udp_rcvbuf_errors()
        sock = sending_socket(Endpoint("127.0.0.1", port), None, 1)
        sent = send(sched, sock, speed=speed, loop=True, duration_s=seconds)
        sock.close()
        wall = sent.wall_s
        last, idle_since = cpu_s(proc.pid), time.monotonic()
        give_up = time.monotonic() + 15.0  # with --http the monitor's snapshots keep the CPU moving
        while time.monotonic() - idle_since < 0.6 and time.monotonic() < give_up:  # decoding done
            time.sleep(0.2)
            now = cpu_s(proc.pid)
            if now - last > 0.02:
                last, idle_since = now, time.monotonic()
        cpu = last - cpu0
        buf_errors = udp_rcvbuf_errors() - buf0
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        page_stop.set()
        proc.kill()
    m = re.search(r"(\d+) packets, (\d+) bytes, (\d+) records, (\d+) unframed, (\d+) decode errors, "
                  r"(\d+) dropped", out)
    assert m, out + err
    packets, _, records, _, _, dropped = map(int, m.groups())
    full, rest = divmod(sent.datagrams, len(sched))
    expected = full * int(per_dgram.sum()) + int(per_dgram[:rest].sum())
    return {"speed": speed, "wall_s": wall, "sent_datagrams": sent.datagrams, "expected": expected,
            "records": records, "packets": packets, "dropped": dropped, "buf_errors": buf_errors,
            "cpu_s": cpu, "late_s": float(sent.late_s)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--keep", type=Path, help="folder of the 3 h recordings (made there if absent)")
    ap.add_argument("--seconds", type=float, default=4.0, help="seconds of sending per speed")
    ap.add_argument("--speeds", default="2000,4000,8000,16000,24000,32000,48000,64000",
                    help="comma-separated speeds, tried in order until records are lost")
    ap.add_argument("--record", action="store_true", help="listen records as pcapng too")
    ap.add_argument("--http", action="store_true", help="listen serves the monitor, one page following it")
    args = ap.parse_args()
    from msdc.pipeline.live.replay import schedule

    paths = recordings(args.keep)
    sched = schedule(paths)
    per_dgram = records_per_datagram(sched, paths)
    rate = per_dgram.sum() / sched.span_s
    print(f"recording: {len(sched)} datagrams, {per_dgram.sum()} records over {sched.span_s:.0f} s "
          f"({rate:.2f} records/s real time); target {TARGET_RECORDS_S} records/s = speed "
          f"{TARGET_RECORDS_S / rate:.0f}; {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}", flush=True)
    print(f"{'speed':>7} {'sent rec/s':>11} {'received':>9} {'lost':>6} {'dropped':>7} {'OS drops':>8} "
          f"{'listen CPU':>10} {'CPU/10k rec/s':>13} {'max late':>8} load", flush=True)
    best = None
    with tempfile.TemporaryDirectory() as tmp:
        for i, speed in enumerate(float(s) for s in args.speeds.split(",")):
            record = Path(tmp) / f"rec{i}" if args.record else None
            sensors = paths[0].parent / "sensors.toml" if args.http else None
            r = run_speed(sched, per_dgram, speed, args.seconds, record, sensors)
            lost = r["expected"] - r["records"]
            sent_rate = r["expected"] / r["wall_s"]
            per10k = r["cpu_s"] / max(r["records"], 1) * 10_000
            print(f"{speed:7.0f} {sent_rate:11.0f} {r['records']:9d} {lost:6d} {r['dropped']:7d} "
                  f"{r['buf_errors']:8d} {r['cpu_s']:9.2f}s {per10k:12.3f}s {r['late_s'] * 1000:6.0f}ms "
                  f"{os.getloadavg()[0]:.1f}", flush=True)
            if lost or r["dropped"]:
                break
            best = (speed, sent_rate, per10k)
    if best:
        print(f"ceiling without loss: speed {best[0]:.0f} = {best[1]:.0f} records/s sent "
              f"({best[1] / TARGET_RECORDS_S:.2f} x the target); listen CPU {best[2]:.3f} core-s per 10,000 "
              "records (a core's share at 10,000 records/s)")


if __name__ == "__main__":
    main()
