"""The shared language, PC48 §6.21: constant velocity contouring.

The contouring engine (:mod:`omsd.engine.contour`) is imported by the handlers that use it: a
board that never contours never loads it (start-up; tests/test_import_boundaries.py)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.table import handles
from omsd.engine.axis import Axis, Motion
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

if TYPE_CHECKING:
    from omsd.engine.contour import ContourDefinition

# -- 6.21 contouring ------------------------------------------------------------------------------


@handles("CV")
def _cv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Changing this parameter will make any previously defined contours invalid."
    raw = ix.one(cmd)
    assert raw is not None
    v = ix.check("CV", float(raw))
    ix.machine.contour_velocity = v
    if ix.machine.contour is not None:
        ix.machine.contour.valid = False


@handles("CD")
def _cd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    from omsd.engine.contour import ContourDefinition

    machine = ix.machine
    if machine.model.contour_queue <= 0:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    start = ix.per_axis(cmd)
    if not start:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    axes = tuple(sorted(start))
    # the start "in absolute units": each held to the position range (its row)
    positions = tuple(ix.check("CD", ix.convert(machine.axes[i], start[i], "dist")) for i in axes)
    ix.contour = ContourDefinition(
        axes=axes,
        start=positions,
        velocity=machine.contour_velocity,
        capacity=machine.model.contour_queue,
    )
    machine.contour = None


def contour_line(ix: Interpreter, cmd: Command, cell: Cell) -> None:
    """MT inside a contour: "only the axes being used in the contour must be provided"."""
    from omsd.engine.contour import Line

    defn = ix.contour
    assert defn is not None
    fields = ix.per_axis(cmd, list(defn.axes))
    target = tuple(
        ix.check("MT", ix.convert(ix.machine.axes[a], fields[a], "dist")) if a in fields else None
        for a in defn.axes
    )
    slots = ix.cost(cell, ix.axis, contour_axes=len(defn.axes))
    if not defn.add(Line(target), slots):
        raise CommandFailed(ErrorKind.CONTOUR_FULL)


@handles("CR")
def _cr(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Attempting to do circular interpolation in a contour which is being defined for more than
    # 2 axes will be flagged as a command error."
    from omsd.engine.contour import Arc

    defn = ix.contour
    assert defn is not None
    if len(defn.axes) != 2:
        raise CommandFailed(ErrorKind.CIRCULAR_AXES)
    xc, yc, angle = ix.required(cmd, 3)
    ax, ay = (ix.machine.axes[i] for i in defn.axes)
    center = (
        ix.check("CR", ix.convert(ax, xc, "dist"), 1),
        ix.check("CR", ix.convert(ay, yc, "dist"), 2),
    )
    if not defn.add(Arc(center, float(ix.check("CR", angle, 3))), ix.cost(cell, ix.axis)):
        raise CommandFailed(ErrorKind.CONTOUR_FULL)


@handles("CE", "CK")
def _ce(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    defn = ix.contour
    assert defn is not None
    if not defn.add(None, ix.cost(cell, ix.axis)):
        raise CommandFailed(ErrorKind.CONTOUR_FULL)
    defn.end = cmd.mnemonic
    ix.machine.contour = defn
    ix.contour = None
    ix.mode = "AA"


def runnable_contour(ix: Interpreter) -> ContourDefinition:
    """The defined contour CX (and the PCIx's CG) may run: "The CX command cannot be placed
    within a loop or while construct."."""
    defn = ix.machine.contour
    if defn is None or not defn.valid:
        raise CommandFailed(ErrorKind.NO_CONTOUR)
    if ix.in_loop(list(ix.machine.axes)):
        raise CommandFailed(ErrorKind.NOT_IN_LOOP)
    return defn


def contour_task(ix: Interpreter, defn: ContourDefinition) -> list[Axis]:
    """The axes whose queues CX (and the PCIx's CG) goes to and meets in: every axis in AA, as
    an AA GO; in AM the contour's own, as an AM GO meets only the axes of its move ("a task may
    be performing coordination motion on 2 axes, while a second task is performing unrelated
    but simultaneous motion on another axis"). In AM the contour is then the task's most recent
    move, the one an ID, II or IP after it speaks for ("In the AM mode, only the axes active in
    the most recent move will set their done flags"), as an AM move's axes are."""
    axes = ix.machine.axes
    if ix.mode == "AM":
        ix.last_move = sorted(defn.axes)
        return [axes[i] for i in defn.axes]
    return list(axes)


@handles("CX")
def _cx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    defn = runnable_contour(ix)
    members = contour_task(ix, defn)
    group = SyncGroup({a.index for a in members})
    group.action = lambda g, when: run_contour(ix, defn, when, "CX")
    ix.enqueue([(a, Op("CX", (), ix.cost(cell, a), group)) for a in members])


def run_contour(ix: Interpreter, defn: ContourDefinition, t: float, command: str) -> None:
    """Start the contour on its axes, which ``command`` (CX, the PCIx's CG) ends the position
    hold and slip detection of as the dialect says (the PCIx's HN: "CG, CX")."""
    from omsd.engine.contour import plan

    machine = ix.machine
    tick = machine.clock.at_or_after(t)
    axes = [machine.axes[i] for i in defn.axes]
    for a in axes:
        machine.executor.cancel(a, command)
    here = {a.index: a.position(tick) for a in axes}
    decel = min(a.ac for a in axes)
    p = plan(defn, here, decel)
    ix.contour_lead.update(p.lead_in)  # (in AM another task's contour may still be running)
    for a in axes:
        a.begin(tick, p.pieces[a.index], Motion.CONTOUR, final=p.finals[a.index])
        machine.executor.power_on(a)
        v = a.traj.velocity(a.traj.end_time - 1e-9) if a.traj.pieces else 0.0
        if v:
            a.direction = 1 if v > 0 else -1
    lead = axes[0]
    for offset, out in p.outputs:
        when = machine.clock.at_or_after(tick + offset)
        lead.outputs.append((when, (out.kind, out.target, out.low)))
    lead.outputs.sort(key=lambda item: item[0])
    lead.invalidate()
