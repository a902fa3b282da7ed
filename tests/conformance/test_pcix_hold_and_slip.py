"""What ends the PCIx's position hold (HN) and slip detection (IS): its manual's own two lists,
not the PC48's one (the PC48, PC46 and VS4 keep theirs: ``tests/board/test_encoder.py``).

* HN (PCIx manual §5): "For stepper axes with encoders, this mode will be canceled (as though
  via an HF command) if an CG, CX, HM, HR, MV, SO, SP command is entered, if a limit is
  encountered or the maximum allowable position error is executed."
* IS: "Slip detection are disabled if a ER, ET, HF, HM, HR, JG, LP, or TM command is entered or
  if a limit is encountered."
* The PC48's HN and IS: "Hold and slip detection are disabled if an LP, HM, HR, SA, ST or KL
  command is entered or if a limit is encountered." omsd used to apply that list on the PCIx
  too (with SO and CG for the hold and JG and TM for slip detection): LP ended the hold, ST, SA
  and KL ended both, and CX, MV, SP, ER and ET ended nothing.

A command counts when it executes from the axis's queue, as on the PC48 (docs/decisions.md).
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness

#: a stepper with an encoder on every axis
MODEL = "PCIX-040"
HOLD_AND_SLIP = "HV1000;HG10;HD0;HN;ES1;IS;"


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r"))


def ea(h: Harness, letter: str = "X") -> str:
    """EA's first two characters: slip detection E/D, position maintenance E/D."""
    return h.query(f"A{letter};EA;").decode()[:2]


def holding(letter: str = "X") -> Harness:
    h = Harness(MODEL)
    h.send(f"A{letter};{HOLD_AND_SLIP}")
    h.run()
    assert ea(h, letter) == "EE"
    return h


@pytest.mark.parametrize("command", ["ST;", "SA;", "KL;"])
def test_a_pcix_stop_or_kill_leaves_hold_and_slip_detection_on(command: str) -> None:
    """Neither PCIx list names SA, ST or KL (the PC48's names all three)."""
    h = holding()
    h.send(command)
    h.run()
    assert ea(h) == "EE"
    assert h.errors() == []


def test_pcix_lp_ends_slip_detection_and_the_hold_holds_the_loaded_position() -> None:
    """IS: "Slip detection are disabled if a ... LP ... command is entered"; LP is not in HN's
    list, so the hold goes on, at the position the load gave."""
    h = holding()
    h.send("LP500;")
    h.run()
    assert ea(h) == "DE"
    h.board.inject_slip("X", -30, h.t)
    h.run()
    assert number(h.send("RE;")) == 500
    assert number(h.send("RP;")) == 530


@pytest.mark.parametrize(("letter", "command"), [("X", "ER1,1;"), ("Y", "ET;")])
def test_pcix_er_and_et_end_slip_detection_not_the_hold(letter: str, command: str) -> None:
    """IS: "Slip detection are disabled if a ER, ET ... command is entered"; neither is in HN's
    list (ET is for the Y to T axes: "ET; AY – AT")."""
    h = holding(letter)
    h.send(command)
    h.run()
    assert h.errors() == []
    assert ea(h, letter) == "DE"


@pytest.mark.parametrize("commands", ["MP;MV100,1000;SP200;", "SP100;", "SO100,10;"])
def test_pcix_mv_sp_and_so_end_the_hold_not_slip_detection(commands: str) -> None:
    """HN: "canceled ... if an ... MV, SO, SP command is entered" (SO too with the axis at rest,
    where it has nothing to stop); none is in IS's list."""
    h = holding()
    h.send(commands)
    h.run()
    assert h.errors() == []
    assert ea(h) == "ED"


@pytest.mark.parametrize("execute", ["CX;", "CG;"])
def test_a_pcix_contour_ends_the_hold_of_its_axes(execute: str) -> None:
    """HN: "canceled ... if an CG, CX ... command is entered", on the axes of the contour; slip
    detection goes on (neither is in IS's list)."""
    h = Harness(MODEL)
    for letter in "XZ":
        h.send(f"A{letter};{HOLD_AND_SLIP}")
    h.send(f"AA;CV10000;CD0,0;MT10000,0;CE;{execute}")
    h.run()
    assert h.errors() == []
    assert ea(h, "X") == "ED"
    assert ea(h, "Z") == "EE"  # not in the contour


def test_a_pcix_kill_of_a_holding_axis_holds_where_the_kill_left_it() -> None:
    """KL leaves the hold on (above): what it holds is where the kill stopped the axis, not where
    the move began."""
    h = Harness(MODEL)
    h.send(f"AX;VL1000;AC10000;{HOLD_AND_SLIP}MR5000;GO;")
    h.until(1.0)
    h.send("KL;")
    h.until(1.01)
    killed = number(h.send("RP;"))
    assert 900 < killed < 1000
    assert ea(h) == "EE"
    h.board.inject_slip("X", -30, h.t)  # (flagged: ES1)
    h.run()
    assert number(h.send("RE;")) == killed
    assert number(h.send("RP;")) == killed + 30


def test_a_pcix_slip_kill_holds_where_the_kill_left_the_axis() -> None:
    """TN: "the PCIx will kill motion on the axis that slipped as though a KL command had been
    issued to the axis": the hold stays on (KL leaves it on) and holds the killed position; it
    used to drive the axis back to where the move began."""
    h = Harness(MODEL)
    h.send("AX;VL1000;AC10000;HV1000;HG10;HD0;HN;ES5;IS;TN;MR5000;GO;")
    h.until(1.0)
    at = number(h.send("RP;"))
    h.board.inject_slip("X", 50, h.t)
    h.run()
    assert ea(h) == "DE"  # "If a slip occurs, slip detection must be re-enabled"
    assert abs(number(h.send("RE;")) - at) <= 2  # (the kill comes a sample or two later)
    assert number(h.send("RE;")) - number(h.send("RP;")) == 50


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040"])
@pytest.mark.parametrize(
    ("command", "ends"),
    [
        ("LP0 ", True),
        ("HM0 ", True),
        ("HR0 ", True),
        ("ST ", True),
        ("SA ", True),
        ("KL ", True),
        ("ER1,1 ", False),
        ("SP100 ", False),
        ("MV100,1000 ", False),
        ("JG100 ", False),
    ],
)
def test_the_pc48_and_vs4_keep_their_one_list(model: str, command: str, ends: bool) -> None:
    """PC48 and VS4 HN and IS: "Hold and slip detection are disabled if an LP, HM, HR, SA, ST or
    KL command is entered or if a limit is encountered." (unchanged)"""
    h = Harness(model)
    h.send("AX HV1000 HG10 HN ES1 IS ")
    h.run(limit=5.0)
    h.send(command)
    h.run(limit=5.0)
    assert h.query("AX EA")[3:5] == (b"DD" if ends else b"EE")


@pytest.mark.parametrize(("start", "command"), [(0, "KM;"), (3000, "KR;")])
def test_a_pcix_kill_home_leaves_hold_and_slip_detection_on(start: int, command: str) -> None:
    """KM and KR are in neither PCIx list, and the KM page ("kill motion immediately; i.e.
    without using a deceleration ramp. The position counter will not be reset or cleared") says
    nothing of hold or slip: as on the PC48 (tests/conformance/test_reviewed_pc48.py). What is
    held after one is where the pulses stopped, not where the axis was held before it (the
    home switch of the default world is around 1000: KM from 0, KR from 3000)."""
    h = Harness(MODEL)
    h.send(f"AX;VL1000;MA{start};GO;{HOLD_AND_SLIP}")
    h.run()
    assert ea(h) == "EE"
    h.send(command)
    h.advance(4.0)
    assert ea(h) == "EE"
    stopped = number(h.query("RP;"))
    assert stopped != start and abs(stopped - 1000) < 100  # it found home
    h.advance(3.0)
    assert number(h.query("RP;")) == stopped  # held there, not driven back
    assert h.errors() == []


def corrected_after_a_slip() -> Harness:
    """X holding at encoder 0 after a slip of 300 steps was corrected: the position counter
    300 ahead of the encoder (the correction's pulses)."""
    h = Harness(MODEL)
    h.send("AX;HV100;HG10;HD0;HN;")
    h.run()
    h.board.inject_slip("X", -300, h.t)
    h.advance(20.0)
    assert (number(h.query("RP;")), number(h.query("RE;"))) == (300, 0)
    return h


@pytest.mark.parametrize("command", ["KL;", "ST;", "SA;"])
def test_a_pcix_stop_of_a_holding_axis_at_rest_moves_nothing(command: str) -> None:
    """A stop leaves the PCIx's hold on (neither list names it), and an axis at rest has nothing
    to stop: what is held stays where it was (a kill used to move the goal by the correction
    the hold had made, and the hold drove the carriage 300 steps away)."""
    h = corrected_after_a_slip()
    h.send(command)
    h.advance(20.0)
    assert (number(h.query("RP;")), number(h.query("RE;"))) == (300, 0)
    assert h.errors() == []


@pytest.mark.parametrize("command", ["KL;", "ST;", "SA;"])
def test_a_pcix_stop_during_a_hold_correction_keeps_the_held_position(command: str) -> None:
    """A stop during the hold's own correction, the hold staying on: the hold goes on toward
    the same goal (it used to hold wherever the stop left the correction)."""
    h = Harness(MODEL)
    h.send("AX;HV100;HG10;HD0;HN;")
    h.run()
    h.board.inject_slip("X", -300, h.t)
    h.advance(0.5)
    assert number(h.query("RE;")) < 0  # the correction is under way
    h.send(command)
    h.advance(20.0)
    assert number(h.query("RE;")) == 0
    assert ea(h)[1] == "E"  # the hold is still on
    assert h.errors() == []
