"""The PC48 family (PC48, VS4, PC46) where a review against the manuals (2026-11-28) found small
gaps, each pinned with the manual's words.

* HH and HL are a command error in the encoder home mode: "The external enable is low true,
  i.e. the HH and HL commands are not valid in this mode" (PC48 §6.18 HE; the VS4's HE the
  same). They were accepted silently.
"""

from __future__ import annotations

import pytest

from omsd.board import Board
from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.link import DriverLink
from omsd.models import get_model


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PC46-2E"])
@pytest.mark.parametrize("level", ["HH", "HL"])
def test_hh_and_hl_are_not_valid_in_the_encoder_home_mode(model: str, level: str) -> None:
    """PC48 §6.18 HE: "Home is defined as the logical AND of the encoder index, the external
    home enable and the encoder quadrant ... The external enable is low true, i.e. the HH and HL
    commands are not valid in this mode." (the VS4's HE: the same words; the PC46 datasheet,
    silent, behaves as the PC48). A command error, as every command "Not valid" in a mode; the
    level is left as it was. HS (the switch mode, whose level "may be controlled by the HH and
    HL commands") makes them valid again."""
    h = Harness(model)
    h.send(f"AX HE {level} ")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, level)]
    h.until(0.01)
    assert h.axis("X").home_high is False  # the power-up level (HL), untouched
    h.send("HS HH ")
    h.until(0.02)
    assert h.errors() == []
    assert h.axis("X").home_high is True


def test_hh_in_the_encoder_home_mode_is_a_hash_through_the_driver() -> None:
    """§7.3.3: "When a command error occurs it places a # symbol followed by the "E:" specified
    end character"."""
    link = DriverLink(Board(get_model("PC48-4E"), 0.0))
    link.from_host(b"AX HE HH WY", 0.0)
    assert link.to_host(0.0).data == b"#\nPC48 ver 3.00-4\n"
