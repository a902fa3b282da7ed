"""The constants and row constructors the parts of the PCIx's range table share."""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange

PCIX = "PCIx manual (seeds/002_5f0bea9264c6d239.txt)"

FAMILIES = ("PCIX",)

POSITION = 33_554_431
POSITION_CITE = f"{PCIX} LP page: “RANGE: −33,554,431 ≤ LP ≤ 33,554,431”"
SLIP = "the printed 33,544,431 is the LP page's 33,554,431 with a digit slipped (models/pcix.py)"

SILENT = "manual silent: "
CONTRADICTS = "manual contradicts itself: "
CHOSEN = "chosen: "  # the manual's bound cannot be applied as written (it depends on the queue)
NOTE = "note: "

_R = OperandRange


def page(mnemonic: str, words: str) -> str:
    return f"{PCIX} {mnemonic} page: “{words}”"


def position(mnemonic: str, operand: int = 1, name: str = "position", **kw: str) -> _R:
    """A position or distance in counts: ±33,554,431."""
    return _R(
        mnemonic,
        operand,
        name,
        -POSITION,
        POSITION,
        units="counts (user units scaled)",
        scaled=True,
        cite=kw.get("cite", POSITION_CITE),
        choice=kw.get("choice", ""),
    )


def flag(mnemonic: str, words: str, units: str = "axis selector: a value picks the axis") -> _R:
    return _R(mnemonic, number="flag", units=units, cite=page(mnemonic, words))


def whole(
    mnemonic: str,
    low: float,
    high: float,
    words: str,
    operand: int = 1,
    name: str = "",
    **kw: object,
) -> _R:
    return _R(mnemonic, operand, name, low, high, cite=page(mnemonic, words), **kw)  # type: ignore[arg-type]


def gain(mnemonic: str, low: float, high: float, words: str, number: str = "decimal") -> _R:
    return _R(
        mnemonic,
        1,
        "coefficient",
        low,
        high,
        number=number,  # type: ignore[arg-type]
        cite=page(mnemonic, words),
    )


S_CURVE_FRACTION = "ALOWER, APEAK, DLOWER, DPEAK: “Range: 0 ≤ … ≤ 1.0”"
S_CURVE_RADIUS = "ARADIUS, DRADIUS: “Range: 1.0 ≤ … ≤ 10.0”"
