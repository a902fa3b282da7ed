"""The PCIx's own commands and the ones whose meaning changed from the PC48 (PCIx manual ch. 5).

Commands the PCIx shares with the older boards keep their handlers in
:mod:`omsd.board.commands`; the handlers here replace or add to them for the ``pcix`` dialect
(:mod:`omsd.board.dialect`). Motion commands new to the PCIx (gearing, GU, SO, TM, TL, ...)
are in :mod:`omsd.board.pcix_motion`.

Queries ``?XX`` answer ``xx<value>`` in lower case, as every example prints them (``ac200000``,
``kp10.00``, ``hs``). Where the manual prints only one of two answers the other is the
obvious pair (``?AB`` ``an``/``af``, ``?DB`` ``dbi``/``dbn``, ``?HM`` ``hs``/``he``, ``?LM``
``ln``/``lf``, ``?PM`` ``hn``/``hf``, ``?SK`` ``tn``/``tf``, ``?SL`` ``sl``/``sf``). Choices where
the manual says nothing:

* ``?PA`` with power automatic off answers ``paf`` (the manual prints only ``pa0``).
* ``?ER`` prints motor steps per encoder count with one decimal or as many as needed
  (``ER1,2`` -> ``er2.0``, ``ER3,2`` -> ``er0.666667``).
* ``?DE`` of an entry that exists answers it as ``?DA`` lists it (``DAB0.10000,0.20000``).
* ``?AJ`` prints the profile number with seven decimals and the six parameters with eight, as
  the example does (``5.0000000,0.50000000,...``).
* Gains print with two decimals (``kp10.00``), KF, KU and KO as integers (``kf12``, ``ku150``,
  ``ko218``), as printed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from decimal import Decimal

from omsd.board import flash
from omsd.board import profiles as pf
from omsd.board.axis import Axis
from omsd.board.commands import Handler, parabolic_steps, registrar
from omsd.board.events import ErrorKind
from omsd.board.interpreter import CommandFailed, Interpreter
from omsd.board.macros import MacroCapture
from omsd.board.queue import Op, SyncGroup
from omsd.board.servo import ServoGains
from omsd.models.spec import Cell, Kind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import parse_number

PCIX_HANDLERS: dict[str, Handler] = {}


handles = registrar(PCIX_HANDLERS)


# -- helpers --------------------------------------------------------------------------------------


def _flag_axes(ix: Interpreter, cmd: Command) -> list[Axis]:
    """``LN;`` / ``LNb,b,b,b;``: the current axis in single-axis mode; in AA/AM "If a parameter
    exists for an axis, then the command affects that axis" (no parameters at all: every axis)."""
    if ix.mode == "single" and ix.contour is None:
        if cmd.fields and any(f is not None for f in cmd.fields):
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        return [ix.axis]
    if not cmd.fields:
        return list(ix.board.axes)
    picked: list[Axis] = []
    for i, text in enumerate(cmd.fields):
        if i < len(ix.board.axes) and text is not None:
            parse_number(text)
            picked.append(ix.board.axes[i])
    return picked


def _apply(
    ix: Interpreter,
    cmd: Command,
    cell: Cell,
    axes: list[Axis],
    apply: Callable[[Axis, float], None],
    t: float,
) -> None:
    """Do ``apply`` now (immediate commands) or when each axis reaches it in its queue."""
    if cell.kind is Kind.IMMEDIATE:
        for a in axes:
            apply(a, t)
        return
    ix.enqueue([(a, Op("SET", (cmd.mnemonic, apply), ix.cost(cell, a))) for a in axes])


def _flag(apply: Callable[[Axis, float], None]) -> Handler:
    def handler(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
        _apply(ix, cmd, cell, _flag_axes(ix, cmd), apply, t)

    return handler


def _one_value(ix: Interpreter, cmd: Command) -> Decimal:
    """The command's one decimal operand, checked against its range row."""
    value = ix.one(cmd)
    assert value is not None
    return ix.check(cmd.mnemonic, value)


def _one_integer(ix: Interpreter, cmd: Command) -> int:
    """The command's one whole-number operand (truncated), checked against its range row."""
    return ix.integer(ix.one(cmd), cmd.mnemonic)


def _reply(ix: Interpreter, text: str, t: float) -> None:
    ix.board.reply_value(text, t)


def _fixed(value: float, places: int) -> str:
    return f"{value:.{places}f}"


# -- axis selection and modes ---------------------------------------------------------------------


@handles("?AQ")
def _aq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "reports the mode that the current axis is in, i.e. AA mode, AM mode, etc." (``ax``)."""
    mode = ix.mode
    _reply(ix, ("a" + ix.axis.letter.lower()) if mode == "single" else mode.lower(), t)


# -- flash: AP, RD, RF, ADH, ADL ------------------------------------------------------------------


@handles("AP")
def _ap(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "The AP command stores the current parameter set as the power-up default set"."""
    ix.board.write_flash(flash.board_parameters(ix.board))


@handles("RD")
def _rd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "restores the motion parameters using power-up defaults" (the factory values where AP
    was never used)."""
    ix.board.load_flash()


@handles("RF")
def _rf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "sets the current parameters to the factory defaults. This process does not alter the
    parameters stored in flash via the AP command"."""
    flash.factory(ix.board)


@handles("ADH", "ADL")
def _ad(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The auxiliary output's power-up state; "This command will also archive all other
    parameter values as power up defaults"."""
    ix.axis.aux_default_high = cmd.mnemonic == "ADH"
    ix.board.write_flash(flash.board_parameters(ix.board))


@handles("?AD")
def _q_ad(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _reply(ix, "adh" if ix.axis.aux_default_high else "adl", t)


# -- macros ---------------------------------------------------------------------------------------


def _macro_number(ix: Interpreter, cmd: Command) -> int:
    """MD "0 ≤ MD ≤ 4", MX "0 ≤ MX ≤ 24", PM "0 ≤ PM ≤ 24" (their range rows)."""
    return _one_integer(ix, cmd)


@handles("MD")
def _md(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "MD# ... the number must be from 0 to 4": what follows, up to Control-Z or ``^Z``, is
    the macro."""
    ix.capture = MacroCapture(_macro_number(ix, cmd))


@handles("MX")
def _mx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    text = ix.macros.get(_macro_number(ix, cmd))
    if text is None:
        raise CommandFailed(ErrorKind.NO_MACRO)
    ix.run_macro(text)


@handles("PM")
def _pm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "returns the contents of the specified macro"; nothing when it is empty."""
    text = ix.macros.get(_macro_number(ix, cmd))
    if text is not None:
        _reply(ix, text.decode("latin-1"), t)


@handles("PT")
def _pt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "PT#,#; copies temporary macro # (0-4) to permanent macro # (5-24)"."""
    src, dst = ix.required(cmd, 2)
    n, m = ix.integer(src, "PT", 1), ix.integer(dst, "PT", 2)
    text = ix.macros.get(n)
    if text is None:
        raise CommandFailed(ErrorKind.NO_MACRO)
    ix.macros.define(m, text)
    ix.board.write_flash()


# -- ramps: PF PN CN LA PR SC SR SS, DAR DAB DAE, AJ ----------------------------------------------


def _ramp_setter(shape: Callable[[Axis], pf.RampShape | None]) -> Callable[[Axis, float], None]:
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
    _apply(ix, cmd, cell, list(ix.board.axes), _ramp_setter(lambda a: pf.LINEAR), t)


@handles("CN")
def _cn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Cosine ramps for all axes, "even in single-axis mode"."""
    shape = pf.RampShape(pf.RampKind.COSINE)
    _apply(ix, cmd, cell, list(ix.board.axes), _ramp_setter(lambda a: shape), t)


@handles("PN")
def _pn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    shape = parabolic(parabolic_steps(ix, ix.one(cmd, required=False), "PN"))
    _apply(ix, cmd, cell, list(ix.board.axes), _ramp_setter(lambda a: shape), t)


@handles("LA")
def _la(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _apply(ix, cmd, cell, _flag_axes(ix, cmd), _ramp_setter(lambda a: pf.LINEAR), t)


@handles("SC")
def _sc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    shape = pf.RampShape(pf.RampKind.COSINE)
    _apply(ix, cmd, cell, _flag_axes(ix, cmd), _ramp_setter(lambda a: shape), t)


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
        axis = ix.board.axes[index]
        apply = _ramp_setter(lambda a, s=shape: s)  # type: ignore[misc]
        ops.append((axis, Op("SET", ("PR", apply), ix.cost(cell, axis))))
    ix.enqueue(ops)


@handles("SR")
def _sr(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "SR# selects custom ramp table # for the current axis" (1..4); a table never defined
    is an error rather than the manual's "unpredictable"."""
    n = _one_integer(ix, cmd)
    shape = flash.custom_ramp(ix.board, n)
    if shape is None:
        raise CommandFailed(ErrorKind.NO_TABLE)
    axis = ix.axis
    # "7 + (2* number of segments in ramp definition)": the segments of the table selected
    slots = ix.cost(cell, axis) + 2 * shape.segments
    ix.enqueue([(axis, Op("SET", ("SR", _ramp_setter(lambda a: shape)), slots))])


@handles("SS")
def _ss(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "SS# selects the S-curve profile #" defined by AJ."""
    n = _one_integer(ix, cmd)
    shape = flash.scurve_ramp(ix.board, n)
    if shape is None:
        raise CommandFailed(ErrorKind.NO_TABLE)
    axis = ix.axis
    ix.enqueue([(axis, Op("SET", ("SS", _ramp_setter(lambda a: shape)), ix.cost(cell, axis)))])


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
    _reply(ix, text, t)


MAX_BREAKPOINTS = 25


@handles("DAR")
def _dar(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "DAR# begins the definition of custom ramp table #" (1..4); "until the DAE command is
    entered, only the DAB and DAE commands will be valid" (others set the command-error flag
    and are ignored)."""
    ix.table = _one_integer(ix, cmd)
    ix.table_points = []


@handles("DAB")
def _dab(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.table is None:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    accel, velocity = ix.required(cmd, 2)
    ix.check("DAB", accel, 1)
    ix.check("DAB", velocity, 2)
    if len(ix.table_points) >= MAX_BREAKPOINTS:
        raise CommandFailed(ErrorKind.TABLE_FULL)
    ix.table_points.append((float(accel), float(velocity)))


@handles("DAE")
def _dae(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.table is None:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    if ix.table_points:
        ix.board.ramp_tables[ix.table] = list(ix.table_points)
    else:  # "An empty table is invalid": the table is left undefined
        ix.board.ramp_tables.pop(ix.table, None)
    ix.table = None
    ix.table_points = []


def _table_number(ix: Interpreter, cmd: Command) -> int:
    return _one_integer(ix, cmd)


def _dab_line(point: tuple[float, float]) -> str:
    return f"DAB{point[0]:.5f},{point[1]:.5f}"


@handles("?DA")
def _q_da(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The table as the commands that would enter it, one per line."""
    n = _table_number(ix, cmd)
    points = ix.board.ramp_tables.get(n, [])
    for line in (f"DAR{n}", *(_dab_line(p) for p in points), "DAE"):
        _reply(ix, line, t)


@handles("?DE")
def _q_de(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    table, entry = ix.required(cmd, 2)
    n, k = ix.integer(table, "?DE", 1), ix.integer(entry, "?DE", 2)
    points = ix.board.ramp_tables.get(n, [])
    _reply(ix, _dab_line(points[k - 1]) if k <= len(points) else "", t)


@handles("?DS")
def _q_ds(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    n = _table_number(ix, cmd)
    _reply(ix, f"ds{len(ix.board.ramp_tables.get(n, []))}", t)


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
    ix.board.scurves[n] = pf.SCurve(alower, apeak, aradius, dlower, dpeak_f, dradius_f)


@handles("?AJ")
def _q_aj(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    n = _one_integer(ix, cmd)
    curve = ix.board.scurves.get(n, pf.SCurve())
    values = (curve.alower, curve.apeak, curve.aradius, curve.dlower, curve.dpeak, curve.dradius)
    _reply(ix, ",".join([f"{n:.7f}", *(f"{v:.8f}" for v in values)]), t)


# -- servo: gains, DAC mode, loop -----------------------------------------------------------------

# mnemonic -> (ServoGains field, places in the query reply; None = integer); the ranges are the
# rows of omsd.protocol.ranges_pcix ("RANGE: 0.00 ≤ KP ≤ 32767.00" ...)
_GAINS: dict[str, tuple[str, int | None]] = {
    "KP": ("kp", 2),
    "KI": ("ki", 2),
    "KD": ("kd", 2),
    "KV": ("kv", 2),
    "KA": ("ka", 2),
    "KB": ("kb", 2),
    "KF": ("kf", None),
    "KU": ("ku", None),
    "KO": ("ko", None),
    "DZ": ("dz", None),
}


def _set_gains(**changes: float | bool) -> Callable[[Axis, float], None]:
    def apply(axis: Axis, t: float) -> None:
        if axis.servo is not None:
            axis.servo_sync(t)
            axis.servo.set_gains(replace(axis.servo.gains, **changes))  # type: ignore[arg-type]
            axis.servo_last = None  # look at the loop again: it may run away now
            axis.invalidate()

    return apply


def _gain(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    name, places = _GAINS[cmd.mnemonic]
    number = float(_one_value(ix, cmd)) if places is not None else float(_one_integer(ix, cmd))
    _apply(ix, cmd, cell, [ix.axis], _set_gains(**{name: number}), t)


def _gain_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    mnemonic = cmd.mnemonic[1:]
    name, places = _GAINS[mnemonic]
    servo = ix.axis.servo
    value = float(getattr(servo.gains if servo is not None else ServoGains(), name))
    text = _fixed(value, places) if places is not None else str(math.trunc(value))
    _reply(ix, mnemonic.lower() + text, t)


for _m in _GAINS:
    PCIX_HANDLERS[_m] = _gain
    PCIX_HANDLERS["?" + _m] = _gain_query


@handles("BI", "UN")
def _bi(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Servo output ±10 V (BI) or 0..+10 V (UN)."""
    _apply(ix, cmd, cell, [ix.axis], _set_gains(bipolar=cmd.mnemonic == "BI"), t)


@handles("SVN", "SVI")
def _sv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Positive voltage for positive motion (SVN) or negative (SVI)."""
    _apply(ix, cmd, cell, [ix.axis], _set_gains(inverted=cmd.mnemonic == "SVI"), t)


def _servo_gains(axis: Axis) -> ServoGains:
    return axis.servo.gains if axis.servo is not None else ServoGains()


@handles("?SO")
def _q_so(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _reply(ix, "bi" if _servo_gains(ix.axis).bipolar else "un", t)


@handles("?SV")
def _q_sv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _reply(ix, "svi" if _servo_gains(ix.axis).inverted else "svn", t)


@handles("?PM")
def _q_pm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """PID (hold) state of the current axis: ``hn`` / ``hf`` (a stepper with an encoder: its
    position maintenance)."""
    axis = ix.axis
    on = axis.servo.closed if axis.servo is not None else axis.hold
    _reply(ix, "hn" if on else "hf", t)


@handles("HN", "HF")
def _hn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """HN closes a servo loop or starts a stepper's position maintenance; HF opens / stops it.
    ``HNb,b,b,b;`` in AA/AM: "a null value in the argument list specifies feedback for that axis
    is not to be" changed; with no list every axis with feedback (HF: "If the current mode is
    multi-axis, all axes will go into open-loop mode")."""
    axes = [a for a in _flag_axes(ix, cmd) if a.has_encoder]
    if ix.mode != "single" and not axes:
        return
    # HN: 1 unit, "2 for servo" axes
    extra = 1 if cmd.mnemonic == "HN" else 0
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a) + extra * a.is_servo)) for a in axes])


# -- simple axis parameters and their queries -----------------------------------------------------


def _setter(attr: str, value: object) -> Callable[[Axis, float], None]:
    def apply(axis: Axis, t: float) -> None:
        setattr(axis, attr, value)
        axis.invalidate()

    return apply


@handles("DBI", "DBN")
def _db(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    value = cmd.mnemonic == "DBI"
    _apply(ix, cmd, cell, _flag_axes(ix, cmd), _setter("direction_inverted", value), t)


@handles("LH", "LL")
def _lh(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    value = cmd.mnemonic == "LH"
    _apply(ix, cmd, cell, _flag_axes(ix, cmd), _setter("limit_high", value), t)


@handles("HH", "HL")
def _hh(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Home switch level; "The HL and HH commands are not valid" in the encoder home mode."""
    axes = _flag_axes(ix, cmd)
    if any(a.home_encoder for a in axes):
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    _apply(ix, cmd, cell, axes, _setter("home_high", cmd.mnemonic == "HH"), t)


@handles("HE", "HS")
def _he(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _apply(ix, cmd, cell, _flag_axes(ix, cmd), _setter("home_encoder", cmd.mnemonic == "HE"), t)


@handles("LN", "LF", "SL", "SF")
def _limits(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a))) for a in _flag_axes(ix, cmd)])


@handles("TN", "TF")
def _tn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Slip kill: a slip beyond ES kills the axis "as though a KL command had been issued"."""
    _apply(ix, cmd, cell, [ix.axis], _setter("slip_kill", cmd.mnemonic == "TN"), t)


@handles("DC")
def _dc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "1 ≤ DC ≤ 8000000": the deceleration GU uses."""
    axis = ix.axis
    raw = ix.one(cmd)
    assert raw is not None
    value = ix.check("DC", ix.convert(axis, raw, "acc"))
    _apply(ix, cmd, cell, [axis], _setter("dc", axis.to_motor(value)), t)


# the queries of one value: mnemonic -> reply text for the current axis
_QUERIES: dict[str, Callable[[Axis, float], str]] = {
    "?AB": lambda a, t: "an" if a.aux else "af",
    "?AC": lambda a, t: f"ac{math.trunc(a.ac)}",
    "?BC": lambda a, t: f"bc{a.backlash}",
    "?DB": lambda a, t: "dbi" if a.direction_inverted else "dbn",
    "?DC": lambda a, t: f"dc{math.trunc(a.dc)}",
    "?ES": lambda a, t: f"es{math.trunc(a.es)}",
    "?HD": lambda a, t: f"hd{math.trunc(a.hd)}",
    "?HG": lambda a, t: f"hg{math.trunc(a.hg)}",
    "?HV": lambda a, t: f"hv{math.trunc(a.hv)}",
    "?HM": lambda a, t: "he" if a.home_encoder else "hs",
    "?HS": lambda a, t: "hh" if a.home_high else "hl",
    "?LM": lambda a, t: "ln" if a.limits_on else "lf",
    "?LS": lambda a, t: "lh" if a.limit_high else "ll",
    "?PA": lambda a, t: "paf" if a.pa is None else ("pa0" if a.pa else "pa1"),
    "?SE": lambda a, t: f"se{a.se_ms}",
    "?SK": lambda a, t: "tn" if a.slip_kill else "tf",
    "?VB": lambda a, t: f"vb{math.trunc(a.vb)}",
    "?VL": lambda a, t: f"vl{math.trunc(a.vl)}",
}


def _query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _reply(ix, _QUERIES[cmd.mnemonic](ix.axis, t), t)


for _m in _QUERIES:
    PCIX_HANDLERS[_m] = _query


@handles("?SL")
def _q_sl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _reply(ix, "sl" if ix.axis.soft_limit else "sf", t)


@handles("UF")
def _uf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """User units off: ``UF;`` or ``UFb,b,b,b;`` ("equivalent to and preferred over UU1;")."""
    for axis in _flag_axes(ix, cmd):
        axis.uu = None


@handles("?ER")
def _q_er(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Motor steps per encoder count: ``ER1,2`` ("The encoder produces 1 count for every 2
    steps of the motor") answers ``er2.0``."""
    ratio = 1.0 / ix.axis.ratio
    text = f"{ratio:.6f}".rstrip("0")
    _reply(ix, "er" + (text + "0" if text.endswith(".") else text), t)


@handles("?UU")
def _q_uu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    uu = ix.axis.uu
    _reply(ix, "uf" if uu is None else f"uu{uu:.6f}", t)


# -- status and reports ---------------------------------------------------------------------------


@handles("RQ")
def _rq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Every axis's free queue units, whatever the mode: the example types ``RQ`` with no mode
    command (every other example that needs AA types ``AA;`` first) and gets "800, 800, 800,
    800"; "MAX value of command queue for all axes = 800". Inside a contour definition the
    contour queue (7160)."""
    if ix.contour is not None:
        _reply(ix, str(ix.contour.free), t)
    else:
        _reply(ix, ", ".join(str(a.queue.free) for a in ix.board.axes), t)


@handles("RC")
def _rc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "2000000, 2000000, 2000000, 2000000": the acceleration now, "zero when the stage is
    stopped or running at constant speed" (unlike the PC48, which reports the ramp's)."""
    axes = [ix.axis] if ix.mode == "single" else ix.board.axes
    _reply(ix, ", ".join(str(math.trunc(abs(a.acceleration(t)))) for a in axes), t)


@handles("RU")
def _ru(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "uu3.50000": the position in user units, five decimals."""
    axes = [ix.axis] if ix.mode == "single" else ix.board.axes
    texts = []
    for axis in axes:
        value = Decimal(axis.counter(t))
        if axis.uu is not None:
            value = value / axis.uu
        texts.append(f"uu{value:.5f}")
    _reply(ix, ",".join(texts), t)


@handles("RE")
def _re(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Encoder position of the current axis, or of every axis in AA/AM (an axis without an
    encoder reports its position counter, which is what an open-loop stepper knows)."""
    axes = [ix.axis] if ix.mode == "single" else ix.board.axes
    if ix.mode == "single" and not ix.axis.has_encoder:
        raise CommandFailed(ErrorKind.NO_ENCODER)
    _reply(ix, ",".join(str(_encoder(a, t)) for a in axes), t)


def _encoder(axis: Axis, t: float) -> int:
    return axis.encoder(t) if axis.has_encoder else axis.counter(t)


@handles("PE")
def _pe(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "same as AA;RE;" whatever the mode."""
    _reply(ix, ",".join(str(_encoder(a, t)) for a in ix.board.axes), t)


@handles("PP")
def _pp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "same as AA; RP" whatever the mode."""
    _reply(ix, ",".join(str(a.counter(t)) for a in ix.board.axes), t)


@handles("RL")
def _rl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """One character per axis: "Open-loop stepper always returns “n” and servo axes always
    returns “N”"."""
    chars = []
    for a in ix.board.axes:
        if not a.has_encoder:
            chars.append("n")
        elif a.is_servo:
            chars.append("N")
        else:
            chars.append("S" if a.slipped else "N")
    _reply(ix, "".join(chars), t)


@handles("EA")
def _ea(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Encoder status, five characters (§5.4.6's table): slip detection E/D, position
    maintenance (or a servo's closed loop) E/D, slip S/N, in position P/N, and home: the table
    prints ``P`` for "Encoder is at home condition", which is sent as printed (the PC48 and VS4
    print ``H``); one field per axis, comma separated, in AA/AM."""
    axes = [ix.axis] if ix.mode == "single" else ix.board.axes
    texts = []
    for axis in axes:
        hold = axis.servo.closed if axis.servo is not None else axis.hold
        texts.append(
            "".join(
                (
                    "E" if axis.slip_detect else "D",
                    "E" if hold else "D",
                    "S" if axis.slipped else "N",
                    "P" if hold and axis.in_position else "N",
                    # "P Encoder is at home condition" (the older boards print H here)
                    "P" if axis.home_condition(t) else "N",
                )
            )
        )
        axis.slipped = False
    ix.board.reply_status(",".join(texts), t)


@handles("CA")
def _ca(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "In multi-axis modes, the CA command clears the flags of all selected axes" (``AA;
    CA,1,1;`` clears Y and Z); "Unlike the IC command, CA will not clear other error flags"."""
    ix.board.clear_done(_flag_axes(ix, cmd))


@handles("AN", "AF")
def _an(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """AN/AF; in a contour definition "The AN and AF commands must have commas for all axes"
    and an axis without a value is left alone, so ``AN,,;`` changes nothing (the CK example)."""
    from omsd.board.commands import _aux

    if ix.contour is not None and not any(f is not None for f in cmd.fields or ()):
        if not ix.contour.add(None, ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    _aux(ix, cmd, cell, t)


@handles("SW", "BW")
def _sw(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Wait for general-purpose input # to go high (SW) or low (BW); in AA every axis waits."""
    board = ix.board
    bit = ix.integer(ix.one(cmd), cmd.mnemonic)
    args = (bit, cmd.mnemonic == "SW")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("SW", args, ix.cost(cell, ix.axis)))])
        return
    group = SyncGroup(set(range(len(board.axes))))
    ix.enqueue([(a, Op("SW", args, ix.cost(cell, a), group)) for a in board.axes])


@handles("PH", "PL")
def _ph(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Auxiliary output high (PH) or low (PL); "disables PA" (queued like AN/AF)."""
    code = "AN" if cmd.mnemonic == "PH" else "AF"
    axes = _flag_axes(ix, cmd)
    ix.enqueue([(a, Op(code, (), ix.cost(cell, a))) for a in axes])
    for a in axes:
        ix.pa_entered[a.index] = False


# -- general-purpose I/O --------------------------------------------------------------------------


def _io_high(ix: Interpreter, t: float) -> int:
    bits = (1 << ix.board.model.io_bits) - 1
    return ~ix.board.io_bits_low(t) & bits


@handles("BX")
def _bx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """I/O state in hex, "low = 0, high = 1" (``05``)."""
    _reply(ix, f"{_io_high(ix, t):02x}", t)


@handles("RB")
def _rb(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """I/O bit directions in hex, 1 = output (``0f``: bits 0-3 outputs)."""
    _reply(ix, f"{ix.board.directions:02x}", t)


@handles("BS")
def _bs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "Set all of the output bits to a known state at the same time ... The mask must be in
    ASCII hex format where the least significant bit (bit 0) is on the right. To set a line
    low, the corresponding bit in the hex mask must be a 0. A one (1) in any bit position will
    set the corresponding bit high." "Range: 00 ≤ Hex number ≤ FF" (its row); "Data written to
    input bits has no effect". The lexer reads the operand as hexadecimal digits (``BSA5;``,
    ``BSff;``: the table row's ``hex_operand``)."""
    fields = cmd.fields or ()
    if len(fields) != 1 or fields[0] is None:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    try:
        mask = int(fields[0], 16)
    except ValueError:
        raise CommandFailed(ErrorKind.BAD_NUMBER) from None
    ix.check("BS", mask)
    axis = ix.axis

    def apply(a: Axis, when: float) -> None:
        board = a.board
        for bit in range(board.model.io_bits):
            if board.directions >> bit & 1:
                board.set_output(bit, not (mask >> bit & 1), when)

    ix.enqueue([(axis, Op("SET", ("BS", apply), ix.cost(cell, axis)))])
