"""PCIx status and reports, flags and the general-purpose I/O whose meaning changed from the
PC48 (RQ, RC, RU, RE, PE, PP, RL, EA, CA, AN/AF, SW/BW, PH/PL, PA, SE, WS, BX, RB, BS)."""

from __future__ import annotations

from decimal import Decimal

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix.common import (
    flag_axes,
    handles,
    reply,
)
from omsd.dialects.shared.io import aux
from omsd.dialects.shared.loops import while_sync
from omsd.dialects.shared.reports import rounded_off, user_position, whole
from omsd.dialects.shared.sync import task_axes
from omsd.engine.axis import Axis, Motion
from omsd.engine.queue import Op, SyncGroup
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- status and reports ---------------------------------------------------------------------------


@handles("RQ")
def _rq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Every axis's free queue units, whatever the mode: the example types ``RQ`` with no mode
    command (every other example that needs AA types ``AA;`` first) and gets "800, 800, 800,
    800"; "MAX value of command queue for all axes = 800". Inside a contour definition the
    contour queue (7160)."""
    if ix.contour is not None:
        reply(ix, str(ix.contour.free), t)
    else:
        reply(ix, ", ".join(str(a.queue.free) for a in ix.machine.axes), t)


@handles("RC")
def _rc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "2000000, 2000000, 2000000, 2000000": the acceleration now, "zero when the stage is
    stopped or running at constant speed" (unlike the PC48, which reports the ramp's). "While a
    contour is executing, the value computed to generate the appropriate lead in will be
    returned", for the whole contour as on the PC48; the whole number meant, as the PC48's
    (``whole``: a lead-in's share of 2500 computed as 2499.9999999999995 is 2500)."""
    axes = [ix.axis] if ix.mode == "single" else ix.machine.axes
    reply(ix, ", ".join(str(whole(_acceleration(ix, a, t))) for a in axes), t)


def _acceleration(ix: Interpreter, axis: Axis, t: float) -> float:
    if axis.motion is Motion.CONTOUR:
        return ix.contour_lead.get(axis.index, 0.0)
    return abs(axis.acceleration(t))


@handles("RU")
def _ru(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "uu3.50000": the position in user units, five decimals; under an encoder ratio in its
    encoder counts, as LP and MA take them (``ER2,1;UU10;LP5;RU;`` answers ``uu5.00000``)."""
    axes = [ix.axis] if ix.mode == "single" else ix.machine.axes
    reply(ix, ",".join("uu" + rounded_off(user_position(axis, t), 5) for axis in axes), t)


@handles("RE")
def _re(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Encoder position of the current axis, or of every axis in AA/AM (an axis without an
    encoder reports its position counter, which is what an open-loop stepper knows)."""
    axes = [ix.axis] if ix.mode == "single" else ix.machine.axes
    if ix.mode == "single" and not ix.axis.has_encoder:
        raise CommandFailed(ErrorKind.NO_ENCODER)
    reply(ix, ",".join(str(_encoder(a, t)) for a in axes), t)


def _encoder(axis: Axis, t: float) -> int:
    return axis.encoder(t) if axis.has_encoder else axis.counter(t)


@handles("PE")
def _pe(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "same as AA;RE;" whatever the mode."""
    reply(ix, ",".join(str(_encoder(a, t)) for a in ix.machine.axes), t)


@handles("PP")
def _pp(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "same as AA; RP" whatever the mode."""
    reply(ix, ",".join(str(a.counter(t)) for a in ix.machine.axes), t)


@handles("RL")
def _rl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """One character per axis: "Open-loop stepper always returns “n” and servo axes always
    returns “N”"."""
    chars = []
    for a in ix.machine.axes:
        if not a.has_encoder:
            chars.append("n")
        elif a.is_servo:
            chars.append("N")
        else:
            chars.append("S" if a.slipped else "N")
    reply(ix, "".join(chars), t)


@handles("EA")
def _ea(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Encoder status, five characters (§5.4.6's table): slip detection E/D, position
    maintenance (or a servo's closed loop) E/D, slip S/N, in position P/N, and home: the table
    prints ``P`` for "Encoder is at home condition", which is sent as printed (the PC48 and VS4
    print ``H``); one field per axis, comma separated, in AA/AM."""
    axes = [ix.axis] if ix.mode == "single" else ix.machine.axes
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
    ix.machine.reply_status(",".join(texts), t)


@handles("CA")
def _ca(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "In multi-axis modes, the CA command clears the flags of all selected axes" (``AA;
    CA,1,1;`` clears Y and Z); "Unlike the IC command, CA will not clear other error flags"."""
    ix.machine.clear_done(flag_axes(ix, cmd))


@handles("AN", "AF")
def _an(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """AN/AF; in a contour definition "The AN and AF commands must have commas for all axes"
    and an axis without a value is left alone, so ``AN,,;`` changes nothing (the CK example)."""
    if ix.contour is not None and not any(f is not None for f in cmd.fields or ()):
        if not ix.contour.add(None, ix.cost(cell, ix.axis)):
            raise CommandFailed(ErrorKind.CONTOUR_FULL)
        return
    aux(ix, cmd, cell, t)


@handles("SW", "BW")
def _sw(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Wait for general-purpose input # to go high (SW) or low (BW); in AA every axis waits, in AM
    the task's."""
    machine = ix.machine
    bit = ix.integer(ix.one(cmd), cmd.mnemonic)
    args = (bit, cmd.mnemonic == "SW")
    if ix.mode == "single":
        ix.enqueue([(ix.axis, Op("SW", args, ix.cost(cell, ix.axis)))])
        return
    members = [machine.axes[i] for i in task_axes(ix)]  # AM: the task's axes
    group = SyncGroup({a.index for a in members})
    ix.enqueue([(a, Op("SW", args, ix.cost(cell, a), group)) for a in members])


@handles("WS")
def _ws(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "WD#[,state];" (the WS page's syntax line): "If the state parameter is zero, the loop
    will continue while the input is low. If the state parameter is non-zero, the loop will
    continue while the input is high. If the state parameter is not entered, the default
    behavior is to loop while the input is low." """
    bit, state = ix.fields(cmd, 2)
    if bit is None:
        raise CommandFailed(ErrorKind.MISSING_PARAMETER)
    while_sync(ix, cell, ix.integer(bit, "WS"), while_high=bool(state))


@handles("PH", "PL")
def _ph(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Auxiliary output high (PH) or low (PL); "disables PA" (queued like AN/AF). The current
    axis takes a ``b`` too: "PHb; AX – AT 1", "PLb; AX – AT 1"."""
    code = "AN" if cmd.mnemonic == "PH" else "AF"
    if ix.mode == "single":
        ix.one(cmd, required=False)  # any numeric value
        axes = [ix.axis]
    else:
        axes = flag_axes(ix, cmd)
    ix.enqueue([(a, Op(code, (), ix.cost(cell, a))) for a in axes])


@handles("PA")
def _pa(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "PA selects the mode immediately but places entries in the axis command queue to set the
    state of the aux bit to the idle state": the mode (what ?PA reports, what the next GO or GD
    does with the aux) is set at once; the entry, when the axis reaches it, sets it again and
    puts the aux line in its idle state. A GO or GD typed after it takes the "+2" of its table
    from the mode in force (``Interpreter.cost``; the PC48's per-GO charge, ``pa_entered``, is
    not the PCIx's: with both, the PA was charged twice)."""
    if ix.mode == "single":
        items: dict[int, Decimal | None] = {ix.axis_index: ix.one(cmd, required=False)}
    else:
        items = dict(ix.per_axis(cmd))
    axes = ix.machine.axes
    ix.enqueue(
        [(axes[i], Op("PA", (value,), ix.cost(cell, axes[i]))) for i, value in items.items()]
    )
    for index, value in items.items():
        # "upon the execution of the GO or GD ... if the parameter is zero or not specified"
        axes[index].pa = value is None or value == 0
        axes[index].invalidate()


@handles("SE")
def _se(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The settling time, in force at once: "SE#; AX – AT Immediate", "SE#,#,##; AA-AM
    Immediate" (the PC48's SE is queued). A GO's "+3" follows it (``Interpreter.cost``), as PA's
    "+2" does."""
    items = {ix.axis_index: ix.one(cmd)} if ix.mode == "single" else dict(ix.per_axis(cmd))
    times = {index: ix.integer(value, "SE") for index, value in items.items()}
    for index, ms in times.items():
        ix.machine.axes[index].se_ms = ms


# -- general-purpose I/O --------------------------------------------------------------------------


def _io_high(ix: Interpreter, t: float) -> int:
    bits = (1 << ix.machine.model.io_bits) - 1
    return ~ix.machine.io_bits_low(t) & bits


@handles("BX")
def _bx(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """I/O state in hex, "low = 0, high = 1" (``05``)."""
    reply(ix, f"{_io_high(ix, t):02x}", t)


@handles("RB")
def _rb(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """I/O bit directions in hex, 1 = output (``0f``: bits 0-3 outputs)."""
    reply(ix, f"{ix.machine.directions:02x}", t)


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

    machine = ix.machine

    def apply(a: Axis, when: float) -> None:
        for bit in range(machine.model.io_bits):
            if machine.directions >> bit & 1:
                machine.set_output(bit, not (mask >> bit & 1), when)

    ix.enqueue([(axis, Op("SET", ("BS", apply), ix.cost(cell, axis)))])
