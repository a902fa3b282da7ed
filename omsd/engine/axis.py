"""One axis of a board in motion: starting and ending motion, and when it next needs a look.

:class:`Axis` is an :class:`~omsd.engine.axis_state.AxisState` (parameters, frames, switches,
encoder) that can begin new motion from wherever it is, come to rest on a whole step, stop at
once or ramp down, and say when something will next happen to it by itself
(:mod:`omsd.engine.sensing`), quantized onto the sample grid so the board can sleep until then.
Whenever its trajectory is replaced the axes geared to it follow (:mod:`omsd.engine.gearing`).
"""

from __future__ import annotations

import math

from omsd.engine import profiles as pf
from omsd.engine.axis_state import SERVO_CHECK, AxisState
from omsd.engine.counter import counted
from omsd.engine.gearing import moved
from omsd.engine.sensing import first_look_needed, next_event
from omsd.engine.states import HomeSearch, Motion, Pending, Wait
from omsd.engine.trajectory import Trajectory

_MOVE = Motion.MOVE
#: Below this (steps a second) the end of a move's ramp down is rest, not a base velocity.
BASE_FLOOR = 1e-6

__all__ = ["SERVO_CHECK", "Axis", "HomeSearch", "Motion", "Pending", "Wait"]


class Axis(AxisState):
    # -- motion -------------------------------------------------------------------------------

    def begin(
        self,
        t: float,
        pieces: list[pf.Piece],
        motion: Motion,
        final: float | None = None,
        *,
        limit_ramp: bool = False,
    ) -> None:
        """Start new motion on tick ``t`` from wherever the axis is then (position and
        velocity). Until ``t`` the axis goes on as it was: asking for the position between now
        and the tick must not show the future. ``limit_ramp``: the new motion is a stop of the
        soft-limit mode's own ramp down, that same ramp at AC (ST, JG0), which keeps its mark
        (``AxisState.limit_ramp``) while it moves; any other motion clears it."""
        if self.gear is not None:  # a geared axis moves only as its master does
            return
        host = self.host
        self.source = host.talker
        keep_ramp = limit_ramp and self.limit_ramp
        self.limit_ramp = False
        from_rest = self.motion is Motion.IDLE
        now = min(host.now, t)
        self.servo_sync(now)
        prefix = pf.segment(self.traj, now, t) if t > now else []
        moving_before = bool(prefix) and any(p.v(0.0) != 0.0 or p.a(0.0) != 0.0 for p in prefix)
        x_now = self.traj.position(now)
        if not pieces and not moving_before:
            x = self.traj.position(t)
            self.traj = Trajectory.at_rest(now, x if final is None else final)
            self.motion = Motion.IDLE
        else:
            if not moving_before:
                prefix = [pf.cruise(0.0, t - now)] if t > now else []
            # taking over from a motion, the count goes on from that motion's (which may have
            # come either way to a position between two steps); from rest, from the position
            count = None if from_rest else self.counter(now)
            self.traj = Trajectory(now, x_now, [*prefix, *pieces], final, count)
            self.motion = motion
            self.limit_ramp = keep_ramp
            if motion is not Motion.HOLD:
                self.in_position = False
        if (
            t > now
            or not (from_rest and host.after_events and host.plain_sensing)
            or first_look_needed(self, t, motion)
        ):
            self.sensor_check = t
        self.invalidate()
        moved(self, now, t, motion)

    def settle(self, t: float) -> None:
        """Come to rest on the whole step the counter shows (end of motion)."""
        self.servo_sync(t)
        self.note_direction(t)
        x = self.traj.position(t)
        self.traj = Trajectory.at_rest(t, float(counted(self.traj, x, t)))
        self.motion = Motion.IDLE
        self.limit_ramp = False
        self.invalidate()
        moved(self, t, None, None)

    def halt(self, t: float) -> None:
        """Stop pulses at once (a kill, a hard limit, home found by a kill-at-home search). A
        motion stopped so has ended as one that runs out does: power automatic's output goes
        back to its idle state (:meth:`power_down`)."""
        ended = self.motion is not Motion.IDLE and self.motion is not Motion.HOLD
        self.servo_sync(t)
        self.note_direction(t)
        x = self.traj.position(t)
        self.traj = Trajectory.at_rest(t, float(counted(self.traj, x, t)))
        self.motion = Motion.IDLE
        self.limit_ramp = False
        self.home = None
        self.outputs.clear()  # (a contour's I/O actions further on its path: never reached)
        if ended:
            self.power_down(t)
        self.invalidate()
        moved(self, t, None, None)

    def power_down(self, t: float) -> None:
        """The end of a motion in power-automatic mode: the auxiliary output, turned on "upon
        the execution of the GO or GD", goes "off at the end of that move" (PC48 §6.6 PA; the
        PCIx: "return to normal at the end"), after the settling time if SE gave one ("to be
        used before the power is reduced")."""
        if self.pa is not None and self.aux == self.pa:
            if self.se_ms:
                self.aux_timer = t + self.se_ms / 1000.0
            else:
                self.aux = not self.pa

    def decelerate(self, t: float, motion: Motion = Motion.STOP) -> None:
        """Ramp down to rest at the axis's acceleration (a stop, a soft limit, after home).

        A move with a base velocity ramps down to it and stops from there: VB "jumps instantly
        to the specified velocity, then ramps as usual. The deceleration is the same in reverse.
        This mode is active only for linear ramps" (PC48 §6.7). The base velocity is the move's
        own, where its profile's ramp down ends (VB on a linear ramp, scaled with the move for
        ML/MT; none on a parabolic or cosine ramp, for the PCIx's GU, or a jog's, "not valid
        with the JG command"), not the registers', which may have changed since it began."""
        v = self.traj.velocity(t)
        if v == 0.0:
            self.stop_on(t)
            return
        self.outputs.clear()  # (a contour's I/O actions further on its path: never reached)
        base = self.stop_base()
        if base and abs(v) <= base:
            self.stop_on(t)  # (at or below the base velocity: it drops to rest at once)
            return
        # a stop of the soft-limit mode's own ramp down (ST typed while it runs) is that same
        # ramp at AC: it runs on past the switch it reacts to (limit_ramp), heard once
        ramp = pf.velocity_change(v, math.copysign(base, v), self.ac)
        self.begin(t, ramp, motion, limit_ramp=True)

    def stop_on(self, t: float) -> None:
        """Stop pulses at once on tick ``t`` (:meth:`decelerate` with no speed to ramp down
        from there). Until the tick the axis goes on as it was, as :meth:`begin` has it, and
        the counter with it: a jog at -2500 at -109.375 (RP -109) given ``MR50 GO ST`` between
        two ticks (its move would start from rest on the next) read -110 at once, the step the
        pulses reach a quarter of a millisecond later. A stop of no length then ends there."""
        now = self.host.now
        if t > now and self.traj.moving_at(now):
            x = self.traj.position(t)
            self.begin(t, [], Motion.STOP, final=float(counted(self.traj, x, t)))
        else:
            self.halt(t)

    def stop_base(self) -> float:
        """The base velocity a stop of the current motion ramps down to and stops from (ST, SA,
        SD, a soft limit, FP): the move's own, where its profile's ramp down ends (VB on a linear
        ramp, scaled for ML/MT), 0 for every other motion (:meth:`decelerate`)."""
        if self.motion is not _MOVE or not self.traj.pieces:
            return 0.0
        last = self.traj.pieces[-1]
        base = abs(last.v(last.duration))
        return base if base >= BASE_FLOOR else 0.0  # (a ramp to rest, less floating point's)

    # -- what happens next --------------------------------------------------------------------

    def next_event_time(self) -> float | None:
        if self.event is None:
            self.event = next_event(self)
        t = self.event[0]
        return None if math.isinf(t) else t

    def due(self) -> str:
        if self.event is None:
            self.event = next_event(self)
        return self.event[1]
