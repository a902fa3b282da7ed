"""GO and GD queue requirements (PC48 §6.8; VS4 §6.8 the same), read back with RQ.

"To find the total queue requirements for a specific application, find the appropriate value in
Table A. If the board is an encoder version, add the value found in Table B to the value from
Table A, to determine total queue usage."

GO   Table A: AX - AS  NO ENCODER 4, ENCODER 7;  AA,AM  NO ENCODER 5, ENCODER 8
GD   Table A: AX - AS  NO ENCODER 5, ENCODER 8;  AA,AM  NO ENCODER 6, ENCODER 9
GO, GD  Table B (the VS4's: "ADDITIONAL ENCODER QUEUE REQUIREMENTS"):
             AX - AS  LINEAR 0, PARABOLIC 0, COSINE 0;  AA,AM  LINEAR 6, PARABOLIC 15, COSINE 15

The totals below are written out from those tables (not taken from the emulator's command
tables). A move queued from rest runs at once and its MR gives its slots back, so RQ right
after ``MR… GO`` is the queue size less what the GO holds while its move runs.
"""

from __future__ import annotations

import pytest

from omsd.board.board import Board
from omsd.board.harness import Harness
from omsd.models import get_model, variant

RAMPS = {"linear": "PF ", "parabolic": "PN; ", "cosine": "CN "}

# slots held by the GO / GD, by (encoder version?, mode, ramp)
NO_ENCODER = {
    # Table A only: the ramp does not matter
    ("GO", "single"): {"linear": 4, "parabolic": 4, "cosine": 4},
    ("GO", "AA"): {"linear": 5, "parabolic": 5, "cosine": 5},
    ("GD", "single"): {"linear": 5, "parabolic": 5, "cosine": 5},
    ("GD", "AA"): {"linear": 6, "parabolic": 6, "cosine": 6},
}
ENCODER = {
    # Table A ENCODER + Table B
    ("GO", "single"): {"linear": 7 + 0, "parabolic": 7 + 0, "cosine": 7 + 0},
    ("GO", "AA"): {"linear": 8 + 6, "parabolic": 8 + 15, "cosine": 8 + 15},
    ("GD", "single"): {"linear": 8 + 0, "parabolic": 8 + 0, "cosine": 8 + 0},
    ("GD", "AA"): {"linear": 9 + 6, "parabolic": 9 + 15, "cosine": 9 + 15},
}

# model -> (queue size, encoder version?)
BOARDS = {
    "PC48-4": (200, False),
    "PC48-4E": (200, True),
    "PC46-42": (200, False),
    "PC46-4E": (200, True),
    "VS4-040": (800, True),
    "VS4-040 without encoders": (800, False),
}


def board(name: str) -> Harness:
    if name == "VS4-040 without encoders":
        h = Harness("VS4-040")
        h.board = Board(variant(get_model("VS4-040"), encoders=""), now=0.0)
        return h
    return Harness(name)


def numbers(reply: bytes) -> list[int]:
    return [int(f) for f in reply.strip(b"\n\r").split(b",")]


@pytest.mark.parametrize("ramp", list(RAMPS))
@pytest.mark.parametrize("command", ["GO", "GD"])
@pytest.mark.parametrize("name", list(BOARDS))
def test_aa_go_is_table_a_plus_table_b_on_encoder_versions_only(
    name: str, command: str, ramp: str
) -> None:
    size, encoder = BOARDS[name]
    slots = (ENCODER if encoder else NO_ENCODER)[(command, "AA")][ramp]
    h = board(name)
    h.send(RAMPS[ramp] + "AA VL1000,1000,1000,1000;")
    h.run()
    assert numbers(h.query("RQ")) == [size] * 4
    h.send(f"MR1000000,1000000,1000000,1000000; {command}")
    assert numbers(h.query("RQ")) == [size - slots] * 4
    assert h.errors() == []


@pytest.mark.parametrize("ramp", list(RAMPS))
@pytest.mark.parametrize("command", ["GO", "GD"])
@pytest.mark.parametrize("name", list(BOARDS))
def test_single_axis_go_is_table_a(name: str, command: str, ramp: str) -> None:
    size, encoder = BOARDS[name]
    slots = (ENCODER if encoder else NO_ENCODER)[(command, "single")][ramp]
    h = board(name)
    h.send(RAMPS[ramp] + "AY VL1000")
    h.run()
    h.send(f"MR1000000 {command}")
    assert numbers(h.query("RQ")) == [size - slots]
    assert h.errors() == []


def test_non_encoder_board_rq_after_aa_moves() -> None:
    """The manual's numbers on a PC48-4 (no encoder) in every ramp mode: AA GO holds Table A's
    5, GD 6, so a queue of 200 reads 195 and 194 whatever the ramp."""
    for ramp in ("PF ", "PN; ", "CN "):
        h = Harness("PC48-4")
        h.send(ramp + "AA VL1000,1000,1000,1000;")
        h.run()
        h.send("MR1000000,1000000,1000000,1000000; GO")
        assert h.query("RQ") == b"\n\r195,195,195,195\n\r"
        h = Harness("PC48-4")
        h.send(ramp + "AA VL1000,1000,1000,1000;")
        h.run()
        h.send("MR1000000,1000000,1000000,1000000; GD")
        assert h.query("RQ") == b"\n\r194,194,194,194\n\r"
