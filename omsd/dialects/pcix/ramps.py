"""PCIx ramps: PF, PN, CN per board; LA, PR, SC, SR, SS per axis; custom ramp tables (DAR, DAB,
DAE, ?DA, ?DE, ?DS) and S-curve profiles (AJ, ?AJ) (PCIx §5.8, §5.12.1)."""

from __future__ import annotations

from collections.abc import Callable

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix import flash
from omsd.dialects.pcix.common import (
    apply_to,
    flag_axes,
    handles,
    one_integer,
    reply,
)
from omsd.dialects.pcix.interpreter import PcixInterpreter
from omsd.dialects.shared.modes import parabolic_steps
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- ramps: PF PN CN LA PR SC SR SS, DAR DAB DAE, AJ ----------------------------------------------


def _rampsetter(shape: Callable[[Axis], pf.RampShape | None]) -> Callable[[Axis, float], None]:
    def apply(axis: Axis, t: float) -> None:
        new = shape(axis)
        if new is not None:
            axis.ramp = new

    return apply


def parabolic(steps: int) -> pf.RampShape:
    """PN/PR: "the acceleration starts at 100% and is reduced in 10% steps ... down to as low as
    10%": PN3 ends its ramp at 70% of AC, PN9 and PN10 at 10%."""
    return pf.RampShape(pf.RampKind.PARABOLIC, steps, floor=0.1)


@handles("PF")
def _pf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "All axes will use linear acceleration"."""
    apply_to(ix, cmd, cell, list(ix.machine.axes), _rampsetter(lambda a: pf.LINEAR), t)


@handles("CN")
def _cn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Cosine ramps for all axes, "even in single-axis mode"."""
    shape = pf.RampShape(pf.RampKind.COSINE)
    apply_to(ix, cmd, cell, list(ix.machine.axes), _rampsetter(lambda a: shape), t)


@handles("PN")
def _pn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    shape = parabolic(parabolic_steps(ix, ix.one(cmd, required=False), "PN"))
    apply_to(ix, cmd, cell, list(ix.machine.axes), _rampsetter(lambda a: shape), t)


@handles("LA")
def _la(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    apply_to(ix, cmd, cell, flag_axes(ix, cmd), _rampsetter(lambda a: pf.LINEAR), t)


@handles("SC")
def _sc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    shape = pf.RampShape(pf.RampKind.COSINE)
    apply_to(ix, cmd, cell, flag_axes(ix, cmd), _rampsetter(lambda a: shape), t)


@handles("PR")
def _pr(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Parabolic ramps per axis: ``PR#;`` or ``PR#,#,#,#;`` (3..10 steps)."""
    if ix.mode == "single":
        items = {ix.axis_index: ix.one(cmd, required=False)}
    else:
        items = dict(ix.per_axis(cmd))
    ops = []
    for index, value in items.items():
        # "similar to the PN command": out of range or left out, 3 steps
        shape = parabolic(parabolic_steps(ix, value, "PR"))
        axis = ix.machine.axes[index]
        apply = _rampsetter(lambda a, s=shape: s)  # type: ignore[misc]
        ops.append((axis, Op("SET", ("PR", apply), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("SR")
def _sr(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "SR# selects custom ramp table # for the current axis" (1..4); a table never defined
    is an error rather than the manual's "unpredictable"."""
    n = one_integer(ix, cmd)
    shape = flash.custom_ramp(ix.machine, n)
    if shape is None:
        raise CommandFailed(ErrorKind.NO_TABLE)
    axis = ix.axis
    # "7 + (2* number of segments in ramp definition)": the segments of the table selected
    slots = ix.cost(cell, axis) + 2 * shape.segments
    ix.enqueue([(axis, Op("SET", ("SR", _rampsetter(lambda a: shape)), slots))])


@handles("SS")
def _ss(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "SS# selects the S-curve profile #" defined by AJ."""
    n = one_integer(ix, cmd)
    shape = flash.scurve_ramp(ix.machine, n)
    if shape is None:
        raise CommandFailed(ErrorKind.NO_TABLE)
    axis = ix.axis
    ix.enqueue([(axis, Op("SET", ("SS", _rampsetter(lambda a: shape)), ix.cost(cell, axis)))])


@handles("?RT")
def _q_rt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Ramp type of the current axis: "LA", "PRn", "SC", "SRn", "SSn" (``sr3``)."""
    ramp = ix.axis.ramp
    kind = ramp.kind
    if kind is pf.RampKind.LINEAR:
        text = "la"
    elif kind is pf.RampKind.PARABOLIC:
        text = f"pr{ramp.steps}"
    elif kind is pf.RampKind.COSINE:
        text = "sc"
    elif kind is pf.RampKind.CUSTOM:
        text = f"sr{ramp.table}"
    else:
        text = f"ss{ramp.table}"
    reply(ix, text, t)


MAX_BREAKPOINTS = 25


@handles("DAR")
def _dar(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "DAR# begins the definition of custom ramp table #" (1..4); "until the DAE command is
    entered, only the DAB and DAE commands will be valid" (others set the command-error flag
    and are ignored)."""
    ix.begin_table(one_integer(ix, cmd))


@handles("DAB")
def _dab(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.table is None:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    accel, velocity = ix.required(cmd, 2)
    ix.check("DAB", accel, 1)
    ix.check("DAB", velocity, 2)
    if len(ix.table_points) >= MAX_BREAKPOINTS:
        raise CommandFailed(ErrorKind.TABLE_FULL)
    ix.table_points.append((float(accel), float(velocity)))


@handles("DAE")
def _dae(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.table is None:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    if ix.table_points:
        ix.machine.ramp_tables[ix.table] = list(ix.table_points)
    else:  # "An empty table is invalid": the table is left undefined
        ix.machine.ramp_tables.pop(ix.table, None)
    ix.end_table()


def _table_number(ix: Interpreter, cmd: Command) -> int:
    return one_integer(ix, cmd)


def _dab_line(point: tuple[float, float]) -> str:
    return f"DAB{point[0]:.5f},{point[1]:.5f}"


@handles("?DA")
def _q_da(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The table as the commands that would enter it, one per line."""
    n = _table_number(ix, cmd)
    points = ix.machine.ramp_tables.get(n, [])
    for line in (f"DAR{n}", *(_dab_line(p) for p in points), "DAE"):
        reply(ix, line, t)


@handles("?DE")
def _q_de(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    table, entry = ix.required(cmd, 2)
    n, k = ix.integer(table, "?DE", 1), ix.integer(entry, "?DE", 2)
    points = ix.machine.ramp_tables.get(n, [])
    reply(ix, _dab_line(points[k - 1]) if k <= len(points) else "", t)


@handles("?DS")
def _q_ds(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    n = _table_number(ix, cmd)
    reply(ix, f"ds{len(ix.machine.ramp_tables.get(n, []))}", t)


@handles("AJ")
def _aj(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """``AJ#[,ALOWER][,APEAK][,ARADIUS][,DLOWER][,DPEAK][,DRADIUS];`` defines S-curve profile
    # (1 to the number of axes). Defaults: ALOWER 0, APEAK = ALOWER, ARADIUS 1; "If the
    parameters are not given to define regions 6, 7, 8, and 9, they will be symmetrical with
    regions 4, 3, 2, and 1"."""
    values = ix.fields(cmd, 7)
    if values[0] is None:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    n = ix.integer(values[0], "AJ", 1)
    for operand, v in enumerate(values[1:], start=2):
        if v is not None:
            ix.check("AJ", v, operand)
    lo, peak, radius, dlo, dpeak, dradius = values[1:]
    alower = float(lo) if lo is not None else 0.0
    apeak = float(peak) if peak is not None else alower
    aradius = float(radius) if radius is not None else 1.0
    dlower = float(dlo) if dlo is not None else alower
    dpeak_f = float(dpeak) if dpeak is not None else (dlower if dlo is not None else apeak)
    dradius_f = float(dradius) if dradius is not None else aradius
    ix.machine.scurves[n] = pf.SCurve(alower, apeak, aradius, dlower, dpeak_f, dradius_f)


@handles("?AJ")
def _q_aj(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    n = one_integer(ix, cmd)
    curve = ix.machine.scurves.get(n, pf.SCurve())
    values = (curve.alower, curve.apeak, curve.aradius, curve.dlower, curve.dpeak, curve.dradius)
    reply(ix, ",".join([f"{n:.7f}", *(f"{v:.8f}" for v in values)]), t)
