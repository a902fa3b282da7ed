"""The PCIx's language (model rows with ``dialect = "pcix"``), with the MAX-family queries a
model row may switch on (``max_queries``).

The shared OMS language (:mod:`omsd.dialects.shared`) with the PCIx's own handlers over it
(:mod:`~omsd.dialects.pcix.settings`, :mod:`~omsd.dialects.pcix.ramps`,
:mod:`~omsd.dialects.pcix.servo`, :mod:`~omsd.dialects.pcix.reports`,
:mod:`~omsd.dialects.pcix.gearing`, :mod:`~omsd.dialects.pcix.motion`,
:mod:`~omsd.dialects.pcix.stops`) and the MAX family's
(:mod:`~omsd.dialects.pcix.max_family`); its interpreter (:mod:`~omsd.dialects.pcix.interpreter`:
macros, ramp-table definitions, flash, the 32-bit operand check), its range table
(:mod:`~omsd.dialects.pcix.ranges`), its framing (``text<LF><CR>``, nothing before it) and
the engine as the PCIx manual describes it: soft limits per axis, for moves and jogs; slip
tolerance 1 at the factory ("factory default value is 1"); its own lists of the commands that
end position hold (HN's) and slip detection (IS's); RM folds the encoder too; ML/MT put VL, AC
and VB back; the GS home-switch watch at every sensor look.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache

from omsd.dialects.pcix import gearing, motion, ramps, reports, servo, settings, stops
from omsd.dialects.pcix.common import PCIX_HANDLERS, PCIX_OPS
from omsd.dialects.pcix.interpreter import PcixInterpreter, check_32_bit
from omsd.dialects.pcix.max_family import MAX_HANDLERS
from omsd.dialects.pcix.motion import watch_home_switch
from omsd.dialects.pcix.ranges import PCIX_RANGES
from omsd.dialects.registry import AnyHandler, Dialect, register
from omsd.dialects.shared import HANDLERS, PURE_REPORTS, REPORTS
from omsd.engine.extensions import Framing, Options
from omsd.engine.states import Motion
from omsd.models import MODELS
from omsd.models.max_family import MAX_COMMANDS
from omsd.models.spec import CommandSpec, Model

_MODULES = (gearing, motion, ramps, reports, servo, settings, stops)  # each files its handlers

#: (a command error sends nothing: it sets CMD_S in the status register, PCIx §3.9 "CMD_S Command
#: error", and the manual defines no text for it; a byte would stick to the front of the next
#: reply, which a MAX-family client reads as text<LF><CR> with nothing before it)
FRAMING = Framing(value=(b"", b"\n\r"), status=(b"", b"\n\r"), error=b"")

#: HN: "For stepper axes with encoders, this mode will be canceled (as though via an HF command)
#: if an CG, CX, HM, HR, MV, SO, SP command is entered, if a limit is encountered or the maximum
#: allowable position error is executed." (LP, SA, ST and KL, the PC48's, are not in it.)
HOLD_CANCELLED_BY = frozenset({"CG", "CX", "HM", "HR", "MV", "SO", "SP"})

#: IS: "Slip detection are disabled if a ER, ET, HF, HM, HR, JG, LP, or TM command is entered or
#: if a limit is encountered." (JF, "like the JG command", with JG; SA, ST and KL are not in it.)
SLIP_CANCELLED_BY = frozenset({"ER", "ET", "HF", "HM", "HR", "JG", "LP", "TM"})

OPTIONS = Options(
    slip_tolerance=1.0,
    soft_limit_per_axis=True,
    soft_limit_motions=frozenset({Motion.MOVE, Motion.JOG}),
    hold_cancelled_by=HOLD_CANCELLED_BY,
    slip_cancelled_by=SLIP_CANCELLED_BY,
    remainder_folds_encoder=True,
    linear_moves_restore=True,
    home_loads_encoder=True,
    # §5.5.1: "In power-automatic mode, the auxiliary line will invert at the beginning of every
    # motion and return to normal at the end" (the PA page names GO and GD; the queue tables of
    # TM, JG, JF, MV, HM, HR, KM, KR, CX and CG charge "If PA ... is active add n" too). Not VS,
    # MO or gearing, whose tables have no PA row, nor the hold's own corrections.
    power_automatic_motions=frozenset(
        {Motion.MOVE, Motion.JOG, Motion.STAIRCASE, Motion.HOME, Motion.CONTOUR}
    ),
)


def _commands(model: Model) -> Mapping[str, CommandSpec]:
    """The model's command table, with the MAX-family extension when it is switched on."""
    if model.max_queries:
        return {**model.commands, **MAX_COMMANDS}
    return model.commands


@cache
def _table(max_queries: bool) -> dict[str, AnyHandler]:
    table: dict[str, AnyHandler] = {**HANDLERS, **PCIX_HANDLERS}
    if max_queries:
        table.update(MAX_HANDLERS)
    return table


def _handlers(model: Model) -> Mapping[str, AnyHandler]:
    return _table(model.max_queries)


def _queries() -> frozenset[str]:
    """Every ``?XX`` query of every PCIx table (and the MAX family's ``?PS``)."""
    tables = [m.commands for m in MODELS.values() if m.dialect == "pcix"] + [MAX_COMMANDS]
    return frozenset(m for table in tables for m in table if m.startswith("?"))


DIALECT = register(
    Dialect(
        name="pcix",
        description="PCIx, with the MAX-family queries",
        commands=_commands,
        handlers=_handlers,
        ranges=PCIX_RANGES,
        framing=FRAMING,
        framing_name="trailing",
        reports=REPORTS
        | {"PP", "PE", "PM", "EG?"}
        | {"QL", "#WS", "PS?", "LT?", "CL?"}
        | _queries(),
        pure_reports=PURE_REPORTS | _queries(),
        loop_reports=frozenset({"RE", "?AB"}),
        interpreter=PcixInterpreter,
        options=OPTIONS,
        ops=PCIX_OPS,
        sensor_hooks=(watch_home_switch,),
        long_mnemonics=True,
        check_fields=check_32_bit,
        feedback_per_axis=True,
    )
)

__all__ = ["DIALECT", "FRAMING", "OPTIONS"]
