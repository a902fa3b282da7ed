"""The control API's ``wait`` operations on one board, evaluated together.

Each wait used to watch the board on its own: an observer of its own, woken at every change of
the board, and a wait for a position ran the board and looked at its axis every
:data:`POSITION_POLL` besides. 256 waits for a position on a moving axis were 256 tasks woken
some 500 times a second each: 77-82 % of a core. A board's waits (of one control server) are
now one :class:`BoardWaits`: one observer of the board and, while a wait for a position is in
progress, one poll; each change of the board, or poll, looks at every waiting condition once,
in one pass, and wakes only the waits whose condition holds.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable

from omsd.board.events import Event
from omsd.service import BoardService
from omsd.telemetry.traffic import Traffic

POSITION_POLL = 0.002
"""Seconds between two looks at a board while a wait for a position is in progress: a board
that nobody else watches is run only when its host could hear something, and a carriage passes
a position unannounced."""

Condition = Callable[[], bool]


class BoardWaits:
    """The waits in progress on one board. ``done`` is called once the last one has ended (the
    owner forgets this object then)."""

    def __init__(self, service: BoardService, done: Callable[[], None]) -> None:
        self.service = service
        self._done = done
        self._waiting: dict[asyncio.Future[None], tuple[Condition, bool]] = {}
        self._positions = 0  # waits for a position among them
        self._soon: asyncio.Handle | None = None  # the look that a change of the board asked
        self._poll: asyncio.TimerHandle | None = None

    async def until(self, condition: Condition, timeout: float, position: bool = False) -> bool:
        """Wait until ``condition`` holds (True) or ``timeout`` seconds have gone (False: it
        still does not hold once the board has been run to now). ``position``: the condition
        is a position's, which the board's changes may not show (:data:`POSITION_POLL`)."""
        loop = asyncio.get_running_loop()
        future: asyncio.Future[None] = loop.create_future()
        first = not self._waiting
        self._waiting[future] = (condition, position)
        if first:
            self.service.observers.append(self)
            # run again now that it is watched: then it is woken at its every deadline, not
            # only when its host could hear something (a move's end, which no host hears)
            self.service.service()
        if position:
            self._positions += 1
            if self._poll is None:
                self._poll = loop.call_later(POSITION_POLL, self._polled)
        try:
            # asyncio.timeout, not wait_for: Python 3.11's wait_for swallows a cancel that
            # comes as the future is set, and the wait of a client that has gone went on
            async with asyncio.timeout(timeout):
                await future
            return True
        except TimeoutError:
            self.service.service()  # the board run to now: the last look
            return condition()
        finally:
            self._forget(future, position)

    def _forget(self, future: asyncio.Future[None], position: bool) -> None:
        del self._waiting[future]
        if position:
            self._positions -= 1
            if not self._positions and self._poll is not None:
                self._poll.cancel()
                self._poll = None
        if self._waiting:
            return
        if self._soon is not None:
            self._soon.cancel()
            self._soon = None
        self.service.observers.remove(self)
        self._done()

    def _polled(self) -> None:
        """Run the board (telling its observers it changed) and look, every
        :data:`POSITION_POLL` while a wait for a position is in progress."""
        self._poll = asyncio.get_running_loop().call_later(POSITION_POLL, self._polled)
        self.service.service()
        self._look()

    def _look(self) -> None:
        """End every wait whose condition holds (one pass over them all). The board is not run
        here: running it tells every observer it changed, and two looks that each ran it would
        wake each other for ever."""
        if self._soon is not None:
            self._soon.cancel()
            self._soon = None
        for future, (condition, _) in list(self._waiting.items()):
            if future.done():
                continue
            try:
                holds = condition()
            except Exception as exc:  # a bug: that wait's error reply, not every wait's end
                future.set_exception(exc)
                continue
            if holds:
                future.set_result(None)

    # -- the board's observer -------------------------------------------------------------------

    def traffic(self, service: BoardService, record: Traffic) -> None:
        pass

    def event(self, service: BoardService, when: float, event: Event) -> None:
        self._soon_look()

    def changed(self, service: BoardService) -> None:
        self._soon_look()

    def _soon_look(self) -> None:
        # once the board's turn is over, and once however many changes come meanwhile
        if self._soon is None:
            self._soon = asyncio.get_running_loop().call_soon(self._look)


__all__ = ["POSITION_POLL", "BoardWaits", "Condition"]
