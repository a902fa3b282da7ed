"""Queued parameter changes: what an axis does when its queue reaches a command that sets
something (PC48 §6.5–§6.7, §6.14–§6.19). Each op is ``fn(executor, axis, op, t)``; the op code
is the command's mnemonic, or ``SET`` for a dialect's own change carried as a function."""

from __future__ import annotations

import math

from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.executor import Executor, OpFunction, Result
from omsd.engine.queue import Op
from omsd.engine.states import Motion


def _set(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    """A queued parameter change: ``Op("SET", (mnemonic, apply), slots)`` runs
    ``apply(axis, t)`` when the axis reaches it (a dialect's own parameters)."""
    apply = op.args[1]
    apply(axis, t)
    return None


def _nop(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    return None


def _vl(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.vl = axis.to_motor(op.args[0])
    return None


def _ac(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.ac = axis.to_motor(op.args[0])
    # the deceleration "will take on whatever value is entered via the AC command" (PCIx DC)
    axis.dc = axis.ac
    return None


def _vb(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.vb = axis.to_motor(op.args[0])
    return None


def _lp(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    value = float(op.args[0])
    if axis.has_encoder:
        # "the parameter will be loaded into the encoder position register and the parameter
        # times the encoder ratio will be loaded into the position counter" (ER3,2 LP30000
        # gives 20,000: the motor/encoder ratio), a whole number of steps (user units may
        # give a fraction of an encoder count: ER1000,2000 UU0.5 LP601 is 300.5, 601 steps)
        axis.load_counter(t, float(math.trunc(axis.to_motor(value))))
        axis.anchor_encoder(t, float(math.trunc(value)))
        ex.cancel(axis, "LP")
        ex.end_correction(axis, t)
    else:
        axis.load_counter(t, float(math.trunc(value)))
    axis.hold_goal = float(axis.encoder(t))
    if axis.hold:  # (the PCIx's LP leaves the hold on: it holds where the load put it)
        ex.check_hold(axis, t)
    return None


def _hh(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.home_high = True
    return None


def _hl(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.home_high = False
    return None


def _ln(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.limits_on = True
    axis.look_at_sensors(t)
    return None


def _lf(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.limits_on = False
    axis.invalidate()
    return None


def _soft_limit(on: bool) -> OpFunction:
    def op_(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
        if ex.machine.options.soft_limit_per_axis:
            axis.soft_limit = on
        else:  # one mode for the whole board
            ex.machine.soft_limits = on
        return None

    return op_


def _dir(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.direction = op.args[0]
    return None


def _cn(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.machine.ramp = pf.RampShape(pf.RampKind.COSINE)
    return None


def _rm(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # "An RM2000 command with a position counter of -4050 will return a position of 1950"
    n = op.args[0]
    x = axis.position(t)
    axis.load_counter(t, x - n * math.floor(axis.counter(t) / n))
    if ex.machine.options.remainder_folds_encoder and axis.has_encoder:
        # "The RM command has the same effect on the encoder position register" (PCIx)
        e = axis.encoder(t)
        axis.anchor_encoder(t, float(e - n * math.floor(e / n)))
    axis.anchor_tracking(t)
    return None


def _er(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.cancel(axis, "ER")
    axis.anchor_encoder(t)
    axis.ratio = op.args[0] / op.args[1]
    axis.anchor_encoder(t)
    return None


def _hv(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.hv = axis.to_motor(op.args[0])
    return None


def _hg(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.hg = float(op.args[0])
    return None


def _hd(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.hd = float(op.args[0])
    return None


def _es(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.es = float(op.args[0])
    axis.invalidate()
    return None


def _hf(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if axis.servo is not None:
        # "HF will open the loop and turn off the PID"
        axis.servo_sync(t)
        axis.servo.closed = False
        axis.invalidate()
        if axis.motion is Motion.JOG:  # opening the loop stops a servo's jog
            axis.decelerate(t)
        return None
    ex.hold_off(axis)
    ex.end_correction(axis, t)
    axis.tracking = False
    return None


def _hn(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if axis.servo is not None:
        # "HN ... will close the loop and enable the PID". Closing is bumpless: an axis at
        # rest is commanded to hold where its motor is (an open loop may have drifted, or run
        # its commanded position on without the motor), and the stage, switches and all, is
        # where the motor is. The set point is the commanded position plus the backlash offset
        # ("offsetting the motor's position "set point" from the commanded position", §5.12.4),
        # so the commanded position is the encoder less that offset
        loop = axis.servo
        axis.servo_sync(t)
        if not loop.closed and axis.motion is Motion.IDLE:
            axis.command_at(t, float(loop.encoder_counts) - axis.setpoint_offset)
            loop.set_position(loop.position)
        loop.closed = True
        axis.servo_trip_reported = False
        axis.servo_last = None
        axis.invalidate()
        return None
    if not axis.hold:
        axis.hold = True
        x = axis.traj.final if axis.traj.is_finite else axis.position(t)
        axis.hold_goal = axis.tracked_encoder(x)
        if not axis.slip_detect:
            axis.anchor_tracking(t)
    ex.check_hold(axis, t)
    return None


def _is(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if not axis.slip_detect and not axis.hold:
        axis.anchor_tracking(t)
    axis.slip_detect = True
    axis.look_at_sensors(t)
    return None


def _et(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.cancel(axis, "ET")
    axis.tracking = True
    axis.anchor_tracking(t)
    return None


def _pa(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.6: "The auxiliary will be turned on, i.e. pulled high, upon the execution of the
    # GO or GD and off at the end of that move, if the parameter is zero or not specified"
    param = op.args[0]
    axis.pa = param is None or param == 0
    if axis.motion is not Motion.MOVE:
        axis.aux = not axis.pa  # "setting the master's X axis auxiliary line low until..."
    axis.aux_timer = None
    return None


def _se(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.se_ms = op.args[0]
    return None


def _an(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.set_aux(axis, True, t)
    return None


def _af(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.set_aux(axis, False, t)
    return None


def _bl(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.machine.set_output(op.args[0], low=True, t=t)
    return None


def _bh(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.machine.set_output(op.args[0], low=False, t=t)
    return None


PARAMETER_OPS: dict[str, OpFunction] = {
    "SET": _set,
    "NOP": _nop,
    "CW": _nop,
    "VL": _vl,
    "AC": _ac,
    "VB": _vb,
    "LP": _lp,
    "HH": _hh,
    "HL": _hl,
    "LN": _ln,
    "LF": _lf,
    "SL": _soft_limit(True),
    "SF": _soft_limit(False),
    "DIR": _dir,
    "CN": _cn,
    "RM": _rm,
    "ER": _er,
    "HV": _hv,
    "HG": _hg,
    "HD": _hd,
    "ES": _es,
    "HF": _hf,
    "HN": _hn,
    "IS": _is,
    "ET": _et,
    "PA": _pa,
    "SE": _se,
    "AN": _an,
    "AF": _af,
    "BL": _bl,
    "BH": _bh,
}
