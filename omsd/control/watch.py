"""A control connection's subscription: the boards' life as a stream (the ``subscribe`` op).

Issue 18: two views of the same live state, ``omsd top`` and a web page, "both built on the
control API's data": a snapshot, then "a stream of state changes and events, with a bounded
rate". The wire format is in :mod:`omsd.control.protocol`; this module makes the messages.

Nothing runs while nothing changes. A subscription watches each of its boards through
:attr:`BoardService.observers` (:class:`_Tap`): a board that runs (a client wrote, a deadline
came, the world or its time was changed) marks itself changed, and a timer is armed to look at
the changed boards at most ``rate`` times a second. A look takes each changed board's state,
compares it with what was sent and queues what differs; while an axis moves (which it does
without waking its board) the timer is armed again, and once nothing moves it is not: an idle
daemon has no timer for its subscribers and sends them nothing. Events are queued as they
happen, traffic counted (and queued chunk by chunk with ``traffic`` on). The observer only
counts, appends and arms: the board is never held up.

Bounded, whatever the client does: messages wait in :class:`Outbox`, which holds at most
:data:`QUEUE_LIMIT` events and traffic chunks (and :data:`TRAFFIC_BYTES` bytes of traffic); when
it is full the oldest chunk goes, the oldest event only when no chunk is left, and each is
counted. Of the state one message waits at most: a newer look merges into it (counted as
``state`` in ``dropped``). The sender task writes a batch and waits for the socket to drain, so
the transport holds at most its high-water mark (64 KiB) besides; a client that never reads
costs the daemon that much and no more, and nothing else waits for it.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import math
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any

from omsd.board.events import (
    CommandErrorEvent,
    DoneEvent,
    Event,
    LimitEvent,
    ServoTripEvent,
    SlipEvent,
    describe,
)
from omsd.board.world import AxisWorld
from omsd.control.protocol import DEFAULT_RATE, MAX_RATE, ControlError, Writer, encode
from omsd.service import BoardService
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog

QUEUE_LIMIT = 1000
"""Events and traffic chunks waiting for one subscriber, at most."""

TRAFFIC_BYTES = 256 * 1024
"""Bytes of traffic chunks waiting for one subscriber, at most."""

BATCH = 64
"""Messages written to the socket in one go before waiting for it to drain."""

#: The limit switches' default positions: an axis whose configuration leaves both has no travel.
_FAR = (AxisWorld().negative_limit, AxisWorld().positive_limit)


def event_record(service: BoardService, event: Event, seq: int, wall: float) -> dict[str, Any]:
    """One event as the subscription and the MQTT bridge's ``event`` topic give it (the bridge
    imports it as ``omsd.mqtt.event_payload``)."""
    out: dict[str, Any] = {
        "seq": seq,
        "board": service.name,
        "time": event.time,
        "t": wall,
        "text": describe(event),
    }
    if isinstance(event, DoneEvent):
        out["kind"] = "done"
        out["done_register"] = event.done_register
        out["axes"] = [a.letter for a in service.board.axes if event.done_register & a.done_bit]
    elif isinstance(event, LimitEvent):
        out.update(kind="limit", axis=event.axis, direction=event.direction)
    elif isinstance(event, SlipEvent):
        out.update(kind="slip", axis=event.axis)
    elif isinstance(event, ServoTripEvent):
        out.update(kind="servo_trip", axis=event.axis, error=event.error)
    else:
        assert isinstance(event, CommandErrorEvent)
        out.update(kind="command_error", error=event.kind.message, command=event.command)
    return out


def travel(service: BoardService) -> dict[str, list[float]]:
    """Per axis, the positions of the negative and positive limit switches (in steps from where
    the carriage was at power-up), for the axes whose configuration places them."""
    out = {}
    for letter, world in service.config.world.items():
        limits = (world.negative_limit, world.positive_limit)
        if limits != _FAR:
            out[letter] = [limits[0], limits[1]]
    return out


def switches(service: BoardService) -> dict[str, dict[str, list[float]]]:
    """Per axis, where its switches are (in steps of the carriage from where it was at
    power-up, the frame of the state's ``physical``): ``home`` [low, high] always, ``limits``
    [negative, positive] when the configuration places them (not the far defaults)."""
    out: dict[str, dict[str, list[float]]] = {}
    far = travel(service)
    for axis in service.board.axes:
        world = service.config.world.get(axis.letter, AxisWorld())
        entry = {"home": [world.home_low, world.home_high]}
        if axis.letter in far:
            entry["limits"] = far[axis.letter]
        out[axis.letter] = entry
    return out


def _rate(value: Any, key: str) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not 0 < value <= MAX_RATE
        or not math.isfinite(value)
    ):
        raise ControlError(f"{key}: expected messages a second above 0, at most {MAX_RATE:g}")
    return float(value)


def options(
    message: dict[str, Any], names: Sequence[str]
) -> tuple[list[str], float, bool | str, dict[str, float]]:
    """A ``subscribe`` request's boards (every board of ``names`` unless it says), rate,
    traffic and per-board rates; :class:`ControlError` for a bad one."""
    wanted = message.get("boards")
    if wanted is None and message.get("board") is not None:
        wanted = [message["board"]]
    if wanted is None:
        boards = list(names)
    elif isinstance(wanted, list) and wanted and all(isinstance(n, str) for n in wanted):
        unknown = [n for n in wanted if n not in names]
        if unknown:
            raise ControlError(f"no board {unknown[0]!r}; boards: {', '.join(names)}")
        boards = list(dict.fromkeys(wanted))
    else:
        raise ControlError(f"boards: expected a list of board names, got {wanted!r}")
    rate = _rate(message.get("rate", DEFAULT_RATE), "rate")
    given = message.get("rates", {})
    if not isinstance(given, dict):
        raise ControlError(f"rates: expected an object of board names and rates, got {given!r}")
    rates = {}
    for name, value in given.items():
        if name not in boards:
            raise ControlError(f"rates: no board {name!r} in this subscription")
        rates[name] = _rate(value, f"rates.{name}")
    traffic = message.get("traffic", False)
    if not isinstance(traffic, bool) and traffic not in boards:
        raise ControlError(
            f"traffic: expected true, false or a board's name ({', '.join(boards)}),"
            f" got {traffic!r}"
        )
    return boards, rate, traffic, rates


class Outbox:
    """One subscriber's bounded queue: events and traffic chunks in order, at most one state
    message (a newer one merges into it). :meth:`pop` gives them back in the order they were
    put, a merged state message where its latest part was put."""

    def __init__(self, limit: int = QUEUE_LIMIT, traffic_bytes: int = TRAFFIC_BYTES) -> None:
        self.limit = limit
        self.traffic_bytes = traffic_bytes
        self.events: deque[tuple[int, dict[str, Any]]] = deque()
        self.traffic: deque[tuple[int, Traffic, int]] = deque()  # seq, chunk, its board's seq
        self.queued_bytes = 0
        self.state: dict[str, Any] | None = None  # {"boards": {...}, "traffic": {...}}
        self.state_seq = 0
        self.dropped = {"event": 0, "traffic": 0, "state": 0}
        self.peak = 0  # the most events and chunks that waited at once
        self.wake = asyncio.Event()
        self._seq = itertools.count(1)

    def __len__(self) -> int:
        return len(self.events) + len(self.traffic) + (self.state is not None)

    def put_event(self, record: dict[str, Any]) -> None:
        self._room(0)
        self.events.append((next(self._seq), record))
        self._put()

    def put_traffic(self, record: Traffic, seq: int) -> None:
        size = len(record.data)
        self._room(size)
        self.traffic.append((next(self._seq), record, seq))
        self.queued_bytes += size
        self._put()

    def put_state(
        self, boards: dict[str, dict[str, Any]], traffic: dict[str, Any], wall: float = 0.0
    ) -> None:
        """A look's changes (``wall``: when it looked), merged into the one waiting if any."""
        state = self.state
        if state is None:
            state = self.state = {"boards": {}, "traffic": {}}
        else:
            self.dropped["state"] += 1
        state["t"] = wall
        waiting = state["boards"]
        for name, changes in boards.items():
            merged = waiting.setdefault(name, {})
            for key, value in changes.items():
                if key == "axes":
                    axes = merged.setdefault("axes", {})
                    for letter, fields in value.items():
                        axes.setdefault(letter, {}).update(fields)
                else:
                    merged[key] = value
        state["traffic"].update(traffic)
        self.state_seq = next(self._seq)  # behind everything put before its newest part
        self.wake.set()

    def _room(self, size: int) -> None:
        """Drop the oldest (a chunk before an event) until one more message of ``size`` bytes
        of traffic fits."""
        while self.events or self.traffic:
            full = len(self.events) + len(self.traffic) >= self.limit
            if not full and self.queued_bytes + size <= self.traffic_bytes:
                return
            if self.traffic:
                _, chunk, _ = self.traffic.popleft()
                self.queued_bytes -= len(chunk.data)
                self.dropped["traffic"] += 1
            else:
                self.events.popleft()
                self.dropped["event"] += 1

    def _put(self) -> None:
        self.peak = max(self.peak, len(self.events) + len(self.traffic))
        self.wake.set()

    def pop(self) -> tuple[str, Any] | None:
        """The oldest message: ``("event", record)``, ``("traffic", (chunk, seq))`` or
        ``("state", {"boards", "traffic"})``; None when empty."""
        heads = []
        if self.events:
            heads.append((self.events[0][0], "event"))
        if self.traffic:
            heads.append((self.traffic[0][0], "traffic"))
        if self.state is not None:
            heads.append((self.state_seq, "state"))
        if not heads:
            return None
        _, kind = min(heads)
        if kind == "event":
            return kind, self.events.popleft()[1]
        if kind == "traffic":
            _, chunk, seq = self.traffic.popleft()
            self.queued_bytes -= len(chunk.data)
            return kind, (chunk, seq)
        state, self.state = self.state, None
        return kind, state


class _Tap:
    """A subscription's observer of one board (:class:`omsd.service.Observer`): it runs inside
    the board's service call, so it only counts, queues and arms the timer."""

    __slots__ = ("name", "subscription")

    def __init__(self, subscription: Subscription, name: str) -> None:
        self.subscription = subscription
        self.name = name

    def traffic(self, service: BoardService, record: Traffic) -> None:
        self.subscription.traffic(self.name, record)

    def event(self, service: BoardService, when: float, event: Event) -> None:
        self.subscription.event(service, event)

    def changed(self, service: BoardService) -> None:
        self.subscription.changed(self.name)


class Subscription:
    """The stream of one control connection. ``state`` is the control API's ``state`` of a
    board (:meth:`ControlServer.state`); ``traffic`` is False, True or a board's name."""

    def __init__(
        self,
        ident: object,
        services: Sequence[BoardService],
        state: Callable[[BoardService], dict[str, Any]],
        log: TrafficLog,
        *,
        rate: float,
        traffic: bool | str = False,
        outbox: Outbox | None = None,
        rates: dict[str, float] | None = None,
    ) -> None:
        self.ident = ident
        self.services = {s.name: s for s in services}
        self.state_of = state
        self.log = log
        self.rate = rate
        self.rates = dict(rates or {})
        # each board's period (``rates`` for the boards it names, else ``rate``) and when it
        # was last looked at: a board is looked at no more often than its own rate
        self.periods = {name: 1.0 / self.rates.get(name, rate) for name in self.services}
        self.seen = dict.fromkeys(self.services, -math.inf)  # loop time of each board's look
        # and looks no closer together than the fastest rate: a slow board due between two
        # looks of a fast one waits for the next (messages: at most the fastest rate a second)
        self.gap = 1.0 / max([rate, *self.rates.values()])
        self.chunks = traffic  # which boards' chunks are sent
        self.outbox = outbox if outbox is not None else Outbox()
        self.loop = asyncio.get_running_loop()
        self.taps = [_Tap(self, name) for name in self.services]
        self.last: dict[str, dict[str, Any]] = {}  # what was last sent, per board, time aside
        self.changed_boards: set[str] = set()
        self.moving: set[str] = set()  # boards an axis of which moved at the last look
        self.totals = {name: [0, 0] for name in self.services}  # bytes in, out
        self.sent_totals: dict[str, tuple[int, int]] = {}
        self.event_seq = dict.fromkeys(self.services, 0)
        self.traffic_seq = dict.fromkeys(self.services, 0)
        self.timer: asyncio.TimerHandle | None = None
        self.last_look = -math.inf  # loop time
        self.looks = 0
        self.sent = 0
        self.sender: asyncio.Task[None] | None = None
        self.closed = False
        self._failed: set[str] = set()
        for service, tap in zip(self.services.values(), self.taps, strict=True):
            service.observers.append(tap)

    # -- what the boards say ----------------------------------------------------------------

    def traffic(self, name: str, record: Traffic) -> None:
        if self.closed:
            return
        self.totals[name][record.direction is Direction.OUT] += len(record.data)
        if self.chunks is True or self.chunks == name:
            self.traffic_seq[name] += 1
            self.outbox.put_traffic(record, self.traffic_seq[name])

    def event(self, service: BoardService, event: Event) -> None:
        if self.closed:
            return
        name = service.name
        self.event_seq[name] += 1
        self.outbox.put_event(event_record(service, event, self.event_seq[name], time.time()))

    def changed(self, name: str) -> None:
        self.changed_boards.add(name)
        self.arm()

    def arm(self) -> None:
        """Look at the boards as soon as the rate allows."""
        if self.timer is not None or self.closed:
            return
        pending = self.changed_boards | self.moving
        if not pending:
            return
        due = min(self.seen[name] + self.periods[name] for name in pending)
        at = max(self.loop.time(), due, self.last_look + self.gap)
        self.timer = self.loop.call_at(at, self.look)

    # -- looking ----------------------------------------------------------------------------

    def snapshot(self, boards: list[dict[str, Any]]) -> dict[str, Any]:
        """The first message: ``boards`` (the ``boards`` op's entries of this subscription's
        boards) with each board's travel and state. What it shows is what later messages
        change."""
        out = []
        for entry in boards:
            service = self.services[entry["name"]]
            state = self.state_of(service)
            self.last[service.name] = self._key(state)
            out.append(
                {
                    **entry,
                    "travel": travel(service),
                    "switches": switches(service),
                    "state": state,
                }
            )
        return {
            "kind": "snapshot",
            "t": time.time(),
            "rate": self.rate,
            "rates": self.rates,
            "traffic": self.chunks,
            "boards": out,
        }

    @staticmethod
    def _key(state: dict[str, Any]) -> dict[str, Any]:
        """What is compared from one look to the next: the state without the times."""
        key = {k: v for k, v in state.items() if k != "time"}
        clock = key.get("clock")
        if isinstance(clock, dict):
            key["clock"] = {k: v for k, v in clock.items() if k != "now"}
        return key

    def look(self) -> None:
        self.timer = None
        if self.closed:
            return
        now = self.last_look = self.loop.time()
        self.looks += 1
        pending = self.changed_boards | self.moving
        # the boards due (a millisecond early is on time: the timer was armed for the first)
        names = [
            n
            for n in self.services
            if n in pending and now >= self.seen[n] + self.periods[n] - 1e-3
        ]
        self.changed_boards -= set(names)
        moving = self.moving - set(names)  # those not due are still moving as far as is known
        boards: dict[str, dict[str, Any]] = {}
        for name in names:
            self.seen[name] = now
            service = self.services[name]
            try:
                state = self.state_of(service)
            except Exception as exc:  # a bug in the engine must cost the look, not the daemon
                if name not in self._failed:
                    self._failed.add(name)
                    self.log.error(f"control: cannot look at {name} for a subscriber: {exc!r}")
                continue
            changes = self._changes(name, state)
            if changes:
                boards[name] = changes
            clock = state.get("clock", {})
            if not clock.get("paused") and any(a["moving"] for a in state["axes"].values()):
                moving.add(name)
        self.moving = moving
        counts = {}
        for name, (sent_in, sent_out) in self.totals.items():
            sent = (sent_in, sent_out)
            if self.sent_totals.get(name, (0, 0)) != sent:
                self.sent_totals[name] = sent
                counts[name] = {"in": sent_in, "out": sent_out}
        if boards or counts:
            self.outbox.put_state(boards, counts, time.time())
        if moving or self.changed_boards:
            self.arm()  # a move runs without waking its board: look again at the rate

    def _changes(self, name: str, state: dict[str, Any]) -> dict[str, Any]:
        """What differs from what was sent last (and remember it as sent): fields whole, axes
        field by field; with the board's time when anything does."""
        key = self._key(state)
        last = self.last.get(name, {})
        changes: dict[str, Any] = {}
        for field, value in key.items():
            if field == "axes":
                before = last.get("axes", {})
                axes = {}
                for letter, axis in value.items():
                    was = before.get(letter, {})
                    diff = {f: v for f, v in axis.items() if was.get(f, _NONE) != v}
                    if diff:
                        axes[letter] = diff
                if axes:
                    changes["axes"] = axes
            elif last.get(field, _NONE) != value:
                changes[field] = value
        self.last[name] = key
        if changes:
            changes["time"] = state.get("time")
        return changes

    # -- sending ----------------------------------------------------------------------------

    def message(self, kind: str, body: Any) -> dict[str, Any]:
        """A queued message as it goes on the wire."""
        if kind == "event":
            return {"id": self.ident, "kind": "event", "event": body}
        if kind == "traffic":
            chunk, seq = body
            return {
                "id": self.ident,
                "kind": "traffic",
                "traffic": {**chunk.to_record(), "seq": seq},
            }
        out = {"id": self.ident, "kind": "state", "t": body["t"], "boards": body["boards"]}
        if body["traffic"]:
            out["traffic"] = body["traffic"]
        if any(self.outbox.dropped.values()):
            out["dropped"] = dict(self.outbox.dropped)
        return out

    def start(self, writer: Writer, lock: asyncio.Lock) -> None:
        """Send what is queued, and what comes, on ``writer`` (after the snapshot's reply)."""
        self.sender = self.loop.create_task(self._send(writer, lock), name="control subscription")

    async def _send(self, writer: Writer, lock: asyncio.Lock) -> None:
        outbox = self.outbox
        while not self.closed:
            batch: list[bytes] = []
            while len(batch) < BATCH and (queued := outbox.pop()) is not None:
                try:
                    batch.append(encode(self.message(*queued)))
                except (TypeError, ValueError) as exc:  # not JSON: a bug, not the client's
                    self.log.error(f"control: cannot send a {queued[0]} message: {exc}")
            if not batch:
                outbox.wake.clear()
                await outbox.wake.wait()
                continue
            async with lock:
                if writer.is_closing():
                    return
                try:
                    writer.write(b"".join(batch))
                    self.sent += len(batch)
                    await writer.drain()  # a client that reads slowly holds up only this task
                except ConnectionError:
                    return

    def stats(self) -> dict[str, Any]:
        return {"sent": self.sent, "dropped": dict(self.outbox.dropped), "peak": self.outbox.peak}

    async def close(self) -> dict[str, Any]:
        """Stop watching and sending (what is queued is dropped); returns :meth:`stats`."""
        self.close_now()
        sender, self.sender = self.sender, None
        if sender is not None and not sender.done():
            sender.cancel()
            with contextlib.suppress(BaseException):
                await sender
        return self.stats()

    def close_now(self) -> None:
        """Stop watching at once (the sender, if any, ends at its next turn)."""
        self.closed = True
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        for service, tap in zip(self.services.values(), self.taps, strict=True):
            with contextlib.suppress(ValueError):
                service.observers.remove(tap)
        self.outbox.wake.set()


_NONE = object()  # a field that was not there before

__all__ = [
    "QUEUE_LIMIT",
    "TRAFFIC_BYTES",
    "Outbox",
    "Subscription",
    "event_record",
    "options",
    "switches",
    "travel",
]
