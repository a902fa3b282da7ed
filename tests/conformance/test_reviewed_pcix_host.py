"""The PCIx beyond its motion commands, where a review against its manual
(002_5f0bea9264c6d239.txt: chapter 3, the host interface; §5.4, identification, flash and
macros) found omsd wrong.

* MD: the command string of a macro begins right after the macro number ("Enter the macro
  number immediately after the MD command ... Next enter the command string"). A number ended
  by the command string's first letter (``MD1VL1000;^Z``, a letter ending an operand as
  everywhere in omsd: ``docs/decisions.md``, "The character stream") lost that letter: the
  macro was ``L1000;`` and the letter was left in the lexer, where it made the host's next
  command after the Control-Z an unknown command.
"""

from __future__ import annotations

from omsd.board.harness import Harness

from .pcix import reply


def test_a_macro_begins_with_the_letter_that_ended_its_number() -> None:
    """MD page: "Enter the macro number immediately after the MD command. The macro number must
    be between 0 and 4. Next enter the command string, which is made up of up to 250 ASCII
    characters. After entering the command string for the macro, enter a control Z to end the
    macro definition." PM "will return the command string stored in the specified macro number
    as a command response". ``MD1VL1000;`` is macro 1, ``VL1000;``; the PM typed after it is
    answered (it was an unknown command ``VP``, and the macro ``L1000;``)."""
    h = Harness("PCIX-004")
    assert h.send("MD1VL1000;\x1a") == b""
    assert h.send("PM1;") == reply("VL1000;")
    assert h.errors() == []
    h.send("MD2?AQ;^Z")  # a query's "?" begins a command string as well
    assert h.send("PM2;") == reply("?AQ;")
    assert h.send("MX1;AX;?VL;") == reply("vl1000")
    assert h.errors() == []


def test_a_macro_number_ended_by_a_separator_is_not_part_of_the_macro() -> None:
    """The MD example: "MD2; AA; VL20000,20000; ^Z" — the separator ends the number ("The operand
    must be terminated by a space, carriage return, or semi-colon", §5.1) and is not stored."""
    h = Harness("PCIX-004")
    h.send("MD2;AA;^Z")
    h.send("MD3 AX;^Z")
    assert h.send("PM2;PM3;") == reply("AA;") + reply("AX;")
    assert h.errors() == []
