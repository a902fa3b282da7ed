"""Motion on the manual clock: profiles, jog, homing, limits, linear interpolation, deadlines.

Every expected value is computed here from the manual's own formulas (PC48 §1.3 "VELOCITY
PROFILES", §6.7–§6.11) and the design decisions of the project, never read back from
``omsd.board.profiles``:

* a move starts on the first sample tick (2048/s) at or after the GO is executed;
* the axis is done at the first tick at or after the analytic end of the profile;
* the position counter counts whole steps, so it is within one step of the ideal position;
* parabolic PN n: the ratio t/T2 is n/10 at the end of the ramp and A0 = AC;
* stops (ST, soft limit, after home) decelerate linearly at AC; KM and hard limits stop at once.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from omsd.board.events import DoneEvent, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.axis import Motion
from omsd.engine.registers import DON_S, OVRT

RATE = 2048  # PC48 §1.2: "calculating the optimum velocity 2048 times each second"
SAMPLE = 1.0 / RATE


# -- the manual's formulas ---------------------------------------------------------------------


def first_tick(t: float) -> float:
    """The first sample tick at or after ``t`` (ticks at k/2048 s from power-up at t=0)."""
    return math.ceil(t * RATE - 1e-9) / RATE


@dataclass(frozen=True)
class Ideal:
    """A rest-to-rest move: ramp up ``x_up`` for ``t_ramp`` covering ``s_ramp``, cruise at
    ``v_peak``, then the ramp up played backwards ("The deceleration is the same in reverse")."""

    distance: float
    t_ramp: float
    s_ramp: float
    v_peak: float
    x_up: Callable[[float], float]

    @property
    def t_cruise(self) -> float:
        rest = self.distance - 2.0 * self.s_ramp
        return rest / self.v_peak if rest > 1e-9 else 0.0

    @property
    def total(self) -> float:
        return 2.0 * self.t_ramp + self.t_cruise

    def x(self, t: float) -> float:
        if t <= 0.0:
            return 0.0
        if t < self.t_ramp:
            return self.x_up(t)
        if t < self.t_ramp + self.t_cruise:
            return self.s_ramp + self.v_peak * (t - self.t_ramp)
        if t < self.total:
            return self.distance - self.x_up(self.total - t)
        return self.distance


def linear(distance: float, vl: float, ac: float, vb: float = 0.0) -> Ideal:
    """§1.3 LINEAR RAMPS: v = A_m t, s = V_p^2 / (2 A_m); triangular when too short (§1.2).
    VB (§6.7): "The velocity jumps instantly to the specified velocity, then ramps as usual.
    The deceleration is the same in reverse."."""
    s_full = (vl * vl - vb * vb) / (2.0 * ac)
    vp = vl if 2.0 * s_full <= distance else math.sqrt(vb * vb + ac * distance)
    t_ramp = (vp - vb) / ac
    return Ideal(
        distance,
        t_ramp,
        (vp * vp - vb * vb) / (2.0 * ac),
        vp,
        lambda t: vb * t + ac * t * t / 2.0,
    )


def parabolic(distance: float, vl: float, ac: float, n: int) -> Ideal:
    """§1.3 PARABOLIC RAMPS: a = A0 - A0 t/T2, v = A0 t - A0 t^2/(2 T2),
    s = A0 t^2/2 - A0 t^3/(6 T2), with t/T2 = n/10 when VL is reached and A0 = AC. A move too
    short for VL "truncates" the same curve at the point where half the distance is covered."""
    r = n / 10.0
    t1 = vl / (ac * (1.0 - r / 2.0))  # v(t1) = A0 t1 (1 - r/2) = VL
    t2 = t1 / r

    def x_up(t: float) -> float:
        return ac * t * t / 2.0 - ac * t**3 / (6.0 * t2)

    def v_up(t: float) -> float:
        return ac * t - ac * t * t / (2.0 * t2)

    if 2.0 * x_up(t1) > distance:
        lo, hi = 0.0, t1
        for _ in range(200):
            mid = (lo + hi) / 2.0
            lo, hi = (mid, hi) if x_up(mid) < distance / 2.0 else (lo, mid)
        t1 = (lo + hi) / 2.0
    return Ideal(distance, t1, x_up(t1), v_up(t1), x_up)


def cosine(distance: float, vl: float, ac: float) -> Ideal:
    """§1.3 COSINE RAMPS: v = Vp/2 (1 - cos(2 Am t / Vp)), s = Vp t/2 - Vp^2/(4 Am) sin(...),
    S1 = pi Vp^2 / (4 Am), T = pi Vp / (2 Am). A short move keeps the whole shape ("360 degrees
    of a sine wave") at the programmed peak acceleration: S1 = d/2, so Vp = sqrt(2 Am d / pi)."""
    vp = vl
    if 2.0 * math.pi * vl * vl / (4.0 * ac) > distance:
        vp = math.sqrt(2.0 * ac * distance / math.pi)

    def x_up(t: float) -> float:
        return vp * t / 2.0 - vp * vp / (4.0 * ac) * math.sin(2.0 * ac * t / vp)

    return Ideal(distance, math.pi * vp / (2.0 * ac), math.pi * vp * vp / (4.0 * ac), vp, x_up)


# -- helpers -----------------------------------------------------------------------------------


def rp(h: Harness, cmd: str = "RP") -> int:
    """Send an RP and return its value, checking the <LF><CR>value<LF><CR> frame."""
    reply = h.query(cmd)
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    return int(reply[2:-2])


def sample_times(t0: float, ideal: Ideal, step: float = 0.001, cruise_step: float = 0.0073):
    """Every ``step`` through both ramps, a coarser sweep of the cruise, and the last ticks."""
    times: set[float] = set()
    k = 1
    while k * step < ideal.t_ramp + step:
        times.add(t0 + k * step)
        times.add(t0 + ideal.total - k * step)
        k += 1
    t = ideal.t_ramp
    while t < ideal.t_ramp + ideal.t_cruise:
        times.add(t0 + t)
        t += cruise_step
    for j in range(1, 4):  # the last few sample ticks before the end
        times.add(first_tick(t0 + ideal.total) - j * SAMPLE)
    return sorted(x for x in times if t0 < x < t0 + ideal.total)


def follow(
    h: Harness,
    t0: float,
    ideal: Ideal,
    times: Iterable[float],
    axis: str = "X",
    sign: int = 1,
    x0: float = 0.0,
) -> None:
    """At every time, both h.position() and the RP reply are within one step of the ideal."""
    bad = []
    for t in times:
        h.until(t)
        want = x0 + sign * ideal.x(t - t0)
        pos = h.position(axis)
        reply = rp(h)
        if abs(pos - want) > 1.0 or abs(reply - want) > 1.0:
            bad.append((t, want, pos, reply))
    assert not bad, f"{len(bad)} samples off the ideal profile, e.g. (t, ideal, pos, RP) {bad[:5]}"


def done_time(h: Harness) -> float:
    """Run until idle; the time of the DoneEvent produced by a queued ID."""
    h.run()
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1, done
    return done[0].time


def check_move(h: Harness, setup: str, ideal: Ideal, sign: int = 1, t_go: float = 0.01) -> None:
    """Send ``setup`` + a GO at ``t_go`` (between ticks); follow the profile; check the end."""
    h.until(t_go)
    h.send(setup + " GO ID")
    t0 = first_tick(t_go)
    end = first_tick(t0 + ideal.total)
    assert h.board.next_deadline() in (t0, end)  # the start tick may itself be a deadline
    h.until(t0)
    assert h.board.next_deadline() == end
    follow(h, t0, ideal, sample_times(t0, ideal), sign=sign)
    h.until(end - SAMPLE)
    assert h.axis().motion is not Motion.IDLE, "the move ended before its analytic end"
    assert done_time(h) == end
    assert end - SAMPLE < t0 + ideal.total <= end + 1e-9
    assert h.position() == round(sign * ideal.distance)
    assert rp(h) == round(sign * ideal.distance)
    assert h.board.next_deadline() is None


# -- 1. the manual's typical move (§1.1) -------------------------------------------------------


def test_x1_typical_move_follows_trapezoid():
    """X1 (§1.1): ``VL400000 AC500000 MR1000000 GO``: 0.8 s ramps of 160000 steps, a 1.7 s
    cruise, done 3.3 s after the start tick (on the first tick at/after it)."""
    ideal = linear(1_000_000, 400_000, 500_000)
    assert ideal.t_ramp == 0.8 and ideal.s_ramp == 160_000
    assert math.isclose(ideal.total, 3.3)
    check_move(Harness("PC48-4"), "VL400000 AC500000 MR1000000", ideal)


def test_x1_typical_move_started_on_a_tick():
    """The same move with GO exactly at t=0: done on tick ceil(3.3 * 2048) = 6759."""
    h = Harness("PC48-4")
    h.send("VL400000 AC500000 MR1000000 GO ID")
    assert h.board.next_deadline() == 6759 / RATE
    h.until(0.4)
    assert h.position() == 40_000  # 500000 * 0.4^2 / 2
    assert rp(h) == 40_000
    h.until(2.0)
    assert h.position() == 160_000 + 400_000 * 1.2
    assert done_time(h) == 6759 / RATE


def test_linear_negative_move_mirrors_profile():
    """MR with a negative distance follows the same profile downwards."""
    check_move(Harness("PC48-4"), "VL400000 AC500000 MR-1000000", linear(1e6, 4e5, 5e5), sign=-1)


def test_linear_short_move_is_triangular():
    """§1.2: "If the move parameters do not allow the motor to accelerate to the desired
    velocity in the desired distance, the PC48 will automatically generate an optimum triangular
    velocity profile": MR100000 at VL400000 AC500000 peaks at sqrt(A d) = 223607."""
    ideal = linear(100_000, 400_000, 500_000)
    assert ideal.t_cruise == 0.0 and math.isclose(ideal.v_peak, math.sqrt(5e10))
    check_move(Harness("PC48-4"), "VL400000 AC500000 MR100000", ideal)


def test_linear_short_move_rv_peaks_below_vl():
    """At the apex of the triangle RV reports the peak sqrt(A d), not VL."""
    h = Harness("PC48-4")
    h.send("VL400000 AC500000 MR100000 GO")
    ideal = linear(100_000, 400_000, 500_000)
    h.until(ideal.t_ramp)
    assert abs(rp(h, "RV") - ideal.v_peak) <= 1.0


def test_e36_vb_base_velocity_long_move():
    """VB (§6.7): the velocity jumps to VB, ramps at AC to VL, and the deceleration is the same in
    reverse: ramp time (VL-VB)/AC = 0.7 s, ramp distance (VL^2-VB^2)/(2 AC) = 157500."""
    ideal = linear(1_000_000, 400_000, 500_000, vb=50_000)
    assert math.isclose(ideal.t_ramp, 0.7) and math.isclose(ideal.s_ramp, 157_500)
    check_move(Harness("PC48-4"), "VL400000 AC500000 VB50000 MR1000000", ideal)


def test_vb_base_velocity_jumps_at_start():
    """One sample after the start tick a VB move has covered VB/2048 + AC/2/2048^2 steps, far
    more than the AC/2/2048^2 of a move without VB; RV reports at least VB right away."""
    h = Harness("PC48-4")
    h.send("VL400000 AC500000 VB50000 MR1000000 GO")
    h.until(0.01)
    assert abs(rp(h) - (50_000 * 0.01 + 500_000 * 0.01**2 / 2)) <= 1.0
    assert abs(rp(h, "RV") - (50_000 + 500_000 * 0.01)) <= 1


def test_vb_base_velocity_short_move():
    """A triangular move with VB peaks at sqrt(VB^2 + A d) (each ramp covers d/2)."""
    ideal = linear(100_000, 400_000, 500_000, vb=50_000)
    assert ideal.t_cruise == 0.0 and math.isclose(ideal.v_peak, math.sqrt(50_000**2 + 5e10))
    check_move(Harness("PC48-4"), "VL400000 AC500000 VB50000 MR100000", ideal)


# -- 2. parabolic and cosine ramps (§1.3) ------------------------------------------------------


def test_e19_pn3_parabolic_long_move():
    """PN3: ratio t/T2 = 0.3 when VL is reached, initial acceleration A0 = AC. The ramp lasts
    t1 = VL / (A0 (1 - 0.15)) and covers A0 t1^2 (1/2 - 0.3/6)."""
    ideal = parabolic(1_000_000, 400_000, 500_000, 3)
    assert math.isclose(ideal.v_peak, 400_000) and ideal.t_cruise > 0.0
    check_move(Harness("PC48-4"), "PN3 VL400000 AC500000 MR1000000", ideal)


def test_e19_pn10_parabolic_long_move():
    """PN10 (E19, "the smoothest parabolic acceleration ramp"): ratio t/T2 = 1.0.

    Digest §8.3 #20: the §1.3 formula gives 0 % acceleration at t/T2 = 1.0 while the PN text
    says "as low as 10%". The project's design decision is ratio = n/10 with a = A0 (1 - t/T2),
    so PN10 reaches VL with zero acceleration: t1 = VL / (A0/2) = 1.6 s."""
    ideal = parabolic(1_000_000, 400_000, 500_000, 10)
    assert math.isclose(ideal.t_ramp, 1.6) and ideal.t_cruise > 0.0
    check_move(Harness("PC48-4"), "PN10 VL400000 AC500000 MR1000000", ideal)


def test_pn3_parabolic_short_move_truncates_curve():
    """§1.3: "If the move is too short to reach the programmed speed the curve is truncated,
    causing the shape of the velocity curve to remain the same": the same a = A0 - A0 t/T2 (T2
    of the full ramp to VL) runs until half the distance is covered, then mirrors."""
    ideal = parabolic(100_000, 400_000, 500_000, 3)
    assert ideal.t_cruise == 0.0 and ideal.v_peak < 400_000
    check_move(Harness("PC48-4"), "PN3 VL400000 AC500000 MR100000", ideal)


def test_pn10_parabolic_short_move_truncates_curve():
    ideal = parabolic(100_000, 400_000, 500_000, 10)
    assert ideal.t_cruise == 0.0 and ideal.v_peak < 400_000
    check_move(Harness("PC48-4"), "PN10 VL400000 AC500000 MR100000", ideal)


def test_parabolic_negative_short_move():
    ideal = parabolic(100_000, 400_000, 500_000, 6)
    check_move(Harness("PC48-4"), "PN6 VL400000 AC500000 MR-100000", ideal, sign=-1)


def test_pn3_rc_reports_end_of_ramp_acceleration_at_cruise():
    """RC (§6.13) at programmed speed returns "the acceleration at the end of the ramp":
    A0 (1 - t/T2) = 70 % of AC for PN3; stopped, "the acceleration at the beginning of a ramp"."""
    h = Harness("PC48-4")
    h.send("PN3 VL400000 AC500000\r")
    assert rp(h, "RC") == 500_000
    h.send("MR1000000 GO")
    h.until(1.5)  # cruise: the PN3 ramp ends at 0.94 s
    assert rp(h, "RC") == 350_000


def test_e18_cosine_long_move():
    """CN: ramp time T = pi VL / (2 AC) = 1.2566 s over S1 = pi VL^2 / (4 AC) = 251327 steps."""
    ideal = cosine(1_000_000, 400_000, 500_000)
    assert math.isclose(ideal.v_peak, 400_000) and ideal.t_cruise > 0.0
    assert math.isclose(ideal.t_ramp, math.pi * 0.4)
    check_move(Harness("PC48-4"), "CN VL400000 AC500000 MR1000000", ideal)


def test_cosine_short_move_keeps_full_shape():
    """CN (§6.5): "The cosine is not truncated in moves that do not reach full speed": the full
    half-cosine on each side at peak acceleration AC, with v_p = sqrt(2 A d / pi) = 178412 for
    d = 100000."""
    ideal = cosine(100_000, 400_000, 500_000)
    assert ideal.t_cruise == 0.0 and math.isclose(ideal.v_peak, math.sqrt(1e11 / math.pi))
    check_move(Harness("PC48-4"), "CN VL400000 AC500000 MR100000", ideal)


def test_cosine_short_move_rv_at_apex_is_lowered_peak():
    h = Harness("PC48-4")
    h.send("CN VL400000 AC500000 MR100000 GO")
    ideal = cosine(100_000, 400_000, 500_000)
    h.until(ideal.t_ramp)
    assert abs(rp(h, "RV") - ideal.v_peak) <= 1.0


def test_cosine_ignores_vb():
    """VB "is active only for linear ramps. It is ignored for cosine and parabolic ramps but not
    flagged as a command error"."""
    h = Harness("PC48-4")
    check_move(h, "CN VL400000 AC500000 VB50000 MR1000000", cosine(1e6, 4e5, 5e5))
    assert h.errors() == []


def test_parabolic_ignores_vb():
    h = Harness("PC48-4")
    check_move(h, "PN3 VL400000 AC500000 VB50000 MR100000", parabolic(1e5, 4e5, 5e5, 3))
    assert h.errors() == []


def test_e20_pf_returns_to_linear_ramps():
    check_move(Harness("PC48-4"), "CN PF VL400000 AC500000 MR1000000", linear(1e6, 4e5, 5e5))


# -- 3. jog (§6.8, §6.9) -----------------------------------------------------------------------


def test_e51_jog_change_speed_and_stop():
    """E51 ``JG100000 JG35000 ST``, each typed after the previous took effect, AC200000:
    0.5 s ramp (25000 steps) to 100000; JG35000 at 2.0 s slows at AC for 0.325 s; ST at 4.0 s
    decelerates at AC over 35000^2 / (2 AC) = 3062.5 steps and ends at rest at 258625."""
    h = Harness("PC48-4")
    h.send("AC200000 JG100000\r")

    def jog1(t: float) -> float:
        return 100_000 * t * t if t < 0.5 else 25_000 + 100_000 * (t - 0.5)

    h.until(0.125)
    assert rp(h, "RV") == 25_000  # ramping at AC
    assert abs(h.position() - jog1(0.125)) <= 1
    h.until(1.0)
    assert rp(h, "RV") == 100_000
    assert abs(rp(h) - jog1(1.0)) <= 1
    h.until(2.0)
    assert h.position() == 175_000
    h.send("JG35000\r")
    assert h.axis().vl == 35_000  # "This command modifies the move velocity parameter (VL)"
    x_slow = 175_000 + (100_000 + 35_000) / 2 * 0.325
    h.until(2.0 + 0.125)
    assert rp(h, "RV") == 100_000 - 25_000
    h.until(3.0)
    assert rp(h, "RV") == 35_000
    assert abs(rp(h) - (x_slow + 35_000 * (3.0 - 2.325))) <= 1
    h.until(4.0)
    x_st = x_slow + 35_000 * (4.0 - 2.325)
    assert x_st == 255_562.5
    h.send("ST")
    h.until(4.0 + 0.0625)  # v = 35000 - 12500
    assert rp(h, "RV") == 22_500
    assert abs(h.position() - (x_st + 35_000 * 0.0625 - 100_000 * 0.0625**2)) <= 1
    h.run()
    assert h.t == first_tick(4.0 + 0.175)
    assert h.position() == 258_625  # x_st + 35000^2 / (2 * 200000)
    assert rp(h, "RV") == 0
    assert h.axis().motion is Motion.IDLE


def test_e51_second_jog_waits_until_first_is_up_to_speed():
    """JG (§6.8): "Output events waiting for completion of JG will begin when JG is up to its
    requested velocity": ``JG100000 JG35000`` in one string: the slow-down starts at 0.5 s."""
    h = Harness("PC48-4")
    h.send("AC200000 JG100000 JG35000\r")
    h.until(0.5 - 0.125)
    assert rp(h, "RV") == 75_000  # still accelerating
    h.until(0.5 + 0.125)
    assert rp(h, "RV") == 75_000
    assert abs(h.position() - (25_000 + 100_000 * 0.125 - 100_000 * 0.125**2)) <= 1
    h.until(2.0)
    assert rp(h, "RV") == 35_000
    assert abs(h.position() - (25_000 + 21_937.5 + 35_000 * (2.0 - 0.825))) <= 1


def test_rv_at_the_instant_a_jog_changes_speed():
    """At the tick where a second JG takes over the axis is still at the first jog's speed: RV
    reports 100000 there (velocity is continuous), and 75000 an eighth of a second later."""
    h = Harness("PC48-4")
    h.send("AC200000 JG100000 JG35000\r")
    h.until(0.5)
    assert rp(h, "RV") == 100_000
    assert h.position() == 25_000
    h.until(0.625)
    assert rp(h, "RV") == 75_000


def test_counter_is_whole_steps_after_a_restart_at_a_half_step():
    """The counter counts whole steps: after ST at 255562.5 steps (a half-step position) the
    counter stays within one step of the ideal position (it should be floor(ideal))."""
    h = Harness("PC48-4")
    h.send("AC200000 JG100000\r")
    h.until(2.0)
    h.send("JG35000\r")
    h.until(4.0)
    h.send("ST")
    for k in range(1, 180):
        t = 4.0 + k * 0.001
        h.until(t)
        tau = t - 4.0 if t < 4.175 else 0.175
        want = 255_562.5 + 35_000 * tau - 100_000 * tau * tau
        assert abs(h.position() - want) <= 1.0, (t, want, h.position())


def test_e86_jog_rv_reports_velocity():
    """E86: ``AY JG 12345`` then ``RV`` replies ``<LF><CR>12345<LF><CR>``."""
    h = Harness("PC48-4")
    h.send("AY JG 12345\r")
    h.advance(0.5)
    assert h.query("RV") == b"\n\r12345\n\r"
    assert h.position("X") == 0
    assert abs(h.position("Y") - (12_345 * 0.5 - 12_345**2 / 2e6)) <= 1


def test_jog_zero_stops_at_ac():
    """``JG0`` is a jog at zero velocity: the axis ramps down at AC like a speed change."""
    h = Harness("PC48-4")
    h.send("AC100000 JG20000\r")
    h.until(1.0)
    x = 2_000 + 20_000 * 0.8  # 0.2 s ramp of 2000 steps
    assert h.position() == x
    h.send("JG0\r")
    h.until(1.125)
    assert rp(h, "RV") == 7_500
    h.run()
    assert h.t == first_tick(1.2)
    assert h.position() == x + 2_000
    assert h.axis().motion is Motion.IDLE


def test_negative_jog_and_stop():
    """``JG-50000`` at AC200000: position falls as -A t^2/2, RV is negative; ST ramps down."""
    h = Harness("PC48-4")
    h.send("AC200000 JG-50000\r")
    h.until(0.125)
    assert h.query("RV") == b"\n\r-25000\n\r"
    assert abs(h.position() + 100_000 * 0.125**2) <= 1
    h.until(1.25)
    assert h.query("RV") == b"\n\r-50000\n\r"
    assert h.position() == -(6_250 + 50_000)
    assert h.axis().direction == -1
    h.send("ST")
    h.run()
    assert h.position() == -(6_250 + 50_000 + 6_250)
    assert h.t == first_tick(1.5)


def test_e54_st_flushes_queue_and_decelerates_move():
    """E54-style ST during a move: decelerates at AC (not the move's own ramp) and the queued
    second move never runs."""
    h = Harness("PC48-4")
    h.send("VL10000 AC100000 MR100000 GO MR-50000 GO")
    h.until(1.0)
    x = 500 + 10_000 * 0.9
    assert h.position() == x
    h.send("ST")
    h.run()
    assert h.position() == x + 500
    assert h.t == first_tick(1.1)
    h.advance(5.0)
    assert h.position() == x + 500


# -- 4. homing (§6.11) -------------------------------------------------------------------------

HOME_WORLD = AxisWorld(home_low=5000, home_high=5100)


def test_e62_home_loads_counter_at_edge_then_ma_returns():
    """E62 ``AX VL1000 HM1000 MA1000 GO`` (with AC10000): the axis ramps to 1000 steps/s in
    0.1 s (50 steps), so x(t) = 1000 t - 50 reaches the switch at 5000 at t = 5.05 s. The edge
    is seen on the first tick at/after that (tick 10343, x = 5000.29); the counter is loaded
    with 1000 there
    and the axis decelerates at AC over 1000^2 / (2 * 10000) = 50 steps: counter 1050. MA1000
    then returns to the home position (physically 5000.29)."""
    h = Harness("PC48-4", world={"X": HOME_WORLD})
    h.send("AX VL1000 AC10000 HM1000 MA1000 GO ID")
    edge = 10_343 / RATE
    assert first_tick(5.05) == edge
    h.until(edge - SAMPLE)
    assert rp(h) == math.floor(1000 * (edge - SAMPLE) - 50)  # 4999, not loaded yet
    h.until(edge)
    assert rp(h) == 1000
    h.until(edge + 0.05)  # decelerating at AC: 1000 * 0.05 - 10000 * 0.05^2 / 2 = 37.5
    assert abs(h.position() - 1037.5) <= 1
    h.until(edge + 0.1)  # the analytic end of the deceleration (the MA1000 GO waits for it)
    assert abs(h.position() - 1050) <= 1
    h.run()
    assert h.position() == 1000
    snap = h.board.snapshot(h.t)["axes"]["X"]
    assert math.isclose(snap["physical"], 1000 * edge - 50, abs_tol=1e-6)
    assert snap["home"] is True


def test_hm_final_counter_is_home_value_plus_stop_distance():
    h = Harness("PC48-4", world={"X": HOME_WORLD})
    h.send("VL1000 AC10000 HM-777\r")
    h.run()
    assert h.position() == -777 + 50
    assert h.t == first_tick(10_343 / RATE + 0.1)
    assert h.axis().motion is Motion.IDLE


def test_e63_hr_from_above_finds_upper_edge():
    """HR moves negative and the home condition becomes true when the carriage enters the switch
    window from above: the switches see whole steps (``Axis.carriage``), so the first step inside
    ``[5000, 5100)`` is 5099. Start at 8000: the position is x(t) = 50 - 1000 t after the 0.1 s
    ramp, and the counter (steps emitted going down: ceil) reaches -2901 (carriage 5099) once
    x <= -2901, at t = 2.951 s, first tick ceil(2.951 * 2048) = ceil(6043.65) = 6044; HR-300
    loads -300 there; 50 steps of deceleration end at -350."""
    world = AxisWorld(start_position=8000, home_low=5000, home_high=5100)
    h = Harness("PC48-4", world={"X": world})
    h.send("VL1000 AC10000 HR-300\r")
    edge = 6044 / RATE
    assert first_tick(2.951) == edge
    h.until(edge - SAMPLE)
    assert rp(h) == -2900  # ceil(50 - 1000 * 6043 / 2048) = ceil(-2900.68): still at step 5100
    h.until(edge)
    assert rp(h) == -300
    h.run()
    assert h.position() == -350
    assert h.axis().direction == -1


def test_e64_km_stops_at_once_without_loading_counter():
    """E64 ``AY KM``: "find home and stop generating pulses immediately, i.e. no deceleration
    ramp ... The position counter is not cleared or reset": at tick 10343 Y stops at
    floor(1000 t - 50) = floor(5000.29) = 5000 and stays there."""
    h = Harness("PC48-4", world={"Y": HOME_WORLD})
    h.send("AY VL1000 AC10000 KM")
    edge = 10_343 / RATE
    h.until(edge - SAMPLE)
    assert h.axis("Y").motion is not Motion.IDLE
    h.until(edge)
    assert h.axis("Y").motion is Motion.IDLE
    assert h.position("Y") == math.floor(1000 * edge - 50) == 5000
    h.advance(2.0)
    assert rp(h) == 5000
    assert h.query("RV") == b"\n\r0\n\r"


def test_e65_kr_stops_at_once_without_loading_counter():
    """KR from above stops on the first whole step inside the window (5099, counter -2901, the
    tick 6044 of test_e63) and the home input reads true there: a carriage stopped by the switch
    is on the switch."""
    world = AxisWorld(start_position=8000, home_low=5000, home_high=5100)
    h = Harness("PC48-4", world={"Y": world})
    h.send("AY VL1000 AC10000 KR")
    h.run()
    assert h.t == 6044 / RATE
    assert h.position("Y") == -2901  # ceil(50 - 1000 * 6044 / 2048) = ceil(-2901.17)
    assert h.query("RA") == b"\n\r\rMNNH\n\r\r"


def test_hm_needs_an_edge_not_a_level():
    """Design decision: HM detects a false->true edge of the home input. Starting inside the
    switch window, HM leaves it without loading the counter; starting below it, it loads."""
    world = AxisWorld(start_position=5050, home_low=5000, home_high=5100)
    h = Harness("PC48-4", world={"X": world})
    h.send("VL1000 AC10000 HM1000\r")
    h.until(1.0)
    assert abs(h.position() - 950) <= 1  # still running, counter never loaded
    assert h.axis().motion is Motion.HOME
    h.send("ST")
    h.run()
    assert h.position() == 1000  # 950 + 50 of deceleration, no home load


# -- 5. limits (§6.5, ch. 7) -------------------------------------------------------------------

LIMIT_WORLD = AxisWorld(positive_limit=20_000)
# VL10000 AC100000: x(t) = 10000 t - 500 after the 0.1 s ramp; 20000 is reached at t = 2.05 s
LIMIT_TICK = 4199 / RATE


def test_hard_limit_stops_at_first_tick_and_flushes_queue():
    """SF (default): the pulses stop on the first tick at/after the switch is reached (2.05 s →
    tick 4199, x = 20002.93: within one sample's travel, 10000/2048 steps, of the switch); the
    axis queue is flushed, so the queued MR-5000 GO never runs; OVRT|DON_S; LimitEvent."""
    assert first_tick(2.05) == LIMIT_TICK
    h = Harness("PC48-4", world={"X": LIMIT_WORLD})
    h.send("VL10000 AC100000 MR100000 GO MR-5000 GO")
    h.until(LIMIT_TICK - SAMPLE)
    assert h.axis().motion is Motion.MOVE
    assert h.board.status_register(h.t) & OVRT == 0
    h.until(LIMIT_TICK)
    x = 10_000 * LIMIT_TICK - 500
    assert 20_000 <= x <= 20_000 + 10_000 / RATE
    assert h.position() == math.floor(x) == 20_002
    assert h.axis().motion is Motion.IDLE
    h.run()
    h.advance(3.0)
    assert rp(h) == 20_002
    assert h.axis().queue.free == 200
    events = h.events()
    assert [e for e in events if isinstance(e, LimitEvent)] == [LimitEvent(LIMIT_TICK, "X", 1)]
    assert h.board.read_status_register(h.t) & (OVRT | DON_S) == OVRT | DON_S
    assert h.board.read_status_register(h.t) & (OVRT | DON_S) == 0


def test_hard_limit_blocks_further_motion_into_it_but_not_away():
    """Limits are directional: at the active + limit a positive move emits no step; a negative
    move runs normally."""
    h = Harness("PC48-4", world={"X": LIMIT_WORLD})
    h.send("VL10000 AC100000 MR100000 GO")
    h.run()
    assert h.position() == 20_002
    h.events()
    h.send("MR100 GO")
    h.run()
    assert h.position() == 20_002
    h.send("MR-5000 GO")
    h.run()
    assert h.position() == 15_002
    h.send("MR1000 GO")  # the switch is released: positive moves work again
    h.run()
    assert h.position() == 16_002


def test_e16_soft_limit_decelerates_and_queue_continues():
    """E16 ``AX SL``: "ramp down instead of terminating immediately. The output queue is not
    flushed except for the current move". At the limit tick the axis decelerates at AC from
    10000 over 500 steps; then the queued MR-5000 GO runs."""
    h = Harness("PC48-4", world={"X": LIMIT_WORLD})
    h.send("SL VL10000 AC100000 MR100000 GO MR-5000 GO")
    x = 10_000 * LIMIT_TICK - 500
    h.until(LIMIT_TICK + 0.05)
    assert abs(h.position() - (x + 10_000 * 0.05 - 50_000 * 0.05**2)) <= 1
    h.until(first_tick(LIMIT_TICK + 0.1))  # the end of the ramp; MR-5000 starts from here
    stopped = h.position()
    assert abs(stopped - (x + 500)) <= 1
    events = h.events()
    assert [e for e in events if isinstance(e, LimitEvent)] == [LimitEvent(LIMIT_TICK, "X", 1)]
    assert h.board.read_status_register(h.t) & (OVRT | DON_S) == OVRT | DON_S
    h.run()
    assert h.position() == stopped - 5000


def test_soft_limit_does_not_ramp_jogs():
    """SL "is effective for point to point moves only": a jog into the limit still stops at once
    and its queue is flushed."""
    h = Harness("PC48-4", world={"X": LIMIT_WORLD})
    h.send("SL AC100000 JG10000\r")
    h.run(limit=10.0)
    assert h.t == LIMIT_TICK
    assert h.position() == 20_002
    assert h.axis().motion is Motion.IDLE


def test_forced_limit_while_jogging():
    """``board.set_limit`` while jogging: a forced − limit does nothing to a positive jog; a
    forced + limit at 1.0001 s stops it on the next tick (2049) and flushes the queue (the
    queued WT/JG8000 never runs); LimitEvent; moving away is then allowed."""
    h = Harness("PC48-4")
    h.send("JG5000 WT2000 JG8000\r")  # AC 1e6: 5 ms ramp of 12.5 steps; x = 5000 t - 12.5
    h.until(0.5)
    h.board.set_limit("X", -1, True, h.t)
    h.until(1.0001)
    assert h.axis().motion is Motion.JOG
    h.board.set_limit("X", +1, True, h.t)
    stop = 2049 / RATE
    h.until(stop)
    assert h.axis().motion is Motion.IDLE
    assert h.position() == math.floor(5000 * stop - 12.5) == 4989
    h.advance(5.0)
    assert rp(h) == 4989
    assert h.query("RV") == b"\n\r0\n\r"
    assert [e for e in h.events() if isinstance(e, LimitEvent)] == [LimitEvent(stop, "X", 1)]
    assert h.board.read_status_register(h.t) & (OVRT | DON_S) == OVRT | DON_S
    h.board.set_limit("X", -1, None, h.t)
    h.send("MR-1000 GO")
    h.run()
    assert h.position() == 3989


def test_negative_hard_limit_reached_by_negative_move():
    world = AxisWorld(negative_limit=-3000)
    h = Harness("PC48-4", world={"Z": world})
    h.send("AZ VL10000 AC100000 MR-100000 GO")
    h.run()
    tick = first_tick(0.35)  # 10000 t - 500 = 3000
    assert h.t == tick
    assert h.position("Z") == math.ceil(-(10_000 * tick - 500))
    assert [e for e in h.events() if isinstance(e, LimitEvent)] == [LimitEvent(tick, "Z", -1)]


# -- 6. linear interpolation (§6.7 ML/MT) ------------------------------------------------------


def test_e44_ml_axes_finish_together_on_a_straight_line():
    """E44 ``AA ML,10000,100,1000; GO``: Y is the longest move (10000 at the default VL100000
    AC1000000: two 0.1 s ramps). Z and T are scaled by 1/100 and 1/10, so all three end on tick
    ceil(0.2 * 2048) = 410; every ms each axis is within 1 step of its ideal and the positions
    stay proportional to Y's within one step."""
    h = Harness("PC48-4")
    h.send("AA ML,10000,100,1000; GO ID")
    y = linear(10_000, 100_000, 1_000_000)
    end = first_tick(y.total)
    assert end == 410 / RATE
    bad = []
    for k in range(1, 200):
        t = k * 0.001
        h.until(t)
        py, pz, pt = (h.position(a) for a in "YZT")
        want = y.x(t)
        if abs(py - want) > 1 or abs(pz - want / 100) > 1 or abs(pt - want / 10) > 1:
            bad.append((t, want, py, pz, pt))
        if abs(pz - py / 100) > 1 or abs(pt - py / 10) > 1:
            bad.append((t, "not proportional", py, pz, pt))
    assert not bad, bad[:5]
    h.until(end - SAMPLE)
    assert all(h.axis(a).motion is Motion.MOVE for a in "YZT")
    h.until(end)
    assert all(h.axis(a).motion is Motion.IDLE for a in "YZT")
    assert h.query("RP") == b"\n\r0,10000,100,1000\n\r"
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert [d.time for d in done] == [end]


def test_ml_scales_to_the_longest_move_time_and_leaves_registers():
    """ML (§6.7): "All axes are scaled to the axis with the longest move time." X (2000 steps
    at VL1000 AC10000: 2.1 s) is the lead although Y moves farther (10000 at VL100000
    AC1000000: 0.2 s). Y is scaled by 10000/2000 = 5 (VL5000, AC50000) and ends on X's tick;
    the scaled values stay in Y's registers, as §6.7 warns, so a later single-axis move uses
    them."""
    h = Harness("PC48-4")
    h.send("AA VL1000,100000; AC10000,1000000; ML2000,10000; GO ID")
    x = linear(2000, 1000, 10_000)
    end = first_tick(x.total)
    assert math.isclose(x.total, 2.1) and end == 4301 / RATE
    for t in (0.05, 0.1, 0.7, 1.3, 2.0, 2.08):
        h.until(t)
        px, py = h.position("X"), h.position("Y")
        assert abs(px - x.x(t)) <= 1 and abs(py - 5 * x.x(t)) <= 1, (t, px, py)
        assert abs(py / 5 - px) <= 1
    assert done_time(h) == end
    assert h.query("RP") == b"\n\r2000,10000,0,0\n\r"
    assert (h.axis("Y").vl, h.axis("Y").ac) == (5000, 50_000)
    assert (h.axis("X").vl, h.axis("X").ac) == (1000, 10_000)
    # a single-axis Y move now ramps at AC50000 to VL5000: 0.1 s ramps of 250 steps
    t0 = h.t
    h.send("AY MR10000 GO ID")
    assert math.isclose(done_time(h), first_tick(t0 + linear(10_000, 5000, 50_000).total))


def test_e45_mt_scales_velocity_and_acceleration():
    """E45 ``AA MT1000,10000,,100; GO``: Y (10000) leads; X is scaled by 0.1 and T by 0.01;
    Z keeps its values; all finish on tick 410."""
    h = Harness("PC48-4")
    h.send("AA MT1000,10000,,100; GO ID")
    assert done_time(h) == 410 / RATE
    assert h.query("RP") == b"\n\r1000,10000,0,100\n\r"
    assert math.isclose(h.axis("X").vl, 10_000) and math.isclose(h.axis("X").ac, 100_000)
    assert math.isclose(h.axis("T").vl, 1000) and math.isclose(h.axis("T").ac, 10_000)
    assert (h.axis("Z").vl, h.axis("Z").ac) == (100_000, 1_000_000)
    assert (h.axis("Y").vl, h.axis("Y").ac) == (100_000, 1_000_000)


def test_aa_mr_axes_start_together_but_need_not_finish_together():
    """E43-style ``AA MR``: each axis uses its own VL/AC; a short move ends first."""
    h = Harness("PC48-4")
    h.send("AA MR10000,100; GO")
    h.until(first_tick(linear(100, 1e5, 1e6).total))
    assert h.axis("Y").motion is Motion.IDLE and h.position("Y") == 100
    assert h.axis("X").motion is Motion.MOVE


# -- 7. deadlines and long simulations ---------------------------------------------------------


def test_next_deadline_is_move_end_and_none_when_idle():
    h = Harness("PC48-4")
    assert h.board.next_deadline() is None
    h.until(0.3)
    h.send("VL400000 AC500000 MR1000000 GO")
    start = first_tick(0.3)
    end = first_tick(start + 3.3)
    assert h.board.next_deadline() in (start, end)  # the start tick itself may be a deadline
    h.until(start)
    assert h.board.next_deadline() == end
    h.until(1.0)
    assert h.board.next_deadline() == end
    h.until(3.0)
    assert h.board.next_deadline() == end
    h.until(end)
    assert h.board.next_deadline() is None


def _count_deadlines(h: Harness, until: float) -> int:
    """Step the board deadline by deadline, as a server would; return how many were visited."""
    board = h.board
    n = 0
    while (d := board.next_deadline()) is not None and d <= until:
        board.advance(d)
        h.t = max(h.t, d)
        n += 1
        assert n < 100, "the board is stepping sample by sample"
    h.until(until)
    return n


def test_ten_minute_move_is_simulated_in_a_few_deadlines():
    """VL1000 AC10000 MR600000: 600.1 s; ends on tick ceil(600.1 * 2048) after a handful of
    deadlines, not 1.2 million samples (how long that takes is measured by ``python -m bench``,
    the interpreter benchmark)."""
    h = Harness("PC48-4")
    h.send("VL1000 AC10000 MR600000 GO ID")
    end = first_tick(600.1)
    assert h.board.next_deadline() == end
    n = _count_deadlines(h, 700.0)
    assert n <= 5
    assert h.position() == 600_000
    assert [e.time for e in h.events() if isinstance(e, DoneEvent)] == [end]


def test_ten_minute_jog_is_simulated_fast():
    """JG10000 for ten minutes: x = 10000 t - 50 (AC 1e6: 10 ms ramp); ST ramps 50 steps; a
    handful of deadlines each, not a sample each (timed by ``python -m bench``)."""
    h = Harness("PC48-4")
    h.send("JG10000\r")
    jogging = _count_deadlines(h, 600.0)
    assert h.position() == 5_999_950
    assert rp(h, "RV") == 10_000
    h.send("ST")
    stopping = _count_deadlines(h, 700.0)
    assert jogging <= 5 and stopping <= 5, (jogging, stopping)
    assert h.position() == 6_000_000
    assert h.board.next_deadline() is None


def test_jog_zero_stops_without_zeroing_vl_and_rc_stays_defined() -> None:
    """Found by the command-soup property test: ``CN JF0 ... RC`` divided by zero."""
    h = Harness("PC48-4")
    h.send("CN AX JF0; RC")
    h.send("VL5000 JG2000 ")
    h.run(limit=1.0)
    h.send("JG0 ")
    h.run(limit=1.0)
    assert h.axis("X").vl == 2000
    assert h.query("RC") == b"\n\r0\n\r"
