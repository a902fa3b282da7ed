"""One axis of a board: its registers, its motion, its switches and its encoder.

Positions live in two frames. The *counter* is the board's position register (RP, LP, HM, RM);
the *physical* position is where the carriage really is, in the frame of the world
(:mod:`omsd.board.world`), and it is what limit and home switches and the encoder see.
``physical = counter + phys_offset``; loading the counter moves the offset, not the carriage.
A stalled motor (injected fault) freezes the physical position while pulses keep counting.

Motion is a :class:`~omsd.board.profiles.Trajectory` in the counter frame. Everything that
happens by itself (a move ends, a switch is reached, an IN threshold is passed, a settling time
runs out) is found analytically and reported by :meth:`Axis.next_event_time`, quantized onto the
sample grid, so the board can sleep until then.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from decimal import Decimal
from enum import Enum, auto
from typing import TYPE_CHECKING

from omsd.board import profiles as pf
from omsd.board.profiles import Trajectory
from omsd.board.queue import CommandQueue, SyncGroup
from omsd.board.servo import ServoGains, ServoLoop
from omsd.board.world import AxisWorld, LimitWiring, SwitchType

if TYPE_CHECKING:
    from omsd.board.board import Board
    from omsd.board.pcix_motion import Gear

#: How often a moving (or settling) servo axis is looked at for a runaway following error:
#: every 32 samples of the 2048-per-second loop, 15.6 ms.
SERVO_CHECK = 1.0 / 64


class Motion(Enum):
    IDLE = auto()
    MOVE = auto()  # point to point (GO/GD), the only kind soft limits apply to
    JOG = auto()
    HOME = auto()
    STOP = auto()
    STAIRCASE = auto()
    STREAM = auto()
    CONTOUR = auto()
    HOLD = auto()  # position-hold correction
    GEAR = auto()  # PCIx EG/TX: following a master axis (omsd.board.pcix_motion)


@dataclass
class Wait:
    """What the axis's current queue op waits for before the queue may go on."""

    kind: str  # "motion", "time", "group", "input", "inpos"
    until: float | None = None
    group: SyncGroup | None = None
    round: int = 0
    bit: int = 0
    high: bool = True  # "input": the level waited for (SW high, PCIx BW low)
    then: Callable[[float], None] | None = None  # run when the wait is over
    jump: int | None = None  # program index to go on from (a loop pass), else the next op


@dataclass
class Pending:
    """A move set up by MA/MR/ML/MT, waiting for GO/GD."""

    kind: str  # "abs" or "rel"
    value: float  # in user counts (encoder counts on encoder axes)
    linear: SyncGroup | None = None  # ML/MT interpolation group


@dataclass
class HomeSearch:
    position: float  # value loaded into the counter at home (HM#/HR#)
    kill: bool  # KM/KR: stop at once, do not load the counter
    direction: int
    prev: bool  # home condition at the previous look
    index_points: tuple[float, ...] = ()  # HE mode: physical points where home is true


class Axis:
    def __init__(self, board: Board, index: int, letter: str, world: AxisWorld) -> None:
        self.board = board
        self.index = index
        self.letter = letter
        self.world = world
        self.has_encoder = board.model.has_encoder(letter)
        self.is_servo = board.model.is_servo(letter)
        self.servo_trip_reported = False  # the trip of the loop's current closing was reported
        self.servo_last: float | None = None  # motor position at the last look (on_servo)
        # PCIx servo axis: the PID loop and motor (omsd.board.servo); the trajectory is the
        # commanded position, the loop's motor the actual one (RE, EA)
        self.servo: ServoLoop | None = (
            ServoLoop(rate=board.model.sample_rate, origin=board.clock.origin)
            if self.is_servo
            else None
        )
        self.done_bit = 1 << board.model.done_bits[index]
        self.queue = CommandQueue(board.model.queue_size)
        self.phys_offset = world.start_position
        self.traj = Trajectory.at_rest(board.clock.origin, 0.0)
        self.stall_phys: float | None = None
        self.source = 0  # the session whose commands the axis last ran (see Board.talker)
        self.reset(board.clock.origin, keep_position=False)

    # -- power-up / RS ------------------------------------------------------------------------

    def reset(self, t: float, keep_position: bool = True) -> None:
        """Power-up defaults (PC48 §8.1 of the digest; each value from its command's text)."""
        self.servo_sync(t)  # the loop runs to the reset on the old trajectory and gains
        phys = self.phys(t) if keep_position else self.world.start_position
        self.traj = Trajectory.at_rest(t, 0.0)
        self.motion = Motion.IDLE
        self.phys_offset = phys if self.stall_phys is None else self.stall_phys
        self.factory_parameters()
        self.slip_kill: bool = False  # PCIx TN / TF
        # PCIx motion state (omsd.board.pcix_motion); inert on the older boards
        self.gear: Gear | None = None  # EG / TX: the axis this one follows
        self.travel_limits: tuple[float, float] | None = None  # TL (lower, upper); TL0,0: None
        self.backlash_dir: int | None = None  # direction BC last took the backlash up in
        self.setpoint_offset = 0.0  # BC on a servo: set point beyond the commanded position
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
        self.sensor_check: float | None = None
        self.limit_latched: int = 0  # direction of the limit last run into, for RA
        self.hold_goal = 0.0
        self.in_position = True
        self.outputs: list[tuple[float, tuple[str, int, bool]]] = []  # contour I/O actions
        self.queue.flush()
        if self.servo is not None:  # HF: "the default mode at power up or reset"
            self.servo_sync(t)
            self.servo.closed = False
        self.enc_base = 0.0
        self.enc_phys = phys
        self.track_enc = 0.0
        self.track_counter = 0.0
        self._cache: tuple[float, str] | None = None

    # -- frames -------------------------------------------------------------------------------

    def factory_parameters(self) -> None:
        """The parameters as they leave the factory: power-up on the older boards; the PCIx's
        RF, and its power-up before the saved defaults (AP) are loaded over them."""
        model = self.board.model
        self.vl: float = float(model.default_velocity)
        self.ac: float = float(model.default_acceleration)
        self.vb: float = 0.0
        self.ramp = pf.LINEAR
        self.uu: Decimal | None = None
        self.ratio = 1.0  # encoder counts per motor count (ER)
        self.hv: float = 0.0
        self.hg: float = 1.0
        self.hd: float = 0.0
        # ES: the PCIx's "factory default value is 1"; the PC48's slip tolerance starts at 0
        self.es: float = 1.0 if model.dialect == "pcix" else 0.0
        self.limits_on: bool = True
        self.home_high: bool = False
        self.pa: bool | None = None  # aux state during a move in PA mode
        self.se_ms: int = 0
        self.soft_limit = False  # SL / SF (per axis on the PCIx; Board.soft_limits sets all)
        # PCIx parameters (the older boards never change them)
        self.dc: float = 200_000.0  # DC: "defaults to 200,000"
        self.backlash: int = 0  # BC
        self.aux_default_high: bool = True  # ADH / ADL
        self.direction_inverted: bool = False  # DBI / DBN
        self.limit_high: bool = False  # LH / LL
        if self.servo is not None:
            self.servo.set_gains(ServoGains())

    def position(self, t: float) -> float:
        return self.traj.position(t)

    # -- servo --------------------------------------------------------------------------------

    def servo_sync(self, t: float) -> None:
        """Run the servo loop up to ``t`` against the commanded trajectory."""
        loop = self.servo
        if loop is None or t <= loop.time:
            return
        offset = self.setpoint_offset  # PCIx BC on a servo axis
        if self.motion is Motion.IDLE and self.traj.end_time <= loop.time:
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
            return max(loop.time, self.board.now)  # found by a query's look at the loop
        if not loop.closed:
            return None
        if self.motion is Motion.IDLE:
            # still since the last look (at rest, or held off its set point by KO against KU),
            # and nothing changed since (gains, HN): nothing will change
            last = self.servo_last
            if last is not None and abs(loop.position - last) < 1e-6 and abs(loop.velocity) < 1e-3:
                return None
        return loop.time + SERVO_CHECK

    def counter(self, t: float) -> int:
        """The position register: whole steps emitted so far."""
        x = self.traj.position(t)
        return math.floor(x + 0.5) if self.motion is Motion.IDLE else _steps(x, self.traj.x0)

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
        emitted, in the frame the stop point is taken in (:meth:`settle`, :meth:`halt`). A
        carriage stopped by a switch is therefore on the switch, whatever fraction of a step
        the counter and the carriage are apart after HM, LP, ER or BC."""
        if self.stall_phys is not None:
            return self.stall_phys
        x = self.traj.position(t)
        if self.motion is not Motion.IDLE:
            x = float(_steps(x, self.traj.x0))
        return x + self.phys_offset

    @property
    def moving(self) -> bool:
        return self.motion is not Motion.IDLE

    def load_counter(self, t: float, value: float) -> None:
        """Set the position register to ``value`` at ``t`` without moving the carriage."""
        self.servo_sync(t)
        x = self.traj.position(t)
        self.phys_offset += x - value
        self.traj = _rebased(self.traj, t, value - x)
        self.invalidate()

    # -- encoder ------------------------------------------------------------------------------

    def encoder(self, t: float) -> int:
        if self.servo is not None:
            self.servo_sync(t)
            return self.servo.encoder_counts
        return math.floor(self.enc_base + self.ratio * (self.phys(t) - self.enc_phys) + 0.5)

    def anchor_encoder(self, t: float, value: float | None = None) -> None:
        """Re-anchor the encoder model at ``t`` (LP loads ``value``; ER keeps the count)."""
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

    def slip_error(self, t: float) -> float:
        expected = self.track_enc + self.ratio * (self.position(t) - self.track_counter)
        return self.encoder(t) - expected

    def to_motor(self, value: float) -> float:
        """User counts (encoder counts on an encoder axis) to motor steps (PC48 §6.15 ER)."""
        return value / self.ratio if self.has_encoder else value

    # -- switches -----------------------------------------------------------------------------

    def limit_active(self, direction: int, t: float) -> bool:
        if self.travel_limits is not None:  # PCIx TL: "flag a limit condition just as it would"
            from omsd.board.pcix_motion import beyond_travel_limit

            if beyond_travel_limit(self, direction, t):
                return True
        forced = self.board.world.forced_limit(self.index, direction)
        if forced is not None:
            hit = forced
        else:
            p = self.carriage(t)
            w = self.world
            hit = p >= w.positive_limit if direction > 0 else p <= w.negative_limit
        wiring = self.world.limit_switches
        if wiring is LimitWiring.MATCHED:
            return hit
        # the line's level: a normally open switch grounds it when hit, a normally closed one
        # until hit; LL (the power-up default) takes low as true, PCIx LH high
        low = hit if wiring is LimitWiring.NORMALLY_OPEN else not hit
        return (not low) if self.limit_high else low

    def home_switch_activated(self, t: float) -> bool:
        forced = self.board.world.forced_home.get(self.index)
        if forced is not None:
            return forced
        return self.world.home_low <= self.carriage(t) < self.world.home_high

    def home_line_low(self, t: float) -> bool:
        activated = self.home_switch_activated(t)
        if self.world.home_switch is SwitchType.NORMALLY_OPEN:
            return activated
        return not activated

    def home_sensed(self, t: float) -> bool:
        """The home input after the HH/HL sense: what RA reports as ``H``."""
        return self.home_line_low(t) != self.home_high

    def encoder_home(self, t: float) -> bool:
        """HE mode (PC48 §6.18): index AND quadrant AND the low-true home enable."""
        if not self.home_line_low(t):
            return False
        cpr = self.world.encoder_counts_per_rev
        return cpr > 0 and (self.encoder(t) - self.world.encoder_index) % cpr == 0

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

    # -- motion -------------------------------------------------------------------------------

    def invalidate(self) -> None:
        self._cache = None

    def begin(
        self, t: float, pieces: list[pf.Piece], motion: Motion, final: float | None = None
    ) -> None:
        """Start new motion on tick ``t`` from wherever the axis is then (position and
        velocity). Until ``t`` the axis goes on as it was: asking for the position between now
        and the tick must not show the future."""
        if self.gear is not None:  # PCIx EG: a geared axis moves only as its master does
            return
        self.source = self.board.talker
        now = min(self.board.now, t)
        self.servo_sync(now)
        prefix = _segment(self.traj, now, t) if t > now else []
        moving_before = any(p.v(0.0) != 0.0 or p.a(0.0) != 0.0 for p in prefix)
        x_now = self.traj.position(now)
        if not pieces and not moving_before:
            x = self.traj.position(t)
            self.traj = Trajectory.at_rest(now, x if final is None else final)
            self.motion = Motion.IDLE
        else:
            if not moving_before:
                prefix = [pf.cruise(0.0, t - now)] if t > now else []
            self.traj = Trajectory(now, x_now, [*prefix, *pieces], final)
            self.motion = motion
            if motion is not Motion.HOLD:
                self.in_position = False
        self.sensor_check = t
        self.invalidate()
        self._moved(now, t, motion)

    def _moved(self, now: float, start: float | None = None, motion: Motion | None = None) -> None:
        """The trajectory was replaced at ``now``: PCIx gearing and NV (omsd.board.pcix_motion)."""
        if self.board.model.dialect == "pcix":
            from omsd.board.pcix_motion import moved

            moved(self, now, start, motion)

    def _note_direction(self, t: float) -> None:
        """Remember the direction the axis was last moving in (RA/QA character 4)."""
        v = self.traj.velocity(t)
        if v == 0.0 and self.traj.pieces:
            v = self.traj.velocity(min(t, self.traj.end_time) - 1e-7)
        if v:
            self.direction = 1 if v > 0 else -1

    def heading(self, t: float) -> int:
        """RA/QA character 4: "Moving in positive direction" / "negative direction"; at rest,
        the direction it last moved in (or was set to by MP/MM)."""
        v = self.traj.velocity(t)
        if v > 0:
            return 1
        if v < 0:
            return -1
        return self.direction

    def settle(self, t: float) -> None:
        """Come to rest on the whole step the counter shows (end of motion)."""
        self.servo_sync(t)
        self._note_direction(t)
        x = self.traj.position(t)
        self.traj = Trajectory.at_rest(t, float(_steps(x, self.traj.x0)))
        self.motion = Motion.IDLE
        self.invalidate()
        self._moved(t)

    def halt(self, t: float) -> None:
        """Stop pulses at once (KL, hard limit, KM/KR at home)."""
        self.servo_sync(t)
        self._note_direction(t)
        x = self.traj.position(t)
        self.traj = Trajectory.at_rest(t, float(_steps(x, self.traj.x0)))
        self.motion = Motion.IDLE
        self.home = None
        self.invalidate()
        self._moved(t)

    def decelerate(self, t: float, motion: Motion = Motion.STOP) -> None:
        """Ramp down to rest at AC (ST, SA, soft limit, after home)."""
        v = self.traj.velocity(t)
        if v == 0.0:
            self.halt(t)
            return
        self.begin(t, pf.velocity_change(v, 0.0, self.ac), motion)

    def end_tick(self) -> float | None:
        if self.motion is Motion.IDLE or not self.traj.is_finite:
            return None
        return self.board.clock.at_or_after(self.traj.end_time)

    # -- what happens next --------------------------------------------------------------------

    def next_event_time(self) -> float | None:
        if self._cache is None:
            self._cache = self._next_event()
        t = self._cache[0]
        return None if math.isinf(t) else t

    def _next_event(self) -> tuple[float, str]:
        best = (math.inf, "")
        candidates: list[tuple[float | None, str]] = [
            (self.end_tick(), "end"),
            (self.sensor_check, "sensor"),
            (self.in_fire, "in"),
            (self.aux_timer, "aux"),
            (self.outputs[0][0] if self.outputs else None, "output"),
            (self.servo_check_time(), "servo"),
        ]
        if self.wait is not None and self.wait.until is not None:
            candidates.append((self.wait.until, "wait"))
        if self.motion is not Motion.IDLE and self.stall_phys is None:
            candidates.append((self._next_crossing(), "sensor"))
        if self.slip_detect and self.stall_phys is not None and self.motion is not Motion.IDLE:
            candidates.append((self._slip_crossing(), "sensor"))
        if self.backlash and self.motion is not Motion.IDLE:  # PCIx BC: a direction change
            from omsd.board.pcix_motion import backlash_tick

            candidates.append((backlash_tick(self), "sensor"))
        for when, what in candidates:
            if when is not None and when < best[0]:
                best = (when, what)
        return best

    def _levels(self, t: float) -> list[tuple[float, bool]]:
        """Counter-frame positions whose crossing the board must notice, with the side that
        counts (``True``: reaching at or above the level). Switches are seen through
        :meth:`carriage` (whole steps): a switch at physical ``s`` closes on the first whole
        step at or beyond it, which the continuous position reaches at ``step -+ STEP_EPS``."""
        levels: list[tuple[float, bool]] = []
        w = self.world
        p = self.carriage(t)
        off = self.phys_offset
        if self.limits_on:
            if p < w.positive_limit:  # active from the first step at or above the switch
                levels.append(_step_at_or_above(w.positive_limit - off))
            if p > w.negative_limit:  # active from the first step at or below it
                levels.append(_step_at_or_below(w.negative_limit - off))
            if self.travel_limits is not None:  # PCIx TL
                from omsd.board.pcix_motion import travel_levels

                levels.extend((level - off, above) for level, above in travel_levels(self, t))
        if self.home is not None:
            if self.home.index_points:
                x = self.phys(t)
                for point in self.home.index_points:
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

    def _first_tick(self, level_counter: float, above: bool, t_from: float) -> float | None:
        clock = self.board.clock
        when = self.traj.first_time(level_counter, above, t_from)
        while when is not None and math.isfinite(when):
            tick = clock.at_or_after(when)
            if tick <= t_from:
                tick = clock.after(t_from)
            x = self.traj.position(tick)
            if (x >= level_counter) if above else (x <= level_counter):
                return tick
            nxt = self.traj.first_time(level_counter, above, tick)
            if nxt is None or not math.isfinite(nxt) or nxt <= when:
                return None if nxt is None else clock.after(tick)
            when = nxt
        return None

    def _next_crossing(self) -> float | None:
        t = self.board.now
        best: float | None = None
        for level, above in self._levels(t):
            tick = self._first_tick(level, above, t)
            if tick is not None and (best is None or tick < best):
                best = tick
        return best

    def _slip_crossing(self) -> float | None:
        t = self.board.now
        stall_enc = float(self.encoder(t))
        best: float | None = None
        for sign in (1, -1):
            # slip_error = stall_enc - track_enc - ratio (x - track_counter) crosses -/+ ES
            level = self.track_counter + (stall_enc - self.track_enc + sign * self.es) / self.ratio
            tick = self._first_tick(level + sign * 1e-6, sign > 0, t)
            if tick is not None and (best is None or tick < best):
                best = tick
        return best

    def due(self) -> str:
        if self._cache is None:
            self._cache = self._next_event()
        return self._cache[1]


#: How close the continuous position must come to a whole step for :func:`_steps` to count it
#: (half its own tolerance, so that a position found at the level is counted whichever way
#: the motion goes).
STEP_EPS = 5e-7


def _step_at_or_above(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first reaches ``level`` going up."""
    return (math.ceil(level - 1e-9) - STEP_EPS, True)


def _step_at_or_below(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first reaches ``level`` going down."""
    return (math.floor(level + 1e-9) + STEP_EPS, False)


def _step_below(level: float) -> tuple[float, bool]:
    """The crossing at which the whole-step position first goes below ``level`` going down."""
    return (math.ceil(level - 1e-9) - 1 + STEP_EPS, False)


def _steps(x: float, origin: float) -> int:
    """The position counter at ``x`` on the way from ``origin``: pulses are counted as whole
    steps in the direction of travel, never rounded ahead."""
    eps = 1e-6
    return math.floor(x + eps) if x >= origin else math.ceil(x - eps)


def _segment(traj: Trajectory, a: float, b: float) -> list[pf.Piece]:
    """The motion of ``traj`` from ``a`` to ``b`` as pieces (rest included)."""
    out: list[pf.Piece] = []
    span = b - a
    acc = 0.0
    rel = a - traj.t0
    start = 0.0
    for piece in traj.pieces:
        end = start + piece.duration
        if end <= rel:
            start = end
            continue
        cut = max(0.0, rel - start)
        tail = _tail(piece, cut)
        length = min(tail.duration, span - acc)
        out.append(replace(tail, duration=length))  # type: ignore[type-var]
        acc += length
        start = end
        if acc >= span:
            return out
    if acc < span:
        out.append(pf.cruise(0.0, span - acc))
    return out


def _rebased(traj: Trajectory, t: float, shift: float) -> Trajectory:
    """The same motion continued from ``t`` with every position shifted by ``shift``."""
    rel = t - traj.t0
    pieces: list[pf.Piece] = []
    acc = 0.0
    for piece in traj.pieces:
        if acc + piece.duration <= rel:
            acc += piece.duration
            continue
        cut = max(0.0, rel - acc)
        pieces.append(_tail(piece, cut))
        acc += piece.duration
    final = traj.final + shift if math.isfinite(traj.final) else None
    return Trajectory(t, traj.position(t) + shift, pieces, final)


def _tail(piece: pf.Piece, cut: float) -> pf.Piece:
    """The part of ``piece`` after ``cut``, as a piece of its own."""
    if cut == 0.0:
        return piece
    rest = piece.duration - cut
    if isinstance(piece, pf.Poly):
        return pf.Poly(piece.v(cut), piece.a(cut), piece.j, rest)
    if isinstance(piece, pf.Cosine):
        return _Shifted(piece, cut, rest)
    if isinstance(piece, pf.Decay):
        return pf.Decay(piece.e0 * math.exp(-piece.k * cut), piece.k, rest)
    if isinstance(piece, pf.Sinusoid):
        return pf.Sinusoid(piece.r, piece.phase0 + piece.omega * cut, piece.omega, rest)
    return _Shifted(piece, cut, rest)


@dataclass(frozen=True, slots=True)
class _Shifted:
    """A piece observed from ``cut`` onwards."""

    inner: pf.Piece
    cut: float
    duration: float

    def x(self, tau: float) -> float:
        return self.inner.x(self.cut + tau) - self.inner.x(self.cut)

    def v(self, tau: float) -> float:
        return self.inner.v(self.cut + tau)

    def a(self, tau: float) -> float:
        return self.inner.a(self.cut + tau)

    def turning_points(self) -> list[float]:
        return [tp - self.cut for tp in self.inner.turning_points() if tp > self.cut]
