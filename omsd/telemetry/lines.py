"""The traffic log's lines, made quickly: the view's plain and rich lines and the JSON lines.

:class:`omsd.telemetry.traffic.TrafficLog` formats a turn's records in a batch (the file's
lines just before the replies, the view's after them), and a busy board makes two records per
command, so each line here costs a few microseconds, not the tens that
``datetime``, ``json.dumps`` and a ``rich`` ``Console.print`` per record cost. The lines are
the same, byte for byte, as those ways made them (``tests/test_traffic_lines.py`` compares them
on random records):

* :func:`clock_text`: ``HH:MM:SS.mmm`` as ``datetime.fromtimestamp`` gives it (the same
  rounding to the microsecond, then truncated to the millisecond), with the local time of day
  worked out once a second;
* :func:`visible`: one ``str.translate`` through a table of the 256 bytes' shown forms;
* :func:`traffic_json`: the JSON object ``json.dumps`` writes for a traffic record, put
  together from ``float.__repr__`` and ``json``'s own string encoder;
* :class:`RichStyles`: the escape codes ``rich`` writes around each style of the view, asked of
  the console once per style (so its colour system and ``NO_COLOR`` are honoured as before).
"""

from __future__ import annotations

import json
import math
import time
from json.encoder import encode_basestring_ascii
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # rich is imported by the rich view only (issue 16: start-up)
    from rich.console import Console
    from rich.style import StyleType
    from rich.text import Text

_NAMED = {0x0A: "<LF>", 0x0D: "<CR>"}


def _shown(byte: int) -> str:
    if 0x20 <= byte < 0x7F:
        return chr(byte)
    if byte in _NAMED:
        return _NAMED[byte]
    if byte < 0x20:
        return "^" + chr(byte + 0x40)
    return f"<{byte:02X}>"


#: How each byte is shown, by its value (``str.translate`` takes it as the table).
SHOWN = [_shown(b) for b in range(256)]


#: Shown forms of recent data (a board's traffic is the same few replies over and over).
_SEEN: dict[bytes, str] = {}
_SEEN_MAX = 1024
_SEEN_LONGEST = 64


def visible(data: bytes) -> str:
    """Show bytes so a person can read them, whatever they are.

    Printable ASCII (space to ``~``) as itself; LF and CR as ``<LF>`` and ``<CR>`` (the manual's
    notation); the other control characters 0x00-0x1F in caret notation (``^D`` for Control-D,
    ``^Y`` for Control-Y, ``^[`` for ESC); DEL and bytes 0x80-0xFF as ``<XX>`` in hex.
    """
    try:
        shown = _SEEN.get(data)
    except TypeError:  # not hashable (a bytearray): shown, not kept
        return data.decode("latin-1").translate(SHOWN)
    if shown is None:
        shown = data.decode("latin-1").translate(SHOWN)
        if len(data) <= _SEEN_LONGEST:
            if len(_SEEN) >= _SEEN_MAX:
                _SEEN.clear()
            _SEEN[data] = shown
    return shown


def pieces(data: bytes) -> list[tuple[str, bool]]:
    """Split ``data`` into runs of printable text (``False``) and shown control bytes (``True``)."""
    out: list[tuple[str, bool]] = []
    start = 0
    for i, byte in enumerate(data):
        if 0x20 <= byte < 0x7F:
            continue
        if start < i:
            out.append((data[start:i].decode("ascii"), False))
        out.append((SHOWN[byte], True))
        start = i + 1
    if start < len(data):
        out.append((data[start:].decode("ascii"), False))
    return out


class _Second:
    """The last whole second shown, and its ``HH:MM:SS`` (local time)."""

    second: int | None = None
    text = ""


_LAST_SECOND = _Second()
_MILLISECONDS = [f".{ms:03d}" for ms in range(1000)]


def clock_text(t: float) -> str:
    """Local time of day to the millisecond (truncated, so it never shows ``60.000``), as
    ``datetime.fromtimestamp(t)`` gives it: the fraction rounded half-even to the microsecond
    (CPython's ``_PyTime_DoubleToDenominator``), then cut to the millisecond."""
    fraction, whole = math.modf(t)
    us = round(fraction * 1e6)
    if us >= 1_000_000:
        us -= 1_000_000
        whole += 1.0
    elif us < 0:
        us += 1_000_000
        whole -= 1.0
    second = int(whole)
    last = _LAST_SECOND
    if second != last.second:
        tm = time.localtime(second)
        # as datetime, seconds 0-59: a leap second (23:59:60 in a right/ zone) shows as 59
        last.text = f"{tm.tm_hour:02d}:{tm.tm_min:02d}:{min(tm.tm_sec, 59):02d}"
        last.second = second
    return last.text + _MILLISECONDS[us // 1000]


def traffic_json(t: float, board: str, endpoint: str, direction: str, data: bytes) -> str:
    """The JSON line of a traffic record (with its newline), as ``json.dumps`` of
    :meth:`omsd.telemetry.Traffic.to_record` writes it."""
    if type(t) is not float or not math.isfinite(t) or type(board) is not str:
        return json_line(
            {
                "t": t,
                "kind": "traffic",
                "board": board,
                "endpoint": endpoint,
                "dir": direction,
                "data": data.decode("latin-1"),
                "hex": data.hex(),
            }
        )
    return (
        f'{{"t": {float.__repr__(t)}, "kind": "traffic", "board": {encode_basestring_ascii(board)}'
        f', "endpoint": {encode_basestring_ascii(endpoint)}, "dir": "{direction}", "data": '
        f'{encode_basestring_ascii(data.decode("latin-1"))}, "hex": "{data.hex()}"}}\n'
    )


def json_line(record: dict[str, Any]) -> str:
    """Any record as its JSON line (ASCII, with its newline)."""
    return json.dumps(record) + "\n"


class RichStyles:
    """The rich view's styles as the escape codes ``console`` writes around them.

    ``rich`` renders a :class:`~rich.text.Text` span by span, each span as the bytes its style
    gives around the span's text (``Style.render``, after the console's colour system and
    ``NO_COLOR``), and a span without a style as the bare text. So the codes of each style are
    asked of the console once, by printing one character in that style to a capture, and a line
    is put together from them: the bytes ``console.print(text)`` would write, in a few
    microseconds instead of a hundred.
    """

    _MARK = "\ue000"  # a character no style code contains

    def __init__(self, console: Console) -> None:
        self.console = console
        self._codes: dict[StyleType, tuple[str, str]] = {}

    def wrap(self, text: str, style: StyleType) -> str:
        """``text`` in ``style``, as the console writes it."""
        if not text:
            return ""
        codes = self._codes.get(style)
        if codes is None:
            from rich.text import Text

            with self.console.capture() as capture:
                self.console.print(Text(self._MARK, style), end="")
            before, _, after = capture.get().partition(self._MARK)
            codes = self._codes[style] = (before, after)
        return f"{codes[0]}{text}{codes[1]}"

    def line(self, text: Text) -> str:
        """Any :class:`~rich.text.Text` as the console prints it, with its newline (slow: for
        the daemon's messages, which are few)."""
        with self.console.capture() as capture:
            self.console.print(text)
        return capture.get()
