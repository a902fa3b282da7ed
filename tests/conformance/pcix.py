"""What the PCIx conformance tests share: the board's rates and defaults, and its reply framing.

The PCIx manual (document 3301-0800000 rev C): "calculates the desired velocity 2048 times each
second" (§7.2); "Acceleration is 2000000 ( AC2000000 )", "Velocity is 200000 ( VL200000 )" (the
factory list); "The current axis command queue size for PC1x is 800."
"""

from __future__ import annotations

from functools import partial

from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from . import support

RATE = 2048
AC0 = 2_000_000.0
VL0 = 200_000.0
QUEUE = 800

tick = partial(support.tick, rate=RATE)
end_tick = partial(support.end_tick, rate=RATE)
linear_move_time = partial(support.linear_move_time, vl=VL0, ac=AC0)


def reply(text: str) -> bytes:
    """A PCIx reply: the manual's ``text<LF>``, framed ``text<LF><CR>`` with nothing before."""
    return text.encode("ascii") + b"\n\r"


def typed(h: Harness, *lines: str) -> bytes:
    """Type an example's ``Enter:`` lines, each ended by the Enter key (CR); return what the
    board sent at once."""
    return b"".join(h.send(line + "\r") for line in lines)


def quiet(model: str, **worlds: AxisWorld) -> Harness:
    """A board whose home switches are out of the way (unless given)."""
    return support.quiet(model, **worlds)
