"""PC48-family edge cases earlier reviews left alone, read again against the manuals
(2026-11-27). The ones the manuals do not decide are in ``docs/decisions.md`` ("The PC48
family, edges read again").

* An AA meeting point (the GO of an AA move, WD, WG) released by the last axis to reach it lets
  every axis go on at that instant: "The synchronized modes (AA) insert special wait opcodes
  that allow the axes to be synchronized in this mode" and "As they are executed the space is
  reclaimed" (PC48 §6.1; the VS4's §6.1 the same). An RQ typed behind it in the same string
  saw the last axis past it and the others still waiting: ``AA WS0 WD RQ`` answered
  ``196,196,196,200``.

The tests after it hold what was read again and kept (a move ending on its limit switch, a limit
during a contour, ST in the shaped ramp modes, a refused axis selection).
"""

from __future__ import annotations

import pytest

from omsd.board.events import DoneEvent, ErrorKind, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import OVRT

from .support import errors, frame, status_frame


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


# -- read again and kept: the choices are in docs/decisions.md ("The PC48 family, edges read
# again"); these tests hold them, so that changing one is a decision --------------------------

#: The X axis's positive limit switch 1000 steps out; the home switch out of the way.
SWITCH_AT_1000 = AxisWorld(positive_limit=1000.0, home_low=5_000_000.0, home_high=5_000_100.0)

STAGE_MODELS = ["PC48-4", "PC46-42", "VS4-040"]


@pytest.mark.parametrize("model", STAGE_MODELS)
def test_a_move_that_ends_on_a_limit_switch_is_done_without_overtravel(model: str) -> None:
    """``AX VL10000 AC100000 MR1000 GO ID`` with the positive switch at 1000: the last step
    closes the switch as the move ends. §4.3: "The limit switch closure will stop the associated
    pulse stream if the motor travels beyond its allowable limits and trips the switch"; OVRT:
    "An overtravel switch was true indicating attempted travel out of bounds". No travel beyond
    was attempted: the ID runs (``PDLN``: done, and RA's "Axis in overtravel" while the switch
    is active), no OVRT, no limit. The next move toward the switch is stopped on its first
    sample, with OVRT and the limit; a move away runs."""
    h = Harness(model, world={"X": SWITCH_AT_1000})
    h.send("AX VL10000 AC100000 MR1000 GO ID ")
    h.run()
    assert h.send("QA RP") == status_frame("PDLN") + frame("1000")
    assert not h.board.read_status_register(h.t) & OVRT
    assert [type(e) for e in h.events()] == [DoneEvent]
    h.send("MR10 GO ")
    h.until(h.t + 0.1)
    assert h.send("RP") == frame("1000")
    assert h.board.read_status_register(h.t) & OVRT
    assert [e.axis for e in h.events() if isinstance(e, LimitEvent)] == ["X"]
    h.send("MR-10 GO ")
    h.run()
    assert h.send("RP") == frame("990")


@pytest.mark.parametrize("model", STAGE_MODELS)
def test_a_limit_during_a_contour_stops_its_own_axis_only(model: str) -> None:
    """Y's positive switch at 500 on a contour from (1000,0) to (2000,1000) and (3000,1000):
    Y stops at 500 and its queue is flushed (§7.3.4: "When the board receives a limit signal from
    the platform, it flushes its command queue"); X runs its share of the contour to the end
    to 3000 and its CE ramp down (50 steps more: 1000² / 2 × 10000). The contour pages say nothing
    of a limit; §4.3 stops "the associated pulse stream"."""
    h = Harness(model, world={"Y": SWITCH_AT_1000.with_changes(positive_limit=500.0)})
    h.send("AA VL1000,1000,1000,1000; AC10000,10000,10000,10000; CV1000 CD1000,0; ")
    h.send("MT2000,1000; MT3000,1000; CE CX ID ")
    h.run()
    assert h.send("RP") == frame("3050,500,0,0")
    assert [e.axis for e in h.events() if isinstance(e, LimitEvent)] == ["Y"]
    assert h.send("RI") == status_frame("PDNN,PNLN,PDNN,PDNN")


@pytest.mark.parametrize("model", STAGE_MODELS)
@pytest.mark.parametrize("ramp", ["CN", "PN5"])
def test_st_decelerates_at_ac_in_every_ramp_mode(model: str, ramp: str) -> None:
    """ST "causes the axis to decelerate to a stop at the rate previously specified in an AC
    command" (PC48 §6.9; the VS4's and the PC46's the same): a constant rate, AC. Its queue
    table has one column ("Flush + 2") where a move's has three (linear 4, parabolic 15, cosine
    15), and JG, stopped by ST, ramps linearly in every mode ("Linear ramp"). Stopped half a
    second into a cosine or parabolic ramp up (VL10000 AC10000), X loses 10000 steps/s each
    second until it is at rest."""
    h = Harness(model)
    h.send(f"AX {ramp} VL10000 AC10000 MR100000 GO ")
    h.until(0.5)
    h.send("ST ")
    x = h.axis("X")
    h.until(0.55)
    v0 = x.velocity(h.t)
    assert v0 > 1000.0
    h.until(0.6)
    assert x.velocity(h.t) == pytest.approx(v0 - 500.0, abs=1e-6)
    h.run()
    assert x.velocity(h.t) == 0.0


@pytest.mark.parametrize("model", ["PC48-2", "PC46-22", "VS4-020"])
@pytest.mark.parametrize("select", ["AZ", "AT"])
def test_a_refused_axis_selection_leaves_the_axis_selected_before(model: str, select: str) -> None:
    """On a two-axis board (X and Y) AZ and AT are a command error (the ``#`` through the
    driver), and the commands after them go to the axis selected before: CMD_S "An
    unrecognizable command has been detected" (Table 3-8); the AZ page: "sets the context to
    direct all the following commands to the Z axis", which there is none of. ``AA MR100,200; GO``
    then ``AY <select> QA RP`` answers for Y."""
    h = Harness(model)
    h.send("AA MR100,200; GO ")
    h.run()
    assert h.send(f"AY {select} QA RP") == status_frame("PNNN") + frame("200")
    assert errors(h) == [(ErrorKind.NO_SUCH_AXIS, select)]
