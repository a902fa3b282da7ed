"""Operand ranges of the PCIx's language (row type: :mod:`omsd.protocol.ranges`).

Source: the PCIx user's manual (``shared/seeds/002_5f0bea9264c6d239.txt``); its command pages
(chapter 5, alphabetical) print most ranges on a "RANGE:" line, quoted in ``cite``. Where a page
prints none, or prints two, ``choice`` records what was chosen ("manual silent: ...", "manual
contradicts itself: ..."). On top of every row, §5.3's rule holds
for every numeric operand: "numeric parameters must be within the range of a 32-bit signed
integer ... Entering parameter values outside the range of a signed 32-bit integer will cause a
Command Error" (checked by the interpreter before the command's own row).

The position range: LP's and SO's pages print "−33,554,431 ≤ … ≤ 33,554,431", the IN, MV and TL
pages "33,544,431" (a digit slip of the same number) and Appendix C "±33,500,000" (rounded):
±33,554,431 is taken for every position (``omsd/models/pcix.py``).

The MAX-family extension's commands (``omsd/models/max_family.py``: CL, LPE) are not in the
PCIx manual; their rows name the client they come from.
"""

from __future__ import annotations

from omsd.protocol.ranges import RangeTable

from .a_to_k import ROWS as _A_TO_K
from .kit import FAMILIES
from .l_to_w import ROWS as _L_TO_W

ROWS = [*_A_TO_K, *_L_TO_W]

PCIX_RANGES = RangeTable("pcix", FAMILIES, ROWS)
