"""A serial line's pace: characters no faster than its baud rate lets them through.

A character on an asynchronous serial line is a start bit, its data bits, a parity bit if the
line has one and its stop bits (:class:`Line`: 9600 baud 8N1 is 10 bits a character, 960
characters a second). :class:`Pacer` hands bytes on as such a line would deliver them: each
character when its last bit has arrived, one character time after the one before it, and no
sooner than the time it was given. The board's output goes through one when a serial or RFC 2217
endpoint has ``pacing`` on (:mod:`omsd.transport.serial`, :mod:`omsd.transport.rfc2217`), and
through the service's when the control API puts a ``baud`` fault on the cable
(:mod:`omsd.service`, :mod:`omsd.faults`), which also gives the cable's ``latency`` as the time
a chunk may not go before.

One timer at a time: the pacer wakes when the next character is due and hands on every character
that is due by then, in one write per chunk (a loop that wakes late writes what the line would
have delivered meanwhile at once, never more). A new rate applies to the bytes given after it;
those already waiting keep their times.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

#: The parities a line may have: pyserial's letters.
PARITIES = {"N": "none", "E": "even", "O": "odd", "M": "mark", "S": "space"}
BYTESIZES = (5, 6, 7, 8)
STOPBITS = (1.0, 1.5, 2.0)


@dataclass(frozen=True)
class Line:
    """A serial line's settings: ``baud`` bits a second, ``bytesize`` data bits, ``parity`` (a
    letter of :data:`PARITIES`), ``stopbits`` (1, 1.5 or 2)."""

    baud: int = 9600
    bytesize: int = 8
    parity: str = "N"
    stopbits: float = 1.0

    @property
    def bits(self) -> float:
        """Bits a character takes on the wire: start, data, parity, stop."""
        return 1 + self.bytesize + (self.parity != "N") + self.stopbits

    @property
    def chars_per_second(self) -> float:
        return self.baud / self.bits

    @property
    def frame(self) -> str:
        """``8N1``, ``7E2``, ``8N1.5``."""
        return f"{self.bytesize}{self.parity}{self.stopbits:g}"

    def __str__(self) -> str:
        return f"{self.baud} {self.frame}"


class _Handle(Protocol):
    def cancel(self) -> None: ...


class Clock(Protocol):
    """What a pacer needs of the event loop (a test gives a manual one)."""

    def time(self) -> float: ...

    def call_at(self, when: float, callback: Callable[..., Any], *args: Any) -> _Handle: ...


class _Chunk:
    """Bytes given to a pacer: where they go, how many have gone, when the first character
    began (the k-th is through at ``start + (k + 1) / rate``) and the rate they go at."""

    __slots__ = ("data", "rate", "sent", "start", "write")

    def __init__(
        self, write: Callable[[bytes], None], data: bytes, start: float, rate: float | None
    ) -> None:
        self.write = write
        self.data = data
        self.sent = 0
        self.start = start
        self.rate = rate

    def next_at(self) -> float:
        """When the next character is through."""
        return self.start if self.rate is None else self.start + (self.sent + 1) / self.rate

    def through(self, now: float) -> int:
        """How many characters are through at ``now``."""
        if now < self.start:
            return 0
        if self.rate is None:
            return len(self.data)
        return min(len(self.data), int((now - self.start) * self.rate + 1e-9))


class Pacer:
    """Bytes handed on at a line's pace, in the order given. ``chars_per_second`` ``None``:
    unpaced (a chunk given a time to wait for waits for it, and for those before it)."""

    def __init__(self, clock: Clock, chars_per_second: float | None = None) -> None:
        self.clock = clock
        self.chars_per_second = chars_per_second
        self._queue: deque[_Chunk] = deque()
        self._free_at = 0.0  # when the line has carried everything given so far
        self._timer: _Handle | None = None
        self._timer_at: float | None = None

    @property
    def idle(self) -> bool:
        """Nothing given is waiting to be handed on."""
        return not self._queue

    @property
    def waiting(self) -> int:
        """Bytes given that have not been handed on yet."""
        return sum(len(chunk.data) - chunk.sent for chunk in self._queue)

    def send(self, write: Callable[[bytes], None], data: bytes, at: float | None = None) -> None:
        """``write`` ``data`` as the line delivers it, beginning no sooner than ``at`` (the
        clock's time; ``None``: now)."""
        if not data:
            return
        now = self.clock.time()
        rate = self.chars_per_second
        start = max(self._free_at, now if at is None else max(at, now))
        if rate is None and start <= now and not self._queue:
            write(data)  # unpaced, nothing waiting, nothing to wait for
            return
        self._queue.append(_Chunk(write, data, start, rate))
        self._free_at = start + (len(data) / rate if rate is not None else 0.0)
        self._schedule()

    def clear(self) -> int:
        """Drop what waits (its client went); returns how many bytes."""
        dropped = self.waiting
        self._queue.clear()
        if self._timer is not None:
            self._timer.cancel()
        self._timer = self._timer_at = None
        self._free_at = min(self._free_at, self.clock.time())
        return dropped

    def _due(self) -> None:
        self._timer = self._timer_at = None
        now = self.clock.time()
        queue = self._queue
        while queue:
            chunk = queue[0]
            through = chunk.through(now)
            if through > chunk.sent:
                data = chunk.data[chunk.sent : through]
                chunk.sent = through
                chunk.write(data)  # which may clear the queue (the client went)
            if not queue or queue[0] is not chunk:
                continue
            if chunk.sent < len(chunk.data):
                break
            queue.popleft()
        self._schedule()

    def _schedule(self) -> None:
        if not self._queue:
            return
        at = self._queue[0].next_at()
        if self._timer is not None:
            if self._timer_at == at:
                return
            self._timer.cancel()
        self._timer = self.clock.call_at(at, self._due)
        self._timer_at = at


__all__ = ["BYTESIZES", "PARITIES", "STOPBITS", "Clock", "Line", "Pacer"]
