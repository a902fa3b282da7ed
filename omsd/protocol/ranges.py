"""Operand ranges as data: one row per command operand, each with the manual's words.

The dialect tables (:mod:`omsd.dialects.pc48.ranges` for the PC48, PC46 and VS4,
:mod:`omsd.dialects.pcix.ranges` for the PCIx) hold an :class:`OperandRange` for every operand of
every command that takes a number; the interpreter asks them (``Interpreter.check`` and
``Interpreter.integer``) instead of carrying bounds of its own, so the table is the one place a
range is stated. A value outside its row sets the command-error flag with
``ErrorKind.OUT_OF_RANGE`` — except for a row with a ``default`` (PN: "A parameter out of this
range or no parameter supplied defaults to 70% or 3 steps"), where the default is taken
instead.

How a row is read:

* ``operand`` is the 1-based position of the operand (``MV#,#``: 1 the position, 2 the
  velocity). The single operand of ``XX#`` and each axis's field of an AA list ``XX#,#,#;`` are
  operand 1: a list gives every axis its own operand 1.
* ``low``/``high`` are the edges, ``None`` where there is none; ``low_open``/``high_open`` make an
  edge exclusive ("greater than zero", "less than 8,000,000"). ``high_axes`` makes the upper edge
  the number of axes fitted (PCIx AJ: "1 ≤ # ≤ number of axes on board").
* ``number``: ``"integer"`` — a whole number; a fraction is truncated toward zero before the check
  (``MR100.9`` moves 100, the design decision for every whole-number operand); ``"decimal"`` — the
  fraction is kept; ``"hex"`` — hexadecimal digits (PCIx BS); ``"flag"`` — the value only says
  *which* axis (``AN1,,1;``) or *whether* (PA non-zero), any number is accepted.
* ``scaled``: the edges are in steps (or counts) after user units (UU) and the encoder ratio
  (ER) have been applied to the operand, as the manual words them ("steps per second").
* ``magnitude``: the edges apply to the size of the value, either sign accepted.
* ``families``: the model families (``Model.family``) the row is for; an empty tuple means every
  family of the table. A row naming a family wins over the general row, which is how the PC46
  and VS4 differ from the PC48.
* ``variant``: a runtime condition the interpreter names when it looks the row up (PCIx BC:
  ``"stepper"`` or ``"servo"``).
* ``cite`` is the manual's statement (file, section or page, words); ``choice`` records what
  was chosen where the manual states no range ("manual silent: chose X because Y") or
  contradicts itself ("manual contradicts itself: ...").

This module and the tables import nothing from the board: they are data a later dialect package
can take with it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from decimal import Decimal
from typing import Literal

Number = Literal["integer", "decimal", "hex", "flag"]
Value = Decimal | float | int


@dataclass(frozen=True)
class OperandRange:
    """The range of one operand of one command, as the manual states it."""

    mnemonic: str
    operand: int = 1
    name: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    number: Number = "integer"
    units: str = ""
    cite: str = ""
    choice: str = ""
    families: tuple[str, ...] = ()
    variant: str = ""
    scaled: bool = False
    magnitude: bool = False
    high_axes: bool = False
    default: float | None = None

    def __post_init__(self) -> None:
        if not (self.cite or self.choice):
            raise ValueError(f"{self.mnemonic} operand {self.operand}: no citation, no choice")
        if self.number == "flag" and (self.low is not None or self.high is not None):
            raise ValueError(f"{self.mnemonic}: a flag operand has no edges")

    def edges(self, axes: int = 0) -> tuple[float | None, float | None]:
        """Lower and upper edge for a board with ``axes`` axes."""
        return self.low, (float(axes) if self.high_axes else self.high)

    def contains(self, value: Value, axes: int = 0) -> bool:
        """Whether ``value`` is inside the row's edges, compared as the decimal numbers they are
        written as (``JF1043999.995`` is inside "≤ 1,043,999.995")."""
        if self.number == "flag":
            return True
        if isinstance(value, float) and not math.isfinite(value):
            return False
        v = _decimal(value)
        if self.magnitude:
            v = abs(v)
        low, high = self.edges(axes)
        if low is not None:
            lo = _decimal(low)
            if v < lo or (self.low_open and v == lo):
                return False
        if high is not None:
            hi = _decimal(high)
            if v > hi or (self.high_open and v == hi):
                return False
        return True

    def describe(self, axes: int = 0) -> str:
        """``0 < ES ≤ 65535``, ``-50 ≤ BC ≤ 50 (servo)``, ``AN: any (flag)``."""
        name = self.mnemonic if self.operand == 1 and not self.name else self.name or "value"
        if self.magnitude:
            name = f"|{name}|"
        if self.number == "flag":
            return f"{self.mnemonic}: any number ({self.units or 'flag'})"
        low, high = self.edges(axes)
        text = name
        if low is not None:
            text = f"{_num(low)} {'<' if self.low_open else '≤'} {text}"
        if high is not None:
            text = f"{text} {'<' if self.high_open else '≤'} {_num(high)}"
        if low is None and high is None:
            text = f"{name}: no bound"
        return text + (f" ({self.variant})" if self.variant else "")


def _decimal(x: Value) -> Decimal:
    if isinstance(x, Decimal):
        return x
    if isinstance(x, int):
        return Decimal(x)
    return Decimal(repr(x))  # the shortest decimal that reads back as the float


def _num(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else repr(x)


class RangeTable:
    """The rows of one dialect, looked up by mnemonic, operand position, family and variant."""

    def __init__(self, dialect: str, families: Iterable[str], rows: Iterable[OperandRange]):
        self.dialect = dialect
        self.families = tuple(families)
        self.rows: tuple[OperandRange, ...] = tuple(rows)
        self._by: dict[tuple[str, int], list[OperandRange]] = {}
        for row in self.rows:
            unknown = set(row.families) - set(self.families)
            if unknown:
                raise ValueError(f"{row.mnemonic}: unknown families {sorted(unknown)}")
            self._by.setdefault((row.mnemonic, row.operand), []).append(row)
        self._cache: dict[tuple[str, int, str, str], OperandRange] = {}

    def lookup(
        self, mnemonic: str, operand: int = 1, family: str = "", variant: str = ""
    ) -> OperandRange:
        """The row for ``mnemonic``'s ``operand`` on ``family``: a row naming the family wins
        over a general one; where rows carry variants, the one named ``variant``. KeyError if
        the table has none (a command without a row cannot take a number)."""
        key = (mnemonic, operand, family, variant)
        row = self._cache.get(key)
        if row is not None:
            return row
        candidates = [
            r
            for r in self._by.get((mnemonic, operand), ())
            if (not r.families or family in r.families) and r.variant in ("", variant)
        ]
        if not candidates:
            raise KeyError(f"no range for {mnemonic} operand {operand} ({family} {variant})")
        candidates.sort(key=lambda r: (bool(r.families), r.variant == variant), reverse=True)
        row = candidates[0]
        self._cache[key] = row
        return row

    def operands(self, mnemonic: str, family: str = "") -> list[int]:
        """The operand positions ``mnemonic`` has rows for on ``family``."""
        return sorted(
            {
                operand
                for (m, operand), rows in self._by.items()
                if m == mnemonic and any(not r.families or family in r.families for r in rows)
            }
        )

    def covers(self, mnemonic: str, family: str = "") -> bool:
        return bool(self.operands(mnemonic, family))

    def for_family(self, family: str) -> list[OperandRange]:
        """Every row that applies on ``family`` (the general rows a family row overrides are
        left out)."""
        out: list[OperandRange] = []
        for (mnemonic, operand), rows in self._by.items():
            variants = sorted({r.variant for r in rows})
            for variant in variants:
                try:
                    row = self.lookup(mnemonic, operand, family, variant)
                except KeyError:
                    continue
                if row not in out:
                    out.append(row)
        return out


__all__ = ["Number", "OperandRange", "RangeTable", "Value"]
