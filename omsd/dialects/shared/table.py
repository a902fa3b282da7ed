"""The handler table of the OMS language the PC48 family and the PCIx share (PC48 chapter 6).

A handler receives the interpreter, the lexed command and the queue-table cell for the current
mode (from the personality's data). It either acts at once (status requests, IC, UU…) or builds
:class:`~omsd.engine.queue.Op` objects and hands them to
:meth:`~omsd.dialects.interpreter.Interpreter.enqueue`, which charges the slots the manual's
table gives. Operand ranges are rows of the dialect's range table, each quoting its manual;
handlers ask :meth:`~omsd.dialects.operands.Operands.check` and
:meth:`~omsd.dialects.operands.Operands.integer`, and a value outside its row sets the
command-error flag (:class:`~omsd.dialects.operands.CommandFailed`).

The chapters of the manual each have a module here that files its handlers in :data:`HANDLERS`
with :func:`handles`; a dialect starts from this table and adds or replaces its own.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from omsd.dialects.interpreter import Interpreter
from omsd.models.spec import Cell
from omsd.protocol.lexer import Command

Handler = Callable[[Interpreter, Command, Cell, float], None]
HANDLERS: dict[str, Handler] = {}

H = TypeVar("H")
Registrar = Callable[..., Callable[[H], H]]


def registrar(table: dict[str, H]) -> Callable[..., Callable[[H], H]]:
    """A ``@handles("XX", ...)`` decorator that files handlers in ``table`` (one per dialect
    module)."""

    def handles(*mnemonics: str) -> Callable[[H], H]:
        def register(fn: H) -> H:
            for m in mnemonics:
                table[m] = fn
            return fn

        return register

    return handles


handles = registrar(HANDLERS)

#: Commands of the shared language that only report or select an axis: they queue nothing, so
#: the axes need not be run after them (the interpreter's hot path: a client polling QA/RP).
REPORTS = frozenset(
    {
        *("RP", "RE", "RA", "QA", "QI", "RI", "RV", "RC", "RU", "RQ", "WY", "BX", "EA", "RL"),
        *("AX", "AY", "AZ", "AT", "AM"),
    }
)

#: The reports among them that change nothing (no flag reset, no axis selected): run twice,
#: they say the same, so a board at rest may answer them again from what it said
#: (``Board._reports_at_rest``; each is checked on every model by
#: ``tests/board/test_fast_paths.py::test_a_pure_report_changes_nothing``).
PURE_REPORTS = frozenset({"RP", "RE", "QA", "QI", "RV", "RC", "RU", "RQ", "WY", "BX", "RL"})
