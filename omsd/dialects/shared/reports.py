"""The shared language, PC48 §6.13 and §6.14: status requests and user units."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from decimal import ROUND_HALF_UP, Context, Decimal

from omsd.dialects.interpreter import Interpreter
from omsd.dialects.shared.table import handles
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis, Motion
from omsd.engine.axis_status import status_inputs
from omsd.engine.registers import OVRT
from omsd.models.spec import Cell
from omsd.protocol.lexer import Command

#: The sixteen statuses, by (moving the positive way, done, overtravel, home): each field's
#: letter when true and when not.
_FIELDS = (("P", "M"), ("D", "N"), ("L", "N"), ("H", "N"))
_STATUSES = {
    flags: "".join(yes if on else no for on, (yes, no) in zip(flags, _FIELDS, strict=True))
    for flags in itertools.product((False, True), repeat=4)
}


def status(axis: Axis, t: float) -> str:
    """RA/QA field (PC48 §6.13 RA): direction P/M, done D/N, overtravel L/N (in the direction
    of char 4), home H/N. The switches see the carriage once, at ``t`` (as a snapshot does)."""
    d, limit, home = status_inputs(axis, t)
    return _STATUSES[d > 0, axis.done, limit, home]


# -- 6.13 status requests -------------------------------------------------------------------------


@handles("WY")
def _wy(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value(ix.machine.model.who_are_you(), t)


def _list(ix: Interpreter, fn: Callable[[Axis], str], t: float) -> None:
    if ix.mode == "single":
        ix.machine.reply_value(fn(ix.axis), t)
    else:
        ix.machine.reply_value(",".join(fn(a) for a in ix.machine.axes), t)


@handles("RP")
def _rp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.mode == "single":  # the query polled most: one axis, said without a list
        machine = ix.machine
        machine.reply_number(machine.axes[ix.axis_index].counter(t), t)
    else:
        _counters(ix, t)


def _counters(ix: Interpreter, t: float) -> None:
    """RP's list (apart from _rp: a closure over ``t`` there costs the single-axis RP a cell)."""
    _list(ix, lambda a: str(a.counter(t)), t)


@handles("RQ")
def _rq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.contour is not None:
        # "The maximum available is 1016. The response is fixed in length at 4 characters."
        ix.machine.reply_value(f"{ix.contour.free:04d}", t)
        return
    _list(ix, lambda a: f"{a.queue.free:03d}", t)


@handles("RC")
def _rc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _list(ix, lambda a: str(whole(_current_acceleration(ix, a, t))), t)


def whole(value: float) -> int:
    """The integer part of ``value`` (what RV and RC report), of the value the arithmetic
    meant: one a hair from a whole number, as floating point leaves the end of a ramp
    (999999.9999999999 for the 1,000,000 at the end of a PN5 ramp at AC2000000, 1e-16 of it),
    is that number; a fraction given on purpose (``JF100.999999``) is not a hair."""
    nearest = round(value)
    if abs(value - nearest) <= 1e-12 * max(1.0, abs(value)):
        return nearest
    return math.trunc(value)


#: Motions whose ramp is linear whatever the ramp mode (``omsd.engine.ramps.velocity_change``;
#: a jog's queue table says "Linear ramp", and a home search and a staircase ramp as a jog does).
_LINEAR_RAMPS = frozenset({Motion.JOG, Motion.HOME, Motion.STAIRCASE})


def _current_acceleration(ix: Interpreter, axis: Axis, t: float) -> float:
    """PC48 §6.13 RC: "When the stage is stopped, the parameter returned will be the acceleration
    at the beginning of a ramp. When the stage is running at programmed speed ... the
    acceleration at the end of the ramp.\"" The ramp is the one the axis ran: linear for a jog
    in any ramp mode. "While a contour is executing, the value computed to generate the
    appropriate lead in will be returned", for the whole contour. A profile that has run out
    (its end is before the sample tick that makes the axis idle) is a stage stopped, as RP and
    RV already say: the acceleration at the beginning of a ramp, not the 0 of no ramp at all."""
    if axis.motion is Motion.CONTOUR:
        return ix.contour_lead.get(axis.index, 0.0)
    if axis.motion is not Motion.IDLE and axis.traj.moving_at(t):
        a = abs(axis.acceleration(t))
        if a > 0.0 or axis.velocity(t) == 0.0:
            return a
        shape = pf.LINEAR if axis.motion in _LINEAR_RAMPS else axis.ramp
        up = pf.ramp_up(axis.vl, axis.ac, axis.base_velocity, shape)
        return abs(up.a(up.duration))
    up = pf.ramp_up(axis.vl, axis.ac, axis.base_velocity, axis.ramp)
    return abs(up.a(0.0))


@handles("RV")
def _rv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "If the JF command is executing, the command only reports the integer part"
    _list(ix, lambda a: str(whole(a.velocity(t))), t)


def user_position(axis: Axis, t: float) -> Decimal:
    """RU's number: "the current position in user units", which with an encoder ratio are
    encoder counts (§6.15 ER: "allowing units such as inches or revolutions to be specified in
    encoder counts"): ER2,1 UU10 LP5 is 50 encoder counts, 25 motor steps, and RU 5."""
    value = Decimal(axis.counter(t))
    if axis.has_encoder and axis.ratio != 1.0:
        value = value * Decimal(axis.ratio)
    if axis.uu is not None:
        value = value / axis.uu
    return value


def rounded_off(value: Decimal, places: int) -> str:
    """``value`` with ``places`` decimals, a half rounded away from zero: ?UU's "the value will be
    rounded off to the sixth decimal place" (PCIx), and RU's five decimals the same way."""
    # (a precision for the widest: a counter of 10^8 steps over a UU of 10^-22, 24 characters)
    exact = Context(prec=100)
    return f"{value.quantize(Decimal(1).scaleb(-places), ROUND_HALF_UP, exact):f}"


@handles("RU")
def _ru(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "a floating point number with five characters to the right of the decimal point"
    ix.machine.reply_value(rounded_off(user_position(ix.axis, t), 5), t)


@handles("RA", "QA")
def _ra(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    axis = machine.axes[ix.axis_index]  # (ix.axis, written out: the query polled most)
    machine.reply_status(status(axis, t), t)
    if cmd.mnemonic == "RA":
        _reset_flags(ix, [axis], t)


@handles("RI", "QI")
def _ri(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    machine.reply_status(",".join(status(a, t) for a in machine.axes), t)
    if cmd.mnemonic == "RI":
        _reset_flags(ix, machine.axes, t)


def _reset_flags(ix: Interpreter, axes: list[Axis], t: float) -> None:
    """RA: "The limit flag in the hardware status register will be reset by the RA command,
    providing another axis is not in limit. The done flag register will also be reset"."""
    machine = ix.machine
    machine.clear_done(axes)
    others = [a for a in machine.axes if a not in axes]
    if not any(a.limit_active(a.direction, t) for a in others):
        machine.registers.status &= ~OVRT


# -- 6.14 user units ------------------------------------------------------------------------------


@handles("UU")
def _uu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # single-axis on the PC48; the VS4 manual also shows ``AA UU10000,10000,10000;``
    if ix.mode == "single":
        value = ix.one(cmd)
        assert value is not None
        items = {ix.axis_index: value}
    else:
        items = ix.per_axis(cmd)
    for value in items.values():
        ix.check("UU", value)
    for index, value in items.items():
        ix.machine.axes[index].uu = None if value == 1 else value


@handles("UF")
def _uf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.axis.uu = None
