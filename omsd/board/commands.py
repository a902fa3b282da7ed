"""Every command of PC48 chapter 6: validation, immediate effects, and the ops it queues.

A handler receives the interpreter, the lexed command and the queue-table cell for the current
mode (from the personality's data). It either acts at once (status requests, IC, UU…) or builds
:class:`~omsd.board.queue.Op` objects and hands them to
:meth:`~omsd.board.interpreter.Interpreter.enqueue`, which charges the slots the manual's table
gives. Operand ranges are rows of the dialect's range table (:mod:`omsd.protocol.ranges_pc48`,
:mod:`omsd.protocol.ranges_pcix`), each quoting its manual; handlers ask
:meth:`~omsd.board.interpreter.Interpreter.check` and
:meth:`~omsd.board.interpreter.Interpreter.integer`, and a value outside its row sets the
command-error flag (:class:`~omsd.board.interpreter.CommandFailed`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from decimal import Decimal

from omsd.board import profiles as pf
from omsd.board.axis import Axis, Motion
from omsd.board.contour import Arc, ContourDefinition, Line, Output, plan
from omsd.board.events import ErrorKind
from omsd.board.interpreter import CommandFailed, Interpreter
from omsd.board.queue import Op, SyncGroup
from omsd.models.spec import Cell, Kind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import truncate

Handler = Callable[[Interpreter, Command, Cell, float], None]
HANDLERS: dict[str, Handler] = {}


Registrar = Callable[..., Callable[[Handler], Handler]]


def registrar(table: dict[str, Handler]) -> Registrar:
    """A ``@handles("XX", ...)`` decorator that files handlers in ``table`` (one per dialect
    module)."""

    def handles(*mnemonics: str) -> Callable[[Handler], Handler]:
        def register(fn: Handler) -> Handler:
            for m in mnemonics:
                table[m] = fn
            return fn

        return register

    return handles


handles = registrar(HANDLERS)


def _status(axis: Axis, t: float) -> str:
    """RA/QA field (PC48 §6.13 RA): direction P/M, done D/N, overtravel L/N (in the direction
    of char 4), home H/N."""
    d = axis.heading(t)
    return "".join(
        (
            "P" if d > 0 else "M",
            "D" if axis.done else "N",
            "L" if axis.limit_active(d, t) else "N",
            "H" if axis.home_sensed(t) else "N",
        )
    )


# -- 6.4 axis specification -----------------------------------------------------------------------


def _select_axis(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    letter = cmd.mnemonic[1]
    axis = ix.board.axis_by_letter(letter)
    if axis is None:
        raise CommandFailed(ErrorKind.NO_SUCH_AXIS)
    ix.mode = "single"
    ix.axis_index = axis.index


for _letter in "XYZTUVRS":
    HANDLERS["A" + _letter] = _select_axis


@handles("AA")
def _aa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if cell.kind is Kind.QUEUED and ix.mode != "single":
        # "AA,AM 2": a synchronizing no-op in every axis queue
        slots = ix.cost(cell, ix.axis)
        ix.enqueue([(a, Op("NOP", (), slots)) for a in ix.board.axes])
    ix.mode = "AA"


@handles("AM")
def _am(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.mode = "AM"


# -- 6.5 system control ---------------------------------------------------------------------------


@handles("EN")
def _en(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.echo = True


@handles("EF")
def _ef(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.echo = False


@handles("HH", "HL", "MO", "HF", "HN", "IS", "ET", "RB")
def _simple(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Single-axis commands with no operand that queue one op on the current axis."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    axis = ix.axis
    if cmd.mnemonic == "MO" and axis.has_encoder and ix.board.model.dialect != "pcix":
        raise CommandFailed(ErrorKind.ENCODER_MODEL)
    ix.enqueue([(axis, Op(cmd.mnemonic, (), ix.cost(cell, axis)))])


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
        axes = [ix.board.axes[i] for i in picked] if picked else list(ix.board.axes)
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a))) for a in axes])


@handles("CN")
def _cn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Cosine ramps for all axes: queued (1 slot) on the PC48, immediate on the VS4."""
    if cmd.fields:
        raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
    if cell.kind is Kind.IMMEDIATE:
        ix.board.ramp = pf.RampShape(pf.RampKind.COSINE)
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
    ix.board.ramp = pf.RampShape(pf.RampKind.PARABOLIC, steps)


@handles("PF")
def _pf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.ramp = pf.LINEAR


@handles("RS")
def _rs(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.reset(t)


# -- 6.6 user I/O ---------------------------------------------------------------------------------


@handles("AN", "AF")
def _aux(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """AN (released, high) / AF (driven low). In AA/AM and in a contour the parameters are
    place holders: "the value given does not affect the active state of the auxiliary line"."""
    code = cmd.mnemonic
    board = ix.board
    if ix.contour is not None:
        targets = ix.per_axis(cmd)
        if not targets:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        slots = ix.cost(cell, ix.axis)
        if not ix.contour.add(None, slots):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        for index in targets:
            ix.contour.items.append(Output("aux", index, code == "AF"))
        return
    axes = [ix.axis] if ix.mode == "single" else [board.axes[i] for i in ix.per_axis(cmd)]
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
        axis = ix.board.axes[index]
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
        axis = ix.board.axes[index]
        ops.append((axis, Op("SE", (ms,), ix.cost(cell, axis))))
        ix.se_entered[index] = ms > 0
    ix.enqueue(ops)


@handles("BL", "BH")
def _bit(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    bit = ix.integer(ix.one(cmd), cmd.mnemonic)
    if not board.directions >> bit & 1:
        # "this is only valid for bits which have been configured as outputs"
        raise CommandFailed(ErrorKind.NOT_AN_OUTPUT)
    low = cmd.mnemonic == "BL"
    if ix.contour is not None:
        if not ix.contour.add(Output("bit", bit, low), ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op(cmd.mnemonic, (bit,), ix.cost(cell, ix.axis)))])
        return
    # AA/AM: the bit is set once every axis has reached it
    group = SyncGroup(set(range(len(board.axes))))
    group.action = lambda g, when: board.set_output(bit, low, when)
    ix.enqueue([(a, Op("WA", (), ix.cost(cell, a), group)) for a in board.axes])


@handles("BX")
def _bx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.reply_value(f"{ix.board.io_bits_low(t):06X}", t)


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
        axis = ix.board.axes[index]
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
        axis = ix.board.axes[index]
        value = ix.check("LP", ix.convert(axis, raw_value, "dist"))
        ops.append((axis, Op("LP", (value,), ix.cost(cell, axis))))
    ix.enqueue(ops)


def _check_target(ix: Interpreter, value: float, mnemonic: str, operand: int = 1) -> float:
    """A position or distance in steps against its row (the position range)."""
    return ix.check(mnemonic, value, operand)


@handles("MA", "MR", "ML", "MT")
def _move(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    code = cmd.mnemonic
    board = ix.board
    if ix.contour is not None:
        _contour_line(ix, cmd, cell)
        return
    cosine = ix.board.ramp.kind is pf.RampKind.COSINE
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
    ops = []
    for index, raw_value in items.items():
        axis = board.axes[index]
        value = _check_target(ix, ix.convert(axis, raw_value, "dist"), code)
        ops.append((axis, Op(code, (value,), ix.cost(cell, axis), group)))
    ix.enqueue(ops)
    if ix.mode != "single":
        ix.last_move = sorted(items)
    else:
        ix.last_move = [ix.axis_index]


@handles("RM")
def _rm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "The parameter must be greater than zero and less than 65,000."
    n = ix.integer(ix.one(cmd), "RM")
    ix.enqueue([(ix.axis, Op("RM", (n,), ix.cost(cell, ix.axis)))])


# -- 6.8 move execution ---------------------------------------------------------------------------


def _go_extra(ix: Interpreter, index: int) -> int:
    """PA adds 2 and SE 3 slots to each GO/GD (PC48 §6.6)."""
    extra = 0
    if ix.pa_entered[index]:
        extra += 2
        if ix.se_entered[index]:
            extra += 3
    return extra


@handles("GO", "GD")
def _go(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    if ix.mode == "single":
        axis = ix.axis
        slots = ix.cost(cell, axis) + _go_extra(ix, axis.index)
        ix.enqueue([(axis, Op(cmd.mnemonic, (), slots))])
        return
    # AA: every axis meets at the GO ("Each axis programmed to move will start together upon
    # executing the GO command"); AM: only the axes of the task just specified.
    if ix.mode == "AM" and ix.last_move:
        members = list(ix.last_move)
    else:
        members = list(range(len(board.axes)))
    group = SyncGroup(set(members))
    group.action = board.executor.go_action
    group.data["gd"] = cmd.mnemonic == "GD"
    group.data["all"] = ix.mode == "AA"
    ops = []
    for index in members:
        axis = board.axes[index]
        slots = ix.cost(cell, axis) + _go_extra(ix, index)
        ops.append((axis, Op(cmd.mnemonic, (), slots, group)))
    ix.enqueue(ops)


@handles("JG", "JF")
def _jog(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # single-axis on the PC48; the PCIx also takes ``JG#,#,#,#;`` in AA/AM
    items = ix.items(cmd)
    ops = []
    for index, value in items.items():
        axis = ix.board.axes[index]
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
    y = ix.board.axis_by_letter("Y")
    vy_f = ix.convert(y, vy, "vel") if (vy is not None and y is not None) else 0.0
    ix.check("VS", vx_f, 2)
    ix.check("VS", vy_f, 3)
    ix.enqueue([(axis, Op("VS", (n, vx_f, vy_f), ix.cost(cell, axis)))])


# -- 6.9 move termination -------------------------------------------------------------------------


def _stop(
    ix: Interpreter, axes: list[Axis], t: float, kill: bool = False, cell: Cell | None = None
) -> None:
    board = ix.board
    for axis in axes:
        board.executor.flush(axis, t)
    for axis in axes:
        # "Flush + 2" (PC48); the PCIx's tables give their own numbers (+PA, +settle)
        slots = ix.cost(cell, axis) if cell is not None and cell.kind is Kind.FLUSH else 2
        axis.queue.append(Op("STOP", (kill,), slots, source=board.input_source))
    ix.mt_blocked = False


@handles("ST")
def _st(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "When executed in the AA mode, the ST command is equivalent to the SA command."
    _stop(ix, ix.context_axes(), t, cell=cell)


@handles("SA")
def _sa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _stop(ix, list(ix.board.axes), t, cell=cell)


@handles("SD")
def _sd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.clear_done(ix.board.axes)
    _stop(ix, list(ix.board.axes), t, cell=cell)


@handles("KL")
def _kl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    kill_all(ix, t)


def kill_all(ix: Interpreter, t: float) -> None:
    """KL / Control-D: "flush the command queue and terminate pulse generation of all axes
    immediately" (PC48 §6.9); also leaves contour definition and the WQ wait."""
    for axis in ix.board.axes:
        axis.halt(t)
        axis.aux_timer = None
    _stop(ix, list(ix.board.axes), t, kill=True)
    ix.contour = None
    ix.wq = None


# -- 6.10 loop control ----------------------------------------------------------------------------


def _loop_axes(ix: Interpreter) -> list[Axis]:
    return ix.context_axes()


@handles("LS")
def _ls(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    n = ix.integer(ix.one(cmd), "LS")
    if ix.contour is not None:
        # the VS4 table accepts LS in a contour definition (2 slots) although LE is not valid
        # there and "The CX command cannot be placed within a loop": it takes its slots and
        # does nothing else
        if not ix.contour.add(None, ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    axes = _loop_axes(ix)
    ix.open_loop("LS", axes)
    ix.enqueue([(a, Op("LS", (n,), ix.cost(cell, a))) for a in axes])
    ix.push_loop("LS", axes)
    if ix.board.ramp.kind is pf.RampKind.COSINE:
        ix.mt_blocked = True  # "invalid while in the CN mode, if loops are being used"


@handles("WS")
def _ws(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    bit = ix.integer(ix.one(cmd), "WS")
    axes = _loop_axes(ix)
    ix.open_loop("WS", axes)
    ix.enqueue([(a, Op("WS", (bit,), ix.cost(cell, a))) for a in axes])
    ix.push_loop("WS", axes)
    for a in axes:
        ix.ws_bits.setdefault(a.index, []).append(bit)


@handles("WH")
def _wh(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axes = _loop_axes(ix)
    ix.open_loop("WH", axes)
    ix.enqueue([(a, Op("WH", (), ix.cost(cell, a))) for a in axes])
    ix.push_loop("WH", axes)


def _loop_end(
    ix: Interpreter, cmd: Command, cell: Cell, opens: str, args: tuple[object, ...]
) -> None:
    axes = _loop_axes(ix)
    ix.close_loop(opens, axes)
    group = None
    if ix.mode != "single" and cmd.mnemonic in ("WD", "WG"):
        group = SyncGroup({a.index for a in axes})
        group.action = ix.board.executor.loop_decision
        group.data["kind"] = cmd.mnemonic
        if args:
            group.data["bit"] = args[0]
    ix.enqueue([(a, Op(cmd.mnemonic, args, ix.cost(cell, a), group)) for a in axes])
    ix.pop_loop(axes)


@handles("LE")
def _le(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _loop_end(ix, cmd, cell, "LS", ())


@handles("WD")
def _wd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axes = _loop_axes(ix)
    bits = ix.ws_bits.get(axes[0].index, [])
    bit = bits[-1] if bits else 0
    _loop_end(ix, cmd, cell, "WS", (bit,))
    for a in axes:
        stack = ix.ws_bits.get(a.index)
        if stack:
            stack.pop()


@handles("WG")
def _wg(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _loop_end(ix, cmd, cell, "WH", ())


@handles("CW")
def _cw(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # The flag is set as CW is read: a CW queued behind a running WH loop could never be
    # reached otherwise, and the manual's WH example sends CW from the keyboard while the loop
    # runs ("operator wants a break so he/she sends CW from keyboard").
    axes = ix.context_axes()
    ix.enqueue([(a, Op("CW", (), ix.cost(cell, a))) for a in axes])
    for a in axes:
        ix.while_flags.add(a.index)


# -- 6.11 home ------------------------------------------------------------------------------------


@handles("HM", "HR")
def _home(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    raw = ix.one(cmd, required=False)
    value = ix.convert(axis, raw, "dist") if raw is not None else 0.0
    _check_target(ix, value, cmd.mnemonic)
    direction = 1 if cmd.mnemonic == "HM" else -1
    ix.enqueue([(axis, Op("HM", (value, False, direction), ix.cost(cell, axis)))])


@handles("KM", "KR")
def _home_kill(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    direction = 1 if cmd.mnemonic == "KM" else -1
    ix.enqueue([(axis, Op("HM", (0.0, True, direction), ix.cost(cell, axis)))])


# -- 6.12 move synchronization --------------------------------------------------------------------


def _task_axes(ix: Interpreter) -> list[int]:
    if ix.mode == "AM" and ix.last_move:
        return list(ix.last_move)
    return list(range(len(ix.board.axes)))


@handles("ID")
def _id(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("ID", (), ix.cost(cell, ix.axis)))])
        return
    # AA: "the done flag register bits will be set as each axis encounters the ID in its command
    # stream, but the done flag in the status register will not be set until all axes have
    # executed the ID command. In the AM mode, only the axes active in the most recent move will
    # set their done flags."
    members = _task_axes(ix)
    group = SyncGroup(set(members), barrier=False)
    group.action = lambda g, when: board.signal_done(when)
    ix.enqueue(
        [(board.axes[i], Op("ID", (), ix.cost(cell, board.axes[i]), group)) for i in members]
    )


@handles("II")
def _ii(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Only those axes which have been supplied a parameter in the most recent move command will
    # cause interrupts."
    board = ix.board
    members = [ix.axis_index] if ix.mode == "single" else (ix.last_move or _task_axes(ix))
    ix.enqueue([(board.axes[i], Op("II", (), ix.cost(cell, board.axes[i]))) for i in members])


@handles("IN")
def _in(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    items = ix.items(cmd)
    group = SyncGroup(set(items), barrier=False)
    group.action = lambda g, when: board.signal_done(when)
    ops = []
    for index, raw in items.items():
        axis = board.axes[index]
        value = ix.check("IN", ix.convert(axis, raw, "dist"))
        ops.append((axis, Op("IN", (value,), ix.cost(cell, axis), group)))
    ix.enqueue(ops)


@handles("IP")
def _ip(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("IP", (), ix.cost(cell, ix.axis)))])
        return
    # VS4 AA form: like ID, DON_S once every encoder axis of the task is in position
    members = [i for i in _task_axes(ix) if board.axes[i].has_encoder]
    group = SyncGroup(set(members), barrier=False)
    group.action = lambda g, when: board.signal_done(when)
    ix.enqueue(
        [(board.axes[i], Op("IP", (), ix.cost(cell, board.axes[i]), group)) for i in members]
    )


@handles("IC")
def _ic(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    clear_flags(ix)


def clear_flags(ix: Interpreter) -> None:
    """IC / Control-Y: "clear the done and error flags in the status register and the done flag
    register"."""
    ix.board.registers.clear_done_and_errors()
    for axis in ix.board.axes:
        axis.done = False


@handles("CA")
def _ca(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.clear_done([ix.axis])


@handles("WA")
def _wa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    group = SyncGroup(set(range(len(board.axes))))
    ix.enqueue([(a, Op("WA", (), ix.cost(cell, a), group)) for a in board.axes])


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
    board = ix.board
    bit = ix.integer(ix.one(cmd), "SW")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("SW", (bit,), ix.cost(cell, ix.axis)))])
        return
    group = SyncGroup(set(range(len(board.axes))))
    ix.enqueue([(a, Op("SW", (bit,), ix.cost(cell, a), group)) for a in board.axes])


@handles("WT")
def _wt(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "In the AA mode, all axes will wait."
    board = ix.board
    ms = ix.integer(ix.one(cmd), "WT")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("WT", (ms,), ix.cost(cell, ix.axis)))])
        return
    group = SyncGroup(set(range(len(board.axes))))
    group.action = board.executor.wt_action
    group.data["ms"] = ms
    ix.enqueue([(a, Op("WT", (ms,), ix.cost(cell, a), group)) for a in board.axes])


# -- 6.13 status requests -------------------------------------------------------------------------


@handles("WY")
def _wy(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.reply_value(ix.board.model.who_are_you(), t)


def _list(ix: Interpreter, fn: Callable[[Axis], str], t: float) -> None:
    if ix.mode == "single":
        ix.board.reply_value(fn(ix.axis), t)
    else:
        ix.board.reply_value(",".join(fn(a) for a in ix.board.axes), t)


@handles("RP")
def _rp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _list(ix, lambda a: str(a.counter(t)), t)


@handles("RQ")
def _rq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    if ix.contour is not None:
        # "The maximum available is 1016. The response is fixed in length at 4 characters."
        ix.board.reply_value(f"{ix.contour.free:04d}", t)
        return
    _list(ix, lambda a: f"{a.queue.free:03d}", t)


@handles("RC")
def _rc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _list(ix, lambda a: str(int(_current_acceleration(ix, a, t))), t)


def _current_acceleration(ix: Interpreter, axis: Axis, t: float) -> float:
    """PC48 §6.13 RC: "When the stage is stopped, the parameter returned will be the acceleration
    at the beginning of a ramp. When the stage is running at programmed speed ... the
    acceleration at the end of the ramp.\""""
    if axis.motion is not Motion.IDLE:
        a = abs(axis.acceleration(t))
        if a > 0.0 or axis.velocity(t) == 0.0:
            return a
        up = pf.ramp_up(axis.vl, axis.ac, axis.vb, axis.ramp)
        return abs(up.a(up.duration))
    up = pf.ramp_up(axis.vl, axis.ac, axis.vb, axis.ramp)
    return abs(up.a(0.0))


@handles("RV")
def _rv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "If the JF command is executing, the command only reports the integer part"
    _list(ix, lambda a: str(math.trunc(a.velocity(t))), t)


@handles("RU")
def _ru(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "a floating point number with five characters to the right of the decimal point"
    axis = ix.axis
    value = Decimal(axis.counter(t))
    if axis.uu is not None:
        value = value / axis.uu
    ix.board.reply_value(f"{value:.5f}", t)


@handles("RA", "QA")
def _ra(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    ix.board.reply_status(_status(axis, t), t)
    if cmd.mnemonic == "RA":
        _reset_flags(ix, [axis], t)


@handles("RI", "QI")
def _ri(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    board.reply_status(",".join(_status(a, t) for a in board.axes), t)
    if cmd.mnemonic == "RI":
        _reset_flags(ix, board.axes, t)


def _reset_flags(ix: Interpreter, axes: list[Axis], t: float) -> None:
    """RA: "The limit flag in the hardware status register will be reset by the RA command,
    providing another axis is not in limit. The done flag register will also be reset"."""
    board = ix.board
    board.clear_done(axes)
    others = [a for a in board.axes if a not in axes]
    if not any(a.limit_active(a.direction, t) for a in others):
        from omsd.board.registers import OVRT

        board.registers.status &= ~OVRT


# -- 6.14 user units ------------------------------------------------------------------------------


@handles("UU")
def _uu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # single-axis on the PC48; the VS4 manual also shows ``AA UU10000,10000,10000;``
    if ix.mode == "single":
        value = ix.one(cmd)
        assert value is not None
        items = {ix.axis_index: value}
    else:
        items = ix.per_axis(cmd)
    for value in items.values():
        ix.check("UU", value)
    for index, value in items.items():
        ix.board.axes[index].uu = None if value == 1 else value


@handles("UF")
def _uf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.axis.uu = None


# -- 6.15 - 6.19 encoder --------------------------------------------------------------------------


@handles("ER")
def _er(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "These counts must be integers unless user units are enabled."
    axis = ix.axis
    enc, motor = ix.required(cmd, 2)
    if axis.uu is None and (enc != enc.to_integral_value() or motor != motor.to_integral_value()):
        raise CommandFailed(ErrorKind.BAD_NUMBER)
    ix.check("ER", enc, 1)
    ix.check("ER", motor, 2)
    ix.enqueue([(axis, Op("ER", (float(enc), float(motor)), ix.cost(cell, axis)))])


@handles("HV", "HG", "HD", "ES")
def _hold_parameter(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    raw = ix.one(cmd)
    assert raw is not None
    code = cmd.mnemonic
    if code == "HV":
        value = ix.check(code, ix.convert(axis, raw, "vel"))
    else:  # HG, HD, ES: whole numbers
        value = float(ix.integer(raw, code))
    ix.enqueue([(axis, Op(code, (value,), ix.cost(cell, axis)))])


@handles("HE", "HS")
def _home_mode(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.axis.home_encoder = cmd.mnemonic == "HE"


@handles("RL")
def _rl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "The number of characters returned corresponds to the number of axes available"
    ix.board.reply_value("".join("S" if a.slipped else "N" for a in ix.board.axes), t)


@handles("EA")
def _ea(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axis = ix.axis
    text = "".join(
        (
            "E" if axis.slip_detect else "D",
            "E" if axis.hold else "D",
            "S" if axis.slipped else "N",
            "P" if axis.hold and axis.in_position else "N",
            "H" if axis.home_condition(t) else "N",
            "N",
        )
    )
    axis.slipped = False  # "reset by execution of EA command"
    ix.board.reply_status(text, t)


@handles("RE")
def _re(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.board.reply_value(str(ix.axis.encoder(t)), t)


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
    p = _check_target(ix, ix.convert(axis, raw, "dist"), cmd.mnemonic)
    if cmd.mnemonic == "FP":
        # "flush the command queue and attempt to stop at the specified position"
        ix.board.executor.flush(axis, t)
        axis.queue.append(Op("FP", (p,), ix.cost(cell, axis), source=ix.board.input_source))
        return
    ix.enqueue([(axis, Op("SP", (p,), ix.cost(cell, axis)))])


# -- 6.21 contouring ------------------------------------------------------------------------------


@handles("CV")
def _cv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Changing this parameter will make any previously defined contours invalid."
    raw = ix.one(cmd)
    assert raw is not None
    v = ix.check("CV", float(raw))
    ix.board.contour_velocity = v
    if ix.board.contour is not None:
        ix.board.contour.valid = False


@handles("CD")
def _cd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    if board.model.contour_queue <= 0:
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    start = ix.per_axis(cmd)
    if not start:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    axes = tuple(sorted(start))
    # the start "in absolute units": each held to the position range (its row)
    positions = tuple(ix.check("CD", ix.convert(board.axes[i], start[i], "dist")) for i in axes)
    ix.contour = ContourDefinition(
        axes=axes,
        start=positions,
        velocity=board.contour_velocity,
        capacity=board.model.contour_queue,
    )
    board.contour = None


def _contour_line(ix: Interpreter, cmd: Command, cell: Cell) -> None:
    """MT inside a contour: "only the axes being used in the contour must be provided"."""
    defn = ix.contour
    assert defn is not None
    fields = ix.per_axis(cmd, list(defn.axes))
    target = tuple(
        ix.check("MT", ix.convert(ix.board.axes[a], fields[a], "dist")) if a in fields else None
        for a in defn.axes
    )
    slots = ix.cost(cell, ix.axis, contour_axes=len(defn.axes))
    if not defn.add(Line(target), slots):
        raise CommandFailed(ErrorKind.CONTOUR_FULL)


@handles("CR")
def _cr(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # "Attempting to do circular interpolation in a contour which is being defined for more than
    # 2 axes will be flagged as a command error."
    defn = ix.contour
    assert defn is not None
    if len(defn.axes) != 2:
        raise CommandFailed(ErrorKind.CIRCULAR_AXES)
    xc, yc, angle = ix.required(cmd, 3)
    ax, ay = (ix.board.axes[i] for i in defn.axes)
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
    ix.board.contour = defn
    ix.contour = None
    ix.mode = "AA"


def runnable_contour(ix: Interpreter) -> ContourDefinition:
    """The defined contour CX (and the PCIx's CG) may run: "The CX command cannot be placed
    within a loop or while construct."."""
    defn = ix.board.contour
    if defn is None or not defn.valid:
        raise CommandFailed(ErrorKind.NO_CONTOUR)
    if ix.in_loop(list(ix.board.axes)):
        raise CommandFailed(ErrorKind.NOT_IN_LOOP)
    return defn


@handles("CX")
def _cx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    board = ix.board
    defn = runnable_contour(ix)
    group = SyncGroup(set(range(len(board.axes))))
    group.action = lambda g, when: run_contour(ix, defn, when)
    ix.enqueue([(a, Op("CX", (), ix.cost(cell, a), group)) for a in board.axes])


def run_contour(ix: Interpreter, defn: ContourDefinition, t: float) -> None:
    board = ix.board
    tick = board.clock.at_or_after(t)
    axes = [board.axes[i] for i in defn.axes]
    here = {a.index: a.position(tick) for a in axes}
    decel = min(a.ac for a in axes)
    p = plan(defn, here, decel)
    for a in axes:
        a.begin(tick, p.pieces[a.index], Motion.CONTOUR, final=p.finals[a.index])
        v = a.traj.velocity(a.traj.end_time - 1e-9) if a.traj.pieces else 0.0
        if v:
            a.direction = 1 if v > 0 else -1
    lead = axes[0]
    for offset, out in p.outputs:
        when = board.clock.at_or_after(tick + offset)
        kind = "aux" if out.kind == "aux" else "bit"
        lead.outputs.append((when, (kind, out.target, out.low)))
    lead.outputs.sort(key=lambda item: item[0])
    lead.invalidate()
