"""The DOS device driver of PC48 chapter 7 (``omsd/link/driver.py``), where a review against the
chapter, sentence by sentence, found gaps; each test quotes the sentence it checks.

* The Control-Y that clears the DONE after a ``!`` wait is sent when the board has room for it,
  ahead of the characters the wait held: "When the DONE interrupt occurs after the driver
  processes the ! symbol, the DONE condition is cleared with a Control-Y. Characters are then
  allowed to be passed to the board." (§7.3.4). When the board's input buffer was full at the
  DONE, the Control-Y was lost and the done flags stayed set.
"""

from __future__ import annotations

from omsd.board import Board
from omsd.link import DriverLink
from omsd.models import get_model


def test_the_control_y_after_a_wait_waits_for_room_in_the_board() -> None:
    """§7.3.4: "When the DONE interrupt occurs after the driver processes the ! symbol, the DONE
    condition is cleared with a Control-Y. Characters are then allowed to be passed to the
    board."

    X's move ends with an ID after 0.1 s; Y's crawl keeps the board's interpreter on WQ for
    100 s, and the reports written after it fill the board's 124-character input buffer to the
    last place, so the driver processes the ``!`` (everything before it is in the board) and
    holds ``AX QA``. X's DONE releases the wait while the board has no room: the Control-Y
    goes to the board once it has, before the held characters, and QA then reads X's done
    flag cleared (N), not D."""
    link = DriverLink(Board(get_model("PC48-2"), 0.0))
    # 20 reports and a bad word of three letters: the last of them fills the board's buffer
    written = b"AX VL1000 MR100 GO ID AY VL10 MR1000 GO WQ " + b"AX RP " * 20 + b"RRR! AX QA"
    assert link.from_host(written, 0.0) == len(written)
    interpreter = link.board.interpreter
    assert len(interpreter.buffer) == interpreter.capacity == 124
    assert link.waiting == "done"
    assert link.to_host(0.5).data == b"!\x01\n"
    assert link.waiting is None
    out = link.to_host(200.0).data
    assert out == b"100\n" * 20 + b"#\nPNNN\n"  # RRR is a command error; X is not done
