"""Numbers the board reports where floating point, a ramp mode or an encoder ratio used to make
them wrong (found by a review of replies against the manuals, 2026-11-27).

* RV at the programmed speed is VL: "The RV command will return the current velocity at which
  the axis is moving. This may differ from the programmed velocity if the axis is ramping up to
  speed or stopping" (VS4 RV, PC48 §6.13). A parabolic or linear ramp's last velocity is a hair
  below VL in floating point (999.9999999999999 for VL1000), and the integer part RV reports
  was 999; the cruise is now at VL itself.
* RC at the programmed speed is "the acceleration at the end of the ramp" (PC48 §6.13), whole
  (1,000,000 at the end of a PN5 ramp at AC2000000, not 999,999), and for a jog, whose ramp is
  linear in every ramp mode, AC.
* An encoder ratio with user units (``ER1000,2000 UU0.5``, the EPICS encoder set-up): "The
  correct number of motor counts are generated" (PC48 §6.15 ER), the ratio "handled internally
  in floating point format" (§5.3); positions were truncated to whole encoder counts before
  the ratio, and every odd step was out of reach.
* RU "returns the current position in user units" (PC48 §6.14), which with ER are encoder
  counts.
* On the raw link a PCIx sends nothing for a command error (it sets CMD_S, PCIx §3.9): a ``#``
  stuck to the front of the next reply (``#0,0,0,0``), which a MAX-family client reads as
  ``text<LF><CR>`` with nothing before it.
"""

from __future__ import annotations

import itertools

import pytest

from omsd.board import Board
from omsd.board.harness import Harness
from omsd.dialects.shared.reports import whole
from omsd.link import make_link
from omsd.models import get_model


def value(reply: bytes) -> str:
    """The text of one PC48-family value reply (``<LF><CR>text<LF><CR>``)."""
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    return reply[2:-2].decode()


RAMPS = ["", "PN", "PN3", "PN5", "PN7", "PN10", "CN"]
SPEEDS = [1000, 2000, 3000, 7000, 259_850]
ACCELERATIONS = [None, 5_000_000, 6_393_415, 123_457]


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040"])
def test_rv_at_the_programmed_speed_is_vl(model: str) -> None:
    for ramp, vl, ac in itertools.product(RAMPS, SPEEDS, ACCELERATIONS):
        h = Harness(model)
        h.send(f"{ramp} AX VL{vl} " + (f"AC{ac} " if ac else "") + "MR30000000 GO ")
        h.until(5.0)  # (the longest ramp here, VL259850 at AC123457 on CN, takes 3.3 s)
        assert value(h.send("RV")) == str(vl), (ramp, vl, ac)


def test_rv_at_the_programmed_speed_in_a_list_and_on_the_pcix() -> None:
    h = Harness("VS4-040")
    h.send("AA PN; VL1000,2000; MR100000,100000; GO ")
    h.until(1.0)
    assert value(h.send("RV")) == "1000,2000,0,0"
    p = Harness("PCIX-400")
    p.send("AX;VL1000;MR100000;GO;")
    p.until(1.0)
    assert p.send("RV;") == b"1000\n\r"


def test_rv_still_reports_the_integer_part_of_a_fractional_jog() -> None:
    h = Harness("PC48-4E")
    h.send("AX JF100.7 ")
    h.until(1.0)
    assert value(h.send("RV")) == "100"


def test_rc_at_the_end_of_a_parabolic_ramp_is_whole() -> None:
    h = Harness("VS4-040")
    h.send("PN5 AX VL5000 MR400000 GO ")
    h.until(1.0)
    assert value(h.send("RC")) == "1000000"  # 50 % of AC2000000 at the peak (PN5)


@pytest.mark.parametrize("mode", ["PN5", "CN", "PF"])
def test_rc_of_a_jog_at_speed_is_its_linear_ramps_in_every_ramp_mode(mode: str) -> None:
    h = Harness("VS4-040")
    h.send(f"{mode} AX JG100000 ")
    h.until(0.02)
    assert value(h.send("RC")) == "2000000"  # ramping, linearly, at AC
    h.until(1.0)
    assert value(h.send("RC")) == "2000000"  # at speed: "the acceleration at the end of the ramp"


def test_whole_is_the_integer_part_of_the_value_meant() -> None:
    assert whole(999_999.9999999999) == 1_000_000
    assert whole(-999.9999999999999) == -1000
    assert whole(100.7) == 100 and whole(-100.7) == -100
    assert whole(0.9999) == 0 and whole(0.0) == 0
    assert whole(100.999999) == 100 and whole(100.9999995) == 100  # a fraction meant
    h = Harness("PC48-4E")
    h.send("AX JF100.999999 ")
    h.until(3.0)
    assert value(h.send("RV")) == "100"  # "only reports the integer part"


def test_an_encoder_ratio_with_user_units_reaches_every_motor_step() -> None:
    h = Harness("PC48-4E")
    h.send("AX ER1000,2000 UU0.5 ")  # EPICS' set-up of an encoder axis: positions in steps
    h.send("LP601 ")
    assert value(h.send("RP")) == "601"
    h.send("MA603 GD ID ")
    h.until(1.0)
    assert value(h.send("RP")) == "603"
    h.send("LP0 MR101.9 GD ID ")
    h.until(2.0)
    assert value(h.send("RP")) == "101"  # 50.95 encoder counts: 101.9 steps, truncated
    h.send("LP0 MR1.9 GD ID ")
    h.until(3.0)
    assert value(h.send("RP")) == "1"  # a one-step correction moves


def test_without_user_units_an_encoder_ratio_takes_whole_encoder_counts() -> None:
    h = Harness("PC48-4E")
    h.send("AX ER3,2 LP30000 ")  # the manual's example: 20,000 in the position counter
    assert value(h.send("RP")) == "20000"
    assert value(h.send("RE")) == "30000"
    h.send("LP7 ")  # 4.67 motor steps: a whole number in the counter
    assert value(h.send("RP")) == "4"
    h.send("LP0 MR100.9 GD ID ")  # 100 encoder counts (MR100.9 moves 100), 66.7 steps
    h.until(1.0)
    assert value(h.send("RP")) == "66"


@pytest.mark.parametrize(
    ("command", "rp"),
    [
        ("UU0.5 LP67108863", "33554431"),
        ("UU0.5 LP67108862.9", "33554431"),
        ("UU0.5 LP67108864", "0"),
    ],
)
def test_the_range_is_checked_on_whole_counts_with_user_units(command: str, rp: str) -> None:
    """LP's range, ±33,554,431, holds the whole number of counts (33,554,431.5 loads
    33,554,431, as it did before the fraction was kept for the encoder ratio); beyond it, a
    command error and nothing loaded."""
    h = Harness("PC48-4E")
    h.send(f"AX {command} ")
    assert value(h.send("RP")) == rp
    assert [e.kind.name for e in h.errors()] == ([] if rp != "0" else ["OUT_OF_RANGE"])


def test_user_units_without_a_ratio_still_truncate_to_whole_steps() -> None:
    h = Harness("PC48-4E")
    h.send("AX UU0.5 LP3 ")  # 1.5 steps
    assert value(h.send("RP")) == "1"
    h.send("MR7 GO ")  # 3.5 steps
    h.until(1.0)
    assert value(h.send("RP")) == "4"


def test_ru_is_the_position_in_the_user_units_of_the_encoder_ratio() -> None:
    h = Harness("PC48-4E")
    h.send("AX ER2,1 UU10 LP5 ")  # 50 encoder counts, 25 motor steps
    assert [value(h.send(c)) for c in ("RU", "RP", "RE")] == ["5.00000", "25", "50"]
    h.send("MA7 GO ")
    h.until(1.0)
    assert value(h.send("RU")) == "7.00000"
    h = Harness("PC48-4E")
    h.send("AX UU10 LP3.5 ")  # without a ratio: 35 steps, RU 3.50000
    assert value(h.send("RU")) == "3.50000"


@pytest.mark.parametrize(
    ("model", "error"), [("PCIX-400", b""), ("PCIX-004", b""), ("PC48-4E", b"#"), ("VS4-040", b"#")]
)
def test_a_command_error_in_the_raw_stream_is_the_dialects(model: str, error: bytes) -> None:
    link = make_link("raw", Board(get_model(model), now=0.0))
    pcix = get_model(model).dialect == "pcix"
    link.from_host(b"AM;KP5;RI;\n" if pcix else b"AA ZZ RP ", 0.0, 1)
    out = link.to_host(0.0)
    axes = len(get_model(model).axes)
    if pcix:  # KP is not valid in AM; the status list follows with nothing before it
        assert out.data == error + b",".join([b"PNNN"] * axes) + b"\n\r"
    else:
        assert out.data == error + b"\n\r" + b",".join([b"0"] * axes) + b"\n\r"
    assert len(out.events) == 1  # the error is in the traffic log either way
