"""The shared language, PC48 §6.12: move synchronization (done flags, interrupts, waits)."""

from __future__ import annotations

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.table import handles
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- 6.12 move synchronization --------------------------------------------------------------------


def task_axes(ix: Interpreter) -> list[int]:
    """The axes a multi-axis wait or meeting applies to: in AM the task's, the axes of its most
    recent move ("a task may be performing coordination motion on 2 axes, while a second task
    is performing unrelated but simultaneous motion on another axis", PC48 AM; ID: "In the AM
    mode, only the axes active in the most recent move"); otherwise, and in AM before any move,
    every axis ("In the AA mode, all axes will wait", WT)."""
    if ix.mode == "AM" and ix.last_move:
        return list(ix.last_move)
    return list(range(len(ix.machine.axes)))


@handles("ID")
def _id(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    if ix.contour is not None:
        # the PCIx's "ID; AA/CD 1": one unit of the contour queue; the done flags of the contour
        # axes are set (and the host interrupted) when the contour reaches it, as AN/AF/BL/BH
        # inside a definition act at their place on the path
        from omsd.engine.contour import Output  # (loaded: a contour is being defined)

        mask = sum(1 << i for i in ix.contour.axes)
        if not ix.contour.add(Output("done", mask, False), ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("ID", (), ix.cost(cell, ix.axis)))])
        return
    # AA: "the done flag register bits will be set as each axis encounters the ID in its command
    # stream, but the done flag in the status register will not be set until all axes have
    # executed the ID command. In the AM mode, only the axes active in the most recent move will
    # set their done flags."
    members = task_axes(ix)
    group = SyncGroup(set(members), barrier=False)
    group.action = machine.executor.done_action
    ix.enqueue(
        [(machine.axes[i], Op("ID", (), ix.cost(cell, machine.axes[i]), group)) for i in members]
    )


@handles("II")
def _ii(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Only those axes which have been supplied a parameter in the most recent move command will
    # cause interrupts."
    machine = ix.machine
    members = [ix.axis_index] if ix.mode == "single" else (ix.last_move or task_axes(ix))
    ix.enqueue([(machine.axes[i], Op("II", (), ix.cost(cell, machine.axes[i]))) for i in members])


@handles("IN")
def _in(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    items = ix.items(cmd)
    group = SyncGroup(set(items), barrier=False)
    group.action = machine.executor.done_action
    ops = []
    for index, raw in items.items():
        axis = machine.axes[index]
        value = ix.check("IN", ix.convert(axis, raw, "dist"))
        ops.append((axis, Op("IN", (value,), ix.cost(cell, axis), group)))
    ix.enqueue(ops)


@handles("IP")
def _ip(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("IP", (), ix.cost(cell, ix.axis)))])
        return
    # VS4 AA form: like ID, DON_S once every encoder axis of the task is in position; where
    # IP is valid on any axis (the PCIx: "If the position hold (HN) is not enabled for an
    # axis, the command will behave like an ID command for that axis"), every axis of the task
    any_axis = not ix.commands["IP"].encoder_only and ix.commands["IP"].motor is None
    members = [i for i in task_axes(ix) if any_axis or machine.axes[i].has_encoder]
    group = SyncGroup(set(members), barrier=False)
    group.action = machine.executor.done_action
    ix.enqueue(
        [(machine.axes[i], Op("IP", (), ix.cost(cell, machine.axes[i]), group)) for i in members]
    )


@handles("IC")
def _ic(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.clear_flags()


@handles("CA")
def _ca(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.clear_done([ix.axis])


@handles("WA")
def _wa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    group = SyncGroup(set(range(len(machine.axes))))
    ix.enqueue([(a, Op("WA", (), ix.cost(cell, a), group)) for a in machine.axes])


@handles("WQ")
def _wq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "stops the board from processing any new command until the queue for the current axis
    # mode is empty ... This command is not valid in looping (LS-LE, WH-WG) mode."
    axes = ix.context_axes()
    if ix.in_loop(axes):
        raise CommandFailed(ErrorKind.NOT_IN_LOOP)
    ix.wq = [a.index for a in axes]


@handles("SW")
def _sw(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    bit = ix.integer(ix.one(cmd), "SW")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("SW", (bit,), ix.cost(cell, ix.axis)))])
        return
    # AA: every axis waits; AM: the task's axes, as its GO and ID
    members = [machine.axes[i] for i in task_axes(ix)]
    group = SyncGroup({a.index for a in members})
    ix.enqueue([(a, Op("SW", (bit,), ix.cost(cell, a), group)) for a in members])


@handles("WT")
def _wt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "In the AA mode, all axes will wait." In AM only the task's axes do (the page names AA
    # alone; AM "allows starting a task while some other task involving one or many axes is
    # active", VS4 §6.1), as an AM GO meets only the axes of its move
    machine = ix.machine
    ms = ix.integer(ix.one(cmd), "WT")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("WT", (ms,), ix.cost(cell, ix.axis)))])
        return
    members = [machine.axes[i] for i in task_axes(ix)]
    group = SyncGroup({a.index for a in members})
    group.action = machine.executor.wt_action
    group.data["ms"] = ms
    ix.enqueue([(a, Op("WT", (ms,), ix.cost(cell, a), group)) for a in members])
