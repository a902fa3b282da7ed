"""PCIx custom ramps (SR#, DAR/DAB/DAE tables) and S-curves (SS#, AJ) in ``omsd.board.profiles``.

Manual: PCIx §5.8.3/§5.8.4 and the DAB/DAR/AJ/SR/SS pages. DAB: "the first specifies the
acceleration level that should be used to achieve the second parameter, velocity level";
DAR's example (digest E38): "Ramp at 10% of AC until 5% of VL". AJ: regions 1 (1-ALOWER,
S-curved), 2 (ALOWER, flat), 3 (APEAK, flat), 4 (1-APEAK, S-curved), 6-9 the same for the ramp
down, "ARADIUS can 'stretch' regions 1 and 4 in the time dimension"; §5.12.1 "The S-curve
profile is not truncated ... selects the velocity that will preserve selected S-curve profile".
The modelling choices where the manual is silent are documented in ``profiles._custom_ramp`` and
``profiles._scurve_ramp``; the hand-computed cases below follow them.
"""

from __future__ import annotations

import itertools
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from omsd.engine import profiles as pf
from omsd.engine.profiles import RampKind, RampShape, SCurve, Trajectory

VL, AC = 100_000.0, 1_000_000.0

# DAR3 of the DAR page (E38): "resembling a jerk-limited linear profile"
E38 = ((0.1, 0.05), (0.3, 0.1), (0.9, 0.9), (0.3, 0.95), (0.1, 1.0))
# ?DA2 of the ?DA page (E37)
E37 = ((0.1, 0.2), (0.9, 0.8), (0.1, 1.0))


def custom(*breakpoints: tuple[float, float]) -> RampShape:
    return RampShape(RampKind.CUSTOM, table=1, breakpoints=tuple(breakpoints))


def scurve(*params: float) -> RampShape:
    return RampShape(RampKind.SCURVE, table=1, scurve=SCurve(*params))


LINEAR = RampShape(RampKind.LINEAR)

# E13: "AJ1,0.5,0.5,1.0; *Defines a profile where ramp down is symmetrical with ramp up."
# (decel fields filled in symmetrically, as the AJ command is to do), and
# "AJ2,0.1,0.1,1.0,0.8,0.8,1.0; *Defines an asymmetrical S-curve profile."
AJ1 = scurve(0.5, 0.5, 1.0, 0.5, 0.5, 1.0)
AJ2 = scurve(0.1, 0.1, 1.0, 0.8, 0.8, 1.0)

SHAPES = {
    "e38": custom(*E38),
    "e37": custom(*E37),
    "one-full": custom((1.0, 1.0)),
    "one-half-accel": custom((0.5, 1.0)),
    "ends-low": custom((0.4, 0.3)),
    "zero-accel": custom((0.0, 0.5), (0.6, 1.0)),
    "all-zero": custom((0.0, 0.5), (0.0, 1.0)),
    "decreasing": custom((1.0, 0.8), (0.5, 0.4), (0.2, 1.0)),
    "zero-velocity": custom((0.3, 0.0), (0.7, 1.0)),
    "empty": custom(),
    "scurve-default": scurve(),
    "aj1": AJ1,
    "aj2": AJ2,
    "scurve-flat": scurve(1.0, 1.0, 1.0, 1.0, 1.0, 1.0),
    "scurve-radius": scurve(0.3, 0.6, 4.0, 0.2, 0.0, 10.0),
    "scurve-none": RampShape(RampKind.SCURVE),
}


def displacement(pieces: list[pf.Piece]) -> float:
    return sum(p.x(p.duration) for p in pieces)


def duration(pieces: list[pf.Piece]) -> float:
    return sum(p.duration for p in pieces)


def assert_well_formed(pieces: list[pf.Piece], distance: float, vl: float, ac: float) -> None:
    """Exact distance, rest to rest, velocity continuous, 0 <= v <= VL along the way (for a
    positive move), |a| <= AC."""
    assert pieces
    assert math.isclose(displacement(pieces), distance, rel_tol=1e-9, abs_tol=1e-6)
    assert all(p.duration > 0.0 for p in pieces)
    tol = vl * 1e-9 + 1e-9
    assert abs(pieces[0].v(0.0)) <= tol
    assert abs(pieces[-1].v(pieces[-1].duration)) <= tol
    for p, q in itertools.pairwise(pieces):
        assert math.isclose(p.v(p.duration), q.v(0.0), rel_tol=1e-9, abs_tol=tol)
    for p in pieces:
        for k in range(11):
            tau = p.duration * k / 10
            assert -tol <= p.v(tau) <= vl + tol
            assert abs(p.a(tau)) <= ac * (1 + 1e-9)
            assert p.x(tau) >= -tol * p.duration


# -- custom ramps: hand-computed ------------------------------------------------------------------


def test_e38_ramp_up_segments_follow_the_table():
    """Each DAB line is "Ramp at f_a of AC until f_v of VL": segment i runs at f_a AC from the
    previous velocity to f_v VL, taking (f_v - f_v') VL / (f_a AC)."""
    up = pf.ramp_up(VL, AC, 0.0, custom(*E38))
    assert isinstance(up, pf.Chain)
    assert len(up.parts) == 5
    v0, t0 = 0.0, 0.0
    for part, (fa, fv) in zip(up.parts, E38, strict=True):
        assert part.a(0.0) == pytest.approx(fa * AC)
        assert part.v(0.0) == pytest.approx(v0 * VL)
        assert part.duration == pytest.approx((fv - v0) * VL / (fa * AC))
        assert part.v(part.duration) == pytest.approx(fv * VL)
        assert up.a(t0 + part.duration / 2) == pytest.approx(fa * AC)
        v0, t0 = fv, t0 + part.duration
    # 0.05 + 1/60 + 0.8/9 + 1/60 + 0.05 s; distance = sum of mean velocity x time
    t_total = 0.05 + 1 / 60 + 0.08 / 0.9 + 1 / 60 + 0.05
    s_total = 125 + 125 + 50_000 * 0.08 / 0.9 + 92_500 / 60 + 97_500 * 0.05
    assert up.duration == pytest.approx(t_total, rel=1e-12)
    assert up.x(up.duration) == pytest.approx(s_total, rel=1e-12)
    # RC: the acceleration at the start and at the end of the ramp
    assert up.a(0.0) == pytest.approx(0.1 * AC)
    assert up.a(up.duration) == pytest.approx(0.1 * AC)


def test_e38_long_move_is_ramp_cruise_mirrored_ramp():
    up = pf.ramp_up(VL, AC, 0.0, custom(*E38))
    assert isinstance(up, pf.Chain)
    s_up = up.x(up.duration)
    d = 1_000_000.0
    pieces = pf.move_pieces(d, VL, AC, 0.0, custom(*E38))
    assert len(pieces) == 11
    assert pieces[:5] == list(up.parts)
    assert pieces[5].v(0.0) == pytest.approx(VL, rel=1e-12)
    assert pieces[5].a(0.0) == 0.0
    assert pieces[5].duration == pytest.approx((d - 2 * s_up) / VL, rel=1e-12)
    # the ramp down is the ramp up in reverse: same durations, accelerations negated
    for down, rise in zip(pieces[6:], reversed(up.parts), strict=True):
        assert down.duration == rise.duration
        assert down.a(0.0) == pytest.approx(-rise.a(rise.duration))
        assert down.v(0.0) == pytest.approx(rise.v(rise.duration))
    assert pf.move_time(d, VL, AC, 0.0, custom(*E38)) == pytest.approx(
        2 * up.duration + (d - 2 * s_up) / VL, rel=1e-12
    )
    assert_well_formed(pieces, d, VL, AC)


def test_custom_short_move_is_truncated_at_half_distance():
    """E38 with 1000 steps: the first two segments cover 250; the third (at 0.9 AC from
    10,000 steps/s) is cut where the ramp has covered 500: 10,000 t + 450,000 t^2 = 250."""
    pieces = pf.move_pieces(1000.0, VL, AC, 0.0, custom(*E38))
    assert len(pieces) == 6
    t3 = (-10_000 + math.sqrt(10_000**2 + 4 * 450_000 * 250)) / (2 * 450_000)
    assert pieces[2].duration == pytest.approx(t3, rel=1e-12)
    peak = 10_000 + 900_000 * t3
    assert pieces[2].v(pieces[2].duration) == pytest.approx(peak, rel=1e-12)
    assert displacement(pieces[:3]) == pytest.approx(500.0, rel=1e-12)
    assert duration(pieces) == pytest.approx(2 * (0.05 + 1 / 60 + t3), rel=1e-12)
    assert_well_formed(pieces, 1000.0, VL, AC)


def test_custom_short_move_cut_inside_first_segment():
    """2 steps on E38: 0.1 AC t^2 / 2 = 1 -> t = sqrt(2 / 100,000)."""
    pieces = pf.move_pieces(2.0, VL, AC, 0.0, custom(*E38))
    assert len(pieces) == 2
    assert pieces[0].duration == pytest.approx(math.sqrt(2 / 100_000), rel=1e-12)
    assert_well_formed(pieces, 2.0, VL, AC)


def test_custom_move_exactly_two_ramps_long_has_no_cruise():
    up = pf.ramp_up(VL, AC, 0.0, custom(*E37))
    d = 2 * up.x(up.duration)
    pieces = pf.move_pieces(d, VL, AC, 0.0, custom(*E37))
    assert all(p.a(p.duration / 2) != 0.0 for p in pieces)
    assert_well_formed(pieces, d, VL, AC)


# -- custom ramps: degenerate tables --------------------------------------------------------------


@pytest.mark.parametrize("d", [3.0, 5_000.0, 10_000_000.0])
def test_single_full_breakpoint_is_the_linear_ramp(d):
    """DAB1,1: "Ramp at 100% of AC until 100% of VL" is the linear (trapezoid) profile."""
    ours = pf.move_pieces(d, VL, AC, 0.0, custom((1.0, 1.0)))
    lin = pf.move_pieces(d, VL, AC, 0.0, LINEAR)
    assert len(ours) == len(lin)
    for a, b in zip(ours, lin, strict=True):
        assert a.duration == pytest.approx(b.duration, rel=1e-12)
        assert a.v(0.0) == pytest.approx(b.v(0.0), rel=1e-12, abs=1e-9)
        assert a.a(0.0) == pytest.approx(b.a(0.0), rel=1e-12)


def test_single_breakpoint_below_full_acceleration_is_a_slower_linear_ramp():
    ours = pf.move_time(1e6, VL, AC, 0.0, custom((0.5, 1.0)))
    assert ours == pytest.approx(pf.move_time(1e6, VL, AC / 2, 0.0, LINEAR), rel=1e-12)


def test_table_ending_below_vl_continues_at_its_last_level():
    """Choice: after the last breakpoint the ramp carries on at the last level up to VL."""
    up = pf.ramp_up(VL, AC, 0.0, custom((1.0, 0.2), (0.4, 0.3)))
    assert isinstance(up, pf.Chain)
    assert [p.a(0.0) for p in up.parts] == pytest.approx([AC, 0.4 * AC, 0.4 * AC])
    assert up.v(up.duration) == pytest.approx(VL)
    assert up.duration == pytest.approx(0.02 + 0.8 * VL / (0.4 * AC))


def test_zero_acceleration_breakpoints_are_skipped():
    """DAB0,.5 would never reach 50% of VL: skipped, the next breakpoint takes over."""
    up = pf.ramp_up(VL, AC, 0.0, custom((0.0, 0.5), (0.6, 1.0)))
    assert isinstance(up, pf.Chain)
    assert len(up.parts) == 1
    assert up.a(0.0) == pytest.approx(0.6 * AC)
    assert up.duration == pytest.approx(VL / (0.6 * AC))


@pytest.mark.parametrize("table", [(), ((0.0, 0.5), (0.0, 1.0))], ids=["empty", "all-zero"])
def test_table_without_usable_breakpoint_ramps_at_ac(table):
    """ "A ramp table containing no breakpoints is invalid": choice, ramp at AC to VL."""
    ours = pf.move_pieces(1e6, VL, AC, 0.0, custom(*table))
    lin = pf.move_pieces(1e6, VL, AC, 0.0, LINEAR)
    assert [p.duration for p in ours] == pytest.approx([p.duration for p in lin], rel=1e-12)


def test_decreasing_breakpoint_is_skipped():
    """ "At no time should a DAB command be entered in which the velocity parameter is less than
    the velocity parameter of the prior DAB ... unpredictable": choice, it is skipped."""
    up = pf.ramp_up(VL, AC, 0.0, custom((1.0, 0.8), (0.5, 0.4), (0.2, 1.0)))
    assert isinstance(up, pf.Chain)
    assert [p.a(0.0) for p in up.parts] == pytest.approx([AC, 0.2 * AC])


def test_custom_ignores_base_velocity():
    """VB: "This mode is active only for linear ramps"."""
    shape = custom(*E38)
    assert pf.move_pieces(1e6, VL, AC, 30_000.0, shape) == pf.move_pieces(1e6, VL, AC, 0.0, shape)


def test_ramp_up_with_zero_velocity_keeps_the_starting_acceleration():
    up = pf.ramp_up(0.0, AC, 0.0, custom((0.0, 0.1), (0.3, 1.0)))
    assert up.duration == 0.0
    assert up.a(0.0) == pytest.approx(0.3 * AC)
    up = pf.ramp_up(0.0, AC, 0.0, AJ1)
    assert up.duration == 0.0
    assert up.a(0.0) == 0.0
    assert pf.ramp_up(0.0, AC, 0.0, scurve(1.0, 1.0)).a(0.0) == pytest.approx(AC)


# -- S-curves: hand-computed ---------------------------------------------------------------------


def test_default_scurve_is_a_pure_s():
    """AJ defaults (ALOWER 0, APEAK 0, ARADIUS 1): no flat region; the acceleration rises at
    constant jerk to AC at VL/2 and falls back to 0 at VL: T = 2 VL / AC, s = VL^2 / AC."""
    up = pf.ramp_up(VL, AC, 0.0, scurve())
    assert isinstance(up, pf.Chain)
    assert len(up.parts) == 2
    assert up.duration == pytest.approx(2 * VL / AC, rel=1e-12)
    assert up.x(up.duration) == pytest.approx(VL * VL / AC, rel=1e-12)
    assert up.v(VL / AC) == pytest.approx(VL / 2, rel=1e-12)
    assert up.a(VL / AC) == pytest.approx(AC, rel=1e-12)
    assert up.a(0.0) == 0.0
    assert up.a(up.duration) == pytest.approx(0.0, abs=1e-6)
    jerk = AC / (VL / AC)
    assert up.a(VL / AC / 4) == pytest.approx(jerk * VL / AC / 4, rel=1e-12)
    # no AJ given at all: the AJ defaults
    assert pf.ramp_up(VL, AC, 0.0, RampShape(RampKind.SCURVE)) == up


def test_e13_aj1_half_flat():
    """AJ1,0.5,0.5,1.0: each half (VL/2) is half jerk, half flat in time: AC (t/2 + t) = VL/2
    for t = VL / (3 AC); ramp 4 VL / (3 AC), symmetric, so s = VL/2 x T."""
    up = pf.ramp_up(VL, AC, 0.0, AJ1)
    assert isinstance(up, pf.Chain)
    t = VL / (3 * AC)
    assert [p.duration for p in up.parts] == pytest.approx([t, 2 * t, t], rel=1e-12)
    assert up.duration == pytest.approx(4 * VL / (3 * AC), rel=1e-12)
    assert up.x(up.duration) == pytest.approx(VL / 2 * up.duration, rel=1e-12)
    assert up.v(2 * t) == pytest.approx(VL / 2, rel=1e-12)  # end of the lower half
    assert up.a(1.5 * t) == pytest.approx(AC)  # regions 2 and 3 are flat at AC


def test_aradius_stretches_the_curved_regions():
    """AJ#,0.5,0.5,2.0: region 1 lasts 2 x (1 - 0.5) tau, region 2 0.5 tau, with
    AC (2 x 0.5 tau / 2 + 0.5 tau) = VL/2, tau = VL / (2 AC)."""
    up = pf.ramp_up(VL, AC, 0.0, scurve(0.5, 0.5, 2.0))
    assert isinstance(up, pf.Chain)
    tau = VL / (2 * AC)
    assert [p.duration for p in up.parts] == pytest.approx([tau, tau, tau], rel=1e-12)
    unstretched = pf.ramp_up(VL, AC, 0.0, AJ1)
    assert isinstance(unstretched, pf.Chain)
    assert up.parts[0].duration > unstretched.parts[0].duration
    assert up.parts[1].duration < unstretched.parts[1].duration
    assert abs(up.parts[0].j) < abs(unstretched.parts[0].j)


def test_e13_aj2_asymmetric_ramp_down():
    """AJ2,0.1,0.1,1.0,0.8,0.8,1.0: up tau = VL / (1.1 AC), ramp 2 tau (0.9 + 0.1);
    down tau = VL / (1.8 AC), ramp 2 tau (0.2 + 0.8); region 6 leaves VL at zero deceleration,
    region 9 arrives at rest at zero deceleration."""
    d = 1_000_000.0
    pieces = pf.move_pieces(d, VL, AC, 0.0, AJ2)
    assert len(pieces) == 7
    up, cruise, down = pieces[:3], pieces[3], pieces[4:]
    tu, td = VL / (1.1 * AC), VL / (1.8 * AC)
    assert [p.duration for p in up] == pytest.approx([0.9 * tu, 0.2 * tu, 0.9 * tu])
    assert [p.duration for p in down] == pytest.approx([0.2 * td, 1.6 * td, 0.2 * td])
    assert cruise.v(0.0) == VL and cruise.a(0.0) == 0.0
    assert down[0].a(0.0) == pytest.approx(0.0, abs=1e-6)
    assert down[0].a(down[0].duration) == pytest.approx(-AC)
    assert down[-1].a(down[-1].duration) == pytest.approx(0.0, abs=1e-6)
    s_up = displacement(up)
    s_down = displacement(down)
    assert s_up == pytest.approx(VL / 2 * 2 * tu, rel=1e-12)  # point-symmetric halves
    assert s_down == pytest.approx(VL / 2 * 2 * td, rel=1e-12)
    assert cruise.duration == pytest.approx((d - s_up - s_down) / VL, rel=1e-12)
    assert_well_formed(pieces, d, VL, AC)


def test_scurve_flat_is_the_linear_ramp():
    """ALOWER = APEAK = 1: nothing S-curved, a constant-acceleration ramp at AC."""
    ours = pf.move_pieces(1e6, VL, AC, 0.0, scurve(1.0, 1.0, 1.0, 1.0, 1.0, 1.0))
    lin = pf.move_pieces(1e6, VL, AC, 0.0, LINEAR)
    assert [p.duration for p in ours] == pytest.approx([p.duration for p in lin], rel=1e-12)
    assert [p.a(0.0) for p in ours] == pytest.approx([p.a(0.0) for p in lin])


def test_short_scurve_keeps_the_profile_at_a_lower_peak():
    """ "not truncated ... selects the velocity that will preserve selected S-curve profile":
    default AJ, 2 V^2 / AC = d gives V = sqrt(AC d / 2), and every region keeps its share."""
    d = 2_000.0
    pieces = pf.move_pieces(d, VL, AC, 0.0, scurve())
    peak = math.sqrt(AC * d / 2)
    assert len(pieces) == 4
    assert pieces[1].v(pieces[1].duration) == pytest.approx(peak, rel=1e-12)
    assert [p.duration for p in pieces] == pytest.approx([peak / AC] * 4, rel=1e-12)
    assert max(abs(p.a(0.0)) for p in pieces) == pytest.approx(AC)
    assert_well_formed(pieces, d, VL, AC)


def test_short_asymmetric_scurve_scales_both_sides():
    d = 5_000.0
    full_up = pf.ramp_up(VL, AC, 0.0, AJ2)
    pieces = pf.move_pieces(d, VL, AC, 0.0, AJ2)
    assert len(pieces) == 6  # no cruise
    k = pieces[2].v(pieces[2].duration) / VL
    assert 0 < k < 1
    assert isinstance(full_up, pf.Chain)
    assert [p.duration for p in pieces[:3]] == pytest.approx(
        [k * p.duration for p in full_up.parts], rel=1e-9
    )
    assert_well_formed(pieces, d, VL, AC)


def test_scurve_acceleration_is_continuous():
    for shape in (scurve(), AJ1, AJ2, scurve(0.3, 0.6, 4.0, 0.2, 0.0, 10.0)):
        for d in (500.0, 1e6):
            pieces = pf.move_pieces(d, VL, AC, 0.0, shape)
            assert pieces[0].a(0.0) == 0.0
            assert pieces[-1].a(pieces[-1].duration) == pytest.approx(0.0, abs=AC * 1e-9)
            for p, q in itertools.pairwise(pieces):
                assert p.a(p.duration) == pytest.approx(q.a(0.0), abs=AC * 1e-9)


def test_scurve_jerk_is_bounded_by_ac_over_the_curved_time():
    shape = scurve(0.3, 0.6, 4.0, 0.2, 0.0, 10.0)
    for p in pf.move_pieces(1e6, VL, AC, 0.0, shape):
        assert isinstance(p, pf.Poly)
        if p.j:
            assert abs(p.j) == pytest.approx(AC / p.duration, rel=1e-9)


def test_scurve_ignores_base_velocity():
    assert pf.move_pieces(1e6, VL, AC, 30_000.0, AJ2) == pf.move_pieces(1e6, VL, AC, 0.0, AJ2)


# -- both kinds: properties ------------------------------------------------------------------------


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES.keys())
@pytest.mark.parametrize("distance", [1, 7, 999, 12_345, 1_000_000, 33_554_431])
@pytest.mark.parametrize("sign", [1, -1])
def test_moves_are_well_formed(shape, distance, sign):
    pieces = pf.move_pieces(sign * distance, VL, AC, 0.0, shape)
    assert math.isclose(displacement(pieces), sign * distance, rel_tol=1e-12, abs_tol=1e-7)
    assert_well_formed([pf.scaled(p, sign) for p in pieces], distance, VL, AC)
    assert pf.move_time(sign * distance, VL, AC, 0.0, shape) == duration(pieces)


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES.keys())
def test_zero_distance_or_parameters_give_no_pieces(shape):
    assert pf.move_pieces(0, VL, AC, 0.0, shape) == []
    assert pf.move_pieces(100, 0.0, AC, 0.0, shape) == []
    assert pf.move_pieces(100, VL, 0.0, 0.0, shape) == []


# Custom tables whose first segment, at a constant fraction f of AC up to a velocity v, covers the
# first 50 steps of a move: it lasts v^2 / (2 f AC) steps
FIRST_SEGMENT = {
    "e38": 0.1,  # 10% AC to 5% VL: 5000^2 / 200,000 = 125 steps
    "e37": 0.1,  # 10% AC to 20% VL: 20,000^2 / 200,000 = 2000 steps
    "one-full": 1.0,  # 100% AC to 100% VL: 5000 steps
    "one-half-accel": 0.5,  # 50% AC to 100% VL: 10,000 steps
    "ends-low": 0.4,  # 40% AC to 30% VL: 30,000^2 / 800,000 = 1125 steps
    "decreasing": 1.0,  # 100% AC to 80% VL: 3200 steps
}


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES.keys())
def test_trajectory_reaches_the_target_monotonically(shape):
    traj = Trajectory(1.0, 50.0, pf.move_pieces(-123_456, VL, AC, 0.0, shape), final=-123_406)
    prev = traj.position(1.0)
    steps = 200
    for k in range(1, steps + 1):
        x = traj.position(1.0 + traj.duration * k / steps)
        assert x <= prev + 1e-9
        prev = x
    assert traj.position(traj.end_time) == -123_406
    # the first time the position, 50 at t0 = 1.0, is down to 0: there, and not before
    t = traj.first_time(0.0, False, 1.0)
    assert t is not None and 1.0 < t < traj.end_time
    assert traj.position(t) == pytest.approx(0.0, abs=1e-6)
    assert traj.position(t - 1e-6) > 0.0
    name = next(k for k, v in SHAPES.items() if v == shape)
    if name in FIRST_SEGMENT:
        # the first segment of the table, "Ramp at f of AC until ... of VL", covers the 50
        # steps: 0.5 * f * AC * t^2 = 50
        f = FIRST_SEGMENT[name]
        assert t == pytest.approx(1.0 + math.sqrt(100.0 / (f * AC)), rel=1e-9)


@pytest.mark.parametrize("shape", SHAPES.values(), ids=SHAPES.keys())
def test_ml_scaling_keeps_the_move_time(shape):
    """ML/MT scale VL and AC by the distance ratio: the move time must not change."""
    t = pf.move_time(1e6, VL, AC, 0.0, shape)
    assert pf.move_time(2.5e5, VL / 4, AC / 4, 0.0, shape) == pytest.approx(t, rel=1e-9)


fraction = st.floats(min_value=0.0, max_value=1.0)
tables = st.lists(st.tuples(fraction, fraction), min_size=0, max_size=25)
monotone_tables = tables.map(
    lambda bps: tuple(zip([a for a, _ in bps], sorted(v for _, v in bps), strict=True))
)
scurves = st.builds(
    SCurve,
    fraction,
    fraction,
    st.floats(min_value=1.0, max_value=10.0),
    fraction,
    fraction,
    st.floats(min_value=1.0, max_value=10.0),
)
moves = {
    "distance": st.integers(min_value=1, max_value=67_000_000),
    "vl": st.floats(min_value=1.0, max_value=1_044_000.0),
    "ac": st.floats(min_value=1.0, max_value=8_000_000.0),
}


@settings(max_examples=300, deadline=None)
@given(table=st.one_of(tables, monotone_tables), **moves)
def test_custom_moves_are_well_formed_for_any_table(table, distance, vl, ac):
    pieces = pf.move_pieces(distance, vl, ac, 0.0, custom(*table))
    assert_well_formed(pieces, distance, vl, ac)


@settings(max_examples=300, deadline=None)
@given(sc=scurves, **moves)
def test_scurve_moves_are_well_formed_for_any_profile(sc, distance, vl, ac):
    pieces = pf.move_pieces(distance, vl, ac, 0.0, RampShape(RampKind.SCURVE, 1, 1, (), sc))
    assert_well_formed(pieces, distance, vl, ac)


# -- Chain ---------------------------------------------------------------------------------------


def test_chain_evaluates_its_parts_in_turn():
    a = pf.Poly(0.0, 2.0, 0.0, 1.0)
    b = pf.Poly(2.0, 0.0, 0.0, 3.0)
    c = pf.Poly(2.0, -1.0, 0.0, 4.0)
    chain = pf.Chain([a, pf.Poly(0.0, 0.0, 0.0, 0.0), b, c])
    assert chain.parts == (a, b, c)
    assert chain.duration == 8.0
    assert chain.x(0.5) == 0.25
    assert chain.x(2.0) == 1.0 + 2.0
    assert chain.v(2.0) == 2.0
    assert chain.a(4.5) == -1.0
    assert chain.x(8.0) == 1.0 + 6.0 + 0.0
    assert chain.turning_points() == [6.0]
    flipped = pf.scaled(chain, -1.0)
    assert isinstance(flipped, pf.Chain)
    assert flipped.x(8.0) == -7.0
