"""Conformance: the PC48 manual's ``Enter:`` examples E1-E55 (chapter 6, §6.4-§6.9).

Numbering follows section 5 of ``shared/reference/pc48-pc46.md``; every example was checked
against the manual text (``shared/seeds/000_438df88d2a6a1670.txt``). Only two of these examples
print a reply (E30 BX, E31 RB); those are asserted byte for byte. For the others the test checks
the state the example's stated purpose implies: positions, velocities, timing, flags, outputs
and queue space.

Timing conventions (brief, design decisions): the PC48 samples 2048 times a second; a move
starts on the first sample tick at or after its GO is executed and is over at the first tick at
or after the analytic end of its §1.3 profile. Power-up defaults: VL 100,000, AC 1,000,000,
linear ramps. Expected times below are worked out from the §1.3 formulas in this file, not read
back from the engine.
"""

from __future__ import annotations

import math

import pytest

from omsd.board.events import CommandErrorEvent, ErrorKind, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import CMD_S, INIT, OVRT

from .support import (
    done_events,
    end_tick,
    enter,
    linear_move_time,
    number,
    numbers,
    soft_stop_bounds,
    tick,
)
from .support import frame as value
from .support import snapshot_physical as physical
from .support import status_frame as status

RATE = 2048  # PC48 sample ticks per second (§1.2, §8.2)
AC0 = 1_000_000.0  # power-up acceleration
VL0 = 100_000.0  # power-up velocity


# -- 6.4 axis specification -----------------------------------------------------------------------


def test_e01_aa_ma_moves_x_and_y_together() -> None:
    """E1 ``AA MA12000,14000; GO``: X and Y start on the same sample tick and reach 12000 and
    14000, each with its own (default) VL/AC, so they finish on different ticks.

    The GO is sent between ticks (t = 0.1 ms) so that "the same tick" is tick 1, not t = 0.
    """
    h = Harness("PC48-4")
    h.until(0.0001)
    assert h.send("AA MA12000,14000; GO") == b""
    h.until(0.0004)  # before tick 1: nothing moves yet
    assert h.query("RV") == value("0,0,0,0")
    h.until(tick(1) + 1 / 4096)  # half a tick after tick 1: v = AC * 1/4096 = 244.1
    assert h.query("RV") == value("244,244,0,0")
    x_end = end_tick(1, linear_move_time(12000))  # 0.22 s
    y_end = end_tick(1, linear_move_time(14000))  # 0.24 s
    assert (x_end, y_end) == (452, 493)
    h.until(tick(x_end - 1))
    assert h.position("X") == 11999
    h.until(tick(x_end))
    assert h.position("X") == 12000
    assert h.position("Y") < 14000
    h.until(tick(y_end - 1))
    assert h.position("Y") == 13999
    h.until(tick(y_end))
    assert h.query("RP") == value("12000,14000,0,0")
    h.run()
    assert h.query("RP") == value("12000,14000,0,0")
    assert h.errors() == []


def test_e02_am_runs_xy_task_and_t_task_independently() -> None:
    """E2 ``AM MR2000,3000; GO MA,,,10000; GO``: an X/Y task and a separate T task.

    All three axes start at once (the T task does not wait for X/Y). To show that the tasks are
    really independent, a second X/Y task is started in AM mode while T is still moving (in AA
    mode it would have to wait for T): it starts at once.
    """
    h = Harness("PC48-4")
    assert h.send("AM MR2000,3000; GO MA,,,10000; GO") == b""
    h.until(1 / 4096)
    assert h.query("RV") == value("244,244,0,244")
    h.until(0.15)  # X (0.089 s) and Y (0.110 s) done, T (0.2 s) still moving
    assert numbers(h.query("RP"))[:3] == [2000, 3000, 0]
    assert h.axis("T").velocity(h.t) > 0
    h.send("MR2000,3000; GO")
    h.until(0.16)
    rv = numbers(h.query("RV"))
    assert rv[0] > 0 and rv[1] > 0 and rv[3] > 0, rv  # new X/Y task runs while T still moves
    h.run()
    assert h.query("RP") == value("4000,6000,0,10000")
    assert h.errors() == []


def test_e03_ax_jg_steps_x_at_5000() -> None:
    """E3 ``AX JG5000;``: X jogs at 5000 steps/s with no GO, ramping at the default AC."""
    h = Harness("PC48-4")
    assert h.send("AX JG5000;") == b""
    h.until(tick(4))
    assert h.query("RV") == value("1953")  # 1e6 * 4/2048 on the way up
    h.until(1.0)
    assert h.query("RV") == value("5000")
    assert h.query("RP") == value("4987")  # 5000 * 1 s - 5000^2 / (2 AC)
    h.until(10.0)
    assert h.query("RV") == value("5000")
    assert h.query("RP") == value("49987")
    assert h.query("AA RP") == value("49987,0,0,0")


def test_e04_ay_ra_reports_y_status() -> None:
    """E4 ``AY RA``: the status of Y (not of X).

    Y starts inside its home window (home switch active, HL default: ``H``), at power-up
    direction P and not done. After a negative move with ID Y reads ``MDNN``; RA resets the done
    flag, so a second RA reads ``MNNN``.
    """
    h = Harness("PC48-4", world={"Y": AxisWorld(start_position=1050)})
    assert h.send("AY RA") == status("PNNH")
    h.send("MR-100 GO ID")
    h.run()
    assert h.send("AY RA") == status("MDNN")
    assert h.send("AY RA") == status("MNNN")
    assert h.send("AX RA") == status("PNNN")


def test_e05_az_vl500_mr2000() -> None:
    """E5 ``AZ VL500 MR2000 GO``: Z peaks at 500 steps/s and ends 2000 steps on; nothing else
    moves. The move lasts 2000/500 + 500/1e6 = 4.0005 s."""
    h = Harness("PC48-4")
    assert h.send("AZ VL500 MR2000 GO") == b""
    h.until(2.0)
    assert h.query("RV") == value("500")
    assert h.query("RP") == value("999")  # 500 * (2 - 0.0005) + 0.125
    h.until(3.9)
    assert h.query("RV") == value("500")
    assert h.query("RP") == value("1949")
    h.until(tick(end_tick(0, linear_move_time(2000, vl=500))))
    assert h.query("RP") == value("2000")
    assert h.query("RV") == value("0")
    assert h.query("AA RP") == value("0,0,2000,0")


def test_e06_at_ma_minus_2468() -> None:
    """E6 ``AT MA-2468; GO``: T ends at -2468 (a triangular move of 0.0994 s), moving M."""
    h = Harness("PC48-4")
    assert h.send("AT MA-2468; GO") == b""
    end = end_tick(0, linear_move_time(2468))
    assert end == 204
    h.until(0.099)
    assert h.query("RP") == value("-2467")
    h.until(tick(end))
    assert h.query("RP") == value("-2468")
    assert h.query("QA") == status("MNNN")
    assert h.query("AA RP") == value("0,0,0,-2468")


def test_e07_au_lp_loads_u_position() -> None:
    """E7 ``AU LP-56789`` (a board with a U axis, PC48-6): the U position register becomes
    -56789 without the motor moving; the other axes are untouched. A following relative move
    counts from the loaded value."""
    h = Harness("PC48-6")
    assert enter(h, "AU LP-56789") == b""
    h.advance(0.01)
    assert h.query("RP") == value("-56789")
    assert physical(h, "U") == 0.0
    assert h.query("AA RP") == value("0,0,0,0,-56789,0")
    h.send("AU MR1000 GO")
    h.run()
    assert h.query("RP") == value("-55789")


def test_e08_av_af_drives_v_aux_low() -> None:
    """E8 ``AV AF`` (PC48-6): the V auxiliary line is driven low; the other aux lines stay on
    (high, their power-up state). V's aux is wired to input 2 so BX can see the line."""
    h = Harness("PC48-6")
    h.board.wire_input_to_aux(2, "V")
    assert h.query("BX") == value("000000")
    assert enter(h, "AV AF") == b""
    h.advance(0.01)
    assert h.axis("V").aux is False
    assert [h.axis(a).aux for a in "XYZTU"] == [True] * 5
    assert h.query("BX") == value("000004")


def test_e09_ar_rq_reports_r_queue() -> None:
    """E9 ``AR RQ`` (8-axis board): R's free queue space, 3 digits.

    At power-up it is 200. Then R is given MR1000 (2 slots) and GO (4) behind an AA WA (0 slots)
    that waits for a long X move: with those 6 slots waiting, RQ on R reads 194; once X is done
    R moves and its queue is free again.
    """
    h = Harness("PC48-8")
    assert h.send("AR RQ") == value("200")
    h.send("AX MR100000 GO AA WA AR MR1000 GO")
    h.until(0.5)
    assert h.send("AR RQ") == value("194")
    assert h.query("RP") == value("0")
    h.run()
    assert h.send("AR RQ") == value("200")
    assert h.query("RP") == value("1000")
    assert h.errors() == []


def test_e10_as_st_stops_only_s() -> None:
    """E10 ``AS ST`` (8-axis board): S decelerates to a stop and its queue is flushed; R, also
    jogging, is unaffected.

    S jogs at 1000 with ``WT5000 MR5000 GO`` queued behind the jog; ST at t = 1 s flushes them,
    so S stays where the 1 ms deceleration leaves it (999.5 + 0.5 = 1000).
    """
    h = Harness("PC48-8")
    h.send("AR JG1000 AS JG1000 WT5000 MR5000 GO")
    h.until(1.0)
    assert h.send("AS ST") == b""
    h.until(2.0)
    assert h.query("AS RV") == value("0")
    assert h.query("AS RP") == value("1000")
    assert h.query("AR RV") == value("1000")
    h.until(10.0)
    assert h.query("AS RP") == value("1000")
    assert h.query("AS RQ") == value("200")
    assert h.query("AR RV") == value("1000")
    assert h.query("AR RP") == value("9999")  # 1000 * 10 - 0.5


# -- 6.5 system control ---------------------------------------------------------------------------


def test_e11_en_turns_echo_on() -> None:
    """E11 ``EN``: afterwards every character is echoed and a command error also prints an
    English message (design: ``<LF><CR><message>: <command><LF><CR>``). EN itself is consumed
    while echo is still off, so it produces nothing."""
    h = Harness("PC48-4")
    assert h.query("RP") == value("0")
    assert h.send("EN") == b""
    assert h.query("RP") == b"RP" + value("0")
    assert h.query("AX RP") == b"AX RP" + value("0")
    assert h.send("XQ ") == b"XQ" + value("Unrecognized command: XQ") + b" "
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "XQ")]


def test_e12_ef_turns_echo_off() -> None:
    """E12 ``EF``: with echo on, the two letters of EF are still echoed (they are consumed
    before EF takes effect); afterwards nothing is echoed and errors print no text (the error
    flag is still set)."""
    h = Harness("PC48-4")
    h.send("EN")
    assert h.query("RP") == b"RP" + value("0")
    assert h.send("EF") == b"EF"
    assert h.query("RP") == value("0")
    assert h.send("XQ ") == b""
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "XQ")]
    assert h.board.read_status_register(h.t) & CMD_S


E13_WORLD = {"X": AxisWorld(home_low=50_000, home_high=50_100)}


def _e13_run(text: str) -> tuple[Harness, list[CommandErrorEvent]]:
    """Run the E13 homing input on X with a normally open home switch at 50000..50100.

    With HH on a normally open switch the home input is true *outside* the window, so the fast
    HM pass sees its false->true edge where the stage leaves the switch at 50100 ("moved through
    home at high speed"); the slow HL HR pass then finds the same edge from the other side.
    """
    h = Harness("PC48-4", world=E13_WORLD)
    assert h.send(text) == b""
    errors = h.errors()
    # first pass: +20000 steps/s (ramp 0.02 s, 200 steps), edge at 50100 at t = 2.515 s
    h.until(1.0)
    assert h.query("RV") == value("20000")
    assert h.query("RP") == value("19800")
    # the counter is loaded with 0 at the edge, then X decelerates (200 steps, to t = 2.535 s)
    # and the HR0 pass starts back at -1000 steps/s
    h.until(2.6)
    assert h.query("RV") == value("-1000")
    rp = number(h.query("RP"))
    assert 130 <= rp <= 140, rp  # about 200 - 1000 * (2.6 - 2.536)
    h.run()
    return h, errors


def _e13_check_final(h: Harness) -> None:
    # HR0 loads 0 at the first tick after crossing 50100 going down (at most 1000/2048 step
    # past it), then stops in 0.5 step: the counter reads 0 or -1 and counter 0 is at the edge.
    assert h.query("RV") == value("0")
    assert h.query("RP") in (value("0"), value("-1"))
    offset = physical(h, "X") - h.position("X")
    assert 50_099.0 <= offset <= 50_100.0, offset
    assert h.axis("X").home_high is False  # HL restored


def test_e13_hh_hm0_then_hl_hr0_two_pass_home() -> None:
    """E13 as intended, ``AX VL20000 HH HM0`` / ``VL1000 HL HR0``: a fast pass through home with
    HH, then a slow reverse pass with HL that loads 0 at the home edge.

    The manual prints ``HMO`` (letter O); this test uses the intended HM0 (digest §8.3 #27).
    """
    h, errors = _e13_run("AX VL20000 HH HM0\r VL1000 HL HR0\r")
    assert errors == []
    _e13_check_final(h)


def test_e13_literal_hmo_typo_is_a_command_error() -> None:
    """E13 as printed, ``AX VL20000 HH HMO`` / ``VL1000 HL HR0``: HM's operand ends at the
    letter O, so HM runs with its default parameter ("The parameter defaults to zero if none is
    supplied") and the stray ``O`` (followed by the line end) is one command error. The homing
    sequence is otherwise exactly the intended one."""
    h, errors = _e13_run("AX VL20000 HH HMO\r VL1000 HL HR0\r")
    # "O" starts no command; the lexer reports a one-letter bad word with the character that
    # ended it, here the CR
    assert [(e.kind, e.command) for e in errors] == [(ErrorKind.UNKNOWN_COMMAND, "O<0D>")]
    assert h.board.read_status_register(h.t) & CMD_S
    _e13_check_final(h)


def test_e14_ay_lf_ignores_y_limits() -> None:
    """E14 ``AY LF``: Y runs through its +limit switch (at 5000) to 10000; X, with the same
    switch and limits on, is stopped by it."""
    world = {a: AxisWorld(positive_limit=5000) for a in "XY"}
    h = Harness("PC48-4", world=world)
    h.send("AY LF")
    h.send("AX MR10000 GO AY MR10000 GO")
    h.run()
    assert h.query("AY RP") == value("10000")
    x = number(h.query("AX RP"))
    assert 5000 <= x <= 5000 + 100_000 / RATE + 1, x
    limits = [e for e in h.events() if isinstance(e, LimitEvent)]
    assert [(e.axis, e.direction) for e in limits] == [("X", 1)]


def test_e15_at_ln_restores_t_limits() -> None:
    """E15 ``AT LN`` (after an ``AT LF``): T stops at once at its +limit (3000), the limit is
    flagged (OVRT, LimitEvent) and T's queue is flushed, so the MR-500 queued behind never
    runs. Stopping at the first tick at or after the switch allows 77,900/2048 < 39 steps."""
    h = Harness("PC48-4", world={"T": AxisWorld(positive_limit=3000)})
    h.send("AT LF")
    assert h.send("AT LN") == b""
    h.send("MR10000 GO MR-500 GO")
    h.run()
    t = number(h.query("RP"))
    assert 3000 <= t <= 3039, t
    assert h.query("RV") == value("0")
    assert h.query("RQ") == value("200")
    limits = [e for e in h.events() if isinstance(e, LimitEvent)]
    assert [(e.axis, e.direction) for e in limits] == [("T", 1)]
    assert h.board.read_status_register(h.t) & OVRT


def test_e16_ax_sl_ramps_down_at_limit_for_all_axes() -> None:
    """E16 ``AX SL``: at the +limit (3000) X ramps down at AC instead of stopping, ending near
    6000; the queue is not flushed ("except for the current move"), so the MR-1000 behind runs.
    SL "affects all axes simultaneously": Y, never addressed by SL, also ramps down."""
    world = {a: AxisWorld(positive_limit=3000) for a in "XY"}
    h = Harness("PC48-4", world=world)
    assert h.send("AX SL") == b""
    h.send("MR10000 GO MR-1000 GO AY MR10000 GO")
    lo, hi = soft_stop_bounds(3000, AC0, RATE)
    h.until(0.3)  # both have ramped down by 0.078 + 0.078 s; X's MR-1000 is running
    y = number(h.query("AY RP"))
    assert lo - 1 <= y <= hi + 1, (y, lo, hi)
    h.run()
    x = number(h.query("AX RP"))
    assert lo - 1 - 1000 <= x <= hi + 1 - 1000, (x, lo, hi)
    assert number(h.query("AY RP")) == y
    limits = [e for e in h.events() if isinstance(e, LimitEvent)]
    assert sorted((e.axis, e.direction) for e in limits) == [("X", 1), ("Y", 1)]


def test_e17_ax_sf_restores_hard_limits() -> None:
    """E17 ``AX SF`` (after ``AX SL``): X stops immediately at its +limit (3000) again and its
    queue is flushed (the MR-500 behind never runs)."""
    h = Harness("PC48-4", world={"X": AxisWorld(positive_limit=3000)})
    h.send("AX SL")
    assert h.send("AX SF") == b""
    h.send("MR10000 GO MR-500 GO")
    h.run()
    x = number(h.query("RP"))
    assert 3000 <= x <= 3039, x
    assert h.query("RQ") == value("200")
    assert h.board.read_status_register(h.t) & OVRT


def test_e18_cn_selects_cosine_ramps_for_all_axes() -> None:
    """E18 ``CN``: cosine ramps on every axis (shown on Y although CN is entered in AX mode).

    §1.3: v = Vp/2 (1 - cos(2 Am t / Vp)); ramp time pi Vp / (2 Am) = 0.157 s over
    pi Vp^2 / (4 Am) = 7854 steps; MR100000 takes 1.1571 s (linear: 1.1 s). Stopped, RC is the
    acceleration at the start of a ramp: 0 for a cosine ramp (design decision).
    """
    h = Harness("PC48-4")
    assert h.send("CN") == b""
    assert h.query("AY RC") == value("0")
    h.send("MR100000 GO")
    h.until(0.0625)
    expected = 50_000 * (1 - math.cos(2 * AC0 * 0.0625 / VL0))  # 34233.9 (linear: 62500)
    assert abs(number(h.query("RV")) - expected) <= 1
    ramp_t = math.pi * VL0 / (2 * AC0)
    ramp_s = math.pi * VL0 * VL0 / (4 * AC0)
    total = 2 * ramp_t + (100_000 - 2 * ramp_s) / VL0
    h.until(1.15)
    assert h.position("Y") < 100_000
    h.until(tick(end_tick(0, total)))
    assert h.query("RP") == value("100000")


def test_e19_pn10_selects_smoothest_parabolic_ramp() -> None:
    """E19 ``PN10;``: parabolic ramps, a = A0 (1 - t/T2) with t/T2 = 10/10 at the end of the
    ramp (design decision; the manual's "10% acceleration at the peak" contradicts its own §1.3
    formula, digest §8.3 #20). So T2 = 2 VL/AC = 0.2 s, ramp distance AC T2^2 / 3 = 13333 steps,
    MR100000 takes 1.1333 s. RC is AC when stopped and 0 (end-of-ramp value) at cruise.
    """
    h = Harness("PC48-4")
    assert h.send("PN10;") == b""
    assert h.query("RC") == value("1000000")
    h.send("MR100000 GO")
    h.until(0.125)
    t2 = 2 * VL0 / AC0
    assert abs(number(h.query("RV")) - (AC0 * 0.125 - AC0 * 0.125**2 / (2 * t2))) <= 1  # 85937
    assert abs(number(h.query("RC")) - AC0 * (1 - 0.125 / t2)) <= 1  # 375000
    h.until(0.5)
    assert h.query("RV") == value("100000")
    assert h.query("RC") == value("0")
    total = 2 * t2 + (100_000 - 2 * AC0 * t2 * t2 / 3) / VL0
    h.until(1.12)
    assert h.position("X") < 100_000
    h.until(tick(end_tick(0, total)))
    assert h.query("RP") == value("100000")


@pytest.mark.parametrize("mode", ["CN", "PN10"])
def test_e20_pf_returns_to_linear_ramps(mode: str) -> None:
    """E20 ``PF``: after CN or PN, linear ramps again: RC (stopped) is AC, v = AC t while
    ramping, and MR100000 ends after 1.1 s."""
    h = Harness("PC48-4")
    h.send(mode)
    assert h.send("PF") == b""
    assert h.query("RC") == value("1000000")
    h.send("MR100000 GO")
    h.until(0.0625)
    assert h.query("RV") == value("62500")
    end = end_tick(0, linear_move_time(100_000))
    h.until(tick(end - 1))
    assert h.position("X") < 100_000
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e21_rs_resets_everything() -> None:
    """E21 ``RS``: all movement stops, queues, modes, parameters and registers go back to the
    power-up state, interrupts are disabled and the INIT status bit is high while the board
    initializes.

    Before RS: X jogging at 20000 with AC 200000 and a queued move, Y aux low, output 10 low, a
    done flag set, Z's counter loaded, parabolic ramps, echo on, AA mode, interrupts enabled.
    The position counters after RS are taken to be 0, as at power-up (not stated by the manual;
    the digest infers it, §8.1, from the driver text where RP returns 0).
    """
    h = Harness("PC48-4")
    h.send("AZ LP777 AY AF ID BL10 AX AC200000 JG20000 MR5000 GO PN5 EN")
    h.board.write_control_register(0xF0, h.t)
    h.until(0.5)
    h.send("AA")
    assert h.board.registers.done != 0
    h.send("RS")
    assert h.board.status_register(h.t) & INIT
    h.advance(0.2)
    assert not h.board.status_register(h.t) & INIT
    here = physical(h, "X")
    assert h.query("RP") == value("0")  # AX mode, echo off, counter 0
    assert h.query("RV") == value("0")
    assert h.query("RC") == value("1000000")  # default AC and linear ramps
    assert h.query("RQ") == value("200")
    assert h.query("BX") == value("000000")
    assert h.query("AA RP") == value("0,0,0,0")
    assert h.query("RQ") == value("200,200,200,200")
    assert [h.axis(a).aux for a in "XYZT"] == [True] * 4
    assert [h.axis(a).vl for a in "XYZT"] == [VL0] * 4
    assert h.board.outputs_low == 0
    assert h.board.registers.done == 0
    assert h.board.read_control_register(h.t) == 0
    h.advance(2.0)
    assert physical(h, "X") == here  # nothing moves any more
    assert h.errors() == []


# -- 6.6 user I/O ---------------------------------------------------------------------------------


def test_e22_ay_an_turns_y_aux_on() -> None:
    """E22 ``AY AN`` (after ``AY AF``): Y's aux line goes high again (seen on input 1, wired
    to it)."""
    h = Harness("PC48-4")
    h.board.wire_input_to_aux(1, "Y")
    enter(h, "AY AF")
    assert h.query("BX") == value("000002")
    assert enter(h, "AY AN") == b""
    assert h.axis("Y").aux is True
    assert h.query("BX") == value("000000")


def test_e23_aa_an_turns_x_and_z_aux_on() -> None:
    """E23 ``AA AN1,,1;``: X and Z aux on, Y (skipped) and T (not given) unchanged. The values
    are place holders only, so ``AN0,,0;`` does the same."""
    for text in ("AA AN1,,1;", "AA AN0,,0;"):
        h = Harness("PC48-4")
        h.send("AA AF1,1,1,1;")
        assert [h.axis(a).aux for a in "XYZT"] == [False] * 4
        assert h.send(text) == b""
        assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, False], text
        assert h.errors() == []


def test_e24_ay_af_turns_y_aux_off() -> None:
    """E24 ``AY AF``: Y's aux line is driven low, the others stay high."""
    h = Harness("PC48-4")
    h.board.wire_input_to_aux(1, "Y")
    assert enter(h, "AY AF") == b""
    assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, True]
    assert h.query("BX") == value("000002")


def test_e25_aa_af_turns_x_and_z_aux_off() -> None:
    """E25 ``AA AF1,,1;``: X and Z aux low, Y and T unchanged (high)."""
    h = Harness("PC48-4")
    assert h.send("AA AF1,,1;") == b""
    assert [h.axis(a).aux for a in "XYZT"] == [False, True, False, True]
    assert h.errors() == []


def test_e26_aa_pa_switches_y_on_and_t_off_during_moves() -> None:
    """E26 ``AA PA,0,,1;``: at each GO Y's aux goes on (parameter 0) and T's goes off
    (non-zero) for the move, complemented after it; X and Z are not in PA mode.

    PA also costs 2 extra slots per GO on the PA axes (§6.6): with a move running, queuing
    ``MR1000,1000,,1000; GO`` takes MR 2 + AA GO 5 (Table A; Table B only on an encoder
    version) (+2 on Y and T): 7, 9, 5, 9 slots.
    """
    h = Harness("PC48-4")
    assert h.send("AA PA,0,,1;") == b""
    h.send("MR1000,1000,,1000; GO")  # 1000 steps: 0.063 s
    h.until(0.03)
    assert [h.axis(a).aux for a in "XYZT"] == [True, True, True, False]
    before = numbers(h.query("RQ"))
    h.send("MR1000,1000,,1000; GO")
    after = numbers(h.query("RQ"))
    assert [b - a for b, a in zip(before, after, strict=True)] == [7, 9, 5, 9]
    h.until(0.1)  # first move over, second one running
    assert h.query("RP") != value("1000,1000,0,1000")
    assert [h.axis(a).aux for a in "XYZT"] == [True, True, True, False]
    h.run()
    assert h.query("RP") == value("2000,2000,0,2000")
    assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, True]


def test_e27_az_pa_se500_keeps_aux_on_500ms_after_move() -> None:
    """E27 ``AZ PA SE500;``: Z's aux goes on with a move and stays on 500 ms after it ends.

    A ``MR1000 GO`` is added to see it: it lasts 2 sqrt(1000/AC) = 0.0632 s, over at tick 130
    (0.0635 s), so the aux goes off at 0.5635 s. Queue: such a GO costs 4 + 2 (PA) + 3 (SE).
    """
    h = Harness("PC48-4")
    assert h.send("AZ PA SE500;") == b""
    h.send("WT1000")  # hold the queue so the GO's cost can be seen
    before = number(h.query("RQ"))
    h.send("MR1000 GO")
    assert before - number(h.query("RQ")) == 2 + 4 + 2 + 3
    h.until(1.0)  # WT over at 1.0: the move starts
    h.until(1.03)
    assert h.axis("Z").aux is True
    end = 1.0 + tick(end_tick(0, linear_move_time(1000)))
    h.until(end + 0.3)
    assert h.query("RP") == value("1000")
    assert h.axis("Z").aux is True
    h.until(end + 0.49)
    assert h.axis("Z").aux is True
    h.until(end + 0.51)
    assert h.axis("Z").aux is False


def test_e28_bl10_bl12_after_move() -> None:
    """E28 ``AX MA1000 GO BL10; BL12;``: outputs 10 and 12 go low only when the X move (0.0632
    s, over at tick 130) has ended."""
    h = Harness("PC48-4")
    assert h.send("AX MA1000 GO BL10; BL12;") == b""
    assert h.board.outputs_low == 0
    h.until(0.05)
    assert h.query("BX") == value("000000")
    end = end_tick(0, linear_move_time(1000))
    assert end == 130
    h.until(tick(end - 1))
    assert h.board.outputs_low == 0
    assert h.position("X") < 1000
    h.until(tick(end))
    assert h.position("X") == 1000
    assert h.board.outputs_low == (1 << 10) | (1 << 12)
    assert h.query("BX") == value("001400")
    assert h.errors() == []


def test_e29_bh8_bh11_set_bits_high() -> None:
    """E29 ``BH8; BH11;`` (after BL8 BL9 BL11): bits 8 and 11 go high; 9 stays low."""
    h = Harness("PC48-4")
    h.send("BL8; BL9; BL11;")
    assert h.query("BX") == value("000B00")
    assert h.send("BH8; BH11;") == b""
    assert h.board.outputs_low == 1 << 9
    assert h.query("BX") == value("000200")
    assert h.errors() == []


def test_e30_bx_reports_low_bits() -> None:
    """E30 ``BX`` with outputs 10 and 12 on (low) and inputs 0 and 3 held low: the manual's
    ``<LF><CR>001409<LF><CR>``."""
    h = Harness("PC48-4")
    h.send("BL10; BL12;")
    h.board.set_input(0, False, h.t)
    h.board.set_input(3, False, h.t)
    assert h.send("BX") == b"\n\r001409\n\r"


def test_e31_rb_reports_factory_directions() -> None:
    """E31 ``RB``: bits 0-7 inputs, 8-13 outputs: ``<LF><CR>003F00<LF><CR>``. RB is queued
    (1 slot), so behind a move the reply comes when the queue reaches it."""
    h = Harness("PC48-4")
    assert h.send("RB") == b"\n\r003F00\n\r"
    assert h.send("MR1000 GO RB") == b""
    h.until(0.05)
    assert h.advance(0) == b""
    assert h.until(tick(end_tick(0, linear_move_time(1000)))) == b"\n\r003F00\n\r"


# -- 6.7 move specification -----------------------------------------------------------------------


def test_e32_ay_ac200000() -> None:
    """E32 ``AY AC200000``: Y accelerates at 200,000 (RC when stopped: the AC); X keeps 1e6."""
    h = Harness("PC48-4")
    assert enter(h, "AY AC200000") == b""
    assert h.query("RC") == value("200000")
    assert h.query("AX RC") == value("1000000")
    h.send("AY MR10000 GO")
    h.until(0.125)
    assert h.query("RV") == value("25000")
    end = end_tick(0, linear_move_time(10_000, ac=200_000))  # 0.447 s
    h.until(tick(end - 1))
    assert h.position("Y") < 10_000
    h.until(tick(end))
    assert h.query("RP") == value("10000")


def test_e33_aa_ac_sets_x_and_z() -> None:
    """E33 ``AA AC200000,,50000;``: X 200,000, Z 50,000, Y and T keep 1,000,000."""
    h = Harness("PC48-4")
    assert h.send("AA AC200000,,50000;") == b""
    assert h.query("RC") == value("200000,1000000,50000,1000000")


def test_e34_ax_vl10000() -> None:
    """E34 ``AX VL10000``: X's peak velocity is 10,000 steps/s (the manual's "counts per second
    per second" is a slip for counts/s, digest §8.3 #22). MR100000 then takes 10.01 s."""
    h = Harness("PC48-4")
    assert enter(h, "AX VL10000") == b""
    h.send("MR100000 GO")
    h.until(5.0)
    assert h.query("RV") == value("10000")
    h.until(10.0)
    assert h.position("X") < 100_000
    h.until(tick(end_tick(0, linear_move_time(100_000, vl=10_000))))
    assert h.query("RP") == value("100000")


def test_e35_aa_vl_sets_x_and_t() -> None:
    """E35 ``AA VL5000,,,50000;``: X cruises at 5000, T at 50000, Y and Z keep 100,000."""
    h = Harness("PC48-4")
    assert h.send("AA VL5000,,,50000;") == b""
    h.send("MR100000,100000,100000,100000; GO")
    h.until(0.5)
    assert h.query("RV") == value("5000,100000,100000,50000")


def test_e36_ay_vb200() -> None:
    """E36 ``AY VB200``: Y's ramp starts by jumping to 200 steps/s; X (no VB) starts from 0.
    Half a tick after the start: X 1e6/4096 = 244, Y 200 + 244 = 444."""
    h = Harness("PC48-4")
    assert enter(h, "AY VB200") == b""
    h.send("MR10000 GO AX MR10000 GO")
    h.until(1 / 4096)
    assert h.query("AA RV") == value("244,444,0,0")
    h.run()
    assert h.query("RP") == value("10000,10000,0,0")


def test_e37_aa_vb200_200() -> None:
    """E37 ``AA VB200,200;``: X and Y start their ramps at 200 steps/s, Z from 0."""
    h = Harness("PC48-4")
    assert h.send("AA VB200,200;") == b""
    h.send("MR10000,10000,10000; GO")
    h.until(1 / 4096)
    assert h.query("RV") == value("444,444,244,0")
    h.run()
    assert h.query("RP") == value("10000,10000,10000,0")


def test_e38_ax_lp1000() -> None:
    """E38 ``AX LP1000``: X's position register reads 1000 and the motor does not move; MA0 then
    moves the stage 1000 steps back."""
    h = Harness("PC48-4")
    assert enter(h, "AX LP1000") == b""
    h.advance(0.01)
    assert h.query("RP") == value("1000")
    assert physical(h, "X") == 0.0
    h.send("MA0 GO")
    h.run()
    assert h.query("RP") == value("0")
    assert physical(h, "X") == -1000.0


def test_e39_ay_er3_2_lp30000_on_encoder_model() -> None:
    """E39 ``AY ER3,2 LP30000`` (PC48-4E): encoder register 30,000, position counter 20,000.

    The manual says "the parameter times the encoder ratio" goes into the position counter but
    its example gives 20,000, i.e. multiplied by motor/encoder counts (digest §8.3 #43): the
    example's numbers are used. With ER set, distances are in encoder counts: MR3000 moves
    3000 encoder counts = 2000 steps.
    """
    h = Harness("PC48-4E")
    assert enter(h, "AY ER3,2 LP30000") == b""
    h.advance(0.01)
    assert h.query("RE") == value("30000")
    assert h.query("RP") == value("20000")
    h.send("MR3000 GO")
    h.run()
    assert h.query("RE") == value("33000")
    assert h.query("RP") == value("22000")
    assert h.errors() == []


def test_e40_ax_ma100000_with_previous_parameters() -> None:
    """E40 ``AX MA100000 GO`` with previously entered VL50000 AC250000: ramps of 0.2 s, 2.2 s
    in all (over at tick 4506)."""
    h = Harness("PC48-4")
    enter(h, "AX VL50000 AC250000")
    assert h.send("AX MA100000 GO") == b""
    h.until(1.0)
    assert h.query("RV") == value("50000")
    end = end_tick(0, linear_move_time(100_000, vl=50_000, ac=250_000))
    assert end == 4506
    h.until(tick(end - 1))
    assert h.query("RP") == value("99999")
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e41_aa_ma_moves_y_and_t_only() -> None:
    """E41 ``AA MA,10000,,1000; GO``: Y to 10000, T to 1000; X and Z (at 777 and -333, loaded
    beforehand) stay where they are."""
    h = Harness("PC48-4")
    h.send("AX LP777 AZ LP-333")
    assert h.send("AA MA,10000,,1000; GO") == b""
    h.until(0.05)
    rv = numbers(h.query("RV"))
    assert rv[0] == 0 and rv[2] == 0 and rv[1] > 0 and rv[3] > 0, rv
    h.run()
    assert h.query("RP") == value("777,10000,-333,1000")


def test_e42_ax_mr_minus_2468() -> None:
    """E42 ``AX MR-2468 GO`` from 1000: X ends at -1468, last moving negative."""
    h = Harness("PC48-4")
    enter(h, "AX LP1000")
    assert h.send("AX MR-2468 GO") == b""
    h.run()
    assert h.query("RP") == value("-1468")
    assert h.query("QA") == status("MNNN")


def test_e43_aa_mr_starts_x_and_y_together() -> None:
    """E43 ``AA MR12345,6789; GO``: both start on the same tick (tick 1: GO sent at 0.1 ms) and
    finish on their own: Y (triangle, 0.165 s) well before X (0.223 s)."""
    h = Harness("PC48-4")
    h.until(0.0001)
    assert h.send("AA MR12345,6789; GO") == b""
    h.until(0.0004)
    assert h.query("RV") == value("0,0,0,0")
    h.until(tick(1) + 1 / 4096)
    assert h.query("RV") == value("244,244,0,0")
    x_end = end_tick(1, linear_move_time(12345))
    y_end = end_tick(1, linear_move_time(6789))
    assert (x_end, y_end) == (459, 339)
    h.until(tick(y_end))
    assert h.position("Y") == 6789
    assert h.position("X") < 12345
    h.until(tick(x_end - 1))
    assert h.position("X") < 12345
    h.until(tick(x_end))
    assert h.query("RP") == value("12345,6789,0,0")


def test_e44_aa_ml_interpolates_y_z_t() -> None:
    """E44 ``AA ML,10000,100,1000; GO``: Y, Z and T move 10000, 100 and 1000 along a straight
    line, starting and finishing together; X stays.

    Y sets the pace (triangle of 0.2 s); Z and T are scaled, so at every instant they have done
    the same fraction of their moves: at 0.125 s, 71.875 %. All end at tick 410."""
    h = Harness("PC48-4")
    assert h.send("AA ML,10000,100,1000; GO") == b""
    h.until(1 / 4096)
    assert h.query("RV") == value("0,244,2,24")
    h.until(0.125)
    assert h.query("RP") == value("0,7187,71,718")
    end = end_tick(0, linear_move_time(10_000))
    assert end == 410
    h.until(tick(end - 1))
    assert h.query("RP") == value("0,9999,99,999")
    h.until(tick(end))
    assert h.query("RP") == value("0,10000,100,1000")


def test_e45_aa_mt_moves_x_y_t_to_absolute_positions() -> None:
    """E45 ``AA MT1000,10000,,100; GO``: X, Y and T go to 1000, 10000 and 100 along a straight
    line, together; Z (loaded with -50) stays. X starts from 400 (LP) to show the target is
    absolute: it travels 600 steps, 6 % of Y's distance."""
    h = Harness("PC48-4")
    h.send("AX LP400 AZ LP-50")
    assert h.send("AA MT1000,10000,,100; GO") == b""
    h.until(0.125)  # 71.875 % of the way
    assert h.query("RP") == value("831,7187,-50,71")
    end = end_tick(0, linear_move_time(10_000))
    h.until(tick(end - 1))
    assert h.query("RP") == value("999,9999,-50,99")
    h.until(tick(end))
    assert h.query("RP") == value("1000,10000,-50,100")


def test_e46_az_mm_mo_moves_one_pulse_negative() -> None:
    """E46 ``AZ MM MO`` (open-loop board): one step in the negative direction within one sample
    interval, with no GO."""
    h = Harness("PC48-4")
    assert h.send("AZ MM MO") == b""
    h.until(tick(1))
    assert h.query("RP") == value("-1")
    h.run()
    assert h.query("RP") == value("-1")
    assert h.query("QA") == status("MNNN")
    assert h.query("AA RP") == value("0,0,-1,0")
    assert h.errors() == []


def test_e46_mo_is_not_available_on_encoder_models() -> None:
    """E46 on a PC48-4E: "This command is not available in models with an encoder option." MO
    is a command error and Z does not move."""
    h = Harness("PC48-4E")
    h.send("AZ MM MO")
    h.run()
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.ENCODER_MODEL, "MO")]
    assert h.query("RP") == value("0")


# -- 6.8 move execution ---------------------------------------------------------------------------


def test_e47_ax_ma12345_go() -> None:
    """E47 ``AX MA12345 GO``: X reaches 12345 at tick 458 (0.22345 s)."""
    h = Harness("PC48-4")
    assert h.send("AX MA12345 GO") == b""
    end = end_tick(0, linear_move_time(12345))
    assert end == 458
    h.until(tick(end - 1))
    assert h.query("RP") == value("12344")
    h.until(tick(end))
    assert h.query("RP") == value("12345")


def test_e48_aa_mr_opposite_directions() -> None:
    """E48 ``AA MR2468,-2468; GO``: X +2468 and Y -2468, mirror images of each other."""
    h = Harness("PC48-4")
    assert h.send("AA MR2468,-2468; GO") == b""
    h.until(0.03125)
    assert h.query("RV") == value("31250,-31250,0,0")
    h.run()
    assert h.query("RP") == value("2468,-2468,0,0")
    assert h.query("QI") == status("PNNN,MNNN,PNNN,PNNN")


def test_e49_gd_resets_done_between_two_moves() -> None:
    """E49 ``AY MR-12345 GO ID MR12345 GD ID``: done is flagged at the end of each move (two
    done interrupts); GD clears the first flag as the second move starts, so during the second
    move Y is not done and the done register is clear. Each move takes 458 ticks."""
    h = Harness("PC48-4")
    assert h.send("AY MR-12345 GO ID MR12345 GD ID") == b""
    h.until(0.2)
    assert number(h.query("RP")) < -10_000
    h.until(0.3)
    assert h.query("QA") == status("PNNN")
    assert h.board.registers.done == 0
    h.run()
    assert h.query("RP") == value("0")
    assert h.query("QA") == status("PDNN")
    events = done_events(h)
    assert [(e.time, e.done_register) for e in events] == [(tick(458), 0b10), (tick(916), 0b10)]
    assert h.board.read_done_register(h.t) == 0b10


def test_e50_aa_mt_go_id_ml_gd_id() -> None:
    """E50 ``AA MT10000,20000; GO ID ML-10000,-20000; GD ID``: a linear move to (10000, 20000)
    flagged done, then GD clears every done flag and a linear move back to (0, 0) is flagged
    done again. Each move is paced by Y (20000 steps, 0.3 s, 615 ticks). In AA mode the ID sets
    the done bit of every axis as it reaches it, DON_S once all have: Z and T, which do
    not move, are done again as soon as GD has cleared them, X and Y at the end."""
    h = Harness("PC48-4")
    assert h.send("AA MT10000,20000; GO ID ML-10000,-20000; GD ID") == b""
    end = end_tick(0, linear_move_time(20_000))
    assert end == 615
    h.until(tick(end))
    assert h.query("RP") == value("10000,20000,0,0")
    h.until(0.45)  # Z and T, not moving, pass the second ID as soon as GD has cleared them
    assert h.query("QI") == status("MNNN,MNNN,PDNN,PDNN")
    assert h.board.registers.done == 0b1100
    h.run()
    assert h.query("RP") == value("0,0,0,0")
    assert h.query("QI") == status("MDNN,MDNN,PDNN,PDNN")
    events = done_events(h)
    assert [(e.time, e.done_register) for e in events] == [(tick(615), 0xF), (tick(1230), 0xF)]


def test_e51_jg_then_slower_jg_then_st() -> None:
    """E51 ``JG100000 JG35000 ST``: jog at 100,000, change to 35,000 "when the second JG is
    entered", then decelerate to a stop.

    The commands are entered one at a time (t = 0, 1, 2 s), as the example's wording implies:
    sent in one burst, ST ("executed immediately", flushing the queue) would cancel the jogs
    before they had begun. Position: 95000 at 1 s, + 4387.5 (slowing) + 32725 (cruise) at 2 s,
    + 612.5 (stop, 35 ms) = 132725. JG also sets VL.
    """
    h = Harness("PC48-4")
    assert enter(h, "JG100000") == b""
    h.until(0.5)
    assert h.query("RV") == value("100000")
    h.until(1.0)
    assert enter(h, "JG35000") == b""
    h.until(1.03125)
    assert h.query("RV") == value("68750")
    h.until(1.5)
    assert h.query("RV") == value("35000")
    h.until(2.0)
    assert h.send("ST") == b""
    h.until(2.03)
    assert number(h.query("RV")) > 0
    h.until(tick(end_tick(round(2.0 * RATE), 35_000 / AC0)))
    assert h.query("RV") == value("0")
    assert h.query("RP") == value("132725")
    h.advance(5.0)
    assert h.query("RP") == value("132725")
    assert h.axis("X").vl == 35_000


def test_e52_ay_jf_fractional_jog() -> None:
    """E52 ``AY JF2.667``: Y jogs at 2.667 steps/s, fraction kept (800 steps in 300 s, not 600),
    RV shows only the integer part, and 2.667 becomes the default velocity."""
    h = Harness("PC48-4")
    assert enter(h, "AY JF2.667") == b""
    h.until(30.0)
    assert h.query("RV") == value("2")
    assert h.query("RP") == value("80")
    h.until(300.0)
    assert h.query("RP") == value("800")
    assert h.axis("Y").vl == pytest.approx(2.667)
    assert h.errors() == []


def test_e53_vs_velocity_staircase() -> None:
    """E53 ``AX VS1024,-1000,1000; ... VS1,0,0;``: X and Y follow the staircase 1000, 2000,
    3000, 2000, 1000 steps/s (X negative, Y positive), each step 1024/1024 s long, then 0 after
    one more 1/1024 s interval.

    VS time is in "1/1024 second sample intervals" although the PC48 samples 2048/s (digest
    §8.3 #2): the VS text and the example ("each step last 1 second") agree on 1/1024 s. The
    example chains six VS commands although VS "cannot be mixed or queued with other commands"
    (§8.3 #16): chaining VS with VS is taken to be allowed.
    """
    h = Harness("PC48-4")
    text = (
        "AX VS1024,-1000,1000; VS1024,-2000,2000; VS1024,-3000,3000;\r"
        "VS1024,-2000,2000; VS1024,-1000,1000; VS1,0,0;"
    )
    assert h.send(text) == b""
    assert h.send("AA") == b""
    steps = [1000, 2000, 3000, 2000, 1000]
    position = 0
    for k, v in enumerate(steps):
        h.until(k + 0.5)
        assert h.query("RV") == value(f"{-v},{v},0,0"), k
        h.until(k + 1 - 1 / 2048)  # last half interval of the step
        assert h.query("RV") == value(f"{-v},{v},0,0"), k
        position += v
        h.until(k + 1)
        assert h.query("RP") == value(f"{-position},{position},0,0"), k
        if k + 1 < len(steps):
            h.until(k + 1 + 1 / 2048)  # first half interval of the next step
            w = steps[k + 1]
            assert h.query("RV") == value(f"{-w},{w},0,0"), k
    h.until(5 + 1 / 2048)  # inside the final 1/1024 s interval at 0
    assert h.query("RV") == value("0,0,0,0")
    h.until(5 + 1 / 1024)
    assert h.query("RP") == value("-9000,9000,0,0")
    h.until(10.0)
    assert h.query("RP") == value("-9000,9000,0,0")
    assert h.query("RQ") == value("200,200,200,200")
    assert h.errors() == []


# -- 6.9 move termination -------------------------------------------------------------------------


def test_e54_ay_jg1200_then_st_ramps_to_stop() -> None:
    """E54 ``AY JG1200 (wait awhile) ST``: Y jogs at 1200, ST decelerates it at its AC.

    Y's AC is set to 10,000 beforehand so the ramps show (0.12 s, 72 steps each), and
    ``WT3000 MR-1000 GO`` is queued behind the jog to show ST flushes Y's queue. "Awhile" is
    2 s: Y stops at 1200 * 2 = 2400 steps at 2.12 s and stays there.
    """
    h = Harness("PC48-4")
    enter(h, "AY AC10000")
    assert h.send("AY JG1200 WT3000 MR-1000 GO") == b""
    h.until(1.0)
    assert h.query("RV") == value("1200")
    h.until(2.0)
    assert h.send("ST") == b""
    h.until(2.0625)
    assert h.query("RV") == value("575")
    h.until(2.11)
    assert number(h.query("RV")) > 0
    h.until(tick(end_tick(round(2.0 * RATE), 1200 / 10_000)))
    assert h.query("RV") == value("0")
    assert h.query("RP") == value("2400")
    h.until(10.0)
    assert h.query("RP") == value("2400")
    assert h.query("RQ") == value("200")


def test_e55_sa_stops_all_eight_axes() -> None:
    """E55 ``AA VL100,...(9 values); MR1000,2000,...,8000; GO (wait awhile) SA`` (PC48-8).

    The VL list has nine values for eight axes (digest §8.3 #29): the surplus field is ignored
    (design decision), every axis gets VL 100 and there is no command error. The MR list has a
    space after a comma, which is skipped. All eight axes cruise at 100 steps/s; SA at 2.5 s
    ("awhile") flushes every queue and ramps every axis down at its AC (0.1 ms, 0.005 step), so
    all stop at 100 * 2.5 = 250, long before their targets, and stay there.
    """
    h = Harness("PC48-8")
    text = (
        "AA VL100,100,100,100,100,100,100,100,100;\r MR1000,2000,3000,4000, 5000,6000,7000,8000; GO"
    )
    assert h.send(text) == b""
    h.until(1.0)
    assert h.query("RV") == value(",".join(["100"] * 8))
    h.until(2.5)
    assert h.send("SA") == b""
    h.until(2.6)
    assert h.query("RV") == value(",".join(["0"] * 8))
    assert h.query("RP") == value(",".join(["250"] * 8))
    assert h.query("RQ") == value(",".join(["200"] * 8))
    h.until(100.0)
    assert h.query("RP") == value(",".join(["250"] * 8))
    assert h.errors() == []
