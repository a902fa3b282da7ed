"""Conformance: the VS4 manual's ``Enter:`` examples E1-E52 (chapter 6, §6.4-§6.9).

Numbering follows section 4 of ``shared/reference/vs4.md``; every example was checked against
the VS4 manual text (``shared/seeds/003_c16e31315d499848.txt``). None of these examples prints a
``Response:``, so each test asserts the state the example's stated purpose implies: positions,
velocities, timing, flags, aux lines, GP outputs and queue space (800-slot queues).

Timing conventions (brief, design decisions, ``omsd/models/vs4.py``): the VS4 samples 1024 times
a second ("calculating the optimum velocity 1024 times each second"); a move starts on the first
sample tick k/1024 s at or after its GO is executed and is over at the first tick at or after the
analytic end of its §1.3 profile. Power-up defaults: VL 200,000, AC 2,000,000, linear ramps (so
a ramp to full speed takes 0.1 s and 10,000 steps). Both VS4 models have an encoder on every
axis (GO costs 7 slots single-axis, 8 + 6 in AA with linear ramps); examples that need MO use a
variant without encoders. Expected times below are worked out from the §1.3 formulas in this
file, not read back from the engine.
"""

from __future__ import annotations

import math
from functools import partial

import pytest

from omsd.board.events import ErrorKind, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import CMD_S, DON_S, INIT, OVRT

from . import support
from .support import done_events, enter, no_encoder_vs4, number, numbers, soft_stop_bounds
from .support import frame as value
from .support import snapshot_physical as physical
from .support import status_frame as status

RATE = 1024  # VS4 sample ticks per second (§1.2, §1.3)
AC0 = 2_000_000.0  # power-up acceleration (AC)
VL0 = 200_000.0  # power-up velocity (VL)
QUEUE = 800  # "The maximum available space in each command queue is 800"


# -- helpers --------------------------------------------------------------------------------------


# The shared helpers at the VS4's sample rate and power-up VL and AC.
tick = partial(support.tick, rate=RATE)
end_tick = partial(support.end_tick, rate=RATE)
linear_move_time = partial(support.linear_move_time, vl=VL0, ac=AC0)


def limit_events(h: Harness) -> list[tuple[str, int]]:
    return [(e.axis, e.direction) for e in h.events() if isinstance(e, LimitEvent)]


def hard_stop_bound(at: float, distance: float) -> float:
    """Where a linear move of ``distance`` that meets a limit at ``at`` (still accelerating)
    can be at most: the switch plus one tick of travel at the velocity a tick later."""
    v = math.sqrt(2 * at * AC0) + AC0 / RATE
    assert at <= distance / 2
    return at + v / RATE + 1


# -- 6.4 axis specification -----------------------------------------------------------------------


def test_e01_aa_ma_moves_x_and_y_together() -> None:
    """E1 ``AA MA12000,14000; GO``: X and Y start on the same sample tick and reach 12000 and
    14000, each with its own (default) VL/AC. Both moves are triangles (VL^2/AC = 20000 steps):
    X takes 0.1549 s, Y 0.1673 s, so they finish on different ticks.

    The GO is sent between ticks (t = 0.1 ms) so that "the same tick" is tick 1, not t = 0.
    """
    h = Harness("VS4-040")
    h.until(0.0001)
    assert h.send("AA MA12000,14000; GO") == b""
    h.until(0.0009)  # before tick 1 (0.000977 s): nothing moves yet
    assert h.query("RV") == value("0,0,0,0")
    h.until(tick(1) + 1 / 2048)  # half a tick after tick 1: v = AC / 2048 = 976.6
    assert h.query("RV") == value("976,976,0,0")
    x_end = end_tick(1, linear_move_time(12000))
    y_end = end_tick(1, linear_move_time(14000))
    assert (x_end, y_end) == (160, 173)
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


def test_e02_am_runs_xy_task_and_third_field_task_independently() -> None:
    """E2 ``AM MR2000,3000; GO MA,,10000; GO``: an X/Y task and a separate single-axis task.

    Contradiction (digest §8 #6): the text says the separate move is on T, but ``MA,,10000;``
    puts 10000 in the third field, which is Z (AA/AM lists are ``x,y,z,t``). The board cannot
    know the intent, so the test expects what was typed: Z goes to 10000 and T stays at 0.

    All three axes start at once (the Z task does not wait for X/Y). To show the tasks really
    are independent, a second X/Y task is started in AM mode while Z is still moving (in AA
    mode it would wait for Z): it starts at once. X 0.063 s, Y 0.077 s, Z 0.141 s.
    """
    h = Harness("VS4-040")
    assert h.send("AM MR2000,3000; GO MA,,10000; GO") == b""
    h.until(1 / 2048)
    assert h.query("RV") == value("976,976,976,0")
    h.until(0.1)  # X and Y done, Z still moving
    assert numbers(h.query("RP"))[:2] == [2000, 3000]
    assert h.axis("Z").velocity(h.t) > 0
    h.send("MR2000,3000; GO")
    h.until(0.11)
    rv = numbers(h.query("RV"))
    assert rv[0] > 0 and rv[1] > 0 and rv[2] > 0 and rv[3] == 0, rv
    h.run()
    assert h.query("RP") == value("4000,6000,10000,0")
    assert h.errors() == []


def test_e03_ax_jg_steps_x_at_5000() -> None:
    """E3 ``AX JG5000;``: X jogs at 5000 steps/s with no GO, ramping at the default AC
    (2,000,000: 2.5 ms, 6.25 steps)."""
    h = Harness("VS4-040")
    assert h.send("AX JG5000;") == b""
    h.until(tick(2))
    assert h.query("RV") == value("3906")  # 2e6 * 2/1024 on the way up
    h.until(1.0)
    assert h.query("RV") == value("5000")
    assert h.query("RP") == value("4993")  # 5000 * 1 s - 5000^2 / (2 AC)
    h.until(10.0)
    assert h.query("RV") == value("5000")
    assert h.query("RP") == value("49993")
    assert h.query("AA RP") == value("49993,0,0,0")


def test_e04_ay_ra_reports_y_status() -> None:
    """E4 ``AY RA``: the status of Y (not of X), 4 characters framed by LF CR CR.

    Y starts inside its home window (home switch active, HL default: ``H``), at power-up
    direction P and not done. After a negative move with ID Y reads ``MDNN``; RA resets the done
    flag, so a second RA reads ``MNNN``. X was never touched: ``PNNN``.
    """
    h = Harness("VS4-040", world={"Y": AxisWorld(start_position=1050)})
    assert h.send("AY RA") == status("PNNH")
    h.send("MR-100 GO ID")
    h.run()
    assert h.send("AY RA") == status("MDNN")
    assert h.send("AY RA") == status("MNNN")
    assert h.send("AX RA") == status("PNNN")


def test_e05_az_vl500_mr2000() -> None:
    """E5 ``AZ VL500 MR2000 GO``: Z peaks at 500 steps/s and ends 2000 steps on; nothing else
    moves. The move lasts 2000/500 + 500/2e6 = 4.00025 s (over at tick 4097)."""
    h = Harness("VS4-040")
    assert h.send("AZ VL500 MR2000 GO") == b""
    h.until(2.0)
    assert h.query("RV") == value("500")
    assert h.query("RP") == value("999")  # 500 * (2 - 0.00025) + 0.0625
    h.until(3.9)
    assert h.query("RV") == value("500")
    assert h.query("RP") == value("1949")
    end = end_tick(0, linear_move_time(2000, vl=500))
    assert end == 4097
    h.until(tick(end - 1))
    assert h.query("RP") == value("1999")
    h.until(tick(end))
    assert h.query("RP") == value("2000")
    assert h.query("RV") == value("0")
    assert h.query("AA RP") == value("0,0,2000,0")


def test_e06_at_ma_minus_2468() -> None:
    """E6 ``AT MA-2468; GO``: T ends at -2468 (a triangular move of 0.0703 s, tick 72), last
    moving M."""
    h = Harness("VS4-040")
    assert h.send("AT MA-2468; GO") == b""
    end = end_tick(0, linear_move_time(2468))
    assert end == 72
    h.until(tick(end - 1))
    assert h.query("RP") == value("-2467")
    h.until(tick(end))
    assert h.query("RP") == value("-2468")
    assert h.query("QA") == status("MNNN")
    assert h.query("AA RP") == value("0,0,0,-2468")


# -- 6.5 system control ---------------------------------------------------------------------------


def test_e07_en_turns_echo_on() -> None:
    """E7 ``EN``: afterwards every character is echoed and a command error also prints an
    English message (design: ``<LF><CR><message>: <command><LF><CR>``). EN itself is consumed
    while echo is still off, so it produces nothing."""
    h = Harness("VS4-040")
    assert h.query("RP") == value("0")
    assert h.send("EN") == b""
    assert h.query("RP") == b"RP" + value("0")
    assert h.query("AY RP") == b"AY RP" + value("0")
    assert h.send("XQ ") == b"XQ" + value("Unrecognized command: XQ") + b" "
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "XQ")]


def test_e07_en_is_not_valid_in_aa_mode() -> None:
    """E7's table: EN is "Not Valid" in AA/AM ("This command would probably be the first
    command executed", in the single-axis power-up mode). ``AA EN`` is a command error and
    echo stays off."""
    h = Harness("VS4-040")
    h.send("AA EN")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, "EN")]
    assert h.board.read_status_register(h.t) & CMD_S
    assert h.query("RP") == value("0,0,0,0")


def test_e08_ef_turns_echo_off() -> None:
    """E8 ``EF``: with echo on, the two letters of EF are still echoed (they are consumed before
    EF takes effect); afterwards nothing is echoed and errors print no text (the error flag is
    still set)."""
    h = Harness("VS4-040")
    h.send("EN")
    assert h.query("RP") == b"RP" + value("0")
    assert h.send("EF") == b"EF"
    assert h.query("RP") == value("0")
    assert h.send("XQ ") == b""
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "XQ")]
    assert h.board.read_status_register(h.t) & CMD_S


def test_e09_hh_hm0_then_hl_hr0_two_pass_home() -> None:
    """E9 ``AX VL20000 HH HM0`` / ``VL1000 HL HR0``: a fast pass through home with HH, then a
    slow reverse pass (1000 steps/s, under the VS4's 1024 limit) with HL that loads 0 at the
    home edge.

    X has a normally open home switch at 50000..50100. With HH the home input is true *outside*
    the window, so the fast HM pass sees its false->true edge where the stage leaves the switch
    at 50100 ("moved through home at high speed"): 0.01 s ramp (100 steps), edge at 2.51 s; the
    counter is loaded with 0 there and X decelerates 100 steps (0.01 s). The HL HR0 pass then
    runs back at -1000 and finds the same edge from the other side.
    """
    h = Harness("VS4-040", world={"X": AxisWorld(home_low=50_000, home_high=50_100)})
    assert h.send("AX VL20000 HH HM0\r VL1000 HL HR0\r") == b""
    assert h.errors() == []
    h.until(1.0)
    assert h.query("RV") == value("20000")
    assert h.query("RP") == value("19900")
    h.until(2.55)  # edge at 2.51 (+ < 1 tick), 0.01 s stop, then back at -1000
    assert h.query("RV") == value("-1000")
    rp = number(h.query("RP"))
    assert 65 <= rp <= 76, rp  # about 100 - 1000 * (2.55 - 2.521)
    h.run()
    # HR0 loads 0 at the first tick at which the carriage is on the first whole step inside the
    # window going down, 50099 (at most 1000/1024 step past it), then stops in 0.25 step: the
    # counter reads 0 or -1 and counter 0 is within a step below that edge.
    assert h.query("RV") == value("0")
    assert h.query("RP") in (value("0"), value("-1"))
    offset = physical(h, "X") - h.position("X")
    assert 50_098.0 <= offset <= 50_099.0, offset
    assert h.axis("X").home_high is False  # HL restored
    assert h.query("RQ") == value("800")


def test_e10_ay_lf_ignores_y_limits() -> None:
    """E10 ``AY LF``: Y runs through its +limit switch (at 5000) to 10000; X, with the same
    switch and limits on, is stopped by it (and its queue flushed)."""
    world = {a: AxisWorld(positive_limit=5000) for a in "XY"}
    h = Harness("VS4-040", world=world)
    assert enter(h, "AY LF") == b""
    h.send("AX MR10000 GO AY MR10000 GO")
    h.run()
    assert h.query("AY RP") == value("10000")
    x = number(h.query("AX RP"))
    assert 5000 <= x <= hard_stop_bound(5000, 10000), x
    assert limit_events(h) == [("X", 1)]
    assert h.query("AA RQ") == value("800,800,800,800")


def test_e11_aa_ln_enables_t_limits_only() -> None:
    """E11 ``AA LN,,,1;``: "Set up the T axis to stop immediately when a limit switch is
    encountered."

    Contradiction (digest §8 #5): LN's table says AA "Not Valid", the example uses the AA form.
    Chosen reading (``omsd/models/vs4.py``): the example shows what the firmware did, so the AA
    form is accepted and, as for AN, the filled fields pick the axes (the value is a place
    holder). With limits off on every axis beforehand, only T's come back on: T stops at once at
    its +limit (3000) with its queue flushed (the MR-500 behind never runs); Z, same switch,
    runs through.
    """
    world = {a: AxisWorld(positive_limit=3000) for a in "ZT"}
    h = Harness("VS4-040", world=world)
    h.send("AX LF AY LF AZ LF AT LF")
    assert h.send("AA LN,,,1;") == b""
    assert h.errors() == []
    h.send("AT MR10000 GO MR-500 GO AZ MR10000 GO")
    h.run()
    t = number(h.query("AT RP"))
    assert 3000 <= t <= hard_stop_bound(3000, 10000), t
    assert h.query("AT RQ") == value("800")
    assert h.query("AZ RP") == value("10000")
    assert limit_events(h) == [("T", 1)]
    assert h.board.read_status_register(h.t) & OVRT


def test_e12_ax_sl_ramps_down_at_limit_for_all_axes() -> None:
    """E12 ``AX SL``: at the +limit (3000) X ramps down at AC instead of stopping, ending near
    6000; the queue is not flushed ("except for the current move"), so the MR-1000 behind runs.
    SL "affects all axes simultaneously": Y, never addressed by SL, also ramps down."""
    world = {a: AxisWorld(positive_limit=3000) for a in "XY"}
    h = Harness("VS4-040", world=world)
    assert h.send("AX SL") == b""
    h.send("MR10000 GO MR-1000 GO AY MR10000 GO")
    lo, hi = soft_stop_bounds(3000, AC0, RATE)
    h.until(0.3)  # both ramped down by 0.11 s; X's MR-1000 (0.045 s) is over
    y = number(h.query("AY RP"))
    assert lo - 1 <= y <= hi + 1, (y, lo, hi)
    h.run()
    x = number(h.query("AX RP"))
    assert lo - 1 - 1000 <= x <= hi + 1 - 1000, (x, lo, hi)
    assert number(h.query("AY RP")) == y
    assert sorted(limit_events(h)) == [("X", 1), ("Y", 1)]


def test_e13_ax_sf_restores_hard_limits() -> None:
    """E13 ``AX SF`` (after ``AX SL``): X stops immediately at its +limit (3000) again and its
    queue is flushed (the MR-500 behind never runs)."""
    h = Harness("VS4-040", world={"X": AxisWorld(positive_limit=3000)})
    h.send("AX SL")
    assert h.send("AX SF") == b""
    h.send("MR10000 GO MR-500 GO")
    h.run()
    x = number(h.query("RP"))
    assert 3000 <= x <= hard_stop_bound(3000, 10000), x
    assert h.query("RQ") == value("800")
    assert h.board.read_status_register(h.t) & OVRT


def test_e14_aa_sf_restores_hard_limits_on_z_and_t() -> None:
    """E14 ``AA SF`` ("make the Z and U axes stop immediately").

    Contradictions (digest §8 #5): SF's table says AA "Not Valid", and the VS4 has no U axis.
    Chosen reading (``omsd/models/vs4.py``): the AA form is accepted (no command error); with no
    fields it applies to all axes, and SF is board-wide anyway. After ``AX SL``, ``AA SF`` makes
    Z (and T, the VS4's last axis) stop at once at their +limits (3000), flushing their queues.
    """
    world = {a: AxisWorld(positive_limit=3000) for a in "ZT"}
    h = Harness("VS4-040", world=world)
    h.send("AX SL")
    assert h.send("AA SF") == b""
    assert h.errors() == []
    h.send("AZ MR10000 GO MR-500 GO AT MR10000 GO MR-500 GO")
    h.run()
    for letter in "ZT":
        p = number(h.query(f"A{letter} RP"))
        assert 3000 <= p <= hard_stop_bound(3000, 10000), (letter, p)
        assert h.query("RQ") == value("800")
    assert sorted(limit_events(h)) == [("T", 1), ("Z", 1)]
    assert h.errors() == []


@pytest.mark.parametrize("prefix", ["", "AA "])
def test_e15_cn_selects_cosine_ramps_at_once_for_all_axes(prefix: str) -> None:
    """E15 ``CN``: cosine ramps on every axis. On the VS4 CN is Immediate (AX-AT and AA/AM;
    the PC48 queues it): sent while X's queue is held by a WT, it still applies to a Y move
    started right after. Also valid in AA mode.

    §1.3: v = Vp/2 (1 - cos(2 Am t / Vp)); ramp time pi Vp / (2 Am) = 0.157 s over
    pi Vp^2 / (4 Am) = 15708 steps; MR100000 takes 0.657 s (linear: 0.6 s). Stopped, RC is
    the acceleration at the start of a ramp: 0 for a cosine ramp (design decision).
    """
    h = Harness("VS4-040")
    h.send("AX WT1000")
    assert h.send(prefix + "CN") == b""
    assert h.errors() == []
    assert h.query("AY RC") == value("0")
    h.send("MR100000 GO")
    h.until(0.0625)
    expected = 100_000 * (1 - math.cos(2 * AC0 * 0.0625 / VL0))  # 68467.6 (linear: 125000)
    assert abs(number(h.query("RV")) - expected) <= 1
    ramp_t = math.pi * VL0 / (2 * AC0)
    ramp_s = math.pi * VL0 * VL0 / (4 * AC0)
    total = 2 * ramp_t + (100_000 - 2 * ramp_s) / VL0
    end = end_tick(0, total)
    assert end == 673
    h.until(tick(end - 1))
    assert h.position("Y") < 100_000
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e16_pn10_selects_smoothest_parabolic_ramp() -> None:
    """E16 ``PN10;``: parabolic ramps, a = A0 (1 - r t/t1) from AC down to "as low as 10%" at
    the peak ("3 to 10 corresponding to 70% and 10% acceleration at the peak"; the VS4 manual
    has no ramp equation, docs/decisions.md): r = 0.9 at the end of the ramp. So the ramp takes
    t1 = VL / (AC (1 - r/2)) = 0.1818 s over AC t1^2/2 - AC r t1^2/6 = 23140 steps, and
    MR100000 takes 0.6322 s (tick 648). RC is AC when stopped and 10 % of it (the end-of-ramp
    value) at cruise."""
    h = Harness("VS4-040")
    assert h.send("PN10;") == b""
    assert h.query("RC") == value("2000000")
    h.send("MR100000 GO")
    h.until(0.125)
    r = 0.9
    t1 = VL0 / (AC0 * (1 - r / 2))
    assert abs(number(h.query("RV")) - (AC0 * 0.125 - AC0 * r * 0.125**2 / (2 * t1))) <= 1
    assert abs(number(h.query("RC")) - AC0 * (1 - r * 0.125 / t1)) <= 1  # 762500
    h.until(0.3)
    assert h.query("RV") == value("200000")
    assert h.query("RC") == value("200000")
    ramp = AC0 * t1 * t1 / 2 - AC0 * r * t1 * t1 / 6
    total = 2 * t1 + (100_000 - 2 * ramp) / VL0
    end = end_tick(0, total)
    assert end == 648
    h.until(tick(end - 1))
    assert h.position("X") < 100_000
    h.until(tick(end))
    assert h.query("RP") == value("100000")


@pytest.mark.parametrize("mode", ["CN", "PN10"])
def test_e17_pf_returns_to_linear_ramps(mode: str) -> None:
    """E17 ``PF``: after CN or PN, linear ramps again: RC (stopped) is AC, v = AC t while
    ramping, and MR100000 ends after 0.6 s (tick 615)."""
    h = Harness("VS4-040")
    h.send(mode)
    assert h.send("PF") == b""
    assert h.query("RC") == value("2000000")
    h.send("MR100000 GO")
    h.until(0.0625)
    assert h.query("RV") == value("125000")
    end = end_tick(0, linear_move_time(100_000))
    assert end == 615
    h.until(tick(end - 1))
    assert h.position("X") < 100_000
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e18_rs_resets_everything() -> None:
    """E18 ``RS``: all movement stops; queues, modes, parameters and registers go back to the
    power-up state; interrupts are disabled; the INIT status bit is high while the board
    initializes (VS4: "wait 1.5 seconds after reset ... before reading the INIT bit").

    Before RS: X jogging at 20000 with AC 200000 and a queued move, Y aux low, output 10 low, a
    done flag set, Z's counter loaded, parabolic ramps, echo on, AA mode, interrupts enabled.
    The position counters after RS are taken to be 0, as at power-up (inferred, as on the PC48).
    """
    h = Harness("VS4-040")
    h.send("AZ LP777 AY AF ID BL10 AX AC200000 JG20000 MR5000 GO PN5 EN")
    h.board.write_control_register(0xF0, h.t)
    h.until(0.5)
    h.send("AA")
    assert h.board.registers.done != 0
    assert h.board.outputs_low != 0
    h.send("RS")
    assert h.board.status_register(h.t) & INIT
    h.advance(1.49)
    assert h.board.status_register(h.t) & INIT
    h.advance(0.02)
    assert not h.board.status_register(h.t) & INIT
    here = physical(h, "X")
    assert h.query("RP") == value("0")  # AX mode, echo off, counter 0
    assert h.query("RV") == value("0")
    assert h.query("RC") == value("2000000")  # default AC and linear ramps
    assert h.query("RQ") == value("800")
    assert h.query("AA RP") == value("0,0,0,0")
    assert h.query("RQ") == value("800,800,800,800")
    assert [h.axis(a).aux for a in "XYZT"] == [True] * 4
    assert [h.axis(a).vl for a in "XYZT"] == [VL0] * 4
    assert [h.axis(a).ac for a in "XYZT"] == [AC0] * 4
    assert h.board.outputs_low == 0
    assert h.board.registers.done == 0
    assert h.board.read_control_register(h.t) == 0
    h.advance(2.0)
    assert physical(h, "X") == here  # nothing moves any more
    assert h.errors() == []


# -- 6.6 user I/O ---------------------------------------------------------------------------------


def test_e19_ay_an_turns_y_aux_on() -> None:
    """E19 ``AY AN`` (after ``AY AF``): Y's aux line goes high again; the others stay high."""
    h = Harness("VS4-040")
    enter(h, "AY AF")
    assert h.axis("Y").aux is False
    assert enter(h, "AY AN") == b""
    assert [h.axis(a).aux for a in "XYZT"] == [True] * 4
    assert h.errors() == []


def test_e20_aa_an_turns_x_and_z_aux_on() -> None:
    """E20 ``AA AN1,,1;``: X and Z aux on, Y (skipped) and T (not given) unchanged. The values
    are place holders only, so ``AN0,,0;`` does the same."""
    for text in ("AA AN1,,1;", "AA AN0,,0;"):
        h = Harness("VS4-040")
        h.send("AA AF1,1,1,1;")
        assert [h.axis(a).aux for a in "XYZT"] == [False] * 4
        assert h.send(text) == b""
        assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, False], text
        assert h.errors() == []


def test_e21_ay_af_turns_y_aux_off() -> None:
    """E21 ``AY AF``: Y's aux line is driven low, the others stay high (power-up: AN)."""
    h = Harness("VS4-040")
    assert [h.axis(a).aux for a in "XYZT"] == [True] * 4
    assert enter(h, "AY AF") == b""
    assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, True]


def test_e22_aa_af_turns_x_and_z_aux_off() -> None:
    """E22 ``AA AF1,,1;``: X and Z aux low, Y and T unchanged (high)."""
    h = Harness("VS4-040")
    assert h.send("AA AF1,,1;") == b""
    assert [h.axis(a).aux for a in "XYZT"] == [False, True, False, True]
    assert h.errors() == []


def test_e23_bl10_bl12_after_move() -> None:
    """E23 ``AX MA1000 GO BL10; BL12;``: outputs 10 and 12 go low only when the X move (a
    triangle of 0.0447 s, over at tick 46) has ended. (The example's "See the RB command" points
    at a command the VS4 does not have; bits 8-13 are outputs from the factory.)"""
    h = Harness("VS4-040")
    assert h.send("AX MA1000 GO BL10; BL12;") == b""
    assert h.board.outputs_low == 0
    end = end_tick(0, linear_move_time(1000))
    assert end == 46
    h.until(tick(end - 1))
    assert h.board.outputs_low == 0
    assert h.position("X") < 1000
    h.until(tick(end))
    assert h.position("X") == 1000
    assert h.board.outputs_low == (1 << 10) | (1 << 12)
    assert h.errors() == []


def test_e23_bl_costs_two_slots_in_single_axis_mode() -> None:
    """E23's queue table: BL takes 2 slots in AX-AT mode (every ramp type); behind a WT (which
    holds the queue) ``MA1000 GO BL10; BL12;`` takes 2 + 7 (GO on an encoder board) + 2 + 2."""
    h = Harness("VS4-040")
    h.send("AX WT1000")
    before = number(h.query("RQ"))
    h.send("AX MA1000 GO BL10; BL12;")
    assert before - number(h.query("RQ")) == 2 + 7 + 2 + 2
    h.run()
    assert h.query("RQ") == value("800")
    assert h.board.outputs_low == (1 << 10) | (1 << 12)


def test_e24_bh8_bh11_set_bits_high() -> None:
    """E24 ``BH8; BH11;`` (after BL8 BL9 BL11): bits 8 and 11 go high; 9 stays low."""
    h = Harness("VS4-040")
    h.send("BL8; BL9; BL11;")
    assert h.board.outputs_low == (1 << 8) | (1 << 9) | (1 << 11)
    assert h.send("BH8; BH11;") == b""
    assert h.board.outputs_low == 1 << 9
    assert h.errors() == []


def test_e25_aa_pa_switches_y_on_and_t_off_during_moves() -> None:
    """E25 ``AA PA,0,,1;``: at each GO Y's aux goes on (parameter 0) and T's goes off
    (non-zero) for the move, complemented after it; X and Z are not in PA mode.

    PA also costs 2 extra slots per GO on the PA axes (§6.6): with a move running, queuing
    ``MR1000,1000,,1000; GO`` takes MR 2 + AA GO 8 + 6 (encoder table B, linear) (+2 on Y and
    T): 16, 18, 14, 18 slots. Each move is a 0.0447 s triangle (46 ticks).
    """
    h = Harness("VS4-040")
    assert h.send("AA PA,0,,1;") == b""
    h.send("MR1000,1000,,1000; GO")
    h.until(0.02)
    assert [h.axis(a).aux for a in "XYZT"] == [True, True, True, False]
    before = numbers(h.query("RQ"))
    h.send("MR1000,1000,,1000; GO")
    after = numbers(h.query("RQ"))
    assert [b - a for b, a in zip(before, after, strict=True)] == [16, 18, 14, 18]
    h.until(0.06)  # first move over, second one running
    assert h.query("RP") != value("1000,1000,0,1000")
    assert [h.axis(a).aux for a in "XYZT"] == [True, True, True, False]
    h.run()
    assert h.query("RP") == value("2000,2000,0,2000")
    assert [h.axis(a).aux for a in "XYZT"] == [True, False, True, True]
    assert h.query("RQ") == value("800,800,800,800")


def test_e26_az_pa_se500_keeps_aux_on_500ms_after_move() -> None:
    """E26 ``AZ PA SE500;``: Z's aux goes on with a move and stays on 500 ms after it ends.

    A ``MR1000 GO`` is added to see it: it lasts 2 sqrt(1000/AC) = 0.0447 s, over at tick 46,
    so the aux goes off 0.5 s later. Queue: such a GO costs 7 (encoder board) + 2 (PA) + 3 (SE)
    and the MR 2.
    """
    h = Harness("VS4-040")
    assert h.send("AZ PA SE500;") == b""
    h.send("WT1000")  # hold the queue so the GO's cost can be seen
    before = number(h.query("RQ"))
    h.send("MR1000 GO")
    assert before - number(h.query("RQ")) == 2 + 7 + 2 + 3
    h.until(1.0)  # WT over at 1.0: the move starts
    h.until(1.02)
    assert h.axis("Z").aux is True
    end = 1.0 + tick(end_tick(0, linear_move_time(1000)))
    h.until(end + 0.3)
    assert h.query("RP") == value("1000")
    assert h.axis("Z").aux is True
    h.until(end + 0.49)
    assert h.axis("Z").aux is True
    h.until(end + 0.51)
    assert h.axis("Z").aux is False


# -- 6.7 move specification -----------------------------------------------------------------------


def test_e27_ay_ac200000() -> None:
    """E27 ``AY AC200000``: Y accelerates at 200,000 (RC when stopped: the AC); X keeps the
    power-up 2,000,000. MR10000 is then a triangle of 0.447 s (tick 458)."""
    h = Harness("VS4-040")
    assert enter(h, "AY AC200000") == b""
    assert h.query("RC") == value("200000")
    assert h.query("AX RC") == value("2000000")
    h.send("AY MR10000 GO")
    h.until(0.125)
    assert h.query("RV") == value("25000")
    end = end_tick(0, linear_move_time(10_000, ac=200_000))
    assert end == 458
    h.until(tick(end - 1))
    assert h.position("Y") < 10_000
    h.until(tick(end))
    assert h.query("RP") == value("10000")


def test_e28_aa_ac_sets_x_and_z() -> None:
    """E28 ``AA AC200000,,50000;``: X 200,000, Z 50,000, Y and T keep 2,000,000."""
    h = Harness("VS4-040")
    assert h.send("AA AC200000,,50000;") == b""
    assert h.query("RC") == value("200000,2000000,50000,2000000")


def test_e29_ax_vl10000() -> None:
    """E29 ``AX VL10000``: X's peak velocity is 10,000 steps/s (the manual's "counts per second
    per second" is a slip for counts/s, digest §8 #31). MR100000 then takes 10.005 s."""
    h = Harness("VS4-040")
    assert enter(h, "AX VL10000") == b""
    h.send("MR100000 GO")
    h.until(5.0)
    assert h.query("RV") == value("10000")
    end = end_tick(0, linear_move_time(100_000, vl=10_000))
    assert end == 10246
    h.until(tick(end - 1))
    assert h.position("X") < 100_000
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e30_aa_vl_sets_x_and_t() -> None:
    """E30 ``AA VL5000,,,50000;``: X cruises at 5000, T at 50000, Y and Z keep 200,000."""
    h = Harness("VS4-040")
    assert h.send("AA VL5000,,,50000;") == b""
    h.send("MR1000000,1000000,1000000,1000000; GO")
    h.until(0.5)
    assert h.query("RV") == value("5000,200000,200000,50000")


def test_e31_ay_vb200() -> None:
    """E31 ``AY VB200``: Y's ramp starts by jumping to 200 steps/s; X (no VB) starts from 0.
    Half a tick after the start: X 2e6/2048 = 976, Y 200 + 976 = 1176."""
    h = Harness("VS4-040")
    assert enter(h, "AY VB200") == b""
    h.send("MR10000 GO AX MR10000 GO")
    h.until(1 / 2048)
    assert h.query("AA RV") == value("976,1176,0,0")
    h.run()
    assert h.query("RP") == value("10000,10000,0,0")


def test_e32_aa_vb200_200() -> None:
    """E32 ``AA VB200,200;``: X and Y start their ramps at 200 steps/s, Z from 0."""
    h = Harness("VS4-040")
    assert h.send("AA VB200,200;") == b""
    h.send("MR10000,10000,10000; GO")
    h.until(1 / 2048)
    assert h.query("RV") == value("1176,1176,976,0")
    h.run()
    assert h.query("RP") == value("10000,10000,10000,0")


def test_e33_aa_lp1000_loads_x_position() -> None:
    """E33 ``AA LP1000``: "would load the X axis position register with 1000."

    Contradiction (digest §8 #5): LP's table says AA "Not Valid" (the PC48's example is
    ``AX LP1000``). Chosen reading (``omsd/models/vs4.py``): the AA form is accepted; in AA the
    list's first field is X, so X's position counter (and, the VS4 having encoders, its
    encoder register, ER 1:1) reads 1000, Y, Z and T are untouched, and the motor does not
    move. MA0 then moves the stage 1000 steps back.
    """
    h = Harness("VS4-040")
    assert enter(h, "AA LP1000") == b""
    assert h.errors() == []
    h.advance(0.01)
    assert h.query("RP") == value("1000,0,0,0")
    assert physical(h, "X") == 0.0
    assert h.query("AX RE") == value("1000")
    h.send("MA0 GO")
    h.run()
    assert h.query("RP") == value("0")
    assert physical(h, "X") == -1000.0


def test_e34_ay_er3_2_lp30000() -> None:
    """E34 ``AY ER3,2 LP30000`` (every VS4 axis has an encoder): encoder register 30,000,
    position counter 20,000.

    The manual says "the parameter times the encoder ratio" goes into the position counter but
    its example gives 20,000, i.e. multiplied by motor/encoder counts (digest §8 #26): the
    example's numbers are used. With ER set, distances are in encoder counts: MR3000 moves
    3000 encoder counts = 2000 steps.
    """
    h = Harness("VS4-040")
    assert enter(h, "AY ER3,2 LP30000") == b""
    h.advance(0.01)
    assert h.query("RE") == value("30000")
    assert h.query("RP") == value("20000")
    h.send("MR3000 GO")
    h.run()
    assert h.query("RE") == value("33000")
    assert h.query("RP") == value("22000")
    assert physical(h, "Y") == 2000.0
    assert h.errors() == []


def test_e35_ax_ma100000_with_previous_parameters() -> None:
    """E35 ``AX MA100000 GO`` with previously entered VL50000 AC250000: ramps of 0.2 s, 2.2 s
    in all (over at tick 2253)."""
    h = Harness("VS4-040")
    enter(h, "AX VL50000 AC250000")
    assert h.send("AX MA100000 GO") == b""
    h.until(1.0)
    assert h.query("RV") == value("50000")
    end = end_tick(0, linear_move_time(100_000, vl=50_000, ac=250_000))
    assert end == 2253
    h.until(tick(end - 1))
    assert h.query("RP") == value("99999")
    h.until(tick(end))
    assert h.query("RP") == value("100000")


def test_e36_aa_ma_moves_y_and_t_only() -> None:
    """E36 ``AA MA,10000,,1000; GO``: Y to 10000, T to 1000; X and Z (at 777 and -333, loaded
    beforehand) stay where they are."""
    h = Harness("VS4-040")
    h.send("AX LP777 AZ LP-333")
    assert h.send("AA MA,10000,,1000; GO") == b""
    h.until(0.02)
    rv = numbers(h.query("RV"))
    assert rv[0] == 0 and rv[2] == 0 and rv[1] > 0 and rv[3] > 0, rv
    h.run()
    assert h.query("RP") == value("777,10000,-333,1000")


def test_e37_ax_mr_minus_2468() -> None:
    """E37 ``AX MR-2468 GO`` from 1000: X ends at -1468, last moving negative."""
    h = Harness("VS4-040")
    enter(h, "AX LP1000")
    assert h.send("AX MR-2468 GO") == b""
    h.run()
    assert h.query("RP") == value("-1468")
    assert h.query("QA") == status("MNNN")


def test_e38_aa_mr_starts_x_and_y_together() -> None:
    """E38 ``AA MR12345,6789; GO``: both start on the same tick (tick 1: GO sent at 0.1 ms) and
    finish on their own: Y (triangle, 0.117 s) well before X (triangle, 0.157 s)."""
    h = Harness("VS4-040")
    h.until(0.0001)
    assert h.send("AA MR12345,6789; GO") == b""
    h.until(0.0009)
    assert h.query("RV") == value("0,0,0,0")
    h.until(tick(1) + 1 / 2048)
    assert h.query("RV") == value("976,976,0,0")
    x_end = end_tick(1, linear_move_time(12345))
    y_end = end_tick(1, linear_move_time(6789))
    assert (x_end, y_end) == (162, 121)
    h.until(tick(y_end))
    assert h.position("Y") == 6789
    assert h.position("X") < 12345
    h.until(tick(x_end - 1))
    assert h.position("X") < 12345
    h.until(tick(x_end))
    assert h.query("RP") == value("12345,6789,0,0")


def test_e39_aa_ml_interpolates_y_z_t() -> None:
    """E39 ``AA ML,10000,100,1000; GO``: Y, Z and T move 10000, 100 and 1000 along a straight
    line, starting and finishing together; X stays.

    Y sets the pace (triangle of 0.1414 s); Z and T are scaled, so at every instant they have
    done the same fraction of their moves: at 0.0625 s, 39.0625 %. All end at tick 145."""
    h = Harness("VS4-040")
    assert h.send("AA ML,10000,100,1000; GO") == b""
    h.until(1 / 2048)
    assert h.query("RV") == value("0,976,9,97")
    h.until(0.0625)
    assert h.query("RP") == value("0,3906,39,390")
    end = end_tick(0, linear_move_time(10_000))
    assert end == 145
    h.until(tick(end - 1))
    assert h.query("RP") == value("0,9999,99,999")
    h.until(tick(end))
    assert h.query("RP") == value("0,10000,100,1000")


def test_e40_aa_mt_moves_x_y_t_to_absolute_positions() -> None:
    """E40 ``AA MT1000,10000,,100; GO``: X, Y and T go to 1000, 10000 and 100 along a straight
    line, together; Z (loaded with -50) stays. X starts from 400 (LP) to show the target is
    absolute: it travels 600 steps, 6 % of Y's distance."""
    h = Harness("VS4-040")
    h.send("AX LP400 AZ LP-50")
    assert h.send("AA MT1000,10000,,100; GO") == b""
    h.until(0.0625)  # 39.0625 % of the way
    assert h.query("RP") == value("634,3906,-50,39")
    end = end_tick(0, linear_move_time(10_000))
    h.until(tick(end - 1))
    assert h.query("RP") == value("999,9999,-50,99")
    h.until(tick(end))
    assert h.query("RP") == value("1000,10000,-50,100")


def test_e41_az_mm_mo_moves_one_pulse_negative_without_encoders() -> None:
    """E41 ``AZ MM MO`` on a VS4 without the encoder option (a per-board variant: both catalogue
    models are "Closed Loop (Encoder)", and MO "is not available in models with an encoder
    option"): one step in the negative direction within one sample interval, no GO. MM is one
    queued slot and MO one (VS4 tables), so the queue is back to 800 afterwards."""
    h = no_encoder_vs4()
    assert h.send("AZ MM MO") == b""
    h.until(tick(1))
    assert h.query("RP") == value("-1")
    h.run()
    assert h.query("RP") == value("-1")
    assert h.query("QA") == status("MNNN")
    assert h.query("AA RP") == value("0,0,-1,0")
    assert h.query("RQ") == value("800,800,800,800")
    assert h.errors() == []


def test_e41_mo_is_not_available_with_encoders() -> None:
    """E41 on a stock VS4-040 (encoders on every axis): "This command is not available in
    models with an encoder option." MO is a command error and Z does not move."""
    h = Harness("VS4-040")
    h.send("AZ MM MO")
    h.run()
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.ENCODER_MODEL, "MO")]
    assert h.query("RP") == value("0")
    assert physical(h, "Z") == 0.0


# -- 6.8 move execution ---------------------------------------------------------------------------


def test_e42_ax_ma12345_go() -> None:
    """E42 ``AX MA12345 GO``: X reaches 12345 at tick 161 (triangle of 0.1571 s)."""
    h = Harness("VS4-040")
    assert h.send("AX MA12345 GO") == b""
    end = end_tick(0, linear_move_time(12345))
    assert end == 161
    h.until(tick(end - 1))
    assert h.query("RP") == value("12344")
    h.until(tick(end))
    assert h.query("RP") == value("12345")


def test_e43_aa_mr_opposite_directions() -> None:
    """E43 ``AA MR2468,-2468; GO``: X +2468 and Y -2468, mirror images of each other (still
    accelerating at 31.25 ms: v = AC t = 62500)."""
    h = Harness("VS4-040")
    assert h.send("AA MR2468,-2468; GO") == b""
    h.until(0.03125)
    assert h.query("RV") == value("62500,-62500,0,0")
    h.run()
    assert h.query("RP") == value("2468,-2468,0,0")
    assert h.query("QI") == status("PNNN,MNNN,PNNN,PNNN")


def test_e44_gd_resets_done_between_two_moves() -> None:
    """E44 ``AY MR-12345 GO ID MR12345 GD ID``: done is flagged at the end of each move (two
    done interrupts); GD clears the first flag as the second move starts, so during the second
    move Y is not done and the done register is clear. Each move takes 161 ticks."""
    h = Harness("VS4-040")
    assert h.send("AY MR-12345 GO ID MR12345 GD ID") == b""
    h.until(0.1)
    assert number(h.query("RP")) < -8000
    h.until(0.2)
    assert h.query("QA") == status("PNNN")
    assert h.board.registers.done == 0
    h.run()
    assert h.query("RP") == value("0")
    assert h.query("QA") == status("PDNN")
    events = done_events(h)
    assert [(e.time, e.done_register) for e in events] == [(tick(161), 0b10), (tick(322), 0b10)]
    assert h.board.read_done_register(h.t) == 0b10


def test_e45_aa_mt_go_id_ml_gd_id() -> None:
    """E45 ``AA MT10000,20000; GO ID ML-10000,-20000; GD ID``: a linear move to (10000, 20000)
    flagged done, then GD clears every done flag and a linear move back to (0, 0) is flagged
    done again. Each move is paced by Y (20000 steps, a 0.2 s triangle, 205 ticks). In AA mode
    "the done flag register bits will be set as each axis encounters the ID", DON_S once all
    have: Z and T, which do not move, are done again as soon as GD has cleared them, X and Y
    at the end."""
    h = Harness("VS4-040")
    assert h.send("AA MT10000,20000; GO ID ML-10000,-20000; GD ID") == b""
    end = end_tick(0, linear_move_time(20_000))
    assert end == 205
    h.until(tick(end))
    assert h.query("RP") == value("10000,20000,0,0")
    h.until(0.3)
    assert h.query("QI") == status("MNNN,MNNN,PDNN,PDNN")
    assert h.board.registers.done == 0b1100
    h.run()
    assert h.query("RP") == value("0,0,0,0")
    assert h.query("QI") == status("MDNN,MDNN,PDNN,PDNN")
    events = done_events(h)
    assert [(e.time, e.done_register) for e in events] == [(tick(205), 0xF), (tick(410), 0xF)]


def test_e46_jg_then_slower_jg_then_st() -> None:
    """E46 ``JG100000 JG35000 ST``: jog at 100,000, change to 35,000 "when the second JG is
    entered", then decelerate to a stop.

    The commands are entered one at a time (t = 0, 1, 2 s), as the example's wording implies:
    sent in one burst, ST ("executed immediately", flushing the queue) would cancel the jogs
    before they had begun. Position: 97500 at 1 s, + 2193.75 (slowing, 32.5 ms) + 33862.5
    (cruise) at 2 s, + 306.25 (stop, 17.5 ms) = 133862.5. JG also sets VL.
    """
    h = Harness("VS4-040")
    assert enter(h, "JG100000") == b""
    h.until(0.5)
    assert h.query("RV") == value("100000")
    h.until(1.0)
    assert enter(h, "JG35000") == b""
    h.until(1.015625)
    assert h.query("RV") == value("68750")
    h.until(1.5)
    assert h.query("RV") == value("35000")
    h.until(2.0)
    assert h.send("ST") == b""
    h.until(2.015)
    assert number(h.query("RV")) > 0
    end = end_tick(2048, 35_000 / AC0)
    assert end == 2066
    h.until(tick(end))
    assert h.query("RV") == value("0")
    assert h.query("RP") == value("133862")
    h.advance(5.0)
    assert h.query("RP") == value("133862")
    assert h.axis("X").vl == 35_000


def test_e47_ay_jf_fractional_jog() -> None:
    """E47 ``AY JF2.667``: Y jogs at 2.667 steps/s, fraction kept (800 steps in 300 s, not 600),
    RV shows only the integer part, and 2.667 becomes the default velocity."""
    h = Harness("VS4-040")
    assert enter(h, "AY JF2.667") == b""
    h.until(30.0)
    assert h.query("RV") == value("2")
    assert h.query("RP") == value("80")
    h.until(300.0)
    assert h.query("RP") == value("800")
    assert h.axis("Y").vl == pytest.approx(2.667)
    assert h.errors() == []


def test_e48_vs_velocity_staircase() -> None:
    """E48 ``AX VS1024,-1000,1000; ... VS1,0,0;``: X and Y follow the staircase 1000, 2000,
    3000, 2000, 1000 steps/s (X negative, Y positive), each step 1024 samples = 1 s long (on the
    VS4 the VS time unit is the sample interval), then 0 after one more 1/1024 s interval.

    The example chains six VS commands although VS "cannot be mixed or queued with other
    commands": chaining VS with VS is taken to be allowed (the example does it). Z and T do not
    move ("Only axes X and Y will be set in motion").
    """
    h = Harness("VS4-040")
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
    assert h.query("RQ") == value("800,800,800,800")
    assert h.errors() == []


def test_e48_vs_in_ay_mode_is_ignored() -> None:
    """E48's queue table: VS in AY-AT is "Ignored" (VS4; the PC48 says "Not Valid"). Chosen
    reading (``omsd/models/vs4.py``): no command error, nothing moves, no queue space used."""
    h = Harness("VS4-040")
    assert h.send("AY VS1024,-1000,1000;") == b""
    h.until(1.5)
    assert h.errors() == []
    assert h.query("AA RP") == value("0,0,0,0")
    assert h.query("RQ") == value("800,800,800,800")


# -- 6.9 move termination -------------------------------------------------------------------------


def test_e49_ay_jg1200_then_st_ramps_to_stop() -> None:
    """E49 ``AY JG1200 (wait awhile) ST``: Y jogs at 1200, ST decelerates it at its AC.

    Y's AC is set to 10,000 beforehand so the ramps show (0.12 s, 72 steps each), and
    ``WT3000 MR-1000 GO`` is queued behind the jog to show ST flushes Y's queue. "Awhile" is
    tick 2050 (2.00195 s): Y stops at 1200 * 2.00195 = 2402.3 steps at 2.122 s and stays there.
    """
    h = Harness("VS4-040")
    enter(h, "AY AC10000")
    assert h.send("AY JG1200 WT3000 MR-1000 GO") == b""
    h.until(1.0)
    assert h.query("RV") == value("1200")
    h.until(tick(2050))
    assert h.send("ST") == b""
    h.until(tick(2050) + 0.0625)
    assert h.query("RV") == value("575")
    h.until(tick(2050) + 0.11)
    assert number(h.query("RV")) > 0
    end = end_tick(2050, 1200 / 10_000)
    assert end == 2173
    h.until(tick(end))
    assert h.query("RV") == value("0")
    assert h.query("RP") == value("2402")
    h.until(10.0)
    assert h.query("RP") == value("2402")
    assert h.query("RQ") == value("800")


def test_e50_sa_stops_all_four_axes() -> None:
    """E50 ``AA VL100,100,100,100;`` / `` MR1000,2000,3000,4000; GO (wait awhile)`` / `` SA``.

    All four axes cruise at 100 steps/s; SA at tick 2562 (2.502 s, "awhile") flushes every queue
    and ramps every axis down at its AC (50 us, 0.0025 step), so all stop at 100 * 2.502 =
    250.2, long before their targets, and stay there. The leading spaces of the continuation
    lines are skipped.
    """
    h = Harness("VS4-040")
    text = "AA VL100,100,100,100;\r MR1000,2000,3000,4000; GO"
    assert h.send(text) == b""
    h.until(1.0)
    assert h.query("RV") == value("100,100,100,100")
    h.until(tick(2562))
    assert h.send("\r SA") == b""
    h.until(2.6)
    assert h.query("RV") == value("0,0,0,0")
    assert h.query("RP") == value("250,250,250,250")
    assert h.query("RQ") == value("800,800,800,800")
    h.until(100.0)
    assert h.query("RP") == value("250,250,250,250")
    assert h.errors() == []


def test_e51_aa_sd_id_flags_done_when_all_axes_have_stopped() -> None:
    """E51 ``AA SD ID``: SD clears the done flags, then stops every axis at its AC; the ID
    flags done (DON_S, one done event) only when the last axis has stopped.

    Beforehand an ``AA ID`` set all four done flags (the case where "The SA ID combination may
    flag the completion early"). The axes cruise at 200000, 100000, 50000 and 20000 (AC 2e6),
    so they need 0.1, 0.05, 0.025 and 0.01 s to stop. SD at tick 1000: the done register is
    clear at once; Y, Z and T set their bits as each reaches the ID, X last, at tick 1103;
    DON_S is set only then.
    """
    h = Harness("VS4-040")
    h.send("AA ID")
    assert h.board.registers.done == 0xF
    h.board.read_status_register(h.t)
    h.board.read_done_register(h.t)
    h.events()
    h.send("VL200000,100000,50000,20000; MR400000,400000,400000,400000; GO")
    h.until(tick(1000))
    assert h.send("SD ID") == b""
    assert h.board.registers.done == 0
    h.until(1.05)  # T, Z and Y stopped, X still decelerating
    assert numbers(h.query("RV"))[1:] == [0, 0, 0]
    assert number(h.query("AX RV")) > 0
    assert h.board.registers.done == 0b1110
    assert not h.board.status_register(h.t) & DON_S
    h.send("AA")
    h.run()
    assert h.query("RP") == value("195312,97656,48828,19531")
    assert [(e.time, e.done_register) for e in done_events(h)] == [(tick(1103), 0xF)]
    assert h.board.read_status_register(h.t) & DON_S
    assert h.query("RQ") == value("800,800,800,800")
    assert h.errors() == []


def test_e52_kl_discards_unstarted_move_then_mr_minus_5000_runs() -> None:
    """E52 ``AX MR5000 (oops!) KL MR-5000 GO``: KL flushes the MR5000 waiting for its GO and
    stops all pulse generation at once; the corrected MR-5000 GO then runs, so X ends at -5000
    (not 0). Y, jogging at 1000 when KL arrives (t = 1 s), stops without decelerating: it stays
    at 999 (1000 - 0.25 lost on its 0.5 ms ramp up)."""
    h = Harness("VS4-040")
    h.send("AY JG1000")
    assert enter(h, "AX MR5000") == b""
    h.until(1.0)
    assert h.send("KL MR-5000 GO") == b""
    h.until(1.0 + tick(1))
    assert h.query("AY RV") == value("0")
    h.run()
    assert h.query("AA RP") == value("-5000,999,0,0")
    assert h.query("RQ") == value("800,800,800,800")
    assert h.errors() == []
