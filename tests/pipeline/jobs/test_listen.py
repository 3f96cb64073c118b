"""msdc listen and msdc replay on the command line: bad options say what is wrong in one line (never a
traceback), and Ctrl-C (SIGINT to the process) ends listen with status 0 and a complete recording that
msdc stats reads."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from asterix_bytes import block
from live_bytes import cat048_record, free_port, send_all

from msdc.pipeline.cli import main
from msdc.pipeline.jobs.listen import status_line

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize(("argv", "message"), [
    (["listen", "--udp", "127.0.0.1"], "--udp '127.0.0.1': expected ADDR:PORT"),
    (["listen", "--udp", "localhost:8600"], "--udp 'localhost:8600': 'localhost' is not an IPv4 address"),
    (["listen", "--udp", "127.0.0.1:70000"], "--udp '127.0.0.1:70000': the port must be a number from 1"),
    (["listen", "--udp", "127.0.0.1:8600", "--udp", "127.0.0.1:8600"], "--udp 127.0.0.1:8600: given twice"),
    (["listen", "--udp", "127.0.0.1:8600", "--rotate", "soon"], "--rotate 'soon': expected a period"),
    (["listen", "--udp", "127.0.0.1:8600", "--iface", "eth0"], "--iface 'eth0': not an IPv4 address"),
    (["listen", "--udp", "127.0.0.1:8600", "--queue", "0"], "--queue 0: must be an integer from 1"),
    (["replay", "nowhere.ast", "--to", "127.0.0.1:8600"], "nowhere.ast: input file does not exist"),
    (["replay", "fixtures/radar.ast", "--to", "127.0.0.1"], "--to '127.0.0.1': expected ADDR:PORT"),
    (["replay", "fixtures/radar.ast", "--to", "127.0.0.1:8600", "--speed", "0"], "--speed 0.0: must be a"),
    # an address not of this machine (TEST-NET-1, RFC 5737) was blamed on --to: "cannot send there"
    (["replay", "fixtures/radar.ast", "--to", "127.0.0.1:8600", "--iface", "192.0.2.1"],
     "--iface 192.0.2.1: cannot send from it (to 127.0.0.1:8600): "),
    (["replay", "fixtures/radar.ast", "--to", "239.1.2.3:8600", "--iface", "192.0.2.1"],
     "--iface 192.0.2.1: cannot send from it (to 239.1.2.3:8600): "),
    # it said "expected HOST:PORT" for a port out of range, and "cannot write in fixtures/radar.ast
    # (permission denied)" for a file where a folder should be
    (["listen", "--udp", "127.0.0.1:8600", "--http", "127.0.0.1:99999"],
     "--http '127.0.0.1:99999': the port must be a number from 1 to 65535"),
    (["listen", "--udp", "127.0.0.1:8600", "--record", "fixtures/radar.ast/sub"],
     "--record fixtures/radar.ast/sub: fixtures/radar.ast is a file, not a folder"),
])
def test_bad_options_are_one_line(argv, message, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"msdc {argv[0]}: {message}") and "Traceback" not in err


def test_a_record_folder_that_cannot_be_written_is_refused_before_listening(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert main(["listen", "--udp", f"127.0.0.1:{free_port()}", "--record", str(tmp_path / "file")]) == 2
    assert f"--record {tmp_path / 'file'}: not a folder" in capsys.readouterr().err
    assert (tmp_path / "file").read_text() == "x"


def test_a_raw_file_s_skipped_bytes_are_said_before_the_first_datagram_goes(tmp_path, capsys, monkeypatch):
    """They were said once sending ended: after an hour's replay at --speed 1."""
    from msdc.pipeline.live import replay

    one = block(48, cat048_record(25, 201, 10.0))
    (tmp_path / "cut.ast").write_bytes(one + one[:5])
    seen: list[str] = []
    real_send = replay.send

    def send(*args, **kwargs):
        seen.append(capsys.readouterr().err)  # what was said when sending began
        return real_send(*args, **kwargs)

    monkeypatch.setattr(replay, "send", send)
    assert main(["replay", str(tmp_path / "cut.ast"), "--to", f"127.0.0.1:{free_port()}"]) == 0
    assert "5 bytes skipped, not sent" in seen[0]
    assert "skipped" not in capsys.readouterr().err  # said once


def test_an_http_port_taken_is_refused(capsys, monkeypatch):
    import socket

    from msdc.pipeline.jobs import listen

    monkeypatch.setattr(listen, "monitor_thresholds", lambda asked: None)  # as if the monitor were there
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        assert main(["listen", "--udp", f"127.0.0.1:{free_port()}", "--http", f"127.0.0.1:{port}"]) == 2
    assert f"--http 127.0.0.1:{port}: cannot serve the monitor there (Address already in use)" in \
        capsys.readouterr().err


def test_a_raw_file_whose_chain_breaks_sends_its_whole_blocks_and_names_the_break(tmp_path, capsys):
    """The truncated block is named as msdc decode names it (offset, LEN read, bytes past the end); the
    whole block before it is sent."""
    one = block(48, cat048_record(25, 201, 10.0))
    (tmp_path / "cut.ast").write_bytes(one + one[:5])
    assert main(["replay", str(tmp_path / "cut.ast"), "--to", f"127.0.0.1:{free_port()}"]) == 0
    out, err = capsys.readouterr()
    said = (f"msdc replay: warning: {tmp_path / 'cut.ast'}: offset {len(one)}: data block runs past the end "
            f"of the data (LEN {len(one)}, {len(one) - 5} bytes past the end): 5 bytes skipped, not sent")
    assert said in err
    assert out.startswith(f"1 datagrams ({len(one)} bytes) sent")
    assert main(["decode", str(tmp_path / "cut.ast")]) == 0  # decode names it alike
    assert f"cut.ast: offset {len(one)}: data block runs past the end of the data (LEN {len(one)}, " \
           f"{len(one) - 5} bytes past the end)" in capsys.readouterr().err


def _listening(port: int, *options: str) -> subprocess.Popen:
    """``msdc listen --udp 127.0.0.1:PORT OPTIONS`` in a process of its own, once it receives. The child
    gets the SIGINT handling a shell gives a foreground command: a suite started in the background (SIGINT
    ignored, inherited) would otherwise leave listen deaf to Ctrl-C."""
    argv = [sys.executable, "-m", "msdc.pipeline.cli", "listen", "--udp", f"127.0.0.1:{port}", *options]
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    line = proc.stderr.readline()
    if "receiving 127.0.0.1:" not in line:
        proc.kill()
        raise AssertionError(line + proc.stderr.read())
    return proc


def _ctrl_c(proc: subprocess.Popen) -> tuple[str, str]:
    """Ctrl-C to a listening process: it ends with status 0 and no traceback; what it printed."""
    try:
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    return out, err


def test_ctrl_c_ends_listen_with_a_complete_recording(tmp_path, capsys):
    port = free_port()
    folder = tmp_path / "rec"
    proc = _listening(port, "--record", str(folder))
    datagrams = [block(48, cat048_record(25, 201, 100.0 + i), cat048_record(25, 201, 100.5 + i))
                 for i in range(5)]
    send_all(datagrams, port)
    time.sleep(0.3)  # received; the decoding thread may still hold them when the signal comes
    out, err = _ctrl_c(proc)
    assert f"127.0.0.1:{port}: 5 packets (5 framed, 0 unframed, 0 empty, 0 dropped), " in out
    (path,) = folder.iterdir()
    assert path.suffix == ".pcapng"  # closed and renamed: no .part left
    capsys.readouterr()
    assert main(["stats", str(path)]) == 0
    stats = capsys.readouterr().out
    row = next(line.split() for line in stats.splitlines() if line.split()[:3] == ["48", "25", "201"])
    assert row[3] == "10"  # records of 048 25/201: 5 datagrams of 2


def _packet_blocks(path: Path) -> int:
    """Enhanced packet blocks (type 6) in a pcapng file, walked by their lengths (pcapng's own layout)."""
    import struct

    data, at, n = path.read_bytes(), 0, 0
    while at < len(data):
        kind, length = struct.unpack_from("<II", data, at)
        n += kind == 6
        at += length
    return n


@pytest.mark.parametrize("second", ["SIGINT", "SIGTERM"])
def test_a_second_signal_while_listen_drains_is_ignored(tmp_path, second):
    """Ctrl-C, then another Ctrl-C or a SIGTERM 50 ms later, as a user pressing twice: the second one was
    caught and the stop begun again (or, a SIGTERM, cut it short): no counts said, exit 130 or 143, a
    recording a datagram short or a 0-byte .part file. Now ignored: status 0, the counts, every datagram
    received in the closed recording."""
    port = free_port()
    folder = tmp_path / "rec"
    proc = _listening(port, "--record", str(folder))
    try:
        send_all([block(48, cat048_record(25, 201, 100.0 + i * 0.01)) for i in range(3000)], port)
        proc.send_signal(signal.SIGINT)
        time.sleep(0.05)
        proc.send_signal(getattr(signal, second))
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    line = next(line for line in out.splitlines() if line.startswith(f"udp:127.0.0.1:{port}: "))
    packets = int(line.split(": ")[1].split()[0])
    assert f"{packets} packets ({packets} framed, 0 unframed, 0 empty, 0 dropped)" in line  # none waiting
    (path,) = folder.iterdir()
    assert path.suffix == ".pcapng" and _packet_blocks(path) == packets


def test_http_without_the_live_extra_is_refused_before_listening(capsys, monkeypatch):
    """Without uvicorn the monitor's thread died with a traceback and listen went on without it; --http is
    now refused, naming the extra, before a socket is opened."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "uvicorn" else
                        real(name, *a))
    assert main(["listen", "--udp", f"127.0.0.1:{free_port()}", "--http", "127.0.0.1:18081"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == ("msdc listen: --http 127.0.0.1:18081: the live monitor's web server needs "
                           "uvicorn, which is not installed: pip install 'msdc[live]'")


def test_a_feeds_status_line_shows_its_packets_parts():
    """100 packets: 90 framed, 3 unframed, 2 empty, 1 dropped, so 4 still waiting to be decoded; with none
    waiting, no 'waiting'."""
    c = {"packets": 100, "bytes": 5000, "framed": 90, "unframed": 3, "empty": 2, "dropped": 1,
         "decode_errors": 1, "records": {"048:25/201": 7, "021:0/107": 5}}
    assert status_line("radar", c) == ("radar: 100 packets (90 framed, 3 unframed, 2 empty, 1 dropped, "
                                       "4 waiting), 5000 bytes, 12 records, 1 decode errors")
    assert "waiting" not in status_line("radar", {**c, "framed": 94})


def test_a_full_queue_is_said_once_as_msdcs_warning(tmp_path):
    """--queue 1 under a burst: each drop note said as msdc's warning, not followed by Python logging's
    bare copy ("513 datagrams dropped"), and no other line that is not msdc's."""
    port = free_port()
    proc = _listening(port, "--queue", "1", "--duration", "1.5")
    try:
        send_all([block(48, cat048_record(25, 201, 100.0 + i * 0.01)) for i in range(3000)], port)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 0, err
    assert "datagram(s) dropped: msdc's queue was full" in err
    assert [line for line in err.splitlines() if not line.startswith("msdc listen: ")] == []


def test_the_live_packages_log_lines_are_said_as_msdcs_warnings(capsys):
    """A feed's socket failing or the monitor failing is logged by pipeline.live; without a handler Python
    printed the bare message, and a traceback with an exception's."""
    import logging

    from msdc.pipeline.cli import _live_log_said

    with _live_log_said("listen"):
        try:
            raise OSError("boom")
        except OSError:
            logging.getLogger("msdc.live.monitor").exception("live monitor: snapshot failed")
        logging.getLogger("msdc.live").error("%s: receiving failed: %s", "udp:1.2.3.4:5", "gone")
    logging.getLogger("msdc.live").error("after the block")  # the handler removed: not said here
    err = capsys.readouterr().err.splitlines()
    assert err[:2] == ["msdc listen: warning: live monitor: snapshot failed",
                       "msdc listen: warning: udp:1.2.3.4:5: receiving failed: gone"]
    assert "Traceback" not in "\n".join(err) and "msdc listen: warning: after the block" not in err


def test_a_dataset_that_is_a_file_is_refused_before_listening(tmp_path, capsys):
    """It was accepted, and said only when the first recording closed (up to an hour later with the
    default --rotate): "not ingested: --dataset ...: is a file, not a folder"."""
    (tmp_path / "afile").write_text("x")
    argv = ["listen", "--udp", f"127.0.0.1:{free_port()}", "--record", str(tmp_path / "rec"), "--dataset",
            str(tmp_path / "afile"), "--duration", "0.1"]
    assert main(argv) == 2
    said = capsys.readouterr().err.strip()
    assert said == f"msdc listen: --dataset {tmp_path / 'afile'}: is a file, not a folder"
    assert not (tmp_path / "rec").exists()


@pytest.mark.parametrize(("sig", "status", "said"), [("SIGINT", 130, "interrupted by Ctrl-C"),
                                                      ("SIGTERM", 143, "terminated by signal 15")])
def test_replay_ended_by_a_signal_says_what_it_sent(tmp_path, sig, status, said):
    """Its docstring promised "Ctrl-C ends it with what was sent so far", yet it printed nothing: the count
    is said, with what ended it, and the status is the signal's. Two datagrams 100 s apart at speed 1: the
    signal comes after the first."""
    import socket

    rec = tmp_path / "two.ast"
    rec.write_bytes(block(48, cat048_record(25, 201, 100.0)) + block(48, cat048_record(25, 201, 200.0)))
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as receiver:
        receiver.bind(("127.0.0.1", 0))
        receiver.settimeout(60)
        argv = [sys.executable, "-m", "msdc.pipeline.cli", "replay", str(rec), "--to",
                f"127.0.0.1:{receiver.getsockname()[1]}"]
        proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        try:
            receiver.recv(65535)  # the first datagram: sending has begun
            time.sleep(0.3)  # ... and replay waits for the second, due 100 s later
            proc.send_signal(getattr(signal, sig))
            out, err = proc.communicate(timeout=30)
        finally:
            proc.kill()
    assert proc.returncode == status, err
    assert out.startswith(f"1 datagrams ({len(block(48, cat048_record(25, 201, 100.0)))} bytes) sent to ")
    assert out.rstrip().endswith(f"; {said})") and "Traceback" not in err


def test_ctrl_c_before_any_recording_removes_the_record_folder_it_made(tmp_path):
    """listen --record rec/day --dataset ds, stopped by Ctrl-C before a datagram came: the folders it made
    for the recording (rec and rec/day) were left behind, empty; now the run leaves tmp_path as it was."""
    proc = _listening(free_port(), "--record", str(tmp_path / "rec" / "day"), "--dataset",
                      str(tmp_path / "ds"))
    _ctrl_c(proc)
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_as_listen_says_it_receives_ends_the_run_as_any_other(tmp_path):
    """A Ctrl-C arriving while ``ready`` runs (the command line prints "receiving" there) escaped the run's
    stop: the KeyboardInterrupt went up past the drain (exit 130 in a loaded suite); it ends the run."""
    from msdc.pipeline.jobs.listen import ListenOptions, listen_job

    def ready(state):
        raise KeyboardInterrupt

    result = listen_job(ListenOptions(udp=(f"127.0.0.1:{free_port()}",), record=str(tmp_path / "rec")),
                        ready=ready)
    assert result.interrupted and result.recordings == [] and list(tmp_path.iterdir()) == []


def test_a_run_failing_after_it_made_the_record_folder_removes_it(tmp_path):
    """A failure once the --record folder is made (here listen_job called with --dataset but no ingest to run)
    leaves the output folder as it was: absent, parents it made included; a folder that was there stays."""
    from msdc.pipeline.jobs.listen import ListenOptions, OptionError, listen_job

    for record in (tmp_path / "rec" / "day", tmp_path):
        options = ListenOptions(udp=(f"127.0.0.1:{free_port()}",), record=str(record),
                                dataset=str(tmp_path / "ds"))
        with pytest.raises(OptionError, match="listen_job needs ``ingest``"):
            listen_job(options)
        assert tmp_path.is_dir() and list(tmp_path.iterdir()) == []


def test_a_duration_ending_with_nothing_recorded_leaves_no_folder_and_one_with_a_file_keeps_it(tmp_path):
    argv = ["listen", "--udp", f"127.0.0.1:{free_port()}", "--record", str(tmp_path / "rec"), "--duration",
            "0.2"]
    assert main(argv) == 0
    assert not (tmp_path / "rec").exists()
    (tmp_path / "rec").mkdir()
    (tmp_path / "rec" / "notes.txt").write_text("kept")
    assert main(argv) == 0
    assert [p.name for p in (tmp_path / "rec").iterdir()] == ["notes.txt"]
