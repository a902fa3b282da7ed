"""The board clock of the control API (omsd/timebase.py): real time by default, paused,
stepped and scaled on demand, and deadlines mapped back to the loop's clock."""

from __future__ import annotations

import pytest

from omsd.timebase import Timebase


class FakeLoop:
    def __init__(self) -> None:
        self.t = 100.0

    def time(self) -> float:
        return self.t


def test_a_fresh_timebase_is_the_loop_clock() -> None:
    loop = FakeLoop()
    tb = Timebase(loop.time)
    assert tb.now() == 100.0
    loop.t = 101.5
    assert tb.now() == 101.5
    assert tb.to_loop(103.0) == 103.0


def test_paused_time_stands_still_and_steps_exactly() -> None:
    loop = FakeLoop()
    tb = Timebase(loop.time)
    loop.t = 101.0
    tb.pause()
    loop.t = 200.0
    assert tb.now() == 101.0
    assert tb.to_loop(102.0) is None  # nothing happens by itself
    tb.step(0.25)
    tb.step(0.25)
    assert tb.now() == 101.5
    tb.resume()
    loop.t = 201.0
    assert tb.now() == 102.5


def test_scale_runs_board_time_faster_and_maps_deadlines() -> None:
    loop = FakeLoop()
    tb = Timebase(loop.time)
    tb.set_scale(10.0)
    loop.t = 101.0
    assert tb.now() == pytest.approx(110.0)
    assert tb.to_loop(120.0) == pytest.approx(102.0)
    tb.set_scale(1.0)
    loop.t = 102.0
    assert tb.now() == pytest.approx(111.0)


@pytest.mark.parametrize("bad", [0.0, -1.0, 1e4, float("nan")])
def test_bad_scales_are_refused(bad: float) -> None:
    with pytest.raises(ValueError):
        Timebase(FakeLoop().time).set_scale(bad)


def test_step_needs_a_pause_and_goes_forward() -> None:
    tb = Timebase(FakeLoop().time)
    with pytest.raises(ValueError, match="paused"):
        tb.step(1.0)
    tb.pause()
    with pytest.raises(ValueError, match="forward"):
        tb.step(-1.0)
