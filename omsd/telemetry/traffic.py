"""The daemon's traffic log: every byte in and out of every board, and the daemon's own messages.

Each chunk of traffic is a :class:`Traffic` record: wall-clock time, board, endpoint, direction
and the bytes. :class:`TrafficLog` shows the records on a stream (standard error by default) and
can also append them to a JSON-lines file.

Control characters are shown the way the PC48 manual writes them: "the response from the board
to the RQ command is <LF><CR>067<LF><CR>" (§6.13, RQ), and the kill and done-clear characters in
caret notation ("A Control-D (ASCII 4)", "Control-Y (hex 19)"), so :func:`visible` turns
``b"WY\\n\\r\\x04\\x19"`` into ``WY<LF><CR>^D^Y``. The DOS driver's done marker is "an ! ...
followed by the byte read from the done flag register of the board" (§7.3.3), any byte at all;
other bytes outside printable ASCII appear as two hex digits in angle brackets (``<8F>``).

Views on the stream
-------------------
``plain``
    One line per record, for pipes and systemd::

        12:00:01.234 board1 tcp:127.0.0.1:7048 #1 <- RQ
        12:00:01.240 board1 tcp:127.0.0.1:7048 #1 -> <LF><CR>067<LF><CR>
        12:00:02.500 board1 [done X]
        12:00:03.000 warning: board1: second client refused

    The arrow points the way the bytes went, as seen from the board named on the left:
    ``<-`` into the board (:attr:`Direction.IN`, host to board, what the client sent),
    ``->`` out of the board (:attr:`Direction.OUT`, board to host, what the client received).
    Board events are in brackets; the daemon's warnings and errors say so. Times are local
    time of day, to the millisecond.
``rich``
    The same columns in colour for a terminal (``rich``): board and endpoint columns aligned,
    ``<-`` in yellow, ``->`` in green, control characters highlighted so that a literal ``<``
    or ``^`` sent as text can be told apart, events in magenta, warnings yellow, errors red.
    A scrolling log, not a full-screen layout: one ``print`` per record. ``NO_COLOR`` is
    honoured.
``off``
    Nothing on the stream; the file, if any, is still written.
``auto`` (the default)
    ``plain`` with journald level prefixes when the stream is connected to the journal, else
    ``rich`` when the stream is a terminal, else ``plain``.

journald
--------
sd-daemon(3): "#define SD_ERR "<3>" ... SD_WARNING "<4>" ... SD_INFO "<6>" ... These prefixes are
intended to be used in conjunction with stderr-based logging (or stdout-based logging) as
implemented by systemd." So when the stream is connected to the journal every plain line starts
with ``<6>`` (traffic, events, info), ``<4>`` (warning) or ``<3>`` (error). systemd.exec(5) says
``$JOURNAL_STREAM`` holds the "device:inode" of the journal stream and that these "should be
compared with the values set in the environment variable": the prefixes are used when the
variable is set and either matches the stream's file descriptor or the stream has no file
descriptor to compare (a test's ``StringIO``). A child that inherited the variable but writes to
a pipe or a file of its own gets no prefixes.

The JSON-lines file
-------------------
One object per line, each with a ``kind``::

    {"t": 1700000000.123456, "kind": "traffic", "board": "board1",
     "endpoint": "tcp:127.0.0.1:7048 #1", "dir": "in", "data": "WY\\r", "hex": "57590d"}
    {"t": 1700000002.5, "kind": "event", "board": "board1", "what": "done X"}
    {"t": 1700000003.0, "kind": "warning", "message": "..."}      (also "info" and "error")

``t`` is the wall-clock time in seconds since the epoch (``time.time()``). ``dir`` is ``in``
(host to board) or ``out`` (board to host). ``data`` is the bytes decoded as latin-1, a lossless
one-to-one mapping (``data.encode("latin-1")`` gives the bytes back; JSON escapes control
characters as ``\\u0004`` and so on); ``hex`` is the same bytes in hex, for grep and for tools
without latin-1. :meth:`Traffic.from_record` reads a traffic object back.

The file is opened for appending (``O_APPEND``; created ``0600`` if missing, or ``0640`` in the
group given, :func:`omsd.files.open_log`; an existing file keeps its permissions) and every line
is handed to the kernel with one ``write(2)`` of the whole line, with no buffering in this
process: when the daemon crashes, even by SIGKILL, every record logged before is in the file,
and at most the line being written is cut short. (A power failure is another matter: there is
no fsync.) :meth:`TrafficLog.reopen` (the daemon's SIGHUP) opens the path again, for logrotate:
after a rotation that renamed the file, the lines go to a new file at the path.

The log is not thread-safe; the daemon calls it from its one event-loop thread.
"""

from __future__ import annotations

import datetime
import json
import os
import pathlib
import sys
import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any, TextIO

from rich.console import Console
from rich.style import Style
from rich.text import Text

from omsd.files import open_log

VIEWS = ("auto", "rich", "plain", "off")
"""The accepted values of ``TrafficLog(view=...)``."""

# sd-daemon(3) level prefixes.
SD_ERR = "<3>"
SD_WARNING = "<4>"
SD_INFO = "<6>"


class Direction(Enum):
    """Which way the bytes went."""

    IN = "in"
    """Host to board: bytes the client sent."""
    OUT = "out"
    """Board to host: bytes sent to the client."""

    @property
    def arrow(self) -> str:
        """``<-`` into the board, ``->`` out of it, as seen from the board's column."""
        return "<-" if self is Direction.IN else "->"


@dataclass(frozen=True)
class Traffic:
    """One chunk of bytes through one endpoint of one board."""

    time: float
    """Wall-clock time, ``time.time()``."""
    board: str
    endpoint: str
    """Where the bytes passed, e.g. ``tcp:127.0.0.1:7048 #3`` or ``pty:/tmp/omsd/board1``."""
    direction: Direction
    data: bytes

    def to_record(self) -> dict[str, Any]:
        """The JSON-lines object for this chunk."""
        return {
            "t": self.time,
            "kind": "traffic",
            "board": self.board,
            "endpoint": self.endpoint,
            "dir": self.direction.value,
            "data": self.data.decode("latin-1"),
            "hex": self.data.hex(),
        }

    @classmethod
    def from_record(cls, record: Mapping[str, Any]) -> Traffic:
        """Read back an object written by :meth:`to_record` (``kind`` must be ``traffic``)."""
        if record.get("kind") != "traffic":
            raise ValueError(f"not a traffic record: kind {record.get('kind')!r}")
        return cls(
            time=float(record["t"]),
            board=str(record["board"]),
            endpoint=str(record["endpoint"]),
            direction=Direction(record["dir"]),
            data=bytes.fromhex(record["hex"]),
        )


class TrafficLogError(OSError):
    """The traffic log file cannot be opened; ``str()`` is one line for the command line."""

    def __str__(self) -> str:
        return f"cannot open traffic log {self.filename}: {self.strerror}"


_NAMED = {0x0A: "<LF>", 0x0D: "<CR>"}


def _pieces(data: bytes) -> list[tuple[str, bool]]:
    """Split ``data`` into runs of printable text (``False``) and shown control bytes (``True``)."""
    out: list[tuple[str, bool]] = []
    start = 0
    for i, byte in enumerate(data):
        if 0x20 <= byte < 0x7F:
            continue
        if start < i:
            out.append((data[start:i].decode("ascii"), False))
        if byte in _NAMED:
            shown = _NAMED[byte]
        elif byte < 0x20:
            shown = "^" + chr(byte + 0x40)
        else:
            shown = f"<{byte:02X}>"
        out.append((shown, True))
        start = i + 1
    if start < len(data):
        out.append((data[start:].decode("ascii"), False))
    return out


def visible(data: bytes) -> str:
    """Show bytes so a person can read them, whatever they are.

    Printable ASCII (space to ``~``) as itself; LF and CR as ``<LF>`` and ``<CR>`` (the manual's
    notation); the other control characters 0x00-0x1F in caret notation (``^D`` for Control-D,
    ``^Y`` for Control-Y, ``^[`` for ESC); DEL and bytes 0x80-0xFF as ``<XX>`` in hex.
    """
    return "".join(text for text, _ in _pieces(data))


def _clock_text(t: float) -> str:
    """Local time of day to the millisecond (truncated, so it never shows ``60.000``)."""
    moment = datetime.datetime.fromtimestamp(t)
    return f"{moment:%H:%M:%S}.{moment.microsecond // 1000:03d}"


def _on_journal(stream: TextIO, env: Mapping[str, str]) -> bool:
    """Whether ``stream`` is the journal stream systemd announced in ``$JOURNAL_STREAM``."""
    announced = env.get("JOURNAL_STREAM", "")
    if not announced:
        return False
    try:
        fd = stream.fileno()
    except (OSError, ValueError, AttributeError):
        return True  # nothing to compare (e.g. StringIO): trust the variable
    try:
        st = os.fstat(fd)
    except OSError:
        return False
    return announced.strip() == f"{st.st_dev}:{st.st_ino}"


def _isatty(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (OSError, ValueError, AttributeError):
        return False


_TIME = Style(dim=True)
_BOARD = Style(color="cyan", bold=True)
_ENDPOINT = Style(color="blue")
_ARROW = {Direction.IN: Style(color="yellow", bold=True), Direction.OUT: Style(color="green")}
_DATA = {Direction.IN: Style(color="yellow"), Direction.OUT: Style(color="green")}
_CONTROL = Style(color="magenta")
_EVENT = Style(color="magenta", bold=True)
_LEVEL = {"info": Style(), "warning": Style(color="yellow"), "error": Style(color="red", bold=True)}


class TrafficLog:
    """Shows traffic, board events and the daemon's messages, and appends them to a file.

    ``view`` is ``auto``, ``rich``, ``plain`` or ``off`` (see the module text); ``file`` a
    JSON-lines file to append to, opened at once (:class:`TrafficLogError`, an ``OSError``,
    if it cannot be); ``stream`` where the view is written (standard error by default); ``env``
    the environment in which ``JOURNAL_STREAM`` is looked up (``os.environ`` by default);
    ``clock`` the wall clock for :meth:`info`, :meth:`warning` and :meth:`error`; ``group``
    the group a file created here is given (mode 0640; without one it is 0600).

    A stream that fails (a closed pipe) is given up silently and the file goes on; a file that
    fails (a full disk) is reported once as an error on the stream and then closed.
    """

    def __init__(
        self,
        view: str = "auto",
        file: pathlib.Path | None = None,
        stream: TextIO | None = None,
        env: Mapping[str, str] | None = None,
        *,
        clock: Callable[[], float] = _time.time,
        group: str | None = None,
    ) -> None:
        if view not in VIEWS:
            raise ValueError(f"unknown log view {view!r}: expected one of {', '.join(VIEWS)}")
        self._stream: TextIO = sys.stderr if stream is None else stream
        self._clock = clock
        environ: Mapping[str, str] = os.environ if env is None else env
        journal = view in ("auto", "plain") and _on_journal(self._stream, environ)
        if view == "auto":
            view = "plain" if journal or not _isatty(self._stream) else "rich"
        self.view = view
        """The view in use: ``rich``, ``plain`` or ``off`` (never ``auto``)."""
        self.journal = journal
        """Whether plain lines carry sd-daemon(3) level prefixes."""
        self.path = file
        self.group = group
        self._console: Console | None = None
        if view == "rich":
            self._console = Console(
                file=self._stream,
                soft_wrap=True,
                markup=False,
                emoji=False,
                highlight=False,
            )
        self._widths = [0, 0]  # board and endpoint columns of the rich view
        self._fd: int | None = None
        if file is not None:
            try:
                self._fd = open_log(file, group)
            except OSError as exc:
                raise TrafficLogError(exc.errno, exc.strerror or str(exc), str(file)) from exc

    # ----------------------------------------------------------------- public interface

    def record(self, item: Traffic) -> None:
        """Log one chunk of traffic."""
        if self._fd is not None:
            self._write_file(item.to_record())
        if self.view == "plain":
            self._plain(
                SD_INFO,
                f"{_clock_text(item.time)} {item.board} {item.endpoint} "
                f"{item.direction.arrow} {visible(item.data)}",
            )
        elif self.view == "rich":
            text = self._rich_head(item.time, item.board, item.endpoint)
            text.append(item.direction.arrow, _ARROW[item.direction])
            text.append(" ")
            for piece, control in _pieces(item.data):
                text.append(piece, _CONTROL if control else _DATA[item.direction])
            self._rich(text)

    def event(self, time: float, board: str, what: str) -> None:
        """Log a board event (``done X``, ``limit X+``, ``slip Y``, ``command error``...)."""
        if self._fd is not None:
            self._write_file({"t": time, "kind": "event", "board": board, "what": what})
        if self.view == "plain":
            self._plain(SD_INFO, f"{_clock_text(time)} {board} [{what}]")
        elif self.view == "rich":
            text = self._rich_head(time, board, None)
            text.append(f"[{what}]", _EVENT)
            self._rich(text)

    @property
    def stream(self) -> TextIO:
        """Where the view is written (standard error unless given)."""
        return self._stream

    def info(self, message: str, *, view: bool = True) -> None:
        """Log one of the daemon's messages (startup, where each board can be reached...);
        ``view=False``: to the file only (the terminal shows it already)."""
        self._message("info", SD_INFO, message, view)

    def warning(self, message: str) -> None:
        """Log something that went wrong but that the daemon survives."""
        self._message("warning", SD_WARNING, message)

    def error(self, message: str) -> None:
        """Log an error."""
        self._message("error", SD_ERR, message)

    def reopen(self) -> bool:
        """Open the file's path again and write there from now on (logrotate's "reopen your
        log files", the daemon's SIGHUP): after a rotation that renamed the file, a new one is
        created (0600, or 0640 in the group). Also a file given up after a failed write gets
        another chance. ``False`` if there is no file or it cannot be opened (logged; the old
        one, if any, is still written)."""
        if self.path is None:
            return False
        try:
            fd = open_log(self.path, self.group)
        except OSError as exc:
            self.error(f"traffic log {self.path}: cannot reopen: {exc.strerror or exc}")
            return False
        old, self._fd = self._fd, fd
        if old is not None:
            os.close(old)
        return True

    def close(self) -> None:
        """Flush the stream and close the file; later calls do nothing. The stream stays usable."""
        self._flush_stream()
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)

    def __enter__(self) -> TrafficLog:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ----------------------------------------------------------------- the file

    def _write_file(self, record: dict[str, Any]) -> None:
        assert self._fd is not None
        line = (json.dumps(record) + "\n").encode("ascii")  # ensure_ascii: always ASCII
        view = memoryview(line)
        try:
            while view:
                view = view[os.write(self._fd, view) :]
        except OSError as exc:
            fd, self._fd = self._fd, None
            os.close(fd)
            self.error(f"traffic log {self.path}: {exc.strerror}; no longer written")

    # ----------------------------------------------------------------- the stream

    def _message(self, level: str, prefix: str, message: str, view: bool = True) -> None:
        t = self._clock()
        if self._fd is not None:
            self._write_file({"t": t, "kind": level, "message": message})
        if not view:
            return
        label = "" if level == "info" else f"{level}: "
        lines = message.splitlines() or [""]
        if self.view == "plain":
            for line in lines:
                self._plain(prefix, f"{_clock_text(t)} {label}{line}")
        elif self.view == "rich":
            for line in lines:
                text = Text()
                text.append(_clock_text(t), _TIME)
                text.append(" ")
                text.append(f"{label}{line}", _LEVEL[level])
                self._rich(text)

    def _plain(self, prefix: str, line: str) -> None:
        try:
            self._stream.write(f"{prefix}{line}\n" if self.journal else f"{line}\n")
            self._stream.flush()
        except (OSError, ValueError):
            self._give_up_stream()

    def _rich_head(self, t: float, board: str, endpoint: str | None) -> Text:
        self._widths[0] = max(self._widths[0], len(board))
        text = Text()
        text.append(_clock_text(t), _TIME)
        text.append(" ")
        text.append(board.ljust(self._widths[0]), _BOARD)
        text.append(" ")
        if endpoint is not None:
            self._widths[1] = max(self._widths[1], len(endpoint))
            text.append(endpoint.ljust(self._widths[1]), _ENDPOINT)
            text.append(" ")
        return text

    def _rich(self, text: Text) -> None:
        assert self._console is not None
        try:
            self._console.print(text)
            self._stream.flush()
        except (OSError, ValueError):
            self._give_up_stream()

    def _flush_stream(self) -> None:
        if self.view == "off":
            return
        try:
            self._stream.flush()
        except (OSError, ValueError):
            self._give_up_stream()

    def _give_up_stream(self) -> None:
        self.view = "off"
        self._console = None
