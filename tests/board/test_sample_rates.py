"""The same move timed on a PC48, a VS4 and a PC46-21 on a manual clock shows the quantization of
each sample rate (issue 4).

PC48 §1.2 / VS4 §1.2 / PC46 "OPERATING PRINCIPLE": the velocity is calculated 2048 (PC48), 1024
(VS4) and 512 (PC46-21 and -41) times a second and "used to control a variable frequency pulse
train which is derived from a crystal oscillator". So the *events* of a move fall on the sample
grid (it starts on the first tick at or after its GO and is done on the first tick at or after
its analytic end) while the *pulse train* follows the analytic profile between ticks: the
position counter is within one step of it at any instant, on all three boards.

The move: ``AX VL10000 AC100000 MR5000 GO ID`` sent at t0 = 0.0003 s, before the first tick of
every grid (1/2048, 1/1024, 1/512 s). Linear ramps of 0.1 s (500 steps) at each end and 0.4 s
at 10,000/s in between: 0.6 s. The tick times are computed here from the rates alone.
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest

from omsd.board.events import DoneEvent
from omsd.board.harness import Harness

T0 = 0.0003
VL = 10_000
AC = 100_000
DISTANCE = 5000
RAMP = Fraction(VL, AC)  # 0.1 s
DURATION = 2 * RAMP + Fraction(DISTANCE - VL * VL // AC, VL)  # 0.6 s
COMMAND = f"AX VL{VL} AC{AC} MR{DISTANCE} GO ID"

BOARDS = [("PC48-4", 2048), ("VS4-040", 1024), ("PC46-21", 512)]


def ticks(rate: int) -> tuple[int, int]:
    """(start, done) as tick numbers on a grid of ``rate`` ticks a second."""
    start = math.ceil(Fraction(T0) * rate)
    done = math.ceil(start + DURATION * rate)
    return start, done


def analytic(tau: float) -> float:
    """Steps emitted ``tau`` seconds after the start of the move (PC48 §1.3, linear ramps)."""
    ramp = float(RAMP)
    total = float(DURATION)
    if tau <= 0:
        return 0.0
    if tau <= ramp:
        return AC * tau * tau / 2
    if tau <= total - ramp:
        return AC * ramp * ramp / 2 + VL * (tau - ramp)
    if tau <= total:
        left = total - tau
        return DISTANCE - AC * left * left / 2
    return float(DISTANCE)


def started(model: str) -> Harness:
    h = Harness(model)
    h.until(T0)
    assert h.send(COMMAND) == b""
    return h


def test_the_expected_ticks() -> None:
    """The arithmetic the other tests rely on, written out: GO at 0.0003 s is before tick 1 of
    every grid (0.61, 0.31, 0.15 ticks); 0.6 s after tick 1 the analytic end falls between
    ticks again (1229.8, 615.4, 308.2)."""
    assert Fraction(3, 5) == DURATION
    assert ticks(2048) == (1, 1230)
    assert ticks(1024) == (1, 616)
    assert ticks(512) == (1, 309)


@pytest.mark.parametrize(("model", "rate"), BOARDS)
def test_move_starts_on_the_first_tick_after_go(model: str, rate: int) -> None:
    """Nothing moves between the GO and the next tick; on the tick the ramp begins."""
    start = ticks(rate)[0] / rate
    h = started(model)
    h.until(start - 1e-7)
    assert h.axis("X").velocity(h.t) == 0.0
    h.until(start + 0.001)
    assert h.axis("X").velocity(h.t) == pytest.approx(AC * 0.001)
    assert h.position("X") == 0  # 0.05 steps so far


@pytest.mark.parametrize(("model", "rate"), BOARDS)
def test_done_on_the_first_tick_at_or_after_the_analytic_end(model: str, rate: int) -> None:
    """The last pulse is out at start + 0.6 s; the done flag waits for the next tick."""
    start_tick, done_tick = ticks(rate)
    end = start_tick / rate + float(DURATION)
    done = done_tick / rate
    assert end < done < end + 1 / rate
    h = started(model)
    h.until(end + 1e-6)
    assert h.position("X") == DISTANCE
    assert h.axis("X").velocity(h.t) == 0.0
    assert h.board.registers.done == 0
    h.until(done - 1e-7)
    assert h.board.registers.done == 0
    h.until(done)
    assert h.board.registers.done == 0b1
    events = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert [e.time for e in events] == [done]


@pytest.mark.parametrize(("model", "rate"), BOARDS)
def test_position_within_one_step_of_the_analytic_profile(model: str, rate: int) -> None:
    """Looked at 997 times during the move, off every grid: the counter is always within ±1
    step of the analytic profile (the pulse train is continuous; only events are quantized)."""
    start = ticks(rate)[0] / rate
    h = started(model)
    worst = 0.0
    n = 997
    for i in range(1, n + 1):
        t = start + float(DURATION) * i / n + 1e-5
        h.until(t)
        expected = analytic(t - start)
        worst = max(worst, abs(h.position("X") - expected))
        assert abs(h.position("X") - expected) <= 1.0, (model, t, h.position("X"), expected)
    assert worst > 0.0  # the counter is whole steps: it was looked at between steps


def test_the_three_boards_differ_only_by_their_grids() -> None:
    """Side by side: the same command at the same instant gives three start times (1/2048,
    1/1024, 1/512 s) and three done times (1230/2048, 616/1024, 309/512 s), each the first
    tick of its grid at or after the event, and all three end at 5000 steps."""
    starts: dict[str, float] = {}
    dones: dict[str, float] = {}
    for model, _rate in BOARDS:
        h = started(model)
        t = T0
        while h.axis("X").velocity(t) == 0.0:
            t += 1e-5
            h.until(t)
        starts[model] = t
        h.run()
        assert h.position("X") == DISTANCE
        (event,) = [e for e in h.events() if isinstance(e, DoneEvent)]
        dones[model] = event.time
    assert dones == {"PC48-4": 1230 / 2048, "VS4-040": 616 / 1024, "PC46-21": 309 / 512}
    for model, rate in BOARDS:
        tick = ticks(rate)[0] / rate
        assert tick < starts[model] <= tick + 1e-5, model
    assert starts["PC48-4"] < starts["VS4-040"] < starts["PC46-21"]
    assert dones["PC48-4"] < dones["VS4-040"] < dones["PC46-21"]
