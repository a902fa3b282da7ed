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
    way the axis travels (:func:`steps` from where the motion began). At its start (``x``
    there exactly: a motion begun between two steps by a stop or a new jog) the way is the one
    it leaves in, not the positive one: a stop of a motion the negative way at -40.12 counts
    -40, as the motion it took over did, not a step ahead (-41). After a turn within the motion
    (a jog turned round by one of the other sign) the steps of the way back are counted from
    the step the turn was on: turned at -500 and back up at -488.975, -489."""
    origin = traj.x0
    if traj.turns:
        way = traj.way
        now = traj.velocity(t)
        if now == 0.0 and traj.t0 < t:  # at the end: the way it came
            now = traj.velocity(max(traj.t0, min(t, traj.end_time) - 1e-9))
        if now * way < 0.0 and (turned := traj.turn(t, way)) is not None:
            at_turn = steps(turned, origin)
            eps = 1e-6
            return (
                max(at_turn, math.floor(x + eps)) if now > 0.0 else min(at_turn, math.ceil(x - eps))
            )
    if x == origin and traj.way < 0.0:
        return math.ceil(x - 1e-6)
    return steps(x, origin)
