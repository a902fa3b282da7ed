"""The EPICS omsMAXnet client's reading of the PCIx's replies, as the MAX-family reviews use it
(``test_reviewed_max_family.py``, ``test_reviewed_max_sequences.py``).

Transcribed from ``epics-motor/motorOmsAsyn`` ``omsAsynApp/src/omsMAXnet.cpp`` and
``omsBaseController.cpp``:

* ``omsMAXnet::sendReceive`` reads up to the input EOS ``"\\n\\r"`` (and would cut "a leading
  CR, NL, /006"; the PCIx manual frames a reply ``text<LF><CR>`` with nothing before it, which
  :func:`receive` holds);
* ``getAxesStatus`` (``AM;RI;``): ``if (!((inputBuff[0] == 'P') || (inputBuff[0] == 'M')))``,
  ``if (strlen(inputBuff) < (unsigned int)(numAxes * 5 -1))``, and the poller's fixed offsets,
  five characters per axis;
* ``getAxesArray`` (``AM PP;``, ``AM PE;``, ``AM;RV;``): ``strtol`` field by field, ``if (count
  != numAxes) ... return asynError;``;
* ``AM;QL;``: ``sscanf(pollInputBuffer, "%x", &limitFlags)``, bit ``i`` the low limit and
  ``i + 8`` the high one, exclusive-or'ed with the axis's invert flag (``LT?`` said ``=l``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from omsd.board.harness import Harness


def receive(h: Harness, line: str) -> str:
    """omsMAXnet::sendReceive: one ``text\\n\\r`` read to the EOS, nothing before it."""
    data = h.send(line + "\n")
    assert data.endswith(b"\n\r") and data.count(b"\n\r") == 1, (line, data)
    assert data[:1] not in (b"\x06", b"\r", b"\n"), (line, data)
    return data[:-2].decode("ascii")


def axes_array(text: str, n: int) -> list[int]:
    """getAxesArray: ``n`` comma-separated integers, each read by strtol."""
    fields = text.split(",")
    assert len(fields) == n, text
    assert all(re.fullmatch(r"-?\d+", f) for f in fields), text
    return [int(f) for f in fields]


def axes_status(text: str, n: int) -> list[str]:
    """getAxesStatus and the poller's fixed offsets (five characters per axis)."""
    assert text[:1] in ("P", "M") and len(text) >= n * 5 - 1, text
    fields = [text[i * 5 : i * 5 + 4] for i in range(n)]
    assert all(re.fullmatch(r"[PM][DN][LN][HN]", f) for f in fields), text
    return fields


@dataclass
class Poll:
    """One round of omsBaseController::omsPoller, as it parses it; ``QL`` the reply's text."""

    RI: list[str]
    PP: list[int]
    PE: list[int]
    RV: list[int]
    CL: list[str]
    EA: list[str]
    QL: str

    def limits(self, i: int, invert: bool = False) -> tuple[bool, bool]:
        """The poller's QL decode for axis ``i``: (low limit, high limit). The reply is hex
        digits and nothing else (``sscanf "%x"`` would stop at anything else)."""
        assert re.fullmatch(r"[0-9a-fA-F]+", self.QL), self.QL
        flags = int(self.QL, 16)
        return bool(flags & (1 << i)) ^ invert, bool(flags & (1 << (i + 8))) ^ invert


def poll(h: Harness) -> Poll:
    """One poll of every axis of the board, each reply read as the client reads it."""
    n = len(h.board.model.axes)
    out = Poll(
        RI=axes_status(receive(h, "AM;RI;"), n),
        PP=axes_array(receive(h, "AM PP;"), n),
        PE=axes_array(receive(h, "AM PE;"), n),
        RV=axes_array(receive(h, "AM;RV;"), n),
        CL=receive(h, "AM;CL?;").split(","),
        EA=receive(h, "AM;EA;").split(","),
        QL=receive(h, "AM;QL;"),
    )
    assert receive(h, "#WS") == "=0"
    assert len(out.CL) == n and set(out.CL) <= {"on", "off"}, out
    assert len(out.EA) == n, out
    assert h.errors() == []
    return out
