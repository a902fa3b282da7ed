"""Handlers of the MAX-family extension of the PCIx personality (rows in
:mod:`omsd.models.max_family`), switched on by ``Model.max_queries``.

The PCIx manual does not define these commands. The MAXv/MAXnet manuals that do are not among
the project's seeds, so what each command means and answers is taken from the client that sends
them, EPICS ``motorOmsAsyn`` (``omsAsynApp/src/omsBaseController.cpp``, ``omsMAXnet.cpp``), and
the older ``motorOms`` MAXv driver (``omsApp/src/drvMAXv.cc``), as used against real MAXv and
MAXnet boards; the replies' framing is the one ``shared/interop/README.md`` gives for this
dialect (``text<LF><CR>``, nothing before it), which the machine's ``reply_value`` applies.
Every answer is read from the board's state at the moment of the query; only ``#WS`` is fixed.

``PS?`` — motor type of the current axis
    omsBaseController::Init sends ``"A? PS?"`` for each axis ("Determine if encoder is present
    and if mode is stepper or servo") and reads the second character: "we expect any of "=O",
    "=E","=M"" — ``O`` an open-loop stepper (no encoder), ``E`` a stepper with encoder, ``M``
    a servo motor (encoder present, not a stepper). Answer ``=O``, ``=E`` or ``=M`` from the axis
    as fitted (PCIx Appendix C: servo axes, "STEPPER AXES, CLOSED LOOP (Encoder)", "STEPPER
    AXES, OPEN LOOP").

``LT?`` — limit switch true level of the current axis
    "Determine limit true state high or low ... you need firmware version 1.30 or higher";
    "we expect any of "=l" or "=h"": ``=h`` after LH ("Limits active high", PCIx §5.5.4),
    ``=l`` after LL (the factory default). It is the MAX spelling of the PCIx's ``?LS`` (``ll``
    / ``lh``), which the client sends instead to firmware older than 1.30.

``CL?`` — closed-loop state
    omsBaseController::getClosedLoopStatus sends ``"AM;CL?;"`` and takes the comma-separated
    fields, comparing each with ``"on"``; to switch, the client sends ``CL1``/``CL0`` to firmware
    1.30 and later and ``HN``/``HF`` to older firmware, so CL is the MAX name for the HN/HF state.
    An axis is ``on`` when its loop is closed: a servo axis whose PID loop runs (PCIx HN: "closes
    the loop and enables the PID"; HF, a limit or a runaway error open it again), a stepper with
    encoder in position maintenance (HN: "enable end-of-move correction"); an open-loop stepper
    has no loop and is always ``off``. In AA/AM: one ``on``/``off`` field per axis, comma
    separated, as the client splits it (the recorded trace's ``off,off,off,off`` is the shape it
    accepts). In single-axis mode ``=on``/``=off``: the MAX family answers its ``XX?`` queries
    with a leading ``=`` (``=O``, ``=h``, ``=0``, and the PCIx's own ``EG?`` → ``=egf``), and the
    client's pre-1.30 fallback compares a single-axis answer with ``"=on"``. Chosen; no source
    prints a single-axis ``CL?``.

``QL`` — limit switch inputs
    omsBaseController::omsPoller sends ``"AM;QL;"``, reads one hexadecimal number (``sscanf
    "%x"``) and decodes, for axis ``i`` (``i`` < 8): bit ``i`` is the negative (low) limit and bit
    ``i + 8`` the positive (high) limit, each *exclusive-or'ed with the level from LT?*
    ("``(limitFlags & (1 << i)) > 0) ^ getLimitInvert()``", with the invert flag set when
    ``LT?`` says ``=l``). So a bit is the electrical level of the limit input, 1 = TTL high,
    not "limit active": with LL (active low) an inactive limit reads 1, with LH 0. The same
    minus-bits-low / plus-bits-high layout is the MAXv's dual-port limit switch register
    (``omsMAXv.h``, "Limit Switch Status - Offset = 0x40", ``x_minus`` … ``x_plus``). The level
    is the input the board senses: active limits are at the active level of LH/LL, inactive ones
    at the other. Answered as four lower-case hex digits (16 bits, room for 8 axes), the width of
    the trace's ``0000``; lower case as the PCIx's only hex answer with letters prints it (RB:
    ``0f``). The whole board is reported in every mode, like ``PP``. A limit switched off with
    LF still shows (PCIx LF: limits "are still reported").

``#WS`` — watchdog timeout counter
    drvMAXv.cc: "For firmware ver:1.33 and above, read Watchdog Timeout Counter. If Counter is
    nonzero, print error message"; omsBaseController::watchdogOK: an answer of ``=`` followed by
    anything but ``0`` disables the card ("watchdog not running"). The emulated firmware never
    misses its watchdog, so the counter is always zero: ``=0`` (interop README: "``#WS`` (must
    answer ``=0``)").

``?PS`` — the motor type, as a client asks firmware before 1.30
    omsBaseController::Init: ``if (firmwareMin(1,30,0)) "A? PS?" else "A? ?PS"``, and the same
    ``=O``/``=E``/``=M`` is read from either answer. A PCIx reports firmware 1.26 (its WY
    example), so a MAX client talking to the PCIx personality asks ``?PS``; it is answered as
    ``PS?`` is. (The client's other pre-1.30 questions are the PCIx's own: ``?LS``, read by its
    second character, ``ll``/``lh``, and ``?PM``.)

``CL#`` — close (1) or open (0) the loop, firmware 1.30 and later
    omsBaseController::writeInt32: ``"A? CL1"`` / ``"A? CL0"`` where older firmware gets ``HN`` /
    ``HF``: the same as HN / HF on the current axis.

``LPE#`` — load the encoder position
    omsBaseController::writeFloat64: ``"A? LPE%d;"`` sets the encoder position of an axis with
    an encoder, where it sends ``LP`` for the motor position; devOmsCom.cc loads the two apart,
    ``"LO%ld LPE%ld;"``. So on a stepper with an encoder LPE loads the encoder alone (the
    mirror of the PCIx's LO, "sets the motor position independently of the encoder
    position"); on a servo, whose position is its encoder, it is LP (the encoder alone loaded
    under a closed loop would move the motor by the difference, as LO, which loads the
    commanded position alone, does there).
    Without this row the PCIx would read ``LP`` (loading 0!) and an unknown ``E``.

``PSO`` / ``PSE`` / ``PSM`` — select the motor type of the current axis
    The MAX-family setters matching ``PS?``'s answers (drvMAXv.cc sets ``typeID`` to ``PSM``,
    ``PSE`` or ``PSO``; the motorOmsAsyn README's example init string is ``"AX LH PSO;"``). A
    PCIx's motor types are not selectable: "The PCIx is configured at the factory for control of
    servo motors, stepper motors or a combination of both" (digest §1.1), and the model row is
    that configuration. The commands are therefore accepted (a MAX init string must not raise a
    command error on every start) and leave the axis as built; ``PS?`` keeps answering the
    truth, so the client sets itself up for the axis it really has.
"""

from __future__ import annotations

import math

from omsd.dialects.interpreter import Interpreter
from omsd.dialects.shared.table import Handler
from omsd.engine.axis import Axis
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.lexer import Command

MAX_HANDLERS: dict[str, Handler] = {}

QL_AXES = 8  # axes the 16-bit QL word has room for (minus limits bits 0-7, plus limits 8-15)


# -- axis state -----------------------------------------------------------------------------------


def motor_type(axis: Axis) -> str:
    """``M`` servo motor, ``E`` stepper with encoder, ``O`` open-loop stepper (``PS?``)."""
    if axis.is_servo:
        return "M"
    return "E" if axis.has_encoder else "O"


def limits_active_high(axis: Axis) -> bool:
    """LH (True) or LL (False, the PCIx factory default: "LL ... Factory default")."""
    return axis.limit_high


def closed_loop(axis: Axis) -> bool:
    """``CL?``: the servo's PID loop runs, or a stepper with encoder maintains position (HN)."""
    if axis.servo is not None:
        return axis.servo.closed
    return axis.has_encoder and axis.hold


def limit_input_high(axis: Axis, direction: int, t: float) -> bool:
    """The TTL level of the limit input for ``direction``: at the LH/LL active level while the
    board senses the limit, at the other level while it does not."""
    return axis.limit_active(direction, t) == limits_active_high(axis)


def limit_word(axes: list[Axis], t: float) -> int:
    """``QL``: bit ``i`` the negative and bit ``i + 8`` the positive limit input of axis ``i``."""
    word = 0
    for i, axis in enumerate(axes[:QL_AXES]):
        if limit_input_high(axis, -1, t):
            word |= 1 << i
        if limit_input_high(axis, 1, t):
            word |= 1 << (i + QL_AXES)
    return word


# -- the commands ---------------------------------------------------------------------------------


def _ps_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value("=" + motor_type(ix.axis), t)


def _lt_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value("=h" if limits_active_high(ix.axis) else "=l", t)


def _cl_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    def word(axis: Axis) -> str:
        return "on" if closed_loop(axis) else "off"

    if ix.mode == "single":
        ix.machine.reply_value("=" + word(ix.axis), t)
    else:
        ix.machine.reply_value(",".join(word(a) for a in ix.machine.axes), t)


def _ql(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.machine.reply_value(f"{limit_word(ix.machine.axes, t):04x}", t)


def _watchdog(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    # the emulated firmware never misses its watchdog: the timeout counter stays at zero
    ix.machine.reply_value("=0", t)


def _closed_loop(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """CL1 = HN, CL0 = HF on the current axis."""
    value = ix.one(cmd)
    assert value is not None
    code = "HN" if value != 0 else "HF"
    axis = ix.axis
    if axis.has_encoder:
        ix.enqueue([(axis, Op(code, (), ix.cost(cell, axis)))])


def _load_encoder(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """LPE#: the encoder position of the current axis. On a stepper with an encoder, the encoder
    alone, as the PCIx's LO loads the motor position alone: the clients load the two apart
    (devOmsCom.cc ``"LO%ld LPE%ld;"``; omsBaseController sends ``LP`` to set the motor position
    and ``LPE`` to set the encoder's). On a servo, whose position is its encoder, and on an axis
    without an encoder, LP."""
    value = ix.one(cmd)
    assert value is not None
    axis = ix.axis
    n = ix.check("LPE", ix.convert(axis, value, "dist"))
    if axis.is_servo or not axis.has_encoder:
        ix.enqueue([(axis, Op("LP", (n,), ix.cost(cell, axis)))])
        return

    def load(a: Axis, when: float) -> None:
        a.anchor_encoder(when, float(math.trunc(n)))
        a.hold_goal = float(a.encoder(when))  # (a hold holds where the axis is)

    ix.enqueue([(axis, Op("SET", ("LPE", load), ix.cost(cell, axis)))])


def _motor_select(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """PSO/PSE/PSM: the PCIx's motor types are fixed at the factory (module docstring); the
    command is accepted and the axis stays as built."""


MAX_HANDLERS.update(
    {
        "PS?": _ps_query,
        "?PS": _ps_query,
        "CL": _closed_loop,
        "LPE": _load_encoder,
        "LT?": _lt_query,
        "CL?": _cl_query,
        "QL": _ql,
        "#WS": _watchdog,
        "PSO": _motor_select,
        "PSE": _motor_select,
        "PSM": _motor_select,
    }
)
