"""User units (UU) and the encoder ratio (ER) in the PCIx's position and acceleration commands,
found by a review of user units against the manuals (PCIx 002_5f0bea9264c6d239.txt).

omsd takes the positions, velocities and accelerations of an encoder axis under ER in encoder
counts and makes motor steps of them when the command runs (docs/decisions.md, "With ER set,
distances, velocities and accelerations on an encoder axis are in encoder counts"; PC48 §6.15:
"All distance, velocity and acceleration parameters are input in encoder counts when this mode is
enabled").

* TL's limits are "absolute positions", as MA's targets: under ER they were left as typed, in
  motor steps, so ``ER2,1;TL1000,-1000;MA1500;GO;`` ran to 1500 counts (750 steps) through the
  limit at 1000.
* RU ignored the ratio: ``ER2,1;UU10;LP5;RU;`` answered ``uu2.50000``, the steps over UU, not
  the position LP loaded (the PC48 family's RU reads it back).
* DC made its steps with the ratio of the moment it was typed, not of when its queue reached it
  ("DC; AX - AT 2"), unlike AC: ``ER2,1;AC600;DC600;`` typed behind a move left AC at 300, DC
  at 600.
"""

from __future__ import annotations

import pytest

from omsd.board.events import LimitEvent
from omsd.board.harness import Harness

from .pcix import reply


def test_travel_limits_are_positions_in_the_encoder_ratios_counts() -> None:
    """TL: "one for the upper travel limit and the other for the lower travel limit, both as
    absolute positions"; "If the axis reaches either of these logical limits, the PCIX will flag
    a limit condition". Under ``ER2,1`` (2 encoder counts a step) MA1500 is 1500 counts, 750
    steps, and the limit at 1000 counts is 500 steps: the move stops there (the first sample
    beyond 500 steps at VL10000 counts/s, 5000 steps/s, is 501), flagging the limit."""
    h = Harness("PCIX-040")  # steppers with encoders
    h.send("AX;ER2,1;VL10000;TL1000,-1000;MA1500;GO;")
    h.advance(2.0)
    assert h.position("X") == 501  # (it was 750: the move ran through the limit)
    assert [e.direction for e in h.events() if isinstance(e, LimitEvent)] == [1]
    assert h.errors() == []


def test_travel_limits_under_user_units_and_a_ratio() -> None:
    """The same with user units, as EPICS sets up an encoder axis (``ER<e>,<m> UU<e/m>``):
    ``ER1,2;UU0.5;`` makes the user unit a motor step again, so TL500 is at step 500."""
    h = Harness("PCIX-040")
    h.send("AX;ER1,2;UU0.5;VL5000;TL500,-500;MA750;GO;")
    h.advance(2.0)
    assert h.position("X") == 501
    assert h.errors() == []


def test_dc_takes_the_ratio_in_force_when_its_queue_reaches_it() -> None:
    """DC "1 ≤ DC ≤ 8000000", queued ("DC; AX - AT 2"), as ER is ("ER#,#; AX - AT 1"). Typed
    behind a move, ``ER2,1;AC600;DC600;`` reach the axis after the move, in the order typed
    (AC first: the deceleration "will take on whatever value is entered via the AC command"):
    DC is then 300 steps/s², as AC is (it was 600: the ratio of the moment DC was typed,
    1:1)."""
    h = Harness("PCIX-040")
    h.send("AX;VL1000;MR1000;GO;ER2,1;AC600;DC600;")
    h.advance(3.0)
    assert h.send("?AC;") == reply("ac300")
    assert h.send("?DC;") == reply("dc300")  # (it was dc600)
    assert h.errors() == []


@pytest.mark.parametrize("mode", ["AX;", "AA;"])
def test_ru_reads_back_the_position_typed_under_an_encoder_ratio(mode: str) -> None:
    """RU "returns the current position in user units"; its example: ``UU2000; LP0; MR3.5; GO;``
    then RU, "uu3.50000". Under ``ER2,1`` LP and MR take encoder counts (as on the PC48 family,
    whose RU already reads them back): ``ER2,1;UU10;LP5;`` loads 50 counts, 25 steps, and RU
    reads ``uu5.00000`` (it read uu2.50000, the steps over UU). In AA ("RU AA-AM Immediate")
    each axis's value."""
    h = Harness("PCIX-040")
    h.send("AX;ER2,1;UU10;LP5;AY;UU2000;LP0;MR3.5;GO;")
    h.advance(1.0)
    assert h.send("AX;RP;RE;") == reply("25") + reply("50")
    if mode == "AX;":
        assert h.send("AX;RU;") == reply("uu5.00000")
        assert h.send("AY;RU;") == reply("uu3.50000")
    else:
        assert h.send("AA;RU;") == reply("uu5.00000,uu3.50000,uu0.00000,uu0.00000")
    assert h.errors() == []


@pytest.mark.parametrize(
    ("uu", "text"),
    [
        ("0.0000025", "uu0.000003"),
        ("0.0000015", "uu0.000002"),
        ("2.1234565", "uu2.123457"),
        ("512", "uu512.000000"),
    ],
)
def test_uu_query_rounds_a_half_up(uu: str, text: str) -> None:
    """?UU: "The command will return the UU value with six digits to the right of the decimal
    point. If the UU value exceeds six digits for the fractional value, the value will be rounded
    off to the sixth decimal place" (example ``uu512.000000``). A half rounds up, as "rounded
    off" reads (``UU0.0000025`` answered ``uu0.000002``: round-half-even)."""
    h = Harness("PCIX-040")
    h.send(f"AX;UU{uu};")
    assert h.send("?UU;") == reply(text)
    assert h.errors() == []


@pytest.mark.parametrize(
    ("model", "framing"), [("PC48-4E", "\n\r{}\n\r"), ("PCIX-040", "uu{}\n\r")]
)
def test_ru_rounds_a_half_up(model: str, framing: str) -> None:
    """RU: "a floating point number with five characters to the right of the decimal point"
    (PC48 §6.13), rounded as ?UU's six ("rounded off"): 1 step under UU200000 is 0.000005 user
    units, ``0.00001`` (it was ``0.00000``: round-half-even), -1 step ``-0.00001``."""
    h = Harness(model)
    sep = ";" if model.startswith("PCIX") else " "
    h.send(sep.join(["AX", "UU200000", "LP0.000005", ""]))
    assert h.send("RU" + sep) == framing.format("0.00001").encode()
    h.send(sep.join(["LP-0.000005", ""]))
    assert h.send("RU" + sep) == framing.format("-0.00001").encode()
    assert h.errors() == []


def test_ru_of_a_tiny_user_unit_is_written_out() -> None:
    """The widest RU: 33,000,000 steps over ``UU0.00000000000000000001`` (24 characters, the
    longest number taken) is 3.3 × 10^27 user units, written out whole with its five decimals
    (rounding it must not run out of decimal precision)."""
    h = Harness("PC48-4E")
    h.send("AX LP33000000 UU0.00000000000000000001 ")
    assert h.send("RU") == b"\n\r3300000000000000000000000000.00000\n\r"
    assert h.errors() == []
