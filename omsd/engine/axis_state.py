"""One axis of a board: its parameters, its frames, its switches and its encoder.

Positions live in two frames. The *counter* is the board's position register; the *physical*
position is where the carriage really is, in the frame of the world (:mod:`omsd.engine.world`),
and it is what limit and home switches and the encoder see. ``physical = counter +
phys_offset``; loading the counter moves the offset, not the carriage. A stalled motor (injected
fault) freezes the physical position while pulses keep counting.

Motion is a :class:`~omsd.engine.trajectory.Trajectory` in the counter frame. This class holds
the state and reads it; :class:`omsd.engine.axis.Axis` adds starting and ending motion and the
search for what happens next. The mechanisms in between (backlash, gearing, sensing) work on an
:class:`AxisState`, so that the axis class can call them without a circle.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from decimal import Decimal
from typing import TYPE_CHECKING, Any, Protocol

from omsd.engine import profiles as pf
from omsd.engine.clock import SampleClock
from omsd.engine.counter import count_at
from omsd.engine.extensions import Options
from omsd.engine.queue import CommandQueue, SyncGroup
from omsd.engine.states import Gear, HomeSearch, Motion, Pending, Wait
from omsd.engine.trajectory import Trajectory
from omsd.engine.world import AxisWorld, LimitWiring, SwitchType, WorldState
from omsd.models.spec import Model

if TYPE_CHECKING:  # the servo loop is imported by the boards that have servo axes (start-up)
    from omsd.engine.servo import ServoLoop

#: How often a moving (or settling) servo axis is looked at for a runaway following error:
#: every 32 samples of the 2048-per-second loop, 15.6 ms.
SERVO_CHECK = 1.0 / 64

#: Enum members as module names, for the readings a query makes (counter, carriage, switches):
#: an Enum member read through its class costs about 70 ns in Python 3.11, a global about 10.
_IDLE = Motion.IDLE
_MATCHED, _NORMALLY_OPEN = LimitWiring.MATCHED, LimitWiring.NORMALLY_OPEN
_SWITCH_NORMALLY_OPEN = SwitchType.NORMALLY_OPEN

#: How close the continuous position must come to a whole step for :func:`steps` to count it
#: (half its own tolerance, so that a position found at the level is counted whichever way
#: the motion goes).
STEP_EPS = 5e-7


class Host(Protocol):
    """What an axis reads of the machine it is part of."""

    @property
    def model(self) -> Model: ...

    @property
    def clock(self) -> SampleClock: ...

    @property
    def world(self) -> WorldState: ...

    @property
    def options(self) -> Options: ...

    @property
    def now(self) -> float: ...

    @property
    def talker(self) -> int: ...

    @property
    def axes(self) -> Sequence[AxisState]: ...

    #: the machine's cached next deadline is to be found again (an axis's next event changed)
    deadline_stale: bool

    #: the fast paths are taken (issue 16; False only in the differential tests' reference)
    fast_paths: bool

    #: fast path (issue 16): a motion's first-tick look at the sensors may be left out where it
    #: cannot find anything (:func:`omsd.engine.sensing.first_look_needed`); False with the
    #: fast paths off, or with a dialect's own sensor hooks (which look at every check)
    plain_sensing: bool

    #: ``Machine.advance`` is running the settle after the events of one instant (whatever is
    #: due at that instant then happens before the advance returns)
    after_events: bool


class AxisState:
    # attributes in slots (issue 16; omsd.engine.core.Core's note)
    # fmt: off
    __slots__ = (
        "ac", "aux", "aux_default_high", "aux_timer", "backlash", "backlash_dir", "contour_origin",
        "dc", "direction", "direction_inverted", "done", "done_bit", "enc_base", "enc_phys", "es",
        "event", "gear", "has_encoder", "hd", "hg", "hold", "hold_goal", "home", "home_encoder",
        "home_high", "home_last_phys", "host", "hv", "in_arm", "in_fire", "in_position", "index",
        "is_servo", "letter", "limit_high", "limit_latched", "limit_ramp", "limits_on", "motion",
        "outputs", "pa", "pending", "phys_offset", "queue", "quiet_known", "quiet_memo", "ramp",
        "ratio", "se_ms", "sensor_check", "servo", "servo_last", "servo_trip_reported",
        "setpoint_offset", "slip_detect", "slip_kill", "slipped", "soft_limit", "source",
        "stall_phys", "stream_end", "track_counter", "track_enc", "tracking", "traj",
        "travel_limits", "uu", "vb", "vl", "wait", "world",
    )
    # fmt: on

    def __init__(self, host: Host, index: int, letter: str, world: AxisWorld) -> None:
        model = host.model
        self.host = host
        self.index = index
        self.letter = letter
        self.world = world
        self.has_encoder = model.has_encoder(letter)
        self.is_servo = model.is_servo(letter)
        self.servo_trip_reported = False  # the trip of the loop's current closing was reported
        self.servo_last: float | None = None  # motor position at the last look (on_servo)
        # a servo axis: the PID loop and motor (omsd.engine.servo); the trajectory is the
        # commanded position, the loop's motor the actual one
        self.servo: ServoLoop | None = None
        if self.is_servo:
            from omsd.engine.servo import ServoLoop

            self.servo = ServoLoop(rate=model.sample_rate, origin=host.clock.origin)
        self.done_bit = 1 << model.done_bits[index]
        self.queue = CommandQueue(model.queue_size)
        self.phys_offset = world.start_position
        self.traj = Trajectory.at_rest(host.clock.origin, 0.0)
        self.stall_phys: float | None = None
        self.source = 0  # the session whose commands the axis last ran (see Machine.talker)
        self.reset(host.clock.origin, keep_position=False)

    # -- power-up / reset ---------------------------------------------------------------------

    def reset(self, t: float, keep_position: bool = True) -> None:
        """Power-up defaults (PC48 §8.1 of the digest; each value from its command's text)."""
        self.servo_sync(t)  # the loop runs to the reset on the old trajectory and gains
        phys = self.phys(t) if keep_position else self.world.start_position
        self.traj = Trajectory.at_rest(t, 0.0)
        self.motion = Motion.IDLE
        self.phys_offset = phys if self.stall_phys is None else self.stall_phys
        self.factory_parameters()
        self.slip_kill: bool = False  # a slip beyond the tolerance kills the axis
        # mechanisms only some dialects switch on; inert until a command sets them
        self.gear: Gear | None = None  # the axis this one follows (omsd.engine.gearing)
        self.travel_limits: tuple[float, float] | None = None  # soft travel limits (lower, upper)
        self.backlash_dir: int | None = None  # direction the backlash was last taken up in
        self.setpoint_offset = 0.0  # backlash on a servo: set point beyond the commanded position
        self.contour_origin: float | None = None  # where a running contour's own pieces begin
        self.home_encoder: bool = False
        self.hold = False
        self.slip_detect = False
        self.tracking = False
        self.done = False
        self.slipped = False
        self.direction = 1
        self.aux: bool = True
        self.aux_timer: float | None = None
        self.in_arm: tuple[float, SyncGroup] | None = None
        self.in_fire: float | None = None
        self.pending: Pending | None = None
        self.home: HomeSearch | None = None
        self.home_last_phys = phys
        self.wait: Wait | None = None
        self.stream_end: float | None = None  # when the last VS entry's time is over, unrounded
        self.sensor_check: float | None = None
        self.limit_latched: int = 0  # direction of the limit last run into, for the status
        # ramping down from a limit in the soft-limit mode (SL): the switch it runs past is what
        # it is reacting to (reactions._limit); cleared by new motion and at rest (Axis.begin,
        # settle, halt: a move started without begin, omsd.engine.follow_on, starts from rest;
        # gearing.follow, which gives a geared axis its master's motion without begin); kept by
        # a stop of that ramp, the same ramp at AC (Axis.begin's limit_ramp, given by
        # Axis.decelerate: ST, SA, SD; and by JG0)
        self.limit_ramp = False
        self.hold_goal = 0.0
        self.in_position = True
        self.outputs: list[tuple[float, tuple[str, int, bool]]] = []  # contour I/O actions
        self.queue.flush()
        if self.servo is not None:  # the loop is open at power up or reset
            self.servo_sync(t)
            self.servo.closed = False
        self.enc_base = 0.0
        self.enc_phys = phys
        self.track_enc = 0.0
        self.track_counter = 0.0
        # the axis's next event, (time, kind) as omsd.engine.sensing.next_event finds it (time
        # inf: none), kept until invalidate(); None: to be found again (Axis.next_event_time)
        self.event: tuple[float, str] | None = None
        # where the queue can take the axis, kept by omsd.engine.quiet (a Plan)
        self.quiet_memo: Any = None
        # whether the axis was found quiet, and the machine's outside_epoch then
        # (Machine._find_wakeup)
        self.quiet_known: tuple[int, bool] | None = None
        self.host.deadline_stale = True

    def factory_parameters(self) -> None:
        """The parameters as they leave the factory: power-up, and a dialect's reset to factory
        defaults (before saved defaults are loaded over them)."""
        model = self.host.model
        self.vl: float = float(model.default_velocity)
        self.ac: float = float(model.default_acceleration)
        self.vb: float = 0.0
        self.ramp = pf.LINEAR
        self.uu: Decimal | None = None
        self.ratio = 1.0  # encoder counts per motor count
        self.hv: float = 0.0
        self.hg: float = 1.0
        self.hd: float = 0.0
        self.es: float = self.host.options.slip_tolerance
        self.limits_on: bool = True
        self.home_high: bool = False
        self.pa: bool | None = None  # aux state during a move in power-automatic mode
        self.se_ms: int = 0
        self.soft_limit = False  # per axis, or the same on every axis (Options)
        self.dc: float = 200_000.0  # the deceleration of an asymmetric move
        self.backlash: int = 0
        self.aux_default_high: bool = True
        self.direction_inverted: bool = False
        self.limit_high: bool = False  # limit lines true when high (else low)
        if self.servo is not None:
            from omsd.engine.servo import ServoGains

            self.servo.set_gains(ServoGains())

    @property
    def base_velocity(self) -> float:
        """The VB a linear move is built with: VB itself (a ramp clamps one above VL to VL),
        but on a board whose model says so (the PCIx: "If ... the velocity value set with VL is
        less than the previously set VB value, the initial velocity used at the start of a move
        will be the VL value minus one") VL less that margin, when VB is above VL."""
        margin = self.host.model.base_above_peak
        if margin is not None and self.vb > self.vl:
            return max(self.vl - margin, 0.0)
        return self.vb

    # -- frames -------------------------------------------------------------------------------

    def position(self, t: float) -> float:
        return self.traj.position(t)

    def servo_sync(self, t: float) -> None:
        """Run the servo loop up to ``t`` against the commanded trajectory."""
        loop = self.servo
        if loop is None or t <= loop.time:
            return
        offset = self.setpoint_offset  # backlash on a servo axis
        if self.motion is _IDLE and self.traj.end_time <= loop.time:
            loop.run(self.traj.position(t) + offset, t)
        elif offset:
            traj = self.traj
            loop.run(lambda s: traj.position(s) + offset, t, traj.velocity, traj.acceleration)
        else:
            loop.run(self.traj.position, t, self.traj.velocity, self.traj.acceleration)

    def servo_check_time(self) -> float | None:
        """When the loop must next be looked at for a runaway (while it has work to do)."""
        loop = self.servo
        if loop is None:
            return None
        if loop.tripped and not self.servo_trip_reported:
            return max(loop.time, self.host.now)  # found by a query's look at the loop
        if not loop.closed:
            return None
        if self.motion is _IDLE:
            # still since the last look (at rest, or held off its set point by the integrator
            # limit), and nothing changed since (gains, loop closed): nothing will change
            last = self.servo_last
            if last is not None and abs(loop.position - last) < 1e-6 and abs(loop.velocity) < 1e-3:
                return None
        return loop.time + SERVO_CHECK

    def counter(self, t: float) -> int:
        """The position register: whole steps emitted so far."""
        if self.motion is _IDLE:
            return math.floor(self.traj.position(t) + 0.5)
        # RP after QA (issue 16): the count the status found at this instant, kept (count_at)
        seen = self.traj.count_seen
        return seen[1] if seen[0] == t else count_at(self.traj, t)

    def velocity(self, t: float) -> float:
        return self.traj.velocity(t)

    def acceleration(self, t: float) -> float:
        return self.traj.acceleration(t)

    def phys(self, t: float) -> float:
        if self.stall_phys is not None:
            return self.stall_phys
        return self.traj.position(t) + self.phys_offset

    def carriage(self, t: float) -> float:
        """Where the switches see the carriage: the physical position of the last whole step
        emitted, in the frame the stop point is taken in (``settle``, ``halt``). A carriage
        stopped by a switch is therefore on the switch, whatever fraction of a step the counter
        and the carriage are apart after a home, a load, an encoder ratio or backlash."""
        if self.stall_phys is not None:
            return self.stall_phys
        if self.motion is _IDLE:
            return self.traj.position(t) + self.phys_offset
        return float(count_at(self.traj, t)) + self.phys_offset

    @property
    def moving(self) -> bool:
        return self.motion is not _IDLE

    def load_counter(self, t: float, value: float) -> None:
        """Set the position register to ``value`` at ``t`` without moving the carriage."""
        self.servo_sync(t)
        x = self.traj.position(t)
        self.phys_offset += x - value
        self.traj = pf.rebased(self.traj, t, value - x)
        self.invalidate()

    def command_at(self, t: float, value: float) -> None:
        """Command a servo at rest to ``value`` at ``t``, where its motor is: the position
        register and the carriage go there together (the switches see the commanded position,
        which a closed loop follows), unlike ``load_counter``, which relabels the carriage."""
        self.servo_sync(t)
        self.traj = pf.rebased(self.traj, t, value - self.traj.position(t))
        self.invalidate()

    # -- encoder ------------------------------------------------------------------------------

    def encoder(self, t: float) -> int:
        if self.servo is not None:
            self.servo_sync(t)
            return self.servo.encoder_counts
        return math.floor(self.enc_base + self.ratio * (self.phys(t) - self.enc_phys) + 0.5)

    def anchor_encoder(self, t: float, value: float | None = None) -> None:
        """Re-anchor the encoder model at ``t`` (a load gives ``value``; a ratio change keeps
        the count)."""
        if self.servo is not None and value is not None:
            self.servo_sync(t)
            self.servo.set_position(value)
        self.enc_base = float(self.encoder(t)) if value is None else value
        self.enc_phys = self.phys(t)
        self.anchor_tracking(t)

    def anchor_tracking(self, t: float) -> None:
        """Take the present encoder/counter relation as the no-slip reference."""
        self.track_enc = float(self.encoder(t))
        self.track_counter = self.position(t)
        self.invalidate()

    def tracked_encoder(self, x: float) -> float:
        """The encoder count the no-slip relation (:meth:`anchor_tracking`) gives for counter
        position ``x``: what slip detection expects, and what a hold holds at the end of a
        motion."""
        return self.track_enc + self.ratio * (x - self.track_counter)

    def slip_error(self, t: float) -> float:
        return self.encoder(t) - self.tracked_encoder(self.position(t))

    def to_motor(self, value: float) -> float:
        """User counts (encoder counts on an encoder axis) to motor steps (PC48 §6.15)."""
        return value / self.ratio if self.has_encoder else value

    # -- switches -----------------------------------------------------------------------------

    def limit_active(self, direction: int, t: float, carriage: float | None = None) -> bool:
        """The limit input in ``direction``; ``carriage``: :meth:`carriage` at ``t`` if the
        caller has it already (a snapshot asks for both limits and home at one instant)."""
        if self.travel_limits is not None and self.beyond_travel_limit(direction, t):
            return True  # soft travel limits flag a limit just as the switches would
        return self.limit_switch_active(direction, t, carriage)

    def limit_switch_active(self, direction: int, t: float, carriage: float | None = None) -> bool:
        """The limit switch input in ``direction`` (the line after its active level), travel
        limits aside."""
        forced = self.host.world.forced_limit(self.index, direction)
        if forced is not None:
            hit = forced
        else:
            p = self.carriage(t) if carriage is None else carriage
            w = self.world
            hit = p >= w.positive_limit if direction > 0 else p <= w.negative_limit
        wiring = self.world.limit_switches
        if wiring is _MATCHED:
            return hit
        # the line's level: a normally open switch grounds it when hit, a normally closed one
        # until hit; limits true when low (the power-up default) or, if set so, when high
        low = hit if wiring is _NORMALLY_OPEN else not hit
        return (not low) if self.limit_high else low

    def look_at_sensors(self, t: float) -> None:
        """The sensors are to be looked at on the sample of ``t`` (how they read, or what is
        looked for, has changed): at ``t``, unless a look is already asked for after it. That
        is a motion's first look, on the sample it begins on: it sees the change, and a look
        at ``t``, before the motion, would see no direction and take its place (the axis
        standing on a switch then ran through it)."""
        check = self.sensor_check
        if check is None or check < t:
            self.sensor_check = t
        self.invalidate()

    def set_travel_limits(self, upper: float, lower: float, t: float) -> None:
        """Soft travel limits, absolute positions; ``0, 0`` switches them off."""
        self.travel_limits = None if upper == 0 and lower == 0 else (lower, upper)
        self.look_at_sensors(t)

    def beyond_travel_limit(self, direction: int, t: float) -> bool:
        """Travel-limit overtravel in ``direction``, for the motions the limits apply to."""
        limits = self.travel_limits
        if limits is None or self.motion not in TRAVEL_LIMITED:
            return False
        lower, upper = limits
        position = self.counter(t)
        return position > upper if direction > 0 else position < lower

    def home_switch_activated(self, t: float, carriage: float | None = None) -> bool:
        forced = self.host.world.forced_home.get(self.index)
        if forced is not None:
            return forced
        p = self.carriage(t) if carriage is None else carriage
        return self.world.home_low <= p < self.world.home_high

    def home_line_low(self, t: float, carriage: float | None = None) -> bool:
        activated = self.home_switch_activated(t, carriage)
        if self.world.home_switch is _SWITCH_NORMALLY_OPEN:
            return activated
        return not activated

    def home_sensed(self, t: float, carriage: float | None = None) -> bool:
        """The home input after the active-high/low sense: what a status reports as home."""
        return self.home_line_low(t, carriage) != self.home_high

    def encoder_home(self, t: float) -> bool:
        """Encoder home mode (PC48 §6.18): index AND quadrant AND the low-true home enable."""
        if not self.home_line_low(t):
            return False
        cpr = self.world.encoder_counts_per_rev
        return cpr > 0 and (self.encoder(t) - self.world.index_count) % cpr == 0

    def home_condition(self, t: float) -> bool:
        return self.encoder_home(t) if self.home_encoder else self.home_sensed(t)

    def direction_at(self, t: float) -> int:
        v = self.traj.velocity(t)
        if v == 0.0 and self.traj.moving_at(t):
            v = self.traj.velocity(min(t + 1e-6, (t + self.traj.end_time) / 2))
        if v > 0:
            return 1
        if v < 0:
            return -1
        return 0

    def note_direction(self, t: float) -> None:
        """Remember the direction the axis was last moving in (the status's direction)."""
        v = self.traj.velocity(t)
        if v == 0.0 and self.traj.pieces:
            v = self.traj.velocity(min(t, self.traj.end_time) - 1e-7)
        if v:
            self.direction = 1 if v > 0 else -1

    def heading(self, t: float) -> int:
        """The status's direction: "Moving in positive direction" / "negative direction"; at
        rest, the direction it last moved in (or was set to)."""
        v = self.traj.velocity(t)
        if v > 0:
            return 1
        if v < 0:
            return -1
        return self.direction

    def invalidate(self) -> None:
        """What happens next to the axis is to be found again (and so is the machine's next
        deadline, the earliest of its axes')."""
        self.event = None
        self.host.deadline_stale = True

    def end_tick(self) -> float | None:
        if self.motion is _IDLE or not self.traj.is_finite:
            return None
        return self.host.clock.at_or_after(self.traj.end_time)


#: "Move Absolute (MA), Move Relative (MR), and Jog (JF, JG) commands are subject to software
#: travel limits" (PCIx §5.5.4; at rest and ramping to a stop, the status still reports the
#: overtravel).
TRAVEL_LIMITED = (Motion.IDLE, Motion.STOP, Motion.MOVE, Motion.JOG)
