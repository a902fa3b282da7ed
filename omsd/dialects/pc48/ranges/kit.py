"""The constants and row constructors the parts of the PC48 family's range table share."""

from __future__ import annotations

from omsd.protocol.ranges import Number, OperandRange

PC48 = "PC48 manual (seeds/000_438df88d2a6a1670.txt)"
VS4 = "VS4 manual (seeds/003_c16e31315d499848.txt)"
PC46 = "PC46 datasheet (seeds/004_47955639fb93103e.txt)"

FAMILIES = ("PC48", "PC46", "VS4")

#: Appendix C "SPECIFICATIONS" of the PC48 and VS4 manuals and the PC46 datasheet alike:
#: "Position range 134,000,000 pulses (±67,000,000)".
POSITION = 67_000_000
POSITION_CITE = f"{PC48} Appendix C: “Position range 134,000,000 pulses (±67,000,000)”"
#: PC48 §6.7 VL: "The operand must be greater than zero and less than or equal to 1,044,000".
VELOCITY = 1_044_000
#: PC46 specifications "0 to 522,000 pulses per second"; VS4 §6.7 VL "less than or equal to
#: 522,000 steps per second".
SLOW_VELOCITY = 522_000

VL_CITE = f"{PC48} §6.7 VL: “The operand must be greater than zero and less than or equal to"
VL_CITE += " 1,044,000 steps per second.”"
PC46_VL_CITE = f"{PC46} specifications: “Velocity 0 to 522,000 pulses per second simultaneous on"
PC46_VL_CITE += " each axis” (the features list's “0 to 1,044,000” is not taken, pc46.py)"
VS4_VL_CITE = f"{VS4} §6.7 VL: “The operand must be greater than zero and less than or equal to"
VS4_VL_CITE += " 522,000 steps per second.”"

SILENT = "manual silent: "
CONTRADICTS = "manual contradicts itself: "

_R = OperandRange


def position(mnemonic: str, operand: int = 1, name: str = "position", *, why: str) -> _R:
    """An absolute position or a distance in steps: the Appendix C position range."""
    return _R(
        mnemonic,
        operand,
        name,
        -POSITION,
        POSITION,
        units="steps (user units scaled)",
        cite=POSITION_CITE,
        choice=SILENT + why,
        scaled=True,
    )


def bits(mnemonic: str, what: str) -> list[_R]:
    """A general-purpose I/O bit number: 14 lines on the PC48 and VS4 (bits 0–13), 16 on the
    PC46 (0–15)."""
    return [
        _R(
            mnemonic,
            1,
            "bit number",
            0,
            13,
            units=what,
            cite=f"{PC48} §6.6 RB: “Factory default settings have bits 0 through 7 as inputs and"
            " 8 through 13 are outputs”; §6.6 BH: “Valid bits depend on which bits are"
            f" programmed as outputs. Factory default output bits are 8 through 13.” {VS4} §6.6"
            " BH: the same words",
        ),
        _R(
            mnemonic,
            1,
            "bit number",
            0,
            15,
            units=what,
            families=("PC46",),
            cite=f"{PC46} features: “8 general purpose inputs with 2.2k Ohm pull-up resistors and"
            " 8 general purpose outputs. All 16 general purpose I/O may be configured as inputs"
            " or outputs”",
        ),
    ]


def per_speed(
    mnemonic: str,
    operand: int,
    name: str,
    *,
    signed: bool,
    choice: str,
    vs4_high: float = SLOW_VELOCITY,
    vs4_cite: str = VS4_VL_CITE,
    number: Number = "integer",
    magnitude: bool = False,
) -> list[_R]:
    """A velocity held to the board's velocity limit (PC48 1,044,000; PC46 522,000; VS4 its
    own): ``-limit ≤ v ≤ limit`` when ``signed``, else ``0 < v ≤ limit`` (of ``|v|`` with
    ``magnitude``)."""

    def row(high: float, cite: str, families: tuple[str, ...]) -> _R:
        return _R(
            mnemonic,
            operand,
            name,
            -high if signed else 0,
            high,
            low_open=not signed,
            number=number,
            units="steps/s (user units scaled)",
            cite=cite,
            choice=SILENT + choice,
            families=families,
            scaled=True,
            magnitude=magnitude,
        )

    return [
        row(VELOCITY, VL_CITE, ()),
        row(SLOW_VELOCITY, PC46_VL_CITE, ("PC46",)),
        row(vs4_high, vs4_cite, ("VS4",)),
    ]
