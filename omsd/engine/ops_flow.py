"""Queued flow: done flags and interrupts, loops, waits and meeting points (PC48 §6.10,
§6.12). Each op is ``fn(executor, axis, op, t)``; an op that carries a
:class:`~omsd.engine.queue.SyncGroup` meets the other axes of its group first."""

from __future__ import annotations

from omsd.engine.axis import Axis
from omsd.engine.executor import Executor, OpFunction, Result
from omsd.engine.queue import LoopFrame, Op
from omsd.engine.states import Motion, Wait

# -- completion flags -----------------------------------------------------------------------------


def _done(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is None:
        ex.machine.set_done([axis], t, interrupt=True)
        return None
    ex.machine.set_done([axis], t, interrupt=False)
    return ex.arrive(axis, op, t)


def _done_in_position(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.12: "like the ID command, except the interrupt is deferred until the stage is
    # within the specified deadband ... If the position hold HN is not enabled for an axis,
    # the command will behave like an ID command for that axis."
    machine = ex.machine
    group = op.group

    def done(when: float) -> None:
        if group is None:
            machine.set_done([axis], when, interrupt=True)
            return
        machine.set_done([axis], when, interrupt=False)
        group.arrive(axis.index)
        ex.check_group(group, when)

    if axis.hold and not (axis.in_position and axis.motion is Motion.IDLE):
        return Wait("inpos", then=done)
    done(t)
    return None


def _arm_interrupt(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    assert op.group is not None
    axis.in_arm = (axis.to_motor(op.args[0]), op.group)
    return None


# -- loops ----------------------------------------------------------------------------------------


def _loop_start(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    count = op.args[0] if op.code == "LS" else 0
    axis.queue.loops.append(LoopFrame(op.code, axis.queue.pc, count, t))
    return None


def _loop_count_end(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    frame = axis.queue.loops[-1] if axis.queue.loops else None
    if frame is None:
        return None
    frame.remaining -= 1
    return ex.loop_end(axis, frame.remaining > 0, t)


def _loop_input_end(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # "execute the commands between the WS and WD commands as a loop while the specified
    # general purpose input line is true, i.e. low ... The test is at the bottom"; args: the
    # bit and whether the loop goes on while it is high instead (the PCIx's WS#,state)
    if op.group is not None:
        return ex.arrive(axis, op, t)
    bit, while_high = op.args
    return ex.loop_end(axis, ex.machine.input_high(bit, t) == while_high, t)


def _loop_while_end(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is not None:
        return ex.arrive(axis, op, t)
    again = not ex.machine.front.take_while_flag(axis.index)
    return ex.loop_end(axis, again, t)


# -- waits and meeting points ---------------------------------------------------------------------


def _wait_time(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is not None:
        return ex.arrive(axis, op, t)
    return Wait("time", until=t + op.args[0] / 1000.0)


def _meet(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    return ex.arrive(axis, op, t)


def _wait_input(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # until the input is high; ``(bit, False)``: until it is low
    if op.group is not None:
        return ex.arrive(axis, op, t)
    return ex.wait_for_input(axis, op, t)


FLOW_OPS: dict[str, OpFunction] = {
    "ID": _done,
    "II": _done,
    "IP": _done_in_position,
    "IN": _arm_interrupt,
    "LS": _loop_start,
    "WS": _loop_start,
    "WH": _loop_start,
    "LE": _loop_count_end,
    "WD": _loop_input_end,
    "WG": _loop_while_end,
    "WT": _wait_time,
    "WA": _meet,
    "CX": _meet,
    "SW": _wait_input,
}
