"""Motion behaviours re-read against the manuals (review of behaviours left alone, 2026-11-27)
and found right, pinned here (docs/decisions.md: "SP/FP on an axis at rest", "ML/MT: the
master and its ramp shape"; a GO during a jog is pinned in tests/board/test_counter_property.py).
"""

from __future__ import annotations

import math

import pytest

from omsd.board.harness import Harness

MODELS = [("PC48-4", " "), ("VS4-040", " "), ("PCIX-040", ";")]


def rp(h: Harness, sep: str) -> int:
    return int(h.send("RP" + sep).strip())


@pytest.mark.parametrize(("model", "sep"), MODELS)
def test_sp_is_a_stop_at_position_queued_behind_what_comes_before(model: str, sep: str) -> None:
    """SP: "Stop at position, stop at specified position if possible after all commands have
    been executed" (PC48 and VS4 command lists); "If there is insufficient distance to stop at
    the previously specified deceleration when the command is received, the controller will
    stop as soon as possible at that deceleration". Behind a move it waits for the move's end
    (at rest, it does nothing); behind a staircase or a jog at speed, a position already passed
    stops the axis as soon as possible."""
    h = Harness(model)
    h.send(sep.join(["AX", "VL1000", "AC100000", "MR5000", "GO", "SP40", ""]))
    h.until(0.5)
    assert rp(h, sep) == 495
    h.run()
    assert rp(h, sep) == 5000
    h = Harness(model)
    h.send(sep.join(["AX", "AC100000", "MP", "MV100,1000", "SP40", ""]))
    h.run()
    assert rp(h, sep) == 105  # (1000 steps/s stop in 5 steps at AC100000)
    h = Harness(model)
    h.send(sep.join(["AX", "AC100000", "JG1000", ""]))
    h.until(0.5)
    assert rp(h, sep) == 495
    h.send("SP40" + sep)
    h.run()
    assert rp(h, sep) == 500
    assert h.errors() == []


@pytest.mark.parametrize(("model", "sep"), [("PC48-4", " "), ("PCIX-040", ";")])
@pytest.mark.parametrize("jog", ["JG1000", "JG-1000", "JG333", "JG-4000"])
@pytest.mark.parametrize("phase", [0.0, 0.3, 0.71])
def test_mo_during_a_jog_ends_one_step_from_the_count_on_a_whole_step(
    model: str, sep: str, jog: str, phase: float
) -> None:
    """MO "will output one step pulse in the current direction ... in one sample interval";
    reached while a jog runs (the jog lets its queue go on once up to speed) it takes over from
    rest on the next tick, as a GO does: the counter ends one step from what it counted on that
    tick, the axis at rest on that whole step (a KL then counts nothing more)."""
    h = Harness(model)
    h.send(sep.join(["AX", "AC1000000", jog, ""]))
    t0 = 0.3 + phase / 2048
    h.until(t0)
    h.send("MO" + sep)
    h.until(math.ceil(t0 * 2048) / 2048)
    before = rp(h, sep)
    h.until(t0 + 0.5)
    after = rp(h, sep)
    x = h.axis("X")
    assert after - before == (1 if jog[2] != "-" else -1)
    assert not x.moving and x.position(h.t) == after
    h.send("KL" + sep)
    assert rp(h, sep) == after
    assert h.errors() == []


@pytest.mark.parametrize("move", ["ML", "MT"])
def test_pcix_mt_scales_to_the_longest_move_time_as_ml(move: str) -> None:
    """The PCIx's MT page calls the master "The axis that will reach its destination first",
    its ML page "the axis with the longest move time"; omsd takes the latter for both (the
    slower axis keeps its VL): Y's 10,000 steps at 10,000 steps/s, X's 1000 stretched to end
    with it, at 1.1 s (plus the tick)."""
    h = Harness("PCIX-004")
    h.send(f"AA;VL10000,10000;AC100000,100000;{move}1000,10000;GO;")
    h.until(1.09)
    assert h.axis("X").moving and h.axis("Y").moving
    h.until(1.102)
    assert not h.axis("X").moving and not h.axis("Y").moving
    assert h.send("RP;") == b"1000,10000,0,0\n\r"


@pytest.mark.parametrize(("model", "sep"), MODELS)
@pytest.mark.parametrize("jog", ["JG1000", "JG-1000", "JG1333", "JG-777"])
@pytest.mark.parametrize("move", ["MR100", "MR-100", "MR0"])
@pytest.mark.parametrize("phase", [0.0, 0.4, 0.93])
def test_a_move_begun_during_a_jog_goes_its_steps_from_the_count_at_its_start(
    model: str, sep: str, jog: str, move: str, phase: float
) -> None:
    """MR: "relative from the current position at the time the move is executed" (PC48 §6.7),
    the position RP returns (§6.13). A GO reached while a jog runs starts its move on the next
    tick (docs/decisions.md, "a GO during a jog"), the jog between two steps there: the counter
    at the end is the move's distance from the count on that tick, either way, and the axis
    rests on that whole step."""
    h = Harness(model)
    rate = h.board.model.sample_rate
    h.send(sep.join(["AX", "AC100000", jog, ""]))
    t0 = 0.3 + phase / rate
    h.until(t0)
    h.send(sep.join([move, "GO", ""]))
    h.until(math.ceil(t0 * rate - 1e-9) / rate)
    start = rp(h, sep)
    h.run()
    end = rp(h, sep)
    assert end - start == int(move[2:])
    assert h.axis("X").position(h.t) == end
    assert h.errors() == []
