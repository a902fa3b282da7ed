"""The PC46 datasheet ("PC46 Intelligent Motion Controller for PC", ``shared/seeds/004_*.txt``):
its four programming examples P1–P4 (digest ``pc48-pc46.md`` §5.y) and the PC46 specifics.

The datasheet prints no replies, so the examples are checked by the state they lead to
(positions, velocities, timing, aux lines, errors) on models that have what they need: P2 the
encoder option (-2E, -4E), P3 contouring and a Z and T axis (-42, -6, -4E; not -21/-41, which
have no contouring, nor -22, which has no Z). Everything the datasheet leaves out is the PC48's
behaviour (``omsd/models/pc46.py``): PC48 defaults (VL 100,000, AC 1,000,000), queue costs and
replies.

Timing: 1024 samples a second, 512 on the -21 and -41; a move starts on the first tick at or
after its GO and is done on the first tick at or after its analytic end.
"""

from __future__ import annotations

import math
import pathlib
import re
from fractions import Fraction

import pytest

from omsd.board.events import DoneEvent, ErrorKind
from omsd.board.harness import Harness
from omsd.models import MODELS
from omsd.models.pc46 import PC46_COMMANDS, PC46_COMMANDS_NO_CONTOUR

from .support import errors, first_time, frame, quiet, status_frame

DATASHEET = pathlib.Path(__file__).parents[3] / "shared" / "seeds" / "004_47955639fb93103e.txt"

# model: (axes, encoder axes, samples per second)
PC46 = {
    "PC46-21": ("XY", "", 512),
    "PC46-22": ("XY", "", 1024),
    "PC46-41": ("XYZT", "", 512),
    "PC46-42": ("XYZT", "", 1024),
    "PC46-6": ("XYZTUV", "", 1024),
    "PC46-2E": ("XY", "XY", 1024),
    "PC46-4E": ("XYZT", "XY", 1024),
}
NO_CONTOUR = ("PC46-21", "PC46-41")
CONTOUR_ONLY = ("CD", "CE", "CK", "CR", "CV", "CX")

# The commands the datasheet describes, in its order ("The following summarizes some of the PC46
# command set"): the PC48's 107 without AR and AS.
_LISTED = (
    "AA AM AX AY AZ AT AU AV EN EF HH HL LF LN SL SF CN PN PF RS AC VL VB LP MA MR MT ML MO RM "
    "GO GD JG JF VS ST SA SD KL LS LE WS WD WH WG CW HM HR KM KR ID II IN IC CA WA WQ SW WT WY "
    "RP RQ RA RI QA QI RC RV RU UU UF AN AF PA SE BL BH BX RB CD CE CK CR CV CX ER HV HG HD HF "
    "HN IP ES IS RL ET HE HS EA RE MP MM MV SP FP"
)
DATASHEET_COMMANDS = _LISTED.split()


def tick_at_or_after(t: float | Fraction, rate: int) -> Fraction:
    return Fraction(math.ceil(Fraction(t) * rate), rate)


def trapezoid(distance: int, vl: int, ac: int) -> Fraction:
    """Duration of a linear-ramp move that reaches ``vl`` (PC48 §1.3)."""
    assert distance * ac >= vl * vl
    return Fraction(2 * vl, ac) + Fraction(distance * ac - vl * vl, ac * vl)


# -- P1: X relative move, then Y absolute after X --------------------------------------------------

P1 = "AA\r\nVL400000,400000; AC500000,500000;\r\nMR1000000; GO\r\nMA,1000000; GO\r\n"


@pytest.mark.parametrize("model", ["PC46-22", "PC46-21", "PC46-6"])
def test_p1_x_moves_then_y_moves_after_x_has_finished(model: str) -> None:
    """P1: "Move a relative distance of 1,000,000 pulses on the X axis with a velocity of
    400,000 pulses per second and a peak acceleration of 500,000 ... Wait for the X axis to
    finish its motion, then move the Y axis to an absolute position of 1,000,000 with the same
    velocity and acceleration parameters." The wait is the AA synchronization: the second GO
    concerns every axis, so Y's waits for X to reach it (digest §7.1, inferred mechanism).

    Each move: 0.8 s ramps of 160,000 pulses and 1.7 s at 400,000/s: 3.3 s. X starts on tick 0
    and is done on the first tick at or after 3.3 s; Y starts on that tick and is done 3.3 s
    later, rounded up to a tick again."""
    rate = PC46[model][2]
    h = quiet(model)
    assert h.send(P1) == b""
    move = trapezoid(1_000_000, 400_000, 500_000)
    assert move == Fraction(33, 10)
    x_done = tick_at_or_after(move, rate)
    y_done = tick_at_or_after(x_done + move, rate)
    h.until(1.0)
    assert h.query("RV") == frame("400000,0" + ",0" * (len(PC46[model][0]) - 2))
    assert abs(h.position("X") - 240_000) <= 1
    h.until(3.29)
    assert 0 < h.axis("X").velocity(h.t) < 400_000
    assert h.position("Y") == 0
    h.until(float(x_done) - 1e-6)
    assert h.position("X") == 1_000_000
    assert h.axis("Y").velocity(h.t) == 0.0
    h.until(float(x_done) + 0.001)
    assert h.axis("Y").velocity(h.t) == pytest.approx(500.0)
    h.until(float(x_done) + 1.0)
    assert h.axis("Y").velocity(h.t) == 400_000
    assert h.position("X") == 1_000_000
    h.send("ID")
    h.run()
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert [e.time for e in done] == [float(y_done)]
    # X moved 1,000,000 and Y went to 1,000,000; the other axes were not asked to move
    assert h.query("RP") == frame("1000000,1000000" + ",0" * (len(PC46[model][0]) - 2))
    assert h.errors() == []


# -- P2: position correction (option E) ------------------------------------------------------------

P2 = "AX VL100000 AC500000\r\nHV50000 HD10 HG2000 HN\r\nMR200000 GO\r\n"


@pytest.mark.parametrize("model", ["PC46-2E", "PC46-4E"])
def test_p2_position_maintained_within_the_deadband(model: str) -> None:
    """P2 (option E): "Perform a relative 200,000 step move. The control will perform the
    200,000 step move then maintain position within the 10 step deadband until commanded to a
    new position." The move takes 2.2 s (0.2 s ramps of 10,000 steps at AC 500,000); slips of
    +500 and -300 steps injected afterwards are corrected back within 10 encoder counts."""
    h = quiet(model)
    h.send(P2)
    assert h.errors() == []
    h.until(2.1)
    assert h.axis("X").moving
    h.until(2.3)
    assert h.position("X") == 200_000
    assert h.query("RE") == frame("200000")
    assert h.query("EA") == status_frame("DENPNN")
    h.board.inject_slip("X", 500, h.t)
    h.until(3.0)
    assert abs(int(h.query("RE")[2:-2]) - 200_000) <= 10
    assert 199_490 <= h.position("X") <= 199_510
    assert h.query("EA") == status_frame("DENPNN")
    h.board.inject_slip("X", -300, h.t)
    h.until(3.5)
    assert abs(int(h.query("RE")[2:-2]) - 200_000) <= 10


def test_p2_on_a_model_without_encoders_only_moves() -> None:
    """P2 is "available in option E controls only": on a PC46-22 HV, HD, HG and HN are
    command errors and the move is made without position maintenance."""
    h = quiet("PC46-22")
    h.send(P2)
    assert errors(h) == [
        (ErrorKind.NO_ENCODER, "HV50000"),
        (ErrorKind.NO_ENCODER, "HD10"),
        (ErrorKind.NO_ENCODER, "HG2000"),
        (ErrorKind.NO_ENCODER, "HN"),
    ]
    h.run()
    assert h.position("X") == 200_000
    h.board.inject_slip("X", 500, h.t)
    h.advance(1.0)
    assert h.position("X") == 200_000
    assert h.axis("X").phys(h.t) == pytest.approx(200_500)


# -- P3: cut a hole with circular interpolation on Z and T -----------------------------------------

P3 = (
    "CV1000\r\nCD,,0,0;\r\nAN0;\r\nCR0,5000,3.1415926\r\nCR0,0,6.2831853\r\nAF0;\r\n"
    "MT-10,10000\r\nCE\r\nMT,,-1000,0; GO\r\nCX"
)


@pytest.mark.parametrize("model", ["PC46-42", "PC46-6", "PC46-4E"])
def test_p3_cut_hole_on_z_and_t_with_x_aux_as_torch(model: str) -> None:
    """P3: "A contour is defined beginning at coordinates 0,0 on the Z and T axes. Auxiliary
    output on the X axis is turned on ... A half circle is cut from the center to the outside of
    the hole ... The hole is then cut, the torch turned off, the stage stopped and the contour
    definition completed. The stage is then positioned and the contour definition executed."

    Readings: the text never enters AA, but CD and CV are AA-mode commands (CD "is executed in
    the AA mode"), so ``AA`` is sent first (digest §5.y: AA mode inferred). In the contour the
    AN/AF lists address X by their first field. ``MT-10,10000`` is as printed: a 10-count line
    to (-10, 10000). The X aux is off before the example.

    Timeline (Z,T): MT,,-1000,0 positions Z 1000 counts before the start (0.0632 s at VL
    100,000, AC 1,000,000); from there CX accelerates to 1000/s over those 1000 counts (2 s)
    reaching (0,0) at speed; torch on; half circle of radius 5000 about (0,5000) to (0,10000)
    (15.708 s); full circle of radius 10,000 about (0,0) (62.832 s); torch off; 0.01 s to
    (-10,10000); CE ramps down at AC (half a count)."""
    h = quiet(model)
    h.send("AX AF AA ")
    h.run()
    assert h.axis("X").aux is False
    h.send(P3)
    assert h.errors() == []
    t0 = float(tick_at_or_after(2 * math.sqrt(1000 / 1e6), 1024))
    h.until(t0 + 1.9)
    assert -1000 < h.position("Z") < 0
    assert h.position("T") == 0
    assert h.axis("X").aux is False
    h.until(t0 + 2.1)
    assert h.axis("X").aux is True
    assert h.axis("Z").velocity(h.t) == pytest.approx(1000, abs=2)
    half = math.pi * 5000 / 1000
    h.until(t0 + 2 + half / 2)
    assert abs(h.position("Z") - 5000) <= 3
    assert abs(h.position("T") - 5000) <= 3
    h.until(t0 + 2 + half)
    assert abs(h.position("Z")) <= 3
    assert abs(h.position("T") - 10_000) <= 3
    full = 2 * math.pi * 10_000 / 1000
    h.until(t0 + 2 + half + full / 4)
    assert abs(h.position("Z") + 10_000) <= 3
    assert abs(h.position("T")) <= 3
    h.until(t0 + 2 + half + full / 2)
    assert abs(h.position("Z")) <= 3
    assert abs(h.position("T") + 10_000) <= 3
    h.until(t0 + 2 + half + full - 0.1)
    assert h.axis("X").aux is True
    h.until(t0 + 2 + half + full + 0.1)
    assert h.axis("X").aux is False
    assert not h.axis("Z").moving and not h.axis("T").moving
    assert abs(h.position("Z") + 10) <= 1
    assert h.position("T") == 10_000
    assert h.position("X") == 0 and h.position("Y") == 0
    h.run()
    assert abs(h.position("Z") + 10) <= 1
    assert h.errors() == []


def test_p3_typed_at_power_up_is_refused_outside_aa_mode() -> None:
    """P3 as printed begins ``CV1000`` / ``CD,,0,0;`` with no ``AA`` (the PC48's and VS4's hole
    examples begin with one); CD "is executed in the AA mode" and CV "from the AA mode" (PC48
    tables: "AX – AS Not valid"). Typed at power-up, in single-axis mode, the contour lines are
    command errors, AN0/AF0 switch X's auxiliary output, and nothing moves (decisions.md, "PC46
    readings")."""
    h = quiet("PC46-42")
    h.send(P3 + " ")
    h.run()
    assert errors(h) == [
        (ErrorKind.NOT_VALID_IN_MODE, "CV1000"),
        (ErrorKind.NOT_VALID_IN_MODE, "CD,,0,0"),
        (ErrorKind.NOT_VALID_IN_MODE, "CR0,5000,3.1415926"),
        (ErrorKind.NOT_VALID_IN_MODE, "CR0,0,6.2831853"),
        (ErrorKind.NOT_VALID_IN_MODE, "MT-10,10000"),
        (ErrorKind.NOT_VALID_IN_MODE, "CE"),
        (ErrorKind.NOT_VALID_IN_MODE, "MT,,-1000,0"),
        (ErrorKind.NOT_VALID_IN_MODE, "CX"),
    ]
    assert h.axis("X").aux is False
    assert h.query("AA RP") == frame("0,0,0,0")


@pytest.mark.parametrize("model", NO_CONTOUR)
def test_p3_needs_contouring_not_on_21_41(model: str) -> None:
    """ "*These commands are not available on the PC46-21 and PC46-41 models." Sent to a -41 (or
    a -21), P3's CV, CD, CR, CR, CE and CX are each an unknown command; the board goes on."""
    h = quiet(model)
    h.send("AA " + P3 + " ")
    assert errors(h) == [
        (ErrorKind.UNKNOWN_COMMAND, "CV"),
        (ErrorKind.UNKNOWN_COMMAND, "CD"),
        (ErrorKind.UNKNOWN_COMMAND, "CR"),
        (ErrorKind.UNKNOWN_COMMAND, "CR"),
        (ErrorKind.UNKNOWN_COMMAND, "CE"),
        (ErrorKind.UNKNOWN_COMMAND, "CX"),
    ]
    assert h.send("WY") == frame(f"PC46 ver 1.00-{len(PC46[model][0])}")


# -- P4: velocity staircase ------------------------------------------------------------------------

P4 = "MP\r\nMV10000,30000\r\nMV20000,50000\r\nMV30000,10000\r\nSP35000\r\n"


@pytest.mark.parametrize("model", ["PC46-22", "PC46-21"])
def test_p4_velocity_staircase(model: str) -> None:
    """P4: "Define a move in the positive direction. Accelerate to 30,000 pulses per second and
    move to position 10,000. Without stopping, accelerate to 50,000 pulses per second and move
    to absolute position 20,000. Without stopping, decelerate to 10,000 pulses per second and
    move to absolute position 30,000. Decelerate to a stop at position 35,000."

    At the default AC 1,000,000 (PC48's; the datasheet gives none): 30,000/s after 0.03 s; the
    change of velocity at each breakpoint starts on the first sample tick at or after the
    breakpoint is passed (so at most one sample's travel beyond it); the stop ends exactly at
    35,000, decelerating over the last 50 pulses."""
    rate = PC46[model][2]
    sample = 1 / rate
    h = quiet(model)
    assert h.send(P4) == b""
    h.until(0.2)
    assert h.query("RV") == frame("30000")
    x = h.axis("X")
    t1 = first_time(h, lambda: x.velocity(h.t) > 30_000, 1e-4, 1.0)
    assert 10_000 <= h.position("X") <= 10_000 + 30_000 * (sample + 1e-4) + 1
    assert t1 - 10_000 / 30_000 <= 0.015 + sample + 1e-4
    h.until(t1 + 0.021 + sample)
    assert h.query("RV") == frame("50000")
    t2 = first_time(h, lambda: x.velocity(h.t) < 50_000, 1e-4, 1.0)
    assert 20_000 <= h.position("X") <= 20_000 + 50_000 * (sample + 1e-4) + 1
    h.until(t2 + 0.041 + sample)
    assert h.query("RV") == frame("10000")
    first_time(h, lambda: h.position("X") >= 34_000, 1e-3, 2.0)
    assert h.query("RV") == frame("10000")
    assert h.position("X") <= 34_950
    first_time(h, lambda: not x.moving, 1e-4, 1.0)
    assert h.position("X") == 35_000
    assert h.axis("X").velocity(h.t) == 0.0
    h.run()
    assert h.position("X") == 35_000
    assert h.errors() == []


# -- PC46 specifics --------------------------------------------------------------------------------


@pytest.mark.parametrize("model", sorted(PC46))
def test_models_axes_and_wy(model: str) -> None:
    """ "ORDERING INFORMATION": -21/-22 two axes, -41/-42 four, -6 six, -2E two and -4E four
    (the "Axes of feedback" 2). Axis letters X, Y, Z, T, U, V; no AR or AS. WY "returns the
    model and firmware revision": no example is printed, so the PC48 form is used
    (``PC46 ver 1.00-<axes>``). Power-up VL and AC are the PC48's."""
    axes = PC46[model][0]
    h = Harness(model)
    assert MODELS[model].axes == axes
    assert h.send("WY") == frame(f"PC46 ver 1.00-{len(axes)}")
    assert h.query("AA RP") == frame(",".join("0" * len(axes)))
    assert h.query("AX RC") == frame("1000000")
    assert h.axis("X").vl == 100_000
    for letter in "XYZTUV":
        h.send(f"A{letter} ")
        expected = [] if letter in axes else [(ErrorKind.NO_SUCH_AXIS, f"A{letter}")]
        assert errors(h) == expected, letter
    h.send("AR AS ")
    assert errors(h) == [(ErrorKind.UNKNOWN_COMMAND, "AR"), (ErrorKind.UNKNOWN_COMMAND, "AS")]


@pytest.mark.parametrize("model", sorted(PC46))
def test_encoders_on_x_and_y_of_the_e_models(model: str) -> None:
    """ "Incremental encoder feedback is available as an option on up to 2 axes": on the -2E
    and -4E the encoder pins are X's and Y's. RE answers there; on Z and T of a -4E, and on
    every axis of the other models, it is a command error."""
    axes, encoders, _ = PC46[model]
    h = Harness(model)
    h.send("AA MR" + ",".join(str(10 * (i + 1)) for i in range(len(axes))) + "; GO")
    h.run()
    for i, letter in enumerate(axes):
        reply = h.query(f"A{letter} RE")
        if letter in encoders:
            assert reply == frame(str(10 * (i + 1))), letter
            assert h.errors() == []
        else:
            assert reply == b""
            assert errors(h) == [(ErrorKind.NO_ENCODER, "RE")], letter


@pytest.mark.parametrize("model", sorted(PC46))
def test_mo_not_on_models_with_the_encoder_option(model: str) -> None:
    """MO: "This command is not available in models with an encoder option." (On a -4E also
    on Z and T, which have no encoder: the option is the model's.)"""
    h = Harness(model)
    letter = PC46[model][0][-1]
    h.send(f"A{letter} MO")
    h.run()
    if PC46[model][1]:
        assert errors(h) == [(ErrorKind.ENCODER_MODEL, "MO")]
        assert h.position(letter) == 0
    else:
        assert h.errors() == []
        assert h.position(letter) == 1


@pytest.mark.parametrize("model", NO_CONTOUR)
@pytest.mark.parametrize(
    "command", ["CD0,0;", "CE", "CK", "CR0,100,3.14;", "CV1000;", "CX"], ids=CONTOUR_ONLY
)
def test_no_contouring_on_21_and_41(model: str, command: str) -> None:
    """ "CONSTANT VELOCITY CONTOURING COMMANDS ... *These commands are not available on the
    PC46-21 and PC46-41 models.": each is an unknown command there, in AA mode as anywhere."""
    h = Harness(model)
    h.send(f"AA {command} ")
    assert errors(h) == [(ErrorKind.UNKNOWN_COMMAND, command[:2])]
    assert h.board.read_status_register(h.t) & 0x01
    assert h.query("RQ") == frame(",".join(["200"] * len(PC46[model][0])))


@pytest.mark.parametrize("model", ["PC46-22", "PC46-42", "PC46-6", "PC46-2E", "PC46-4E"])
def test_contouring_on_the_other_models(model: str) -> None:
    """The other models have the contour commands, with the PC48's 1016-slot contour queue."""
    h = Harness(model)
    h.send("AA CV1000; CD0,0;")
    assert h.query("RQ") == frame("1016")
    h.send("MT100,100; CE CX")
    h.run()
    assert h.errors() == []
    # the contour's end, 100,100 (the ramp down from CV 1000 at AC 1,000,000 is under a step:
    # 707^2 / 2,000,000 = 0.25 per axis); the other axes are not in the contour
    assert h.query("RP") == frame("100,100" + ",0" * (len(PC46[model][0]) - 2))


@pytest.mark.parametrize("model", sorted(PC46))
def test_sample_rate_512_or_1024(model: str) -> None:
    """ "calculating the optimum velocity 1024 times each second (512 times each second on the
    -21 and -41 models)". ``MR5000`` at VL 10,000, AC 100,000 (0.6 s) sent at 0.0003 s starts on
    tick 1 and is done on tick 616 of 1024 (tick 309 of 512)."""
    rate = PC46[model][2]
    h = Harness(model)
    h.until(0.0003)
    h.send("AX VL10000 AC100000 MR5000 GO ID")
    h.until(1 / rate - 1e-6)
    assert h.axis("X").velocity(h.t) == 0.0
    h.until(1 / rate + 1e-4)
    assert h.axis("X").velocity(h.t) > 0.0
    h.run()
    done = [e.time for e in h.events() if isinstance(e, DoneEvent)]
    assert done == [616 / 1024 if rate == 1024 else 309 / 512]
    assert h.position("X") == 5000


@pytest.mark.parametrize("model", ["PC46-21", "PC46-41", "PC46-22"])
def test_velocity_stream_time_is_in_1024ths_also_at_512_samples(model: str) -> None:
    """VS: "The VS command will generate a pulse train without acceleration or deceleration at
    the rates specified for the time specified by the first parameter" (datasheet); the PC48
    page gives the unit: "time in 1/1024 second sample intervals" (on a board that samples
    2048 times a second: the unit is not the sample). The datasheet names no other unit for the
    -21 and -41, which sample "512 times each second", so a stream takes the time it asks for
    there too: twenty ``VS3,1024,0;`` are 60/1024 s at 1024 steps/s, 60 steps, not 80 (each
    entry's three 1024ths rounded up to the next 512th sample, as before). A velocity changes
    on the sample at or after the entry's time; the entries' times add up as given.
    ``VS1024,1000,0;`` lasts one second on every model."""
    h = quiet(model)
    for _ in range(2):
        h.send("AX " + "VS3,1024,0;" * 10)
    h.send("VS1,0,0;")
    x = h.axis("X")
    h.until(59 / 1024)
    assert x.velocity(h.t) == 1024
    h.until(61 / 1024)
    assert x.velocity(h.t) == 0
    assert h.position("X") == 60
    h.run()
    assert h.position("X") == 60
    h = quiet(model)
    h.send("AX VS1024,1000,0; VS1,0,0;")
    h.until(2.0)
    assert h.position("X") == 1000
    assert h.errors() == []


@pytest.mark.parametrize("model", ["PC46-21", "PC46-41", "PC46-22"])
@pytest.mark.parametrize("arrives", [3.4, 4.0])
@pytest.mark.parametrize("interrupt", ["KL;", "ST;"])
def test_a_stream_begun_after_an_interruption_takes_its_whole_time(
    model: str, arrives: float, interrupt: str
) -> None:
    """VS: "generate a pulse train ... at the rates specified for the time specified by the
    first parameter" (datasheet), the time "in 1/1024 second sample intervals" (PC48 §6.8). A
    stream stopped (KL, ST) while its entry's time still ran, and begun again by a new VS, has
    nothing to follow on from: the new entry counts its time from the sample it begins on, on
    every PC46 (a 512-sample board rounds it up to the next sample). ``VS3,1024,0;`` killed at
    1.5/1024 s, ``VS3,1024,0;VS1,0,0;`` sent at 3.4/1024 s (or 4/1024 s, on a sample): X runs at
    1024 steps a second from 4/1024 s for 3/1024 s (4/1024 s on the -21 and -41), and did not
    count from the end of the killed entry's time (3/1024 s), which left the new one 2/1024 s."""
    rate = MODELS[model].sample_rate
    h = quiet(model)
    h.send("AX VS3,1024,0;")
    h.until(1.5 / 1024)
    h.send(interrupt)
    h.until(arrives / 1024)
    h.send("VS3,1024,0;VS1,0,0;")
    x = h.axis("X")
    start = h.position("X")
    end = tick_at_or_after(Fraction(4 + 3, 1024), rate)
    h.until(float(end) - 0.5 / 1024)
    assert x.velocity(h.t) == 1024
    h.until(float(end) + 0.5 / 1024)
    assert x.velocity(h.t) == 0
    h.run()
    assert h.position("X") - start == (end - Fraction(4, 1024)) * 1024
    assert h.errors() == []


@pytest.mark.parametrize("model", ["PC46-22", "PC46-21"])
def test_velocity_at_most_522000(model: str) -> None:
    """ "Velocity 0 to 522,000 pulses per second simultaneous on each axis" (the features' "0 to
    1,044,000 steps per second" is the other reading, digest §8.3 item 37; the specification is
    taken, and JG is held to it too)."""
    h = Harness(model)
    h.send("AX VL522000; VL522001; JG522001; JG-522001;")
    assert errors(h) == [
        (ErrorKind.OUT_OF_RANGE, "VL522001"),
        (ErrorKind.OUT_OF_RANGE, "JG522001"),
        (ErrorKind.OUT_OF_RANGE, "JG-522001"),
    ]
    h.send("JG522000;")
    h.until(h.t + 1.0)
    assert h.query("RV") == frame("522000")
    assert h.errors() == []


@pytest.mark.parametrize("model", ["PC46-22", "PC46-6", "PC46-4E"])
def test_sixteen_gp_bits_inputs_0_to_7_outputs_8_to_15(model: str) -> None:
    """ "8 general purpose inputs with 2.2k Ohm pull-up resistors and 8 general purpose outputs"
    with "pull-up resistors on I/O bits 0-7": inputs 0–7, outputs 8–15 (the -21..-42 pin table
    names them the other way round; the text about the pull-ups decides). RB reports the
    directions (00FF00), BL/BH drive 8–15, BX shows both inputs and outputs low."""
    h = Harness(model)
    b = h.board
    assert h.query("RB") == frame("00FF00")
    assert h.query("BX") == frame("000000")
    h.send("BL15; BL8;")
    h.run()
    assert h.errors() == []
    assert b.outputs_low == 0x8100
    b.set_input(3, False, h.t)
    assert h.query("BX") == frame("008108")
    h.send("BH15;")
    h.run()
    assert h.query("BX") == frame("000108")
    h.send("BL7; BL16;")
    assert errors(h) == [(ErrorKind.NOT_AN_OUTPUT, "BL7"), (ErrorKind.OUT_OF_RANGE, "BL16")]
    with pytest.raises(ValueError):
        b.set_input(16, False, h.t)
    pc48 = Harness("PC48-4")
    assert pc48.query("RB") == frame("003F00")


@pytest.mark.parametrize("model", ["PC46-22", "PC46-41"])
def test_buffer_124_characters_and_queues_of_200(model: str) -> None:
    """ "An internal queue can store up to 200 command parameters in an input queue for each axis
    as well as 124 characters in an input character buffer"."""
    h = Harness(model)
    b = h.board
    assert h.query("AX RQ") == frame("200")
    h.send("VL1000 MR100000 GO WQ")
    assert b.receive(b"RP" * 100, h.t) == 124


def test_the_datasheet_lists_105_commands() -> None:
    """The copied list is the datasheet's: 105 two-letter commands, the PC48's without AR, AS."""
    assert len(DATASHEET_COMMANDS) == len(set(DATASHEET_COMMANDS)) == 105
    assert "AR" not in DATASHEET_COMMANDS and "AS" not in DATASHEET_COMMANDS


@pytest.mark.skipif(
    not DATASHEET.exists(),
    reason=f"{DATASHEET} is absent: the manuals are kept in ../shared beside the repository, not"
    " in a clone of it",
)
def test_the_copied_list_is_the_datasheets() -> None:
    text = DATASHEET.read_text(encoding="utf-8")
    found = re.findall(r"^#+ +\*\*([A-Z]{2})(?:#(?:,#)*;?)?\s+[A-Z\"]", text, re.M)
    assert set(found) == set(DATASHEET_COMMANDS)


def test_personality_has_the_datasheet_commands() -> None:
    """ "The following commands are available in the PC46": the table is exactly the list, and
    the -21/-41 table is it without the contouring group."""
    assert set(PC46_COMMANDS) == set(DATASHEET_COMMANDS)
    assert set(PC46_COMMANDS_NO_CONTOUR) == set(DATASHEET_COMMANDS) - set(CONTOUR_ONLY)


@pytest.mark.parametrize("model", sorted(PC46))
def test_every_datasheet_command_is_known(model: str) -> None:
    """Each listed command, sent bare in single-axis, AA and contour-definition mode, is
    recognised (it may be invalid in that mode or lack its operand, but it is never an unknown
    command), except the contouring group on the -21 and -41."""
    unknown: list[str] = []
    for mnemonic in DATASHEET_COMMANDS:
        if model in NO_CONTOUR and mnemonic in CONTOUR_ONLY:
            continue
        for prefix in ("AX ", "AA ", "AA CD0,0; " if model not in NO_CONTOUR else "AM "):
            h = Harness(model)
            h.send(f"{prefix}{mnemonic} ;")
            h.advance(0.01)
            kinds = [e.kind for e in h.errors()]
            if ErrorKind.UNKNOWN_COMMAND in kinds:
                unknown.append(f"{prefix}{mnemonic}")
    assert unknown == []
