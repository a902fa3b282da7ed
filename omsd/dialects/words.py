"""What the command table's mnemonics are to the lexer, and the words the interpreter's fast
path takes whole (issue 16).

:class:`SyntaxTable` tells the lexer, for every mnemonic, whether an operand follows
(:func:`syntax`, from the queue table's row). :class:`Words` are the operand-less commands a
lexer between commands reads whole, in every spelling: the interpreter looks its input buffer's
first characters up among them (``Interpreter.pump``) and the board a whole input among the
reports (``Board.receive``), instead of feeding the lexer a character at a time.
"""

from __future__ import annotations

from dataclasses import dataclass

from omsd.models.spec import CommandSpec
from omsd.protocol.lexer import Command, Lexer, Syntax


class SyntaxTable(dict[str, Syntax]):
    """Mnemonic -> syntax, UNKNOWN for anything else (looked up for every letter received)."""

    def __missing__(self, key: str) -> Syntax:
        return Syntax.UNKNOWN


def syntax(spec: CommandSpec) -> Syntax:
    if spec.letter_operand:
        return Syntax.AXIS
    if spec.hex_operand:
        return Syntax.HEX
    if not spec.operand:
        return Syntax.BARE
    return Syntax.OPTIONAL if spec.optional else Syntax.REQUIRED


@dataclass(frozen=True, eq=False, repr=False)  # one a syntax: as omsd.dialects.registry.Dialect
class Words:
    """The operand-less commands a lexer between commands takes whole
    (:meth:`~omsd.protocol.lexer.Lexer.bare_words`): by their spelling, by the spelling packed
    into an int with its length (:func:`packed`: what the input buffer's first characters are
    looked up by), and the reports among them. Shared by every interpreter of the same syntax
    (:func:`words_of`)."""

    spelled: dict[bytes, Command]
    packed: dict[int, Command]
    reports: dict[bytes, Command]
    longest: int


def pack2(a: int, b: int) -> int:
    """Two characters as one int (a dict key): ``1 << 16 | a << 8 | b``."""
    return 0x10000 | a << 8 | b


def pack3(a: int, b: int, c: int) -> int:
    """Three characters as one int, never equal to two packed (whatever the bytes)."""
    return 0x1000000 | a << 16 | b << 8 | c


def packed(word: bytes) -> int:
    return pack2(*word) if len(word) == 2 else pack3(*word)


_WORDS: dict[tuple[frozenset[tuple[str, Syntax]], bool, frozenset[str]], Words] = {}


def words_of(lexer: Lexer, syntax: dict[str, Syntax], long: bool, reports: frozenset[str]) -> Words:
    key = (frozenset(syntax.items()), long, reports)
    words = _WORDS.get(key)
    if words is None:
        spelled = lexer.bare_words(list(syntax))
        words = _WORDS[key] = Words(
            spelled,
            {packed(w): c for w, c in spelled.items()},
            {w: c for w, c in spelled.items() if c.mnemonic in reports},
            max(map(len, spelled), default=0),
        )
    return words
