"""Operand ranges of the PCIx's language (row type: :mod:`omsd.protocol.ranges`).

Source: the PCIx user's manual (``shared/seeds/002_5f0bea9264c6d239.txt``); its command pages
(chapter 5, alphabetical) print most ranges on a "RANGE:" line, quoted in ``cite``. Where a page
prints none, or prints two, ``choice`` records what was chosen ("manual silent: ...", "manual
contradicts itself: ..."). On top of every row, §5.3's rule holds
for every numeric operand: "numeric parameters must be within the range of a 32-bit signed
integer ... Entering parameter values outside the range of a signed 32-bit integer will cause a
Command Error" (checked by the interpreter before the command's own row).

The position range: LP's and SO's pages print "−33,554,431 ≤ … ≤ 33,554,431", the IN, MV and TL
pages "33,544,431" (a digit slip of the same number) and Appendix C "±33,500,000" (rounded):
±33,554,431 is taken for every position (``omsd/models/pcix.py``).

The MAX-family extension's commands (``omsd/models/max_family.py``: CL, LPE) are not in the
PCIx manual; their rows name the client they come from.
"""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange, RangeTable

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


def _page(mnemonic: str, words: str) -> str:
    return f"{PCIX} {mnemonic} page: “{words}”"


def _position(mnemonic: str, operand: int = 1, name: str = "position", **kw: str) -> _R:
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


def _flag(mnemonic: str, words: str, units: str = "axis selector: a value picks the axis") -> _R:
    return _R(mnemonic, number="flag", units=units, cite=_page(mnemonic, words))


def _whole(
    mnemonic: str,
    low: float,
    high: float,
    words: str,
    operand: int = 1,
    name: str = "",
    **kw: object,
) -> _R:
    return _R(mnemonic, operand, name, low, high, cite=_page(mnemonic, words), **kw)  # type: ignore[arg-type]


def _gain(mnemonic: str, low: float, high: float, words: str, number: str = "decimal") -> _R:
    return _R(
        mnemonic,
        1,
        "coefficient",
        low,
        high,
        number=number,  # type: ignore[arg-type]
        cite=_page(mnemonic, words),
    )


_S_CURVE_FRACTION = "ALOWER, APEAK, DLOWER, DPEAK: “Range: 0 ≤ … ≤ 1.0”"
_S_CURVE_RADIUS = "ARADIUS, DRADIUS: “Range: 1.0 ≤ … ≤ 10.0”"

ROWS: list[_R] = [
    # -- queries with an operand ---------------------------------------------------------------
    _whole(
        "?AJ",
        1,
        4,
        "Range: 1 ≤ Profile Number ≤ 4",
        name="profile",
        choice=CONTRADICTS
        + "the page's own example asks ?AJ5: the RANGE line is taken (?AJ5 is a command"
        " error with no reply, E14 of the conformance tests)",
    ),
    _whole("?DA", 1, 4, "RANGE: 1 ≤ Ramp Table Numbers ≤ 4", name="table"),
    _whole("?DE", 1, 4, "RANGE: 1 ≤ Parameter1 ≤ 4", name="table"),
    _whole("?DE", 1, 25, "RANGE: 1 ≤ Parameter2 ≤ 25", operand=2, name="entry"),
    _whole("?DS", 1, 4, "RANGE: 1 ≤ ?DS ≤ 4", name="table"),
    # -- A ---------------------------------------------------------------------------------
    _R(
        "AC",
        1,
        "acceleration",
        1,
        8_000_000,
        units="counts/s² (user units scaled)",
        scaled=True,
        cite=_page("AC", "RANGE: 1 ≤ AC ≤ 8,000,000"),
        choice=CONTRADICTS
        + "the prose's “greater than zero ... and less than 999,999,999” is not taken: the"
        " RANGE line is (omsd/models/pcix.py)",
    ),
    _flag("AF", "AF1,,1; ... The Y axis is unchanged in this example"),
    _flag("AN", "A parameter must be supplied for the desired axes when used in the AA mode"),
    _whole(
        "AJ",
        1,
        0,
        "Range: 1 ≤ # ≤ number of axes on board",
        name="profile",
        high_axes=True,
    ),
    *(
        _R(
            "AJ",
            operand,
            name,
            low,
            high,
            number="decimal",
            cite=_page("AJ", words),
        )
        for operand, name, low, high, words in (
            (2, "ALOWER", 0, 1, "Range: 0 ≤ ALOWER ≤ 1.0"),
            (3, "APEAK", 0, 1, "Range: 0 ≤ APEAK ≤ 1.0"),
            (4, "ARADIUS", 1, 10, "Range: 1.0 ≤ ARADIUS ≤ 10.0"),
            (5, "DLOWER", 0, 1, "Range: 0 ≤ DLOWER ≤ 1.0"),
            (6, "DPEAK", 0, 1, "Range: 0 ≤ DPEAK ≤ 1.0"),
            (7, "DRADIUS", 1, 10, "Range: 1.0 ≤ DRADIUS ≤ 10.0"),
        )
    ),
    # -- B ---------------------------------------------------------------------------------
    _R(
        "BC",
        1,
        "backlash",
        0,
        50,
        variant="stepper",
        units="steps",
        cite=_page("BC", "RANGE: 0 ≤ BACKLASH ≤ +50 STEPPERS"),
    ),
    _R(
        "BC",
        1,
        "backlash",
        -50,
        50,
        variant="servo",
        units="counts",
        cite=_page("BC", "-50 ≤ BACKLASH ≤ +50 SERVOS"),
    ),
    _whole("BH", 0, 7, "Range: 0 ≤ bit number ≤ 7", name="bit number"),
    _whole("BL", 0, 7, "RANGE: 0 ≤ bit number ≤ 7", name="bit number"),
    _R(
        "BS",
        1,
        "output mask",
        0x00,
        0xFF,
        number="hex",
        units="hexadecimal mask, bit 0 on the right, 1 = high",
        cite=_page("BS", "The mask must be in ASCII hex format ... Range: 00 ≤ Hex number ≤ FF"),
    ),
    _whole("BW", 0, 7, "RANGE: 0 ≤ Bit Number ≤ 7", name="bit number"),
    # -- C ---------------------------------------------------------------------------------
    _flag(
        "CA",
        "In AA or AM mode, a null value in the argument list specifies the done bit of"
        " that axis is not to be cleared",
    ),
    _position(
        "CD",
        choice=SILENT
        + "the CD page gives starting points “in absolute coordinates”, no RANGE line: the"
        " position range",
    ),
    _position(
        "CR",
        1,
        "first centre coordinate",
        cite=_page(
            "CR",
            "Min Pos. Value ≤ Parameter 1 (First Coordinate for Center of Circle) ≤ Max Pos. Value",
        ),
    ),
    _position(
        "CR",
        2,
        "second centre coordinate",
        cite=_page(
            "CR",
            "Min Pos. Value ≤ Parameter 2 (Second Coordinate for Center of Circle)"
            " ≤ Max Pos. Value",
        ),
    ),
    _R(
        "CR",
        3,
        "angle",
        number="decimal",
        units="radians",
        cite=_page("CR", "the third parameter is the distance to move in radians"),
        choice=SILENT + "no bound on the angle (any number of turns either way)",
    ),
    _R(
        "CV",
        1,
        "contour velocity",
        1,
        1_043_999,
        number="decimal",
        units="counts/s",
        cite=_page("CV", "RANGE: 1 ≤ CV ≤ 1,043,999"),
    ),
    # -- D ---------------------------------------------------------------------------------
    _R(
        "DAB",
        1,
        "acceleration level",
        0,
        1,
        number="decimal",
        cite=_page("DAB", "0.0 ≤ Parameter 1 ≤ 1.0"),
    ),
    _R(
        "DAB",
        2,
        "velocity level",
        0,
        1,
        number="decimal",
        cite=_page("DAB", "0.0 ≤ Parameter 2 ≤ 1.0"),
    ),
    _whole(
        "DAR",
        1,
        4,
        "RANGE: 1 ≤ DAR ≤ 4",
        name="table",
        choice=CONTRADICTS
        + "the prose's “from 1 to 8” is not taken: the RANGE line, and SR/?DA/?DS/?DE"
        " address tables 1 to 4",
    ),
    _flag(
        "DBI",
        "In AA or AM mode a null value in the argument list specifies that the sense"
        " of that direction bit is not to be changed",
    ),
    _flag("DBN", "DBN,,1,1;"),
    _R(
        "DC",
        1,
        "deceleration",
        1,
        8_000_000,
        units="counts/s² (user units scaled)",
        scaled=True,
        cite=_page("DC", "RANGE: 1 ≤ DC ≤ 8000000"),
    ),
    _whole(
        "DZ",
        -32_667,
        32_667,
        "RANGE: -32,667 ≤ DZ ≤ 32,667",
        name="offset",
        choice=CONTRADICTS
        + "§2.7.2's “The values for DZ and KO range from -32640 to 32640” is not taken: the"
        " command page's RANGE line is",
    ),
    # -- E ---------------------------------------------------------------------------------
    _R(
        "EG",
        1,
        "|ratio| × master VL",
        1,
        1_048_574,
        high_open=True,
        number="decimal",
        units="counts/s",
        cite=_page(
            "EG",
            "The gear ratio must be such that (Gear Ratio *X the Master Axis' VL value) is at"
            " least 1 and less than the maximum controller step rate of 1,048,574 steps per"
            " second",
        ),
    ),
    _R(
        "ER",
        1,
        "encoder counts",
        0,
        None,
        low_open=True,
        cite=_page("ER", "Both parameters must be integers."),
        choice=SILENT + "no bound is given: counts are greater than zero, no upper edge",
    ),
    _R(
        "ER",
        2,
        "motor counts",
        0,
        None,
        low_open=True,
        cite=_page("ER", "Both parameters must be integers."),
        choice=SILENT + "as the encoder counts",
    ),
    _R(
        "ES",
        1,
        "slip tolerance",
        0,
        65_535,
        low_open=True,
        units="counts",
        cite=_page("ES", "STEPPER RANGE: 0 < ES ≤ 65,535"),
    ),
    # -- F - H -------------------------------------------------------------------------------
    _position("FP", choice=SILENT + "the FP page prints no RANGE line: the position range"),
    _whole("HD", 0, 64_000, "RANGE: 0 ≤ HD ≤ 64,000", name="deadband", units="counts"),
    _flag("HE", "HE,1;"),
    _flag(
        "HF",
        "In AA or AM mode, a null value in the argument list specifies feedback for"
        " that axis is not to be disabled",
    ),
    _whole("HG", 1, 32_000, "RANGE: 1 ≤ HG ≤ 32,000", name="hold gain"),
    _flag(
        "HH",
        "In AA or AM modes, a null argument in the parameter list specifies that axis"
        " home switch to be unchanged",
    ),
    _flag(
        "HL",
        "In AA or AM modes, a null argument in the parameter list specifies that axis"
        " home switch to be unchanged",
    ),
    _position(
        "HM",
        choice=SILENT
        + "the HM page prints no RANGE line: “The position counters will be initialized to"
        " the positions supplied”, held to the position range",
    ),
    _flag(
        "HN",
        "In AA or AM mode, a null value in the argument list specifies that encoder"
        " feedback is not to be enabled for that axis",
    ),
    _position(
        "HR",
        choice=SILENT
        + "the HR page prints no RANGE line (“the position and encoder counters are loaded"
        " with the parameter(s)”): the position range",
    ),
    _flag("HS", "HS,1;"),
    _R(
        "HV",
        1,
        "hold velocity",
        1,
        1_039_999,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("HV", "RANGE: 1 ≤ HV ≤ 1,039,999"),
    ),
    # -- I - K -------------------------------------------------------------------------------
    _R(
        "IN",
        1,
        "distance before end of move",
        -POSITION,
        POSITION,
        units="counts (user units scaled)",
        scaled=True,
        cite=_page("IN", "-33,544,431 ≤ Parameter (Distance Before End of Move) ≤ 33,544,431"),
        choice=CONTRADICTS
        + "the edges are the position range: "
        + SLIP
        + "; a negative distance is never"
        " nearer the end than the end itself: it interrupts when the move is done, as IN0",
    ),
    _R(
        "JF",
        1,
        "jog velocity",
        -1_043_999.999,
        1_043_999.995,
        number="decimal",
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("JF", "RANGE: -1,043,999.999 ≤ JF ≤ 1,043,999.995"),
    ),
    _R(
        "JG",
        1,
        "jog velocity",
        -1_043_999,
        1_043_999,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("JG", "RANGE: -1,043,999 ≤ JG ≤ 1,043,999"),
    ),
    _gain("KA", 0, 32_767, "RANGE: 0.00 ≤ KA ≤ 32,767.00"),
    _gain("KB", 0, 10, "RANGE: 0.0 ≤ KB ≤ 10.0"),
    _gain("KD", 0, 32_767, "RANGE: 0.00 ≤ KD ≤ 32,767.00"),
    _gain("KF", 0, 32_767, "Range: 0 ≤ KF ≤ 32,767", number="integer"),
    _gain("KI", 0, 32_767, "RANGE: 0.00 ≤ KI ≤ 32767.00"),
    _R(
        "KO",
        1,
        "offset",
        -32_767,
        32_767,
        cite=_page("KO", "RANGE: -32767 ≤ KO ≤ 32767"),
        choice=CONTRADICTS
        + "§2.7.2's “The values for DZ and KO range from -32640 to 32640” is not taken: the"
        " command page's RANGE line is",
    ),
    _R(
        "KP",
        1,
        "coefficient",
        0,
        32_767,
        number="decimal",
        cite=_page("KP", "RANGE: 0.00 ≤ KP ≤ 32767.00"),
        choice=CONTRADICTS
        + "§2.7.2's “The values for KP range from 0 to 249.99” (and KI, KD, KV, KA) is not"
        " taken: the command pages' RANGE lines are",
    ),
    _flag(
        "KS",
        "In AA or AM modes, null values in the argument list specify that motion on"
        " that axis is not to be killed",
    ),
    _gain("KU", 0, 32_767, "RANGE: 0 ≤ KU ≤ 32767", number="integer"),
    _gain("KV", 0, 32_767, "RANGE: 0.00 ≤ KV ≤ 32,767.00"),
    # -- L ---------------------------------------------------------------------------------
    _flag("LA", "LA,1,,1;"),
    _flag("LF", "LF,1;"),
    _flag(
        "LH",
        "In AA or AM modes, a null argument in the argument list specifies that axis is"
        " not to be affected",
    ),
    _flag(
        "LL",
        "In AA or AM modes, a null argument in the argument list specifies that axis is"
        " not to be affected",
    ),
    _flag(
        "LN",
        "In AA or AM modes, a null argument in the parameter list specifies that axis is"
        " not to be affected",
    ),
    _position(
        "LO",
        cite=_page("LO", "Any valid position within the allowable position range may be used."),
    ),
    _position("LP"),
    _whole(
        "LS",
        1,
        32_767,
        "RANGE: 1 ≤ LS ≤ 32,767",
        name="loop count",
        choice=CONTRADICTS
        + "the prose's “The parameter must be less than 32,767” is not taken: the RANGE"
        " line is",
    ),
    # -- M ---------------------------------------------------------------------------------
    _position("MA", choice=SILENT + "the MA page prints no RANGE line: the position range"),
    _whole(
        "MD",
        0,
        4,
        "RANGE: 0 ≤ MD ≤ 4",
        name="macro",
    ),
    _position(
        "ML",
        name="distance",
        choice=SILENT + "the ML page prints no RANGE line: the position range",
    ),
    _position(
        "MR",
        name="distance",
        choice=SILENT + "the MR page prints no RANGE line: the position range",
    ),
    _position(
        "MT",
        choice=SILENT + "the MT page prints no RANGE line: the position range, in or out of"
        " a contour definition",
    ),
    _position(
        "MV",
        cite=_page("MV", "-33,544,431 ≤ Parameter 1 (Absolute Position) ≤ 33,544,431"),
        choice=CONTRADICTS + "the position range: " + SLIP,
    ),
    _R(
        "MV",
        2,
        "velocity",
        1,
        1_043_999,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("MV", "1 ≤ Parameter 2 (Velocity) ≤ 1,043,999"),
    ),
    _whole("MX", 0, 24, "RANGE: 0 ≤ MX ≤ 24", name="macro"),
    # -- N - P -------------------------------------------------------------------------------
    _R(
        "NV",
        1,
        "contour velocity",
        1,
        1_043_999,
        number="decimal",
        units="counts/s",
        cite=_page("NV", "RANGE: 1 ≤ NV ≤ 1,043,999"),
    ),
    _flag(
        "PA",
        "the auxiliary output is turned off (driven low) upon the execution of the GO or GD"
        " command and on at the end of the move",
        units="zero or non-zero, per axis",
    ),
    _flag("PH", "This command disables power automatic (PA) mode."),
    _flag("PL", "This command disables power automatic (PA) mode."),
    _whole("PM", 0, 24, "RANGE: 0 ≤ PM ≤ 24", name="macro"),
    _whole(
        "PN",
        3,
        10,
        "RANGE: 3 ≤ PN ≤ 10 ... A parameter out of this range or no parameter supplied defaults"
        " to 70% or 3 steps.",
        name="parabolic steps",
        default=3,
    ),
    _whole(
        "PR",
        3,
        10,
        "RANGE: 3 ≤ PR ≤ 10",
        name="parabolic steps",
        default=3,
        choice=SILENT
        + "PR is “similar to the PN command”: out of range it defaults to 3 steps as PN's"
        " does",
    ),
    _whole("PT", 0, 4, "0 ≤ Parameter 1 ≤ 4", name="temporary macro"),
    _whole("PT", 5, 24, "5 ≤ Parameter 2 ≤ 24", operand=2, name="permanent macro"),
    # -- R - S -------------------------------------------------------------------------------
    _R(
        "RM",
        1,
        "divisor",
        0,
        65_000,
        low_open=True,
        high_open=True,
        cite=_page("RM", "RANGE: 0 < RM < 65,000"),
    ),
    _flag("SC", "SC,1,,1;"),
    _whole("SE", 0, 1000, "RANGE: 0 ≤ SE ≤ 1000", name="settling time", units="ms"),
    _flag("SF", "SF,1,,1;"),
    _flag(
        "SI",
        "Any non-zero value in a parameter will cause the corresponding axis to be stopped.",
        units="zero: not stopped, non-zero: stopped",
    ),
    _flag("SL", "SL,1,,1;"),
    _position(
        "SO",
        1,
        "stop position",
        cite=_page("SO", "-33,554,431 ≤ Parameter 1 (Stop Position) ≤ 33,554,431"),
    ),
    _position(
        "SO",
        2,
        "distance",
        cite=_page(
            "SO",
            "-33,554,431 ≤ Parameter 2 (Distance from Stop Position to Start Decelerating) ≤"
            " 33,554,431",
        ),
    ),
    _position("SP", choice=SILENT + "the SP page prints no RANGE line: the position range"),
    _whole("SR", 1, 4, "RANGE: 1 ≤ SR ≤ 4", name="table"),
    _whole("SS", 1, 4, "RANGE: 1 ≤ Ramp Number ≤ 4", name="profile"),
    _whole(
        "SW",
        0,
        7,
        "RANGE: 0 ≤ Bit Number ≤ 7 ... must be configured as an input",
        name="bit number",
    ),
    # -- T - W -------------------------------------------------------------------------------
    _position(
        "TL", 1, "upper limit", cite=_page("TL", "RANGE: ±33,544,431"), choice=CONTRADICTS + SLIP
    ),
    _position(
        "TL", 2, "lower limit", cite=_page("TL", "RANGE: ±33,544,431"), choice=CONTRADICTS + SLIP
    ),
    _whole("TM", 0, 200_000, "RANGE: 0 ≤ TM ≤ 200,000", name="time", units="ms"),
    _R(
        "TX",
        1,
        "|ratio| × X's VL",
        1,
        1_048_574,
        high_open=True,
        number="decimal",
        units="counts/s",
        cite=_page(
            "TX", "The command argument is the tracking ratio specified as a floating point."
        ),
        choice=SILENT + "no range is printed: TX is gearing to X, so EG's rule (“Gear Ratio *X the"
        " Master Axis' VL value ... at least 1 and less than ... 1,048,574”) is applied",
    ),
    _flag("UF", "UF1,1,1;"),
    _R(
        "UU",
        1,
        "multiplier",
        0,
        1_000_000_000,
        low_open=True,
        number="decimal",
        units="counts per user unit",
        cite=_page(
            "UU",
            "converts all move velocities, distances, etc. to user specified units"
            " by multiplying by the specified parameter",
        ),
        choice=SILENT
        + "no RANGE line: greater than zero, at most 1,000,000,000 (as the PC48 family)",
    ),
    _R(
        "VB",
        1,
        "base velocity",
        0,
        1_044_000,
        high_open=True,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("VB", "RANGE: 0 ≤ VB < VL value"),
        choice=CHOSEN
        + "the upper edge is the largest VL (“1 ≤ VL ≤ 1044000”), not the VL in force: a VL"
        " entered just before may still wait in the queue; the page itself says what a VB at"
        " or above VL does (“the initial velocity used at the start of a move will be the VL"
        " value”)",
    ),
    _R(
        "VL",
        1,
        "velocity",
        1,
        1_044_000,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=_page("VL", "RANGE: 1 ≤ VL ≤ 1044000"),
    ),
    _whole(
        "VS",
        1,
        1_043_999,
        "1 ≤ Parameter 1 (Time in 1 update rate of a second) ≤ 1,043,999",
        name="time",
        units="samples",
    ),
    *(
        _R(
            "VS",
            operand,
            name,
            -1_043_999,
            1_043_999,
            units="counts/s (user units scaled)",
            scaled=True,
            cite=_page("VS", f"0 ≤ Parameter {operand} ({name}) ≤ 1,043,999"),
            choice=CONTRADICTS
            + "the page's own example streams VS1024,-1000,1000 (X backwards): the"
            " velocities are taken to be signed, ±1,043,999",
        )
        for operand, name in ((2, "X Axis Velocity"), (3, "Y Axis Velocity"))
    ),
    _whole(
        "WS",
        0,
        3,
        "#RANGE : 0 ≤ Parameter1 ≤ 3",
        name="input bit",
        choice=NOTE + "the factory inputs are bits 0-3 (§2.2 S3), which the range line matches; the"
        " optional second parameter (state) is not emulated",
    ),
    _whole("WT", 1, 200_000, "RANGE: 1 ≤ WT ≤ 200,000", name="time", units="ms"),
    # -- the MAX-family extension (omsd/models/max_family.py) ---------------------------------
    _R(
        "CL",
        number="flag",
        units="0 opens the loop (HF), anything else closes it (HN)",
        choice=SILENT + "not in the PCIx manual: EPICS omsBaseController sends CL1/CL0 where older"
        " firmware gets HN/HF (omsd/board/max_family.py); any non-zero value closes",
    ),
    _R(
        "LPE",
        1,
        "encoder position",
        -POSITION,
        POSITION,
        units="counts (user units scaled)",
        scaled=True,
        cite=POSITION_CITE,
        choice=SILENT + "not in the PCIx manual: LPE is LP on the current axis (EPICS"
        " omsBaseController, omsd/board/max_family.py), with LP's range",
    ),
]


PCIX_RANGES = RangeTable("pcix", FAMILIES, ROWS)
