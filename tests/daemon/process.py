"""The real daemon, ``python -m omsd``, as a subprocess, and a socket client to talk to it.

The daemon says where each board can be reached with one line per endpoint on standard output::

    board1 PC48-4E driver tcp 127.0.0.1:40123
    board1 PC48-4E driver pty /tmp/.../board1 -> /dev/pts/7

:class:`Omsd` starts daemons (on free ports: ``--tcp 127.0.0.1:0``), waits for those lines with a
timeout and parses them into :class:`Endpoint` objects. Standard output and standard error are
drained by threads the whole time, so a daemon logging traffic on standard error never blocks on a
full pipe. :meth:`Omsd.close` (the fixture's teardown) stops every daemon still running with
SIGTERM, checks that it exited 0 and removed its pty links, and kills it in a ``finally``
whatever happened, so no process outlives a test.

:class:`Conn` is a TCP client with deadlines on every read: nothing here waits for ever and nothing
sleeps for a fixed long time.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO

TIMEOUT = 10.0
"""Seconds allowed for anything that should take a fraction of one (start, stop, a reply)."""

POLL = 0.01
"""Seconds between two looks at something that is expected to change soon."""


def daemon_env() -> dict[str, str]:
    """The environment of a daemon under test: never systemd's notify socket or journal, even
    when the tests themselves run under systemd."""
    env = dict(os.environ)
    for name in ("NOTIFY_SOCKET", "JOURNAL_STREAM", "WATCHDOG_USEC", "WATCHDOG_PID", "LISTEN_FDS"):
        env.pop(name, None)
    env["PYTHONUNBUFFERED"] = "1"
    return env


def run_omsd(
    *args: str, cwd: Path | None = None, timeout: float = TIMEOUT
) -> subprocess.CompletedProcess[str]:
    """Run ``omsd ARGS`` to completion (for the commands and errors that exit by themselves)."""
    return subprocess.run(
        [sys.executable, "-m", "omsd", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=daemon_env(),
        cwd=cwd,
        stdin=subprocess.DEVNULL,
    )


@dataclass(frozen=True)
class Endpoint:
    """One line of the daemon's standard output."""

    board: str
    model: str
    link: str
    kind: str  # "tcp", "pty", "serial" or "rfc2217"
    address: str  # "127.0.0.1:40123", "/path/link -> /dev/pts/7", "/dev/ttyUSB0,9600,8N1"

    @classmethod
    def parse(cls, line: str) -> Endpoint:
        parts = line.rstrip("\n").split(" ", 4)
        if len(parts) != 5 or parts[3] not in ("tcp", "pty", "serial", "rfc2217"):
            raise AssertionError(f"not an endpoint line: {line!r}")
        return cls(*parts)

    @property
    def host(self) -> str:
        assert self.kind in ("tcp", "rfc2217"), self
        return self.address.rsplit(":", 1)[0].strip("[]")

    @property
    def port(self) -> int:
        assert self.kind in ("tcp", "rfc2217"), self
        return int(self.address.rsplit(":", 1)[1])

    @property
    def path(self) -> Path:
        """The pty's symlink."""
        assert self.kind == "pty", self
        return Path(self.address.split(" -> ")[0])

    @property
    def device(self) -> str:
        """The pty's slave device, ``/dev/pts/N``."""
        assert self.kind == "pty", self
        return self.address.split(" -> ")[1]


class _Drain(threading.Thread):
    """Reads a pipe line by line into a list until EOF."""

    def __init__(self, pipe: IO[str]) -> None:
        super().__init__(daemon=True)
        self.pipe = pipe
        self.lines: list[str] = []
        self.changed = threading.Condition()
        self.eof = False

    def run(self) -> None:
        try:
            for line in self.pipe:
                with self.changed:
                    self.lines.append(line)
                    self.changed.notify_all()
        finally:
            with self.changed:
                self.eof = True
                self.changed.notify_all()

    def wait_lines(self, n: int, timeout: float, alive: Callable[[], bool]) -> list[str]:
        deadline = time.monotonic() + timeout
        with self.changed:
            while len(self.lines) < n and not self.eof:
                left = deadline - time.monotonic()
                if left <= 0 or not alive():
                    break
                self.changed.wait(min(left, 0.1))
            return list(self.lines)


class Daemon:
    """One running ``omsd``."""

    def __init__(self, args: Sequence[str], expect: int, cwd: Path) -> None:
        self.args = list(args)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "omsd", *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=daemon_env(),
            cwd=cwd,
        )
        assert self.proc.stdout is not None and self.proc.stderr is not None
        self._out = _Drain(self.proc.stdout)
        self._err = _Drain(self.proc.stderr)
        self._out.start()
        self._err.start()
        self.endpoints: list[Endpoint] = []
        lines = self._out.wait_lines(expect, TIMEOUT, lambda: self.proc.poll() is None)
        if len(lines) < expect:
            self.kill()
            raise AssertionError(
                f"omsd {' '.join(args)}: {len(lines)} of {expect} endpoint lines "
                f"(exit status {self.proc.returncode}); stdout {lines!r}; stderr {self.stderr!r}"
            )
        self.endpoints = [Endpoint.parse(line) for line in lines[:expect]]

    # -- what it said ---------------------------------------------------------------------------

    @property
    def stdout(self) -> str:
        return "".join(self._out.lines)

    @property
    def stderr(self) -> str:
        return "".join(self._err.lines)

    def tcp(self, board: str | None = None) -> tuple[str, int]:
        """The (first) TCP address of ``board`` (of the only board when None)."""
        endpoint = self._one("tcp", board)
        return endpoint.host, endpoint.port

    def pty(self, board: str | None = None) -> Path:
        """The (first) pty symlink of ``board``."""
        return self._one("pty", board).path

    def _one(self, kind: str, board: str | None) -> Endpoint:
        for endpoint in self.endpoints:
            if endpoint.kind == kind and board in (None, endpoint.board):
                return endpoint
        raise AssertionError(f"no {kind} endpoint for {board or 'the board'} in {self.endpoints}")

    @property
    def pty_links(self) -> list[Path]:
        return [e.path for e in self.endpoints if e.kind == "pty"]

    def connect(self, board: str | None = None) -> Conn:
        return Conn(*self.tcp(board))

    # -- life -----------------------------------------------------------------------------------

    @property
    def running(self) -> bool:
        return self.proc.poll() is None

    def stop(self, sig: signal.Signals = signal.SIGTERM, timeout: float = TIMEOUT) -> int:
        """Send ``sig`` and wait for the exit; returns the exit status (negative: killed by a
        signal). A daemon that does not exit in time is killed and the test fails."""
        if self.running:
            self.proc.send_signal(sig)
        try:
            status = self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            raise AssertionError(
                f"omsd did not exit within {timeout} s of {sig.name}; stderr {self.stderr!r}"
            ) from None
        self._join()
        return status

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(TIMEOUT)
        self._join()

    def _join(self) -> None:
        for drain in (self._out, self._err):
            drain.join(TIMEOUT)
            drain.pipe.close()


class Omsd:
    """Starts daemons in a test's directory and cleans up after them."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.daemons: list[Daemon] = []
        self._configs = 0

    def __call__(self, *args: str, config: str | None = None, expect: int | None = None) -> Daemon:
        """Start ``omsd ARGS`` (with ``--view plain`` unless a view is given) and wait for its
        endpoint lines. ``config`` is the text of a TOML file to write and pass as ``--config``;
        ``expect`` the number of endpoint lines (by default one per ``--tcp``, ``--pty``,
        ``--serial`` and ``--rfc2217``)."""
        argv = list(args)
        if config is not None:
            self._configs += 1
            path = self.directory / f"omsd-{self._configs}.toml"
            path.write_text(config)
            argv[:0] = ["--config", str(path)]
            if expect is None:
                raise ValueError("say how many endpoint lines a config file gives (expect=)")
        if "--view" not in argv:
            argv += ["--view", "plain"]
        if expect is None:
            expect = sum(a in ("--tcp", "--pty", "--serial", "--rfc2217") for a in argv)
        daemon = Daemon(argv, expect, self.directory)
        self.daemons.append(daemon)
        return daemon

    def close(self) -> None:
        """Stop every daemon still running with SIGTERM; it must exit 0 and leave no pty link.
        Each is killed in a ``finally`` whatever happens."""
        problems: list[str] = []
        for daemon in self.daemons:
            try:
                if daemon.running:
                    status = daemon.stop(signal.SIGTERM)
                    if status != 0:
                        problems.append(
                            f"omsd {' '.join(daemon.args)} exited {status} on SIGTERM; "
                            f"stderr tail {daemon.stderr[-2000:]!r}"
                        )
                for link in daemon.pty_links:
                    if os.path.lexists(link):
                        problems.append(f"pty link {link} left behind")
            except AssertionError as exc:
                problems.append(str(exc))
            finally:
                daemon.kill()
        assert not problems, "\n".join(problems)


class Conn:
    """A TCP client of one board, every read bounded by a deadline."""

    def __init__(self, host: str, port: int, timeout: float = TIMEOUT) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buffer = bytearray()
        self.eof = False

    def __enter__(self) -> Conn:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self.sock.close()

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def _fill(self, deadline: float) -> bool:
        """Read what comes before ``deadline``; False when nothing came (timeout or EOF)."""
        if self.eof:
            return False
        left = deadline - time.monotonic()
        if left <= 0:
            return False
        self.sock.settimeout(left)
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return False
        except ConnectionResetError:
            data = b""
        if not data:
            self.eof = True
            return False
        self.buffer += data
        return True

    def read(self, n: int, timeout: float = TIMEOUT) -> bytes:
        """Exactly ``n`` bytes, or fail with what did come."""
        deadline = time.monotonic() + timeout
        while len(self.buffer) < n:
            if not self._fill(deadline):
                break
        data = bytes(self.buffer[:n])
        if len(data) < n:
            raise AssertionError(
                f"expected {n} bytes within {timeout} s, got {data!r}" + (" and EOF" * self.eof)
            )
        del self.buffer[:n]
        return data

    def expect(self, expected: bytes, timeout: float = TIMEOUT) -> None:
        """The next bytes are exactly ``expected``."""
        got = self.read(len(expected), timeout)
        assert got == expected, f"expected {expected!r}, got {got!r}"

    def read_until(self, terminator: bytes, timeout: float = TIMEOUT) -> bytes:
        """Up to and including ``terminator``."""
        deadline = time.monotonic() + timeout
        while (i := self.buffer.find(terminator)) < 0:
            if not self._fill(deadline):
                raise AssertionError(
                    f"no {terminator!r} within {timeout} s; got {bytes(self.buffer)!r}"
                    + (" and EOF" * self.eof)
                )
        data = bytes(self.buffer[: i + len(terminator)])
        del self.buffer[: i + len(terminator)]
        return data

    def ask(self, command: bytes, end: bytes = b"\n", timeout: float = TIMEOUT) -> bytes:
        """Send ``command`` and return the reply up to ``end`` (excluded)."""
        self.send(command)
        return self.read_until(end, timeout)[: -len(end)]

    def quiet(self, duration: float) -> bytes:
        """Everything that arrives within ``duration`` (normally nothing)."""
        deadline = time.monotonic() + duration
        while self._fill(deadline):
            pass
        data, self.buffer = bytes(self.buffer), bytearray()
        return data

    def at_eof(self, timeout: float = TIMEOUT) -> bool:
        """Whether the daemon closes the connection within ``timeout`` (after any data)."""
        deadline = time.monotonic() + timeout
        while self._fill(deadline):
            pass
        return self.eof


def wait_for(condition: Callable[[], bool], timeout: float = TIMEOUT) -> bool:
    """Poll ``condition`` every few milliseconds until it holds or ``timeout`` passes."""
    deadline = time.monotonic() + timeout
    while True:
        if condition():
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(POLL)
