"""Conformance: the PCIx manual's ``Enter:`` examples E73-E144 (HM to PL).

Numbering follows §5 of ``shared/reference/pcix.md``; every example was checked against the
manual itself (``shared/seeds/002_5f0bea9264c6d239.txt``, chapter 5.13), which wins where the
two differ. Each ``Enter:`` line is typed as printed and ended with the Enter key (CR);
annotations that are not meant to be typed (``(*oops!*)``, ``(done flag set, ...)``,
``(terminates the LS20; command)``) are left out. Where the manual prints a ``Response:`` it is
asserted byte for byte in the PCIx framing (``text<LF><CR>``: the manual prints ``text<LF>``);
otherwise the state the example's stated purpose implies is asserted: positions, velocities at
given times, flags (QA, the done register), parameters through their ``?XX`` query, aux lines
(``?AB``) and queue space (RQ).

Timing (PCIx §7.2): the board "calculates the desired velocity 2048 times each second"; a move
starts on the sample tick k/2048 s at or after its GO and is over on the first tick at or after
the analytic end of its §1.3 profile; a queued command waiting for a position, a velocity or a
time goes on at the first tick at or after it is reached. Power-up VL 200,000 and AC 2,000,000
(§2.8 "Velocity is 200000", "Acceleration is 2000000"): a ramp to full speed takes 0.1 s and
10,000 counts, a 100,000-count move 0.6 s, a move of d < 20,000 counts 2·sqrt(d / 2,000,000) s.
Expected times are worked out here from these formulas, not read back from the engine.

Boards: PCIX-400 for the servo commands (K* gains, ?PM, PE), PCIX-040 where an encoder is needed
(HN position maintenance, IP, HE/HS, ER, LO), PCIX-004 (open-loop steppers) otherwise; PCIX-002
where the example says "a two axes board". Home switches are put out of the way
(``support.NO_HOME``) unless an example homes.
"""

from __future__ import annotations

import math

import pytest

from omsd.board.events import LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld, LimitWiring
from omsd.engine.registers import DON_S

from .pcix import AC0, QUEUE, RATE, end_tick, linear_move_time, quiet, reply, tick, typed
from .support import NO_HOME, done_events, moving, velocity
from .support import snapshot_physical as physical

move_time = linear_move_time


# -- helpers --------------------------------------------------------------------------------------


def free(x: int, y: int = QUEUE) -> bytes:
    """RQ's reply: every axis's free units whatever the mode (E165: "800, 800, 800, 800" at
    power-up); X's and Y's given, Z and T idle."""
    return reply(", ".join(str(n) for n in (x, y, QUEUE, QUEUE)))


def ticks_after(seconds: float) -> int:
    """The first sample tick at or after ``seconds``."""
    return math.ceil(seconds * RATE - 1e-9)


def positions(h: Harness) -> list[int]:
    return [h.position(a) for a in h.board.model.axes]


def limit_events(h: Harness) -> list[tuple[str, int]]:
    return [(e.axis, e.direction) for e in h.events() if isinstance(e, LimitEvent)]


# -- HM, ?HM, HN, HR, HS, ?HS, ?HV (5.5.3, 5.7.1, 5.7.4) -------------------------------------------


def test_e73_hm1000_finds_home_then_ma1000_returns_to_it() -> None:
    """E73 ``AX; VL1000; HM1000; MA1000; GO;``: "find home, initialize it to 1000 counts, and then
    return to home".

    X's home switch is at physical 5000..5100. HM runs positive at VL 1000 (ramp 0.5 ms), so the
    switch is reached at 5.00025 s; the counter still counts travelled steps until then. "A
    velocity set to less than or equal to the update rate will provide a homing accuracy of +/-0
    counts": home is seen on the first sample inside the switch, less than one sample's travel
    (1000/2048 count) past its edge, and 1000 is loaded there. The axis then "will ramp to a stop"
    beyond the switch (0.25 count at AC 2,000,000) and ``MA1000`` brings it back to the point
    where the counter was loaded."""
    h = quiet("PCIX-004", X=AxisWorld(home_low=5000.0, home_high=5100.0))
    assert typed(h, "AX;", "VL1000;", "HM1000;", "MA1000;", "GO;") == b""
    h.until(2.0)
    assert h.position("X") == 1999  # 1000 * 2 s - 0.25 count lost in the ramp
    assert velocity(h, "X") == 1000
    h.until(5.0)
    assert h.position("X") == 4999  # not home yet: counter not loaded
    h.until(5.1)
    h.run()
    assert not moving(h, "X")
    assert h.position("X") == 1000
    assert 5000.0 <= physical(h, "X") < 5000.0 + 1000 / RATE
    assert h.send("QA\r") == reply("PNNH")
    assert h.errors() == []


def test_e74_query_hm_reports_switch_home_mode() -> None:
    """E74 ``AX; ?HM`` -> ``hs<LF>``: X in the default HS (switch) home mode. (The prose names the
    answers 'switch' and 'encoder'; the example prints ``hs``, which the test takes.)"""
    h = Harness("PCIX-400")
    assert typed(h, "AX;", "?HM") == reply("hs")
    assert h.errors() == []


def test_e75_hn_maintains_position_within_deadband_after_move() -> None:
    """E75 ``AX; VL100000; AC500000; HV50000; HD10; HG2000; HN; MR200000; GO;`` on a stepper
    with encoder: "A 200,000 step move is performed, then that position is maintained within the
    10 step dead band until commanded to a new position."

    The move is a trapezoid (VL²/AC = 20,000 counts of ramps): 2 s + 0.2 s = 2.2 s, over on tick
    4506. Then the load is knocked back 300 counts: with HG2000 the correction would ask for
    600,000 counts/s, "Hold gain (HG) will be used to scale the HV value" so it runs at most at
    HV 50,000, and brings the encoder back inside ±10 counts."""
    h = quiet("PCIX-040")
    assert typed(h, "AX;", "VL100000;", "AC500000;", "HV50000;", "HD10;", "HG2000;", "HN;") == b""
    assert typed(h, "MR200000;", "GO;") == b""
    end = end_tick(0, 200_000 / 100_000 + 100_000 / 500_000)
    assert end == 4506
    h.until(tick(end - 1))
    assert h.position("X") == 199_999
    h.until(tick(end))
    assert h.position("X") == 200_000
    assert (h.send("?HV\r"), h.send("?HD\r"), h.send("?HG\r")) == (
        reply("hv50000"),
        reply("hd10"),
        reply("hg2000"),
    )
    h.until(2.5)
    h.board.inject_slip("X", -300, h.t)
    h.advance(0.001)
    encoder = int(h.send("RE\r")[:-2])
    assert encoder < 199_990  # knocked out of the deadband
    for _ in range(40):  # the correction never runs faster than HV
        h.advance(0.0005)
        assert abs(velocity(h, "X")) <= 50_000
    h.until(3.5)
    assert abs(int(h.send("RE\r")[:-2]) - 200_000) <= 10
    assert not moving(h, "X")
    assert h.errors() == []


def test_e76_hn_closes_servo_loop() -> None:
    """E76 ``AX; HN;``: "Close PID loop or X axis". The servo loop is open at power-up (HF,
    ``?PM`` -> ``hf``); after HN ``?PM`` reports ``hn`` and the motor follows a move: the encoder
    ends where the trajectory does."""
    h = quiet("PCIX-400")
    assert typed(h, "AX;", "?PM") == reply("hf")
    assert typed(h, "AX;", "HN;") == b""
    assert h.send("?PM\r") == reply("hn")
    typed(h, "MR1000;", "GO;")
    h.run()
    h.advance(0.5)
    assert h.send("RP\r") == reply("1000")
    assert abs(int(h.send("RE\r")[:-2]) - 1000) <= 1
    assert h.errors() == []


def test_e77_fast_hh_home_then_slow_hl_hr_refines_it() -> None:
    """E77 ``AX; VL100000; HH; HM; VL1000; HL; HR;``: "get close to home at higher speed, and then
    refine the position at lower speed in the reverse direction".

    A normally open home switch at physical 50,000..50,200. With HH (active high) the home
    condition is "switch open"; the fast HM pass finds its false-to-true edge where the stage
    leaves the switch at 50,200, loads 0 (no parameter: "HM command will use zero") and ramps to a
    stop 2,500 counts beyond (100,000² / 2 AC). HR at 1000 counts/s with HL comes back and finds
    the switch closing at its upper edge, "less than the update rate" so within one sample's
    travel of the first whole step inside the switch (50,199: the switches see whole steps); it
    loads 0 there and stops 0.25 count further, still on count 0."""
    h = quiet("PCIX-004", X=AxisWorld(home_low=50_000.0, home_high=50_200.0))
    assert typed(h, "AX;", "VL100000;", "HH;", "HM;", "VL1000;", "HL;", "HR;") == b""
    h.until(0.3)
    assert velocity(h, "X") == 100_000
    h.until(0.6)  # through the switch at 0.527 s, stopped 25 ms later
    assert velocity(h, "X") <= 0
    assert 52_700.0 - 100 <= physical(h, "X") <= 52_700.0 + 100
    h.until(2.0)
    assert velocity(h, "X") == -1000  # the slow reverse pass
    h.run()
    assert not moving(h, "X")
    assert h.position("X") == 0
    assert 50_199.0 - 1000 / RATE <= physical(h, "X") <= 50_199.0
    assert 3.0 <= h.t <= 3.2
    assert h.send("QA\r") == reply("MNNH")
    assert h.errors() == []


@pytest.mark.parametrize("lines", [("AY;", "HS;"), ("AM;", "HS,1;")], ids=["AY-HS", "AM-HS,1"])
def test_e78_hs_returns_y_to_switch_homing(lines: tuple[str, ...]) -> None:
    """E78 ``AY; HS;`` or ``AM; HS,1;``: "Set up the Y axis so it will ignore the encoder signals
    and only use the home input". Y is first put in HE mode; its encoder index is away from the
    home switch (index at count 2050 of every 4000, switch at 1000..1100), so in HE mode home is
    never found. After HS, ``?HM`` reports ``hs`` and a slow HM stops at the switch edge alone."""
    world = NO_HOME.with_changes(home_low=1000.0, home_high=1100.0, encoder_index=2050)
    h = quiet("PCIX-040", Y=world)
    assert typed(h, "AY;", "HE;", "?HM") == reply("he")
    assert typed(h, *lines) == b""
    assert typed(h, "AY;", "?HM") == reply("hs")
    assert typed(h, "AX;", "?HM") == reply("hs")
    typed(h, "AY;", "VL1000;", "HM;")
    h.run(limit=5.0)
    assert not moving(h, "Y")
    assert h.position("Y") == 0
    assert 1000.0 <= physical(h, "Y") < 1000.0 + 1000 / RATE
    assert h.errors() == []


def test_e79_query_hs_reports_active_high_home() -> None:
    """E79 ``AZ; ?HS`` -> ``hh<LF>`` (printed "Response hh<LF>"): Z's home switch was set active
    high with HH. X, untouched, still reports the power-up HL."""
    h = Harness("PCIX-040")
    typed(h, "AZ;", "HH;")
    assert typed(h, "AZ;", "?HS") == reply("hh")
    assert typed(h, "AX;", "?HS") == reply("hl")
    assert h.errors() == []


def test_e80_query_hv_reports_t_hold_velocity() -> None:
    """E80 ``AT; ?HV`` -> ``hv20000<LF>``: T's hold velocity is 20000 (stepper with encoder; "This
    command works only with stepper + encoder axes"). X keeps the factory HV0."""
    h = Harness("PCIX-040")
    typed(h, "AT;", "HV20000;")
    assert typed(h, "AT;", "?HV") == reply("hv20000")
    assert typed(h, "AX;", "?HV") == reply("hv0")
    assert h.errors() == []


# -- IC, ID, II, IN, IP (5.9.5) --------------------------------------------------------------------


def test_e81_ic_clears_done_flags_set_by_id() -> None:
    """E81 ``AX; MR5000; GO; ID; IC;``: ID sets X's done flag when the 5000-count move is over
    (tick 205); IC ("done flag cleared on PC1x") clears it and DON_S."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "MR5000;", "GO;", "ID;") == b""
    end = end_tick(0, move_time(5000))
    assert end == 205
    h.until(tick(end - 1))
    assert h.board.registers.done == 0
    h.until(tick(end))
    assert h.send("QA\r") == reply("PDNN")
    assert h.board.registers.done == 0b0001
    assert h.board.status_register(h.t) & DON_S
    assert typed(h, "IC;") == b""
    assert h.send("QA\r") == reply("PNNN")
    assert h.board.registers.done == 0
    assert h.board.status_register(h.t) & DON_S == 0
    assert h.position("X") == 5000
    assert h.errors() == []


def test_e82_id_after_ma_flags_done_when_move_is_finished() -> None:
    """E82 ``AX; MA100000; GO; ID;``: "When the move is finished the ID command will be
    encountered in the command queue and will set the done flags": at tick 1229 (0.6 s), not
    before."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "MA100000;", "GO;", "ID;") == b""
    end = end_tick(0, move_time(100_000))
    assert end == 1229
    h.until(tick(end - 1))
    assert h.position("X") == 99_999
    assert h.board.registers.done == 0
    assert done_events(h) == []
    h.until(tick(end))
    assert h.position("X") == 100_000
    assert h.board.registers.done == 0b0001
    events = done_events(h)
    assert [e.time for e in events] == [tick(end)]
    assert events[0].done_register == 0b0001


def test_e83_sw2_id_notifies_when_input_2_goes_false() -> None:
    """E83 ``SW2; ID;``: "Wait until an input line becomes false then notify the host".

    Wording (digest §8.2 27): SW waits "until the general purpose input line has been released
    (allowed to go high)", and an input is "true; i.e. low (default)" (WS), so "becomes false"
    is the same event: the line going high. Bit 2 is a factory input (bits 0-3). The line is held
    low (true) first: no done flag; released, the flag is set at once."""
    h = quiet("PCIX-004")
    h.board.set_input(2, False, h.t)
    assert typed(h, "SW2;", "ID;") == b""
    h.until(1.0)
    assert h.board.registers.done == 0
    assert done_events(h) == []
    h.board.set_input(2, None, h.t)  # released: pulled high
    h.advance(1 / RATE)
    assert h.board.registers.done == 0b0001
    events = done_events(h)
    assert len(events) == 1
    assert 1.0 <= events[0].time <= 1.0 + 1 / RATE
    assert h.errors() == []


def test_e84_ii_interrupts_separately_as_y_and_t_finish() -> None:
    """E84 ``AM; MR,1000,,10000; GO; II;``: "interrupts when the Y and T axes finish. If they do
    not complete at the same time, two separate interrupts would be generated." Y (1000 counts)
    is over on tick 92, T (10,000) on tick 290; X and Z had no parameter."""
    h = quiet("PCIX-004")
    assert typed(h, "AM;", "MR,1000,,10000;", "GO;", "II;") == b""
    y_end, t_end = end_tick(0, move_time(1000)), end_tick(0, move_time(10_000))
    assert (y_end, t_end) == (92, 290)
    h.until(tick(y_end - 1))
    assert h.board.registers.done == 0
    h.until(tick(y_end))
    assert h.board.status_register(h.t) & DON_S
    assert h.board.registers.done == 0b0010
    h.until(tick(t_end - 1))
    assert h.board.registers.done == 0b0010
    h.until(tick(t_end))
    assert h.board.registers.done == 0b1010
    events = done_events(h)
    assert [e.time for e in events] == [tick(y_end), tick(t_end)]
    assert positions(h) == [0, 1000, 0, 10_000]
    assert h.send("QI\r") == reply("PNNN,PDNN,PNNN,PDNN")


def test_e85_in_interrupts_once_when_x_done_and_z_nearly_done() -> None:
    """E85 ``AA; IN0,,10000; MR100000,100000; GO; MR,,50000; GO;``: "interrupt the host once when
    the X axis is complete and the Z axis is within 10,000 counts of being complete. The Y axis
    completion would be ignored".

    X and Y move 100,000 (over on tick 1229); in AA mode the Z move waits for them and starts on
    tick 1229. Z's 50,000 counts: ramp 0.1 s, cruise 0.15 s, ramp down 0.1 s over exactly 10,000
    counts, so it is within 10,000 counts when it starts decelerating, 0.25 s = 512 ticks after
    its start: tick 1741. One interrupt then, with X and Z in the done register."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "IN0,,10000;", "MR100000,100000;", "GO;", "MR,,50000;", "GO;") == b""
    xy_end = end_tick(0, move_time(100_000))
    near = xy_end + 512
    assert near == 1741
    h.until(tick(xy_end))
    assert h.board.registers.done == 0b0001  # X complete
    assert h.board.status_register(h.t) & DON_S == 0
    h.until(tick(near - 1))
    assert h.position("Z") < 40_000
    assert done_events(h) == []
    h.until(tick(near))
    events = done_events(h)
    assert [(e.time, e.done_register) for e in events] == [(tick(near), 0b0101)]
    assert h.position("Z") == 40_000
    h.run()
    assert positions(h) == [100_000, 100_000, 50_000, 0]
    assert h.board.registers.done & 0b0010 == 0  # Y ignored
    assert done_events(h) == []  # "only a single interrupt"
    assert h.errors() == []


def test_e86_ip_waits_until_encoder_is_inside_deadband() -> None:
    """E86 ``AX; HV1000; HG100; HD10; HN; MR1000; GO; IP;``: "Set the done flag when axis is
    within its dead band".

    The load slips +50 counts during the move (at 0.02 s), so when the pulses end (tick 92) the
    encoder reads about 1045: outside the 10-count deadband, no done flag. Position maintenance
    (at most HV 1000 counts/s) brings it back; the flag is set only once the encoder is within
    10 counts of 1000."""
    h = quiet("PCIX-040")
    typed(h, "AX;", "HV1000;", "HG100;", "HD10;", "HN;", "MR1000;", "GO;", "IP;")
    h.until(0.02)
    h.board.inject_slip("X", 50, h.t)
    end = end_tick(0, move_time(1000))
    h.until(tick(end))
    assert h.board.registers.done == 0
    assert int(h.send("RE\r")[:-2]) > 1010
    h.until(0.5)
    events = done_events(h)
    assert len(events) == 1
    # the correction of at least 35 counts takes at least 35 ms at 1000 counts/s
    assert events[0].time >= tick(end) + 0.035
    assert h.board.registers.done == 0b0001
    assert abs(int(h.send("RE\r")[:-2]) - 1000) <= 10
    assert h.send("EA\r")[:4] == b"DENP"  # maintenance enabled, no slip, within deadband
    assert h.errors() == []


# -- JF, JG (5.9.1) -------------------------------------------------------------------------------


def test_e87_jf_jogs_y_at_fractional_velocity() -> None:
    """E87 ``AY; JF2.667;``: "Jog the Y axis at 2 2/3 steps per second". The fraction is kept
    (800 counts in 300 s, not 600 or 900); RV shows the integer part; "The velocity set by this
    command will remain the default velocity"."""
    h = quiet("PCIX-004")
    assert typed(h, "AY;", "JF2.667;") == b""
    h.until(30.0)
    assert h.send("RV\r") == reply("2")
    assert h.send("RP\r") == reply("80")
    h.until(300.0)
    assert h.send("RP\r") == reply("800")
    assert h.send("AX;RP\r") == reply("0")
    assert h.axis("Y").vl == pytest.approx(2.667)
    assert h.errors() == []


def test_e88_jg_staircase_wt_then_st_and_reverse_jog() -> None:
    """E88 ``JG100000; JG35000; WT5000; ST; JG-5000;``: "the motor will ramp from zero to
    100,000, ramp back down to 35,000, flatten out at 35,000 for 5 seconds, then ramp to a stop,
    before moving in the negative direction at a velocity of 5,000."

    "Output events waiting for completion of JG will begin when JG is up to its requested
    velocity": JG35000 starts on the first tick after 100,000 is reached at 0.05 s (103), reaches
    35,000 32.5 ms later, and WT5000 starts on the next tick (170) and ends 5 s later.

    ST "is executed immediately upon receipt" and "flushes the queue": typed in the same burst it
    would cancel JG35000 and WT5000 before they ran, and the stated behaviour could not happen.
    So the test types the first three lines, then ST and JG-5000 once the 5 s are over (tick
    10424), as the description implies. Positions: 2500 + 100,000 × (103/2048 - 0.05) at tick
    103, + 2193.75 slowing to 35,000, + 35,000 × cruise, + 306.25 stopping (35,000² / 2 AC).
    The reverse jog starts on the tick after the stop and reaches -5000 in 2.5 ms."""
    h = quiet("PCIX-004")
    assert typed(h, "JG100000;", "JG35000;", "WT5000;") == b""
    h.until(0.025)
    assert h.send("RV\r") == reply("50000")
    h.until(tick(103))
    assert h.send("RV\r") == reply("100000")
    h.until(tick(103) + 0.01)
    assert h.send("RV\r") == reply("80000")
    h.until(0.2)
    assert h.send("RV\r") == reply("35000")
    assert h.send("?VL\r") == reply("vl35000")  # "This command modifies ... (VL)"
    assert h.send("RQ\r") == free(QUEUE - 3)  # WT5000 waiting (3 units)
    wt_start = ticks_after(tick(103) + 65_000 / AC0)
    assert wt_start == 170
    h.until(tick(wt_start) + 5.0 - 1 / 4096)
    assert h.send("RQ\r") == free(QUEUE - 3)
    h.until(tick(wt_start) + 5.0 + 1 / 4096)
    assert h.send("RQ\r") == free(QUEUE)
    st = 10_424
    h.until(tick(st))
    assert h.send("RV\r") == reply("35000")
    assert typed(h, "ST;", "JG-5000;") == b""
    stop_end = ticks_after(tick(st) + 35_000 / AC0)
    assert stop_end == 10_460
    at_tick_103 = 2500 + 100_000 * (tick(103) - 0.05)
    cruise = 35_000 * (tick(st) - tick(103) - 65_000 / AC0)
    stopped_at = at_tick_103 + 2193.75 + cruise + 306.25
    h.until(tick(stop_end))
    assert h.send("RP\r") == reply(str(math.floor(stopped_at)))
    h.until(tick(stop_end) + 1.0)
    assert h.send("RV\r") == reply("-5000")
    later = stopped_at - 6.25 - 5000 * (1.0 - 0.0025)
    assert h.send("RP\r") == reply(str(math.ceil(later)))  # whole steps taken going down
    assert h.errors() == []


# -- servo gains K* (5.6.2) ------------------------------------------------------------------------


def test_e89_ka_sets_t_acceleration_feedforward() -> None:
    """E89 ``AT; KA2;``: KA of T becomes 2 (``?KA`` prints two decimals, as ``ka10.50``); the
    other axes keep the factory 0."""
    h = Harness("PCIX-400")
    assert typed(h, "AT;", "KA2;") == b""
    assert h.send("?KA\r") == reply("ka2.00")
    assert typed(h, "AX;", "?KA") == reply("ka0.00")
    assert h.errors() == []


def test_e90_query_ka_reports_y_acceleration_feedforward() -> None:
    """E90 ``AY; ?KA`` -> ``ka10.50<LF>`` with Y's KA at 10.5."""
    h = Harness("PCIX-400")
    typed(h, "AY;", "KA10.5;")
    assert typed(h, "AY;", "?KA") == reply("ka10.50")
    assert h.errors() == []


def test_e91_kb_limits_y_dac_output_bound() -> None:
    """E91 ``AY; KB9;``: "Limit the servo output from DAC to 9 max on Y axis". The example's
    "approximately half of its normal range" cannot be squared with "0.0 ≤ KB ≤ 10.0" (digest
    §8.2 3); the test takes the value: ``?KB`` reports ``kb9.00`` and X is untouched."""
    h = Harness("PCIX-400")
    assert typed(h, "AY;", "KB9;") == b""
    assert h.send("?KB\r") == reply("kb9.00")
    servo = h.axis("Y").servo
    assert servo is not None and servo.gains.kb == 9.0
    assert typed(h, "AX;", "?KB") != reply("kb9.00")
    assert h.errors() == []


def test_e92_query_kb_reports_x_upper_bound() -> None:
    """E92 ``AX; ?KB`` -> ``kb5.00<LF>`` with X's KB at 5."""
    h = Harness("PCIX-400")
    typed(h, "AX;", "KB5;")
    assert typed(h, "AX;", "?KB") == reply("kb5.00")
    assert h.errors() == []


def test_e93_kd_sets_z_derivative_gain() -> None:
    """E93 ``AZ; KD56;``: Z's KD becomes 56; the others keep the factory 20.00 (KD page "The
    factory default value is 20.00" and RF's "KD20.00" over §2.8's "KD160.0", digest §8.2 1)."""
    h = Harness("PCIX-400")
    assert typed(h, "AZ;", "KD56;") == b""
    assert h.send("?KD\r") == reply("kd56.00")
    assert typed(h, "AY;", "?KD") == reply("kd20.00")
    assert h.errors() == []


def test_e94_query_kd_reports_y_derivative_gain() -> None:
    """E94 ``AY; ?KD`` -> ``kd5.12<LF>`` with Y's KD at 5.12."""
    h = Harness("PCIX-400")
    typed(h, "AY;", "KD5.12;")
    assert typed(h, "AY;", "?KD") == reply("kd5.12")
    assert h.errors() == []


def test_e95_kf_sets_y_friction_coefficient() -> None:
    """E95 ``AY; KF100;``: Y's friction coefficient becomes 100 (``?KF`` prints an integer, as
    ``kf12``); the others keep "The default value is 0"."""
    h = Harness("PCIX-400")
    assert typed(h, "AY;", "KF100;") == b""
    assert h.send("?KF\r") == reply("kf100")
    assert typed(h, "AZ;", "?KF") == reply("kf0")
    assert h.errors() == []


def test_e96_query_kf_reports_z_friction_offset() -> None:
    """E96 ``AZ; ?KF`` -> ``kf12<LF>`` with Z's KF at 12."""
    h = Harness("PCIX-400")
    typed(h, "AZ;", "KF12;")
    assert typed(h, "AZ;", "?KF") == reply("kf12")
    assert h.errors() == []


def test_e97_ki_sets_x_integral_gain() -> None:
    """E97 ``AX; KI3.42;``: X's KI becomes 3.42; the others keep "Default value is 0.04" (KI
    page and RF list over §2.8's "KI1.0", digest §8.2 2)."""
    h = Harness("PCIX-400")
    assert typed(h, "AX;", "KI3.42;") == b""
    assert h.send("?KI\r") == reply("ki3.42")
    assert typed(h, "AT;", "?KI") == reply("ki0.04")
    assert h.errors() == []


def test_e98_query_ki_reports_z_integral_gain() -> None:
    """E98 ``AZ; ?KI`` -> ``ki1.00<LF>`` with Z's KI at 1."""
    h = Harness("PCIX-400")
    typed(h, "AZ;", "KI1;")
    assert typed(h, "AZ;", "?KI") == reply("ki1.00")
    assert h.errors() == []


# -- KL, KM, KR, KS (5.9.4, 5.7.4) -----------------------------------------------------------------


def test_e99_kl_discards_wrong_move_before_go() -> None:
    """E99 ``AX; MR5000; (*oops!*) KL; MR-5000; GO;``: KL flushes "a partially entered incorrect
    move command ... before GO is entered", so only the -5000 move runs: X never goes positive
    and ends at -5000 on tick 205."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "MR5000;", "KL;", "MR-5000;", "GO;") == b""
    h.until(0.01)
    assert velocity(h, "X") == -20_000
    end = end_tick(0, move_time(5000))
    h.until(tick(end))
    assert h.send("RP\r") == reply("-5000")
    h.run()
    assert h.send("RP\r") == reply("-5000")
    assert h.send("QA\r")[:1] == b"M"
    assert h.errors() == []


def test_e100_km_moves_y_to_home_and_stops_without_ramp() -> None:
    """E100 ``AY; KM;``: "Move the Y axis in the positive direction to the home sensor and stop
    movement as quickly as possible". Y runs at VL 200,000 toward a switch at 3000..3500 (reached
    at about 109,500 counts/s, 53 counts per sample) and stops at once: a ramp at AC would carry
    it 3000 counts past. "The position counter will not be reset": it equals the distance run."""
    h = quiet("PCIX-004", Y=AxisWorld(home_low=3000.0, home_high=3500.0))
    assert typed(h, "AY;", "KM;") == b""
    h.run()
    assert not moving(h, "Y")
    v_switch = math.sqrt(2 * 3000 * AC0)
    assert 3000 <= h.position("Y") < 3000 + v_switch / RATE + 1
    assert h.position("Y") == math.floor(physical(h, "Y"))
    assert h.send("QA\r") == reply("PNNH")
    assert h.errors() == []


def test_e101_ko_sets_y_offset() -> None:
    """E101 ``AY; KO-2000;``: Y's offset coefficient becomes -2000 ("~ -610mV", one count being
    "approximately ... 0.0003 volts"); X keeps the factory 0."""
    h = Harness("PCIX-400")
    assert typed(h, "AY;", "KO-2000;") == b""
    assert h.send("?KO\r") == reply("ko-2000")
    assert typed(h, "AX;", "?KO") == reply("ko0")
    assert h.errors() == []


def test_e102_query_ko_reports_offset_of_current_axis() -> None:
    """E102 ``?KO`` -> ``ko218<LF >`` (the space is a typesetting artefact) with KO 218 on the
    current axis (X, the power-up mode)."""
    h = Harness("PCIX-400")
    typed(h, "KO218;")
    assert typed(h, "?KO") == reply("ko218")
    assert h.errors() == []


def test_e103_kp_sets_z_proportional_gain() -> None:
    """E103 ``AZ; KP45.6;``: Z's KP becomes 45.6; X keeps the factory 10.00."""
    h = Harness("PCIX-400")
    assert typed(h, "AZ;", "KP45.6;") == b""
    assert h.send("?KP\r") == reply("kp45.60")
    assert typed(h, "AX;", "?KP") == reply("kp10.00")
    assert h.errors() == []


def test_e104_query_kp_reports_factory_gain() -> None:
    """E104 ``AX; ?KP`` -> ``kp10.00<LF >`` at power-up ("Default value is 10.00")."""
    h = Harness("PCIX-400")
    assert typed(h, "AX;", "?KP") == reply("kp10.00")
    assert h.errors() == []


def test_e105_kr_moves_y_to_home_in_reverse_and_stops_without_ramp() -> None:
    """E105 ``AY; KR;``: as E100 in the negative direction ("identical to the KM command except
    that the direction of motion is reversed"), switch at -3500..-3000."""
    h = quiet("PCIX-004", Y=AxisWorld(home_low=-3500.0, home_high=-3000.0))
    assert typed(h, "AY;", "KR;") == b""
    h.run()
    assert not moving(h, "Y")
    v_switch = math.sqrt(2 * 3000 * AC0)
    assert -(3000 + v_switch / RATE + 1) < h.position("Y") <= -3000
    assert h.send("QA\r") == reply("MNNH")
    assert h.errors() == []


@pytest.mark.parametrize("lines", [("AY;", "KS;"), ("AA;", "KS,1;")], ids=["AY-KS", "AA-KS,1"])
def test_e106_ks_kills_y_only(lines: tuple[str, ...]) -> None:
    """E106 ``AY; KS;`` or ``AA; KS,1;``: "The Y axis has hit a limit switch and is now executing
    commands that were waiting in the queue. This axis must be reset but the other axes must be
    allowed to continue operation."

    Y runs in SL mode (a limit ramps it to a stop and "The output queue is not flushed except for
    the current move") into its positive limit at 5000, then goes on with its queued -2000
    moves. KS then stops Y at once ("performs the same operation as the KL command": no ramp)
    and flushes Y's queue only; X's long move goes on to its end."""
    h = quiet("PCIX-004", Y=NO_HOME.with_changes(positive_limit=5000.0))
    typed(h, "AY;", "SL;", "MR10000;", "GO;", "MR-2000;", "GO;", "MR-2000;", "GO;")
    typed(h, "MR-2000;", "GO;", "AX;", "MR200000;", "GO;")
    h.until(0.2)  # Y has met the limit and is running its queued -2000 moves
    assert ("Y", 1) in limit_events(h)
    assert velocity(h, "Y") < 0
    assert typed(h, *lines) == b""
    h.advance(1 / RATE)
    assert velocity(h, "Y") == 0
    stopped = h.position("Y")
    assert typed(h, "AY;", "RQ").split(b", ")[1] == str(QUEUE).encode()  # Y's queue is empty
    assert moving(h, "X")
    h.run()
    assert h.position("Y") == stopped
    assert h.position("X") == 200_000
    assert h.errors() == []


def test_e107_ku_sets_x_integration_sum_limit() -> None:
    """E107 ``AX; KU150;``: X's integration sum upper limit becomes 150 (integer reply, as
    ``ku150``)."""
    h = Harness("PCIX-400")
    assert typed(h, "AX;", "KU150;") == b""
    assert h.send("?KU\r") == reply("ku150")
    assert typed(h, "AY;", "?KU") != reply("ku150")
    assert h.errors() == []


def test_e108_query_ku_reports_x_integration_sum_limit() -> None:
    """E108 ``AX; ?KU`` -> ``ku150<LF>`` with X's KU at 150."""
    h = Harness("PCIX-400")
    typed(h, "AX;", "KU150;")
    assert typed(h, "AX;", "?KU") == reply("ku150")
    assert h.errors() == []


def test_e109_kv_sets_y_velocity_feedforward() -> None:
    """E109 ``AY; KV35.3;``: Y's KV becomes 35.3; the others keep "The factory default value is
    zero"."""
    h = Harness("PCIX-400")
    assert typed(h, "AY;", "KV35.3;") == b""
    assert h.send("?KV\r") == reply("kv35.30")
    assert typed(h, "AX;", "?KV") == reply("kv0.00")
    assert h.errors() == []


def test_e110_query_kv_reports_t_velocity_feedforward_zero() -> None:
    """E110 ``AT; ?KV`` -> ``kv0.00<LF>``: T's KV at its factory zero."""
    h = Harness("PCIX-400")
    assert typed(h, "AT;", "?KV") == reply("kv0.00")
    assert h.errors() == []


# -- LA, LS/LE, LF, LH, LL, ?LM, LN, LO, LP, ?LS ---------------------------------------------------


def test_e111_la_selects_linear_ramp_for_x_only() -> None:
    """E111 ``AX; LA;`` after PN (parabolic ramps on all axes): X alone goes back to linear
    (``?RT`` ``la``; the manual lists the answer "LA" and prints them lower case, ``sr3``). A
    100,000-count move of X and Y: X is over on tick 1229 as a linear ramp, Y with its parabolic
    ramp is not."""
    h = quiet("PCIX-004")
    typed(h, "PN;")
    assert typed(h, "AX;", "LA;") == b""
    assert typed(h, "AX;", "?RT") == reply("la")
    assert typed(h, "AY;", "?RT") == reply("pr3")
    typed(h, "AA;", "MR100000,100000;", "GO;")
    end = end_tick(0, move_time(100_000))
    h.until(tick(end - 1))
    assert h.position("X") == 99_999
    h.until(tick(end))
    assert h.position("X") == 100_000
    assert h.position("Y") < 100_000
    h.run()
    assert positions(h)[:2] == [100_000, 100_000]
    assert h.errors() == []


def test_e112_aa_la_selects_linear_ramp_for_y_and_t() -> None:
    """E112 ``AA ; LA,1,,1;`` after CN (cosine on all axes): Y and T linear, X and Z cosine."""
    h = quiet("PCIX-004")
    typed(h, "CN;")
    assert typed(h, "AA ;", "LA,1,,1;") == b""
    assert [typed(h, f"A{a};", "?RT") for a in "XYZT"] == [
        reply("sc"),
        reply("la"),
        reply("sc"),
        reply("la"),
    ]
    typed(h, "AA;", "MR100000,100000,100000,100000;", "GO;")
    end = end_tick(0, move_time(100_000))
    h.until(tick(end))
    x, y, z, t = positions(h)
    assert (y, t) == (100_000, 100_000)
    assert x < 100_000 and z < 100_000
    assert h.errors() == []


def test_e113_nested_loops_in_single_axis_mode_run_per_axis() -> None:
    """E113 ``AZ; LS5; MR5000; GO; AT; LS20; MR50; GO; MR-50; GO; LE; AZ; LE;``.

    The purpose printed ("After each Z move, wiggle the T axis 20 times") cannot be what the
    board does with these lines: LS "sets the loop counter for the axis being programmed in the
    single axis mode" and "If you are in the single axis mode in the loop, each axis' commands
    will go into their separate queues and execute independently of each other". The test takes
    the command pages: Z's queue holds LS5 MR5000 GO LE, T's LS20 (MR50 GO MR-50 GO) LE; both
    start at once. Z: five 5000-count moves of 205 ticks each, back to back (1025 ticks); T: 40
    moves of 50 counts, 21 ticks each (840 ticks), ending at 0. Queue space used inside a loop
    comes back when the loop is over."""
    h = quiet("PCIX-004")
    lines = ("AZ;", "LS5;", "MR5000;", "GO;", "AT;", "LS20;", "MR50;", "GO;", "MR-50;", "GO;")
    assert typed(h, *lines, "LE;", "AZ;", "LE;") == b""
    z_move, t_move = end_tick(0, move_time(5000)), end_tick(0, move_time(50))
    assert (z_move, t_move) == (205, 21)
    h.until(tick(t_move))
    assert h.position("T") == 50
    assert h.position("Z") == math.floor(AC0 * tick(t_move) ** 2 / 2)  # Z still ramping up
    h.until(tick(40 * t_move - 1))
    assert moving(h, "T")
    h.until(tick(40 * t_move))
    assert not moving(h, "T")
    assert h.position("T") == 0
    assert moving(h, "Z")
    h.until(tick(5 * z_move - 1))
    assert h.position("Z") == 24_999
    h.until(tick(5 * z_move))
    assert h.position("Z") == 25_000
    h.run()
    assert positions(h) == [0, 0, 25_000, 0]
    assert h.send("AA;RQ\r") == reply(", ".join([str(QUEUE)] * 4))
    assert h.errors() == []


@pytest.mark.parametrize("lines", [("AY;", "LF;"), ("AA;", "LF,1;")], ids=["AY-LF", "AA-LF,1"])
def test_e114_lf_lets_y_run_through_its_limit(lines: tuple[str, ...]) -> None:
    """E114 ``AY; LF;`` or ``AA; LF,1;``: "Set up a board to ignore the Y axis limit switches."
    Y's positive limit is at 5000; a 10,000-count move runs through it to the end (tick 290), and
    "The PC1x will still recognize that a limit switch has been closed ... and will report this
    information via the query commands" (QA ``L``). The LF note's "a null argument in the
    parameter list specifies that axis home switch to be affected" (digest §8.2 18) is taken as
    the LN/LH/LL notes word it: a null argument leaves that axis alone, so X keeps its limits."""
    h = quiet("PCIX-004", Y=NO_HOME.with_changes(positive_limit=5000.0))
    assert typed(h, *lines) == b""
    assert typed(h, "AY;", "?LM") == reply("lf")
    assert typed(h, "AX;", "?LM") == reply("ln")
    typed(h, "AY;", "MR10000;", "GO;")
    h.until(tick(end_tick(0, move_time(10_000))))
    assert h.position("Y") == 10_000
    assert h.send("QA\r") == reply("PNLN")
    assert h.errors() == []


def test_e115_lh_selects_active_high_limits_for_x() -> None:
    """E115 ``AX; LH;``: "Select the limit switch high true condition for the X axis": ``?LS``
    reports ``lh``; Y keeps the factory ``ll``."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "LH;") == b""
    assert h.send("?LS\r") == reply("lh")
    assert typed(h, "AY;", "?LS") == reply("ll")
    assert h.errors() == []


def test_e115_lh_treats_a_high_limit_line_as_overtravel() -> None:
    """E115, what LH does: "This command allows TTL logic high to be treated as the 'true'
    state". A stage whose limit switches are normally open (they ground their line when the
    carriage reaches them, ``limit_switches = "normally_open"``): in mid travel both of X's lines
    are high, which after LH is overtravel: QA shows ``L`` and a move of X is stopped at once by
    the limit it starts in. Y (LL) moves normally. (With the default "matched" wiring the
    switches suit whatever level is set, as the EPICS omsMAXnet init string ``AX LH`` needs.)"""
    wired = NO_HOME.with_changes(limit_switches=LimitWiring.NORMALLY_OPEN)
    h = quiet("PCIX-004", X=wired, Y=wired)
    typed(h, "AX;", "LH;")
    assert h.send("QA\r")[2:3] == b"L"
    typed(h, "AX;", "MR1000;", "GO;", "AY;", "MR1000;", "GO;")
    h.run()
    assert h.position("X") == 0
    assert h.position("Y") == 1000
    assert ("X", 1) in limit_events(h)


def test_e116_aa_lh_selects_active_high_limits_for_z_and_t() -> None:
    """E116 ``AA; LH,,1,1;``: Z and T active high; "a null argument ... specifies that axis is
    not to be affected": X and Y stay ``ll``."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "LH,,1,1;") == b""
    assert [typed(h, f"A{a};", "?LS") for a in "XYZT"] == [
        reply("ll"),
        reply("ll"),
        reply("lh"),
        reply("lh"),
    ]
    assert h.errors() == []


def test_e117_ll_restores_active_low_limits_for_x() -> None:
    """E117 ``AX; LL;`` (after LH): X's limits are active low again (``ll``, "This is the factory
    default mode"), so in mid travel X is not in overtravel and moves normally."""
    h = quiet("PCIX-004")
    typed(h, "AX;", "LH;")
    assert typed(h, "AX;", "LL;") == b""
    assert h.send("?LS\r") == reply("ll")
    assert h.send("QA\r") == reply("PNNN")
    typed(h, "MR1000;", "GO;")
    h.run()
    assert h.position("X") == 1000
    assert h.errors() == []


def test_e118_aa_ll_restores_active_low_limits_for_y_and_t() -> None:
    """E118 ``AA; LL,1,,1;`` after all four were set active high: Y and T go back to ``ll``, X
    and Z ("null argument ... not to be affected") stay ``lh``."""
    h = quiet("PCIX-004")
    typed(h, "AA;", "LH1,1,1,1;")
    assert typed(h, "AA;", "LL,1,,1;") == b""
    assert [typed(h, f"A{a};", "?LS") for a in "XYZT"] == [
        reply("lh"),
        reply("ll"),
        reply("lh"),
        reply("ll"),
    ]
    assert h.errors() == []


def test_e119_query_lm_reports_z_limits_enabled() -> None:
    """E119 ``AZ; ?LM``: the manual prints ``In<LF>``, an OCR-garbled ``ln`` (digest §8.2 14):
    the reply is the mnemonic of the mode set, LN, lower case, like every other ``?`` reply."""
    h = Harness("PCIX-004")
    assert typed(h, "AZ;", "?LM") == reply("ln")
    assert h.errors() == []


@pytest.mark.parametrize(
    "lines", [("AA;", "LN,1,,1;"), ("AY;", "LN;", "AT;", "LN;")], ids=["AA-LN", "AY-LN-AT-LN"]
)
def test_e120_ln_makes_y_and_t_stop_at_their_limits(lines: tuple[str, ...]) -> None:
    """E120 ``AA; LN,1,,1;`` or ``AY; LN; AT; LN;``: "Set up the Y and T axes to stop immediately
    when a limit switch is encountered". All four limits were off (LF); after LN, Y and T stop at
    their positive limits (5000) within one sample's travel (SF: "abruptly halt"), X and Z,
    still LF, run through theirs to 10,000."""
    limit = NO_HOME.with_changes(positive_limit=5000.0)
    h = quiet("PCIX-004", X=limit, Y=limit, Z=limit, T=limit)
    typed(h, "AA;", "LF1,1,1,1;")
    assert typed(h, *lines) == b""
    assert [typed(h, f"A{a};", "?LM") for a in "XYZT"] == [
        reply("lf"),
        reply("ln"),
        reply("lf"),
        reply("ln"),
    ]
    typed(h, "AA;", "MR10000,10000,10000,10000;", "GO;")
    h.run()
    x, y, z, t = positions(h)
    assert (x, z) == (10_000, 10_000)
    v_limit = math.sqrt(2 * 5000 * AC0)
    for p in (y, t):
        assert 5000 <= p <= 5000 + v_limit / RATE + 1
    assert sorted(limit_events(h)) == [("T", 1), ("Y", 1)]
    assert h.errors() == []


def test_e121_lo_sets_motor_position_apart_from_encoder() -> None:
    """E121 ``AT; LP100000; LO50000;``: "Set the motor position to 50,000 and the encoder
    position to 100,000 on the T axis" (T has an encoder)."""
    h = Harness("PCIX-040")
    assert typed(h, "AT;", "LP100000;", "LO50000;") == b""
    assert h.send("RP\r") == reply("50000")
    assert h.send("RE\r") == reply("100000")
    assert h.errors() == []


def test_e122_aa_lp_loads_x_and_z() -> None:
    """E122 ``AA; LP1000,,2000;``: X's position register 1000, Z's 2000; "if no parameter is
    supplied for an axis, the position is left unchanged"."""
    h = quiet("PCIX-004")
    typed(h, "AA;", "LP,7,,9;")
    assert typed(h, "AA;", "LP1000,,2000;") == b""
    assert h.send("RP\r") == reply("1000,7,2000,9")
    assert h.errors() == []


def test_e123_er_then_lp_loads_encoder_and_scaled_position() -> None:
    """E123 ``AY; ER3,2; LP30000;``: "load the Y axis position register with 20,000 and the
    encoder position register with 30,000 counts": the parameter goes to the encoder register
    and "the parameter times the encoder ratio" (2/3) to the position counter."""
    h = quiet("PCIX-040")
    assert typed(h, "AY;", "ER3,2;", "LP30000;") == b""
    assert h.send("RE\r") == reply("30000")
    assert h.send("RP\r") == reply("20000")
    assert h.errors() == []


def test_e124_ls_first_pass_runs_at_once_rest_after_le() -> None:
    """E124 ``AZ; LS5; MR100000; GO; LE;``: "The first move will occur immediately after entering
    the GO command. The remaining 4 moves will be executed after the loop terminator LE has been
    entered." LE is typed 2 s after GO: Z has made one move (1229 ticks) and waits; after LE
    four more run back to back."""
    h = quiet("PCIX-004")
    assert typed(h, "AZ;", "LS5;", "MR100000;", "GO;") == b""
    move = end_tick(0, move_time(100_000))
    h.until(tick(move))
    assert h.position("Z") == 100_000
    h.until(2.0)
    assert h.position("Z") == 100_000
    assert not moving(h, "Z")
    assert typed(h, "LE;") == b""
    h.until(2.0 + tick(4 * move) - 1 / RATE)
    assert h.position("Z") == 499_999
    h.until(2.0 + tick(4 * move))
    assert h.position("Z") == 500_000
    h.run()
    assert h.position("Z") == 500_000
    assert h.send("RQ\r") == free(QUEUE)
    assert h.errors() == []


def test_e125_aa_loop_relative_then_absolute_four_times() -> None:
    """E125 ``AA; LS4; MR100000,,,100; GO; MA100,,,200; GO; LE;``: X +100,000 with T +100, then
    X to 100 and T to 200, four times. Every pass ends at X 100, T 200. AA moves wait for each
    other; X sets the pace: 99,900 counts back in the first pass (1228 ticks), 100,000 every
    other move (1229)."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "LS4;", "MR100000,,,100;", "GO;", "MA100,,,200;", "GO;", "LE;") == b""
    first = end_tick(0, move_time(100_000))
    back = end_tick(0, move_time(99_900))
    assert (first, back) == (1229, 1228)
    h.until(tick(first))
    assert positions(h) == [100_000, 0, 0, 100]
    h.until(tick(first + back))
    assert positions(h) == [100, 0, 0, 200]
    total = first + back + 6 * first
    h.until(tick(total - 1))
    assert moving(h, "X")
    h.until(tick(total))
    assert positions(h) == [100, 0, 0, 200]
    assert not moving(h, "X")
    h.run()
    assert h.send("RP\r") == reply("100,0,0,200")
    assert h.send("RQ\r") == reply(", ".join([str(QUEUE)] * 4))
    assert h.errors() == []


def test_e126_query_ls_reports_y_limit_level() -> None:
    """E126 ``AY; ?LS`` -> ``ll<LF> or lh<LF>``: ``ll`` at power-up, ``lh`` after LH."""
    h = Harness("PCIX-004")
    assert typed(h, "AY;", "?LS") == reply("ll")
    typed(h, "LH;")
    assert typed(h, "AY;", "?LS") == reply("lh")
    assert h.errors() == []


# -- MA, MD, ML, MM, MO, MR, MT, MV, MX (5.9.2, 5.9.6, 5.4.7) --------------------------------------


def test_e127_ma_moves_x_to_100000() -> None:
    """E127 ``AX; MA100000; GO;``: with the power-up VL and AC, a 0.6 s trapezoid over on tick
    1229."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "MA100000;", "GO;") == b""
    h.until(0.3)
    assert h.send("RV\r") == reply("200000")
    end = end_tick(0, move_time(100_000))
    h.until(tick(end - 1))
    assert h.send("RP\r") == reply("99999")
    h.until(tick(end))
    assert h.send("RP\r") == reply("100000")
    assert not moving(h, "X")
    assert h.errors() == []


def test_e128_aa_ma_moves_y_and_t_together() -> None:
    """E128 ``AA; MA,10000,,1000;GO;``: Y to 10,000 and T to 1000 start on the same tick, "The
    other axes will remain in their current positions"; each with its own VL/AC, so T is over on
    tick 92 and Y on tick 290."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "MA,10000,,1000;", "GO;") == b""
    h.until(tick(1))
    assert h.send("RV\r") == reply("0,976,0,976")
    y_end, t_end = end_tick(0, move_time(10_000)), end_tick(0, move_time(1000))
    assert (y_end, t_end) == (290, 92)
    h.until(tick(t_end))
    assert h.position("T") == 1000
    assert moving(h, "Y")
    h.until(tick(y_end))
    assert h.send("RP\r") == reply("0,10000,0,1000")
    assert h.errors() == []


def test_e129_md_defines_macro_2_for_a_two_axis_board() -> None:
    """E129 ``MD2; AA; VL20000,20000; ^Z``: "Define macro 2 to set velocities to 20000 on all axes
    of a two axes board". Defining runs nothing (VL is still 200,000); PM2 prints the macro string
    as it was typed between ``MD2;`` and ``^Z`` (Enter keys included: "If <LF> character is used
    as command terminator it will be sent back"); MX2 runs it."""
    h = quiet("PCIX-002")
    assert typed(h, "MD2;", "AA;", "VL20000,20000;", "^Z") == b""
    assert typed(h, "AX;", "?VL") == reply("vl200000")
    assert h.send("PM2;") == b"\rAA;\rVL20000,20000;\r" + b"\n\r"
    assert typed(h, "MX2;") == b""
    assert typed(h, "AX;", "?VL") == reply("vl20000")
    assert typed(h, "AY;", "?VL") == reply("vl20000")
    assert h.errors() == []


def test_e130_aa_ml_moves_y_z_t_starting_and_finishing_together() -> None:
    """E130 ``AA; ML,10000,100,1000; GO;``: "move the Y, Z and T axes 10000, 100 and 1000 counts
    respectively with all axes starting and finishing together". Y, the longest, is the master
    (0.1414 s, tick 290); Z and T are scaled to it, so they stay in proportion all the way."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "ML,10000,100,1000;", "GO;") == b""
    end = end_tick(0, move_time(10_000))
    assert end == 290
    h.until(0.07)
    assert h.send("RP\r") == reply("0,4900,49,490")
    assert h.send("RV\r") == reply("0,140000,1400,14000")
    h.until(tick(end - 1))
    assert h.send("RP\r") == reply("0,9999,99,999")
    h.until(tick(end))
    assert h.send("RP\r") == reply("0,10000,100,1000")
    assert not any(moving(h, a) for a in "YZT")
    assert h.errors() == []


def test_e130_ml_restores_velocities_and_accelerations() -> None:
    """E130, the ML page: "At the end of the move, all involved velocities and accelerations will
    be restored to their pre-move values." Z and T (scaled to 1/100 and 1/10 of Y) are back at
    VL 200,000 and AC 2,000,000 afterwards, and a following move of Z runs at them.

    (The MA/MR/JG queue tables' add-on "because the last move just prior to this move was either
    a MT or ML move" suggests the firmware does the restoring as part of the next move; either
    way ``?VL`` after the move and the next move's speed must show the pre-move values.)"""
    h = quiet("PCIX-004")
    typed(h, "AA;", "ML,10000,100,1000;", "GO;")
    h.run()
    for a in "YZT":
        assert typed(h, f"A{a};", "?VL") == reply("vl200000")
        assert h.send("?AC\r") == reply("ac2000000")
    start = ticks_after(h.t)
    typed(h, "AZ;", "MR10000;", "GO;")  # at the restored VL/AC: 290 ticks, as Y took
    h.until(tick(start + end_tick(0, move_time(10_000))))
    assert h.position("Z") == 10_100


def test_e131_mm_sets_y_direction_negative() -> None:
    """E131 ``AY; MM;``: "Set the direction line to move in the negative direction on the Y
    axis": QA's direction character is ``M``, and "All non-direction-specific move commands will
    now move in the negative direction" (MO takes Y to -1)."""
    h = quiet("PCIX-004")
    assert h.send("AY;QA\r") == reply("PNNN")
    assert typed(h, "AY;", "MM;") == b""
    assert h.send("QA\r") == reply("MNNN")
    typed(h, "MO;")
    h.advance(1 / RATE)
    assert h.position("Y") == -1
    assert h.errors() == []


@pytest.mark.parametrize(
    "model",
    [
        "PCIX-004",
        "PCIX-040",
    ],
)
def test_e132_mm_mo_moves_z_one_pulse_negative(model: str) -> None:
    """E132 ``AZ; MM; MO;``: "Move the Z axis one pulse in the negative direction", output "in one
    sample interval". The PCIx MO page sets no condition on the motor type (the VS4's "not
    available with encoders" is not in it), so a stepper with encoder does the same."""
    h = quiet(model)
    assert typed(h, "AZ;", "MM;", "MO;") == b""
    h.until(tick(1))
    assert h.position("Z") == -1
    h.run()
    assert h.position("Z") == -1
    assert h.send("QA\r")[:1] == b"M"
    assert h.errors() == []


def test_e133_mr_moves_x_2468_negative() -> None:
    """E133 ``AX; MR-2468; GO;``: a triangle of 0.0703 s, over on tick 144."""
    h = quiet("PCIX-004")
    assert typed(h, "AX;", "MR-2468;", "GO;") == b""
    end = end_tick(0, move_time(2468))
    assert end == 144
    h.until(tick(end - 1))
    assert h.send("RP\r") == reply("-2467")
    h.until(tick(end))
    assert h.send("RP\r") == reply("-2468")
    assert h.send("QA\r") == reply("MNNN")
    assert h.errors() == []


def test_e134_aa_mr_starts_x_and_y_together() -> None:
    """E134 ``AA; MR12345,6789; GO;``: "Both axes will start at the same time", each with its own
    profile: Y (0.1165 s) is over on tick 239, X (0.1571 s) on tick 322."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "MR12345,6789;", "GO;") == b""
    h.until(tick(1))
    assert h.send("RV\r") == reply("976,976,0,0")
    x_end, y_end = end_tick(0, move_time(12_345)), end_tick(0, move_time(6789))
    assert (x_end, y_end) == (322, 239)
    h.until(tick(y_end))
    assert h.position("Y") == 6789
    assert moving(h, "X")
    h.until(tick(x_end))
    assert h.send("RP\r") == reply("12345,6789,0,0")
    assert h.errors() == []


def test_e135_aa_mt_moves_x_y_t_arriving_together() -> None:
    """E135 ``AA; MT1000,10000,,100; GO;``: X, Y and T to 1000, 10,000 and 100 "with each
    starting and finishing together".

    Contradiction (digest §8.2 22): MT calls "The axis that will reach its destination first"
    the master, ML "the axis with the longest move time". Scaling Y's 10,000 counts into T's
    0.014 s would take an acceleration of 2·10⁸, far above "AC ≤ 8,000,000"; only the slowest
    axis can set the pace, so Y (tick 290) is the master and X and T follow in proportion."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "MT1000,10000,,100;", "GO;") == b""
    end = end_tick(0, move_time(10_000))
    h.until(0.07)
    assert h.send("RP\r") == reply("490,4900,0,49")
    h.until(tick(end - 1))
    assert all(moving(h, a) for a in "XYT")
    h.until(tick(end))
    assert h.send("RP\r") == reply("1000,10000,0,100")
    assert not any(moving(h, a) for a in "XYT")
    assert h.errors() == []


def test_e135_mt_restores_velocities_and_accelerations() -> None:
    """E135, the MT page: "At the end of the move, any velocity or acceleration value that was
    modified is restored to its pre-move value." X and T are back at the power-up VL and AC."""
    h = quiet("PCIX-004")
    typed(h, "AA;", "MT1000,10000,,100;", "GO;")
    h.run()
    for a in "XYT":
        assert typed(h, f"A{a};", "?VL") == reply("vl200000")
        assert h.send("?AC\r") == reply("ac2000000")


def test_e136_mv_sp_velocity_staircase() -> None:
    """E136 ``MP; MV10000,30000; MV20000,50000; MV30000,10000; SP35000;``: "Generate a velocity
    staircase with the breakpoints given in absolute position. Default acceleration (AC) of
    200,000".

    The factory AC is 2,000,000 (§2.8); the example assumes 200,000, so AC200000 is entered first.
    Each MV ramps at AC to its velocity and holds it until its position is reached; the next
    command goes on at the first sample tick at or after that. SP35000 then stops exactly at
    35,000, starting its ramp 10,000²/(2·200,000) = 250 counts before. Breakpoints worked out
    below: 10,000 at 0.40833 s (tick 837), 20,000 at tick 1288, 30,000 at tick 2513, stop at
    about 1.752 s."""
    ac = 200_000.0
    h = quiet("PCIX-004")
    typed(h, "AC200000;")
    lines = ("MP;", "MV10000,30000;", "MV20000,50000;", "MV30000,10000;", "SP35000;")
    assert typed(h, *lines) == b""

    # each step: (start time, start position, start velocity, target velocity, breakpoint)
    t0, x0, v0 = 0.0, 0.0, 0.0
    starts = []
    for breakpoint, v1 in ((10_000, 30_000), (20_000, 50_000), (30_000, 10_000)):
        ramp = abs(v1 - v0) / ac
        x_ramp = x0 + (v0 + v1) / 2 * ramp
        reached = t0 + ramp + (breakpoint - x_ramp) / v1
        starts.append((t0, x0, v0, v1))
        t_next = tick(ticks_after(reached))
        x0 = breakpoint + v1 * (t_next - reached)
        t0, v0 = t_next, v1
    assert [ticks_after(s[0]) for s in starts[1:]] == [837, 1288]
    assert ticks_after(t0) == 2513
    decel_at = t0 + (35_000 - 250 - x0) / 10_000
    stop = decel_at + 10_000 / ac

    def rv(t: float) -> bytes:
        h.until(t)
        return h.send("RV\r")

    def ramping(start: float, v_start: float, v_end: float, dv: float) -> tuple[bytes, bytes]:
        """RV ``dv + 0.5`` counts/s into a ramp from ``v_start`` toward ``v_end`` (half a count
        off a whole number, so the integer part RV prints does not hang on rounding)."""
        sign = 1 if v_end > v_start else -1
        expected = math.floor(v_start + sign * (dv + 0.5))
        return rv(start + (dv + 0.5) / ac), reply(str(expected))

    assert rv(0.1) == reply("20000")
    assert rv(0.3) == reply("30000")
    assert h.send("RP\r") == reply("6750")  # 2250 counts of ramp + 0.15 s at 30,000
    got, want = ramping(starts[1][0], 30_000, 50_000, 8000)
    assert got == want
    assert rv(0.6) == reply("50000")
    got, want = ramping(starts[2][0], 50_000, 10_000, 14_000)
    assert got == want
    assert rv(1.2) == reply("10000")
    assert rv(decel_at - 0.001) == reply("10000")
    got, want = ramping(decel_at, 10_000, 0, 4000)
    assert got == want
    h.until(stop - 0.001)
    assert 34_999 >= h.position("X") > 34_990
    h.until(stop + 1 / RATE)
    assert h.position("X") == 35_000
    assert not moving(h, "X")
    h.run()
    assert h.position("X") == 35_000
    assert h.errors() == []


def test_e137_mx_executes_permanent_macro_6() -> None:
    """E137 ``MX6;``: macro 6 (a permanent one, made from a temporary with PT) holds
    ``AX;MR1000;GO;``; each MX6 runs it: "MX itself is an immediate command. However, the
    commands contained within the macro may have queue requirements"."""
    h = quiet("PCIX-004")
    typed(h, "MD0;AX;MR1000;GO;^Z", "PT0,6;")
    assert h.position("X") == 0
    assert typed(h, "MX6;") == b""
    h.until(tick(end_tick(0, move_time(1000))))
    assert h.position("X") == 1000
    typed(h, "MX6;")
    h.run()
    assert h.position("X") == 2000
    assert h.errors() == []


def test_e138_nv_changes_executing_contour_velocity_at_next_segment() -> None:
    """E138 ``NV30000;``: "The contour is executing at 25,000 counts per second. Change the
    velocity to 30,000 counts per second upon execution of the next command in the contour
    queue", "without ramping".

    NV is valid only inside a contour definition ("NV#; AA/CD Immediate") yet acts on "a contour
    currently in execution"; the CV page's advice to "Use WQ between contour definitions to avoid
    having a CV ... affect a prior contour still in motion" shows a second definition may be
    typed while a contour runs. So: a contour along X (0 -> 10,000 -> 20,000 -> 30,000 at CV
    25,000, ramped up from -5000) is started with CX; during its first segment a new definition
    is begun and NV30000 typed. The first segment (over at 0.8 s) stays at 25,000, the second
    starts at 30,000 at once."""
    h = quiet("PCIX-004")
    typed(h, "AA;", "LP-5000,0;", "CV25000;", "CD0,0;", "MT10000,0;", "MT20000,0;")
    typed(h, "MT30000,0;", "CE;", "CX;")
    h.until(0.5)
    assert velocity(h, "X") == 25_000
    assert typed(h, "CD30000,0;", "NV30000;") == b""
    h.until(0.799)
    assert velocity(h, "X") == 25_000
    h.until(0.8015)  # a ramp at AC would still be below 28,000 here
    assert velocity(h, "X") == 30_000
    h.until(0.9)
    assert velocity(h, "X") == 30_000
    assert h.errors() == []


# -- PA, ?PA, PE, PF, PH, PL (5.5.1, 5.7.5, 5.8.3) ------------------------------------------------


def test_e139_aa_pa_turns_y_aux_on_and_t_aux_off_during_moves() -> None:
    """E139 ``AA; PA,0,,1;``: "Turn on the Y axis auxiliary output at the beginning of a move and
    turn the T axis output off at the beginning of a move".

    Contradiction (digest §8.2 21): the PA text says on = "pulled high" and the example's note
    says "'on' pulls the signal line to ground". Both agree that 0 means on during the move and
    non-zero off, which is what ``?AB`` (``an``/``af``) shows; the test does not depend on the
    voltage. "PA selects the mode immediately but places entries in the axis command queue to set
    the state of the aux bit to the idle state": Y idles off, T on. X and Z are not affected."""
    h = quiet("PCIX-004")
    assert typed(h, "AA;", "PA,0,,1;") == b""
    aux = [reply("an"), reply("af"), reply("an"), reply("an")]
    assert [typed(h, f"A{a};", "?AB") for a in "XYZT"] == aux
    typed(h, "AA;", "MR1000,1000,1000,1000;", "GO;")
    h.advance(0.01)
    assert [typed(h, f"A{a};", "?AB") for a in "XYZT"] == [
        reply("an"),
        reply("an"),
        reply("an"),
        reply("af"),
    ]
    h.run()
    assert [typed(h, f"A{a};", "?AB") for a in "XYZT"] == aux
    assert h.errors() == []


def test_e140_query_pa_reports_aux_high_during_moves() -> None:
    """E140 ``AX; ?PA`` -> ``pa0<LF>``: "Power automatic mode is enabled for X axis such that the
    aux bit is high during a move" (PA with no parameter: "if the parameter is zero or not
    specified")."""
    h = quiet("PCIX-004")
    typed(h, "AX;", "PA;")
    assert typed(h, "AX;", "?PA") == reply("pa0")
    assert h.errors() == []


def test_e141_pe_reports_all_encoder_positions_in_single_axis_mode() -> None:
    """E141 ``PE`` -> ``0,50,156,0<LF>``: a four-axis servo board whose encoders read 0, 50, 156
    and 0 (loaded with LP: "the parameter will be loaded into the encoder position register").
    "All encoder positions will be reported even in single axis mode"."""
    h = quiet("PCIX-400")
    typed(h, "AA;", "LP,50,156;", "AX;")
    assert typed(h, "PE") == reply("0,50,156,0")
    assert h.errors() == []


def test_e142_pf_returns_all_axes_to_linear_ramps() -> None:
    """E142 ``PF;``: "Turn off cosine or parabolic ramps, returning to linear." After CN on all
    and PR on Y, PF (typed in single-axis mode: "This command affects all axes even if issued in
    the single axis mode") makes every axis linear: ``la``, and a 100,000-count move of all four
    is over on tick 1229."""
    h = quiet("PCIX-004")
    typed(h, "CN;", "AY;", "PR5;")
    assert typed(h, "AX;", "PF;") == b""
    assert [typed(h, f"A{a};", "?RT") for a in "XYZT"] == [reply("la")] * 4
    typed(h, "AA;", "MR100000,100000,100000,100000;", "GO;")
    end = end_tick(0, move_time(100_000))
    h.until(tick(end - 1))
    assert all(p < 100_000 for p in positions(h))
    h.until(tick(end))
    assert positions(h) == [100_000] * 4
    assert h.errors() == []


def test_e143_ph_sets_t_aux_high_and_ends_pa() -> None:
    """E143 ``AT; PH;``: "Set aux bit of axis T to high", from low; "This command disables power
    automatic (PA) mode": T's aux, under PA1 before, stays high through a move."""
    h = quiet("PCIX-004")
    typed(h, "AT;", "PA1;")
    typed(h, "AT;", "PL;")
    assert typed(h, "AT;", "?AB") == reply("af")
    assert typed(h, "AT;", "PH;") == b""
    assert h.send("?AB\r") == reply("an")
    assert h.send("?PA\r") == reply("paf")  # PA off (docs/decisions.md)
    typed(h, "MR1000;", "GO;")
    h.advance(0.01)
    assert moving(h, "T")
    assert h.send("?AB\r") == reply("an")
    h.run()
    assert h.send("?AB\r") == reply("an")
    assert typed(h, "AX;", "?AB") == reply("an")
    assert h.errors() == []


def test_e144_pl_sets_t_aux_low_and_ends_pa() -> None:
    """E144 ``AT; PL;``: "Set aux bit of axis T to low" (power-up ADH: high); PL "disables power
    automatic (PA) mode": under PA (aux high during moves) before, T's aux stays low through a
    move. X is not touched."""
    h = quiet("PCIX-004")
    typed(h, "AT;", "PA0;")
    assert typed(h, "AT;", "PL;") == b""
    assert h.send("?AB\r") == reply("af")
    assert h.send("?PA\r") == reply("paf")  # PA off (docs/decisions.md)
    typed(h, "MR1000;", "GO;")
    h.advance(0.01)
    assert moving(h, "T")
    assert h.send("?AB\r") == reply("af")
    h.run()
    assert h.send("?AB\r") == reply("af")
    assert typed(h, "AX;", "?AB") == reply("an")
    assert h.errors() == []
