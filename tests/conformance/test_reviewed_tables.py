"""The queue tables of the manuals against omsd's, reviewed command by command (PC48, VS4, PCIx).

Every table entry of the three manuals was compared with the model tables and driven on a
board; the differences left are the choices recorded in the model modules and in
docs/decisions.md. What was wrong is tested here.
"""

from __future__ import annotations

import re

import pytest

from omsd.board.harness import Harness
from omsd.engine.events import DoneEvent


def _free(reply: bytes) -> int:
    return int(re.findall(rb"\d+", reply)[0])


def test_pcix_id_in_a_contour_definition_takes_a_contour_queue_unit() -> None:
    """PCIx ID page (seed 002, L3917-3919): "ID; AX – AT 1", "ID; AA-AM 1", "ID; AA/CD 1".
    Inside a definition RQ reports the contour queue ("RQ AA/CD Immediate"); ID takes one unit
    of it (it used to go to the axis queues and leave the contour queue as it was)."""
    h = Harness("PCIX-004")
    before = _free(h.send("AA;CD0,0;MT1000,0;RQ;"))
    after = _free(h.send("ID;RQ;"))
    assert h.errors() == []
    assert before - after == 1


def test_pcix_id_in_a_contour_sets_the_done_flags_where_it_stands() -> None:
    """An ID queued in the contour (ID AA/CD 1) acts at its place on the path, as AN/AF/BL/BH
    do: here after the first segment (1000 steps at the default CV of 1000, one second), not
    when it is typed nor at the end of the contour."""
    h = Harness("PCIX-004")
    h.send("AA;CD0,0;MT1000,0;ID;MT2000,0;CE;")
    h.events()
    h.send("CX;")
    h.advance(0.5)
    assert [e for e in h.events() if isinstance(e, DoneEvent)] == []
    h.advance(0.6)
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert len(done) == 1 and abs(done[0].time - 1.0) < 0.01
    assert done[0].done_register & 0b11 == 0b11  # the contour axes X and Y


def test_pc48_id_stays_not_valid_in_a_contour_definition() -> None:
    """PC48 §6.12 ID (seed 000, L1975-1979): "AA/CD Not valid"; unchanged by the PCIx fix."""
    h = Harness("PC48-4")
    h.send("AA CD0,0; ID")
    assert len(h.errors()) == 1


@pytest.mark.parametrize("stop", ["KL;", "AA;ST;"])
def test_an_id_in_a_contour_stopped_before_it_sets_no_done_flag(stop: str) -> None:
    """A contour killed or stopped before the place of its ID never reaches it: no done flags,
    no interrupt (the contour's I/O actions further on, AN/AF/BL/BH, are dropped too)."""
    h = Harness("PCIX-004")
    h.send("AA;VL1000;AC100000;CD0,0;MT1000,0;ID;MT2000,0;CE;CX;")
    h.advance(0.5)
    h.send(stop)
    h.advance(5.0)
    assert [e for e in h.events() if isinstance(e, DoneEvent)] == []
