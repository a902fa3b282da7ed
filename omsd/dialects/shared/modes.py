"""The shared language, PC48 §6.4 and §6.5: axis specification and system control (the
single-axis flags, limit modes, ramp selection)."""

from __future__ import annotations

from decimal import Decimal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.table import HANDLERS, handles
from omsd.engine import profiles as pf
from omsd.engine.queue import Op
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import truncate

# -- 6.4 axis specification -----------------------------------------------------------------------


def _select_axis(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    letter = cmd.mnemonic[1]
    axis = ix.machine.axis_by_letter(letter)
    if axis is None:
        raise CommandFailed(ErrorKind.NO_SUCH_AXIS)
    ix.mode = "single"
    ix.axis_index = axis.index


for _letter in "XYZTUVRS":
    HANDLERS["A" + _letter] = _select_axis


@handles("AA")
def _aa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if cell.kind is Kind.QUEUED:
        # a synchronizing no-op in every axis queue: PC48 "AA,AM 2" (its single-axis cell is
        # immediate); PCIx "AA; AX – AT 1", "AA; AA-AM 1", "it places synchronization entries
        # in all axis queues" whichever mode it is typed in
        slots = ix.cost(cell, ix.axis)
        ix.enqueue([(a, Op("NOP", (), slots)) for a in ix.machine.axes])
    ix.mode = "AA"


@handles("AM")
def _am(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.mode = "AM"


@handles("MO", "HF", "HN", "IS", "ET")
def simple(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Single-axis commands with no operand that queue one op on the current axis."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    axis = ix.axis
    ix.enqueue([(axis, Op(cmd.mnemonic, (), ix.cost(cell, axis)))])


@handles("HH", "HL")
def _home_level(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The home switch level, which the encoder home mode has no use for (PC48 §6.18 and VS4
    HE: "The external enable is low true, i.e. the HH and HL commands are not valid in this
    mode"): a command error there, as for the PCIx's HH/HL and every command the queue tables
    call "Not valid" in a mode. The mode is the one HE/HS (immediate) left when HH/HL is read."""
    if ix.axis.home_encoder:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    simple(ix, cmd, cell, t)


@handles("LN", "LF", "SL", "SF")
def _limits(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Limit switch modes. Single-axis on the PC48; the VS4 manual also shows the AA form
    (``AA LN,,,1;``: the fields pick the axes, as for AN; ``AA SF``: no fields, all axes)."""
    if ix.mode == "single":
        if cmd.fields:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        axes = [ix.axis]
    else:
        picked = ix.per_axis(cmd)
        axes = [ix.machine.axes[i] for i in picked] if picked else list(ix.machine.axes)
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a))) for a in axes])


@handles("CN")
def _cn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Cosine ramps for all axes: queued (1 slot) on the PC48, immediate on the VS4."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    if cell.kind is Kind.IMMEDIATE:
        ix.machine.ramp = pf.RampShape(pf.RampKind.COSINE)
        return
    ix.enqueue([(ix.axis, Op("CN", (), ix.cost(cell, ix.axis)))])


def parabolic_steps(ix: Interpreter, value: Decimal | None, mnemonic: str) -> int:
    """PN (and the PCIx's PR): "A parameter out of this range or no parameter supplied defaults
    to 70% or 3 steps" — the row's default, no command error. A whole number: a fraction is
    truncated first, as for every whole-number operand."""
    row = ix.operand_range(mnemonic)
    if value is not None and row.contains(truncate(value)):
        return truncate(value)
    assert row.default is not None
    return int(row.default)


@handles("PN")
def _pn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    steps = parabolic_steps(ix, ix.one(cmd, required=False), "PN")
    floor = ix.machine.model.parabolic_floor
    ix.machine.ramp = pf.RampShape(pf.RampKind.PARABOLIC, steps, floor=floor)


@handles("PF")
def _pf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.ramp = pf.LINEAR
