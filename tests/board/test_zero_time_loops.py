"""A loop whose passes take no time runs one pass a sample, wherever between two samples it
was entered, and never hangs the board.

The board's command processor makes at most one pass a sample of a loop of commands that take
no time (``Executor.loop_end``). A pass entered a hair before a tick (within the slack a time
wait is taken to be over early, ``WAIT_SLACK``) used to wait for that very tick: the wait was
over at once, and pass after pass ran at the same instant; with a while loop whose flag never
changes, for ever (found by ``test_fast_paths.py``'s random streams on a VS4-040: the daemon
would have hung on that client's bytes).
"""

from __future__ import annotations

import pytest
from robustness.fuzz import watchdog

from omsd.board import Board
from omsd.engine.executor import WAIT_SLACK
from omsd.models import get_model


def tick(board: Board) -> float:
    """A sample of the board's grid (2048 Hz on the PC48, its own rate on the others), some
    two seconds after power-up."""
    return board.clock.time_of(2 * board.clock.rate)


def pass_count(board: Board, loops: int) -> int:
    """Passes of X's loop made so far (an LS loop counts down from ``loops``)."""
    frames = board.axes[0].queue.loops
    return loops - frames[-1].remaining if frames else loops


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PCIX-004"])
@pytest.mark.parametrize(
    "offset", [-10 * WAIT_SLACK, -WAIT_SLACK, -WAIT_SLACK / 2, 0.0, WAIT_SLACK, 1e-4]
)
def test_a_pass_a_sample_wherever_the_loop_is_entered(model: str, offset: float) -> None:
    board = Board(get_model(model), now=0.0)
    t = tick(board) + offset
    board.receive(b"AX LS1000 WT0 LE ", t)
    assert pass_count(board, 1000) <= 2  # this sample's pass (and the next tick's, if due)
    later = t + 10 / board.clock.rate
    board.advance(later)
    assert 9 <= pass_count(board, 1000) <= 12  # a pass a sample since


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PCIX-004"])
@pytest.mark.parametrize("program", [b"AX WH WG ", b"AX WH WT0 WG "])
@pytest.mark.parametrize("offset", [-WAIT_SLACK, -WAIT_SLACK / 2, 0.0])
def test_a_while_loop_that_never_ends_does_not_hang_the_board(
    model: str, program: bytes, offset: float
) -> None:
    """The random stream's case, reduced: a ``WH`` ... ``WG`` loop with nothing in it that takes
    time and nothing to end it, entered a hair before a tick (on the old code this never
    returned): the board answers, and goes on a pass a sample."""
    board = Board(get_model(model), now=0.0)
    t = tick(board) + offset
    with watchdog(10.0, "a while loop entered a hair before a tick"):
        board.receive(program, t)
        board.receive(b"WY", t)
        board.advance(t + 1.0)  # a second of passes, one a sample
    replies = [o for o in board.take_output() if getattr(o, "text", None)]
    assert replies and b"ver" in replies[-1].text  # the WY after the loop is answered
