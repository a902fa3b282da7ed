"""One emulated board living on the event loop: its link, its clients, its wake-ups.

The board engine is pure; this is where it meets real time. Every time a client writes, and
whenever the board's own next deadline comes (a move ends, a switch is reached, a WT runs
out), :meth:`BoardService.service` lets the board run to the time now and hands what the
board said to every client attached to it. Between those moments nothing runs: an idle board
costs nothing (no tick loop).

The board is a card in a PC: it outlives every client. Clients come and go (a program opens and
closes the pty, a TCP connection drops mid-command); the board keeps its state and its motion.

Each connection is a *session* (a TCP connection; the time between a pty's first open and its
last close): what the board produces in answer to a session's bytes belongs to that session
(replies, the driver's ``# ! @ $`` markers for the commands it sent, the motion it started), and
goes to its client only (:attr:`omsd.link.LinkOutput.pieces`). When a client goes, what it wrote
that the board has not taken yet (held by a driver wait, or waiting for room) is dropped, its
wait ends, and what the board still says for it is discarded; each is logged with a count. The
board's own doing (session 0) goes to the client that last wrote. A TCP client that shuts down
only its sending side is kept until what it sent is done (``linger``). The traffic log shows
everything.
"""

from __future__ import annotations

import asyncio
import functools
import itertools
import time
import traceback
from collections import OrderedDict, deque
from typing import Protocol

from omsd.board import Board
from omsd.board.events import Event, describe
from omsd.config import BoardConfig
from omsd.faults import Faults
from omsd.link import Link, make_link
from omsd.pacing import Pacer
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog
from omsd.timebase import Timebase
from omsd.wakeups import Handle, wakeups_for

#: Host bytes offered to a board in one go; the rest waits for the next turn of the event loop.
FEED_BITE = 4096
#: Host bytes a faulty cable holds in flight (paced or damaged) before it drops more.
MAX_IN_FLIGHT = 64 * 1024
#: Labels of gone sessions remembered for the log (what is discarded for them later).
GONE_LABELS = 256


class Client(Protocol):
    """An endpoint connection as the service sees it. ``session`` is given by the service
    (:meth:`BoardService.attach`, :meth:`BoardService.open_session`)."""

    label: str
    session: int

    def send(self, data: bytes) -> None:
        """Bytes for the host."""
        ...

    def input_room(self) -> None:
        """The link may take more of what this client has written: try again."""
        ...


class Lingering(Client, Protocol):
    """A client that has shut down its sending side and waits for its answers."""

    @property
    def unsent(self) -> int:
        """Bytes it wrote that the link has not taken yet."""
        ...

    def finish(self) -> None:
        """Close, after what has been sent to it is written."""
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
        # the board runs on the monotonic clock (asyncio's loop.time(); to the nanosecond under
        # uvloop too) unless the control API pauses, steps or scales its time; its deadlines
        # wake it through the loop's timerfd (omsd.wakeups), on time to tens of microseconds
        self.timebase = Timebase(time.monotonic)
        self.clock = self.timebase.now
        self._timers = wakeups_for(loop)
        self.faults = Faults()
        self.observers: list[Observer] = []
        self._inbound = bytearray()  # host bytes on a faulty cable, not yet at the board
        self._in_timer: asyncio.TimerHandle | None = None
        self._out = Pacer(loop)  # the faulty cable's latency and pace, on the way out
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
        self.active: Client | None = None  # the client that last wrote: the board's own output
        self._timer: Handle | None = None
        self._timer_at: float | None = None  # the monotonic time the board is woken at
        self._closed = False
        self._sessions = itertools.count(1)
        self._live: dict[int, Client] = {}  # session -> its client, while it is there
        self._gone: OrderedDict[int, str] = OrderedDict()  # session -> label, recently gone
        self._inbound_sessions: deque[list[int]] = deque()  # [session, count] of _inbound
        self._lingering: dict[int, tuple[Lingering, asyncio.TimerHandle]] = {}

    @property
    def faults(self) -> Faults:
        """The cable's faults (control API); :meth:`set_faults` changes them."""
        return self._faults

    @faults.setter
    def faults(self, faults: Faults) -> None:
        self._faults = faults
        # the fast path's test: a whole cable with nothing on it (see feed and _route)
        self._clean = (
            faults.cable and not faults.damaging and faults.baud is None and faults.latency <= 0
        )

    # -- clients --------------------------------------------------------------------------------

    def attach(self, client: Client) -> None:
        self.clients.append(client)
        self.open_session(client)
        for observer in list(self.observers):
            observer.changed(self)  # a new client is a change to those who watch the board

    def open_session(self, client: Client) -> int:
        """A new conversation on ``client`` (a new connection, a pty opened again)."""
        session = next(self._sessions)
        client.session = session
        self._live[session] = client
        return session

    def detach(self, client: Client) -> None:
        """The endpoint is going away (after :meth:`end_session`, or at shutdown)."""
        if client in self.clients:
            self.clients.remove(client)
        self._forget(client)

    def _forget(self, client: Client) -> None:
        session = client.session
        if self._live.get(session) is client:
            del self._live[session]
            self._gone[session] = client.label
            while len(self._gone) > GONE_LABELS:
                self._gone.popitem(last=False)
        if self.active is client:
            self.active = None
        if client in self._waiting:
            self._waiting.remove(client)
        lingering = self._lingering.pop(session, None)
        if lingering is not None:
            lingering[1].cancel()

    def end_session(self, client: Client, unsent: int = 0, why: str = "gone") -> None:
        """The client went (disconnected, closed the pty, taken over, cut): what it wrote and
        the board has not taken is dropped (``unsent`` of it never left the transport), its
        wait ends, and from now on what the board says for it is discarded."""
        session = client.session
        if self._live.get(session) is not client:
            return
        held = self.link.held()
        wait = held.describe() if held is not None and held.session == session else None
        dropped = self.link.drop_input(session) + unsent
        for run in self._inbound_sessions:
            if run[0] == session:
                run[0] = -1  # still on the wire; it reaches the board as nobody's
        self._forget(client)
        if dropped or wait:
            because = f" ({wait})" if wait else ""
            self.log.info(
                f"{self.name}: {client.label} {why}: dropped {dropped} bytes of its input "
                f"that the board had not taken{because}"
            )
        self.service()

    def power_cycle(self) -> None:
        """Switch the card off and on (control API): the board resets, the link forgets what it
        held."""
        self.board.power_cycle(self.clock())
        dropped = self.link.reset_input()
        if dropped:
            self.log.info(f"{self.name}: reset: dropped {dropped} bytes of held input")
        self.service()

    def session_busy(self, client: Lingering) -> bool:
        """Something ``client`` sent is yet to be taken or done (see :meth:`Board.session_busy`)."""
        session = client.session
        return bool(
            client.unsent
            or self.link.busy(session)
            or self.board.session_busy(session)
            or any(run[0] == session for run in self._inbound_sessions)
        )

    def half_closed(self, client: Lingering) -> bool:
        """``client`` shut down its sending side. True: keep it open until what it sent is
        done (at most ``linger`` seconds), then :meth:`Lingering.finish`; False: close now."""
        linger = self.config.linger
        if linger <= 0:
            return False
        # the board run to now first: with quiet wake-ups (Machine.next_wakeup) a move may have
        # ended since it was last run, and the session would look busy
        self.service()
        if not self.session_busy(client):
            return False
        timer = self.loop.call_later(linger, self._linger_over, client)
        self._lingering[client.session] = (client, timer)
        self._reschedule()  # a board with a client lingering is woken at every deadline
        return True

    def _linger_over(self, client: Lingering) -> None:
        if self._lingering.pop(client.session, None) is not None:
            self.log.info(
                f"{self.name}: {client.label}: closed {self.config.linger:g} s after it stopped "
                "sending, with its commands still running"
            )
            client.finish()

    def _traffic(self, label: str, direction: Direction, data: bytes) -> None:
        """A chunk of traffic for the log and the observers; no record is made for nobody (the
        per-poll callers ask ``self.observers or self.log.wants_traffic`` first themselves, so
        that a board nobody watches pays for no call)."""
        log = self.log
        observers = self.observers
        if not (observers or log.wants_traffic):
            return
        t = time.time()
        log.traffic(t, self.name, label, direction, data)
        if observers:
            record = Traffic(t, self.name, label, direction, data)
            for observer in list(observers):
                observer.traffic(self, record)

    def feed(self, client: Client, data: bytes) -> int:
        """Bytes a client wrote; returns how many the link took (the client keeps the rest and
        stops reading until :meth:`Client.input_room` is called).

        The log is held meanwhile: the lines of the bytes in, the replies, the events, are made
        and written in one go, just before the replies are sent (:meth:`_run`)."""
        if self._closed:
            return 0
        if not self._clean or self._inbound:
            faults = self.faults
            if not faults.cable:
                return len(data)  # into a cut cable: lost
            if faults.damaging or faults.baud is not None or self._inbound:
                # (bytes still on the wire from before the cable was healed go first)
                return self._feed_faulty(client, data)
        log = self.log
        log.hold()
        try:
            # a bite at a time: a client that wrote megabytes gets the rest taken on later turns
            # of the loop, so the other boards are served in between
            now = self.clock()
            taken = self.link.from_host(data[:FEED_BITE], now, client.session)
            if taken:
                self.active = client
                if self.observers or log.wants_traffic:
                    self._traffic(client.label, Direction.IN, data[:taken])
            if taken < len(data) and client not in self._waiting:
                self._waiting.append(client)
            self._run(now)  # service() at the time the bytes were taken, already held
        finally:
            log.release()
        return taken

    def _feed_faulty(self, client: Client, data: bytes) -> int:
        """A noisy or slow cable: the bytes are on the wire (taken from the client), damaged,
        and reach the board at the line's pace."""
        self.active = client
        room = MAX_IN_FLIGHT - len(self._inbound)
        if room <= 0:
            # the wire is full: the client waits, and is called (input_room) when it drains
            if client not in self._waiting:
                self._waiting.append(client)
            return 0
        data = data[:room]
        self._traffic(client.label, Direction.IN, data)
        damaged = self.faults.damage(data)
        self._inbound += damaged
        runs = self._inbound_sessions
        if damaged:
            if runs and runs[-1][0] == client.session:
                runs[-1][1] += len(damaged)
            else:
                runs.append([client.session, len(damaged)])
        if client not in self._waiting:
            self._waiting.append(client)
        self._drain_inbound()
        return len(data)

    def _drain_inbound(self) -> None:
        self._in_timer = None
        if self._closed or not self._inbound:
            return
        cps = self.faults.chars_per_second
        runs = self._inbound_sessions
        session, length = runs[0]
        n = length if cps is None else 1
        taken = self.link.from_host(bytes(self._inbound[:n]), self.clock(), max(session, 0))
        del self._inbound[:taken]
        runs[0][1] -= taken
        if not runs[0][1]:
            runs.popleft()
        self.service()
        if self._inbound:
            delay = 1.0 / cps if cps is not None and taken else 0.005
            self._in_timer = self.loop.call_later(delay, self._drain_inbound)

    def _deliver(self, client: Client, data: bytes) -> None:
        """Output on its way to the host, through whatever faults the cable has."""
        faults = self.faults
        if not faults.cable:
            return
        data = faults.damage(data)
        if not data:
            return
        cps = faults.chars_per_second
        if faults.latency <= 0.0 and cps is None and not self._out.waiting:
            client.send(data)
            return
        # late by the latency, then a character at a time at the line's pace (omsd.pacing)
        self._out.chars_per_second = cps
        self._out.send(
            functools.partial(self._send_later, client), data, self.loop.time() + faults.latency
        )

    def _send_later(self, client: Client, data: bytes) -> None:
        if self._closed or not self.faults.cable:
            return
        if self._live.get(client.session) is client:
            client.send(data)

    def set_faults(self, faults: Faults) -> None:
        """New cable faults; cutting the cable closes the TCP clients (they see EOF)."""
        self.faults = faults
        if not faults.cable:
            self._inbound.clear()
            self._inbound_sessions.clear()
            for client in list(self.clients):
                cut = getattr(client, "cut", None)
                if cut is not None:
                    cut()
        self.service()

    # -- time -----------------------------------------------------------------------------------

    def service(self) -> None:
        """Let the board run to now; deliver its output; schedule the next wake-up. The log is
        held meanwhile (its lines are written just before the output is sent)."""
        if self._closed:
            return
        log = self.log
        log.hold()
        try:
            self._run(self.clock())
        finally:
            log.release()

    def _run(self, now: float) -> None:
        try:
            out = self.link.to_host(now)
        except Exception:  # a bug in the engine must not take the daemon down
            self.log.error(f"{self.name}: board engine failed:\n{traceback.format_exc()}")
            self._reschedule()
            return
        for note in self.link.take_notes():
            self.log.info(f"{self.name}: {self.link.kind} link: {note}")
        for event in out.events:
            self.log.event(time.time(), self.name, describe(event))
            if self.observers:
                for observer in list(self.observers):
                    observer.event(self, now, event)
        if out.pieces:
            # each piece logged and given its client (its session's; the board's own, session
            # 0, the last writer's); a piece whose client has gone is logged and discarded
            log = self.log
            sending: list[tuple[Client, bytes]] = []
            for session, data in out.pieces:
                client = self._live.get(session) if session else self.active
                if client is None:
                    self._discard(session, data)
                    continue
                if self.observers or log.wants_traffic:
                    self._traffic(client.label, Direction.OUT, data)
                sending.append((client, data))
            # the lines of this turn are in the file before any client can have a reply
            log.write_kept()
            for client, data in sending:
                if self._clean and self._out.idle:
                    client.send(data)  # the fast path: nothing on the cable
                else:
                    self._deliver(client, data)
        if self._waiting:
            # never call back into a client from here: a client may be inside feed()
            room = self.link.room
            # (a client held back by a full faulty wire waits for the wire to drain too)
            wire = len(self._inbound) < MAX_IN_FLIGHT
            ready = [c for c in self._waiting if wire and room(c.session) > 0]
            for client in ready:
                self._waiting.remove(client)
                self.loop.call_soon(client.input_room)
        if self._lingering:
            for lingering, _ in list(self._lingering.values()):
                if not self.session_busy(lingering):
                    self._forget(lingering)
                    lingering.finish()
        self._reschedule()

    def _discard(self, session: int, data: bytes) -> None:
        """Log the output of ``session`` whose client has gone (or, for the board's own, 0,
        that has no last writer): it goes nowhere."""
        gone = self._gone.get(session) if session else None
        label = f"(gone: {gone})" if gone is not None else "(no client)"
        self._traffic(label, Direction.OUT, data)
        if gone is not None:
            self.log.info(f"{self.name}: discarded {len(data)} bytes for {gone}: it has gone")

    def _reschedule(self) -> None:
        if self.observers and not self._closed:
            for observer in list(self.observers):
                observer.changed(self)
        if self._closed:
            deadline = None
        elif self.observers or self._waiting or self._lingering:
            # someone watches the board's every change, a client waits for room, a gone
            # client's session waits for its motion to end: woken at every deadline
            deadline = self.link.next_deadline()
        else:
            # woken when the host could hear something; what no host can hear until it asks
            # is let happen, at its own times, when the board is next run (omsd.engine.quiet)
            deadline = self.link.next_wakeup()
        # when, on the monotonic clock, the board is next to be woken (None: time is paused or
        # nothing happens by itself)
        at = None if deadline is None else self.timebase.to_loop(deadline)
        timer = self._timer
        if timer is not None:
            if at == self._timer_at:
                return  # woken then already
            timer.cancel()
            self._timer = None
            self._timer_at = None
        if at is None:
            return
        self._timer = self._timers.call_at(at, self._wake)
        self._timer_at = at

    def _wake(self) -> None:
        self._timer = None
        self._timer_at = None
        self.service()

    def close(self) -> None:
        self._closed = True
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
            self._timer_at = None
        if self._in_timer is not None:
            self._in_timer.cancel()
            self._in_timer = None
        self._out.clear()
