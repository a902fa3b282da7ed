"""Streaming lexer for the OMS two-letter command language (PC48 §6.1).

The board reads a continuous character stream and never waits for a line end. Real clients send
``EFICAA SAAA RP`` and ``AX  LP600AX QA RP`` with no terminator at all (see
``shared/interop/README.md``), so:

* "All the commands are two ASCII characters and may be in upper or lower case." A command that
  takes no operand is complete the moment its second letter arrives.
* "The operand must be terminated by a space, carriage return or semi-colon to indicate the end
  of the number." A line feed, the next letter or any other character ends it as well.
* Multi-axis operands are comma separated; "An axis may be skipped by entering a comma with no
  parameter. The command may be prematurely terminated with a ';'."
* The manual's own examples put spaces between a mnemonic and its operand (``AY JG 12345``,
  ``MT 10,000,-1000;``) and after commas (``MR, -1000``, ``MR1000, 2000``). Spaces after a comma,
  and after a mnemonic whose operand is *required*, are skipped. After a mnemonic whose operand
  is optional (``HM``, ``MA``, ``AN`` …) a space ends the command, as §6.1 says ("The operand must
  immediately follow the command"): ``AX HM `` homes at once rather than waiting for a number.
  A space after a number ends the operand.

Bad input never raises. A character that cannot start a command, or a letter pair that is not a
command, produces one :class:`Garbage` token at once (a client waiting for the ``#`` of a bad
query must get it without sending more); the rest of the bad word (digits, punctuation, further
unknown letter pairs) is swallowed silently until a separator or a known command. The lexer
stores at most :data:`MAX_FIELD` characters per field and :data:`MAX_FIELDS` fields, so its
memory is bounded whatever it is fed.

Control-D and Control-Y never reach the lexer: they bypass the interpreter (PC48 §6.9, §6.12).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum, auto

from omsd.protocol.errors import ErrorKind

MAX_FIELD = 24
MAX_FIELDS = 16
MAX_TEXT = 48

SEPARATORS = frozenset(b" \t\r\n;")
NUMBER_CHARS = frozenset(b"0123456789+-.")
HEX_CHARS = frozenset(b"0123456789abcdefABCDEF")


@dataclass(frozen=True, slots=True)
class Command:
    """A complete command: upper-case mnemonic and its comma-separated fields.

    ``fields`` is ``None`` when no operand was given at all; a skipped field is ``None``.
    ``error`` is set when the operand was lexically unusable (too long, too many fields).
    """

    mnemonic: str
    fields: tuple[str | None, ...] | None
    text: str
    error: ErrorKind | None = None


@dataclass(frozen=True, slots=True)
class Garbage:
    """Characters that are not a command."""

    text: str
    kind: ErrorKind


Token = Command | Garbage


class Syntax(Enum):
    """What a mnemonic is to the lexer."""

    UNKNOWN = auto()
    BARE = auto()  # complete at its last character
    OPTIONAL = auto()  # may be followed by an operand; a space ends it
    REQUIRED = auto()  # expects an operand; spaces before it are skipped
    AXIS = auto()  # expects an operand that starts with an axis letter (PCIx EGX2,1;)
    HEX = auto()  # expects a hexadecimal operand (PCIx BS: "00 ≤ Hex number ≤ FF")


class _State(Enum):
    IDLE = auto()
    MNEMONIC = auto()  # part of a mnemonic seen
    OPERAND = auto()
    SWALLOW = auto()  # inside a bad word, after its error was reported


#: The states and syntaxes as module names: the lexer looks at them for every character, and
#: reading an Enum member through its class costs about 70 ns in Python 3.11 (a global, 10).
_IDLE, _MNEMONIC, _OPERAND, _SWALLOW = _State.IDLE, _State.MNEMONIC, _State.OPERAND, _State.SWALLOW
_UNKNOWN, _BARE, _REQUIRED, _AXIS, _HEX = (
    Syntax.UNKNOWN,
    Syntax.BARE,
    Syntax.REQUIRED,
    Syntax.AXIS,
    Syntax.HEX,
)

AXIS_LETTERS = frozenset(b"XYZTUVRSxyztuvrs")


def _is_letter(b: int) -> bool:
    return 65 <= b <= 90 or 97 <= b <= 122


class Lexer:
    """Byte-at-a-time tokenizer.

    ``syntax(mnemonic)`` classifies upper-case mnemonics. ``prefix(text)`` says whether ``text``
    begins a longer mnemonic: the PCIx dialect has three-letter mnemonics (``ADH``), queries
    (``?AC``, ``EG?``) and ``#WS``; the PC48 family has two-letter mnemonics only, none a prefix
    of another, so without ``prefix`` a command is complete at its second letter.
    """

    def __init__(
        self, syntax: Callable[[str], Syntax], prefix: Callable[[str], bool] | None = None
    ) -> None:
        self._syntax = syntax
        self._prefix = prefix or (lambda text: len(text) < 2 and text.isalpha())
        self.reset()

    def reset(self) -> None:
        self._state = _IDLE
        self._word = ""  # the mnemonic being read (upper case)
        self._raw = bytearray()  # as received
        self._swallowing = False
        self._mnemonic = ""
        self._text = bytearray()
        self._fields: list[str | None] = []
        self._field = bytearray()
        self._started = False
        self._skip_spaces = False
        self._axis_first = False
        self._digits = NUMBER_CHARS
        self._error: ErrorKind | None = None

    @property
    def idle(self) -> bool:
        """True when no command is partly received."""
        return self._state in (_IDLE, _SWALLOW)

    @property
    def between_commands(self) -> bool:
        """True when the next character starts afresh (not inside a command or a bad word)."""
        return self._state is _IDLE

    def bare_words(self, mnemonics: list[str]) -> dict[bytes, Command]:
        """For the fast paths (issue 16): every spelling (any case) of the operand-less
        mnemonics of two or three characters that a lexer between commands takes whole, each
        with the command it is. Fed to a lexer between commands, such a word gives exactly that
        command and leaves the lexer between commands again (what a word has to be is not
        reasoned out here: each spelling is fed to a fresh lexer of the same syntax, and kept
        if that is what it does). A mnemonic that begins a longer one is not among them."""
        out: dict[bytes, Command] = {}
        for m in mnemonics:
            if not 2 <= len(m) <= 3 or self._syntax(m) is not _BARE:
                continue
            command = Command(m, None, m)
            spellings = [b""]
            for c in m:
                cases = {c.upper(), c.lower()}
                spellings = [s + x.encode("latin-1") for s in spellings for x in sorted(cases)]
            for word in spellings:
                probe = Lexer(self._syntax, self._prefix)
                tokens: list[Token] = []
                for b in word:
                    tokens += probe.feed(b)
                if tokens == [command] and probe.between_commands:
                    out[word] = command
        return out

    def feed(self, b: int) -> list[Token]:
        out: list[Token] = []
        self._step(b, out)
        return out

    def give_back(self) -> bytes:
        """The characters of a word begun and not complete (the letter that ended the last
        command's operand), handed back; the lexer is between commands again. For text that
        follows a command and is not commands (the PCIx's MD: the macro's command string)."""
        begun = bytes(self._raw) if self._state is _MNEMONIC else b""
        self.reset()
        return begun

    # -- states -------------------------------------------------------------------------------

    def _step(self, b: int, out: list[Token]) -> None:
        state = self._state
        if state is _OPERAND:
            self._operand(b, out)
        elif state is _MNEMONIC:
            self._more(b, out)
        elif state is _SWALLOW:
            if b in SEPARATORS:
                self._state = _IDLE
            elif self._starts_word(b):
                self._begin_word(b, swallowing=True)
        else:
            self._idle(b, out)

    def _starts_word(self, b: int) -> bool:
        return _is_letter(b) or (b in (0x3F, 0x23) and self._prefix(chr(b)))  # ? #

    def _begin_word(self, b: int, swallowing: bool) -> None:
        self._word = chr(b).upper()
        self._raw = bytearray([b])
        self._swallowing = swallowing
        self._state = _MNEMONIC

    def _idle(self, b: int, out: list[Token]) -> None:
        if b in SEPARATORS:
            return
        if self._starts_word(b):
            self._begin_word(b, swallowing=False)
            return
        out.append(Garbage(_printable(bytes([b])), ErrorKind.BAD_CHARACTER))
        self._state = _SWALLOW

    def _more(self, b: int, out: list[Token]) -> None:
        word = self._word
        extends = _is_letter(b) or b == 0x3F  # a letter, or the ? of "EG?"
        if extends:
            candidate = word + chr(b).upper()
            syntax = self._syntax(candidate)
            longer = self._prefix(candidate)
            if syntax is not _UNKNOWN or longer:
                self._word = candidate
                self._raw.append(b)
                if syntax is not _UNKNOWN and not longer:
                    self._complete(candidate, out, syntax)
                return
        syntax = self._syntax(word)
        if syntax is not _UNKNOWN:
            # a complete mnemonic that could have been the start of a longer one, and is not
            self._complete(word, out, syntax)
            self._step(b, out)
            return
        if not self._swallowing:
            text = bytes(self._raw) + (bytes([b]) if extends or len(self._raw) == 1 else b"")
            kind = ErrorKind.UNKNOWN_COMMAND
            out.append(Garbage(_printable(text).upper() if extends else _printable(text), kind))
        if len(self._raw) == 1 or not extends:
            self._state = _IDLE if b in SEPARATORS else _SWALLOW
        else:
            self._state = _SWALLOW
            self._step(b, out)

    def _complete(self, mnemonic: str, out: list[Token], syntax: Syntax) -> None:
        self._swallowing = False
        if syntax is _BARE:
            out.append(Command(mnemonic, None, mnemonic))
            self._state = _IDLE
        else:
            self._begin_operand(mnemonic, syntax)

    def _begin_operand(self, mnemonic: str, syntax: Syntax) -> None:
        self._mnemonic = mnemonic
        self._text = bytearray(mnemonic.encode("ascii"))
        self._fields = []
        self._field = bytearray()
        self._started = False
        self._skip_spaces = syntax is _REQUIRED
        self._axis_first = syntax is _AXIS
        self._digits = HEX_CHARS if syntax is _HEX else NUMBER_CHARS
        self._error = None
        self._state = _OPERAND

    def _operand(self, b: int, out: list[Token]) -> None:
        if self._axis_first:
            self._axis_first = False
            if b in AXIS_LETTERS:  # EGX…: the axis letter is the first field
                self._field.append(b & 0xDF)
                self._keep(b)
                self._started = True
                return
        if b in self._digits:
            if len(self._field) < MAX_FIELD:
                self._field.append(b)
            else:
                self._error = ErrorKind.OVERLONG
            self._keep(b)
            self._started = True
            self._skip_spaces = False
        elif b == 0x2C:  # ','
            self._close_field()
            self._keep(b)
            self._started = True
            self._skip_spaces = True
        elif b in (0x20, 0x09) and self._skip_spaces:
            self._keep(b)
        else:
            self._finish(out)
            if b not in SEPARATORS:
                self._step(b, out)

    def _keep(self, b: int) -> None:
        if len(self._text) < MAX_TEXT:
            self._text.append(b)

    def _close_field(self) -> None:
        if len(self._fields) < MAX_FIELDS:
            self._fields.append(self._field.decode("ascii") if self._field else None)
        else:
            self._error = self._error or ErrorKind.TOO_MANY_PARAMETERS
        self._field = bytearray()

    def _finish(self, out: list[Token]) -> None:
        fields: tuple[str | None, ...] | None = None
        if self._started:
            self._close_field()
            fields = tuple(self._fields)
        text = self._text.decode("ascii").rstrip(" \t")
        out.append(Command(self._mnemonic, fields, text, self._error))
        self._state = _IDLE


def _printable(raw: bytes) -> str:
    return "".join(chr(c) if 32 <= c < 127 else f"<{c:02X}>" for c in raw)
