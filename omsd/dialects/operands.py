"""Reading a command's operands, for the handlers: the single operand, positional fields, the
AA-syntax per-axis list; user units and whole-number truncation; the range rows
(:mod:`omsd.protocol.ranges`) every numeric operand is checked against."""

from __future__ import annotations

from decimal import Decimal
from typing import TypeVar

from omsd.engine.axis import Axis
from omsd.engine.machine import Machine
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command
from omsd.protocol.operands import parse_number, truncate
from omsd.protocol.ranges import OperandRange, RangeTable

N = TypeVar("N", Decimal, float, int)


class CommandFailed(Exception):
    def __init__(self, kind: ErrorKind) -> None:
        super().__init__(kind.message)
        self.kind = kind


class Operands:
    """The operand readers of :class:`~omsd.dialects.interpreter.Interpreter` (a mixin)."""

    machine: Machine
    mode: str
    axis_index: int
    ranges: RangeTable

    def one(self, cmd: Command, required: bool = True) -> Decimal | None:
        """The single operand of a single-axis command."""
        fields = cmd.fields
        if not fields or fields == (None,):
            if required:
                raise CommandFailed(ErrorKind.MISSING_PARAMETER)
            return None
        if len(fields) > 1:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        assert fields[0] is not None
        return parse_number(fields[0])

    def fields(self, cmd: Command, count: int) -> list[Decimal | None]:
        """Positional operands (VS#,#,#); missing ones are ``None``."""
        fields = list(cmd.fields or ())
        if len(fields) > count:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        fields += [None] * (count - len(fields))
        return [None if f is None else parse_number(f) for f in fields]

    def required(self, cmd: Command, count: int) -> list[Decimal]:
        """Positional operands that must all be given (ER#,#  MV#,#  CR#,#,#)."""
        values = self.fields(cmd, count)
        present = [v for v in values if v is not None]
        if len(present) < count:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        return present

    def items(self, cmd: Command) -> dict[int, Decimal]:
        """``XX#;`` for the current axis in single-axis mode (the operand required), the
        ``XX#,#,#,#;`` list in AA/AM (skipped fields leave their axis out)."""
        if self.mode == "single":
            value = self.one(cmd)
            assert value is not None
            return {self.axis_index: value}
        return self.per_axis(cmd)

    def per_axis(self, cmd: Command, axes: list[int] | None = None) -> dict[int, Decimal]:
        """AA-syntax operands: ``MRx#,y#,z#,...;`` with skipped fields. Fields beyond the
        fitted axes are ignored (the manual's own ``VL100,...`` of E55 has nine fields)."""
        order = axes if axes is not None else list(range(len(self.machine.axes)))
        out: dict[int, Decimal] = {}
        for i, text in enumerate(cmd.fields or ()):
            if i >= len(order):
                break
            if text is not None:
                out[order[i]] = parse_number(text)
        return out

    def convert(self, axis: Axis, value: Decimal, kind: str) -> float:
        """User units (UU) and integer truncation. ``kind``: "dist" (whole counts), "steps"
        (a position or distance the engine takes to motor steps and truncates there: whole
        counts, but with user units on the fraction is kept), "vel" and "acc" (whole unless
        user units are on), "frac" (fractions kept: JF).

        "steps" is for an encoder ratio (ER), which the engine applies when the command runs:
        with user units "All parameters are then input in the user units which have been
        defined", and "The correct number of motor counts are generated" (PC48 §6.15 ER), the
        ratio "handled internally in floating point format" (§5.3). So ``ER1000,2000 UU0.5
        LP601`` is 300.5 encoder counts, 601 motor steps; truncated to whole encoder counts
        first it was 300 and 600, and every odd step out of reach. Without a ratio the engine's
        truncation gives what truncating here gave."""
        scaled = value * axis.uu if axis.uu is not None else value
        if kind == "steps":
            return float(scaled) if axis.uu is not None else float(truncate(scaled))
        if kind == "dist" or (kind in ("vel", "acc") and axis.uu is None):
            return float(truncate(scaled))
        return float(scaled)

    def operand_range(self, mnemonic: str, operand: int = 1, variant: str = "") -> OperandRange:
        """The row of the dialect's range table (:mod:`omsd.protocol.ranges`) for this model
        family: the one place a command's operand range is stated."""
        return self.ranges.lookup(mnemonic, operand, self.machine.model.family, variant)

    def check(self, mnemonic: str, value: N, operand: int = 1, variant: str = "") -> N:
        """``value`` if its range row holds it, else a command error (``OUT_OF_RANGE``)."""
        row = self.operand_range(mnemonic, operand, variant)
        if not row.contains(value, len(self.machine.axes)):
            raise CommandFailed(ErrorKind.OUT_OF_RANGE)
        return value

    def integer(
        self, value: Decimal | None, mnemonic: str, operand: int = 1, variant: str = ""
    ) -> int:
        """A whole-number operand: truncated toward zero (``MR100.9`` is 100), then checked
        against its range row."""
        if value is None:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        return self.check(mnemonic, truncate(value), operand, variant)
