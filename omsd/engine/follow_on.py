"""A queued move that follows on (issue 16): the fast path of a queue that runs move after move.

A queue such as ``MR3000 GO MR-3000 GO ...`` spends its time here: a move ends, the command that
waited for it lets the queue go on, the next ``MR`` (or ``MA``) sets up a move and the next
``GO`` starts it on the same tick (PC48 §6.8: "GO ... Starts the specified axes moving"). The
straightforward way (:meth:`~omsd.engine.executor.Executor.step`) goes through the op table: the
wait is over, the move command leaves a :class:`~omsd.engine.states.Pending`, ``GO`` runs
:meth:`~omsd.engine.executor.Executor.start_pending`, which runs
:meth:`~omsd.engine.axis.Axis.begin`; each is general (groups, linear interpolation, a start
later than now, a geared axis, an aux output, an armed interrupt, a servo loop). In a board
polled while it runs such queues, that was half of what a poll cost.

:func:`follow_on` does the same in one place, for the one case where none of that generality
applies, and leaves the axis, its queue and the machine as the straightforward way leaves them;
anywhere else it does nothing and says so, and the straightforward way runs.
``tests/board/test_fast_paths.py`` runs it against the board without fast paths.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.executor import OpFunction
from omsd.engine.ops_motion import MOTION_OPS
from omsd.engine.ramps import kept_course
from omsd.engine.sensing import first_look_needed
from omsd.engine.states import Motion, Wait
from omsd.engine.trajectory import Trajectory

#: The move commands a move may follow on with: to a position, by a distance.
MOVE_TO = frozenset({"MA", "MT"})
MOVE_BY = frozenset({"MR", "ML"})
_MOVE = Motion.MOVE


def own_move_codes(ops: Mapping[str, OpFunction]) -> frozenset[str]:
    """The move commands of :data:`MOVE_TO` and :data:`MOVE_BY` that run the engine's own code
    in the op table ``ops``, none if ``GO`` does not (a dialect's replacement is its own)."""
    if ops.get("GO") is not MOTION_OPS["GO"]:
        return frozenset()
    return frozenset(code for code in MOVE_TO | MOVE_BY if ops.get(code) is MOTION_OPS[code])


def follow_on(machine: Core, axis: Axis, codes: frozenset[str], t: float) -> bool:
    """At ``t``, ``axis`` is at rest and its queue waits for its motion to end (a ``Wait`` of
    kind ``"motion"``): if the next commands are a move (``codes``: :func:`own_move_codes`) and
    ``GO``, neither in a group with other axes, start that move as ``Executor.step`` would and
    return True; otherwise change nothing and return False.

    Left to the straightforward way: a wait with something to run or a jump at its end, a
    geared axis or one another axis follows, a servo axis, an aux output or an armed interrupt
    to set up, a move that goes nowhere, a start after now.

    What it changes is the axis and its queue (and so the room in it) alone: no other axis, no
    group, no output, no input; so a settle that saw nothing else progress need not go round
    again for it (:meth:`~omsd.engine.machine.Machine.settle`)."""
    wait = axis.wait
    queue = axis.queue
    program, pc = queue.program, queue.pc
    if len(program) - pc < 3 or wait is None or wait.then is not None or wait.jump is not None:
        return False
    move, go = program[pc + 1], program[pc + 2]
    code = move.code
    if (
        code not in codes
        or go.code != "GO"
        or move.group is not None
        or go.group is not None
        or axis.gear is not None
        or axis.servo is not None
        or axis.pa is not None
        or axis.in_arm is not None
    ):
        return False
    index = axis.index
    for other in machine.axes:  # (gearing.moved would have it follow: left to the general way)
        gear = other.gear
        if gear is not None and gear.master == index:
            return False
    tick = machine.clock.at_or_after(t)
    if tick > machine.now:
        return False
    # Executor.start_pending's arithmetic: the target, from where the axis stands on the tick
    x = axis.traj.position(tick)
    value = axis.to_motor(move.args[0])
    target = float(math.trunc(value)) if code in MOVE_TO else x + math.trunc(value)
    distance = target - x
    course = kept_course(distance, axis.vl, axis.ac, axis.vb, axis.ramp)
    if not course.pieces:
        return False
    # the wait is over, the commands are passed, and GO starts the move (its sender's doing)
    queue.advance()
    queue.advance()
    saved = machine.talker
    machine.talker = axis.source = go.source
    axis.pending = None
    axis.direction = 1 if distance > 0 else -1
    # Axis.begin from rest on this tick (``now`` is the tick: nothing before it to keep)
    axis.traj = Trajectory.along(tick, x, course, target)  # (its profile and course are kept)
    axis.motion = _MOVE
    axis.in_position = False
    if not (machine.after_events and machine.plain_sensing) or first_look_needed(axis, tick, _MOVE):
        axis.sensor_check = tick
    axis.contour_origin = None  # (gearing.moved, with no axis to follow this one)
    axis.home = None
    axis.wait = Wait("motion")
    axis.invalidate()
    machine.talker = saved
    return True
