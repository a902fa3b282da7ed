"""Signals (issue 7): "SIGTERM mid-traffic leaves a complete traffic log and no stale pty links;
SIGKILL loses at most the log line in progress; a restart comes back on the same endpoints."

A real daemon (one PC48-4E on the DOS-driver link) on a fixed TCP port picked free for the test
and a pty, logging its traffic to a JSON-lines file (``--log``). Two clients talk to it without
pause, one over TCP and one through the pty (which it holds open when the signal comes), each
asking ``AY RP`` and reading the answer, again and again.

* SIGTERM: the daemon exits 0; every line of the log is a whole JSON object (the last one says
  ``stopped``); what the TCP client received is exactly the start of what the log says was sent
  to it, and what the log says it received from the client is the start of what the client
  wrote ("every byte in and out", ``omsd/telemetry/traffic.py``); the pty link is gone although
  a client still had the pty open.
* SIGKILL: every line but possibly the last is a whole JSON object, and only the last may lack
  its line end ("at most the line being written is cut short", ibid.); the pty link is left
  (nobody could remove it).
* Restart, after either: the same command line comes back on the same TCP port and the same pty
  path (the stale link of a killed daemon replaced), the board answers on both, and the log goes
  on after what was there.
"""

from __future__ import annotations

import json
import os
import select
import signal
import socket
import threading
import time
from pathlib import Path

from daemon.process import TIMEOUT, Daemon, Omsd

from .support import free_port


class Talker(threading.Thread):
    """A client asking ``AY RP`` without pause until the daemon goes away; keeps every byte it
    wrote and read."""

    def __init__(self, open_: str, target: object) -> None:
        super().__init__(daemon=True)
        self.kind = open_
        self.target = target
        self.sent = bytearray()
        self.received = bytearray()
        self.answers = 0
        self.local = ""
        self.stopping = threading.Event()
        self.error: BaseException | None = None
        self._ready = threading.Event()

    def run(self) -> None:
        try:
            if self.kind == "tcp":
                self._tcp()
            else:
                self._pty()
        except BaseException as exc:  # re-raised by finish()
            self.error = exc
        finally:
            self._ready.set()

    def _tcp(self) -> None:
        assert isinstance(self.target, tuple)
        with socket.create_connection(self.target, timeout=TIMEOUT) as sock:
            host, port = sock.getsockname()[:2]
            self.local = f"({host}:{port})"
            while not self.stopping.is_set():
                try:
                    sock.sendall(b"AY RP")
                except OSError:
                    return
                self.sent += b"AY RP"
                if not self._read(lambda: sock.recv(256)):
                    return

    def _pty(self) -> None:
        assert isinstance(self.target, Path)
        fd = os.open(self.target, os.O_RDWR | os.O_NOCTTY)
        try:
            while not self.stopping.is_set():
                os.write(fd, b"AY RP")
                self.sent += b"AY RP"

                def read() -> bytes:
                    if not select.select([fd], [], [], 0.5)[0]:
                        return b""  # the daemon is gone: the pty's other side says nothing
                    return os.read(fd, 256)

                if not self._read(read):
                    return
        except OSError:
            return  # EIO: the daemon closed its side
        finally:
            os.close(fd)

    def _read(self, recv: object) -> bool:
        assert callable(recv)
        line = bytearray()
        while not line.endswith(b"\n"):
            try:
                data = recv()
            except OSError:
                return False
            if not data:
                return False
            line += data
        self.received += line
        self.answers += 1
        assert bytes(line) == b"-777\n", line
        if self.answers == 20:
            self._ready.set()
        return True

    def wait_busy(self) -> None:
        assert self._ready.wait(TIMEOUT), "the client never got going"
        assert self.error is None, self.error

    def finish(self) -> None:
        self.stopping.set()
        self.join(TIMEOUT)
        assert not self.is_alive()
        if self.error is not None:
            raise self.error


def command_line(port: int, link: Path, log: Path) -> tuple[str, ...]:
    return (
        "--tcp",
        f"127.0.0.1:{port}",
        "--pty",
        str(link),
        "--log",
        str(log),
        "--control",
        "off",
        "--view",
        "off",
    )


def start_talking(daemon: Daemon, link: Path) -> tuple[Talker, Talker]:
    with daemon.connect() as conn:
        assert conn.ask(b"AY LP-777 RP") == b"-777"
    tcp = Talker("tcp", daemon.tcp())
    pty = Talker("pty", link)
    tcp.start()
    pty.start()
    tcp.wait_busy()
    pty.wait_busy()
    return tcp, pty


def records(log: Path) -> tuple[list[dict[str, object]], bytes]:
    """The whole lines of the log as objects, and the rest (a last line without its end)."""
    data = log.read_bytes()
    lines = data.split(b"\n")
    whole, rest = lines[:-1], lines[-1]
    parsed = []
    for number, line in enumerate(whole, 1):
        try:
            parsed.append(json.loads(line))
        except ValueError:
            raise AssertionError(f"{log}:{number} is not a JSON object: {line[:200]!r}") from None
    return parsed, rest


def traffic_of(items: list[dict[str, object]], endpoint: str, direction: str) -> bytes:
    return b"".join(
        bytes.fromhex(str(r["hex"]))
        for r in items
        if r["kind"] == "traffic" and endpoint in str(r["endpoint"]) and r["dir"] == direction
    )


def restart_on_the_same_endpoints(
    omsd: Omsd, old: Daemon, args: tuple[str, ...], log: Path, before: bytes
) -> None:
    new = omsd(*args)
    assert [
        (e.board, e.model, e.link, e.kind, e.address) for e in new.endpoints if e.kind == "tcp"
    ] == [(e.board, e.model, e.link, e.kind, e.address) for e in old.endpoints if e.kind == "tcp"]
    assert new.pty_links == old.pty_links
    link = new.pty_links[0]
    (pty,) = [e for e in new.endpoints if e.kind == "pty"]
    assert os.readlink(link) == pty.device
    with new.connect() as conn:
        assert conn.ask(b"AY LP5 RP") == b"5"
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"AY RP")
        reply = b""
        deadline = time.monotonic() + TIMEOUT
        while not reply.endswith(b"\n") and time.monotonic() < deadline:
            if select.select([fd], [], [], 0.1)[0]:
                reply += os.read(fd, 256)
        assert reply == b"5\n", reply
    finally:
        os.close(fd)
    assert new.stop(signal.SIGTERM) == 0, new.stderr
    assert not os.path.lexists(link)
    # the log went on after what was there
    assert log.read_bytes().startswith(before)
    items, rest = records(log)
    assert rest == b""
    assert any(r["kind"] == "traffic" and r.get("data") == "AY LP5 RP" for r in items)


def test_sigterm_mid_traffic(omsd: Omsd, tmp_path: Path) -> None:
    link = tmp_path / "board1"
    log = tmp_path / "traffic.jsonl"
    args = command_line(free_port(), link, log)
    daemon = omsd(*args)
    tcp, pty = start_talking(daemon, link)
    try:
        assert daemon.stop(signal.SIGTERM) == 0, daemon.stderr
    finally:
        tcp.finish()
        pty.finish()
    assert not os.path.lexists(link), "pty link left behind"
    items, rest = records(log)
    assert rest == b"", f"the log ends in a cut line: {rest[:200]!r}"
    assert items[-1] == {"t": items[-1]["t"], "kind": "info", "message": "stopped"}
    # every byte in and out of the TCP client is in the log, in order
    logged_out = traffic_of(items, tcp.local, "out")
    logged_in = traffic_of(items, tcp.local, "in")
    assert tcp.answers >= 20
    assert logged_out.startswith(bytes(tcp.received)), "an answer the client got is not logged"
    assert bytes(tcp.sent).startswith(logged_in), "the log has input the client never wrote"
    assert len(logged_in) >= len(tcp.received) // 5 * 5  # each answer was to a logged question
    # and the pty's
    assert traffic_of(items, str(link), "out").startswith(bytes(pty.received))
    assert bytes(pty.sent).startswith(traffic_of(items, str(link), "in"))
    restart_on_the_same_endpoints(omsd, daemon, args, log, log.read_bytes())


def test_sigkill_mid_traffic(omsd: Omsd, tmp_path: Path) -> None:
    link = tmp_path / "board1"
    log = tmp_path / "traffic.jsonl"
    args = command_line(free_port(), link, log)
    daemon = omsd(*args)
    tcp, pty = start_talking(daemon, link)
    try:
        assert daemon.stop(signal.SIGKILL) == -signal.SIGKILL
    finally:
        tcp.finish()
        pty.finish()
    # every line but the last is whole; the last may be cut short (``rest``, not checked)
    items, _ = records(log)
    assert sum(r["kind"] == "traffic" for r in items) > 40
    logged_out = traffic_of(items, tcp.local, "out")
    assert logged_out.startswith(bytes(tcp.received))
    assert os.path.islink(link), "killed: nothing could remove the link"
    restart_on_the_same_endpoints(omsd, daemon, args, log, log.read_bytes())
