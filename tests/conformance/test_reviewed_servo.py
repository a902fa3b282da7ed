"""Servo and encoder commands where a review against the manuals (PCIx
002_5f0bea9264c6d239.txt, PC48 000_438df88d2a6a1670.txt) found omsd wrong.

* Ending position hold ends its correction: HF (every board) and the PC48's LP, entered while the
  hold is moving the axis back toward the held position, left the correction running to its end
  (EA already said "Position maintenance disabled").
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness

from .support import moving, quiet


def _correcting(model: str, hold: str) -> Harness:
    """An axis holding position (HV100, HG1, HD0: a correction at 100 counts a second) whose
    carriage has slipped 1000 counts and that has been correcting for one second."""
    h = quiet(model)
    h.send(hold)
    h.advance(0.1)
    h.board.inject_slip("X", 1000, h.t)
    h.advance(1.0)
    assert moving(h, "X")
    return h


@pytest.mark.parametrize(
    ("model", "hold", "command"),
    [
        ("PCIX-040", "AX;HV100;HG1;HD0;HN;", "HF;"),
        ("PC48-4E", "AX HV100 HG1 HD0 HN ", "HF "),
        ("VS4-040", "AX HV100 HG1 HD0 HN ", "HF "),
        ("PC48-4E", "AX HV100 HG1 HD0 HN ", "LP0 "),
    ],
)
def test_ending_the_hold_ends_its_correction(model: str, hold: str, command: str) -> None:
    """PCIx §5.7.1: "Once the axis has initially stopped, the axis will begin moving again to
    correct for any error encountered during the course of the full move. This process will
    continue until the encoder position is within the dead band"; HG: "This gain parameter is
    multiplied by the position error in determining the velocity during correction". HF "disables
    position hold" (PCIx and PC48 §6.15); the PC48's HN: "Hold and slip detection are disabled if
    an LP, HM, HR, SA, ST or KL command is entered". With the hold off nothing computes a
    correction velocity: the correction stops where it is (it started with no ramp, at HG × error,
    and ends the same way). Before, it ran on to the old goal, 9 more seconds here."""
    h = _correcting(model, hold)
    h.send(command)
    h.advance(0.01)
    assert not moving(h, "X")
    x = h.position("X")
    h.advance(1.0)
    assert h.position("X") == x
    assert h.errors() == []
