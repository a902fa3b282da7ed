"""Conformance: the PCIx manual's ``Enter:`` examples E1-E72 (§5.12.3-§5.13, BC to HL).

Numbering follows section 5 of ``shared/reference/pcix.md``; every example was checked against
the manual text (``shared/seeds/002_5f0bea9264c6d239.txt``), which wins where the two differ.
Each test types the example's ``Enter:`` lines (annotations such as ``* Store as table #3`` and
the ``(1)``/``(2)``/``Or`` labels are not typed; each line is ended by CR), lets the manual clock
run where motion must happen and asserts the reply byte for byte where the manual prints one,
otherwise the state the example's stated purpose implies.

Conventions
-----------
* Replies: the manual prints ``text<LF>``; omsd frames every PCIx reply ``text<LF><CR>``
  (``omsd/models/pcix.py``, ``framing="trailing"``), so ``ac200000<LF>`` is
  ``b"ac200000\\n\\r"``. Typographic spaces in the printed replies (``dc20000<LF >``,
  ``hg100<LF >``) are not part of the reply.
* Timing: "The highest priority process calculates the desired velocity 2048 times each second"
  (§7.2). A move starts on the first sample tick at or after its GO is executed and is over at
  the first tick at or after the analytic end of its linear (trapezoid/triangle) profile.
  Power-up VL 200,000 ("The factory default is 200,000") and AC 2,000,000 ("The default value is
  2,000,000"), so a ramp to full speed takes 0.1 s and 10,000 steps. Expected times are worked
  out from those formulas here, not read back from the engine.
* Boards: a stepper axis is a PCIX-004 (open loop) unless the example needs an encoder
  (PCIX-040); a servo axis is a PCIX-400. Home switches are moved out of the way
  (``support.NO_HOME``) unless the example homes.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from omsd.board.board import Board
from omsd.board.events import ErrorKind, SlipEvent
from omsd.board.harness import Harness
from omsd.engine.registers import ENC_S
from omsd.models import get_model

from . import support
from .pcix import AC0, QUEUE, RATE, VL0, end_tick, linear_move_time, quiet, reply, tick
from .support import done_events, errors

INIT = 0.2  # longer than the INIT time after a power cycle (omsd: 0.1 s)


# -- helpers --------------------------------------------------------------------------------------


def enter(h: Harness, *lines: str) -> bytes:
    """Type ``Enter:`` lines, each ended by the Enter key (CR); the replies produced at once."""
    return b"".join(h.send(line + "\r") for line in lines)


def power_cycle(h: Harness) -> None:
    """Switch the board off and on and wait until it has initialised."""
    h.board.power_cycle(h.t)
    h.advance(INIT)


def all_outputs(model: str) -> Harness:
    """A board whose S3 switches make all eight general-purpose bits outputs ("A switch in the
    ON position sets the associated I/O bit as an output", §2.2); the factory setting is "I/O
    bits 0-3 as inputs and bits 4-7 as outputs"."""
    h = quiet(model)
    h.board = Board(replace(get_model(model), factory_outputs=0xFF, io_inputs=0x00), now=0.0)
    return h


def qa(h: Harness, letter: str) -> bytes:
    """QA of one axis (status without clearing anything)."""
    return enter(h, f"A{letter};", "QA")


def qi_fields(h: Harness) -> list[str]:
    """QI in AA mode, split into its per-axis four-character fields."""
    raw = enter(h, "AA;", "QI")
    assert raw.endswith(b"\n\r"), raw
    return raw[:-2].decode("ascii").split(",")


def done_ticks(h: Harness) -> list[float]:
    """Sample ticks of the done interrupts seen so far (the harness forgets them)."""
    return [round(e.time * RATE, 6) for e in done_events(h)]


def enc_s(h: Harness) -> bool:
    """The status register's ENC_S bit, read without clearing it."""
    return bool(h.board.status_register(h.t) & ENC_S)


# -- 5.12.3 / 5.12.4 backlash ---------------------------------------------------------------------


def test_e01_bc_stepper_outputs_ten_extra_steps_on_reversal() -> None:
    """E1 ``AX; BC10;`` (§5.12.3): "cause the controller to output an additional 10 motor steps
    whenever a move causes the motor direction to be reversed"; "The backlash compensation count
    is output to the motor during the first motor update cycle following a direction change."

    The position counter counts the commanded move only (RP is the commanded position, E2); the
    motor itself (the carriage, ``Axis.phys``) gets the 10 extra steps in the first update after
    the reversal: after MR1000 then MR-1000 the counter is back at 0 and the motor at -10. The
    first move is positive, the power-up direction, so it is no reversal.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "BC10;") == b""
    assert enter(h, "?BC") == reply("bc10")
    x = h.axis("X")
    enter(h, "MR1000;", "GO;")
    h.run()
    assert h.position("X") == 1000
    assert x.phys(h.t) == pytest.approx(1000.0)
    h.until(tick(end_tick(0, linear_move_time(1000)) + 10))
    k0 = round(h.t * RATE)
    enter(h, "MR-1000;", "GO;")
    h.until(tick(k0 + 1))  # the first update of the reversed move
    assert h.position("X") == 1000  # 0.24 step of commanded travel: no whole step yet
    assert x.phys(h.t) - x.position(h.t) == pytest.approx(-10.0)
    h.run()
    assert h.position("X") == 0
    assert x.phys(h.t) == pytest.approx(-10.0)
    assert h.errors() == []


def test_e02_bc_servo_offsets_set_point_after_reversal() -> None:
    """E2 (§5.12.4) ``(1) AX; BC-10; MA1000; GO; (2) AX; MA-1000; GO;`` on a servo X axis "that
    has been homed in the positive direction": "go to a position set point of 1000. ... the RP
    command would report the motor's commanded position of 1000. The RE command would report the
    motor's actual position of 1000. However, in the second command you would be changing
    directions so that the motor will go 2010 steps, ending at -1000, and the encoder will read
    -1010."

    Reading: "ending at -1000" is the commanded position (RP), the encoder (RE) reads -1010.
    The homing direction only explains why the sign is negative; the board is not homed here.
    The servo loop is closed first (HN; the loop is open at power-up) so that the motor follows
    its set point; the test waits until the loop has settled.
    """
    h = quiet("PCIX-400")
    enter(h, "AX;", "HN;")
    assert enter(h, "AX;", "BC-10;", "MA1000;", "GO;") == b""
    h.run()
    assert enter(h, "RP") == reply("1000")
    assert enter(h, "RE") == reply("1000")
    assert enter(h, "AX;", "MA-1000;", "GO;") == b""
    h.run()
    assert enter(h, "RP") == reply("-1000")
    assert enter(h, "RE") == reply("-1010")
    assert h.errors() == []


# -- 5.13 command descriptions: AA ... AZ ---------------------------------------------------------


def test_e03_aa_y_z_t_move_waits_for_x_y_move() -> None:
    """E3 ``AA MA12000,14000; GO; MR,5000,1500,100000; GO;``: "Perform an absolute move using
    the X and Y axes. When this move is complete, perform a relative move using the Y, Z, and T
    axes." ("the Y axis move will not begin until the X axis move has completed").

    X (12000) and Y (14000) are triangles (VL^2/AC = 20000): 0.1549 s and 0.1673 s, ticks 318
    and 343. The second move starts on tick 343, when the first is complete (not when X is):
    Y 5000 (0.1 s, 205 ticks), Z 1500 (0.0548 s, 113 ticks), T 100000 (0.6 s, 1229 ticks).
    """
    h = quiet("PCIX-004")
    assert enter(h, "AA", "MA12000,14000;", "GO;", "MR,5000,1500,100000;", "GO;") == b""
    x_end, y_end = end_tick(0, linear_move_time(12000)), end_tick(0, linear_move_time(14000))
    assert (x_end, y_end) == (318, 343)
    h.until(tick(x_end - 1))
    assert h.position("X") == 11999
    h.until(tick(x_end))
    assert h.position("X") == 12000
    h.until(tick(y_end - 1))  # X is done, Y is not: Z and T have not started
    assert [h.position(a) for a in "YZT"] == [13999, 0, 0]
    h.until(tick(y_end))
    assert [h.position(a) for a in "XYZT"] == [12000, 14000, 0, 0]
    h.until(tick(y_end + 2))
    assert all(h.axis(a).velocity(h.t) > 0 for a in "YZT")
    # (axis, distance, target, end tick): Z first, then Y, then T
    second = [("Z", 1500, 1500, 456), ("Y", 5000, 19000, 548), ("T", 100000, 100000, 1572)]
    for letter, distance, target, end in second:
        assert y_end + end_tick(0, linear_move_time(distance)) == end
        h.until(tick(end - 1))
        assert h.position(letter) == target - 1
        h.until(tick(end))
        assert h.position(letter) == target
    assert enter(h, "RP") == reply("12000,19000,1500,100000")
    assert h.errors() == []


def test_e04_query_ab_reports_x_aux_on() -> None:
    """E4 ``AX; ?AB`` -> ``an<LF>``: "Determine if the X axis auxiliary bit is set on" (AN "is
    the default mode for the auxiliary line at power up or reset"). After AF the same query
    answers ``af`` (the reply reflects the state)."""
    h = quiet("PCIX-400")
    assert enter(h, "AX;", "?AB") == reply("an")
    enter(h, "AF;")
    assert enter(h, "?AB") == reply("af")
    assert h.errors() == []


def test_e05_ac_single_axis_sets_y_acceleration() -> None:
    """E5 ``AY; AC200000;``: "In the single axis mode, set the Y axis acceleration to 200,000".
    Only Y changes (X keeps 2,000,000), and Y's next move ramps at 200,000: MR1000 is then a
    triangle of 2*sqrt(1000/200000) = 0.1414 s (tick 290) instead of 0.0447 s."""
    h = quiet("PCIX-004")
    assert enter(h, "AY;", "AC200000;") == b""
    assert enter(h, "?AC") == reply("ac200000")
    assert enter(h, "AX;", "?AC") == reply("ac2000000")
    enter(h, "AY;", "MR1000;", "GO;")
    end = end_tick(0, support.linear_move_time(1000, vl=VL0, ac=200_000))
    assert end == 290
    h.until(tick(end - 1))
    assert h.position("Y") == 999
    h.until(tick(end))
    assert h.position("Y") == 1000
    assert h.errors() == []


def test_e06_ac_aa_mode_sets_x_and_z_only() -> None:
    """E6 ``AA ; AC200000,,50000;``: "set the acceleration of the X axis to 200,000 and the Z
    axis to 50,000 and leave the other axes with their previous values" (the space before the
    semicolon is an operand terminator, §5.1)."""
    h = quiet("PCIX-400")
    assert enter(h, "AA ;", "AC200000,,50000;") == b""
    replies = [enter(h, f"A{a};", "?AC") for a in "XYZT"]
    assert replies == [reply("ac200000"), reply("ac2000000"), reply("ac50000"), reply("ac2000000")]
    assert h.errors() == []


def test_e07_query_ac_reports_current_axis_acceleration() -> None:
    """E7 ``?AC`` -> ``ac200000<LF>`` "Report the current AC value for this axis", here after
    E5 set Y to 200,000 (at power-up the same query reads ``ac2000000``)."""
    h = quiet("PCIX-004")
    assert enter(h, "AY;", "?AC") == reply("ac2000000")
    enter(h, "AC200000;")
    assert enter(h, "?AC") == reply("ac200000")
    assert h.errors() == []


def test_e08_query_ad_reports_y_aux_power_up_state() -> None:
    """E8 ``AY; ?AD`` -> ``adh<LF>``: the factory power-up state is high ("Auxiliary output bit
    power up states are high( ADH )", §2.8); after ADL the query reads ``adl``."""
    h = quiet("PCIX-400")
    assert enter(h, "AY;", "?AD") == reply("adh")
    enter(h, "ADL;")
    assert enter(h, "?AD") == reply("adl")
    assert h.errors() == []


def test_e09_adh_stores_z_aux_power_up_high_in_flash() -> None:
    """E9 ``AZ; ADH;``: "sets the default power up or reset state of the auxiliary line for the
    current axis to high. This change is stored as a power up parameter in flash automatically";
    "NOTE: This command will also archive all other parameter values as power up defaults."

    Z is first made to power up low (ADL), then the example restores ADH: after a power cycle Z
    powers up with its aux on and ``?AD`` reads ``adh``; a VL entered before ADH (and never
    saved with AP) is a power-up default too.
    """
    h = quiet("PCIX-400")
    enter(h, "AZ;", "ADL;")
    power_cycle(h)
    assert enter(h, "AZ;", "?AB") == reply("af")
    enter(h, "AZ;", "VL5000;")
    assert enter(h, "AZ;", "ADH;") == b""
    assert enter(h, "?AD") == reply("adh")
    power_cycle(h)
    assert enter(h, "AZ;", "?AD") == reply("adh")
    assert enter(h, "?AB") == reply("an")
    assert enter(h, "?VL") == reply("vl5000")
    assert h.errors() == []


def test_e10_adl_stores_y_aux_power_up_low_in_flash() -> None:
    """E10 ``AY; ADL;``: "sets the default power up or reset state of the auxiliary line for the
    current axis to low. This change is stored in nonvolatile memory automatically". The current
    aux state is not changed; after a power cycle Y's aux is off (low) and the other axes' still
    on."""
    h = quiet("PCIX-400")
    assert enter(h, "AY;", "ADL;") == b""
    assert enter(h, "?AD") == reply("adl")
    assert enter(h, "?AB") == reply("an")
    power_cycle(h)
    assert enter(h, "AY;", "?AD") == reply("adl")
    assert enter(h, "?AB") == reply("af")
    assert enter(h, "AX;", "?AB") == reply("an")
    assert enter(h, "?AD") == reply("adh")
    assert h.errors() == []


def test_e11_af_single_axis_turns_y_aux_off() -> None:
    """E11 ``AY; AF;``: "Turn off the Y axis auxiliary output in the single axis mode" (AF "causes
    the signal to be driven low"); the other axes keep theirs on."""
    h = quiet("PCIX-400")
    assert enter(h, "AY;", "AF;") == b""
    assert [enter(h, f"A{a};", "?AB") for a in "XYZT"] == [
        reply("an"),
        reply("af"),
        reply("an"),
        reply("an"),
    ]
    assert h.errors() == []


def test_e12_af_aa_mode_turns_x_and_z_aux_off() -> None:
    """E12 ``AA; AF1,,1;``: "Turn off the X and Z axes auxiliary outputs ... The Y axis is
    unchanged". Y is turned off beforehand so that "unchanged" is visible; T keeps its power-up
    on."""
    h = quiet("PCIX-400")
    enter(h, "AY;", "AF;")
    assert enter(h, "AA;", "AF1,,1;") == b""
    assert [enter(h, f"A{a};", "?AB") for a in "XYZT"] == [
        reply("af"),
        reply("af"),
        reply("af"),
        reply("an"),
    ]
    assert h.errors() == []


def test_e13_aj_defines_symmetric_and_asymmetric_s_curves() -> None:
    """E13 ``AX; AJ1,0.5,0.5,1.0; AZ; AJ2,0.1,0.1,1.0,0.8,0.8,1.0;`` (the ``*Defines ...`` lines
    are annotations, not typed). Profile 1 gives only ALOWER, APEAK, ARADIUS: "If the parameters
    are not given to define regions 6, 7, 8, and 9, they will be symmetrical with regions 4, 3,
    2, and 1", so DLOWER 0.5, DPEAK 0.5, DRADIUS 1.0. ``?AJ`` reports them in the format of E14;
    SS1 selects the profile (``?RT`` ``ss1``)."""
    h = quiet("PCIX-400")
    assert enter(h, "AX;", "AJ1,0.5,0.5,1.0;", "AZ;", "AJ2,0.1,0.1,1.0,0.8,0.8,1.0;") == b""
    assert enter(h, "AX;", "?AJ1;") == reply(
        "1.0000000,0.50000000,0.50000000,1.00000000,0.50000000,0.50000000,1.00000000"
    )
    assert enter(h, "?AJ2;") == reply(
        "2.0000000,0.10000000,0.10000000,1.00000000,0.80000000,0.80000000,1.00000000"
    )
    enter(h, "SS1;")
    assert enter(h, "?RT") == reply("ss1")
    assert h.errors() == []


def test_e14_query_aj_reports_profile_parameters() -> None:
    """E14 ``AX; ?AJ5;`` -> ``5.0000000,0.50000000,0.50000000,1.00000000,0.10000000,0.10000000,
    1.00000000<LF>`` (printed across two lines: a page wrap, not a line break in the reply).

    Contradiction (digest §8.2 10): ?AJ's "Range: 1 ≤ Profile Number ≤ 4" and AJ's "1 ≤ # ≤
    number of axes on board" make profile 5 impossible. Reading taken: the reply *format* is the
    printed one (profile number with seven decimals, parameters with eight), shown with profile
    1 holding the printed values; ``?AJ5`` is out of range, a command error with no reply.
    """
    h = quiet("PCIX-400")
    enter(h, "AX;", "AJ1,0.5,0.5,1.0,0.1,0.1,1.0;")
    assert enter(h, "AX;", "?AJ1;") == reply(
        "1.0000000,0.50000000,0.50000000,1.00000000,0.10000000,0.10000000,1.00000000"
    )
    assert h.errors() == []
    assert enter(h, "AX;", "?AJ5;") == b""
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.OUT_OF_RANGE, "?AJ5")]


def test_e15_am_runs_xy_linear_task_and_t_task_at_once() -> None:
    """E15 ``AM; ML2000,3000; GO; MA,,,10000; GO;``: "Perform a coordinated relative move on the
    X and Y axes, while moving the T axis as a separate move at the same time."

    ML: "All axes are scaled to the axis with the longest move time (the master axis)": Y (3000,
    0.0775 s) is the master, X is scaled to finish on the same tick, 159. In AM the T move does
    not wait for the X/Y task: all three start on tick 0; T (10000, 0.1414 s) ends on tick 290.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AM;", "ML2000,3000;", "GO;", "MA,,,10000;", "GO;") == b""
    xy_end, t_end = end_tick(0, linear_move_time(3000)), end_tick(0, linear_move_time(10000))
    assert (xy_end, t_end) == (159, 290)
    h.until(tick(1))
    assert all(h.axis(a).velocity(h.t) > 0 for a in "XYT")
    vx, vy = h.axis("X").velocity(h.t), h.axis("Y").velocity(h.t)
    assert vx / vy == pytest.approx(2000 / 3000)
    h.until(tick(xy_end - 1))
    assert [h.position("X"), h.position("Y")] == [1999, 2999]
    h.until(tick(xy_end))
    assert [h.position("X"), h.position("Y")] == [2000, 3000]
    assert h.axis("T").velocity(h.t) > 0
    h.until(tick(t_end - 1))
    assert h.position("T") == 9999
    h.until(tick(t_end))
    assert enter(h, "RP") == reply("2000,3000,0,10000")
    assert h.errors() == []


def test_e16_an_single_axis_turns_y_aux_on() -> None:
    """E16 ``AY; AN;``: "Turn on the Y axis auxiliary output in the single axis mode" (AN "allows
    the signal to be pulled high"). Y is turned off first so that the change is visible."""
    h = quiet("PCIX-400")
    enter(h, "AY;", "AF;")
    assert enter(h, "?AB") == reply("af")
    assert enter(h, "AY;", "AN;") == b""
    assert enter(h, "?AB") == reply("an")
    assert h.errors() == []


def test_e17_an_aa_mode_turns_x_and_z_aux_on() -> None:
    """E17 ``AA; AN1,,1;``: "Turn on the X and Z axes auxiliary outputs ... The Y axis is
    unchanged". All four are turned off first (``AF1,1,1,1``)."""
    h = quiet("PCIX-400")
    enter(h, "AA;", "AF1,1,1,1;")
    assert enter(h, "AA;", "AN1,,1;") == b""
    assert [enter(h, f"A{a};", "?AB") for a in "XYZT"] == [
        reply("an"),
        reply("af"),
        reply("an"),
        reply("af"),
    ]
    assert h.errors() == []


def test_e18_ap_saves_parameters_as_power_up_defaults() -> None:
    """E18 ``AP;``: "stores the current parameter set as the power-up default set of values";
    the list includes AC, VL and LH/LL. Values set before AP come back after a power cycle;
    values changed after AP do not."""
    h = quiet("PCIX-400")
    enter(h, "AX;", "VL50000;", "AC300000;", "AY;", "LH;")
    assert enter(h, "AP;") == b""
    enter(h, "AX;", "VL70000;", "AC400000;", "AY;", "LL;")
    assert enter(h, "AX;", "?VL") == reply("vl70000")
    power_cycle(h)
    assert enter(h, "AX;", "?VL") == reply("vl50000")
    assert enter(h, "?AC") == reply("ac300000")
    assert enter(h, "AY;", "?LS") == reply("lh")
    assert enter(h, "AZ;", "?VL") == reply("vl200000")
    assert h.errors() == []


def test_e19_query_aq_reports_the_mode() -> None:
    """E19 ``AX; ?AQ`` -> ``ax<LF>``: "reports the mode that the current axis is in". The other
    single-axis modes answer their own mnemonic (``az``; not printed, the obvious pair)."""
    h = quiet("PCIX-400")
    assert enter(h, "AX;", "?AQ") == reply("ax")
    assert enter(h, "AZ;", "?AQ") == reply("az")
    assert h.errors() == []


def test_e20_at_ma_moves_t_to_minus_2468() -> None:
    """E20 ``AT; MA-2468; GO;``: "Move the T axis to absolute position -2468." A triangle of
    2*sqrt(2468/2e6) = 0.0703 s, over on tick 144; T last moved negative (QA ``M``)."""
    h = quiet("PCIX-004")
    assert enter(h, "AT;", "MA-2468;", "GO;") == b""
    end = end_tick(0, linear_move_time(2468))
    assert end == 144
    h.until(tick(end - 1))
    assert h.position("T") == -2467
    h.until(tick(end))
    assert h.position("T") == -2468
    assert qa(h, "T") == reply("MNNN")
    assert enter(h, "AA;", "RP") == reply("0,0,0,-2468")
    assert h.errors() == []


def test_e21_ax_jg_steps_x_at_5000() -> None:
    """E21 ``AX; JG5000;``: "Make the X axis step at a rate of 5,000 steps/second", reached at AC
    (2,000,000: 2.5 ms) with no GO. At tick 2 the velocity is 2e6 * 2/2048 = 1953; at 1 s X is
    at 5000 - 5000^2/(2 AC) = 4993.75 (4993 whole steps)."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "JG5000;") == b""
    h.until(tick(2))
    assert enter(h, "RV") == reply("1953")
    h.until(1.0)
    assert enter(h, "RV") == reply("5000")
    assert enter(h, "RP") == reply("4993")
    h.until(10.0)
    assert enter(h, "RP") == reply("49993")
    assert h.errors() == []


def test_e22_ay_ra_reports_y_status() -> None:
    """E22 ``AY; RA`` -> ``PNNN<LF>``: Y last moved positive, no done flag, no limit, home switch
    not active. Y has just made a positive move (MR500) without ID. The reply is Y's own: with
    its home switch active the same RA reads ``PNNH``."""
    h = quiet("PCIX-004")
    enter(h, "AY;", "MR500;", "GO;")
    h.run()
    assert enter(h, "AY;", "RA") == reply("PNNN")
    h.board.set_home("Y", True, h.t)
    assert enter(h, "AY;", "RA") == reply("PNNH")
    assert h.errors() == []


def test_e23_az_vl500_mr2000() -> None:
    """E23 ``AZ; VL500; MR2000; GO;``: "Move the Z axis 2,000 steps at a rate of 500 steps per
    second". 2000/500 + 500/2e6 = 4.00025 s: over on tick 8193."""
    h = quiet("PCIX-004")
    assert enter(h, "AZ;", "VL500;", "MR2000;", "GO;") == b""
    h.until(2.0)
    assert enter(h, "RV") == reply("500")
    assert enter(h, "RP") == reply("999")  # 500 * 2 - 0.0625
    end = end_tick(0, support.linear_move_time(2000, vl=500, ac=AC0))
    assert end == 8193
    h.until(tick(end - 1))
    assert h.position("Z") == 1999
    h.until(tick(end))
    assert enter(h, "AA;", "RP") == reply("0,0,2000,0")
    assert h.errors() == []


# -- BC, ?BC, BH, BI, BL, BS, BX ------------------------------------------------------------------


def test_e24_bc_sets_x_backlash_immediately() -> None:
    """E24 ``AX; BC12;``: "Set backlash compensation factor of axis X to 12 counts".

    Contradiction (digest §8.2 11): the BC page's table says "BC; AX – AT Immediate", §5.12.3's
    "BC#; AX – AT 1". The command's own page is taken: BC sent while a move is running takes
    effect at once (``?BC`` reads it before the move ends) and uses no queue space.
    """
    h = quiet("PCIX-004")
    enter(h, "AX;", "MR100000;", "GO;")
    h.until(0.1)
    free = h.axis("X").queue.free
    assert enter(h, "AX;", "BC12;") == b""
    assert enter(h, "?BC") == reply("bc12")
    assert h.axis("X").queue.free == free
    assert h.axis("X").velocity(h.t) > 0
    assert h.errors() == []


def test_e25_query_bc_reports_x_backlash() -> None:
    """E25 ``AX; ?BC`` -> ``bc23<LF>`` with the X backlash set to 23 (factory 0: ``bc0``)."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "?BC") == reply("bc0")
    enter(h, "BC23;")
    assert enter(h, "AX;", "?BC") == reply("bc23")
    assert h.errors() == []


def test_e26_bh_sets_bits_4_and_5_high() -> None:
    """E26 ``BH4; BH5;``: "Set general purpose bits 4 and 5 to high" (factory: bits 4-7 are the
    outputs). All outputs are driven low first (BS00); afterwards BX reads bits 4 and 5 high,
    6 and 7 still low, inputs 0-3 pulled high: ``3f``."""
    h = quiet("PCIX-004")
    enter(h, "BS00;")
    assert enter(h, "BX") == reply("0f")
    assert enter(h, "BH4;", "BH5;") == b""
    assert enter(h, "BX") == reply("3f")
    assert h.errors() == []


def test_e27_bi_sets_x_servo_output_bipolar() -> None:
    """E27 ``AX; BI;`` on a servo axis: "a zero torque reference will result in a 0VDC output
    (+/- offset voltage). The analog output will range between +10VDC and -10VDC". From UN (zero
    torque at 5 V: "To maintain position the board outputs 5VDC") BI brings the open-loop output
    back to 0 V and ``?SO`` reads ``bi``."""
    h = quiet("PCIX-400")
    servo = h.axis("X").servo
    assert servo is not None
    enter(h, "AX;", "UN;")
    h.advance(0.01)
    assert enter(h, "?SO") == reply("un")
    assert servo.dac_volts == pytest.approx(5.0)
    assert enter(h, "AX;", "BI;") == b""
    h.advance(0.01)
    assert enter(h, "?SO") == reply("bi")
    assert servo.dac_volts == pytest.approx(0.0)
    assert h.errors() == []


def test_e28_bl_after_move_sets_bits_4_and_5_low() -> None:
    """E28 ``AX; MA1000; GO; BL4; BL5;``: "Turn on output bits 4 and 5 after a move" (BL "turns
    the selected general purpose output line on (i.e. logic low)"). BL is queued behind the
    move (2 units): bits 4 and 5 go low on the tick the move ends (tick 92), not before. BX:
    ``ff`` before, ``cf`` after."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "MA1000;", "GO;", "BL4;", "BL5;") == b""
    end = end_tick(0, linear_move_time(1000))
    assert end == 92
    h.until(tick(end - 1))
    assert h.position("X") == 999
    assert enter(h, "BX") == reply("ff")
    h.until(tick(end))
    assert h.position("X") == 1000
    assert enter(h, "BX") == reply("cf")
    assert h.errors() == []


def test_e29_bs_sets_all_outputs_at_once() -> None:
    """E29 ``BS71;``: "Assume I/O bit direction is set all outputs. Set output 0 high, 1-3 low,
    4-6 high and 7 low (71 = (hex) 01110001)". With all eight bits outputs BX reads ``71``.
    With the factory directions (bits 0-3 inputs) the same command leaves the inputs pulled high:
    "Data written to input bits has no effect" (``7f``)."""
    h = all_outputs("PCIX-004")
    assert enter(h, "BX") == reply("ff")
    assert enter(h, "BS71;") == b""
    assert enter(h, "BX") == reply("71")
    factory = quiet("PCIX-004")
    enter(factory, "BS71;")
    assert enter(factory, "BX") == reply("7f")
    assert h.errors() == [] and factory.errors() == []


def test_e30_bx_reports_io_bits_in_hex() -> None:
    """E30 ``BX`` -> ``05<LF>``: "Assuming the default I/O bit direction = FF, bits 0-7 outputs"
    with bits 0 and 2 high and the others low (set here with BS05).

    Contradiction (digest §8.2 12): the factory direction is "bits 0-3 as inputs and bits 4-7 as
    outputs", not FF. The example's own assumption is taken: a board with all bits outputs.
    """
    h = all_outputs("PCIX-004")
    enter(h, "BS05;")
    assert enter(h, "BX") == reply("05")
    assert h.errors() == []


# -- CA, CD, CG, CK, CN ---------------------------------------------------------------------------


def test_e31_ca_clears_only_z_done_flag() -> None:
    """E31 ``AA; MR1000,2000,3000,4000; GO; ID; AZ; CA;``: "After a multi-axis move, clear the Z
    axis done flag only" (CA "clears the done flag of the addressed axis only").

    CA is immediate; sent at once it would run before the move and its ID. The example's "After
    a multi-axis move" is taken literally: ``AZ; CA;`` is sent once the move and its ID are over.
    QI (which clears nothing) shows every axis done before and only Z cleared after.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AA;", "MR1000,2000,3000,4000;", "GO;", "ID;") == b""
    h.run()
    assert qi_fields(h) == ["PDNN", "PDNN", "PDNN", "PDNN"]
    assert enter(h, "AZ;", "CA;") == b""
    assert qi_fields(h) == ["PDNN", "PDNN", "PNNN", "PDNN"]
    assert h.errors() == []


def test_e32_ca_aa_mode_clears_y_and_z_done_flags() -> None:
    """E32 ``AA; MR1000,2000,3000,4000; GO; ID CA,1,1;``: "After a multi-axis move, clear the Y
    and Z axis done flags only" ("a null value in the argument list specifies the done bit of
    that axis is not to be cleared"). As in E31, ``CA,1,1;`` is sent after the move and its ID
    (``ID`` without a semicolon is ended by the Enter key)."""
    h = quiet("PCIX-004")
    assert enter(h, "AA;", "MR1000,2000,3000,4000;", "GO;", "ID") == b""
    h.run()
    assert qi_fields(h) == ["PDNN", "PDNN", "PDNN", "PDNN"]
    assert enter(h, "AA;", "CA,1,1;") == b""
    assert qi_fields(h) == ["PDNN", "PNNN", "PNNN", "PDNN"]
    assert h.errors() == []


def assert_near(h: Harness, x: float, y: float, tolerance: float = 2.0) -> None:
    """X and Y within ``tolerance`` counts of (x, y) (a contour at 1000 counts/s covers half a
    count per sample tick)."""
    at = (h.position("X"), h.position("Y"))
    assert abs(at[0] - x) <= tolerance and abs(at[1] - y) <= tolerance, (h.t, at, (x, y))


HALF_TURN = 3.1415926  # the examples' radians
FULL_TURN = 6.2831853


def test_e33_cd_contour_cuts_with_circular_interpolation() -> None:
    """E33 ``AA; CV1000; CD0,0; AN,,1; CR5000,0,-3.1415926; CR0,0,-6.2831853; AF,,0;
    MT1000,-1000; CE; MT1000,0; GO; CX;``.

    The commands are taken as typed (digest §8.2 35: the prose's "1000 count radius" does not
    match them). The stage is first positioned at (1000,0) (MT, tick 92). CX then "use[s] the
    distance between the current position and the contour starting point to linearly ramp up":
    1000 counts to reach 1000 counts/s, 2 s. From (0,0): a clockwise half circle about (5000,0)
    (radius 5000, 15.708 s; top (5000,5000) halfway) to (10000,0); a clockwise full circle about
    (0,0) (radius 10000, 62.832 s; (0,-10000) after a quarter, (-10000,0) after half); a line to
    (1000,-1000) (9055 counts, 9.055 s); CE ramps down at AC (0.25 count at 1000 counts/s, no
    whole step).

    "The AN and AF commands must have commas for all axes since they can all be addressed from
    within the contour definition": ``AN,,1`` / ``AF,,0`` switch Z's aux (the torch) at the
    contour start and after the full circle. The torch is off beforehand (AF,,1) as the example
    assumes.
    """
    h = quiet("PCIX-004")
    enter(h, "AA;", "AF,,1;")
    lines = ("AA;", "CV1000;", "CD0,0;", "AN,,1;", "CR5000,0,-3.1415926;", "CR0,0,-6.2831853;")
    assert enter(h, *lines, "AF,,0;", "MT1000,-1000;", "CE;", "MT1000,0;", "GO;", "CX;") == b""
    z = h.axis("Z")
    t_cx = tick(end_tick(0, linear_move_time(1000)))
    h.until(t_cx)
    assert_near(h, 1000, 0, 0)
    t0 = t_cx + 2.0  # at the contour's starting point
    h.until(t0 - 0.5)
    assert h.axis("X").velocity(h.t) < 0 and h.position("Y") == 0
    assert not z.aux
    h.until(t0)
    assert_near(h, 0, 0)
    h.until(t0 + 0.01)
    assert z.aux
    t1 = t0 + 5000 * HALF_TURN / 1000
    h.until(t0 + (t1 - t0) / 2)
    assert_near(h, 5000, 5000)
    h.until(t1)
    assert_near(h, 10000, 0)
    circle = 10000 * FULL_TURN / 1000
    for fraction, (x, y) in ((0.25, (0, -10000)), (0.5, (-10000, 0)), (0.75, (0, 10000))):
        h.until(t1 + fraction * circle)
        assert_near(h, x, y)
        assert z.aux
    t2 = t1 + circle
    h.until(t2 - 0.01)
    assert z.aux
    h.until(t2 + 0.01)
    assert not z.aux
    line = math.hypot(9000, 1000)
    t3 = t2 + line / 1000
    h.until(t3 - 1.0)  # 1000 counts before the end of the line
    assert_near(h, 1000 + 1000 * 9000 / line, -1000 + 1000 * 1000 / line)
    h.run()
    assert enter(h, "RP") == reply("1000,-1000,0,0")
    assert h.errors() == []


def test_e34_cg_runs_contour_and_holds_following_mt() -> None:
    """E34 ``AA; CV1000; CD0,0; AN,,1; CR5000,0,-3.1415926; CR0,0,6.2831853; AF,,0;
    MT10000,-1000; CE; MT-10000,0; GO; CG;``: CG "is a form of the CX command, use if CE is
    followed by a MT command. When CG is used to execute the contour, the following MT commands
    will be on hold until the contour execution is complete"; "Make sure that the hole is
    completely cut before executing the move to the new command position."

    As typed (differs from E33: the second CR is +6.2831853, counter-clockwise, and the MTs are
    10000,-1000 and -10000,0): positioned at (-10000,0) (tick 290), a 20 s ramp over 10000
    counts to (0,0), the clockwise half circle to (10000,0), a counter-clockwise full circle
    ((0,10000) after a quarter), a 1 s line to (10000,-1000), CE. The example has no MT after
    CG; one (``MT0,0; GO;``, sent right after CG) shows what CG is for: it starts only when the
    contour is over and goes from the contour's end to (0,0).
    """
    h = quiet("PCIX-004")
    lines = ("AA;", "CV1000;", "CD0,0;", "AN,,1;", "CR5000,0,-3.1415926;", "CR0,0,6.2831853;")
    assert enter(h, *lines, "AF,,0;", "MT10000,-1000;", "CE;", "MT-10000,0;", "GO;", "CG;") == b""
    assert enter(h, "MT0,0;", "GO;") == b""
    t_cg = tick(end_tick(0, linear_move_time(10000)))
    h.until(t_cg)
    assert_near(h, -10000, 0, 0)
    t0 = t_cg + 2 * 10000 / 1000
    h.until(t0)
    assert_near(h, 0, 0)
    t1 = t0 + 5000 * HALF_TURN / 1000
    h.until(t0 + (t1 - t0) / 2)
    assert_near(h, 5000, 5000)
    h.until(t1)
    assert_near(h, 10000, 0)
    circle = 10000 * FULL_TURN / 1000
    h.until(t1 + circle / 4)
    assert_near(h, 0, 10000)
    t2 = t1 + circle
    h.until(t2)
    assert_near(h, 10000, 0)
    h.until(t2 + 0.5)  # on the last line: the held MT has not started
    assert_near(h, 10000, -500)
    h.run()
    assert enter(h, "RP") == reply("0,0,0,0")
    assert h.errors() == []


def ck_example(h: Harness, end: str) -> None:
    """E35's lines, ending the definition with ``end`` (CK as printed, or CE to compare)."""
    lines = ("AA;", "CV1000;", "CD0,0;", "AN,,;", "CR5000,0,-3.1415926;", "CR0,0,-6.2831853;")
    enter(h, *lines, "AF,,0;", "MT10000,-1000;", end, "MT-1000,0;", "GO;", "CX;")


def test_e35_ck_ends_contour_without_ramp_down() -> None:
    """E35 ``AA; CV1000; CD0,0; AN,,; CR5000,0,-3.1415926; CR0,0,-6.2831853; AF,,0;
    MT10000,-1000; CK; MT-1000,0; GO; CX;``: "end the contour with the minimum ramp down"; CK
    "will end the contour sequence, like the CE command, except there is no ramp down; i.e.
    motion will stop abruptly."

    X and Y accelerate at 1000 counts/s^2 here (``AC1000,1000``) so that a ramp down would be
    visible: from 1000 counts/s it would take 1 s and 500 counts. Positioned at (-1000,0) (a 2 s
    triangle at that AC), 2 s ramp-up to (0,0), the clockwise half and full circles as in E33,
    a 1 s line to (10000,-1000): CK stops there, on the tick the contour ends; the same contour
    ended by CE coasts on to (10000,-1500).

    ``AN,,;`` names no axis (digest §8.2 35): taken as typed, it changes no aux output ("if the
    parameter does not exist for that axis, then the command has no effect on that axis"), so
    Z's aux is on from power-up during the cut and ``AF,,0`` turns it off after the circles.
    Whether that line is accepted at all is
    :func:`test_e35_ck_example_an_without_values_is_accepted`.
    """
    h = quiet("PCIX-004")
    enter(h, "AA;", "AC1000,1000;")
    ck_example(h, "CK;")
    t_cx = 2.0  # MT-1000,0 at AC 1000: 2 * sqrt(1000 / 1000)
    t0 = t_cx + 2.0
    h.until(t_cx)
    assert_near(h, -1000, 0, 0)
    h.until(t0)
    assert_near(h, 0, 0)
    assert h.axis("Z").aux
    t1 = t0 + 5000 * HALF_TURN / 1000
    t2 = t1 + 10000 * FULL_TURN / 1000
    h.until(t2 - 0.01)
    assert h.axis("Z").aux
    h.until(t2 + 0.01)
    assert not h.axis("Z").aux
    t3 = t2 + 1.0
    h.until(t3 - 0.5)
    assert_near(h, 10000, -500)
    h.until(t3 + tick(2))
    assert enter(h, "RP") == reply("10000,-1000,0,0")
    assert h.axis("Y").velocity(h.t) == 0
    h.run()
    assert enter(h, "RP") == reply("10000,-1000,0,0")
    ce = quiet("PCIX-004")
    enter(ce, "AA;", "AC1000,1000;")
    ck_example(ce, "CE;")
    ce.run()
    assert enter(ce, "RP") == reply("10000,-1500,0,0")


def test_e35_ck_example_an_without_values_is_accepted() -> None:
    """E35's ``AN,,;`` is part of a printed ``Enter:`` sequence with "Response: None": the board
    accepts it. In a multi-axis command "a 'b' parameter may be omitted if that axis is to remain
    unchanged" (§5.1); with every one omitted no axis is affected, which is not an error."""
    h = quiet("PCIX-004")
    ck_example(h, "CK;")
    assert errors(h) == []


def test_e36_cn_selects_cosine_ramps_on_all_axes() -> None:
    """E36 ``CN;``: "enables cosine velocity ramps; i.e. half sinusoid acceleration profiles, for
    all axes"; "This command affects all axes even if issued in the single axis mode". ``?RT``
    reads ``sc`` ("SC Cosine ramp") on every axis. A half-sine acceleration starts from zero, so
    one tick into a move the velocity is below the linear ramp's AC/2048 = 976.6; the move still
    ends on its target."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "?RT") == reply("la")
    assert enter(h, "CN;") == b""
    assert [enter(h, f"A{a};", "?RT") for a in "XYZT"] == [reply("sc")] * 4
    enter(h, "AZ;", "MR10000;", "GO;")
    h.until(tick(1))
    assert 0 < h.axis("Z").velocity(h.t) < AC0 / RATE
    h.run()
    assert h.position("Z") == 10000
    assert h.errors() == []


# -- custom ramps: ?DA DAR DAB DAE, ?DE ?DS -------------------------------------------------------


def test_e37_query_da_prints_ramp_table_2() -> None:
    """E37 ``?DA2;`` prints the table as the commands that enter it, one per line:
    ``DAR2<LF> DAB0.10000,0.20000<LF> DAB0.90000,0.80000<LF> DAB0.10000,1.00000<LF> DAE<LF>``
    (each line framed ``<LF><CR>``). Table 2 is defined with those breakpoints first."""
    h = quiet("PCIX-400")
    enter(h, "DAR2;", "DAB.1,.2;", "DAB.9,.8;", "DAB.1,1;", "DAE;")
    assert enter(h, "?DA2;") == b"".join(
        reply(line)
        for line in (
            "DAR2",
            "DAB0.10000,0.20000",
            "DAB0.90000,0.80000",
            "DAB0.10000,1.00000",
            "DAE",
        )
    )
    assert h.errors() == []


def test_e38_dar_dab_dae_define_table_3() -> None:
    """E38 ``DAR3; DAB.1,.05; DAB.3,.1; DAB.9,.9; DAB.3,.95; DAB.1,1; DAE;`` (the ``* Store as
    table #3`` ... annotations are not typed): five breakpoints in table 3 (``?DS3`` ``ds5``,
    ``?DA3`` lists them). The table is a usable ramp: SR3 selects it (``?RT`` ``sr3``) and a move
    with it ends on its target."""
    h = quiet("PCIX-004")
    lines = ("DAR3;", "DAB.1,.05;", "DAB.3,.1;", "DAB.9,.9;", "DAB.3,.95;", "DAB.1,1;", "DAE;")
    assert enter(h, *lines) == b""
    assert enter(h, "?DS3;") == reply("ds5")
    points = ("0.10000,0.05000", "0.30000,0.10000", "0.90000,0.90000", "0.30000,0.95000")
    expected = ("DAR3", *(f"DAB{p}" for p in points), "DAB0.10000,1.00000", "DAE")
    assert enter(h, "?DA3;") == b"".join(reply(line) for line in expected)
    enter(h, "AX;", "SR3;")
    assert enter(h, "?RT") == reply("sr3")
    enter(h, "MR30000;", "GO;")
    h.run()
    assert h.position("X") == 30000
    assert h.errors() == []


# -- direction bit: ?DB DBI DBN -------------------------------------------------------------------


def test_e39_query_db_reports_t_direction_inverted() -> None:
    """E39 ``AT; ?DB`` -> ``dbi<LF>`` "(The inverted result indicates the T axis direction bit is
    high for positive moves)", after DBI on T; before it (factory DBN) ``dbn``."""
    h = quiet("PCIX-400")
    assert enter(h, "AT;", "?DB") == reply("dbn")
    enter(h, "DBI;")
    assert enter(h, "AT;", "?DB") == reply("dbi")
    assert h.errors() == []


def direction_replies(h: Harness) -> list[bytes]:
    return [enter(h, f"A{a};", "?DB") for a in "XYZT"]


@pytest.mark.parametrize("form", [("AZ;", "DBI;", "AT;", "DBI;"), ("AA;", "DBI,,1,1;")])
def test_e40_dbi_inverts_z_and_t(form: tuple[str, ...]) -> None:
    """E40 ``AZ; DBI; AT; DBI;`` "Or" ``AA; DBI,,1,1;``: "Set the direction outputs for axes Z and
    T to output high when traveling positive ... Leaves X and Y as they are." Both forms."""
    h = quiet("PCIX-400")
    assert enter(h, *form) == b""
    assert direction_replies(h) == [reply("dbn"), reply("dbn"), reply("dbi"), reply("dbi")]
    assert h.errors() == []


@pytest.mark.parametrize("form", [("AZ;", "DBN;", "AT;", "DBN;"), ("AA;", "DBN,,1,1;")])
def test_e41_dbn_normalises_z_and_t(form: tuple[str, ...]) -> None:
    """E41 ``AZ; DBN; AT; DBN;`` "Or" ``AA; DBN,,1,1;``: Z and T back to the default logic, X and
    Y left as they are. All four are inverted first so that both halves are visible.

    Contradiction (digest §8.2 16): the example calls the default "output high when traveling
    positive", the DBN/DBI definitions "TTL low when traveling in the positive direction". The
    query reports the logic by name (``dbn``), so the test does not depend on which is right.
    """
    h = quiet("PCIX-400")
    enter(h, "AA;", "DBI1,1,1,1;")
    assert enter(h, *form) == b""
    assert direction_replies(h) == [reply("dbi"), reply("dbi"), reply("dbn"), reply("dbn")]
    assert h.errors() == []


# -- DC, ?DC --------------------------------------------------------------------------------------


def test_e42_dc_gu_decelerates_at_dc() -> None:
    """E42 ``AY; AC100000; DC20000; VL50000; MR100000; GU;``: "Send the Y axis on a 100,000
    count move that accelerates at 100,000 ... up to 50,000 ... and decelerates at 20,000".

    DC comes after AC, so it is not overwritten ("will take on whatever value is entered via the
    AC command"). Up: 0.5 s, 12,500 counts; down: 2.5 s, 62,500; cruise 25,000 counts, 0.5 s.
    Total 3.5 s = tick 7168. At 1.0 s the decel begins at 37,500; at 2.25 s v = 25,000 and
    x = 84,375.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AY;", "AC100000;", "DC20000;", "VL50000;", "MR100000;", "GU;") == b""
    assert enter(h, "?DC") == reply("dc20000")
    h.until(1.0)
    assert enter(h, "RV") == reply("50000")
    assert enter(h, "RP") == reply("37500")
    h.until(2.25)
    assert enter(h, "RV") == reply("25000")
    assert enter(h, "RP") == reply("84375")
    h.until(tick(7167))
    assert h.position("Y") == 99999
    h.until(tick(7168))
    assert h.position("Y") == 100000
    assert h.axis("Y").velocity(h.t) == 0
    assert h.errors() == []


def test_e43_query_dc_reports_x_deceleration() -> None:
    """E43 ``AX; ?DC`` -> ``dc20000<LF >`` (the space is typographic) with X's DC set to 20000.
    Before that it reads the power-up value ("The deceleration rate defaults to 200,000"); an AC
    entered afterwards replaces it ("will take on whatever value is entered via the AC command.
    Therefore, the DC command must be reentered after using AC")."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "?DC") == reply("dc200000")
    enter(h, "DC20000;")
    assert enter(h, "AX;", "?DC") == reply("dc20000")
    enter(h, "AC300000;")
    assert enter(h, "AX;", "?DC") == reply("dc300000")
    assert h.errors() == []


def test_e44_query_de_of_missing_entry_is_empty_line() -> None:
    """E44 ``?DE4,23;`` -> ``<LF>`` "(there is no 23rd entry in table 4)": an empty framed
    line. Table 4 here has three entries; an entry that exists is reported as ``?DA`` lists it
    (omsd's choice, ``pcix_commands`` docstring; the manual prints no such reply)."""
    h = quiet("PCIX-400")
    enter(h, "DAR4;", "DAB.1,.2;", "DAB.5,.6;", "DAB.1,1;", "DAE;")
    assert enter(h, "?DE4,23;") == b"\n\r"
    assert enter(h, "?DE4,3;") == reply("DAB0.10000,1.00000")
    assert h.errors() == []


def test_e45_query_ds_reports_17_breakpoints() -> None:
    """E45 ``?DS3;`` -> ``ds17<LF>`` with table 3 holding 17 breakpoints (velocity fractions
    1/17 ... 17/17, never decreasing as DAB requires)."""
    h = quiet("PCIX-400")
    points = [f"DAB.5,{k / 17:.4f};" for k in range(1, 17)] + ["DAB.5,1;"]
    enter(h, "DAR3;", *points, "DAE;")
    assert enter(h, "?DS3;") == reply("ds17")
    assert h.errors() == []


# -- DZ, EA ---------------------------------------------------------------------------------------


def test_e46_dz_sets_open_loop_offset() -> None:
    """E46 ``AX; DZ250;``: "Define the offset coefficient to be 250 (~ +76mV) for the X axis";
    DZ "affects the offset only when in open-loop mode" (the power-up HF) and each count is "an
    approximate change in the output voltage of 0.0003 volts": the DAC outputs code 250,
    250 * 10/32768 = 76.3 mV."""
    h = quiet("PCIX-400")
    servo = h.axis("X").servo
    assert servo is not None
    assert servo.dac_counts == 0
    assert enter(h, "AX;", "DZ250;") == b""
    h.advance(0.01)
    assert servo.dac_counts == 250
    assert servo.dac_volts == pytest.approx(0.076, abs=0.0005)
    assert h.errors() == []


def test_e47_ea_reports_y_encoder_status() -> None:
    """E47 ``AY; EA`` -> ``DDNNN<LF>``: slip detection disabled, position maintenance disabled,
    no slip, not within a maintained deadband, encoder not at home (home switch away). The reply
    is Y's: with slip detection on X (IS), X reads ``EDNNN`` and Y still ``DDNNN``."""
    h = quiet("PCIX-040")
    assert enter(h, "AY;", "EA") == reply("DDNNN")
    enter(h, "AX;", "IS;")
    assert enter(h, "AX;", "EA") == reply("EDNNN")
    assert enter(h, "AY;", "EA") == reply("DDNNN")
    assert h.errors() == []


# -- electronic gearing: EG, EG?, EGF -------------------------------------------------------------


def test_e48_eg_gears_z_to_half_of_x() -> None:
    """E48 ``AZ; EGX1,2;``: "Gear the Z axis to the X axis such that the Z axis velocity is
    always one half that of X" ("current axis velocity = Ratio X Master Axis velocity"). X then
    moves 10000 (0.1414 s): Z moves at half its velocity throughout and ends at 5000."""
    h = quiet("PCIX-004")
    assert enter(h, "AZ;", "EGX1,2;") == b""
    enter(h, "AX;", "MR10000;", "GO;")
    for t in (0.03, 0.07, 0.1):
        h.until(t)
        assert h.axis("Z").velocity(h.t) == pytest.approx(h.axis("X").velocity(h.t) / 2, abs=1)
    h.run()
    assert enter(h, "AA;", "RP") == reply("10000,0,5000,0")
    assert h.errors() == []


def test_e49_eg_gears_t_to_minus_twice_y() -> None:
    """E49 ``AT; EGY-2,1;``: "Gear the T axis to the Y axis such that the T axis velocity is
    always twice that of Y but in a direction that is opposite to Y" ("Negative ratio values
    indicate that the current axis is to track the master axis in the opposite direction"). Y
    moves 1000: T moves -2000."""
    h = quiet("PCIX-004")
    assert enter(h, "AT;", "EGY-2,1;") == b""
    enter(h, "AY;", "MR1000;", "GO;")
    h.until(0.02)
    assert h.axis("T").velocity(h.t) == pytest.approx(-2 * h.axis("Y").velocity(h.t), abs=1)
    h.run()
    assert enter(h, "AA;", "RP") == reply("0,1000,0,-2000")
    assert h.errors() == []


def test_e50_eg_query_reports_y_geared_to_x() -> None:
    """E50 ``AY; EG?`` -> ``=egx1,2`` "(Y axis is geared to the X with a gear ratio of 1:2)".
    The manual prints no terminator here; omsd frames this reply like every other
    (``=egx1,2<LF><CR>``)."""
    h = quiet("PCIX-004")
    enter(h, "AY;", "EGX1,2;")
    assert enter(h, "AY;", "EG?") == reply("=egx1,2")
    assert h.errors() == []


def test_e51_eg_query_reports_z_not_geared() -> None:
    """E51 ``AZ; EG?`` -> ``=egf`` "(Z axis is either not geared to another axis or it is the
    master axis in a electronic gearing relationship)": both cases."""
    h = quiet("PCIX-004")
    assert enter(h, "AZ;", "EG?") == reply("=egf")
    enter(h, "AY;", "EGZ;")
    assert enter(h, "AZ;", "EG?") == reply("=egf")
    assert enter(h, "AY;", "EG?").startswith(b"=egz")  # Y is the geared one
    assert h.errors() == []


def test_e52_egf_turns_x_gearing_off() -> None:
    """E52 ``AX; EGF;``: "Turn off electronic gearing on the X axis". X geared 1:1 to Y follows a
    Y move; after EGF (immediate: "the geared axis will only respond to immediate commands until
    the gearing is cancelled") it reports ``=egf`` and stays put when Y moves again."""
    h = quiet("PCIX-004")
    enter(h, "AX;", "EGY;", "AY;", "MR1000;", "GO;")
    h.run()
    assert enter(h, "AA;", "RP") == reply("1000,1000,0,0")
    assert enter(h, "AX;", "EGF;") == b""
    assert enter(h, "EG?") == reply("=egf")
    enter(h, "AY;", "MR1000;", "GO;")
    h.run()
    assert enter(h, "AA;", "RP") == reply("1000,2000,0,0")
    assert h.errors() == []


# -- encoder: ER ?ER ES ?ES ET --------------------------------------------------------------------


@pytest.mark.parametrize("form", ["ER10000,25000;", "ER2,5;"])
def test_e53_er_sets_encoder_motor_ratio(form: str) -> None:
    """E53 ``ER10000,25000;`` "or" ``ER2,5;``: "When the motor steps 25,000 times, the encoder
    produces 10,000 counts" (parameter 1 encoder counts, parameter 2 motor counts). Both forms
    give ``?ER`` ``er2.5`` (motor steps per encoder count, the form of E54's ``er2.0``), and
    after a move the encoder has counted 2 for every 5 motor steps.

    The PCIx manual does not say whether MR then takes motor steps or encoder counts (the PC48
    and VS4 manuals: "All distance, velocity and acceleration parameters are input in encoder
    counts"); the ratio check does not depend on it.
    """
    h = quiet("PCIX-040")
    assert enter(h, "AX;", form) == b""
    assert enter(h, "?ER") == reply("er2.5")
    enter(h, "MR10000;", "GO;")
    h.run()
    steps = round(h.axis("X").phys(h.t))
    assert steps in (10000, 25000)
    assert 5 * h.axis("X").encoder(h.t) == 2 * steps
    assert h.errors() == []


def test_e54_query_er_reports_two_steps_per_count() -> None:
    """E54 ``?ER`` -> ``er2.0<LF>`` "(The encoder produces 1 count for every 2 steps of the
    motor.)": ER1,2. The factory ratio "is 1:1" reads ``er1.0``."""
    h = quiet("PCIX-040")
    assert enter(h, "?ER") == reply("er1.0")
    enter(h, "ER1,2;")
    assert enter(h, "?ER") == reply("er2.0")
    assert h.errors() == []


def test_e55_es_is_tolerate_five_steps_of_slip() -> None:
    """E55 ``ES5; IS;``: "Your application can tolerate being up to 5 steps from the desired
    position before the controlling program should be notified of a slip condition."

    On a stepper with encoder (X): a slip of 5 steps during a move is tolerated (RL ``NNNN``, EA
    still ``E`` for detection); 6 steps are flagged: RL shows ``S`` for X and EA's slip
    character ``S`` ("reset by execution of EA"). RL is read before EA so that EA's reset does
    not hide it.
    """
    h = quiet("PCIX-040")
    assert enter(h, "ES5;", "IS;") == b""
    assert enter(h, "?ES") == reply("es5")
    assert enter(h, "EA") == reply("EDNNN")
    enter(h, "MR1000;", "GO;")
    h.until(0.01)
    h.board.inject_slip("X", 5, h.t)
    h.run()
    assert enter(h, "RL") == reply("NNNN")
    assert enter(h, "AX;", "EA") == reply("EDNNN")
    slipping = quiet("PCIX-040")
    enter(slipping, "ES5;", "IS;", "MR1000;", "GO;")
    slipping.until(0.01)
    slipping.board.inject_slip("X", 6, slipping.t)
    slipping.run()
    assert enter(slipping, "RL") == reply("SNNN")
    assert enter(slipping, "AX;", "EA")[2:3] == b"S"
    assert h.errors() == [] and slipping.errors() == []


def test_e56_query_es_reports_tolerance() -> None:
    """E56 ``?ES`` -> ``es15<LF>`` "Report the current value for encoder slip detection
    tolerance", with ES15 set on the current axis (X) of a stepper-with-encoder board."""
    h = quiet("PCIX-040")
    enter(h, "ES15;")
    assert enter(h, "?ES") == reply("es15")
    assert h.errors() == []


def test_e56_query_es_at_power_up_reads_factory_one() -> None:
    """E56's query before any ES: "The factory default value is 1" (ES page), "Encoder slip
    detection tolerance is 1 ( ES1 )" (§2.8), "Encoder slip tolerance is one( ES1 )" (RF); the
    range is "0 < ES ≤ 65,535", so 0 is not even a valid setting."""
    h = quiet("PCIX-040")
    assert enter(h, "AX;", "?ES") == reply("es1")


def test_e57_et_y_tracks_its_encoder() -> None:
    """E57 ``AY; ET;``: "Set up the Y axis so it will follow its encoder input" ("The axis will
    duplicate the encoder input"; "No acceleration or deceleration ramps are generated"). With
    the encoder driven from outside Y's position follows it at once; X, not tracking, does not
    move when its encoder is driven."""
    h = quiet("PCIX-040")
    assert enter(h, "AY;", "ET;") == b""
    h.advance(0.01)
    h.board.set_encoder_input("Y", 500, h.t)
    h.advance(tick(1))
    assert enter(h, "AY;", "RP") == reply("500")
    h.board.set_encoder_input("Y", -250, h.t)
    h.advance(tick(1))
    assert enter(h, "AY;", "RP") == reply("-250")
    h.board.set_encoder_input("X", 500, h.t)
    h.advance(tick(1))
    assert enter(h, "AX;", "RP") == reply("0")
    assert h.errors() == []


# -- FL, FP, GD, GN, GO, GS, GU -------------------------------------------------------------------


def test_e58_fl_flushes_x_queue_and_lets_move_finish() -> None:
    """E58 ``AX; FL;``: "Several motion commands have been sent to the X axis but ... those
    commands must be cleared out. The currently executing motion must be allowed to complete"
    (FL: "All unexecuted commands remaining in the current axis queue will be flushed upon
    receipt"; "current motion will remain unaffected").

    X runs MR10000 (ticks 0-290) with two more moves queued; FL at 0.05 s leaves the first move
    to end at 10000 on tick 290 and nothing after it; the queue is empty again.
    """
    h = quiet("PCIX-004")
    enter(h, "AX;", "MR10000;", "GO;", "MR5000;", "GO;", "MR7000;", "GO;")
    h.until(0.05)
    assert enter(h, "AX;", "FL;") == b""
    end = end_tick(0, linear_move_time(10000))
    h.until(tick(end - 1))
    assert h.position("X") == 9999
    h.until(tick(end))
    assert h.position("X") == 10000
    h.run()
    assert h.position("X") == 10000
    assert h.axis("X").queue.free == QUEUE
    assert h.errors() == []


def test_e59_fp_forces_stop_at_25000() -> None:
    """E59 ``FP25000;``: "Force axis to stop at 25,000" ("will flush the command queue and
    attempt to stop at the specified position"). X jogs at 100,000 (reached in 0.05 s); FP at
    0.1 s (X at 7500) leaves 17,500 counts, more than the 2500 needed to stop at AC: X cruises to
    22,500 and decelerates to stop exactly on 25,000 at 0.3 s (tick 615)."""
    h = quiet("PCIX-004")
    enter(h, "AX;", "JG100000;")
    h.until(0.1)
    assert h.position("X") == 7500
    assert enter(h, "FP25000;") == b""
    h.until(tick(614))
    assert h.position("X") == 24999
    h.until(tick(615))
    assert h.position("X") == 25000
    assert h.axis("X").velocity(h.t) == 0
    h.run()
    assert h.position("X") == 25000
    assert h.errors() == []


def test_e60_gd_resets_y_done_flag_before_second_move() -> None:
    """E60 ``AY; MR-12345; GO; ID; MR12345; GD; ID;``: "move the Y axis 12345 counts in the
    negative direction and set the done flag when the move is completed. Then clear the done
    flag, move the motor 12345 counts in the positive direction, and set the done flag again".

    Each move is a triangle of 0.1571 s (322 ticks). The first ID sets the flag on tick 322 (a
    done interrupt), GD clears it as the second move starts on the same tick, so during the
    second move QA shows no done flag (GO would have left it set); the second ID sets it on
    tick 644.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AY;", "MR-12345;", "GO;", "ID;", "MR12345;", "GD;", "ID;") == b""
    leg = end_tick(0, linear_move_time(12345))
    assert leg == 322
    h.until(tick(leg - 1))
    assert qa(h, "Y") == reply("MNNN")
    h.until(tick(leg))
    assert h.position("Y") == -12345
    assert done_ticks(h) == [leg]
    h.until(tick(leg + 100))
    assert qa(h, "Y") == reply("PNNN")
    h.until(tick(2 * leg - 1))
    assert qa(h, "Y") == reply("PNNN")
    h.until(tick(2 * leg))
    assert h.position("Y") == 0
    assert qa(h, "Y") == reply("PDNN")
    assert done_ticks(h) == [2 * leg]
    assert h.errors() == []


def test_e61_gd_aa_mode_linear_moves_with_done_flags() -> None:
    """E61 ``AA; MT10000,20000; GO; ID; ML-10000,-20000; GD; ID;``: "perform a linear absolute
    move with the X and Y axes to the position 10000,20000 and set the done flag ... Then clear
    the done flag, perform a linear relative move ... moving the X axis 10000 steps in the
    negative direction and the Y axis 20000 steps in the negative direction, and set the flag
    once again."

    Y is the master (20000 = VL^2/AC: 0.2 s, tick 410), X is scaled to finish with it. The ID
    interrupts come on ticks 410 and 820; between them GD ("In AA mode, all the done flags will
    be reset") has cleared X's and Y's flags. Only X and Y are asserted: Z and T have no move to
    wait for and meet their IDs at once.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AA;", "MT10000,20000;", "GO;", "ID;", "ML-10000,-20000;", "GD;", "ID;") == b""
    leg = end_tick(0, linear_move_time(20000))
    assert leg == 410
    h.until(tick(leg - 1))
    assert [h.position("X"), h.position("Y")] == [9999, 19999]
    assert qi_fields(h)[:2] == ["PNNN", "PNNN"]
    h.until(tick(leg))
    assert [h.position("X"), h.position("Y")] == [10000, 20000]
    assert done_ticks(h) == [leg]
    h.until(tick(leg + 100))
    assert qi_fields(h)[:2] == ["MNNN", "MNNN"]
    x, y = h.position("X"), h.position("Y")
    assert y == pytest.approx(2 * x, abs=2)
    h.until(tick(2 * leg))
    assert [h.position("X"), h.position("Y")] == [0, 0]
    assert qi_fields(h)[:2] == ["MDNN", "MDNN"]
    assert done_ticks(h) == [2 * leg]
    assert h.errors() == []


def test_e62_gn_moves_x_and_sets_done_flag() -> None:
    """E62 ``AX; MA12345; GN;``: "initiate a move ... and set the axis done flags when the move is
    complete" (no ID needed). Over on tick 322: QA ``PNNN`` before, ``PDNN`` and a done
    interrupt then."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "MA12345;", "GN;") == b""
    end = end_tick(0, linear_move_time(12345))
    h.until(tick(end - 1))
    assert qa(h, "X") == reply("PNNN")
    assert done_ticks(h) == []
    h.until(tick(end))
    assert h.position("X") == 12345
    assert qa(h, "X") == reply("PDNN")
    assert done_ticks(h) == [end]
    assert h.errors() == []


def test_e63_gn_aa_mode_moves_x_and_y_and_sets_done_flags() -> None:
    """E63 ``AA; MR2468,-2468; GN;``: X +2468, Y -2468 (triangles of 0.0703 s, tick 144), the
    done flags of both set when the move is complete."""
    h = quiet("PCIX-004")
    assert enter(h, "AA;", "MR2468,-2468;", "GN;") == b""
    end = end_tick(0, linear_move_time(2468))
    h.until(tick(end - 1))
    assert qi_fields(h)[:2] == ["PNNN", "MNNN"]
    h.until(tick(end))
    assert [h.position("X"), h.position("Y")] == [2468, -2468]
    assert qi_fields(h)[:2] == ["PDNN", "MDNN"]
    assert done_ticks(h) == [end]
    assert h.errors() == []


def test_e64_go_moves_x_to_12345() -> None:
    """E64 ``AX; MA12345; GO;``: "move the X axis to absolute position 12345": a triangle of
    0.1571 s, over on tick 322. GO sets no done flag (QA ``PNNN``)."""
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "MA12345;", "GO;") == b""
    end = end_tick(0, linear_move_time(12345))
    assert end == 322
    h.until(tick(end - 1))
    assert h.position("X") == 12344
    h.until(tick(end))
    assert h.position("X") == 12345
    h.run()
    assert qa(h, "X") == reply("PNNN")
    assert done_ticks(h) == []
    assert h.errors() == []


def test_e65_go_aa_mode_moves_x_and_y_opposite() -> None:
    """E65 ``AA; MR2468,-2468; GO;``: "move the X axis 2468 steps in the positive direction and
    the Y axis 2468 steps in the negative direction": both start on tick 0 and end on tick 144."""
    h = quiet("PCIX-004")
    assert enter(h, "AA;", "MR2468,-2468;", "GO;") == b""
    end = end_tick(0, linear_move_time(2468))
    assert end == 144
    h.until(tick(1) + 1 / 4096)
    assert h.axis("X").velocity(h.t) == pytest.approx(-h.axis("Y").velocity(h.t))
    assert h.axis("X").velocity(h.t) > 0
    h.until(tick(end - 1))
    assert [h.position("X"), h.position("Y")] == [2467, -2467]
    h.until(tick(end))
    assert enter(h, "RP") == reply("2468,-2468,0,0")
    assert h.errors() == []


def test_e66_gs_sets_slip_flag_when_home_switch_closes() -> None:
    """E66 ``AX; MR50000; GS;`` on an open-loop stepper: "If the motor slips it will close a
    switch wired to the home input of the X axis. Monitor this switch during the move and set the
    slip flag for axis X if the switch becomes active"; GS "works exactly like the GO command"
    otherwise.

    The switch closes at 0.1 s: from then on the axis's slip is flagged (a slip event for X and
    the status register's ENC_S bit, the host's view of slip), and the move still ends at 50000
    (0.35 s, tick 717). RL is not used: it "always returns “n”" for open-loop steppers.
    """
    h = quiet("PCIX-004")
    assert enter(h, "AX;", "MR50000;", "GS;") == b""
    h.until(0.1)
    assert not enc_s(h)
    assert not any(isinstance(e, SlipEvent) for e in h.events())
    h.board.set_home("X", True, h.t)
    h.advance(tick(2))
    assert enc_s(h)
    assert [e.axis for e in h.events() if isinstance(e, SlipEvent)] == ["X"]
    end = end_tick(0, linear_move_time(50000))
    assert end == 717
    h.until(tick(end))
    assert h.position("X") == 50000
    assert h.errors() == []


def test_e67_gu_moves_y_to_1500_decelerating_at_5000() -> None:
    """E67 ``AY; DC5000; MA1500; GU;``: "Move the Y axis to position 1,500 using the current
    acceleration and velocity and a deceleration of 5,000".

    Up at 2,000,000, down at 5,000: the peak v satisfies v^2/(2*2e6) + v^2/(2*5000) = 1500,
    v = 3868.1 counts/s (far below VL), reached after 1.93 ms; the decel takes 0.7736 s. Over at
    0.7756 s (tick 1589).
    """
    h = quiet("PCIX-004")
    assert enter(h, "AY;", "DC5000;", "MA1500;", "GU;") == b""
    peak = math.sqrt(1500 / (1 / (2 * AC0) + 1 / (2 * 5000)))
    up, down = peak / AC0, peak / 5000
    end = end_tick(0, up + down)
    assert end == 1589
    h.until(up + down / 2)
    assert h.axis("Y").velocity(h.t) == pytest.approx(peak / 2, rel=1e-3)
    h.until(tick(end - 1))
    assert h.position("Y") == 1499
    h.until(tick(end))
    assert h.position("Y") == 1500
    assert h.errors() == []


# -- ?HD HE HF ?HG HL -----------------------------------------------------------------------------


def test_e68_query_hd_reports_deadband() -> None:
    """E68 ``?HD`` -> ``hd5<LF>`` on a stepper axis with encoder, HD5 (factory "Position
    maintenance dead band is zero( HD0 )": ``hd0``)."""
    h = quiet("PCIX-040")
    assert enter(h, "?HD") == reply("hd0")
    enter(h, "HD5;")
    assert enter(h, "?HD") == reply("hd5")
    assert h.errors() == []


@pytest.mark.parametrize("form", [("AY;", "HE;"), ("AA;", "HE,1;")])
def test_e69_he_y_homes_on_encoder(form: tuple[str, ...]) -> None:
    """E69 ``AY; HE;`` "or" ``AA; HE,1;``: "Set up the Y axis so it will use the encoder signals
    to recognize the home position." Both forms: Y's ``?HM`` reads ``he`` (the pair of the
    printed ``hs``), X keeps ``hs``; "The HL and HH commands are not valid in this state" (a
    command error for Y, none for X)."""
    h = quiet("PCIX-040")
    assert enter(h, *form) == b""
    assert enter(h, "AY;", "?HM") == reply("he")
    assert enter(h, "AX;", "?HM") == reply("hs")
    assert h.errors() == []
    enter(h, "AX;", "HH;")
    assert h.errors() == []
    enter(h, "AY;", "HH;")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, "HH")]


def test_e70_hf_turns_x_hold_off() -> None:
    """E70 ``AX; HF;``: "Turn off encoder hold mode on the X axis". On a stepper with encoder HF
    "disables position hold": EA's position-maintenance character goes from ``E`` (after HN) to
    ``D``. On a servo axis HF "will open the loop and turn off the PID": ``?PM`` ``hn`` ->
    ``hf``."""
    h = quiet("PCIX-040")
    enter(h, "AX;", "HN;")
    h.advance(0.01)
    assert enter(h, "EA")[1:2] == b"E"
    assert enter(h, "AX;", "HF;") == b""
    h.advance(0.01)
    assert enter(h, "EA") == reply("DDNNN")
    servo = quiet("PCIX-400")
    enter(servo, "AX;", "HN;")
    servo.advance(0.01)
    assert enter(servo, "?PM") == reply("hn")
    assert enter(servo, "AX;", "HF;") == b""
    servo.advance(0.01)
    assert enter(servo, "?PM") == reply("hf")
    x = servo.axis("X").servo
    assert x is not None and not x.closed
    assert h.errors() == [] and servo.errors() == []


def test_e71_query_hg_reports_hold_gain() -> None:
    """E71 ``?HG`` -> ``hg100<LF >`` (the space is typographic) with HG100 (factory "Position
    maintenance hold gain is one( HG1 )": ``hg1``)."""
    h = quiet("PCIX-040")
    assert enter(h, "?HG") == reply("hg1")
    enter(h, "HG100;")
    assert enter(h, "?HG") == reply("hg100")
    assert h.errors() == []


def test_e72_hl_hm0_homes_x_at_low_speed() -> None:
    """E72 ``AX; VL2000; HL; HM0;``: "The stage is moved through home with the home switch set
    for active low at low speed to meet the less than 2048 steps per second requirement of the
    home command."

    The home switch (normally open: active low, HL) is closed from carriage position 1000 on.
    HM moves positive at VL until home; "The position counters will be initialized to the
    positions supplied as parameters" (0); then "the axis will ramp to a stop" beyond the switch
    (2000^2/(2 AC) = 1 step). "A velocity set to less than or equal to the update rate will
    provide a homing accuracy of +/-0 counts": the step at which the switch closed (1000) is
    position 0 exactly, so at rest carriage step - counter = 1000. Home is found after about
    1000/2000 s.
    """
    h = Harness("PCIX-004")  # default world: X's home switch from 1000 to 1100
    assert enter(h, "AX;", "VL2000;", "HL;", "HM0;") == b""
    h.until(0.49)
    assert h.position("X") > 900
    assert enter(h, "AX;", "QA") == reply("PNNN")
    h.run()
    assert h.t == pytest.approx(0.5, abs=0.01)
    rp = h.position("X")
    assert 0 <= rp <= 2
    assert math.floor(h.axis("X").phys(h.t)) - rp == 1000
    assert enter(h, "AX;", "?HS") == reply("hl")
    assert h.errors() == []
