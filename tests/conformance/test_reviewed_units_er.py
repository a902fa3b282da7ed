"""The encoder ratio (ER) and user units (UU), command by command, on the PC48 family (PC48
000_438df88d2a6a1670.txt, VS4 003_c16e31315d499848.txt) and the PCIx (002_5f0bea9264c6d239.txt),
found by the review of units under ER (docs/decisions.md, "What UU scales", "Open: the units of
the queries under UU and ER").

ER: "All distance, velocity and acceleration parameters are input in encoder counts when this
mode is enabled. The correct number of motor counts are generated, while the user need only be
concerned with encoder counts" (PC48 §6.15; the VS4's the same). omsd takes the PCIx's the same
way.

* HM and HR loaded the position counter with their parameter as motor steps under ER: after
  ``ER2,1 VL1000 HM1000`` the counter read 1000 at home, so the page's ``MA1000`` "to the same
  position as specified in the HM command" (1000 counts, 500 steps) stopped 500 steps short of
  home. The counter now gets the parameter over the ratio, as LP's (and the PCIx's encoder the
  parameter, as LP's: "the parameter will be loaded into the encoder position register and the
  parameter times the encoder ratio will be loaded into the position counter").
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

from .pcix import reply
from .support import frame, number

# -- HM, HR --------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PC46-4E"])
def test_hm_then_ma_to_the_same_position_returns_home_under_a_ratio(model: str) -> None:
    """HM: "The position counter will be initialized to the position supplied as a parameter
    ... The axis may be commanded to go home by following this command with a move absolute to
    the same position as specified in the HM command" (example ``AX VL1000 HM1000 MA1000 GO``),
    and ER: "All distance ... parameters are input in encoder counts". Under ``ER2,1`` (two
    counts a step) home at step 1000 is 1000 counts' worth of steps, 500, in the counter; MA1000
    goes back to it (the carriage was left at step 500: the counter read 1000 at home). The
    PC48's HM loads the counter alone, and the encoder went on counting: 2000 at home."""
    h = Harness(model)  # home switch from step 1000 to 1100
    h.send("AX ER2,1 VL1000 HM1000 MA1000 GO ")
    h.run()
    assert round(h.axis("X").phys(h.t)) == 1000  # (it was 500)
    assert h.send("RP ") == frame("500")  # (500 too, but 500 steps from home)
    assert number(h.send("RE ")) in (2000, 2001)  # the carriage at home (it was 1000)
    assert h.errors() == []


def test_pcix_home_loads_the_counter_over_the_ratio_and_the_encoder_with_the_parameter() -> None:
    """The PCIx's HM "The position counters will be initialized to the positions supplied as
    parameters"; HR "the position and encoder counters are loaded with the parameter(s)", LP's
    words for the same pair of registers: "the parameter will be loaded into the encoder position
    register and the parameter times the encoder ratio will be loaded into the position
    counter". ``ER2,1;VL1000;HM1000;MA1000;GO;`` (the HM page's example under a ratio) ends at
    home, RP 500, RE 1000 (it ended at step 500 with RP 500, RE 0: both registers had been
    loaded with 1000, the counter as steps)."""
    h = Harness("PCIX-040")
    h.send("AX;ER2,1;VL1000;HM1000;MA1000;GO;")
    h.run()
    assert round(h.axis("X").phys(h.t)) == 1000  # (it was 500)
    assert h.send("RP;RE;") == reply("500") + reply("1000")  # (it was 500, 0)
    assert h.errors() == []


@pytest.mark.parametrize("model", ["PC48-4E", "PCIX-040"])
def test_hr_loads_the_counter_over_the_ratio(model: str) -> None:
    """HR "behaves exactly like the HM command, except it travels in the reverse direction"
    (PCIx; PC48 "find home in reverse direction and initialize position counter"): from step
    2000 under ``ER1,2`` (a count every two steps) home (entered from above at the switch's top,
    step 1099) loads -1000 counts, -2000 steps, and ``MA-1000`` returns there (the counter read
    -1000 at home, and MA-1000, -2000 steps, went on down 1000 steps, to step 99)."""
    h = Harness(model, world={"X": AxisWorld(start_position=2000.0)})
    sep = ";" if model.startswith("PCIX") else " "
    h.send(sep.join(["AX", "ER1,2", "VL1000", "HR-1000", "MA-1000", "GO", ""]))
    h.run()
    assert round(h.axis("X").phys(h.t)) == 1099  # (it was 99)
    assert h.position("X") == -2000
    assert h.errors() == []


# -- readings the manuals leave open, pinned (docs/decisions.md) ---------------------------------


def test_parameter_queries_answer_in_motor_steps_under_uu_and_er() -> None:
    """docs/decisions.md, "Open: the units of the queries under UU and ER": ?VL "as set by the
    VL command", ?TL "the software travel limits for the current axis assigned via the TL
    command" and the others answer the board's registers, in motor steps, RE in encoder counts,
    RU in user units. The bytes the entry quotes."""
    h = Harness("PCIX-040")
    steps = "AX;UU2000;VL5;?VL;AC10;?AC;VB1;?VB;HV5;?HV;TL10,-10;?TL;LP2000;RP;RU;RE;"
    assert h.send(steps) == b"".join(
        reply(r)
        for r in (
            *("vl10000", "ac20000", "vb2000", "hv10000", "tl20000,-20000"),
            *("4000000", "uu2000.00000", "4000000"),
        )
    )
    h = Harness("PCIX-040")
    assert h.send("AX;ER2,1;" + steps[3:]) == b"".join(
        reply(r)
        for r in (
            *("vl5000", "ac10000", "vb1000", "hv5000", "tl10000,-10000"),
            *("2000000", "uu2000.00000", "4000000"),
        )
    )
    assert h.errors() == []


@pytest.mark.parametrize(
    ("ratio", "vl", "refused"),
    [("ER1,2;", "1044000", False), ("ER1,2;", "1044001", True), ("ER2,1;", "1044001", True)],
)
def test_velocity_edges_hold_the_operand_before_the_ratio(
    ratio: str, vl: str, refused: bool
) -> None:
    """ "RANGE: 1 ≤ VL ≤ 1044000" (PCIx; the PC48's "less than or equal to 1,044,000 steps per
    second") is checked on the operand in the units it is typed in, encoder counts under ER,
    when the command is typed: ER reaches the axis through its queue ("ER#,#; AX - AT 1"), so
    the ratio the value will meet is not yet in force (docs/decisions.md, "Edges in steps").
    ``ER1,2;VL1044000;`` is taken (2,088,000 steps/s), ``ER2,1;VL1044001;`` refused."""
    h = Harness("PCIX-040")
    h.send("AX;" + ratio + "VL" + vl + ";")
    assert [e.command for e in h.errors()] == (["VL" + vl] if refused else [])


def test_lo_sets_the_motor_position_scaled_by_user_units_not_by_the_ratio() -> None:
    """LO "sets the motor position independently of the encoder position" (its example
    ``LP100000; LO50000;``, "Set the motor position to 50,000"): under ``ER2,1;UU10;`` LO10 is
    100 in the motor counter, the encoder left (docs/decisions.md, "What UU scales")."""
    h = Harness("PCIX-040")
    assert h.send("AX;ER2,1;UU10;LP0;LO10;RP;RE;") == reply("100") + reply("0")
    assert h.errors() == []


def test_a_contour_runs_in_motor_steps_under_a_ratio() -> None:
    """Contour positions (CD, MT in a contour, CR) are not divided by the ratio: the path is the
    one typed, in the counters' steps, at CV "counts per second" (docs/decisions.md,
    "Contouring"). Under ``ER2,1`` on X and Y, ``MT1000,0`` in a contour ends at step 1000."""
    h = Harness("PC48-4E")
    h.send("AX ER2,1 AY ER2,1 AA VL1000,1000 CV1000 CD0,0; MT1000,0; CE CX ")
    h.run()
    assert h.position("X") == 1000
    assert h.errors() == []


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PCIX-040"])
@pytest.mark.parametrize(("search", "start"), [("HM", 0.0), ("HR", 2000.0)])
def test_home_under_user_units_and_a_ratio_loads_the_steps_lp_loads(
    model: str, search: str, start: float
) -> None:
    """HM: "The position counter will be initialized to the position supplied as a parameter
    ... The axis may be commanded to go home by following this command with a move absolute to
    the same position as specified in the HM command" (PC48 §6.11; HR "behaves exactly like the
    HM command"), and ER: "This mode can be combined with user units ... All parameters are then
    input in the user units which have been defined. The correct number of motor counts are
    generated" (§6.15), the ratio "handled internally in floating point format" (§5.3). Under
    ``ER1000,2000 UU0.5`` the parameter 601 is 300.5 counts, 601 steps, as LP601 and MA601 take
    it: the search loads 601 where it is home, and ``MA601`` returns there. HM and HR truncated
    to whole counts first: 300, 600 steps, and MA601 stopped a step past home."""
    sep = ";" if model.startswith("PCIX") else " "

    def home(position: int) -> tuple[float, int]:
        h = Harness(model, world={"X": AxisWorld(start_position=start)})
        h.send(sep.join(["AX", "ER1000,2000", "UU0.5", "VL500", f"{search}{position}", ""]))
        h.run()
        counted = int(h.send("RP" + sep).strip())
        h.send(sep.join([f"MA{position}", "GO", ""]))
        h.run()
        assert h.errors() == []
        return h.axis("X").phys(h.t), counted

    at_600, counted_600 = home(600)
    at_601, counted_601 = home(601)
    assert counted_601 - counted_600 == 1  # (it was 0: both loaded 600)
    assert at_601 == at_600  # home, both (601's was a step past it)
