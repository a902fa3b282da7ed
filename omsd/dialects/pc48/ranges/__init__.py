"""Operand ranges of the PC48 family's language: PC48, PC46, VS4 (row type:
:mod:`omsd.protocol.ranges`).

Sources: the PC48 user's manual (``shared/seeds/000_438df88d2a6a1670.txt``), the VS4 user's
manual (``003_c16e31315d499848.txt``) and the PC46 datasheet (``004_47955639fb93103e.txt``).
The PC46 datasheet gives no command ranges but its velocity; everything else it leaves out is
the PC48's (``omsd/models/pc46.py``). The VS4 manual repeats the PC48's words except where a row
names the VS4.

Every command of the three command tables that takes a number has a row here
(``tests/board/test_operand_ranges.py`` checks it). A row with ``choice`` set records a choice:
the manual states no range for that operand ("manual silent: ..."), or states two ("manual
contradicts itself: ...").
"""

from __future__ import annotations

from omsd.protocol.ranges import RangeTable

from .control import ROWS as _SECOND
from .kit import FAMILIES
from .moves import ROWS as _FIRST

ROWS = [*_FIRST, *_SECOND]

PC48_RANGES = RangeTable("oms", FAMILIES, ROWS)
