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
group given, :func:`omsd.files.open_log`; an existing file keeps its permissions), and nothing
is buffered in this process beyond one turn of the daemon's work. The daemon *holds* the log
(:meth:`TrafficLog.hold`) while it handles what one client wrote, or one of a board's
deadlines. It writes the turn's lines to the file (:meth:`TrafficLog.write_kept`) when it has
made the replies and before it sends them: the traffic in and out, the events and messages, in
order, whole lines in one ``write(2)``; the view's lines follow the replies, in one write to
the stream, so that their formatting never delays a reply. A reply is in the file before its
client can have it: when the daemon crashes, even by SIGKILL, every byte a client got is in
the file, and only the last line may be cut short. (A power failure is
another matter: there is no fsync.) :meth:`TrafficLog.reopen` (the daemon's SIGHUP) opens the
path again, for logrotate: after a rotation that renamed the file, the lines go to a new file
at the path.

Making the lines is :mod:`omsd.telemetry.lines`: the same bytes as ``datetime``,
``json.dumps`` and ``rich``'s ``Console.print`` made, in a fraction of their time.

The log is not thread-safe; the daemon calls it from its one event-loop thread.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import sys
import time as _time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Any, TextIO

from omsd.files import open_log
from omsd.telemetry.lines import (
    RichStyles,
    clock_text,
    json_line,
    pieces,
    traffic_json,
    visible,
)

if TYPE_CHECKING:
    import asyncio

VIEWS = ("auto", "rich", "plain", "off")
"""The accepted values of ``TrafficLog(view=...)``."""

#: How long the view's lines may wait for more in a batch (:meth:`TrafficLog.batch_view`): too
#: short for a reader to notice, long enough that a client's round trips do not each pay for a
#: line formatted and a write to the stream (issue 16).
VIEW_BATCH = 0.01

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


# The rich view's styles, in rich's style syntax: rich is imported only when the view is rich,
# not for a daemon whose traffic goes to a file, the journal or nowhere (issue 16: start-up)
_TIME = "dim"
_BOARD = "bold cyan"
_ENDPOINT = "blue"
_ARROW = {Direction.IN: "bold yellow", Direction.OUT: "green"}
_DATA = {Direction.IN: "yellow", Direction.OUT: "green"}
_CONTROL = "magenta"
_EVENT = "bold magenta"
_LEVEL = {"info": "none", "warning": "yellow", "error": "bold red"}


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

    **Held** (:meth:`hold` ... :meth:`release`, the board service's way while it handles a
    client's bytes or a deadline): what is logged meanwhile is kept, in order; its JSON lines
    are written to the file by :meth:`write_kept` (the service's, just before a turn's replies
    are sent) or when the outermost hold is released, the view's lines at that release, each
    in one write. Not held, each call is written at once.

    **Batched view** (:meth:`batch_view`, the daemon's way once it serves): the file is written
    as above, but the view's lines wait up to :data:`VIEW_BATCH` for more and are then formatted
    and written in one go, off the reply path (issue 16: the view costs <= 5 % of a round
    trip). :meth:`close` and :meth:`unbatch_view` write what waits.
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
        on_journal = _on_journal(self._stream, environ)
        journal = view in ("auto", "plain") and on_journal
        if view == "auto":
            view = "plain" if journal or not _isatty(self._stream) else "rich"
        self.view = view
        """The view in use: ``rich``, ``plain`` or ``off`` (never ``auto``)."""
        self.journal = journal
        """Whether plain lines carry sd-daemon(3) level prefixes."""
        self._on_journal = on_journal  # (for the errors said with the view off)
        self.path = file
        self.group = group
        self._styles: RichStyles | None = None
        if view == "rich":
            from rich.console import Console

            console = Console(
                file=self._stream,
                soft_wrap=True,
                markup=False,
                emoji=False,
                highlight=False,
            )
            self._styles = RichStyles(console)
        self._widths = [0, 0]  # board and endpoint columns of the rich view
        self._fd: int | None = None
        if file is not None:
            try:
                self._fd = open_log(file, group)
            except OSError as exc:
                raise TrafficLogError(exc.errno, exc.strerror or str(exc), str(file)) from exc
            self._end_cut_line(file, self._fd)
        self._held = 0  # depth of hold() calls not yet released
        self._queue: list[_Entry] = []  # what was logged while held, in order
        self._filed = 0  # how many of them are in the file already (write_kept)
        self._batch: tuple[asyncio.AbstractEventLoop, float] | None = None  # batch_view's
        self._unshown: list[_Entry] = []  # entries in the file whose view lines wait
        self._show_timer: asyncio.TimerHandle | None = None  # when they are to be written
        self.wants_traffic = True
        """Whether traffic is shown or written anywhere (a caller may skip making records)."""
        self._wanted()

    def _wanted(self) -> None:
        self.wants_traffic = self._fd is not None or self.view != "off"

    # ----------------------------------------------------------------- public interface

    def record(self, item: Traffic) -> None:
        """Log one chunk of traffic."""
        self.traffic(item.time, item.board, item.endpoint, item.direction, item.data)

    def traffic(
        self, time: float, board: str, endpoint: str, direction: Direction, data: bytes
    ) -> None:
        """Log one chunk of traffic, given as the fields of a :class:`Traffic`."""
        if not self.wants_traffic:
            return
        self._queue.append((_TRAFFIC, time, board, endpoint, direction, data))
        if not self._held:
            self._flush()

    def event(self, time: float, board: str, what: str) -> None:
        """Log a board event (``done X``, ``limit X+``, ``slip Y``, ``command error``...)."""
        self._queue.append((_EVENT_ENTRY, time, board, what))
        if not self._held:
            self._flush()

    @property
    def stream(self) -> TextIO:
        """Where the view is written (standard error unless given)."""
        return self._stream

    def info(self, message: str, *, view: bool = True) -> None:
        """Log one of the daemon's messages (startup, where each board can be reached...);
        ``view=False``: to the file only (the terminal shows it already)."""
        self._message("info", message, view)

    def warning(self, message: str) -> None:
        """Log something that went wrong but that the daemon survives."""
        self._message("warning", message)

    def error(self, message: str) -> None:
        """Log an error."""
        self._message("error", message)

    def batch_view(self, loop: asyncio.AbstractEventLoop, delay: float = VIEW_BATCH) -> None:
        """From now on let the view's lines wait up to ``delay`` seconds on ``loop`` and write
        them in one go (see the class text). The file is written as before."""
        self._batch = (loop, delay)

    def unbatch_view(self) -> None:
        """Write the view's lines that wait, and from now on each at once again."""
        self._batch = None
        self._show_unshown()

    def hold(self) -> None:
        """Keep what is logged from now on until the matching :meth:`release` (holds nest)."""
        self._held += 1

    def release(self) -> None:
        """End a :meth:`hold`; the outermost one formats and writes what was kept."""
        self._held -= 1
        if not self._held and self._queue:
            self._flush()

    def write_kept(self) -> None:
        """Write what is kept to the file now, in one write; the holds stay, and the view's
        lines wait for the release. The service calls it when it has made a turn's replies and
        before it sends them, so that a reply is in the file before the client can have it
        (even a SIGKILL then loses no line of what a client got) while the view's formatting
        stays off the reply path."""
        queue = self._queue
        if self._fd is not None and len(queue) > self._filed:
            lines = [self._json(entry) for entry in queue[self._filed :]]
            self._filed = len(queue)
            self._write_file("".join(lines))

    def reopen(self) -> bool:
        """Open the file's path again and write there from now on (logrotate's "reopen your
        log files", the daemon's SIGHUP): after a rotation that renamed the file, a new one is
        created (0600, or 0640 in the group). Also a file given up after a failed write gets
        another chance. ``False`` if there is no file or it cannot be opened (logged; the old
        one, if any, is still written)."""
        if self.path is None:
            return False
        if self._queue:
            self._flush()  # what was logged before the signal goes to the old file
        try:
            fd = open_log(self.path, self.group)
        except OSError as exc:
            self.error(f"traffic log {self.path}: cannot reopen: {exc.strerror or exc}")
            return False
        self._end_cut_line(self.path, fd)
        old, self._fd = self._fd, fd
        self._wanted()
        if old is not None:
            os.close(old)
        return True

    def close(self) -> None:
        """Write what is kept, flush the stream and close the file; later calls do nothing. The
        stream stays usable."""
        while self._queue:
            self._flush()
        self.unbatch_view()
        self._flush_stream()
        if self._fd is not None:
            fd, self._fd = self._fd, None
            self._wanted()
            os.close(fd)

    def __enter__(self) -> TrafficLog:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # ----------------------------------------------------------------- writing a batch

    def _message(self, level: str, message: str, view: bool = True) -> None:
        t = self._clock()
        self._queue.append((_MESSAGE, t, level, message, view))
        if level == "error" and self.view == "off" and self._fd is None:
            self._say(t, message)
        if not self._held:
            self._flush()

    def _say(self, t: float, message: str) -> None:
        """An error that neither the view (off) nor the file (none, or given up: a full disk)
        would take, as one plain line on the stream all the same (the journal's error level on
        the journal): the failure of the log itself must reach someone."""
        prefix = SD_ERR if self._on_journal else ""
        line = " ".join(message.split())
        with contextlib.suppress(OSError, ValueError):  # (a stream given up: a closed pipe)
            self._stream.write(f"{prefix}{clock_text(t)} error: {line}\n")
            self._stream.flush()

    def _flush(self) -> None:
        """Format what is kept and write it: the JSON lines in one write to the file, the
        view's lines in one write to the stream."""
        entries, self._queue = self._queue, []
        filed, self._filed = self._filed, 0
        lines: list[str] = []
        if self._fd is not None:
            lines = [self._json(entry) for entry in entries[filed:]]
        if lines:
            self._write_file("".join(lines))
        if self.view == "off":
            return
        if self._batch is not None:
            self._unshown += entries
            if self._show_timer is None:
                loop, delay = self._batch
                self._show_timer = loop.call_later(delay, self._show_unshown)
            return
        self._show_entries(entries)

    def _show_unshown(self) -> None:
        """Write the view's lines that wait (:meth:`batch_view`)."""
        if self._show_timer is not None:
            self._show_timer.cancel()
            self._show_timer = None
        entries, self._unshown = self._unshown, []
        if entries and self.view != "off":
            self._show_entries(entries)

    def _show_entries(self, entries: list[_Entry]) -> None:
        view: list[str] = []
        for entry in entries:
            self._show(entry, view)
        if view and self.view != "off":
            self._write_stream("".join(view))

    @staticmethod
    def _json(entry: _Entry) -> str:
        kind = entry[0]
        if kind is _TRAFFIC:
            _, t, board, endpoint, direction, data = entry
            return traffic_json(t, board, endpoint, direction.value, data)
        if kind is _EVENT_ENTRY:
            _, t, board, what = entry
            return json_line({"t": t, "kind": "event", "board": board, "what": what})
        _, t, level, message, _ = entry
        return json_line({"t": t, "kind": level, "message": message})

    def _show(self, entry: _Entry, out: list[str]) -> None:
        """The view's lines of one entry, appended to ``out``."""
        kind = entry[0]
        if self.view == "plain":
            prefix = SD_INFO if self.journal else ""
            if kind is _TRAFFIC:
                _, t, board, endpoint, direction, data = entry
                # (the arrow found without a dict: an Enum member's hash is Python code)
                arrow = _IN_ARROW if direction is _IN else _OUT_ARROW
                out.append(f"{prefix}{clock_text(t)} {board} {endpoint} {arrow} {visible(data)}\n")
            elif kind is _EVENT_ENTRY:
                _, t, board, what = entry
                out.append(f"{prefix}{clock_text(t)} {board} [{what}]\n")
            elif entry[4]:
                _, t, level, message, _ = entry
                prefix = _PREFIX[level] if self.journal else ""
                label = "" if level == "info" else f"{level}: "
                for line in message.splitlines() or [""]:
                    out.append(f"{prefix}{clock_text(t)} {label}{line}\n")
            return
        styles = self._styles
        assert styles is not None
        if kind is _TRAFFIC:
            _, t, board, endpoint, direction, data = entry
            parts = [self._rich_head(styles, t, board, endpoint)]
            parts.append(styles.wrap(_ARROWS[direction], _ARROW[direction]))
            parts.append(" ")
            for piece, control in pieces(data):
                parts.append(styles.wrap(piece, _CONTROL if control else _DATA[direction]))
            parts.append("\n")
            out.append("".join(parts))
        elif kind is _EVENT_ENTRY:
            _, t, board, what = entry
            head = self._rich_head(styles, t, board, None)
            out.append(f"{head}{styles.wrap(f'[{what}]', _EVENT)}\n")
        elif entry[4]:
            _, t, level, message, _ = entry
            label = "" if level == "info" else f"{level}: "
            from rich.text import Text

            for line in message.splitlines() or [""]:
                text = Text()
                text.append(clock_text(t), _TIME)
                text.append(" ")
                text.append(f"{label}{line}", _LEVEL[level])
                out.append(styles.line(text))

    def _rich_head(self, styles: RichStyles, t: float, board: str, endpoint: str | None) -> str:
        widths = self._widths
        widths[0] = max(widths[0], len(board))
        head = f"{styles.wrap(clock_text(t), _TIME)} {styles.wrap(board.ljust(widths[0]), _BOARD)} "
        if endpoint is not None:
            widths[1] = max(widths[1], len(endpoint))
            head += f"{styles.wrap(endpoint.ljust(widths[1]), _ENDPOINT)} "
        return head

    # ----------------------------------------------------------------- the file

    def _write_file(self, text: str) -> None:
        assert self._fd is not None
        data = text.encode("ascii")  # ensure_ascii: always ASCII
        view = memoryview(data)
        written = 0
        try:
            while view:
                n = os.write(self._fd, view)
                written += n
                view = view[n:]
        except OSError as exc:
            fd, self._fd = self._fd, None
            self._wanted()
            # the part of a line that fitted (a full disk) is taken back: the file keeps whole
            # lines, and what is appended after a reopen starts a line of its own
            cut = written - (data.rfind(b"\n", 0, written) + 1)
            if cut:
                with contextlib.suppress(OSError):
                    os.ftruncate(fd, os.fstat(fd).st_size - cut)
            os.close(fd)
            self.error(f"traffic log {self.path}: {exc.strerror}; no longer written")

    @staticmethod
    def _end_cut_line(path: pathlib.Path, fd: int) -> None:
        """A file that ends in the middle of a line (its writer was killed while writing it)
        gets its line ended, so that the first line written now is a line of its own."""
        with contextlib.suppress(OSError):
            if os.fstat(fd).st_size == 0:
                return
            with open(path, "rb") as file:
                file.seek(-1, os.SEEK_END)
                last = file.read(1)
            if last not in (b"", b"\n"):
                os.write(fd, b"\n")

    # ----------------------------------------------------------------- the stream

    def _write_stream(self, text: str) -> None:
        try:
            self._stream.write(text)
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
        self._unshown = []
        self.view = "off"
        self._styles = None
        self._wanted()


# What is kept while the log is held: (_TRAFFIC, time, board, endpoint, direction, data),
# (_EVENT_ENTRY, time, board, what) or (_MESSAGE, time, level, message, shown on the view).
_TRAFFIC = "traffic"
_EVENT_ENTRY = "event"
_MESSAGE = "message"
_Entry = tuple[Any, ...]
_PREFIX = {"info": SD_INFO, "warning": SD_WARNING, "error": SD_ERR}
_ARROWS = {direction: direction.arrow for direction in Direction}
_IN = Direction.IN
_IN_ARROW, _OUT_ARROW = Direction.IN.arrow, Direction.OUT.arrow
