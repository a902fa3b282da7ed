"""Which handlers and which mnemonics a personality's command language has.

The PC48, PC46 and VS4 speak one language (:mod:`omsd.board.commands`). The PCIx speaks a newer
one: most commands keep their names and meaning, some change (its own handlers in
:mod:`omsd.board.pcix_commands` replace the older ones), and there are two- and three-letter
mnemonics, ``?XX`` queries and ``EG?``. With ``Model.max_queries`` the MAX-family queries the
EPICS omsMAXnet client sends are added (:mod:`omsd.board.max_family`).
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cache
from typing import TYPE_CHECKING

from omsd.models.spec import CommandSpec, Model
from omsd.protocol.ranges import RangeTable
from omsd.protocol.ranges_pc48 import PC48_RANGES
from omsd.protocol.ranges_pcix import PCIX_RANGES

if TYPE_CHECKING:
    from omsd.board.commands import Handler


@cache
def _tables(dialect: str, max_queries: bool) -> dict[str, Handler]:
    from omsd.board.commands import HANDLERS

    table = dict(HANDLERS)
    if dialect == "pcix":
        from omsd.board.pcix_commands import PCIX_HANDLERS
        from omsd.board.pcix_motion import MOTION_HANDLERS

        table.update(PCIX_HANDLERS)
        table.update(MOTION_HANDLERS)
        if max_queries:
            from omsd.board.max_family import MAX_HANDLERS

            table.update(MAX_HANDLERS)
    return table


def handlers(model: Model) -> Mapping[str, Handler]:
    return _tables(model.dialect, model.max_queries and model.dialect == "pcix")


def commands(model: Model) -> Mapping[str, CommandSpec]:
    """The model's command table, with the MAX-family extension when it is switched on."""
    if model.dialect == "pcix" and model.max_queries:
        from omsd.models.max_family import MAX_COMMANDS

        return {**model.commands, **MAX_COMMANDS}
    return model.commands


def ranges(model: Model) -> RangeTable:
    """The operand ranges of the model's language (:mod:`omsd.protocol.ranges`): the PC48
    family's table (rows per family for the PC46 and VS4) or the PCIx's."""
    return PCIX_RANGES if model.dialect == "pcix" else PC48_RANGES


def prefixes(table: Mapping[str, CommandSpec]) -> frozenset[str]:
    """Every proper beginning of a mnemonic, for the lexer: ``A``, ``AD`` (of ``ADH``), ``?``,
    ``?A`` (of ``?AC``), ``EG`` (of ``EG?``), ``#``, ``#W``."""
    out: set[str] = set()
    for m in table:
        for n in range(1, len(m)):
            out.add(m[:n])
    return frozenset(out)
