"""The position counter (PC48 §6.13 RP: "returns the current position"): the whole steps an
axis has emitted, counted the way it travels, never a step ahead of the pulses."""

from __future__ import annotations

import math

from omsd.engine.trajectory import Trajectory


def steps(x: float, origin: float) -> int:
    """The position counter at ``x`` on the way from ``origin``: pulses are counted as whole
    steps in the direction of travel, never rounded ahead."""
    eps = 1e-6
    return math.floor(x + eps) if x >= origin else math.ceil(x - eps)


def counted(traj: Trajectory, x: float, t: float) -> int:
    """The position counter at ``x``, at ``t`` on ``traj``: the steps emitted, whole steps the
    way the axis travels, so that the counter moves with the axis and never ahead of it. A
    trajectory that took over from a motion (``traj.count``) counts on from that motion's
    count, whichever way it had come: a stop just after a turn at 700.195, at 700.099, counts
    700 (not 701); a move up from a jog down that reached -150.278 counts -150 (not -151).
    From rest the count begins at the start rounded the way the motion leaves in (a stop of a
    motion the negative way at -40.12 counts -40, not -41). After a turn (a jog turned round by
    one of the other sign, a contour's arc) the steps of the way back are counted from the step
    the turn was on: turned at -500 and back up at -488.975, -489."""
    count = traj.count
    if traj.turns:
        legs = traj.legs(t)
        if legs:
            if count is None:
                count = _onward_from(traj.x0, legs[0][1])
            for k, (_, way) in enumerate(legs):
                count = _onward(count, legs[k + 1][0] if k + 1 < len(legs) else x, way)
            return count
    if count is not None:
        return _onward(count, x, traj.way or x - traj.x0)
    origin = traj.x0
    if x == origin and traj.way < 0.0:
        return math.ceil(x - 1e-6)
    return steps(x, origin)


def count_at(traj: Trajectory, t: float) -> int:
    """:func:`counted` at ``t`` on ``traj`` (at its position then), the last one found kept on
    the trajectory (``Trajectory.count_seen``; a trajectory never changes): a poll asks for
    one instant's count more than once (QA's carriage, RP's counter)."""
    seen = traj.count_seen
    if seen[0] == t:
        return seen[1]
    count = counted(traj, traj.position(t), t)
    traj.count_seen = (t, count)
    return count


def count_velocity(traj: Trajectory, t: float) -> tuple[int, float]:
    """:func:`count_at` and the velocity at ``t`` on ``traj`` together, the piece running then
    found once (:meth:`Trajectory.position_velocity`): a status of a moving axis asks for both
    (its carriage and its direction), and the count is kept as :func:`count_at` keeps it, for
    RP's counter at the same instant to read."""
    x, v = traj.position_velocity(t)
    seen = traj.count_seen
    if seen[0] == t:
        return seen[1], v
    plain = traj.one_way_from_rest
    if plain is None:
        plain = traj.one_way_from_rest = traj.count is None and not traj.turns
    if plain and x != traj.x0:
        # fast path (issue 16): the motion most polled, from rest and one way (a jog, a queued
        # move), away from its start: counted's last rule, whole steps the way it has gone
        count = math.floor(x + 1e-6) if x > traj.x0 else math.ceil(x - 1e-6)
    else:
        count = counted(traj, x, t)
    traj.count_seen = (t, count)
    return count, v


def _onward_from(x: float, way: float) -> int:
    """The count at ``x`` where a motion from rest leaves the ``way`` way."""
    eps = 1e-6
    return math.floor(x + eps) if way > 0.0 else math.ceil(x - eps)


def _onward(count: int, x: float, way: float) -> int:
    """The counter at ``x`` after ``count``, travelling the ``way`` way (its sign) since: it
    moves on only as whole steps are passed that way."""
    eps = 1e-6
    if way > 0.0:
        return max(count, math.floor(x + eps))
    if way < 0.0:
        return min(count, math.ceil(x - eps))
    return count
