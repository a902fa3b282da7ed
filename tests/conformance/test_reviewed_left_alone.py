"""Behaviour earlier reviews found and left alone, read again against the manuals (2026-11-27),
where the manual's words found omsd wrong.

* A settling time (SE) that runs out while a motion power automatic does not drive is running
  (the PC48 family's jogs and home searches: its PA is "at the beginning of each GO or GD
  command execution") reduces the power then: SE is "a settling time, in milliseconds, to be
  used before the power is reduced, when using the PA mode" (PC48 §6.6). Before, the output
  stayed in its moving state until that jog or search ended.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness
from omsd.engine.world import AxisWorld


@pytest.mark.parametrize(
    ("model", "after"),
    [
        ("PC48-4", "JG5000"),
        ("VS4-040", "JG5000"),
        ("PC48-4", "HM"),
    ],
)
def test_settling_time_reduces_the_power_during_a_motion_pa_does_not_drive(
    model: str, after: str
) -> None:
    """``AX PA SE200 VL10000 AC100000 MR1000 GO JG5000``: the move ends at 0.2 s, the jog starts
    from there, the settling time runs out at 0.4 s. PA (PC48 §6.6): "turn on or off the
    auxiliary outputs at the beginning of each GO or GD command execution and complement the
    outputs after the move is executed"; SE: "to be used before the power is reduced". A jog or
    a home search is no GO or GD, so nothing keeps the power up past the settling time: ``aux``
    is off at 0.6 s (it was on until the jog was stopped)."""
    far = AxisWorld(home_low=1_000_000, home_high=1_000_100)  # (a search that runs on)
    h = Harness(model, world={"X": far})
    h.send(" ".join(["AX", "PA", "SE200", "VL10000", "AC100000", "MR1000", "GO", after, ""]))
    h.until(0.3)
    x = h.axis("X")
    assert x.moving and x.aux  # the move over, still settling
    h.until(0.6)
    assert x.moving and x.motion.name in ("JOG", "HOME")
    assert not x.aux  # power reduced once the settling time is over
