"""PCIx behaviour where a review against its manual (002_5f0bea9264c6d239.txt) found omsd wrong.

* ``AA;`` typed in single-axis mode takes its queue unit in every axis queue ("AA; AX – AT 1";
  "it places synchronization entries in all axis queues"), as it does typed in AA/AM mode.
* A VB above VL starts a linear move at VL minus one, a one-step ramp up to VL (the VB page);
  the PC48, whose VB page has no such sentence, still starts it at VL.
* RD restores the power-up defaults through the axis queues ("This command places entries in
  all axis command queues to set up the motion profile parameters"): an axis takes them when
  its queue reaches the entry, after the moves queued before RD.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness


def queues(h: Harness) -> list[int]:
    return [int(n) for n in h.send("RQ;").strip(b"\n\r").split(b",")]


def test_aa_typed_in_single_axis_mode_takes_a_unit_in_every_axis_queue() -> None:
    """AA: "This command changes the axis mode immediately, but has axis queue requirements
    because it places synchronization entries in all axis queues", "AA; AX – AT 1", "AA; AA-AM
    1". RQ "reports the number of available entries in the queue". X is busy with a move, so
    the entry waits in its queue (the idle axes execute theirs at once)."""
    h = Harness("PCIX-040")
    h.send("AX;VL1000;MR100000;GO;")
    busy = queues(h)
    h.send("AA;")  # typed in single-axis mode
    assert queues(h) == [busy[0] - 1, 800, 800, 800]
    h.send("AA;")  # typed in AA mode: the same
    assert queues(h) == [busy[0] - 2, 800, 800, 800]
    assert h.errors() == []


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r"))


def test_a_base_velocity_above_vl_starts_a_move_at_vl_minus_one() -> None:
    """VB: "If the VL command is used after the VB command and the velocity value set with VL
    is less than the previously set VB value, the initial velocity used at the start of a move
    will be the VL value minus one. This will result in a one-step acceleration ramp". ?VB
    "returns the base (starting) velocity setting for the current axis as set by the VB
    command": VB's own value. The ramp from 299 to 300 at AC1000 takes 1 ms."""
    h = Harness("PCIX-040")
    h.send("AX;VB500;VL300;AC1000;MR10000;GO;")
    h.advance(0.0006)
    assert number(h.send("RV;")) == 299  # (it was 300: VB clamped to VL)
    assert number(h.send("RC;")) == 1000  # ramping: the one-step ramp's acceleration
    h.advance(0.01)
    assert (number(h.send("RV;")), number(h.send("RC;"))) == (300, 0)
    assert h.send("?VB;") == b"vb500\n\r"
    h.until(40.0)
    assert number(h.send("RP;")) == 10000
    e = Harness("PCIX-040")  # VL equal to VB is not "less than" it: the move starts at VB
    e.send("AX;VB300;VL300;AC1000;MR10000;GO;")
    e.advance(0.0006)
    assert number(e.send("RV;")) == 300
    assert h.errors() == [] and e.errors() == []


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040"])
def test_the_older_boards_still_start_a_move_at_vl_under_a_vb_above_it(model: str) -> None:
    """PC48 VB: "The parameter must be greater than zero and less than the programmed
    velocity"; no word on a VL set below it afterwards: the move starts at VL."""
    h = Harness(model)
    h.send("AX VB500 VL300 AC1000 MR10000 GO ")
    h.advance(0.0006)
    assert number(h.send("RV")) == 300


def test_rd_restores_the_defaults_through_every_axis_queue() -> None:
    """RD "restores the motion parameters using power-up defaults"; "NOTE: This command places
    entries in all axis command queues to set up the motion profile parameters." Its table
    ("RD AX – AT Immediate") gives no units: RQ is as before. X has two moves queued at VL1000
    when RD arrives: the second still runs at 1000 and X reads its saved VL5000 only after
    both; Y, whose queue is empty, has its saved value at once."""
    h = Harness("PCIX-040")
    h.send("AX;VL5000;AY;VL5000;AP;VL2000;")
    h.send("AX;VL1000;MR1000;GO;MR2000;GO;")
    before = queues(h)
    h.send("RD;")
    assert queues(h) == before
    assert h.send("AX;?VL;") == b"vl1000\n\r"  # (it was vl5000: RD acted at once)
    assert h.send("AY;?VL;") == b"vl5000\n\r"
    h.advance(1.5)  # the second move, MR2000, at the VL queued before RD
    assert h.send("AX;RV;") == b"1000\n\r"  # (it was 5000)
    h.advance(3.0)
    assert h.send("AX;?VL;RP;") == b"vl5000\n\r3000\n\r"
    assert queues(h) == [800, 800, 800, 800]
    assert h.errors() == []
