"""Quiet axes: an axis whose coming events no host can notice unless it asks (issue 16).

A board's deadlines (:meth:`~omsd.engine.machine.Machine.next_deadline`) are every instant at
which it changes by itself: each move's first sample (a look at the switches), each move's end,
each timed wait running out. The daemon used to wake at every one of them. Most say nothing: an
axis running a queue of moves ends one, starts the next, and nobody hears of it until they ask
for its position. What can be heard without asking is the board's output (a done, a limit, a
slip, a servo trip, an error) and what a deadline does to the input (room for held commands).

An axis is *quiet* when, from now until its state is next changed from outside (a command, a
change of the world, a reset: each of which runs the board and finds its wake-up again), nothing
it does can be heard: its motion and the queued commands after it are plain moves, jogs, timed
waits and their parameters (:data:`QUIET_OPS`, the engine's own, never a dialect's replacement,
none of them in a group with other axes), and none of its reactions can fire: no switch within
reach of where the queue takes it (the whole queue's reach, not only the running move's: the
limit a later move would hit must not be learnt late), no home search, no slip detection, no
position hold, no backlash, no servo loop, no aux output or scheduled output, no armed
interrupt, no gearing on the board, no look of the dialect's own at the sensors. Whatever a
quiet axis does meanwhile, the board does at its exact time when it is next run (the engine is
pure: running it to ``t`` at once or deadline by deadline is the same), so replies and state are
those of a board woken at every deadline.

:meth:`~omsd.engine.machine.Machine.next_wakeup` is the earliest deadline of the axes that are
not quiet. It is found again after every instant's events, but an axis found quiet is not asked
again until the machine is changed from outside (``Core.outside_epoch``: a command, a change of
the world, a reset) or runs something other than a move that follows on (a reaction or a queued
command may change other axes than its own): what it does meanwhile is what the plan said.
Everything here is conservative: an axis that might be heard is not quiet, and the board is
woken at its every deadline, as before.
"""

from __future__ import annotations

import math
from collections.abc import Collection

from omsd.engine.axis import Axis
from omsd.engine.queue import Op
from omsd.engine.sensing import SWITCH_MARGIN, looks_at_nothing_else, switches_clear
from omsd.engine.states import Motion

#: Queued commands after which an axis stays quiet: moves, jogs, timed waits and the parameters
#: of moves (PC48 §6.5-§6.8, §6.10 WT). None says anything, reads an input or drives an output.
QUIET_OPS = frozenset({"MA", "MT", "MR", "ML", "GO", "JG", "JF", "WT", "VL", "AC", "VB", "NOP"})
MOVE_TO = frozenset({"MA", "MT"})
MOVE_BY = frozenset({"MR", "ML"})
JOGS = frozenset({"JG", "JF"})
#: Motions a quiet axis may be in (not a home search, a hold, a contour, a servo's own).
QUIET_MOTIONS = frozenset({Motion.IDLE, Motion.MOVE, Motion.JOG, Motion.STOP})


def quiet(axis: Axis, codes: Collection[str]) -> bool:
    """Whether nothing ``axis`` does until it is next changed from outside can be heard (see the
    module text); ``codes``: the :data:`QUIET_OPS` that run the engine's own code on this
    board."""
    if axis.motion not in QUIET_MOTIONS:
        return False
    if not looks_at_nothing_else(axis) or (
        axis.servo is not None
        or axis.pa is not None
        or axis.aux_timer is not None
        or axis.outputs
        or axis.in_arm is not None
        or axis.in_fire is not None
    ):
        return False
    wait = axis.wait
    if wait is not None and (
        wait.kind not in ("motion", "time") or wait.then is not None or wait.jump is not None
    ):
        return False
    reach = _reach(axis, codes, skip_current=wait is not None)
    if reach is None:
        return False
    lowest, highest = reach
    offset = axis.phys_offset  # (the whole reach of the queue, SWITCH_MARGIN inside the switches)
    return switches_clear(axis, lowest + offset, highest + offset, SWITCH_MARGIN)


def _reach(axis: Axis, codes: Collection[str], skip_current: bool) -> tuple[float, float] | None:
    """The lowest and highest position (counter frame) the axis's motion and its queued
    commands can take it to (``-inf`` or ``inf`` on the side a jog heads to, or everywhere once
    a move starts from where a jog stopped); ``None`` if a command is not quiet.

    The queue's part is read once and kept on the axis (:class:`Plan`, ``AxisState.quiet_memo``):
    as the axis works through the same queue, what is left is the end of the same plan, and its
    reach is the plan's from there on, as long as the axis stands where the plan said it would
    (a board polled between two of its deadlines asks again and again; a queue holds up to
    hundreds of commands)."""
    traj = axis.traj
    lowest, highest = traj.extent()
    queue = axis.queue
    program = queue.program
    pc = queue.pc + (1 if skip_current else 0)
    left = len(program) - pc
    pending = axis.pending
    if left <= 0 and pending is None:
        return lowest, highest
    start = traj.final if traj.is_finite else math.nan
    plan = axis.quiet_memo
    if (
        pending is None
        and left > 0
        and plan is not None
        and plan.codes is codes
        and plan.ratio == axis.ratio
        and plan.ops[-1] is program[-1]
        and (k := len(plan.ops) - left) >= 0
        and plan.ops[k] is program[pc]
        and plan.entering[k] == start  # (never so for NaN: read again)
    ):
        pass  # the rest of the same plan, from where it said the axis would be
    else:
        target: float | None = None
        if pending is not None:
            if pending.linear is not None:
                return None
            target = _target(axis, pending.kind == "abs", pending.value, start)
        plan = Plan(axis, codes, program[pc:], start, target)
        axis.quiet_memo = plan if pending is None else None
        k = 0
    if k < plan.loud:
        return None
    low, high = plan.low[k], plan.high[k]
    return min(lowest, low), max(highest, high)


class Plan:
    """Where the queued commands ``ops`` take an axis that starts at ``start`` (counter frame;
    NaN: unknown, where a jog stops) with the move ``target`` set up: for each command, where
    the axis stands when it is reached (``entering``), and the lowest and highest position of
    the moves from it to the end (``low``, ``high``); ``loud``: the index after the last
    command that is not quiet (0: none), before which there is no reach."""

    __slots__ = ("codes", "entering", "high", "loud", "low", "ops", "ratio")

    def __init__(
        self,
        axis: Axis,
        codes: Collection[str],
        ops: list[Op],
        start: float,
        target: float | None,
    ) -> None:
        self.codes = codes
        self.ratio = axis.ratio
        self.ops = ops
        n = len(ops)
        entering = [math.nan] * n
        reached: list[tuple[float, float]] = [(math.inf, -math.inf)] * n  # by each command
        loud = 0
        position = start
        for i, op in enumerate(ops):
            entering[i] = position if target is None else math.nan
            code = op.code
            if code not in codes or op.group is not None:
                loud = i + 1
            elif code in MOVE_BY:
                target = _target(axis, False, op.args[0], position)
            elif code in MOVE_TO:
                target = _target(axis, True, op.args[0], position)
            elif code == "GO":
                if target is not None:
                    position = target
                    target = None
                    if math.isnan(position):  # a move by so much from where a jog stopped
                        reached[i] = (-math.inf, math.inf)
                    else:
                        reached[i] = (position, position)
            elif code in JOGS:
                v = op.args[0]
                reached[i] = (-math.inf if v < 0 else math.inf, math.inf if v > 0 else -math.inf)
                position = math.nan  # where a jog stops is not known before it does
        self.entering = entering
        self.loud = loud
        low = [math.inf] * (n + 1)
        high = [-math.inf] * (n + 1)
        for i in range(n - 1, -1, -1):
            a, b = reached[i]
            low[i] = a if a < low[i + 1] else low[i + 1]
            high[i] = b if b > high[i + 1] else high[i + 1]
        self.low = low
        self.high = high


def _target(axis: Axis, absolute: bool, value: float, position: float) -> float:
    """Where a GO takes the axis (``Executor.start_pending``'s arithmetic); NaN for a move by
    so much from where a jog stopped."""
    steps = math.trunc(axis.to_motor(value))
    return float(steps) if absolute else position + steps
