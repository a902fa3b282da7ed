"""One emulated board living on the event loop: its link, its clients, its wake-ups.

The board engine is pure; this is where it meets real time. Every time a client writes, and
whenever the board's own next deadline comes (a move ends, a switch is reached, a WT runs
out), :meth:`BoardService.service` lets the board run to ``loop.time()`` and hands what the
board said to every client attached to it. Between those moments nothing runs: an idle board
costs nothing (no tick loop).

The board is a card in a PC: it outlives every client. Clients come and go (a program opens and
closes the pty, a TCP connection drops mid-command); the board keeps its state, and what a
client wrote before it vanished is still passed on in order.

A board has one data port but may be reachable on several endpoints (by default a TCP port and
a pty). What the board says goes to the client that last wrote to it: that is the program
holding the conversation, and a pty nobody has open does not fill up with another client's
replies. The traffic log shows everything.
"""

from __future__ import annotations

import asyncio
import time
import traceback
from typing import Protocol

from omsd.board import Board
from omsd.board.events import describe
from omsd.config import BoardConfig
from omsd.link import Link, make_link
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog


class Client(Protocol):
    """An endpoint connection as the service sees it."""

    label: str

    def send(self, data: bytes) -> None:
        """Bytes for the host."""
        ...

    def input_room(self) -> None:
        """The link may take more of what this client has written: try again."""
        ...


class BoardService:
    def __init__(
        self,
        config: BoardConfig,
        loop: asyncio.AbstractEventLoop,
        log: TrafficLog,
    ) -> None:
        self.config = config
        self.name = config.name
        self.loop = loop
        self.log = log
        # the board runs on the loop's monotonic clock, so loop.call_at can wake it exactly
        self.clock = loop.time
        now = self.clock()
        self.model = config.personality()
        self.board = Board(self.model, now=now, world=dict(config.world))
        for bit, high in config.inputs.items():
            self.board.set_input(bit, high, now)
        self.link: Link = make_link(
            config.link, self.board, eos=config.eos, buffer_size=config.buffer_size
        )
        self.clients: list[Client] = []
        self._waiting: list[Client] = []
        self.active: Client | None = None  # the client that last wrote: it gets the output
        self._timer: asyncio.TimerHandle | None = None
        self._orphan = bytearray()
        self._closed = False

    # -- clients --------------------------------------------------------------------------------

    def attach(self, client: Client) -> None:
        self.clients.append(client)

    def detach(self, client: Client) -> None:
        if client in self.clients:
            self.clients.remove(client)
        if self.active is client:
            self.active = None
        if client in self._waiting:
            self._waiting.remove(client)

    def orphan_input(self, data: bytes) -> None:
        """What a client wrote and the board had not yet taken when the client went away: it is
        still passed on, in order, as the board can take it."""
        self._orphan += data
        self._feed_orphan()

    def _feed_orphan(self) -> None:
        if self._orphan:
            taken = self.link.from_host(bytes(self._orphan), self.clock())
            if taken:
                label = "(disconnected client)"
                chunk = bytes(self._orphan[:taken])
                self.log.record(Traffic(time.time(), self.name, label, Direction.IN, chunk))
            del self._orphan[:taken]

    def feed(self, client: Client, data: bytes) -> int:
        """Bytes a client wrote; returns how many the link took (the client keeps the rest and
        stops reading until :meth:`Client.input_room` is called)."""
        if self._closed:
            return 0
        self._feed_orphan()
        taken = 0
        if not self._orphan:  # a vanished client's bytes go first
            taken = self.link.from_host(data, self.clock())
        if taken:
            self.active = client
            chunk = data[:taken]
            self.log.record(Traffic(time.time(), self.name, client.label, Direction.IN, chunk))
        if taken < len(data) and client not in self._waiting:
            self._waiting.append(client)
        self.service()
        return taken

    # -- time -----------------------------------------------------------------------------------

    def service(self) -> None:
        """Let the board run to now; deliver its output; schedule the next wake-up."""
        if self._closed:
            return
        now = self.clock()
        try:
            out = self.link.to_host(now)
        except Exception:  # a bug in the engine must not take the daemon down
            self.log.error(f"{self.name}: board engine failed:\n{traceback.format_exc()}")
            self._reschedule()
            return
        for event in out.events:
            self.log.event(time.time(), self.name, describe(event))
        if out.data:
            client = self.active
            label = client.label if client is not None else "(no client)"
            self.log.record(Traffic(time.time(), self.name, label, Direction.OUT, out.data))
            if client is not None:
                client.send(out.data)
        if self._orphan:
            self._feed_orphan()
        if self._waiting and self.link.room() > 0:
            # never call back into a client from here: a client may be inside feed()
            waiting, self._waiting = self._waiting, []
            for client in waiting:
                self.loop.call_soon(client.input_room)
        self._reschedule()

    def _reschedule(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        deadline = self.link.next_deadline()
        if deadline is None or self._closed:
            return
        # loop.call_at takes the loop's clock, which is the board's clock here
        self._timer = self.loop.call_at(max(deadline, self.loop.time()), self.service)

    def close(self) -> None:
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
