"""The pure profile math of ``omsd.board.profiles`` against the formulas of PC48 §1.3.

Expected values are computed here from the manual ("VELOCITY PROFILES"): linear ramps
v = A_m t, s = V_p^2 / (2 A_m); parabolic a = A_0 - A_0 t/T_2 with t/T_2 = n/10 at the end of
the ramp (project design decision, see digest §8.3 #20) and A_0 = AC; cosine
v = V_p/2 (1 - cos(2 A_m t / V_p)), S_1 = pi V_p^2 / (4 A_m), T = pi V_p / (2 A_m).
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from omsd.engine import profiles as pf
from omsd.engine.profiles import Cosine, Poly, RampKind, RampShape, Trajectory

LINEAR = RampShape(RampKind.LINEAR)
COSINE = RampShape(RampKind.COSINE)


def parabolic(n: int) -> RampShape:
    return RampShape(RampKind.PARABOLIC, n)


SHAPES = [LINEAR, COSINE, *(parabolic(n) for n in range(3, 11))]
SHAPE_IDS = ["linear", "cosine", *(f"pn{n}" for n in range(3, 11))]


def displacement(pieces: list[pf.Piece]) -> float:
    return sum(p.x(p.duration) for p in pieces)


def duration(pieces: list[pf.Piece]) -> float:
    return sum(p.duration for p in pieces)


def boundaries(traj: Trajectory) -> list[float]:
    out, t = [], traj.t0
    for p in traj.pieces[:-1]:
        t += p.duration
        out.append(t)
    return out


# -- ramp shape ---------------------------------------------------------------------------------


@pytest.mark.parametrize("n", range(3, 11))
def test_pn_ratio_is_a_tenth_of_the_parameter(n):
    """§1.3: "The parameter supplied with the PN command is 10 times the ratio t/T_2"."""
    assert RampShape(RampKind.PARABOLIC, n).ratio == n / 10


@pytest.mark.parametrize("n", range(3, 11))
def test_parabolic_ramp_up_follows_manual_formula(n):
    """The ramp to VL starts at A_0 = AC, reaches VL when t/T_2 = n/10, and its velocity and
    distance are A_0 t - A_0 t^2 / (2 T_2) and A_0 t^2/2 - A_0 t^3 / (6 T_2) all along."""
    vl, ac = 400_000.0, 500_000.0
    r = n / 10
    t1 = vl / (ac * (1 - r / 2))
    t2 = t1 / r
    up = pf.ramp_up(vl, ac, 0.0, parabolic(n))
    assert math.isclose(up.duration, t1, rel_tol=1e-12)
    assert math.isclose(up.a(0.0), ac, rel_tol=1e-12)
    assert math.isclose(up.a(t1), ac * (1 - r), rel_tol=1e-9, abs_tol=1e-6)
    for k in range(11):
        t = t1 * k / 10
        assert math.isclose(up.v(t), ac * t - ac * t * t / (2 * t2), rel_tol=1e-9, abs_tol=1e-6)
        x = ac * t * t / 2 - ac * t**3 / (6 * t2)
        assert math.isclose(up.x(t), x, rel_tol=1e-9, abs_tol=1e-6)
    assert math.isclose(up.v(t1), vl, rel_tol=1e-12)


def test_cosine_ramp_up_follows_manual_formula():
    vp, am = 400_000.0, 500_000.0
    up = pf.ramp_up(vp, am, 0.0, COSINE)
    assert math.isclose(up.duration, math.pi * vp / (2 * am), rel_tol=1e-12)
    assert math.isclose(up.x(up.duration), math.pi * vp * vp / (4 * am), rel_tol=1e-12)
    for k in range(11):
        t = up.duration * k / 10
        w = 2 * am * t / vp
        assert math.isclose(up.v(t), vp / 2 * (1 - math.cos(w)), rel_tol=1e-9, abs_tol=1e-6)
        assert math.isclose(up.a(t), am * math.sin(w), rel_tol=1e-9, abs_tol=1e-6)
        x = vp / 2 * t - vp * vp / (4 * am) * math.sin(w)
        assert math.isclose(up.x(t), x, rel_tol=1e-9, abs_tol=1e-6)


def test_linear_ramp_up_with_base_velocity():
    """VB: "The velocity jumps instantly to the specified velocity, then ramps as usual"."""
    up = pf.ramp_up(400_000.0, 500_000.0, 50_000.0, LINEAR)
    assert up.v(0.0) == 50_000.0
    assert math.isclose(up.duration, 0.7)
    assert math.isclose(up.x(up.duration), (400_000**2 - 50_000**2) / 1e6)


def test_base_velocity_is_ignored_by_cosine_and_parabolic():
    """VB "is active only for linear ramps. It is ignored for cosine and parabolic ramps"."""
    for shape in (COSINE, parabolic(3)):
        with_vb = pf.move_pieces(1e6, 4e5, 5e5, 5e4, shape)
        without = pf.move_pieces(1e6, 4e5, 5e5, 0.0, shape)
        assert with_vb == without


# -- move_pieces ------------------------------------------------------------------------------


@pytest.mark.parametrize("shape", SHAPES, ids=SHAPE_IDS)
@pytest.mark.parametrize("distance", [1, 7, 999, 100_000, 1_000_000, 33_554_431])
@pytest.mark.parametrize("sign", [1, -1])
def test_move_pieces_distance_is_exact(shape, distance, sign):
    """Rest-to-rest: the pieces add up to the commanded distance, in either direction."""
    for vb in (0.0, 50_000.0):
        pieces = pf.move_pieces(sign * distance, 400_000.0, 500_000.0, vb, shape)
        assert math.isclose(displacement(pieces), sign * distance, rel_tol=1e-12, abs_tol=1e-7)
        traj = Trajectory(0.0, 0.0, pieces)
        assert math.isclose(traj.final, sign * distance, rel_tol=1e-12, abs_tol=1e-7)
        assert traj.velocity(traj.end_time - 1e-12) * sign >= 0.0


@settings(max_examples=300, deadline=None)
@given(
    distance=st.integers(min_value=1, max_value=67_000_000),
    vl=st.floats(min_value=1.0, max_value=1_044_000.0),
    ac=st.floats(min_value=1.0, max_value=8_000_000.0),
    shape=st.sampled_from(SHAPES),
)
def test_move_pieces_distance_is_exact_for_any_parameters(distance, vl, ac, shape):
    pieces = pf.move_pieces(distance, vl, ac, 0.0, shape)
    assert math.isclose(displacement(pieces), distance, rel_tol=1e-9, abs_tol=1e-6)
    peak = max(p.v(p.duration) for p in pieces)
    assert peak <= vl * (1 + 1e-9)


@pytest.mark.parametrize("shape", SHAPES, ids=SHAPE_IDS)
def test_zero_distance_move_has_no_pieces(shape):
    assert pf.move_pieces(0, 400_000.0, 500_000.0, 0.0, shape) == []


def test_linear_move_time_matches_manual():
    """Trapezoid: T = d/V + V/A (X1: 1e6 steps at 4e5, 5e5 -> 3.3 s); triangle: 2 sqrt(d/A)."""
    assert math.isclose(pf.move_time(1e6, 4e5, 5e5, 0.0, LINEAR), 3.3, rel_tol=1e-12)
    assert math.isclose(pf.move_time(1e5, 4e5, 5e5, 0.0, LINEAR), 2 * math.sqrt(0.2))
    # with VB: ramps of (V - VB)/A and distance (V^2 - VB^2)/(2A) each
    t = 2 * 0.7 + (1e6 - 2 * 157_500) / 4e5
    assert math.isclose(pf.move_time(1e6, 4e5, 5e5, 5e4, LINEAR), t, rel_tol=1e-12)
    vp = math.sqrt(5e4**2 + 5e5 * 1e5)
    assert math.isclose(pf.move_time(1e5, 4e5, 5e5, 5e4, LINEAR), 2 * (vp - 5e4) / 5e5)


@pytest.mark.parametrize("n", range(3, 11))
def test_parabolic_move_time_matches_manual(n):
    r = n / 10
    v, a, d = 400_000.0, 500_000.0, 1_000_000.0
    t1 = v / (a * (1 - r / 2))
    s1 = a * t1 * t1 * (0.5 - r / 6)
    assert 2 * s1 < d
    assert math.isclose(pf.move_time(d, v, a, 0.0, parabolic(n)), 2 * t1 + (d - 2 * s1) / v)


def test_cosine_move_time_matches_manual():
    """Cruise plus two ramps of pi V / (2 A): T = d/V + pi V / (2 A) ("pi/2 times longer than a
    linear ramp to reach the same velocity")."""
    t = pf.move_time(1e6, 4e5, 5e5, 0.0, COSINE)
    assert math.isclose(t, 1e6 / 4e5 + math.pi * 4e5 / (2 * 5e5), rel_tol=1e-12)
    lin_ramp = pf.ramp_up(4e5, 5e5, 0.0, LINEAR).duration
    assert math.isclose(pf.ramp_up(4e5, 5e5, 0.0, COSINE).duration, math.pi / 2 * lin_ramp)


def test_linear_short_move_is_triangular():
    pieces = pf.move_pieces(1e5, 4e5, 5e5, 0.0, LINEAR)
    assert len(pieces) == 2
    assert math.isclose(pieces[0].v(pieces[0].duration), math.sqrt(5e5 * 1e5))
    assert pieces[0].a(0.0) == 5e5 and pieces[1].a(0.0) == -5e5


def test_linear_long_move_reaches_vl_and_cruises():
    pieces = pf.move_pieces(1e6, 4e5, 5e5, 0.0, LINEAR)
    assert len(pieces) == 3
    assert pieces[1].v(0.0) == 4e5 and pieces[1].a(0.0) == 0.0
    assert math.isclose(pieces[1].duration, 1.7)


@pytest.mark.parametrize("n", [3, 6, 10])
def test_parabolic_short_move_truncates_keeping_shape(n):
    """§1.3: "If the move is too short to reach the programmed speed the curve is truncated,
    causing the shape of the velocity curve to remain the same": the same initial acceleration
    AC and the same jerk -A_0/T_2 as the full ramp, cut where half the distance is covered."""
    full = pf.ramp_up(4e5, 5e5, 0.0, parabolic(n))
    pieces = pf.move_pieces(1e5, 4e5, 5e5, 0.0, parabolic(n))
    assert len(pieces) == 2
    up = pieces[0]
    assert isinstance(up, Poly) and isinstance(full, Poly)
    assert math.isclose(up.a(0.0), 5e5) and math.isclose(up.j, full.j)
    assert up.duration < full.duration
    assert math.isclose(up.x(up.duration), 5e4, rel_tol=1e-9)
    assert up.v(up.duration) < 4e5
    for k in range(11):  # the deceleration mirrors the acceleration
        tau = up.duration * k / 10
        assert math.isclose(pieces[1].v(tau), up.v(up.duration - tau), abs_tol=1e-6)


def test_cosine_short_move_keeps_full_shape_with_lower_peak():
    """Short cosine move: peak acceleration AC, 360 degrees of sine, v_p = sqrt(2 A d / pi)."""
    d, a = 1e5, 5e5
    vp = math.sqrt(2 * a * d / math.pi)
    pieces = pf.move_pieces(d, 4e5, a, 0.0, COSINE)
    assert len(pieces) == 2
    up, down = pieces
    assert math.isclose(up.v(up.duration), vp, rel_tol=1e-12)
    assert math.isclose(up.duration, math.pi * vp / (2 * a), rel_tol=1e-12)
    assert math.isclose(up.a(up.duration / 2), a, rel_tol=1e-12)  # peak acceleration
    assert math.isclose(down.a(down.duration / 2), -a, rel_tol=1e-12)
    assert abs(up.a(0.0)) < 1e-6 and abs(down.a(down.duration)) < 1e-6


@pytest.mark.parametrize("shape", SHAPES, ids=SHAPE_IDS)
@pytest.mark.parametrize("distance", [5_000, 100_000, 1_000_000])
def test_trajectory_is_continuous_at_piece_boundaries(shape, distance):
    """Position and velocity are continuous where one piece hands over to the next."""
    traj = Trajectory(2.0, 17.0, pf.move_pieces(distance, 4e5, 5e5, 0.0, shape))
    assert boundaries(traj)
    eps = 1e-9
    for b in boundaries(traj):
        assert abs(traj.position(b + eps) - traj.position(b - eps)) < 1e-3
        assert abs(traj.velocity(b + eps) - traj.velocity(b - eps)) < 1e-2
    assert traj.position(2.0) == 17.0
    assert traj.position(1.0) == 17.0
    assert math.isclose(traj.position(traj.end_time + 5), 17.0 + distance, rel_tol=1e-12)
    assert abs(traj.velocity(2.0 + eps)) < 1.0  # starts from rest
    assert abs(traj.velocity(traj.end_time - eps)) < 1.0  # ends at rest
    assert traj.velocity(traj.end_time + 1) == 0.0


def test_vb_trajectory_jumps_to_base_velocity_only_at_the_ends():
    traj = Trajectory(0.0, 0.0, pf.move_pieces(1e6, 4e5, 5e5, 5e4, LINEAR))
    eps = 1e-9
    assert math.isclose(traj.velocity(eps), 5e4, rel_tol=1e-6)
    assert math.isclose(traj.velocity(traj.end_time - eps), 5e4, rel_tol=1e-6)
    for b in boundaries(traj):
        assert abs(traj.velocity(b + eps) - traj.velocity(b - eps)) < 1e-2


def test_velocity_at_the_start_instant_of_a_moving_trajectory():
    """A trajectory that starts in motion (a jog speed change, a counter reload mid-move)
    has its initial velocity at its own start instant, not zero."""
    traj = Trajectory(1.0, 0.0, [Poly(1000.0, -500.0, 0.0, 1.0), pf.cruise(500.0)])
    assert traj.velocity(1.0) == 1000.0


def test_trajectory_final_given_exactly():
    traj = Trajectory(0.0, 0.0, pf.move_pieces(1e6, 4e5, 5e5, 0.0, COSINE), final=1_000_000)
    assert traj.position(traj.end_time) == 1_000_000
    assert traj.is_finite
    assert not Trajectory(0.0, 0.0, [pf.cruise(10.0)]).is_finite


# -- first_time ---------------------------------------------------------------------------------


def test_first_time_monotonic_move():
    """A symmetric trapezoid crosses half its distance at half its duration; a level reached in
    the cruise is reached at s_ramp/V later than the ramp end."""
    traj = Trajectory(1.0, 0.0, pf.move_pieces(1e6, 4e5, 5e5, 0.0, LINEAR))
    assert math.isclose(traj.first_time(5e5, True, 1.0), 1.0 + 3.3 / 2, rel_tol=1e-12)
    assert math.isclose(traj.first_time(160_000 + 4e5, True, 0.0), 1.0 + 0.8 + 1.0)
    t = traj.first_time(40_000, True, 1.0)  # in the ramp: A t^2 / 2 = 40000 -> t = 0.4
    assert math.isclose(t, 1.4, rel_tol=1e-12)
    assert traj.first_time(1e6 + 1, True, 1.0) is None
    assert traj.first_time(-1, False, 1.0) is None
    # a level already reached at t_from is reached at t_from
    assert traj.first_time(100, True, 3.0) == 3.0


def test_first_time_negative_move():
    traj = Trajectory(0.0, 500.0, pf.move_pieces(-1000, 4e5, 5e5, 0.0, COSINE))
    half = traj.first_time(0.0, False, 0.0)
    assert math.isclose(half, traj.end_time / 2, rel_tol=1e-9)
    assert traj.first_time(0.0, True, 0.0) == 0.0  # 500 >= 0 already
    assert traj.first_time(-501, False, 0.0) is None


def test_first_time_final_level_is_reached_at_end():
    traj = Trajectory(0.0, 0.0, pf.move_pieces(1000, 4e5, 5e5, 0.0, LINEAR), final=1000)
    t = traj.first_time(1000, True, 0.0)
    assert t is not None and math.isclose(t, traj.end_time, rel_tol=1e-9, abs_tol=1e-9)


def test_first_time_through_turning_point_in_one_poly():
    """x = 1000 t - 500 t^2 over 2 s: up to 500 at t=1, back to 0 at t=2."""
    traj = Trajectory(0.0, 0.0, [Poly(1000.0, -1000.0, 0.0, 2.0)], final=0.0)
    assert math.isclose(traj.first_time(400, True, 0.0), 1 - math.sqrt(0.2), rel_tol=1e-12)
    assert math.isclose(traj.first_time(450, False, 1.0), 1 + math.sqrt(0.1), rel_tol=1e-12)
    assert math.isclose(traj.first_time(450, False, 0.5), 0.5)  # already below at t_from
    assert traj.first_time(500.001, True, 0.0) is None  # never quite reached
    assert math.isclose(traj.first_time(499.999, True, 0.0), 1 - math.sqrt(2e-6), rel_tol=1e-9)


def test_first_time_through_split_velocity_change_and_infinite_cruise():
    """velocity_change(1000, -1000) splits at zero; then an endless cruise at -1000."""
    pieces = [*pf.velocity_change(1000.0, -1000.0, 1000.0), pf.cruise(-1000.0)]
    assert len(pieces) == 3
    traj = Trajectory(10.0, 0.0, pieces)
    assert math.isclose(traj.first_time(450, False, 11.0), 11 + math.sqrt(0.1), rel_tol=1e-12)
    assert math.isclose(traj.first_time(-1000, False, 10.0), 13.0, rel_tol=1e-12)
    assert traj.first_time(600, True, 10.0) is None


def test_first_time_through_cosine_turning_point():
    """x = 1000 sin(t) for a Cosine piece from +1000 to -1000 over pi seconds."""
    traj = Trajectory(0.0, 0.0, [Cosine(1000.0, -2000.0, 1.0, math.pi)], final=0.0)
    assert math.isclose(traj.position(math.pi / 2), 1000.0, rel_tol=1e-12)
    assert math.isclose(traj.first_time(500, True, 0.0), math.pi / 6, rel_tol=1e-12)
    assert math.isclose(traj.first_time(500, False, math.pi / 2), 5 * math.pi / 6, rel_tol=1e-12)
    assert traj.first_time(1000.5, True, 0.0) is None


# -- stops --------------------------------------------------------------------------------------


def test_stop_distance_and_velocity_change():
    assert pf.stop_distance(35_000.0, 200_000.0) == 3062.5
    assert pf.stop_distance(-35_000.0, 200_000.0) == 3062.5
    (piece,) = pf.velocity_change(100_000.0, 35_000.0, 200_000.0)
    assert math.isclose(piece.duration, 0.325) and piece.a(0.0) == -200_000.0
    assert math.isclose(piece.x(piece.duration), 21_937.5)
    assert pf.velocity_change(5.0, 5.0, 1.0) == []


def test_stop_at_reaches_the_position_exactly_or_overshoots():
    """SP/FP: cruise then brake at AC to land on the position; too close: stop at once at AC."""
    pieces = pf.stop_at(10_000.0, 1000.0, 10_000.0)
    assert math.isclose(displacement(pieces), 10_000.0, rel_tol=1e-12)
    assert math.isclose(duration(pieces), 9.95 + 0.1, rel_tol=1e-12)
    short = pf.stop_at(10.0, 1000.0, 10_000.0)
    assert math.isclose(displacement(short), 50.0)
    back = pf.stop_at(-10_000.0, -1000.0, 10_000.0)
    assert math.isclose(displacement(back), -10_000.0, rel_tol=1e-12)
