"""What every link discipline offers the transports.

A link sits between a host program and a board (``shared/design/ARCHITECTURE.md``): the
transport hands it the bytes a client wrote and the time; the link passes them to the board as
its discipline says, lets the board run, and returns the bytes the client is to read, with the
board's events for the traffic log. Links are sans-I/O.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

from omsd.board import Board, Event


@dataclass(frozen=True)
class LinkOutput:
    data: bytes
    events: list[Event] = field(default_factory=list)


class Link(Protocol):
    kind: str
    board: Board

    def from_host(self, data: bytes, now: float) -> int:
        """Take host bytes; returns how many were taken (the rest must be offered again)."""
        ...

    def to_host(self, now: float) -> LinkOutput:
        """Run the board up to ``now``; what the host is to read, and the events."""
        ...

    def next_deadline(self) -> float | None: ...

    def room(self) -> int:
        """How many more host bytes :meth:`from_host` would take now."""
        ...
