"""Conformance: the PCIx manual's examples outside the command pages, S1-S9 of
``shared/reference/pcix.md`` §5 ("Supplementary examples outside the command descriptions"):
chapter 1's typical move string, chapter 2's installation, servo check-out and tuning steps, and
§5.1, §5.2 and §5.12.4's inline command strings. Checked against the manual text
(``shared/seeds/002_5f0bea9264c6d239.txt``). None prints a reply in ``Enter:``/``Response:``
form; each test types the string as printed and asserts what the sentence around it says.

Where the printed string is not what a board takes as meant (a typo, a comma that belongs to
the sentence, a servo-only operand), the test pins what omsd does with it and says why
(docs/decisions.md, "Command strings quoted in running text").
"""

from __future__ import annotations

import pytest

from omsd.board.events import ErrorKind
from omsd.board.harness import Harness

from .pcix import QUEUE, end_tick, linear_move_time, quiet, reply, tick
from .support import errors


def enter(h: Harness, *lines: str) -> bytes:
    """Type each line and the Enter key (CR); the replies produced at once."""
    return b"".join(h.send(line + "\r") for line in lines)


def test_s1_typical_move_string() -> None:
    """S1 (§1.1): "A typical motion requirement of 1,000,000 counts at 400,000 counts/sec and
    an acceleration of 500,000 counts/sec/sec" is ``VL400000; AC500000; MR1000000; GO;``.
    A trapezoid: 0.8 s up, 1.7 s at 400,000, 0.8 s down, 3.3 s in all (tick 6759)."""
    h = quiet("PCIX-004")
    assert enter(h, "VL400000;", "AC500000;", "MR1000000;", "GO;") == b""
    duration = linear_move_time(1_000_000, vl=400_000, ac=500_000)
    assert duration == pytest.approx(3.3)
    end = end_tick(0, duration)
    assert end == 6759
    h.until(tick(1.5 * 2048))
    assert h.axis("X").velocity(h.t) == pytest.approx(400_000)
    h.until(tick(end - 1))
    assert h.position("X") < 1_000_000
    h.until(tick(end))
    assert enter(h, "RP") == reply("1000000")
    assert errors(h) == []


def test_s2_servo_checkout_zero_and_encoder_direction() -> None:
    """S2 (§2.6.1): ``DZ100;``, ``DZ50;``, ``DZ150;``, ``DZ3277;`` ("The output of PCIx will be
    near 1VDC"), ``DZ-3277;``, then the zero value with ``KO`` ("e.g. "KO-175;""), then
    "Send the "LP0; DZ2000;" command ... Send the "RE" command ... If the response is positive,
    no further action need be taken". The simulated encoder is wired the right way round: RE
    is positive, RP (the loop is open) stays 0."""
    h = quiet("PCIX-400")
    for line in ("DZ100;", "DZ50;", "DZ150;", "DZ3277;", "DZ-3277;", "DZ-175;", "KO-175;"):
        assert enter(h, line) == b""
        h.advance(0.05)
    assert enter(h, "LP0; DZ2000;") == b""
    h.advance(0.5)
    re = enter(h, "RE")
    assert re.endswith(b"\n\r") and int(re[:-2]) > 0
    assert enter(h, "RP") == reply("0")
    assert errors(h) == []


def test_s2_dz0_with_the_sentences_comma() -> None:
    """S2 step 3a: 'send the command "DZ0," to the PCIx'. The comma inside the quotes is the
    sentence's (American punctuation); typed as printed, the board reads a second operand DZ
    does not take: one command error (too many parameters) and the offset is not changed, as
    for any single-axis command with a trailing comma (``VL1000,``). ``DZ0;`` is the command."""
    h = quiet("PCIX-400")
    enter(h, "DZ3277;")
    h.advance(0.2)
    enter(h, "DZ0,")
    assert errors(h) == [(ErrorKind.TOO_MANY_PARAMETERS, "DZ0,")]
    before = int(enter(h, "RE")[:-2])
    h.advance(0.2)
    assert int(enter(h, "RE")[:-2]) > before  # the DZ3277 drift goes on
    enter(h, "DZ0;")
    assert errors(h) == []


def test_s3_s4_tuning_sequence_with_the_mrmr_typo() -> None:
    """S3/S4 (§2.7.2): the profile "((50,000)^2 / (2 x 500,000)) x 2.4 = 6,000" moved with
    ``MR6000; GO;``, then the tuning sequence as printed, which has ``MRMR6000;`` (sic) in its
    fifth round. Typed as printed the first ``MR`` has no operand: one command error
    (parameter required) and nothing queued for it; the second ``MR6000`` is read as the
    command meant, so the round still moves 6000 counts and every round ends at 6000 with the
    loop closed (HN) and holding."""
    h = quiet("PCIX-400")
    h.send("AC500000;VL50000;\r")
    rounds = [
        ("LP0;", "KP3;", "HN;", "MR6000;", "GO;"),
        ("LP0;", "KP10;", "HN;", "MR6000;", "GO;"),
        ("LP0;", "KP25;", "HN;", "MR6000;", "GO;"),
        ("LP0;", "KD100;", "HN;"),
        ("LP0;", "KP35;", "HN;", "MRMR6000;", "GO;"),
        ("LP0;", "KD125;", "HN;"),
    ]
    for lines in rounds:
        assert enter(h, *lines) == b""
        h.advance(1.0)
        moved = "MR6000;" in lines or "MRMR6000;" in lines
        expected = "6000" if moved else "0"
        assert enter(h, "RP") == reply(expected), lines
        assert abs(int(enter(h, "RE")[:-2]) - int(expected)) <= 2, lines
        if "MRMR6000;" in lines:
            assert errors(h) == [(ErrorKind.MISSING_PARAMETER, "MR")]
        else:
            assert errors(h) == [], lines
    assert enter(h, "?PM") == reply("hn")


def test_s5_holding_and_eight_revolution_move() -> None:
    """S5 (§2.7.2): ``LP0;HN;`` to see the motor hold, then "AC100000;VL5000;MR64000;GO" and
    ``RE``/``RP`` ("With a 2000 line encoder this move would be equivalent to 8 revolutions":
    64,000 counts of 4 x 2000). 64000/5000 + 5000/100000 = 12.85 s; at the end the loop has
    brought the encoder to the commanded 64,000."""
    h = quiet("PCIX-400")
    assert enter(h, "LP0;HN;") == b""
    h.advance(1.0)
    assert enter(h, "RP") == reply("0")
    assert enter(h, "RE") == reply("0")
    start = h.t
    assert enter(h, "AC100000;VL5000;MR64000;GO") == b""
    duration = linear_move_time(64_000, vl=5_000, ac=100_000)
    assert duration == pytest.approx(12.85)
    h.until(start + duration / 2)
    assert 0 < h.position("X") < 64_000
    h.until(start + duration + 1.0)
    assert enter(h, "RE") == reply("64000")
    assert enter(h, "RP") == reply("64000")
    assert errors(h) == []


def test_s6_wy_reply_is_similar_to_the_installation_text() -> None:
    """S6 (§2.4): "You should receive a reply similar to "PCIX-400 ver 1.26 S/N 000000, Oregon
    Micro Systems"". The WY command page prints the reply itself (E216,
    ``PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems``) and wins; the installation text
    is "similar": the same model, version and maker, in the same order."""
    h = quiet("PCIX-400")
    got = enter(h, "WY")
    assert got == reply("PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems")
    text = got.decode("ascii")
    positions = [text.index(part) for part in ("PCIX-400", "1.26", "Oregon Micro Systems")]
    assert positions == sorted(positions)


@pytest.mark.parametrize("line", ["LN,1,1;", "LN,0,0;", "LN,50,99;"])
def test_s7_ln_flag_values_are_equivalent(line: str) -> None:
    """S7 (§5.1): "Each 'b' position, if used, can be any numeric value ... the following
    commands are equivalent: "LN,1,1;" "LN,0,0;" "LN,50,99;"": each turns the Y and Z limits
    on and leaves X and T as they were."""
    h = quiet("PCIX-004")
    enter(h, "AA;", "LF,1,1,1;", "LN1;")
    assert [h.axis(a).limits_on for a in "XYZT"] == [True, False, False, False]
    assert enter(h, line) == b""
    assert [h.axis(a).limits_on for a in "XYZT"] == [True, True, True, False]
    assert errors(h) == []


def test_s7_ln_1_100_enables_y_and_z_only() -> None:
    """S7 (§5.1): "to enable the Y and Z axes limit switches and leave the X and T axes
    unchanged, send the command "LN,1,100;"". From all off (X's left off): Y and Z stop at
    their switches, X and T run through theirs."""
    h = quiet("PCIX-004")
    enter(h, "AA;", "LF,,,1;", "AX;", "LF;")
    enter(h, "AA;", "LF,1,1;")
    assert [h.axis(a).limits_on for a in "XYZT"] == [False, False, False, False]
    assert enter(h, "AA;", "LN,1,100;") == b""
    assert [h.axis(a).limits_on for a in "XYZT"] == [False, True, True, False]
    assert errors(h) == []


def test_s7_template_for_y_and_z_follows_the_rule_not_the_printed_mr() -> None:
    """§5.1: "to move only the Y and Z axes, enter the command as "MR#, #;"" contradicts the
    paragraph's own rule ("An axis may be skipped by entering a comma with no parameter") and
    its ``MR#, #, #, #;`` layout, where the first field is X. omsd follows the rule: ``MR100,
    200;`` moves X and Y, ``MR,100,200;`` moves Y and Z. The spaces after the commas of the
    template are skipped."""
    h = quiet("PCIX-004")
    enter(h, "AA;", "MR100, 200;", "GO;")
    h.run()
    assert enter(h, "RP") == reply("100,200,0,0")
    enter(h, "MR,100, 200;", "GO;")
    h.run()
    assert enter(h, "RP") == reply("100,300,200,0")
    assert errors(h) == []


def test_s8_single_axis_string_goes_to_the_x_queue_only() -> None:
    """S8 (§5.2): "in the string "AX; MR100; GO;" the X axis command queues would get "AX; MR;
    GO;" and the X axis argument queue would get "100"": only X's queue is used (the others
    keep their 800 free) and X moves 100; afterwards every queue is empty again."""
    h = quiet("PCIX-004")
    assert enter(h, "AX; MR100; GO;") == b""
    used = enter(h, "RQ").decode("ascii").rstrip("\n\r").split(", ")
    assert used[1:] == [str(QUEUE)] * 3
    assert int(used[0]) < QUEUE
    h.run()
    assert h.position("X") == 100
    assert enter(h, "RQ") == reply(", ".join([str(QUEUE)] * 4))
    assert errors(h) == []


def power_cycle(h: Harness) -> None:
    """Switch the board off and on and wait until it has initialised."""
    h.board.power_cycle(h.t)
    h.advance(0.2)


def test_s9_backlash_per_axis_archived_with_ap() -> None:
    """S9 (§5.12.4, servo motor axis): "assign backlash compensation for each axis and archive
    the command, so that the compensation will occur automatically, for each appropriate axis,
    For example, AX;BC-10;AY;BC5;AZ;BC7; AP;". On a servo board (BC "limited to a range of
    from minus 50 to plus 50 encoder counts") all three are taken and survive a power cycle."""
    h = quiet("PCIX-400")
    assert enter(h, "AX;BC-10;AY;BC5;AZ;BC7; AP;") == b""
    power_cycle(h)
    got = [enter(h, f"A{a};", "?BC") for a in "XYZT"]
    assert got == [reply("bc-10"), reply("bc5"), reply("bc7"), reply("bc0")]
    assert errors(h) == []


def test_s9_negative_backlash_is_out_of_range_on_a_stepper_axis() -> None:
    """S9's ``BC-10`` is a servo value: "The backlash compensation for stepper motors is
    limited to a range of from 0 to 50 steps" (§5.12.3). Typed on a stepper board it is one
    out-of-range error and X keeps BC0; Y and Z take theirs."""
    h = quiet("PCIX-004")
    enter(h, "AX;BC-10;AY;BC5;AZ;BC7; AP;")
    assert errors(h) == [(ErrorKind.OUT_OF_RANGE, "BC-10")]
    got = [enter(h, f"A{a};", "?BC") for a in "XYZ"]
    assert got == [reply("bc0"), reply("bc5"), reply("bc7")]


@pytest.mark.parametrize(
    ("line", "query", "y"),
    [("EGX;", "=egx", 1000), ("EGX2;", "=egx2", 2000), ("EGX1,2;", "=egx1,2", 500)],
)
def test_eg_inline_forms(line: str, query: str, y: int) -> None:
    """The EG page's inline examples: "EGX; gears the current axis to the X axis using a ratio
    of 1 to 1", "EGX2; ... with a ratio of 2 to 1", "EGX1,2; ... with a gear ratio of 1 to 2"
    ("the ratio of geared axis motion to master axis motion"). Y geared to X follows X's
    1000-count move by the ratio; EG? names the form entered."""
    h = quiet("PCIX-004")
    assert enter(h, "AY;", line) == b""
    assert enter(h, "EG?") == reply(query)
    enter(h, "AX;", "VL10000;", "MR1000;", "GO;")
    h.run()
    assert enter(h, "AA;", "RP") == reply(f"1000,{y},0,0")
    assert errors(h) == []
