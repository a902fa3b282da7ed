"""What an axis's status shows at one instant (PC48 §6.13 RA): the way it is heading, and its
limit and home inputs as the switches see the carriage then.

The straightforward reading asks :meth:`~omsd.engine.axis_state.AxisState.heading`,
:meth:`~omsd.engine.axis_state.AxisState.carriage`,
:meth:`~omsd.engine.axis_state.AxisState.limit_active` and
:meth:`~omsd.engine.axis_state.AxisState.home_sensed`. A status is the report polled most
(issue 16), so where the world is plain (no switch forced, no soft travel limits, the limit
switches wired as the board expects them: ``LimitWiring.MATCHED``) :func:`status_inputs` finds
the trajectory's piece once for the position and the velocity, and tests the switches here, in
one place; anywhere else, and on a board without its fast paths (``Core.fast_paths``, what the
differential tests in ``tests/board/test_fast_paths.py`` compare with), it reads the axis the
straightforward way.
"""

from __future__ import annotations

from omsd.engine.axis_state import AxisState
from omsd.engine.counter import count_velocity
from omsd.engine.states import Motion
from omsd.engine.world import LimitWiring, SwitchType

_IDLE = Motion.IDLE
_MATCHED = LimitWiring.MATCHED
_NORMALLY_OPEN = SwitchType.NORMALLY_OPEN


def status_inputs(axis: AxisState, t: float) -> tuple[int, bool, bool]:
    """The status's direction (+1 or -1: ``heading``), its overtravel (``limit_active`` in
    that direction) and its home (``home_sensed``) at ``t``, the switches seeing the carriage
    once."""
    host = axis.host
    forced = host.world
    w = axis.world
    if not (
        host.fast_paths
        and axis.travel_limits is None
        and axis.stall_phys is None
        and w.limit_switches is _MATCHED
        and not forced.forced_limits
        and not forced.forced_home
    ):
        d = axis.heading(t)
        carriage = axis.carriage(t)
        return d, axis.limit_active(d, t, carriage), axis.home_sensed(t, carriage)
    if axis.motion is _IDLE:
        x, v = axis.traj.position_velocity(t)
    else:  # a moving carriage is at its last whole step (AxisState.carriage): x, the count
        x, v = count_velocity(axis.traj, t)
    d = 1 if v > 0 else -1 if v < 0 else axis.direction
    p = x + axis.phys_offset
    limit = p >= w.positive_limit if d > 0 else p <= w.negative_limit
    home = w.home_low <= p < w.home_high
    if w.home_switch is not _NORMALLY_OPEN:
        home = not home
    return d, limit, home != axis.home_high
