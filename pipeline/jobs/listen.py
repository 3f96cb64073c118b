"""The listen job (``msdc listen``): receive ASTERIX feeds over UDP, decode them in batches, count what each
feed brings, record it as pcapng and serve the monitor page (pipeline.live). Runs until Ctrl-C (or
--duration), then closes the recording and returns the counts."""

from __future__ import annotations

import contextlib
import os
import re
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from msdc.pipeline.jobs.common import (
    JobError,
    first_missing,
    nonempty_path,
    pinned_editions,
    remove_if_empty,
    sensor_table,
    writable_dataset,
)
from msdc.pipeline.jobs.options import ListenOptions, OptionError, check_declared, check_installed

if TYPE_CHECKING:
    from msdc.pipeline.live.state import LiveState

STATUS_S = 10.0  # a status line on stderr this often
DROP_NOTE_S = 1.0  # datagrams dropped are said at most this often (each time with the count since)
_PERIODS = {"s": 1, "m": 60, "h": 3600, "d": 86400}
_SIZES = {"kb": 10**3, "mb": 10**6, "gb": 10**9}
MIN_ROTATE_S, MIN_ROTATE_BYTES = 1, 10**5


def parse_rotate(text: str) -> tuple[float | None, int | None]:
    """--rotate: a period ("30s", "15m", "1h", "1d") -> (seconds, None), a size ("500MB", "2GB") -> (None,
    bytes); OptionError otherwise."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([a-zA-Z]+)\s*", str(text))
    unit = m.group(2).lower() if m else ""
    if m and unit in _PERIODS and float(m.group(1)) * _PERIODS[unit] >= MIN_ROTATE_S:
        return float(m.group(1)) * _PERIODS[unit], None
    if m and unit in _SIZES and float(m.group(1)) * _SIZES[unit] >= MIN_ROTATE_BYTES:
        return None, int(float(m.group(1)) * _SIZES[unit])
    raise OptionError(f"--rotate {text!r}: expected a period (30s, 15m, 1h, 1d; at least 1 s) or a size "
                      "(500MB, 2GB; at least 0.1 MB)")


def parse_http(text: str) -> tuple[str, int]:
    """--http HOST:PORT (a bare PORT serves on 127.0.0.1)."""
    host, sep, port = str(text).strip().rpartition(":")
    host = host if sep else "127.0.0.1"
    if not port.isdigit() or not host:
        raise OptionError(f"--http {text!r}: expected HOST:PORT, e.g. 127.0.0.1:8080")
    if not 1 <= int(port) <= 65535:
        raise OptionError(f"--http {text!r}: the port must be a number from 1 to 65535")
    return host, int(port)


@dataclass
class Checked:
    """The listen options, checked."""

    endpoints: list
    sensors: object | None
    editions: dict[int, str]
    record: Path | None
    rotate_s: float | None
    rotate_bytes: int | None
    http: tuple[str, int] | None
    thresholds: object | None
    warnings: list[str] = field(default_factory=list)


def validate(options: ListenOptions) -> Checked:
    """Check every option before a socket is opened; OptionError naming the option otherwise."""
    from msdc.pipeline.live.receive import parse_endpoint

    check_declared(options)
    if not options.udp:
        raise OptionError("--udp: give at least one feed, e.g. --udp 239.1.2.3:8600")
    endpoints = []
    for text in options.udp:
        try:
            e = parse_endpoint(text, "--udp")
        except ValueError as exc:
            raise OptionError(str(exc)) from None
        if e in endpoints:
            raise OptionError(f"--udp {text}: given twice")
        endpoints.append(e)
    if options.iface is not None:
        try:
            import ipaddress

            ipaddress.IPv4Address(options.iface)
        except ValueError:
            raise OptionError(f"--iface {options.iface!r}: not an IPv4 address (give the interface's "
                              "address, e.g. 10.1.2.3)") from None
    rotate_s, rotate_bytes = parse_rotate(options.rotate)
    if options.dataset is not None and options.record is None:
        raise OptionError(f"--dataset {options.dataset}: needs --record (the recordings are what is "
                          "ingested)")
    if options.dataset is not None:  # refused now, not when the first recording closes (up to --rotate)
        nonempty_path("--dataset", options.dataset)
        writable_dataset(options.dataset)
    record = None
    if options.record is not None:
        nonempty_path("--record", options.record)
        record = Path(options.record)
        if record.exists() and not record.is_dir():
            raise OptionError(f"--record {record}: not a folder")
        parent = record if record.exists() else next((p for p in record.parents if p.exists()), Path("."))
        if not parent.is_dir():  # a file where a folder of the path should be
            raise OptionError(f"--record {record}: {parent} is a file, not a folder")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise OptionError(f"--record {record}: cannot write in {parent} (permission denied)")
    http = thresholds = None
    warnings: list[str] = []
    asked = {name: getattr(options, name) for name in ("alarm_silent_s", "alarm_min_pd",
                                                        "alarm_min_mode3a_valid", "alarm_min_modec_valid",
                                                        "window_s") if getattr(options, name) is not None}
    if options.http is not None:
        http = parse_http(options.http)
        check_installed(f"--http {options.http}", "the live monitor's web server", ("starlette", "uvicorn"),
                        "live")
        thresholds = monitor_thresholds(asked)
    elif asked:
        warnings.append("--alarm-* and --window set the monitor page's alarms: ignored without --http")
    sensors = None if options.sensors is None else sensor_table(options.sensors)
    editions = pinned_editions(list(options.editions))
    return Checked(endpoints, sensors, editions, record, rotate_s, rotate_bytes, http, thresholds, warnings)


def monitor_thresholds(asked: dict[str, float]):
    """The monitor's Thresholds, its defaults replaced by the options given."""
    import dataclasses

    from msdc.pipeline.live.monitor import Thresholds

    names = {"alarm_silent_s": "silent_s", "alarm_min_pd": "min_pd",
             "alarm_min_mode3a_valid": "min_mode3a_valid", "alarm_min_modec_valid": "min_modec_valid",
             "window_s": "window_s"}
    return dataclasses.replace(Thresholds(), **{names[k]: v for k, v in asked.items()})


def check_http_port(host: str, port: int) -> None:
    """--http: the address can be served (a TCP socket binds to it), else OptionError naming it."""
    import socket

    try:
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind((host, port))
    except (OSError, OverflowError) as exc:
        why = getattr(exc, "strerror", None) or str(exc)
        raise OptionError(f"--http {host}:{port}: cannot serve the monitor there ({why})") from None


def prepare_record(folder: Path) -> None:
    """Make the --record folder and check a file can be created in it (OptionError otherwise)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".msdc-check-"):
            pass
    except OSError as exc:
        raise OptionError(f"--record {folder}: cannot write there ({exc.strerror or exc})") from None


@dataclass
class ListenResult:
    """What listening received: the counters per feed, the recordings written, and what went wrong."""

    counters: dict[str, dict]
    recordings: list[Path]
    recording_error: str | None
    clashes: dict[str, list[str]]
    wall_s: float
    interrupted: bool
    warnings: list[str]
    decoding_failure: str | None = None
    ingested: list[Path] = field(default_factory=list)  # recording files ingested into --dataset

    @property
    def records(self) -> int:
        return sum(sum(c["records"].values()) for c in self.counters.values())


def listen_job(options: ListenOptions, *, stop: threading.Event | None = None,
               say: Callable[[str], None] | None = None,
               ready: Callable[[LiveState], None] | None = None,
               ingest: Callable[[Path], list[str]] | None = None) -> ListenResult:
    """Validate, open the feeds, then receive, decode, record (and serve the monitor) until ``stop`` is set,
    --duration has passed or Ctrl-C (KeyboardInterrupt, or SIGTERM's Terminated) arrives; then drain the
    queues, close the recording and return the counts. ``say`` prints status lines and drop notes;
    ``ready`` is called with the LiveState once every socket listens; ``ingest`` (with --dataset) is given
    each recording file once closed, in a thread of its own, and returns lines to say. A --record folder it
    made and recorded no file in is removed at the end, however the run ends."""
    checked = validate(options)
    made = None if checked.record is None else first_missing(checked.record)
    try:
        return _listen(options, checked, stop, say, ready, ingest)
    finally:
        remove_if_empty(made)


def _listen(options: ListenOptions, checked: Checked, stop: threading.Event | None,
            say: Callable[[str], None] | None, ready: Callable[[LiveState], None] | None,
            ingest: Callable[[Path], list[str]] | None) -> ListenResult:
    """listen_job's run, its options checked."""
    from msdc.pipeline.live.decode import BatchDecoder
    from msdc.pipeline.live.receive import Listener
    from msdc.pipeline.live.record import Recorder
    from msdc.pipeline.live.state import LiveState
    from msdc.pipeline.report.transaction import Terminated

    say = say or (lambda line: print(line, file=sys.stderr, flush=True))
    names = [e.name for e in checked.endpoints]
    state = LiveState(names)
    decoder = BatchDecoder(state, names, sensors=checked.sensors, editions=checked.editions,
                           reports=checked.http is not None)
    listener = Listener(checked.endpoints, state, decoder, None, iface=options.iface,
                        queue_datagrams=options.queue)
    try:
        listener.open()
    except OSError as exc:
        raise OptionError(f"--udp {exc.strerror}") from None
    if checked.http is not None:
        try:
            check_http_port(*checked.http)
        except OptionError:
            listener.close_sockets()
            raise
    recorder = ingesting = None
    try:
        if checked.record is not None:
            prepare_record(checked.record)
            if options.dataset is not None and ingest is None:
                raise OptionError(f"--dataset {options.dataset}: listen_job needs ``ingest`` (the command "
                                  "line gives msdc ingest's job)")
            ingesting = Ingesting(ingest, say) if options.dataset is not None else None
            recorder = Recorder(checked.record, names, [(e.host, e.port) for e in checked.endpoints],
                                rotate_s=checked.rotate_s, rotate_bytes=checked.rotate_bytes,
                                on_closed=ingesting.put if ingesting else None)
            listener.recorder = recorder
    except OptionError:
        listener.close_sockets()
        raise
    stop = stop or threading.Event()
    server = None
    started = time.monotonic()
    interrupted = False
    said: set[str] = set()  # what _watch has said once: the recording's failure
    try:  # a Ctrl-C from the moment the threads start (the user sees "receiving") ends the run as any other
        server = _start_monitor(state, checked, stop) if checked.http is not None else None
        listener.start()
        if ready is not None:
            ready(state)
        _watch(listener, state, recorder, options.duration_s, stop, say, started, said)
    except (KeyboardInterrupt, Terminated):
        interrupted = True
    finally:
        with signals_held():  # a second Ctrl-C, SIGTERM or SIGHUP must not cut the drain short
            stop.set()
            listener.stop()
            if server is not None:
                server.join(timeout=5)
            if ingesting is not None:
                ingesting.finish()
            if recorder is not None and recorder.error and "record" not in said:  # it failed as it closed
                say(f"msdc listen: --record {recorder.folder}: {recorder.error}")
    failure = listener.failure
    result = ListenResult(state.counters(), list(recorder.files) if recorder else [],
                        recorder.error if recorder else None, state.clashes(), time.monotonic() - started,
                        interrupted, checked.warnings,
                          None if failure is None else f"{type(failure).__name__}: {failure}")
    result.ingested = list(ingesting.ingested) if ingesting else []
    return result


class Ingesting:
    """Recording files handed, once closed, to ``ingest`` one after the other in a thread of their own (an
    ingest takes seconds: the decoding thread must not wait for it); what it says, and its failures, go
    to ``say``."""

    def __init__(self, ingest: Callable[[Path], list[str]], say: Callable[[str], None]):
        import queue

        self.ingest, self.say = ingest, say
        self.paths: queue.Queue = queue.Queue()
        self.ingested: list[Path] = []
        self.thread = threading.Thread(target=self._run, name="msdc-ingest", daemon=True)
        self.thread.start()

    def put(self, path: Path) -> None:
        self.paths.put(path)

    def finish(self) -> None:
        """Ingest what is left, then end the thread."""
        self.paths.put(None)
        self.thread.join()

    def _run(self) -> None:
        while (path := self.paths.get()) is not None:
            try:
                for line in self.ingest(path):
                    self.say(f"msdc listen: --dataset: {line}")
                self.ingested.append(path)
            except Exception as exc:  # said; listening and recording go on
                self.say(f"msdc listen: --dataset: {path} not ingested: {exc}")


@contextlib.contextmanager
def signals_held():
    """SIGINT, SIGTERM and SIGHUP ignored inside the block (from the main thread; elsewhere they cannot
    reach it), their handlers back after: the queues are drained and the recording closed whole. A second
    Ctrl-C was caught and the stop begun again, which could close the recording under the decoding thread
    or leave it a 0-byte .part file (a SIGTERM); one arriving then is dropped, as the docs say."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    held = [getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)]
    previous = {sig: signal.signal(sig, signal.SIG_IGN) for sig in held}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _watch(listener, state, recorder, duration_s, stop, say, started, said: set[str]) -> None:
    """Wait for the end, saying drops (at once), the recording's failure (once: "record" put in ``said``)
    and a status line every STATUS_S."""
    dropped_said = 0
    next_status = started + STATUS_S
    while not stop.wait(0.1):
        now = time.monotonic()
        if duration_s is not None and now - started >= duration_s:
            return
        counters = state.counters()
        dropped = sum(c["dropped"] for c in counters.values())
        if dropped > dropped_said:
            per_feed = ", ".join(f"{name} {c['dropped']}" for name, c in counters.items() if c["dropped"])
            say(f"msdc listen: warning: {dropped - dropped_said} datagram(s) dropped: msdc's queue was full "
                f"(decoding cannot keep up; dropped so far: {per_feed})")
            dropped_said = dropped
            stop.wait(DROP_NOTE_S)
        if recorder is not None and recorder.error and "record" not in said:
            say(f"msdc listen: --record {recorder.folder}: {recorder.error}")
            said.add("record")
        if listener.failure is not None:
            raise JobError(f"decoding stopped: {listener.failure}")
        if now >= next_status:
            say("msdc listen: " + "; ".join(status_line(n, c) for n, c in counters.items()))
            next_status = now + STATUS_S


def status_line(name: str, c: dict) -> str:
    """One feed's counters in a line; its packets' parts add up to them (framed, unframed, empty, dropped
    and, while decoding goes on, waiting)."""
    from msdc.pipeline.live.state import waiting_datagrams

    records = sum(c["records"].values())
    waiting = waiting_datagrams(c)
    parts = ", ".join([f"{c['framed']} framed", f"{c['unframed']} unframed", f"{c['empty']} empty",
                       f"{c['dropped']} dropped", *([f"{waiting} waiting"] if waiting else [])])
    return (f"{name}: {c['packets']} packets ({parts}), {c['bytes']} bytes, {records} records, "
            f"{c['decode_errors']} decode errors")


def _start_monitor(state, checked: Checked, stop: threading.Event) -> threading.Thread:
    """The monitor's web server in a thread of its own (it runs until ``stop`` is set)."""
    from msdc.pipeline.live import monitor  # type: ignore[attr-defined]

    host, port = checked.http
    thread = threading.Thread(target=monitor.serve, args=(state, host, port, checked.thresholds, stop),
                              name="msdc-monitor", daemon=True)
    thread.start()
    return thread


def summary_lines(result: ListenResult) -> list[str]:
    """The final counts, one line per feed then one per feed and sensor (stdout)."""
    lines = []
    for name, c in result.counters.items():
        lines.append(status_line(name, c))
        for sensor, n in sorted(c["records"].items()):
            lines.append(f"  {name} {sensor}: {n} records")
    for sensor, feeds in result.clashes.items():
        lines.append(f"sensor {sensor} on {len(feeds)} feeds ({', '.join(feeds)}): kept apart, counted per "
                     "feed")
    for path in result.recordings:
        lines.append(f"recorded: {path}")
    return lines


__all__ = ["ListenOptions", "ListenResult", "listen_job", "summary_lines", "validate"]
