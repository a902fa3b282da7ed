"""The control protocol: one JSON object per line each way.

Request: ``{"id": 1, "op": "limit", "board": "xy", "axis": "X", "direction": 1, "active":
true}``. Reply: ``{"id": 1, "ok": true, "result": ...}`` or ``{"id": 1, "ok": false, "error":
"one line"}``. A connection may send several requests without waiting; replies carry the
request's ``id`` and come in the order the operations finish (a ``wait`` finishes late).

Operations (``board`` names a board of the daemon):

========== ========================================================================= =========
op         arguments                                                                 result
========== ========================================================================= =========
boards                                                                               the boards
                                                                                     and their
                                                                                     endpoints
state      board                                                                     snapshot
limit      board, axis, direction (+1 / -1), active (true, false, null = follow the  state of
           carriage)                                                                 the axis
home       board, axis, active (true / false / null)
input      board, bit, high (true / false / null = released, pulled up)
slip       board, axis, steps (the carriage slips that many steps)
stall      board, axis, stalled (true / false)
encoder    board, axis, counts (external encoder input; ET tracking)
fault      board, any of latency, baud, drop, garble, cable, seed                    the faults
time       board, action: pause / resume / step (seconds) / scale (scale)            the clock
reset      board (a power cycle)
wait       board, until: done / idle / position, axis, position (with until         the state
           position), timeout (seconds of real time, default 10)
========== ========================================================================= =========

A board's state (``state``, the snapshot's) is the engine's (``omsd.board.Board.snapshot``)
with the board's ``clock``, ``faults``, ``link``, ``clients``, and ``world``: what is done to
its world from outside and not undone (``limits``: per axis [negative, positive], each true,
false or null; ``home``: per axis; ``stalled``: the axes; ``inputs``: per bit, driven by the
configuration's ``inputs`` or an ``input`` operation).

Streams (:mod:`omsd.control.watch`): ``subscribe`` turns the connection into a stream of the
boards' life. Its arguments: ``boards`` (a list of names; default every board; ``board`` names
one), ``rate`` (state messages a second at most, above 0 and at most :data:`MAX_RATE`, default
:data:`DEFAULT_RATE`), ``traffic`` (false: byte counts only; true: every chunk of traffic of
the boards too; a board's name: that board's chunks). Its reply's ``result`` is the snapshot,
``{"kind": "snapshot", "t": ..., "rate": 10.0, "traffic": false, "boards": [{"name", "model",
"link", "endpoints", "travel", "switches", "state"}, ...]}`` (``state`` as the ``state`` op
gives it; ``travel``: the limit switches' positions the configuration gives, per axis;
``switches``: per axis ``home`` [low, high] and, where configured, ``limits``, in the
carriage's steps, the frame of the state's ``physical``). Then, each
carrying the subscribe's ``id``:

* ``{"id": 1, "kind": "state", "t": ..., "boards": {"xy": {"time": ..., "axes": {"X":
  {"position": 1200, "velocity": 5000.0, ...}}, ...}}, "traffic": {"xy": {"in": 120, "out":
  80}}, "dropped": {...}}``: what changed since the last one, at most ``rate`` a second, and
  none while nothing changes. Per board its ``time`` and the fields that changed (whole), and
  in ``axes`` per axis the fields that changed (:func:`merge` applies them to the snapshot's
  state); ``traffic``: bytes in and out since the subscription began, for the boards whose
  counts changed; ``dropped`` (only once something was): messages dropped because the client
  read too slowly, by kind (``event``, ``traffic``), and state messages merged into a later one
  (``state``).
* ``{"id": 1, "kind": "event", "event": {"seq": 1, "board": "xy", "kind": "done", ...}}``: an
  event as it happens (the MQTT bridge's event object; ``seq`` counts the board's events from 1
  for this subscription: a gap means some were dropped).
* ``{"id": 1, "kind": "traffic", "traffic": {"t": ..., "kind": "traffic", "board": "xy",
  "endpoint": ..., "dir": "in", "data": ..., "hex": ..., "seq": 4}}``: a chunk of traffic (with
  ``traffic`` on), the traffic log's object.

``unsubscribe`` ends the stream (its reply comes after the last stream message; ``result``:
``{"sent": N, "dropped": {...}}``); the connection then takes requests and answers them as
before. Requests sent during a stream are answered too, their replies among its messages.
"""

from __future__ import annotations

import json
import math
from typing import Any, Protocol

MAX_LINE = 64 * 1024  # a request longer than this is refused (and the connection closed)
DEFAULT_RATE = 10.0  # state messages a second of a subscription, at most, unless told
MAX_RATE = 50.0
MAX_WAIT = 3600.0  # seconds a ``wait`` may be given, at most

OPS = (
    "boards",
    "state",
    "limit",
    "home",
    "input",
    "slip",
    "stall",
    "encoder",
    "fault",
    "time",
    "reset",
    "wait",
)

STREAM_OPS = ("subscribe", "unsubscribe")
"""Operations of a control connection itself (not run over MQTT): a stream of the boards."""


class Writer(Protocol):
    """Where a control connection's replies and stream go: an ``asyncio.StreamWriter`` (the
    control socket), or the web dashboard's WebSocket (:mod:`omsd.web.server`). ``write``
    takes whole JSON lines; ``drain`` waits until the peer has taken them."""

    def write(self, data: bytes) -> None: ...

    async def drain(self) -> None: ...

    def is_closing(self) -> bool: ...

    def close(self) -> None: ...


READ_ONLY_OPS = ("boards", "state", "subscribe", "unsubscribe")
"""What a watcher may ask (the web dashboard without ``control = true``)."""


class ControlError(Exception):
    """An operation that cannot be done; ``str()`` is one line."""


def encode(message: dict[str, Any]) -> bytes:
    return json.dumps(message, separators=(",", ":"), allow_nan=False).encode() + b"\n"


def decode(line: bytes) -> dict[str, Any]:
    try:
        message = json.loads(line, parse_constant=_not_json, parse_float=_finite)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ControlError(f"not a JSON object: {exc}") from None
    except RecursionError:  # json nests by recursion: thousands of [ ran out of stack
        raise ControlError("not a JSON object: nested too deeply") from None
    if not isinstance(message, dict):
        raise ControlError("not a JSON object")
    return message


def _not_json(name: str) -> Any:
    """Python's json reads NaN and Infinity, which JSON has not (and a reply echoing them in its
    id could not be written)."""
    raise ValueError(f"{name} is not JSON")


def _finite(text: str) -> float:
    """A JSON number as a float, one beyond a float's range (``1e999``) refused: read as
    infinity, it could not be written back (a reply echoing it in its id was never sent)."""
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text} is beyond a float's range")
    return value


def merge(state: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    """Apply one board's changes from a ``state`` message to that board's state (the snapshot's,
    kept up to date): fields replaced whole, but ``axes`` merged axis by axis, field by field.
    Returns ``state``."""
    for key, value in changes.items():
        if key == "axes":
            axes = state.setdefault("axes", {})
            for letter, fields in value.items():
                axes.setdefault(letter, {}).update(fields)
        else:
            state[key] = value
    return state
