"""The PCIx's range rows: the commands L to W, and the MAX-family extension's."""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange

from .kit import (
    CHOSEN,
    CONTRADICTS,
    NOTE,
    POSITION,
    POSITION_CITE,
    SILENT,
    SLIP,
    flag,
    page,
    position,
    whole,
)

_R = OperandRange

ROWS: list[_R] = [
    # -- L ---------------------------------------------------------------------------------
    flag("LA", "LA,1,,1;"),
    flag("LF", "LF,1;"),
    flag(
        "LH",
        "In AA or AM modes, a null argument in the argument list specifies that axis is"
        " not to be affected",
    ),
    flag(
        "LL",
        "In AA or AM modes, a null argument in the argument list specifies that axis is"
        " not to be affected",
    ),
    flag(
        "LN",
        "In AA or AM modes, a null argument in the parameter list specifies that axis is"
        " not to be affected",
    ),
    position(
        "LO",
        cite=page("LO", "Any valid position within the allowable position range may be used."),
    ),
    position("LP"),
    whole(
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
    position("MA", choice=SILENT + "the MA page prints no RANGE line: the position range"),
    whole(
        "MD",
        0,
        4,
        "RANGE: 0 ≤ MD ≤ 4",
        name="macro",
    ),
    position(
        "ML",
        name="distance",
        choice=SILENT + "the ML page prints no RANGE line: the position range",
    ),
    position(
        "MR",
        name="distance",
        choice=SILENT + "the MR page prints no RANGE line: the position range",
    ),
    position(
        "MT",
        choice=SILENT + "the MT page prints no RANGE line: the position range, in or out of"
        " a contour definition",
    ),
    position(
        "MV",
        cite=page("MV", "-33,544,431 ≤ Parameter 1 (Absolute Position) ≤ 33,544,431"),
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
        cite=page("MV", "1 ≤ Parameter 2 (Velocity) ≤ 1,043,999"),
    ),
    whole("MX", 0, 24, "RANGE: 0 ≤ MX ≤ 24", name="macro"),
    # -- N - P -------------------------------------------------------------------------------
    _R(
        "NV",
        1,
        "contour velocity",
        1,
        1_043_999,
        number="decimal",
        units="counts/s",
        cite=page("NV", "RANGE: 1 ≤ NV ≤ 1,043,999"),
    ),
    flag(
        "PA",
        "the auxiliary output is turned off (driven low) upon the execution of the GO or GD"
        " command and on at the end of the move",
        units="zero or non-zero, per axis",
    ),
    flag("PH", "This command disables power automatic (PA) mode."),
    flag("PL", "This command disables power automatic (PA) mode."),
    whole("PM", 0, 24, "RANGE: 0 ≤ PM ≤ 24", name="macro"),
    whole(
        "PN",
        3,
        10,
        "RANGE: 3 ≤ PN ≤ 10 ... A parameter out of this range or no parameter supplied defaults"
        " to 70% or 3 steps.",
        name="parabolic steps",
        default=3,
    ),
    whole(
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
    whole("PT", 0, 4, "0 ≤ Parameter 1 ≤ 4", name="temporary macro"),
    whole("PT", 5, 24, "5 ≤ Parameter 2 ≤ 24", operand=2, name="permanent macro"),
    # -- R - S -------------------------------------------------------------------------------
    _R(
        "RM",
        1,
        "divisor",
        0,
        65_000,
        low_open=True,
        high_open=True,
        cite=page("RM", "RANGE: 0 < RM < 65,000"),
    ),
    flag("SC", "SC,1,,1;"),
    whole("SE", 0, 1000, "RANGE: 0 ≤ SE ≤ 1000", name="settling time", units="ms"),
    flag("SF", "SF,1,,1;"),
    flag(
        "SI",
        "Any non-zero value in a parameter will cause the corresponding axis to be stopped.",
        units="zero: not stopped, non-zero: stopped",
    ),
    flag("SL", "SL,1,,1;"),
    position(
        "SO",
        1,
        "stop position",
        cite=page("SO", "-33,554,431 ≤ Parameter 1 (Stop Position) ≤ 33,554,431"),
    ),
    position(
        "SO",
        2,
        "distance",
        cite=page(
            "SO",
            "-33,554,431 ≤ Parameter 2 (Distance from Stop Position to Start Decelerating) ≤"
            " 33,554,431",
        ),
    ),
    position("SP", choice=SILENT + "the SP page prints no RANGE line: the position range"),
    whole("SR", 1, 4, "RANGE: 1 ≤ SR ≤ 4", name="table"),
    whole("SS", 1, 4, "RANGE: 1 ≤ Ramp Number ≤ 4", name="profile"),
    whole(
        "SW",
        0,
        7,
        "RANGE: 0 ≤ Bit Number ≤ 7 ... must be configured as an input",
        name="bit number",
    ),
    # -- T - W -------------------------------------------------------------------------------
    position(
        "TL", 1, "upper limit", cite=page("TL", "RANGE: ±33,544,431"), choice=CONTRADICTS + SLIP
    ),
    position(
        "TL", 2, "lower limit", cite=page("TL", "RANGE: ±33,544,431"), choice=CONTRADICTS + SLIP
    ),
    whole("TM", 0, 200_000, "RANGE: 0 ≤ TM ≤ 200,000", name="time", units="ms"),
    _R(
        "TX",
        1,
        "|ratio| × X's VL",
        1,
        1_048_574,
        high_open=True,
        number="decimal",
        units="counts/s",
        cite=page(
            "TX", "The command argument is the tracking ratio specified as a floating point."
        ),
        choice=SILENT + "no range is printed: TX is gearing to X, so EG's rule (“Gear Ratio *X the"
        " Master Axis' VL value ... at least 1 and less than ... 1,048,574”) is applied",
    ),
    flag("UF", "UF1,1,1;"),
    _R(
        "UU",
        1,
        "multiplier",
        0,
        1_000_000_000,
        low_open=True,
        number="decimal",
        units="counts per user unit",
        cite=page(
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
        cite=page("VB", "RANGE: 0 ≤ VB < VL value"),
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
        cite=page("VL", "RANGE: 1 ≤ VL ≤ 1044000"),
    ),
    whole(
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
            cite=page("VS", f"0 ≤ Parameter {operand} ({name}) ≤ 1,043,999"),
            choice=CONTRADICTS
            + "the page's own example streams VS1024,-1000,1000 (X backwards): the"
            " velocities are taken to be signed, ±1,043,999",
        )
        for operand, name in ((2, "X Axis Velocity"), (3, "Y Axis Velocity"))
    ),
    whole(
        "WS",
        0,
        3,
        "#RANGE : 0 ≤ Parameter1 ≤ 3",
        name="input bit",
        choice=NOTE + "the factory inputs are bits 0-3 (§2.2 S3), which the range line matches; the"
        " optional second parameter (state) has no range line: any number, zero or not",
    ),
    whole("WT", 1, 200_000, "RANGE: 1 ≤ WT ≤ 200,000", name="time", units="ms"),
    # -- the MAX-family extension (omsd/models/max_family.py) ---------------------------------
    _R(
        "CL",
        number="flag",
        units="0 opens the loop (HF), anything else closes it (HN)",
        choice=SILENT + "not in the PCIx manual: EPICS omsBaseController sends CL1/CL0 where older"
        " firmware gets HN/HF (omsd/dialects/pcix/max_family.py); any non-zero value closes",
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
        " omsBaseController, omsd/dialects/pcix/max_family.py), with LP's range",
    ),
]
