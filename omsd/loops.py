"""The event loop the daemon runs on: asyncio's own, or uvloop (``--loop``, issue 16).

``pip install omsd[fast]`` installs uvloop, a drop-in event loop on libuv. ``--loop auto`` (the
default) runs on it when it can be imported and on asyncio's loop otherwise, so a plain install
runs asyncio's and one with the extra runs uvloop without being asked; ``--loop asyncio`` and
``--loop uvloop`` choose (the latter is an error where uvloop is missing). asyncio's loop meets
issue 16's latency targets by itself; ``python -m bench --fast`` measures both.

Nothing in omsd depends on which loop runs it: the services read the monotonic clock themselves
(uvloop's ``loop.time()`` counts whole milliseconds) and wake at their deadlines through a
timerfd on either loop (:mod:`omsd.wakeups`).

This module is imported by the command line before anything else, so it imports neither asyncio
nor uvloop until it runs something.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Coroutine
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import asyncio

from omsd.defaults import LOOPS as LOOPS  # the accepted values of --loop


class LoopUnavailable(Exception):
    """The loop asked for cannot be had here; ``str()`` is one line for the command line."""


def loop_factory(choice: str) -> tuple[Callable[[], asyncio.AbstractEventLoop] | None, str]:
    """The factory of the loop ``choice`` names (None: asyncio's default) and the loop's name
    (``asyncio`` or ``uvloop``). Raises :class:`LoopUnavailable` for ``uvloop`` without uvloop."""
    if choice not in LOOPS:
        raise ValueError(f"unknown event loop {choice!r}: expected one of {', '.join(LOOPS)}")
    if choice == "asyncio":
        return None, "asyncio"
    try:
        uvloop = importlib.import_module("uvloop")
    except ImportError:
        if choice == "uvloop":
            raise LoopUnavailable(
                "--loop uvloop: uvloop is not installed (pip install 'omsd[fast]')"
            ) from None
        return None, "asyncio"
    factory: Callable[[], asyncio.AbstractEventLoop] = uvloop.new_event_loop
    return factory, "uvloop"


def run(
    main: Coroutine[Any, Any, None], factory: Callable[[], asyncio.AbstractEventLoop] | None
) -> None:
    """``asyncio.run(main)`` on the loop ``factory`` makes (None: asyncio's own)."""
    import asyncio

    with asyncio.Runner(loop_factory=factory) as runner:
        runner.run(main)
