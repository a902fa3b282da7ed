"""The commands of the PC48 family's language that the PCIx does not share, or shares with
another meaning (PC48 chapter 6): echo (EN, EF), reset (RS), one step (MO, not on an encoder
axis) and RB, queued, reporting the I/O directions in six hex digits."""

from __future__ import annotations

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.modes import simple
from omsd.dialects.shared.table import Handler, registrar
from omsd.engine.axis import Axis
from omsd.engine.executor import Executor, OpFunction, Result
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

PC48_HANDLERS: dict[str, Handler] = {}
handles = registrar(PC48_HANDLERS)


@handles("EN")
def _en(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """§6.5 EN: every character the interpreter reads is echoed (``docs/decisions.md``)."""
    ix.echo = True


@handles("EF")
def _ef(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.echo = False


@handles("RS")
def _rs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """§6.5 RS: the machine's reset (INIT high for the model's ``init_time``)."""
    ix.machine.reset(t)


@handles("MO")
def _mo(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """§6.20 MO: one step; not on an axis with an encoder."""
    if not cmd.fields and ix.axis.has_encoder:
        raise CommandFailed(ErrorKind.ENCODER_MODEL)
    simple(ix, cmd, cell, t)


# §6.13 RB: queued (1 slot, as its table says); the reply comes when the queue reaches it
PC48_HANDLERS["RB"] = simple


def _op_rb(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    ex.machine.reply_value(f"{ex.machine.directions:06X}", t)
    return None


PC48_OPS: dict[str, OpFunction] = {"RB": _op_rb}
