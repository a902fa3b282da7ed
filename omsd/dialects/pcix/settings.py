"""PCIx settings: modes, flash (AP, RD, RF, ADH, ADL), macros (MD, MX, PM, PT), the simple
axis parameters and the queries of one value (PCIx manual ch. 5)."""

from __future__ import annotations

import math
from collections.abc import Callable

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix import flash
from omsd.dialects.pcix.common import (
    PCIX_HANDLERS,
    apply_to,
    flag_axes,
    handles,
    one_integer,
    reply,
    setter,
)
from omsd.dialects.pcix.interpreter import PcixInterpreter
from omsd.dialects.shared.reports import rounded_off
from omsd.engine.axis import Axis
from omsd.engine.queue import Op
from omsd.models.spec import Cell
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command

# -- axis selection and modes ---------------------------------------------------------------------


@handles("?AQ")
def _aq(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "reports the mode that the current axis is in, i.e. AA mode, AM mode, etc." (``ax``)."""
    mode = ix.mode
    reply(ix, ("a" + ix.axis.letter.lower()) if mode == "single" else mode.lower(), t)


# -- flash: AP, RD, RF, ADH, ADL ------------------------------------------------------------------


@handles("AP")
def _ap(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "The AP command stores the current parameter set as the power-up default set"."""
    ix.write_flash(flash.board_parameters(ix.machine))


@handles("RD")
def _rd(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "restores the motion parameters using power-up defaults" (the factory values where AP
    was never used), through every axis queue (``PcixInterpreter.restore_defaults``)."""
    ix.restore_defaults()


@handles("RF")
def _rf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "sets the current parameters to the factory defaults. This process does not alter the
    parameters stored in flash via the AP command"."""
    flash.factory(ix.machine)


@handles("ADH", "ADL")
def _ad(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """The auxiliary output's power-up state; "This command will also archive all other
    parameter values as power up defaults"."""
    ix.axis.aux_default_high = cmd.mnemonic == "ADH"
    ix.write_flash(flash.board_parameters(ix.machine))


@handles("?AD")
def _q_ad(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    reply(ix, "adh" if ix.axis.aux_default_high else "adl", t)


# -- macros ---------------------------------------------------------------------------------------


def _macro_number(ix: PcixInterpreter, cmd: Command) -> int:
    """MD "0 ≤ MD ≤ 4", MX "0 ≤ MX ≤ 24", PM "0 ≤ PM ≤ 24" (their range rows)."""
    return one_integer(ix, cmd)


@handles("MD")
def _md(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "MD# ... the number must be from 0 to 4": what follows, up to Control-Z or ``^Z``, is
    the macro."""
    ix.record_macro(_macro_number(ix, cmd))


@handles("MX")
def _mx(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    text = ix.macros.get(_macro_number(ix, cmd))
    if text is None:
        raise CommandFailed(ErrorKind.NO_MACRO)
    ix.run_macro(text)


@handles("PM")
def _pm(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "returns the contents of the specified macro"; nothing when it is empty."""
    text = ix.macros.get(_macro_number(ix, cmd))
    if text is not None:
        reply(ix, text.decode("latin-1"), t)


@handles("PT")
def _pt(ix: PcixInterpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "PT#,#; copies temporary macro # (0-4) to permanent macro # (5-24)"."""
    src, dst = ix.required(cmd, 2)
    n, m = ix.integer(src, "PT", 1), ix.integer(dst, "PT", 2)
    text = ix.macros.get(n)
    if text is None:
        raise CommandFailed(ErrorKind.NO_MACRO)
    ix.macros.define(m, text)
    ix.write_flash()


@handles("DBI", "DBN")
def _db(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    value = cmd.mnemonic == "DBI"
    apply_to(ix, cmd, cell, flag_axes(ix, cmd), setter("direction_inverted", value), t)


@handles("LH", "LL")
def _lh(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    high = cmd.mnemonic == "LH"

    def apply(axis: Axis, t: float) -> None:
        # the lines read the other way from now on: a moving axis looks at them on this sample
        # (a line that now reads true stops it, LN: "if the axis encounters a limit switch in
        # the course of executing any motion, the axis will be instructed to stop")
        axis.limit_high = high
        axis.look_at_sensors(t)

    apply_to(ix, cmd, cell, flag_axes(ix, cmd), apply, t)


@handles("HH", "HL")
def _hh(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Home switch level; "The HL and HH commands are not valid" in the encoder home mode."""
    axes = flag_axes(ix, cmd)
    if any(a.home_encoder for a in axes):
        raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
    apply_to(ix, cmd, cell, axes, setter("home_high", cmd.mnemonic == "HH"), t)


@handles("HE", "HS")
def _he(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    apply_to(ix, cmd, cell, flag_axes(ix, cmd), setter("home_encoder", cmd.mnemonic == "HE"), t)


@handles("LN", "LF", "SL", "SF")
def _limits(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    ix.enqueue([(a, Op(cmd.mnemonic, (), ix.cost(cell, a))) for a in flag_axes(ix, cmd)])


@handles("TN", "TF")
def _tn(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Slip kill: a slip beyond ES kills the axis "as though a KL command had been issued"."""
    apply_to(ix, cmd, cell, [ix.axis], setter("slip_kill", cmd.mnemonic == "TN"), t)


@handles("DC")
def _dc(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """ "1 ≤ DC ≤ 8000000": the deceleration GU uses."""
    axis = ix.axis
    raw = ix.one(cmd)
    assert raw is not None
    value = ix.check("DC", ix.convert(axis, raw, "acc"))

    def apply(a: Axis, when: float) -> None:
        # motor steps with the ratio in force when the queue reaches DC ("DC#; AX - AT 2"), as AC
        a.dc = a.to_motor(value)
        a.invalidate()

    apply_to(ix, cmd, cell, [axis], apply, t)


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
    reply(ix, _QUERIES[cmd.mnemonic](ix.axis, t), t)


for _m in _QUERIES:
    PCIX_HANDLERS[_m] = _query


@handles("?SL")
def _q_sl(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    reply(ix, "sl" if ix.axis.soft_limit else "sf", t)


@handles("UF")
def _uf(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """User units off: ``UF;`` or ``UFb,b,b,b;`` ("equivalent to and preferred over UU1;")."""
    for axis in flag_axes(ix, cmd):
        axis.uu = None


@handles("?ER")
def _q_er(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    """Motor steps per encoder count: ``ER1,2`` ("The encoder produces 1 count for every 2
    steps of the motor") answers ``er2.0``."""
    ratio = 1.0 / ix.axis.ratio
    text = f"{ratio:.6f}".rstrip("0")
    reply(ix, "er" + (text + "0" if text.endswith(".") else text), t)


@handles("?UU")
def _q_uu(ix: Interpreter, cmd: Command, cell: Cell, t: float) -> None:
    uu = ix.axis.uu
    # "six digits to the right of the decimal point ... rounded off to the sixth decimal place"
    reply(ix, "uf" if uu is None else "uu" + rounded_off(uu, 6), t)
