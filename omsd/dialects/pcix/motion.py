"""PCIx motion commands the older boards do not have (PCIx manual §5.9, §5.12, §5.7.5, §5.5.4):
backlash (the engine's :mod:`omsd.engine.backlash`), travel limits (the engine's soft travel
limits), LO, and the moves GU, GN, GS, SO and TM with their executor ops.

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

Moves
    * GU (§5.9.3): "initiates a previously defined move using the AC value for acceleration and
      the DC value for deceleration"; "GU is used only with linear acceleration ramps": the
      profile is linear whatever the axis's ramp selection (and VB, which "will not work in
      conjunction with the DC command", is not used). A move too short to reach VL is
      triangular, peaking where the two ramps meet.
    * DC (§5.8.2) is set by :mod:`omsd.dialects.pcix.settings` ("defaults to 200,000 and will take
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
      disables slip detection (the IS page). In power-automatic mode the output is in its
      moving state for the whole jog, ramps included (§5.5.1: "invert at the beginning of every
      motion and return to normal at the end"; ``Executor.power_on``).

Limits and positions
    * TL upper,lower (§5.5.4): "If the axis reaches either of these logical limits, the PCIX will
      flag a limit condition just as it would be using the physical limit switch inputs. Move
      Absolute (MA), Move Relative (MR), and Jog (JF, JG) commands are subject". The ?TL page says
      "If one of these limits is exceeded": a position *beyond* a limit is overtravel (a move to
      the limit itself is allowed). It acts as a limit switch does: RA shows ``L`` while the
      position is beyond it, the axis stops (SF) or ramps down (SL) and its queue is flushed,
      the limit event is raised. LF does not turn it off (LF "disables the limit switches";
      "Software overtravel limits and physical limit switch inputs can be enabled at the same
      time"): TL0,0 does. Point-to-point moves (GO, GD, GN, GU) and jogs
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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix.common import (
    executes,
    handles,
    position,
)
from omsd.dialects.shared.sync import task_axes
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis, HomeSearch, Motion, Wait
from omsd.engine.backlash import set_backlash
from omsd.engine.events import SlipEvent
from omsd.engine.executor import Executor, Result
from omsd.engine.queue import Op, SyncGroup
from omsd.engine.registers import DON_S, ENC_S
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import truncate


@handles("BC")
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


@handles("TL")
def _tl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TL#,# (§5.5.4): "Two parameters must be supplied; one for the upper travel limit and the
    other for the lower travel limit, both as absolute positions"; "TL0,0; Turns software limits
    off"."""
    axis = ix.axis
    raw_upper, raw_lower = ix.required(cmd, 2)
    upper = position(ix, axis, raw_upper, "TL", 1)
    lower = position(ix, axis, raw_lower, "TL", 2)
    if lower >= upper and not (upper == 0 and lower == 0):
        raise CommandFailed(ErrorKind.OUT_OF_RANGE)

    def apply(a: Axis, when: float) -> None:
        # "absolute positions", as MA's: under an encoder ratio in encoder counts, compared with
        # the position counter in motor steps
        a.set_travel_limits(a.to_motor(upper), a.to_motor(lower), when)

    ix.enqueue([(axis, Op("SET", ("TL", apply), ix.cost(cell, axis)))])


@handles("?TL")
def _tl_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """?TL (§5.5.4): "The first value returned is the upper (or "positive") limit and the second
    value is the lower"."""
    limits = ix.axis.travel_limits
    if limits is None:
        ix.machine.reply_value("tl0,0;", t)  # as printed for "soft limits ... disabled"
        return
    lower, upper = limits
    ix.machine.reply_value(f"tl{math.trunc(upper)},{math.trunc(lower)}", t)


@handles("LO")
def _lo(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """LO# / LO#,#,#,# (§5.7.5): "sets the motor position independently of the encoder position";
    "For AA and AM modes, any value missing in the argument list specifies that axis is not to be
    affected"."""
    items = ix.items(cmd)
    ops = []
    for index, raw_value in items.items():
        axis = ix.machine.axes[index]
        value = position(ix, axis, raw_value, "LO")

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


@handles("GU")
def _gu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GU (§5.9.3): "This command may be used with only one axis at a time"."""
    _single_go(ix, cmd, cell, "GU")


@executes("GU")
def _op_gu(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    pending = axis.pending
    if pending is None:  # "If this command is issued without having defined a move ..."
        return None
    axis.pending = None
    tick = ex.machine.clock.at_or_after(t)
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
    ex.power_on(axis)
    ex.arm_in(axis, target)
    return Wait("motion")


@handles("GN")
def _gn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GN (§5.9.3): "initiate a move ... and set the axis done flags when the move is complete".
    Queued as the GO it is, followed by the done flag (no slots of its own)."""
    machine = ix.machine
    if ix.mode == "single":
        axis = ix.axis
        ix.enqueue([(axis, Op("GO", (), ix.cost(cell, axis))), (axis, Op("GN", (), 0))])
        return
    members = task_axes(ix)
    go = SyncGroup(set(members))
    go.action = machine.executor.go_action
    go.data["gd"] = False
    done = SyncGroup(set(members), barrier=False)
    done.action = machine.executor.done_action
    items: list[tuple[Axis, Op]] = []
    for index in members:
        axis = machine.axes[index]
        items.append((axis, Op("GO", (), ix.cost(cell, axis), go)))
        items.append((axis, Op("GN", (), 0, done)))
    ix.enqueue(items)


@executes("GN")
def _op_gn(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is None:
        ex.machine.set_done([axis], t, interrupt=True)
        return None
    ex.machine.set_done([axis], t, interrupt=False)
    return ex.arrive(axis, op, t)


@handles("GS")
def _gs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """GS (§5.9.3): "works exactly like the GO command except that the home switch will be
    monitored during the motion"."""
    _single_go(ix, cmd, cell, "GS")


@dataclass(eq=False)  # state, compared by identity (omsd.engine.states)
class SlipWatch(HomeSearch):
    """GS: the home switch watched during a move (not a home search: nothing stops or loads)."""


@executes("GS")
def _op_gs(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.start_pending([axis], t)
    if not axis.moving:
        return None
    tick = ex.machine.clock.at_or_after(t)
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


def watch_home_switch(ex: Executor, axis: Axis, t: float) -> None:
    """A look at the sensors (the dialect's sensor hook): during a GS move, the slip flag each
    time the home switch becomes active."""
    watch = axis.home
    if not isinstance(watch, SlipWatch) or axis.motion is Motion.IDLE:
        return
    active = axis.home_sensed(t)
    if active and not watch.prev:
        axis.slipped = True
        machine = ex.machine
        machine.registers.status |= ENC_S | DON_S
        machine.emit(SlipEvent(t, axis.letter))
    watch.prev = active


# -- SO, TM ---------------------------------------------------------------------------------------


@handles("SO")
def _so(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """SO#,# (§5.9.4): stop position, and the distance from it at which to start decelerating;
    both "-33,554,431 ... 33,554,431"."""
    axis = ix.axis
    raw_stop, raw_distance = ix.required(cmd, 2)
    stop = position(ix, axis, raw_stop, "SO", 1)
    distance = position(ix, axis, raw_distance, "SO", 2)
    ix.enqueue([(axis, Op("SO", (stop, distance), ix.cost(cell, axis)))])


@executes("SO")
def _op_so(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    stop = float(math.trunc(axis.to_motor(op.args[0])))
    distance = abs(axis.to_motor(op.args[1]))
    ex.cancel(axis, "SO")  # HN: "canceled ... if an CG, CX, HM, HR, MV, SO, SP command is entered"
    tick = ex.machine.clock.at_or_after(t)
    v0 = axis.velocity(tick)
    if v0 == 0.0:
        return None
    s = 1 if v0 > 0 else -1 if v0 < 0 else 0
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
        keep = pf.pieces_between(traj, tick, when)
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


def _timed_jog(ex: Executor, axis: Axis, ms: int, tick: float) -> None:
    v = axis.direction * axis.vl
    v0 = axis.velocity(tick)
    pieces = [
        *pf.velocity_change(v0, v, axis.ac),
        pf.cruise(v, ms / 1000.0),
        *pf.velocity_change(v, 0.0, axis.ac),
    ]
    ex.cancel(axis, "TM")  # IS: "disabled if a ... TM command is entered"
    axis.home = None
    axis.begin(tick, pieces, Motion.JOG)
    ex.power_on(axis)


@handles("TM")
def _tm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TM# / TM#,#,#,# (§5.9.1): "0 ≤ TM ≤ 200,000" milliseconds; "In multi-axis mode, all axes
    begin moving at the same time and ramp to a stop when their respective jog times have
    elapsed"."""
    machine = ix.machine
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
        tick = machine.clock.at_or_after(when)
        for index, ms in times.items():
            _timed_jog(machine.executor, machine.axes[index], ms, tick)

    group.action = start
    # "GO" ops: the executor starts members together and waits for each one's motion after
    ix.enqueue(
        [(machine.axes[i], Op("GO", (), ix.cost(cell, machine.axes[i]), group)) for i in times]
    )


@executes("TM")
def _op_tm(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    _timed_jog(ex, axis, op.args[0], ex.machine.clock.at_or_after(t))
    return Wait("motion") if axis.moving else None
