"""The OMS language the PC48 family and the PCIx share: PC48 chapter 6, one module per group of
sections (:mod:`~omsd.dialects.shared.modes`, :mod:`~omsd.dialects.shared.io`,
:mod:`~omsd.dialects.shared.moves`, :mod:`~omsd.dialects.shared.stops`,
:mod:`~omsd.dialects.shared.loops`, :mod:`~omsd.dialects.shared.sync`,
:mod:`~omsd.dialects.shared.reports`, :mod:`~omsd.dialects.shared.encoder`,
:mod:`~omsd.dialects.shared.contour`), all filed in one table (:mod:`~omsd.dialects.shared.table`).
"""

from omsd.dialects.shared import (  # noqa: F401 (each files its handlers in HANDLERS)
    contour,
    encoder,
    io,
    loops,
    modes,
    moves,
    reports,
    stops,
    sync,
)
from omsd.dialects.shared.table import (
    HANDLERS,
    PURE_REPORTS,
    REPORTS,
    Handler,
    handles,
    registrar,
)

__all__ = ["HANDLERS", "PURE_REPORTS", "REPORTS", "Handler", "handles", "registrar"]
