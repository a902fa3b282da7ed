"""The simulated PCIx servo loop (omsd.board.servo), on a manual clock.

Each PID term the manual names is checked for the direction control theory gives it, the DAC
offsets for the manual's voltages, and the runaway protection for "if the error is greater than
32768 then the controller will disable the PID" (PCIx §2.7.2).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import pytest

from omsd.engine import servo
from omsd.engine.profiles import LINEAR, Trajectory, move_pieces
from omsd.engine.servo import (
    RUNAWAY_ERROR,
    Plant,
    ServoGains,
    ServoLoop,
    step_response,
)

RATE = servo.SERVO_RATE
T = 1.0 / RATE
FACTORY = ServoGains()
NO_I = ServoGains(ki=0.0)


def closed_loop(gains: ServoGains = FACTORY, plant: Plant | None = None) -> ServoLoop:
    loop = ServoLoop(gains, plant)
    loop.closed = True
    return loop


def trace(loop: ServoLoop, setpoint: servo.Setpoint, seconds: float) -> list[float]:
    """The following error at every sample for ``seconds`` from the loop's present time."""
    start = loop.clock.index_at_or_before(loop.time)
    errors = []
    for k in range(1, round(seconds * RATE) + 1):
        loop.run(setpoint, loop.clock.time_of(start + k))
        errors.append(loop.following_error)
    return errors


def move(distance: float, vl: float, ac: float, t0: float = 0.0) -> Trajectory:
    return Trajectory(t0, 0.0, move_pieces(distance, vl, ac, 0.0, LINEAR), final=distance)


# -- factory values -------------------------------------------------------------------------


def test_factory_gains_are_the_command_pages_values() -> None:
    assert (FACTORY.kp, FACTORY.ki, FACTORY.kd) == (10.0, 0.04, 20.0)  # KP/KI/KD pages, RF list
    assert (FACTORY.ku, FACTORY.kb) == (200.0, 10.0)  # §2.8 table
    assert (FACTORY.kv, FACTORY.ka, FACTORY.kf, FACTORY.ko, FACTORY.dz) == (0, 0, 0, 0, 0)
    assert FACTORY.bipolar and not FACTORY.inverted  # BI, SVN


def test_power_up_is_open_loop() -> None:
    """HF: "This is the default mode at power up or reset." """
    loop = ServoLoop()
    assert not loop.closed and not loop.tripped
    assert loop.dac_counts == 0 and loop.dac_volts == 0.0


# -- step response --------------------------------------------------------------------------


def test_default_gains_settle_a_step() -> None:
    r = step_response(step=100.0, duration=1.0)
    assert not r.tripped
    assert abs(r.final_error) < 1.0
    assert r.rise_time < 0.01  # about 3.4 ms
    assert r.overshoot_fraction < 0.05  # well damped: about 2%
    assert r.settling_time < 0.2, f"settled into one count after {r.settling_time:.4f} s"


def test_default_gains_settle_a_negative_step_symmetrically() -> None:
    up = step_response(step=100.0)
    down = step_response(step=-100.0)
    assert down.overshoot == pytest.approx(up.overshoot)
    assert down.settling_time == pytest.approx(up.settling_time)


def test_pd_alone_is_nearly_critically_damped() -> None:
    r = step_response(NO_I, step=100.0)
    assert r.overshoot_fraction < 0.01
    assert r.settling_time < 0.02


def test_raising_kp_shortens_rise_and_raises_overshoot() -> None:
    responses = [step_response(replace(FACTORY, kp=kp), step=100.0) for kp in (10, 15, 25)]
    rises = [r.rise_time for r in responses]
    overshoots = [r.overshoot for r in responses]
    assert rises == sorted(rises, reverse=True) and rises[0] > rises[-1]
    assert overshoots == sorted(overshoots) and overshoots[-1] > 5 * overshoots[0]
    assert all(not r.tripped and abs(r.final_error) < 1.0 for r in responses)


def test_removing_kd_raises_overshoot_and_ringing_and_slows_settling() -> None:
    with_d = step_response(FACTORY, step=100.0, band=5.0)
    without_d = step_response(replace(FACTORY, kd=0.0), step=100.0, band=5.0)
    assert without_d.overshoot > 5 * with_d.overshoot
    assert without_d.zero_crossings > with_d.zero_crossings
    assert without_d.settling_time > with_d.settling_time
    # Without the integrator's slow tail the one-count settling shows the same thing.
    pd = step_response(NO_I, step=100.0)
    p_only = step_response(replace(NO_I, kd=0.0), step=100.0)
    assert p_only.settling_time > pd.settling_time
    assert p_only.overshoot > 10 * pd.overshoot


def test_more_kd_damps_a_lively_loop() -> None:
    lively = step_response(replace(FACTORY, kp=25.0), step=100.0)
    damped = step_response(replace(FACTORY, kp=25.0, kd=40.0), step=100.0)
    assert damped.overshoot < lively.overshoot
    assert damped.zero_crossings <= lively.zero_crossings


def test_a_bad_tuning_oscillates_visibly() -> None:
    """Huge KP and no KD: the loop rings at full DAC swing instead of settling."""
    loop = closed_loop(ServoGains(kp=100.0, kd=0.0, ki=0.0))
    errors = trace(loop, 100.0, 1.0)
    tail = errors[-RATE // 10 :]
    assert max(abs(e) for e in tail) > 100.0  # larger than the step itself, a second later
    crossings = sum(1 for a, b in itertools.pairwise(tail) if a * b < 0)
    assert crossings > 20
    assert step_response(ServoGains(kp=100.0, kd=0.0), step=100.0).settling_time == math.inf


# -- the integrator and KU ------------------------------------------------------------------

BIAS = Plant(bias_volts=0.05)  # 0.05 V is 163.84 DAC counts of disturbance
BIAS_COUNTS = 0.05 / servo.VOLTS_PER_COUNT


def test_without_ki_a_disturbance_leaves_a_steady_error_of_bias_over_kp() -> None:
    loop = closed_loop(NO_I, BIAS)
    loop.run(0.0, 2.0)
    assert loop.following_error == pytest.approx(-BIAS_COUNTS / NO_I.kp, abs=1e-3)
    assert loop.at_rest(tolerance=20.0)


def test_ki_removes_the_steady_error() -> None:
    loop = closed_loop(FACTORY, BIAS)
    loop.run(0.0, 3.0)
    assert abs(loop.following_error) < 0.01
    assert loop.integral == pytest.approx(-BIAS_COUNTS, abs=0.1)
    assert loop.dac_counts == round(-BIAS_COUNTS)


def test_ku_bounds_the_integral_term() -> None:
    gains = replace(FACTORY, ku=100.0)
    loop = closed_loop(gains, BIAS)
    loop.run(0.0, 3.0)
    assert loop.integral == -100.0
    assert loop.following_error == pytest.approx(-(BIAS_COUNTS - 100.0) / gains.kp, abs=1e-3)


def test_ku_zero_disables_the_integrator() -> None:
    loop = closed_loop(replace(FACTORY, ku=0.0), BIAS)
    loop.run(0.0, 2.0)
    assert loop.integral == 0.0
    assert loop.following_error == pytest.approx(-BIAS_COUNTS / FACTORY.kp, abs=1e-3)


def test_ku_bounds_integral_overshoot_on_a_long_step() -> None:
    """The wound-up integral can push at most KU / KP counts past where P and D would stop."""
    no_ku = step_response(replace(FACTORY, ku=0.0), step=2000.0)
    overshoots = [step_response(replace(FACTORY, ku=ku), step=2000.0).overshoot for ku in (50, 200)]
    large_ku = step_response(replace(FACTORY, ku=2000.0), step=2000.0)
    assert no_ku.overshoot < overshoots[0] < overshoots[1] < large_ku.overshoot
    for ku, overshoot in zip((50, 200), overshoots, strict=True):
        assert overshoot <= no_ku.overshoot + ku / FACTORY.kp + 0.5


# -- feedforward and friction ---------------------------------------------------------------


def cruise_error(
    gains: ServoGains, plant: Plant | None = None, velocity: float = 200_000.0
) -> float:
    """Following error in the middle of a long constant-velocity stretch."""
    trajectory = move(velocity * 0.5, abs(velocity), 2_000_000.0)
    loop = closed_loop(gains, plant)
    loop.run(trajectory.position, 0.25)
    return loop.following_error


def test_kp_alone_follows_at_velocity_over_gain() -> None:
    """A velocity-mode amplifier needs an error to make speed: v / (KP * counts/s per count)."""
    g = 200_000.0 * 10.0 / 32768  # the plant's 200,000 counts/s per volt, 10 V / 32,768 a count
    assert cruise_error(NO_I) == pytest.approx(200_000.0 / (g * NO_I.kp), rel=1e-3)


def test_kv_feedforward_removes_the_velocity_following_error() -> None:
    plain = cruise_error(NO_I)
    half = cruise_error(replace(NO_I, kv=Plant().ideal_kv() / 2))
    full = cruise_error(replace(NO_I, kv=Plant().ideal_kv()))
    assert half == pytest.approx(plain / 2, rel=1e-3)
    assert abs(full) < 1e-3 * plain


def test_ka_feedforward_reduces_the_error_while_accelerating() -> None:
    trajectory = move(100_000.0, 200_000.0, 2_000_000.0)
    ramp = 0.1  # the acceleration lasts 0.1 s

    def peak_error(gains: ServoGains) -> float:
        loop = closed_loop(gains)
        return max(abs(e) for e in trace(loop, trajectory.position, ramp))

    kv = replace(NO_I, kv=Plant().ideal_kv())
    assert peak_error(replace(kv, ka=Plant().ideal_ka())) < 0.5 * peak_error(kv)


def test_explicit_feeds_match_the_setpoints_differences() -> None:
    trajectory = move(50_000.0, 200_000.0, 2_000_000.0)
    gains = replace(NO_I, kv=30.0, ka=80.0)
    derived = closed_loop(gains)
    derived.run(trajectory.position, 0.2)
    explicit = closed_loop(gains)
    explicit.run(trajectory.position, 0.2, trajectory.velocity, trajectory.acceleration)
    assert explicit.position == pytest.approx(derived.position, abs=0.5)


FRICTION = Plant(friction_volts=0.1)  # 327.68 DAC counts before the motor turns


def test_kf_offsets_friction_in_the_direction_of_motion() -> None:
    friction = 0.1 / servo.VOLTS_PER_COUNT
    plain = cruise_error(NO_I, FRICTION, velocity=10_000.0)
    compensated = cruise_error(replace(NO_I, kf=friction), FRICTION, velocity=10_000.0)
    assert plain - compensated == pytest.approx(friction / NO_I.kp, rel=1e-3)
    assert compensated == pytest.approx(cruise_error(NO_I, velocity=10_000.0), rel=1e-3)
    backwards = cruise_error(replace(NO_I, kf=friction), FRICTION, velocity=-10_000.0)
    assert backwards == pytest.approx(-compensated, rel=1e-3)


def test_kf_is_silent_at_rest() -> None:
    loop = closed_loop(replace(NO_I, kf=500.0))
    loop.run(0.0, 0.1)
    assert loop.dac_counts == 0 and loop.position == 0.0


# -- the DAC: KB, KO, DZ, BI/UN, SVN/SVI --------------------------------------------------------


def test_kb_bounds_the_output_voltage() -> None:
    loop = closed_loop(replace(FACTORY, kb=1.0))
    volts = []
    speeds = []
    for k in range(1, RATE // 10):
        loop.run(20_000.0, k * T)
        volts.append(loop.dac_volts)
        speeds.append(loop.velocity)
    assert max(volts) == pytest.approx(1.0, abs=servo.VOLTS_PER_COUNT)
    assert max(speeds) <= 200_000.0 * 1.0 + 1e-6  # KB1: 1 V at most, 200,000 counts/s per volt
    free = closed_loop()
    free.run(20_000.0, T)
    assert free.dac_volts > 9.9  # KB10 lets the DAC reach full scale


def test_kb_zero_holds_the_output_at_zero() -> None:
    loop = closed_loop(replace(FACTORY, kb=0.0))
    loop.run(500.0, 0.1)
    assert loop.dac_counts == 0 and loop.position == 0.0


@pytest.mark.parametrize(
    ("dz", "volts"),
    [(3277, 1.0), (250, 0.076), (32667, 9.97), (-32667, -9.97)],
    ids=["DZ3277 near 1VDC", "DZ250 ~ +76mV", "DZ+full", "DZ-full"],
)
def test_dz_is_the_open_loop_output(dz: int, volts: float) -> None:
    loop = ServoLoop(replace(FACTORY, dz=dz))
    assert loop.dac_counts == dz
    assert loop.dac_volts == pytest.approx(volts, abs=0.001)


def test_ko_minus_2000_is_about_minus_610_mv() -> None:
    loop = closed_loop(replace(NO_I, ko=-2000.0))
    loop.run(0.0, T)  # at the setpoint: P, I and D are all zero
    assert loop.dac_volts == pytest.approx(-0.610, abs=0.001)


def test_ko_holds_position_against_a_load() -> None:
    """KO "compensate[s] for additional torque on the motor from loading"."""
    load = Plant(bias_volts=2000 * servo.VOLTS_PER_COUNT)
    plain = closed_loop(NO_I, load)
    plain.run(0.0, 1.0)
    offset = closed_loop(replace(NO_I, ko=-2000.0), load)
    offset.run(0.0, 1.0)
    assert plain.following_error == pytest.approx(-200.0, abs=1e-3)
    assert abs(offset.following_error) < 1e-3


def test_dz_only_acts_in_open_loop_and_ko_only_in_closed() -> None:
    gains = replace(NO_I, dz=1000.0, ko=-300.0)
    loop = ServoLoop(gains, Plant(friction_volts=1.0))  # DZ alone cannot turn this motor
    assert loop.dac_counts == 1000
    loop.closed = True
    loop.run(0.0, T)
    assert loop.dac_counts == -300
    loop.closed = False
    assert loop.dac_counts == 1000


def test_unipolar_maps_zero_to_five_volts() -> None:
    gains = replace(FACTORY, bipolar=False)
    assert ServoLoop(gains).dac_volts == 5.0
    assert ServoLoop(replace(gains, dz=32767)).dac_volts == pytest.approx(10.0, abs=0.001)
    assert ServoLoop(replace(gains, dz=-32767)).dac_volts == pytest.approx(0.0, abs=0.001)
    assert ServoLoop(replace(gains, dz=3277)).dac_volts == pytest.approx(5.5, abs=0.001)


def test_unipolar_moves_the_motor_like_bipolar() -> None:
    bi = step_response(FACTORY, step=100.0)
    un = step_response(replace(FACTORY, bipolar=False), step=100.0)
    assert un == bi


def test_svi_inverts_the_servo_output() -> None:
    normal = closed_loop(NO_I)
    normal.run(10.0, T)
    inverted = closed_loop(replace(NO_I, inverted=True))
    inverted.run(10.0, T)
    assert normal.dac_counts > 0
    assert inverted.dac_counts == -normal.dac_counts


def test_svi_does_not_invert_the_offsets() -> None:
    loop = closed_loop(replace(NO_I, inverted=True, ko=400.0))
    loop.run(0.0, T)
    assert loop.dac_counts == 400
    assert ServoLoop(replace(FACTORY, inverted=True, dz=400.0)).dac_counts == 400


def test_svi_corrects_a_motor_wired_backwards() -> None:
    """SVI example: "The Y axis encoder is counting opposite the expected direction"."""
    backwards = Plant(reversed=True)
    runaway = closed_loop(FACTORY, backwards)
    runaway.run(100.0, 1.0)
    assert runaway.tripped and not runaway.closed
    fixed = step_response(replace(FACTORY, inverted=True), backwards, step=100.0)
    assert fixed == step_response(FACTORY, step=100.0)


# -- HN / HF and the runaway protection ---------------------------------------------------


def test_hf_opens_the_loop_and_outputs_dz_whatever_the_error() -> None:
    loop = closed_loop(replace(FACTORY, dz=-100.0))
    loop.run(50.0, 0.01)
    loop.closed = False
    loop.run(5000.0, 0.5)
    assert loop.dac_counts == -100
    # DZ-100 alone: -100 counts x 10 V / 32,768 = -30.52 mV, x 200,000 counts/s per volt
    assert loop.velocity == pytest.approx(-6103.515625)
    assert loop.following_error == pytest.approx(5000.0 - loop.position)


def test_dz_zeroes_an_unbalanced_amplifier_in_open_loop() -> None:
    """2.7.2: "While still in open-loop mode, hold off (HF), use the DZ command to zero the
    motor"."""
    drifting = ServoLoop(FACTORY, BIAS)
    drifting.run(0.0, 1.0)
    zeroed = ServoLoop(replace(FACTORY, dz=-BIAS_COUNTS), BIAS)
    zeroed.run(0.0, 1.0)
    assert drifting.position > 9000.0
    assert abs(zeroed.position) < 1e-6


def test_open_loop_coasting_follows_the_first_order_lag() -> None:
    """With the output constant the motor speed approaches its target as exp(-t / tau)."""
    gains = replace(FACTORY, dz=1234.0)
    # DZ1234 alone: 1234 counts x 10 V / 32,768 x 200,000 counts/s per volt, with the plant's
    # 1.4 ms lag
    target = 75_317.3828125
    tau = 0.0014
    one = ServoLoop(gains, position=7.0)
    one.velocity = -50_000.0
    many = ServoLoop(gains, position=7.0)
    many.velocity = -50_000.0
    one.run(0.0, 0.01)
    for k in range(1, round(0.01 * RATE) + 1):
        many.run(0.0, k * T)
    t = one.time
    slip = -50_000.0 - target
    expected_v = target + slip * math.exp(-t / tau)
    expected_x = 7.0 + target * t + slip * tau * (1.0 - math.exp(-t / tau))
    for loop in (one, many):
        assert loop.velocity == pytest.approx(expected_v, rel=1e-9)
        assert loop.position == pytest.approx(expected_x, rel=1e-9)


def test_an_error_beyond_32768_disables_the_pid() -> None:
    loop = closed_loop(replace(FACTORY, dz=5.0))
    loop.run(RUNAWAY_ERROR + 1000.0, T)
    assert loop.tripped and not loop.closed
    assert loop.dac_counts == 5  # open loop: DZ only
    loop.run(RUNAWAY_ERROR + 1000.0, 0.5)
    assert loop.tripped and loop.dac_counts == 5
    # DZ5 alone: 5 counts x 10 V / 32,768 = 1.526 mV, x 200,000 counts/s per volt
    assert loop.velocity == pytest.approx(305.17578125)


def test_an_error_within_the_limit_is_chased() -> None:
    loop = closed_loop()
    loop.run(RUNAWAY_ERROR - 1.0, 1.0)
    assert not loop.tripped and loop.closed
    assert abs(loop.following_error) < 1.0


def test_hn_starts_the_integrator_afresh() -> None:
    loop = closed_loop(FACTORY, BIAS)
    loop.run(0.0, 2.0)
    assert loop.integral != 0.0
    loop.closed = False
    loop.closed = True
    assert loop.integral == 0.0
    loop.closed = True  # HN on a closed loop changes nothing
    loop.run(0.0, 2.0 + T)
    assert loop.integral != 0.0
    integral = loop.integral
    loop.closed = True
    assert loop.integral == integral


def test_hn_after_a_trip_closes_the_loop_again() -> None:
    loop = closed_loop()
    loop.run(50_000.0, 0.01)
    assert loop.tripped
    loop.set_position(50_000.0)  # LP: "used to set the position error to 0"
    loop.closed = True
    assert not loop.tripped
    loop.run(50_100.0, 1.0)
    assert abs(loop.following_error) < 1.0 and loop.closed


def test_a_runaway_during_a_move_trips_mid_move() -> None:
    trajectory = move(400_000.0, 200_000.0, 2_000_000.0)
    loop = closed_loop(replace(FACTORY, kb=0.5))  # 0.5 V: the motor cannot reach 200,000/s
    errors = []
    for k in range(1, 2 * RATE):
        loop.run(trajectory.position, k * T)
        errors.append(loop.following_error)
        if loop.tripped:
            break
    assert loop.tripped
    assert errors[-2] <= RUNAWAY_ERROR < errors[-1]


# -- the manual's tuning check and the engine's needs -------------------------------------


def test_the_manuals_position_check_re_equals_rp() -> None:
    """2.7.2: "AC100000;VL5000;MR64000;GO" then compare RE and RP."""
    trajectory = move(64_000.0, 5_000.0, 100_000.0)
    loop = closed_loop()
    loop.run(trajectory.position, trajectory.end_time + 0.2)
    assert loop.encoder_counts > 64_000  # the integrator, wound up by the move, creeps back
    loop.run(trajectory.position, trajectory.end_time + 1.0)
    assert loop.encoder_counts == 64_000
    assert loop.at_rest()


def test_running_in_chunks_gives_the_same_state() -> None:
    trajectory = move(30_000.0, 200_000.0, 2_000_000.0)
    whole = closed_loop()
    whole.run(trajectory.position, 0.4)
    chunked = closed_loop()
    t = 0.0
    while t < 0.4:
        t = min(0.4, t + 0.0123)
        chunked.run(trajectory.position, t)
    assert (chunked.position, chunked.velocity) == (whole.position, whole.velocity)
    assert chunked.time == whole.time == pytest.approx(0.4, abs=T)


def test_run_uses_the_sample_grid_and_never_goes_back() -> None:
    loop = ServoLoop(origin=10.0)
    loop.closed = True
    loop.run(5.0, 10.0 + 2.5 * T)
    assert loop.time == pytest.approx(10.0 + 2 * T)
    position = loop.position
    loop.run(5.0, 10.0)
    assert loop.position == position and loop.time == pytest.approx(10.0 + 2 * T)


def test_a_loop_at_rest_skips_ahead_without_iterating(monkeypatch: pytest.MonkeyPatch) -> None:
    loop = closed_loop()
    loop.run(100.0, 3.0)
    assert loop.at_rest(1e-3)
    calls = 0
    original = ServoLoop._sample

    def counting(self: ServoLoop, *args: object) -> None:
        nonlocal calls
        calls += 1
        original(self, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(ServoLoop, "_sample", counting)
    position = loop.position
    loop.run(100.0, 3600.0)
    assert calls < 100
    assert loop.time == pytest.approx(3600.0)
    assert loop.position == pytest.approx(position, abs=1e-6)
    loop.run(101.0, 3601.0)  # a new setpoint wakes it
    assert calls > 1000
    assert abs(loop.following_error) < 1.0


def test_a_loop_whose_output_still_pushes_is_not_skipped() -> None:
    """A heavy load has not moved yet one sample after HN, but KO is pushing it."""
    heavy = Plant(time_constant=1000.0)
    loop = closed_loop(replace(NO_I, ko=1000.0), heavy)
    loop.run(0.0, T)
    assert abs(loop.position) < 1e-6 and abs(loop.velocity) < 1e-4
    loop.run(0.0, 10.0)
    assert loop.position > 1.0


def test_a_callable_setpoint_is_never_skipped() -> None:
    loop = closed_loop()
    loop.run(0.0, 1.0)
    loop.run(lambda t: 0.0 if t < 1.5 else 10.0, 2.0)
    assert loop.encoder_counts == 10


def test_set_position_is_lp() -> None:
    loop = closed_loop()
    loop.run(200.0, 1.0)
    loop.set_position(0.0)
    assert loop.following_error == 0.0 and loop.position == 0.0
    loop.run(0.0, 1.0 + 10 * T)
    assert abs(loop.dac_counts) <= abs(round(loop.integral)) + 1  # no derivative kick


def test_new_gains_take_effect_without_resetting_the_loop() -> None:
    loop = closed_loop(NO_I, BIAS)
    loop.run(0.0, 1.0)
    loop.set_gains(replace(NO_I, kp=20.0))
    loop.run(0.0, 2.0)
    assert loop.following_error == pytest.approx(-BIAS_COUNTS / 20.0, abs=1e-3)
