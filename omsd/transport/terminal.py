"""The terminal option of an endpoint: a board a person can type to from picocom, minicom or
screen.

Off by default, so that programs get the card's exact bytes. On (``terminal = true`` on a pty or
TCP endpoint of the configuration, ``--terminal`` for the ptys of the single-board command
line), the endpoint stands between the board and the terminal program as a terminal driver's
cooked mode would (docs/decisions.md, "The terminal option"):

* **Input, a line at a time.** What is typed is shown as it is typed (the terminal programs
  show nothing of it themselves); Backspace or DEL erases the last character, Control-U the
  line; Enter (CR, LF or CR LF) sends the line to the board followed by a CR, a separator the
  board accepts (§6.1). Arrow and function keys (escape sequences) are ignored. Any other
  control character goes to the board at once, ahead of the line being typed (Control-D, the
  kill of §6.9, never waits for Enter), and is shown as ``^D`` on a line of its own.
* **While the board's own echo is on** (``EN``) characters go to the board as they are typed,
  and the board's echo is what shows, as with OMS's PC4XCOMM program: no local echo, no line
  editing. Enter still starts a new line on the screen.
* **Output.** Each line end of the board (LF, CR, the pairs of its framing, the driver's end
  character) is shown as one CR LF, and no empty line is shown: ``RP`` shows ``0`` on a line
  of its own. What the board says never lands on the line being typed: a new line first, and
  the typed line is shown again after it. On the driver link the byte after a ``!`` (the
  done-flag register, binary) is shown as two hex digits (``!01``: X is done), since the byte
  itself could be a line feed, a backspace or an escape; other control characters are shown as
  ``^X``, bytes above 0x7E as ``\\xNN``.

The traffic log shows what reached the board and what the board said, not the display. Sans-I/O:
the endpoints (:mod:`omsd.transport.pty`, :mod:`omsd.transport.tcp`) hand it bytes.
"""

from __future__ import annotations

from collections.abc import Callable

from omsd.link import DriverLink, Link

LF, CR, BS, TAB, ESC, DEL = 0x0A, 0x0D, 0x08, 0x09, 0x1B, 0x7F
CONTROL_U = 0x15
BELL = b"\x07"
NEWLINE = b"\r\n"
MAX_LINE = 4096  # characters of a typed line; more rings the bell

# where the cursor is
_START, _TYPED, _BOARD = 0, 1, 2  # at a line start; on the typed line; on the board's line


def _visible(b: int) -> bytes:
    if b < 0x20 or b == DEL:
        return b"^" + bytes([b ^ 0x40])
    if b > DEL:
        return b"\\x%02X" % b
    return bytes([b])


class Terminal:
    """One terminal session's line editing and display.

    ``eos``: the driver link's end-of-string character (a line end here too), None on the raw
    link; ``markers``: the output carries the driver's ``!`` + done byte; ``echoing``: whether
    the board's own echo (EN) is on now.
    """

    def __init__(
        self,
        eos: int | None = None,
        markers: bool = False,
        echoing: Callable[[], bool] = lambda: False,
    ) -> None:
        self.eos = eos
        self.markers = markers
        self.echoing = echoing
        self.reset()

    def reset(self) -> None:
        """A new session: a new program on the other side, nothing typed, nothing shown."""
        self.line = bytearray()  # typed, not yet sent
        self._cursor = _START
        self._after_cr = False  # the last key was a CR (a CR LF is one Enter)
        self._escape = 0  # inside an escape sequence: 1 after ESC, 2 in CSI, 3 after ESC O
        self._string_start = True  # the board's next byte begins a string (driver framing)
        self._done_byte = False  # the board's next byte is the done-flag register

    # -- what the user types --------------------------------------------------------------------

    def typed(self, data: bytes) -> tuple[bytes, bytes]:
        """Bytes from the terminal: what goes to the board, and what to show."""
        board = bytearray()
        screen = bytearray()
        for b in data:
            if self._escape:
                self._skip_escape(b)
                continue
            if b == ESC:
                self._escape = 1
                continue
            if b == LF and self._after_cr:
                self._after_cr = False
                continue
            self._after_cr = b == CR
            if self.echoing():  # the board shows what it reads: pass it straight on
                board += self.line
                self.line.clear()
                board.append(b)
                if b in (CR, LF):
                    screen += self._new_line()
                continue
            if b in (CR, LF):
                board += self.line
                board.append(CR)
                self.line.clear()
                screen += NEWLINE
                self._cursor = _START
            elif b in (BS, DEL):
                if self.line:
                    self.line.pop()
                    if self._cursor == _TYPED:
                        screen += b"\b \b"
                        if not self.line:  # a typed line starts a screen line
                            self._cursor = _START
                    else:  # the board wrote after it: show what is left on a new line
                        screen += self._new_line() + self._retype()
            elif b == CONTROL_U:
                if self._cursor == _TYPED:
                    screen += b"\b \b" * len(self.line)
                    self._cursor = _START  # a typed line starts a screen line
                self.line.clear()
            elif b < 0x20 and b != TAB:
                board.append(b)
                screen += self._new_line() + _visible(b) + NEWLINE
                self._cursor = _START
                screen += self._retype()
            elif len(self.line) >= MAX_LINE:
                screen += BELL
            else:
                if self._cursor == _BOARD:  # the board wrote after it: a new line, the line again
                    screen += self._new_line() + self._retype()
                self.line.append(b)
                screen += b" " if b == TAB else bytes([b])
                self._cursor = _TYPED
        return bytes(board), bytes(screen)

    def _skip_escape(self, b: int) -> None:
        if self._escape == 1:
            self._escape = 2 if b == ord("[") else 3 if b == ord("O") else 0
        elif self._escape == 2:
            if 0x40 <= b <= 0x7E:
                self._escape = 0
        else:
            self._escape = 0

    # -- what the board says --------------------------------------------------------------------

    def shown(self, data: bytes) -> bytes:
        """Bytes from the board: what to show."""
        screen = bytearray()
        eos = self.eos
        for b in data:
            if self._done_byte:
                self._done_byte = False
                screen += b"%02X" % b
                continue
            if b in (LF, CR, eos):
                if self._cursor == _BOARD:
                    screen += NEWLINE
                    self._cursor = _START
                self._string_start = True
                continue
            if self._cursor == _TYPED:
                screen += self._new_line()
            if self.markers and self._string_start and b == 0x21:  # "!"
                self._done_byte = True
            self._string_start = False
            screen += _visible(b)
            self._cursor = _BOARD
        screen += self._retype()
        return bytes(screen)

    # -- the cursor -----------------------------------------------------------------------------

    def _new_line(self) -> bytes:
        if self._cursor == _START:
            return b""
        self._cursor = _START
        return NEWLINE

    def _retype(self) -> bytes:
        """At a line start with a line being typed: show it again."""
        if self._cursor != _START or not self.line:
            return b""
        self._cursor = _TYPED
        return bytes(self.line.replace(b"\t", b" "))


def terminal_for(link: Link, echoing: Callable[[], bool]) -> Terminal:
    """The terminal of an endpoint of a board served through ``link``."""
    if isinstance(link, DriverLink):
        return Terminal(eos=link.eos[0], markers=True, echoing=echoing)
    return Terminal(echoing=echoing)
