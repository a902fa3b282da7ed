"""PCIx servo axes: the gains (KP ... DZ and their queries), the DAC mode (BI/UN, SVN/SVI) and
the loop (HN/HF, ?PM) (PCIx §2.7, §5.11)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

from omsd.dialects.interpreter import Interpreter
from omsd.dialects.pcix.common import (
    PCIX_HANDLERS,
    apply_to,
    flag_axes,
    handles,
    one_integer,
    one_value,
    reply,
)
from omsd.engine.axis import Axis
from omsd.engine.queue import Op
from omsd.engine.servo import ServoGains
from omsd.models.spec import Cell
from omsd.protocol.lexer import Command

# -- servo: gains, DAC mode, loop -----------------------------------------------------------------

# mnemonic -> (ServoGains field, places in the query reply; None = integer); the ranges are the
# rows of omsd.dialects.pcix.ranges ("RANGE: 0.00 ≤ KP ≤ 32767.00" ...)
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
    number = float(one_value(ix, cmd)) if places is not None else float(one_integer(ix, cmd))
    apply_to(ix, cmd, cell, [ix.axis], _set_gains(**{name: number}), t)


#: "?KP" -> the ServoGains field, and the reply's format for a gain with places ("kp%.2f",
#: the same digits as ``fixed``) or its prefix for an integer one ("kf")
_GAIN_QUERIES: dict[str, tuple[str, str, bool]] = {
    "?" + m: (name, f"{m.lower()}%.{places}f" if places is not None else m.lower(), places is None)
    for m, (name, places) in _GAINS.items()
}
_FACTORY_GAINS = ServoGains()


def _gain_query(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    name, form, integer = _GAIN_QUERIES[cmd.mnemonic]
    servo = ix.axis.servo
    value = float(getattr(servo.gains if servo is not None else _FACTORY_GAINS, name))
    reply(ix, form + str(math.trunc(value)) if integer else form % value, t)


for _m in _GAINS:
    PCIX_HANDLERS[_m] = _gain
    PCIX_HANDLERS["?" + _m] = _gain_query


@handles("BI", "UN")
def _bi(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Servo output ±10 V (BI) or 0..+10 V (UN)."""
    apply_to(ix, cmd, cell, [ix.axis], _set_gains(bipolar=cmd.mnemonic == "BI"), t)


@handles("SVN", "SVI")
def _sv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Positive voltage for positive motion (SVN) or negative (SVI)."""
    apply_to(ix, cmd, cell, [ix.axis], _set_gains(inverted=cmd.mnemonic == "SVI"), t)


def _servo_gains(axis: Axis) -> ServoGains:
    return axis.servo.gains if axis.servo is not None else ServoGains()


@handles("?SO")
def _q_so(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    reply(ix, "bi" if _servo_gains(ix.axis).bipolar else "un", t)


@handles("?SV")
def _q_sv(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    reply(ix, "svi" if _servo_gains(ix.axis).inverted else "svn", t)


@handles("?PM")
def _q_pm(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """PID (hold) state of the current axis: ``hn`` / ``hf`` (a stepper with an encoder: its
    position maintenance; an open-loop stepper: ``hf``, it holds nothing)."""
    axis = ix.axis
    on = axis.servo.closed if axis.servo is not None else axis.hold
    reply(ix, "hn" if on else "hf", t)


@handles("HN", "HF")
def _hn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """HN closes a servo loop or starts a stepper's position maintenance; HF opens / stops it.
    ``HNb,b,b,b;`` in AA/AM: "a null value in the argument list specifies feedback for that axis
    is not to be" changed; with no list, HN no axis (§5.1's rule, ``flag_axes``) and HF every
    axis with feedback (HF: "If the current mode is multi-axis, all axes will go into open-loop
    mode"; its table prints "HF; AA-AM 2")."""
    axes = [
        a for a in flag_axes(ix, cmd, "all" if cmd.mnemonic == "HF" else "none") if a.has_encoder
    ]
    if ix.mode != "single" and not axes:
        return
    # HN: 1 unit, "2 for servo" axes
    extra = 1 if cmd.mnemonic == "HN" else 0
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a) + extra * a.is_servo)) for a in axes])
