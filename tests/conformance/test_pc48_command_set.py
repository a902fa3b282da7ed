"""Every command of the PC48 manual's §6.3 command summary is in the PC48 personality, with a
handler, and nothing else is."""

from __future__ import annotations

import pathlib
import re

import pytest

from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.dialects.pc48 import TABLE as HANDLERS
from omsd.engine.registers import CMD_S
from omsd.models import MODELS
from omsd.models.pc48 import PC48_COMMANDS
from omsd.models.spec import Kind

MANUAL = pathlib.Path(__file__).parents[3] / "shared" / "seeds" / "000_438df88d2a6a1670.txt"

# The §6.3 "COMMAND SUMMARY" of the PC48 manual, copied in order ('#' marks an operand).
SUMMARY = [
    "AA",
    "AC#",
    "AF",
    "AM",
    "AN",
    "AR",
    "AS",
    "AT",
    "AU",
    "AV",
    "AX",
    "AY",
    "AZ",
    "BH#",
    "BL#",
    "BX",
    "CA",
    "CD#,#;",
    "CE",
    "CK",
    "CN",
    "CR#,#,#",
    "CV#",
    "CW",
    "CX",
    "EA",
    "EF",
    "EN",
    "ER#,#",
    "ES#",
    "ET",
    "FP#",
    "GD",
    "GO",
    "HD#",
    "HE",
    "HF",
    "HG#",
    "HH",
    "HL",
    "HM#",
    "HN",
    "HR#",
    "HS",
    "HV#",
    "IC",
    "ID",
    "II",
    "IN#",
    "IP",
    "IS",
    "JF#",
    "JG#",
    "KL",
    "KM",
    "KR",
    "LE",
    "LF",
    "LN",
    "LP#",
    "LS#",
    "MA#",
    "ML#,#;",
    "MM",
    "MO",
    "MP",
    "MR#",
    "MT#,#;",
    "MV#,#",
    "PA#",
    "PF",
    "PN#",
    "QA",
    "QI",
    "RA",
    "RB",
    "RC",
    "RE",
    "RI",
    "RL",
    "RM#",
    "RP",
    "RQ",
    "RS",
    "RU",
    "RV",
    "SA",
    "SD",
    "SE#",
    "SF",
    "SL",
    "SP#",
    "ST",
    "SW#",
    "UF",
    "UU#",
    "VB#",
    "VL#",
    "VS#,#,#",
    "WA",
    "WD",
    "WG",
    "WH",
    "WQ",
    "WS#",
    "WT#",
    "WY",
]


def summary() -> dict[str, bool]:
    """Mnemonic -> takes an operand."""
    return {entry[:2]: "#" in entry for entry in SUMMARY}


def test_the_summary_lists_107_commands() -> None:
    assert len(summary()) == 107


@pytest.mark.skipif(
    not MANUAL.exists(),
    reason=f"{MANUAL} is absent: the manuals are kept in ../shared beside the repository, not in"
    " a clone of it",
)
def test_the_copied_summary_is_the_manuals() -> None:
    text = MANUAL.read_text(encoding="utf-8")
    section = text[text.index("6.3. COMMAND SUMMARY") : text.index("6.4. AXIS SPECIFICATION")]
    found = [m.group(1) for m in re.finditer(r"^([A-Z]{2}[#,;]*)\t6-", section, re.M)]
    assert found == list(SUMMARY)


def test_personality_has_exactly_the_summary_commands() -> None:
    assert set(PC48_COMMANDS) == set(summary())


def test_operand_commands_match_the_summary() -> None:
    """'#' marks a command that takes an operand; AN and AF take the placeholder lists of the
    AA mode and of contours (§6.6, §6.21) although the summary prints them bare."""
    listed = {m for m, operand in summary().items() if operand} | {"AN", "AF"}
    assert {m for m, spec in PC48_COMMANDS.items() if spec.operand} == listed


def test_every_command_has_a_handler() -> None:
    assert set(PC48_COMMANDS) <= set(HANDLERS)


# -- each command, in each mode, with each form of operand --------------------------------------

# The four columns of every queue table (§6.2: "The single axis cases are indicated by the mode
# reference indicating the appropriate axis. The synchronized mode is indicated by the mode
# identifier AA or AM. The contouring case is indicated by AA/CD"), each entered as a user
# would, and the three forms each command is given: bare, one operand, three operands.
MODES = {"single": "AX ", "AA": "AA ", "AM": "AM ", "CD": "AA CD0,0; "}
FORMS = ("", "1", "1,1,1")

OK = None
MISSING = ErrorKind.MISSING_PARAMETER
TOO_MANY = ErrorKind.TOO_MANY_PARAMETERS
Rule = tuple[ErrorKind | None, ErrorKind | None, ErrorKind | None]  # outcome per FORMS entry

# One operand ("#"), required: missing when bare, too many when given three.
ONE: Rule = (MISSING, OK, TOO_MANY)
# One operand that may be left out: MA, LP, PA ("the default value of zero is used if no
# parameter is supplied in the single axis mode"), HM/HR ("The parameter defaults to zero if
# none is supplied"), PN ("no parameter supplied defaults to 70% or 3 steps").
OPTIONAL: Rule = (OK, OK, TOO_MANY)
# Anything goes: an operand-less command (the stray "1" after it is a separate error, see
# below), the AA syntax (§6.1: "An axis may be skipped by entering a comma with no parameter.
# The command may be prematurely terminated with a ';'"), and AN/AF in the single axis mode ("No
# parameter is required in the single axis mode"; "The parameter only serves as a place holder").
ANY: Rule = (OK, OK, OK)
# At least one AA field: CD ("The parameters define the axes for which the contour is
# defined"), AN/AF in a contour ("All axes must be specified or specifically skipped").
SOME: Rule = (MISSING, OK, OK)
# ER#,# and MV#,#: exactly two operands.
TWO: Rule = (MISSING, MISSING, TOO_MANY)
# BL#/BH#: bit 1 is an input at the factory setting (RB: "Factory default settings have bits 0
# through 7 as inputs and 8 through 13 are outputs"), and BL "is only valid for bits which have
# been configured as outputs".
OUTPUT_BIT: Rule = (MISSING, ErrorKind.NOT_AN_OUTPUT, TOO_MANY)

# What each command does with each form in the modes its queue table allows (every other mode
# is "Not valid": NOT_VALID_IN_MODE). "multi" is AA and AM.
RULES: dict[str, dict[str, Rule]] = {
    # 6.5: EN/EF/HH/HL/LF/LN/SL/SF/CN take no operand; PN# is one operand in every mode
    **{m: {"single": ANY} for m in ("EN", "EF", "HH", "HL", "LF", "LN", "SL", "SF", "CN")},
    "PN": {"single": OPTIONAL, "multi": OPTIONAL},
    "PF": {"single": ANY, "multi": ANY},
    "RS": {"single": ANY, "multi": ANY},
    # 6.6
    "AN": {"single": ANY, "multi": ANY, "CD": SOME},
    "AF": {"single": ANY, "multi": ANY, "CD": SOME},
    "PA": {"single": OPTIONAL, "multi": ANY},
    "SE": {"single": ONE, "multi": ANY},
    "BL": {"single": OUTPUT_BIT, "multi": OUTPUT_BIT, "CD": OUTPUT_BIT},
    "BH": {"single": OUTPUT_BIT, "multi": OUTPUT_BIT, "CD": OUTPUT_BIT},
    "BX": {"single": ANY, "multi": ANY, "CD": ANY},
    "RB": {"single": ANY},
    # 6.7: AC 1 ("greater than zero ... less than 8,000,000"), VL 1 ("greater than zero"),
    # VB 1 (below the power-up VL of 100,000), RM 1 ("greater than zero and less than 65,000")
    **{m: {"single": ONE, "multi": ANY} for m in ("AC", "VL", "VB", "MR")},
    "LP": {"single": OPTIONAL},
    "MA": {"single": OPTIONAL, "multi": ANY},
    "ML": {"multi": ANY},
    "MT": {"multi": ANY, "CD": ANY},  # in a contour: "only the axes being used" (X, Y here)
    "MO": {"single": ANY},
    "RM": {"single": ONE},
    # 6.8: JG/JF one velocity; VS#,#,# needs its sample count and no more than three fields
    "GO": {"single": ANY, "multi": ANY},
    "GD": {"single": ANY, "multi": ANY},
    "JG": {"single": ONE},
    "JF": {"single": ONE},
    "VS": {"single": SOME},
    # 6.9
    **{m: {"single": ANY, "multi": ANY} for m in ("ST", "SA", "SD", "KL")},
    # 6.10: LS# (1 to 32000 loops), WS# (an input bit) take one operand in AA too ("AA LS4",
    # "AA WS1"); LE/WD/WG with no loop open: CMD_S "LS and LE commands are not in [matched] pairs"
    "LS": {"single": ONE, "multi": ONE},
    "WS": {"single": ONE, "multi": ONE},
    "WH": {"single": ANY, "multi": ANY},
    "CW": {"single": ANY, "multi": ANY},
    **{
        m: {"single": (ErrorKind.LOOP_MISMATCH,) * 3, "multi": (ErrorKind.LOOP_MISMATCH,) * 3}
        for m in ("LE", "WD", "WG")
    },
    # 6.11
    "HM": {"single": OPTIONAL},
    "HR": {"single": OPTIONAL},
    "KM": {"single": ANY},
    "KR": {"single": ANY},
    # 6.12: IN# is a distance per axis in AA ("IN0,,10000;"); SW#/WT# one operand in AA too
    "ID": {"single": ANY, "multi": ANY},
    "II": {"single": ANY, "multi": ANY},
    "IN": {"single": ONE, "multi": ANY},
    "IP": {"single": ANY},
    "IC": {"single": ANY, "multi": ANY},
    "CA": {"single": ANY},
    "WA": {"multi": ANY},
    "WQ": {"single": ANY, "multi": ANY},
    "SW": {"single": ONE, "multi": ONE},
    "WT": {"single": ONE, "multi": ONE},
    # 6.13 (the replies are in REPLIES)
    **{m: {"single": ANY, "multi": ANY} for m in ("WY", "RP", "RC", "RV")},
    "RQ": {"single": ANY, "multi": ANY, "CD": ANY},
    **{m: {"single": ANY} for m in ("RA", "QA", "RU")},
    **{m: {"multi": ANY} for m in ("RI", "QI")},
    # 6.14: UU 1 is in range (UF "is equivalent to and preferred over UU1")
    "UU": {"single": ONE},
    "UF": {"single": ANY},
    # 6.15 - 6.19: HV 1, HG 1 ("between 1 and 32,000"), HD 1 ("A parameter of zero is
    # allowed"), ES 1
    "ER": {"single": TWO},
    **{m: {"single": ONE} for m in ("HV", "HG", "HD", "ES")},
    **{m: {"single": ANY} for m in ("HF", "HN", "IS", "ET", "HE", "HS", "EA", "RE")},
    "RL": {"single": ANY, "multi": ANY},
    # 6.20
    "MP": {"single": ANY, "multi": ANY},
    "MM": {"single": ANY, "multi": ANY},
    "MV": {"single": TWO},
    "SP": {"single": ONE},
    "FP": {"single": ONE},
    # 6.21: CR#,#,# needs all three (centre and angle); CX with no contour defined has nothing
    # to execute
    "CD": {"multi": SOME},
    "CE": {"CD": ANY},
    "CK": {"CD": ANY},
    "CR": {"CD": (MISSING, MISSING, OK)},
    "CV": {"multi": ONE},
    "CX": {"multi": (ErrorKind.NO_CONTOUR,) * 3},
    # 6.4
    "AA": {"single": ANY, "multi": ANY},
    "AM": {"single": ANY, "multi": ANY},
    **{f"A{letter}": {"single": ANY, "multi": ANY} for letter in "XYZTUVRS"},
}


def test_the_rules_cover_exactly_the_valid_cells() -> None:
    """RULES has an entry for each mode a command's queue table does not call "Not valid"."""
    for mnemonic, spec in PC48_COMMANDS.items():
        valid = {
            column
            for column, modes in (("single", ["single"]), ("multi", ["AA", "AM"]), ("CD", ["CD"]))
            if any(spec.cell(mode).kind is not Kind.NOT_VALID for mode in modes)
        }
        assert set(RULES[mnemonic]) == valid, mnemonic


def status(text: str) -> bytes:
    """RA/QA/RI/QI/EA: "one line feed and two carriage returns on each end"."""
    return b"\n\r\r" + text.encode() + b"\n\r\r"


def value(text: str) -> bytes:
    """Every other reply is "surrounded by line feeds and carriage returns"."""
    return b"\n\r" + text.encode() + b"\n\r"


def replies(model: str, mode: str) -> dict[str, bytes]:
    """What each status request answers at power-up (position 0, nothing moving, nothing done,
    no switch active: the default world's home switch is at 1000..1100, its limits far away)."""
    n = len(MODELS[model].axes)

    def each(text: str) -> str:
        return text if mode == "single" else ",".join([text] * n)

    return {
        "WY": value(f"PC48 ver 3.00-{n}"),  # "<LF><CR>PC48 ver 3.00-2<LF><CR>"
        "RP": value(each("0")),
        # "The maximum available in each command queue is 200" (3 characters); in a contour
        # definition "The maximum available is 1016 ... fixed in length at 4 characters"
        "RQ": value("1016" if mode == "CD" else each("200")),
        # at rest, "the acceleration at the beginning of a ramp": the power-up AC, linear ramps
        "RC": value(each("1000000")),
        "RV": value(each("0")),
        # direction P at power-up (docs/decisions.md), not done, no limit, not home
        "RA": status("PNNN"),
        "QA": status("PNNN"),
        "RI": status(each("PNNN")),
        "QI": status(each("PNNN")),
        "RU": value("0.00000"),  # "five characters to the right of the decimal point"
        # no input grounded, every output "off at power up" (high): no bit is low
        "BX": value("000000"),
        "RB": value("003F00"),  # "Response: <LF><CR>003F00<LF><CR>"
        # "The number of characters returned corresponds to the number of axes available"
        "RL": value("N" * n),
        "EA": status("DDNNNN"),  # slip and hold disabled, no slip, not in position, not home
        "RE": value("0"),
    }


def outcome(model: str, mnemonic: str, mode: str, form: str) -> tuple[bytes, list[object]]:
    """The reply and the command errors ``<mnemonic><form>;`` gives in ``mode`` on a board at
    power-up, from the queue table (``PC48_COMMANDS``, checked against the manual above) and
    RULES."""
    spec = PC48_COMMANDS[mnemonic]
    board = MODELS[model]
    text = mnemonic + (form if spec.operand else "")
    # An operand after a command that takes none: the command is complete at its second
    # letter, and "1" cannot start a command: one error for the bad word (docs/decisions.md,
    # "Bad input")
    stray = [(ErrorKind.BAD_CHARACTER, "1")] if form and not spec.operand else []
    column = "multi" if mode in ("AA", "AM") else mode
    if spec.cell(mode).kind is Kind.NOT_VALID:
        return b"", [(ErrorKind.NOT_VALID_IN_MODE, text), *stray]
    axis_has_encoder = "X" in board.encoder_axes if mode == "single" else bool(board.encoder_axes)
    # (RL's "AA,AM  Immediate" is one cell across both columns: valid without encoders too)
    needs_encoder = spec.encoder_only and (mode == "single" or not spec.encoder_only_single)
    if needs_encoder and not axis_has_encoder:
        # "AX - AT  NO ENCODER  Not valid", "This command is available only in models with the
        # encoder option"
        return b"", [(ErrorKind.NO_ENCODER, text), *stray]
    if spec.not_on_encoder_models and board.encoder_axes:
        # MO: "This command is not available in models with an encoder option"
        return b"", [(ErrorKind.ENCODER_MODEL, text), *stray]
    if mnemonic[0] == "A" and mnemonic[1] in "XYZTUVRS" and mnemonic[1] not in board.axes:
        return b"", [(ErrorKind.NO_SUCH_AXIS, text), *stray]
    kind = RULES[mnemonic][column][FORMS.index(form)]
    if kind is not None:
        return b"", [(kind, text), *stray]
    reply = replies(model, mode).get(mnemonic, b"")
    if mnemonic == "EN":
        # "All commands and parameters will be echoed to the host ... an English readable error
        # message": what follows EN comes back, with the message for the stray operand
        # (docs/decisions.md: "<LF><CR><English message>: <command><LF><CR>")
        rest = form + ";"
        reply = rest[:1] + b"\n\rInvalid character: 1\n\r".decode() + rest[1:] if form else rest
        return reply.encode(), stray
    return reply, stray


@pytest.mark.parametrize("model", sorted(m for m in MODELS if m.startswith("PC48")))
@pytest.mark.parametrize("mnemonic", sorted(PC48_COMMANDS))
def test_no_command_crashes_in_any_mode(model: str, mnemonic: str) -> None:
    """Each command, bare and with an operand, in single-axis, AA, AM and contour-definition
    mode, either works (its exact reply, or none, and no error) or sets the command-error flag
    (CMD_S, Table 3-8, with exactly the expected error and no reply), on a board at power-up.
    Then all twelve in a row on one board: the board still answers WY."""
    for mode, prefix in MODES.items():
        for form in FORMS:
            h = Harness(model)
            assert h.send(prefix) == b"" and h.errors() == []
            # 0.2 s: past RS's initialisation (0.1 s), when what follows RS is read
            reply = h.send(f"{mnemonic}{form};") + h.advance(0.2)
            got = [(e.kind, e.command) for e in h.errors()]
            where = f"{prefix}{mnemonic}{form};"
            assert (reply, got) == outcome(model, mnemonic, mode, form), where
            assert bool(h.board.status_register(h.t) & CMD_S) == bool(got), where
    h = Harness(model)
    for prefix in MODES.values():
        for form in FORMS:
            h.send(f"{prefix}{mnemonic}{form};")
            h.advance(0.01)
        h.send("\x04")
    # EF is "Not valid" in AA/AM (and Control-D leaves the axis mode as it was): AX first
    h.send("\x04AX EF")
    assert h.send("WY") == value(f"PC48 ver 3.00-{len(MODELS[model].axes)}")
