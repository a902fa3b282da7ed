"""PCIx stops (KS, SI, FL) and contours (CG, NV, MT after CG) (PCIx manual §5.4.4, §5.9.4,
§5.9.8). NV's retiming is the engine's (:mod:`omsd.engine.retime`).

Stops
    * SI (§5.9.4): single axis "behaves identically to ST"; multi-axis "Any non-zero value in a
      parameter will cause the corresponding axis to be stopped" (flush, ramp down at AC).
    * KS: "the same operation as the KL (kill) command except that individual axes can be killed
      ... KS will flush only the selected axes' command queues"; "null values in the argument
      list specify that motion on that axis is not to be killed" (so ``AA KS;`` kills nothing).
    * FL (§5.4.4): "All unexecuted commands remaining in the current axis queue will be flushed
      ... current motion will remain unaffected" (an IN armed for the running move stays armed).

Contours
    * CG (§5.9.8): CX, but "the following MT commands will be on hold until the contour execution
      is complete": an MT received after CG waits (holding the interpreter, like a full queue)
      until every axis has finished the contour (this module's MT handler wraps the shared one to
      do it). CG cancels stepper position maintenance on the contour's axes (the HN page: "CG,
      CX").
    * NV (§5.9.8, "AA/CD Immediate"): "set a new velocity for a contour currently in execution
      ... the PCIX will switch to the new velocity at the start of the next command in the
      contour queue without ramping. An NV command issued without a contour currently executing
      will have no effect." The segments after the one being run go at the new speed (the
      final CE ramp down starts from it, at the same deceleration), and the contour's AN/AF/BH/BL
      actions move with them.
"""

from __future__ import annotations

from omsd.dialects.interpreter import Blocked, CommandFailed, Interpreter
from omsd.dialects.pcix.common import (
    executes,
    handles,
)
from omsd.dialects.shared import HANDLERS
from omsd.dialects.shared.contour import contour_task, run_contour, runnable_contour
from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.executor import Executor, Result
from omsd.engine.queue import Op, SyncGroup
from omsd.engine.retime import new_contour_velocity
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- stops and kills ------------------------------------------------------------------------------


def _selected(ix: Interpreter, cmd: Command, nonzero: bool) -> list[Axis]:
    if ix.mode == "single":
        if cmd.fields:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        return [ix.axis]
    picked = ix.per_axis(cmd)
    return [ix.machine.axes[i] for i, v in sorted(picked.items()) if v != 0 or not nonzero]


def _stop(ix: Interpreter, axes: list[Axis], cell: Cell, t: float, kill: bool) -> None:
    executor = ix.machine.executor
    for axis in axes:
        executor.flush(axis, t)
        axis.queue.append(
            Op("STOP", (kill, None), ix.cost(cell, axis), source=ix.machine.input_source)
        )


@handles("KS")
def _ks(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """KS / KSb,b,b,b (§5.9.4): KL for the selected axes only."""
    axes = _selected(ix, cmd, nonzero=False)
    for axis in axes:
        axis.halt(t)
    _stop(ix, axes, cell, t, kill=True)


@handles("SI")
def _si(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """SI / SIb,b,b,b (§5.9.4): ramp the selected axes to a stop at AC, flushing their queues."""
    _stop(ix, _selected(ix, cmd, nonzero=True), cell, t, kill=False)
    if ix.mode == "single":
        ix.mt_blocked = False  # as ST: "makes MT valid again"


@handles("FL")
def _fl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """FL (§5.4.4): flush the current axis's queue, leaving its motion alone."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    axis = ix.axis
    armed, fire = axis.in_arm, axis.in_fire
    ix.machine.executor.flush(axis, t)
    if axis.moving:
        axis.in_arm, axis.in_fire = armed, fire
    axis.invalidate()


# -- contours: CG, NV, and MT after CG ------------------------------------------------------------


@handles("CG")
def _cg(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """CG (§5.9.8): "a form of the CX command"; a marker after it in each of its queues (every
    axis's in AA, the contour's in AM: ``contour_task``) holds MT."""
    defn = runnable_contour(ix)
    members = contour_task(ix, defn)
    group = SyncGroup({a.index for a in members})
    group.action = lambda g, when: run_contour(ix, defn, when, "CG")
    items: list[tuple[Axis, Op]] = []
    for axis in members:
        items.append((axis, Op("CX", (), ix.cost(cell, axis), group)))
        items.append((axis, Op("CGEND", (), 0)))
    ix.enqueue(items)


@executes("CGEND")
def _op_cgend(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    return None


def contour_pending(machine: Core) -> bool:
    """A CG's contour has not finished on some axis (its marker is still queued)."""
    return any(
        op.code == "CGEND" for axis in machine.axes for op in axis.queue.program[axis.queue.pc :]
    )


@handles("MT")
def _mt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """MT as the shared language handles it, held while a CG contour runs (see CG)."""
    if ix.contour is None and contour_pending(ix.machine):
        raise Blocked
    HANDLERS["MT"](ix, cmd, cell, t)


@handles("NV")
def _nv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """NV# (§5.9.8): "1 ≤ NV ≤ 1,043,999"; the executing contour's next segments go at it."""
    raw = ix.one(cmd)
    assert raw is not None
    velocity = ix.check("NV", float(raw))
    new_contour_velocity(ix.machine.axes, velocity, t)
