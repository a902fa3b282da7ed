"""Dialects: the command languages the engine is driven in, each registered here.

* :mod:`~omsd.dialects.registry`: the :class:`~omsd.dialects.registry.Dialect` record and the
  registry (:func:`lookup` by a model row's ``dialect``);
* :mod:`~omsd.dialects.interpreter`: the generic interpreter (input buffer, lexer, modes,
  queueing, dispatch through the dialect's tables), typed against the engine's machine;
* :mod:`~omsd.dialects.shared`: the OMS language both dialects share (PC48 chapter 6);
* :mod:`~omsd.dialects.pc48`: the PC48 family's language (PC48, PC46, VS4);
* :mod:`~omsd.dialects.pcix`: the PCIx's, with the MAX-family queries.

A dialect is imported, and registers itself, when it is first looked up (:func:`lookup`,
:func:`registered` for all of them).
"""

from omsd.dialects.registry import (
    Dialect,
    commands,
    framing,
    handlers,
    known,
    lookup,
    prefixes,
    ranges,
    register,
    registered,
)

known("oms", "omsd.dialects.pc48", framing_name="surround")
known("pcix", "omsd.dialects.pcix", framing_name="trailing")

__all__ = [
    "Dialect",
    "commands",
    "framing",
    "handlers",
    "known",
    "lookup",
    "prefixes",
    "ranges",
    "register",
    "registered",
]
