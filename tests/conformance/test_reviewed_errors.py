"""A review of command errors against the manuals (PC48 Table 3-8 and §6.5 EN, §7.3.3 the DOS
driver's ``#``; VS4 Table 3-6; PCIx Table 3-3 and its CA/IC pages; the PC46 datasheet's status
bits). The manuals name two causes of CMD_S ("An unrecognizable command has been detected or LS
and LE commands are not in matched pairs"), print no error message text, and say nothing of a
command line after an error or of a multi-axis list with one bad field: the choices are in
``docs/decisions.md`` ("The character stream", "What a command error does"). These tests pin
them on each family."""

from __future__ import annotations

import pytest

from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.engine.registers import CMD_S, DON_S


def _errors(h: Harness) -> list[tuple[ErrorKind, str]]:
    return [(e.kind, e.command) for e in h.errors()]


@pytest.mark.parametrize(
    ("model", "line", "kind"),
    [
        ("PC48-4", "AA VL1000,0,3000 ", ErrorKind.OUT_OF_RANGE),
        ("PC48-4", "AA VL1000,1.2.3,3000 ", ErrorKind.BAD_NUMBER),
        ("VS4-040", "AA VL1000,0,3000 ", ErrorKind.OUT_OF_RANGE),
        ("PC46-41", "AA VL1000,0,3000 ", ErrorKind.OUT_OF_RANGE),
        ("PCIX-400", "AA;VL1000,0,3000;", ErrorKind.OUT_OF_RANGE),
    ],
)
def test_one_bad_field_refuses_the_whole_list(model: str, line: str, kind: ErrorKind) -> None:
    """§6.1: "Numbers are entered for each axis"; nothing says what a list with one bad number
    does. Chosen: the command is refused whole, one command error, no axis takes its field (a
    status bit names no axis, so a host could not tell which axes took a half-applied list)."""
    h = Harness(model)
    before = [h.axis(letter).vl for letter in "XYZ"]
    h.send(line)
    h.run()
    assert [k for k, _ in _errors(h)] == [kind]
    assert [h.axis(letter).vl for letter in "XYZ"] == before


@pytest.mark.parametrize(
    ("model", "line"),
    [("PC48-4", "AA MR100,1.2.3,300 GO"), ("PCIX-400", "AA;MR100,99999999999,300;GO;")],
)
def test_a_move_with_one_bad_field_moves_no_axis(model: str, line: str) -> None:
    h = Harness(model)
    h.send(line)
    h.run()
    assert len(h.errors()) == 1
    assert [h.position(letter) for letter in "XYZ"] == [0, 0, 0]


@pytest.mark.parametrize(
    ("model", "line"),
    [("PC48-4", "AA MR100,x200,300 GO"), ("PCIX-400", "AA;MR100,x200,300;GO;")],
)
def test_a_letter_in_a_list_ends_it_and_the_fields_before_run(model: str, line: str) -> None:
    """A letter ends an operand (§6.1's terminators plus the EPICS traces' ``LP600AX``), in a
    list too: ``MR100,`` is complete (X 100, Y skipped: "An axis may be skipped by entering a
    comma with no parameter"), ``x2`` is one unrecognised word (the rest of it swallowed up to
    the separator) and ``GO`` runs. Left as it is (decisions.md)."""
    h = Harness(model)
    h.send(line)
    h.run()
    assert _errors(h) == [(ErrorKind.UNKNOWN_COMMAND, "x2")]
    assert [h.position(letter) for letter in "XYZ"] == [100, 0, 0]


@pytest.mark.parametrize(
    ("model", "line", "reply"),
    [
        ("PC48-4", "AX XQ VL5000 MR100 GO RP", b"\n\r0\n\r"),
        ("VS4-040", "AX VL0 MR100 GO RP", b"\n\r0\n\r"),
        ("PCIX-400", "AX;XQ;MR100;GO;?VL;", b"vl200000\n\r"),
    ],
)
def test_the_rest_of_the_line_runs_after_an_error(model: str, line: str, reply: bytes) -> None:
    """The board reads a character stream with no notion of a line (§6.1: "No terminator is
    required"); an error drops the bad command only, what follows it is read and run."""
    h = Harness(model)
    assert h.send(line) == reply
    h.run()
    assert len(h.errors()) == 1
    assert h.position("X") == 100


@pytest.mark.parametrize("model", ["PC48-4", "PC46-41", "VS4-040", "PCIX-400"])
def test_an_error_sets_cmd_s_with_don_s(model: str) -> None:
    """PC48 Table 3-8: "DON_S Done or error status. This high true bit indicates the command
    is complete, i.e. an ID command has been executed or an error has been detected"; "CMD_S
    Command error. An unrecognizable command has been detected" (VS4 Table 3-6, PCIx Table 3-3,
    PC46 "0 Command error", "4 Done or error flag set")."""
    h = Harness(model)
    h.send("XQ;")
    assert h.board.status_register(h.t) & (CMD_S | DON_S) == CMD_S | DON_S


@pytest.mark.parametrize(
    ("model", "clear"),
    [
        ("PC48-4", "AX RA "),
        ("PC48-4", "AA RI "),
        ("PC48-4", "AX QA "),
        ("PC48-4", "WY "),
        ("PCIX-400", "AX;CA;"),
        ("PCIX-400", "AX;RA;"),
    ],
)
def test_only_a_status_read_ic_or_control_y_clears_cmd_s(model: str, clear: str) -> None:
    """PC48 §3.4.4: "The error bits, CMD_S, ENC_S and OVRT are automatically reset after reading
    the register"; IC/Control-Y "clear the done and error flags in the status register". RA
    names "The limit flag in the hardware status register" and "The done flag register" only;
    the PCIx's CA "will not clear other error flags in the status register"; a good command
    after a bad one does not clear it either."""
    h = Harness(model)
    h.send("XQ;")
    h.send(clear)
    h.run()
    assert h.board.status_register(h.t) & CMD_S
    for ic in ("IC;", "\x19"):
        h.send("XQ;" + ic)
        assert not h.board.status_register(h.t) & CMD_S
    h.send("XQ;")
    assert h.board.read_status_register(h.t) & CMD_S
    assert not h.board.read_status_register(h.t) & CMD_S


def test_pcix_has_no_echo_and_says_nothing_on_an_error() -> None:
    """The PCIx manual has no EN/EF and no error query; CMD_S (Table 3-3) is all a host sees:
    EN is itself an unrecognised command, and no text follows."""
    h = Harness("PCIX-400")
    assert h.send("EN;XQ;") == b""
    assert [k for k, _ in _errors(h)] == [ErrorKind.UNKNOWN_COMMAND] * 2


@pytest.mark.parametrize(
    ("line", "kinds"),
    [
        # the pages ask for their operands: "Two parameters must be supplied" (TL)
        ("AX;TL5;", [ErrorKind.MISSING_PARAMETER]),
        ("AX;ER2;", [ErrorKind.MISSING_PARAMETER]),
        ("AX;MV100;", [ErrorKind.MISSING_PARAMETER]),
        # AJ: "from 2 to 7 parameters", but every one after the number bracketed with a default
        ("AX;AJ1;", []),
    ],
)
def test_pcix_too_few_operands(line: str, kinds: list[ErrorKind]) -> None:
    """Pinned (``docs/decisions.md``, "PCIx AJ's omitted parameters"): too few operands is a
    missing-parameter error where the page asks for them; ``AJ1;`` defines the all-default
    profile, its page saying both "It can accept from 2 to 7 parameters" and "Parameters in
    brackets [] are optional" with ALOWER's "Default value: 0.0"."""
    h = Harness("PCIX-040")
    h.send(line)
    assert [k for k, _ in _errors(h)] == kinds
    if not kinds:
        assert h.send("?AJ1;") == b"1.0000000" + b",0.00000000" * 2 + b",1.00000000" + (
            b",0.00000000" * 2 + b",1.00000000\n\r"
        )


def test_pcix_gu_after_an_ml() -> None:
    """Pinned (``docs/decisions.md``, "GU after an ML or MT"): GU is "not valid with the ML and
    MT commands" and "AA-AM Not Valid": typed in AA, a command error; after ``AX;`` it runs X's
    part of the move alone and Y's waits for a GO."""
    h = Harness("PCIX-004")
    h.send("AA;ML1000,500;GU;")
    assert [k for k, _ in _errors(h)] == [ErrorKind.NOT_VALID_IN_MODE]
    h.send("AX;GU;")
    h.run()
    assert _errors(h) == []
    assert h.send("AA;RP;") == b"1000,0,0,0\n\r"
    h.send("GO;")
    h.run()
    assert h.send("AA;RP;") == b"1000,500,0,0\n\r"
