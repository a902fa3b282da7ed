"""The lexer on the PCIx dialect's forms: three-letter mnemonics (ADH, SVN), queries (?AC, ?AJ5;),
query suffixes of the MAX family (EG?, PS?), ``#WS``, and EG's axis-letter operand (EGX1,2;)."""

from __future__ import annotations

import pytest

from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command, Garbage, Lexer, Syntax, Token

TABLE = {
    "AC": Syntax.REQUIRED,
    "AD": Syntax.UNKNOWN,
    "ADH": Syntax.BARE,
    "ADL": Syntax.BARE,
    "AX": Syntax.BARE,
    "EG": Syntax.AXIS,
    "EGF": Syntax.BARE,
    "EG?": Syntax.BARE,
    "PS?": Syntax.BARE,
    "?AC": Syntax.BARE,
    "?AJ": Syntax.REQUIRED,
    "#WS": Syntax.BARE,
    "SVN": Syntax.BARE,
    "RP": Syntax.BARE,
    "MR": Syntax.REQUIRED,
    "MA": Syntax.OPTIONAL,
}
KNOWN = {m: s for m, s in TABLE.items() if s is not Syntax.UNKNOWN}
PREFIXES = {m[:i] for m in KNOWN for i in range(1, len(m))}


def lex(data: bytes) -> list[Token]:
    lexer = Lexer(lambda m: KNOWN.get(m, Syntax.UNKNOWN), lambda t: t in PREFIXES)
    out: list[Token] = []
    for b in data:
        out += lexer.feed(b)
    return out


def names(tokens: list[Token]) -> list[str]:
    return [t.mnemonic if isinstance(t, Command) else f"!{t.text}" for t in tokens]


def test_three_letter_mnemonics_complete_at_their_third_letter() -> None:
    assert names(lex(b"ADH")) == ["ADH"]
    assert names(lex(b"AX;SVN;ADL")) == ["AX", "SVN", "ADL"]


def test_a_two_letter_command_that_begins_a_longer_one_waits_for_the_next_character() -> None:
    """EG is a command and the start of EGF and EG?: the next character decides."""
    assert names(lex(b"EGF")) == ["EGF"]
    assert names(lex(b"EG?")) == ["EG?"]
    tokens = lex(b"EGX2,1;RP")
    assert tokens == [Command("EG", ("X2", "1"), "EGX2,1"), Command("RP", None, "RP")]


def test_axis_letter_operand() -> None:
    assert lex(b"egy-2,1;")[0] == Command("EG", ("Y-2", "1"), "EGy-2,1")
    assert lex(b"EGX;")[0] == Command("EG", ("X",), "EGX")


def test_queries() -> None:
    assert names(lex(b"?AC ?AJ5;RP")) == ["?AC", "?AJ", "RP"]
    assert lex(b"?AJ5;")[0] == Command("?AJ", ("5",), "?AJ5")
    assert names(lex(b"PS?;#WS")) == ["PS?", "#WS"]


def test_lower_case() -> None:
    assert names(lex(b"adh;svn;?ac;eg?")) == ["ADH", "SVN", "?AC", "EG?"]


def test_unknown_words_are_one_error_each() -> None:
    assert names(lex(b"ADX RP")) == ["!ADX", "RP"]
    assert names(lex(b"?ZZ RP")) == ["!?Z", "RP"]
    assert names(lex(b"QQ RP")) == ["!QQ", "RP"]


@pytest.mark.parametrize("cut", range(1, 12))
def test_split_anywhere(cut: int) -> None:
    data = b"ADH;?AC;EGX2,1;PS?"
    lexer = Lexer(lambda m: KNOWN.get(m, Syntax.UNKNOWN), lambda t: t in PREFIXES)
    out: list[Token] = []
    for chunk in (data[:cut], data[cut:]):
        for b in chunk:
            out += lexer.feed(b)
    assert names(out) == ["ADH", "?AC", "EG", "PS?"]


def test_hash_and_question_mark_are_garbage_without_such_mnemonics() -> None:
    """The PC48 family: '?' and '#' begin no command."""
    lexer = Lexer(lambda m: Syntax.BARE if m == "RP" else Syntax.UNKNOWN)
    out: list[Token] = []
    for b in b"?KP #WS RP":
        out += lexer.feed(b)
    assert out == [
        Garbage("?", ErrorKind.BAD_CHARACTER),
        Garbage("#", ErrorKind.BAD_CHARACTER),
        Command("RP", None, "RP"),
    ]
