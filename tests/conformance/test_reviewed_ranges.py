"""Operand ranges and power-up defaults against the manuals' own words (PC48, VS4, PC46, PCIx).

``tests/board/test_operand_ranges.py`` drives every row of the range tables at its edges, so it
holds the behaviour to the tables; this file holds the tables to the manuals. Each case is an
edge the manual states in so many words (a "RANGE:" line, "must be greater than zero and less
than ..."), sent one value inside and one outside, with the manual's line quoted. The review
(every command page of the four manuals, by script, then by hand) found the tables and the
manuals in agreement; the points where a manual says two things are the choices of
docs/decisions.md ("Operand ranges") and are not repeated here.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness

PC48 = "PC48-4E"
VS4 = "VS4-040"
PC46 = "PC46-4E"
PCIX = "PCIX-040"
SERVO = "PCIX-400"

# (model, command, accepted, the manual's words with the seed file's line)
CASES: list[tuple[str, str, bool, str]] = []


def _edge(models: tuple[str, ...], inside: list[str], outside: list[str], words: str) -> None:
    for model in models:
        CASES.extend((model, cmd, True, words) for cmd in inside)
        CASES.extend((model, cmd, False, words) for cmd in outside)


FAMILY = (PC48, VS4, PC46)
_edge(
    (PC48,),
    ["VL1", "VL1044000"],
    ["VL0", "VL-1", "VL1044001"],
    "PC48 L1439: “The operand must be greater than zero and less than or equal to 1,044,000"
    " steps per second.”",
)
_edge(
    (VS4,),
    ["VL1", "VL522000"],
    ["VL0", "VL522001"],
    "VS4 L1063: “The operand must be greater than zero and less than or equal to 522,000 steps"
    " per second.”",
)
_edge(
    (PC46,),
    ["VL1", "VL522000"],
    ["VL0", "VL522001"],
    "PC46 L690: “0 to 522,000 pulses per second simultaneous on each axis”",
)
_edge(
    FAMILY,
    ["AC1", "AC7999999"],
    ["AC0", "AC-5", "AC8000000"],
    "PC48 L1419: “The parameter must be greater than zero (zero is not valid) and less than"
    " 8,000,000.” (VS4 L1043 the same)",
)
_edge(
    FAMILY,
    ["LP33554431", "LP-33554431"],
    ["LP33554432", "LP-33554432"],
    "PC48 L1477: “The range is −33,554,431 ≤ LP ≤ 33,554,431.” (VS4 L1103: “Range:"
    " -33,554,431 to +33,554,431”)",
)
_edge(
    FAMILY,
    ["RM1", "RM64999"],
    ["RM0", "RM-1", "RM65000"],
    "PC48 L1587: “The parameter must be greater than zero and less than 65,000.”",
)
_edge(
    FAMILY,
    ["WT1", "WT32000"],
    ["WT0", "WT32001"],
    "PC48 L2121: “The parameter must be between 1 and 32,000.”",
)
_edge(
    FAMILY,
    ["HG1", "HG32000"],
    ["HG0", "HG32001"],
    "PC48 L2404: “The parameter must be between 1 and 32,000.”",
)
_edge(FAMILY, ["HD0"], [], "PC48 L2417: “A parameter of zero is allowed.”")
_edge(
    FAMILY,
    ["SE0", "SE1000"],
    ["SE1001", "SE-1"],
    "PC48 L1341: “The parameter may be any value to 1000 milliseconds. Specification of a"
    " parameter of zero turns off the mode.”",
)
_edge(
    FAMILY,
    ["PN2", "PN3", "PN10", "PN11"],
    [],
    "PC48 L1241: “A parameter out of this range or no parameter supplied defaults to 70% or 3"
    " steps.” (no command error)",
)
_edge(
    (VS4,),
    ["JG1044000", "JG-1044000"],
    ["JG1044001", "JG-1044001"],
    "VS4 L1290: “Range: -1,044,000 <= JG <= +1,044,000”",
)
_edge(
    (VS4,),
    ["JF1044000.000", "JF-1044000.000"],
    ["JF1044000.001"],
    "VS4 L1306: “Range: -1,044,000.000 <= JG <= +1,044,000.000” (the JF page)",
)
_edge(
    (PCIX,),
    ["AC1", "AC8000000"],
    ["AC0", "AC8000001"],
    "PCIx L1676: “RANGE: 1 ≤ AC ≤ 8,000,000”",
)
_edge((PCIX,), ["DC1", "DC8000000"], ["DC0", "DC8000001"], "PCIx L2819: “RANGE: 1 ≤ DC ≤ 8000000”")
_edge((PCIX,), ["VL1", "VL1044000"], ["VL0", "VL1044001"], "PCIx L6924: “RANGE: 1 ≤ VL ≤ 1044000”")
_edge((PCIX,), ["VB0"], ["VB-1"], "PCIx L6872: “RANGE: 0 ≤ VB < VL value”")
_edge(
    (PCIX,),
    ["JG1043999", "JG-1043999"],
    ["JG1044000", "JG-1044000"],
    "PCIx L4060: “RANGE: -1,043,999 ≤ JG ≤ 1,043,999”",
)
_edge(
    (PCIX,),
    ["JF1043999.995", "JF-1043999.999"],
    ["JF1043999.996", "JF-1044000"],
    "PCIx L4030: “RANGE: -1,043,999.999 ≤ JF ≤ 1,043,999.995”",
)
_edge(
    (PCIX,),
    ["LP33554431", "LP-33554431"],
    ["LP33554432", "LP-33554432"],
    "PCIx L4869: “RANGE: −33,554,431 ≤ LP ≤ 33,554,431”",
)
_edge((PCIX,), ["LS1", "LS32767"], ["LS0", "LS32768"], "PCIx L4914: “RANGE: 1 ≤ LS ≤ 32,767”")
_edge(
    (PCIX,), ["HV1", "HV1039999"], ["HV0", "HV1040000"], "PCIx L3818: “RANGE: 1 ≤ HV ≤ 1,039,999”"
)
_edge((PCIX,), ["HD0", "HD64000"], ["HD-1", "HD64001"], "PCIx L3457: “RANGE: 0 ≤ HD ≤ 64,000”")
_edge((PCIX,), ["HG1", "HG32000"], ["HG0", "HG32001"], "PCIx L3550: “RANGE: 1 ≤ HG ≤ 32,000”")
_edge(
    (PCIX,),
    ["ES1", "ES65535"],
    ["ES0", "ES65536"],
    "PCIx L3159: “STEPPER RANGE: 0 < ES ≤ 65,535”",
)
_edge((PCIX,), ["RM1", "RM64999"], ["RM0", "RM65000"], "PCIx L5897: “RANGE: 0 < RM < 65,000”")
_edge((PCIX,), ["SE0", "SE1000"], ["SE1001"], "PCIx L6142: “RANGE: 0 ≤ SE ≤ 1000”")
_edge((PCIX,), ["TM0", "TM200000"], ["TM200001"], "PCIx L6683: “RANGE: 0 ≤ TM ≤ 200,000”")
_edge((PCIX,), ["WT1", "WT200000"], ["WT0", "WT200001"], "PCIx L7241: “RANGE: 1 ≤ WT ≤ 200,000”")
_edge((PCIX,), ["BH7"], ["BH8"], "PCIx L2203: “Range: 0 ≤ bit number ≤ 7”")
_edge((PCIX,), ["BSFF"], ["BS100"], "PCIx L2277: “Range: 00 ≤ Hex number ≤ FF”")
_edge((PCIX,), ["BC0", "BC50"], ["BC-1", "BC51"], "PCIx L2153: “0 ≤ BACKLASH ≤ +50 STEPPERS”")
_edge((SERVO,), ["BC-50", "BC50"], ["BC-51"], "PCIx L2155: “-50 ≤ BACKLASH ≤ +50 SERVOS”")
_edge((PCIX,), ["MD4"], ["MD5"], "PCIx L5030: “RANGE: 0 ≤ MD ≤ 4”")
_edge((PCIX,), ["DAR4"], ["DAR0", "DAR5"], "PCIx L2716: “RANGE: 1 ≤ DAR ≤ 4”")
_edge((PCIX,), ["?DS4"], ["?DS5"], "PCIx L2899: “RANGE: 1 ≤ ?DS ≤ 4”")
_edge(
    (PCIX,),
    ["?DE4,25"],
    ["?DE4,26", "?DE5,1"],
    "PCIx L2874-2875: “1 ≤ Parameter1 ≤ 4”, “1 ≤ Parameter2 ≤ 25”",
)
_edge((PCIX,), ["WS3"], ["WS4"], "PCIx L7211: “RANGE : 0 ≤ Parameter1 ≤ 3”")
_edge(
    (PCIX,),
    ["AJ1,0,1,10,0,1,1"],
    ["AJ5", "AJ1,1.1", "AJ1,0,0,0.9", "AJ1,0,0,10.1"],
    "PCIx L1837-1869: “1 ≤ # ≤ number of axes on board”, “0 ≤ ALOWER ≤ 1.0”, “1.0 ≤ ARADIUS ≤"
    " 10.0”",
)
_edge(
    (PCIX,),
    ["PN2", "PN11", "PR2"],
    [],
    "PCIx L5509: “A parameter out of this range ... defaults to 70% or 3 steps.”",
)
_edge((SERVO,), ["KP32767"], ["KP32767.01", "KP-0.01"], "PCIx L4436: “RANGE: 0.00 ≤ KP ≤ 32767.00”")
_edge((SERVO,), ["KB10"], ["KB10.1"], "PCIx L4146: “RANGE: 0.0 ≤ KB ≤ 10.0”")
_edge((SERVO,), ["KF32767"], ["KF32768"], "PCIx L4238: “Range: 0 ≤ KF ≤ 32,767”")
_edge((SERVO,), ["KU32767"], ["KU32768"], "PCIx L4538: “RANGE: 0 ≤ KU ≤ 32767”")
_edge((SERVO,), ["KO-32767", "KO32767"], ["KO32768"], "PCIx L4391: “RANGE: -32767 ≤ KO ≤ 32767”")
_edge(
    (SERVO,),
    ["DZ-32667", "DZ32667"],
    ["DZ32668", "DZ-32668"],
    "PCIx L2927: “RANGE: -32,667 ≤ DZ ≤ 32,667”",
)
_edge(
    (PCIX,),
    ["AN2147483647"],
    ["AN2147483648", "UU1.0000000001"],
    "PCIx L845: “Entering parameter values outside the range of a signed 32-bit integer will"
    " cause a Command Error.”; “For fixed point numeric parameters, the value without the"
    " decimal point must be within the range of a signed 32-bit integer.”",
)


@pytest.mark.parametrize(
    ("model", "command", "accepted", "words"),
    CASES,
    ids=[f"{m}-{c}" for m, c, _, _ in CASES],
)
def test_an_edge_the_manual_states(model: str, command: str, accepted: bool, words: str) -> None:
    h = Harness(model)
    h.send(f"AX {command} ")
    errors = h.errors()
    assert (errors == []) is accepted, (words, errors)


@pytest.mark.parametrize(
    ("prefix", "inside", "outside"),
    [("AA ", "CV1", "CV0"), ("AA ", "CV1043999", "CV1044000"), ("AX MP ", "MV100,1", "MV100,0")],
)
def test_pcix_contour_and_staircase_velocities_at_their_edge(
    prefix: str, inside: str, outside: str
) -> None:
    """PCIx L2572 “RANGE: 1 ≤ CV ≤ 1,043,999”; L5245 “1 ≤ Parameter 2 (Velocity) ≤
    1,043,999”: the edge is taken, one past it is a command error."""
    h = Harness(PCIX)
    h.send(f"{prefix}{inside} ")
    assert h.errors() == []
    h.send(f"{prefix}{outside} ")
    assert len(h.errors()) == 1


# -- power-up defaults -------------------------------------------------------------------------

#: (model, query, reply, the manual's words): a stepper's defaults on PCIX, the servo gains on
#: SERVO
PCIX_DEFAULTS = [
    (PCIX, "?AC", b"ac2000000", "L1674: “The default value is 2,000,000.”"),
    (PCIX, "?VL", b"vl200000", "L6922: “The factory default is 200,000 steps per second.”"),
    (PCIX, "?VB", b"vb0", "L6868: “where the factory default is zero steps per second”"),
    (PCIX, "?DC", b"dc200000", "L2817: “The deceleration rate defaults to 200,000”"),
    (PCIX, "?ES", b"es1", "L3153: “The factory default value is 1.”"),
    (PCIX, "?HG", b"hg1", "L3548: “The factory default value is 1.”"),
    (PCIX, "?HD", b"hd0", "L3455: “The factory default value is zero.”"),
    (PCIX, "?HV", b"hv0", "L3814: “The factory default setting is zero”"),
    (PCIX, "?SE", b"se0", "L6140: “The factory default settling time is zero.”"),
    (PCIX, "?ER", b"er1.0", "L3098: “The factory default ratio is 1:1.”"),
    (SERVO, "?KP", b"kp10.00", "L4434: “Default value is 10.00.”"),
    (SERVO, "?KI", b"ki0.04", "L4286: “Default value is 0.04.”"),
    (SERVO, "?KD", b"kd20.00", "L4190: “The factory default value is 20.00.”"),
    (SERVO, "?KV", b"kv0.00", "L4584: “The factory default value is zero.”"),
    (SERVO, "?KA", b"ka0.00", "L4098: “The factory default value is zero.”"),
    (SERVO, "?KF", b"kf0", "L4236: “The default value is 0.”"),
    (SERVO, "?KO", b"ko0", "L4387: “The factory default value is zero.”"),
]


@pytest.mark.parametrize(
    ("model", "query", "reply", "words"),
    PCIX_DEFAULTS,
    ids=[f"{m}{q}" for m, q, _, _ in PCIX_DEFAULTS],
)
def test_pcix_factory_value_reported(model: str, query: str, reply: bytes, words: str) -> None:
    h = Harness(model)
    assert h.send(f"AX {query} ") == reply + b"\n\r", words


@pytest.mark.parametrize(
    ("model", "vl", "ac", "words"),
    [
        (
            PC48,
            100_000,
            1_000_000,
            "PC48 L1439 “The velocity defaults to 100,000”, L1419 “default"
            " to 1,000,000 steps per second per second”",
        ),
        (
            VS4,
            200_000,
            2_000_000,
            "VS4 L1063 “The velocity defaults to 200,000”, L1043 “default"
            " to 2,000,000 steps per second per second”",
        ),
    ],
)
def test_pc48_family_power_up_velocity_and_acceleration(
    model: str, vl: int, ac: int, words: str
) -> None:
    """The PC48 family has no query for VL, AC or VB: the axis's registers after power-up
    (VB: "The base velocity defaults to zero at power up or reset", PC48 L1459, VS4 L1083)."""
    h = Harness(model)
    a = h.axis("X")
    assert (a.vl, a.ac, a.vb) == (vl, ac, 0.0), words
