"""The less common motion modes, where a review against the manuals (2026-11-27) found omsd
wrong: timed jogs, GU/GN/GD, SO, the velocity staircase, velocity streaming, linear
interpolation and the jog variants.

* A linear move (ML, MT) on the PCIx, whose ramps are chosen per axis (LA, PR, SR, SS), ends on
  every axis at the same sample, on a straight line: ML "uses linear interpolation to perform a
  straight line relative move ... The velocity and acceleration parameters are scaled to allow
  the axes to move and finish together. All axes are scaled to the axis with the longest move
  time (the master axis)"; MT: "This is done to ensure all involved axes arrive at their targets
  simultaneously". Every axis of the move follows the master's profile, its ramp shape
  included, scaled by its share of the distance. Before, each axis kept its own ramp shape with
  the scaled VL and AC: ``AA;VL10000,10000;AC20000,20000;AY;PR5;AA;ML10000,5000;GO;`` ended X
  (linear, the master) at 1.5 s and Y (parabolic) at 1.593 s, off the line between.
"""

from __future__ import annotations

import pytest

from omsd.board.events import DoneEvent
from omsd.board.harness import Harness


@pytest.mark.parametrize(
    "ramps",
    [
        "AY;PR5;",  # Y parabolic, X (the master) linear
        "AX;PR5;",  # the master parabolic, Y linear
        "AY;PR10;AX;PR3;",  # two parabolic ramps of different steps
    ],
)
def test_pcix_ml_axes_of_different_ramps_finish_together_on_a_line(ramps: str) -> None:
    h = Harness("PCIX-004")
    h.send(f"AA;VL10000,10000;AC20000,20000;{ramps}AA;ML10000,5000;GO;ID;")
    x, y = h.axis("X"), h.axis("Y")
    assert x.traj.end_time == pytest.approx(y.traj.end_time)
    for t in (0.1, 0.3, 0.7, 1.0, 1.3, 1.45):
        h.until(t)
        # on the straight line from (0, 0) to (10000, 5000), and moving along it
        assert y.position(h.t) == pytest.approx(x.position(h.t) / 2, abs=1e-6)
        assert y.velocity(h.t) == pytest.approx(x.velocity(h.t) / 2, abs=1e-6)
    h.run()
    assert (h.position("X"), h.position("Y")) == (10000, 5000)
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1


def test_pcix_mt_axes_of_different_ramps_arrive_simultaneously() -> None:
    """MT: "The axis that will reach its destination first (the master axis) is used as a gauge
    to modify the acceleration and velocity values of the other axes. This is done to ensure all
    involved axes arrive at their targets simultaneously." """
    h = Harness("PCIX-004")
    h.send("AA;VL1000,100000;AC100000,100000;AY;PR7;AA;MT2000,10000;GO;")
    x, y = h.axis("X"), h.axis("Y")
    assert x.traj.end_time == pytest.approx(y.traj.end_time)
    h.until(1.0)
    assert y.position(h.t) == pytest.approx(5 * x.position(h.t), abs=1e-6)
    h.run()
    assert (h.position("X"), h.position("Y")) == (2000, 10000)
