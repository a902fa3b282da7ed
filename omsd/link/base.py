"""What every link discipline offers the transports.

A link sits between a host program and a board (``shared/design/ARCHITECTURE.md``): the
transport hands it the bytes a client wrote and the time; the link passes them to the board as
its discipline says, lets the board run, and returns the bytes the client is to read, with the
board's events for the traffic log. Links are sans-I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from omsd.board import Board, CommandErrorEvent, Event, Output, Reply


class LinkOutput:
    """What the host is to read, and the events. ``pieces`` is what the host is to read, by the
    session whose conversation produced each part (0: the board's own doing, for whoever holds
    the line); ``data`` all of it, in order.

    A plain class with slots, not a dataclass: one is made for every command a client sends,
    and a frozen dataclass's ``__init__`` costs several times as much (issue 16). Treat it as a
    value."""

    __slots__ = ("events", "pieces")

    def __init__(
        self, pieces: list[tuple[int, bytes]] | None = None, events: list[Event] | None = None
    ) -> None:
        self.pieces: list[tuple[int, bytes]] = [] if pieces is None else pieces
        self.events: list[Event] = [] if events is None else events

    @property
    def data(self) -> bytes:
        pieces = self.pieces
        return pieces[0][1] if len(pieces) == 1 else b"".join(p[1] for p in pieces)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, LinkOutput):
            return NotImplemented
        return (self.pieces, self.events) == (other.pieces, other.events)

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return f"LinkOutput(pieces={self.pieces!r}, events={self.events!r})"


@dataclass(frozen=True)
class Held:
    """Host bytes a link holds back from the board, and why (``omsd ctl state``, the log)."""

    count: int
    waiting: str | None  # "done" or "limit" while a wait character holds them
    since: float  # board time the wait (or the hold) began
    axes: tuple[str, ...]  # what the wait waits on: the axes moving or with commands queued
    session: int  # the session whose wait it is (0: held only because the board is full)

    def describe(self) -> str:
        if self.waiting is not None:
            on = f" on {', '.join(self.axes)}" if self.axes else ""
            return f"waiting for {self.waiting}{on}, {self.count} bytes held"
        return f"board input buffer full, {self.count} bytes held"


def merge(pieces: list[tuple[int, bytes]], session: int, data: bytes) -> None:
    """Add ``data`` for ``session`` to ``pieces``, joining it to a last piece of the same."""
    if pieces and pieces[-1][0] == session:
        pieces[-1] = (session, pieces[-1][1] + data)
    else:
        pieces.append((session, data))


def message_first(out: list[Output], sources: list[int]) -> None:
    """With echo on (EN) a command error comes with "an English readable error message", a
    framed reply the board writes just after it sets CMD_S. The driver delays its ``#`` "until
    after the end of the message string" (§7.3.3), and so does the raw link's: each such error
    event is moved after its message, in place (docs/decisions.md, "Echo (EN)")."""
    for i in range(len(out) - 1):
        event, message = out[i], out[i + 1]
        if (
            isinstance(event, CommandErrorEvent)
            and isinstance(message, Reply)
            and message.text is not None
            and sources[i] == sources[i + 1]
            and message.time == event.time
            and message.text == f"{event.kind.message}: {event.command}".encode("latin-1")
        ):
            out[i], out[i + 1] = message, event
            sources[i], sources[i + 1] = sources[i + 1], sources[i]


class Link(Protocol):
    """Sessions: each connection a transport serves gets a number (``session``, never 0) and
    what it writes carries it, so that what the board says back, the driver's waits and the
    bytes held for it belong to that connection and go when it goes (``drop_input``)."""

    kind: str
    board: Board

    def from_host(self, data: bytes, now: float, session: int = 0) -> int:
        """Take host bytes; returns how many were taken (the rest must be offered again)."""
        ...

    def to_host(self, now: float) -> LinkOutput:
        """Run the board up to ``now``; what the host is to read, and the events."""
        ...

    def next_deadline(self) -> float | None:
        """When the board next changes by itself (``None``: never on its own)."""
        ...

    def next_wakeup(self) -> float | None:
        """When the board must next be run for the host to hear everything on time
        (:meth:`omsd.engine.machine.Machine.next_wakeup`)."""
        ...

    def room(self, session: int = 0) -> int:
        """How many more host bytes :meth:`from_host` would take now from ``session``."""
        ...

    def drop_input(self, session: int) -> int:
        """The session has gone: forget what it wrote that the board has not taken, and any
        wait of its; returns the number of bytes dropped."""
        ...

    def reset_input(self) -> int:
        """The board was reset: drop every held byte and wait; returns the number dropped."""
        ...

    def held(self) -> Held | None:
        """What is held back from the board now, if anything."""
        ...

    def busy(self, session: int) -> bool:
        """The session has bytes held here or a wait of its own pending."""
        ...

    def take_notes(self) -> list[str]:
        """Lines for the traffic log about what the link did (a wait began or ended, held
        input dropped)."""
        ...
