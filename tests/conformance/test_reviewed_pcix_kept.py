"""PCIx behaviour an earlier review left alone, read again against its manual
(002_5f0bea9264c6d239.txt) and the omsMAXnet client, and kept: the manual does not decide
otherwise (docs/decisions.md, "The PCIx", "Read a third time and kept"). These tests pin what
omsd does, so that a change to any of them is a decision, not an accident.

* A home search begun on the home switch (parked there by the MA after a home) takes no home
  until the line goes true again: HM/KM run on to the positive limit, HR/KR to the negative.
* EA resets the one slip flag that RL also reports ("reset by execution of EA command").
* ``AM;EA;`` answers a field for every axis, an open-loop stepper's too; ``AX;EA;`` on an
  open-loop stepper is a command error.
* A limit flushes the ID behind the move (§5.5.4), so RI shows no D for it; omsMAXnet ends the
  move from the L and a zero RV. Under SL the ID stays ("The output queue is not flushed except
  for the current move").
"""

from __future__ import annotations

import pytest

from omsd.board.events import CommandErrorEvent, ErrorKind, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from .pcix import reply

STAGE = AxisWorld(negative_limit=-20_000.0, positive_limit=20_000.0)  # home switch 1000..1100


def parked_at_home(model: str = "PCIX-004") -> Harness:
    """The HM page's example: ``AX; VL1000; HM1000; MA1000; GO;`` leaves the axis at rest on the
    home switch ("The axis can be easily returned to the precise home position by using an MA
    command after the HM command")."""
    h = Harness(model, world={"X": STAGE})
    h.send("AX;VL1000;AC100000;HM1000;MA1000;GO;")
    h.run(limit=60.0)
    assert h.send("AX;RP;") == reply("1000")
    assert h.send("AX;QA;") == reply("MNNH")  # on the switch
    h.events()
    return h


@pytest.mark.parametrize(
    ("search", "direction", "rp"),
    [
        ("HM1000;", 1, "20000"),
        ("KM;", 1, "20000"),
        ("HR1000;", -1, "-20001"),
        ("KR;", -1, "-20001"),
    ],
)
def test_a_home_search_begun_on_the_switch_runs_to_the_limit(
    search: str, direction: int, rp: str
) -> None:
    """HM "move in the positive direction ... until the home is detected"; §4.6 the counter "will
    be reset to a select value when the switch is activated"; §4.2 HM/HR cause "the motor to
    decelerate to a stop when the switch closes"; the PC48's HM "until the home input line goes
    true". Begun with the line already true, the search meets only the switch's far edge (the
    line going false) and then no closing: it runs on to the limit, the counter not reloaded."""
    h = parked_at_home()
    h.send("AX;" + search + "ID;")
    h.run(limit=120.0)
    assert h.send("AX;RP;") == reply(rp)
    assert [e.direction for e in h.events() if isinstance(e, LimitEvent)] == [direction]


def test_omsmaxnet_home_repeated_from_home_ends_at_the_limit() -> None:
    """omsMAXnet's home (``A%c AC%d; VL%d; HM; MA0 GO ID``) sent twice: the first parks the axis
    on the switch at 0, the second runs to the positive limit, which flushes ``MA0 GO ID``. The
    client ends the motion from RI's L with RV 0 (``omsBaseController::omsPoller``) and sets the
    high limit; no done flag comes."""
    h = Harness("PCIX-004", world={"X": STAGE})
    h.send("AX AC100000; VL1000; HM; MA0 GO ID\n")
    h.run(limit=60.0)
    assert h.send("AM;RI;\n") == reply("MDNH,PNNN,PNNN,PNNN")
    h.send("AX AC100000; VL1000; HM; MA0 GO ID\n")
    h.run(limit=60.0)
    assert h.send("AM;RI;\n") == reply("PNLN,PNNN,PNNN,PNNN")
    assert h.send("AM;RV;\n") == reply("0,0,0,0")
    assert h.send("AA RP;\n") == reply("19000,0,0,0")


def test_ea_resets_the_slip_flag_rl_reports() -> None:
    """EA's third character: "Slip or stall detected (reset by execution of EA command)"; ES: the
    tolerance "before slip or stall is flagged in the status register and in the RL command
    response"; RL: "S is returned if a slip condition has occurred for that axis". One flag:
    RL reads it without resetting it, EA resets it (nothing else in the manual does)."""
    h = Harness("PCIX-040")
    h.send("AX;ES5;IS;VL1000;MR2000;GO;")
    h.advance(0.5)
    h.board.inject_slip("X", 50, h.t)
    h.advance(0.01)
    assert h.send("RL;") == reply("SNNN")
    assert h.send("RL;") == reply("SNNN")  # RL does not reset it
    assert h.send("AX;EA;") == reply("DDSNN")  # (detection switched itself off)
    assert h.send("RL;") == reply("NNNN")
    assert h.send("AX;EA;") == reply("DDNNN")


def test_am_ea_answers_every_axis_ax_ea_only_an_axis_with_an_encoder() -> None:
    """EA "returns encoder status of the currently addressed axis or axes" ("EA AX – AT
    Immediate", "EA AA-AM Immediate"). omsMAXnet polls ``AM;EA;`` on every board, PCIX-004
    included, and takes the axis's field by position (``getSubstring(i, ...)``): the multi-axis
    form answers for every axis. The single-axis form on an open-loop stepper is a command error,
    as the PCIx's other encoder commands are there (RE) and as drvOmsPC68 learns "no encoder"
    from EA's error on the older boards."""
    h = Harness("PCIX-202")  # X, Y servo; Z, T open-loop steppers
    assert h.send("AM;EA;\n") == reply("DDNNN,DDNNN,DDNNN,DDNNN")
    assert h.send("AX;EA;") == reply("DDNNN")
    assert h.errors() == []
    assert h.send("AZ;EA;") == b""
    errors = [e for e in h.events() if isinstance(e, CommandErrorEvent)]
    assert [e.kind for e in errors] == [ErrorKind.WRONG_MOTOR]


@pytest.mark.parametrize(("soft", "ri"), [("", "PNLN"), ("SL; ", "PDLN")], ids=["SF", "SL"])
def test_a_limit_flushes_the_id_unless_soft(soft: str, ri: str) -> None:
    """§5.5.4: "When a limit is encountered, the axis involved will cease motion and flush any
    pending motion commands for that axis"; SL: "The output queue is not flushed except for the
    current move". omsMAXnet's ``MA... GO ID`` into a limit: no D (the ID went with the queue),
    RV 0 and RI's L, from which the client ends the move; under SL the ID is still done."""
    far = AxisWorld(positive_limit=3000.0, home_low=5e6, home_high=5e6 + 100)
    h = Harness("PCIX-004", world={"X": far})
    h.send(f"AX {soft}AC20000; VB0; VL5000; MA10000; GO ID\n")
    h.advance(2.0)
    assert h.send("AM;RI;\n") == reply(ri + ",PNNN,PNNN,PNNN")
    assert h.send("AM;RV;\n") == reply("0,0,0,0")
    assert [e.direction for e in h.events() if isinstance(e, LimitEvent)] == [1]
