"""PCIx behaviour where a review against its manual (002_5f0bea9264c6d239.txt) found omsd wrong.

* ``AA;`` typed in single-axis mode takes its queue unit in every axis queue ("AA; AX – AT 1";
  "it places synchronization entries in all axis queues"), as it does typed in AA/AM mode.
"""

from __future__ import annotations

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
