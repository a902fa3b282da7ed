"""Queue accounting (PC48 §6.2, §6.4–§6.21 "QUEUE REQUIREMENTS", §8.2).

"The RQ command may be used to determine the actual space available at any time." Commands are
queued behind a long move so that they do not execute, and RQ must drop by exactly the slots the
command's table charges. What a move that is *running* holds is not printed in the manual, so the
tests only look at differences of RQ around the command under test (and at 200 when idle).

Ramp mode and encoder option are those in force when the command is entered (digest §4.1). PN
is immediate; CN is queued (1 slot) and is therefore given while the board is idle.
"""

from __future__ import annotations

import re

import pytest

from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.engine.registers import CMD_S, DON_S, TBE_S

RAMPS = {"linear": "PF", "parabolic": "PN;", "cosine": "CN"}
RAMP_INDEX = {"linear": 0, "parabolic": 1, "cosine": 2}


def value(text: str) -> bytes:
    return b"\n\r" + text.encode("ascii") + b"\n\r"


def rq(h: Harness) -> list[int]:
    """RQ in the current mode: 3 digits per field, zero padded (PC48 §6.13)."""
    reply = h.query("RQ")
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    fields = reply[2:-2].split(b",")
    assert all(len(f) == 3 and f.isdigit() for f in fields), reply
    return [int(f) for f in fields]


def idle_board(model: str, ramp: str) -> Harness:
    h = Harness(model)
    h.send(RAMPS[ramp])
    h.run()
    assert h.errors() == []
    assert rq(h) == [200]
    return h


def long_move_single(model: str, ramp: str) -> Harness:
    """X on a 1000 s move; the queue behind it does not execute during the test."""
    h = idle_board(model, ramp)
    h.send("AX VL1000 MR1000000 GO")
    h.advance(0.01)
    return h


def long_move_aa(model: str, ramp: str) -> Harness:
    h = idle_board(model, ramp)
    h.send("AA VL1000,1000,1000,1000; MR1000000,1000000,1000000,1000000; GO")
    h.advance(0.01)
    return h


def cost_of(h: Harness, command: str) -> list[int]:
    before = rq(h)
    h.send(command)
    after = rq(h)
    assert h.errors() == [], command
    return [b - a for b, a in zip(before, after, strict=True)]


# -- single-axis tables ---------------------------------------------------------------------------

# command -> slots, by (no encoder, encoder) and by ramp (linear, parabolic, cosine)
T = tuple[tuple[int, int, int], tuple[int, int, int]]


def flat(n: int) -> T:
    return ((n, n, n), (n, n, n))


def by_ramp(lin: int, par: int, cos: int) -> T:
    return ((lin, par, cos), (lin, par, cos))


def by_encoder(no: int, yes: int) -> T:
    return ((no, no, no), (yes, yes, yes))


SINGLE: dict[str, T] = {
    # 6.5
    "HH": flat(1),
    "HL": flat(1),
    "LF": flat(1),
    "LN": flat(1),
    "SL": flat(1),
    "SF": flat(1),
    "CN": flat(1),
    # 6.6
    "AN;": flat(1),
    "AF;": flat(1),
    # BL/BH: §6.6 says 2, §6.21 says 1 (digest §8.3 item 4); the command's own section wins
    "BL10;": flat(2),
    "BH10;": flat(2),
    "RB": flat(1),
    # 6.7
    "AC5000;": by_ramp(4, 15, 15),
    "VL500;": by_ramp(2, 13, 13),
    "VB10;": flat(2),
    "LP5;": by_encoder(2, 4),
    "MA5;": flat(2),
    "MR5;": flat(2),
    "RM5;": flat(1),
    # 6.8 (single-axis GO/GD: Table A; Table B adds 0)
    "GO": by_encoder(4, 7),
    "GD": by_encoder(5, 8),
    "JG5;": flat(2),
    "JF5;": by_encoder(2, 3),
    # 6.11
    "HM5;": by_encoder(4, 6),
    "HR5;": by_encoder(4, 6),
    "KM": flat(2),
    "KR": flat(2),
    # 6.12
    "ID": flat(1),
    "II": flat(1),
    "IN5;": flat(2),
    "WT5;": flat(3),
    # SW: "Immediate" in its table but a wait in the stream (item 12): queued with 0 slots
    "SW3;": flat(0),
    # 6.20
    "MV5,5;": by_encoder(4, 5),
    "SP5;": by_encoder(3, 4),
}

ENCODER_ONLY: dict[str, int] = {
    "ER1,1;": 1,
    "HV100;": 2,
    "HG5;": 2,
    "HD5;": 1,
    "HF": 2,
    "HN": 2,
    "ES5;": 2,
    "IS": 1,
    "ET": 2,
    "IP": 1,
}


@pytest.mark.parametrize("ramp", list(RAMPS))
@pytest.mark.parametrize("model", ["PC48-4", "PC48-4E"])
@pytest.mark.parametrize("command", list(SINGLE))
def test_single_axis_queue_table(model: str, ramp: str, command: str) -> None:
    h = long_move_single(model, ramp)
    expected = SINGLE[command][1 if model.endswith("E") else 0][RAMP_INDEX[ramp]]
    assert cost_of(h, command) == [expected]


@pytest.mark.parametrize("ramp", list(RAMPS))
def test_mo_takes_one_slot_on_open_loop_board(ramp: str) -> None:
    h = long_move_single("PC48-4", ramp)
    assert cost_of(h, "MO") == [1]


@pytest.mark.parametrize("command", list(ENCODER_ONLY))
def test_encoder_queue_table(command: str) -> None:
    h = long_move_single("PC48-4E", "linear")
    assert cost_of(h, command) == [ENCODER_ONLY[command]]


def test_queued_commands_do_not_execute_behind_the_move() -> None:
    """The premise of the table tests: a VL queued behind the long move has not changed VL."""
    h = long_move_single("PC48-4", "linear")
    h.send("VL500;")
    h.advance(1.0)
    assert h.axis("X").vl == 1000
    assert h.query("RV") == value("1000")


# -- AA tables ------------------------------------------------------------------------------------

AA: dict[str, T] = {
    "AC5,5,5,5;": by_ramp(4, 15, 15),
    "VL5,5,5,5;": by_ramp(2, 13, 13),
    "VB5,5,5,5;": flat(2),
    "MA5,5,5,5;": flat(2),
    "MR5,5,5,5;": flat(2),
    "ML5,5,5,5;": by_ramp(6, 30, 30),
    "MT5,5,5,5;": by_ramp(6, 30, 30),
    # GO/GD: Table A (NO ENCODER 5 / 6, ENCODER 8 / 9) + Table B (LINEAR 6, PARABOLIC 15,
    # COSINE 15) on the encoder version only (PC48 §6.8)
    "GO": ((5, 5, 5), (8 + 6, 8 + 15, 8 + 15)),
    "GD": ((6, 6, 6), (9 + 6, 9 + 15, 9 + 15)),
    "ID": flat(1),
    "II": flat(1),
    "IN5,5,5,5;": flat(2),
    "WT5;": flat(3),
    "WA": flat(0),
    "SW3;": flat(0),
    "AA": flat(2),
    "AN1,1,1,1;": flat(1),
    "AF1,1,1,1;": flat(1),
    "BL10;": flat(2),
    "BH10;": flat(2),
    "LS5;": flat(2),
    "WH": flat(2),
    "WS3;": flat(2),
}


@pytest.mark.parametrize("ramp", list(RAMPS))
@pytest.mark.parametrize("model", ["PC48-4", "PC48-4E"])
@pytest.mark.parametrize("command", list(AA))
def test_aa_queue_table(model: str, ramp: str, command: str) -> None:
    """Every axis queue is charged the AA,AM row (GO/GD: Table A, plus Table B on an encoder
    board).

    GO/GD (PC48 §6.8): "find the appropriate value in Table A. If the board is an encoder
    version, add the value found in Table B to the value from Table A": a board without
    encoders is charged Table A's NO ENCODER column only, whatever the ramp.
    """
    h = long_move_aa(model, ramp)
    expected = AA[command][1 if model.endswith("E") else 0][RAMP_INDEX[ramp]]
    assert cost_of(h, command) == [expected] * 4


def test_aa_field_charges_only_the_axes_given() -> None:
    h = long_move_aa("PC48-4", "linear")
    assert cost_of(h, "MR,5,,5;") == [0, 2, 0, 2]
    assert cost_of(h, "AC5;") == [4, 0, 0, 0]


def test_aa_loop_ends_cost_two() -> None:
    h = long_move_aa("PC48-4", "linear")
    h.send("LS5; WH WS3;")
    assert cost_of(h, "WD") == [2] * 4
    assert cost_of(h, "WG") == [2] * 4
    assert cost_of(h, "LE") == [2] * 4


def test_aa_from_single_axis_mode_is_immediate() -> None:
    """AA table: "AX - AS Immediate, AA,AM 2"."""
    h = long_move_aa("PC48-4", "linear")
    h.send("AX")
    before = [a.queue.free for a in h.board.axes]
    h.send("AA")
    assert [a.queue.free for a in h.board.axes] == before
    assert cost_of(h, "AA") == [2] * 4


# -- PA and SE: per GO/GD -------------------------------------------------------------------------


@pytest.mark.parametrize(("model", "go", "gd"), [("PC48-4", 4, 5), ("PC48-4E", 7, 8)])
def test_pa_and_se_add_to_every_single_axis_go(model: str, go: int, gd: int) -> None:
    """PA: "The following queue requirements apply to each GO or GD command" (2); SE: "requires 3
    queue slots with the execution of each GO or GD command". AN/AF turn PA mode off."""
    h = long_move_single(model, "linear")
    assert cost_of(h, "GO") == [go]
    h.send("PA;")
    assert cost_of(h, "GO") == [go + 2]
    assert cost_of(h, "GD") == [gd + 2]
    assert cost_of(h, "GO") == [go + 2]
    h.send("SE500;")
    assert cost_of(h, "GO") == [go + 2 + 3]
    assert cost_of(h, "GD") == [gd + 2 + 3]
    h.send("SE0;")
    assert cost_of(h, "GO") == [go + 2]
    h.send("AN;")
    assert cost_of(h, "GO") == [go]


@pytest.mark.parametrize("model", ["PC48-4", "PC48-4E"])
def test_pa_and_se_add_to_every_aa_go(model: str) -> None:
    h = long_move_aa(model, "linear")
    go = 5 if model == "PC48-4" else 14  # Table A 5; encoder: 8 + Table B linear 6
    h.send("PA1,1,1,1;")
    assert cost_of(h, "GO") == [go + 2] * 4
    h.send("SE5,5,5,5;")
    assert cost_of(h, "GO") == [go + 5] * 4


def test_pa_on_some_axes_only_charges_them() -> None:
    """AA PA,0,,1; (E-example of §6.6) affects Y and T only."""
    h = long_move_aa("PC48-4", "linear")
    h.send("PA,0,,1;")
    assert cost_of(h, "GO") == [5, 7, 5, 7]


# -- immediate commands ---------------------------------------------------------------------------


def test_immediate_commands_take_no_queue_space() -> None:
    """MP/MM are used here in single-axis mode although their table says "AX - AS Not valid":
    every manual example uses them so (digest §8.3 item 7)."""
    h = long_move_single("PC48-4E", "linear")
    before = rq(h)
    out = h.send("WY RP RQ QA RA RC RV RU BX IC CA UU2 UF MP MM PN; PF EF HE HS EA RE AY AX")
    assert rq(h) == before
    assert h.errors() == []
    # WY, RP, RQ, QA, RA, RC, RV, RU, BX, EA, RE: eleven replies
    assert len(re.findall(rb"\n\r\r?[^\n\r]*\n\r\r?", out)) == 11


def test_immediate_commands_in_aa_take_no_queue_space() -> None:
    h = long_move_aa("PC48-4", "linear")
    before = rq(h)
    h.send("RP QI RI RC RV BX IC PN; PF CV500;")
    assert rq(h) == before
    assert h.errors() == []


def test_rq_reply_is_fixed_three_digits_and_one_field_per_axis() -> None:
    h = Harness("PC48-6")
    assert h.query("AT RQ") == value("200")
    assert h.query("AA RQ") == value("200,200,200,200,200,200")
    h.send("AX")
    h.send("VL1000 MR1000000 GO")
    for _ in range(45):
        h.send("MR1;")
    # GO (4) while running + 45 MR (2 each)
    assert h.query("RQ") == value("106")
    for _ in range(50):
        h.send("MR1;")
    assert h.query("RQ") == value("006")


def test_rq_in_contour_definition_is_the_contour_queue() -> None:
    """PC48 §6.21: "Enter: AA CD0,0; RQ  Response: <LF><CR>1016<LF><CR>". MT in a contour costs
    "4 + number of axes", CR 8, AN/AF 2, BH/BL 2. §6.13's table says RQ is "Not valid" in AA/CD
    (digest §8.3 item 6); the §6.21 example, which shows the reply, is followed."""
    h = Harness("PC48-4")
    assert h.query("AA CD0,0; RQ") == value("1016")
    assert h.query("MT100,100; RQ") == value("1010")
    assert h.query("CR0,5000,3.1415926; RQ") == value("1002")
    assert h.query("AN,,0; RQ") == value("1000")
    assert h.query("BL10; RQ") == value("0998")
    assert h.errors() == []


# -- flushing commands: Flush + 2 -----------------------------------------------------------------


def two_busy_axes() -> Harness:
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000 MR1000000 GO AY VL1000 AC1000 MR1000000 GO")
    h.advance(2.0)
    h.send("AX MR5 GO WT100 AY MR5 GO")
    h.send("AA")
    assert rq(h) == [200 - 4 - 2 - 4 - 3, 200 - 4 - 2 - 4, 200, 200]
    return h


def test_st_flushes_current_axis_and_holds_two_while_decelerating() -> None:
    """ST: "flushes the queue for the current axis only ... decelerate to a stop at the rate
    previously specified in an AC command" (1 s from 1000 at AC1000); Flush + 2."""
    h = two_busy_axes()
    h.send("AX ST AA")
    assert rq(h) == [198, 190, 200, 200]
    h.advance(0.5)
    assert h.query("RQ") == value("198,190,200,200")
    h.advance(0.6)
    assert h.query("RQ") == value("200,190,200,200")
    assert h.axis("X").velocity(h.t) == 0
    assert h.axis("Y").velocity(h.t) == 1000


def test_st_in_aa_is_sa() -> None:
    h = two_busy_axes()
    h.send("ST")
    assert rq(h) == [198, 198, 200, 200]
    h.advance(1.1)
    assert h.query("RQ") == value("200,200,200,200")


def test_sa_flushes_all_axes() -> None:
    h = two_busy_axes()
    h.send("AX SA AA")
    assert rq(h) == [198, 198, 200, 200]
    h.advance(1.1)
    assert h.query("RQ") == value("200,200,200,200")
    assert h.axis("X").velocity(h.t) == 0
    assert h.axis("Y").velocity(h.t) == 0


def test_sd_flushes_all_axes_and_clears_done() -> None:
    h = two_busy_axes()
    h.send("AZ ID")
    h.advance(0.01)
    assert h.axis("Z").done
    h.send("SD AA")
    assert rq(h) == [198, 198, 200, 200]
    assert not h.axis("Z").done


@pytest.mark.parametrize("kill", ["KL", "\x04"])
def test_kl_and_control_d_flush_all_and_stop_at_once(kill: str) -> None:
    """KL and Control-D: "flush the command queue and terminate pulse generation of all axes
    immediately": the 2 slots are free at once, positions freeze."""
    h = two_busy_axes()
    x, y = h.position("X"), h.position("Y")
    h.send(kill)
    assert rq(h) == [200, 200, 200, 200]
    h.advance(1.0)
    assert (h.position("X"), h.position("Y")) == (x, y)
    assert h.errors() == []


def test_fp_is_flush_plus_four() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000 MR1000000 GO MR5 GO WT100")
    h.advance(2.0)
    h.send("FP5000;")
    assert rq(h) == [196]
    assert h.errors() == []


# -- loops ----------------------------------------------------------------------------------------


def test_loop_keeps_its_slots_until_done() -> None:
    """§6.2: "When the commands are nested within loops, the queue space is not reclaimed until
    after the loop has been executed the programmed number of times." LS 2 + MR 2 + GO 4 +
    LE 2 = 10; each pass is a 500 step move at 1000 steps/s."""
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000000 LS3 MR500 GO LE")
    assert rq(h) == [190]
    for t in (0.25, 0.75, 1.25):
        h.until(t)
        assert rq(h) == [190], t
    h.run()
    assert rq(h) == [200]
    assert h.position("X") == 1500


def test_without_loop_space_is_reclaimed_as_commands_execute() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000000 MR500 GO MR500 GO MR500 GO")
    assert rq(h) == [200 - 4 - 2 - 4 - 2 - 4]
    h.until(0.75)
    assert rq(h) == [200 - 4 - 2 - 4]
    h.until(1.25)
    assert rq(h) == [196]


def test_aa_loop_keeps_slots_on_every_axis() -> None:
    h = Harness("PC48-4")
    h.send("AA VL1000,1000,1000,1000; AC1000000,1000000,1000000,1000000;")
    h.send("LS2; MR500,500,500,500; GO LE")
    assert rq(h) == [200 - 2 - 2 - 5 - 2] * 4  # LS, MR, GO (Table A, no encoder), LE
    h.until(0.75)
    assert rq(h) == [189] * 4
    h.run()
    assert h.query("RQ RP") == value("200,200,200,200") + value("1000,1000,1000,1000")


def test_loops_nest_four_deep() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000000 LS2 LS2 LS2 LS2 MR100 GO LE LE LE LE MR5 GO")
    assert h.errors() == []
    assert rq(h) == [200 - 8 - 2 - 4 - 8 - 2 - 4]
    for t in (0.15, 0.85, 1.55):
        h.until(t)
        # inner loops finished their passes, the outermost is still running: nothing reclaimed
        assert rq(h) == [200 - 8 - 2 - 4 - 8 - 2 - 4], t
        assert 100 <= h.position("X") < 1600
    h.run()
    assert h.position("X") == 1605
    assert rq(h) == [200]


def test_fifth_nested_loop_is_one_command_error_and_takes_no_slots() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 MR1000000 GO LS2 LS2 LS2 LS2")
    before = rq(h)
    h.board.read_status_register(h.t)
    h.send("LS2;")
    errors = h.errors()
    assert [e.kind for e in errors] == [ErrorKind.LOOP_TOO_DEEP]
    assert rq(h) == before
    assert h.board.read_status_register(h.t) & CMD_S


def test_unmatched_le_is_an_error_and_takes_no_slots() -> None:
    h = long_move_single("PC48-4", "linear")
    before = rq(h)
    h.send("LE")
    assert [e.kind for e in h.errors()] == [ErrorKind.LOOP_MISMATCH]
    assert rq(h) == before
    assert h.board.status_register(h.t) & CMD_S


def test_loop_end_in_another_axis_mode_is_an_error() -> None:
    """LS: "The axis mode (e.g. AX, AY, AA) must be the same when entering and exiting the loop";
    CMD_S flags "LS and LE commands are not in [matched] pairs". The X loop stays open and its
    own LE still closes it."""
    h = Harness("PC48-4")
    h.send("AX VL1000 MR1000000 GO LS2 MR1 GO AY")
    y_before = rq(h)
    h.send("LE")
    assert [e.kind for e in h.errors()] == [ErrorKind.LOOP_MISMATCH]
    assert rq(h) == y_before
    h.send("AA LE")
    assert [e.kind for e in h.errors()] == [ErrorKind.LOOP_MISMATCH]
    h.send("AX LE")
    assert h.errors() == []


def test_while_loop_holds_slots_until_cw() -> None:
    """WH ... WG loops until CW (§6.10); WH 2 + MR 2 + GO 4 + WG 2 = 10 held; CW is queued
    (1 slot) and ends the loop at the end of the current pass."""
    h = Harness("PC48-4")
    h.send("AX VL1000 WH MR100 GO WG")
    assert rq(h) == [190]
    h.until(1.05)
    assert rq(h) == [190]
    h.until(5.05)
    assert rq(h) == [190]
    assert h.query("CW RQ") == value("189")
    h.run()
    assert rq(h) == [200]
    assert h.position("X") == 5000
    assert h.t < 5.2


def test_while_sync_loops_while_input_low() -> None:
    """WS: "execute the commands between the WS and WD commands as a loop while the specified
    general purpose input line is true, i.e. low"; the test is at the bottom."""
    h = Harness("PC48-4")
    h.board.set_input(3, False, h.t)
    h.send("AX VL1000 WS3 MR100 GO WD")
    assert rq(h) == [190]
    h.until(1.05)
    assert rq(h) == [190]
    assert h.position("X") > 900
    h.board.set_input(3, True, h.t)
    h.run()
    assert rq(h) == [200]
    assert h.position("X") == 1100


def test_while_sync_runs_once_when_input_high() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 WS3 MR100 GO WD")
    h.run()
    assert h.position("X") == 100
    assert rq(h) == [200]


# -- waits ----------------------------------------------------------------------------------------


def test_wt_holds_three_slots_for_its_time() -> None:
    h = Harness("PC48-4")
    h.send("AX WT1000")
    assert rq(h) == [197]
    h.until(0.99)
    assert rq(h) == [197]
    h.until(1.01)
    assert rq(h) == [200]


def test_wt_delays_the_next_queued_command() -> None:
    h = Harness("PC48-4")
    h.send("AX WT500 MR100 GO")
    h.until(0.49)
    assert h.position("X") == 0
    h.run()
    assert h.position("X") == 100


def test_wa_takes_no_slots_and_waits_for_all_axes() -> None:
    """WA (AA only): "allows a command to wait until all moves on all axes are finished". Its
    table reads "AX - AS Immediate, AA,AM Not valid", taken as transposed (digest §8.3 item 8):
    the text says "only valid in the AA mode"."""
    h = Harness("PC48-4")
    h.send("AA VL1000,1000; MR100,2000; GO")
    assert cost_of(h, "WA") == [0, 0, 0, 0]
    h.send("MR100; GO")
    h.until(1.0)
    assert h.position("X") == 100
    h.run()
    assert h.position("X") == 200
    assert h.position("Y") == 2000


def test_wa_in_single_axis_mode_is_an_error() -> None:
    h = Harness("PC48-4")
    h.send("AX WA")
    assert [e.kind for e in h.errors()] == [ErrorKind.NOT_VALID_IN_MODE]
    assert rq(h) == [200]


def test_sw_takes_no_slots_and_waits_for_input_high() -> None:
    h = Harness("PC48-4")
    h.board.set_input(3, False, h.t)
    h.send("AX VL1000")
    assert cost_of(h, "SW3;") == [0]
    h.send("MR100 GO")
    assert rq(h) == [194]
    h.advance(1.0)
    assert h.position("X") == 0
    h.board.set_input(3, True, h.t)
    h.run()
    assert h.position("X") == 100
    assert rq(h) == [200]


def test_wq_holds_the_interpreter_until_the_queue_is_empty() -> None:
    """E73: "AY MR1000 GO WQ RP": RP answers when the move is complete."""
    h = Harness("PC48-4")
    assert h.send("AY VL1000 MR1000 GO WQ RP") == b""
    assert h.advance(0.5) == b""
    assert h.run() == value("1000")


def test_wq_waits_for_the_queues_of_the_current_mode() -> None:
    """§6.12 WQ: "until the queue for the current axis mode is empty, i.e. all previous moves
    have finished". In single-axis mode the current axis only (Y's WQ does not wait for X's
    WT); in AA and in AM every axis (an AM WQ waits for another task's axis too: "all previous
    moves"), docs/decisions.md, Synchronisation."""
    h = Harness("PC48-4")
    assert h.send("AX WT1000 AY WQ RQ") == value("200")
    for mode in ("AA", "AM"):
        h = Harness("PC48-4")
        assert h.send(f"AY WT1000 {mode} MR100; GO WQ WY") == b""
        assert h.advance(0.9) == b""
        assert h.advance(0.2) == b"\n\rPC48 ver 3.00-4\n\r"


def test_queued_cn_acts_when_reached_and_immediate_pf_when_read() -> None:
    """CN is queued (§6.5: "AX - AS 1"), PF and PN immediate: each acts at its own time. Typed
    behind a busy axis, `CN PF` leaves the ramp linear while CN waits, and the CN then makes
    the move that follows cosine; the slot column a command is charged is the ramp in force
    when it is read (AC after the waiting CN: linear, 4). docs/decisions.md, Queue tables."""
    h = Harness("PC48-4")
    h.send("AX WT1000 CN AC100")
    assert rq(h) == [200 - 3 - 1 - 4]
    h = Harness("PC48-4")
    h.send("AX VL1000 AC1000 WT1000 CN PF MR1000 GO")
    assert h.axis("X").ramp.kind.value == "linear"
    h.advance(1.5)
    assert h.axis("X").ramp.kind.value == "cosine"


def test_wq_is_not_valid_in_a_loop() -> None:
    h = Harness("PC48-4")
    h.send("AX LS2 WQ")
    assert [e.kind for e in h.errors()] == [ErrorKind.NOT_IN_LOOP]


def test_input_buffer_holds_124_characters_while_held_by_wq() -> None:
    """PC48 §8.2: "temporarily stored in a 124 character buffer". While WQ holds the
    interpreter the board takes 124 characters and no more (TBE_S low)."""
    h = Harness("PC48-4")
    h.send("AX VL1000 MR1000 GO WQ")
    board = h.board
    assert board.receive(b"RP" * 100, h.t) == 124
    assert not board.status_register(h.t) & TBE_S
    with pytest.raises(BufferError):
        h.send("RP")
    assert h.run() == value("1000") * 62
    assert board.status_register(h.t) & TBE_S


def test_full_queue_holds_the_interpreter_and_the_input_buffer() -> None:
    """The GO of the long move holds 4 slots; 98 "MR1 " fill the other 196. The 99th MR has been
    read and waits for space, 124 more characters wait in the input buffer, and the board takes
    nothing more until the move ends and the queue drains."""
    h = Harness("PC48-4")
    h.send("AX VL1000 MR1000000 GO")
    board = h.board
    data = b"MR1 " * 250
    taken = board.receive(data, h.t)
    assert taken == 99 * 4 + 124
    assert h.axis("X").queue.free == 0
    assert not board.status_register(h.t) & TBE_S
    assert board.receive(data[taken:], h.t) == 0
    h.advance(10.0)
    assert board.receive(data[taken:], h.t) == 0
    h.run()
    rest = data[taken:]
    assert board.receive(rest, h.t) == len(rest)
    h.run()
    # the MR1 without GO only set up moves; the long move ends at 1000000
    assert h.query("RP RQ") == value("1000000") + value("200")


# -- a loop larger than the queue, Control-D, Control-Y -------------------------------------------


def test_loop_larger_than_queue_hangs_until_control_d() -> None:
    """§6.10: "If, when entering a looping sequence of commands, all 200 queue slots are filled,
    before the LE loop terminator is entered, the board will hang ... send the board a
    Control-D (same as KL, but shorter) to kill all moves and flush all queues."

    LS 2 + 33 x (MR 2 + GO 4) fills the queue; the 34th MR cannot be queued. The input buffer
    is not full, so Control-D gets through (§6.2: "A Control-D may clear this condition if the
    input character queue is not also filled").
    """
    h = Harness("PC48-4")
    h.send("AX VL1000 LS2 " + "MR1 GO " * 40 + "LE")
    assert h.axis("X").queue.free == 0
    assert h.send("RQ") == b""
    h.advance(30.0)
    assert h.send("WY") == b""
    assert h.position("X") == 33
    h.send(b"\x04")
    assert h.query("RQ") == value("200")
    h.send("LE")
    assert [e.kind for e in h.errors()] == [ErrorKind.LOOP_MISMATCH]
    assert h.query("WY") == b"\n\rPC48 ver 3.00-4\n\r"
    h.send("MR5 GO")
    h.run()
    assert h.position("X") == 38


def test_control_d_bypasses_a_held_interpreter() -> None:
    h = Harness("PC48-4")
    h.send("AX VL1000 MR1000000 GO WQ MR5 GO")
    h.advance(1.0)
    h.send(b"\x04")
    x = h.position("X")
    assert h.query("RQ") == value("200")
    h.advance(1.0)
    assert h.position("X") == x
    assert h.query("WY") == b"\n\rPC48 ver 3.00-4\n\r"


def _flags_set(h: Harness) -> None:
    h.send("AX MR5 GO ID XQ")
    h.run()
    assert h.board.status_register(h.t) & (CMD_S | DON_S) == CMD_S | DON_S
    assert h.board.registers.done == 1
    assert h.query("QA") == b"\n\r\rPDNN\n\r\r"


@pytest.mark.parametrize("clear", ["IC", "\x19"])
def test_control_y_clears_done_and_error_flags_like_ic(clear: str) -> None:
    """IC / Control-Y (hex 19): "clear the done and error flags in the status register and the
    done flag register"."""
    h = Harness("PC48-4")
    _flags_set(h)
    h.send(clear)
    assert h.board.status_register(h.t) & (CMD_S | DON_S) == 0
    assert h.board.registers.done == 0
    assert h.query("QA") == b"\n\r\rPNNN\n\r\r"
    assert [e.kind for e in h.errors()] == [ErrorKind.UNKNOWN_COMMAND]


def test_control_y_bypasses_a_held_interpreter() -> None:
    """ "The Control-Y version of this command is preferred to minimize the latency": it is
    acted on even while WQ holds the interpreter."""
    h = Harness("PC48-4")
    _flags_set(h)
    h.send("VL1000 MR1000 GO WQ")
    h.send(b"\x19")
    assert h.board.status_register(h.t) & (CMD_S | DON_S) == 0
    assert h.board.registers.done == 0
    assert h.axis("X").queue.free < 200
