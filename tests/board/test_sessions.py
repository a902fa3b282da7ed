"""Sessions in the engine: whose command each piece of output answers (issue 13).

``Board.receive(data, now, source)`` names the session the bytes come from; every output item
carries the session whose command caused it (``Board.take_output_sourced``). The rules where a
client's bytes meet another's (docs/decisions.md, "Sessions"):

* the input buffer holds one session's characters at a time;
* an unfinished command of the last session ends where its bytes ended, as that session's;
* a PCIx macro definition or ramp table the last session left open is abandoned, so that it
  does not swallow the newcomer's commands;
* queued commands keep their sender: a done, a limit or a slip goes to whoever sent the ID or
  started the motion.
"""

from __future__ import annotations

from omsd.board import Board, CommandErrorEvent, DoneEvent, LimitEvent, Reply
from omsd.board.world import AxisWorld
from omsd.models import get_model

A, B = 1, 2


def said(board: Board) -> list[tuple[int, object]]:
    out, sources = board.take_output_sourced()
    return list(zip(sources, out, strict=True))


def replies(items: list[tuple[int, object]], session: int) -> list[bytes]:
    return [o.data for s, o in items if s == session and isinstance(o, Reply)]


def run(board: Board, until: float) -> None:
    while (t := board.next_deadline()) is not None and t <= until:
        board.advance(t)
    board.advance(until)


def test_answers_go_to_the_session_that_asked() -> None:
    board = Board(get_model("PC48-4"))
    board.receive(b"AY LP-5 RP ", 0.0, A)
    board.receive(b"AX RP ", 0.0, B)
    items = said(board)
    assert replies(items, A) == [b"\n\r-5\n\r"]
    assert replies(items, B) == [b"\n\r0\n\r"]


def test_a_done_goes_to_the_sender_of_its_id_whoever_writes_meanwhile() -> None:
    board = Board(get_model("PC48-4"))
    board.receive(b"AX VL1000 MR1000 GO ID ", 0.0, A)
    board.receive(b"AY RP ", 0.5, B)
    run(board, 2.0)
    items = said(board)
    assert [s for s, o in items if isinstance(o, DoneEvent)] == [A]
    assert replies(items, B) == [b"\n\r0\n\r"]


def test_a_limit_goes_to_whoever_started_the_motion() -> None:
    world = {"X": AxisWorld(positive_limit=500.0)}
    board = Board(get_model("PC48-4"), world=world)
    board.receive(b"AX VL1000 JG1000 ", 0.0, A)
    board.receive(b"AY RP ", 0.1, B)
    run(board, 2.0)
    items = said(board)
    assert [s for s, o in items if isinstance(o, LimitEvent)] == [A]


def test_an_unfinished_command_ends_as_its_senders_when_another_writes() -> None:
    """``AX JG0`` at the very end of A's input waits for its terminator (the lexer cannot know
    the number is over); B's first byte ends it as A's: the jog (of 0, so VL is kept) runs, and
    an error in it would be A's."""
    board = Board(get_model("PC48-4"))
    board.receive(b"AX JG1234", 0.0, A)
    assert board.axes[0].moving is False
    board.receive(b"MR-", 0.0, A)  # and a bad number left unfinished
    board.receive(b"AY RP ", 0.0, B)
    items = said(board)
    assert board.axes[0].moving is True  # A's JG1234 ended at B's first byte
    errors = [s for s, o in items if isinstance(o, CommandErrorEvent)]
    assert errors == [A]
    assert replies(items, B) == [b"\n\r0\n\r"]


def test_a_pcix_macro_left_open_does_not_swallow_the_next_session() -> None:
    """PCIx MD: "Enter the commands ... then enter a control Z to end the macro definition".
    A leaves one open; B's WY is answered, and the macro keeps its old (empty) text."""
    board = Board(get_model("PCIX-040"))
    board.receive(b"MD1;AX;MR100;", 0.0, A)
    board.receive(b"WY;", 0.0, B)
    items = said(board)
    assert replies(items, B) == [board.model.who_are_you().encode() + b"\n\r"]
    board.receive(b"PM1;", 0.0, B)
    assert b"MR100" not in b"".join(replies(said(board), B))


def test_another_sessions_characters_hold_the_newcomer_until_read() -> None:
    """A's WQ holds the interpreter ("wait for queue empty") with A's ``RP`` behind it in the
    input buffer; B's characters are not taken until A's have been read, except a Control-D,
    which throws them away (and kills the move)."""
    board = Board(get_model("PC48-4"))
    board.receive(b"AX VL1000 MR1000000 GO WQ RP ", 0.0, A)
    assert board.interpreter.buffer
    assert board.receive(b"AY RP ", 0.0, B) == 0
    assert board.input_room(B) == 0
    assert board.input_room(A) > 0
    assert board.receive(b"\x04AY RP ", 0.0, B) == len(b"\x04AY RP ")
    items = said(board)
    assert replies(items, A) == []  # A's RP was thrown away unread
    assert replies(items, B) == [b"\n\r0\n\r"]
    assert board.axes[0].moving is False  # killed
