"""Dialects: the command languages the engine is driven in, each registered here.

* :mod:`~omsd.dialects.registry`: the :class:`~omsd.dialects.registry.Dialect` record and the
  registry (:func:`lookup` by a model row's ``dialect``);
* :mod:`~omsd.dialects.interpreter`: the generic interpreter (input buffer, lexer, modes,
  queueing, dispatch through the dialect's tables), typed against the engine's machine;
* :mod:`~omsd.dialects.shared`: the OMS language both dialects share (PC48 chapter 6);
* :mod:`~omsd.dialects.pc48`: the PC48 family's language (PC48, PC46, VS4);
* :mod:`~omsd.dialects.pcix`: the PCIx's, with the MAX-family queries.

Importing this package registers both dialects.
"""

from omsd.dialects import pc48, pcix
from omsd.dialects.registry import (
    Dialect,
    commands,
    framing,
    handlers,
    lookup,
    prefixes,
    ranges,
    register,
    registered,
)

__all__ = [
    "Dialect",
    "commands",
    "framing",
    "handlers",
    "lookup",
    "pc48",
    "pcix",
    "prefixes",
    "ranges",
    "register",
    "registered",
]
