"""The board's own byte stream, as a serially attached OMS board presents it.

EPICS' ``drvOmsPC68`` talks to the PC48-family dialect this way (``shared/interop/README.md``):
replies keep their native framing (``<LF><CR>value<LF><CR>``, ``<LF><CR><CR>status<LF><CR><CR>``);
"A command error must be visible in the stream as a lone ``#``"; and the client "must not
receive ``!``, ``@`` or ``$`` bytes on this link: its parser counts them as header bytes and then
eats the first byte of the next reply." Done, limit and slip are therefore reported only as
events (for the traffic log), never as bytes.
"""

from __future__ import annotations

from omsd.board import Board, CommandErrorEvent, Event, Reply
from omsd.link.base import LinkOutput


class RawLink:
    kind = "raw"

    def __init__(self, board: Board) -> None:
        self.board = board

    def from_host(self, data: bytes, now: float) -> int:
        return self.board.receive(data, now)

    def to_host(self, now: float) -> LinkOutput:
        self.board.advance(now)
        out = bytearray()
        events: list[Event] = []
        for item in self.board.take_output():
            if isinstance(item, Reply):
                out += item.data
            else:
                events.append(item)
                if isinstance(item, CommandErrorEvent):
                    out += b"#"
        return LinkOutput(bytes(out), events)

    def next_deadline(self) -> float | None:
        return self.board.next_deadline()

    def room(self) -> int:
        return self.board.input_room()
