"""The PC48 family's language: the PC48, PC46 and VS4 (model rows with ``dialect = "oms"``).

The shared OMS language (:mod:`omsd.dialects.shared`) with the commands of
:mod:`~omsd.dialects.pc48.commands`, the range table of :mod:`~omsd.dialects.pc48.ranges`
(rows per family where the PC46 or VS4 differ), the ``<LF><CR>text<LF><CR>`` framing (a status
"one line feed and two carriage returns on each end") and the engine as the PC48 manual
describes it (soft limits one mode for the board, for point-to-point moves only; slip tolerance
0 at power-up; one list of the commands that end position hold and slip detection, HN and IS:
"Hold and slip detection are disabled if an LP, HM, HR, SA, ST or KL command is entered").
"""

from __future__ import annotations

from collections.abc import Mapping

from omsd.dialects.interpreter import Interpreter
from omsd.dialects.pc48.commands import PC48_HANDLERS, PC48_OPS
from omsd.dialects.pc48.ranges import PC48_RANGES
from omsd.dialects.registry import AnyHandler, Dialect, register
from omsd.dialects.shared import HANDLERS, PURE_REPORTS, REPORTS
from omsd.engine.extensions import PC48_CANCELS, Framing, Options
from omsd.engine.states import Motion
from omsd.models.spec import CommandSpec, Model

TABLE: dict[str, AnyHandler] = {**HANDLERS, **PC48_HANDLERS}

#: (a command error is a lone ``#`` in the stream: what EPICS' drvOmsPC68 learns an axis's
#: missing encoder or servo loop from, ``shared/interop/README.md``)
FRAMING = Framing(value=(b"\n\r", b"\n\r"), status=(b"\n\r\r", b"\n\r\r"), error=b"#")

OPTIONS = Options(
    slip_tolerance=0.0,
    soft_limit_per_axis=False,
    soft_limit_motions=frozenset({Motion.MOVE}),
    hold_cancelled_by=PC48_CANCELS,
    slip_cancelled_by=PC48_CANCELS,
    remainder_folds_encoder=False,
    linear_moves_restore=False,
)


def _commands(model: Model) -> Mapping[str, CommandSpec]:
    return model.commands


def _handlers(model: Model) -> Mapping[str, AnyHandler]:
    return TABLE


DIALECT = register(
    Dialect(
        name="oms",
        description="PC48, PC46, VS4",
        commands=_commands,
        handlers=_handlers,
        ranges=PC48_RANGES,
        framing=FRAMING,
        framing_name="surround",
        reports=REPORTS | {"AU", "AV", "AR", "AS"},
        pure_reports=PURE_REPORTS,
        interpreter=Interpreter,
        options=OPTIONS,
        ops=PC48_OPS,
    )
)

__all__ = ["DIALECT", "FRAMING", "OPTIONS", "TABLE"]
