"""Bad input (PC48 §6.1, §6.5 EN, Table 3-8 CMD_S).

CMD_S: "An unrecognizable command has been detected or LS and LE commands are not in [matched]
pairs." EN: "This mode also outputs an English readable error message to the host". Design
decisions: one command error (CMD_S|DON_S in status, a CommandErrorEvent) per bad word; the
board keeps working; a "Not valid" cell of a queue table is a command error; with EN the error
also prints ``\\n\\r<English message>: <command text>\\n\\r``.

The board never raises, whatever it is fed, and its memory stays bounded.
"""

from __future__ import annotations

import math
import random
import tracemalloc

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from omsd.board import AxisWorld
from omsd.board.board import Board
from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.engine.registers import CMD_S, DON_S
from omsd.models import get_model
from omsd.models.pc48 import PC48_COMMANDS
from omsd.models.pcix import PCIX_COMMANDS

WY = {
    "PC48-4": b"\n\rPC48 ver 3.00-4\n\r",
    "PC48-4E": b"\n\rPC48 ver 3.00-4\n\r",
    "PC48-6E": b"\n\rPC48 ver 3.00-6\n\r",
    "PC48-8": b"\n\rPC48 ver 3.00-8\n\r",
}


def one_error(
    model: str, setup: str, word: str | bytes, kind: ErrorKind | None, after: str = "AX WY"
) -> tuple[Harness, bytes]:
    """Send ``word`` after ``setup``; check exactly one command error of ``kind``, CMD_S set and
    cleared by reading the status register, and that the board still answers WY."""
    h = Harness(model)
    h.send(setup)
    assert h.errors() == [], setup
    h.board.read_status_register(h.t)
    out = h.send(word)
    errors = h.errors()
    assert len(errors) == 1, (word, errors)
    if kind is not None:
        assert errors[0].kind is kind, (word, errors[0])
    assert h.board.status_register(h.t) & (CMD_S | DON_S) == CMD_S | DON_S
    assert h.board.read_status_register(h.t) & CMD_S
    assert not h.board.read_status_register(h.t) & CMD_S
    assert h.query(after) == WY[model]
    assert h.errors() == []
    return h, out


# -- unknown and malformed ------------------------------------------------------------------------

UNKNOWN = ["XQ ", "ZZ;", "QQ", "A1 ", "KP ", "?KP ", "PL ", "* "]


@pytest.mark.parametrize("word", UNKNOWN)
def test_unknown_word_is_one_error(word: str) -> None:
    _, out = one_error("PC48-4", "", word, None)
    assert out == b""


@pytest.mark.parametrize("word", ["MR1.2.3 ", "VL- ", "AC--5 ", "MR1-2 ", "VL+-3 ", "MR. "])
def test_malformed_number_is_one_error_and_changes_nothing(word: str) -> None:
    h, _ = one_error("PC48-4", "", word, ErrorKind.BAD_NUMBER)
    h.send("GO")
    h.run()
    assert h.position("X") == 0
    assert h.axis("X").vl == 100_000
    assert h.axis("X").ac == 1_000_000


def test_board_keeps_working_after_a_bad_number(pc48: Harness) -> None:
    pc48.send("VL- MR5 GO")
    pc48.run()
    assert pc48.position("X") == 5
    assert [(e.kind, e.command) for e in pc48.errors()] == [(ErrorKind.BAD_NUMBER, "VL-")]


OUT_OF_RANGE = [
    ("PC48-4", "VL0 "),
    ("PC48-4", "VL1044001 "),
    ("PC48-4", "VL-5 "),
    ("PC48-4", "AC0 "),
    ("PC48-4", "AC8000000 "),
    ("PC48-4", "AC-5 "),
    ("PC48-4", "LS0 "),
    ("PC48-4", "LS32001 "),
    ("PC48-4", "WT0 "),
    ("PC48-4", "WT32001 "),
    ("PC48-4", "RM0 "),
    ("PC48-4", "RM65000 "),
    ("PC48-4", "LP33554432 "),
    ("PC48-4", "LP-33554432 "),
    ("PC48-4", "BL14 "),
    ("PC48-4", "BH14 "),
    ("PC48-4", "SE1001 "),
    ("PC48-4E", "HG0 "),
    ("PC48-4E", "HG32001 "),
]


@pytest.mark.parametrize(("model", "word"), OUT_OF_RANGE)
def test_out_of_range_is_one_error(model: str, word: str) -> None:
    h, _ = one_error(model, "", word, ErrorKind.OUT_OF_RANGE)
    assert h.axis("X").vl == 100_000
    assert h.axis("X").ac == 1_000_000
    assert h.query("RQ") == b"\n\r200\n\r"


@pytest.mark.parametrize(
    "word",
    [
        *("VL1044000 ", "AC7999999 ", "LS32000 ", "LS1 ", "WT1 ", "WT32000 ", "RM64999 "),
        *("RM1 ", "LP33554431 ", "LP-33554431 ", "BL13 ", "BL8 ", "SE1000 ", "VB0 "),
        *("PN11 ", "PN "),
    ],
)
def test_limits_of_range_are_accepted(pc48: Harness, word: str) -> None:
    """The manual's bounds themselves are valid; VB0 turns the base velocity off; PN outside
    3..10 "defaults to 70% or 3 steps" (no error)."""
    pc48.send(word)
    assert pc48.errors() == []
    assert not pc48.board.status_register(pc48.t) & CMD_S


def test_vl_and_ac_bounds_set_the_registers(pc48: Harness) -> None:
    pc48.send("VL1044000 AC7999999;")
    pc48.run()
    assert pc48.axis("X").vl == 1_044_000
    assert pc48.axis("X").ac == 7_999_999


def test_bl_on_an_input_bit_is_one_error() -> None:
    """BL: "this is only valid for bits which have been configured as outputs" (factory: bits
    8-13 are outputs, RB 003F00)."""
    one_error("PC48-4", "", "BL3 ", ErrorKind.NOT_AN_OUTPUT)
    h, _ = one_error("PC48-4", "", "BH0 ", ErrorKind.NOT_AN_OUTPUT)
    assert h.board.outputs_low == 0


# -- not valid in this mode -----------------------------------------------------------------------

NOT_VALID = [
    ("AA", "RA"),
    ("AA", "QA"),
    ("AX", "RI"),
    ("AX", "QI"),
    ("AX", "ML5 "),
    ("AX", "MT5 "),
    ("AA", "EN"),
    ("AA", "EF"),
    ("AA", "CA"),
    ("AA", "UU5 "),
    ("AA", "LP5 "),
    ("AA", "JG5 "),
    ("AA", "HM5 "),
    ("AA", "RB"),
    ("AA", "RU"),
    ("AX", "WA"),
    ("AY", "VS1,1,1 "),
    ("AX", "CD0,0;"),
    ("AX", "CV500 "),
    ("AX", "CX"),
    ("AA", "CN"),
    # contour commands outside a contour definition
    ("AX", "CE"),
    ("AX", "CK"),
    ("AX", "CR0,100,3.14 "),
    ("AA", "CE"),
    ("AA", "CK"),
    ("AA", "CR0,100,3.14 "),
    # AA/CD: not valid inside a contour definition
    ("AA CD0,0;", "CV500 "),
    ("AA CD0,0;", "GO"),
    ("AA CD0,0;", "LS2 "),
    ("AA CD0,0;", "MR5,5;"),
]


@pytest.mark.parametrize(("setup", "word"), NOT_VALID)
def test_command_not_valid_in_mode_is_one_error(setup: str, word: str) -> None:
    # WY and AX are not valid inside a contour definition: end it first
    after = "CE AX WY" if "CD" in setup else "AX WY"
    one_error("PC48-4", setup, word, ErrorKind.NOT_VALID_IN_MODE, after)


def test_cx_without_contour_is_one_error() -> None:
    one_error("PC48-4", "AA", "CX", ErrorKind.NO_CONTOUR)


def test_mo_on_encoder_model_is_one_error() -> None:
    """MO: "This command is not available in models with an encoder option"."""
    h, _ = one_error("PC48-4E", "", "MO", None)
    h.run()
    assert h.position("X") == 0


ENCODER_COMMANDS = [
    "ER1,1 ",
    "HV100 ",
    "HG5 ",
    "HD5 ",
    "HF",
    "HN",
    "ES5 ",
    "IS",
    "ET",
    "HE",
    "HS",
    "EA",
    "RE",
    "IP",
    "RL",
]


@pytest.mark.parametrize("word", ENCODER_COMMANDS)
def test_encoder_command_on_open_loop_board_is_one_error(word: str) -> None:
    """Encoder tables: "AX - AT  NO ENCODER Not valid"."""
    _, out = one_error("PC48-4", "AY", word, ErrorKind.NO_ENCODER)
    assert out == b""


@pytest.mark.parametrize("word", ENCODER_COMMANDS)
def test_encoder_command_on_u_of_pc48_6e_is_one_error(word: str) -> None:
    """Encoder tables: "AU - AS Not valid"."""
    _, out = one_error("PC48-6E", "AU", word, None)
    assert out == b""


def test_rl_on_an_open_loop_board_is_one_error_in_single_axis_mode_alone() -> None:
    """RL's queue table: "AX - AT  Not valid  Immediate", and one cell "Immediate" across both
    columns for "AA,AM" (as IS's one "Not valid" spans both): without encoders, RL in AA mode
    answers an N for each axis ("The number of characters returned corresponds to the number of
    axes available on the board"); until 2026-11-27 it was an error here too."""
    one_error("PC48-4", "AX", "RL", ErrorKind.NO_ENCODER)
    h = Harness("PC48-4")
    assert h.send("AA RL") == b"\n\rNNNN\n\r" and h.errors() == []


@pytest.mark.parametrize("word", ["AU", "AV", "AR", "AS"])
def test_selecting_an_axis_not_fitted_is_one_error(word: str) -> None:
    """AU on a PC48-4: there is no U axis. The context stays on the previous axis."""
    h, _ = one_error("PC48-4", "AY", word, ErrorKind.NO_SUCH_AXIS)
    h.send("AY")
    h.send(word + " MR5 GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [0, 5, 0, 0]


def test_axis_r_on_pc48_6_is_an_error_but_u_is_not() -> None:
    one_error("PC48-6E", "", "AR", ErrorKind.NO_SUCH_AXIS)
    h = Harness("PC48-6E")
    h.send("AU")
    assert h.errors() == []


# -- loops ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("setup", "word"),
    [
        ("", "LE"),
        ("", "WD"),
        ("", "WG"),
        ("AX LS2", "AY LE"),
        ("AX LS2", "AA LE"),
        ("AA LS2", "AX LE"),
        ("AX WS1", "LE"),
        ("AX LS2", "WG"),
        ("AX WH", "WD"),
        ("AX LS2 LS2 LS2 LS2", "LS2 "),
        ("AX WH", "WH"),
    ],
)
def test_unmatched_loops_are_one_error(setup: str, word: str) -> None:
    one_error("PC48-4", setup, word, None)


# -- overlong, control characters, bytes >= 0x80 --------------------------------------------------


@pytest.mark.parametrize(
    "word",
    [
        "MR" + "1" * 30 + " ",
        "VL" + "9" * 30 + " ",
        "MR-" + "7" * 30 + ".5 ",
        "AA MR" + "1" * 30 + ",5;",
    ],
)
def test_overlong_number_is_one_error(word: str) -> None:
    h, _ = one_error("PC48-4", "", word, None)
    h.send("AX GO")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [0, 0, 0, 0]
    assert h.axis("X").vl == 100_000


CONTROL = [c for c in range(0x20) if c not in (0x04, 0x09, 0x0A, 0x0D, 0x19)] + [0x7F]


@pytest.mark.parametrize("byte", CONTROL)
def test_control_character_is_one_error(byte: int) -> None:
    _, out = one_error("PC48-4", "", bytes([byte, 0x20]), None)
    assert out == b""


@pytest.mark.parametrize("byte", [0x80, 0x9B, 0xA0, 0xC3, 0xE9, 0xFE, 0xFF])
def test_byte_above_7f_is_one_error(byte: int) -> None:
    _, out = one_error("PC48-4", "", bytes([byte, 0x20]), None)
    assert out == b""


@pytest.mark.parametrize(
    "word", [b"W\xffY ", b"W\x01Y ", b"\xc3\xa9\xc3\xa9 ", b"\x80\x81\x82\x83 "]
)
def test_bad_byte_inside_a_word_is_one_error(word: bytes) -> None:
    h, out = one_error("PC48-4", "", word, None)
    assert out == b""
    h.send("GO")
    h.run()
    assert h.position("X") == 0


@pytest.mark.parametrize("sep", [b" ", b";", b"\r", b"\n"])
def test_bad_word_ends_at_separator_and_next_command_runs(pc48: Harness, sep: bytes) -> None:
    assert pc48.query(b"XQ12,3" + sep + b"WY") == WY["PC48-4"]
    assert [(e.kind, e.command) for e in pc48.errors()] == [(ErrorKind.UNKNOWN_COMMAND, "XQ")]


# -- EN: echo and English error messages ----------------------------------------------------------


@pytest.mark.parametrize(
    ("word", "kind", "text"),
    [
        ("XQ ", ErrorKind.UNKNOWN_COMMAND, "XQ"),
        ("VL0 ", ErrorKind.OUT_OF_RANGE, "VL0"),
        ("MR1.2.3;", ErrorKind.BAD_NUMBER, "MR1.2.3"),
        ("RI", ErrorKind.NOT_VALID_IN_MODE, "RI"),
        ("LE", ErrorKind.LOOP_MISMATCH, "LE"),
        ("AU", ErrorKind.NO_SUCH_AXIS, "AU"),
        ("EA", ErrorKind.NO_ENCODER, "EA"),
        ("BL3 ", ErrorKind.NOT_AN_OUTPUT, "BL3"),
    ],
)
def test_echo_on_prints_english_error_message(word: str, kind: ErrorKind, text: str) -> None:
    """With EN every character taken is echoed and a command error also prints
    ``\\n\\r<message>: <command>\\n\\r`` (design decision; PC48 §6.5 EN)."""
    h = Harness("PC48-4")
    assert h.send("EN") == b""
    out = h.send(word)
    message = b"\n\r" + kind.message.encode("ascii") + b": " + text.encode("ascii") + b"\n\r"
    assert out.count(message) == 1, out
    assert out.replace(message, b"", 1) == word.encode("ascii")
    assert [(e.kind, e.command) for e in h.errors()] == [(kind, text)]
    assert h.send("WY") == b"WY" + WY["PC48-4"]


def test_echo_off_prints_no_message(pc48: Harness) -> None:
    assert pc48.send("XQ VL0 LE ") == b""
    assert [(e.kind, e.command) for e in pc48.errors()] == [
        (ErrorKind.UNKNOWN_COMMAND, "XQ"),
        (ErrorKind.OUT_OF_RANGE, "VL0"),  # VL "must be greater than zero"
        (ErrorKind.LOOP_MISMATCH, "LE"),  # no LS: "not in [matched] pairs"
    ]


def test_each_bad_word_in_a_stream_is_one_error(pc48: Harness) -> None:
    pc48.board.read_status_register(pc48.t)
    out = pc48.send("XQ MR1.2.3 VL0 WY ?KP AA RA AX LE \x01 \xff RP")
    assert out == WY["PC48-4"] + b"\n\r0\n\r"
    assert [(e.kind, e.command) for e in pc48.errors()] == [
        (ErrorKind.UNKNOWN_COMMAND, "XQ"),
        (ErrorKind.BAD_NUMBER, "MR1.2.3"),
        (ErrorKind.OUT_OF_RANGE, "VL0"),
        (ErrorKind.BAD_CHARACTER, "?"),  # "?" cannot start a command; KP is swallowed with it
        (ErrorKind.NOT_VALID_IN_MODE, "RA"),  # RA: "AA,AM Not valid"
        (ErrorKind.LOOP_MISMATCH, "LE"),
        (ErrorKind.BAD_CHARACTER, "<01>"),
        (ErrorKind.BAD_CHARACTER, "<FF>"),
    ]
    assert pc48.board.read_status_register(pc48.t) & CMD_S
    assert not pc48.board.read_status_register(pc48.t) & CMD_S


# -- floods and random streams --------------------------------------------------------------------


def deliver(board: Board, data: bytes, t: float, patience: float = 200.0) -> tuple[float, int]:
    """A host writing ``data``: what the board does not take is offered again later; after
    ``patience`` seconds without progress the rest is dropped (a host write timeout). Output is
    read as it comes. Returns the time and the number of bytes dropped."""
    pos = 0
    wait = 0.001
    waited = 0.0
    while pos < len(data):
        n = board.receive(data[pos:], t)
        board.take_output()
        pos += n
        if pos >= len(data):
            break
        if n:
            wait, waited = 0.001, 0.0
        if waited > patience:
            break
        t += wait
        waited += wait
        wait = min(wait * 2, 20.0)
    return t, len(data) - pos


def recover_and_ask_wy(board: Board, t: float, model: str = "PC48-4") -> None:
    """Control-D, then AX EF (EF is not valid in AA, so AX first), then WY must answer exactly.
    RS may have left INIT high for 0.1 s, so time is let pass before reading."""
    t, dropped = deliver(board, b"\x04", t)
    assert dropped == 0, "Control-D not taken"
    t, dropped = deliver(board, b"AX EF AX", t + 0.001)
    assert dropped == 0
    board.advance(t + 0.5)
    board.take_output()
    assert board.receive(b"WY", t + 0.5) == 2
    board.advance(t + 0.6)
    assert board.take_bytes() == WY[model]


def test_random_megabyte_never_raises_and_memory_stays_bounded() -> None:
    """1 MB of seeded random bytes in 256-byte chunks, 1 ms apart (longer while the board holds
    the host off). Nothing raises, the input buffer never exceeds 124 characters, memory does
    not grow with the amount fed, and afterwards the board answers WY."""
    rng = random.Random(20240531)
    data = rng.randbytes(1 << 20)
    board = Board(get_model("PC48-4"), now=0.0)
    tracemalloc.start()
    try:
        baseline = tracemalloc.get_traced_memory()[0]
        t = 0.0
        for start in range(0, len(data), 256):
            t = deliver(board, data[start : start + 256], t)[0] + 0.001
            assert len(board.interpreter.buffer) <= 124
            assert all(0 <= a.queue.free <= 200 for a in board.axes)
        grown = tracemalloc.get_traced_memory()[0] - baseline
    finally:
        tracemalloc.stop()
    assert grown < 2_000_000, grown
    recover_and_ask_wy(board, t)


@pytest.mark.parametrize(
    ("setup", "word"),
    [("AA VL1000,1000,1000,1000; MR1000000,1000000,1000000,1000000; GO", "WA "), ("AX", "SW3 ")],
)
def test_flood_of_zero_slot_waits_keeps_memory_bounded(setup: str, word: str) -> None:
    """WA and SW take no queue slots ("Immediate" in their tables) but make the queue wait.
    A host that sends them 100,000 times behind a long move (or with the SW input low) must not
    make the board's memory grow without bound: either they are bounded by the queue or the
    board holds the host off."""
    board = Board(get_model("PC48-4"), now=0.0)
    board.set_input(3, False, 0.0)
    board.receive(setup.encode("ascii"), 0.0)
    chunk = word.encode("ascii") * 1000
    tracemalloc.start()
    try:
        baseline = tracemalloc.get_traced_memory()[0]
        t = 0.0
        for _ in range(100):
            board.receive(chunk, t)
            board.take_output()
            t += 0.001
        grown = tracemalloc.get_traced_memory()[0] - baseline
    finally:
        tracemalloc.stop()
    assert grown < 2_000_000, grown
    assert all(0 <= a.queue.free <= 200 for a in board.axes)


def test_control_d_recovers_from_endless_garbage_inside_a_command() -> None:
    board = Board(get_model("PC48-4"), now=0.0)
    t, dropped = deliver(board, b"MR" + b"1" * 200_000, 0.0)
    assert dropped == 0
    t, dropped = deliver(board, b"," * 100_000 + b"-" * 100_000, t)
    assert dropped == 0
    recover_and_ask_wy(board, t)


# -- property-based -------------------------------------------------------------------------------

_MNEMONICS = [*sorted(PC48_COMMANDS), "XQ", "ZZ", "KP"]
_PIECES = st.one_of(
    st.sampled_from(_MNEMONICS),
    st.sampled_from(["0", "1", "-5", "+7", ".5", "100.9", "2000", "-33554432", "99999999"]),
    st.sampled_from([",", ";", " ", "\r", "\n", "\t", "?", "*", "\x00", "\x19", "\xff"]),
    st.integers(min_value=-10_000_000, max_value=10_000_000).map(str),
)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.binary(max_size=2000), st.sampled_from(["PC48-4", "PC48-4E", "PC48-6E", "PC48-8"]))
def test_any_bytes_never_raise_and_wy_still_answers(data: bytes, model: str) -> None:
    board = Board(get_model(model), now=0.0)
    t, _ = deliver(board, data, 0.0)
    board.advance(t + 1.0)
    recover_and_ask_wy(board, t + 1.0, model)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(_PIECES, min_size=10, max_size=120),
    st.sampled_from(["PC48-4", "PC48-4E", "PC48-6E"]),
)
# an encoder home search that can never find its index made the next crossing infinite
@example(["AC", "AC", "HE", "HM", "AA", "AA", "AA", "AA", "AA", "AA"], "PC48-4E")
def test_any_command_soup_never_raises_and_wy_still_answers(pieces: list[str], model: str) -> None:
    """Streams made of real mnemonics, numbers and separators reach much deeper into the
    interpreter than random bytes."""
    board = Board(get_model(model), now=0.0)
    data = "".join(pieces).encode("latin-1")
    t = 0.0
    for start in range(0, len(data), 7):
        t = deliver(board, data[start : start + 7], t)[0] + 0.01
    board.advance(t + 1.0)
    recover_and_ask_wy(board, t + 1.0, model)


_PCIX_PIECES = st.one_of(
    st.sampled_from(sorted(PCIX_COMMANDS)),
    st.sampled_from(["0", "1", "-5", "+7", ".5", "100.9", "2000", "-33554432", "99999999", "ff"]),
    st.sampled_from([",", ";", " ", "\r", "\n", "?", "*", "^", "\x00", "\x19", "\x1a", "\xff"]),
    st.integers(min_value=-10_000_000, max_value=10_000_000).map(str),
)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(_PCIX_PIECES, min_size=10, max_size=120),
    st.sampled_from(["PCIX-400", "PCIX-202", "PCIX-040", "PCIX-004"]),
)
def test_any_pcix_command_soup_never_raises_and_wy_still_answers(
    pieces: list[str], model: str
) -> None:
    """The PCIx's own language: three-letter mnemonics, ?XX queries, macros (MD ... ^Z),
    ramp tables (DAR ... DAE), servo gains. After Control-D (which also ends a macro definition
    being received) and ^Z, DAE for a table left open, the board answers WY."""
    board = Board(get_model(model), now=0.0)
    data = "".join(pieces).encode("latin-1")
    t = 0.0
    for start in range(0, len(data), 7):
        t = deliver(board, data[start : start + 7], t)[0] + 0.01
    board.advance(t + 1.0)
    t, dropped = deliver(board, b"\x04 DAE; AX;", t + 1.0)
    assert dropped == 0
    board.advance(t + 0.5)
    board.take_output()
    assert board.receive(b"WY;", t + 0.5) == 3
    board.advance(t + 0.6)
    # the WY page: "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems", text<LF><CR>
    assert board.take_bytes() == f"{model} ver:1.26, s/n:000217 - Oregon Micro Systems\n\r".encode()


@pytest.mark.parametrize(
    ("line", "error"),
    [
        ("AA;AN,99999999999;", True),  # flag parameters "can be any numeric value" ... 32-bit
        ("AA;AN,2147483647;", False),
        ("AA;AN,-2147483648;", False),
        ("AA;AN,-2147483649;", True),
        ("AX;PA5000000000;", True),
        ("AX;KP21474836.48;", True),  # in 32 bits without the point, but above KP's range
        ("AX;KP2147.483648;", True),  # 2147483648 without the point: 33 bits
    ],
)
def test_pcix_numbers_beyond_32_bits_are_command_errors(line: str, error: bool) -> None:
    """PCIx §5.1: "Entering parameter values outside the range of a signed 32-bit integer will
    cause a Command Error"; "For fixed point numeric parameters, the value without the decimal
    point must be within the range"."""
    h = Harness("PCIX-400")
    h.send(line + "\n")
    assert bool(h.errors()) is error


@pytest.mark.parametrize(
    "name", ["start_position", "negative_limit", "positive_limit", "home_low", "home_high"]
)
@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_a_world_position_that_is_not_finite_is_refused(name: str, value: float) -> None:
    """Through the Python API (``Board``, ``Harness``, the pytest fixture) as through the
    configuration file and the control API: a switch at infinity is refused at once, in one
    line that names the key, rather than failing in the middle of a jog (``math.ceil(inf)``)."""
    with pytest.raises(ValueError, match=rf"^AxisWorld {name}: expected a finite number"):
        AxisWorld(**{name: value})
    with pytest.raises(ValueError, match=rf"^AxisWorld {name}: expected a finite number"):
        AxisWorld().with_changes(**{name: value})
