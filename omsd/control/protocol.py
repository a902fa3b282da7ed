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
"""

from __future__ import annotations

import json
from typing import Any

MAX_LINE = 64 * 1024  # a request longer than this is refused (and the connection closed)

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


class ControlError(Exception):
    """An operation that cannot be done; ``str()`` is one line."""


def encode(message: dict[str, Any]) -> bytes:
    return json.dumps(message, separators=(",", ":"), allow_nan=False).encode() + b"\n"


def decode(line: bytes) -> dict[str, Any]:
    try:
        message = json.loads(line)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ControlError(f"not a JSON object: {exc}") from None
    if not isinstance(message, dict):
        raise ControlError("not a JSON object")
    return message
