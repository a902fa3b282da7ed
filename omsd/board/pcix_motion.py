"""PCIx motion commands the older boards do not have (PCIx manual §5.9, §5.12, §5.7.5, §5.5.4).

:data:`MOTION_HANDLERS` are the interpreter's handlers (as in :mod:`omsd.board.commands`),
:data:`MOTION_OPS` the executor's functions for the queued op codes they introduce. The pieces
of the board these commands reach into (an axis starting or ending motion, a sensor look, the
queue being flushed) call the hooks at the end of this module.

Electronic gearing (§5.12.5 EG, EGF, EG?; §5.7.3 TX)
    "the current axis (geared axis) is to track the master axis velocity such that the current
    axis velocity = Ratio X Master Axis velocity", whatever the master is doing (a move, a jog, a
    contour, a home search, a stop). Whenever the master's trajectory changes (it begins new
    motion, comes to rest or is killed) the geared axis takes the master's motion from that
    instant on, scaled by the ratio, from where it is: its velocity is the ratio times the
    master's at every instant. The geared axis keeps an exact record of where the ratio puts it
    (:class:`Gear`), so fractional ratios do not drift: a move of 1001 counts at EGX1,2 ends on
    500 or 501 and the next one makes up the half count.

    * "Once a gearing engagement command is issued the geared axis will only respond to immediate
      commands until the gearing is cancelled." Chosen reading: a geared axis moves only as its
      master does. Commands queued for it still run in their turn (parameters such as VL or AC
      change, done flags are set), but none of them moves it: a GO, JG, HM, TM ... addressed to a
      geared axis starts nothing. Holding its queue instead would make every AA command that
      puts entries in all queues (GO, WT, CX, ...) wait for the gearing to end, hanging the
      other axes; rejecting the commands would leave an EG that is still queued (it is queued:
      "EG#,#,#, AX – AT 2", and engages when the queue reaches it) with commands after it that
      were accepted. TX is immediate.
    * Cancelled by "The EGF command ... or over-travel on the geared axis", and "the following
      commands FL, KL, KS, SA, SD or SI flush the axis queue and will also cancel electronic
      gearing": every flush of the geared axis's queue cancels it (so ST and FP do too). When the
      gearing is cancelled the axis finishes the motion it was given last (FL: "current motion
      will remain unaffected"): a copy of a master's move ends where it would have; a copy of a
      master's jog goes on as a jog until it is stopped. The stop commands that flush then stop
      it as they stop any axis.
    * "the current axis cannot be geared to itself or to an axis that has been geared to a master
      axis": the command error "Axis is geared". A master may itself be geared later (the
      manual does not forbid it); its geared axes then follow it through.
    * "(Gear Ratio *X the Master Axis' VL value) is at least 1 and less than ... 1,048,574":
      checked against the master's VL when the command is received.
    * EG? answers ``=eg`` and the engagement as it was entered, lower case (``=egx1,2`` for
      ``EGX1,2``, ``=egy-2,1``, ``=egx`` for ``EGX``), or ``=egf``. TX is reported the same way,
      as the gearing to X it is (``TX0.5`` -> ``=egx0.5``): the manual names no reply for it.
    * TX: "Set up the current axis so that it tracks the X axis. The command argument is the
      tracking ratio specified as a floating point." Without an argument the ratio is 1 (the
      manual's example is ``TX;``). "The command is invalid for the X axis."

Backlash compensation (§5.12.2 - §5.12.4 BC)
    * Stepper: "additional motor steps ... are generated, whenever a move command causes the
      motor to reverse direction ... output to the motor during the first motor update cycle
      following a direction change. This permits the compensation to be used with constant
      velocity contours." On the first sample tick at which the axis moves in the other
      direction (the start of a move, a jog reversing, an arc turning back), the carriage (the
      physical position the switches and encoder see) jumps ``BC`` steps in the new direction;
      the position counter does not count them. The board knows it sent them: slip detection
      and position maintenance do not take them for slip.
    * Servo: "offsetting the motor's position "set point" from the commanded position ...
      occurs in the direction of the sign": from the first update after the axis starts moving
      in the direction of BC's sign the set point is ``BC`` counts beyond the commanded position;
      after it reverses again, none. The manual's example comes out: homed positive, BC-10,
      MA1000 GO ends with RP and RE 1000; MA-1000 GO ends with RP -1000 and RE -1010.
    * The direction the backlash is taken up in starts as the direction the axis last moved in
      when BC is set (at power-up: positive, the direction RA reports). ``BC0;`` "negates the
      backlash compensation" (a servo's set point returns to the commanded position).
    * Queue: the BC page says Immediate, the §5.12.3 table 1 unit: whichever the command table
      says (:mod:`omsd.models.pcix`) is done.

Moves and stops
    * GU (§5.9.3): "initiates a previously defined move using the AC value for acceleration and
      the DC value for deceleration"; "GU is used only with linear acceleration ramps": the
      profile is linear whatever the axis's ramp selection (and VB, which "will not work in
      conjunction with the DC command", is not used). A move too short to reach VL is
      triangular, peaking where the two ramps meet.
    * DC (§5.8.2) is set by :mod:`omsd.board.pcix_commands` ("defaults to 200,000 and will take
      on whatever value is entered via the AC command").
    * GN: GO, then "set the axis done flags when the move is complete" (with the interrupt, as
      ID). In AA mode each axis's flag is set as it finishes and DON_S once all have, as AA ID
      does.
    * GS: GO with the home switch monitored: "If the home switch becomes active the slip flag will
      be set for the axis". Chosen: the slip flag is what slip detection sets (the axis's slip
      flag, status ENC_S with DON_S and its interrupt), raised each time the switch becomes
      active during the move. (RL cannot show it: "Open-loop stepper always returns “n”", and GS
      is for open-loop steppers only.)
    * SO#,# (§5.9.4): "continue moving until reaching a specified distance (parameter 2) from a
      specified stop point (parameter 1). The axis will then ramp to a stop within the specified
      distance": the deceleration is whatever stops it exactly there. If the axis is already
      inside that distance it starts ramping at once, at the rate that stops it on the point;
      if it is already past the point it stops as soon as possible at AC (as SP does); if its
      present motion ends before the deceleration point, SO changes nothing. A negative distance
      is taken as its size. SO "cancels" stepper position maintenance (the HN page).
    * TM (§5.9.1): "performs a jog at the current velocity limits defined for the axis ... for the
      specified number of milliseconds ... The overall jog time will be the parameter passed to
      the TM command plus deceleration time and acceleration time": ramp at AC to VL, run for
      the time, ramp down at AC. The manual gives no sign: the jog runs in the axis's direction
      (the one MP/MM set, or the last move's), as the other undirected motions (MO, MV) do. In AA
      mode "all axes begin moving at the same time". The queue waits for the jog to end. TM
      disables slip detection (the IS page).
    * SI (§5.9.4): single axis "behaves identically to ST"; multi-axis "Any non-zero value in a
      parameter will cause the corresponding axis to be stopped" (flush, ramp down at AC).
    * KS: "the same operation as the KL (kill) command except that individual axes can be killed
      ... KS will flush only the selected axes' command queues"; "null values in the argument
      list specify that motion on that axis is not to be killed" (so ``AA KS;`` kills nothing).
    * FL (§5.4.4): "All unexecuted commands remaining in the current axis queue will be flushed
      ... current motion will remain unaffected" (an IN armed for the running move stays armed).

Limits, positions, contours
    * TL upper,lower (§5.5.4): "If the axis reaches either of these logical limits, the PCIX will
      flag a limit condition just as it would be using the physical limit switch inputs. Move
      Absolute (MA), Move Relative (MR), and Jog (JF, JG) commands are subject". The ?TL page says
      "If one of these limits is exceeded": a position *beyond* a limit is overtravel (a move to
      the limit itself is allowed). It acts as a limit switch does: LN/LF enable it, RA shows
      ``L`` while the position is beyond it, the axis stops (SF) or ramps down (SL) and its queue
      is flushed, the limit event is raised. Point-to-point moves (GO, GD, GN, GU) and jogs
      (JG, JF, TM) are checked, other motion (homing, contours, stair-casing, gearing) is not.
      ``TL0,0;`` switches them off; a lower limit above the upper one is a range error. The range
      is the position range (the page prints 33,544,431, the LP page 33,554,431, a digit slip).
      ?TL answers ``tl<upper>,<lower>`` in counts (the manual's ``t!101000,-1000`` is an OCR
      garble of ``tl``); when they are off it answers ``tl0,0;`` as printed (E195 ``t!0,0;``,
      with the semicolon the other reply lacks: the command that turns them off).
    * LO (§5.7.5): "sets the motor position independently of the encoder position": the position
      counter is loaded, the encoder is left alone (and slip detection re-anchored, so the new
      difference is not slip). On a servo the counter is the commanded position, so a closed
      loop drives the motor to it, which is what loading a servo's command register does.
    * CG (§5.9.8): CX, but "the following MT commands will be on hold until the contour execution
      is complete": an MT received after CG waits (holding the interpreter, like a full queue)
      until every axis has finished the contour (this module's MT handler wraps the PCIx one to
      do it). CG cancels stepper position maintenance on the contour's axes (the HN page: "CG,
      CX").
    * NV (§5.9.8, "AA/CD Immediate"): "set a new velocity for a contour currently in execution
      ... the PCIX will switch to the new velocity at the start of the next command in the
      contour queue without ramping. An NV command issued without a contour currently executing
      will have no effect." The segments after the one being run go at the new speed (the
      final CE ramp down starts from it, at the same deceleration), and the contour's AN/AF/BH/BL
      actions move with them.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass
from decimal import Decimal
from typing import TYPE_CHECKING

from omsd.board import profiles as pf
from omsd.board.axis import Axis, HomeSearch, Motion, Wait
from omsd.board.commands import HANDLERS, Handler, registrar, run_contour, runnable_contour
from omsd.board.events import SlipEvent
from omsd.board.interpreter import Blocked, CommandFailed, Interpreter
from omsd.board.queue import Op, SyncGroup
from omsd.board.registers import DON_S, ENC_S
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import parse_number, truncate

if TYPE_CHECKING:
    from omsd.board.board import Board
    from omsd.board.executor import Executor

Result = Wait | int | None
OpFunction = Callable[["Executor", Axis, Op, float], Result]

MOTION_HANDLERS: dict[str, Handler] = {}
MOTION_OPS: dict[str, OpFunction] = {}


_handles = registrar(MOTION_HANDLERS)


def _op(code: str) -> Callable[[OpFunction], OpFunction]:
    def register(fn: OpFunction) -> OpFunction:
        MOTION_OPS[code] = fn
        return fn

    return register


# -- pieces of other trajectories ----------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class _Window:
    """``inner`` seen from ``cut`` on for ``duration`` seconds, every displacement times ``k``:
    the part of another axis's motion this axis copies (gearing, k = ratio) or keeps (SO, k = 1).
    """

    inner: pf.Piece
    k: float
    cut: float
    duration: float
    x_cut: float

    def x(self, tau: float) -> float:
        return self.k * (self.inner.x(self.cut + tau) - self.x_cut)

    def v(self, tau: float) -> float:
        return self.k * self.inner.v(self.cut + tau)

    def a(self, tau: float) -> float:
        return self.k * self.inner.a(self.cut + tau)

    def turning_points(self) -> list[float]:
        end = self.cut + self.duration
        return [tp - self.cut for tp in self.inner.turning_points() if self.cut < tp < end]


def _window(piece: pf.Piece, k: float, cut: float, duration: float) -> pf.Piece:
    if k == 1.0 and cut == 0.0 and duration == piece.duration:
        return piece
    return _Window(piece, k, cut, duration, piece.x(cut))


def _pieces_between(traj: pf.Trajectory, a: float, b: float, k: float = 1.0) -> list[pf.Piece]:
    """The motion of ``traj`` from time ``a`` to ``b`` (``b`` may be infinite), scaled by ``k``;
    nothing for the time it is at rest after its end."""
    out: list[pf.Piece] = []
    start = traj.t0
    for piece in traj.pieces:
        end = start + piece.duration
        lo, hi = max(a, start), min(b, end)
        if hi > lo:
            out.append(_window(piece, k, lo - start, hi - lo))
        start = end
        if start >= b:
            break
    return out


def _sign(v: float) -> int:
    return 1 if v > 0 else -1 if v < 0 else 0


# -- electronic gearing -------------------------------------------------------------------------


@dataclass
class Gear:
    """An axis geared to ``master`` (an axis index) at ``ratio`` geared counts per master count.

    ``base`` is where the ratio put this axis at ``path.t0``, ``path`` the scaled copy of the
    master's motion since then (starting from 0): the exact position the gearing asks for at
    any time is ``base + path.position(t)``, whatever the counter has been rounded to.
    """

    master: int
    ratio: float
    text: str  # the engagement as entered, for EG?: "x1,2"
    base: float = 0.0
    path: pf.Trajectory | None = None

    def ideal(self, t: float) -> float:
        return self.base + (self.path.position(t) if self.path is not None else 0.0)


def _check_ratio(ix: Interpreter, mnemonic: str, ratio: float, master: Axis) -> None:
    """EG (and TX, its row): "(Gear Ratio *X the Master Axis' VL value) is at least 1 and less
    than the maximum controller step rate of 1,048,574 steps per second"."""
    ix.check(mnemonic, abs(ratio) * master.vl)


def _gearable(slave: Axis, master: Axis) -> bool:
    return master is not slave and master.gear is None


def engage(slave: Axis, master: Axis, ratio: float, text: str, t: float) -> None:
    """Gear ``slave`` to ``master`` from ``t`` on: it takes up the master's present motion."""
    slave.gear = Gear(master.index, ratio, text, base=slave.position(t))
    follow(slave, master, t)


def disengage(slave: Axis, t: float) -> None:
    """EGF and the flushes: the axis keeps the motion it was last given (see the module doc)."""
    if slave.gear is None:
        return
    slave.gear = None
    if slave.motion is Motion.GEAR:
        slave.motion = Motion.MOVE if slave.traj.is_finite else Motion.JOG
    slave.invalidate()


def follow(slave: Axis, master: Axis, now: float) -> None:
    """The master's motion changed at ``now``: the geared axis takes its scaled copy."""
    gear = slave.gear
    assert gear is not None
    board = slave.board
    slave.servo_sync(now)
    ideal = gear.ideal(now)
    x = slave.position(now)
    v_before = slave.velocity(now)
    if v_before:
        slave.direction = _sign(v_before)
    pieces = _pieces_between(master.traj, now, math.inf, gear.ratio)
    path = pf.Trajectory(now, 0.0, pieces)
    gear.base, gear.path = ideal, path
    if not pieces:
        slave.traj = pf.Trajectory.at_rest(now, float(math.floor(ideal + 0.5)))
        slave.motion = Motion.IDLE
    else:
        final: float | None = None
        if master.traj.is_finite:
            travel = master.traj.final - master.traj.position(now)
            final = float(math.floor(ideal + gear.ratio * travel + 0.5))
        slave.traj = pf.Trajectory(now, x, pieces, final)
        slave.motion = Motion.GEAR
        slave.in_position = False
        slave.home = None
    slave.sensor_check = board.clock.at_or_after(now)
    slave.invalidate()
    moved(slave, now, None, None)


def _gear_text(letter: str, geared: str, master_count: str | None) -> str:
    text = letter.lower() + geared
    return text if master_count is None else f"{text},{master_count}"


@_handles("EG")
def _eg(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """EG<Master Axis>[<Geared axis count>][,<Master axis count>] (§5.12.5): "EGX; ... ratio of 1
    to 1", "EGX2; ... 2 to 1", "EGX1,2; ... 1 to 2"; "Negative ratio values indicate that the
    current axis is to track the master axis in the opposite direction"."""
    slave = ix.axis
    fields = cmd.fields or ()
    if not fields or not fields[0]:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    if len(fields) > 2:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    first = fields[0]
    master = ix.board.axis_by_letter(first[0].upper())
    if master is None or not first[0].isalpha():
        raise CommandFailed(ErrorKind.NO_SUCH_AXIS)
    if not _gearable(slave, master):
        raise CommandFailed(ErrorKind.GEARED)
    geared_text = first[1:]
    geared = parse_number(geared_text) if geared_text else Decimal(1)
    master_text = fields[1] if len(fields) == 2 else None
    if len(fields) == 2 and master_text is None:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    count = parse_number(master_text) if master_text is not None else Decimal(1)
    if count == 0 or geared == 0:
        raise CommandFailed(ErrorKind.OUT_OF_RANGE)
    ratio = float(geared / count)
    _check_ratio(ix, "EG", ratio, master)
    text = _gear_text(master.letter, geared_text, master_text)
    ix.enqueue([(slave, Op("EG", (master.index, ratio, text, cmd.text), ix.cost(cell, slave)))])


@_op("EG")
def _op_eg(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    master_index, ratio, text, command = op.args
    master = ex.board.axes[master_index]
    if not _gearable(axis, master):
        # the master was geared to another axis after EG was received
        ex.board.command_error(ErrorKind.GEARED, command, t)
        return None
    engage(axis, master, ratio, text, t)
    return None


@_handles("TX")
def _tx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TX[#] (§5.7.3): track the X axis at a floating point ratio (default 1); "If this is a
    negative, then the axis moves in the opposite direction of the X axis. The command is invalid
    for the X axis." Immediate ("TX; AY – AT Immediate")."""
    slave = ix.axis
    master = ix.board.axis_by_letter("X")
    if master is None or master is slave:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    raw = ix.one(cmd, required=False)
    ratio = 1.0 if raw is None else float(raw)
    if not _gearable(slave, master):
        raise CommandFailed(ErrorKind.GEARED)
    if ratio == 0.0:
        raise CommandFailed(ErrorKind.OUT_OF_RANGE)
    _check_ratio(ix, "TX", ratio, master)
    field = (cmd.fields or (None,))[0]
    engage(slave, master, ratio, _gear_text("X", field or "", None), t)


@_handles("EGF")
def _egf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """EGF (§5.12.5): "turns off electronic gearing for the current axis"."""
    disengage(ix.axis, t)


@_handles("EG?")
def _eg_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """EG? (§5.12.5): ``=egx1,2`` "(Y axis is geared to the X with a gear ratio of 1:2)", ``=egf``
    "(Z axis is either not geared to another axis or it is the master axis ...)"."""
    gear = ix.axis.gear
    ix.board.reply_value("=egf" if gear is None else f"=eg{gear.text}", t)


# -- backlash -------------------------------------------------------------------------------------


def _compensation(backlash: int, direction: int) -> float:
    """The offset BC asks for while moving in ``direction``: BC's own sign, or none."""
    return float(backlash) if direction * backlash > 0 else 0.0


def set_backlash(axis: Axis, value: int, t: float) -> None:
    axis.backlash = value
    if value == 0:
        axis.backlash_dir = None
        if axis.servo is not None and axis.setpoint_offset:
            axis.servo_sync(t)
            axis.setpoint_offset = 0.0
    elif axis.backlash_dir is None:
        axis.backlash_dir = axis.heading(t)
    axis.invalidate()


@_handles("BC")
def _bc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """BC# (§5.12): "between 0 and 50 for stepper motors and between -50 and +50 for servo
    motors"."""
    axis = ix.axis
    raw = ix.one(cmd, required=False)
    value = 0 if raw is None else truncate(raw)  # the BC page's format is "BC;"
    ix.check("BC", value, variant="servo" if axis.is_servo else "stepper")
    if cell.kind is Kind.IMMEDIATE:
        set_backlash(axis, value, t)
        return

    def apply(a: Axis, when: float) -> None:
        set_backlash(a, value, when)

    ix.enqueue([(axis, Op("SET", ("BC", apply), ix.cost(cell, axis)))])


def _reversal(axis: Axis, t_from: float, direction: int) -> float | None:
    """The first sample tick at or after ``t_from`` at which the axis is moving against
    ``direction`` (a moment of reversal shorter than the gap to the next tick is never seen)."""
    traj = axis.traj
    clock = axis.board.clock
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


def backlash_tick(axis: Axis) -> float | None:
    """When the axis next takes up backlash (an event time for :meth:`Axis.next_event_time`)."""
    if not axis.backlash or axis.motion is Motion.IDLE:
        return None
    if axis.backlash_dir is None:
        axis.backlash_dir = axis.direction
    return _reversal(axis, axis.board.now, axis.backlash_dir)


def take_up_backlash(axis: Axis, t: float) -> None:
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


# -- parameters: TL, LO ----------------------------------------------------------------------


def _position(ix: Interpreter, axis: Axis, raw: Decimal, mnemonic: str, operand: int = 1) -> float:
    """A position in counts (user units applied) against its row (the position range)."""
    return ix.check(mnemonic, ix.convert(axis, raw, "dist"), operand)


def set_travel_limits(axis: Axis, upper: float, lower: float, t: float) -> None:
    axis.travel_limits = None if upper == 0 and lower == 0 else (lower, upper)
    axis.sensor_check = t
    axis.invalidate()


@_handles("TL")
def _tl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TL#,# (§5.5.4): "Two parameters must be supplied; one for the upper travel limit and the
    other for the lower travel limit, both as absolute positions"; "TL0,0; Turns software limits
    off"."""
    axis = ix.axis
    raw_upper, raw_lower = ix.required(cmd, 2)
    upper = _position(ix, axis, raw_upper, "TL", 1)
    lower = _position(ix, axis, raw_lower, "TL", 2)
    if lower >= upper and not (upper == 0 and lower == 0):
        raise CommandFailed(ErrorKind.OUT_OF_RANGE)

    def apply(a: Axis, when: float) -> None:
        set_travel_limits(a, upper, lower, when)

    ix.enqueue([(axis, Op("SET", ("TL", apply), ix.cost(cell, axis)))])


@_handles("?TL")
def _tl_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """?TL (§5.5.4): "The first value returned is the upper (or "positive") limit and the second
    value is the lower"."""
    limits = ix.axis.travel_limits
    if limits is None:
        ix.board.reply_value("tl0,0;", t)  # as printed for "soft limits ... disabled"
        return
    lower, upper = limits
    ix.board.reply_value(f"tl{math.trunc(upper)},{math.trunc(lower)}", t)


def beyond_travel_limit(axis: Axis, direction: int, t: float) -> bool:
    """TL overtravel in ``direction``, for the motions the soft limits apply to."""
    limits = axis.travel_limits
    if limits is None or axis.motion not in _TL_MOTIONS:
        return False
    lower, upper = limits
    position = axis.counter(t)
    return position > upper if direction > 0 else position < lower


#: "Move Absolute (MA), Move Relative (MR), and Jog (JF, JG) commands are subject to software
#: travel limits" (at rest and ramping to a stop, RA still reports the overtravel).
_TL_MOTIONS = (Motion.IDLE, Motion.STOP, Motion.MOVE, Motion.JOG)


def travel_levels(axis: Axis, t: float) -> list[tuple[float, bool]]:
    """Physical positions where a moving axis goes beyond its TL limits (for the sensor search):
    the counter shows ``upper + 1`` at ``upper + 1 - 1e-6`` on the way up."""
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


@_handles("LO")
def _lo(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """LO# / LO#,#,#,# (§5.7.5): "sets the motor position independently of the encoder position";
    "For AA and AM modes, any value missing in the argument list specifies that axis is not to be
    affected"."""
    items = ix.items(cmd)
    ops = []
    for index, raw_value in items.items():
        axis = ix.board.axes[index]
        value = _position(ix, axis, raw_value, "LO")

        def apply(a: Axis, when: float, value: float = value) -> None:
            a.load_counter(when, value)
            a.anchor_tracking(when)

        ops.append((axis, Op("SET", ("LO", apply), ix.cost(cell, axis))))
    ix.enqueue(ops)


# -- GU, GN, GS -----------------------------------------------------------------------------------


def asymmetric_move(distance: float, vmax: float, accel: float, decel: float) -> list[pf.Piece]:
    """A linear move over ``distance`` accelerating at ``accel`` and decelerating at ``decel``;
    triangular (peak where the ramps meet) when it cannot reach ``vmax``."""
    d = abs(distance)
    if d == 0.0 or vmax <= 0.0 or accel <= 0.0 or decel <= 0.0:
        return []
    peak = vmax
    if vmax * vmax / (2.0 * accel) + vmax * vmax / (2.0 * decel) > d:
        peak = math.sqrt(2.0 * d * accel * decel / (accel + decel))
    pieces: list[pf.Piece] = [pf.Poly(0.0, accel, 0.0, peak / accel)]
    rest = d - peak * peak / (2.0 * accel) - peak * peak / (2.0 * decel)
    if rest > 1e-9:
        pieces.append(pf.cruise(peak, rest / peak))
    pieces.append(pf.Poly(peak, -decel, 0.0, peak / decel))
    return [pf.scaled(p, 1.0 if distance > 0 else -1.0) for p in pieces]


def _single_go(ix: Interpreter, cmd: Command, cell: Cell, code: str) -> None:
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    axis = ix.axis
    ix.enqueue([(axis, Op(code, (), ix.cost(cell, axis)))])


@_handles("GU")
def _gu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GU (§5.9.3): "This command may be used with only one axis at a time"."""
    _single_go(ix, cmd, cell, "GU")


@_op("GU")
def _op_gu(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    pending = axis.pending
    if pending is None:  # "If this command is issued without having defined a move ..."
        return None
    axis.pending = None
    tick = ex.board.clock.at_or_after(t)
    here = axis.position(tick)
    value = axis.to_motor(pending.value)
    target = float(math.trunc(value)) if pending.kind == "abs" else here + math.trunc(value)
    distance = target - here
    if distance:
        axis.direction = 1 if distance > 0 else -1
    axis.begin(tick, asymmetric_move(distance, axis.vl, axis.ac, axis.dc), Motion.MOVE, target)
    axis.home = None
    if axis.motion is Motion.IDLE:
        return None
    if axis.pa is not None:
        axis.aux = axis.pa
        axis.aux_timer = None
    ex._arm_in(axis, target)
    return Wait("motion")


def _go_members(ix: Interpreter) -> list[int]:
    if ix.mode == "AM" and ix.last_move:
        return list(ix.last_move)
    return list(range(len(ix.board.axes)))


@_handles("GN")
def _gn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GN (§5.9.3): "initiate a move ... and set the axis done flags when the move is complete".
    Queued as the GO it is, followed by the done flag (no slots of its own)."""
    board = ix.board
    if ix.mode == "single":
        axis = ix.axis
        ix.enqueue([(axis, Op("GO", (), ix.cost(cell, axis))), (axis, Op("GN", (), 0))])
        return
    members = _go_members(ix)
    go = SyncGroup(set(members))
    go.action = board.executor.go_action
    go.data["gd"] = False
    done = SyncGroup(set(members), barrier=False)
    done.action = lambda g, when: board.signal_done(when)
    items: list[tuple[Axis, Op]] = []
    for index in members:
        axis = board.axes[index]
        items.append((axis, Op("GO", (), ix.cost(cell, axis), go)))
        items.append((axis, Op("GN", (), 0, done)))
    ix.enqueue(items)


@_op("GN")
def _op_gn(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is None:
        ex.board.set_done([axis], t, interrupt=True)
        return None
    ex.board.set_done([axis], t, interrupt=False)
    return ex.arrive(axis, op, t)


@_handles("GS")
def _gs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GS (§5.9.3): "works exactly like the GO command except that the home switch will be
    monitored during the motion"."""
    _single_go(ix, cmd, cell, "GS")


@dataclass
class SlipWatch(HomeSearch):
    """GS: the home switch watched during a move (not a home search: nothing stops or loads)."""


@_op("GS")
def _op_gs(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.start_pending([axis], t)
    if not axis.moving:
        return None
    tick = ex.board.clock.at_or_after(t)
    watch = SlipWatch(
        position=0.0, kill=False, direction=axis.direction, prev=axis.home_sensed(tick)
    )
    axis.home = watch
    axis.home_last_phys = axis.phys(tick)
    axis.invalidate()

    def done(when: float) -> None:
        if axis.home is watch:
            axis.home = None
            axis.invalidate()

    return Wait("motion", then=done)


def _watch_home(axis: Axis, watch: SlipWatch, t: float) -> None:
    active = axis.home_sensed(t)
    if active and not watch.prev:
        axis.slipped = True
        board = axis.board
        board.registers.status |= ENC_S | DON_S
        board.emit(SlipEvent(t, axis.letter))
    watch.prev = active


# -- SO, TM ---------------------------------------------------------------------------------------


@_handles("SO")
def _so(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """SO#,# (§5.9.4): stop position, and the distance from it at which to start decelerating;
    both "-33,554,431 ... 33,554,431"."""
    axis = ix.axis
    raw_stop, raw_distance = ix.required(cmd, 2)
    stop = _position(ix, axis, raw_stop, "SO", 1)
    distance = _position(ix, axis, raw_distance, "SO", 2)
    ix.enqueue([(axis, Op("SO", (stop, distance), ix.cost(cell, axis)))])


@_op("SO")
def _op_so(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    stop = float(math.trunc(axis.to_motor(op.args[0])))
    distance = abs(axis.to_motor(op.args[1]))
    tick = ex.board.clock.at_or_after(t)
    v0 = axis.velocity(tick)
    if v0 == 0.0:
        return None
    if not axis.is_servo:
        axis.hold = False  # HN: cancelled by ... SO
        axis.in_position = True
    s = _sign(v0)
    motion = axis.motion
    x = axis.position(tick)
    traj = axis.traj
    begin_at = stop - s * distance
    keep: list[pf.Piece] = []
    speed = v0
    remaining = (stop - x) * s
    if (begin_at - x) * s > 0:
        when = traj.first_time(begin_at, s > 0, tick)
        if when is None or traj.velocity(when) * s <= 0:
            return Wait("motion")  # the present motion ends before the deceleration point
        keep = _pieces_between(traj, tick, when)
        speed = traj.velocity(when)
        remaining = distance
    elif remaining < 0:
        # already past the stop point: stop as soon as possible at AC, as SP does
        axis.begin(tick, pf.velocity_change(v0, 0.0, axis.ac), Motion.STOP)
        return Wait("motion") if axis.moving else None
    pieces = list(keep)
    if remaining > 0:
        decel = speed * speed / (2.0 * remaining)
        pieces.append(pf.Poly(speed, -s * decel, 0.0, abs(speed) / decel))
    axis.begin(tick, pieces, motion, final=stop)
    return Wait("motion") if axis.moving else None


def _timed_jog(axis: Axis, ms: int, tick: float) -> None:
    v = axis.direction * axis.vl
    v0 = axis.velocity(tick)
    pieces = [
        *pf.velocity_change(v0, v, axis.ac),
        pf.cruise(v, ms / 1000.0),
        *pf.velocity_change(v, 0.0, axis.ac),
    ]
    axis.slip_detect = False  # IS: disabled by ... TM
    axis.home = None
    axis.begin(tick, pieces, Motion.JOG)


@_handles("TM")
def _tm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TM# / TM#,#,#,# (§5.9.1): "0 ≤ TM ≤ 200,000" milliseconds; "In multi-axis mode, all axes
    begin moving at the same time and ramp to a stop when their respective jog times have
    elapsed"."""
    board = ix.board
    if ix.mode == "single":
        raw = ix.one(cmd)
        assert raw is not None
        ms = ix.integer(raw, "TM")
        ix.enqueue([(ix.axis, Op("TM", (ms,), ix.cost(cell, ix.axis)))])
        return
    times = {i: ix.integer(v, "TM") for i, v in ix.per_axis(cmd).items()}
    if not times:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    group = SyncGroup(set(times))

    def start(g: SyncGroup, when: float) -> None:
        tick = board.clock.at_or_after(when)
        for index, ms in times.items():
            _timed_jog(board.axes[index], ms, tick)

    group.action = start
    # "GO" ops: the executor starts members together and waits for each one's motion after
    ix.enqueue([(board.axes[i], Op("GO", (), ix.cost(cell, board.axes[i]), group)) for i in times])


@_op("TM")
def _op_tm(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    _timed_jog(axis, op.args[0], ex.board.clock.at_or_after(t))
    return Wait("motion") if axis.moving else None


# -- stops and kills ------------------------------------------------------------------------------


def _selected(ix: Interpreter, cmd: Command, nonzero: bool) -> list[Axis]:
    if ix.mode == "single":
        if cmd.fields:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        return [ix.axis]
    picked = ix.per_axis(cmd)
    return [ix.board.axes[i] for i, v in sorted(picked.items()) if v != 0 or not nonzero]


def _stop(ix: Interpreter, axes: list[Axis], cell: Cell, t: float, kill: bool) -> None:
    executor = ix.board.executor
    for axis in axes:
        executor.flush(axis, t)
        axis.queue.append(Op("STOP", (kill,), ix.cost(cell, axis), source=ix.board.input_source))


@_handles("KS")
def _ks(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """KS / KSb,b,b,b (§5.9.4): KL for the selected axes only."""
    axes = _selected(ix, cmd, nonzero=False)
    for axis in axes:
        axis.halt(t)
        axis.aux_timer = None
    _stop(ix, axes, cell, t, kill=True)


@_handles("SI")
def _si(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """SI / SIb,b,b,b (§5.9.4): ramp the selected axes to a stop at AC, flushing their queues."""
    _stop(ix, _selected(ix, cmd, nonzero=True), cell, t, kill=False)
    if ix.mode == "single":
        ix.mt_blocked = False  # as ST: "makes MT valid again"


@_handles("FL")
def _fl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """FL (§5.4.4): flush the current axis's queue, leaving its motion alone."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    axis = ix.axis
    armed, fire = axis.in_arm, axis.in_fire
    ix.board.executor.flush(axis, t)
    if axis.moving:
        axis.in_arm, axis.in_fire = armed, fire
    axis.invalidate()


# -- contours: CG, NV, and MT after CG ------------------------------------------------------------


@_handles("CG")
def _cg(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """CG (§5.9.8): "a form of the CX command"; a marker after it in every queue holds MT."""
    board = ix.board
    defn = runnable_contour(ix)
    group = SyncGroup(set(range(len(board.axes))))

    def run(g: SyncGroup, when: float) -> None:
        for index in defn.axes:
            axis = board.axes[index]
            if not axis.is_servo:  # HN: stepper position maintenance "cancelled by CG, CX"
                axis.hold = False
                axis.in_position = True
        run_contour(ix, defn, when)

    group.action = run
    items: list[tuple[Axis, Op]] = []
    for axis in board.axes:
        items.append((axis, Op("CX", (), ix.cost(cell, axis), group)))
        items.append((axis, Op("CGEND", (), 0)))
    ix.enqueue(items)


@_op("CGEND")
def _op_cgend(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    return None


def contour_pending(board: Board) -> bool:
    """A CG's contour has not finished on some axis (its marker is still queued)."""
    return any(
        op.code == "CGEND" for axis in board.axes for op in axis.queue.program[axis.queue.pc :]
    )


def _previous_handler(mnemonic: str) -> Handler:
    from omsd.board.pcix_commands import PCIX_HANDLERS

    return PCIX_HANDLERS.get(mnemonic) or HANDLERS[mnemonic]


@_handles("MT")
def _mt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """MT as the PCIx handles it elsewhere, held while a CG contour runs (see CG)."""
    if ix.contour is None and contour_pending(ix.board):
        raise Blocked
    _previous_handler("MT")(ix, cmd, cell, t)


@_handles("NV")
def _nv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """NV# (§5.9.8): "1 ≤ NV ≤ 1,043,999"; the executing contour's next segments go at it."""
    raw = ix.one(cmd)
    assert raw is not None
    velocity = ix.check("NV", float(raw))
    board = ix.board
    origins: dict[float, list[Axis]] = {}
    for axis in board.axes:
        if axis.motion is Motion.CONTOUR and axis.contour_origin is not None:
            origins.setdefault(axis.contour_origin, []).append(axis)
    for origin, axes in origins.items():
        _new_contour_velocity(axes, origin, velocity, t)


def _future(axis: Axis, after: float) -> tuple[list[pf.Piece], list[pf.Piece], float]:
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
    """A contour piece run ``f`` times as fast (the CE ramp: from ``f`` times the speed, at the
    same deceleration)."""
    if isinstance(piece, pf.Sinusoid):
        return pf.Sinusoid(piece.r, piece.phase0, piece.omega * f, piece.duration / f)
    if isinstance(piece, pf.Poly) and piece.j == 0.0:
        if ramp:
            return pf.Poly(piece.v0 * f, piece.a0, 0.0, piece.duration * f)
        if piece.a0 == 0.0:
            return pf.Poly(piece.v0 * f, 0.0, 0.0, piece.duration / f)
    return None


def _new_contour_velocity(axes: list[Axis], origin: float, velocity: float, t: float) -> None:
    board = axes[0].board
    after = max(t, origin)
    splits = {a.index: _future(a, after) for a in axes}
    futures = [splits[a.index][1] for a in axes]
    if not futures[0]:
        return  # on the last piece (or the CE ramp): there is no next command
    boundary = splits[axes[0].index][2]
    # the CE ramp down is the last piece of a contour that has one: it decelerates
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
        axis.servo_sync(board.now)
        axis.traj = pf.Trajectory(traj.t0, traj.x0, pieces, float(math.floor(end + 0.5)))
        axis.outputs = [
            (_retimed(board, when, boundary, factor), action) for when, action in axis.outputs
        ]
        axis.invalidate()
        moved(axis, board.now, origin, Motion.CONTOUR)


def _retimed(board: Board, when: float, boundary: float, factor: float) -> float:
    if when <= boundary:
        return when
    return board.clock.at_or_after(boundary + (when - boundary) / factor)


# -- hooks called by the axis and the executor ----------------------------------------------------


def moved(axis: Axis, now: float, start: float | None, motion: Motion | None) -> None:
    """The axis's trajectory was replaced at ``now`` (new motion beginning at ``start``, or rest):
    remember where a contour's own pieces begin (NV), and let geared axes follow."""
    axis.contour_origin = start if motion is Motion.CONTOUR else None
    for other in axis.board.axes:
        if other.gear is not None and other.gear.master == axis.index:
            follow(other, axis, now)


def sensed(axis: Axis, t: float) -> None:
    """A look at the axis's sensors (before limits are checked): backlash, GS."""
    if axis.backlash:
        take_up_backlash(axis, t)
    watch = axis.home
    if isinstance(watch, SlipWatch) and axis.motion is not Motion.IDLE:
        _watch_home(axis, watch, t)


__all__ = [
    "MOTION_HANDLERS",
    "MOTION_OPS",
    "Gear",
    "SlipWatch",
    "asymmetric_move",
    "backlash_tick",
    "beyond_travel_limit",
    "contour_pending",
    "disengage",
    "engage",
    "follow",
    "moved",
    "sensed",
    "set_backlash",
    "set_travel_limits",
    "take_up_backlash",
    "travel_levels",
]
