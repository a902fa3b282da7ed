"""The OMS DOS device driver (``omsdrive.sys``), PC48 manual §7.3, as a link discipline.

What a host program sees through the driver differs from the board's own stream:

* Replies (§7.3.2, E:XX): "Normally an OMS board surrounds each response it returns with an
  LF-CR pair ... This program strips off the LF and CR's and allows the user to define a
  character to show the end of the string. The default value is an LF." ``RP`` answers ``0<LF>``.
* Status markers (§7.3.3): "When a command error occurs it places a # symbol followed by the
  'E:' specified end character ... A limit interrupt causes an @ character followed by the end
  character ... an encoder slip interrupt will place a $ and the end character into the stream.
  A DONE interrupt will place an ! into the data stream followed by the byte read from the done
  flag register of the board, followed by the end character. If the board is returning a message
  when an interrupt occurs, the interrupt symbol will be delayed until after the end of the
  message string." The done byte is the raw register value, not ASCII.
* Wait characters and comments (§7.3.4): on ``!`` the driver "stops sending characters to the
  board until the board produces a DONE interrupt ... When the DONE interrupt occurs after the
  driver processes the ! symbol, the DONE condition is cleared with a Control-Y"; ``@`` likewise
  waits for a limit interrupt; "All characters following the * up to the next control character
  (<LF>, <CR>, <TAB>, et cetera) are ignored by the device driver and are not passed to the
  controller."
* The 'output to board' buffer (§7.3.2, B:XXXX, default 256 characters) holds what the host
  has written and the driver has not passed on; when it is full the host is held off.

Like every link here this is sans-I/O: bytes and the time go in, bytes come out.
"""

from __future__ import annotations

from omsd.board import (
    Board,
    CommandErrorEvent,
    DoneEvent,
    Event,
    LimitEvent,
    Reply,
    SlipEvent,
)
from omsd.link.base import LinkOutput

CONTROL_Y = b"\x19"
WAIT_DONE = 0x21  # "!"
WAIT_LIMIT = 0x40  # "@"
COMMENT = 0x2A  # "*"
DEFAULT_EOS = 0x0A
DEFAULT_BUFFER = 256


def _is_control(b: int) -> bool:
    return b < 0x20 or b == 0x7F


class DriverLink:
    """One board seen through the DOS device driver."""

    kind = "driver"

    def __init__(self, board: Board, eos: int = DEFAULT_EOS, buffer_size: int = DEFAULT_BUFFER):
        if not 0 <= eos <= 255:
            raise ValueError(f"end-of-string character must be a byte, got {eos}")
        if not 16 <= buffer_size <= 0x7FFF:
            raise ValueError(f"driver buffer must be 16..32767 characters, got {buffer_size}")
        self.board = board
        self.eos = bytes([eos])
        self.buffer_size = buffer_size
        self._pending = bytearray()  # the 'output to board' buffer
        self._comment = False
        self._waiting: int | None = None  # WAIT_DONE or WAIT_LIMIT while held
        self._wait_since = 0.0
        self._out = bytearray()
        self._events: list[Event] = []
        self._last_done: float | None = None
        # the time of a DONE / limit that no wait character has claimed yet (each one can
        # release at most one wait)
        self._unclaimed: dict[int, float] = {}

    # -- host to board --------------------------------------------------------------------------

    def from_host(self, data: bytes, now: float) -> int:
        """Put host bytes into the driver's buffer; returns how many fitted."""
        room = self.buffer_size - len(self._pending)
        taken = data[: max(0, room)]
        self._pending += taken
        self._pass_on(now)
        return len(taken)

    @property
    def waiting(self) -> str | None:
        """``"done"`` or ``"limit"`` while a ``!`` or ``@`` holds the host's bytes back."""
        if self._waiting == WAIT_DONE:
            return "done"
        if self._waiting == WAIT_LIMIT:
            return "limit"
        return None

    @property
    def pending(self) -> int:
        return len(self._pending)

    def room(self) -> int:
        return self.buffer_size - len(self._pending)

    def _pass_on(self, now: float) -> None:
        """Feed the buffer to the board, up to a wait character or a full board buffer."""
        while True:
            progressed = self._step(now)
            held = self._waiting
            self._collect(now)
            if not progressed and not (held is not None and self._waiting is None):
                return  # nothing passed on, and no wait was released by the board's output

    def _step(self, now: float) -> bool:
        """One piece of the buffer: a comment, a wait character or a run of characters for the
        board. Returns False when nothing could be passed on."""
        pending = self._pending
        if self._waiting is not None or not pending:
            return False
        if self._comment:
            j = 0
            while j < len(pending) and not _is_control(pending[j]):
                j += 1
            del pending[:j]
            if not pending:
                return j > 0
            self._comment = False  # the control character itself goes to the board
        b = pending[0]
        if b == COMMENT:
            self._comment = True
            del pending[0]
            return True
        if b in (WAIT_DONE, WAIT_LIMIT):
            del pending[0]
            # a DONE (or limit) caused by what was sent at this same instant counts: on the real
            # card the interrupt comes well after the driver has moved on to the wait character
            seen = self._unclaimed.pop(b, None)
            if seen is not None and seen >= now:
                if b == WAIT_DONE:
                    self.board.receive(CONTROL_Y, now)
                return True
            self._waiting = b
            self._wait_since = now
            return True
        j = 0
        while j < len(pending) and pending[j] not in (COMMENT, WAIT_DONE, WAIT_LIMIT):
            j += 1
        sent = self.board.receive(bytes(pending[:j]), now)
        del pending[:sent]
        return sent > 0

    # -- board to host --------------------------------------------------------------------------

    def to_host(self, now: float) -> LinkOutput:
        """Let the board run to ``now``; return what the host is to receive, and the events."""
        self.board.advance(now)
        self._pass_on(now)
        data, self._out = bytes(self._out), bytearray()
        events, self._events = self._events, []
        return LinkOutput(data, events)

    def next_deadline(self) -> float | None:
        return self.board.next_deadline()

    def _collect(self, now: float) -> None:
        board = self.board
        for item in board.take_output():
            if isinstance(item, Reply):
                if item.text is not None:
                    self._out += item.text + self.eos
                else:
                    # echoed characters: the driver "strips off the LF and CR's"
                    self._out += item.data.replace(b"\n", b"").replace(b"\r", b"")
                continue
            self._events.append(item)
            # the interrupt service routine reads the status register (clearing it) first
            board.read_status_register(now)
            if isinstance(item, CommandErrorEvent):
                self._out += b"#" + self.eos
            elif isinstance(item, LimitEvent):
                self._out += b"@" + self.eos
                if self._waiting == WAIT_LIMIT and item.time >= self._wait_since:
                    self._waiting = None
                else:
                    self._unclaimed[WAIT_LIMIT] = item.time
            elif isinstance(item, SlipEvent):
                self._out += b"$" + self.eos
            elif isinstance(item, DoneEvent):
                done = board.read_done_register(now)
                if not (done == 0 and self._last_done == item.time):
                    # completions on the same sample are one interrupt: the first read of the
                    # register has every bit, a second marker would only say "nothing"
                    self._out += b"!" + bytes([done]) + self.eos
                self._last_done = item.time
                if self._waiting == WAIT_DONE and item.time >= self._wait_since:
                    self._waiting = None
                    board.receive(CONTROL_Y, now)
                else:
                    self._unclaimed[WAIT_DONE] = item.time
