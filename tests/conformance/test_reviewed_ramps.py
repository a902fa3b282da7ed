"""Ramps, the base velocity and homing, reviewed against the manuals (2026-11-27).

* FP on a move with a base velocity ramps down to it and stops from there at the position, as
  the move's own end and ST do: VB "jumps instantly to the specified velocity, then ramps as
  usual. The deceleration is the same in reverse. This mode is active only for linear ramps"
  (PC48 §6.7; the PCIx's VB page, the VS4's the same); FP "will flush the command queue and
  attempt to stop at the specified position" (PC48 §6.20). It used to ramp down to 0, VB/AC
  later and (VB^2 / 2AC) earlier on its way.
* A home search takes no base velocity (the choice in docs/decisions.md): it ramps from rest at
  AC to VL, as a jog does ("This command is not valid with the JG command"; the PCIx's KR "will
  find home by issuing a JG in reverse").
"""

from __future__ import annotations

import math

import pytest

from omsd.board.events import DoneEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

RATE = 2048  # "calculating the optimum velocity 2048 times each second" (PC48 §1.2, PCIx 7.2)


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r;"))


@pytest.mark.parametrize(("model", "sep"), [("PC48-4", " "), ("VS4-040", " "), ("PCIX-004", ";")])
def test_fp_on_a_move_with_a_base_velocity_stops_from_the_base_velocity(
    model: str, sep: str
) -> None:
    """VB5000 VL10000 AC10000 MR100000: the ramp 5000 -> 10000 takes 0.5 s over 3750 steps, so
    at 3.0 s the axis is at 28750, cruising. FP50000 then cruises to 50000 - 3750 = 46250
    (4.75 s), ramps down to 5000 over the 3750 steps left and stops there at 5.25 s; at 5.0 s
    it runs at 10000 - 10000 * 0.25 = 7500. (Ramping down to 0 it braked at 4.625 s, ran at
    6250 at 5.0 s and stopped at 5.625 s.)"""
    h = Harness(model)
    h.send(sep.join(["AX", "VB5000", "VL10000", "AC10000", "MR100000", "GO", ""]))
    h.until(3.0)
    assert number(h.send("RP" + sep)) == 28750
    h.events()
    h.send(sep.join(["FP50000", "ID", ""]))
    h.until(4.7)
    assert number(h.send("RV" + sep)) == 10000
    h.until(5.0)
    assert number(h.send("RV" + sep)) == 7500
    h.until(6.0)
    assert number(h.send("RP" + sep)) == 50000
    assert number(h.send("RV" + sep)) == 0
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1
    assert 5.25 <= done[0].time <= 5.25 + 2 / RATE


def test_fp_at_or_below_the_base_velocity_runs_on_to_the_position_and_stops_there() -> None:
    """A move still at its base velocity (VB5000, 0.1 s after the GO: 5000 + 10000 * 0.1 would
    be 6000, so here VL5000 and VB5000 are one: the move jumps to 5000 and cruises) has no ramp
    down to make: FP1000 runs on at 5000 to 1000 and stops there at once, at 0.2 s."""
    h = Harness("PC48-4")
    h.send("AX VB5000 VL5000 AC10000 MR100000 GO ")
    h.until(0.1)
    h.send("FP1000 ID ")
    h.until(0.19)
    assert number(h.send("RV")) == 5000
    h.until(0.3)
    assert number(h.send("RP")) == 1000
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1 and 0.2 <= done[0].time <= 0.2 + 2 / RATE


def test_fp_too_close_overshoots_from_the_base_velocity() -> None:
    """FP "The axis will overshoot if there is insufficient distance left to stop at the
    programmed acceleration": at 10000 with VB5000 the ramp down takes 3750 steps; FP to a
    position 1000 ahead brakes at once and stops 3750 steps on."""
    h = Harness("PC48-4")
    h.send("AX VB5000 VL10000 AC10000 MR100000 GO ")
    h.until(3.0)
    h.send("FP29750 ")
    h.until(4.0)
    assert number(h.send("RP")) == 28750 + 3750


@pytest.mark.parametrize(("model", "sep"), [("PC48-4", " "), ("PCIX-004", ";")])
def test_a_home_search_takes_no_base_velocity(model: str, sep: str) -> None:
    """VB100 VL1000 AC10000 HM (EPICS's "VL101 VB100 AC200 CA HM0 GD ID" sends VB with a home):
    the search ramps from rest, 10 steps/s after 1 ms, not 100 + 10."""
    h = Harness(model, world={"X": AxisWorld(home_low=5000, home_high=5100)})
    h.send(sep.join(["AX", "VB100", "VL1000", "AC10000", "HM0", ""]))
    h.until(1 / RATE * 3)
    assert number(h.send("RV" + sep)) == math.floor(10000 * 3 / RATE)
