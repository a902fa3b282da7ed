"""Loops (PC48 §6.10, loop control: LS/LE, WS/WD, WH/WG), as the interpreter keeps them: per
axis, a stack of the loops entered, each with the mode it was entered in, and the axes whose
while flag is set."""

from __future__ import annotations

from dataclasses import dataclass

from omsd.dialects.operands import CommandFailed
from omsd.engine.axis import Axis
from omsd.protocol.errors import ErrorKind

MAX_LOOP_DEPTH = 4


@dataclass(eq=False)  # state, compared by identity (omsd.engine.states)
class LoopMark:
    """A loop entered on an axis."""

    kind: str  # "LS", "WS", "WH"
    context: str  # axis letter, or "AA" for a loop entered in AA/AM


class LoopStacks:
    """The loop bookkeeping of :class:`~omsd.dialects.interpreter.Interpreter` (a mixin)."""

    loops: list[list[LoopMark]]
    while_flags: set[int]

    def context_tag(self) -> str:
        """The mode a loop is entered in (the interpreter's)."""
        raise NotImplementedError

    def in_loop(self, axes: list[Axis]) -> bool:
        return any(self.loops[a.index] for a in axes)

    def open_loop(self, kind: str, axes: list[Axis]) -> None:
        for a in axes:
            stack = self.loops[a.index]
            if len(stack) >= MAX_LOOP_DEPTH:
                raise CommandFailed(ErrorKind.LOOP_TOO_DEEP)
            if kind == "WH" and any(m.kind == "WH" for m in stack):
                raise CommandFailed(ErrorKind.LOOP_TOO_DEEP)

    def push_loop(self, kind: str, axes: list[Axis]) -> None:
        tag = self.context_tag()
        for a in axes:
            self.loops[a.index].append(LoopMark(kind, tag))

    def close_loop(self, kind: str, axes: list[Axis]) -> None:
        """LE/WD/WG must match the most recent LS/WS/WH entered in the same axis mode:
        "otherwise the matching loop termination command will not be found"; CMD_S flags "LS
        and LE commands are not in [matched] pairs"."""
        tag = self.context_tag()
        for a in axes:
            stack = self.loops[a.index]
            if not stack or stack[-1].kind != kind or stack[-1].context != tag:
                raise CommandFailed(ErrorKind.LOOP_MISMATCH)

    def pop_loop(self, axes: list[Axis]) -> None:
        for a in axes:
            self.loops[a.index].pop()

    def forget_loops(self, index: int) -> None:
        """The axis queue was flushed: its loops are gone with it."""
        self.loops[index].clear()
        self.while_flags.discard(index)

    def take_while_flag(self, index: int) -> bool:
        if index in self.while_flags:
            self.while_flags.discard(index)
            return True
        return False
