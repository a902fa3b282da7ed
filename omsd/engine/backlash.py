"""Backlash compensation: a general mechanism, inert until an axis is given a backlash.

* Stepper: extra motor steps "whenever a move command causes the motor to reverse direction
  ... output to the motor during the first motor update cycle following a direction change"
  (PCIx §5.12.2). On the first sample tick at which the axis moves in the other direction (the
  start of a move, a jog reversing, an arc turning back), the carriage (the physical position the
  switches and encoder see) jumps ``backlash`` steps in the new direction; the position counter
  does not count them. The board knows it sent them: slip detection and position maintenance do
  not take them for slip.
* Servo: the set point is offset from the commanded position "in the direction of the sign":
  from the first update after the axis starts moving in the direction of the backlash's sign the
  set point is ``backlash`` counts beyond the commanded position; after it reverses again, none.
* The direction the backlash is taken up in starts as the direction the axis last moved in when
  the backlash is set (at power-up: positive). A backlash of 0 switches it off (a servo's set
  point returns to the commanded position).
"""

from __future__ import annotations

import itertools
import math

from omsd.engine.axis_state import AxisState
from omsd.engine.states import Motion


def _compensation(backlash: int, direction: int) -> float:
    """The offset the backlash asks for while moving in ``direction``: its own sign, or none."""
    return float(backlash) if direction * backlash > 0 else 0.0


def set_backlash(axis: AxisState, value: int, t: float) -> None:
    axis.backlash = value
    if value == 0:
        axis.backlash_dir = None
        if axis.servo is not None and axis.setpoint_offset:
            axis.servo_sync(t)
            axis.setpoint_offset = 0.0
    elif axis.backlash_dir is None:
        axis.backlash_dir = axis.heading(t)
    axis.invalidate()


def _reversal(axis: AxisState, t_from: float, direction: int) -> float | None:
    """The first sample tick at or after ``t_from`` at which the axis is moving against
    ``direction`` (a moment of reversal shorter than the gap to the next tick is never seen)."""
    traj = axis.traj
    clock = axis.host.clock
    start = traj.t0
    for piece in traj.pieces:
        end = start + piece.duration
        if end <= t_from:
            start = end
            continue
        lo = max(0.0, t_from - start)
        bounds = [lo, *(tp for tp in piece.turning_points() if tp > lo), piece.duration]
        for a, b in itertools.pairwise(bounds):
            if b <= a:
                continue
            mid = a + 1.0 if math.isinf(b) else (a + b) / 2.0
            if piece.v(mid) * direction < 0:
                tick = clock.at_or_after(start + a)
                if tick < start + b:
                    return tick
        start = end
    return None


def backlash_tick(axis: AxisState) -> float | None:
    """When the axis next takes up backlash (an event time for the axis's next event)."""
    if not axis.backlash or axis.motion is Motion.IDLE:
        return None
    if axis.backlash_dir is None:
        axis.backlash_dir = axis.direction
    return _reversal(axis, axis.host.now, axis.backlash_dir)


def take_up_backlash(axis: AxisState, t: float) -> None:
    """The first update after a direction change: the extra steps (stepper), the set point
    offset (servo)."""
    old = axis.backlash_dir if axis.backlash_dir is not None else axis.direction
    new = axis.direction_at(t)
    if new == 0 or new == old:
        return
    axis.backlash_dir = new
    bc = axis.backlash
    if axis.servo is not None:
        axis.servo_sync(t)
        axis.setpoint_offset = _compensation(bc, new)
    else:
        delta = _compensation(bc, new) - _compensation(bc, old)
        if axis.stall_phys is not None:
            axis.stall_phys += delta
        else:
            axis.phys_offset += delta
        # the encoder sees the extra steps; the board sent them and does not count them as slip
        axis.track_enc += axis.ratio * delta
        axis.hold_goal += axis.ratio * delta
    axis.invalidate()
