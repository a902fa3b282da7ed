"""Operand values (PC48 §6.1 and §6.3).

"The '#' indicates a signed integer input parameter or a signed fixed point number of the format
##.# when user units are enabled." Numbers are parsed exactly (``decimal.Decimal``) so that user
unit arithmetic such as ``MA,,.5`` with ``UU10000`` gives exactly 5000 steps.

A fraction where the board expects an integer is truncated toward zero: real clients send
``MR100.9`` and ``MR-5.9`` and the board moves 100 and -5 steps (``shared/interop/README.md``).
"""

from __future__ import annotations

import re
from decimal import ROUND_DOWN, Decimal, InvalidOperation

from omsd.protocol.errors import ErrorKind

_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)\Z")


class OperandError(Exception):
    """A field that is not a usable number; carries the command-error reason."""

    def __init__(self, kind: ErrorKind) -> None:
        super().__init__(kind.message)
        self.kind = kind


def parse_number(text: str) -> Decimal:
    if not _NUMBER.match(text):
        raise OperandError(ErrorKind.BAD_NUMBER)
    try:
        return Decimal(text)
    except InvalidOperation as exc:  # pragma: no cover - the regex admits only valid literals
        raise OperandError(ErrorKind.BAD_NUMBER) from exc


def parse_field(text: str | None) -> Decimal | None:
    return None if text is None else parse_number(text)


def truncate(value: Decimal) -> int:
    """Toward zero, as the board does with ``MR100.9``."""
    return int(value.to_integral_value(rounding=ROUND_DOWN))


def check_range(value: Decimal | float | int, low: float, high: float) -> None:
    if not low <= value <= high:
        raise OperandError(ErrorKind.OUT_OF_RANGE)
