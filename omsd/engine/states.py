"""What an axis is doing and what it waits for: the small records the axis, the executor and
the mechanisms share.

* :class:`Motion`: the kind of motion an axis is in (which rules apply to it: soft limits, home
  searching, following another axis ...);
* :class:`Wait`: what the op at the head of an axis queue waits for before the queue goes on;
* :class:`Pending`: a move that has been specified and waits for its start;
* :class:`HomeSearch`: the home switch (or encoder index) being looked for;
* :class:`Gear`: the axis follows another one (electronic gearing, :mod:`omsd.engine.gearing`).

The records are state, not values: like the queue's :class:`~omsd.engine.queue.Op`, they are
compared by identity (``eq=False``: nothing compares two of them, and a dataclass's ``__eq__``
is source compiled at import, start-up's largest cost).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum, auto

from omsd.engine.queue import SyncGroup
from omsd.engine.trajectory import Trajectory


class Motion(Enum):
    IDLE = auto()
    MOVE = auto()  # point to point, the only kind soft limits apply to by default
    JOG = auto()
    HOME = auto()
    STOP = auto()
    STAIRCASE = auto()
    STREAM = auto()
    CONTOUR = auto()
    HOLD = auto()  # position-hold correction
    GEAR = auto()  # following a master axis (omsd.engine.gearing)

    # Members are compared by identity; hashed by identity too, in C (Enum's own __hash__ is a
    # Python function, run at every look-up in a set of motions: issue 16)
    __hash__ = object.__hash__


@dataclass(eq=False)
class Wait:
    """What the axis's current queue op waits for before the queue may go on."""

    kind: str  # "motion", "time", "group", "input", "inpos"
    until: float | None = None
    group: SyncGroup | None = None
    round: int = 0
    bit: int = 0
    high: bool = True  # "input": the level waited for (high, or low for a wait-for-low)
    then: Callable[[float], None] | None = None  # run when the wait is over
    jump: int | None = None  # program index to go on from (a loop pass), else the next op


@dataclass(eq=False)
class Pending:
    """A move set up by an absolute or relative move command, waiting for its start."""

    kind: str  # "abs" or "rel"
    value: float  # in user counts (encoder counts on encoder axes)
    linear: SyncGroup | None = None  # linear interpolation group


@dataclass(eq=False)
class HomeSearch:
    """A home search under way: what to do at home, the direction, and what was seen last."""

    position: float  # value loaded into the counter at home
    kill: bool  # stop at once at home, do not load the counter
    direction: int
    prev: bool  # home condition at the previous look
    index_points: tuple[float, ...] = ()  # encoder-home mode: physical points where home is true


@dataclass(eq=False)
class Gear:
    """An axis geared to ``master`` (an axis index) at ``ratio`` geared counts per master count.

    ``base`` is where the ratio put this axis at ``path.t0``, ``path`` the scaled copy of the
    master's motion since then (starting from 0): the exact position the gearing asks for at
    any time is ``base + path.position(t)``, whatever the counter has been rounded to.
    """

    master: int
    ratio: float
    text: str  # the engagement as entered, for the dialect's report of it
    base: float = 0.0
    path: Trajectory | None = None

    def ideal(self, t: float) -> float:
        return self.base + (self.path.position(t) if self.path is not None else 0.0)
