"""The shared language, PC48 §6.15 - §6.19: the encoder (ratio, position maintenance, slip,
encoder home, status)."""

from __future__ import annotations

from omsd.dialects.interpreter import CommandFailed, Interpreter, motor_fits
from omsd.dialects.shared.table import handles
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- 6.15 - 6.19 encoder --------------------------------------------------------------------------


@handles("ER")
def _er(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "These counts must be integers unless user units are enabled."
    axis = ix.axis
    enc, motor = ix.required(cmd, 2)
    if axis.uu is None and (enc != enc.to_integral_value() or motor != motor.to_integral_value()):
        raise CommandFailed(ErrorKind.BAD_NUMBER)
    ix.check("ER", enc, 1)
    ix.check("ER", motor, 2)
    ix.enqueue([(axis, Op("ER", (float(enc), float(motor)), ix.cost(cell, axis)))])


@handles("HV", "HG", "HD", "ES")
def _hold_parameter(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The current axis, or in AA/AM (the PCIx's ``HD#,#,#,#;``; a field left empty: "not to
    be changed for that axis") each axis given, which must be one the command applies to."""
    code = cmd.mnemonic
    motor = ix.commands[code].motor
    items = ix.items(cmd)
    if not items:  # (AA/AM with no field: no axis given)
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    ops = []
    for index, raw in items.items():
        axis = ix.machine.axes[index]
        if ix.mode != "single" and motor is not None and not motor_fits(motor, axis):
            raise CommandFailed(ErrorKind.WRONG_MOTOR)
        if code == "HV":
            value = ix.check(code, ix.convert(axis, raw, "vel"))
        else:  # HG, HD, ES: whole numbers
            value = float(ix.integer(raw, code))
        ops.append((axis, Op(code, (value,), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("HE", "HS")
def _home_mode(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.axis.home_encoder = cmd.mnemonic == "HE"


@handles("RL")
def _rl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "The number of characters returned corresponds to the number of axes available"
    ix.machine.reply_value("".join("S" if a.slipped else "N" for a in ix.machine.axes), t)


@handles("EA")
def _ea(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    text = "".join(
        (
            "E" if axis.slip_detect else "D",
            "E" if axis.hold else "D",
            "S" if axis.slipped else "N",
            "P" if axis.hold and axis.in_position else "N",
            "H" if axis.home_condition(t) else "N",
            "N",
        )
    )
    axis.slipped = False  # "reset by execution of EA command"
    ix.machine.reply_status(text, t)


@handles("RE")
def _re(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value(str(ix.axis.encoder(t)), t)
