"""The shared language, PC48 §6.9: move termination."""

from __future__ import annotations

from omsd.dialects.interpreter import Interpreter
from omsd.dialects.shared.table import handles
from omsd.models.spec import Cell
from omsd.protocol.lexer import Command

# -- 6.9 move termination -------------------------------------------------------------------------


@handles("ST")
def _st(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "When executed in the AA mode, the ST command is equivalent to the SA command."
    ix.stop(ix.context_axes(), t, cell=cell)


@handles("SA")
def _sa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.stop(list(ix.machine.axes), t, cell=cell)


@handles("SD")
def _sd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.clear_done(ix.machine.axes)
    ix.stop(list(ix.machine.axes), t, cell=cell)


@handles("KL")
def _kl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """KL (as Control-D): "flush the command queue and terminate pulse generation of all axes
    immediately" (PC48 §6.9)."""
    ix.kill_all(t)
