"""The PCIx command table against the digest's §4 table (``shared/reference/pcix.md``), which
transcribes every command page's QUEUE REQUIREMENTS table, and the seven PCIx model rows."""

from __future__ import annotations

import pathlib
import re

import pytest

from omsd.models.pcix import PCIX_COMMANDS, PCIX_MODELS
from omsd.models.spec import Cell, Kind

DIGEST = pathlib.Path(__file__).parents[3] / "shared" / "reference" / "pcix.md"

MODES = {"AX–AT": "single", '"AY – AT"': "single", '"AX"': "single", "AA/AM": "AA", "CD": "CD"}
_SEGMENT = re.compile(r'^(AX–AT|"AY – AT"|"AX"|AA/AM|CD) (.+)$')

# Rows whose queue column is not "<mode> <entry>; …", with what the manual's tables say.
IRREGULAR = {
    # "AC#; … AX-AT or AA-AM Linear ( LA or PF ) 6 … All other Parabolic Forms 15 … Custom Ramps
    # ( SR ) 3 + (No. of ramp segments +12) … S-curve ( AJ ) 69"; no AA/CD row
    "AC",
    # "Short Form Parabolic (PN0) 15", "All Other Parabolic (PN,PN0) 29", "AA/CD Not Valid"
    "PN",
    "PR",
    # "?AQ AA/CD Immediate", "RQ AA/CD Immediate"
    "?AQ",
    "RQ",
    # the BC page's "Immediate" against §5.12.3's "1" (the page is taken)
    "BC",
}

# Plain-number entries whose cell also charges a ramp add-on with linear ramps: CG's "Add the
# following queue requirements for the ramp types listed … Linear ( PF, LA ) 8"
LINEAR_RAMP_ADDON = {"CG": 8}

# The formula entries, checked by hand: (command, mode) -> {contour axes: units}
FORMULAS = {
    ("SR", "single"): {0: 7},  # "7 + (2* number of segments …)": the segments are the handler's
    ("CD", "AA"): {1: 6, 2: 7, 4: 9},  # "5 + number of axes in the contour"
    ("MT", "CD"): {1: 7, 2: 8, 4: 10},  # "6 + (number of axes included in contour definition)"
}

FLUSHING = {"ST", "SA", "SD", "SI", "KL", "KS", "FP"}


def _rows() -> dict[str, str]:
    text = DIGEST.read_text(encoding="utf-8")
    section = text[text.index("## 4. Command table") : text.index("## 5. Verbatim examples")]
    rows: dict[str, str] = {}
    for line in section.splitlines():
        if not line.startswith("| ") or line.startswith("| CMD"):
            continue
        cells = [c.strip() for c in line.split("|")]
        rows[cells[1]] = cells[4]
    return rows


def _entries(column: str) -> dict[str, str] | None:
    """{mode: entry} of a regular queue column, None for an irregular one."""
    out: dict[str, str] = {}
    for segment in column.split(";"):
        m = _SEGMENT.match(segment.strip())
        if m is None:
            return None
        out[MODES[m.group(1)]] = m.group(2)
    return out if set(out) == {"single", "AA", "CD"} else None


ABSENT = (
    f"{DIGEST} is absent: the manuals' digests are kept in ../shared beside the repository,"
    " not in a clone of it"
)
needs_digest = pytest.mark.skipif(not DIGEST.exists(), reason=ABSENT)


@needs_digest
def test_the_table_is_the_digests_203_commands() -> None:
    rows = _rows()
    assert len(rows) == 203
    assert set(PCIX_COMMANDS) == set(rows)
    assert len(PCIX_COMMANDS) == 203
    for key, spec in PCIX_COMMANDS.items():
        assert spec.mnemonic == key


def test_no_pc48_only_commands() -> None:
    for mnemonic in ("EN", "EF", "RS", "AR", "AS", "AU", "AV", "SQ", "?SQ"):
        assert mnemonic not in PCIX_COMMANDS
    assert "SO" in PCIX_COMMANDS and "?SO" in PCIX_COMMANDS


@needs_digest
def test_only_the_known_rows_are_irregular() -> None:
    irregular = {cmd for cmd, column in _rows().items() if _entries(column) is None}
    assert irregular == IRREGULAR


def _linear(cell: Cell, axes: int = 0) -> int:
    return cell.cost("linear", False, axes)


@needs_digest
@pytest.mark.parametrize(
    "mnemonic",
    sorted(set(_rows()) - IRREGULAR)
    if DIGEST.exists()
    else [pytest.param("", marks=pytest.mark.skip(reason=ABSENT))],
)
def test_cells_match_the_queue_column(mnemonic: str) -> None:
    entries = _entries(_rows()[mnemonic])
    assert entries is not None
    spec = PCIX_COMMANDS[mnemonic]
    for mode, entry in entries.items():
        cell = spec.cell(mode)
        where = f"{mnemonic} {mode}: {entry!r}"
        if entry.startswith("Imm"):
            assert cell.kind is Kind.IMMEDIATE, where
        elif entry in ("NV", "N/A"):
            assert cell.kind is Kind.NOT_VALID, where
        elif entry.startswith('"'):
            assert cell.kind is Kind.QUEUED, where
            for axes, units in FORMULAS[(mnemonic, mode)].items():
                assert _linear(cell, axes) == units, where
        else:
            m = re.fullmatch(r"(\d+)\*?( \(sic\))?", entry)
            assert m is not None, where
            expected = Kind.FLUSH if mnemonic in FLUSHING else Kind.QUEUED
            assert cell.kind is expected, where
            assert _linear(cell) - LINEAR_RAMP_ADDON.get(mnemonic, 0) == int(m.group(1)), where


def test_irregular_rows() -> None:
    ac = PCIX_COMMANDS["AC"]
    for cell in (ac.single, ac.multi):
        assert cell.kind is Kind.QUEUED
        assert cell.cost("linear", False) == 6
        assert cell.cost("parabolic", False) == 15  # "All other Parabolic Forms"
        assert cell.cost("cosine", False) == 15  # no cosine row: the parabolic number
        assert cell.cost("custom", False, segments=4) == 3 + (4 + 12)
        assert cell.cost("scurve", False) == 69
    assert ac.contour.kind is Kind.NOT_VALID
    for mnemonic in ("PN", "PR"):
        spec = PCIX_COMMANDS[mnemonic]
        assert _linear(spec.single) == _linear(spec.multi) == 29
        assert spec.contour.kind is Kind.NOT_VALID
    for mnemonic in ("?AQ", "RQ"):
        spec = PCIX_COMMANDS[mnemonic]
        assert {spec.cell(m).kind for m in ("single", "AA", "AM", "CD")} == {Kind.IMMEDIATE}
    bc = PCIX_COMMANDS["BC"]
    assert (bc.single.kind, bc.multi.kind, bc.contour.kind) == (
        Kind.IMMEDIATE,
        Kind.NOT_VALID,
        Kind.NOT_VALID,
    )


def test_flushing_commands() -> None:
    assert {
        m for m, s in PCIX_COMMANDS.items() for c in (s.single, s.multi) if c.kind is Kind.FLUSH
    } == FLUSHING


# -- add-ons ----------------------------------------------------------------------------------


def test_go_add_ons() -> None:
    go = PCIX_COMMANDS["GO"].single
    assert go.cost("linear", False) == 5
    assert go.cost("linear", True) == 5 + 3
    assert go.cost("linear", True, pa=True) == 5 + 3 + 2
    assert go.cost("linear", True, pa=True, settle=True) == 5 + 3 + 2 + 3
    assert PCIX_COMMANDS["GO"].multi.cost("scurve", True, pa=True, settle=True) == 7 + 3 + 2 + 3


def test_move_add_ons() -> None:
    ma = PCIX_COMMANDS["MA"]
    assert ma.single.cost("linear", True) == 2 + 2
    assert ma.single.cost("cosine", False) == 2 + 11
    assert ma.multi.cost("scurve", True) == 4 + 44 + 2
    assert PCIX_COMMANDS["MR"].single.cost("parabolic", True) == 2 + 1
    assert PCIX_COMMANDS["ML"].multi.cost("cosine", True) == 4 + 11
    assert PCIX_COMMANDS["LP"].single.cost("linear", True) == 2 + 2
    assert PCIX_COMMANDS["HM"].single.cost("linear", True, pa=True, settle=True) == 4 + 2 + 2 + 3
    assert PCIX_COMMANDS["MV"].single.cost("linear", True, pa=True) == 4 + 2 + 1
    assert PCIX_COMMANDS["SO"].single.cost("linear", True, pa=True, settle=True) == 5 + 1 + 1 + 3


def test_velocity_by_ramp() -> None:
    vl = PCIX_COMMANDS["VL"].single
    assert vl.cost("linear", False) == 2
    assert vl.cost("parabolic", False) == vl.cost("cosine", False) == 2 + 9
    assert vl.cost("custom", False, segments=5) == 2 + (5 - 1)
    assert vl.cost("scurve", False) == 2


def test_contour_execution_add_ons() -> None:
    cx = PCIX_COMMANDS["CX"].multi
    assert cx.cost("linear", False) == 8  # no linear row
    assert cx.cost("parabolic", True, pa=True, settle=True) == 8 + 18 + 1 + 2 + 3
    assert cx.cost("custom", False, segments=3) == 8 + 6 + 2 * 3
    cg = PCIX_COMMANDS["CG"].multi
    assert cg.cost("linear", False) == 9 + 8
    assert cg.cost("scurve", True) == 9 + 113 + 1


def test_stop_add_ons() -> None:
    for mnemonic in ("ST", "SA", "SI", "KL", "KS"):
        cell = PCIX_COMMANDS[mnemonic].single
        assert cell.cost("linear", True, pa=True, settle=True) == 1 + 1 + 3
    assert PCIX_COMMANDS["SD"].multi.cost("linear", False, pa=True) == 2 + 1
    assert PCIX_COMMANDS["FP"].single.cost("linear", True, settle=True) == 3 + 3
    assert PCIX_COMMANDS["KM"].single.cost("linear", True, pa=True) == 2 + 2


# -- syntax and motor types -------------------------------------------------------------------

BARE = {"AA", "AM", "AX", "AY", "AZ", "AT", "GO", "GD", "GN", "GS", "GU", "ST", "SA", "SD", "KL"}
BARE |= {"KM", "KR", "CN", "PF", "WD", "WG", "WH", "WA", "CE", "CK", "CX", "CG", "ET", "IS"}
FLAG_LISTS = {"LN", "LF", "LH", "LL", "SL", "SF", "HH", "HL", "HE", "HS", "HN", "HF", "AN", "AF"}
FLAG_LISTS |= {"PA", "PH", "PL", "LA", "SC", "DBI", "DBN", "CA", "KS", "SI", "UF"}
OPTIONAL_VALUES = {"HM", "HR", "LP", "TX", "PN", "PR"}
REQUIRED = {"AC", "VL", "VB", "MA", "MR", "ML", "MT", "JG", "JF", "TM", "DC", "BC", "LO", "RM"}
REQUIRED |= {"?AJ", "?DA", "?DE", "?DS", "AJ", "DAR", "DAB", "SR", "SS", "ER", "ES", "HD", "HV"}


def test_operands() -> None:
    for m in BARE:
        assert not PCIX_COMMANDS[m].operand, m
    for m in FLAG_LISTS | OPTIONAL_VALUES:
        assert PCIX_COMMANDS[m].operand and PCIX_COMMANDS[m].optional, m
    for m in REQUIRED:
        assert PCIX_COMMANDS[m].operand and not PCIX_COMMANDS[m].optional, m
    for spec in PCIX_COMMANDS.values():
        if spec.mnemonic.startswith("?") and spec.mnemonic not in ("?AJ", "?DA", "?DE", "?DS"):
            assert not spec.operand, spec.mnemonic
    assert [m for m, s in PCIX_COMMANDS.items() if s.letter_operand] == ["EG"]
    assert not PCIX_COMMANDS["EGF"].operand and not PCIX_COMMANDS["EG?"].operand


def test_axis_restricted_modes() -> None:
    assert PCIX_COMMANDS["TX"].single_axes == "YZT"  # "The command is invalid for the X axis."
    assert PCIX_COMMANDS["ET"].single_axes == "YZT"  # "ET; AY – AT 2"
    assert PCIX_COMMANDS["VS"].single_axes == "X"  # "AX mode is the only valid mode"
    others = {m for m, s in PCIX_COMMANDS.items() if s.single_axes is not None}
    assert others == {"TX", "ET", "VS"}


SERVO = {"BI", "UN", "SVI", "SVN", "KO", "DZ", "KA", "KB", "KD", "KF", "KI", "KP", "KU", "KV"}
SERVO |= {"?KA", "?KB", "?KD", "?KF", "?KI", "?KO", "?KP", "?KU", "?KV", "?SO", "?SV"}
# (?PM, in §5.6.2's servo list, answers on every axis: docs/decisions.md, omsMAXnet)
STEPPER_ENCODER = {"HD", "HG", "HV", "?HD", "?HG", "?HV", "ER", "?ER", "ES", "?ES", "IS", "ET"}
STEPPER_ENCODER |= {"TN", "TF", "?SK"}
# (IP is on every axis: "If the position hold (HN) is not enabled for an axis, the command will
# behave like an ID command for that axis")
FEEDBACK = {"HN", "HF", "HE", "RE", "EA"}


def test_motor_types() -> None:
    by_motor: dict[str | None, set[str]] = {}
    for m, spec in PCIX_COMMANDS.items():
        by_motor.setdefault(spec.motor, set()).add(m)
    assert by_motor["servo"] == SERVO
    assert by_motor["stepper_encoder"] == STEPPER_ENCODER
    assert by_motor["feedback"] == FEEDBACK
    assert by_motor["open_loop"] == {"GS"}
    assert set(by_motor) == {None, "servo", "stepper_encoder", "feedback", "open_loop"}
    for spec in PCIX_COMMANDS.values():  # the PC48 family's flags are not used by the PCIx
        assert not spec.encoder_only and not spec.not_on_encoder_models


# -- models -----------------------------------------------------------------------------------

# name: (axes, servo axes, encoder axes), from Appendix C's servo / closed loop / open loop columns
LAYOUT = {
    "PCIX-002": ("XY", "", ""),
    "PCIX-020": ("XY", "", "XY"),
    "PCIX-202": ("XYZT", "XY", "XY"),
    "PCIX-200": ("XY", "XY", "XY"),
    "PCIX-004": ("XYZT", "", ""),
    "PCIX-040": ("XYZT", "", "XYZT"),
    "PCIX-400": ("XYZT", "XYZT", "XYZT"),
}


def test_models() -> None:
    assert [m.name for m in PCIX_MODELS] == list(LAYOUT)
    for model in PCIX_MODELS:
        axes, servo, encoders = LAYOUT[model.name]
        assert (model.axes, model.servo_axes, model.encoder_axes) == (axes, servo, encoders)
        digits = model.name.removeprefix("PCIX-")
        assert int(digits[0]) == len(servo)  # servo
        assert int(digits[1]) == len(encoders) - len(servo)  # stepper with encoder
        assert int(digits[2]) == len(axes) - len(encoders)  # open-loop stepper
        assert model.done_bits == tuple(range(len(axes)))
        assert model.family == "PCIX" and model.dialect == "pcix" and model.framing == "trailing"
        assert model.commands is PCIX_COMMANDS
        assert (model.queue_size, model.contour_queue, model.input_buffer) == (800, 7160, 124)
        assert model.sample_rate == 2048
        assert (model.io_bits, model.factory_outputs, model.io_inputs) == (8, 0xF0, 0x0F)
        assert model.max_queries
        assert model.description


def test_who_are_you() -> None:
    replies = {m.name: m.who_are_you() for m in PCIX_MODELS}
    # the WY page: "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems"
    assert replies["PCIX-400"] == "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems"
    for name, reply in replies.items():
        assert reply == f"{name} ver:1.26, s/n:000217 - Oregon Micro Systems"


def test_ranges() -> None:
    for model in PCIX_MODELS:
        # "RANGE: 1 ≤ AC ≤ 8,000,000" against the exclusive bound the handlers test
        assert 0 < 8_000_000 < model.max_acceleration
        assert model.max_acceleration <= 8_000_000.001  # so 8,000,000.001 is refused
        assert model.max_velocity == 1_044_000  # "1 ≤ VL ≤ 1044000"
        assert model.jog_limit == 1_043_999  # "-1,043,999 ≤ JG ≤ 1,043,999"
        assert model.load_position_limit == 33_554_431
        assert (model.default_velocity, model.default_acceleration) == (200_000, 2_000_000)
        assert model.default_contour_velocity == 1000
