"""The real daemon's life cycle and traffic log.

The issue: "SIGTERM and SIGINT stop cleanly (stop accepting, flush logs, remove pty links)";
"Traffic log. Every byte in and out, with time, board, endpoint and direction ... and a JSON-lines
file on request, written so a crash loses at most the line in progress."
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import serial

from .process import TIMEOUT, Omsd, daemon_env

STOP_SIGNALS = [signal.SIGTERM, signal.SIGINT]


@pytest.mark.parametrize("sig", STOP_SIGNALS, ids=lambda s: s.name)
def test_signal_stops_cleanly(omsd: Omsd, tmp_path: Path, sig: signal.Signals) -> None:
    link = tmp_path / "board1"
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(link))
    host, port = daemon.tcp()
    with daemon.connect() as c, serial.Serial(str(link), timeout=TIMEOUT) as pty:
        assert c.ask(b"WY") == b"PC48 ver 3.00-4"
        pty.write(b"RP")
        assert pty.read_until(b"\n") == b"0\n"
        c.send(b"AX JG5000")  # a board in motion does not hold the daemon up
        assert daemon.stop(sig) == 0, daemon.stderr[-2000:]
        assert c.at_eof(), "the TCP client should be disconnected"
    assert not os.path.lexists(link), "the pty link should be removed"
    assert "Traceback" not in daemon.stderr
    # it no longer accepts
    with pytest.raises(OSError):
        socket.create_connection((host, port), timeout=TIMEOUT).close()


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_while_the_configuration_is_read_is_status_130(tmp_path: Path) -> None:
    """Ctrl-C before the daemon ran (its modules imported, its file read) ended in a
    KeyboardInterrupt's traceback and death by SIGINT, where the help promises status 130.
    The file is a FIFO: omsd waits in its read, where the signal is sure to find it."""
    fifo = tmp_path / "omsd.toml"
    os.mkfifo(fifo)
    command = [sys.executable, "-m", "omsd", "--config", str(fifo), "--control", "off"]
    env = {**daemon_env(), "XDG_RUNTIME_DIR": str(tmp_path)}
    process = subprocess.Popen(
        command,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
        # Ctrl-C as a terminal delivers it: a test run started in the background by a shell
        # without job control (a CI runner's, `pytest &`) ignores SIGINT, and so would omsd,
        # which Python starts with the disposition it inherits
        preexec_fn=_default_sigint,
    )
    try:
        deadline = time.monotonic() + TIMEOUT
        while True:  # until omsd has the FIFO open for reading
            try:
                writer = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
                break
            except OSError:
                assert time.monotonic() < deadline, "omsd never opened its configuration"
                time.sleep(0.01)
        try:
            process.send_signal(signal.SIGINT)
            out, err = process.communicate(timeout=TIMEOUT)
        finally:
            os.close(writer)
    finally:
        process.kill()
        process.wait()
    assert b"Traceback" not in err, err.decode()
    assert (process.returncode, out, err) == (130, b"", b"")


@pytest.mark.parametrize("sig", STOP_SIGNALS, ids=lambda s: s.name)
def test_signal_right_after_the_endpoint_lines_stops_cleanly(
    omsd: Omsd, tmp_path: Path, sig: signal.Signals
) -> None:
    """Once it has said where its boards are, the daemon is serving: a supervisor or a script
    that reads those lines and stops it at once must get a clean stop too (exit 0, links
    removed), not death by the signal's default action."""
    link = tmp_path / "board1"
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(link))
    status = daemon.stop(sig)
    assert status == 0, f"exit status {status}; stderr {daemon.stderr!r}"
    assert not os.path.lexists(link), "the pty link should be removed"


def test_json_lines_log_has_the_traffic(omsd: Omsd, tmp_path: Path) -> None:
    log = tmp_path / "traffic.jsonl"
    daemon = omsd("--tcp", "127.0.0.1:0", "--log", str(log))
    sent = b"WY ZZ\x04AX MR10 GO ID"
    with daemon.connect() as c:
        c.send(sent)
        reply = c.read_until(b"!\x01\n")
        assert reply == b"PC48 ver 3.00-4\n#\n!\x01\n"
        assert daemon.stop() == 0
    text = log.read_text(encoding="ascii")
    assert text.endswith("\n")
    records = [json.loads(line) for line in text.splitlines()]  # every line parses
    traffic = [r for r in records if r["kind"] == "traffic"]
    assert {r["board"] for r in traffic} == {"board1"}
    (endpoint,) = {r["endpoint"] for r in traffic}
    assert endpoint.startswith(f"tcp:127.0.0.1:{daemon.tcp()[1]}")
    for r in traffic:
        assert isinstance(r["t"], float)
        assert bytes.fromhex(r["hex"]) == r["data"].encode("latin-1")
    into = b"".join(bytes.fromhex(r["hex"]) for r in traffic if r["dir"] == "in")
    out = b"".join(bytes.fromhex(r["hex"]) for r in traffic if r["dir"] == "out")
    assert into == sent  # every byte in, control characters included
    assert out == reply  # every byte out, the done register byte included
    times = [r["t"] for r in records]
    assert times == sorted(times)
    events = [r["what"] for r in records if r["kind"] == "event"]
    assert any("done" in e for e in events), events
