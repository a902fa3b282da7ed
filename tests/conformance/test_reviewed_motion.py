"""Motion and its flags where a review against the manuals (2026-11-27) found omsd wrong.

* A stop ramps down to the base velocity and stops from there: VB "jumps instantly to the
  specified velocity, then ramps as usual. The deceleration is the same in reverse. This mode is
  active only for linear ramps" (PC48 §6.7); ST decelerates "at the rate previously specified in
  an AC command" (§6.9). EPICS sends the motor record's base speed as VB and stops with ST.
* An AA ID whose group lost an axis to a flush sets no done flag in the status register: it
  "will not be set until all axes have executed the ID command" (§6.12), and the flushed axis
  never does. It used to come at once, with an empty done register (``!\\x00`` through the
  driver).
* The PCIx homes several axes at once in AA/AM (``HM#,#,#,#;``: "Parameters must be specified
  in multi-axis modes to inform the PCIx which axes are to be homed"), sets HD/HG/HV for several
  axes (their ``#,#,#,#`` forms), loads the encoder of a stepper with an encoder when it homes
  (HR: "the position and encoder counters are loaded with the parameter(s)"), and RF disables
  the software travel limits (its list: "Software over travel limits are disabled ( TL0,0; )").
* The default world's encoder index is inside its home window, so that an encoder home (HE)
  finds home as a switch home (HS) does.
"""

from __future__ import annotations

import pytest

from omsd.board.events import DoneEvent, ErrorKind
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import DON_S

from .support import frame


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r"))


def test_a_stop_ramps_down_to_the_base_velocity_and_stops_from_there() -> None:
    h = Harness("PC48-4E")
    h.send("AX VB500 VL1000 AC5000 MR5000 GO ")
    h.until(1.0)  # at 1000 steps/s since 0.1 s: the ramp 1000 -> 500 takes 0.1 s, 75 steps
    start = number(h.send("RP"))
    h.send("ST ID ")
    h.until(1.05)
    assert number(h.send("RV")) == 750
    h.until(1.2)
    assert number(h.send("RV")) == 0
    assert number(h.send("RP")) - start == 75  # (without VB: 100 steps, 0.2 s)
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1 and 1.1 <= done[0].time <= 1.1 + 2 / 2048


@pytest.mark.parametrize("ramp", ["PN", "CN"])
def test_the_base_velocity_is_ignored_on_other_ramps_and_by_jogs(ramp: str) -> None:
    """ "It is ignored for cosine and parabolic ramps"; "not valid with the JG command"."""
    h = Harness("PC48-4E")
    h.send(f"{ramp} AX VB500 VL1000 AC5000 MR5000 GO ")
    h.until(1.0)
    h.send("ST ")
    h.until(1.15)
    assert number(h.send("RV")) > 0  # still ramping to rest at AC: 0.2 s from 1000
    j = Harness("PC48-4E")
    j.send("AX VB500 AC5000 JG1000 ")
    j.until(1.0)
    j.send("ST ")
    j.until(1.15)
    assert number(j.send("RV")) == 250


def test_an_aa_id_that_lost_an_axis_to_a_flush_sets_no_done_flag() -> None:
    h = Harness("PC48-4E")
    h.send("AA VL1000,1000,1000,1000; AC10000,10000,1000,10000; MR5000,5000,5000; GO ID ")
    h.until(1.0)  # T alone has reached the ID (it has no move); X, Y, Z are moving
    board = h.board
    board.read_status_register(h.t)
    board.read_done_register(h.t)
    h.events()
    h.send("SA ")  # flushes every queue: X, Y and Z never execute the ID
    h.until(5.0)
    assert not [e for e in h.events() if isinstance(e, DoneEvent)]
    assert board.read_status_register(h.t) & DON_S == 0
    h.send("AA MR10,10,10,10; GO ID ")  # a group that completes still does
    h.until(6.0)
    assert board.read_status_register(h.t) & DON_S
    assert board.read_done_register(h.t) == 0x0F


def test_the_pcix_homes_several_axes_at_once_in_aa_mode() -> None:
    h = Harness("PCIX-040")
    h.send("AA;VL1000,1000,1000,1000;HM5,,7;")
    h.until(20.0)
    assert h.send("AA;RP;") == b"5,0,7,0\n\r"
    h.send("AA;HM;")  # "Parameters must be specified in multi-axis modes"
    assert [e.kind for e in h.errors()] == [ErrorKind.MISSING_PARAMETER]


def test_the_pcix_sets_hold_parameters_of_several_axes_in_aa_mode() -> None:
    h = Harness("PCIX-040")
    h.send("AA;HD5,,7;HG3,4;HV100,,,200;")
    assert h.errors() == []
    replies = [h.send(f"A{a};?HD;?HG;?HV;") for a in "XYZT"]
    assert replies == [
        b"hd5\n\rhg3\n\rhv100\n\r",
        b"hd0\n\rhg4\n\rhv0\n\r",  # an empty field: "not to be changed for that axis"
        b"hd7\n\rhg1\n\rhv0\n\r",
        b"hd0\n\rhg1\n\rhv200\n\r",
    ]
    h.send("AA;HD;")  # no field, no axis given
    assert [e.kind for e in h.errors()] == [ErrorKind.MISSING_PARAMETER]
    s = Harness("PCIX-202")  # X, Y servo, Z, T open loop: HD is for steppers with encoders
    s.send("AA;HD5,5,5,5;")
    assert [e.kind for e in s.errors()] == [ErrorKind.WRONG_MOTOR]


def test_a_pcix_home_loads_the_encoder_of_a_stepper_with_an_encoder() -> None:
    h = Harness("PCIX-040")
    h.send("AX;VL1000;HM0;")
    h.until(5.0)
    assert h.send("RP;RE;") == b"0\n\r0\n\r"  # (RE was 1000, where the home switch is)
    h.send("MA3000;GO;")
    h.until(10.0)
    h.send("HR5;")
    h.until(20.0)
    assert h.send("RP;RE;") == b"5\n\r5\n\r"
    p = Harness("PC48-4E")  # the PC48's HM: "The position counter will be initialized"
    p.send("AX VL1000 HM0 ")
    p.until(5.0)
    assert p.send("RP RE") == frame("0") + frame("1000")


def test_rf_disables_the_pcix_software_travel_limits() -> None:
    h = Harness("PCIX-040")
    h.send("AX;TL1000,-1000;")
    h.until(0.1)
    assert h.send("?TL;") == b"tl1000,-1000\n\r"
    h.send("RF;")
    assert h.send("?TL;") == b"tl0,0;\n\r"


@pytest.mark.parametrize(
    ("model", "commands"), [("PC48-4E", "AX HE VL1000 HM0 "), ("PCIX-040", "AX;HE;VL1000;HM0;")]
)
def test_an_encoder_home_finds_home_in_the_default_world(model: str, commands: str) -> None:
    h = Harness(model)
    h.send(commands)
    h.until(5.0)
    assert h.axis("X").motion.name == "IDLE"
    assert h.axis("X").phys(h.t) == pytest.approx(1050, abs=1.5)  # the index, in the window


@pytest.mark.parametrize("model", ["PC48-4", "VS4-040"])
def test_rc_during_a_contour_is_its_lead_in_value_throughout(model: str) -> None:
    """RC: "While a contour is executing, the value computed to generate the appropriate lead in
    will be returned" (PC48 §6.13, VS4 RC): each axis's share of the lead-in acceleration, on
    the lines and the arc after the lead-in too (it was AC there, and the arc's centripetal
    share); at rest again, the acceleration at the beginning of a ramp."""
    h = Harness(model)
    h.send("AA AC100000,100000; VL10000,10000; MT-1000,-1000; GO ")
    h.until(1.0)
    h.send("AA CV1000 CD0,0; MT5000,5000; CR5000,7000,1.5707963; MT0,20000; CE CX ")
    for t in (1.5, 5.0, 10.5, 13.0):  # lead-in, line, line, arc
        h.until(t)
        assert h.send("AA RC").split(b",")[:2] == [b"\n\r250", b"250"], t
    h.until(40.0)
    assert h.send("AA RC").split(b",")[:2] == [b"\n\r100000", b"100000"]


def test_a_flush_keeps_the_done_of_the_rounds_every_axis_finished() -> None:
    """In a loop, the AA/AM ID of a round every axis executed before one of them was flushed
    (a limit on X in the second pass) still sets the done flag; the rounds it missed do not."""
    h = Harness("PC48-4E", world={"X": AxisWorld(positive_limit=2000)})
    h.send("AM VL1000,1000; AC10000,10000; LS2 MR100,3000 GO ID MR5000 GO LE ")
    h.until(20.0)
    assert [(e.time, e.done_register) for e in h.events() if isinstance(e, DoneEvent)] == [
        (pytest.approx(3.1, abs=1e-3), 3)
    ]


def stop_run(model: str, setup: str, rp: str, stop: str) -> int:
    """How far an axis runs from a stop at 1 s after ``setup`` (``rp``: its RP)."""
    h = Harness(model)
    h.send(setup)
    h.until(1.0)
    start = number(h.send(rp))
    h.send(stop)
    h.until(3.0)
    return number(h.send(rp)) - start


def test_a_stop_takes_the_base_velocity_of_the_move_it_stops() -> None:
    """The move's own: a CN sent for another axis after the move began does not take its VB
    away; the PCIx's GU move, which has none ("does not work with DC"), ramps to rest (1000
    steps/s at AC5000: 100 steps)."""
    assert stop_run("PC48-4E", "AY VB500 VL1000 AC5000 MR5000 GO AX CN ", "AY RP", "AY ST ") == 75
    setup = "AX;VB500;VL1000;AC5000;DC5000;MR5000;GU;"
    assert stop_run("PCIX-040", setup, "RP;", "ST;") == 100
