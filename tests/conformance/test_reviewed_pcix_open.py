"""PCIx behaviour an earlier review of its manual (002_5f0bea9264c6d239.txt) left open, where a
second reading found omsd wrong.

* IP on an axis without an encoder behaves like ID: "If the position hold (HN) is not enabled for
  an axis, the command will behave like an ID command for that axis"; it was a command error.
* A bare flag command in AA/AM (``AA;LN;``) affects no axis, as ``AA;AF;`` already did: §5.1 "If
  a parameter exists for an axis, then the command affects that axis and if the parameter does
  not exist for that axis, then the command has no effect on that axis"; it acted on every axis.
* LF leaves the software travel limits (TL) on: LF "disables the limit switches"; TL's page
  "Software overtravel limits and physical limit switch inputs can be enabled at the same time"
  and "TL0,0; Turns software limits off"; LF switched them off too.
"""

from __future__ import annotations

import pytest

from omsd.board.events import LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from .pcix import reply
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


@pytest.mark.parametrize("command", ["LN", "LF", "SL", "SF", "HH", "HL", "UF", "HN", "CA"])
def test_a_bare_flag_command_in_aa_mode_affects_no_axis(command: str) -> None:
    """§5.1: "These commands require numeric parameters in multi-axis modes, and the parameters
    indicate whether or not to take action for each axis. If a parameter exists for an axis, then
    the command affects that axis and if the parameter does not exist for that axis, then the
    command has no effect on that axis" (its example is LN); AF's page in AA: "AF1,,1; ... The Y
    axis is unchanged". The first command's opposite is set on each axis, then the bare command
    is typed in AA: each axis keeps what it had."""
    h = Harness("PCIX-040")  # steppers with encoders: UU and ER apply
    opposite = {
        "LN": ("LF", "?LM", "lf"),
        "LF": ("LN", "?LM", "ln"),
        "SL": ("SF", "?SL", "sf"),
        "SF": ("SL", "?SL", "sl"),
        "HH": ("HL", "?HS", "hl"),
        "HL": ("HH", "?HS", "hh"),
        "UF": ("UU2", "?UU", "uu2.000000"),
        "HN": ("HF", "?PM", "hf"),
    }
    if command == "CA":
        h.send("AA;MR10,10,10,10;GO;ID;")
        h.advance(0.1)
        h.send("CA;")
        assert h.board.registers.done == 0b1111  # (it was 0: every flag cleared)
    else:
        setting, query, answer = opposite[command]
        for letter in "XYZT":
            h.send(f"A{letter};{setting};")
        h.send(f"AA;{command};")
        for letter in "XYZT":
            assert h.send(f"A{letter};{query};") == reply(answer)
    assert h.errors() == []


def test_aa_hf_bare_still_opens_every_loop() -> None:
    """HF's own page says otherwise: "If the current mode is multi-axis, all axes will go into
    open-loop mode" ("HF; AA-AM 2")."""
    h = Harness("PCIX-400")
    h.send("AA;HN1,1,1,1;HF;")
    for letter in "XYZT":
        assert h.send(f"A{letter};?PM;") == reply("hf")
    assert h.errors() == []


def test_aa_af_bare_still_affects_no_axis() -> None:
    """The rule AF already followed ("AF1,,1; ... The Y axis is unchanged")."""
    h = Harness("PCIX-040")
    h.send("AA;AF;AX;")
    assert h.send("?AB;") == reply("an")
    assert h.errors() == []


def limit_events(h: Harness) -> list[LimitEvent]:
    return [e for e in h.events() if isinstance(e, LimitEvent)]


@pytest.mark.parametrize("mode", ["LN;", "LF;"])
def test_lf_leaves_the_software_travel_limits_on(mode: str) -> None:
    """LF "disables the limit switches for the addressed axis or axes"; TL: "If the axis reaches
    either of these logical limits, the PCIX will flag a limit condition", "Software overtravel
    limits and physical limit switch inputs can be enabled at the same time", "TL0,0; Turns
    software limits off". Each has its own switch: with the switches off (LF) a move past the
    travel limit is still stopped there and reported, as with LN (at VL10000 the first sample
    beyond 1000 is at 1005)."""
    h = Harness("PCIX-004")
    h.send("AX;VL10000;TL1000,-1000;" + mode + "MR5000;GO;")
    h.advance(2.0)
    assert h.position("X") == 1005  # (with LF it was 5000: the travel limit ignored)
    assert [e.direction for e in limit_events(h)] == [1]
    assert h.errors() == []


def test_lf_still_ignores_the_switches_with_travel_limits_set() -> None:
    """LF: "the limit switch closure will have no effect on motion". The switch at 3000 lies
    inside the travel limits: with LF the move runs through it to the end."""
    h = Harness("PCIX-004", world={"X": AxisWorld(positive_limit=3000.0)})
    h.send("AX;VL10000;TL100000,-100000;LF;MR5000;GO;")
    h.advance(2.0)
    assert h.position("X") == 5000
    assert limit_events(h) == []
    h.send("LN;MR-1000;GO;MR1000;GO;")  # back inside, then out again through the switch
    h.advance(2.0)
    assert h.position("X") == 4000  # moving away from an active limit is allowed...
    assert [e.direction for e in limit_events(h)] == [1]  # ...toward it is not
