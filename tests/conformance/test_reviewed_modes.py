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
* Power automatic on the PCIx drives the auxiliary output for every motion, not only for the
  moves of GO/GD/GN/GU: "In power-automatic mode, the auxiliary line will invert at the
  beginning of every motion and return to normal at the end" (PCIx §5.5.1), and the queue tables
  of TM, JG, JF, MV, HM, HR, KM, KR, CX and CG charge "If PA (power automatic) mode is active
  add n". Before, ``AX;PA;TM1000;`` left the output idle through the timed jog (``?AB`` answered
  ``af`` at 0.5 s; now ``an``, and ``af`` again after the jog). The PC48, PC46 and VS4 keep PA
  to GO and GD, as their PA pages say ("upon the execution of the GO or GD").
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


def aux_state(h: Harness) -> bytes:
    return h.send("?AB;")


@pytest.mark.parametrize(
    ("start", "stop"),
    [
        ("TM1000;", ""),  # a timed jog ends by itself
        ("JG10000;", "ST;"),
        ("JF2500.5;", "ST;"),
        ("MP;MV100000,10000;", "SP60000;"),
        ("HM;", ""),  # the default world's home switch is met on the way
    ],
)
def test_pcix_power_automatic_drives_the_output_through_every_motion(start: str, stop: str) -> None:
    h = Harness("PCIX-004")
    h.send("AX;PA;")
    h.run()
    assert aux_state(h) == b"af\n\r"  # PA: the idle state, "on at the end of the move"
    h.send(start)
    h.until(0.0005)
    assert h.axis("X").moving
    assert aux_state(h) == b"an\n\r"  # "invert at the beginning of every motion"
    h.until(0.5)
    h.send(stop)
    h.run()
    assert not h.axis("X").moving
    assert aux_state(h) == b"af\n\r"  # "and return to normal at the end"


def test_pcix_power_automatic_drives_the_output_through_a_contour() -> None:
    h = Harness("PCIX-004")
    h.send("AA;PA1,1;")
    h.run()
    assert h.axis("X").aux and h.axis("Y").aux  # PA1: the idle state is on (high)
    h.send("CD0,0;MT1000,1000;CE;CX;")
    h.until(0.0005)
    assert h.axis("X").moving
    assert not h.axis("X").aux and not h.axis("Y").aux
    h.run()
    assert h.axis("X").aux and h.axis("Y").aux


@pytest.mark.parametrize("model", ["PC48-4", "VS4-040"])
def test_older_boards_power_automatic_is_for_go_and_gd_only(model: str) -> None:
    """PC48 §6.6 PA (the VS4's the same): "The auxiliary will be turned on ... upon the
    execution of the GO or GD and off at the end of that move"; their JG tables have no PA
    row."""
    h = Harness(model)
    h.send("AX PA ")
    h.run()
    h.send("JG10000 ")
    h.until(0.5)
    assert h.axis("X").moving and not h.axis("X").aux
    h.send("ST MR1000 GO ")  # the stop takes 0.01 s, the move 0.11 s
    h.until(0.55)
    assert h.axis("X").moving and h.axis("X").aux


@pytest.mark.parametrize(("model", "sep"), [("PC48-4E", " "), ("PCIX-040", ";")])
def test_power_automatic_settles_off_while_position_maintenance_corrects(
    model: str, sep: str
) -> None:
    """PC48 §6.6 SE: "a settling time, in milliseconds, to be used before the power is
    reduced, when using the PA mode"; PA: "off at the end of that move". The hold's own
    corrections (HN) are no motion PA drives: without SE the output goes idle as the move ends
    and stays so through a correction. With SE, a correction still running when the settling
    time ran out kept the output in its moving state for good (``aux`` on at 3 s, the axis at
    rest): the end of a correction is no end of a move, so nothing turned it back."""
    h = Harness(model)
    h.send(sep.join(["AX", "PA", "SE200", "HV1000", "HG10", "HD0", "HN", "VL10000", "AC100000"]))
    h.send(sep)
    h.run()
    assert not h.axis("X").aux  # PA: the idle state
    h.send(sep.join(["MR1000", "GO"]) + sep)
    h.until(0.05)
    assert h.axis("X").aux  # moving: "on"
    h.board.inject_slip("X", 50, h.t)  # the encoder is 50 ahead: a correction follows the move
    h.until(0.3)
    assert h.axis("X").motion.name == "HOLD"  # correcting, within the settling time
    h.until(3.0)
    x = h.axis("X")
    assert not x.moving and not x.aux  # power reduced once the settling time is over
