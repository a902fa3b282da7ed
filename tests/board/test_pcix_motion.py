"""PCIx motion commands (omsd/board/pcix_motion.py) through the board, on the manual clock.

Each test drives a PCIx model the way a host does (commands, the ``text<LF><CR>`` replies) and
looks at what the manual says must happen: positions and velocities over time, RA/QA flags, the
done-flag register, limit/slip/done events, command errors, what is left in the queues. The
examples of the PCIx manual's command pages are quoted by their number in the digest
(shared/reference/pcix.md §5): E1/E2/E24/E25 BC, E34 CG, E42/E43 DC, E48-E52 EG, E58 FL,
E62/E63 GN, E66 GS, E67 GU, E106 KS, E121 LO, E138 NV, E177 SI, E182 SO, E193-E195 TL,
E196/E197 TM, E199 TX.

Factory values used in the arithmetic: VL 200,000 and AC 2,000,000 ("Velocity is 200000",
"Acceleration is 2000000"), 2048 samples per second.
"""

from __future__ import annotations

import math

import pytest

from omsd.board.events import (
    CommandErrorEvent,
    DoneEvent,
    ErrorKind,
    Event,
    LimitEvent,
    SlipEvent,
)
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

RATE = 2048
VL = 200_000.0
AC = 2_000_000.0


def tick_after(t: float) -> float:
    """The first sample tick at or after ``t``."""
    return math.ceil(t * RATE - 1e-9) / RATE


def lines(reply: bytes) -> list[str]:
    """The payloads of ``text<LF><CR>`` replies."""
    assert reply.endswith(b"\n\r") or reply == b""
    return [x.decode("ascii") for x in reply.split(b"\n\r") if x]


def rp(h: Harness, letter: str = "X") -> int:
    return h.position(letter)


def rv(h: Harness, letter: str = "X") -> float:
    return h.axis(letter).velocity(h.t)


def only(events: list[Event], kind: type) -> list[Event]:
    return [e for e in events if isinstance(e, kind)]


def error_kinds(h: Harness) -> list[ErrorKind]:
    return [e.kind for e in h.errors()]


# -- EG, EGF, EG?, TX: electronic gearing ----------------------------------------------------------


def test_e48_eg_z_geared_half_of_x() -> None:
    """E48: "Gear the Z axis to the X axis such that the Z axis velocity is always one half that
    of X." AZ; EGX1,2;"""
    h = Harness("PCIX-004")
    assert h.send("AZ;EGX1,2;") == b""
    h.send("AX;VL10000;AC100000;MR20000;GO;")
    for t in (0.05, 0.1, 0.5, 1.0, 1.9, 2.05):
        h.until(t)
        assert rv(h, "Z") == pytest.approx(rv(h, "X") / 2, abs=1e-6)
        assert h.axis("Z").position(h.t) == pytest.approx(h.axis("X").position(h.t) / 2)
    h.run()
    assert (rp(h, "X"), rp(h, "Z")) == (20000, 10000)
    assert not h.axis("Z").moving
    assert h.errors() == []


def test_e49_eg_t_twice_y_opposite_direction() -> None:
    """E49: "the T axis velocity is always twice that of Y but in a direction that is opposite
    to Y." AT; EGY-2,1;"""
    h = Harness("PCIX-004")
    h.send("AT;EGY-2,1;AY;VL5000;MR3000;GO;")
    h.until(0.3)
    assert rv(h, "Y") == pytest.approx(5000)
    assert rv(h, "T") == pytest.approx(-10000)
    h.run()
    assert (rp(h, "Y"), rp(h, "T")) == (3000, -6000)
    assert rp(h, "X") == 0 and rp(h, "Z") == 0


def test_e50_e51_eg_query() -> None:
    """E50: geared Y answers ``=egx1,2``; E51: "Z axis is either not geared to another axis or
    it is the master axis" answers ``=egf``. Framing: text<LF><CR>."""
    h = Harness("PCIX-004")
    assert h.send("AY;EG?") == b"=egf\n\r"
    h.send("AY;EGX1,2;")
    assert h.send("AY;EG?") == b"=egx1,2\n\r"
    assert h.send("AX;EG?") == b"=egf\n\r"  # the master
    assert h.send("AZ;EG?") == b"=egf\n\r"
    h.send("AT;EGX;")
    assert h.send("AT;EG?") == b"=egx\n\r"


def test_eg_to_a_geared_axis_or_itself_is_an_error() -> None:
    """EG: "the current axis cannot be geared to itself or to an axis that has been geared to a
    master axis"."""
    h = Harness("PCIX-004")
    h.send("AY;EGX1,2;")
    h.errors()
    h.send("AZ;EGY;")  # Y is geared to X
    assert error_kinds(h) == [ErrorKind.GEARED]
    assert h.send("AZ;EG?") == b"=egf\n\r"
    h.send("AX;EGX;")
    assert error_kinds(h) == [ErrorKind.GEARED]


def test_eg_reaching_a_master_geared_meanwhile_is_an_error() -> None:
    """Y's EGX waits behind Y's move; X is geared to Z before Y gets to it: the engagement
    fails then (command error) and Y stays ungeared."""
    h = Harness("PCIX-004")
    h.send("AY;VL1000;MR500;GO;EGX;AX;EGZ;")
    assert h.errors() == []
    h.run()
    assert error_kinds(h) == [ErrorKind.GEARED]
    assert h.send("AY;EG?") == b"=egf\n\r"
    assert h.send("AX;EG?") == b"=egz\n\r"


def test_eg_to_an_axis_the_board_has_not_got() -> None:
    h = Harness("PCIX-002")  # X and Y only
    h.send("AY;EGT;")
    assert error_kinds(h) == [ErrorKind.NO_SUCH_AXIS]


def test_eg_ratio_times_master_vl_range() -> None:
    """EG: "(Gear Ratio *X the Master Axis' VL value) is at least 1 and less than the maximum
    controller step rate of 1,048,574 steps per second"."""
    h = Harness("PCIX-004")
    h.send("AX;VL1;AY;EGX1,2;")  # 0.5 step/s
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]
    h.send("AX;VL200000;AY;EGX6;")  # 1,200,000 steps/s
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]
    h.send("AY;EGX5;")  # 1,000,000
    assert h.errors() == []
    assert h.send("AY;EG?") == b"=egx5\n\r"
    h.send("AZ;EGX1,0;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]


def test_eg_is_not_valid_in_multi_axis_mode() -> None:
    h = Harness("PCIX-004")
    h.send("AA;EGX;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]


def test_eg_takes_two_queue_units_and_engages_in_queue_order() -> None:
    """EG: "EG#,#,#, AX – AT 2": queued; the Z axis finishes its own move first."""
    h = Harness("PCIX-004")
    z = h.axis("Z")
    h.send("AZ;VL1000;MR500;GO;")
    free = z.queue.free
    h.send("AZ;EGX;")
    assert z.queue.free == free - 2
    h.send("AX;VL1000;MR100000;GO;")
    h.until(0.2)
    assert rv(h, "Z") == pytest.approx(1000)  # its own move, not X's copy
    assert h.send("AZ;EG?") == b"=egf\n\r"
    h.until(0.7)  # Z has done its 500 counts (ramp 1 ms), EG has engaged
    assert h.send("AZ;EG?") == b"=egx\n\r"
    assert rv(h, "Z") == pytest.approx(rv(h, "X"))


def test_geared_axis_does_not_move_on_its_own_commands() -> None:
    """ "Once a gearing engagement command is issued the geared axis will only respond to
    immediate commands until the gearing is cancelled": a move queued for it starts nothing;
    immediate commands are answered; once ungeared it moves again."""
    h = Harness("PCIX-004")
    h.send("AZ;EGX;MR100;GO;JG5000;")
    h.run(limit=5.0)
    assert rp(h, "Z") == 0 and not h.axis("Z").moving
    h.send("AX;MR1000;GO;")
    h.run()
    assert (rp(h, "X"), rp(h, "Z")) == (1000, 1000)
    assert h.send("AZ;RP") == b"1000\n\r"
    h.send("AZ;EGF;MR100;GO;")
    h.run()
    assert rp(h, "Z") == 1100
    h.send("AX;MR1000;GO;")
    h.run()
    assert (rp(h, "X"), rp(h, "Z")) == (2000, 1100)


def test_aa_commands_run_with_a_geared_axis() -> None:
    """AA commands put entries in every axis queue, the geared one's too; they do not wait for
    it, and it keeps following its master."""
    h = Harness("PCIX-004")
    h.send("AT;EGX1,2;AA;MR1000,2000,3000;GO;WT10;MR1000;GO;")
    h.run()
    assert [rp(h, a) for a in "XYZT"] == [2000, 2000, 3000, 1000]


def test_e52_egf_the_copy_of_a_move_finishes() -> None:
    """E52 EGF "turns off electronic gearing for the current axis". A geared axis ungeared in
    the middle of the master's move finishes the motion it was given."""
    h = Harness("PCIX-004")
    h.send("AY;EGX1,2;AX;VL10000;MR10000;GO;")
    h.until(0.5)
    h.send("AY;EGF;")
    assert h.send("AY;EG?") == b"=egf\n\r"
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (10000, 5000)
    h.send("AX;MR10000;GO;")
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (20000, 5000)


def test_fractional_ratio_does_not_drift() -> None:
    """EGX1,2 on odd moves: the geared axis ends within half a count of half the master, every
    time."""
    h = Harness("PCIX-004")
    h.send("AZ;EGX1,2;AX;VL50000;")
    for _ in range(7):
        h.send("AX;MR1001;GO;")
        h.run()
        assert abs(rp(h, "Z") - rp(h, "X") / 2) <= 0.5
    assert (rp(h, "X"), rp(h, "Z")) == (7007, 3504)


def test_geared_axis_follows_jog_and_stop() -> None:
    """The master's motion "of any kind": a jog, then ST's ramp down."""
    h = Harness("PCIX-004")
    h.send("AT;EGX-1,4;AX;AC100000;JG8000;")
    h.until(0.04)
    assert rv(h, "T") == pytest.approx(-rv(h, "X") / 4)
    h.until(1.0)
    assert rv(h, "T") == pytest.approx(-2000)
    h.send("AX;ST;")
    h.until(1.04)
    assert rv(h, "T") == pytest.approx(-rv(h, "X") / 4)
    h.run()
    assert not h.axis("T").moving
    assert rp(h, "T") == round(-rp(h, "X") / 4)


@pytest.mark.parametrize(
    "cancel", ["AZ;FL;", "AZ;KS;", "AZ;SI;", "SA;", "KL;", "AA;KS,,1;", "AA;SI,,1;"]
)
def test_flushing_commands_cancel_gearing(cancel: str) -> None:
    """ "the following commands FL, KL, KS, SA, SD or SI flush the axis queue and will also
    cancel electronic gearing"."""
    h = Harness("PCIX-004")
    h.send("AZ;EGX;")
    h.send(cancel)
    h.run()
    assert h.send("AZ;EG?") == b"=egf\n\r"
    h.send("AX;MR1000;GO;")
    h.run()
    assert rp(h, "Z") == 0


def test_overtravel_on_the_geared_axis_cancels_gearing() -> None:
    """EG: "over-travel on the geared axis will cancel electronic gearing"."""
    h = Harness("PCIX-004", world={"Z": AxisWorld(positive_limit=300.0)})
    h.send("AZ;EGX;AX;VL2000;MR1000;GO;")
    h.run()
    limits = only(h.events(), LimitEvent)
    assert [(e.axis, e.direction) for e in limits] == [("Z", 1)]
    assert 300 <= rp(h, "Z") <= 302
    assert rp(h, "X") == 1000
    assert h.send("AZ;EG?") == b"=egf\n\r"


def test_a_master_geared_later_carries_its_geared_axis() -> None:
    """Z follows X; X is then geared to Y (Y is not geared, so it is allowed): Y's move drives
    X, and X drives Z."""
    h = Harness("PCIX-004")
    h.send("AZ;EGX1,2;AX;EGY2;AY;MR1000;GO;")
    h.run()
    assert (rp(h, "Y"), rp(h, "X"), rp(h, "Z")) == (1000, 2000, 1000)


def test_e199_tx_tracks_x() -> None:
    """E199: "Set the Z axis to track the X axis." AZ; TX; (ratio 1); a negative ratio "moves in
    the opposite direction of the X axis"."""
    h = Harness("PCIX-004")
    assert h.send("AZ;TX;") == b""
    h.send("AY;TX-0.5;")
    h.send("AX;MR4000;GO;")
    h.run()
    assert (rp(h, "X"), rp(h, "Y"), rp(h, "Z")) == (4000, -2000, 4000)
    assert h.send("AY;EG?") == b"=egx-0.5\n\r"
    assert h.errors() == []


def test_tx_is_invalid_for_the_x_axis() -> None:
    """TX: "The command is invalid for the X axis." ("AY – AT")"""
    h = Harness("PCIX-004")
    h.send("AX;TX;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]
    h.send("AY;TX0;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]


# -- BC: backlash compensation ---------------------------------------------------------------------


def test_e1_e24_e25_bc_and_query() -> None:
    """E1 "BC10;", E24 "BC12;", E25 ?BC "bc23"."""
    h = Harness("PCIX-004")
    assert h.send("AX;BC10;") == b""
    assert h.send("?BC") == b"bc10\n\r"
    h.send("BC12;AY;BC23;")
    assert h.send("AY;?BC") == b"bc23\n\r"
    assert h.send("AX;?BC") == b"bc12\n\r"


def test_bc_ranges_stepper_and_servo() -> None:
    """ "0 ≤ BACKLASH ≤ +50 STEPPERS", "-50 ≤ BACKLASH ≤ +50 SERVOS"."""
    h = Harness("PCIX-004")
    h.send("AX;BC-1;")
    h.send("BC51;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE] * 2
    h.send("BC50;")
    assert h.errors() == []
    s = Harness("PCIX-400")
    s.send("AX;BC-50;")
    assert s.send("?BC") == b"bc-50\n\r"
    s.send("BC-51;")
    assert error_kinds(s) == [ErrorKind.OUT_OF_RANGE]


def test_stepper_backlash_extra_steps_on_reversal() -> None:
    """§5.12.3: "additional motor steps ... are generated, whenever a move command causes the
    motor to reverse direction": the encoder (where the motor is) moves BC further, the position
    counter does not count them."""
    h = Harness("PCIX-040")
    h.send("AX;BC10;MR1000;GO;")
    h.run()
    assert h.send("RP;RE;") == b"1000\n\r1000\n\r"  # same direction as before: nothing
    h.send("MR-1000;GO;")
    h.run()
    assert h.send("RP;RE;") == b"0\n\r-10\n\r"
    h.send("MR-500;GO;")
    h.run()
    assert h.send("RP;RE;") == b"-500\n\r-510\n\r"
    h.send("MR500;GO;")
    h.run()
    assert h.send("RP;RE;") == b"0\n\r0\n\r"


def test_stepper_backlash_in_the_first_update_after_the_reversal() -> None:
    """ "The backlash compensation count is output to the motor during the first motor update
    cycle following a direction change": a jog reversing through zero."""
    h = Harness("PCIX-004")
    x = h.axis("X")
    h.send("AX;BC7;JG1000;")
    h.until(1.0)
    h.send("JG-1000;")  # starts on the tick at 1.0; through zero 0.5 ms later
    zero = 1.0 + 1000 / AC
    h.until(tick_after(zero) - 1e-6)
    assert x.velocity(h.t) < 0  # already reversed, no update yet
    assert x.phys(h.t) - x.position(h.t) == pytest.approx(0.0)
    h.until(tick_after(zero))
    assert x.phys(h.t) - x.position(h.t) == pytest.approx(-7.0)


def test_stepper_backlash_in_a_contour_arc() -> None:
    """ "This permits the compensation to be used with constant velocity contours": Y turns back
    at the top of a half circle (radius 1,000 at 1,000 counts/s: after π/2 s)."""
    h = Harness("PCIX-004")
    y = h.axis("Y")
    h.send("AX;LP1000;AY;BC5;AA;CV1000;CD1000,0;CR0,0,3.1415926;MT-1000,-100;CE;CX;")
    turn = math.pi / 2
    h.until(turn - 0.01)
    assert y.velocity(h.t) > 0
    assert y.phys(h.t) - y.position(h.t) == pytest.approx(0.0)
    h.until(tick_after(turn) + 1e-6)
    assert y.velocity(h.t) < 0
    assert y.phys(h.t) - y.position(h.t) == pytest.approx(-5.0)
    h.run()
    assert y.phys(h.t) - y.position(h.t) == pytest.approx(-5.0)


def test_backlash_is_not_slip() -> None:
    """The board sent the compensation steps itself: slip detection (IS) does not flag them."""
    h = Harness("PCIX-040")
    h.send("AX;BC20;ES1;IS;MR-100;GO;")
    h.run()
    assert only(h.events(), SlipEvent) == []
    assert h.send("RP;RE;") == b"-100\n\r-120\n\r"


def test_bc0_switches_compensation_off() -> None:
    h = Harness("PCIX-040")
    h.send("AX;BC10;BC0;MR-100;GO;")
    h.run()
    assert h.send("RP;RE;") == b"-100\n\r-100\n\r"


def test_e2_servo_backlash_offsets_the_set_point() -> None:
    """E2: "homed in the positive direction", BC-10; MA1000; GO: "RP ... 1000. The RE command
    would report the motor's actual position of 1000"; then MA-1000; GO: "the motor will go 2010
    steps, ending at -1000, and the encoder will read -1010"."""
    h = Harness("PCIX-400")
    h.send("AX;HN;BC-10;MA1000;GO;")
    h.run()
    h.advance(0.5)
    assert h.send("RP;RE;") == b"1000\n\r1000\n\r"
    h.send("MA-1000;GO;")
    h.run()
    h.advance(0.5)
    assert h.send("RP;RE;") == b"-1000\n\r-1010\n\r"
    h.send("MA0;GO;")
    h.run()
    h.advance(0.5)
    assert h.send("RP;RE;") == b"0\n\r0\n\r"


# -- DC, GU ----------------------------------------------------------------------------------------


def test_e42_gu_accelerates_at_ac_decelerates_at_dc() -> None:
    """E42: "a 100,000 count move that accelerates at 100,000 counts per second per second up
    to 50,000 counts per second and decelerates at 20,000". Up 0.5 s (12,500 counts), down 2.5 s
    (62,500 counts), 25,000 at speed (0.5 s): 3.5 s."""
    h = Harness("PCIX-004")
    h.send("AY;AC100000;DC20000;VL50000;MR100000;GU;")
    h.until(0.25)
    assert rv(h, "Y") == pytest.approx(25000)
    h.until(0.75)
    assert rv(h, "Y") == pytest.approx(50000)
    h.until(2.25)
    assert rv(h, "Y") == pytest.approx(25000)
    assert h.axis("Y").acceleration(h.t) == pytest.approx(-20000)
    h.until(3.49)
    assert h.axis("Y").moving
    h.until(3.51)
    assert not h.axis("Y").moving
    assert rp(h, "Y") == 100000
    assert h.errors() == []


def test_e43_dc_query() -> None:
    """E43: ?DC "dc20000"; DC "defaults to 200,000 and will take on whatever value is entered via
    the AC command"."""
    h = Harness("PCIX-004")
    assert h.send("AX;?DC") == b"dc200000\n\r"
    h.send("DC20000;")
    assert h.send("?DC") == b"dc20000\n\r"
    h.send("AC300000;")
    assert h.send("?DC") == b"dc300000\n\r"


def test_e67_gu_short_move_is_triangular() -> None:
    """E67: "Move the Y axis to position 1,500 using the current acceleration and velocity and a
    deceleration of 5,000": too short to reach VL, the ramps meet at
    sqrt(2 d AC DC / (AC + DC))."""
    h = Harness("PCIX-004")
    h.send("AY;DC5000;MA1500;GU;")
    peak = math.sqrt(2 * 1500 * AC * 5000 / (AC + 5000))
    t_peak = peak / AC
    h.until(t_peak)
    assert rv(h, "Y") == pytest.approx(peak, rel=1e-6)
    h.until(t_peak + 0.1)
    assert rv(h, "Y") == pytest.approx(peak - 500, rel=1e-6)
    end = t_peak + peak / 5000
    h.until(end - 0.01)
    assert h.axis("Y").moving
    h.until(end + 0.01)
    assert rp(h, "Y") == 1500 and not h.axis("Y").moving


def test_gu_queue_units_and_validity() -> None:
    """GU "3*": +3 on an axis with an encoder; AA: Not Valid."""
    h = Harness("PCIX-040")
    x = h.axis("X")
    h.send("AX;MR100000;GO;")
    free = x.queue.free
    h.send("MR10;GU;")
    assert free - x.queue.free == 2 + 1 + 3 + 3  # MR 2+1, GU 3+3
    h.send("AA;GU;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]


# -- GN --------------------------------------------------------------------------------------------


def test_e62_gn_sets_the_done_flag_when_complete() -> None:
    """E62: AX; MA12345; GN; "set the axis done flags when the move is complete"."""
    h = Harness("PCIX-004")
    h.send("AX;MA12345;GN;")
    end = 2 * math.sqrt(12345 / AC)  # triangular: 10,000 counts to reach VL
    h.until(end - 0.005)
    assert h.send("QA") == b"PNNN\n\r"
    assert only(h.events(), DoneEvent) == []
    h.run()
    done = only(h.events(), DoneEvent)
    assert len(done) == 1 and done[0].done_register & 1
    assert done[0].time == pytest.approx(tick_after(end), abs=1 / RATE)
    assert h.send("RA") == b"PDNN\n\r"
    assert rp(h) == 12345


def test_e63_gn_aa_both_flags_one_done() -> None:
    """E63: AA; MR2468,-2468; GN;: both axes' flags, DON_S once all have finished."""
    h = Harness("PCIX-004")
    h.send("AA;MR2468,-2468;GN;")
    h.run()
    done = only(h.events(), DoneEvent)
    assert len(done) == 1
    assert done[0].done_register == 0b1111  # AA: every axis moved (two of them by 0)
    assert (rp(h, "X"), rp(h, "Y")) == (2468, -2468)
    assert h.send("AA;QI") == b"PDNN,MDNN,PDNN,PDNN\n\r"


def test_gn_am_only_the_moving_axes() -> None:
    h = Harness("PCIX-004")
    h.send("AM;MR,,1000;GN;")
    h.run()
    done = only(h.events(), DoneEvent)
    assert len(done) == 1 and done[0].done_register == 0b0100


# -- GS --------------------------------------------------------------------------------------------


def test_e66_gs_home_switch_sets_the_slip_flag() -> None:
    """E66: "If the motor slips it will close a switch wired to the home input of the X axis.
    Monitor this switch during the move and set the slip flag for axis X if the switch becomes
    active." AX; MR50000; GS;"""
    h = Harness("PCIX-004", world={"X": AxisWorld(home_low=20000.0, home_high=20100.0)})
    h.send("AX;VL10000;MR50000;GS;")
    h.run()
    slips = only(h.events(), SlipEvent)
    assert [e.axis for e in slips] == ["X"]
    # 25 counts in the 5 ms ramp, then 10,000/s to 20,000
    assert slips[0].time == pytest.approx(tick_after(0.005 + 19975 / 10000))
    assert h.axis("X").slipped
    assert rp(h) == 50000  # the move is not stopped


def test_gs_without_the_switch_and_go_do_not_flag() -> None:
    world = {"X": AxisWorld(home_low=20000.0, home_high=20100.0)}
    h = Harness("PCIX-004", world=world)
    h.send("AX;VL10000;MR10000;GS;")
    h.run()
    h.send("MR20000;GO;")  # GO crosses the switch: not watched
    h.run()
    assert only(h.events(), SlipEvent) == []
    assert not h.axis("X").slipped


def test_gs_is_not_valid_with_encoder_feedback() -> None:
    """GS: "this command is not valid in controls with encoder feedback which includes servo
    motors"."""
    h = Harness("PCIX-040")
    h.send("AX;MR100;GS;")
    assert error_kinds(h) == [ErrorKind.WRONG_MOTOR]


# -- SO --------------------------------------------------------------------------------------------


def test_e182_so_stop_by_ramping_from_distance() -> None:
    """E182: "The X axis is jogging at 10,000 steps per second. We want the axis to stop at
    position 50,000 but it must not start ramping until reaching position 46,000."
    SO50000,4000;: ramp down over the last 4,000 counts, 10,000²/(2·4,000) = 12,500 /s²."""
    h = Harness("PCIX-004")
    h.send("AX;JG10000;")
    h.until(0.1)
    h.send("SO50000,4000;")
    ramp = 10000 / AC  # 5 ms, 25 counts
    t_begin = ramp + (46000 - 25) / 10000
    h.until(t_begin - 0.01)
    assert rv(h) == pytest.approx(10000)
    h.until(t_begin + 0.4)
    assert rv(h) == pytest.approx(5000)
    assert h.axis("X").acceleration(h.t) == pytest.approx(-12500)
    h.until(t_begin + 0.79)
    assert h.axis("X").moving
    h.until(t_begin + 0.81)
    assert not h.axis("X").moving
    assert rp(h) == 50000


def test_so_inside_the_distance_ramps_at_once() -> None:
    h = Harness("PCIX-004")
    h.send("AX;JG10000;")
    h.until(4.8)  # at about 47,975
    h.send("SO50000,4000;")
    h.run()
    assert rp(h) == 50000


def test_so_past_the_stop_point_stops_at_ac() -> None:
    h = Harness("PCIX-004")
    h.send("AX;JG10000;")
    h.until(1.0)
    here = h.axis("X").position(h.t)
    h.send("SO5000,100;")
    h.run()
    assert rp(h) == pytest.approx(here + 10000**2 / (2 * AC), abs=2)


def test_so_is_single_axis_and_needs_both_parameters() -> None:
    h = Harness("PCIX-004")
    h.send("AX;SO5000;")
    assert error_kinds(h) == [ErrorKind.MISSING_PARAMETER]
    h.send("AA;SO5000,100;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]
    h.send("AX;SO40000000,0;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]


# -- TM --------------------------------------------------------------------------------------------


def test_e196_tm_timed_jog() -> None:
    """E196: AX; TM1000; "The overall jog time will be the parameter passed to the TM command
    plus deceleration time and acceleration time": 0.1 s up, 1 s at VL, 0.1 s down."""
    h = Harness("PCIX-004")
    h.send("AX;TM1000;")
    h.until(0.05)
    assert rv(h) == pytest.approx(100000)
    h.until(0.6)
    assert rv(h) == pytest.approx(VL)
    h.until(1.15)
    assert rv(h) == pytest.approx(100000)
    h.until(1.21)
    assert not h.axis("X").moving
    assert rp(h) == 220000


def test_e197_tm_aa_start_together_stop_on_their_own() -> None:
    """E197: AA; TM1000,,2000;: "Jog the X axis for 1000 milliseconds and the Z axis for 2000
    milliseconds, starting both at the same time"."""
    h = Harness("PCIX-004")
    h.send("AX;VL1000;AY;VL2000;AZ;VL3000;AA;TM1000,,2000;")
    h.until(0.5)
    assert (rv(h, "X"), rv(h, "Y"), rv(h, "Z")) == pytest.approx((1000, 0, 3000))
    h.until(1.5)
    assert not h.axis("X").moving and rv(h, "Z") == pytest.approx(3000)
    h.run()
    # 1 s (2 s) at VL and the ramps: VL²/AC counts more
    assert (rp(h, "X"), rp(h, "Y"), rp(h, "Z")) == (1000, 0, 6004)


def test_tm_runs_in_the_direction_set_by_mm() -> None:
    h = Harness("PCIX-004")
    h.send("AX;VL1000;MM;TM500;")
    h.run()
    assert rp(h) == -500


def test_tm_holds_the_queue_until_the_jog_ends() -> None:
    h = Harness("PCIX-004")
    h.send("AX;VL1000;TM500;MR-100;GO;")
    h.until(0.4)
    assert rv(h) == pytest.approx(1000)
    h.run()
    assert rp(h) == 400


def test_tm_range() -> None:
    """ "0 ≤ TM ≤ 200,000"."""
    h = Harness("PCIX-004")
    h.send("AX;TM200001;")
    h.send("TM-1;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE] * 2
    h.send("TM0;")
    h.run()
    assert h.errors() == []


# -- TL, ?TL ---------------------------------------------------------------------------------------


def test_e193_tl_jog_stops_at_the_soft_limit() -> None:
    """E193: TL1000000,-1000000; "If the axis reaches either of these logical limits, the PCIX
    will flag a limit condition just as it would be using the physical limit switch inputs"."""
    h = Harness("PCIX-004")
    h.send("AX;TL1000000,-1000000;JG100000;")
    h.until(20.0)
    limits = only(h.events(), LimitEvent)
    assert [(e.axis, e.direction) for e in limits] == [("X", 1)]
    assert limits[0].time == pytest.approx(10.025, abs=2 / RATE)
    assert not h.axis("X").moving
    assert 1_000_000 < rp(h) <= 1_000_100
    assert h.send("QA") == b"PNLN\n\r"


def test_tl_move_to_the_limit_is_allowed_beyond_is_overtravel() -> None:
    """The ?TL page: "If one of these limits is exceeded, the PC1x will set the current axis'
    limit flag". Moving to the limit itself is not overtravel; the queue of an axis that
    overtravels is flushed, as at a limit switch."""
    h = Harness("PCIX-004")  # (the home switch is at 1,000..1,100)
    h.send("AX;TL500,-500;MA500;GO;")
    h.run()
    assert rp(h) == 500 and only(h.events(), LimitEvent) == []
    assert h.send("QA") == b"PNNN\n\r"
    h.send("MA2000;GO;MA0;GO;")
    h.run()
    assert [e.direction for e in only(h.events(), LimitEvent)] == [1]
    assert 500 < rp(h) < 600  # stopped at once; MA0 GO was flushed
    assert h.axis("X").queue.free == 800
    h.send("MR-500;GO;")  # away from the limit
    h.run()
    assert only(h.events(), LimitEvent) == []
    assert h.send("QA") == b"MNNN\n\r"


def test_tl_negative_limit() -> None:
    h = Harness("PCIX-004")
    h.send("AX;TL1000,-1000;MR-5000;GO;")
    h.run()
    assert [e.direction for e in only(h.events(), LimitEvent)] == [-1]
    assert -1100 < rp(h) < -1000
    assert h.send("RA") == b"MNLN\n\r"


def test_tl_off_with_tl0_0() -> None:
    """ "TL0,0; Turns software limits off". (LF does not: the switches only,
    tests/conformance/test_reviewed_pcix_open.py.)"""
    h = Harness("PCIX-004")
    h.send("AX;TL1000,-1000;TL0,0;MR5000;GO;")
    h.run()
    assert rp(h) == 5000 and only(h.events(), LimitEvent) == []


def test_tl_soft_limit_mode_ramps_down() -> None:
    """SL: "ramp to a stop instead of abruptly halt" applies to the soft limits as to a switch."""
    h = Harness("PCIX-004")
    h.send("AX;SL;TL1000,-1000;VL10000;MR5000;GO;")
    h.run()
    assert [e.direction for e in only(h.events(), LimitEvent)] == [1]
    assert rp(h) == pytest.approx(1001 + 10000**2 / (2 * AC), abs=6)


def test_tl_does_not_stop_homing() -> None:
    """MA, MR, JF, JG are "subject to software travel limits"; a home search is not."""
    h = Harness("PCIX-004", world={"X": AxisWorld(home_low=3000.0, home_high=3100.0)})
    h.send("AX;TL1000,-1000;VL1000;HM;")
    h.run()
    assert only(h.events(), LimitEvent) == []
    assert h.axis("X").phys(h.t) > 3000  # found home beyond the upper limit
    assert 0 <= rp(h) <= 1  # loaded with 0 at home, then the ramp down


def test_e194_e195_tl_query() -> None:
    """E194 ``t!101000,-1000`` and E195 ``t!0,0;`` as printed: the prefix is ``tl`` (OCR), upper
    first; switched off, the reply is printed with a semicolon."""
    h = Harness("PCIX-004")
    h.send("AY;TL101000,-1000;")
    assert h.send("AY;?TL") == b"tl101000,-1000\n\r"
    assert h.send("AT;?TL") == b"tl0,0;\n\r"


def test_tl_errors() -> None:
    """ "Two parameters must be supplied"; the range is the position range; AA: Not Valid."""
    h = Harness("PCIX-004")
    h.send("AX;TL1000;")
    h.send("TL-5,5;")
    h.send("TL40000000,0;")
    h.send("AA;TL1000,-1000;")
    assert error_kinds(h) == [
        ErrorKind.MISSING_PARAMETER,
        ErrorKind.OUT_OF_RANGE,
        ErrorKind.OUT_OF_RANGE,
        ErrorKind.NOT_VALID_IN_MODE,
    ]
    assert h.send("AX;?TL") == b"tl0,0;\n\r"


def test_tl_takes_three_queue_units() -> None:
    h = Harness("PCIX-004")
    x = h.axis("X")
    h.send("AX;MR100000;GO;")
    free = x.queue.free
    h.send("TL1000000,-1000000;")
    assert free - x.queue.free == 3


# -- KS, SI, FL ------------------------------------------------------------------------------------


@pytest.mark.parametrize("form", ["AY;KS;", "AA;KS,1;"])
def test_e106_ks_kills_only_the_selected_axis(form: str) -> None:
    """E106: "The Y axis ... must be reset but the other axes must be allowed to continue
    operation." AY; KS; or AA; KS,1;: no ramp, only Y's queue flushed."""
    h = Harness("PCIX-004")
    h.send("AX;VL10000;MR5000;GO;MR1;GO;AY;VL10000;MR5000;GO;MR1;GO;")
    h.until(0.2)
    y_at = h.axis("Y").counter(h.t)
    h.send(form)
    assert rv(h, "Y") == 0.0
    assert rv(h, "X") == pytest.approx(10000)
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (5001, y_at)
    assert h.axis("Y").queue.free == 800


def test_ks_aa_without_parameters_kills_nothing() -> None:
    """KS: "null values in the argument list specify that motion on that axis is not to be
    killed"."""
    h = Harness("PCIX-004")
    h.send("AA;MR1000,1000;GO;KS;")
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (1000, 1000)


def test_e177_si_stops_y_and_t_only() -> None:
    """E177: "stop axes Y and T without affecting X and Z": AM; MR15000,30000,20000,40000; GO;
    ... SI,1,,1; (the SW1 of the example is the trigger; here SI is sent at 50 ms). The stopped
    axes ramp down at AC."""
    h = Harness("PCIX-004")
    h.send("AM;VL10000,10000,10000,10000;MR15000,30000,20000,40000;GO;")
    h.until(0.05)
    h.send("SI,1,,1;")
    h.until(tick_after(0.05) + 0.0025)  # the ramp down starts on the next tick
    assert rv(h, "Y") == pytest.approx(5000, abs=1)
    assert rv(h, "T") == pytest.approx(5000, abs=1)
    assert rv(h, "X") == pytest.approx(10000)
    h.run()
    assert rp(h, "X") == 15000 and rp(h, "Z") == 20000
    assert 400 < rp(h, "Y") < 600 and rp(h, "Y") == rp(h, "T")


def test_si_zero_parameter_does_not_stop() -> None:
    """SI: "Any non-zero value in a parameter will cause the corresponding axis to be stopped"."""
    h = Harness("PCIX-004")
    h.send("AA;VL1000,1000;MR1000,1000;GO;")
    h.until(0.3)
    h.send("SI0,5;")
    h.run()
    assert rp(h, "X") == 1000 and rp(h, "Y") < 400


def test_si_single_axis_is_st() -> None:
    """SI: "In a single axis mode, the SI command behaves identically to ST"."""
    h = Harness("PCIX-004")
    h.send("AX;JG1000;WT5000;MR5;GO;")
    h.until(0.5)
    h.send("SI;")
    h.run()
    assert rp(h) == pytest.approx(500, abs=2)
    assert h.axis("X").queue.free == 800


def test_e58_fl_flushes_the_queue_not_the_motion() -> None:
    """E58: "The currently executing motion must be allowed to complete": AX; FL;"""
    h = Harness("PCIX-004")
    h.send("AX;VL10000;MR10000;GO;MR5000;GO;")
    h.until(0.3)
    h.send("AX;FL;")
    assert h.axis("X").queue.free == 800
    assert rv(h) == pytest.approx(10000)
    h.run()
    assert rp(h) == 10000
    h.send("MR1;GO;")
    h.run()
    assert rp(h) == 10001


def test_fl_is_single_axis_only() -> None:
    h = Harness("PCIX-004")
    h.send("AA;FL;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]


# -- LO --------------------------------------------------------------------------------------------


def test_e121_lo_motor_position_apart_from_the_encoder() -> None:
    """E121: "Set the motor position to 50,000 and the encoder position to 100,000 on the T
    axis": AT; LP100000; LO50000;"""
    h = Harness("PCIX-040")
    h.send("AT;LP100000;LO50000;")
    assert h.send("AT;RP;RE;") == b"50000\n\r100000\n\r"
    h.send("ES1;IS;MR1000;GO;")
    h.run()
    assert h.send("AT;RP;RE;") == b"51000\n\r101000\n\r"
    assert only(h.events(), SlipEvent) == []


def test_lo_multi_axis_skips_missing_values() -> None:
    """LO: "any value missing in the argument list specifies that axis is not to be affected"."""
    h = Harness("PCIX-004")
    h.send("AA;LO100,,-300;")
    assert h.send("AA;RP") == b"100,0,-300,0\n\r"


def test_lo_range_and_queue_units() -> None:
    """LO: "Any valid position within the allowable position range"; "LO#; AX – AT 2"."""
    h = Harness("PCIX-004")
    x = h.axis("X")
    h.send("AX;LO40000000;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]
    h.send("MR100000;GO;")
    free = x.queue.free
    h.send("LO5;")
    assert free - x.queue.free == 2


# -- contours: NV, CG ------------------------------------------------------------------------------


def contour_lines(h: Harness, cv: int) -> None:
    """Three 50,000-count segments along X from 0 (the stage at 0: no lead-in), ramp down."""
    h.send(f"AA;CV{cv};CD0,0;MT50000,0;MT100000,0;MT150000,0;CE;")


def test_e138_nv_changes_the_next_segment_velocity() -> None:
    """E138: "The contour is executing at 25,000 counts per second. Change the velocity to
    30,000 counts per second upon execution of the next command in the contour queue."
    NV30000; (valid only in a contour definition: "NV#; AA/CD Immediate")."""
    h = Harness("PCIX-004")
    contour_lines(h, 25000)
    h.send("CX;")
    h.until(1.0)
    assert rv(h) == pytest.approx(25000)
    h.send("CD0,0;NV30000;")
    h.until(1.9)
    assert rv(h) == pytest.approx(25000)  # the segment being run keeps its velocity
    h.until(2.5)
    assert rv(h) == pytest.approx(30000)
    # 2 s for the first segment, 50,000/30,000 for each of the next two, then the ramp down
    end_of_path = 2.0 + 2 * 50000 / 30000
    h.until(end_of_path + 0.01)
    assert h.axis("X").acceleration(h.t) == pytest.approx(-AC)
    h.run()
    assert rp(h) == 150000 + round(30000**2 / (2 * AC))
    assert h.errors() == []


def test_nv_speeds_up_a_following_arc() -> None:
    """NV before an arc: the arc runs at the new speed (radius 1,000, a quarter turn), as does the
    line after it; the AN/AF-free path still ends where it was defined."""
    h = Harness("PCIX-004")
    h.send("AX;LP1000;AA;CV1000;CD1000,0;MT1000,1000;CR0,1000,1.5707963;MT-1000,2000;CE;CX;")
    h.until(0.5)
    h.send("CD0,0;NV2000;")
    h.until(1.3)  # on the arc
    speed = math.hypot(rv(h, "X"), rv(h, "Y"))
    assert speed == pytest.approx(2000)
    arc = (math.pi / 2 * 1000) / 2000
    h.until(1.0 + arc + 0.25)  # on the last line
    assert (rv(h, "X"), rv(h, "Y")) == pytest.approx((-2000, 0), abs=1e-6)
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (-1001, 2000)


def test_nv_moves_the_contour_outputs_with_the_path() -> None:
    """A BL placed between two segments happens where the path puts it, at the new speed."""
    h = Harness("PCIX-004")
    h.send("AA;CV1000;CD0,0;MT1000,0;MT2000,0;BL4;MT3000,0;CE;CX;")
    h.until(0.5)
    h.send("CD0,0;NV2000;")
    h.until(1.45)  # segment 2 runs from 1.0 to 1.5 at 2,000 counts/s
    assert not h.board.outputs_low >> 4 & 1
    h.until(1.55)
    assert h.board.outputs_low >> 4 & 1
    h.run()
    assert rp(h, "X") == 3001


def test_nv_without_a_running_contour_has_no_effect() -> None:
    """NV: "An NV command issued without a contour currently executing will have no effect.";
    outside a contour definition it is not valid."""
    h = Harness("PCIX-004")
    h.send("AA;CD0,0;NV30000;MT1000,0;CE;")
    assert h.errors() == []
    h.send("CX;")
    h.until(0.5)
    assert rv(h) == pytest.approx(1000)  # CV's power-up 1000
    h.send("AA;NV5000;")
    assert error_kinds(h) == [ErrorKind.NOT_VALID_IN_MODE]
    h.send("AA;CD0,0;NV0;")
    assert error_kinds(h) == [ErrorKind.OUT_OF_RANGE]


def test_e34_cg_holds_following_mt_until_the_contour_is_done() -> None:
    """E34/CG: "When CG is used to execute the contour, the following MT commands will be on hold
    until the contour execution is complete.\""""
    h = Harness("PCIX-004")
    h.send("AA;CV10000;CD0,0;MT10000,0;MT10000,10000;CE;")
    h.send("CG;MT0,0;GO;")
    h.until(0.5)
    assert h.axis("X").moving
    assert not any(op.code == "MT" for op in h.axis("X").queue.program)
    assert h.board.interpreter.pending  # the MT waits in the interpreter
    h.run()
    assert (rp(h, "X"), rp(h, "Y")) == (0, 0)
    assert h.errors() == []


def test_cx_does_not_hold_mt() -> None:
    h = Harness("PCIX-004")
    h.send("AA;CV10000;CD0,0;MT10000,0;CE;CX;MT0,0;GO;")
    assert any(op.code == "MT" for op in h.axis("X").queue.program)


def test_cg_needs_a_contour_and_multi_axis_mode() -> None:
    h = Harness("PCIX-004")
    h.send("AA;CG;")
    h.send("AX;CG;")
    assert error_kinds(h) == [ErrorKind.NO_CONTOUR, ErrorKind.NOT_VALID_IN_MODE]


def test_geared_axis_follows_a_contour() -> None:
    """The master's motion of any kind: Z geared to a contouring X."""
    h = Harness("PCIX-004")
    h.send("AZ;EGX1,2;")
    contour_lines(h, 20000)
    h.send("CX;")
    h.until(1.0)
    assert rv(h, "Z") == pytest.approx(10000)
    h.run()
    assert rp(h, "Z") == round(rp(h, "X") / 2)


def test_every_error_is_a_command_error_event() -> None:
    """Out-of-range values set the command-error flag (CMD_S): one event per bad command. TM:
    "RANGE: 0 <= TM <= 200,000"."""
    h = Harness("PCIX-004")
    h.send("AX;TM300000;")
    errors = h.errors()
    assert errors == [CommandErrorEvent(0.0, ErrorKind.OUT_OF_RANGE, "TM300000")]
