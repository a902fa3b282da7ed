"""PC48 manual examples E56–E110 and the other worked examples X1–X5 (digest §5).

Every ``Enter:`` example of chapter 6 from §6.9 SD to §6.21 RQ, sent as printed (parenthetical
remarks such as "(wait awhile)" and the DOS driver's ``*`` comments removed), on a board put in
the state the example assumes. Where the manual prints a ``Response:`` it is asserted byte for
byte; otherwise the resulting state (positions, flags, done register, aux lines, GP outputs,
queue space, timing) is asserted. X6–X8 are DOS-driver and config.sys examples and belong to the
daemon's tests.

Timing notes used throughout: the PC48 samples 2048 times a second and a move starts on the
first sample tick at or after its GO; power-up VL is 100,000 and AC 1,000,000, so a linear ramp
to full speed takes 0.1 s and 5,000 counts.
"""

from __future__ import annotations

import math

from omsd.board.board import Board
from omsd.board.events import ErrorKind, LimitEvent, SlipEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import DON_S, ENC_S, OVRT
from omsd.link import DriverLink
from omsd.models import get_model

from .support import (
    at,
    done_events,
    frame,
    moving,
    path_times,
    physical,
    quiet,
    status_frame,
    velocity,
)

TICK = 1.0 / 2048.0

# -- §6.9 move termination ----------------------------------------------------------------------


def test_e56_sd_id_flags_done_when_all_axes_have_stopped() -> None:
    """E56 ``AA SD ID``: "Flag a done when all axes have stopped."

    State built: a 4-axis board in AA mode; an earlier ``ID`` left every done flag set (the
    "SA ID" pitfall the SD text describes), then all four axes start a long move at 100,000/s.
    SD at t=0.5 s must clear the done flags at once and decelerate every axis at AC; the ID that
    follows sets them again, and DON_S, only when all axes have stopped (0.1 s later)."""
    h = quiet("PC48-4")
    h.send("AA MR100,100,100,100; GO ID")
    h.run()
    assert h.board.registers.done == 0b1111
    h.board.read_status_register(h.t)  # the host serviced that interrupt
    h.events()
    t0 = h.t
    h.send("MR1000000,1000000,1000000,1000000; GO")
    at(h, t0 + 0.5)
    assert all(moving(h, a) for a in "XYZT")
    h.send("SD ID")
    assert h.board.registers.done == 0
    assert not any(h.axis(a).done for a in "XYZT")
    at(h, t0 + 0.59)
    assert h.board.status_register(h.t) & DON_S == 0
    assert all(moving(h, a) for a in "XYZT")
    assert done_events(h.events()) == []
    at(h, t0 + 0.61)
    assert not any(moving(h, a) for a in "XYZT")
    assert h.board.registers.done == 0b1111
    assert h.board.status_register(h.t) & DON_S
    events = done_events(h.events())
    assert len(events) == 1
    assert abs(events[0].time - (t0 + 0.6)) <= 2 * TICK
    # 5,000 up, 40,000 at speed, 5,000 down, from 100 each
    for a in "XYZT":
        assert abs(h.position(a) - 50_100) <= 50


def test_e57_kl_discards_partially_entered_move() -> None:
    """E57 ``AX MR5000 (oops!) KL MR-5000 GO`` ("(oops!)" is a remark, not sent): KL flushes the
    MR5000 that had no GO yet, so only the negative move runs."""
    h = Harness("PC48-4")
    assert h.send("AX MR5000 KL MR-5000 GO") == b""
    h.advance(0.05)
    assert h.position("X") < 0
    h.run()
    assert h.position("X") == -5000
    assert h.query("RQ") == frame("200")
    assert h.errors() == []


# -- §6.10 loop control ---------------------------------------------------------------------------


def test_e58_ls_repeats_z_move_five_times_and_reclaims_queue_after_loop() -> None:
    """E58 ``AZ LS5 MR100000 GO LE``: "The first move will occur immediately after entering the
    GO command. The remaining 4 moves will be executed after the loop terminator LE has been
    entered." Queue space of a loop "is not reclaimed until after the loop has been executed the
    programmed number of times" (LS 2 + MR 2 + GO 4 + LE 2 = 10 slots)."""
    h = Harness("PC48-4")
    assert h.send("AZ LS5 MR100000 GO") == b""
    h.advance(0.05)
    assert moving(h, "Z")
    at(h, 1.5)
    # first pass done (1.1 s), waiting for LE; its slots are still held
    assert h.position("Z") == 100_000
    assert not moving(h, "Z")
    assert h.query("RQ") == frame("192")
    at(h, 2.0)
    assert h.position("Z") == 100_000
    h.send("LE")
    at(h, 2.0 + 2.2 + 0.5)  # inside the 3rd of the remaining 4 moves
    assert moving(h, "Z")
    assert 300_000 < h.position("Z") < 400_000
    assert h.query("RQ") == frame("190")
    at(h, 2.0 + 4.4 - 0.05)
    assert moving(h, "Z")
    at(h, 2.0 + 4.4 + 0.01)
    assert not moving(h, "Z")
    assert h.position("Z") == 500_000
    assert h.query("RQ") == frame("200")
    h.run()
    assert h.position("Z") == 500_000
    assert [h.position(a) for a in "XYT"] == [0, 0, 0]


def test_e59_aa_loop_relative_and_absolute_moves_four_times() -> None:
    """E59 ``AA LS4 MR100000,,,100; GO MA100,,,200; GO LE`` on a 4-axis board: four passes of
    X +100,000 / T +100 then X to 100 / T to 200 (X and T start together at each GO)."""
    h = Harness("PC48-4")
    h.send("AA LS4 MR100000,,,100; GO MA100,,,200; GO LE")
    excursions = 0
    high = False
    t_peak: list[float] = []
    for k in range(1, 1200):
        at(h, k * 0.01)
        x = h.position("X")
        if x > 99_000 and not high:
            excursions += 1
            t_peak.append(h.t)
        high = x > 99_000
        if not any(moving(h, a) for a in "XT") and h.query("RQ") == frame("200,200,200,200"):
            break
    assert excursions == 4
    # each pass: 1.1 s out (100,000 counts) and ~1.1 s back (99,900 counts)
    assert 8.7 <= h.t <= 8.9
    assert h.position("X") == 100
    assert h.position("T") == 200
    assert h.position("Y") == 0
    assert h.position("Z") == 0


def test_e60_ws_loops_while_input_low_and_exits_at_bottom() -> None:
    """E60 ``AA WS1 MR10000; GO MR, -1000; GO WD``: loop while input 1 is true (low).

    Input 1 is held low by the "external device" and released (high) at t=0.62 s, during the
    X move of the 3rd pass (a pass is X 10,000 in 0.2 s plus Y -1,000 in 0.063 s). The test is at
    the bottom, so the 3rd pass completes and the loop ends: X = 30,000, Y = -3,000."""
    h = Harness("PC48-4")
    h.board.set_input(1, False, h.t)
    h.send("AA WS1 MR10000; GO MR, -1000; GO WD")
    at(h, 0.25)  # first pass: X done, Y moving
    assert h.position("X") == 10_000
    assert -1000 < h.position("Y") < 0
    at(h, 0.3)  # second pass under way
    assert 10_000 < h.position("X") < 20_000
    assert h.position("Y") == -1000
    at(h, 0.62)
    assert moving(h, "X")
    assert 20_000 < h.position("X") < 30_000
    h.board.set_input(1, None, h.t)
    h.run()
    assert h.position("X") == 30_000
    assert h.position("Y") == -3000
    assert h.query("RQ") == frame("200,200,200,200")
    assert h.errors() == []


def test_e60_ws_body_runs_once_when_input_already_high() -> None:
    """E60 with input 1 released from the start: "The test is at the bottom of the loop, i.e. it
    will always be executed at least once"."""
    h = Harness("PC48-4")
    h.send("AA WS1 MR10000; GO MR, -1000; GO WD")
    h.run()
    assert h.position("X") == 10_000
    assert h.position("Y") == -1000


E61_PROGRAM = """
AX UU10000
AY UU10000
AZ UU10000
AX VL.1; AC10;
AY VL.1; AC10;
AZ VL.1; AC10;
AX HR AY HR AZ HR
AA VL3,3,.5;
WH
      SW0
      MA3,3; GO
      MA,,.5; GO

      MA,,0; GO
      MA0,0; GO
WG
"""


def test_e61_wh_drilling_loop_until_cw() -> None:
    """E61, the drilling platform (``*`` comments are the DOS driver's and are not sent; "(CW)"
    is the operator sending CW later).

    World: X, Y and Z have home switches at -1000..-900 steps (HR finds the upper edge, loads 0
    and decelerates 5 counts past it at AC10 = 100,000 steps/s²). The normally closed "Ready to
    Drill" switch holds user input 0 low; pressing it opens it and the line goes high. User units
    are 10,000 steps per inch: VL.1 = 1,000, VL3 = 30,000 and VL.5 = 5,000 steps/s. Each pass
    takes ~4.7 s: X/Y to 3 in (1.3 s), Z down 0.5 in and up (2 × 1.05 s), X/Y home (1.3 s)."""
    home = AxisWorld(home_low=-1000.0, home_high=-900.0)
    h = Harness("PC48-4", world={"X": home, "Y": home, "Z": home})
    h.board.set_input(0, False, h.t)  # NC switch closed: line grounded
    h.send(E61_PROGRAM)
    assert h.errors() == []
    at(h, 2.0)
    for a in "XYZ":
        assert not moving(h, a)
        assert -6 <= h.position(a) <= -4  # counter 0 at home, then 5 counts of deceleration
        assert -1000 <= physical(h, a) < -900
    assert h.position("T") == 0

    def press(when: float) -> None:
        at(h, when)
        h.board.set_input(0, None, h.t)  # switch opened: line pulled high
        at(h, when + 0.1)
        h.board.set_input(0, False, h.t)

    press(2.0)
    at(h, 3.8)  # X/Y at the centre (3.3 s), Z drilling down
    assert (h.position("X"), h.position("Y")) == (30_000, 30_000)
    assert 0 < h.position("Z") < 5000
    at(h, 6.0)  # Z back up, X/Y on their way home
    assert h.position("Z") == 0
    assert 0 < h.position("X") < 30_000
    at(h, 7.0)
    assert [h.position(a) for a in "XYZ"] == [0, 0, 0]
    at(h, 9.0)  # waiting at SW0 for the next square
    assert not any(moving(h, a) for a in "XYZ")

    press(9.0)
    at(h, 10.5)
    assert (h.position("X"), h.position("Y")) == (30_000, 30_000)
    at(h, 14.0)
    assert [h.position(a) for a in "XYZ"] == [0, 0, 0]

    # the operator wants a break: CW, then the commands after the loop
    assert h.send("CW") == b""
    h.send("MA0,0,0; GO")
    at(h, 15.0)
    assert not any(moving(h, a) for a in "XYZ")  # still waiting for the switch
    press(15.0)  # "presses switch once more": the current pass is finished
    at(h, 16.5)
    assert (h.position("X"), h.position("Y")) == (30_000, 30_000)
    at(h, 20.5)
    assert [h.position(a) for a in "XYZ"] == [0, 0, 0]
    assert h.query("RQ") == frame("200,200,200,200")
    press(21.0)  # the loop is over: the switch does nothing any more
    at(h, 23.0)
    assert [h.position(a) for a in "XYZ"] == [0, 0, 0]
    assert h.errors() == []


# -- §6.11 home -----------------------------------------------------------------------------------


def test_e62_hm_finds_home_loads_counter_and_ma_returns_there() -> None:
    """E62 ``AX VL1000 HM1000 MA1000 GO``: X's home switch is at physical 5000..5100. HM runs
    positive at 1000 steps/s (5 s to the switch), loads 1000 into the counter there,
    decelerates, and MA1000 GO brings the stage back to the home position."""
    h = Harness("PC48-4", world={"X": AxisWorld(home_low=5000.0, home_high=5100.0)})
    h.send("AX VL1000 HM1000 MA1000 GO")
    at(h, 2.0)
    assert 1990 <= h.position("X") <= 2000  # counter not loaded yet
    assert velocity(h, "X") == 1000
    at(h, 4.9)
    assert moving(h, "X")
    at(h, 5.2)
    assert not moving(h, "X")
    assert h.position("X") == 1000
    assert abs(physical(h, "X") - 5000.0) <= 1.0
    assert h.query("QA") == status_frame("PNNH")
    assert h.errors() == []


def test_e63_fast_hh_pass_through_home_then_slow_hr_with_hl() -> None:
    """E63 ``AX VL100000 HH HM VL1000 HL HR``: a normally open home switch at physical
    50,000..50,200. With HH (active high) the home condition is "switch open", which becomes true
    again when the fast pass leaves the switch at 50,200: the counter is loaded with 0 there and
    the axis decelerates 5,000 counts beyond. HR at 1000 steps/s with HL then comes back and
    finds the switch closing at its upper edge, loading 0 again: the "refined" home."""
    h = Harness("PC48-4", world={"X": AxisWorld(home_low=50_000.0, home_high=50_200.0)})
    h.send("AX VL100000 HH HM VL1000 HL HR\r\n")
    at(h, 0.3)
    assert velocity(h, "X") == 100_000
    at(h, 0.7)  # through the switch at ~0.55 s, decelerating at ~0.6 s, stopped by 0.65 s
    assert not moving(h, "X") or velocity(h, "X") < 0
    assert abs(physical(h, "X") - 55_200.0) <= 100.0
    at(h, 3.0)
    assert velocity(h, "X") == -1000  # the slow reverse pass
    h.run()
    assert -1 <= h.position("X") <= 0
    assert 50_198.0 <= physical(h, "X") < 50_200.0
    assert 5.6 <= h.t <= 5.8
    assert h.query("QA") == status_frame("MNNH")


def test_e64_km_stops_at_home_without_ramp_or_counter_reset() -> None:
    """E64 ``AY KM``: Y runs positive at its default VL (100,000) to a home switch at
    3000..3100 and stops generating pulses at once. A deceleration at AC would carry it 5,000
    counts past the switch; stopping inside the 100-count window shows there is none. "The
    position counter is not cleared or reset": it still equals the travelled distance."""
    h = Harness("PC48-4", world={"Y": AxisWorld(home_low=3000.0, home_high=3100.0)})
    h.send("AY KM")
    h.run()
    assert not moving(h, "Y")
    assert 3000 <= h.position("Y") < 3100
    assert h.position("Y") == round(physical(h, "Y"))
    assert h.query("QA") == status_frame("PNNH")


def test_e65_kr_stops_at_home_in_reverse_without_counter_reset() -> None:
    """E65 ``AY KR``: like E64 in the negative direction, switch at -3100..-3000."""
    h = Harness("PC48-4", world={"Y": AxisWorld(home_low=-3100.0, home_high=-3000.0)})
    h.send("AY KR")
    h.run()
    assert not moving(h, "Y")
    assert -3100 <= h.position("Y") < -3000
    assert h.position("Y") == round(physical(h, "Y"))
    assert h.query("QA") == status_frame("MNNH")


# -- §6.12 move synchronization -------------------------------------------------------------------


def test_e66_id_sets_done_when_move_finishes() -> None:
    """E66 ``AX MA100000 GO ID``: the done flag (register bit 0, DON_S, RA/QA 'D') is set when
    the 1.1 s move is finished, not before."""
    h = quiet("PC48-4")
    h.send("AX MA100000 GO ID")
    at(h, 1.09)
    assert h.board.registers.done == 0
    assert h.board.status_register(h.t) & DON_S == 0
    assert done_events(h.events()) == []
    at(h, 1.11)
    assert h.position("X") == 100_000
    assert h.board.registers.done == 0b0001
    assert h.board.status_register(h.t) & DON_S
    events = done_events(h.events())
    assert len(events) == 1
    assert 1.1 <= events[0].time <= 1.1 + TICK
    assert h.query("QA") == status_frame("PDNN")


def test_e67_ii_interrupts_as_each_moved_axis_finishes() -> None:
    """E67 ``MR,1000,,10000; GO II`` in AA mode (the AA syntax implies it): Y (1,000 counts,
    0.063 s) and T (10,000 counts, 0.2 s) each interrupt when they finish: two interrupts.
    X and Z had no parameter and raise nothing."""
    h = quiet("PC48-4")
    h.send("AA")
    h.send("MR,1000,,10000; GO II")
    at(h, 0.1)
    assert h.board.read_status_register(h.t) & DON_S
    assert h.board.read_done_register(h.t) == 0b0010
    at(h, 0.3)
    assert h.board.read_status_register(h.t) & DON_S
    assert h.board.read_done_register(h.t) == 0b1000
    events = done_events(h.events())
    assert len(events) == 2
    assert abs(events[0].time - 0.0632) <= 2 * TICK
    assert abs(events[1].time - 0.2) <= 2 * TICK
    assert h.query("QI") == status_frame("PNNN,PDNN,PNNN,PDNN")


def test_e68_in_fires_at_x_completion_and_z_deceleration_start() -> None:
    """E68 ``AA IN0,,10000; MR100000,100000; GO MR,,50000; GO``.

    X and Y move 100,000 (done at 1.1 s); the second GO waits for them, so Z's 50,000 runs from
    1.1 s to 1.7 s and begins decelerating at 1.6 s, 5,000 counts before its end. "The test is
    only performed during deceleration. If the IN parameter is greater than the ramp down
    distance, the interrupt will be generated when the control starts decelerating": Z is
    within 10,000 of its end from 1.55 s, but the interrupt (X complete AND Z nearly done) comes
    at 1.6 s, with Z at 45,000. Y has no parameter and is ignored."""
    h = quiet("PC48-4")
    h.send("AA\r\n IN0,,10000;\r\n MR100000,100000; GO\r\n MR,,50000; GO\r\n")
    at(h, 1.09)
    assert h.board.registers.done == 0
    at(h, 1.12)
    assert h.board.registers.done == 0b0001  # X complete
    assert h.board.status_register(h.t) & DON_S == 0
    assert moving(h, "Z")
    at(h, 1.58)
    assert 40_000 < h.position("Z") < 45_000
    assert h.board.status_register(h.t) & DON_S == 0
    events = done_events(h.events())
    assert events == []
    at(h, 1.62)
    events = done_events(h.events())
    assert len(events) == 1
    assert abs(events[0].time - 1.6) <= 3 * TICK
    assert events[0].done_register == 0b0101
    assert moving(h, "Z")
    h.run()
    assert h.position("Z") == 50_000
    assert h.board.registers.done & 0b0010 == 0  # Y ignored


def test_e69_ip_waits_until_position_hold_brings_encoder_into_deadband() -> None:
    """E69 ``AX HV1000 HG100 HD10 HN MR1000 GO IP`` on a PC48-4E.

    The load slips +50 steps during the move (injected at 0.03 s), so when the pulses end
    (0.063 s) the encoder reads ~1050. The hold correction (at most HV = 1000 steps/s) brings it
    within the 10-count deadband; only then does IP set the done flag."""
    h = quiet("PC48-4E")
    h.send("AX HV1000 HG100 HD10 HN\r\n MR1000 GO IP")
    at(h, 0.03)
    h.board.inject_slip("X", 50, h.t)
    at(h, 0.07)
    assert h.board.registers.done == 0
    assert done_events(h.events()) == []
    at(h, 0.5)
    events = done_events(h.events())
    assert len(events) == 1
    assert events[0].time > 0.063 + 0.02  # 40 steps of correction at 1000 steps/s
    assert h.board.registers.done == 0b0001
    assert h.query("RE") in {frame(str(n)) for n in range(990, 1011)}
    assert 950 <= h.position("X") <= 960
    assert h.query("EA") == status_frame("DENPNN")


def test_e70_ic_clears_done_and_error_flags() -> None:
    """E70 ``AX MR5000 GO ID (done flag set) IC``: the flags set by ID are cleared by IC."""
    h = quiet("PC48-4")
    h.send("AX MR5000 GO ID")
    h.run()
    assert h.query("QA") == status_frame("PDNN")
    assert h.board.registers.done == 0b0001
    assert h.board.status_register(h.t) & DON_S
    assert h.send("IC") == b""
    assert h.query("QA") == status_frame("PNNN")
    assert h.board.registers.done == 0
    assert h.board.status_register(h.t) & DON_S == 0
    assert h.position("X") == 5000


def test_e71_ca_clears_only_the_z_done_flag() -> None:
    """E71 ``AA MR1000, 2000, 3000, 4000; GO ID`` then ``AZ CA`` (4-axis board)."""
    h = quiet("PC48-4")
    h.send("AA MR1000, 2000, 3000, 4000; GO ID\r\n")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [1000, 2000, 3000, 4000]
    assert h.query("QI") == status_frame("PDNN,PDNN,PDNN,PDNN")
    assert h.send("AZ CA") == b""
    assert h.query("QA") == status_frame("PNNN")
    assert h.board.registers.done == 0b1011
    h.send("AA")
    assert h.query("QI") == status_frame("PDNN,PDNN,PNNN,PDNN")


def test_e72_wa_holds_z_aux_until_xy_moves_finish() -> None:
    """E72, the laser: ``AA VL1000,1000,1000; AC10000,10000.10000;`` then
    ``LS10 MR1000,1000; GO WA AN,,1; MR,,500; GO AF,,1; MR,,-500 GO LE``.

    ``AC10000,10000.10000;`` is a typo (digest §8.3 item 28). The board reads what was sent: two
    fields, X = 10000 and Y = 10000.10000, truncated to 10000 (no user units); Z's AC keeps its
    power-up 1,000,000. Nothing below depends on Z's acceleration except that register check.

    Prior state: the laser (Z aux) is switched off before the example (``AA AF,,1;``), as it is
    on at power-up. Invariants sampled every 5 ms: the laser is never on while X or Y moves
    (that is what WA is for) or while Z moves negative, and it goes on 10 times."""
    h = quiet("PC48-4")
    h.send("AA AF,,1;")
    h.run()
    assert h.axis("Z").aux is False
    h.send("AA VL1000,1000,1000; AC10000,10000.10000;\r\n")
    h.send(" LS10 MR1000,1000; GO WA AN,,1; MR,,500; GO AF,,1;\r\n MR,,-500 GO LE")
    assert h.errors() == []
    accel = {a: h.board.snapshot(h.t)["axes"][a]["acceleration_setting"] for a in "XYZ"}
    assert accel == {"X": 10_000, "Y": 10_000, "Z": 1_000_000}
    at(h, 0.5)
    assert moving(h, "X")
    assert h.axis("Z").aux is False  # WA: AN,,1 waits for the X/Y move
    rising = 0
    was_on = False
    start = h.t
    k = 0
    while k < 5000:
        k += 1
        at(h, start + k * 0.005)
        on = h.axis("Z").aux
        if on:
            assert not moving(h, "X")
            assert not moving(h, "Y")
            assert velocity(h, "Z") >= 0
        if velocity(h, "Z") < 0:
            assert not on
        if on and not was_on:
            rising += 1
        was_on = on
        if h.t > 1.0 and not any(moving(h, a) for a in "XYZ") and h.axis("Z").queue.free == 200:
            break
    assert rising == 10
    assert 20.9 <= h.t <= 21.2  # 10 × (1.1 s X/Y + 2 × 0.5 s Z)
    assert [h.position(a) for a in "XYZ"] == [10_000, 10_000, 0]
    assert h.axis("Z").aux is False


def test_e73_wq_holds_rp_until_the_y_queue_is_empty() -> None:
    """E73 ``AY MR1000 GO WQ RP``: the RP reply comes when the 0.063 s move has finished and
    gives the final position."""
    h = Harness("PC48-4")
    assert h.send("AY MR1000 GO WQ RP") == b""
    assert at(h, 0.06) == b""
    assert at(h, 0.07) == frame("1000")
    assert at(h, 1.0) == b""


def test_e74_sw0_with_y_aux_on_does_not_hold_x() -> None:
    """E74 ``AY AN MR2000 GO AF`` / ``AX SW0 MR10000 GO`` with Y's aux wired to input 0.

    Contradiction (digest §8.3 item 23): the text says X waits "until the Y axis has finished
    its move and turned off its auxiliary output", but SW waits until the line "has been
    released (allowed to go high)", AN drives the aux high and AF low. The definitions of SW, AN
    and AF are taken over the example's prose (the master/slave example E75 agrees with them):
    during Y's move the line is high, so X does not wait and both move at once; after Y's AF
    the line is low. A later SW0 then does hold X until the line is released again."""
    h = Harness("PC48-4")
    h.board.wire_input_to_aux(0, "Y")
    h.send("AY AN MR2000 GO AF\r\n AX SW0 MR10000 GO")
    at(h, 0.05)
    assert moving(h, "Y")
    assert moving(h, "X")  # not held by SW0
    assert h.position("X") > 0
    at(h, 0.3)
    assert h.position("Y") == 2000
    assert h.position("X") == 10_000
    assert h.axis("Y").aux is False
    assert h.query("BX") == frame("000001")  # input 0 pulled low by Y's aux
    # with the line low, SW0 does wait
    h.send("AX SW0 MR10000 GO")
    at(h, 0.6)
    assert h.position("X") == 10_000
    assert not moving(h, "X")
    h.send("AY AN;")
    at(h, 1.0)
    assert h.position("X") == 20_000
    assert h.query("BX") == frame("000000")


def test_e75_master_pa0_releases_slaves_waiting_at_sw0() -> None:
    """E75: three 8-axis boards; the master's X aux is wired to input 0 of both slaves
    (simulated by copying the master's X aux level onto the slaves' input 0 whenever it may have
    changed). ``AX PA0;`` holds the master's X aux low until its move starts; the slaves wait at
    ``AA SW0;``; the master's ``AA MR100,...; GO`` raises the aux and all three boards start."""
    master = Harness("PC48-8")
    slaves = [Harness("PC48-8"), Harness("PC48-8")]
    boards = [master, *slaves]

    def wire() -> None:
        level = master.axis("X").aux
        for s in slaves:
            s.board.set_input(0, None if level else False, s.t)

    def until(t: float) -> None:
        while master.t < t - 1e-12:
            step = min(TICK, t - master.t)
            for b in boards:
                b.advance(step)
            wire()

    master.send("AX PA0;")
    wire()
    assert master.axis("X").aux is False
    until(0.1)
    slaves[0].send("AA SW0; MR200,200,200,200,200,200,200,200; GO")
    slaves[1].send("AA SW0; MR300,300,300,300,300,300,300,300; GO")
    until(1.0)
    for s in slaves:
        assert not any(moving(s, a) for a in "XYZTUVRS")
        assert all(s.position(a) == 0 for a in "XYZTUVRS")
    master.send("AA MR100,100,100,100,100,100,100,100; GO")
    wire()
    until(1.0 + 4 * TICK)
    for b in boards:
        assert all(moving(b, a) for a in "XYZTUVRS")
    until(1.5)
    assert all(master.position(a) == 100 for a in "XYZTUVRS")
    assert all(slaves[0].position(a) == 200 for a in "XYZTUVRS")
    assert all(slaves[1].position(a) == 300 for a in "XYZTUVRS")
    assert master.axis("X").aux is False  # complemented after the move
    assert all(b.errors() == [] for b in boards)


def test_e76_wt_jog_staircase_timing() -> None:
    """E76 ``AX JG5000 WT2000 JG10000 WT3000 JG0``: 5,000 steps/s for 2 s, then 10,000 for 3 s,
    then stop (JG0 read as a jog at velocity zero). About 5000·2 + 10000·3 + ramps ≈ 40,100."""
    h = Harness("PC48-4")
    h.send("AX JG5000 WT2000 JG10000 WT3000 JG0\r\n")
    at(h, 1.0)
    assert h.query("RV") == frame("5000")
    at(h, 1.99)
    assert h.query("RV") == frame("5000")
    at(h, 2.03)
    assert h.query("RV") == frame("10000")
    at(h, 4.99)
    assert h.query("RV") == frame("10000")
    at(h, 5.04)
    assert h.query("RV") == frame("0")
    assert not moving(h, "X")
    assert abs(h.position("X") - 40_100) <= 30


# -- §6.13 status requests ------------------------------------------------------------------------


def test_e77_wy_two_axis_board() -> None:
    """E77 ``WY`` → ``<LF><CR>PC48 ver 3.00-2<LF><CR>`` (a 2-axis PC48)."""
    h = Harness("PC48-2")
    assert h.send("WY") == b"\n\rPC48 ver 3.00-2\n\r"


def test_e78_rp_y_position() -> None:
    """E78 ``AY RP`` → ``<LF><CR>12345<LF><CR>`` once Y is at 12345."""
    h = Harness("PC48-4")
    h.send("AY MR12345 GO")
    h.run()
    h.send("AX")
    assert h.send("AY RP") == b"\n\r12345\n\r"


def test_e79_rq_t_queue_empty() -> None:
    """E79 ``AT RQ`` → ``<LF><CR>200<LF><CR>``."""
    h = Harness("PC48-4")
    assert h.send("AT RQ") == b"\n\r200\n\r"


def test_e80_bx_outputs_10_12_and_inputs_0_3_low() -> None:
    """E80 ``BX`` → ``<LF><CR>001409<LF><CR>``: outputs 10 and 12 turned on (low) earlier,
    inputs 0 and 3 grounded."""
    h = Harness("PC48-4")
    h.send("BL10 BL12\r\n")
    h.run()
    h.board.set_input(0, False, h.t)
    h.board.set_input(3, False, h.t)
    assert h.send("BX") == b"\n\r001409\n\r"


def test_e81_ra_y_in_positive_limit() -> None:
    """E81 ``AY RA`` → ``<LF><CR><CR>PNLN<LF><CR><CR>``: Y ran into its positive limit switch
    (at 5000 in the world) during ``MR10000``. RA also resets the limit flag (OVRT) since no
    other axis is in limit."""
    h = quiet("PC48-4", Y=AxisWorld(positive_limit=5000.0, home_low=9e6, home_high=9e6 + 100))
    h.send("AY MR10000 GO")
    h.run()
    assert 5000 <= h.position("Y") < 5100
    limits = [e for e in h.events() if isinstance(e, LimitEvent)]
    assert [(e.axis, e.direction) for e in limits] == [("Y", 1)]
    assert h.board.status_register(h.t) & OVRT
    h.send("AX")
    assert h.send("AY RA") == b"\n\r\rPNLN\n\r\r"
    assert h.board.status_register(h.t) & OVRT == 0


def test_e82_ri_four_axes_moved_negative_and_done() -> None:
    """E82 ``AA RI`` → ``<LF><CR><CR>MDNN,MDNN,MDNN,MDNN<LF><CR><CR>``: every axis of a 4-axis
    board moved negative and executed ID. RI then resets the done flags."""
    h = quiet("PC48-4")
    h.send("AA MR-1000,-1000,-1000,-1000; GO ID")
    h.run()
    assert h.send("AA RI") == b"\n\r\rMDNN,MDNN,MDNN,MDNN\n\r\r"
    assert h.send("QI") == status_frame("MNNN,MNNN,MNNN,MNNN")
    assert h.board.registers.done == 0


def test_e83_qa_x_positive_at_home() -> None:
    """E83 ``AX QA`` → ``<LF><CR><CR>PNNH<LF><CR><CR>``: X last moved positive onto its home
    switch (1000..1100 in the default world), no ID, no limit."""
    h = Harness("PC48-4")
    h.send("AX MR1050 GO")
    h.run()
    assert h.send("AX QA") == b"\n\r\rPNNH\n\r\r"
    assert h.send("QA") == b"\n\r\rPNNH\n\r\r"


def test_e84_qi_mixed_state_four_axes() -> None:
    """E84 ``AA QI`` → ``<LF><CR><CR>PNNN,MNNN,PDNN,MNLN<LF><CR><CR>``: X moved positive; Y
    moved negative; Z moved positive and executed ID; T ran into its negative limit (-500).
    QI does not affect the flags."""
    h = quiet("PC48-4", T=AxisWorld(negative_limit=-500.0, home_low=9e6, home_high=9e6 + 100))
    h.send("AX MR100 GO AY MR-100 GO AZ MR100 GO ID AT MR-1000 GO")
    h.run()
    expected = b"\n\r\rPNNN,MNNN,PDNN,MNLN\n\r\r"
    assert h.send("AA QI") == expected
    assert h.send("QI") == expected
    assert h.board.registers.done == 0b0100


def test_e85_rc_all_axes_two_million() -> None:
    """E85 ``AA RC`` → ``<LF><CR>2000000,2000000,2000000,2000000<LF><CR>``: the manual does
    not show how the accelerations became 2,000,000 (the default is 1,000,000); they are set
    with AC beforehand. Idle, linear ramp: RC reports the acceleration at the start of a ramp."""
    h = Harness("PC48-4")
    h.send("AA AC2000000,2000000,2000000,2000000;")
    h.run()
    assert h.send("AA RC") == b"\n\r2000000,2000000,2000000,2000000\n\r"


def test_e86_rv_y_jogging() -> None:
    """E86 ``AY JG 12345`` then ``RV`` → ``<LF><CR>12345<LF><CR>`` (RV sent once the jog has
    reached speed, 12 ms later; note the space in ``JG 12345``)."""
    h = Harness("PC48-4")
    assert h.send("AY JG 12345\r\n") == b""
    h.advance(0.1)
    assert h.send(" RV") == b"\n\r12345\n\r"
    assert h.errors() == []


def test_e87_ru_three_and_a_half_revolutions() -> None:
    """E87 ``AZ UU2000; LP0; MR3.5; GO`` (wait) ``RU`` → ``<LF><CR>3.50000<LF><CR>``."""
    h = Harness("PC48-4")
    h.send("AZ UU2000; LP0;\r\n MR3.5; GO\r\n")
    h.run()
    assert h.position("Z") == 7000
    assert h.send(" RU") == b"\n\r3.50000\n\r"


# -- §6.14 user units -----------------------------------------------------------------------------


def test_e88_uu_inches_on_x_y_z_also_in_aa_mode() -> None:
    """E88 ``AX UU10000 AY UU10000 AZ UU10000``: no reply; moves are then in inches on X, Y and
    Z, in AA mode too ("will remain effective in the AA or AM mode"); T is untouched."""
    h = Harness("PC48-4")
    assert h.send("AX UU10000 AY UU10000 AZ UU10000\r\n") == b""
    h.send("AA MR1,2,.5,3;")
    h.send("GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [10_000, 20_000, 5000, 3]


def test_e89_uf_turns_user_units_off() -> None:
    """E89 ``AX UF AY UF AZ UF`` after UU10000: moves are in steps again."""
    h = Harness("PC48-4")
    h.send("AX UU10000 AY UU10000 AZ UU10000\r\n")
    assert h.send("AX UF AY UF AZ UF") == b""
    h.send("AA MR5,5,5; GO")
    h.run()
    assert [h.position(a) for a in "XYZ"] == [5, 5, 5]
    h.send("AZ")
    assert h.query("RU") == frame("5.00000")


# -- §6.15 position maintenance -------------------------------------------------------------------


def test_e90_er_distances_in_encoder_counts() -> None:
    """E90 ``ER10000,25000`` (X, the power-up axis, of a PC48-4E): "All distance ... parameters
    are input in encoder counts"; "The correct number of motor counts are generated": MR10000
    gives 25,000 motor steps and 10,000 encoder counts."""
    h = quiet("PC48-4E")
    assert h.send("ER10000,25000\r\n") == b""
    h.send("MR10000 GO")
    h.run()
    assert h.position("X") == 25_000
    assert h.query("RE") == frame("10000")


def test_e91_hf_turns_position_hold_off() -> None:
    """E91 ``AX HF``: with hold on, X is moved 1000; after HF a 100-step slip stays
    uncorrected and EA reports slip detection and position maintenance disabled."""
    h = quiet("PC48-4E")
    h.send("AX HV1000 HG100 HD10 HN MR1000 GO")
    h.run()
    assert h.query("EA")[3:5] == b"DE"
    assert h.send("AX HF") == b""
    h.run()
    h.board.inject_slip("X", 100, h.t)
    h.advance(1.0)
    assert h.position("X") == 1000
    assert h.query("RE") == frame("1100")
    assert h.query("EA")[3:5] == b"DD"


def test_e92_hn_maintains_position_within_deadband_after_slips() -> None:
    """E92 ``AX VL100000 AC500000 HV50000 HD10 HG2000 HN MR200000 GO`` (PC48-4E): the 2.2 s
    move, then "that position is maintained within the 10 step deadband": slips of +500 and
    -300 steps injected afterwards are corrected back within 10 encoder counts."""
    h = quiet("PC48-4E")
    h.send("AX VL100000 AC500000\r\nHV50000 HD10 HG2000 HN\r\nMR200000 GO\r\n")
    at(h, 2.1)
    assert moving(h, "X")
    at(h, 2.3)
    assert h.position("X") == 200_000
    assert h.query("RE") == frame("200000")
    assert h.query("EA") == status_frame("DENPNN")
    at(h, 3.0)
    h.board.inject_slip("X", 500, h.t)
    at(h, 3.5)
    encoder = int(h.query("RE").strip())
    assert abs(encoder - 200_000) <= 10
    assert 199_490 <= h.position("X") <= 199_510
    assert h.query("EA") == status_frame("DENPNN")
    h.board.inject_slip("X", -300, h.t)
    at(h, 4.0)
    encoder = int(h.query("RE").strip())
    assert abs(encoder - 200_000) <= 10


def test_e93_ip_immediately_in_position_then_hold_keeps_it() -> None:
    """E93 (the IP example repeated in §6.15): without a slip the stage is within the deadband
    when the move ends, so IP sets done then (0.063 s); a later -30 step slip is corrected by
    the hold back into the deadband."""
    h = quiet("PC48-4E")
    h.send("AX HV1000 HG100 HD10 HN\r\n MR1000 GO IP")
    at(h, 0.06)
    assert h.board.registers.done == 0
    at(h, 0.07)
    assert h.board.registers.done == 0b0001
    events = done_events(h.events())
    assert len(events) == 1
    assert abs(events[0].time - 0.0632) <= 2 * TICK
    at(h, 0.5)
    h.board.inject_slip("X", -30, h.t)
    at(h, 1.0)
    encoder = int(h.query("RE").strip())
    assert abs(encoder - 1000) <= 10
    assert 1020 <= h.position("X") <= 1030


# -- §6.16 slip and stall -------------------------------------------------------------------------


def test_e94_es5_is_tolerates_five_steps_flags_six() -> None:
    """E94 ``ES5 IS`` (X, PC48-4E): "tolerate being up to 5 steps from the desired position":
    a 5-step slip raises nothing, one more step raises the slip (ENC_S, RL 'S', EA 'S'), and
    slip detection is then off until re-enabled."""
    h = quiet("PC48-4E")
    assert h.send("ES5 IS") == b""
    h.run()
    h.board.inject_slip("X", 5, h.t)
    h.advance(0.01)
    assert not [e for e in h.events() if isinstance(e, SlipEvent)]
    assert h.board.status_register(h.t) & ENC_S == 0
    h.board.inject_slip("X", 1, h.t)
    h.advance(0.01)
    slips = [e for e in h.events() if isinstance(e, SlipEvent)]
    assert [e.axis for e in slips] == ["X"]
    assert h.board.status_register(h.t) & ENC_S
    assert h.query("RL") == frame("SNNN")
    assert h.query("EA")[3:6] == b"DDS"


def test_e95_rl_z_slipped() -> None:
    """E95 ``RL`` → ``<LF><CR>NNSN<LF><CR>`` ("(The Z axis has slipped.)" is a remark): a
    4-axis encoder board, Z with ``ES5 IS`` stalls during a move."""
    h = quiet("PC48-4E")
    h.send("AZ ES5 IS MR10000 GO")
    at(h, 0.05)
    h.board.set_stall("Z", True, h.t)
    at(h, 0.1)
    assert [e.axis for e in h.events() if isinstance(e, SlipEvent)] == ["Z"]
    assert h.send("RL") == b"\n\rNNSN\n\r"


def test_e96_hf_disables_slip_detection() -> None:
    """E96 ``AX HF`` after ``ES5 IS``: a 100-step slip then raises nothing."""
    h = quiet("PC48-4E")
    h.send("AX ES5 IS")
    assert h.send("AX HF") == b""
    h.run()
    h.board.inject_slip("X", 100, h.t)
    h.advance(0.1)
    assert not [e for e in h.events() if isinstance(e, SlipEvent)]
    assert h.board.status_register(h.t) & ENC_S == 0
    assert h.query("RL") == frame("NNNN")


# -- §6.17 encoder tracking -----------------------------------------------------------------------


def test_e97_et_x_follows_its_encoder_input() -> None:
    """E97 ``AX ET``: the axis duplicates its encoder input (ER 1:1): an encoder input moved to
    5000 brings the position counter to 5000."""
    h = quiet("PC48-4E")
    assert h.send("AX ET") == b""
    h.run()
    h.board.set_encoder_input("X", 5000, h.t)
    h.run()
    assert h.position("X") == 5000
    assert h.query("RE") == frame("5000")


def test_e98_hf_ends_encoder_tracking() -> None:
    """E98 ``AX HF`` after ET: the encoder input no longer moves the axis."""
    h = quiet("PC48-4E")
    h.send("AX ET")
    h.run()
    h.board.set_encoder_input("X", 2000, h.t)
    h.run()
    assert h.position("X") == 2000
    assert h.send("AX HF") == b""
    h.run()
    h.board.set_encoder_input("X", 7000, h.t)
    h.advance(1.0)
    assert h.position("X") == 2000


# -- §6.18 encoder home ---------------------------------------------------------------------------

ENCODER_HOME = AxisWorld(
    home_low=1000.0, home_high=3000.0, encoder_counts_per_rev=4000, encoder_index=2000
)


def test_e99_he_homes_on_encoder_index_inside_home_enable() -> None:
    """E99 ``AY HE``: home = index AND quadrant AND the (low true) home enable. The enable is
    active over 1000..3000 and the index is at encoder count 2000: a following
    ``VL1000 HM0 MA0 GO`` homes at 2000, not where the enable switch closes (1000)."""
    h = Harness("PC48-4E", world={"Y": ENCODER_HOME})
    assert h.send("AY HE") == b""
    h.send("AY VL1000 HM0 MA0 GO")
    h.run()
    assert h.position("Y") == 0
    assert abs(physical(h, "Y") - 2000.0) <= 1.0


def test_e100_hs_homes_on_switch_only() -> None:
    """E100 ``AY HS`` after HE: the encoder signals are ignored again and the same homing
    sequence stops where the home switch closes (1000)."""
    h = Harness("PC48-4E", world={"Y": ENCODER_HOME})
    h.send("AY HE")
    assert h.send("AY HS") == b""
    h.send("AY VL1000 HM0 MA0 GO")
    h.run()
    assert h.position("Y") == 0
    assert abs(physical(h, "Y") - 1000.0) <= 1.0


# -- §6.19 encoder status -------------------------------------------------------------------------


def test_e101_ea_y_slip_and_hold_enabled_in_position() -> None:
    """E101 ``AY EA`` → ``<LF><CR><CR>EENPNN<LF><CR><CR>``: Y (PC48-4E) with slip detection
    (ES5 IS) and position maintenance (HN) enabled, no slip, within the deadband, not home."""
    h = quiet("PC48-4E")
    h.send("AY HV1000 HG100 HD10 HN ES5 IS")
    h.run()
    h.send("AX")
    assert h.send("AY EA") == b"\n\r\rEENPNN\n\r\r"


def test_e102_re_y_encoder_position() -> None:
    """E102 ``AY RE`` → ``<LF><CR>12345<LF><CR>``: Y's encoder at 12345 after a move there."""
    h = quiet("PC48-4E")
    h.send("AY MR12345 GO")
    h.run()
    h.send("AX")
    assert h.send("AY RE") == b"\n\r12345\n\r"


# -- §6.20 velocity staircase ---------------------------------------------------------------------


def test_e103_mm_sets_y_direction_minus() -> None:
    """E103 ``AY MM``: Y's direction becomes minus (QA char 4 'M'), and a staircase that follows
    runs in that direction."""
    h = quiet("PC48-4")
    assert h.send("AY MM") == b""
    assert h.query("QA") == status_frame("MNNN")
    assert h.errors() == []
    h.send("MV-1000,5000 SP-2000\r\n")
    h.run()
    assert h.position("Y") == -2000


def test_e104_mv_velocity_staircase_breakpoints() -> None:
    """E104 ``MP MV10000,30000 MV20000,50000 MV30000,10000 SP35000`` on X.

    The example says "Default acceleration (AC) of 200,000" while AC's own text gives a
    1,000,000 default (digest §8.3 item 21). Read as the acceleration the example's figure was
    drawn with, it is set first (``AC200000``). Then, from rest at 0:
    30,000/s reached at 0.15 s (2,250 counts), breakpoint 10,000 at 0.408 s; up to 50,000/s by
    0.508 s (14,000), breakpoint 20,000 at 0.628 s; down to 10,000/s by 0.828 s (26,000),
    breakpoint 30,000 at 1.228 s; cruise and a 0.05 s stop ending exactly at 35,000 (1.753 s)."""
    h = Harness("PC48-4")
    h.send("AX AC200000\r\n")
    assert h.send("MP\r\nMV10000,30000\r\nMV20000,50000\r\nMV30000,10000\r\nSP35000\r\n") == b""
    at(h, 0.3)
    assert h.query("RV") == frame("30000")
    at(h, 0.40)
    assert h.position("X") < 10_000
    assert h.query("RV") == frame("30000")
    at(h, 0.45)
    assert 30_000 < velocity(h, "X") < 50_000
    at(h, 0.55)
    assert h.query("RV") == frame("50000")
    at(h, 0.62)
    assert h.position("X") < 20_000
    assert h.query("RV") == frame("50000")
    at(h, 0.70)
    assert 10_000 < velocity(h, "X") < 50_000
    at(h, 1.0)
    assert h.query("RV") == frame("10000")
    at(h, 1.22)
    assert h.position("X") < 30_000
    at(h, 1.70)
    assert h.query("RV") == frame("10000")
    at(h, 1.745)
    assert 0 < velocity(h, "X") < 10_000
    at(h, 1.76)
    assert not moving(h, "X")
    assert h.position("X") == 35_000
    assert h.errors() == []


def test_e105_fp_flushes_queue_and_stops_at_25000() -> None:
    """E105 ``FP25000``: X is on a 100,000-step move at full speed (15,000 at t=0.2 s) with
    another move queued behind it. FP flushes the queue and stops exactly at 25,000
    (deceleration from 20,000 at 0.25 s, stopped at 0.35 s); the queued move never runs."""
    h = Harness("PC48-4")
    h.send("AX MR100000 GO MR5000 GO")
    at(h, 0.2)
    assert h.send("FP25000\r\n") == b""
    at(h, 0.24)
    assert h.query("RV") == frame("100000")
    at(h, 0.30)
    assert 0 < velocity(h, "X") < 100_000
    at(h, 0.36)
    assert not moving(h, "X")
    assert h.position("X") == 25_000
    h.run()
    assert h.position("X") == 25_000
    assert h.query("RQ") == frame("200")


def test_e105_fp_overshoots_when_too_close() -> None:
    """E105, the other half of FP's text: "The axis will overshoot if there is insufficient
    distance left to stop": FP17000 at 15,000 and 100,000/s (5,000 counts needed)."""
    h = Harness("PC48-4")
    h.send("AX MR100000 GO")
    at(h, 0.2)
    h.send("FP17000\r\n")
    h.run()
    assert 17_000 < h.position("X") <= 20_050  # FP acts on the next tick (≤ 49 counts)


# -- §6.21 contouring -----------------------------------------------------------------------------


def test_e106_bh_bl_bit10_at_contour_start_and_end() -> None:
    """E106 ``AA CV2000 CD0,0; BH10 CR0,10000,6.2831853; BL10 CE CK``.

    The example has both CE and CK (digest §8.3 item 25). CE ends the definition and returns to
    AA mode, where CK is not valid: the contour ends with CE and the CK is one command error.
    The example never runs the contour; ``CX`` is added, and bit 10 is driven low beforehand
    (``BL10``) so that BH10 at the start is visible. From (0,0) (the start point, so no
    lead-in) a full circle of radius 10,000 about (0,10,000) at 2,000/s takes 31.416 s: bit 10
    is high all along it and low after."""
    h = Harness("PC48-4")
    h.send("AA BL10;")
    h.run()
    assert h.board.outputs_low == 1 << 10
    h.events()
    h.send("AA CV2000\r\n CD0,0;\r\n BH10\r\n CR0,10000,6.2831853;\r\n BL10\r\n CE\r\n CK\r\n")
    # CE ended the definition (back to AA); CK: "AA,AM Not valid"
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, "CK")]
    assert h.board.outputs_low == 1 << 10  # nothing runs before CX
    h.send("CX")
    period = 2 * math.pi * 10_000 / 2000
    at(h, 0.01)
    assert h.board.outputs_low == 0
    at(h, period / 4)
    assert abs(h.position("X") - 10_000) <= 3
    assert abs(h.position("Y") - 10_000) <= 3
    at(h, period / 2)
    assert abs(h.position("X")) <= 3
    assert abs(h.position("Y") - 20_000) <= 3
    assert h.board.outputs_low == 0
    at(h, 3 * period / 4)
    assert abs(h.position("X") + 10_000) <= 3
    assert abs(h.position("Y") - 10_000) <= 3
    at(h, period - 0.01)
    assert h.board.outputs_low == 0
    at(h, period + 0.02)
    assert h.board.outputs_low == 1 << 10
    h.run()
    assert not moving(h, "X") and not moving(h, "Y")
    assert 0 <= h.position("X") <= 3  # CE: 2 counts of ramp-down along +X at AC 1,000,000
    assert abs(h.position("Y")) <= 1


E107_DEFINITION = "AA\r\n CV1000 CD0,0;\r\n AN,,0; CR0,5000,3.1415926;\r\n CR0,0,6.2831853;\r\n"
E107_TAIL = " AF,0; MT 10,000,-1000;\r\n"


def _run_hole(end: str, prior: str = "") -> tuple[Harness, float]:
    """E107/E108 up to CX; returns the harness and the CX start time."""
    h = quiet("PC48-4")
    h.send("AA AF,,1;" + prior)  # the torch (Z aux) is off before the example
    h.run()
    assert h.axis("Z").aux is False
    h.send(E107_DEFINITION + E107_TAIL + f" {end}\r\n MT-1000,0; GO CX")
    assert h.errors() == []
    t_cx = math.ceil(math.sqrt(1000 / 1e6) * 2 * 2048) / 2048  # MT-1000,0 takes 0.0632 s
    return h, h.t + t_cx


def test_e107_cd_cut_hole_with_torch_on_z_aux() -> None:
    """E107: cut a hole of radius 10,000 at CV1000 with circular interpolation.

    Readings: ``MT 10,000,-1000;`` (digest §8.3 item 24) is what the board receives: a comma
    separates axis fields, so it is MT to X=10, Y=000=0, and the third field falls beyond the
    two contour axes and is ignored (as surplus fields are). ``AF,0;`` addresses Y, not Z: the
    board does what was sent, so Y's aux goes low at the end of the circle and the torch (Z)
    stays on. The torch is off before the example.

    Timeline from CX (which starts when MT-1000,0 has positioned the stage): lead-in from
    (-1000,0) reaching 1000/s at (0,0) after 2 s; AN,,0 there; half circle (15.708 s) to
    (0,10000); full circle (62.832 s); AF,0; 10 s line to (10,0); CE."""
    h, t0 = _run_hole("CE")
    at(h, t0 + 1.9)
    assert -1000 < h.position("X") < 0
    assert h.axis("Z").aux is False
    at(h, t0 + 2.1)
    assert h.axis("Z").aux is True
    half = math.pi * 5000 / 1000
    at(h, t0 + 2 + half / 2)
    assert abs(h.position("X") - 5000) <= 3
    assert abs(h.position("Y") - 5000) <= 3
    at(h, t0 + 2 + half)
    assert abs(h.position("X")) <= 3
    assert abs(h.position("Y") - 10_000) <= 3
    full = 2 * math.pi * 10_000 / 1000
    at(h, t0 + 2 + half + full / 4)
    assert abs(h.position("X") + 10_000) <= 3
    assert abs(h.position("Y")) <= 3
    at(h, t0 + 2 + half + full - 0.1)
    assert h.axis("Y").aux is True
    at(h, t0 + 2 + half + full + 0.1)
    assert h.axis("Y").aux is False
    assert h.axis("Z").aux is True
    at(h, t0 + 2 + half + full + 5)
    assert abs(h.position("X") - 5) <= 2
    assert abs(h.position("Y") - 5000) <= 3
    at(h, t0 + 2 + half + full + 10.05)
    assert not moving(h, "X") and not moving(h, "Y")
    assert h.position("X") == 10
    assert abs(h.position("Y")) <= 1
    assert h.axis("Z").aux is True


def test_e108_ck_ends_contour_without_ramp() -> None:
    """E108: E107 ended with CK ("the pulses will stop abruptly"); same readings as E107. The
    stage moves at the full 1000/s along the last line until it is at (10,0) and stops there."""
    h, t0 = _run_hole("CK")
    end = t0 + 2 + math.pi * 5000 / 1000 + 2 * math.pi * 10_000 / 1000 + 10.0
    at(h, end - 0.01)
    assert abs(velocity(h, "Y") + 1000) <= 2
    at(h, end + 2 * TICK)
    assert not moving(h, "X") and not moving(h, "Y")
    assert h.position("X") == 10
    assert h.position("Y") == 0


def test_e107_e108_ce_ramps_down_at_ac_ck_does_not() -> None:
    """E107 vs E108 with the contour axes' AC lowered to 1000 beforehand: CE ramps down along
    the last segment (about 1000²/(2·1000) = 500 counts past (10,0) in -Y; "This distance is
    adjustable using the AC command"), CK stops on the point ("It can almost be eliminated using
    the CK command")."""
    ce, _ = _run_hole("CE", prior=" AC1000,1000;")
    ce.run()
    ck, _ = _run_hole("CK", prior=" AC1000,1000;")
    ck.run()
    assert -600 < ce.position("Y") < -400
    assert abs(ck.position("Y")) <= 1
    assert abs(ck.position("X") - 10) <= 1


HEXAGON = [(10_000, 0), (20_000, 0), (25_000, 10_000), (20_000, 20_000), (10_000, 20_000)]
HEXAGON += [(5000, 10_000), (10_000, 0)]


def test_e109_mt_hexagon_with_bit9() -> None:
    """E109, the hexagon at CV5000 from (10000,0), with ``MT20000,2 0000`` read as the intended
    ``MT20000,20000`` (the hexagon's vertex; the literal text is tested below). The stage starts
    at (0,0): the lead-in reaches 5000/s at (10000,0) after 4 s. Bit 9 goes low at (20000,20000)
    and high again at (5000,10000); CK stops at (10000,0)."""
    h = Harness("PC48-4")
    text = "AA CV5000;\r\nCD10000,0;\r\nMT20000,0\r\nMT25000,10000\r\nMT20000,20000\r\nBL9\r\n"
    text += "MT10000,20000\r\nMT5000,10000\r\nBH9\r\nMT10000,0\r\nCK\r\nCX\r\n"
    h.send(text)
    assert h.errors() == []
    times = path_times(HEXAGON, 4.0, 5000.0)
    at(h, 2.0)
    assert 0 < h.position("X") < 10_000
    bit9_low = []
    for (x, y), t in zip(HEXAGON, times, strict=True):
        at(h, t - 0.01)
        bit9_low.append(bool(h.board.outputs_low & (1 << 9)))
        at(h, t)
        assert abs(h.position("X") - x) <= 3, (x, y, t)
        assert abs(h.position("Y") - y) <= 3, (x, y, t)
        at(h, t + 0.01)
        bit9_low.append(bool(h.board.outputs_low & (1 << 9)))
    # just before and just after each vertex: low from (20000,20000) to (5000,10000)
    assert bit9_low == [False] * 7 + [True] * 4 + [False] * 3
    assert not moving(h, "X") and not moving(h, "Y")
    assert (h.position("X"), h.position("Y")) == (10_000, 0)


def test_e109_mt_hexagon_verbatim_stray_space() -> None:
    """E109 exactly as printed, ``MT20000,2 0000`` (digest §8.3 item 26): the operand ends at the
    space, so the board goes to (20000,2), and ``0000`` is one bad word (one command error); the
    rest of the contour is unaffected and still ends at (10000,0)."""
    h = Harness("PC48-4")
    text = "AA CV5000;\r\nCD10000,0;\r\nMT20000,0\r\nMT25000,10000\r\nMT20000,2 0000\r\nBL9\r\n"
    text += "MT10000,20000\r\nMT5000,10000\r\nBH9\r\nMT10000,0\r\nCK\r\nCX\r\n"
    h.send(text)
    # "0" cannot start a command: one error for the bad word "0000"
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.BAD_CHARACTER, "0")]
    path = [(10_000, 0), (20_000, 0), (25_000, 10_000), (20_000, 2), (10_000, 20_000)]
    path += [(5000, 10_000), (10_000, 0)]
    times = path_times(path, 4.0, 5000.0)
    at(h, times[3])
    assert abs(h.position("X") - 20_000) <= 3
    assert abs(h.position("Y") - 2) <= 3
    at(h, times[3] + 0.01)
    assert h.board.outputs_low & (1 << 9)
    at(h, times[6] + 2 * TICK)
    assert not moving(h, "X") and not moving(h, "Y")
    assert (h.position("X"), h.position("Y")) == (10_000, 0)
    assert h.board.outputs_low & (1 << 9) == 0


def test_e110_rq_contour_queue_after_cd() -> None:
    """E110 ``AA CD0,0; RQ`` → ``<LF><CR>1016<LF><CR>``."""
    h = Harness("PC48-4")
    assert h.send("AA CD0,0; RQ") == b"\n\r1016\n\r"


# -- other worked examples ------------------------------------------------------------------------


def test_x1_typical_move_string() -> None:
    """X1 (§1.1) ``VL400000 AC500000 MR1000000 GO`` at power-up: no reply; 0.8 s ramps of
    160,000 counts, 1.7 s at 400,000/s, done at 3.3 s at 1,000,000."""
    h = Harness("PC48-4")
    assert h.send("VL400000 AC500000 MR1000000 GO") == b""
    at(h, 0.4)
    assert abs(h.position("X") - 40_000) <= 250
    at(h, 1.0)
    assert h.query("RV") == frame("400000")
    at(h, 3.29)
    assert moving(h, "X")
    at(h, 3.3 + 2 * TICK)
    assert not moving(h, "X")
    assert h.position("X") == 1_000_000


def test_x2_en_wy_echo_then_model() -> None:
    """X2 (§2.3 step 14, §7.1) ``EN WY`` on a 4-axis board: "EN turns echoing on which causes
    the typed commands to be echoed from the controller to the display. WY asks the PC48 board
    "who are you". The board responds with its model type and firmware version number (i.e.
    PC48 ver 3.00-4)." EN is read while echo is still off; what is read after it (the space, W,
    Y) is echoed as it is read, and the answer comes "surrounded by line feeds and carriage
    returns" (§7.3.2), so it starts on a line of its own: exactly these bytes."""
    h = Harness("PC48-4")
    assert h.send("EN WY") == b" WY\n\rPC48 ver 3.00-4\n\r"


def test_x2_en_wy_through_the_driver() -> None:
    """X2 through the DOS driver, which "strips off the LF and CR's" and ends each string with
    its end character (LF): the echo is one string and the answer another, so the two never run
    together (docs/decisions.md, "Echo (EN)")."""
    link = DriverLink(Board(get_model("PC48-4"), 0.0))
    link.from_host(b"EN WY", 0.0)
    assert link.to_host(0.0).data == b" WY\nPC48 ver 3.00-4\n"


def test_x3_rm_of_minus_4050_by_2000_gives_1950() -> None:
    """X3 (§6.7 RM): "An RM2000 command with a position counter of -4050 will return a position
    of 1950"."""
    h = Harness("PC48-4")
    h.send("AX MR-4050 GO")
    h.run()
    assert h.query("RP") == frame("-4050")
    h.send("RM2000\r\n")
    h.run()
    assert h.query("RP") == b"\n\r1950\n\r"


def test_x4_rq_67_free_slots_zero_padded() -> None:
    """X4 (§6.13 RQ): "if the current free queue space is 67, the response ... is
    <LF><CR>067<LF><CR>". X is held at ``SW0`` (input 0 low; SW takes no slot) while 22 × MR1 GO
    (2 + 4 slots) and an ID (1) fill 133 slots."""
    h = Harness("PC48-4")
    h.board.set_input(0, False, h.t)
    h.send("AX SW0 " + "MR1 GO " * 22 + "ID")
    assert h.query("RQ") == b"\n\r067\n\r"
    h.board.set_input(0, None, h.t)
    h.run()
    assert h.position("X") == 22
    assert h.query("RQ") == frame("200")


def test_x5_rp_at_power_up() -> None:
    """X5 (§7.3.2): "The response to an RP command when talking straight to the board is
    <LF><CR>0<LF><CR>"."""
    h = Harness("PC48-4")
    assert h.send("RP") == b"\n\r0\n\r"
