"""The PC48 family's range rows, PC48 §6.10 - §6.21: loops, home, synchronization, user
units, encoder, staircase, contouring; the VS4's AA forms of the limit commands."""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange

from .kit import (
    CONTRADICTS,
    PC48,
    POSITION,
    SILENT,
    VS4,
    bits,
    per_speed,
    position,
)

_R = OperandRange

ROWS: list[_R] = [
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
    *bits("WS", "input bit"),
    # -- 6.11 home ---------------------------------------------------------------------------
    position(
        "HM",
        why="the HM page states no range for the position the counter is initialised to:"
        " the Appendix C position range",
    ),
    position(
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
    *bits("SW", "input bit"),
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
    *per_speed(
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
    position("MV", 1, why="the MV page states no range for the position: Appendix C"),
    *per_speed(
        "MV",
        2,
        "velocity",
        signed=False,
        magnitude=True,
        choice="the MV page states no range for the velocity: greater than zero and at most VL's"
        " limit in size (the direction is MP/MM's, a sign is accepted)",
    ),
    position("SP", why="the SP page states no range: the Appendix C position range"),
    position("FP", why="the FP page states no range: the Appendix C position range"),
    # -- 6.21 contouring ---------------------------------------------------------------------
    position(
        "CD",
        why="the CD page gives “the starting position of the contour in absolute units”, no"
        " range: the Appendix C position range",
    ),
    position(
        "CR",
        1,
        "X centre",
        why="the CR page gives “the center of the circle in absolute units”, no range: the"
        " Appendix C position range",
    ),
    position("CR", 2, "Y centre", why="as the X centre"),
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
    *per_speed(
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
