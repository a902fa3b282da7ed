"""The synchronized-move template of the four manuals, typed as printed.

PC48 §6.1: "This command performs a context switch which allows entering the commands in the
format MRx#,y#,z#,t#,u#,v#,r#,s#;. ... a move requiring only the X and Y axes would use the
command MRx#,y#; followed by the GO command." The VS4 (§6.1), the PC46 datasheet ("MRx#y#,z#,
t#,u#,v#") and the PCIx (§5.1, "MRx#,y#,z#,t#;") say the same. ``x#`` is a placeholder for the
X value: every worked example of the four manuals writes the bare numbers (PC48 E1 ``AA
MA12000,14000; GO``, E43 ``AA MR12345,6789 GO``, PCIx E3 ``MA12000,14000;``). Typed literally,
``MRx100,y200;`` is read as a bad word: one command error, nothing moves (docs/decisions.md,
"Command strings quoted in running text").
"""

from __future__ import annotations

import pytest

from omsd.board.events import ErrorKind

from .support import errors, quiet

MODELS = [("PC48-4", "\r"), ("VS4-040", "\r"), ("PC46-42", "\r"), ("PCIX-004", ";\r")]


@pytest.mark.parametrize(("model", "end"), MODELS, ids=[m for m, _ in MODELS])
def test_template_letters_are_placeholders(model: str, end: str) -> None:
    h = quiet(model)
    h.send(f"AA{end}MRx100,y200;GO{end}")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [0, 0, 0, 0]
    assert errors(h) == [(ErrorKind.UNKNOWN_COMMAND, "x1")]


@pytest.mark.parametrize(("model", "end"), MODELS, ids=[m for m, _ in MODELS])
def test_template_with_the_numbers_moves_x_and_y(model: str, end: str) -> None:
    """``MRx#,y#;`` with the numbers in place of ``x#`` and ``y#``: X and Y start together and Z
    and T, left out by the early ";", stay."""
    h = quiet(model)
    h.send(f"AA{end}MR100,200;GO{end}")
    h.run()
    assert [h.position(a) for a in "XYZT"] == [100, 200, 0, 0]
    assert errors(h) == []
