"""Per-axis command queues (PC48 §6.2, §8.2).

"The commands are then placed in separate command queues for each axis. As they are executed
the space is reclaimed allowing the host to pass commands ahead of the moves actually being
processed." A command from the host "may be expanded into several commands to the appropriate
axis", which is why a command occupies a number of *slots* given by the manual's queue tables.

The queue is kept as a program with a program counter so that loops can jump backwards: "The LS
command will save its parameter, i.e. the loop count, on a loop stack along with the address of
the LS command ... If the loop count has reached zero and it is not nested inside another loop,
the queue space will be flagged as available". Slots of everything from the start of the
outermost running loop stay used until that loop is finished; a loop larger than the queue can
therefore never be completed (§6.10: "the board will hang").

An :class:`Op` that several axes must execute together (a GO in AA mode, an AA WT, an AA ID...)
shares a :class:`SyncGroup`; "The synchronized modes (AA) insert special wait opcodes that allow
the axes to be synchronized in this mode."
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass(eq=False)
class SyncGroup:
    """Axes that meet at the same op. A group is re-used by every pass of a loop, so arrivals
    are counted per axis and a *round* is complete when every member has arrived that often.

    ``barrier`` groups hold their members until the round is complete and then run ``action``
    once; other groups (AA ID, AA IN) let members pass and only run ``action`` at completion.
    """

    members: set[int]
    barrier: bool = True
    action: Callable[[SyncGroup, float], None] | None = None
    arrivals: dict[int, int] = field(default_factory=dict)
    completed_round: int = 0
    data: dict[str, Any] = field(default_factory=dict)

    def arrive(self, axis: int) -> int:
        """Record an arrival; return the round this axis is now in."""
        n = self.arrivals.get(axis, 0) + 1
        self.arrivals[axis] = n
        return n

    def ready_round(self) -> int:
        """The highest round every member has reached (0 if some member never arrived)."""
        if not self.members:
            return max(self.arrivals.values(), default=0)
        return min(self.arrivals.get(m, 0) for m in self.members)

    def released(self, round_: int) -> bool:
        return self.completed_round >= round_


@dataclass(eq=False, slots=True)
class Op:
    """One queued command for one axis."""

    code: str
    args: tuple[Any, ...] = ()
    slots: int = 0
    group: SyncGroup | None = None
    source: int = 0  # the session that sent it (Board.input_source when it was queued)


@dataclass(eq=False, slots=True)  # state, compared by identity (omsd.engine.states)
class LoopFrame:
    """A loop running in an axis queue: its kind, where it starts, the passes left (LS) and when
    the current pass began."""

    kind: str  # "LS", "WS" or "WH"
    start: int  # program index of the loop-start op
    remaining: int = 0
    began: float = 0.0  # when the current pass began


class CommandQueue:
    """Program, program counter and slot accounting of one axis queue."""

    def __init__(self, capacity: int) -> None:
        self.capacity = capacity
        self.program: list[Op] = []
        self.pc = 0
        self.loops: list[LoopFrame] = []
        self.used = 0

    @property
    def free(self) -> int:
        return self.capacity - self.used

    @property
    def current(self) -> Op | None:
        return self.program[self.pc] if self.pc < len(self.program) else None

    @property
    def empty(self) -> bool:
        """Nothing left to execute and nothing held by a loop."""
        return self.pc >= len(self.program) and not self.loops

    def append(self, op: Op) -> None:
        self.program.append(op)
        self.used += op.slots

    def advance(self, ops: int = 1) -> None:
        """Pass the current op (and ``ops - 1`` after it), reclaiming their slots: as that many
        single advances would."""
        self.pc += ops
        self.reclaim()

    def jump(self, index: int) -> None:
        self.pc = index

    def reclaim(self) -> None:
        if self.loops or self.pc == 0:
            return
        program = self.program
        used = self.used
        for op in program[: self.pc]:
            used -= op.slots
        del program[: self.pc]
        self.used = used
        self.pc = 0

    def flush(self) -> list[Op]:
        """Drop everything; return the ops that were still pending or held."""
        dropped = self.program
        self.program = []
        self.pc = 0
        self.loops = []
        self.used = 0
        return dropped
