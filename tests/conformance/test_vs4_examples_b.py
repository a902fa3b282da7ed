"""VS4 manual examples E53–E105 and the addenda X1–X3 (``shared/reference/vs4.md`` §4).

Every ``Enter:`` example of the VS4 manual from §6.10 LS to §6.21 BH, sent as printed
(parenthetical remarks such as "(Wait until move is complete.)" or "(Board 2)" and the ``*``
comments of the WH example removed), on a board put in the state the example assumes. Where the
manual prints a ``Response:`` it is asserted byte for byte; otherwise the resulting state
(positions, flags, done register, aux lines, GP outputs, queue space, timing) is asserted.

Timing notes used throughout: the VS4 calculates its velocity "1024 times each second", so a
move starts on the first sample tick (k/1024 s) at or after its GO; power-up VL is 200,000 and
AC 2,000,000, so a linear ramp to full speed takes 0.1 s and 10,000 counts, a 100,000-count move
takes 0.6 s and a move of d < 20,000 counts takes 2·sqrt(d / 2,000,000) s. Both VS4 models have
an encoder on every axis (appendix C), so a single-axis GO takes 7 queue slots; the queues hold
800 slots ("RQ" prints ``800`` when empty) and the contour queue 7160.
"""

from __future__ import annotations

import math

from omsd.board.board import Board
from omsd.board.events import ErrorKind, LimitEvent, SlipEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import DON_S, ENC_S, INIT, OVRT
from omsd.models import get_model, variant

from . import support
from .support import (
    NO_HOME,
    at,
    done_events,
    frame,
    moving,
    path_times,
    physical,
    status_frame,
    velocity,
)

TICK = 1.0 / 1024.0


def quiet(model: str = "VS4-040", **worlds: AxisWorld) -> Harness:
    """A board whose axes all have their home switch out of the way (unless given)."""
    return support.quiet(model, **worlds)


def custom(
    encoders: str | None = None,
    serial: str | None = None,
    firmware: str | None = None,
    **worlds: AxisWorld,
) -> Harness:
    """A VS4-040 as fitted in one installation (``omsd.models.variant``), e.g. without encoders."""
    h = Harness("VS4-040")
    model = variant(get_model("VS4-040"), encoders=encoders, serial=serial, firmware=firmware)
    world = {letter: worlds.get(letter, NO_HOME) for letter in "XYZT"}
    h.board = Board(model, now=0.0, world=world)
    return h


def ticks_after(seconds: float) -> float:
    """The first sample tick at or after ``seconds``."""
    return math.ceil(seconds * 1024 - 1e-9) / 1024


def triangle(distance: float, ac: float = 2_000_000.0) -> float:
    """Duration of a move too short to reach VL (linear ramps)."""
    return 2.0 * math.sqrt(distance / ac)


# -- §6.10 loop control ---------------------------------------------------------------------------


def test_e53_ls_repeats_z_move_five_times_and_reclaims_queue_after_loop() -> None:
    """E53 ``AZ LS5 MR100000 GO LE``: "NOTE: The first move will occur immediately after entering
    the GO command. The remaining 4 moves will be executed after the loop terminator LE has been
    entered." Each move takes 0.6 s. The loop's queue space (LS 2 + MR 2 + GO 7 on an encoder
    board, then LE 2) is held until the last pass: RQ 789 while waiting for LE, 787 while the
    other passes run, 800 afterwards."""
    h = Harness("VS4-040")
    assert h.send("AZ LS5 MR100000 GO") == b""
    h.advance(0.05)
    assert moving(h, "Z")
    at(h, 0.7)
    assert h.position("Z") == 100_000
    assert not moving(h, "Z")
    assert h.query("RQ") == frame("789")
    at(h, 1.0)
    assert h.position("Z") == 100_000  # still waiting for LE
    h.send("LE")
    at(h, 1.0 + 1.2 + 0.3)  # inside the 3rd of the remaining 4 moves (the 4th pass)
    assert moving(h, "Z")
    assert 300_000 < h.position("Z") < 400_000
    assert h.query("RQ") == frame("787")
    at(h, 1.0 + 2.4 - 0.05)
    assert moving(h, "Z")
    at(h, 1.0 + 2.4 + 0.01)
    assert not moving(h, "Z")
    assert h.position("Z") == 500_000
    assert h.query("RQ") == frame("800")
    h.run()
    assert h.position("Z") == 500_000
    assert [h.position(a) for a in "XYT"] == [0, 0, 0]
    assert h.errors() == []


def test_e54_aa_loop_relative_and_absolute_moves_four_times() -> None:
    """E54 ``AA LS4 MR100000,,,100; GO MA100,,,200; GO LE`` (VS4-040): four passes of
    X +100,000 / T +100 then X to 100 / T to 200 (X and T start together at each GO). A pass is
    0.6 s out and 0.5995 s back, so the loop ends after about 4.8 s."""
    h = Harness("VS4-040")
    h.send("AA LS4 MR100000,,,100; GO MA100,,,200; GO LE")
    excursions = 0
    high = False
    for k in range(1, 1200):
        at(h, k * 0.01)
        x = h.position("X")
        if x > 99_000 and not high:
            excursions += 1
        high = x > 99_000
        if not any(moving(h, a) for a in "XT") and h.query("RQ") == frame("800,800,800,800"):
            break
    assert excursions == 4
    assert 4.75 <= h.t <= 4.85
    assert h.position("X") == 100
    assert h.position("T") == 200
    assert h.position("Y") == 0
    assert h.position("Z") == 0
    assert h.errors() == []


def test_e55_ws_loops_while_input_low_and_exits_at_bottom() -> None:
    """E55 ``AA WS1 MR10000; GO MR, -1000; GO WD``: loop while input 1 is true (low).

    Input 1 is held low by the "external device" and released (high) at t=0.45 s, during the
    X move of the 3rd pass (a pass is X 10,000 in 0.1416 s plus Y -1,000 in 0.0449 s). "The test
    is at the bottom of the loop", so the 3rd pass completes and the loop ends: X = 30,000,
    Y = -3,000. (Note the space in ``MR, -1000;``.)"""
    h = Harness("VS4-040")
    h.board.set_input(1, False, h.t)
    h.send("AA WS1 MR10000; GO MR, -1000; GO WD")
    at(h, 0.16)  # first pass: X done, Y moving
    assert h.position("X") == 10_000
    assert -1000 < h.position("Y") < 0
    at(h, 0.25)  # second pass under way
    assert 10_000 < h.position("X") < 20_000
    assert h.position("Y") == -1000
    at(h, 0.45)
    assert moving(h, "X")
    assert 20_000 < h.position("X") < 30_000
    h.board.set_input(1, None, h.t)
    h.run()
    assert h.position("X") == 30_000
    assert h.position("Y") == -3000
    assert h.query("RQ") == frame("800,800,800,800")
    assert h.errors() == []


def test_e55_ws_body_runs_once_when_input_already_high() -> None:
    """E55 with input 1 released from the start: "The test is at the bottom of the loop, i.e. it
    will always be executed at least once"."""
    h = Harness("VS4-040")
    h.send("AA WS1 MR10000; GO MR, -1000; GO WD")
    h.run()
    assert h.position("X") == 10_000
    assert h.position("Y") == -1000
    assert h.errors() == []


def test_e55_ws_is_valid_in_am_mode_on_the_vs4() -> None:
    """E55 sent in AM mode: the VS4's WS table gives "AA, AM 2" (the PC48's says AM Not valid),
    so the same loop is accepted in multitasking mode and runs once with input 1 high."""
    h = Harness("VS4-040")
    h.send("AM WS1 MR10000; GO MR, -1000; GO WD")
    h.run()
    assert h.errors() == []
    assert h.position("X") == 10_000
    assert h.position("Y") == -1000
    assert h.query("RQ") == frame("800,800,800,800")


E56_PROGRAM = """
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


def test_e56_wh_drilling_loop_until_cw() -> None:
    """E56, the drilling platform. The ``*`` comments are annotations, not board input (the VS4
    manual never says the board ignores ``*``, digest §8.29); "(CW)" is the operator sending CW
    later from the keyboard.

    World: X, Y and Z have home switches at -1000..-900 steps (HR at VL.1 = 1,000 steps/s finds
    the upper edge, loads 0 and decelerates 5 counts past it at AC10 = 100,000 steps/s²). The
    normally closed "Ready to Drill" switch holds user I/O line 0 low; pressing it opens it and
    the line goes high (SW0 waits "until the sync line has been released"). User units are
    10,000 steps per inch: VL3 = 30,000 and VL.5 = 5,000 steps/s. Each pass takes ~4.7 s: X/Y to
    3 in (1.3 s), Z down 0.5 in and up (2 × 1.05 s), X/Y home (1.3 s)."""
    home = AxisWorld(home_low=-1000.0, home_high=-900.0)
    h = Harness("VS4-040", world={"X": home, "Y": home, "Z": home, "T": NO_HOME})
    h.board.set_input(0, False, h.t)  # NC switch closed: line grounded
    h.send(E56_PROGRAM)
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
    assert h.query("RQ") == frame("800,800,800,800")
    press(21.0)  # the loop is over: the switch does nothing any more
    at(h, 23.0)
    assert [h.position(a) for a in "XYZ"] == [0, 0, 0]
    assert not any(moving(h, a) for a in "XYZ")
    assert h.errors() == []


# -- §6.11 home -----------------------------------------------------------------------------------


def test_e57_hm_finds_home_loads_counter_and_ma_returns_there() -> None:
    """E57 ``AX VL1000 HM1000 MA1000 GO``: X's home switch is at physical 5000..5100. HM runs
    positive at 1000 steps/s (5 s to the switch), "initializes the position counter to the
    parameter supplied" there, decelerates, and MA1000 GO brings the stage back to home."""
    h = Harness("VS4-040", world={"X": AxisWorld(home_low=5000.0, home_high=5100.0)})
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
    assert h.query("QA")[4:7] == b"NNH"
    assert h.errors() == []


def test_e58_fast_hh_pass_through_home_then_slow_hr_with_hl() -> None:
    """E58 ``AX VL100000 HH HM VL1000 HL HR``: a normally open home switch at physical
    50,000..50,200. With HH (active high) the home condition is "switch open", which becomes true
    again when the fast pass leaves the switch at 50,200 (0.527 s): the counter is loaded with 0
    there and the axis decelerates 2,500 counts beyond (AC 2,000,000). HR at 1000 steps/s with
    HL then comes back and finds the switch closing at its upper edge, loading 0 again: the
    "refined" home, about 2.5 s later."""
    h = Harness("VS4-040", world={"X": AxisWorld(home_low=50_000.0, home_high=50_200.0)})
    h.send("AX VL100000 HH HM VL1000 HL HR\r\n")
    at(h, 0.3)
    assert velocity(h, "X") == 100_000
    at(h, 0.6)  # through the switch at ~0.527 s, stopped at ~0.577 s
    assert not moving(h, "X") or velocity(h, "X") < 0
    assert abs(physical(h, "X") - 52_700.0) <= 100.0
    at(h, 2.0)
    assert velocity(h, "X") == -1000  # the slow reverse pass
    h.run()
    assert -1 <= h.position("X") <= 0
    assert 50_198.0 <= physical(h, "X") < 50_200.0
    assert 3.0 <= h.t <= 3.2
    assert h.query("QA") == status_frame("MNNH")


def test_e59_km_stops_at_home_without_ramp_or_counter_reset() -> None:
    """E59 ``AY KM``: Y runs positive at its default VL (200,000) toward a home switch at
    3000..3500 (reached at ~110,000 steps/s, 107 counts per sample) and stops generating pulses
    at once. A deceleration at AC would carry it 3,000 counts past the switch; stopping within a
    sample of its edge shows there is none. "The position counter is not cleared or reset": it
    still equals the travelled distance."""
    h = Harness("VS4-040", world={"Y": AxisWorld(home_low=3000.0, home_high=3500.0)})
    h.send("AY KM")
    h.run()
    assert not moving(h, "Y")
    assert 3000 <= h.position("Y") < 3200
    assert 3000.0 <= physical(h, "Y") < 3200.0
    assert h.position("Y") == round(physical(h, "Y"))
    assert h.query("QA") == status_frame("PNNH")


def test_e60_kr_stops_at_home_in_reverse_without_counter_reset() -> None:
    """E60 ``AY KR``: like E59 in the negative direction, switch at -3500..-3000."""
    h = Harness("VS4-040", world={"Y": AxisWorld(home_low=-3500.0, home_high=-3000.0)})
    h.send("AY KR")
    h.run()
    assert not moving(h, "Y")
    assert -3200 <= h.position("Y") <= -3000
    assert -3200.0 < physical(h, "Y") < -3000.0
    assert h.position("Y") == round(physical(h, "Y"))
    assert h.query("QA") == status_frame("MNNH")


# -- §6.12 move synchronization -------------------------------------------------------------------


def test_e61_id_sets_done_when_move_finishes() -> None:
    """E61 ``AX MA100000 GO ID``: the done flag (register bit 0, DON_S, RA/QA 'D') is set when
    the 0.6 s move is finished, not before."""
    h = quiet()
    h.send("AX MA100000 GO ID")
    at(h, 0.59)
    assert h.board.registers.done == 0
    assert h.board.status_register(h.t) & DON_S == 0
    assert done_events(h.events()) == []
    at(h, 0.61)
    assert h.position("X") == 100_000
    assert h.board.registers.done == 0b0001
    assert h.board.status_register(h.t) & DON_S
    events = done_events(h.events())
    assert len(events) == 1
    assert 0.6 <= events[0].time <= 0.6 + TICK
    assert h.query("QA") == status_frame("PDNN")


def test_e62_example_as_printed_moves_y_and_t_without_interrupts() -> None:
    """E62 ``MR,1000,,10000; GO`` exactly as the VS4 prints it, in AA mode (the comma syntax
    implies it). Contradiction (digest §8.7): the text promises interrupts "when the Y and T axes
    finish", but the VS4 example leaves out the II the PC48 version has (``... GO II``). The
    board does what it is sent: Y moves +1,000 and T +10,000, and with no II or ID nothing sets
    a done flag. The interrupts of the text are tested with II in the next test."""
    h = quiet()
    h.send("AA")
    h.send("MR,1000,,10000; GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [0, 1000, 0, 10_000]
    assert done_events(h.events()) == []
    assert h.board.registers.done == 0
    assert h.board.status_register(h.t) & DON_S == 0


def test_e62_ii_interrupts_as_each_moved_axis_finishes() -> None:
    """E62 with the II of the text (PC48 form ``MR,1000,,10000; GO II``): Y (1,000 counts,
    0.0447 s) and T (10,000 counts, 0.1414 s) each interrupt when they finish: "If they do not
    complete at the same time, two interrupts would be generated." X and Z had no parameter."""
    h = quiet()
    h.send("AA")
    h.send("MR,1000,,10000; GO II")
    at(h, 0.1)
    assert h.board.read_status_register(h.t) & DON_S
    assert h.board.read_done_register(h.t) == 0b0010
    at(h, 0.2)
    assert h.board.read_status_register(h.t) & DON_S
    assert h.board.read_done_register(h.t) == 0b1000
    events = done_events(h.events())
    assert len(events) == 2
    assert abs(events[0].time - triangle(1000)) <= 2 * TICK
    assert abs(events[1].time - triangle(10_000)) <= 2 * TICK
    assert h.query("QI") == status_frame("PNNN,PDNN,PNNN,PDNN")


def test_e63_in_fires_at_x_completion_and_z_nearly_done() -> None:
    """E63 ``AA IN0,,10000; MR100000,100000;GO MR,,50000; GO``.

    X and Y move 100,000 (done at 0.6 s); the second GO waits for them (AA mode), so Z's 50,000
    runs from 0.6 s to 0.95 s and begins decelerating at 0.85 s, 10,000 counts (its ramp-down
    distance) before its end. The interrupt ("when the X axis is complete and the Z axis is
    within 10,000 counts of being complete") comes then, with Z at 40,000; X's done bit is in
    the register from 0.6 s but DON_S waits for Z. "The Y axis completion would be ignored"."""
    h = quiet()
    h.send("AA\r\n IN0,,10000;\r\n MR100000,100000;GO\r\n MR,,50000; GO\r\n")
    at(h, 0.59)
    assert h.board.registers.done == 0
    at(h, 0.62)
    assert h.board.registers.done == 0b0001  # X complete
    assert h.board.status_register(h.t) & DON_S == 0
    assert moving(h, "Z")
    at(h, 0.84)
    assert 35_000 < h.position("Z") < 40_000
    assert h.board.status_register(h.t) & DON_S == 0
    assert done_events(h.events()) == []
    at(h, 0.87)
    events = done_events(h.events())
    assert len(events) == 1
    assert abs(events[0].time - 0.85) <= 3 * TICK
    assert events[0].done_register == 0b0101
    assert moving(h, "Z")
    h.run()
    assert h.position("Z") == 50_000
    assert h.board.registers.done & 0b0010 == 0  # Y ignored


def test_e64_ip_waits_until_position_hold_brings_encoder_into_deadband() -> None:
    """E64 ``AX HV1000 HG100 HD10 HN MR1000 GO IP`` (the VS4 has encoders on all axes).

    The load slips +50 steps during the move (injected at 0.02 s), so when the pulses end
    (0.045 s) the encoder reads ~1050. The hold correction (at most HV = 1000 steps/s) brings it
    within the 10-count deadband; only then does IP set the done flag ("DONE will occur after
    move is complete and in position")."""
    h = quiet()
    h.send("AX HV1000 HG100 HD10 HN\r\n MR1000 GO IP")
    at(h, 0.02)
    h.board.inject_slip("X", 50, h.t)
    at(h, 0.05)
    assert h.board.registers.done == 0
    assert done_events(h.events()) == []
    at(h, 0.5)
    events = done_events(h.events())
    assert len(events) == 1
    assert events[0].time > 0.045 + 0.02  # 40 steps of correction at 1000 steps/s
    assert h.board.registers.done == 0b0001
    assert h.query("RE") in {frame(str(n)) for n in range(990, 1011)}
    assert 950 <= h.position("X") <= 960
    assert h.query("EA") == status_frame("DENPNN")


def test_e65_ic_clears_done_and_error_flags() -> None:
    """E65 ``AX MR5000 GO ID (done flag set) IC``: the flags set by ID are cleared by IC."""
    h = quiet()
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


def test_e66_ca_clears_only_the_z_done_flag() -> None:
    """E66 ``AA MR1000, 2000, 3000, 4000; GO ID`` then ``AZ CA`` (VS4-040; note the spaces after
    the commas, digest §8.8)."""
    h = quiet()
    h.send("AA MR1000, 2000, 3000, 4000; GO ID\r\n")
    assert h.errors() == []
    h.run()
    assert [h.position(a) for a in "XYZT"] == [1000, 2000, 3000, 4000]
    assert h.query("QI") == status_frame("PDNN,PDNN,PDNN,PDNN")
    assert h.send("AZ CA") == b""
    assert h.query("QA") == status_frame("PNNN")
    assert h.board.registers.done == 0b1011
    h.send("AA")
    assert h.query("QI") == status_frame("PDNN,PDNN,PNNN,PDNN")


def test_e67_wa_holds_z_aux_until_xy_moves_finish() -> None:
    """E67, the laser: ``AA VL1000,1000,1000; AC10000,10000,10000;`` then
    ``LS10; MR1000,1000; GO WA AN,,1; MR,,500; GO AF,,1; MR,,-500 GO LE`` (``MR,,-500 GO``: the
    space ends the list).

    Prior state: the laser (Z aux) is switched off before the example (``AA AF,,1;``), as it is
    on at power-up. Invariants sampled every 5 ms: the laser is never on while X or Y moves
    (that is what WA is for) or while Z moves negative, and it goes on 10 times. A pass is
    X/Y 1,000 at VL 1000 / AC 10,000 (1.1 s) plus Z +500 and -500 (0.6 s each)."""
    h = quiet()
    h.send("AA AF,,1;")
    h.run()
    assert h.axis("Z").aux is False
    h.send("AA VL1000,1000,1000; AC10000,10000,10000;\r\n")
    h.send(" LS10; MR1000,1000; GO WA AN,,1; MR,,500; GO AF,,1;\r\n MR,,-500 GO LE")
    assert h.errors() == []
    accel = {a: h.board.snapshot(h.t)["axes"][a]["acceleration_setting"] for a in "XYZT"}
    assert accel == {"X": 10_000, "Y": 10_000, "Z": 10_000, "T": 2_000_000}
    at(h, 0.5)
    assert moving(h, "X")
    assert h.axis("Z").aux is False  # WA: AN,,1 waits for the X/Y move
    rising = 0
    was_on = False
    start = h.t
    k = 0
    while k < 6000:
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
        if h.t > 1.0 and not any(moving(h, a) for a in "XYZ") and h.axis("Z").queue.free == 800:
            break
    assert rising == 10
    assert 22.9 <= h.t <= 23.2  # 10 × (1.1 s X/Y + 2 × 0.6 s Z)
    assert [h.position(a) for a in "XYZ"] == [10_000, 10_000, 0]
    assert h.axis("Z").aux is False


def test_e67_wa_is_not_valid_in_single_axis_mode() -> None:
    """E67's WA: "The WA command, only valid in the AA mode" (table: AX - AT Not Valid, AA, AM
    2). Sent in single-axis mode it is one command error and X's queue is untouched."""
    h = Harness("VS4-040")
    h.send("AX WA")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, "WA")]
    assert h.query("RQ") == frame("800")


def test_e68_wq_holds_rp_until_the_y_queue_is_empty() -> None:
    """E68 ``AY MR1000 GO WQ RP``: the RP reply comes when the 0.045 s move has finished and
    gives the final position."""
    h = Harness("VS4-040")
    assert h.send("AY MR1000 GO WQ RP") == b""
    assert at(h, 0.04) == b""
    assert at(h, 0.05) == frame("1000")
    assert at(h, 1.0) == b""


def test_e69_sw0_with_y_aux_on_does_not_hold_x() -> None:
    """E69 ``AY AN MR2000 GO AF`` / ``AX SW0 MR10000 GO`` with Y's aux wired to sync line 0.

    Reading: the text says X waits "until the Y axis has finished its move and turned off its
    auxiliary output", but SW waits "until the sync line has been released (allowed to go
    high)", AN releases the aux (high) and AF drives it low. The definitions of SW, AN and AF
    are taken over the example's prose (the master/slave example E70 agrees with them): during
    Y's move the line is high, so X does not wait and both move at once; after Y's AF the line
    is low. A later SW0 then does hold X until the line is released again."""
    h = Harness("VS4-040")
    h.board.wire_input_to_aux(0, "Y")
    h.send("AY AN MR2000 GO AF\r\n AX SW0 MR10000 GO")
    at(h, 0.03)
    assert moving(h, "Y")
    assert moving(h, "X")  # not held by SW0
    assert h.position("X") > 0
    at(h, 0.2)
    assert h.position("Y") == 2000
    assert h.position("X") == 10_000
    assert h.axis("Y").aux is False
    assert h.board.input_high(0, h.t) is False  # input 0 pulled low by Y's aux
    # with the line low, SW0 does wait
    h.send("AX SW0 MR10000 GO")
    at(h, 0.6)
    assert h.position("X") == 10_000
    assert not moving(h, "X")
    h.send("AY AN;")
    at(h, 1.0)
    assert h.position("X") == 20_000
    assert h.board.input_high(0, h.t) is True


def test_e70_master_pa0_releases_slaves_waiting_at_sw0() -> None:
    """E70: three four-axis boards; the master's X aux is wired to sync line 0 of both slaves
    (simulated by copying the master's X aux level onto the slaves' input 0 whenever it may have
    changed). ``AX PA0;`` holds the master's X aux low "until its move starts"; the slaves wait
    at ``AA SW0;``; the master's ``AA MR100,100,100,100; GO`` raises the aux and "All three
    boards will start their moves". The "(Board n)" labels say where each line goes."""
    master = Harness("VS4-040")
    slaves = [Harness("VS4-040"), Harness("VS4-040")]
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
    slaves[0].send(" AA SW0; MR200,200,200,200; GO")
    slaves[1].send(" AA SW0; MR300,300,300,300; GO")
    until(1.0)
    for s in slaves:
        assert not any(moving(s, a) for a in "XYZT")
        assert all(s.position(a) == 0 for a in "XYZT")
    master.send(" AA MR100,100,100,100; GO")
    wire()
    until(1.0 + 4 * TICK)
    for b in boards:
        assert all(moving(b, a) for a in "XYZT")
    until(1.5)
    assert all(master.position(a) == 100 for a in "XYZT")
    assert all(slaves[0].position(a) == 200 for a in "XYZT")
    assert all(slaves[1].position(a) == 300 for a in "XYZT")
    assert master.axis("X").aux is False  # low again after the move
    assert all(b.errors() == [] for b in boards)


def test_e71_wt_jog_staircase_then_stop() -> None:
    """E71 ``AX JG5000 WT2000 JG10000 WT3000 ST``: 5,000 steps/s for 2 s "once up to speed"
    ("In the case of the Jog command the wait will begin when the axis has ramped up"), then
    10,000 for 3 s, then stop.

    Reading: ST "flushes the queue for the current axis" and "is executed immediately" (table
    Flush + 2), so it cannot wait behind the WTs; sent on the same line it would end the jog at
    once (next test). The example's timeline is obtained with the queued part sent first and
    ST sent by the host when the 3 s are over (t = 5.1 s); WT3000 must not stop the jog by
    itself. About 5000·2 + 10000·3.1 + ramps ≈ 41,000 counts."""
    h = Harness("VS4-040")
    assert h.send("AX JG5000 WT2000 JG10000 WT3000\r\n") == b""
    at(h, 1.0)
    assert h.query("RV") == frame("5000")
    at(h, 1.99)
    assert h.query("RV") == frame("5000")
    at(h, 2.02)
    assert h.query("RV") == frame("10000")
    at(h, 4.99)
    assert h.query("RV") == frame("10000")
    at(h, 5.1)
    assert h.query("RV") == frame("10000")  # WT3000 over; nothing queued stops the jog
    assert h.send("ST") == b""
    at(h, 5.12)
    assert h.query("RV") == frame("0")
    assert not moving(h, "X")
    assert abs(h.position("X") - 41_000) <= 40
    assert h.query("RQ") == frame("800")


def test_e71_st_on_the_same_line_is_immediate() -> None:
    """E71 typed as one line: ST is "executed immediately" and flushes X's queue, so the WTs and
    the second JG are discarded and the jog is stopped before it gets anywhere."""
    h = Harness("VS4-040")
    assert h.send("AX JG5000 WT2000 JG10000 WT3000 ST") == b""
    at(h, 1.0)
    assert h.query("RV") == frame("0")
    assert not moving(h, "X")
    assert 0 <= h.position("X") <= 10
    at(h, 3.0)
    assert h.query("RV") == frame("0")
    assert h.query("RQ") == frame("800")


# -- §6.13 status requests ------------------------------------------------------------------------


def test_e72_wy_four_axis_board() -> None:
    """E72 ``WY`` → ``<LF><CR>VS4-040 ver 1.00 S/N 123456<LF><CR>``."""
    h = Harness("VS4-040")
    assert h.send("WY") == b"\n\rVS4-040 ver 1.00 S/N 123456\n\r"


def test_e72_wy_two_axis_board_and_other_serial() -> None:
    """E72's format on the other model and on a board with its own serial number: model, "ver",
    firmware, "S/N", serial."""
    assert Harness("VS4-020").send("WY") == b"\n\rVS4-020 ver 1.00 S/N 123456\n\r"
    assert custom(serial="000217").send("WY") == b"\n\rVS4-040 ver 1.00 S/N 000217\n\r"


def test_e73_rp_y_position() -> None:
    """E73 ``AY RP`` → ``<LF><CR>12345<LF><CR>`` once Y is at 12345."""
    h = Harness("VS4-040")
    h.send("AY MR12345 GO")
    h.run()
    h.send("AX")
    assert h.send("AY RP") == b"\n\r12345\n\r"


def test_e74_rq_t_queue_with_200_free() -> None:
    """E74 ``AT RQ`` → ``<LF><CR>200<LF><CR>``.

    Contradiction (digest §8.2): "The maximum available space in each command queue is 800", yet
    the example prints 200 (the PC48's maximum). Reading: an empty queue answers 800 (the model's
    choice), and the example shows a T queue with 200 free slots. T's queue is filled with 600
    slots that a loop keeps held until its LE: LS 2, 66 × (MR 2 + GO 7), 4 × ID 1."""
    h = Harness("VS4-040")
    assert h.send("AT RQ") == frame("800")
    h.send("AT LS2 " + "MR1 GO " * 66 + "ID ID ID ID ")
    h.run()
    assert h.position("T") == 66
    h.send("AX")
    assert h.send("AT RQ") == b"\n\r200\n\r"
    h.send("LE")
    h.run()
    assert h.position("T") == 132
    assert h.query("RQ") == frame("800")


def test_e74_rq_is_three_digits_zero_padded() -> None:
    """RQ text: "The response is at a fixed length of 3 characters. For example, if the current
    free queue space is 67, the response ... is <LF><CR>067<LF><CR>." X's queue holds 733 slots
    in a loop body: LS 2, 81 × (MR 2 + GO 7), 2 × ID 1."""
    h = Harness("VS4-040")
    h.send("AX LS2 " + "MR1 GO " * 81 + "ID ID ")
    h.run()
    assert h.query("RQ") == b"\n\r067\n\r"


def test_e75_ra_y_in_positive_limit() -> None:
    """E75 ``AY RA`` → ``<LF><CR><CR>PNLN<LF><CR><CR>``: Y ran into its positive limit switch
    (at 5000 in the world) during ``MR10000``; the hard limit stops the pulses within a sample.
    RA also resets the limit flag (OVRT) since no other axis is in limit."""
    h = quiet(Y=AxisWorld(positive_limit=5000.0, home_low=9e6, home_high=9e6 + 100))
    h.send("AY MR10000 GO")
    h.run()
    assert 5000 <= h.position("Y") < 5200
    limits = [e for e in h.events() if isinstance(e, LimitEvent)]
    assert [(e.axis, e.direction) for e in limits] == [("Y", 1)]
    assert h.board.status_register(h.t) & OVRT
    h.send("AX")
    assert h.send("AY RA") == b"\n\r\rPNLN\n\r\r"
    assert h.board.status_register(h.t) & OVRT == 0


def test_e76_ri_four_axes_moved_negative_and_done() -> None:
    """E76 ``AA RI`` → ``<LF><CR><CR>MDNN,MDNN,MDNN,MDNN<LF><CR><CR>``: every axis of a
    4-axis board moved negative and executed ID. "The done flag is reset by this command"."""
    h = quiet()
    h.send("AA MR-1000,-1000,-1000,-1000; GO ID")
    h.run()
    assert h.send("AA RI") == b"\n\r\rMDNN,MDNN,MDNN,MDNN\n\r\r"
    assert h.send("QI") == status_frame("MNNN,MNNN,MNNN,MNNN")
    assert h.board.registers.done == 0


def test_e77_qa_x_positive_at_home() -> None:
    """E77 ``AX QA`` → ``<LF><CR><CR>PNNH<LF><CR><CR>``: X last moved positive onto its home
    switch (1000..1100 in the default world), no ID, no limit; QA changes no flag."""
    h = Harness("VS4-040")
    h.send("AX MR1050 GO")
    h.run()
    assert h.send("AX QA") == b"\n\r\rPNNH\n\r\r"
    assert h.send("QA") == b"\n\r\rPNNH\n\r\r"


def test_e78_qi_mixed_state_four_axes() -> None:
    """E78 ``AA QI`` → ``<LF><CR><CR>PNNN,MNNN,PDNN,MNLN<LF><CR><CR>``: X moved positive; Y
    moved negative; Z moved positive and executed ID; T ran into its negative limit (-500).
    QI does not affect the flags."""
    h = quiet(T=AxisWorld(negative_limit=-500.0, home_low=9e6, home_high=9e6 + 100))
    h.send("AX MR100 GO AY MR-100 GO AZ MR100 GO ID AT MR-1000 GO")
    h.run()
    expected = b"\n\r\rPNNN,MNNN,PDNN,MNLN\n\r\r"
    assert h.send("AA QI") == expected
    assert h.send("QI") == expected
    assert h.board.registers.done == 0b0100


def test_e79_rc_all_axes_at_the_power_up_acceleration() -> None:
    """E79 ``AA RC`` → ``<LF><CR>2000000,2000000,2000000,2000000<LF><CR>``: "All acceleration
    registers default to 2,000,000 steps per second per second upon power-up", so no set-up is
    needed; idle with linear ramps, RC reports the acceleration at the start of a ramp. A
    two-axis board answers two fields."""
    h = Harness("VS4-040")
    assert h.send("AA RC") == b"\n\r2000000,2000000,2000000,2000000\n\r"
    assert Harness("VS4-020").send("AA RC") == b"\n\r2000000,2000000\n\r"


def test_e80_rv_y_jogging() -> None:
    """E80 ``AY JG 12345`` then ``RV`` → ``<LF><CR>12345<LF><CR>`` (RV sent once the jog has
    reached speed, 6 ms later; note the space in ``JG 12345``)."""
    h = Harness("VS4-040")
    assert h.send("AY JG 12345\r\n") == b""
    h.advance(0.1)
    assert h.send(" RV") == b"\n\r12345\n\r"
    assert h.errors() == []
    assert h.position("Y") > 1000


def test_e81_ru_three_and_a_half_revolutions() -> None:
    """E81 ``AZ UU2000; LP0; MR3.5; GO`` (wait) ``RU`` → ``<LF><CR>3.50000<LF><CR>``."""
    h = Harness("VS4-040")
    h.send("AZ UU2000; LP0;\r\n MR3.5; GO\r\n")
    h.run()
    assert h.position("Z") == 7000
    assert h.send(" RU") == b"\n\r3.50000\n\r"


# -- §6.14 user units -----------------------------------------------------------------------------


def test_e82_uu_inches_on_x_y_z_single_axis_form() -> None:
    """E82, first form ``AX UU10000;AY UU10000;AZ UU10000;``: no reply; moves are then in inches
    on X, Y and Z, in AA mode too ("will remain effective in the AA or AM mode"); T is not."""
    h = Harness("VS4-040")
    assert h.send("AX UU10000;AY UU10000;AZ UU10000;\r\n") == b""
    h.send("AA MR1,2,.5,3; GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [10_000, 20_000, 5000, 3]
    assert h.errors() == []


def test_e82_uu_inches_on_x_y_z_aa_form() -> None:
    """E82, second form ``AA UU10000,10000,10000;``. Contradiction (digest §8.5): UU's table says
    "AA, AM Not Valid" but the example uses it; the model accepts the example's AA form
    (``omsd/models/vs4.py``: an example shows what the firmware did). Same effect as the first
    form."""
    h = Harness("VS4-040")
    assert h.send("AA UU10000,10000,10000;\r\n") == b""
    assert h.errors() == []
    h.send("AA MR1,2,.5,3; GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [10_000, 20_000, 5000, 3]


def test_e83_uf_turns_user_units_off() -> None:
    """E83 ``AX UF AY UF AZ UF`` after UU10000: moves are in steps again."""
    h = Harness("VS4-040")
    h.send("AX UU10000 AY UU10000 AZ UU10000\r\n")
    assert h.send("AX UF AY UF AZ UF") == b""
    h.send("AA MR5,5,5; GO")
    h.run()
    assert [h.position(a) for a in "XYZ"] == [5, 5, 5]
    h.send("AZ")
    assert h.query("RU") == frame("5.00000")


# -- §6.15 position maintenance -------------------------------------------------------------------


def test_e84_er_distances_in_encoder_counts() -> None:
    """E84 ``ER10000,25000;`` (X, the power-up axis): "All distance ... parameters are input in
    encoder counts"; "The correct number of motor counts are generated": MR10000 gives 25,000
    motor steps and 10,000 encoder counts."""
    h = quiet()
    assert h.send("ER10000,25000;\r\n") == b""
    h.send("MR10000 GO")
    h.run()
    assert h.position("X") == 25_000
    assert h.query("RE") == frame("10000")
    assert h.errors() == []


def test_e85_hf_turns_position_hold_off() -> None:
    """E85 ``AX HF``: with hold on, X is moved 1000; after HF a 100-step slip stays
    uncorrected and EA reports slip detection and position maintenance disabled."""
    h = quiet()
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


def test_e86_hn_maintains_position_within_deadband_after_slips() -> None:
    """E86 ``AX VL100000 AC500000 HV50000 HD10 HG2000 HN MR200000 GO``: the 2.2 s move, then
    "that position is maintained within the 10 step deadband": slips of +500 and -300 steps
    injected afterwards are corrected back within 10 encoder counts."""
    h = quiet()
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


def test_e87_ip_immediately_in_position_then_hold_keeps_it() -> None:
    """E87 (the IP example repeated in §6.15): without a slip the stage is within the deadband
    when the move ends, so IP sets done then (0.045 s); a later -30 step slip is corrected by
    the hold back into the deadband."""
    h = quiet()
    h.send("AX HV1000 HG100 HD10 HN\r\n MR1000 GO IP")
    at(h, 0.04)
    assert h.board.registers.done == 0
    at(h, 0.05)
    assert h.board.registers.done == 0b0001
    events = done_events(h.events())
    assert len(events) == 1
    assert abs(events[0].time - triangle(1000)) <= 2 * TICK
    at(h, 0.5)
    h.board.inject_slip("X", -30, h.t)
    at(h, 1.0)
    encoder = int(h.query("RE").strip())
    assert abs(encoder - 1000) <= 10
    assert 1020 <= h.position("X") <= 1030


def test_e87_ip_is_valid_in_aa_mode() -> None:
    """E87's table (§6.15: "AA, AM 1", against §6.12's "Not Valid", digest §8.11): the model
    takes §6.15's. Without HN, IP "will behave like an ID command for that axis": in AA mode
    every axis sets its done bit when it reaches the IP, and DON_S when all have."""
    h = quiet()
    h.send("AA MR1000,2000; GO IP")
    assert h.errors() == []
    h.run()
    assert [h.position(a) for a in "XYZT"] == [1000, 2000, 0, 0]
    assert h.board.registers.done == 0b1111
    assert h.board.status_register(h.t) & DON_S
    assert len(done_events(h.events())) == 1


# -- §6.16 slip and stall -------------------------------------------------------------------------


def test_e88_es5_is_tolerates_five_steps_flags_six() -> None:
    """E88 ``ES5 IS`` (X): "tolerate being up to 5 steps from the desired position": a 5-step
    slip raises nothing, one more step raises the slip (status bit 2, RL 'S', EA 'S'), and slip
    detection is then off ("If a slip occurs, slip detection must be re-enabled")."""
    h = quiet()
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


def test_e89_rl_z_slipped() -> None:
    """E89 ``RL`` → ``<LF><CR>NNSN<LF><CR>`` ("(The Z axis has slipped.)" is a remark): Z with
    ``ES5 IS`` stalls during a move."""
    h = quiet()
    h.send("AZ ES5 IS MR10000 GO")
    at(h, 0.05)
    h.board.set_stall("Z", True, h.t)
    at(h, 0.1)
    assert [e.axis for e in h.events() if isinstance(e, SlipEvent)] == ["Z"]
    assert h.send("RL") == b"\n\rNNSN\n\r"


def test_e90_hf_disables_slip_detection() -> None:
    """E90 ``AX HF`` after ``ES5 IS``: a 100-step slip then raises nothing."""
    h = quiet()
    h.send("AX ES5 IS")
    assert h.send("AX HF") == b""
    h.run()
    h.board.inject_slip("X", 100, h.t)
    h.advance(0.1)
    assert not [e for e in h.events() if isinstance(e, SlipEvent)]
    assert h.board.status_register(h.t) & ENC_S == 0
    assert h.query("RL") == frame("NNNN")


# -- §6.17 encoder tracking -----------------------------------------------------------------------


def test_e91_et_x_follows_its_encoder_input() -> None:
    """E91 ``AX ET``: "The axis will duplicate the encoder input" (ER 1:1): an encoder input
    moved to 5000 brings the position counter to 5000."""
    h = quiet()
    assert h.send("AX ET") == b""
    h.run()
    h.board.set_encoder_input("X", 5000, h.t)
    h.run()
    assert h.position("X") == 5000
    assert h.query("RE") == frame("5000")


def test_e92_hf_ends_encoder_tracking() -> None:
    """E92 ``AX HF`` after ET: the encoder input no longer moves the axis."""
    h = quiet()
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


def test_e93_he_homes_on_encoder_index_inside_home_enable() -> None:
    """E93 ``AY HE``: home = index AND quadrant AND the (low true) home enable. The enable is
    active over 1000..3000 and the index is at encoder count 2000: a following
    ``VL1000 HM0 MA0 GO`` homes at 2000, not where the enable switch closes (1000)."""
    h = Harness("VS4-040", world={"Y": ENCODER_HOME})
    assert h.send("AY HE") == b""
    h.send("AY VL1000 HM0 MA0 GO")
    h.run()
    assert h.position("Y") == 0
    assert abs(physical(h, "Y") - 2000.0) <= 1.0
    assert h.errors() == []


def test_e94_hs_homes_on_switch_only() -> None:
    """E94 ``AY HS`` after HE: the encoder signals are ignored again and the same homing
    sequence stops where the home switch closes (1000)."""
    h = Harness("VS4-040", world={"Y": ENCODER_HOME})
    h.send("AY HE")
    assert h.send("AY HS") == b""
    h.send("AY VL1000 HM0 MA0 GO")
    h.run()
    assert h.position("Y") == 0
    assert abs(physical(h, "Y") - 1000.0) <= 1.0


# -- §6.19 encoder status -------------------------------------------------------------------------


def test_e95_ea_y_slip_and_hold_enabled_in_position() -> None:
    """E95 ``AY EA`` → ``<LF><CR><CR>EENPNN<LF><CR><CR>``: Y with slip detection (ES5 IS) and
    position maintenance (HN) enabled, no slip, within the deadband, not home."""
    h = quiet()
    h.send("AY HV1000 HG100 HD10 HN ES5 IS")
    h.run()
    h.send("AX")
    assert h.send("AY EA") == b"\n\r\rEENPNN\n\r\r"


def test_e96_re_y_encoder_position() -> None:
    """E96 ``AY RE`` → ``<LF><CR>12345<LF><CR>``: Y's encoder at 12345 after a move there."""
    h = quiet()
    h.send("AY MR12345 GO")
    h.run()
    h.send("AX")
    assert h.send("AY RE") == b"\n\r12345\n\r"


# -- §6.20 velocity staircase ---------------------------------------------------------------------


def test_e97_mm_sets_y_direction_minus() -> None:
    """E97 ``AY MM``: Y's direction becomes minus (QA char 4 'M'; MM takes one queue slot on the
    VS4 and runs at once on an idle axis), and a staircase that follows runs that way."""
    h = quiet()
    assert h.send("AY MM") == b""
    assert h.errors() == []
    assert h.query("QA") == status_frame("MNNN")
    h.send("MV-1000,5000 SP-2000\r\n")
    h.run()
    assert h.position("Y") == -2000
    assert h.errors() == []


def test_e97_mm_is_not_valid_in_aa_mode() -> None:
    """E97's table: MM "AX - AT 1 / AA, AM Not Valid" (the PC48's is the other way round). In
    AA mode it is one command error and no direction changes."""
    h = quiet()
    h.send("AA MM")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, "MM")]
    assert h.send("QI") == status_frame("PNNN,PNNN,PNNN,PNNN")


def test_e97_mm_then_mo_steps_minus_on_a_board_without_encoders() -> None:
    """E97's "direction line ... minus" as MO uses it ("output one step pulse in the current
    direction"): MO "is not available in models with an encoder option", so on a VS4 built
    without encoders (``variant(encoders="")``) ``AY MM MO`` moves Y exactly one step to -1."""
    h = custom(encoders="")
    h.send("AY MM MO")
    h.run()
    assert h.errors() == []
    assert h.position("Y") == -1
    assert [h.position(a) for a in "XZT"] == [0, 0, 0]


def test_e98_mv_velocity_staircase_breakpoints() -> None:
    """E98 ``MP MV10000,30000 MV20000,50000 MV30000,10000 SP35000`` on X at the power-up AC
    (2,000,000; the VS4 text names no other). From rest at 0: 30,000/s reached at 0.015 s
    (225 counts), breakpoint 10,000 at 0.341 s; up to 50,000/s by 0.351 s (10,400), breakpoint
    20,000 at 0.543 s; down to 10,000/s by 0.563 s (20,600), breakpoint 30,000 at 1.503 s;
    cruise and a 5 ms stop ending exactly at 35,000 (2.005 s)."""
    h = Harness("VS4-040")
    text = "MP\r\n        MV10000,30000\r\n        MV20000,50000\r\n"
    text += "        MV30000,10000\r\n        SP35000\r\n"
    assert h.send(text) == b""
    at(h, 0.2)
    assert h.query("RV") == frame("30000")
    at(h, 0.335)
    assert h.position("X") < 10_000
    assert h.query("RV") == frame("30000")
    at(h, 0.346)
    assert 30_000 < velocity(h, "X") < 50_000
    at(h, 0.4)
    assert h.query("RV") == frame("50000")
    at(h, 0.535)
    assert h.position("X") < 20_000
    assert h.query("RV") == frame("50000")
    at(h, 0.553)
    assert 10_000 < velocity(h, "X") < 50_000
    at(h, 1.0)
    assert h.query("RV") == frame("10000")
    at(h, 1.49)
    assert h.position("X") < 30_000
    at(h, 1.99)
    assert h.query("RV") == frame("10000")
    assert h.position("X") < 35_000
    at(h, 2.02)
    assert not moving(h, "X")
    assert h.position("X") == 35_000
    assert h.errors() == []


def test_e99_fp_flushes_queue_and_stops_at_25000() -> None:
    """E99 ``FP25000``: X is on a 100,000-step move at full speed (10,000 at t=0.1 s) with
    another move queued behind it. FP flushes the queue and stops exactly at 25,000
    (deceleration from 15,000 at 0.125 s, stopped at 0.225 s); the queued move never runs."""
    h = Harness("VS4-040")
    h.send("AX MR100000 GO MR5000 GO")
    at(h, 0.1)
    assert h.send("FP25000\r\n") == b""
    at(h, 0.12)
    assert h.query("RV") == frame("200000")
    at(h, 0.17)
    assert 0 < velocity(h, "X") < 200_000
    at(h, 0.23)
    assert not moving(h, "X")
    assert h.position("X") == 25_000
    h.run()
    assert h.position("X") == 25_000
    assert h.query("RQ") == frame("800")


def test_e99_fp_overshoots_when_too_close() -> None:
    """E99, the rest of FP's text: "The axis will overshoot if there is insufficient distance
    left to stop at the programmed acceleration": FP17000 at 10,000 and 200,000/s (10,000
    counts needed to stop)."""
    h = Harness("VS4-040")
    h.send("AX MR100000 GO")
    at(h, 0.1)
    h.send("FP17000\r\n")
    h.run()
    assert 17_000 < h.position("X") <= 20_200  # FP acts on the next sample (≤ 196 counts)


# -- §6.21 contouring -----------------------------------------------------------------------------


def test_e100_cd_cut_hole_on_z_and_t() -> None:
    """E100: cut a hole of radius 10,000 on Z,T at CV1000 with circular interpolation.

    Readings:
    * ``MT 10,000,-1000;`` (digest §8.9): a comma separates axis fields, so it is MT to Z=10,
      T=000=0, and the third field falls beyond the two contour axes and is ignored.
    * The arc direction is not stated in the VS4 manual; the PC48's ("Positive radians equal
      counter clockwise movement") is used, as in E101, whose lead-in from (-1000,0) travels
      along the CCW tangent at the start. E100's ``MT,,1000,0;`` places the stage on the other
      side (it must then be "traveling in the proper direction", which is the user's concern):
      the lead-in still brings it to (0,0) at CV after 2 s, and the path is the same.
    * The torch is Y's aux: ``AN,0;`` and ``AF,0;`` both address Y (consistent here). It is off
      before the example (``AA AF,0;``), as aux outputs are on at power-up.

    Contour queue: CD takes 0 slots; AN 2, CR 8, CR 8, AF 2 and MT 4 + 2 axes: RQ 7134 before
    CE. Timeline from CX (which starts when MT,,1000,0 has positioned Z): lead-in 2 s; half circle
    (15.708 s) to (0,10000) through (5000,5000); full circle (62.832 s) through (-10000,0);
    AF,0; 10 s line to (10,0); CE."""
    h = quiet()
    h.send("AA AF,0;")
    h.run()
    assert h.axis("Y").aux is False
    h.send("AA\r\nCV1000 CD,,0,0;\r\nAN,0; CR0,5000,3.1415926;\r\nCR0,0,6.2831853;\r\n")
    h.send("AF,0; MT 10,000,-1000;\r\n")
    assert h.query("RQ") == b"\n\r7134\n\r"
    h.send("CE\r\nMT,,1000,0; GO CX")
    assert h.errors() == []
    t0 = ticks_after(triangle(1000))
    at(h, t0)
    assert h.position("Z") == 1000
    at(h, t0 + 1.0)
    assert 0 < h.position("Z") < 1000
    assert h.position("T") == 0
    assert h.axis("Y").aux is False
    at(h, t0 + 2.1)
    assert h.axis("Y").aux is True
    half = math.pi * 5000 / 1000
    at(h, t0 + 2 + half / 2)
    assert abs(h.position("Z") - 5000) <= 3
    assert abs(h.position("T") - 5000) <= 3
    at(h, t0 + 2 + half)
    assert abs(h.position("Z")) <= 3
    assert abs(h.position("T") - 10_000) <= 3
    full = 2 * math.pi * 10_000 / 1000
    at(h, t0 + 2 + half + full / 4)
    assert abs(h.position("Z") + 10_000) <= 3
    assert abs(h.position("T")) <= 3
    at(h, t0 + 2 + half + full - 0.1)
    assert h.axis("Y").aux is True
    at(h, t0 + 2 + half + full + 0.1)
    assert h.axis("Y").aux is False
    at(h, t0 + 2 + half + full + 5)
    assert abs(h.position("Z") - 5) <= 2
    assert abs(h.position("T") - 5000) <= 3
    at(h, t0 + 2 + half + full + 10.05)
    assert not moving(h, "Z") and not moving(h, "T")
    assert h.position("Z") == 10
    assert abs(h.position("T")) <= 1
    assert [h.position(a) for a in "XY"] == [0, 0]


def test_e101_ck_ends_contour_without_ramp() -> None:
    """E101 ``AA CV1000 CD0,0; AN,,0; CR0,5000,3.1415926; CR0,0,6.2831853; AF,0;
    MT 10,000,-1000; CK MT-1000,0; GO CX`` (X,Y contour).

    Readings: ``MT 10,000,-1000;`` as in E100 (to (10,0)). Aux pairing (digest §8.10):
    ``AN,,0;`` addresses Z and ``AF,0;`` Y; the board does what was sent, so Z's aux goes on at
    the start of the path and stays on, and Y's goes off after the full circle. Z's aux is off
    beforehand. CK: "the pulses will stop abruptly": the stage moves at the full 1000/s along
    the last line until it is at (10,0) and stops there."""
    h = quiet()
    h.send("AA AF,,1;")
    h.run()
    assert h.axis("Z").aux is False
    assert h.axis("Y").aux is True
    h.send("AA\r\n CV1000 CD0,0;\r\n AN,,0; CR0,5000,3.1415926;\r\n CR0,0,6.2831853;\r\n")
    h.send(" AF,0; MT 10,000,-1000;\r\n CK\r\n MT-1000,0; GO CX")
    assert h.errors() == []
    t0 = ticks_after(triangle(1000))
    at(h, t0 + 1.0)
    assert -1000 < h.position("X") < 0
    assert h.axis("Z").aux is False
    at(h, t0 + 2.1)
    assert h.axis("Z").aux is True
    half = math.pi * 5000 / 1000
    full = 2 * math.pi * 10_000 / 1000
    at(h, t0 + 2 + half / 2)
    assert abs(h.position("X") - 5000) <= 3
    assert abs(h.position("Y") - 5000) <= 3
    at(h, t0 + 2 + half + full - 0.1)
    assert h.axis("Y").aux is True
    at(h, t0 + 2 + half + full + 0.1)
    assert h.axis("Y").aux is False
    assert h.axis("Z").aux is True
    end = t0 + 2 + half + full + 10.0
    at(h, end - 0.01)
    assert abs(velocity(h, "Y") + 1000) <= 2
    at(h, end + 2 * TICK)
    assert not moving(h, "X") and not moving(h, "Y")
    assert h.position("X") == 10
    assert h.position("Y") == 0


HEXAGON = [(10_000, 0), (20_000, 0), (25_000, 10_000), (20_000, 20_000), (10_000, 20_000)]
HEXAGON += [(5000, 10_000), (10_000, 0)]


def test_e102_mt_hexagon_with_bit9() -> None:
    """E102, the hexagon at CV5000 from (10000,0), sent as printed (leading spaces included; the
    VS4 prints ``MT20000,20000`` without the PC48's stray space). The stage starts at (0,0): the
    lead-in reaches 5000/s at (10000,0) after 4 s. Bit 9 (an output: "Factory default output
    bits are 8 through 13") goes low at (20000,20000) and high again at (5000,10000); CK stops
    at (10000,0). In the definition each MT takes 4 + 2 contour slots and BL 2 ("AA/CD 2"):
    RQ shows 7140 after three MTs and BL9."""
    h = Harness("VS4-040")
    h.send("            AA CV5000;\r\n                 CD10000,0;\r\n")
    assert h.query("RQ") == frame("7160")
    body = ["MT20000,0", "MT25000,10000", "MT20000,20000", "BL9"]
    h.send("".join(f"                 {line}\r\n" for line in body))
    assert h.query("RQ") == frame("7140")
    tail = ["MT10000,20000", "MT5000,10000", "BH9", "MT10000,0", "CK", "CX"]
    h.send("".join(f"                 {line}\r\n" for line in tail))
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


def test_e103_rq_contour_queue_after_cd() -> None:
    """E103 ``AA CD0,0; RQ`` → ``<LF><CR>7160<LF><CR>``. Contradiction (digest §8.1): §6.21's
    text says the contour queue "holds 1760 command words"; RQ's own text ("The maximum
    available is 7160") and this example say 7160, which the model uses."""
    h = Harness("VS4-040")
    assert h.send("AA CD0,0; RQ") == b"\n\r7160\n\r"


def test_e104_bl10_bl11_after_the_move() -> None:
    """E104 ``AX MA1000 GO BL10; BL11;``: bits 10 and 11 (outputs by default) are driven low
    ("on") after the 0.045 s move, not before."""
    h = Harness("VS4-040")
    h.send("AX MA1000 GO BL10; BL11;")
    assert h.errors() == []
    at(h, 0.02)
    assert moving(h, "X")
    assert h.board.outputs_low == 0
    at(h, 0.05)
    assert h.position("X") == 1000
    assert h.board.outputs_low == (1 << 10) | (1 << 11)


def test_e104_rb_referenced_by_the_example_is_not_a_vs4_command() -> None:
    """E104's "See the RB command in this section": the VS4 manual has no RB (digest §8.14);
    the model leaves RB out, so it is an unrecognised command: one command error, no reply."""
    h = Harness("VS4-040")
    assert h.send("RB") == b""
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "RB")]


def test_e105_bh8_bh11_set_bits_high() -> None:
    """E105 ``BH8; BH11;`` (the E24 example repeated in §6.21): bits 8 and 11, driven low
    earlier together with bit 10, are set high ("off"); bit 10 stays low."""
    h = Harness("VS4-040")
    h.send("BL8; BL10; BL11;")
    h.run()
    assert h.board.outputs_low == (1 << 8) | (1 << 10) | (1 << 11)
    assert h.send("BH8; BH11;") == b""
    h.run()
    assert h.board.outputs_low == 1 << 10
    assert h.errors() == []


# -- addenda --------------------------------------------------------------------------------------


def test_x1_wy_bytes_at_installation_firmware_1_04() -> None:
    """X1 (§2.9 steps 10 and 11): after power-up and the 1.5 s wait, the interrupt vector
    register reads back what was written, and the two bytes 0x57 0x59 written to the data
    register make the board answer ``0A 0D 56 53 34 2D 30 34 30 20 76 65 72 20 31 2E 30 34 20
    53 2F 4E 20 31 32 33 34 35 36 0A 0D`` (a board with firmware 1.04)."""
    board = Board(variant(get_model("VS4-040"), firmware="1.04"), now=0.0)
    board.advance(1.5)
    assert board.status_register(1.5) & INIT == 0
    board.write_vector_register(0xA5, 1.5)
    assert board.read_vector_register(1.5) == 0xA5
    assert board.receive(bytes([0x57]), 1.5) == 1
    assert board.take_bytes() == b""  # one byte of two
    assert board.receive(bytes([0x59]), 1.5) == 1
    expected = bytes.fromhex(
        "0A 0D 56 53 34 2D 30 34 30 20 76 65 72 20 31 2E 30 34 20"
        "53 2F 4E 20 31 32 33 34 35 36 0A 0D"
    )
    assert expected == b"\n\rVS4-040 ver 1.04 S/N 123456\n\r"
    assert board.take_bytes() == expected


def test_x2_rm_of_minus_4050_by_2000_gives_1950() -> None:
    """X2 (§6.7 RM): "An RM2000 command with a position counter of -4050 will return a position
    of 1950"; "This command has no effect on the encoder position register". The counter is
    loaded with LP-4050 (which also loads the encoder register, ER 1:1)."""
    h = Harness("VS4-040")
    h.send("AX LP-4050\r\n")
    h.run()
    assert h.query("RP") == frame("-4050")
    assert h.send("RM2000\r\n") == b""
    h.run()
    assert h.query("RP") == b"\n\r1950\n\r"
    assert h.query("RE") == frame("-4050")


def test_x3_typical_move_string() -> None:
    """X3 (§1.1) ``VL400000 AC500000 MR1000000 GO`` at power-up: no reply; 0.8 s ramps of
    160,000 counts, 1.7 s at 400,000/s, done at 3.3 s at 1,000,000."""
    h = Harness("VS4-040")
    assert h.send("VL400000 AC500000 MR1000000 GO") == b""
    at(h, 0.4)
    assert abs(h.position("X") - 40_000) <= 400
    at(h, 1.0)
    assert h.query("RV") == frame("400000")
    at(h, 3.29)
    assert moving(h, "X")
    at(h, 3.3 + 2 * TICK)
    assert not moving(h, "X")
    assert h.position("X") == 1_000_000
    assert h.errors() == []
