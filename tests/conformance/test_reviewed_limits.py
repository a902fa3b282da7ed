"""Limit switches, stops and kills and the flags they leave, a second review on the four boards
(2026-11-27). Each test quotes what it checks; where a manual is silent the choice is in
``docs/decisions.md`` ("Switches and the simulated world", "Flags and registers").
"""

from __future__ import annotations

import pytest

from omsd.board.events import LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import OVRT
from omsd.engine.world import LimitWiring

#: Normally open limit switches far out; the home switch out of the way.
OPEN = AxisWorld(
    home_low=5_000_000.0, home_high=5_000_100.0, limit_switches=LimitWiring.NORMALLY_OPEN
)
#: ... and normally closed ones (grounded until hit: a limit for LH, none for LL).
CLOSED = OPEN.with_changes(limit_switches=LimitWiring.NORMALLY_CLOSED)


def limits(h: Harness) -> list[tuple[str, int]]:
    return [(e.axis, e.direction) for e in h.events() if isinstance(e, LimitEvent)]


@pytest.mark.parametrize(("world", "level"), [(OPEN, "LH"), (CLOSED, "LL")])
def test_a_limit_level_that_makes_the_line_true_stops_a_running_jog(
    world: AxisWorld, level: str
) -> None:
    """PCIx LH: "This command allows TTL logic high to be treated as the 'true' state"; LN:
    "if the axis encounters a limit switch in the course of executing any motion, the axis will
    be instructed to stop and the host will be notified of the event"; §5.5.4: "When a limit is
    encountered, the axis involved will cease motion and flush any pending motion commands".
    A jog has left its queue, so a queued LH (LL) runs while it moves. With the switches wired
    the other way the line, away from the switch, now reads true: QA said ``PNLN`` at once, but
    the jog ran on (``RP`` 9975 at 1 s) with no limit and no OVRT. It stops on the next sample."""
    h = Harness("PCIX-400", world={"X": world})
    if level == "LL":
        h.send("AX;LH;")
    h.send("AX;VL10000;JG10000;")
    h.until(0.1)
    assert h.send("QA;") == b"PNNN\n\r"
    h.send(level + ";")
    h.until(1.0)
    assert limits(h) == [("X", 1)]
    assert h.position("X") <= 1000 + 10  # stopped within a sample of the LH (5 steps a sample)
    assert h.send("RV;") == b"0\n\r"
    assert h.board.read_status_register(h.t) & OVRT
    h.send("JG-10000;")  # moving the other way, the line true there too: stopped again
    h.until(1.1)
    assert limits(h) == [("X", -1)]


#: The Y axis standing on its positive limit switch (hit from -10 up), the line true (LL).
ON_THE_SWITCH = AxisWorld(positive_limit=-10.0, home_low=5_000_000.0, home_high=5_000_100.0)


@pytest.mark.parametrize("level", ["", "AY;LL;", "AY;LH;LL;"])
def test_a_limit_level_command_keeps_the_first_look_of_a_motion_about_to_begin(
    level: str,
) -> None:
    """Found by review: LH/LL ask for a look at the sensors at once, and that look replaced the
    one a motion begun on the next sample had asked for. Y, geared to X (EG), stands on its
    positive switch, the line true; X's MR GO starts both on the next sample, and Y's queued LL
    (which changes nothing) ran at the same instant: its look, before the motion began, saw no
    direction, and the one on the first sample was gone. Y ran through the switch to 500 with no
    limit. LN: "if the axis encounters a limit switch in the course of executing any motion, the
    axis will be instructed to stop and the host will be notified of the event"; it stops on
    its first sample, with or without the LL."""
    h = Harness("PCIX-040", world={"Y": ON_THE_SWITCH})
    h.send("AY;EGX;")
    h.until(0.0123)  # (between two samples)
    h.send("AX;VL1000;MR500;GO;" + level)
    h.until(1.0)
    assert limits(h) == [("Y", 1)]
    assert h.send("AA;RP;") == b"500,0,0,0\n\r"


@pytest.mark.parametrize("command", ["LN;", "TL100000,-100000;", "IS;"])
def test_a_command_that_asks_for_a_look_keeps_the_first_look_of_a_motion_about_to_begin(
    command: str,
) -> None:
    """The same as LH/LL's (above), for the other commands that ask for a look at once: Y,
    geared to X, its switches off (LF), stands on its positive switch; X's MR GO starts both on
    the next sample, and Y's queued LN (the switches on again), then TL (travel limits far
    away) or IS (slip detection on), ran at the same instant. Their look came before the motion
    and took the place of the first sample's: Y ran through the switch to 500. LN: "if the axis
    encounters a limit switch in the course of executing any motion, the axis will be
    instructed to stop"."""
    h = Harness("PCIX-040", world={"Y": ON_THE_SWITCH})
    h.send("AY;LF;EGX;")
    h.until(0.0123)
    h.send("AX;VL1000;MR500;GO;AY;LN;" + ("" if command == "LN;" else command))
    h.until(1.0)
    assert limits(h) == [("Y", 1)]
    assert h.send("AA;RP;") == b"500,0,0,0\n\r"
