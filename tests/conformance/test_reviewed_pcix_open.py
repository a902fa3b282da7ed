"""PCIx behaviour an earlier review of its manual (002_5f0bea9264c6d239.txt) left open, where a
second reading found omsd wrong.

* IP on an axis without an encoder behaves like ID: "If the position hold (HN) is not enabled for
  an axis, the command will behave like an ID command for that axis"; it was a command error.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness

from .support import done_events


@pytest.mark.parametrize("mode", ["AX;", "AA;"])
def test_ip_on_an_open_loop_axis_behaves_like_id(mode: str) -> None:
    """IP: "If the position hold (HN) is not enabled for an axis, the command will behave like an
    ID command for that axis" ("IP; AX – AT 1", "IP; AA-AM 1"). An open-loop stepper cannot have
    HN on, so IP there sets the done flag when its queue reaches it, as ID does."""
    h = Harness("PCIX-004")  # four open-loop steppers
    move = "MR1000;GO;" if mode == "AX;" else "MR1000,1000,1000,1000;GO;"
    h.send(mode + "VL1000;" if mode == "AX;" else mode + "VL1000,1000,1000,1000;")
    h.send(move + "IP;")
    assert h.errors() == []  # (it was a command error: not valid for the motor type)
    assert done_events(h) == []
    h.advance(1.1)
    events = done_events(h)
    assert len(events) == 1
    assert events[0].done_register == (0b1 if mode == "AX;" else 0b1111)
