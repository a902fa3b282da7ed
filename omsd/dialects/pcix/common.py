"""What the PCIx's handler modules share: the dialect's handler and op tables with their
decorators, and helpers for its command forms (``LN;`` / ``LNb,b,b,b;`` flags, commands that act
at once or when the axis reaches them, one-value operands, lower-case replies).

The PCIx's handlers replace or add to the shared language's (:mod:`omsd.dialects.shared`); a
handler may expect the PCIx's interpreter
(:class:`~omsd.dialects.pcix.interpreter.PcixInterpreter`), whose macros, ramp-table definition
and flash it uses.
"""

from __future__ import annotations

from collections.abc import Callable
from decimal import Decimal
from typing import Literal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix.interpreter import PcixInterpreter
from omsd.dialects.shared.table import registrar
from omsd.engine.axis import Axis
from omsd.engine.executor import OpFunction
from omsd.engine.queue import Op
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import parse_number

PcixHandler = Callable[[PcixInterpreter, Command, Cell, float], None]

#: The PCIx's own handlers, over the shared language's.
PCIX_HANDLERS: dict[str, PcixHandler] = {}
#: The executor ops of the queued commands the shared language does not have.
PCIX_OPS: dict[str, OpFunction] = {}

handles = registrar(PCIX_HANDLERS)


def executes(code: str) -> Callable[[OpFunction], OpFunction]:
    def register(fn: OpFunction) -> OpFunction:
        PCIX_OPS[code] = fn
        return fn

    return register


def flag_axes(ix: Interpreter, cmd: Command, bare: Literal["none", "all"] = "none") -> list[Axis]:
    """``LN;`` / ``LNb,b,b,b;``: the current axis in single-axis mode; in AA/AM §5.1: "If a
    parameter exists for an axis, then the command affects that axis and if the parameter does
    not exist for that axis, then the command has no effect on that axis", so with no parameters
    at all no axis (``bare="none"``; as AN/AF). A page that says otherwise passes
    ``bare="all"`` (HF: "If the current mode is multi-axis, all axes will go into open-loop
    mode")."""
    if ix.mode == "single" and ix.contour is None:
        if cmd.fields and any(f is not None for f in cmd.fields):
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        return [ix.axis]
    if not cmd.fields:
        return list(ix.machine.axes) if bare == "all" else []
    picked: list[Axis] = []
    for i, text in enumerate(cmd.fields):
        if i < len(ix.machine.axes) and text is not None:
            parse_number(text)
            picked.append(ix.machine.axes[i])
    return picked


def apply_to(
    ix: Interpreter,
    cmd: Command,
    cell: Cell,
    axes: list[Axis],
    apply: Callable[[Axis, float], None],
    t: float,
) -> None:
    """Do ``apply`` now (immediate commands) or when each axis reaches it in its queue."""
    if cell.kind is Kind.IMMEDIATE:
        for a in axes:
            apply(a, t)
        return
    ix.enqueue([(a, Op("SET", (cmd.mnemonic, apply), ix.cost(cell, a))) for a in axes])


def flag(apply: Callable[[Axis, float], None]) -> PcixHandler:
    def handler(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
        apply_to(ix, cmd, cell, flag_axes(ix, cmd), apply, t)

    return handler


def one_value(ix: Interpreter, cmd: Command) -> Decimal:
    """The command's one decimal operand, checked against its range row."""
    value = ix.one(cmd)
    assert value is not None
    return ix.check(cmd.mnemonic, value)


def one_integer(ix: Interpreter, cmd: Command) -> int:
    """The command's one whole-number operand (truncated), checked against its range row."""
    return ix.integer(ix.one(cmd), cmd.mnemonic)


def reply(ix: Interpreter, text: str, t: float) -> None:
    ix.machine.reply_value(text, t)


def fixed(value: float, places: int) -> str:
    return f"{value:.{places}f}"


def setter(attr: str, value: object) -> Callable[[Axis, float], None]:
    def apply(axis: Axis, t: float) -> None:
        setattr(axis, attr, value)
        axis.invalidate()

    return apply


def position(ix: Interpreter, axis: Axis, raw: Decimal, mnemonic: str, operand: int = 1) -> float:
    """A position in counts (user units applied) against its row (the position range)."""
    return ix.check(mnemonic, ix.convert(axis, raw, "dist"), operand)
