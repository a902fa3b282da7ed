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

:func:`follow_on` does the same in one place, in the settle, for the one case where none of
that generality applies, and leaves the axis, its queue and the machine as the straightforward
way leaves them; anywhere else it does nothing and says so, and the straightforward way runs.
:func:`ends_that_follow_on` goes one step further, before an instant's reactions: when
everything due then is such a move's end, it ends each and starts its next move at once,
without the at-rest trajectory ``reactions.on_end`` would give the axis for no time at all.
``tests/board/test_fast_paths.py`` runs both against the board without fast paths.

The move commands are those of ``quiet``'s :data:`~omsd.engine.quiet.MOVE_TO` and
:data:`~omsd.engine.quiet.MOVE_BY` that run the engine's own code on the board (the machine
gives them, ``codes``; none if its ``GO`` is a dialect's own). ``ML`` and ``MT`` are among them
but never follow on: they always move in a group (linear interpolation), which
:func:`_next_move` leaves to the straightforward way.
"""

from __future__ import annotations

import math
from collections.abc import Collection

from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.counter import counted
from omsd.engine.executor import Executor
from omsd.engine.gearing import followed
from omsd.engine.queue import Op
from omsd.engine.quiet import MOVE_TO
from omsd.engine.ramps import kept_course
from omsd.engine.sensing import begun_clear, first_look_needed
from omsd.engine.states import Motion, Wait
from omsd.engine.trajectory import Course, Trajectory

_MOVE = Motion.MOVE
_IDLE = Motion.IDLE


def follow_on(machine: Core, axis: Axis, codes: Collection[str], t: float) -> bool:
    """At ``t``, in a settle, ``axis`` is at rest and its queue waits for its motion to end (a
    ``Wait`` of kind ``"motion"``): if the next commands are a move (``codes``, see the module
    text) and ``GO``, neither in a group with other axes, start that move as
    ``Executor.step`` would and return True; otherwise change nothing and return False.

    Left to the straightforward way: a wait with something to run or a jump at its end, a
    geared axis or one another axis follows, a servo axis, an aux output or an armed interrupt
    to set up, a move that goes nowhere, a start after now.

    What it changes is the axis and its queue (and so the room in it) alone: no other axis, no
    group, no output, no input; so a settle that saw nothing else progress need not go round
    again for it (:meth:`~omsd.engine.machine.Machine.settle`)."""
    tick = machine.clock.at_or_after(t)
    start = _next_move(machine, axis, codes, tick, axis.traj.position(tick))
    if start is None:
        return False
    _start(machine, axis, tick, start, machine.after_events)
    return True


def ends_that_follow_on(ex: Executor, codes: Collection[str], t: float) -> bool:
    """At ``t``, in ``Machine.advance``, before the reactions to what is due: if everything due
    is the plain end of a move (:func:`_ending`) on an axis whose queue then follows on with the
    next (:func:`follow_on`'s conditions), end each and start its next move, leaving every axis
    as ``reactions.on_end`` and then the settle's :func:`follow_on` leave it, and return True;
    otherwise change nothing and return False.

    Why together, and only so: between an axis's end and its queue's step the straightforward
    way runs the reactions of the axes after it and the steps of the axes before it; here each
    of them is another such end or follow-on, which touches its own axis alone, so their order
    changes nothing. That needs every axis with nothing due to take no step at ``t`` either
    (its wait not over, ``Executor.satisfied``): a queued op of one could change another axis
    (``CN`` every axis's ramp, ``VS`` the Y axis's motion), before its next move in the
    straightforward way and after it here. The at-rest trajectory ``on_end`` gives the axis,
    which its next move replaces on the same tick, is not made; what stays of the end is its
    position and the held position it sets (``hold_goal``)."""
    machine = ex.machine
    tick = machine.clock.at_or_after(t)
    starts: list[tuple[Axis, float, _Start]] = []
    for axis in machine.axes:
        event = axis.event
        when = axis.next_event_time() if event is None else event[0]
        if when is None or when > t:
            # nothing due: it must take no step in the settle at t either (a time wait is over
            # WAIT_SLACK before its deadline; an input wait may be released by a rewiring)
            wait = axis.wait
            if wait is None:
                if axis.queue.pc < len(axis.queue.program):
                    return False
            elif wait.kind == "motion":  # (Executor.satisfied's first case, written out)
                if axis.motion is _IDLE:
                    return False
            elif ex.satisfied(axis, wait, t):
                return False
            continue
        ending = _ending(machine, axis, codes, t, tick)
        if ending is None:
            return False
        starts.append(ending)
    if not starts:
        return False
    _start_all(machine, starts, tick)
    return True


def follow_on_until(ex: Executor, codes: Collection[str], now: float) -> None:
    """The start of ``Machine.advance`` to ``now`` (issue 16): while every instant due by ``now``
    is :func:`ends_that_follow_on`'s case, moves that end with the next in their queue, run
    each instant, in time order, as that function and the settle after it would, looking at
    the axes the instant is about alone, and stop before the first instant that is not (the
    straightforward way goes on from there).

    Why the other axes need not be looked at again at each instant: they are looked at once,
    first, and each has nothing queued, or waits for its own motion with its mover the waiting
    command's sender (``Machine.settle``'s own fast path passes it by, and ``Executor.step``
    would change nothing), and the front holds nothing; anything else (a timed wait, a wait for
    an input or a group, a front with input to read), and nothing is done here. What an instant
    of follow-ons changes is its own axes, each left moving and waiting for that motion with its
    mover the sender (:func:`_start`): so every axis stays as it was looked at, every settle
    after an instant would step no axis and read nothing (its pump, made once at the end, names
    the sender the talker), and what it says of the machine (``Core.unsettle``) is said once,
    at the end, for all. So is the machine's next deadline, found from what was looked at (the
    due axes' own next events, the earliest of the others'), not by looking at every axis
    again; and the wake-up is kept where only quiet axes moved (:func:`_wakeup_kept`).
    ``tests/board/test_fast_paths.py`` and ``tests/board/test_quiet_deadlines.py`` run it
    against the board without fast paths."""
    machine = ex.machine
    if machine.init_until is not None or not machine.front.holds_nothing():
        return
    due: list[Axis] = []
    others = math.inf  # the earliest next event of the axes not due
    for axis in machine.axes:
        if axis.gear is not None:
            return  # (no axis is geared: none follows another's move, _next_move need not ask)
        wait = axis.wait
        if wait is None:
            if axis.queue.pc < len(axis.queue.program):
                return  # (a step would run its queue)
        elif wait.kind != "motion" or axis.motion is _IDLE:
            return
        else:  # passed by in a settle: its mover is the waiting command's sender
            queue = axis.queue
            if queue.pc >= len(queue.program) or queue.program[queue.pc].source != axis.source:
                return
        event = axis.event  # (read without a call where it is known, as Machine._next_internal)
        when = axis.next_event_time() if event is None else event[0]
        if when is None:
            continue
        if when <= now:
            due.append(axis)
        elif when < others:
            others = when
    looked = due.copy()
    last: float | None = None
    while due:
        t = math.inf  # the earliest of the due axes' events
        for axis in due:
            event = axis.event
            if event is not None and event[0] < t:
                t = event[0]
        tick = machine.clock.at_or_after(t)
        if tick > max(machine.now, t):
            break  # (_next_move's own condition: a start after now)
        machine.now = max(machine.now, t)  # (as Machine.advance, before the instant's events)
        starts: list[tuple[Axis, float, _Start]] = []
        for axis in due:
            event = axis.event
            if event is None or event[0] != t:
                continue  # due later
            ending = _ending(machine, axis, codes, t, tick, gears=False)
            if ending is None:
                break
            starts.append(ending)
        else:
            _start_all(machine, starts, tick)
            for axis, _, _ in starts:
                event = axis.event  # (read without a call where _start found it)
                when = axis.next_event_time() if event is None else event[0]
                if when is None or when > now:
                    due.remove(axis)
            last = t
            continue
        break  # (an instant with more than follow-ons: the straightforward way's)
    if last is not None:
        machine.talker = 0  # (Machine._handle_due, after the follow-ons)
        kept = _wakeup_kept(ex, looked)
        machine.unsettle(outside=False)  # (the settle after an instant's events)
        # the machine's next deadline, as Machine._next_internal would find it: the axes not
        # due are as they were looked at, and each due one has its own next event
        for axis in looked:
            event = axis.event
            if event is not None and event[0] < others:
                others = event[0]
        machine.deadline = None if others == math.inf else others
        machine.deadline_stale = False
        machine.wakeup_stale = not kept
        machine.front.pump(last)
        machine.settled = True


def _wakeup_kept(ex: Executor, axes: list[Axis]) -> bool:
    """The board's wake-up (``Machine.next_wakeup``), found before the follow-ons of ``axes``,
    is the same after them: it was found (not stale) by ``Machine._find_wakeup``'s search of
    the axes that are not quiet (no sensor hook, no contour; no INIT and no gearing, which
    :func:`follow_on_until` has looked at), and each of ``axes`` was found quiet then and in
    this epoch (``AxisState.quiet_known``), so the search passed it by, as it would again; the
    follow-ons change nothing else it looks at."""
    machine = ex.machine
    if machine.wakeup_stale or ex.sensor_hooks or machine.contour is not None:
        return False
    epoch = machine.outside_epoch
    for axis in axes:
        known = axis.quiet_known
        if known is None or known[0] != epoch or not known[1]:
            return False
    return True


def _ending(
    machine: Core, axis: Axis, codes: Collection[str], t: float, tick: float, gears: bool = True
) -> tuple[Axis, float, _Start] | None:
    """What is due for ``axis`` at ``t`` is the plain end of a move and its queue follows on
    with the next (:func:`_next_move`, from where the end leaves it, on a whole step as
    ``Axis.settle`` counts it): the axis, that place and the move; None if not. Changes nothing.

    A plain end: ``reactions.on_end`` would leave the axis at rest with nothing more due at
    ``t`` and nothing to do but note where it is: no hold (``Executor.check_hold``), no look at
    the sensors, no armed interrupt, no timer and no scheduled output (no aux output or servo
    loop either: :func:`_next_move` asks)."""
    event = axis.event
    if (
        event is None
        or event[1] != "end"
        or axis.motion is not _MOVE
        or axis.hold
        or axis.sensor_check is not None
        or axis.in_fire is not None
        or axis.aux_timer is not None
        or axis.outputs
    ):
        return None
    traj = axis.traj
    x = float(counted(traj, traj.position(t), t))
    start = _next_move(machine, axis, codes, tick, x, gears)
    return None if start is None else (axis, x, start)


def _start_all(machine: Core, starts: list[tuple[Axis, float, _Start]], tick: float) -> None:
    """End each move of ``starts`` (:func:`_ending`) as ``reactions.on_end`` would, noting the
    position it holds, and start its next on ``tick`` (after_events: the straightforward way
    starts it in the settle that follows the instant's reactions, which ``Machine.advance``
    runs with after_events set)."""
    for axis, x, start in starts:
        axis.hold_goal = axis.tracked_encoder(x)  # (on_end)
        _start(machine, axis, tick, start, True)


#: What :func:`_next_move` finds: the ``GO`` that starts the move, where it starts, its target,
#: its distance and its course.
_Start = tuple[Op, float, float, float, Course]


def _next_move(
    machine: Core, axis: Axis, codes: Collection[str], tick: float, x: float, gears: bool = True
) -> _Start | None:
    """The move the axis's queue starts next, on ``tick`` from ``x``, if it follows on (see
    :func:`follow_on`); ``None`` if not. Changes nothing. ``gears=False``: no axis of the
    machine is geared (the caller has looked), so none follows this one."""
    wait = axis.wait
    queue = axis.queue
    program, pc = queue.program, queue.pc
    if (
        len(program) - pc < 3
        or wait is None
        or wait.kind != "motion"
        or wait.then is not None
        or wait.jump is not None
        or tick > machine.now
    ):
        return None
    command, go = program[pc + 1], program[pc + 2]
    code = command.code
    if (
        code not in codes
        or go.code != "GO"
        or command.group is not None
        or go.group is not None
        or axis.gear is not None
        or axis.servo is not None
        or axis.pa is not None
        or axis.in_arm is not None
        or (gears and followed(axis))  # (gearing.moved would have them follow: the general way)
    ):
        return None
    # Executor.start_pending's arithmetic: the target, from where the axis stands on the tick
    value = axis.to_motor(command.args[0])
    target = float(math.trunc(value)) if code in MOVE_TO else x + math.trunc(value)
    distance = target - x
    course = kept_course(distance, axis.vl, axis.ac, axis.base_velocity, axis.ramp)
    if not course.pieces:
        return None
    return go, x, target, distance, course


def _start(machine: Core, axis: Axis, tick: float, start: _Start, after_events: bool) -> None:
    """The held command's wait is over, the move command and ``GO`` are passed, and ``GO``
    starts the move (its sender's doing), as ``Executor.start_pending`` and ``Axis.begin`` from
    rest on ``tick`` (``now``: nothing before it to keep) would."""
    go, x, target, distance, course = start
    queue = axis.queue
    queue.advance(2)  # (the move command and GO)
    saved = machine.talker
    machine.talker = axis.source = go.source
    axis.pending = None
    axis.direction = 1 if distance > 0 else -1
    axis.traj = Trajectory.along(tick, x, course, target)
    axis.motion = _MOVE
    axis.in_position = False
    axis.wait = Wait("motion")
    # its next event, found at once where it is the move's end (sensing.begun_clear, which
    # needs no look at the sensors on its first tick either); asked before a home search is
    # dropped, as first_look_needed is
    plain = after_events and machine.plain_sensing
    event = begun_clear(axis) if plain else None
    if event is None and (not plain or first_look_needed(axis, tick, _MOVE)):
        axis.sensor_check = tick
    axis.contour_origin = None  # (gearing.moved, with no axis to follow this one)
    axis.home = None
    if event is None:
        axis.invalidate()
    else:
        axis.event = event
        machine.deadline_stale = True  # (as axis.invalidate)
    machine.talker = saved
