"""The streaming lexer (omsd/protocol/lexer.py), operands (omsd/protocol/operands.py) and parsing
through the board (PC48 §6.1, §6.3, §6.14), plus a replay of the RX side of the EPICS drvOmsPC68
trace (shared/interop/epics-drvOmsPC68.trace) against a PC48-4.

PC48 §6.1: "All the commands are two ASCII characters and may be in upper or lower case. ... The
operand must be terminated by a space, carriage return or semi-colon to indicate the end of the
number. ... No terminator is required on the other commands". Design decisions: the board reads a
continuous stream; a bare command completes at its second letter; an operand also ends at LF,
the next letter or any other character; spaces after a mnemonic and after commas are skipped; a
fraction without user units is truncated toward zero.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from decimal import Decimal
from pathlib import Path

import pytest

from omsd.board.events import CommandErrorEvent, ErrorKind
from omsd.board.harness import Harness
from omsd.engine.registers import CMD_S, INIT
from omsd.protocol.lexer import MAX_FIELD, MAX_FIELDS, MAX_TEXT, Command, Garbage, Lexer, Syntax
from omsd.protocol.operands import OperandError, check_range, parse_field, parse_number, truncate

WY4 = b"\n\rPC48 ver 3.00-4\n\r"

_FRAME = re.compile(rb"\n\r\r([^\n\r]*)\n\r\r|\n\r([^\n\r]*)\n\r")


def frames(data: bytes) -> list[tuple[str, str]]:
    """Split reply bytes into frames; every byte must belong to a correctly framed reply."""
    out: list[tuple[str, str]] = []
    pos = 0
    while pos < len(data):
        m = _FRAME.match(data, pos)
        assert m is not None, f"unframed bytes at {pos}: {data[pos:]!r}"
        if m.group(1) is not None:
            out.append(("status", m.group(1).decode("ascii")))
        else:
            out.append(("value", m.group(2).decode("ascii")))
        pos = m.end()
    return out


def value(text: str | bytes) -> bytes:
    t = text.encode("ascii") if isinstance(text, str) else text
    return b"\n\r" + t + b"\n\r"


def status(text: str) -> bytes:
    return b"\n\r\r" + text.encode("ascii") + b"\n\r\r"


# -- the lexer on its own -------------------------------------------------------------------------

_SYNTAX = {
    "WY": Syntax.BARE,
    "GO": Syntax.BARE,
    "AX": Syntax.BARE,
    "RP": Syntax.BARE,
    "MR": Syntax.REQUIRED,
    "VL": Syntax.REQUIRED,
    "MA": Syntax.OPTIONAL,
}


def lex(data: bytes) -> tuple[list[Command | Garbage], Lexer]:
    lexer = Lexer(lambda m: _SYNTAX.get(m, Syntax.UNKNOWN))
    out: list[Command | Garbage] = []
    for b in data:
        out.extend(lexer.feed(b))
    return out, lexer


def test_lexer_bare_command_completes_at_second_letter() -> None:
    lexer = Lexer(lambda m: _SYNTAX.get(m, Syntax.UNKNOWN))
    assert lexer.feed(ord("W")) == []
    assert not lexer.idle
    assert lexer.feed(ord("Y")) == [Command("WY", None, "WY")]
    assert lexer.idle


def test_lexer_lower_case_mnemonic_is_upper_cased() -> None:
    tokens, _ = lex(b"mr100 wy")
    assert tokens == [Command("MR", ("100",), "MR100"), Command("WY", None, "WY")]


@pytest.mark.parametrize("terminator", [b" ", b"\r", b"\n", b";", b"\t"])
def test_lexer_operand_ends_at_separator(terminator: bytes) -> None:
    tokens, lexer = lex(b"MR-25" + terminator)
    assert tokens == [Command("MR", ("-25",), "MR-25")]
    assert lexer.idle


def test_lexer_operand_ends_at_next_letter_which_starts_next_command() -> None:
    tokens, _ = lex(b"MR100GO")
    assert tokens == [Command("MR", ("100",), "MR100"), Command("GO", None, "GO")]


def test_lexer_operand_is_not_complete_without_terminator() -> None:
    tokens, lexer = lex(b"MR100")
    assert tokens == []
    assert not lexer.idle


def test_lexer_operand_command_without_operand() -> None:
    tokens, _ = lex(b"MR;")
    assert tokens == [Command("MR", None, "MR")]


def test_lexer_skipped_fields_and_early_semicolon() -> None:
    tokens, _ = lex(b"MR1,,3;")
    assert tokens == [Command("MR", ("1", None, "3"), "MR1,,3")]
    tokens, _ = lex(b"MR,10000,,1000;")
    assert tokens == [Command("MR", (None, "10000", None, "1000"), "MR,10000,,1000")]


def test_lexer_skips_spaces_after_comma_and_after_mnemonic() -> None:
    tokens, _ = lex(b"MR, -1000; MR1000, 2000 ; VL 5 ")
    assert [t.fields for t in tokens if isinstance(t, Command)] == [
        (None, "-1000"),
        ("1000", "2000"),
        ("5",),
    ]
    assert all(isinstance(t, Command) for t in tokens)


def test_lexer_space_ends_command_with_optional_operand() -> None:
    """ "The operand must immediately follow the command" (§6.1): after a mnemonic whose operand
    may be left out (MA, HM, AN ...) a space ends the command, so ``AX HM `` acts at once."""
    lexer = Lexer(lambda m: _SYNTAX.get(m, Syntax.UNKNOWN))
    for b in b"MA":
        assert lexer.feed(b) == []
    assert lexer.feed(ord(" ")) == [Command("MA", None, "MA")]
    assert lexer.idle
    tokens, _ = lex(b"MA-5 MA;")
    assert tokens == [Command("MA", ("-5",), "MA-5"), Command("MA", None, "MA")]


def test_lexer_space_after_number_ends_operand() -> None:
    """ "MR 5 6": the space after 5 ends the operand; the stray 6 is a bad word of its own."""
    tokens, _ = lex(b"MR 5 6 ")
    assert tokens[0] == Command("MR", ("5",), "MR 5")
    assert len(tokens) == 2
    assert isinstance(tokens[1], Garbage)
    assert tokens[1].kind is ErrorKind.BAD_CHARACTER


def test_lexer_unknown_pair_is_one_garbage_token_at_second_letter() -> None:
    lexer = Lexer(lambda m: _SYNTAX.get(m, Syntax.UNKNOWN))
    assert lexer.feed(ord("X")) == []
    assert lexer.feed(ord("Q")) == [Garbage("XQ", ErrorKind.UNKNOWN_COMMAND)]


def test_lexer_bad_word_gives_one_token_and_known_command_after_it_is_recognised() -> None:
    tokens, _ = lex(b"?KP")
    assert tokens == [Garbage("?", ErrorKind.BAD_CHARACTER)]
    tokens, _ = lex(b"XQWY")
    assert tokens == [Garbage("XQ", ErrorKind.UNKNOWN_COMMAND), Command("WY", None, "WY")]


def test_lexer_overlong_operand_is_bounded_and_flagged() -> None:
    """docs/decisions.md: "Numbers longer than 24 characters (leading zeros count) ... are an
    error when the command ends; memory stays bounded": the first 24 digits are kept."""
    tokens, _ = lex(b"MR" + b"1" * 30 + b" ")
    assert tokens == [Command("MR", ("1" * 24,), "MR" + "1" * 30, ErrorKind.OVERLONG)]
    assert MAX_FIELD == 24


def test_lexer_too_many_fields_is_flagged() -> None:
    """ "... or more than 16 fields": the first 16 are kept."""
    tokens, _ = lex(b"MR" + b"1," * (MAX_FIELDS + 4) + b"1;")
    assert tokens == [
        Command("MR", ("1",) * 16, "MR" + "1," * 20 + "1", ErrorKind.TOO_MANY_PARAMETERS)
    ]
    assert MAX_FIELDS == 16


def test_lexer_memory_is_bounded_on_endless_operand() -> None:
    """An overlong first number, then more commas than fields: the first error found is the one
    reported (the number), 24 digits and 16 fields are kept, and the text is cut at MAX_TEXT."""
    tokens, _ = lex(b"MR" + b"9" * 100_000 + b"," * 100_000 + b"-" * 50_000 + b";")
    fields = ("9" * 24,) + (None,) * 15
    assert tokens == [Command("MR", fields, ("MR" + "9" * 100_000)[:MAX_TEXT], ErrorKind.OVERLONG)]


def test_lexer_reset_drops_partial_command() -> None:
    lexer = Lexer(lambda m: _SYNTAX.get(m, Syntax.UNKNOWN))
    for b in b"MR12":
        lexer.feed(b)
    lexer.reset()
    assert lexer.idle
    out: list[Command | Garbage] = []
    for b in b"WY":
        out.extend(lexer.feed(b))
    assert out == [Command("WY", None, "WY")]


def test_protocol_modules_import_on_their_own() -> None:
    """The protocol layer must be importable without importing the board first (a server or a
    tool may want only the lexer)."""
    for module in ("omsd.protocol.lexer", "omsd.protocol.operands"):
        result = subprocess.run(
            [sys.executable, "-c", f"import {module}"],
            capture_output=True,
            text=True,
            cwd=Path(__file__).resolve().parents[2],
        )
        assert result.returncode == 0, f"import {module} failed:\n{result.stderr}"


# -- operands -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("0", Decimal(0)),
        ("100", Decimal(100)),
        ("+25", Decimal(25)),
        ("-2468", Decimal(-2468)),
        ("100.9", Decimal("100.9")),
        ("-5.9", Decimal("-5.9")),
        (".5", Decimal("0.5")),
        ("-.1", Decimal("-0.1")),
        ("5.", Decimal(5)),
    ],
)
def test_parse_number_accepts_signed_fixed_point(text: str, expected: Decimal) -> None:
    assert parse_number(text) == expected


@pytest.mark.parametrize("text", ["", "-", "+", ".", "1.2.3", "--5", "1-2", "+-3", "1..2", "-."])
def test_parse_number_rejects_malformed(text: str) -> None:
    with pytest.raises(OperandError) as info:
        parse_number(text)
    assert info.value.kind is ErrorKind.BAD_NUMBER


def test_parse_field_skipped_is_none() -> None:
    assert parse_field(None) is None
    assert parse_field("7") == Decimal(7)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("100.9", 100), ("-5.9", -5), ("0.99", 0), ("-0.99", 0), ("7", 7), ("-7", -7)],
)
def test_truncate_toward_zero(text: str, expected: int) -> None:
    assert truncate(Decimal(text)) == expected


def test_check_range_is_inclusive() -> None:
    check_range(1, 1, 32_000)
    check_range(32_000, 1, 32_000)
    for bad in (0, 32_001):
        with pytest.raises(OperandError) as info:
            check_range(bad, 1, 32_000)
        assert info.value.kind is ErrorKind.OUT_OF_RANGE


# -- parsing through the board --------------------------------------------------------------------


def test_lower_case_wy(pc48: Harness) -> None:
    assert pc48.query("wy") == WY4


def test_lower_case_ax_lp_rp(pc48: Harness) -> None:
    assert pc48.query("ax lp1000 rp") == value("1000")
    assert pc48.errors() == []


def test_lower_case_rs_resets(pc48: Harness) -> None:
    """ "ax lp1000 rs": the lower-case RS is a reset; INIT goes high (PC48 §6.5 RS)."""
    pc48.send("ax lp1000 rs")
    assert pc48.board.status_register(pc48.t) & INIT
    pc48.advance(0.5)
    assert pc48.query("RP") == value("0")
    assert pc48.errors() == []


def test_no_terminator_efic_aa_sa_aa_rp_one_reply(pc48: Harness) -> None:
    """EPICS drvOmsPC68 start-up string: one reply, one field per fitted axis."""
    assert pc48.query("EFICAA SAAA RP") == value("0,0,0,0")
    assert pc48.errors() == []


def test_no_terminator_lp600ax_qa_rp_byte_by_byte(pc48: Harness) -> None:
    """ "AX  LP600AX QA RP" one byte at a time: LP600 ends at the A of AX; QA answers at its A,
    RP at its P, and nothing else produces output."""
    text = b"AX  LP600AX QA RP"
    got: dict[int, bytes] = {}
    for i, b in enumerate(text):
        out = pc48.send(bytes([b]))
        if out:
            got[i] = out
    assert got == {text.index(b"QA") + 1: status("PNNN"), len(text) - 1: value("600")}
    assert pc48.errors() == []


_SCRIPT = (
    b"ax vl5000 AC20000;MR-1234\rGO ID AY MR 77;GO\nAZ mr+300 gd "
    b"AA MR100, ,300; GO RP AX QA RP wy AT VL2000 MA-2468;GO AA RQ"
)


def _play(pieces: list[bytes]) -> tuple[bytes, bytes, list[int], list[tuple[ErrorKind, str]]]:
    h = Harness("PC48-4")
    now = b"".join(h.send(p) for p in pieces)
    later = h.run()
    positions = [h.position(a) for a in "XYZT"]
    errors = [(e.kind, e.command) for e in h.errors()]
    return now, later, positions, errors


def test_split_reference_script_result() -> None:
    """The reference script for the split tests does what it says when sent whole."""
    now, later, positions, errors = _play([_SCRIPT])
    assert errors == []
    assert positions == [-1234 + 100, 77, 300 + 300, -2468]
    # RP, QA RP, WY, RQ at t = 0 (X's move starts, negative, at the t = 0 sample tick). RQ: X
    # holds its GO (4) + ID (1) + AA MR (2) + AA GO (5: Table A, no encoder); Y its GO (4) + AA
    # GO; Z its GD (5) + AA MR + AA GO; T waits at the AA GO (5) with VL (2), MA (2), GO (4)
    # behind it.
    assert now == (value("0,0,0,0") + status("MNNN") + value("0") + WY4 + value("188,191,188,187"))
    assert later == b""


@pytest.mark.parametrize("cut", range(1, len(_SCRIPT)))
def test_split_at_every_point_gives_same_result(cut: int) -> None:
    whole = _play([_SCRIPT])
    assert _play([_SCRIPT[:cut], _SCRIPT[cut:]]) == whole


def test_split_byte_by_byte_gives_same_result() -> None:
    whole = _play([_SCRIPT])
    assert _play([bytes([b]) for b in _SCRIPT]) == whole


def test_split_in_three_at_every_pair_of_points_in_aa_list() -> None:
    text = b"AA MR1, -20,,4000;GO"
    whole = _play([text])
    assert whole[2] == [1, -20, 0, 4000]
    for i in range(1, len(text)):
        for j in range(i + 1, len(text)):
            assert _play([text[:i], text[i:j], text[j:]]) == whole, (i, j)


@pytest.mark.parametrize("terminator", [" ", "\r", "\n", ";", ""])
def test_number_ends_at_space_cr_lf_semicolon_or_letter(pc48: Harness, terminator: str) -> None:
    pc48.send(f"MR25{terminator}GO")
    pc48.run()
    assert pc48.query("RP") == value("25")
    assert pc48.errors() == []


@pytest.mark.parametrize(
    ("move", "expected"),
    [("MR+25", 25), ("MR-25", -25), ("MA-2468", -2468), ("MR100.9", 100), ("MR-5.9", -5)],
)
def test_signed_and_fractional_moves(pc48: Harness, move: str, expected: int) -> None:
    """Signed integers; "MR100.9" moves 100 and "MR-5.9" moves -5 (truncated toward zero,
    shared/interop/README.md)."""
    pc48.send(f"{move};GO")
    pc48.run()
    assert pc48.query("RP") == value(str(expected))
    assert pc48.errors() == []


def test_user_units_mr_3_5_revolutions_is_7000_steps(pc48: Harness) -> None:
    """PC48 §6.13 RU example: AZ UU2000; LP0; MR3.5; GO ... RU gives 3.50000."""
    pc48.send("AZ UU2000; LP0; MR3.5; GO")
    pc48.run()
    assert pc48.query("RP") == value("7000")
    assert pc48.query("RU") == value("3.50000")


def test_user_units_vl_point_one_with_uu10000(pc48: Harness) -> None:
    """PC48 §6.10 WH example: AX UU10000 ... AX VL.1; AC10; (0.1 inch/s at 10000 steps/inch)."""
    pc48.send("AX UU10000 VL.1; AC10;")
    pc48.run()
    assert pc48.axis("X").vl == 1000
    assert pc48.axis("X").ac == 100_000
    assert pc48.errors() == []


def test_user_units_aa_fraction_field(pc48: Harness) -> None:
    """PC48 §6.10 WH example: with UU10000 on Z, "MA,,.5; GO" is a half-inch (5000 step) move."""
    pc48.send("AZ UU10000 AA MA,,.5; GO")
    pc48.run()
    assert pc48.query("RP") == value("0,0,5000,0")


@pytest.mark.parametrize(
    ("command", "expected"),
    [
        ("MR,10000,,1000; GO", "0,10000,0,1000"),
        ("MR12345,6789; GO", "12345,6789,0,0"),
        ("MR1000, 2000, 3000, 4000; GO", "1000,2000,3000,4000"),
        ("MR, -1000; GO", "0,-1000,0,0"),
        ("MR ,,,7;GO", "0,0,0,7"),
        ("MR5,6\rGO", "5,6,0,0"),
        ("MR1,2,3,4,5,6,7,8,9; GO", "1,2,3,4"),
    ],
)
def test_aa_lists(pc48: Harness, command: str, expected: str) -> None:
    """AA syntax (PC48 §6.1): skipped fields, early ';', spaces after commas, fields beyond the
    fitted axes ignored (E55 gives nine fields)."""
    pc48.send("AA " + command)
    pc48.run()
    assert pc48.query("RP") == value(expected)
    assert pc48.errors() == []


def test_aa_nine_velocity_fields_on_four_axis_board(pc48: Harness) -> None:
    """E55: AA VL100,100,100,100,100,100,100,100,100; on a board with fewer axes."""
    pc48.send("AA VL100,100,100,100,100,100,100,100,100;")
    pc48.run()
    assert [pc48.axis(a).vl for a in "XYZT"] == [100, 100, 100, 100]
    assert pc48.errors() == []


def test_space_after_mnemonic(pc48: Harness) -> None:
    """The manual's own examples write "AY JG 12345"."""
    pc48.send("AY JG 12345\r")
    pc48.advance(1.0)
    assert pc48.query("RV") == value("12345")
    pc48.send("AX MR 77 GO")
    pc48.run(limit=1.0)
    assert pc48.position("X") == 77
    assert pc48.errors() == []


# -- replay of the EPICS drvOmsPC68 trace ---------------------------------------------------------

TRACE = Path(__file__).resolve().parents[3] / "shared" / "interop" / "epics-drvOmsPC68.trace"

# The RX side of the trace, times relative to the first line (the file is checked against this
# copy when it is present).
RX: list[tuple[float, bytes]] = [
    (0.000, b"WY"),
    (0.000, b"EFICAA SAAA RP"),
    (0.001, b"AX EA"),
    (0.001, b"AX ?KP"),
    (0.001, b"AY EA"),
    (0.001, b"AY ?KP"),
    (0.001, b"AZ EA"),
    (0.001, b"AZ ?KP"),
    (0.001, b"AT EA"),
    (0.001, b"AT ?KP"),
    (0.001, b"AA RP"),
    (0.001, b"AX QA RP"),
    (0.001, b"AY QA RP"),
    (0.001, b"AZ QA RP"),
    (0.001, b"AT QA RP"),
    (4.987, b"AX  VL1000 VB100 AC1800 MA600 GD ID"),
    (5.087, b"AX QA RP"),
    (5.187, b"AX QA RP"),
    (8.988, b"AX  VB100 AC2000 CA JG-1000;"),
    (9.088, b"AX QA RP"),
    (9.990, b"AX QA RP"),
    (11.992, b"AX  VL101 VB100 AC200 CA HM0 GD ID"),
    (12.091, b"AX QA RP"),
    (12.993, b"AX  AC1800 ST ID"),
    (14.994, b"AX  LP600AX QA RP"),
]

_QUERIES = re.compile(rb"WY|RP|QA|EA|RQ")


def test_trace_copy_matches_file() -> None:
    if not TRACE.exists():
        pytest.skip(
            f"{TRACE} is absent: the interop traces are kept in ../shared beside the repository,"
            " not in a clone of it"
        )
    rx: list[tuple[float, bytes]] = []
    t0: float | None = None
    for line in TRACE.read_text().splitlines():
        parts = line.split(" ", 2)
        if len(parts) < 3 or parts[1] != "RX":
            continue
        t = float(parts[0])
        t0 = t if t0 is None else t0
        rx.append((round(t - t0, 3), ast.literal_eval(parts[2])))
    assert rx == RX


def _replay(h: Harness, upto: int) -> list[tuple[bytes, list[CommandErrorEvent]]]:
    out = []
    for t, data in RX[:upto]:
        h.until(t)
        out.append((h.send(data), h.errors()))
    return out


def test_trace_every_reply_is_framed_and_counted() -> None:
    """Every reply is `\\n\\r<v>\\n\\r` or `\\n\\r\\r<s>\\n\\r\\r`; one frame per query the board
    understands (EA is a command error on a PC48-4 and gives none)."""
    h = Harness("PC48-4")
    for (_, data), (reply, _) in zip(RX, _replay(h, len(RX)), strict=True):
        fr = frames(reply)
        expected = [m for m in _QUERIES.findall(data) if m != b"EA"]
        assert len(fr) == len(expected), (data, reply)
        for (kind, _), query in zip(fr, expected, strict=True):
            assert kind == ("status" if query == b"QA" else "value"), (data, reply)


def test_trace_ea_and_kp_are_one_command_error_each() -> None:
    """drvOmsPC68 learns "no encoder" from EA and "no servo" from ?KP: each must be exactly one
    command error (CMD_S) and no reply bytes on a PC48-4."""
    h = Harness("PC48-4")
    results = _replay(h, 2)
    for t, data in RX[2:10]:
        h.until(t)
        h.board.read_status_register(h.t)
        reply = h.send(data)
        errors = [(e.kind, e.command) for e in h.errors()]
        assert reply == b"", data
        if data.endswith(b"EA"):  # "AX - AT  NO ENCODER  Not valid"
            assert errors == [(ErrorKind.NO_ENCODER, "EA")], data
        else:  # "?" cannot start a command; the KP after it is swallowed with it
            assert errors == [(ErrorKind.BAD_CHARACTER, "?")], data
        assert h.board.read_status_register(h.t) & CMD_S, data
        assert not h.board.read_status_register(h.t) & CMD_S, data
    assert results[0][0] == WY4


def test_trace_ea_answers_on_encoder_board_and_kp_still_errors() -> None:
    h = Harness("PC48-4E")
    assert h.send("AX EA") == status("DDNNNN")
    assert h.errors() == []
    assert h.send("AX ?KP") == b""
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.BAD_CHARACTER, "?")]


def test_trace_replies_follow_the_manual_up_to_the_jog() -> None:
    """Exact replies, line by line, up to the jog (before the HM). Derivations (linear ramps,
    PC48 §1.3; moves start at the first 1/2048 s tick at or after the command):

    * MA600 with VL1000 VB100 AC1800 starts at tick 10214 (4.98730 s): 0.5 s ramp of 275 steps,
      50 steps cruise, 275 down: 1.05 s. RP at 5.087 = floor(100 t + 900 t^2) at t = 0.09970
      = 18; at 5.187, t = 0.19970: 55.
    * JG-1000 at AC2000 (VB does not apply to JG) starts at tick 18408 (8.98828 s); at 9.088 it
      has moved 9.94 steps: counter 591; at 9.990 it has moved 250 + 501.7 steps: -151. QA shows
      M (moving negative) and N (CA cleared the done flag).
    """
    h = Harness("PC48-4")
    results = _replay(h, 21)
    expected: list[bytes] = [
        WY4,
        value("0,0,0,0"),
        *[b""] * 8,
        value("0,0,0,0"),
        *[status("PNNN") + value("0")] * 4,
        b"",
        status("PNNN") + value("18"),
        status("PNNN") + value("55"),
        b"",
        status("MNNN") + value("591"),
        status("MNNN") + value("-151"),
    ]
    assert [r for r, _ in results] == expected
    assert [len(e) for _, e in results] == [0, 0, *[1] * 8, *[0] * 11]


def test_trace_ma600_ends_at_600_with_done_after_id() -> None:
    """Probes (QA RP, side-effect free) between trace lines: the move of line 16 ends at the
    tick at or after 4.98730 + 1.05 = 6.03730 s, at 600, and the ID then sets D and the done
    flag register bit of X."""
    h = Harness("PC48-4")
    _replay(h, 18)
    h.board.read_done_register(h.t)
    h.until(6.03)
    assert h.send("AX QA RP") == status("PNNN") + value("599")
    h.until(6.04)
    assert h.send("AX QA RP") == status("PDNN") + value("600")
    assert h.board.read_done_register(h.t) == 0b0001
    h.until(8.9)
    assert h.send("AX QA RP") == status("PDNN") + value("600")


def test_trace_home_after_jog_positions() -> None:
    """HM0 is executed while the jog runs at -1000 (JG is up to speed, so the queue goes on):
    the axis ramps toward +101 at AC200. At 12.091 it has decelerated for 0.0988 s from the
    tick 11.99219 at -2153.9: -2251. ST at 12.993 flushes the queue (AC1800 entered before it is
    still in the queue and is flushed with the HM) and decelerates at the AC200 in force from
    -799.8 steps/s: at 14.994 the axis is at -4254. LP600 is queued (PC48 §6.7 LP table) behind
    the ST, so RP still shows -4254; when the stop ends (16.992) the ID sets D and LP loads 600.
    """
    h = Harness("PC48-4")
    results = _replay(h, len(RX))
    assert frames(results[22][0])[1] == ("value", "-2251")
    assert frames(results[24][0])[1] == ("value", "-4254")
    h.run()
    assert h.send("AX RP") == value("600")
    assert 16.99 < h.t < 17.0


def test_trace_direction_while_reversing_from_jog_to_home() -> None:
    """RA/QA char 4: "P Moving in positive direction / M Moving in negative direction"; design
    decision: the last direction of motion. After HM0 the axis is still moving negative (from
    -1000 toward +101 at AC200 it would take 5 s to reverse) and ST stops it before it ever
    moves positive, so char 4 must be M throughout, and M after it stops."""
    probe = Harness("PC48-4")
    _replay(probe, 23)
    assert probe.send("AX RV") == value("-980")
    h = Harness("PC48-4")
    results = _replay(h, len(RX))
    assert frames(results[22][0])[0] == ("status", "MNNN")
    assert frames(results[24][0])[0] == ("status", "MNNN")
    h.run()
    assert h.send("AX QA") == status("MDNN")
