"""The recording file: a header, then the traffic log's records (issue 17).

A recording is a JSON-lines file, one object per line, as the daemon's traffic log
(:mod:`omsd.telemetry.traffic`, "The JSON-lines file") writes them, with one more kind first::

    {"t": 81234.500112, "kind": "header", "format": 1, "version": "0.1.0", "clock": "monotonic",
     "started": 1700000000.25, "board": "card", "model": "PC48-4E", "link": "driver",
     "eos": "0A", "buffer_size": 256, "to": "serial:/dev/ttyS0,9600,8N1",
     "line": {"baud": 9600, "bits": 10}, "listen": "tcp:127.0.0.1:7100"}
    {"t": 81234.612, "kind": "traffic", "board": "card", "endpoint": "tcp:127.0.0.1:7100 #1
     (127.0.0.1:50312)", "dir": "in", "data": "AX RP\\n", "hex": "41582052500a"}
    {"t": 81234.613, "kind": "traffic", ..., "dir": "out", "data": "0\\n", "hex": "300a"}
    {"t": 81240.001, "kind": "info", "message": "client ... disconnected"}

* ``clock`` says what ``t`` counts: ``monotonic`` (``time.monotonic()``: the recorder's, immune
  to the wall clock being set) in a recording; the daemon's log has no header and wall-clock
  ``t`` (``time.time()``). Only the differences between times matter to a replay.
* ``started`` is the wall-clock time the recording began, for people.
* ``board`` ... ``buffer_size`` describe the card as the replay is to emulate it: the model (a
  name of ``omsd models``), the link (``driver``: the DOS driver's conventions, PC48 manual
  §7.3; ``raw``: the board's own stream), the driver's end-of-string character (hex, the
  driver's ``E:XX``, §7.3.2) and its buffer (``B:XXXX``). With a configuration file the
  recorder also writes the board's simulated world (``world``: per axis, the keys of
  :class:`omsd.board.AxisWorld`; ``inputs``) and what makes it a variant of its model
  (``encoders``, ``serial``, ``firmware``, ``max_queries``), so that a recording replays
  without the file.
* ``to`` is where the card was reached; ``line`` the serial line's speed, in bauds, and the
  bits each character takes on it (start, data, parity and stop bits), which the replay uses to
  place each command at the time its last character reached the card (``null`` over TCP).
* ``dir`` is as in the traffic log: ``in`` host to card, ``out`` card to host.

:func:`read_recording` reads a recording or a daemon's ``--log`` file. A log may hold several
boards (the ``board`` field; one is chosen) and several clients (the ``endpoint`` field: each is
a stream of its own, as each was a session of the daemon); its ``serving BOARD MODEL LINK ...``
lines say each board's model and link, and one after the board's traffic that a new daemon,
appending to the same file, started it again at power-up (``restarts``). A line cut short (a
recorder or a daemon killed while writing it: the last, or one the next daemon ended) is left
out and said so (:func:`cut_short`); any other line that is not a record is an error.
:class:`RecordingError` is one line, ``FILE:LINE: what``.
"""

from __future__ import annotations

import errno
import gzip
import io
import json
import math
import os
import re
import stat
import zlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, fields
from enum import Enum
from pathlib import Path
from typing import Any

from omsd import __version__
from omsd.board import AxisWorld, Board
from omsd.config import BoardConfig
from omsd.defaults import BUFFER_SIZE_MAX, BUFFER_SIZE_MIN, LINKS
from omsd.files import FILE_MODE
from omsd.models import UnknownModel, get_model
from omsd.telemetry.lines import json_line, traffic_json
from omsd.telemetry.traffic import Direction, Traffic

FORMAT = 1
"""The layout of this module's header; a file of a later one is not read."""

NO_CLIENT = "(no client)"
"""The endpoint of card output that reached nobody (the traffic log's word for it)."""


_DEFAULT_WORLD = AxisWorld()


class RecordingError(ValueError):
    """A file that cannot be replayed, or options that do not fit it; ``str()`` is one line."""


@dataclass(frozen=True)
class Line:
    """A serial line's speed: ``baud`` bits a second, ``bits`` per character."""

    baud: int
    bits: int = 10

    @property
    def char_time(self) -> float:
        """Seconds one character takes on the line."""
        return self.bits / self.baud


@dataclass(frozen=True)
class Chunk:
    """One traffic record: ``time`` in seconds from the first traffic record of the board."""

    time: float
    direction: Direction
    data: bytes
    endpoint: str


@dataclass
class Recording:
    """What a file holds for one board. ``header`` is ``None`` for a daemon's log."""

    path: str
    header: dict[str, Any] | None
    board: str
    chunks: list[Chunk]
    #: the daemon's messages and the recorder's, (time, kind, message), times as the chunks'
    notes: list[tuple[float, str, str]] = field(default_factory=list)
    #: a daemon log's ``serving`` lines: board name -> (model, link)
    served: dict[str, tuple[str, str]] = field(default_factory=dict)
    origin: float = 0.0  # the file's ``t`` of time 0
    #: the numbers of the lines cut short (a writer killed while writing them) and left out
    cut: list[int] = field(default_factory=list)
    #: times a daemon's log says a new daemon began serving the board (at power-up)
    restarts: list[float] = field(default_factory=list)

    @property
    def truncated(self) -> bool:
        """Some line was cut short and left out."""
        return bool(self.cut)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last record of the board."""
        last = self.chunks[-1].time if self.chunks else 0.0
        if self.notes:
            last = max(last, self.notes[-1][0])
        return last

    @property
    def line(self) -> Line | None:
        line = (self.header or {}).get("line")
        if not isinstance(line, Mapping):
            return None
        return Line(int(line["baud"]), int(line.get("bits", 10)))

    @property
    def one_stream(self) -> bool:
        """All the traffic is one conversation: a recording (the card sees one byte stream
        whoever the client is), not a daemon's log (where each client was a session)."""
        return self.header is not None


# -- the board in a header ------------------------------------------------------------------


def board_record(board: BoardConfig) -> dict[str, Any]:
    """The header's keys that describe ``board`` (its name, model, link, world, variant)."""
    record: dict[str, Any] = {
        "board": board.name,
        "model": board.model,
        "link": board.link,
        "eos": f"{board.eos:02X}",
        "buffer_size": board.buffer_size,
    }
    for key in ("encoders", "serial", "firmware", "max_queries"):
        value = getattr(board, key)
        if value is not None:
            record[key] = value
    if board.world:
        record["world"] = {
            letter: {
                f.name: _plain(getattr(world, f.name))
                for f in fields(world)
                if getattr(world, f.name) != getattr(_DEFAULT_WORLD, f.name)
            }
            for letter, world in board.world.items()
        }
    if board.inputs:
        record["inputs"] = {str(bit): high for bit, high in board.inputs.items()}
    return record


def _plain(value: object) -> object:
    return value.value if isinstance(value, Enum) else value


def board_from_record(record: Mapping[str, Any], where: str = "header") -> BoardConfig:
    """The board a header (or :func:`board_record`'s keys) describes; :class:`RecordingError`
    for keys that make no board."""
    try:
        model = get_model(str(record["model"])).name
    except KeyError as exc:
        if isinstance(exc, UnknownModel):
            raise RecordingError(f"{where}: {exc}") from None
        raise RecordingError(f"{where}: no model") from None
    link = str(record.get("link", "driver"))
    if link not in LINKS:
        raise RecordingError(f"{where}: link {link!r}: expected one of {', '.join(LINKS)}")
    eos = parse_eos(record.get("eos", 0x0A), where)
    buffer_size = record.get("buffer_size", 256)
    if type(buffer_size) is not int or not BUFFER_SIZE_MIN <= buffer_size <= BUFFER_SIZE_MAX:
        raise RecordingError(f"{where}: buffer_size {buffer_size!r}: expected 16..32767")
    world: dict[str, AxisWorld] = {}
    try:
        for letter, keys in dict(record.get("world") or {}).items():
            values: dict[str, object] = {}
            for name, value in dict(keys).items():
                default = getattr(_DEFAULT_WORLD, name)  # AttributeError: no such key
                values[name] = type(default)(value) if isinstance(default, Enum) else value
            world[str(letter).upper()] = _DEFAULT_WORLD.with_changes(**values)
        inputs = {int(bit): bool(high) for bit, high in dict(record.get("inputs") or {}).items()}
    except (AttributeError, TypeError, ValueError) as exc:
        raise RecordingError(f"{where}: world or inputs: {exc}") from None
    return BoardConfig(
        name=str(record.get("board", "card")),
        model=model,
        link=link,
        eos=eos,
        buffer_size=buffer_size,
        world=world,
        inputs=inputs,
        encoders=_optional(record, "encoders", str),
        serial=_optional(record, "serial", str),
        firmware=_optional(record, "firmware", str),
        max_queries=_optional(record, "max_queries", bool),
    )


def fitted(card: BoardConfig, where: str) -> BoardConfig:
    """``card``, once its world, inputs and variant keys are known to fit its model (a header
    or a configuration of a four-axis board, with ``--model`` a two-axis one);
    :class:`RecordingError` otherwise, not the board's ``ValueError`` in the middle of a run."""
    try:
        board = Board(card.personality(), now=0.0, world=dict(card.world))
        for bit, high in card.inputs.items():
            board.set_input(bit, high, 0.0)
    except ValueError as exc:
        raise RecordingError(f"{where}: {exc}") from None
    return card


def config_board(path: str | Path, name: str | None, fallback: str | None = None) -> BoardConfig:
    """A board of an omsd configuration file: the one named ``name``, else the one named
    ``fallback`` (the recording's board), else the file's only board; :class:`RecordingError`
    (one line) for a file that does not load or does not say which."""
    from omsd.config import ConfigError, load_config  # the schema: only when a file is read

    try:
        boards = load_config(path).boards
    except ConfigError as exc:
        raise RecordingError(str(exc)) from None
    names = [b.name for b in boards]
    if name is not None:
        for b in boards:
            if b.name == name:
                return b
        raise RecordingError(f"{path}: no board {name} (it has {', '.join(names)})")
    for b in boards:
        if b.name == fallback:
            return b
    if len(boards) == 1:
        return boards[0]
    raise RecordingError(f"{path}: several boards ({', '.join(names)}): choose one with --board")


def _optional(record: Mapping[str, Any], key: str, kind: type[Any]) -> Any:
    value = record.get(key)
    return None if value is None else kind(value)


def parse_eos(value: object, where: str = "--eos") -> int:
    """The driver's end-of-string character: hex text (``0A``, ``0x0d``) or a number."""
    try:
        if isinstance(value, str):
            number = int(value.strip().removeprefix("0x").removeprefix("0X"), 16)
        elif type(value) is int:
            number = value
        else:
            raise ValueError
    except ValueError:
        raise RecordingError(f"{where}: expected a character code in hex, got {value!r}") from None
    if not 0 <= number <= 0xFF:
        raise RecordingError(f"{where}: expected a character code 00..FF, got {value!r}")
    return number


# -- writing ------------------------------------------------------------------------------------


class RecordingWriter:
    """Writes a recording: :meth:`header` first, then :meth:`traffic` and :meth:`message`.

    The file is created 0600 (as the daemon's log, :mod:`omsd.files`); an existing file that is
    not empty is refused (``FileExistsError``): a recording is one session, and appending a second
    header, or overwriting a recording, would lose one. Each record is written with one
    ``write(2)`` as it comes, so a recorder that is killed leaves every record before the last.
    ``OSError`` from a write is the caller's to handle."""

    def __init__(self, path: Path) -> None:
        self.path = path
        flags = os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC
        fd = os.open(path, flags, FILE_MODE)
        try:
            if os.fstat(fd).st_size:
                raise FileExistsError(
                    f"{path} is not empty: a recording is one session; remove it or name"
                    " another file"
                )
        except BaseException:
            os.close(fd)
            raise
        self._fd: int | None = fd

    def header(self, t: float, started: float, board: BoardConfig, **more: Any) -> None:
        """The first line: the board as the replay is to emulate it, and ``more`` (``to``,
        ``line``, ``listen``)."""
        record = {
            "t": t,
            "kind": "header",
            "format": FORMAT,
            "version": __version__,
            "clock": "monotonic",
            "started": started,
            **board_record(board),
            **more,
        }
        self._write(json_line(record))

    def traffic(
        self, t: float, board: str, endpoint: str, direction: Direction, data: bytes
    ) -> None:
        self._write(traffic_json(t, board, endpoint, direction.value, data))

    def message(self, t: float, level: str, message: str) -> None:
        """``level``: ``info``, ``warning`` or ``error``, as the daemon's messages."""
        self._write(json_line({"t": t, "kind": level, "message": message}))

    def _write(self, text: str) -> None:
        if self._fd is None:
            return
        view = memoryview(text.encode("ascii"))
        while view:
            view = view[os.write(self._fd, view) :]

    def close(self) -> None:
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)


# -- reading ------------------------------------------------------------------------------------

_MESSAGES = ("info", "warning", "error")


def read_recording(
    path: str | Path, board: str | None = None, *, renamed: bool = False
) -> Recording:
    """The traffic of one board in ``path`` (a recording, or a daemon's ``--log`` file). With
    several boards in a log, ``board`` says which; :class:`RecordingError` otherwise, and for a
    file that is not a recording (one line, ``FILE:LINE: what``). ``renamed``: ``board`` is
    also the board of a configuration to replay the card as (``--config --board``), so a
    recording, which holds one card's traffic under the name it was recorded with, is read
    whatever ``board`` is."""
    name = str(path)
    header: dict[str, Any] | None = None
    traffic: list[tuple[int, Traffic]] = []
    notes: list[tuple[float, str, str]] = []
    served: dict[str, tuple[str, str]] = {}
    serving: list[tuple[int, float, str]] = []  # (line, t, board) of the serving lines
    cut: list[int] = []
    with _open(name) as f:
        lines = _lines(f, name)
        for number, text in lines:
            where = f"{name}:{number}"
            try:
                record = json.loads(text)
            except json.JSONDecodeError as exc:
                if cut_short(text, exc):
                    cut.append(number)
                    continue
                raise RecordingError(f"{where}: not a JSON object: {exc.msg}") from None
            except RecursionError:  # json nests by recursion: thousands of [ ran out of stack
                raise RecordingError(f"{where}: not a JSON object: nested too deeply") from None
            if not isinstance(record, dict) or not isinstance(record.get("kind"), str):
                raise RecordingError(f"{where}: not a record: expected an object with a kind")
            kind = record["kind"]
            if kind == "header":
                if header is not None or traffic or notes:
                    raise RecordingError(f"{where}: a header, but not on the first line")
                header = _header(record, where)
                continue
            t = record.get("t")
            if not isinstance(t, int | float) or isinstance(t, bool) or not math.isfinite(t):
                raise RecordingError(f"{where}: {kind} record without a time t")
            if kind == "traffic":
                try:
                    item = Traffic.from_record(record)
                except (KeyError, ValueError, TypeError) as exc:
                    raise RecordingError(f"{where}: not a traffic record: {_why(exc)}") from None
                traffic.append((number, item))
            elif kind in _MESSAGES:
                message = str(record.get("message", ""))
                notes.append((float(t), kind, message))
                parts = message.split()
                if kind == "info" and len(parts) >= 4 and parts[0] == "serving":
                    served[parts[1]] = (parts[2], parts[3])
                    serving.append((number, float(t), parts[1]))
    if not traffic:
        raise RecordingError(f"{name}: no traffic in the file")
    boards = list(dict.fromkeys(item.board for _, item in traffic))
    if renamed and header is not None and board not in boards and len(boards) == 1:
        chosen = boards[0]  # a recording is one card's, replayed as ``board``
    elif board is not None:
        if board not in boards:
            raise RecordingError(f"{name}: no traffic of board {board} (it has {_list(boards)})")
        chosen = board
    elif header is not None and header.get("board") in boards:
        chosen = str(header["board"])
    elif len(boards) > 1:
        raise RecordingError(
            f"{name}: the traffic of several boards ({_list(boards)}): choose one with --board"
        )
    else:
        chosen = boards[0]
    mine = [item for _, item in traffic if item.board == chosen]
    origin = mine[0].time
    chunks: list[Chunk] = []
    last = 0.0
    for item in mine:
        last = max(last, item.time - origin)  # a wall clock set back: keep the order
        chunks.append(Chunk(last, item.direction, item.data, item.endpoint))
    kept = [(max(0.0, t - origin), kind, text) for t, kind, text in notes]
    restarts = [] if header is not None else _restarts(traffic, serving, chosen, origin)
    return Recording(name, header, chosen, chunks, kept, served, origin, cut, restarts)


def _restarts(
    traffic: list[tuple[int, Traffic]],
    serving: list[tuple[int, float, str]],
    board: str,
    origin: float,
) -> list[float]:
    """When, in a daemon's log, ``board`` was served by a new daemon (omsd appends to its log:
    restarted on the same file, it starts the board at power-up): the time of the first of
    its ``serving`` lines after traffic of the board, in the chunks' times (never before the
    traffic ahead of it, as the chunks keep their order when the wall clock is set back)."""
    lines = sorted(
        [(number, item.time, True) for number, item in traffic if item.board == board]
        + [(number, t, False) for number, t, name in serving if name == board]
    )
    restarts: list[float] = []
    last = 0.0
    since = False  # traffic since the board was last served
    for _, t, is_traffic in lines:
        last = max(last, t - origin)
        if is_traffic:
            since = True
        elif since:
            restarts.append(last)
            since = False
    return restarts


_NUMBER_CUT = re.compile(r"[.eE][-+]?")
_LITERALS = ("true", "false", "null", "-")


def cut_short(text: str, exc: json.JSONDecodeError) -> bool:
    """Whether ``text``, which ``json`` could not read (``exc``), is the beginning of a record
    whose writer was killed while writing it: the last line of the file, or one the next
    daemon ended before appending its own (:class:`omsd.telemetry.traffic.TrafficLog`). It is,
    when the text is an object that ``json`` read up to where it stops: the end, or a string,
    escape, number or ``null``/``true``/``false`` cut there. Anything else is no record."""
    body = text.removesuffix("\n")
    if not body.startswith("{"):
        return False
    rest = body[exc.pos :]
    if not rest or exc.msg.startswith("Unterminated string"):
        return True
    if exc.msg.startswith("Invalid \\uXXXX escape"):
        return re.fullmatch(r"u[0-9a-fA-F]{0,4}", rest) is not None
    if exc.msg.startswith("Invalid \\escape"):
        return rest == "\\"
    if exc.msg.startswith("Expecting ',' delimiter") and _NUMBER_CUT.fullmatch(rest):
        return body[exc.pos - 1].isdigit()
    return exc.msg == "Expecting value" and any(word.startswith(rest) for word in _LITERALS)


#: The longest line read, in characters: far more than any record (a traffic record of the
#: largest read, 64 KiB, is at most 6 characters a byte). A longer one is no recording, and is
#: not read further (a file of NULs, or binary garbage, without a line end).
MAX_LINE = 1 << 23

_KINDS = (
    (stat.S_ISCHR, "a device"),
    (stat.S_ISBLK, "a device"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISDIR, "a directory"),
)


def _open(name: str) -> io.TextIOWrapper:
    """``name`` opened for reading as text, once it is known to be a regular file or a pipe
    (``<(zcat run.jsonl.gz)``; a named one is opened without waiting for a writer, and with
    none read as empty): a device (/dev/zero) or a directory is refused. A gzip file (a
    rotated log, ``traffic.jsonl.1.gz``) is read through gzip."""
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    except OSError as exc:
        if exc.errno == errno.EISDIR:
            raise RecordingError(f"{name}: not a recording: a directory, not a file") from None
        raise RecordingError(f"cannot read {name}: {exc.strerror or exc}") from None
    try:
        mode = os.fstat(fd).st_mode
        if not (stat.S_ISREG(mode) or stat.S_ISFIFO(mode)):
            what = next((what for test, what in _KINDS if test(mode)), "not a regular file")
            raise RecordingError(f"{name}: not a recording: {what}, not a file")
        os.set_blocking(fd, True)
    except BaseException:
        os.close(fd)
        raise
    return _text(open(fd, "rb", buffering=0), name)


def _text(raw: io.FileIO, name: str) -> io.TextIOWrapper:
    """``raw`` read as text, through gzip when it begins as a gzip file does. The first bytes
    are read in as many reads as they come in: a pipe gives what its writer has written so far,
    and one byte of the magic was taken for no gzip (a buffer's ``peek`` reads once)."""
    head = b""
    try:
        while len(head) < len(_GZIP) and _GZIP.startswith(head):
            more = raw.read(len(_GZIP) - len(head))
            if not more:
                break
            head += more
    except OSError as exc:
        raw.close()
        raise RecordingError(f"cannot read {name}: {exc.strerror or exc}") from None
    stream = io.BufferedReader(_Prefixed(head, raw))
    if head == _GZIP:
        return io.TextIOWrapper(gzip.GzipFile(fileobj=stream, mode="rb"), "utf-8", "replace")
    return io.TextIOWrapper(stream, encoding="utf-8", errors="replace")


class _Prefixed(io.RawIOBase):
    """``raw`` with the bytes already read from it (``head``) given back first."""

    def __init__(self, head: bytes, raw: io.FileIO) -> None:
        super().__init__()
        self._head = head
        self._raw = raw

    def readable(self) -> bool:
        return True

    def readinto(self, buffer: Any) -> int:
        head = self._head
        if not head:
            return self._raw.readinto(buffer) or 0
        n = min(len(buffer), len(head))
        buffer[:n] = head[:n]
        self._head = head[n:]
        return n

    def close(self) -> None:
        try:
            self._raw.close()
        finally:
            super().close()


_GZIP = b"\x1f\x8b"
"""The first bytes of a gzip file (RFC 1952 §2.3.1): logrotate's ``compress``, ``gzip -k``."""


def _lines(f: io.TextIOWrapper, name: str) -> Iterator[tuple[int, str]]:
    """The numbered lines of ``f`` that are not blank, each read at most :data:`MAX_LINE`
    characters far (:class:`RecordingError` for a longer one). Compressed data that ends
    before its end marker (a copy or a compression stopped part way) ends in a line cut short
    (``{``, which :func:`cut_short` says is one): the lines before it are whole."""
    number = 0
    try:
        while True:
            try:
                text = f.readline(MAX_LINE + 1)
            except EOFError:  # gzip: "Compressed file ended before the end-of-stream marker"
                yield number + 1, "{"
                return
            if not text:
                return
            number += 1
            if len(text) > MAX_LINE:
                raise RecordingError(
                    f"{name}:{number}: not a recording: a line longer than {MAX_LINE} characters"
                )
            if text.strip():
                yield number, text
    except (OSError, zlib.error) as exc:  # (gzip.BadGzipFile is an OSError)
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise RecordingError(f"cannot read {name}: {why}") from None


def _header(record: dict[str, Any], where: str) -> dict[str, Any]:
    version = record.get("format")
    if type(version) is not int or version < 1:
        raise RecordingError(f"{where}: header without a format number")
    if version > FORMAT:
        raise RecordingError(
            f"{where}: a recording of format {version}, newer than this omsd reads ({FORMAT})"
        )
    if record.get("clock") not in ("monotonic", "wall"):
        raise RecordingError(f"{where}: header: clock {record.get('clock')!r}: expected monotonic")
    board_from_record(record, f"{where}: header")  # every key checked now, not at the replay
    line = record.get("line")
    if line is not None and not (
        isinstance(line, dict)
        and type(line.get("baud")) is int
        and line["baud"] > 0
        and type(line.get("bits", 10)) is int
        and line.get("bits", 10) > 0
    ):
        raise RecordingError(f"{where}: header: line {line!r}: expected baud and bits")
    return record


def _why(exc: Exception) -> str:
    if isinstance(exc, KeyError):
        return f"no {exc.args[0]!r}"
    return str(exc)


def _list(names: list[str]) -> str:
    return ", ".join(names)


__all__ = [
    "FORMAT",
    "NO_CLIENT",
    "Chunk",
    "Line",
    "Recording",
    "RecordingError",
    "RecordingWriter",
    "board_from_record",
    "board_record",
    "config_board",
    "fitted",
    "parse_eos",
    "read_recording",
]
