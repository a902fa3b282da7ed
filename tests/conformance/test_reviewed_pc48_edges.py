"""PC48-family edge cases earlier reviews left alone, read again against the manuals
(2026-11-27). The ones the manuals do not decide are in ``docs/decisions.md`` ("The PC48
family, edges read again").

* An AA meeting point (the GO of an AA move, WD, WG) released by the last axis to reach it lets
  every axis go on at that instant: "The synchronized modes (AA) insert special wait opcodes
  that allow the axes to be synchronized in this mode" and "As they are executed the space is
  reclaimed" (PC48 §6.1; the VS4's §6.1 the same). An RQ typed behind it in the same string
  saw the last axis past it and the others still waiting: ``AA WS0 WD RQ`` answered
  ``196,196,196,200``.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness


@pytest.mark.parametrize(
    ("model", "sep", "commands", "free"),
    [
        ("PC48-4", " ", "AA WS0 WD RQ", "200,200,200,200"),
        ("PC48-4", " ", "AA WH CW WG RQ", "200,200,200,200"),
        ("PC48-4", " ", "AA MR0,0,0,0; GO RQ", "200,200,200,200"),
        ("PC48-2", " ", "AA WS0 WD RQ", "200,200"),
        ("PC46-42", " ", "AA WS0 WD RQ", "200,200,200,200"),
        ("VS4-040", " ", "AA WS0 WD RQ", "800,800,800,800"),
        ("PCIX-400", ";", "AA;WH;CW;WG;RQ;", None),
    ],
)
def test_axes_leave_an_aa_meeting_point_together(
    model: str, sep: str, commands: str, free: str | None
) -> None:
    """``AA WS0 WD RQ`` (input 0 high, so the WS loop runs once): the four axes leave the loop at
    one instant, and RQ typed behind it sees every queue given back. WS: "The test is at the
    bottom of the loop, i.e. it will always be executed at least once"; §6.1: "When the commands
    are nested within loops, the queue space is not reclaimed until after the loop has been
    executed". Before, T, the last to reach the WD, had left and the others not yet:
    ``196,196,196,200`` (``AA WH CW WG RQ`` ``195,195,195,200``, ``AA MR0,0,0,0; GO RQ``
    ``195,195,195,200``; the VS4 ``796,796,796,800``). A moment later every axis read 200."""
    h = Harness(model)
    reply = h.send(commands)
    fields = reply.strip(b"\n\r").replace(b" ", b"").split(b",")
    assert len(set(fields)) == 1, reply
    if free is not None:
        assert reply == f"\n\r{free}\n\r".encode()
    assert h.errors() == []
