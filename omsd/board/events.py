"""What comes out of a board, as the board's public API: :data:`Output` is a :class:`Reply` or
an :data:`Event` (done, limit, slip, servo trip, command error); :func:`describe` gives one
line for each. They are defined in :mod:`omsd.engine.events`; code above the board takes them
from :mod:`omsd.board`."""

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

__all__ = [
    "CommandErrorEvent",
    "DoneEvent",
    "ErrorKind",
    "Event",
    "LimitEvent",
    "Output",
    "Reply",
    "ServoTripEvent",
    "SlipEvent",
    "describe",
]
