"""The shared language, PC48 §6.7, §6.8, §6.11 and §6.20: move specification and execution,
homing and the velocity staircase."""

from __future__ import annotations

import math
from decimal import Decimal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.contour import contour_line
from omsd.dialects.shared.sync import task_axes
from omsd.dialects.shared.table import handles
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis, Motion
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- 6.7 move specification -----------------------------------------------------------------------


_PARAMETER_KIND = {"AC": "acc", "VL": "vel", "VB": "vel"}


@handles("AC", "VL", "VB")
def _parameter(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """AC, VL, VB: the value in steps (user units applied) against the row ("must be greater
    than zero (zero is not valid) and less than 8,000,000", "greater than zero and less than or
    equal to 1,044,000", VB "less than the programmed velocity")."""
    code = cmd.mnemonic
    items = {ix.axis_index: ix.one(cmd)} if ix.mode == "single" else dict(ix.per_axis(cmd))
    ops = []
    for index, raw in items.items():
        axis = ix.machine.axes[index]
        assert raw is not None
        value = ix.check(code, ix.convert(axis, raw, _PARAMETER_KIND[code]))
        ops.append((axis, Op(code, (value,), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("LP")
def _lp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "If no parameter is supplied, the value of zero is used." Range ±33,554,431. (The VS4
    # manual also shows ``AA LP1000``: "would load the X axis position register with 1000".)
    if ix.mode == "single":
        raw = ix.one(cmd, required=False)
        items = {ix.axis_index: raw if raw is not None else Decimal(0)}
    else:
        items = ix.per_axis(cmd)
    ops = []
    for index, raw_value in items.items():
        axis = ix.machine.axes[index]
        value = _steps(ix, axis, raw_value, "LP")
        ops.append((axis, Op("LP", (value,), ix.cost(cell, axis))))
    ix.enqueue(ops)


def _check_target(ix: Interpreter, value: float, mnemonic: str, operand: int = 1) -> float:
    """A position or distance in steps against its row (the position range)."""
    return ix.check(mnemonic, value, operand)


def _steps(ix: Interpreter, axis: Axis, raw: Decimal, mnemonic: str) -> float:
    """A position or distance the engine takes to whole motor steps (``Operands.convert``'s
    "steps": with user units, the fraction is kept for the encoder ratio), checked against its
    row as the whole number of counts it was always checked as (``UU0.5 LP67108863`` is
    33,554,431.5 counts, and loads 33,554,431)."""
    value = ix.convert(axis, raw, "steps")
    ix.check(mnemonic, float(math.trunc(value)))
    return value


@handles("MA", "MR", "ML", "MT")
def _move(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    code = cmd.mnemonic
    machine = ix.machine
    if ix.contour is not None:
        contour_line(ix, cmd, cell)
        return
    cosine = ix.machine.ramp.kind is pf.RampKind.COSINE
    if code in ("MA", "MT") and cosine and ix.in_loop(ix.context_axes()):
        # "absolute moves, such as MA and MT, cannot be used within loops ... while the board is
        # in the cosine (CN) velocity profile mode"
        raise CommandFailed(ErrorKind.NOT_IN_LOOP)
    if code == "MT" and (ix.in_loop(ix.context_axes()) or ix.mt_blocked):
        raise CommandFailed(ErrorKind.NOT_IN_LOOP)
    if ix.mode == "single":
        raw = ix.one(cmd, required=code == "MR")
        items = {ix.axis_index: raw if raw is not None else Decimal(0)}
    else:
        items = dict(ix.per_axis(cmd))
    group = SyncGroup(set(items), barrier=False) if code in ("ML", "MT") else None
    values = {index: _steps(ix, machine.axes[index], raw, code) for index, raw in items.items()}
    follower = ix.commands[code].follower
    followers = _followers(ix, code, values, t) if follower is not None else set()
    ops = []
    for index, value in values.items():
        axis = machine.axes[index]
        slots = ix.cost(cell, axis)
        if follower is not None and index in followers:
            slots += ix.cost(follower, axis)
        ops.append((axis, Op(code, (value,), slots, group)))
    ix.enqueue(ops)
    if ix.mode != "single":
        ix.last_move = sorted(items)
    else:
        ix.last_move = [ix.axis_index]


def _followers(ix: Interpreter, code: str, values: dict[int, float], t: float) -> set[int]:
    """The axes of a linear move (ML, MT) other than its master, as the command is read: the
    master is the axis with the longest move time at its own VL, AC, VB and ramp ("All axes are
    scaled to the axis with the longest move time (the master axis)", as
    ``Executor._interpolate`` picks it when the move starts), an MT's distance from where the
    axis is now. An axis the move leaves where it is has nothing modified."""
    distance: dict[int, float] = {}
    for index, value in values.items():
        axis = ix.machine.axes[index]
        target = axis.to_motor(value)
        d = abs(math.trunc(target) if code == "ML" else math.trunc(target) - axis.position(t))
        if d > 0:
            distance[index] = float(d)
    if not distance:
        return set()

    def move_time(index: int) -> float:
        a = ix.machine.axes[index]
        return pf.move_time(distance[index], a.vl, a.ac, a.base_velocity, a.ramp)

    master = max(sorted(distance), key=move_time)
    return set(distance) - {master}


@handles("RM")
def _rm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "The parameter must be greater than zero and less than 65,000."
    n = ix.integer(ix.one(cmd), "RM")
    ix.enqueue([(ix.axis, Op("RM", (n,), ix.cost(cell, ix.axis)))])


# -- 6.8 move execution ---------------------------------------------------------------------------


def _go_extra(ix: Interpreter, index: int) -> int:
    """PA adds 2 and SE 3 slots to each GO/GD (PC48 §6.6; the PCIx's GO and GD tables print them
    as add-ons, which ``Interpreter.cost`` charges from the mode in force, and its PA and SE
    leave ``pa_entered`` and ``se_entered`` alone). SE's are charged whether PA is on or not:
    "The use of this command requires 3 queue slots with the execution of each GO or GD
    command", as the PCIx's "If an auxiliary output bit settle time has been specified add 3"."""
    extra = 0
    if ix.pa_entered[index]:
        extra += 2
    if ix.se_entered[index]:
        extra += 3
    return extra


@handles("GO", "GD")
def _go(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    machine = ix.machine
    if ix.mode == "single":
        axis = ix.axis
        slots = ix.cost(cell, axis) + _go_extra(ix, axis.index)
        ix.enqueue([(axis, Op(cmd.mnemonic, (), slots))])
        return
    # AA: every axis meets at the GO ("Each axis programmed to move will start together upon
    # executing the GO command"); AM: only the axes of the task just specified.
    members = task_axes(ix)
    group = SyncGroup(set(members))
    group.action = machine.executor.go_action
    group.data["gd"] = cmd.mnemonic == "GD"
    group.data["all"] = ix.mode == "AA"
    ops = []
    for index in members:
        axis = machine.axes[index]
        slots = ix.cost(cell, axis) + _go_extra(ix, index)
        ops.append((axis, Op(cmd.mnemonic, (), slots, group)))
    ix.enqueue(ops)


@handles("JG", "JF")
def _jog(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # single-axis on the PC48; the PCIx also takes ``JG#,#,#,#;`` in AA/AM
    items = ix.items(cmd)
    ops = []
    for index, value in items.items():
        axis = ix.machine.axes[index]
        v = ix.convert(axis, value, "frac" if cmd.mnemonic == "JF" else "vel")
        ix.check(cmd.mnemonic, v)
        ops.append((axis, Op(cmd.mnemonic, (v,), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("VS")
def _vs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    samples, vx, vy = ix.fields(cmd, 3)
    n = ix.integer(samples, "VS", 1)
    axis = ix.axis
    vx_f = ix.convert(axis, vx, "vel") if vx is not None else 0.0
    y = ix.machine.axis_by_letter("Y")
    vy_f = ix.convert(y, vy, "vel") if (vy is not None and y is not None) else 0.0
    ix.check("VS", vx_f, 2)
    ix.check("VS", vy_f, 3)
    ix.enqueue([(axis, Op("VS", (n, vx_f, vy_f), ix.cost(cell, axis)))])


# -- 6.11 home ------------------------------------------------------------------------------------


@handles("HM", "HR")
def _home(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The current axis, or in AA/AM (the PCIx: ``HM#,#,#,#;``, "Parameters must be specified
    in multi-axis modes to inform the PCIx which axes are to be homed") each axis given."""
    if ix.mode == "single":
        items: dict[int, Decimal | None] = {ix.axis_index: ix.one(cmd, required=False)}
    else:
        items = dict(ix.per_axis(cmd))
        if not items:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    direction = 1 if cmd.mnemonic == "HM" else -1
    ops = []
    for index, raw in items.items():
        axis = ix.machine.axes[index]
        # a position as LP's: with user units the fraction is kept for the encoder ratio
        # (ER1000,2000 UU0.5 HM601 loads 601 steps, as LP601; truncated to whole counts first
        # it loaded 600, and HM's "move absolute to the same position" went a step past home)
        value = _steps(ix, axis, raw, cmd.mnemonic) if raw is not None else 0.0
        ops.append((axis, Op("HM", (value, False, direction), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("KM", "KR")
def _home_kill(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    direction = 1 if cmd.mnemonic == "KM" else -1
    ix.enqueue([(axis, Op("HM", (0.0, True, direction), ix.cost(cell, axis)))])


# -- 6.20 velocity staircase ----------------------------------------------------------------------


@handles("MP", "MM")
def _direction(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Direction for MV and MO: immediate on the PC48, one queued slot on the VS4."""
    direction = 1 if cmd.mnemonic == "MP" else -1
    if cell.kind is Kind.QUEUED:
        ix.enqueue([(ix.axis, Op("DIR", (direction,), ix.cost(cell, ix.axis)))])
        return
    for axis in ix.context_axes():
        if axis.motion is Motion.IDLE:
            axis.direction = direction


@handles("MV")
def _mv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    pos, vel = ix.required(cmd, 2)
    p = _check_target(ix, ix.convert(axis, pos, "dist"), "MV", 1)
    v = ix.check("MV", ix.convert(axis, vel, "vel"), 2)
    ix.enqueue([(axis, Op("MV", (p, v), ix.cost(cell, axis)))])


@handles("SP", "FP")
def _sp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    raw = ix.one(cmd)
    assert raw is not None
    p = _steps(ix, axis, raw, cmd.mnemonic)
    if cmd.mnemonic == "FP":
        # "flush the command queue and attempt to stop at the specified position"
        ix.machine.executor.flush(axis, t)
        axis.queue.append(Op("FP", (p,), ix.cost(cell, axis), source=ix.machine.input_source))
        return
    ix.enqueue([(axis, Op("SP", (p,), ix.cost(cell, axis)))])
