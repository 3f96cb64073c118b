"""The replay job (``msdc replay``): send recordings' data blocks as UDP with their original timing scaled
(pipeline.live.replay), so that a live feed can be simulated from any recording."""

from __future__ import annotations

import ipaddress
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from msdc.pipeline.jobs.common import JobError, input_files
from msdc.pipeline.jobs.options import OptionError, ReplayOptions, check_declared


@dataclass
class ReplayResult:
    """What was sent: datagrams, bytes, passes, wall time, and the recording's span in its own time."""

    datagrams: int
    bytes: int
    passes: int
    wall_s: float
    span_s: float
    scheduled: int  # datagrams in one pass
    late_s: float
    warnings: list[str]
    interrupted: BaseException | None = None  # the Ctrl-C (KeyboardInterrupt) or SIGTERM that ended it


def validate(options: ReplayOptions):
    """The inputs and the destination, checked before anything is read or sent."""
    from msdc.pipeline.live.receive import parse_endpoint

    check_declared(options)
    if options.to is None:
        raise OptionError("--to: give where to send, e.g. --to 239.1.2.3:8600")
    try:
        to = parse_endpoint(options.to, "--to")
    except ValueError as exc:
        raise OptionError(str(exc)) from None
    if options.iface is not None:
        try:
            ipaddress.IPv4Address(options.iface)
        except ValueError:
            raise OptionError(f"--iface {options.iface!r}: not an IPv4 address") from None
    if not options.inputs:
        raise OptionError("RECORDING: give at least one recording to replay")
    paths, warnings = input_files(list(options.inputs))
    return to, paths, warnings


def replay_job(options: ReplayOptions, *, stop: Callable[[], bool] = lambda: False,
               before_sending: Callable[[list[str]], None] | None = None) -> ReplayResult:
    """Read the recordings' datagrams and times, then send them to --to at --speed (--loop, --duration)
    until done or ``stop()``; Ctrl-C (or SIGTERM, SIGHUP) ends it with what was sent so far, in
    ``interrupted``. ``before_sending`` is given the warnings known before the first datagram goes (the
    options', the recordings' skipped bytes): a long replay says them at its start; the result has them
    all."""
    import time

    from msdc.pipeline.live.replay import InterfaceError, ReplayError, Sent, schedule, send, sending_socket
    from msdc.pipeline.report.transaction import Terminated

    to, paths, warnings = validate(options)
    try:
        sched = schedule([Path(p) for p in paths], options.format)
    except ReplayError as exc:
        raise JobError(str(exc), 2) from None
    warnings = [*warnings, *sched.warnings]
    try:
        sock = sending_socket(to, options.iface, options.ttl)
    except InterfaceError as exc:
        raise OptionError(f"--iface {options.iface}: cannot send from it (to {options.to}): "
                          f"{exc.strerror or exc}") from None
    except OSError as exc:
        raise OptionError(f"--to {options.to}: cannot send there ({exc.strerror or exc})") from None
    if before_sending is not None:
        before_sending(warnings)
    sent, interrupted, started = Sent(), None, time.monotonic()
    try:
        send(sched, sock, speed=options.speed, loop=options.loop, duration_s=options.duration_s, stop=stop,
             out=sent)
    except (KeyboardInterrupt, Terminated) as exc:  # what was sent so far is said, as at the end
        interrupted, sent.wall_s = exc, time.monotonic() - started
    except OSError as exc:
        raise JobError(f"--to {options.to}: sending failed: {exc.strerror or exc}") from None
    finally:
        sock.close()
    if sent.refused:
        warnings = [*warnings, f"--to {options.to}: nothing was listening there {sent.refused} time(s) "
                    "(ICMP port unreachable); the datagrams were sent regardless (UDP needs no receiver)"]
    return ReplayResult(sent.datagrams, sent.bytes, sent.passes, sent.wall_s, sched.span_s, len(sched),
                        float(sent.late_s), warnings, interrupted)


__all__ = ["ReplayOptions", "ReplayResult", "replay_job", "validate"]
