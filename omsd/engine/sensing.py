"""What happens next to an axis, found analytically.

Everything that happens by itself (a move ends, a switch is reached, an interrupt threshold is
passed, a settling time runs out, backlash is taken up) is found from the trajectory and
quantized onto the sample grid, so the machine can sleep until then. :func:`next_event` returns
the earliest such time and what it is; :class:`omsd.engine.axis.Axis` caches it.
"""

from __future__ import annotations

import math

from omsd.engine.axis_state import STEP_EPS, AxisState
from omsd.engine.backlash import backlash_tick
from omsd.engine.states import Motion
from omsd.engine.world import LimitWiring

_MATCHED = LimitWiring.MATCHED
_IDLE = Motion.IDLE

#: How far inside its limit switches (steps) a span must stay to be taken as clear of them
#: (:func:`switches_clear`) where the fast paths leave a search out: the whole of a trajectory
#: (:func:`_next_crossing`), the whole reach of a quiet axis's queue (``omsd.engine.quiet``).
#: Switches are seen on whole steps, a move's target is truncated to one, and
#: ``Trajectory.first_time`` has a margin of its own: more than any of them.
SWITCH_MARGIN = 2.0


def next_event(axis: AxisState) -> tuple[float, str]:
    """The earliest of what happens next to the axis and when; ``(inf, "")``: nothing. Of
    several at the same time, the first in this order."""
    # (written out, one test each, in that order: found for every move a poll sees begin)
    best, what = math.inf, ""
    when = axis.end_tick()
    if when is not None and when < best:
        best, what = when, "end"
    when = axis.sensor_check
    if when is not None and when < best:
        best, what = when, "sensor"
    when = axis.in_fire
    if when is not None and when < best:
        best, what = when, "in"
    when = axis.aux_timer
    if when is not None and when < best:
        best, what = when, "aux"
    if axis.outputs:
        when = axis.outputs[0][0]
        if when < best:
            best, what = when, "output"
    wait = axis.wait
    if wait is not None and wait.until is not None and wait.until < best:
        best, what = wait.until, "wait"
    if axis.motion is not _IDLE:
        later: float | None = None
        if axis.stall_phys is None:
            later = _next_crossing(axis)
        elif axis.slip_detect:
            later = _slip_crossing(axis)
        if later is not None and later < best:
            best, what = later, "sensor"
        if axis.backlash:  # a direction change
            later = backlash_tick(axis)
            if later is not None and later < best:
                best, what = later, "sensor"
    if axis.servo is not None:
        # after the look at the sensors: a look at the loop on the sample a switch is reached
        # would take the sample, and the crossing, searched for after it, is never looked at
        when = axis.servo_check_time()
        if when is not None and when < best:
            best, what = when, "servo"
    return best, what


def first_look_needed(axis: AxisState, t: float, motion: Motion) -> bool:
    """Fast path (issue 16): whether the look at the sensors on the first tick ``t`` of a move
    can find anything. ``Axis.begin`` (and ``omsd.engine.follow_on``, which starts such moves
    its own way) asks only for a move begun from rest on the instant ``Machine.advance`` is
    settling (``t`` is now: a move queued behind another, begun on the tick that one ends),
    whose look the reference would take in that same advance, right after the settle; the
    move's ``GO`` holds the queue until it ends, and the axis stands on a whole step, so nothing
    on that instant can move its carriage before the look. The look cannot find anything for a
    plain move (:func:`looks_at_nothing_else`) whose carriage is strictly between its limit
    switches (:func:`switches_clear`): no limit is active at ``t``, and a switch reached later
    is found by the search for crossings (:func:`_next_crossing`) on the tick it is reached.
    Left out there, the look's event and the settle after it are saved: a queued move costs one
    event, its end. ``tests/board/test_fast_paths.py`` runs it against the board that looks
    every time."""
    if motion is not Motion.MOVE or not looks_at_nothing_else(axis):
        return True
    p = axis.carriage(t)
    return not switches_clear(axis, p, p, 0.0)


def begun_clear(axis: AxisState) -> tuple[float, str] | None:
    """Fast path (issue 16): :func:`next_event` of an axis that has just begun a move of a
    kept course (``omsd.engine.follow_on``), found without the general search, where nothing
    can come before its end: nothing else is due (no look at the sensors, interrupt, timer,
    output, timed wait or servo loop), and the whole move stays clear of the switches
    (:func:`switches_clear`, with :data:`SWITCH_MARGIN`), for a look that can find nothing but
    a limit (:func:`looks_at_nothing_else`); None where that is not so (the general way).
    Where it answers, :func:`first_look_needed` would say no look is needed: the carriage
    stands within a step of the move's start, which is in its extent. Changes nothing."""
    if (
        axis.sensor_check is not None
        or axis.in_fire is not None
        or axis.aux_timer is not None
        or axis.outputs
        or axis.servo is not None
        or (axis.wait is not None and axis.wait.until is not None)
        or not looks_at_nothing_else(axis)
    ):
        return None
    lowest, highest = axis.traj.extent()
    off = axis.phys_offset
    if not switches_clear(axis, lowest + off, highest + off, SWITCH_MARGIN):
        return None
    return axis.host.clock.at_or_after(axis.traj.end_time), "end"


def looks_at_nothing_else(axis: AxisState) -> bool:
    """A look at the sensors (``reactions.on_sensor``) can do nothing to the axis but find a
    limit: no home search, backlash (with which the carriage is also apart from the counter by
    up to that much), slip detection, position hold, travel limits or stall."""
    return not (
        axis.backlash
        or axis.home is not None
        or axis.slip_detect
        or axis.hold
        or axis.travel_limits is not None
        or axis.stall_phys is not None
    )


def switches_clear(axis: AxisState, lowest: float, highest: float, margin: float) -> bool:
    """No limit is active anywhere from ``lowest`` to ``highest`` (physical positions) with
    ``margin`` steps to spare: the limits are off, or switches wired as the board's limit level
    expects (a line that reads as a limit away from its switch is never clear), neither forced
    from outside, lie beyond both ends."""
    if not axis.limits_on:
        return True
    w = axis.world
    if w.limit_switches is not _MATCHED:
        return False
    if axis.host.world.limit_forced(axis.index):
        return False
    return lowest > w.negative_limit + margin and highest < w.positive_limit - margin


def _levels(axis: AxisState, t: float) -> list[tuple[float, bool]]:
    """Counter-frame positions whose crossing the board must notice, with the side that
    counts (``True``: reaching at or above the level). Switches are seen through
    :meth:`~AxisState.carriage` (whole steps): a switch at physical ``s`` closes on the first
    whole step at or beyond it, which the continuous position reaches at ``step -+ STEP_EPS``."""
    levels: list[tuple[float, bool]] = []
    w = axis.world
    p = axis.carriage(t)
    off = axis.phys_offset
    if axis.limits_on:
        if p < w.positive_limit:  # active from the first step at or above the switch
            levels.append(_step_at_or_above(w.positive_limit - off))
        if p > w.negative_limit:  # active from the first step at or below it
            levels.append(_step_at_or_below(w.negative_limit - off))
    if axis.travel_limits is not None:  # (on with the switches off too: TL0,0 ends them, not LF)
        levels.extend((level - off, above) for level, above in _travel_levels(axis, t))
    if axis.home is not None:
        if axis.home.index_points:
            x = axis.phys(t)
            for point in axis.home.index_points:
                levels.append((point - off, point > x))
        else:
            # activated while home_low <= carriage < home_high: each edge is crossed
            # upwards at its first step at or above it, downwards at the step below it
            for edge in (w.home_low, w.home_high):
                if p < edge:
                    levels.append(_step_at_or_above(edge - off))
                else:
                    levels.append(_step_below(edge - off))
    return levels


def _travel_levels(axis: AxisState, t: float) -> list[tuple[float, bool]]:
    """Physical positions where a moving axis goes beyond its travel limits: the counter shows
    ``upper + 1`` at ``upper + 1 - 1e-6`` on the way up."""
    limits = axis.travel_limits
    if limits is None or axis.motion not in (Motion.MOVE, Motion.JOG):
        return []
    lower, upper = limits
    offset = axis.phys_offset
    position = axis.counter(t)
    levels: list[tuple[float, bool]] = []
    if position <= upper:
        levels.append((upper + 1.0 - 1e-6 + offset, True))
    if position >= lower:
        levels.append((lower - 1.0 + 1e-6 + offset, False))
    return levels


def first_tick(axis: AxisState, level_counter: float, above: bool, t_from: float) -> float | None:
    """The first sample tick after ``t_from`` at which the position is at (or beyond) the
    level."""
    clock = axis.host.clock
    traj = axis.traj
    when = traj.first_time(level_counter, above, t_from)
    while when is not None and math.isfinite(when):
        tick = clock.at_or_after(when)
        if tick <= t_from:
            tick = clock.after(t_from)
        x = traj.position(tick)
        if (x >= level_counter) if above else (x <= level_counter):
            return tick
        nxt = traj.first_time(level_counter, above, tick)
        if nxt is None or not math.isfinite(nxt) or nxt <= when:
            return None if nxt is None else clock.after(tick)
        when = nxt
    return None


def _next_crossing(axis: AxisState) -> float | None:
    # fast path (issue 16): with only limits to look for, a trajectory whose whole extent stays
    # clear of both switches crosses neither (each level would be found beyond its reach by
    # Trajectory.first_time); tests/board/test_fast_paths.py runs it against the search
    if axis.home is None and axis.travel_limits is None and axis.host.fast_paths:
        lowest, highest = axis.traj.extent()
        off = axis.phys_offset
        if switches_clear(axis, lowest + off, highest + off, SWITCH_MARGIN):
            return None
    t = axis.host.now
    best: float | None = None
    for level, above in _levels(axis, t):
        tick = first_tick(axis, level, above, t)
        if tick is not None and (best is None or tick < best):
            best = tick
    return best


def _slip_crossing(axis: AxisState) -> float | None:
    t = axis.host.now
    stall_enc = float(axis.encoder(t))
    best: float | None = None
    for sign in (1, -1):
        # slip_error = stall_enc - track_enc - ratio (x - track_counter) crosses -/+ tolerance
        level = axis.track_counter + (stall_enc - axis.track_enc + sign * axis.es) / axis.ratio
        tick = first_tick(axis, level + sign * 1e-6, sign > 0, t)
        if tick is not None and (best is None or tick < best):
            best = tick
    return best


def _step_at_or_above(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first reaches ``level`` going up."""
    return (math.ceil(level - 1e-9) - STEP_EPS, True)


def _step_at_or_below(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first reaches ``level`` going down."""
    return (math.floor(level + 1e-9) + STEP_EPS, False)


def _step_below(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first goes below ``level`` going down."""
    return (math.ceil(level - 1e-9) - 1 + STEP_EPS, False)
