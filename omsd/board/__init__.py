"""The board engine: a pure (sans-I/O) model of an OMS motion control card.

Time is an argument of every call; nothing here sleeps, reads a clock or imports asyncio.
"""

from omsd.board.board import Board
from omsd.board.events import (
    CommandErrorEvent,
    DoneEvent,
    ErrorKind,
    Event,
    LimitEvent,
    Output,
    Reply,
    SlipEvent,
)
from omsd.board.world import AxisWorld, SwitchType

__all__ = [
    "AxisWorld",
    "Board",
    "CommandErrorEvent",
    "DoneEvent",
    "ErrorKind",
    "Event",
    "LimitEvent",
    "Output",
    "Reply",
    "SlipEvent",
    "SwitchType",
]
