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
from omsd.board.events import Event, describe
from omsd.config import BoardConfig
from omsd.faults import Faults
from omsd.link import Link, make_link
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog
from omsd.timebase import Timebase

#: Host bytes offered to a board in one go; the rest waits for the next turn of the event loop.
FEED_BITE = 4096
#: Host bytes a faulty cable holds in flight (paced or damaged) before it drops more.
MAX_IN_FLIGHT = 64 * 1024


class Client(Protocol):
    """An endpoint connection as the service sees it."""

    label: str

    def send(self, data: bytes) -> None:
        """Bytes for the host."""
        ...

    def input_room(self) -> None:
        """The link may take more of what this client has written: try again."""
        ...


class Observer(Protocol):
    """Someone watching a board (the MQTT bridge, a control client waiting for a condition)."""

    def traffic(self, service: BoardService, record: Traffic) -> None: ...

    def event(self, service: BoardService, when: float, event: Event) -> None: ...

    def changed(self, service: BoardService) -> None:
        """The board ran (a client wrote, a deadline came, the world or time was changed)."""
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
        # the board runs on the loop's monotonic clock (so loop.call_at can wake it exactly)
        # unless the control API pauses, steps or scales its time
        self.timebase = Timebase(loop.time)
        self.clock = self.timebase.now
        self.faults = Faults()
        self.observers: list[Observer] = []
        self._inbound = bytearray()  # host bytes on a faulty cable, not yet at the board
        self._in_timer: asyncio.TimerHandle | None = None
        self._out_free_at = 0.0  # loop time the paced line is free again
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
        self.service()  # what the board answers goes to "(no client)", not to the next one

    def _feed_orphan(self) -> None:
        if self._orphan:
            taken = self.link.from_host(bytes(self._orphan), self.clock())
            if taken:
                label = "(disconnected client)"
                chunk = bytes(self._orphan[:taken])
                self._record(Traffic(time.time(), self.name, label, Direction.IN, chunk))
            del self._orphan[:taken]

    def _record(self, record: Traffic) -> None:
        self.log.record(record)
        for observer in list(self.observers):
            observer.traffic(self, record)

    def feed(self, client: Client, data: bytes) -> int:
        """Bytes a client wrote; returns how many the link took (the client keeps the rest and
        stops reading until :meth:`Client.input_room` is called)."""
        if self._closed:
            return 0
        faults = self.faults
        if not faults.cable:
            return len(data)  # into a cut cable: lost
        if faults.damaging or faults.baud is not None:
            return self._feed_faulty(client, data)
        self._feed_orphan()
        taken = 0
        if not self._orphan:  # a vanished client's bytes go first
            # a bite at a time: a client that wrote megabytes gets the rest taken on later
            # turns of the loop, so the other boards are served in between
            taken = self.link.from_host(data[:FEED_BITE], self.clock())
        if taken:
            self.active = client
            chunk = data[:taken]
            self._record(Traffic(time.time(), self.name, client.label, Direction.IN, chunk))
        if taken < len(data) and client not in self._waiting:
            self._waiting.append(client)
        self.service()
        return taken

    def _feed_faulty(self, client: Client, data: bytes) -> int:
        """A noisy or slow cable: the bytes are on the wire (taken from the client), damaged,
        and reach the board at the line's pace."""
        self.active = client
        room = MAX_IN_FLIGHT - len(self._inbound)
        if room <= 0:
            return 0  # the wire is full: the client waits (input_room when it drains)
        data = data[:room]
        self._record(Traffic(time.time(), self.name, client.label, Direction.IN, data))
        self._inbound += self.faults.damage(data)
        if client not in self._waiting:
            self._waiting.append(client)
        self._drain_inbound()
        return len(data)

    def _drain_inbound(self) -> None:
        self._in_timer = None
        if self._closed or not self._inbound:
            return
        cps = self.faults.chars_per_second
        n = len(self._inbound) if cps is None else 1
        taken = self.link.from_host(bytes(self._inbound[:n]), self.clock())
        del self._inbound[:taken]
        self.service()
        if self._inbound:
            delay = 1.0 / cps if cps is not None and taken else 0.005
            self._in_timer = self.loop.call_later(delay, self._drain_inbound)

    def _deliver(self, client: Client | None, data: bytes) -> None:
        """Output on its way to the host, through whatever faults the cable has."""
        faults = self.faults
        if not faults.cable or client is None:
            return
        data = faults.damage(data)
        if not data:
            return
        cps = faults.chars_per_second
        if faults.latency <= 0.0 and cps is None:
            client.send(data)
            return
        now = self.loop.time()
        at = now + faults.latency
        if cps is None:
            self.loop.call_at(at, self._send_later, client, data)
            return
        for i in range(len(data)):  # one character at a time, at the line's pace
            self._out_free_at = max(self._out_free_at, at) + 1.0 / cps
            self.loop.call_at(self._out_free_at, self._send_later, client, data[i : i + 1])

    def _send_later(self, client: Client, data: bytes) -> None:
        if self._closed or not self.faults.cable:
            return
        if client in self.clients:
            client.send(data)

    def set_faults(self, faults: Faults) -> None:
        """New cable faults; cutting the cable closes the TCP clients (they see EOF)."""
        self.faults = faults
        if not faults.cable:
            self._inbound.clear()
            for client in list(self.clients):
                cut = getattr(client, "cut", None)
                if cut is not None:
                    cut()
        self.service()

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
            for observer in list(self.observers):
                observer.event(self, now, event)
        if out.data:
            client = self.active
            label = client.label if client is not None else "(no client)"
            self._record(Traffic(time.time(), self.name, label, Direction.OUT, out.data))
            self._deliver(client, out.data)
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
        if not self._closed:
            for observer in list(self.observers):
                observer.changed(self)
        deadline = self.link.next_deadline()
        if deadline is None or self._closed:
            return
        at = self.timebase.to_loop(deadline)
        if at is None:  # time is paused: nothing happens by itself
            return
        self._timer = self.loop.call_at(max(at, self.loop.time()), self.service)

    def close(self) -> None:
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        if self._in_timer is not None:
            self._in_timer.cancel()
            self._in_timer = None
