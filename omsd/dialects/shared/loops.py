"""The shared language, PC48 §6.10: loop control."""

from __future__ import annotations

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.shared.table import handles
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

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
    if ix.machine.ramp.kind is pf.RampKind.COSINE:
        ix.mt_blocked = True  # "invalid while in the CN mode, if loops are being used"


@handles("WS")
def _ws(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    while_sync(ix, cell, ix.integer(ix.one(cmd), "WS"), while_high=False)


def while_sync(ix: Interpreter, cell: Cell, bit: int, while_high: bool) -> None:
    """Open a WS loop on input ``bit``: its WD loops again while the input is low ("true"), or
    while it is high (``while_high``, the PCIx's non-zero state)."""
    axes = _loop_axes(ix)
    ix.open_loop("WS", axes)
    ix.enqueue([(a, Op("WS", (bit,), ix.cost(cell, a))) for a in axes])
    ix.push_loop("WS", axes)
    for a in axes:
        ix.ws_bits.setdefault(a.index, []).append((bit, while_high))


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
        group.action = ix.machine.executor.loop_decision
        group.data["kind"] = cmd.mnemonic
        if args:
            group.data["bit"], group.data["while_high"] = args
    ix.enqueue([(a, Op(cmd.mnemonic, args, ix.cost(cell, a), group)) for a in axes])
    ix.pop_loop(axes)


@handles("LE")
def _le(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    _loop_end(ix, cmd, cell, "LS", ())


@handles("WD")
def _wd(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    axes = _loop_axes(ix)
    bits = ix.ws_bits.get(axes[0].index, [])
    bit, while_high = bits[-1] if bits else (0, False)
    _loop_end(ix, cmd, cell, "WS", (bit, while_high))
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
