"""Servo and encoder commands where a review against the manuals (PCIx
002_5f0bea9264c6d239.txt, PC48 000_438df88d2a6a1670.txt) found omsd wrong.

* Ending position hold ends its correction: HF (every board) and the PC48's LP, entered while the
  hold is moving the axis back toward the held position, left the correction running to its end
  (EA already said "Position maintenance disabled").
* Closing a servo's loop does not move its motor when backlash compensation holds the set point
  off the commanded position: HN took RP to RE and then added the offset again, so each
  ``HF;HN;`` walked the motor one backlash further (second review of the servo axes).
* Position hold goes on from where its correction left the encoder: after the hold had put a
  slipped stage back, the next move's goal was taken from the counter/encoder relation of before
  the slip, so the hold undid ``MR100`` (in part or whole), and an ``HF;HN;`` drove the stage
  to a place never commanded (same review).
* A switch reached on the very sample the servo loop was looked at (every 32nd sample) went
  unseen: a closed-loop servo ran through its limit switch or past home (same review).
* A servo's home loads its encoder with its position counter: with the commanded position alone
  loaded, the closed loop drove the motor back by the difference (same review).
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from .support import moving, quiet


def _correcting(model: str, hold: str) -> Harness:
    """An axis holding position (HV100, HG1, HD0: a correction at 100 counts a second) whose
    carriage has slipped 1000 counts and that has been correcting for one second."""
    h = quiet(model)
    h.send(hold)
    h.advance(0.1)
    h.board.inject_slip("X", 1000, h.t)
    h.advance(1.0)
    assert moving(h, "X")
    return h


@pytest.mark.parametrize(
    ("model", "hold", "command"),
    [
        ("PCIX-040", "AX;HV100;HG1;HD0;HN;", "HF;"),
        ("PC48-4E", "AX HV100 HG1 HD0 HN ", "HF "),
        ("VS4-040", "AX HV100 HG1 HD0 HN ", "HF "),
        ("PC48-4E", "AX HV100 HG1 HD0 HN ", "LP0 "),
    ],
)
def test_ending_the_hold_ends_its_correction(model: str, hold: str, command: str) -> None:
    """PCIx §5.7.1: "Once the axis has initially stopped, the axis will begin moving again to
    correct for any error encountered during the course of the full move. This process will
    continue until the encoder position is within the dead band"; HG: "This gain parameter is
    multiplied by the position error in determining the velocity during correction". HF "disables
    position hold" (PCIx and PC48 §6.15); the PC48's HN: "Hold and slip detection are disabled if
    an LP, HM, HR, SA, ST or KL command is entered". With the hold off nothing computes a
    correction velocity: the correction stops where it is (it started with no ramp, at HG × error,
    and ends the same way). Before, it ran on to the old goal, 9 more seconds here."""
    h = _correcting(model, hold)
    h.send(command)
    h.advance(0.01)
    assert not moving(h, "X")
    x = h.position("X")
    h.advance(1.0)
    assert h.position("X") == x
    assert h.errors() == []


def _rp_re(h: Harness) -> tuple[int, int]:
    rp, re = (int(x) for x in h.send("AX;RP;RE;\n").split(b"\n\r") if x)
    return rp, re


def test_closing_the_loop_under_backlash_leaves_the_motor_where_it_is() -> None:
    """PCIx §5.12.4, its example: "AX; BC-10; MA1000; GO; ... MA-1000; GO;" ... "the motor will
    go 2010 steps, ending at -1000, and the encoder will read -1010": "offsetting the motor's
    position "set point" from the commanded position will compensate for backlash". HN "closes
    the loop, enabling the PID" (§2.7.2: "Send LP0;HN; commands and check the shaft of the motor
    to make sure it is stiff"), and RP is "the motor's commanded position", RE "the motor's
    actual position". Closing the loop at rest commands the motor where it is, so the set point
    (commanded position plus the offset) is the encoder: RP -1000 and RE -1010 stay as they are.
    Before, HN made RP the encoder count and the offset was added on top: the motor moved 10
    counts (RP -1010, RE -1020), and each HF;HN moved it 10 more."""
    h = Harness("PCIX-400")
    h.send("AX;HN;BC-10;MA1000;GO;\n")
    h.advance(1.0)
    assert _rp_re(h) == (1000, 1000)
    h.send("AX;MA-1000;GO;\n")
    h.advance(1.0)
    assert _rp_re(h) == (-1000, -1010)
    for _ in range(3):
        h.send("AX;HF;\n")
        h.advance(0.2)
        assert _rp_re(h) == (-1000, -1010)
        h.send("AX;HN;\n")
        h.advance(0.5)
        assert _rp_re(h) == (-1000, -1010)
    assert h.send("AX;?PM;\n") == b"hn\n\r"
    # and the next move still goes where it is told, with the set point offset kept
    h.send("AX;MR-500;GO;\n")
    h.advance(1.0)
    assert _rp_re(h) == (-1500, -1510)
    assert h.errors() == []


@pytest.mark.parametrize(
    ("model", "sep", "ratio"),
    [("PCIX-040", ";", "ER1,1;"), ("PCIX-020", ";", "ER2,1;"), ("PC48-4E", " ", "")],
)
def test_after_a_hold_correction_the_next_move_counts_from_the_held_position(
    model: str, sep: str, ratio: str
) -> None:
    """PCIx HN: "A 200,000 step move is performed, then that position is maintained within the
    10 step dead band until commanded to a new position"; §5.7.1: "the axis will begin moving
    again to correct for any error encountered during the course of the full move. This process
    will continue until the encoder position is within the dead band of the motor's target
    position". A slip of the carriage is corrected back to the encoder's 1000 (the counter,
    "the motor's commanded position", steps back to make up for it); MR100 is then "a new
    position" 100 encoder counts on, 1100, and the hold keeps it there. Before, the goal of
    the next move came from the counter/encoder relation of before the slip: MR100 ran to the
    counter's 1000 and the hold drove it back to encoder 1000 (MR100 undone)."""
    h = quiet(model)
    h.send(f"AX;{ratio}HV1000;HG10;HD0;HN;MR1000;GO;".replace(";", sep))
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1000
    h.board.inject_slip("X", 50, h.t)  # 50 steps: 50 x the ratio in encoder counts
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1000 and not moving(h, "X")
    h.send("AX;MR100;GO;".replace(";", sep))
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1100 and not moving(h, "X")
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1100
    assert h.errors() == []


@pytest.mark.parametrize(
    ("model", "sep", "ratio"),
    [
        ("PCIX-040", ";", "ER1,1;"),
        ("PCIX-020", ";", "ER2,1;"),
        ("PC48-4E", " ", ""),
        ("VS4-040", " ", ""),
    ],
)
@pytest.mark.parametrize("slip", [50, -50])
def test_what_the_dead_band_leaves_is_not_carried_into_the_next_goal(
    model: str, sep: str, ratio: str, slip: int
) -> None:
    """§5.7.1: the correction goes on "until the encoder position is within the dead band of
    the motor's target position"; HN: "that position is maintained within the 10 step dead band
    until commanded to a new position". With HD10 a correction stops up to 10 counts short of
    the held 1000 (at 1010 after a slip of +50); MR100 is then "a new position", 1100, and the
    hold keeps it within 10 of 1100. Before, the end of each correction took the encoder where
    the correction stopped as the held position, so every slip, correction and MR100 carried
    the dead band's remainder into the next target: four of them held 1440, not 1400 (40
    outside the dead band of the position commanded)."""
    h = quiet(model)
    h.send(f"AX;{ratio}HV1000;HG10;HD10;HN;MR1000;GO;".replace(";", sep))
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1000
    for k in range(1, 5):
        h.board.inject_slip("X", slip, h.t)
        h.advance(2.0)
        assert abs(h.board.axes[0].encoder(h.t) - (900 + 100 * k)) <= 10
        h.send("AX;MR100;GO;".replace(";", sep))
        h.advance(2.0)
        assert abs(h.board.axes[0].encoder(h.t) - (1000 + 100 * k)) <= 10
        assert not moving(h, "X")
    assert h.errors() == []


def test_hn_again_after_hf_holds_the_last_commanded_position() -> None:
    """HF "disables position hold"; HN again "enables position correction after a move": the
    position held is the one last commanded (the move's, as at power-up, where HN puts back a
    slip made with the hold off). With a slip corrected earlier by the hold, HF, another slip of
    100 and HN, the encoder goes back to the commanded 1000; before, the old relation sent it to
    900, a place never commanded."""
    h = quiet("PCIX-040")
    h.send("AX;HV1000;HG10;HD0;HN;MR1000;GO;")
    h.advance(2.0)
    h.board.inject_slip("X", 100, h.t)
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1000
    h.send("AX;HF;")
    h.advance(0.1)
    h.board.inject_slip("X", 100, h.t)
    h.advance(0.1)
    assert h.board.axes[0].encoder(h.t) == 1100
    h.send("AX;HN;")
    h.advance(2.0)
    assert h.board.axes[0].encoder(h.t) == 1000 and not moving(h, "X")
    assert h.errors() == []


@pytest.mark.parametrize("limit", [1000.0, 1001.0, 1016.0])
def test_a_closed_loop_servo_stops_at_its_limit_whatever_the_sample(limit: float) -> None:
    """HN: "For servo axes, this mode is disabled when ... a limit is encountered"; LN: the
    limit switch closure "will stop the associated pulse stream" (and §5.5: a limit flushes the
    queue). `AX;HN;AC2000;JG1000;` reaches the switch at 1000 on sample 2560 (1.25 s), one of
    the samples at which the board also looks at the servo loop (1/64 s apart): the jog stops
    there, QA shows the limit and the loop is open. Before, the look at the loop took that
    sample and the switch's edge was never looked for again: the jog ran on through the switch
    (RP 2750 at 3 s, QA ``PNLN`` while moving, ``?PM`` ``hn``); at 1001 or 1016 it stopped."""
    h = Harness(
        "PCIX-400", world={"X": AxisWorld(positive_limit=limit, home_low=5e6, home_high=5e6 + 100)}
    )
    h.send("AX;HN;AC2000;JG1000;\n")
    h.advance(3.0)
    rp, _ = _rp_re(h)
    assert limit <= rp <= limit + 1
    assert h.send("AX;QA;?PM;\n") == b"PNLN\n\rhf\n\r"
    assert h.send("AX;RV;\n") == b"0\n\r"


def test_a_closed_loop_servo_finds_home_whatever_the_sample() -> None:
    """HM "will cause the current axis or specified axes to move in the positive direction at
    the predefined velocity until the home is detected": with AC2000 the home switch (1000) is
    reached on a sample at which the servo loop is also looked at. Before, the search ran past
    it and on (RP 2750 at 3 s and still going)."""
    h = Harness("PCIX-400")
    h.send("AX;HN;AC2000;VL1000;HM500;\n")
    h.advance(3.0)
    rp, _ = _rp_re(h)
    assert rp == 750  # loaded 500 at the switch's edge, then 1000**2 / (2 * 2000) to stop
    assert h.send("AX;RV;\n") == b"0\n\r"


@pytest.mark.parametrize("loop", ["HN;", "HF;"])
def test_a_servo_home_loads_the_encoder_and_ramps_to_a_stop(loop: str) -> None:
    """HR: "When the home input is detected, the position and encoder counters are loaded with
    the parameter(s) supplied in the HR command. Then the axis is ramped to a stop. It behaves
    exactly like the HM command"; HM: "This will result in the axis stopping beyond the home
    switch ... The axis can be easily returned to the precise home position by using an MA
    command after the HM command". Loading is not moving: the servo's encoder takes the
    parameter with its commanded position, so the closed loop goes on ramping forwards, the
    motor never turns back, RE reads RP, and MA500 returns to the switch. Before, only the
    commanded position was loaded on a servo: the closed loop drove the motor straight back by
    the difference (RE 1001, then 807, 629 ... 500 within 5 ms) while the switches stayed where
    the counter said; with the loop open RE stayed 0."""
    h = Harness("PCIX-400")
    h.send(f"AX;{loop}AC2000;VL1000;HM500;\n")
    res = []
    for k in range(1, 3000):
        h.until(k * 0.001)
        res.append(_rp_re(h))
    rp, re = res[-1]
    assert rp == 500 + 250  # found at the switch's edge, 1000**2 / (2 * 2000) counts to stop
    if loop == "HN;":
        assert re == rp
        # the motor follows its commanded position throughout: it never turns back
        assert max(abs(rp - re) for rp, re in res) <= 2
    else:
        assert re == 500  # loaded at home; the undriven motor stayed there
    assert h.send("AX;QA;\n") == b"PNNN\n\r"  # beyond the home switch
    h.send("AX;HN;MA500;GO;\n")
    h.advance(2.0)
    assert _rp_re(h) == (500, 500)
    assert h.send("AX;QA;\n")[3:4] == b"H"
    assert h.errors() == []
