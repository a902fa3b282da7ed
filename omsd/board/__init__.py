"""The board: the façade that joins one model row, its dialect and the engine (a pure,
sans-I/O model of an OMS motion control card).

Time is an argument of every call; nothing here sleeps, reads a clock or imports asyncio.
:class:`Board` is the card, :class:`Harness` drives one on a manual clock (tests, experiments);
what a board says is :data:`Output` (replies and events); :class:`AxisWorld` describes the stage
around an axis; :data:`OVRT` is the status register's limit bit (a link's interrupt service
reads it). ``docs/architecture.md`` draws the layers: engine, dialects, board.
"""

from omsd.board.board import Board
from omsd.board.harness import Harness
from omsd.engine.events import (
    CommandErrorEvent,
    DoneEvent,
    ErrorKind,
    Event,
    LimitEvent,
    Output,
    Reply,
    ServoTripEvent,
    SlipEvent,
    describe,
)
from omsd.engine.registers import OVRT
from omsd.engine.world import AxisWorld, LimitWiring, SwitchType

__all__ = [
    "OVRT",
    "AxisWorld",
    "Board",
    "CommandErrorEvent",
    "DoneEvent",
    "ErrorKind",
    "Event",
    "Harness",
    "LimitEvent",
    "LimitWiring",
    "Output",
    "Reply",
    "ServoTripEvent",
    "SlipEvent",
    "SwitchType",
    "describe",
]
