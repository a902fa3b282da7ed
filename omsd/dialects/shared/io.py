"""The shared language, PC48 §6.6: user I/O (the auxiliary output, power automatic, settling
time, the general-purpose bits)."""

from __future__ import annotations

from decimal import Decimal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.sync import task_axes
from omsd.dialects.shared.table import handles
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- 6.6 user I/O ---------------------------------------------------------------------------------


@handles("AN", "AF")
def aux(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """AN (released, high) / AF (driven low). In AA/AM and in a contour the parameters are
    place holders: "the value given does not affect the active state of the auxiliary line"."""
    code = cmd.mnemonic
    machine = ix.machine
    if ix.contour is not None:
        from omsd.engine.contour import Output  # (loaded: a contour is being defined)

        targets = ix.per_axis(cmd)
        if not targets:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        slots = ix.cost(cell, ix.axis)
        if not ix.contour.add(None, slots):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        for index in targets:
            ix.contour.items.append(Output("aux", index, code == "AF"))
        return
    axes = [ix.axis] if ix.mode == "single" else [machine.axes[i] for i in ix.per_axis(cmd)]
    ix.enqueue([(a, Op(code, (), ix.cost(cell, a))) for a in axes])
    for a in axes:
        ix.pa_entered[a.index] = False


@handles("PA")
def _pa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.mode == "single":
        value = ix.one(cmd, required=False)
        items: dict[int, Decimal | None] = {ix.axis_index: value}
    else:
        items = dict(ix.per_axis(cmd))
    ops = []
    for index, value in items.items():
        axis = ix.machine.axes[index]
        ops.append((axis, Op("PA", (value,), ix.cost(cell, axis))))
    ix.enqueue(ops)
    for index in items:
        ix.pa_entered[index] = True


@handles("SE")
def _se(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "The parameter may be any value to 1000 milliseconds. ... zero turns off the mode."
    items = {ix.axis_index: ix.one(cmd)} if ix.mode == "single" else dict(ix.per_axis(cmd))
    ops = []
    for index, value in items.items():
        ms = ix.integer(value, "SE")
        axis = ix.machine.axes[index]
        ops.append((axis, Op("SE", (ms,), ix.cost(cell, axis))))
        ix.se_entered[index] = ms > 0
    ix.enqueue(ops)


@handles("BL", "BH")
def _bit(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    bit = ix.integer(ix.one(cmd), cmd.mnemonic)
    if not machine.directions >> bit & 1:
        # "this is only valid for bits which have been configured as outputs"
        raise CommandFailed(ErrorKind.NOT_AN_OUTPUT)
    low = cmd.mnemonic == "BL"
    if ix.contour is not None:
        from omsd.engine.contour import Output  # (loaded: a contour is being defined)

        if not ix.contour.add(Output("bit", bit, low), ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op(cmd.mnemonic, (bit,), ix.cost(cell, ix.axis)))])
        return
    # AA: the bit is set once every axis has reached it; AM: once the task's axes have
    members = [machine.axes[i] for i in task_axes(ix)]
    group = SyncGroup({a.index for a in members})
    group.action = lambda g, when: machine.set_output(bit, low, when)
    ix.enqueue([(a, Op("WA", (), ix.cost(cell, a), group)) for a in members])


@handles("BX")
def _bx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value(f"{ix.machine.io_bits_low(t):06X}", t)
