"""PCIx macros (§5.4.7): "Macros are storage areas in the PCIX of which 5 are “temporary”; i.e.
not saved at power-off, and 20 are “permanent”; i.e. stored in non-volatile flash RAM."

* ``MD#`` (0..4) starts a definition: every character up to Control-Z ("ASCII value 26 or the
  string “^Z”") is the macro, stored "as ASCII character strings" as typed, line feeds
  included ("If <LF> character is used as command terminator it will be sent back to the host
  computer by the PM command").
* "Be careful not to exceed 250 ASCII characters": a longer definition sets the command-error
  flag and leaves the slot as it was (the manual does not say what the board does; storing a
  truncated macro would run half a program).
* ``PT#,#`` copies a temporary macro into a permanent one; the permanent ones live in the
  board's flash (:class:`omsd.statefile.BoardFlash`), which the board saves.
* A power cycle or reset empties the temporary macros only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

CONTROL_Z = 0x1A
MACRO_LIMIT = 250
TEMPORARY = range(0, 5)
PERMANENT = range(5, 25)


@dataclass
class MacroCapture:
    """An MD definition being received (the interpreter's capture: characters go here, not to
    the lexer); ``done`` is told when it has ended."""

    slot: int
    data: bytearray = field(default_factory=bytearray)
    overlong: bool = False
    done: Callable[[MacroCapture, float], None] | None = field(default=None, repr=False)

    def feed(self, b: int) -> bool:
        """Take one character; True once the definition has ended."""
        if b == CONTROL_Z:
            return True
        if b in (0x5A, 0x7A) and self.data.endswith(b"^"):  # ^Z (or ^z)
            del self.data[-1]
            return True
        if len(self.data) > MACRO_LIMIT:
            self.overlong = True
            del self.data[:-1]  # keep the last character: it may be the caret of ^Z
        self.data.append(b)
        return False

    def finish(self, t: float) -> None:
        if self.done is not None:
            self.done(self, t)

    @property
    def text(self) -> bytes | None:
        if self.overlong or len(self.data) > MACRO_LIMIT:
            return None
        return bytes(self.data)


class MacroStore:
    """The 25 macro slots. Permanent slots are loaded from and saved to flash by the board."""

    def __init__(self) -> None:
        self.slots: dict[int, bytes] = {}

    def reset(self) -> None:
        """Power-up: "5 are “temporary”; i.e. not saved at power-off"."""
        for n in TEMPORARY:
            self.slots.pop(n, None)

    def define(self, slot: int, text: bytes | None) -> bool:
        if text is None:
            return False
        self.slots[slot] = text
        return True

    def get(self, slot: int) -> bytes | None:
        return self.slots.get(slot)

    def permanent(self) -> dict[int, str]:
        return {n: t.decode("latin-1") for n, t in self.slots.items() if n in PERMANENT}

    def load_permanent(self, macros: dict[int, str]) -> None:
        for n in PERMANENT:
            self.slots.pop(n, None)
        for n, text in macros.items():
            if n in PERMANENT:
                self.slots[n] = text.encode("latin-1")
