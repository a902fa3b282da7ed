"""The PC48 family's range rows, PC48 §6.5 - §6.8: system control, user I/O, move
specification and execution."""

from __future__ import annotations

from omsd.protocol.ranges import OperandRange

from .kit import (
    CONTRADICTS,
    PC46_VL_CITE,
    PC48,
    SILENT,
    SLOW_VELOCITY,
    VELOCITY,
    VL_CITE,
    VS4,
    VS4_VL_CITE,
    bits,
    per_speed,
    position,
)

_R = OperandRange

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
    *bits("BL", "output bit"),
    *bits("BH", "output bit"),
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
    position(
        "MA",
        why="the MA page states no range: an absolute target is held to the Appendix C"
        " position range",
    ),
    position(
        "MR",
        name="distance",
        why="the MR page states no range: a relative distance is held to the Appendix C"
        " position range",
    ),
    position(
        "ML",
        name="distance",
        why="the ML page states no range: each axis's distance is held to the Appendix C"
        " position range",
    ),
    position(
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
    *per_speed(
        "JG",
        1,
        "jog velocity",
        signed=True,
        choice="the PC48 JG page states no range: held to VL's, as “This command modifies the"
        " move velocity parameter (VL)”; the VS4 has its own range line",
        vs4_high=VELOCITY,
        vs4_cite=f"{VS4} §6.8 JG: “Range: -1,044,000 <= JG <= +1,044,000”",
    ),
    *per_speed(
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
    *per_speed(
        "VS",
        2,
        "X velocity",
        signed=True,
        choice="the VS page states no range for the velocities: held to VL's; a negative one"
        " runs backwards (the example's VS1024,-1000,1000)",
    ),
    *per_speed(
        "VS",
        3,
        "Y velocity",
        signed=True,
        choice="as the X velocity",
    ),
]
