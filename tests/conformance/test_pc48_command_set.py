"""Every command of the PC48 manual's §6.3 command summary is in the PC48 personality, with a
handler, and nothing else is."""

from __future__ import annotations

import pathlib
import re

import pytest

from omsd.board.commands import HANDLERS
from omsd.board.harness import Harness
from omsd.models import MODELS
from omsd.models.pc48 import PC48_COMMANDS

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


@pytest.mark.skipif(not MANUAL.exists(), reason="manual text not present")
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


@pytest.mark.parametrize("model", sorted(m for m in MODELS if m.startswith("PC48")))
@pytest.mark.parametrize("mnemonic", sorted(PC48_COMMANDS))
def test_no_command_crashes_in_any_mode(model: str, mnemonic: str) -> None:
    """Each command, bare and with an operand, in single-axis, AA, AM and contour-definition
    mode, either works or sets the command-error flag, and the board still answers WY."""
    h = Harness(model)
    for prefix in ("AX ", "AA ", "AM ", "AA CD0,0; "):
        for form in (mnemonic, mnemonic + "1", mnemonic + "1,1,1"):
            h.send(f"{prefix}{form};")
            h.advance(0.01)
        h.send("\x04")
    h.send("\x04EF AX WY")
    assert h.send("WY").endswith(f"PC48 ver 3.00-{len(MODELS[model].axes)}\n\r".encode())
