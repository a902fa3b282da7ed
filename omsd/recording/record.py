"""``omsd record``: a transparent recorder between a host application and a card (issue 17).

The application talks to the recorder's endpoint (a pty, through a symlink, or a TCP port) as
it would to the card; the recorder passes every byte to the card (a serial port, or a TCP
address: a terminal server, another omsd) and every byte of the card's back, unchanged, and
writes both directions to a recording (:mod:`omsd.recording.format`), timed on the monotonic
clock as each chunk is read. It passes a chunk on first and writes its record after, in the same
callback of the event loop (:mod:`omsd.recording.ports`): the delay it adds is a ``read(2)``
and a ``write(2)``, microseconds.

Choices (``docs/decisions.md``, "Recording and replay"):

* **The card side is opened first and kept for the recorder's life**, as the card's data port is
  one stream whoever talks to it. It is opened before the endpoint is offered: a card that
  cannot be reached stops the recorder at once (exit status 2, one line).
* **A client that stops sending** (``nc -N``, ``shutdown(SHUT_WR)``) is kept for the card's
  answers: its connection is closed once the card has said nothing for ``linger`` seconds (one
  by default, ``--linger``), or when another client connects. The recorder cannot know what the
  card still owes it (omsd's daemon, which can, keeps such a client until its commands are done):
  a longer move's done marker needs a longer ``--linger``.
* **One client at a time.** A TCP client that connects while another is connected gets one line,
  ``omsd record: busy: another client is connected``, and is closed (its bytes would otherwise
  be interleaved with the first's on the card's one stream); the refusal is logged. The pty is
  held open by the recorder, so it is one client for the recorder's life: programs may open and
  close it in turn, and what the card says while none has it open waits in the pty for the next.
  What the card says while no TCP client is connected is recorded (endpoint ``(no client)``) and
  goes nowhere, as on a serial port nobody has open.
* **When the card goes away** (its socket closed or reset, the serial device gone), the recorder
  says so on standard error and in the recording, closes everything and exits with status 1:
  the recording is complete up to that moment and the application sees its connection close. No
  retry: a card that comes back is a new session, whose state the recording could not know.
* **SIGINT and SIGTERM** stop it cleanly: the endpoint closed (the pty link removed), the last
  record written, exit status 0.
* **The file is new**: an existing file that is not empty is refused (a recording is one
  session). It is created 0600, as the daemon's log.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import os
import signal
import socket
import sys
import termios
import time
import tty
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

from omsd.config import BoardConfig, TcpEndpoint
from omsd.files import missing_directory, pty_link_refusal
from omsd.hostport import host_port
from omsd.recording.format import NO_CLIENT, Line, RecordingWriter
from omsd.recording.ports import Port
from omsd.telemetry.traffic import Direction

CONNECT_TIMEOUT = 5.0
"""Seconds the recorder waits for the card's TCP address to accept."""

DEFAULT_LINGER = 1.0
"""Seconds a TCP client that has stopped sending is kept after the card last spoke to it."""

BUSY = b"omsd record: busy: another client is connected\r\n"

PARITIES = {"N": "none", "E": "even", "O": "odd", "M": "mark", "S": "space"}


class StartError(Exception):
    """The recorder cannot start; ``str()`` is one line."""


@dataclass(frozen=True)
class Card:
    """Where the card is: ``serial:PATH[,BAUD[,8N1]]`` or ``tcp:HOST:PORT``."""

    kind: str  # "serial" or "tcp"
    path: str = ""
    host: str = ""
    port: int = 0
    baud: int = 9600
    bytesize: int = 8
    parity: str = "N"
    stopbits: int = 1

    def __str__(self) -> str:
        if self.kind == "serial":
            return f"serial:{self.path},{self.baud},{self.bytesize}{self.parity}{self.stopbits}"
        return f"tcp:{host_port(self.host, self.port)}"

    @property
    def line(self) -> Line | None:
        """The serial line's speed (``None`` over TCP)."""
        if self.kind != "serial":
            return None
        bits = 1 + self.bytesize + (self.parity != "N") + self.stopbits
        return Line(self.baud, bits)


def parse_card(text: str) -> Card:
    """``serial:PATH[,BAUD[,8N1]]`` or ``tcp:HOST:PORT``; ``ValueError`` with what is wrong."""
    kind, _, rest = text.partition(":")
    if kind == "serial" and rest:
        path, *settings = rest.split(",")
        if not path or len(settings) > 2:
            raise ValueError(f"expected serial:PATH[,BAUD[,8N1]], got {text!r}")
        baud = 9600
        if settings:
            if not settings[0].isdigit() or int(settings[0]) <= 0:
                raise ValueError(f"expected a baud rate, got {settings[0]!r}")
            baud = int(settings[0])
        bytesize, parity, stopbits = 8, "N", 1
        if len(settings) == 2:
            frame = settings[1].upper()
            if (
                len(frame) != 3
                or frame[0] not in "5678"
                or frame[1] not in PARITIES
                or frame[2] not in "12"
            ):
                raise ValueError(f"expected data bits, parity and stop bits (8N1), got {frame!r}")
            bytesize, parity, stopbits = int(frame[0]), frame[1], int(frame[2])
        return Card("serial", path=path, baud=baud, bytesize=bytesize, parity=parity,
                    stopbits=stopbits)  # fmt: skip
    if kind == "tcp" and rest:
        host, _, port = rest.rpartition(":")
        host = host.strip("[]")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise ValueError(f"expected tcp:HOST:PORT, got {text!r}")
        return Card("tcp", host=host, port=int(port))
    raise ValueError(f"expected serial:PATH[,BAUD[,8N1]] or tcp:HOST:PORT, got {text!r}")


class Recorder:
    """The recorder: ``card`` where the card is, ``board`` what it is (for the header),
    ``log`` the recording's path, and one endpoint for the application: ``tcp`` or ``pty`` (a
    symlink's path). :meth:`start`, then :meth:`wait` (its exit status); :meth:`stop` from a
    signal handler or a test. ``out`` gets the endpoint line, ``err`` the messages."""

    def __init__(
        self,
        card: Card,
        board: BoardConfig,
        log: Path,
        *,
        tcp: TcpEndpoint | None = None,
        pty: Path | None = None,
        out: TextIO | None = None,
        err: TextIO | None = None,
        linger: float = DEFAULT_LINGER,
    ) -> None:
        if (tcp is None) == (pty is None):
            raise ValueError("one endpoint: tcp or pty")
        self.card = card
        self.board = board
        self.log = log
        self.tcp = tcp
        self.pty = pty
        self.out = out if out is not None else sys.stdout
        self.err = err if err is not None else sys.stderr
        self.writer: RecordingWriter | None = None
        self.upstream: Port | None = None
        self.client: Port | None = None
        self.label = NO_CLIENT
        self.address = ""  # the endpoint as bound: "127.0.0.1:40123" or "/path -> /dev/pts/7"
        self.status: int | None = None
        self._done = asyncio.Event()
        self._listener: socket.socket | None = None
        self._master = -1
        self._slave = -1
        self._device = ""
        self._serial = itertools.count(1)
        self._loop: asyncio.AbstractEventLoop | None = None
        self.linger = linger
        self._linger: asyncio.TimerHandle | None = None  # while a client that stopped sending

    # -- starting -----------------------------------------------------------------------------

    async def start(self) -> str:
        """Open the card, the recording and the endpoint; the endpoint line (as omsd's: board,
        model, link, kind, address). :class:`StartError` (nothing left behind) otherwise."""
        self._loop = asyncio.get_running_loop()
        if self.pty is not None:
            problem = pty_link_refusal(self.pty) or missing_directory(self.pty.parent)
            if problem is not None:
                raise StartError(f"--pty: {problem}")
        created = not os.path.lexists(self.log)
        try:
            self.writer = RecordingWriter(self.log)
        except FileExistsError as exc:
            raise StartError(f"--log: {exc}") from None
        except OSError as exc:
            raise StartError(f"--log: cannot open {self.log}: {exc.strerror or exc}") from None
        try:
            self.upstream = self._open_card()
            try:
                listen = self._open_endpoint()
            except OSError as exc:
                why = (exc.strerror or str(exc)).lower()
                raise StartError(f"--pty: cannot create a pty at {self.pty}: {why}") from None
        except BaseException:
            self._close_all()
            if created:
                with contextlib.suppress(OSError):
                    self.log.unlink()
            raise
        now = time.monotonic()
        line = self.card.line
        self.writer.header(
            now,
            time.time(),
            self.board,
            to=str(self.card),
            line=None if line is None else {"baud": line.baud, "bits": line.bits},
            listen=listen,
        )
        kind = "tcp" if self.tcp is not None else "pty"
        endpoint = f"{self.board.name} {self.board.model} {self.board.link} {kind} {self.address}"
        self._note("info", f"recording {self.card} into {self.log}, serving {listen}")
        self.out.write(endpoint + "\n")
        self.out.flush()
        self._say(f"recording the card on {self.card} into {self.log}; Ctrl-C stops")
        return endpoint

    def _open_card(self) -> Port:
        card = self.card
        loop = self._loop
        assert loop is not None
        if card.kind == "tcp":
            try:
                sock = socket.create_connection((card.host, card.port), timeout=CONNECT_TIMEOUT)
            except OSError as exc:
                why = exc.strerror or str(exc) or type(exc).__name__
                raise StartError(f"--to: cannot reach the card on {card}: {why.lower()}") from None
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            return Port(loop, sock.fileno(), self._from_card, self._card_gone, sock.close)
        from omsd.pacing import Line as SerialLine
        from omsd.transport.serial import open_device

        line = SerialLine(card.baud, card.bytesize, card.parity, card.stopbits)
        try:
            # locked against other openers, VMIN 1 (a read of nothing is a hang-up), non-blocking
            port = open_device(card.path, line)
        except (OSError, ValueError) as exc:
            raise StartError(f"--to: cannot open the card on {card}: {exc}") from None
        fd = port.fileno()
        return Port(loop, fd, self._from_card, self._card_gone, port.close)

    def _open_endpoint(self) -> str:
        loop = self._loop
        assert loop is not None
        if self.tcp is not None:
            family = socket.AF_INET6 if ":" in self.tcp.host else socket.AF_INET
            try:
                listener = socket.create_server(
                    (self.tcp.host, self.tcp.port), family=family, reuse_port=False
                )
            except OSError as exc:
                why = (exc.strerror or str(exc)).lower()
                raise StartError(f"--tcp: cannot listen on {self.tcp}: {why}") from None
            listener.setblocking(False)
            self._listener = listener
            host, port = listener.getsockname()[:2]
            self.address = host_port(host, port)
            loop.add_reader(listener.fileno(), self._accept)
            return f"tcp:{self.address}"
        assert self.pty is not None
        master, slave = os.openpty()
        self._master, self._slave = master, slave
        tty.setraw(slave, termios.TCSANOW)
        os.set_blocking(master, False)
        self._device = os.ttyname(slave)
        tmp = self.pty.with_name(f".{self.pty.name}.{os.getpid()}.tmp")
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        os.symlink(self._device, tmp)
        os.replace(tmp, self.pty)
        self.address = f"{self.pty} -> {self._device}"
        self.label = f"pty:{self.pty}"
        # the recorder holds the slave open: the pty is one client for the recorder's life
        self.client = Port(loop, master, self._from_client, self._client_gone, self._no_close)
        self._pair()
        return f"pty:{self.pty}"

    @staticmethod
    def _no_close() -> None:
        """The pty's master is closed with the endpoint (:meth:`_close_all`)."""

    def _pair(self) -> None:
        if self.client is not None and self.upstream is not None:
            self.client.source = self.upstream
            self.upstream.source = self.client

    # -- clients ------------------------------------------------------------------------------

    def _accept(self) -> None:
        listener = self._listener
        loop = self._loop
        if listener is None or loop is None:
            return
        try:
            sock, peer = listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._note("warning", f"accept failed: {exc.strerror or exc}")
            return
        peer_text = host_port(peer[0], peer[1]) if isinstance(peer, tuple) else str(peer)
        label = f"tcp:{self.address} #{next(self._serial)} ({peer_text})"
        if self.client is not None and self.client.eof:
            self._say(f"{label} takes over from {self.label}, which had stopped sending")
            self._end_linger()
        if self.client is not None:
            with contextlib.suppress(OSError):
                sock.send(BUSY)
            sock.close()
            self._note("warning", f"{self.board.name}: refused {label}: {self.label} is connected")
            self._say(f"refused {label}: {self.label} is connected")
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.label = label
        self.client = Port(
            loop, sock.fileno(), self._from_client, self._client_gone, sock.close, self._client_eof
        )
        self._pair()
        self._note("info", f"{self.board.name}: {label} connected")
        self._say(f"{label} connected")

    def _client_eof(self) -> None:
        """The client stopped sending: kept for the card's answers (``linger``)."""
        self._note("info", f"{self.board.name}: {self.label} stopped sending")
        self._linger_again()

    def _linger_again(self) -> None:
        if self._linger is not None:
            self._linger.cancel()
        assert self._loop is not None
        self._linger = self._loop.call_later(self.linger, self._end_linger)

    def _end_linger(self) -> None:
        self._linger = None
        client = self.client
        if client is not None:
            client.close()
            self._client_gone("closed")

    def _client_gone(self, why: str) -> None:
        if self._linger is not None:
            self._linger.cancel()
            self._linger = None
        label = self.label
        self.client = None
        self.label = NO_CLIENT
        if self.upstream is not None:
            self.upstream.source = None
            self.upstream.resume()
        self._note("info", f"{self.board.name}: {label} disconnected")
        self._say(f"{label} disconnected" + ("" if why == "closed" else f" ({why})"))

    # -- the bytes ----------------------------------------------------------------------------

    def _from_client(self, data: bytes) -> None:
        t = time.monotonic()
        if self.upstream is not None:
            self.upstream.write(data)  # first: the card's time is not the log's to take
        self._record(t, Direction.IN, data)

    def _from_card(self, data: bytes) -> None:
        t = time.monotonic()
        if self.client is not None:
            self.client.write(data)
            if self._linger is not None:
                self._linger_again()
        self._record(t, Direction.OUT, data)

    def _record(self, t: float, direction: Direction, data: bytes) -> None:
        writer = self.writer
        if writer is None:
            return
        try:
            writer.traffic(t, self.board.name, self.label, direction, data)
        except OSError as exc:
            self._say(f"cannot write {self.log}: {exc.strerror or exc}; stopping")
            self._finish(1)

    def _card_gone(self, why: str) -> None:
        self._note("error", f"the card on {self.card} went away: {why}")
        self._say(
            f"the card on {self.card} went away ({why}); the recording in {self.log} ends here"
        )
        self._finish(1)

    # -- stopping -----------------------------------------------------------------------------

    def stop(self) -> None:
        """Stop cleanly (SIGINT, SIGTERM): exit status 0."""
        self._finish(0)

    def _finish(self, status: int) -> None:
        if self.status is None:
            self.status = status
        self._done.set()

    async def wait(self) -> int:
        """Record until :meth:`stop` or the card goes; close everything; the exit status."""
        await self._done.wait()
        self.close()
        return self.status or 0

    def close(self) -> None:
        """Close the endpoint, the card and the recording (idempotent)."""
        if self.writer is not None and self.status == 0:
            self._note("info", "stopped")
        self._close_all()

    def _close_all(self) -> None:
        loop = self._loop
        if self._linger is not None:
            self._linger.cancel()
            self._linger = None
        if self._listener is not None:
            if loop is not None:
                loop.remove_reader(self._listener.fileno())
            self._listener.close()
            self._listener = None
        if self.client is not None:
            client, self.client = self.client, None
            client.close()
        if self.upstream is not None:
            upstream, self.upstream = self.upstream, None
            upstream.close()
        if self._master >= 0 or self._slave >= 0:
            assert self.pty is not None
            with contextlib.suppress(OSError):
                if self.pty.is_symlink() and os.readlink(self.pty) == self._device:
                    self.pty.unlink()
            for fd in (self._master, self._slave):
                if fd >= 0:
                    with contextlib.suppress(OSError):
                        os.close(fd)
            self._master = self._slave = -1
        if self.writer is not None:
            writer, self.writer = self.writer, None
            writer.close()

    # -- messages -----------------------------------------------------------------------------

    def _note(self, level: str, message: str) -> None:
        if self.writer is not None:
            with contextlib.suppress(OSError):
                self.writer.message(time.monotonic(), level, message)

    def _say(self, message: str) -> None:
        try:
            self.err.write(f"omsd record: {message}\n")
            self.err.flush()
        except (OSError, ValueError):
            pass


async def record(recorder: Recorder, signals: bool = True) -> int:
    """Start ``recorder`` and record until a signal (``signals``: SIGINT and SIGTERM stop it)
    or the card goes; the exit status (:class:`StartError` if it cannot start)."""
    loop = asyncio.get_running_loop()
    if signals:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, recorder.stop)
    try:
        await recorder.start()
        return await recorder.wait()
    finally:
        recorder.close()
        if signals:
            for sig in (signal.SIGINT, signal.SIGTERM):
                loop.remove_signal_handler(sig)


__all__ = ["BUSY", "DEFAULT_LINGER", "Card", "Recorder", "StartError", "parse_card", "record"]
