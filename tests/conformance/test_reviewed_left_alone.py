"""Behaviour earlier reviews found and left alone, read again against the manuals (2026-11-27),
where the manual's words found omsd wrong.

* A settling time (SE) that runs out while a motion power automatic does not drive is running
  (the PC48 family's jogs and home searches: its PA is "at the beginning of each GO or GD
  command execution") reduces the power then: SE is "a settling time, in milliseconds, to be
  used before the power is reduced, when using the PA mode" (PC48 §6.6). Before, the output
  stayed in its moving state until that jog or search ended.
* A home search begun while the axis still moves the other way (HM reached while a JG-
  runs, the jog letting its queue go on once up to speed) takes no home until it travels its
  own way: HM "will cause the current axis to step in the positive direction at the predefined
  velocity, until the home input line goes true" (PC48 §6.11; PCIx HM "move in the positive
  direction ... until the home is detected"; HR "exactly like the HM command, except it travels
  in the reverse direction"). Before, the switch's far edge, met while reversing out of the jog,
  counted as home and the counter was loaded about a switch width off.
* The PCIx's ML and MT charge their rows for the axes that are not the master: "If this is not
  the master axis, then the acceleration and velocity values will be modified, and the following
  queue requirements will be added" (ML: linear 6, parabolic 20 ...; MT: linear 6, parabolic 26
  ...). RQ showed ML's and MT's 4 on every axis of the move.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness
from omsd.engine.world import AxisWorld


@pytest.mark.parametrize(
    ("model", "after"),
    [
        ("PC48-4", "JG5000"),
        ("VS4-040", "JG5000"),
        ("PC48-4", "HM"),
    ],
)
def test_settling_time_reduces_the_power_during_a_motion_pa_does_not_drive(
    model: str, after: str
) -> None:
    """``AX PA SE200 VL10000 AC100000 MR1000 GO JG5000``: the move ends at 0.2 s, the jog starts
    from there, the settling time runs out at 0.4 s. PA (PC48 §6.6): "turn on or off the
    auxiliary outputs at the beginning of each GO or GD command execution and complement the
    outputs after the move is executed"; SE: "to be used before the power is reduced". A jog or
    a home search is no GO or GD, so nothing keeps the power up past the settling time: ``aux``
    is off at 0.6 s (it was on until the jog was stopped)."""
    far = AxisWorld(home_low=1_000_000, home_high=1_000_100)  # (a search that runs on)
    h = Harness(model, world={"X": far})
    h.send(" ".join(["AX", "PA", "SE200", "VL10000", "AC100000", "MR1000", "GO", after, ""]))
    h.until(0.3)
    x = h.axis("X")
    assert x.moving and x.aux  # the move over, still settling
    h.until(0.6)
    assert x.moving and x.motion.name in ("JOG", "HOME")
    assert not x.aux  # power reduced once the settling time is over


@pytest.mark.parametrize(
    ("model", "sep", "jog", "search"),
    [
        ("PC48-4", " ", "JG-5000", "HM"),
        ("PCIX-400", ";", "JG-5000", "HM"),
        ("PC48-4", " ", "JG5000", "HR"),
        ("PCIX-040", ";", "JG5000", "HR"),
    ],
)
def test_a_home_search_reversing_out_of_a_jog_takes_home_on_its_own_way(
    model: str, sep: str, jog: str, search: str
) -> None:
    """The switch at 1000..1100, the carriage 2000 steps beyond it on the side the jog comes
    from. ``AX AC10000 VL2000 JG-5000 HM MA0 GO``: the jog is up to speed at 0.5 s, HM turns it
    round at AC through the switch (moving negative) and back (moving positive). Home is where
    the search meets the switch on its own way, as a search from rest does: ``MA0 GO`` ends at
    the same edge as after a search from rest (1000.2 for HM, 1098.4 for HR: the switch's side
    the search comes from). Before, HM took the edge at 1100 met on the way down: ``RP`` after
    the search answered -597 (now 500), MA0 GO ended at 1097.6 (now 1000.6); HR took the one at
    1000 (RP 599, now -502; MA0 GO at 1000.8, now 1097.9)."""
    start, rest = (3000.0, 0.0) if search == "HM" else (-900.0, 2000.0)

    def home_after(commands: list[str], position: float) -> float:
        h = Harness(model, world={"X": AxisWorld(start_position=position)})
        h.send(sep.join(["AX", "AC10000", "VL2000", *commands, search, "MA0", "GO", ""]))
        h.run()
        assert h.errors() == []
        return h.axis("X").carriage(h.t)

    from_rest = home_after([], rest)
    assert abs(from_rest - 1050.0) > 40.0  # (an edge of the switch, 1000..1100)
    assert home_after([jog], start) == pytest.approx(from_rest, abs=1.0)


@pytest.mark.parametrize(
    ("commands", "free"),
    [
        # X (10000 at the same VL and AC) is the master; Y, linear, adds 6
        ("AA;WT1000;ML10000,5000;", "793, 787, 797, 797"),
        # Y (5000) is the master now; X adds 6
        ("AA;WT1000;ML1000,5000;", "787, 793, 797, 797"),
        # X at VL1000 is the master; Y, parabolic (PR5), adds MT's 26 to MT's 4
        ("AA;VL1000,100000;AY;PR5;AA;WT1000;MT2000,10000;", "793, 767, 797, 797"),
        # an axis the move leaves where it is is not modified: nothing added
        ("AA;WT1000;ML0,5000;", "793, 793, 797, 797"),
    ],
)
def test_pcix_linear_moves_charge_the_rows_of_the_axes_other_than_the_master(
    commands: str, free: str
) -> None:
    """ML: "All axes are scaled to the axis with the longest move time (the master axis)"; its
    table "ML#,#,##; AA-AM 4*" and "If this is not the master axis, then the acceleration and
    velocity values will be modified, and the following queue requirements will be added: ...
    Linear ( PF , LA ) 6 ... All other Parabolic forms ( PN , PR ) 20"; MT's the same with
    "All other Parabolic forms 26". The WT holds the queues (3 slots) so RQ sees the entries.
    Before, every axis of the move showed 793."""
    h = Harness("PCIX-004")
    assert h.send(commands + "RQ;") == f"{free}\n\r".encode()
    assert h.errors() == []
