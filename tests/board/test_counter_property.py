"""The position counter against a step-by-step reference (a property test).

The rule (``docs/decisions.md``, "The counter counts the steps emitted, the way the axis
travels"; PC48 §6.13 RP: "returns the current position").
"""

from __future__ import annotations

import math

import pytest

from omsd.board.harness import Harness

MODELS = ["PC48-4", "PC48-4E", "VS4-040", "PCIX-040"]
EPS = 1e-6


# -- what the property found -------------------------------------------------------------------


def rp(h: Harness) -> int:
    return int(h.send("AX RP ").strip())


@pytest.mark.parametrize("model", MODELS)
def test_a_kill_at_rest_after_a_move_by_nothing_from_a_jog_keeps_the_count(model: str) -> None:
    """The property's first find, minimised. ``MR0 GO`` reached while a jog at -1 step/s runs
    (the move starts from rest on the next tick, docs/decisions.md "a GO during a jog") left
    the axis at rest at -0.00144, between two steps: RP read 0 (no step emitted), and a KL
    there, at rest, made it -1, a step never emitted. RP "returns the current position" (PC48
    §6.13); MR moves "relative from the current position at the time the move is executed"
    (PC48 §6.7): by nothing from 0, to rest on 0."""
    h = Harness(model)
    h.send("AX AC500 JG-1 MR0 GO ")
    h.until(0.5)
    assert rp(h) == 0
    h.send("KL ")
    assert rp(h) == 0


@pytest.mark.parametrize("model", MODELS)
def test_a_move_reached_while_a_jog_runs_goes_its_steps_from_the_count(model: str) -> None:
    """``JG-1000`` at AC3333 has emitted 150 steps when it reaches its speed at -150.278 (RP
    -150) and ``MR100 GO`` starts from rest there. The move's target was taken from the
    carriage between two steps, -150.278 + 100 = -50.278, and it came to rest on -51: 99 steps
    by the counter for an MR100. MR "will set up the axis to move relative from the current
    position at the time the move is executed" (PC48 §6.7; PCIx: "from their current
    positions"), and the current position is what RP returns (§6.13): -150 + 100 = -50."""
    h = Harness(model)
    h.send("AX AC3333 JG-1000 MR100 GO ")
    h.until(0.3005)
    assert rp(h) == -150
    h.run()
    assert rp(h) == -50


@pytest.mark.parametrize("model", MODELS)
def test_a_stop_between_two_ticks_counts_no_step_before_its_tick(model: str) -> None:
    """The property's second find, minimised. A jog at -2500 (AC200000) is at -109.375 at
    0.05 s, between two ticks: 109 steps emitted, RP -109. ``MR50 GO ST`` there: the move
    would start from rest on the next tick (0.05029), so the ST found no speed to ramp down
    from on that tick and stopped the pulses "at once" as of the tick, where the carriage is
    at -110.107 (on the PC48), and RP read -110 at 0.05: a step the pulses reach only at
    0.05025. RP "returns the current position" (PC48 §6.13), and this command "is not queued,
    i.e. the current position will be returned immediately even if the axis is in motion":
    until the tick the jog goes on, and RP counts -110 once the carriage gets there."""
    h = Harness(model)
    h.send("AX AC200000 JG-2500 ")
    h.until(0.05)
    assert rp(h) == -109
    assert int(h.send("AX MR50 GO ST RP ").strip()) == -109
    h.until(0.05026)
    assert rp(h) == -110
    tick = h.board.clock.at_or_after(0.05)
    at_tick = math.ceil(-109.375 - 2500 * (tick - 0.05) - EPS)  # (where the jog stops)
    h.run()
    assert rp(h) == at_tick
    assert h.axis().position(h.t) == at_tick
