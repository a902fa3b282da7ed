"""The DOS device driver of PC48 chapter 7 (``omsd/link/driver.py``), where a review against the
chapter, sentence by sentence, found gaps; each test quotes the sentence it checks.

* The Control-Y that clears the DONE after a ``!`` wait is sent when the board has room for it,
  ahead of the characters the wait held: "When the DONE interrupt occurs after the driver
  processes the ! symbol, the DONE condition is cleared with a Control-Y. Characters are then
  allowed to be passed to the board." (§7.3.4). When the board's input buffer was full at the
  DONE, the Control-Y was lost and the done flags stayed set.
* A DONE that happened before the host's next characters is read (its ``!`` and the done flag
  register's byte) before those characters reach the board: "A DONE interrupt will place an !
  into the data stream followed by the byte read from the done flag register of the board"
  (§7.3.3), and the driver serves the interrupt when it occurs. When the link was not run
  between the DONE and the host's next write, an ``RA``, ``IC`` or Control-Y in it cleared the
  register first and the marker read ``!\x00``.
"""

from __future__ import annotations

import pytest

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


@pytest.mark.parametrize(
    ("written", "answer"),
    [(b"RA ", b"PDNN\n"), (b"IC ", b""), (b"\x19", b"")],
)
def test_a_done_is_read_before_the_characters_written_after_it(
    written: bytes, answer: bytes
) -> None:
    """§7.3.3: "When a DONE, LIMIT, SLIP or COMMAND ERROR interrupt occur, the device driver
    processes the interrupt and inserts certain characters into the data stream from the board.
    ... A DONE interrupt will place an ! into the data stream followed by the byte read from
    the done flag register of the board, followed by the end character."

    X's move ends with an ID at 0.101 s; the host writes again at 0.5 s, and the link is not
    run in between (a service woken late). The driver has served the DONE at 0.101 s, reading
    0x01 from the done flag register, before RA ("The done flag register will also be reset by
    this command", §6.13), IC or Control-Y ("clear the done and error flags in the status
    register and the done flag register", §6.12) can reach the board."""
    link = DriverLink(Board(get_model("PC48-4"), 0.0))
    link.from_host(b"AX VL1000 MR100 GO ID ", 0.0)
    assert link.to_host(0.0).data == b""
    assert link.from_host(written, 0.5) == len(written)
    assert link.to_host(0.5).data == b"!\x01\n" + answer
