"""The board's own byte stream, as a serially attached OMS board presents it.

EPICS' ``drvOmsPC68`` talks to the PC48-family dialect this way (``shared/interop/README.md``):
replies keep their native framing (``<LF><CR>value<LF><CR>``, ``<LF><CR><CR>status<LF><CR><CR>``);
"A command error must be visible in the stream as a lone ``#``"; and the client "must not
receive ``!``, ``@`` or ``$`` bytes on this link: its parser counts them as header bytes and then
eats the first byte of the next reply." Done, limit and slip are therefore reported only as
events (for the traffic log), never as bytes. With echo on (EN) the ``#`` follows the English
error message (``XQ<LF><CR>Unrecognized command: XQ<LF><CR>#``), as the driver's does.

What a command error puts in the stream is the dialect's (``Framing.error``): the ``#`` above
for the PC48 family, nothing for the PCIx, whose manual has a command error set CMD_S in the
status register and defines no text for it (§3.9), and whose MAX-family clients read each reply
as ``text<LF><CR>`` with nothing before it. Either way the error is an event in the traffic log.
"""

from __future__ import annotations

from omsd.board import Board, CommandErrorEvent, Event, Output, Reply
from omsd.link.base import Held, LinkOutput, merge, message_first


class RawLink:
    kind = "raw"

    def __init__(self, board: Board) -> None:
        self.board = board

    def from_host(self, data: bytes, now: float, session: int = 0) -> int:
        return self.board.receive(data, now, session)

    def to_host(self, now: float) -> LinkOutput:
        board = self.board
        board.advance(now)
        out, sources = board.take_output_sourced()
        if len(out) <= 1:
            # the fast path: nothing, or one reply (a query's answer) as it is
            if not out:
                return LinkOutput()
            item = out[0]
            if isinstance(item, Reply):
                return LinkOutput([(sources[0], item.data)])
        return self.output(out, sources)

    def output(self, out: list[Output], sources: list[int]) -> LinkOutput:
        """The board's output for the host, item by item (what :meth:`to_host` does but for its
        fast path)."""
        error = self.board.framing.error
        message_first(out, sources)
        pieces: list[tuple[int, bytes]] = []
        events: list[Event] = []
        for item, source in zip(out, sources, strict=True):
            if isinstance(item, Reply):
                merge(pieces, source, item.data)
            else:
                events.append(item)
                if error and isinstance(item, CommandErrorEvent):
                    merge(pieces, source, error)
        return LinkOutput(pieces, events)

    def next_deadline(self) -> float | None:
        return self.board.next_deadline()

    def next_wakeup(self) -> float | None:
        return self.board.next_wakeup()

    def room(self, session: int = 0) -> int:
        return self.board.input_room(session)

    def drop_input(self, session: int) -> int:
        return 0  # nothing is held here: what the board has not taken stays with the transport

    def reset_input(self) -> int:
        return 0

    def held(self) -> Held | None:
        return None

    def busy(self, session: int) -> bool:
        return False

    def take_notes(self) -> list[str]:
        return []
