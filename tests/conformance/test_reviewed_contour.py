"""Contouring and linear interpolation where a review against the manuals found omsd wrong.

* PCIx RC inside a contour: "While a contour is executing, the value computed to generate the
  appropriate lead in will be returned" (PCIx §5, RC REPORT ACCELERATION), as the PC48 already
  does; it used to report the acceleration of the moment (0 on the constant-velocity path).
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r"))


@pytest.mark.parametrize("start", ["CX;", "CG;"])
def test_pcix_rc_reports_the_lead_in_for_the_whole_contour(start: str) -> None:
    """RC: "When the stage is running at programmed speed; i.e. not accelerating, the parameter
    returned will be zero (0). While a contour is executing, the value computed to generate the
    appropriate lead in will be returned." X goes 1000 steps from 0 to the start (1000,0) to
    reach CV1000 there: 1000² / (2 × 1000) = 500 steps/s² over the 2 s lead-in; then a line at
    constant speed (2 s to 3 s), a quarter circle (3 s to 4.57 s) and the CE ramp down. RC is
    500 all along (it was 0 on the line and the arc's centripetal share on the arc), and 0 once
    the axis is at rest."""
    h = Harness("PCIX-004")
    h.send(f"AA;CV1000;CD1000,0;MT2000,0;CR2000,1000,1.5707963;MT3000,2000;CE;{start}")
    for t in (0.5, 2.5, 3.5, 4.2):
        h.until(t)
        assert number(h.send("AX;RC;")) == 500, t
        assert number(h.send("AY;RC;")) == 0, t  # Y has no share of the lead-in (along X)
    h.run()
    assert number(h.send("AX;RC;")) == 0
    assert h.errors() == []
