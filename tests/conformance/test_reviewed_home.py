"""Homing, limits and travel limits on the four boards, reviewed against the manuals
(2026-11-28). Each test quotes what it checks; where a manual is silent the choice is in
``docs/decisions.md`` ("Switches and the simulated world").

* A limit switch stops an axis that is ramping down: the deceleration after ST, JG0 or a home
  found runs into a limit and stops there, as every other motion does: "The limit switch
  closure will stop the associated pulse stream if the motor travels beyond its allowable limits
  and trips the switch" (PC48 §4.3; the VS4's the same); "if the axis encounters a limit switch
  in the course of executing any motion, the axis will be instructed to stop and the host will
  be notified of the event" (PCIx LN). Such a ramp ran on through the switch with no limit
  event. The soft-limit mode's own ramp down (SL) still runs on beyond the switch, and so does
  a stop of it (ST, JG0: the same ramp at AC); what comes after it (a queued move, gearing to
  another axis) is stopped by the switch again.
"""

from __future__ import annotations

import pytest

from omsd.board.events import LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from .pcix import reply
from .support import physical

#: A stage whose positive limit is 3000 steps out and whose home switch is at 1000..1100.
SHORT = AxisWorld(negative_limit=-20_000.0, positive_limit=3_000.0)

BOARDS = [("PC48-4", " "), ("VS4-040", " "), ("PC46-6", " "), ("PCIX-400", ";")]


def typed(h: Harness, text: str, sep: str) -> bytes:
    return h.send(text.replace(" ", sep))


def limits(h: Harness) -> list[tuple[str, int]]:
    return [(e.axis, e.direction) for e in h.events() if isinstance(e, LimitEvent)]


def position(h: Harness, sep: str) -> int:
    reply = typed(h, "RP ", sep)
    return int(reply.strip(b"\n\r"))


@pytest.mark.parametrize(("model", "sep"), BOARDS)
@pytest.mark.parametrize("stop", ["ST", "JG0"])
def test_a_ramp_down_that_reaches_a_limit_stops_there(model: str, sep: str, stop: str) -> None:
    """PC48 §4.3: "The limit switch closure will stop the associated pulse stream if the motor
    travels beyond its allowable limits and trips the switch" (VS4 §4.3 the same; PC48 §2.2:
    "the associated axis will stop moving if the limit line, for the direction the axis is
    moving, is grounded"); PCIx LN: "With limit switches enabled, if the axis encounters a limit
    switch in the course of executing any motion, the axis will be instructed to stop and the
    host will be notified of the event." A jog at 20,000 steps/s stopped 1000 steps short of the
    limit at AC100000 needs 2000 steps to ramp down: it stops at the switch, with the limit
    event and ``L`` in its status. It ran on to 4000, beyond the switch, with no event."""
    h = Harness(model, world={"X": SHORT})
    typed(h, "AX AC100000 JG20000 ", sep)
    h.until(0.2)  # at speed (0.2 s), 2000 steps out
    assert position(h, sep) == 2000
    typed(h, f"{stop} ", sep)
    h.run()
    assert limits(h) == [("X", 1)]
    assert 3000 <= position(h, sep) <= 3000 + 20_000 // 2048 + 1  # on the sample it was seen
    assert b"PNL" in typed(h, "QA ", sep)


@pytest.mark.parametrize(("model", "sep"), BOARDS)
def test_the_deceleration_after_home_stops_at_a_limit(model: str, sep: str) -> None:
    """PC48 §6.11 HM: "The axis will not stop at home, but will initialize the position counter
    when the home switch becomes true and decelerates to a stop"; the PCIx's HM: "This will
    result in the axis stopping beyond the home switch so care should be taken to ensure
    adequate stopping distance is available beyond the switches". Where there is not, the limit
    switch stops it (§4.3, PCIx LN above). Home at 1000 at 20,000 steps/s and AC400000 needs 500
    steps to stop; the limit is at 1200: the carriage stops there, the counter loaded with 0 at
    home reads about 200, and the host hears of the limit (it ran on to about 1500, beyond the
    switch, unheard)."""
    world = AxisWorld(negative_limit=-20_000.0, positive_limit=1_200.0)
    h = Harness(model, world={"X": world})
    typed(h, "AX AC400000 VL20000 HM0 ", sep)
    h.run()
    assert limits(h) == [("X", 1)]
    assert 1200 <= physical(h, "X") <= 1200 + 20_000 // 2048 + 1  # on the sample it was seen
    assert 190 <= position(h, sep) <= 210  # (home, too, is seen on a sample)
    assert b"PNL" in typed(h, "QA ", sep)


@pytest.mark.parametrize(("model", "sep"), BOARDS)
def test_the_soft_limit_ramp_still_runs_beyond_the_switch(model: str, sep: str) -> None:
    """PC48 §6.5 SL: "The SL command changes the operation of the limit inputs causing the
    output pulse train to ramp down instead of terminating immediately. The output queue is not
    flushed except for the current move." (PCIx SL: "ramp an axis to a stop rather than
    abruptly killing the motion when a limit switch is encountered".) That ramp is the limit's
    own reaction and is not stopped again by the switch it runs past: a move at 20,000 steps/s
    and AC400000 meets the switch at 3000 and stops about 500 steps beyond it; the ID after it
    is still done."""
    h = Harness(model, world={"X": SHORT})
    typed(h, "AX SL AC400000 VL20000 MR10000 GO ID ", sep)
    h.run()
    assert limits(h) == [("X", 1)]
    assert 3400 <= position(h, sep) <= 3600
    assert h.axis("X").done


@pytest.mark.parametrize(("model", "sep"), BOARDS)
def test_after_the_soft_limit_ramp_the_limit_stops_the_next_move(model: str, sep: str) -> None:
    """SL: "The output queue is not flushed except for the current move": the move queued after
    the one that met the limit runs when the ramp has ended, and the limit switch, still active,
    stops it at once (§4.3: "will stop the associated pulse stream"); the host is told again.
    Only the ramp SL makes is let run beyond the switch, not what follows it."""
    h = Harness(model, world={"X": SHORT})
    typed(h, "AX SL AC400000 VL20000 MR10000 GO MR1000 GO ", sep)
    h.run()
    assert limits(h) == [("X", 1), ("X", 1)]
    assert 3400 <= position(h, sep) <= 3600  # where the ramp ended: the second move never ran


@pytest.mark.parametrize(("model", "sep"), BOARDS)
def test_a_stop_during_the_soft_limit_ramp_ramps_on(model: str, sep: str) -> None:
    """SL: "ramp down instead of terminating immediately" (PC48 §6.5; PCIx SL: "ramp an axis to
    a stop rather than abruptly killing the motion when a limit switch is encountered"). An ST
    typed while that ramp runs beyond the switch ramps down as the axis already does, at AC: the
    switch it runs past is still the one the ramp reacts to, met once and reported once. The ST
    stopped the axis dead on its first sample (about 3050 instead of 3500) and the host heard of
    the same limit a second time."""
    h = Harness(model, world={"X": SHORT})
    typed(h, "AX SL AC400000 VL20000 MR10000 GO ", sep)
    h.until(0.18)  # the switch at 3000 was met at about 0.175 s: ramping down beyond it
    assert limits(h) == [("X", 1)]
    typed(h, "ST ", sep)
    h.run()
    assert limits(h) == []
    assert 3400 <= position(h, sep) <= 3600


def test_an_axis_geared_during_its_soft_limit_ramp_is_stopped_by_the_limit() -> None:
    """PCIx TX: "Set up the current axis so that it tracks the X axis" (immediate); EG:
    gearing is cancelled by "over-travel on the geared axis"; LN: "if the axis encounters a
    limit switch in the course of executing any motion, the axis will be instructed to stop and
    the host will be notified of the event". Y, ramping down beyond its switch in the soft-limit
    mode, is geared to X; X's move would carry it further out: the switch, still active, stops
    it at once and the host is told. The mark of the soft-limit ramp stayed on the geared axis,
    and X's move carried Y 5000 steps beyond its switch, unheard."""
    h = Harness("PCIX-400", world={"Y": SHORT})
    h.send("AY;SL;AC400000;VL20000;MR10000;GO;")
    h.until(0.18)
    assert limits(h) == [("Y", 1)]
    h.send("AY;TX;")
    h.send("AX;AC400000;VL20000;MR5000;GO;")
    h.run()
    assert limits(h) == [("Y", 1)]
    assert 3000 <= h.position("Y") <= 3100
    assert h.send("AY;EG?;") == reply("=egf")


def test_jg0_during_the_soft_limit_ramp_of_a_jog_ramps_on() -> None:
    """PCIx SL: "ramp an axis to a stop rather than abruptly killing the motion when a limit
    switch is encountered ... This mode is effective for point to point and JG moves only"; JG:
    "will accelerate to the programmed velocity at the current AC rate and run until altered by
    an ST, SA, KL, HF (servo models), another JG command, or a limit switch". JG0, typed to end
    the jog while the soft-limit ramp runs beyond the switch, ramps down as the axis already
    does, at AC, as ST does (above): the limit is met and reported once, and the axis stops
    about 2000 steps beyond the switch. JG0 stopped it dead on its first sample (3199) and the
    host heard of the same limit a second time."""
    h = Harness("PCIX-400", world={"X": SHORT})
    h.send("AX;SL;AC100000;JG20000;")
    h.until(0.26)  # at speed at 0.2 s; the switch at 3000 met at 0.25 s
    assert limits(h) == [("X", 1)]
    h.send("JG0;")
    h.run()
    assert limits(h) == []
    assert 4900 <= h.position("X") <= 5100
