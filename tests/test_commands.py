"""``omsd commands MODEL [--grep TEXT]`` (issue 14): the commands a personality understands, one a
line, with operand form, range, manual section and page, and what each does."""

from __future__ import annotations

import re

import pytest
from daemon.process import run_omsd

from omsd.commands import MAX_FAMILY, Listed, format_listing, listing
from omsd.dialects import commands as command_table
from omsd.models import MODELS, get_model
from omsd.models.summary import OMS_SECTIONS, PC48_SUMMARY, PCIX_SUMMARY, VS4_SUMMARY


def test_the_homing_commands_of_a_pc48() -> None:
    done = run_omsd("commands", "PC48-4E", "--grep", "home")
    assert done.returncode == 0 and done.stderr == ""
    assert done.stdout.splitlines() == [
        "HE  HE     -                                      §6.18 p.6-64  Encoder home mode, set"
        " home on encoder logic [AX-AT only]",
        "HH  HH     -                                      §6.5 p.6-12   Home high, home switches"
        " are active high [AX-AT only]",
        "HL  HL     -                                      §6.5 p.6-12   Home low, home switches"
        " are active low [AX-AT only]",
        "HM  HM[#]  -67000000 ≤ position ≤ 67000000 steps  §6.11 p.6-41  Home, find home and"
        " initialize the position counter [AX-AT only]",
        "HR  HR[#]  -67000000 ≤ position ≤ 67000000 steps  §6.11 p.6-42  Home reverse, find home"
        " in reverse direction and initialize position counter [AX-AT only]",
        "HS  HS     -                                      §6.18 p.6-64  Home switch, enable home"
        " switch mode [AX-AT only]",
        "KM  KM     -                                      §6.11 p.6-42  Home and kill pulse"
        " generation [AX-AT only]",
        "KR  KR     -                                      §6.11 p.6-43  Home in reverse and kill"
        " pulse generation [AX-AT only]",
    ]


def test_the_filter_matches_mnemonic_or_description_whatever_the_case() -> None:
    done = run_omsd("commands", "pcix-400", "--grep", "KP")
    assert done.returncode == 0
    assert done.stdout.splitlines() == [
        "DAB  DAB#,#  0 ≤ acceleration level ≤ 1; 0 ≤ velocity level ≤ 1  §5.13 p.5-62   Define"
        " custom ramp breakpoint [AX-AT only]",  # "breaKPoint"
        "KP   KP#     0 ≤ coefficient ≤ 32767                       §5.13 p.5-112  Proportional"
        " gain coefficient [AX-AT only]",
        "?KP  ?KP     -                                             §5.13 p.5-112  Report"
        " proportional gain [AX-AT only]",
    ]


def test_the_same_command_on_other_families() -> None:
    """Ranges and pages are the model's: the VS4's VL stops at 522,000, on its own page."""
    vs4 = run_omsd("commands", "VS4-040", "--grep", "vl").stdout
    assert vs4 == (
        "VL  VL# | VL#,#,…;  0 < velocity ≤ 522000 steps/s  §6.7 p.6-20  Set maximum velocity to"
        " be used in profile\n"
    )
    (pc48,) = [c for c in listing(get_model("PC48-4E")) if c.mnemonic == "VL"]
    assert pc48 == Listed(
        "VL",
        "VL# | VL#,#,…;",
        "0 < velocity ≤ 1044000 steps/s",
        "§6.7 p.6-23",
        "Set maximum velocity to be used in profile",
    )


def test_an_unknown_model_is_one_line_and_status_2() -> None:
    done = run_omsd("commands", "PC99")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.startswith("omsd commands: unknown board model 'PC99'; known models: ")
    assert done.stderr.count("\n") == 1


def test_nothing_matching_is_status_1_as_grep() -> None:
    done = run_omsd("commands", "PC48-2", "--grep", "zzz")
    assert (done.returncode, done.stdout) == (1, "")
    assert done.stderr == "omsd commands: no PC48-2 command matches 'zzz'\n"


def test_without_a_model_the_default_board() -> None:
    assert run_omsd("commands").stdout == run_omsd("commands", "PC48-4E").stdout


@pytest.mark.parametrize("name", list(MODELS))
def test_every_command_the_model_accepts_is_listed_once(name: str) -> None:
    model = get_model(name)
    listed = listing(model)
    mnemonics = [c.mnemonic for c in listed]
    assert len(mnemonics) == len(set(mnemonics))
    table = set(command_table(model))
    left_out = table - set(mnemonics)
    # what is left out is what the model cannot do: axes it lacks, encoder or motor commands
    for mnemonic in left_out:
        spec = command_table(model)[mnemonic]
        assert (
            (re.fullmatch(r"A[XYZTUVRS]", mnemonic) and mnemonic[1] not in model.axes)
            or (spec.encoder_only and not model.encoder_axes)
            or (spec.not_on_encoder_models and model.encoder_option)
            or spec.motor is not None
        ), mnemonic
    assert set(mnemonics) <= table
    for c in listed:
        assert c.description and c.where and c.syntax.startswith(c.mnemonic), c
        assert "\n" not in "".join((c.syntax, c.range, c.where, c.description))
    lines = format_listing(listed)
    assert len(lines) == len(listed)
    assert [line.split()[0] for line in lines] == mnemonics


def test_every_command_has_its_manuals_words() -> None:
    """The summaries cover the command tables exactly: nothing listed without a description."""
    for model in MODELS.values():
        for mnemonic in command_table(model):
            if model.dialect == "pcix":
                assert mnemonic in PCIX_SUMMARY or mnemonic in MAX_FAMILY, mnemonic
            else:
                summary = VS4_SUMMARY if model.family == "VS4" else PC48_SUMMARY
                assert mnemonic in summary and mnemonic in OMS_SECTIONS, (model.name, mnemonic)


def test_where_a_command_applies_is_said() -> None:
    by = {c.mnemonic: c for c in listing(get_model("PC48-6E"))}
    assert by["ER"].description.endswith("[encoder axes: X, Y; AX-AV only]")
    assert by["CD"].description.endswith("[AA/AM only]")
    assert by["CE"].description.endswith("[contour definition only]")
    assert by["VS"].description.endswith("[AX only]")
    assert "[" not in by["MR"].description  # everywhere but a contour definition
    assert "MO" not in by  # "not available in models with an encoder option"
    servo = {c.mnemonic: c for c in listing(get_model("PCIX-202"))}
    assert servo["KP"].description.endswith("[servo axes: X, Y; AX-AT only]")
    assert servo["PS?"].where == "MAX extension"
    assert "KP" not in {c.mnemonic for c in listing(get_model("PCIX-004"))}
