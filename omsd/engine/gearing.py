"""Electronic gearing: an axis follows a master axis, a general mechanism (PCIx §5.12.5).

"the current axis (geared axis) is to track the master axis velocity such that the current axis
velocity = Ratio X Master Axis velocity", whatever the master is doing (a move, a jog, a contour,
a home search, a stop). Whenever the master's trajectory changes (it begins new motion, comes to
rest or is killed) the geared axis takes the master's motion from that instant on, scaled by the
ratio, from where it is: its velocity is the ratio times the master's at every instant. The
geared axis keeps an exact record of where the ratio puts it (:class:`~omsd.engine.states.Gear`),
so fractional ratios do not drift: a move of 1001 counts at a ratio of 1:2 ends on 500 or 501
and the next one makes up the half count.

A geared axis moves only as its master does (:meth:`omsd.engine.axis.Axis.begin` starts nothing
on it); a flush of its queue disengages it, and it then finishes the motion it was given last (a
copy of a master's move ends where it would have; a copy of a jog goes on as a jog).
"""

from __future__ import annotations

import math

from omsd.engine import profiles as pf
from omsd.engine.axis_state import AxisState
from omsd.engine.states import Gear, Motion


def _sign(v: float) -> int:
    return 1 if v > 0 else -1 if v < 0 else 0


def gearable(slave: AxisState, master: AxisState) -> bool:
    """An axis cannot be geared to itself nor to an axis that is itself geared."""
    return master is not slave and master.gear is None


def engage(slave: AxisState, master: AxisState, ratio: float, text: str, t: float) -> None:
    """Gear ``slave`` to ``master`` from ``t`` on: it takes up the master's present motion."""
    slave.gear = Gear(master.index, ratio, text, base=slave.position(t))
    follow(slave, master, t)


def disengage(slave: AxisState, t: float) -> None:
    """The gearing ends: the axis keeps the motion it was last given (see the module doc)."""
    if slave.gear is None:
        return
    slave.gear = None
    if slave.motion is Motion.GEAR:
        slave.motion = Motion.MOVE if slave.traj.is_finite else Motion.JOG
    slave.invalidate()


def follow(slave: AxisState, master: AxisState, now: float) -> None:
    """The master's motion changed at ``now``: the geared axis takes its scaled copy."""
    gear = slave.gear
    assert gear is not None
    slave.servo_sync(now)
    ideal = gear.ideal(now)
    x = slave.position(now)
    v_before = slave.velocity(now)
    if v_before:
        slave.direction = _sign(v_before)
    pieces = pf.pieces_between(master.traj, now, math.inf, gear.ratio)
    path = pf.Trajectory(now, 0.0, pieces)
    gear.base, gear.path = ideal, path
    slave.limit_ramp = False  # (its motion is the master's copy now, not a soft-limit ramp)
    if not pieces:
        slave.traj = pf.Trajectory.at_rest(now, float(math.floor(ideal + 0.5)))
        slave.motion = Motion.IDLE
    else:
        final: float | None = None
        if master.traj.is_finite:
            travel = master.traj.final - master.traj.position(now)
            final = float(math.floor(ideal + gear.ratio * travel + 0.5))
        count = None if slave.motion is Motion.IDLE else slave.counter(now)
        slave.traj = pf.Trajectory(now, x, pieces, final, count)
        slave.motion = Motion.GEAR
        slave.in_position = False
        slave.home = None
    slave.sensor_check = slave.host.clock.at_or_after(now)
    slave.invalidate()
    moved(slave, now, None, None)


def followed(axis: AxisState) -> bool:
    """Some axis is geared to ``axis`` (``moved`` has it follow)."""
    index = axis.index
    for other in axis.host.axes:
        gear = other.gear
        if gear is not None and gear.master == index:
            return True
    return False


def moved(axis: AxisState, now: float, start: float | None, motion: Motion | None) -> None:
    """The axis's trajectory was replaced at ``now`` (new motion beginning at ``start``, or
    rest): remember where a contour's own pieces begin (for retiming it), and let the axes geared
    to it follow."""
    axis.contour_origin = start if motion is Motion.CONTOUR else None
    for other in axis.host.axes:
        if other.gear is not None and other.gear.master == axis.index:
            follow(other, axis, now)
