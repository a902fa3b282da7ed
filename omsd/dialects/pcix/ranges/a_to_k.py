"""The PCIx's range rows: the queries with an operand, and the commands A to K (the manual's
command pages are alphabetical)."""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange

from .kit import (
    CONTRADICTS,
    POSITION,
    SILENT,
    SLIP,
    flag,
    gain,
    page,
    position,
    whole,
)

_R = OperandRange

ROWS: list[_R] = [
    # -- queries with an operand ---------------------------------------------------------------
    whole(
        "?AJ",
        1,
        4,
        "Range: 1 ≤ Profile Number ≤ 4",
        name="profile",
        choice=CONTRADICTS
        + "the page's own example asks ?AJ5: the RANGE line is taken (?AJ5 is a command"
        " error with no reply, E14 of the conformance tests)",
    ),
    whole("?DA", 1, 4, "RANGE: 1 ≤ Ramp Table Numbers ≤ 4", name="table"),
    whole("?DE", 1, 4, "RANGE: 1 ≤ Parameter1 ≤ 4", name="table"),
    whole("?DE", 1, 25, "RANGE: 1 ≤ Parameter2 ≤ 25", operand=2, name="entry"),
    whole("?DS", 1, 4, "RANGE: 1 ≤ ?DS ≤ 4", name="table"),
    # -- A ---------------------------------------------------------------------------------
    _R(
        "AC",
        1,
        "acceleration",
        1,
        8_000_000,
        units="counts/s² (user units scaled)",
        scaled=True,
        cite=page("AC", "RANGE: 1 ≤ AC ≤ 8,000,000"),
        choice=CONTRADICTS
        + "the prose's “greater than zero ... and less than 999,999,999” is not taken: the"
        " RANGE line is (omsd/models/pcix.py)",
    ),
    flag("AF", "AF1,,1; ... The Y axis is unchanged in this example"),
    flag("AN", "A parameter must be supplied for the desired axes when used in the AA mode"),
    whole(
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
            cite=page("AJ", words),
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
        cite=page("BC", "RANGE: 0 ≤ BACKLASH ≤ +50 STEPPERS"),
    ),
    _R(
        "BC",
        1,
        "backlash",
        -50,
        50,
        variant="servo",
        units="counts",
        cite=page("BC", "-50 ≤ BACKLASH ≤ +50 SERVOS"),
    ),
    whole("BH", 0, 7, "Range: 0 ≤ bit number ≤ 7", name="bit number"),
    whole("BL", 0, 7, "RANGE: 0 ≤ bit number ≤ 7", name="bit number"),
    _R(
        "BS",
        1,
        "output mask",
        0x00,
        0xFF,
        number="hex",
        units="hexadecimal mask, bit 0 on the right, 1 = high",
        cite=page("BS", "The mask must be in ASCII hex format ... Range: 00 ≤ Hex number ≤ FF"),
    ),
    whole("BW", 0, 7, "RANGE: 0 ≤ Bit Number ≤ 7", name="bit number"),
    # -- C ---------------------------------------------------------------------------------
    flag(
        "CA",
        "In AA or AM mode, a null value in the argument list specifies the done bit of"
        " that axis is not to be cleared",
    ),
    position(
        "CD",
        choice=SILENT
        + "the CD page gives starting points “in absolute coordinates”, no RANGE line: the"
        " position range",
    ),
    position(
        "CR",
        1,
        "first centre coordinate",
        cite=page(
            "CR",
            "Min Pos. Value ≤ Parameter 1 (First Coordinate for Center of Circle) ≤ Max Pos. Value",
        ),
    ),
    position(
        "CR",
        2,
        "second centre coordinate",
        cite=page(
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
        cite=page("CR", "the third parameter is the distance to move in radians"),
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
        cite=page("CV", "RANGE: 1 ≤ CV ≤ 1,043,999"),
    ),
    # -- D ---------------------------------------------------------------------------------
    _R(
        "DAB",
        1,
        "acceleration level",
        0,
        1,
        number="decimal",
        cite=page("DAB", "0.0 ≤ Parameter 1 ≤ 1.0"),
    ),
    _R(
        "DAB",
        2,
        "velocity level",
        0,
        1,
        number="decimal",
        cite=page("DAB", "0.0 ≤ Parameter 2 ≤ 1.0"),
    ),
    whole(
        "DAR",
        1,
        4,
        "RANGE: 1 ≤ DAR ≤ 4",
        name="table",
        choice=CONTRADICTS
        + "the prose's “from 1 to 8” is not taken: the RANGE line, and SR/?DA/?DS/?DE"
        " address tables 1 to 4",
    ),
    flag(
        "DBI",
        "In AA or AM mode a null value in the argument list specifies that the sense"
        " of that direction bit is not to be changed",
    ),
    flag("DBN", "DBN,,1,1;"),
    _R(
        "DC",
        1,
        "deceleration",
        1,
        8_000_000,
        units="counts/s² (user units scaled)",
        scaled=True,
        cite=page("DC", "RANGE: 1 ≤ DC ≤ 8000000"),
    ),
    whole(
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
        cite=page(
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
        cite=page("ER", "Both parameters must be integers."),
        choice=SILENT + "no bound is given: counts are greater than zero, no upper edge",
    ),
    _R(
        "ER",
        2,
        "motor counts",
        0,
        None,
        low_open=True,
        cite=page("ER", "Both parameters must be integers."),
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
        cite=page("ES", "STEPPER RANGE: 0 < ES ≤ 65,535"),
    ),
    # -- F - H -------------------------------------------------------------------------------
    position("FP", choice=SILENT + "the FP page prints no RANGE line: the position range"),
    whole("HD", 0, 64_000, "RANGE: 0 ≤ HD ≤ 64,000", name="deadband", units="counts"),
    flag("HE", "HE,1;"),
    flag(
        "HF",
        "In AA or AM mode, a null value in the argument list specifies feedback for"
        " that axis is not to be disabled",
    ),
    whole("HG", 1, 32_000, "RANGE: 1 ≤ HG ≤ 32,000", name="hold gain"),
    flag(
        "HH",
        "In AA or AM modes, a null argument in the parameter list specifies that axis"
        " home switch to be unchanged",
    ),
    flag(
        "HL",
        "In AA or AM modes, a null argument in the parameter list specifies that axis"
        " home switch to be unchanged",
    ),
    position(
        "HM",
        choice=SILENT
        + "the HM page prints no RANGE line: “The position counters will be initialized to"
        " the positions supplied”, held to the position range",
    ),
    flag(
        "HN",
        "In AA or AM mode, a null value in the argument list specifies that encoder"
        " feedback is not to be enabled for that axis",
    ),
    position(
        "HR",
        choice=SILENT
        + "the HR page prints no RANGE line (“the position and encoder counters are loaded"
        " with the parameter(s)”): the position range",
    ),
    flag("HS", "HS,1;"),
    _R(
        "HV",
        1,
        "hold velocity",
        1,
        1_039_999,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=page("HV", "RANGE: 1 ≤ HV ≤ 1,039,999"),
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
        cite=page("IN", "-33,544,431 ≤ Parameter (Distance Before End of Move) ≤ 33,544,431"),
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
        cite=page("JF", "RANGE: -1,043,999.999 ≤ JF ≤ 1,043,999.995"),
    ),
    _R(
        "JG",
        1,
        "jog velocity",
        -1_043_999,
        1_043_999,
        units="counts/s (user units scaled)",
        scaled=True,
        cite=page("JG", "RANGE: -1,043,999 ≤ JG ≤ 1,043,999"),
    ),
    gain("KA", 0, 32_767, "RANGE: 0.00 ≤ KA ≤ 32,767.00"),
    gain("KB", 0, 10, "RANGE: 0.0 ≤ KB ≤ 10.0"),
    gain("KD", 0, 32_767, "RANGE: 0.00 ≤ KD ≤ 32,767.00"),
    gain("KF", 0, 32_767, "Range: 0 ≤ KF ≤ 32,767", number="integer"),
    gain("KI", 0, 32_767, "RANGE: 0.00 ≤ KI ≤ 32767.00"),
    _R(
        "KO",
        1,
        "offset",
        -32_767,
        32_767,
        cite=page("KO", "RANGE: -32767 ≤ KO ≤ 32767"),
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
        cite=page("KP", "RANGE: 0.00 ≤ KP ≤ 32767.00"),
        choice=CONTRADICTS
        + "§2.7.2's “The values for KP range from 0 to 249.99” (and KI, KD, KV, KA) is not"
        " taken: the command pages' RANGE lines are",
    ),
    flag(
        "KS",
        "In AA or AM modes, null values in the argument list specify that motion on"
        " that axis is not to be killed",
    ),
    gain("KU", 0, 32_767, "RANGE: 0 ≤ KU ≤ 32767", number="integer"),
    gain("KV", 0, 32_767, "RANGE: 0.00 ≤ KV ≤ 32,767.00"),
]
