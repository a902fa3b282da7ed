"""PCIx electronic gearing: EG, EGF, EG? (§5.12.5) and TX (§5.7.3). The mechanism is the
engine's (:mod:`omsd.engine.gearing`); the commands and the choices are here.

Electronic gearing (§5.12.5 EG, EGF, EG?; §5.7.3 TX)
    "the current axis (geared axis) is to track the master axis velocity such that the current
    axis velocity = Ratio X Master Axis velocity", whatever the master is doing (a move, a jog, a
    contour, a home search, a stop). Whenever the master's trajectory changes (it begins new
    motion, comes to rest or is killed) the geared axis takes the master's motion from that
    instant on, scaled by the ratio, from where it is: its velocity is the ratio times the
    master's at every instant. The geared axis keeps an exact record of where the ratio puts it
    (:class:`omsd.engine.states.Gear`), so fractional ratios do not drift: a move of
    1001 counts at EGX1,2 ends on 500 or 501 and the next one makes up the half count.

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
"""

from __future__ import annotations

from decimal import Decimal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix.common import (
    executes,
    handles,
)
from omsd.engine.axis import Axis
from omsd.engine.executor import Executor, Result
from omsd.engine.gearing import disengage, engage, gearable
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import parse_number


def _check_ratio(ix: Interpreter, mnemonic: str, ratio: float, master: Axis) -> None:
    """EG (and TX, its row): "(Gear Ratio *X the Master Axis' VL value) is at least 1 and less
    than the maximum controller step rate of 1,048,574 steps per second"."""
    ix.check(mnemonic, abs(ratio) * master.vl)


def _gear_text(letter: str, geared: str, master_count: str | None) -> str:
    text = letter.lower() + geared
    return text if master_count is None else f"{text},{master_count}"


@handles("EG")
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
    master = ix.machine.axis_by_letter(first[0].upper())
    if master is None or not first[0].isalpha():
        raise CommandFailed(ErrorKind.NO_SUCH_AXIS)
    if not gearable(slave, master):
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


@executes("EG")
def _op_eg(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    master_index, ratio, text, command = op.args
    master = ex.machine.axes[master_index]
    if not gearable(axis, master):
        # the master was geared to another axis after EG was received
        ex.machine.command_error(ErrorKind.GEARED, command, t)
        return None
    engage(axis, master, ratio, text, t)
    return None


@handles("TX")
def _tx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """TX[#] (§5.7.3): track the X axis at a floating point ratio (default 1); "If this is a
    negative, then the axis moves in the opposite direction of the X axis. The command is invalid
    for the X axis." Immediate ("TX; AY – AT Immediate")."""
    slave = ix.axis
    master = ix.machine.axis_by_letter("X")
    if master is None or master is slave:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    raw = ix.one(cmd, required=False)
    ratio = 1.0 if raw is None else float(raw)
    if not gearable(slave, master):
        raise CommandFailed(ErrorKind.GEARED)
    if ratio == 0.0:
        raise CommandFailed(ErrorKind.OUT_OF_RANGE)
    _check_ratio(ix, "TX", ratio, master)
    field = (cmd.fields or (None,))[0]
    engage(slave, master, ratio, _gear_text("X", field or "", None), t)


@handles("EGF")
def _egf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """EGF (§5.12.5): "turns off electronic gearing for the current axis"."""
    disengage(ix.axis, t)


@handles("EG?")
def _eg_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """EG? (§5.12.5): ``=egx1,2`` "(Y axis is geared to the X with a gear ratio of 1:2)", ``=egf``
    "(Z axis is either not geared to another axis or it is the master axis ...)"."""
    gear = ix.axis.gear
    ix.machine.reply_value("=egf" if gear is None else f"=eg{gear.text}", t)
