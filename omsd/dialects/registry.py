"""Dialects: which command language a model row speaks, and what that language gives the engine.

A :class:`Dialect` is a record: the language's handler table and command table (the latter from
the model row, with any extension it switches on), its operand-range table, its framing and
lexer options, the commands that only report (the interpreter's hot path skips running the
queues after them), the engine options, ops and sensor hooks it needs, and the interpreter class
that runs it. Each dialect package registers its record here (:func:`register`); the board looks
the model row's dialect up (:func:`lookup`) and joins the three in ``Board(...)``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from omsd.engine.executor import OpFunction, SensorHook
from omsd.engine.extensions import Framing, Options
from omsd.models.spec import Cell, CommandSpec, Model
from omsd.protocol.lexer import Command
from omsd.protocol.ranges import RangeTable

#: A command's behaviour: ``handler(interpreter, command, cell, t)``. A dialect's handlers may
#: expect its own interpreter class; the table is only ever used with that class.
AnyHandler = Callable[[Any, Command, Cell, float], None]


@dataclass(frozen=True, eq=False, repr=False)
class Dialect:
    """A command language, as the board needs it (see the module's text); one a language, so
    compared by identity, and without a repr (of its tables and functions)."""

    name: str  # the model row's ``dialect``
    description: str
    commands: Callable[[Model], Mapping[str, CommandSpec]]
    handlers: Callable[[Model], Mapping[str, AnyHandler]]
    ranges: RangeTable
    #: the framing of its replies, and the name a model row gives it (``Model.framing``)
    framing: Framing
    framing_name: str
    #: commands that only report or select an axis: they queue nothing
    reports: frozenset[str]
    #: the interpreter class, ``interpreter(machine, dialect)``: the generic one
    #: (:class:`omsd.dialects.interpreter.Interpreter`) or a subclass with the dialect's state
    interpreter: Callable[[Any, Dialect], Any]
    options: Options = field(default_factory=Options)
    ops: Mapping[str, OpFunction] = field(default_factory=dict)
    sensor_hooks: Sequence[SensorHook] = ()
    #: mnemonics longer than two letters (the lexer needs every proper beginning of one)
    long_mnemonics: bool = False
    #: a check of every command's numeric fields before its handler runs
    check_fields: Callable[[Command], None] | None = None
    #: queue cost: an axis's own encoder decides the feedback column (else the board's option)
    feedback_per_axis: bool = False
    #: the reports that change nothing at all (``omsd.dialects.shared.table.PURE_REPORTS``)
    pure_reports: frozenset[str] = frozenset()
    #: those of them that run a servo loop up to the moment they are asked (the encoder's
    #: count): not pure on a board with servo axes (``Board.pure_reports``)
    loop_reports: frozenset[str] = frozenset()


_DIALECTS: dict[str, Dialect] = {}

#: Where each dialect is (:func:`known`), imported (and so registered) when it is first looked
#: up: a daemon of PC48-family boards never loads the PCIx's language (start-up, issue 16).
#: ``_FRAMINGS``: the dialect whose framing each framing name is.
_MODULES: dict[str, str] = {}
_FRAMINGS: dict[str, str] = {}


def known(name: str, module: str, framing_name: str) -> None:
    """Dialect ``name`` is in ``module`` (which registers it when imported), and its framing is
    the one model rows call ``framing_name``."""
    _MODULES[name] = module
    _FRAMINGS[framing_name] = name


def register(dialect: Dialect) -> Dialect:
    _DIALECTS[dialect.name] = dialect
    return dialect


def lookup(name: str) -> Dialect:
    found = _DIALECTS.get(name)
    if found is None and name in _MODULES:
        importlib.import_module(_MODULES[name])
        found = _DIALECTS.get(name)
    if found is None:
        known = ", ".join(sorted(_MODULES))
        raise KeyError(f"no dialect {name!r} (known: {known})")
    return found


def registered() -> list[str]:
    """Every dialect (each imported, if it was not yet)."""
    for name in _MODULES:
        lookup(name)
    return sorted(_DIALECTS)


def commands(model: Model) -> Mapping[str, CommandSpec]:
    """The model's command table, with any extension its dialect switches on."""
    return lookup(model.dialect).commands(model)


def handlers(model: Model) -> Mapping[str, AnyHandler]:
    return lookup(model.dialect).handlers(model)


def ranges(model: Model) -> RangeTable:
    """The operand ranges of the model's language (:mod:`omsd.protocol.ranges`)."""
    return lookup(model.dialect).ranges


def framing(model: Model) -> Framing:
    """The framing the model row names: the framing of the dialect whose framing it is (a row
    may name another dialect's: a PC48 presented as the MAX family presents it)."""
    name = _FRAMINGS.get(model.framing)
    if name is None:
        raise KeyError(f"no framing {model.framing!r}")
    dialect = lookup(name)
    assert dialect.framing_name == model.framing, (dialect.name, model.framing)
    return dialect.framing


def prefixes(table: Mapping[str, CommandSpec] | Sequence[str]) -> frozenset[str]:
    """Every proper beginning of a mnemonic, for the lexer: ``A``, ``AD`` (of ``ADH``), ``?``,
    ``?A`` (of ``?AC``), ``EG`` (of ``EG?``), ``#``, ``#W``."""
    out: set[str] = set()
    for m in table:
        for n in range(1, len(m)):
            out.add(m[:n])
    return frozenset(out)
