"""The pytest plugin: ``omsd_boards``, a fixture that serves virtual OMS boards to a test.

Installed with omsd, pytest loads this module through the ``pytest11`` entry point ``omsd``
(disable it with ``-p no:omsd``). Loading it costs an import of the standard library and
pytest: nothing starts until a test asks for the fixture. A test calls the fixture with the
boards it wants and gets a running daemon back::

    def test_something(omsd_boards):
        boards = omsd_boards(xy="PC48-4E", servo={"model": "PCIX-400", "link": "raw"}, pty=True)
        boards.connect("xy")                 # a TCP connection to the board (Connection)
        boards.serial("servo", pty=True)     # a pyserial port on the board's pty
        boards.control                       # omsd.control.client.Control, connected
        boards["xy"].tcp, boards["xy"].pty   # ("127.0.0.1", 40123), Path(".../xy")

Each call writes a TOML configuration (``omsd.toml`` in a directory of the test's
``tmp_path``; the keys are those of ``config/omsd.toml``), starts ``python -m omsd.tethered
--config`` (``omsd --config`` that stops when this process is gone) as a subprocess with every
board on a free TCP port of 127.0.0.1 (port 0, read back from the daemon's endpoint lines on
standard output) and, with ``pty=True``, on a pty whose link is in that directory; the control
socket is there too. It returns once every endpoint line is in and the control client is
connected. Teardown closes every connection the helpers opened, sends the
daemon SIGTERM, waits for it (and kills it if it does not go within ten seconds, which fails
the test), and removes any pty link or socket a killed daemon left behind. A daemon that
cannot start fails the test with one line: what happened and the daemon's standard error. When
a test fails, the tail of each daemon's standard error (the traffic, ``--view plain``) is added
to the report as a section "omsd".

Choices (the issue asks for "a fixture that starts a daemon with the boards they ask for on free
ports or ptys and hands back the endpoints and the control client, and tears everything down
afterwards"; the rest is left open):

* The fixture is a factory (``omsd_boards(...)``), function-scoped: a test says what it needs,
  and may start several daemons; each is stopped at the end of the test. Boards are keyword
  arguments (the name is the board's name), a model string or a table of ``[[board]]`` keys
  passed through to the TOML (``axes``, ``inputs``, ``link``, ``eos``, ``encoders``,
  ``firmware`` ...); positional models are named ``board1``, ``board2`` ... as the daemon names
  them; names that are not Python identifiers (``xy-stage``) or clash with an option go in
  ``boards={...}``. No boards at all: one PC48-4E, ``board1``, as ``omsd`` alone serves.
* ``tcp=True`` (the default) serves each board on ``127.0.0.1:0``; ``pty=True`` adds a pty;
  a board's own ``tcp``/``pty`` key (``True``, ``False`` or the config file's values) wins.
* The Unix socket path is limited to 107 bytes by the kernel; when the test's directory is too
  deep for that, the control socket goes into a short temporary directory under ``/tmp``,
  removed at teardown.
* The daemon runs the omsd this module belongs to (its directory is put first on
  ``PYTHONPATH``), without systemd's notify socket or journal even when the tests run under
  systemd, so it never reports "ready" to a unit that is not its own.
* The daemon stops when the test run that started it is gone, also when the run could not tear
  down (a CI timeout's SIGTERM, SIGKILL): it runs as :mod:`omsd.tethered`, whose standard input
  is a pipe from this process and whose end of file is SIGTERM. In a session of its own (so that
  a Ctrl-C reaches pytest, which tears down, and not the daemon) it would otherwise serve on.
* A daemon that exited during the test without being asked to (:meth:`Omsd.stop`) fails the test
  at teardown with its exit status and standard error: a crash of the emulator is a finding.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Generator, Iterator, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import TracebackType
from typing import IO, TYPE_CHECKING, Any, NoReturn

import pytest

from omsd.hostport import host_port

if TYPE_CHECKING:
    from omsd.control.client import Control

START_TIMEOUT = 15.0
"""Seconds a daemon may take to announce its endpoints and open its control socket."""

STOP_TIMEOUT = 10.0
"""Seconds a daemon may take to exit after SIGTERM before it is killed."""

IO_TIMEOUT = 10.0
"""Seconds a :class:`Connection` read waits by default."""

REPORT_LINES = 200
"""Lines of a daemon's standard error shown in the report of a failed test."""

VIEW_SETTLE = 0.05
"""Seconds a daemon's standard error must have been quiet before a failed test's report takes
its tail: a serving daemon writes its view's lines in batches, up to 10 ms after the bytes they
show (``omsd.telemetry.traffic.VIEW_BATCH``)."""

_SUN_PATH_MAX = 100  # bytes; sockaddr_un.sun_path is 108 with its NUL, keep a margin
_ENV_DROP = ("NOTIFY_SOCKET", "JOURNAL_STREAM", "WATCHDOG_USEC", "WATCHDOG_PID", "LISTEN_FDS")
_ENDPOINTS = ("tcp", "pty", "serial_port", "rfc2217")  # [[board]] keys: an endpoint line each
_OPTIONS = ("boards", "tcp", "pty", "link", "state", "timeout")
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


# -- what the daemon serves ---------------------------------------------------------------------


@dataclass(frozen=True)
class Board:
    """One board of a running daemon and where it can be reached (from the endpoint lines
    ``board1 PC48-4E driver tcp 127.0.0.1:40123``, ``... pty /path/board1 -> /dev/pts/7``,
    ``... serial /dev/ttyUSB0,9600,8N1``, ``... rfc2217 127.0.0.1:7148``)."""

    name: str
    model: str
    link: str  # "driver" or "raw"
    tcps: tuple[tuple[str, int], ...] = ()
    ptys: tuple[tuple[Path, str], ...] = ()  # (link, device)
    serials: tuple[str, ...] = ()  # "/dev/ttyUSB0,9600,8N1"
    rfc2217s: tuple[tuple[str, int], ...] = ()  # (host, port)

    @property
    def tcp(self) -> tuple[str, int] | None:
        """The (first) TCP address, ``(host, port)``."""
        return self.tcps[0] if self.tcps else None

    @property
    def host(self) -> str:
        return self._tcp()[0]

    @property
    def port(self) -> int:
        return self._tcp()[1]

    @property
    def pty(self) -> Path | None:
        """The (first) pty's link."""
        return self.ptys[0][0] if self.ptys else None

    @property
    def device(self) -> str | None:
        """The (first) pty's device, ``/dev/pts/N``."""
        return self.ptys[0][1] if self.ptys else None

    def _tcp(self) -> tuple[str, int]:
        if not self.tcps:
            raise LookupError(f"board {self.name} is not served on TCP")
        return self.tcps[0]


def _parse_endpoints(lines: list[str]) -> dict[str, Board]:
    boards: dict[str, Board] = {}
    for line in lines:
        parts = line.rstrip("\n").split(" ", 4)
        if len(parts) != 5 or parts[3] not in ("tcp", "pty", "serial", "rfc2217"):
            raise ValueError(f"not an endpoint line: {line!r}")
        name, model, link, kind, address = parts
        board = boards.get(name, Board(name, model, link))
        if kind in ("tcp", "rfc2217"):
            host, _, port = address.rpartition(":")
            where = (host.strip("[]"), int(port))
            if kind == "tcp":
                board = replace(board, tcps=(*board.tcps, where))
            else:
                board = replace(board, rfc2217s=(*board.rfc2217s, where))
        elif kind == "pty":
            path, _, device = address.partition(" -> ")
            board = replace(board, ptys=(*board.ptys, (Path(path), device)))
        else:
            board = replace(board, serials=(*board.serials, address))
        boards[name] = board
    return boards


# -- a TCP client -------------------------------------------------------------------------------


class Connection:
    """A TCP client of one board; every read has a deadline, nothing waits for ever."""

    def __init__(self, host: str, port: int, timeout: float = IO_TIMEOUT) -> None:
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.timeout = timeout
        self.buffer = bytearray()
        self.eof = False

    def __enter__(self) -> Connection:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self.sock.close()

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def _fill(self, deadline: float) -> bool:
        """Read what comes before ``deadline``; False when nothing came (time up or EOF)."""
        left = deadline - time.monotonic()
        if self.eof or left <= 0:
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

    def _deadline(self, timeout: float | None) -> tuple[float, float]:
        timeout = self.timeout if timeout is None else timeout
        return timeout, time.monotonic() + timeout

    def read(self, n: int, timeout: float | None = None) -> bytes:
        """Exactly ``n`` bytes; :class:`TimeoutError` (with what did come) otherwise."""
        timeout, deadline = self._deadline(timeout)
        while len(self.buffer) < n and self._fill(deadline):
            pass
        if len(self.buffer) < n:
            raise TimeoutError(
                f"expected {n} bytes within {timeout:g} s, got {bytes(self.buffer)!r}"
                + " and EOF" * self.eof
            )
        data = bytes(self.buffer[:n])
        del self.buffer[:n]
        return data

    def read_until(self, terminator: bytes = b"\n", timeout: float | None = None) -> bytes:
        """Everything up to and including ``terminator``."""
        timeout, deadline = self._deadline(timeout)
        while (i := self.buffer.find(terminator)) < 0:
            if not self._fill(deadline):
                raise TimeoutError(
                    f"no {terminator!r} within {timeout:g} s, got {bytes(self.buffer)!r}"
                    + " and EOF" * self.eof
                )
        data = bytes(self.buffer[: i + len(terminator)])
        del self.buffer[: i + len(terminator)]
        return data

    def ask(self, command: bytes, end: bytes = b"\n", timeout: float | None = None) -> bytes:
        """Send ``command``; the reply up to ``end`` (the driver link's end character, LF by
        default), without it."""
        self.send(command)
        return self.read_until(end, timeout)[: -len(end)]

    def quiet(self, duration: float) -> bytes:
        """Everything that arrives within ``duration`` seconds (often: nothing)."""
        deadline = time.monotonic() + duration
        while self._fill(deadline):
            pass
        data, self.buffer = bytes(self.buffer), bytearray()
        return data

    def at_eof(self, timeout: float | None = None) -> bool:
        """Whether the daemon closes the connection within ``timeout`` (after any data)."""
        _, deadline = self._deadline(timeout)
        while self._fill(deadline):
            pass
        return self.eof


# -- the daemon ---------------------------------------------------------------------------------


class _Drain(threading.Thread):
    """Reads a pipe into a list of lines until EOF, so the daemon never blocks on it."""

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
        except (OSError, ValueError):
            pass  # the pipe was closed under us at teardown
        finally:
            with self.changed:
                self.eof = True
                self.changed.notify_all()

    def wait_quiet(self, quiet: float, deadline: float) -> None:
        """Until no line has come for ``quiet`` seconds (or EOF, or ``deadline``)."""
        with self.changed:
            seen = len(self.lines)
            while not self.eof:
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                self.changed.wait(min(left, quiet))
                if len(self.lines) == seen:
                    return
                seen = len(self.lines)

    def wait_lines(self, n: int, deadline: float, alive: Callable[[], bool]) -> list[str]:
        with self.changed:
            while len(self.lines) < n and not self.eof and alive():
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self.changed.wait(min(left, 0.1))
            return list(self.lines)


def _one_line(text: str, limit: int = 4000) -> str:
    text = " | ".join(line.strip() for line in text.strip().splitlines() if line.strip())
    return text if len(text) <= limit else "..." + text[-limit:]


class Omsd:
    """A running ``omsd`` started by :func:`omsd_boards`: its boards, their endpoints and the
    control client. Use as ``boards["xy"]``, ``boards.connect("xy")``, ``boards.control``."""

    control: Control
    """The control client (:class:`omsd.control.client.Control`), connected to this daemon;
    its ``board=`` may be left out when the daemon has one board."""

    def __init__(self, directory: Path, config: Path, socket_path: Path, expect: int) -> None:
        self.directory = directory
        self.config = config
        self.control_socket = socket_path
        self.boards: dict[str, Board] = {}
        self.stopped = False  # stop() was asked for: an exit is no surprise
        self._closers: list[Callable[[], None]] = []
        env = {k: v for k, v in os.environ.items() if k not in _ENV_DROP}
        env["PYTHONUNBUFFERED"] = "1"
        here = str(Path(__file__).resolve().parent.parent)
        env["PYTHONPATH"] = os.pathsep.join(
            [here, *(p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p)]
        )
        self.process = subprocess.Popen(
            [sys.executable, "-m", "omsd.tethered", "--config", str(config)],
            stdin=subprocess.PIPE,  # its end of file stops the daemon: this process is gone
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            errors="replace",
            env=env,
            cwd=directory,
            start_new_session=True,  # a Ctrl-C at the terminal reaches pytest, not the daemon
        )
        assert self.process.stdout is not None and self.process.stderr is not None
        self._out = _Drain(self.process.stdout)
        self._err = _Drain(self.process.stderr)
        self._out.start()
        self._err.start()
        self._expect = expect

    # -- starting -------------------------------------------------------------------------------

    def _start(self, timeout: float) -> None:
        """Wait for the endpoint lines and the control socket; :class:`_StartFailure` if they
        do not come."""
        from omsd.control.client import Control

        deadline = time.monotonic() + timeout
        lines = self._out.wait_lines(self._expect, deadline, self.running)
        if len(lines) < self._expect:
            self._fail_start(f"{len(lines)} of {self._expect} endpoint lines", deadline)
        try:
            self.boards = _parse_endpoints(lines[: self._expect])
        except ValueError as exc:
            self._fail_start(str(exc), deadline)
        while True:
            try:
                self.control = Control(self.control_socket, timeout=timeout)
                break
            except OSError as exc:
                if not self.running() or time.monotonic() >= deadline:
                    what = f"no control socket at {self.control_socket} ({exc})"
                    self._fail_start(what, deadline)
                time.sleep(0.01)
        self._closers.append(self.control.close)

    def _fail_start(self, what: str, deadline: float) -> NoReturn:
        """A daemon that gave up by itself has closed its output and is exiting: wait for its
        status. One that is still at it when time is up is killed."""
        if self.running():
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(max(0.0, deadline - time.monotonic()))
        if self.running():
            self.process.kill()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(STOP_TIMEOUT)
            how = "not ready in time, killed"
        else:
            how = f"exit status {self.process.returncode}"
        self._join()
        self.stopped = True  # reported here, not again at teardown
        stderr = _one_line(self.stderr) or "(nothing on standard error)"
        raise _StartFailure(f"omsd did not start ({what}, {how}): {stderr}")

    # -- looking --------------------------------------------------------------------------------

    def __getitem__(self, name: str) -> Board:
        try:
            return self.boards[name]
        except KeyError:
            raise KeyError(f"no board {name!r}; boards: {', '.join(self.boards)}") from None

    def board(self, name: str | None = None) -> Board:
        """The board called ``name``; the only one when ``None``."""
        if name is not None:
            return self[name]
        if len(self.boards) != 1:
            raise LookupError(f"say which board: {', '.join(self.boards)}")
        return next(iter(self.boards.values()))

    @property
    def pid(self) -> int:
        return self.process.pid

    @property
    def stdout(self) -> str:
        """What the daemon wrote on standard output (its endpoint lines)."""
        return "".join(self._out.lines)

    @property
    def stderr(self) -> str:
        """What the daemon wrote on standard error so far: its log and the traffic (whose
        lines a serving daemon writes in batches, up to 10 ms after the bytes:
        :meth:`settled_stderr`)."""
        return "".join(self._err.lines)

    def settled_stderr(self, limit: float = 1.0) -> str:
        """:attr:`stderr` once the daemon has written what it had to say: nothing new for
        :data:`VIEW_SETTLE` (it writes its view's lines in batches, up to 10 ms after what
        they show), or at most ``limit`` seconds."""
        if self.running():
            self._err.wait_quiet(VIEW_SETTLE, time.monotonic() + limit)
        return self.stderr

    def running(self) -> bool:
        return self.process.poll() is None

    # -- talking --------------------------------------------------------------------------------

    def connect(self, board: str | None = None, timeout: float = IO_TIMEOUT) -> Connection:
        """A TCP connection to ``board`` (its first TCP endpoint), closed at teardown if the
        test has not closed it."""
        connection = Connection(*self.board(board)._tcp(), timeout=timeout)
        self._closers.append(connection.close)
        return connection

    def serial(self, board: str | None = None, *, pty: bool = False, timeout: float = 1.0) -> Any:
        """A pyserial port on ``board``: ``serial_for_url("socket://HOST:PORT")``, or with
        ``pty=True`` ``serial.Serial(pty link)``. Closed at teardown. Needs pyserial."""
        try:
            import serial  # type: ignore[import-untyped]
        except ImportError:
            raise ImportError(
                "omsd_boards(...).serial() needs pyserial: pip install pyserial"
            ) from None
        target = self.board(board)
        if pty:
            if target.pty is None:
                raise LookupError(f"board {target.name} is not served on a pty (pty=True)")
            port = serial.Serial(str(target.pty), timeout=timeout)
        else:
            host, number = target._tcp()
            port = serial.serial_for_url(f"socket://{host_port(host, number)}", timeout=timeout)
        self._closers.append(port.close)
        return port

    # -- stopping -------------------------------------------------------------------------------

    def stop(self, sig: int = signal.SIGTERM, timeout: float = STOP_TIMEOUT) -> int:
        """Send ``sig`` and wait for the daemon to exit; its exit status (negative: the signal
        that killed it). A daemon that does not exit in time is killed (:class:`TimeoutError`).
        The connections stay as they are (they see EOF)."""
        self.stopped = True
        if self.running():
            self.process.send_signal(sig)
        try:
            return self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(STOP_TIMEOUT)
            raise TimeoutError(f"omsd did not exit within {timeout:g} s of signal {sig}") from None

    def close(self) -> list[str]:
        """Teardown: close the helpers' connections, SIGTERM, wait, kill if need be, remove what
        a killed daemon left. Returns the problems (empty when all went well)."""
        problems: list[str] = []
        try:
            for close in reversed(self._closers):
                with contextlib.suppress(Exception):
                    close()
            self._closers.clear()
            if self.running():
                self.process.send_signal(signal.SIGTERM)
                try:
                    status = self.process.wait(STOP_TIMEOUT)
                except subprocess.TimeoutExpired:
                    problems.append(f"omsd did not exit within {STOP_TIMEOUT:g} s of SIGTERM")
                else:
                    if status != 0:
                        problems.append(f"omsd exited with status {status} on SIGTERM")
            elif not self.stopped:
                problems.append(
                    f"omsd exited by itself during the test (status {self.process.returncode})"
                )
        finally:
            if self.process.poll() is None:
                self.process.kill()
                with contextlib.suppress(subprocess.TimeoutExpired):
                    self.process.wait(STOP_TIMEOUT)
            self._join()
            for board in self.boards.values():
                for link, _ in board.ptys:
                    if os.path.lexists(link):
                        link.unlink()
                        if not problems:
                            problems.append(f"omsd left its pty link {link}")
            with contextlib.suppress(OSError):
                self.control_socket.unlink()
        if problems:
            problems[-1] += f"; stderr: {_one_line(self.stderr) or '(empty)'}"
        return problems

    def _join(self) -> None:
        if self.process.stdin is not None:
            with contextlib.suppress(OSError):
                self.process.stdin.close()
        for drain in (self._out, self._err):
            drain.join(STOP_TIMEOUT)
            with contextlib.suppress(OSError):
                drain.pipe.close()


class _StartFailure(Exception):
    """A daemon that did not come up (one line)."""


# -- the configuration --------------------------------------------------------------------------


def _toml_key(key: object) -> str:
    text = str(key)
    return text if _BARE_KEY.fullmatch(text) else _toml_string(text)


def _toml_string(text: str) -> str:
    # JSON escapes '"', '\' and the control characters as TOML basic strings want them; DEL
    # must be escaped in TOML too.
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007F")


def _toml_value(value: object, where: str) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{where}: expected a finite number, got {value!r}")
        return repr(value)
    if isinstance(value, str | Path):
        return _toml_string(str(value))
    if isinstance(value, Mapping):
        items = (f"{_toml_key(k)} = {_toml_value(v, f'{where}.{k}')}" for k, v in value.items())
        return "{ " + ", ".join(items) + " }" if value else "{}"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v, f"{where}[{i}]") for i, v in enumerate(value)) + "]"
    raise TypeError(f"{where}: cannot write {type(value).__name__} {value!r} into the TOML")


def _count(value: object) -> int:
    """Endpoint lines an endpoint key (``tcp``, ``pty``, ``serial_port``, ``rfc2217``) gives:
    one per item."""
    if value is None or value is False:
        return 0
    return len(value) if isinstance(value, list | tuple) else 1


@dataclass
class _Plan:
    """The TOML text of one daemon and how many endpoint lines it will print."""

    lines: list[str] = field(default_factory=list)
    endpoints: int = 0

    def table(self, header: str, values: Mapping[str, object]) -> None:
        self.lines += ["", header]
        self.lines += [f"{_toml_key(k)} = {_toml_value(v, k)}" for k, v in values.items()]

    @property
    def text(self) -> str:
        return "\n".join(self.lines).lstrip("\n") + "\n"


def _board_table(
    name: str, spec: str | Mapping[str, object], directory: Path, tcp: bool, pty: bool, link: str
) -> dict[str, object]:
    if isinstance(spec, str):
        table: dict[str, object] = {"model": spec}
    elif isinstance(spec, Mapping):
        table = {str(k): v for k, v in spec.items()}
    else:
        raise TypeError(
            f"board {name}: expected a model name or a table of [[board]] keys, got {spec!r}"
        )
    if table.setdefault("name", name) != name:
        raise ValueError(f"board {name}: its table says name = {table['name']!r}")
    table.setdefault("model", "PC48-4E")
    table.setdefault("link", link)
    want_tcp = table.pop("tcp", tcp)
    want_pty = table.pop("pty", pty)
    if want_tcp is True:
        table["tcp"] = "127.0.0.1:0"
    elif want_tcp is not False and want_tcp is not None:
        table["tcp"] = want_tcp
    if want_pty is True:
        table["pty"] = str(directory / name)
    elif want_pty is not False and want_pty is not None:
        table["pty"] = want_pty
    return table


# -- the fixture --------------------------------------------------------------------------------


class OmsdBoards:
    """The ``omsd_boards`` fixture: call it to start a daemon (see :meth:`__call__`)."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.daemons: list[Omsd] = []
        self._scratch: list[Path] = []

    def __call__(
        self,
        *models: str | Mapping[str, object],
        boards: Mapping[str, str | Mapping[str, object]] | None = None,
        tcp: bool = True,
        pty: bool = False,
        link: str = "driver",
        state: bool | str | Path = False,
        timeout: float = START_TIMEOUT,
        **named: str | Mapping[str, object],
    ) -> Omsd:
        """Start a daemon serving the boards asked for and wait until it is ready.

        ``models``: boards by model, named ``board1``, ``board2`` ...; ``name=MODEL`` or
        ``name={...}`` (and ``boards={name: ...}``): a board of that name, a model or a table of
        ``[[board]]`` keys (``model``, ``link``, ``axes``, ``inputs``, ``eos``, ``encoders``,
        ``firmware``, ``tcp``, ``pty`` ...). ``tcp``/``pty``: serve every board on a free TCP
        port / a pty (a board's own key wins). ``link``: the link of boards that do not say.
        ``state``: a state file for the boards' flash (``True``: ``omsd.state`` in the
        daemon's directory). ``timeout``: seconds to wait for the daemon to be ready."""
        specs: dict[str, str | Mapping[str, object]] = {}
        for i, model in enumerate(models):
            specs[f"board{i + 1}"] = model
        for name, spec in named.items():
            if not isinstance(spec, str | Mapping):
                raise TypeError(
                    f"omsd_boards({name}={spec!r}): {name} is no option ({', '.join(_OPTIONS)})"
                    " and a board is a model name or a table of [[board]] keys"
                )
        for name, spec in [*(boards or {}).items(), *named.items()]:
            if name in specs:
                raise ValueError(f"board {name} is given twice")
            specs[name] = spec
        if not specs:
            specs["board1"] = "PC48-4E"
        directory = self.directory / f"omsd-{len(self.daemons) + 1}"
        directory.mkdir(parents=True, exist_ok=True)
        socket_path = directory / "control.sock"
        if len(os.fsencode(socket_path)) > _SUN_PATH_MAX:
            short = "/tmp" if Path("/tmp").is_dir() else None
            scratch = Path(tempfile.mkdtemp(prefix="omsd-", dir=short))
            self._scratch.append(scratch)
            socket_path = scratch / "control.sock"
        plan = _Plan()
        plan.table("[log]", {"view": "plain"})
        plan.table("[control]", {"socket": str(socket_path)})
        if state is not False:
            file = directory / "omsd.state" if state is True else Path(state)
            plan.table("[state]", {"file": str(file)})
        for name, spec in specs.items():
            table = _board_table(name, spec, directory, tcp, pty, link)
            plan.endpoints += sum(_count(table.get(key)) for key in _ENDPOINTS)
            plan.table("[[board]]", table)
        config = directory / "omsd.toml"
        config.write_text(plan.text)
        daemon = Omsd(directory, config, socket_path, plan.endpoints)
        self.daemons.append(daemon)
        try:
            daemon._start(timeout)
        except _StartFailure as exc:
            failure = str(exc)
        else:
            return daemon
        pytest.fail(f"omsd_boards: {failure}", pytrace=False)  # outside the except: one message

    def close(self) -> list[str]:
        problems: list[str] = []
        for daemon in self.daemons:
            problems += daemon.close()
        for scratch in self._scratch:
            shutil.rmtree(scratch, ignore_errors=True)
        return problems

    def report(self) -> str:
        """The tail of every daemon's standard error, for a failed test's report."""
        parts = []
        for i, daemon in enumerate(self.daemons, 1):
            tail = daemon.settled_stderr().splitlines()[-REPORT_LINES:]
            head = f"-- omsd {i} (pid {daemon.pid}, {daemon.config}) --"
            parts.append("\n".join([head, *tail]))
        return "\n".join(parts)


_FACTORY = pytest.StashKey[OmsdBoards]()


@pytest.fixture
def omsd_boards(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[OmsdBoards]:
    """Start omsd daemons for this test: ``boards = omsd_boards(xy="PC48-4E", pty=True)``.

    Returns an :class:`Omsd` per call (``boards["xy"].tcp``, ``boards.connect("xy")``,
    ``boards.serial("xy")``, ``boards.control``); every daemon is stopped at the end of the
    test and its connections closed."""
    factory = OmsdBoards(tmp_path)
    request.node.stash[_FACTORY] = factory
    try:
        yield factory
    finally:
        problems = factory.close()
    if problems:
        pytest.fail("omsd_boards teardown: " + "; ".join(problems), pytrace=False)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, pytest.TestReport, pytest.TestReport]:
    """A failed test's report gets the tail of its daemons' standard error."""
    report = yield
    factory = item.stash.get(_FACTORY, None)
    if factory is not None and report.failed and factory.daemons:
        report.sections.append(("omsd", factory.report()))
    return report


__all__ = ["Board", "Connection", "Omsd", "OmsdBoards", "omsd_boards"]


# -- recordings (issue 17) ----------------------------------------------------------------------


def assert_replays(
    path: str | Path,
    *,
    model: str | None = None,
    config: str | Path | None = None,
    board: str | None = None,
    tolerance: float | None = None,
    time_tolerance: float | None = None,
) -> None:
    """Replay the recording at ``path`` (``omsd record``'s, or an ``omsd --log`` file) through
    the emulator, as ``omsd replay`` does, and fail with the table of differences if what omsd
    answers is not what the card answered::

        assert_replays("tests/sessions/homing.jsonl")

    ``model``, ``config`` and ``board`` are ``omsd replay``'s ``--model``, ``--config`` and
    ``--board``; ``tolerance`` (steps) and ``time_tolerance`` (seconds) its ``--tolerance`` and
    ``--time-tolerance`` (default: theirs). A file that is no recording raises
    :class:`omsd.recording.format.RecordingError` (one line)."""
    from omsd.recording.compare import DEFAULT_SECONDS, DEFAULT_STEPS, Tolerance
    from omsd.recording.replay import replay_file

    limits = Tolerance(
        DEFAULT_STEPS if tolerance is None else tolerance,
        DEFAULT_SECONDS if time_tolerance is None else time_tolerance,
    )
    result = replay_file(path, model=model, config=config, board=board, tolerance=limits)
    if not result.ok:
        raise AssertionError(f"{path} does not replay:\n{result.report()}")


__all__ += ["assert_replays"]
