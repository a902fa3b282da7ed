"""A running contour switched to a new speed at its next segment, without ramping (a general
mechanism; PCIx §5.9.8 NV: "the PCIX will switch to the new velocity at the start of the next
command in the contour queue without ramping").

The segments after the one being run go at the new speed (a final ramp down starts from it, at
the same deceleration), and the contour's output actions after the switch move with them.
:func:`new_contour_velocity` does it for every contour running on a machine's axes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from omsd.engine import profiles as pf
from omsd.engine.axis_state import AxisState
from omsd.engine.clock import SampleClock
from omsd.engine.gearing import moved
from omsd.engine.states import Motion


def new_contour_velocity(axes: Sequence[AxisState], velocity: float, t: float) -> None:
    """Every contour running at ``t`` goes on at ``velocity`` from its next segment."""
    origins: dict[float, list[AxisState]] = {}
    for axis in axes:
        if axis.motion is Motion.CONTOUR and axis.contour_origin is not None:
            origins.setdefault(axis.contour_origin, []).append(axis)
    for origin, members in origins.items():
        _retime(members, origin, velocity, t)


def _future(axis: AxisState, after: float) -> tuple[list[pf.Piece], list[pf.Piece], float]:
    """The axis's pieces split at the first piece boundary after ``after``, and that boundary."""
    traj = axis.traj
    start = traj.t0
    for i, piece in enumerate(traj.pieces):
        end = start + piece.duration
        if end > after + 1e-12:
            return list(traj.pieces[: i + 1]), list(traj.pieces[i + 1 :]), end
        start = end
    return list(traj.pieces), [], start


def _rescaled(piece: pf.Piece, f: float, ramp: bool) -> pf.Piece | None:
    """A contour piece run ``f`` times as fast (the final ramp: from ``f`` times the speed, at
    the same deceleration)."""
    if isinstance(piece, pf.Sinusoid):
        return pf.Sinusoid(piece.r, piece.phase0, piece.omega * f, piece.duration / f)
    if isinstance(piece, pf.Poly) and piece.j == 0.0:
        if ramp:
            return pf.Poly(piece.v0 * f, piece.a0, 0.0, piece.duration * f)
        if piece.a0 == 0.0:
            return pf.Poly(piece.v0 * f, 0.0, 0.0, piece.duration / f)
    return None


def _retime(axes: list[AxisState], origin: float, velocity: float, t: float) -> None:
    host = axes[0].host
    after = max(t, origin)
    splits = {a.index: _future(a, after) for a in axes}
    futures = [splits[a.index][1] for a in axes]
    if not futures[0]:
        return  # on the last piece (or the final ramp): there is no next segment
    boundary = splits[axes[0].index][2]
    # the final ramp down is the last piece of a contour that has one: it decelerates
    ramp = any(isinstance(f[-1], pf.Poly) and f[-1].a0 != 0.0 for f in futures)
    if ramp and len(futures[0]) == 1:
        return  # only the ramp down is left
    speed = math.sqrt(sum(f[0].v(0.0) ** 2 for f in futures))
    if speed <= 0.0:
        return
    factor = velocity / speed
    replaced: dict[int, list[pf.Piece]] = {}
    for axis, future in zip(axes, futures, strict=True):
        pieces: list[pf.Piece] = []
        for k, piece in enumerate(future):
            new = _rescaled(piece, factor, ramp and k == len(future) - 1)
            if new is None:
                return  # not a contour's pieces after all: leave it alone
            pieces.append(new)
        replaced[axis.index] = pieces
    for axis in axes:
        past = splits[axis.index][0]
        traj = axis.traj
        pieces = past + replaced[axis.index]
        end = pf.Trajectory(traj.t0, traj.x0, pieces).final
        axis.servo_sync(host.now)
        axis.traj = pf.Trajectory(
            traj.t0, traj.x0, pieces, float(math.floor(end + 0.5)), traj.count
        )
        axis.outputs = [
            (_retimed(host.clock, when, boundary, factor), action) for when, action in axis.outputs
        ]
        axis.invalidate()
        moved(axis, host.now, origin, Motion.CONTOUR)


def _retimed(clock: SampleClock, when: float, boundary: float, factor: float) -> float:
    if when <= boundary:
        return when
    return clock.at_or_after(boundary + (when - boundary) / factor)
