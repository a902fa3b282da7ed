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
  driver processes the ! symbol, the DONE condition is cleared with a Control-Y" (when the
  board has room for it, before the characters the wait held); ``@`` likewise waits for a limit
  interrupt; "All characters following the * up to the next control character
  (<LF>, <CR>, <TAB>, et cetera) are ignored by the device driver and are not passed to the
  controller."
* Echo (EN): the board's echo of what it reads is a string from the board like any other: the
  driver strips its LF and CR characters and ends it with the end character where the board's
  LF or CR ends it (the host's own line end, echoed, or the ``<LF><CR>`` that opens a reply or
  the English error message), and before a marker. ``EN WY`` gives `` WY<LF>PC48 ver
  3.00-4<LF>``: the echo and the reply are two strings, never one (docs/decisions.md, "Echo").
  The ``#`` of a command error follows its message ("the interrupt symbol will be delayed
  until after the end of the message string").
* The 'output to board' buffer (§7.3.2, B:XXXX, default 256 characters) holds what the host
  has written and the driver has not passed on; when it is full the host is held off.

Like every link here this is sans-I/O: bytes and the time go in, bytes come out.
"""

from __future__ import annotations

from collections import deque
from operator import attrgetter

from omsd.board import (
    OVRT,
    Board,
    CommandErrorEvent,
    DoneEvent,
    Event,
    LimitEvent,
    Output,
    Reply,
    SlipEvent,
)
from omsd.link.base import Held, LinkOutput, merge, message_first

CONTROL_D = 0x04
CONTROL_Y = b"\x19"
WAIT_DONE = 0x21  # "!"
WAIT_LIMIT = 0x40  # "@"
COMMENT = 0x2A  # "*"
DEFAULT_EOS = 0x0A
DEFAULT_BUFFER = 256
_WAIT_NAMES = {WAIT_DONE: "done", WAIT_LIMIT: "limit"}
_TEXT = attrgetter("text")  # a framed Reply's payload (_collect)


def _is_control(b: int) -> bool:
    return b < 0x20 or b == 0x7F


class DriverLink:
    """One board seen through the DOS device driver.

    Every byte in the driver's buffer belongs to the session that wrote it, and a wait belongs
    to the session whose ``!`` or ``@`` began it: when that session goes, its bytes and its wait
    go with it (:meth:`drop_input`), and what the board answers it is not anybody else's
    (``LinkOutput.pieces``). Control-D from the host, while the driver holds bytes, ends the
    wait and drops what was held before passing the kill on (the manual's driver would hold the
    Control-D too, and a board waiting for a done that a kill prevents would never be free).
    """

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
        self._runs: deque[list[int]] = deque()  # [session, count] covering _pending in order
        self._comment: int | None = None  # the session inside a * comment
        self._waiting: int | None = None  # WAIT_DONE or WAIT_LIMIT while held
        self._wait_session = 0
        self._wait_since = 0.0
        self._pieces: list[tuple[int, bytes]] = []
        self._echoing: set[int] = set()  # sessions given echoed text not yet ended by the EOS
        self._events: list[Event] = []
        self._notes: list[str] = []
        # when the done register was last read for a DONE marker (the link's time then)
        self._done_read_at: float | None = None
        # each session's sample of its last limit given its "@" (limits on one sample are one
        # interrupt: one "@" for each session, each a host of its own)
        self._limit_marked_at: dict[int, float] = {}
        # the time of a DONE / limit that no wait character of its session has claimed yet
        # (each one can release at most one wait)
        self._unclaimed: dict[tuple[int, int], float] = {}

    # -- host to board --------------------------------------------------------------------------

    def from_host(self, data: bytes, now: float, session: int = 0) -> int:
        """Put host bytes into the driver's buffer; returns how many fitted."""
        if (
            not self._pending
            and self._waiting is None
            and self._comment is None
            and b"*" not in data
            and b"!" not in data
            and b"@" not in data
        ):
            return self._straight_through(data, now, session)
        return self.through_buffer(data, now, session)

    def through_buffer(self, data: bytes, now: float, session: int = 0) -> int:
        """:meth:`from_host` the driver's way, by its buffer, whatever the bytes (what it does
        but for its fast path)."""
        self._serve_due(now)
        skipped = 0
        if (self._pending or self._waiting is not None) and CONTROL_D in data:
            skipped = data.index(CONTROL_D)
            dropped = len(self._pending) + skipped
            what = self._wait_text()
            self._clear()
            self._notes.append(f"Control-D: dropped {dropped} held bytes{what}")
            data = data[skipped:]
        room = self.buffer_size - len(self._pending)
        taken = data[: max(0, room)]
        self._append(session, taken)
        self._pass_on(now)
        return skipped + len(taken)

    def _straight_through(self, data: bytes, now: float, session: int) -> int:
        """The fast path of :meth:`from_host` (issue 16): with nothing held, no comment open and
        no ``*``, ``!`` or ``@`` in the bytes, the driver has nothing to do but pass them on, so
        they go to the board as they are, without a stay in the buffer; what the board does not
        take waits there as it would have. The same steps as :meth:`_pass_on` takes for them."""
        board = self.board
        if not board.at_rest(now):  # (at rest, nothing is due by now: nothing to serve)
            self._serve_due(now)
        taken = data[: self.buffer_size]
        sent = board.receive(taken, now, session) if taken else 0
        if sent < len(taken):
            self._append(session, taken[sent:])
        touched = self._collect(now)
        if sent and (self._pending or touched):
            self._pass_on(now)  # (with nothing left and the board not asked again, a no-op)
        return len(taken)

    def _serve_due(self, now: float) -> None:
        """What the board did by itself before ``now`` (a DONE, a limit), served before the
        host's bytes of ``now`` go on: the driver processes an interrupt when it occurs (§7.3.3),
        so its marker, the done flag register's byte and a wait it ends come before anything
        written after it reaches the board (an RA or a Control-Y would clear the register).
        What :meth:`to_host` would have done had the link been run then."""
        board = self.board
        deadline = board.next_deadline()
        if deadline is not None and deadline <= now:
            board.advance(now)
            self._pass_on(now)

    @property
    def waiting(self) -> str | None:
        """``"done"`` or ``"limit"`` while a ``!`` or ``@`` holds the host's bytes back."""
        return None if self._waiting is None else _WAIT_NAMES[self._waiting]

    @property
    def pending(self) -> int:
        return len(self._pending)

    def room(self, session: int = 0) -> int:
        return self.buffer_size - len(self._pending)

    def held(self) -> Held | None:
        if self._waiting is None and not self._pending:
            return None
        waiting = self.waiting
        return Held(
            count=len(self._pending),
            waiting=waiting,
            since=self._wait_since,
            axes=tuple(self.board.busy_axes()) if waiting else (),
            session=self._wait_session if waiting else 0,
        )

    def busy(self, session: int) -> bool:
        if self._waiting is not None and self._wait_session == session:
            return True
        return any(run[0] == session for run in self._runs)

    def drop_input(self, session: int) -> int:
        dropped = 0
        kept = bytearray()
        runs: deque[list[int]] = deque()
        offset = 0
        for owner, count in self._runs:
            if owner == session:
                dropped += count
            else:
                kept += self._pending[offset : offset + count]
                runs.append([owner, count])
            offset += count
        self._pending, self._runs = kept, runs
        if self._waiting is not None and self._wait_session == session:
            self._waiting = None
        if self._comment == session:
            self._comment = None
        self._echoing.discard(session)
        for key in [k for k in self._unclaimed if k[1] == session]:
            del self._unclaimed[key]
        self._limit_marked_at.pop(session, None)
        return dropped

    def reset_input(self) -> int:
        dropped = len(self._pending)
        self._clear()
        self._echoing.clear()
        return dropped

    def take_notes(self) -> list[str]:
        notes, self._notes = self._notes, []
        return notes

    def _clear(self) -> None:
        self._pending = bytearray()
        self._runs.clear()
        self._waiting = None
        self._comment = None
        self._unclaimed.clear()

    def _wait_text(self) -> str:
        held = self.held()
        return f" ({held.describe()})" if held is not None and held.waiting else ""

    def _append(self, session: int, data: bytes) -> None:
        if not data:
            return
        self._pending += data
        runs = self._runs
        if runs and runs[-1][0] == session:
            runs[-1][1] += len(data)
        else:
            runs.append([session, len(data)])

    def _consume(self, n: int) -> None:
        del self._pending[:n]
        runs = self._runs
        while n:
            run = runs[0]
            k = min(n, run[1])
            run[1] -= k
            n -= k
            if not run[1]:
                runs.popleft()

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
        board, all of one session. Returns False when nothing could be passed on."""
        pending = self._pending
        if self._waiting is not None or not pending:
            return False
        session, length = self._runs[0]
        if self._comment is not None:
            if self._comment != session:
                self._comment = None  # another session's bytes end an unfinished comment
            else:
                j = 0
                while j < length and not _is_control(pending[j]):
                    j += 1
                self._consume(j)
                if j == length:
                    return j > 0
                self._comment = None  # the control character itself goes to the board
                return True
        b = pending[0]
        if b == COMMENT:
            self._comment = session
            self._consume(1)
            return True
        if b in (WAIT_DONE, WAIT_LIMIT):
            self._consume(1)
            # a DONE (or limit) caused by what was sent at this same instant counts: on the real
            # card the interrupt comes well after the driver has moved on to the wait character
            seen = self._unclaimed.pop((b, session), None)
            if seen is not None and seen >= now:
                if b == WAIT_DONE:
                    self._clear_done(now, session)
                return True
            self._waiting = b
            self._wait_session = session
            self._wait_since = now
            self._notes.append(f"{chr(b)} holds the host's input: {self._wait_text()[2:-1]}")
            return True
        j = 0
        while j < length and pending[j] not in (COMMENT, WAIT_DONE, WAIT_LIMIT):
            j += 1
        sent = self.board.receive(bytes(pending[:j]), now, session)
        self._consume(sent)
        return sent > 0

    def _clear_done(self, now: float, session: int) -> None:
        """ "the DONE condition is cleared with a Control-Y. Characters are then allowed to be
        passed to the board" (§7.3.4): a board with no room for it now (its input buffer full)
        gets it first when it has, ahead of every character held here."""
        if self.board.receive(CONTROL_Y, now, session):
            return
        self._pending[:0] = CONTROL_Y
        runs = self._runs
        if runs and runs[0][0] == session:
            runs[0][1] += 1
        else:
            runs.appendleft([session, 1])

    def _release(self, now: float) -> None:
        what = _WAIT_NAMES[self._waiting] if self._waiting is not None else "?"
        self._waiting = None
        held = len(self._pending)
        after = f"{now - self._wait_since:.3f} s"
        self._notes.append(f"{what} after {after}: passing on {held} held bytes")

    # -- board to host --------------------------------------------------------------------------

    def to_host(self, now: float) -> LinkOutput:
        """Let the board run to ``now``; return what the host is to receive, and the events."""
        board = self.board
        if not (now == board.now and board.at_rest(now)):  # (else advance would change nothing)
            board.advance(now)
        # fast path (issue 16): with nothing held and nothing said, _pass_on has nothing to
        # pass on or collect (tests/link/test_link_fast_paths.py runs the link without it)
        if self._pending or board.has_output:
            self._pass_on(now)
        pieces, self._pieces = self._pieces, []
        events, self._events = self._events, []
        return LinkOutput(pieces, events)

    def next_deadline(self) -> float | None:
        return self.board.next_deadline()

    def next_wakeup(self) -> float | None:
        # bytes held here mean a board whose input is full (not settled: its next wake-up is
        # its next deadline); a wait character is released by a done or a limit, which no
        # quiet axis gives
        return self.board.next_wakeup()

    def _collect(self, now: float) -> bool:
        """The board's output to the pieces and events; True if the board was asked something
        (an event's registers were read), so that it may have said more."""
        out, sources = self.board.take_output_sourced()
        if not out:
            return False
        # the fast path: nothing but framed replies (a poll's answers): each its text and the
        # end character, as collect_all gives them (with no event, there is nothing to reorder)
        eos = self.eos
        try:
            # the texts, joined in C: an event has no text (AttributeError), echoed characters
            # have None (TypeError); only a Reply has the attribute
            data = eos.join(map(_TEXT, out)) + eos
        except (AttributeError, TypeError):
            return self.collect_all(out, sources, now)
        pieces, echoing = self._pieces, self._echoing
        source = sources[0]
        if not echoing and sources.count(source) == len(sources):
            # (one session's replies, no echo to end: merged one by one, they would be one
            # piece all the same; to_host has usually taken the pieces before)
            if pieces:
                merge(pieces, source, data)
            else:
                pieces.append((source, data))
            return False
        for item, source in zip(out, sources, strict=True):
            if source in echoing:
                self._end_echo(source)
            merge(pieces, source, _TEXT(item) + eos)
        return False

    def collect_all(self, out: list[Output], sources: list[int], now: float) -> bool:
        """The board's output to the pieces and events, item by item (what :meth:`_collect`
        does but for its fast path)."""
        board = self.board
        message_first(out, sources)
        pieces = self._pieces
        eos = self.eos
        events_before = len(self._events)
        for item, source in zip(out, sources, strict=True):
            if isinstance(item, Reply):
                if item.text is not None:
                    self._end_echo(source)
                    merge(pieces, source, item.text + eos)
                else:
                    self._echo(source, item.data)
                continue
            self._events.append(item)
            # the interrupt service routine reads the status register (clearing it) first
            status = board.read_status_register(now)
            mine = self._waiting is not None and source in (self._wait_session, 0)
            self._end_echo(source)
            if isinstance(item, CommandErrorEvent):
                merge(pieces, source, b"#" + eos)
            elif isinstance(item, LimitEvent):
                marked = self._limit_marked_at
                if marked.get(source) == item.time and not status & OVRT:
                    # limits reached on one sample set OVRT once: one interrupt, one "@"
                    # (§7.3.3: "A limit interrupt causes an @ character"); the first one's
                    # read of the status register cleared the bit, and it is not set again.
                    # Another session's limit of the sample is its host's interrupt: its "@"
                    # (and the wait it releases) is its own
                    continue
                marked[source] = item.time
                merge(pieces, source, b"@" + eos)
                if mine and self._waiting == WAIT_LIMIT and item.time >= self._wait_since:
                    self._release(now)
                else:
                    self._unclaimed[(WAIT_LIMIT, source)] = item.time
            elif isinstance(item, SlipEvent):
                merge(pieces, source, b"$" + eos)
            elif isinstance(item, DoneEvent):
                done = board.read_done_register(now)
                read_before = self._done_read_at
                self._done_read_at = now
                if not (done == 0 and read_before is not None and read_before >= item.time):
                    # completions a read of the register came after are one interrupt: those on
                    # the same sample, and those before a late run of the link (an interrupt
                    # served late); the first read has every bit, a second marker would only
                    # say "nothing"
                    merge(pieces, source, b"!" + bytes([done]) + eos)
                if mine and self._waiting == WAIT_DONE and item.time >= self._wait_since:
                    session = self._wait_session
                    self._release(now)
                    self._clear_done(now, session)
                else:
                    self._unclaimed[(WAIT_DONE, source)] = item.time
        return len(self._events) > events_before

    def _echo(self, source: int, data: bytes) -> None:
        """Echoed characters: the driver "strips off the LF and CR's"; where one ends echoed
        text, the text is a string and gets the end character."""
        out = bytearray()
        echoing = source in self._echoing
        for b in data:
            if b == 0x0A or b == 0x0D:
                if echoing:
                    out += self.eos
                    echoing = False
            else:
                out.append(b)
                echoing = True
        if echoing:
            self._echoing.add(source)
        else:
            self._echoing.discard(source)
        if out:
            merge(self._pieces, source, bytes(out))

    def _end_echo(self, source: int) -> None:
        """A reply or a marker for ``source``: echoed text before it is a string of its own."""
        if source in self._echoing:
            self._echoing.discard(source)
            merge(self._pieces, source, self.eos)
