"""Operand ranges of the PC48 family's language: PC48, PC46, VS4 (row type:
:mod:`omsd.protocol.ranges`).

Sources: the PC48 user's manual (``shared/seeds/000_438df88d2a6a1670.txt``), the VS4 user's
manual (``003_c16e31315d499848.txt``) and the PC46 datasheet (``004_47955639fb93103e.txt``).
The PC46 datasheet gives no command ranges but its velocity; everything else it leaves out is
the PC48's (``omsd/models/pc46.py``). The VS4 manual repeats the PC48's words except where a row
names the VS4.

Every command of the three command tables that takes a number has a row here
(``tests/board/test_operand_ranges.py`` checks it). A row with ``choice`` set records a choice:
the manual states no range for that operand ("manual silent: ..."), or states two ("manual
contradicts itself: ...").
"""

from __future__ import annotations

from omsd.protocol.ranges import Number, OperandRange, RangeTable

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


def _position(mnemonic: str, operand: int = 1, name: str = "position", *, why: str) -> _R:
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


def _bits(mnemonic: str, what: str) -> list[_R]:
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


def _per_speed(
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


ROWS: list[_R] = [
    # -- 6.5 system control ------------------------------------------------------------------
    _R(
        "PN",
        1,
        "parabolic steps",
        3,
        10,
        default=3,
        cite=f"{PC48} §6.5 PN: “It must be in the range of 3 to 10 corresponding to 70% and 10%"
        " acceleration at the peak respectively. A parameter out of this range or no parameter"
        " supplied defaults to 70% or 3 steps.” (no command error)",
    ),
    # -- 6.6 user I/O ------------------------------------------------------------------------
    _R(
        "AN",
        number="flag",
        units="place holder: which axes",
        cite=f"{PC48} §6.6 AN: “The parameter only serves as a place holder to show which axes"
        " should be affected, the value given does not affect the active state of the auxiliary"
        " line.”; §6.21: “All axes must be specified or specifically skipped”",
    ),
    _R(
        "AF",
        number="flag",
        units="place holder: which axes",
        cite=f"{PC48} §6.6 AF: “Same parameter rules apply as the AN command.”",
    ),
    _R(
        "PA",
        number="flag",
        units="zero or non-zero",
        cite=f"{PC48} §6.6 PA: “if the parameter is zero or not specified ... If the parameter is"
        " non-zero, the sense is reversed”",
    ),
    _R(
        "SE",
        1,
        "settling time",
        0,
        1000,
        units="ms",
        cite=f"{PC48} §6.6 SE: “The parameter may be any value to 1000 milliseconds."
        " Specification of a parameter of zero turns off the mode.”",
    ),
    *_bits("BL", "output bit"),
    *_bits("BH", "output bit"),
    # -- 6.7 move specification --------------------------------------------------------------
    _R(
        "AC",
        1,
        "acceleration",
        0,
        8_000_000,
        low_open=True,
        high_open=True,
        units="steps/s² (user units scaled)",
        scaled=True,
        cite=f"{PC48} §6.7 AC: “The parameter must be greater than zero (zero is not valid) and"
        f" less than 8,000,000.” {VS4} §6.7 AC: “greater than zero and less than 8,000,000”",
    ),
    _R(
        "VL",
        1,
        "velocity",
        0,
        VELOCITY,
        low_open=True,
        units="steps/s (user units scaled)",
        scaled=True,
        cite=VL_CITE,
    ),
    _R(
        "VL",
        1,
        "velocity",
        0,
        SLOW_VELOCITY,
        low_open=True,
        units="steps/s (user units scaled)",
        scaled=True,
        families=("PC46",),
        cite=PC46_VL_CITE,
    ),
    _R(
        "VL",
        1,
        "velocity",
        0,
        SLOW_VELOCITY,
        low_open=True,
        units="steps/s (user units scaled)",
        scaled=True,
        families=("VS4",),
        cite=VS4_VL_CITE,
    ),
    *(
        _R(
            "VB",
            1,
            "base velocity",
            0,
            high,
            high_open=True,
            units="steps/s (user units scaled)",
            scaled=True,
            families=families,
            cite=f"{PC48} §6.7 VB: “The parameter must be greater than zero and less than the"
            " programmed velocity. ... The base velocity defaults to zero at power up or reset.”",
            choice=CONTRADICTS
            + "VB0 is accepted (it restores the power-up value, switching the base"
            " velocity off; the PCIx page of the same command reads “0 ≤ VB < VL value”); the"
            " upper edge is the largest VL, not the VL in force: a VL entered just before may"
            " still wait in the queue, and a VB at or above VL is clamped to VL when a move"
            " starts (decisions.md)",
        )
        for high, families in ((VELOCITY, ()), (SLOW_VELOCITY, ("PC46", "VS4")))
    ),
    _R(
        "LP",
        1,
        "position",
        -33_554_431,
        33_554_431,
        units="steps (user units scaled)",
        scaled=True,
        cite=f"{PC48} §6.7 LP: “The range is −33,554,431 ≤ LP ≤ 33,554,431.” {VS4} §6.7 LP:"
        " “Range: -33,554,431 to +33,554,431”",
    ),
    _position(
        "MA",
        why="the MA page states no range: an absolute target is held to the Appendix C"
        " position range",
    ),
    _position(
        "MR",
        name="distance",
        why="the MR page states no range: a relative distance is held to the Appendix C"
        " position range",
    ),
    _position(
        "ML",
        name="distance",
        why="the ML page states no range: each axis's distance is held to the Appendix C"
        " position range",
    ),
    _position(
        "MT",
        why="the MT pages (§6.7, §6.21) state no range: each target, in or out of a contour"
        " definition, is held to the Appendix C position range",
    ),
    _R(
        "RM",
        1,
        "divisor",
        0,
        65_000,
        low_open=True,
        high_open=True,
        cite=f"{PC48} §6.7 RM: “The parameter must be greater than zero and less than 65,000.”",
    ),
    # -- 6.8 move execution ------------------------------------------------------------------
    *_per_speed(
        "JG",
        1,
        "jog velocity",
        signed=True,
        choice="the PC48 JG page states no range: held to VL's, as “This command modifies the"
        " move velocity parameter (VL)”; the VS4 has its own range line",
        vs4_high=VELOCITY,
        vs4_cite=f"{VS4} §6.8 JG: “Range: -1,044,000 <= JG <= +1,044,000”",
    ),
    *_per_speed(
        "JF",
        1,
        "jog velocity",
        signed=True,
        number="decimal",
        choice="the PC48 JF page states no range: held to VL's (“like the JG command”); the VS4"
        " has its own range line",
        vs4_high=VELOCITY,
        vs4_cite=f"{VS4} §6.8 JF: “Range: -1,044,000.000 <= JG <= +1,044,000.000”",
    ),
    _R(
        "VS",
        1,
        "time",
        1,
        32_767,
        units="1/1024 s samples",
        choice=SILENT
        + "the VS page gives the unit (“time in 1/1024 second sample intervals”), not the"
        " range: 1 to 32,767 (a sample at least; a signed 16-bit count at most)",
    ),
    *_per_speed(
        "VS",
        2,
        "X velocity",
        signed=True,
        choice="the VS page states no range for the velocities: held to VL's; a negative one"
        " runs backwards (the example's VS1024,-1000,1000)",
    ),
    *_per_speed(
        "VS",
        3,
        "Y velocity",
        signed=True,
        choice="as the X velocity",
    ),
    # -- 6.10 loop control -------------------------------------------------------------------
    _R(
        "LS",
        1,
        "loop count",
        1,
        32_000,
        cite=f"{PC48} §6.3 summary: “Loop start, set loop counter, from 1 to 32000 loops”; §6.10"
        " LS: “The parameter must be less than 32,000.”",
        choice=CONTRADICTS
        + "the manual says both “from 1 to 32000” and “less than 32,000”: the summary's"
        " explicit range is taken, as the PCIx's RANGE line “1 ≤ LS ≤ 32,767” is over its own"
        " prose “less than 32,767”",
    ),
    *_bits("WS", "input bit"),
    # -- 6.11 home ---------------------------------------------------------------------------
    _position(
        "HM",
        why="the HM page states no range for the position the counter is initialised to:"
        " the Appendix C position range",
    ),
    _position(
        "HR",
        why="the HR page states no range (“It behaves exactly like the HM command”): the"
        " Appendix C position range",
    ),
    # -- 6.12 move synchronization -----------------------------------------------------------
    _R(
        "IN",
        1,
        "distance",
        0,
        POSITION,
        units="steps (user units scaled)",
        scaled=True,
        choice=SILENT + "the IN page states no range: a distance from the end of the move, 0 (the"
        " example's IN0) up to the Appendix C position range",
    ),
    *_bits("SW", "input bit"),
    _R(
        "WT",
        1,
        "time",
        1,
        32_000,
        units="ms",
        cite=f"{PC48} §6.12 WT: “The parameter must be between 1 and 32,000.”",
    ),
    # -- 6.14 user units ---------------------------------------------------------------------
    _R(
        "UU",
        1,
        "multiplier",
        0,
        1_000_000_000,
        low_open=True,
        number="decimal",
        units="steps per user unit",
        choice=SILENT
        + "the UU page states no range: greater than zero (a unit of zero or less steps"
        " cannot scale anything), at most 1,000,000,000",
    ),
    # -- 6.15 - 6.16 encoder -----------------------------------------------------------------
    _R(
        "ER",
        1,
        "encoder counts",
        0,
        None,
        low_open=True,
        units="counts (a fraction only with user units on)",
        cite=f"{PC48} §6.15 ER: “These counts must be integers unless user units are enabled.”",
        choice=SILENT
        + "no bound is given: counts are greater than zero (a ratio needs both), no upper"
        " edge",
    ),
    _R(
        "ER",
        2,
        "motor counts",
        0,
        None,
        low_open=True,
        units="counts (a fraction only with user units on)",
        cite=f"{PC48} §6.15 ER: “These counts must be integers unless user units are enabled.”",
        choice=SILENT + "as the encoder counts",
    ),
    *_per_speed(
        "HV",
        1,
        "hold velocity",
        signed=False,
        choice="the HV page states no range (“the peak velocity which will be used while making"
        " position corrections”): greater than zero, at most VL's limit",
    ),
    _R(
        "HG",
        1,
        "hold gain",
        1,
        32_000,
        cite=f"{PC48} §6.15 HG: “The parameter must be between 1 and 32,000.”",
    ),
    _R(
        "HD",
        1,
        "deadband",
        0,
        POSITION,
        units="counts",
        cite=f"{PC48} §6.15 HD: “A parameter of zero is allowed.”",
        choice=SILENT + "no upper edge is given: the Appendix C position range",
    ),
    _R(
        "ES",
        1,
        "slip tolerance",
        0,
        POSITION,
        units="steps",
        choice=SILENT
        + "the ES page states no range (“tolerance before slip or stall is flagged”): 0 up"
        " to the Appendix C position range",
    ),
    # -- 6.20 velocity staircase -------------------------------------------------------------
    _position("MV", 1, why="the MV page states no range for the position: Appendix C"),
    *_per_speed(
        "MV",
        2,
        "velocity",
        signed=False,
        magnitude=True,
        choice="the MV page states no range for the velocity: greater than zero and at most VL's"
        " limit in size (the direction is MP/MM's, a sign is accepted)",
    ),
    _position("SP", why="the SP page states no range: the Appendix C position range"),
    _position("FP", why="the FP page states no range: the Appendix C position range"),
    # -- 6.21 contouring ---------------------------------------------------------------------
    _position(
        "CD",
        why="the CD page gives “the starting position of the contour in absolute units”, no"
        " range: the Appendix C position range",
    ),
    _position(
        "CR",
        1,
        "X centre",
        why="the CR page gives “the center of the circle in absolute units”, no range: the"
        " Appendix C position range",
    ),
    _position("CR", 2, "Y centre", why="as the X centre"),
    _R(
        "CR",
        3,
        "angle",
        number="decimal",
        units="radians",
        cite=f"{PC48} §6.21 CR: “the third parameter is the distance to move in radians."
        " Positive radians equal counter clockwise movement. Negative radians equal clockwise"
        " movement.”",
        choice=SILENT + "no bound on the angle (any number of turns either way)",
    ),
    *_per_speed(
        "CV",
        1,
        "contour velocity",
        signed=False,
        number="decimal",
        choice="the CV page states no range: greater than zero, at most VL's limit; a vector"
        " speed, not scaled by user units (decisions.md)",
    ),
    # -- the VS4's AA forms of the limit commands (``AA LN,,,1;``): place holders ------------
    *(
        _R(
            mnemonic,
            number="flag",
            units="place holder: which axes",
            families=("VS4",),
            cite=f"{VS4} examples “AA LN,,,1;”, “AA SF” (omsd/models/vs4.py)",
        )
        for mnemonic in ("LN", "LF", "SL", "SF")
    ),
]


PC48_RANGES = RangeTable("oms", FAMILIES, ROWS)
