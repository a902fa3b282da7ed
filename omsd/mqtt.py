"""The MQTT bridge: the boards' life published to a broker, the control operations taken from it.

Off unless the configuration has an ``[mqtt]`` table (:class:`omsd.config.MqttConfig`). Issue 6:
"Publishes per board: retained state (per axis position, velocity, flags), events (done, limit,
slip, command error), the traffic as it flows, the daemon's online/offline status as a retained
last will; rates bounded while axes move. Accepts the control operations on command topics. A
broker that is down or goes away never stops or slows the boards: the bridge reconnects with
backoff and says so in the log once."

Topics (``omsd`` is the default ``prefix``; board names are ``[A-Za-z0-9_.-]+``, so always one
topic level)::

    omsd/status              "online" / "offline"              retained, QoS 1, the last will
    omsd/<board>/state       the board's state (JSON)          retained, QoS 1
    omsd/<board>/event       one event (JSON), in order        QoS 1
    omsd/<board>/traffic     one chunk of traffic (JSON)       QoS 0
    omsd/<board>/cmd/<op>    a control operation (JSON args)   subscribed, QoS 1
    omsd/<board>/reply/<op>  its outcome (JSON)                QoS 1
    omsd/status/reply        the outcome of a command for a board that does not exist

``state`` is the board's snapshot, the board part of the control API's ``state`` (``axes``
with, per axis, ``position``, ``encoder``, ``velocity``, ``moving``, ``done``,
``limit_positive``, ``limit_negative``, ``home`` and the rest; ``status``, ``done_register``,
``mode``...; not the clock, faults, link or clients), with ``board``, ``time`` (the board's
clock, seconds) and ``t`` (wall clock, seconds since the epoch). It is published when the
board changes, at most ``state_rate`` times a second per board; while an axis moves the bridge
looks at the board at that rate by itself (a move runs without waking the board), and once more
when it stops. A state equal to the last one published (times aside) is not published again.

``event`` is ``{"seq": 3, "board": "xy", "kind": "limit", "time": 1234.5625, "t": 1700000000.1,
"text": "limit X+", "axis": "X", "direction": 1}``; ``kind`` is ``done`` (with ``done_register``
and ``axes``, the letters whose done flag is set), ``limit`` (``axis``, ``direction`` +1/-1),
``slip`` (``axis``), ``servo_trip`` (``axis``, ``error``: the following error in counts) or
``command_error`` (``error``: the EN-mode message, ``command``). ``seq`` counts a board's events
from 1: a gap means events were dropped. ``time`` is the board's clock when it happened, exact
(the engine's time, not when the bridge saw it).

``traffic``: the object the JSON-lines traffic log writes (:meth:`Traffic.to_record`; choice: one
format for both, so :meth:`Traffic.from_record` reads either), plus ``seq``: ``{"t": ...,
"kind": "traffic", "board": "xy", "endpoint": "tcp:127.0.0.1:7048 #1", "dir": "in", "data":
"WY\\n", "hex": "57590a", "seq": 12}``. ``dir`` is ``in`` (host to board) or ``out``; ``data``
is the bytes as latin-1 text (lossless; JSON escapes the control characters), ``hex`` the same
bytes in hex.

Commands: a message on ``<prefix>/<board>/cmd/<op>`` is the control protocol's request
(:mod:`omsd.control.protocol`) with ``op`` and ``board`` taken from the topic and the other
arguments from the JSON object in the payload (an empty payload is ``{}``; read as the
control socket reads a request: no NaN, Infinity or 1e999, at most ``MAX_LINE`` bytes), run by
:meth:`ControlServer.run`, so it does exactly what the control socket does. The reply goes to
``<prefix>/<board>/reply/<op>``: ``{"id": 7, "ok": true, "result": ...}`` or ``{"id": 7, "ok":
false, "error": "one line"}``, ``id`` echoed from the payload (``null`` without one) so a caller
can match replies. Choices: the topic's board and op win over any in the payload; a *retained*
message on a command topic is ignored (logged once per topic), since it would otherwise be run
again at every reconnection and every daemon start. A command for a board the daemon does not
serve (or whose op is too long for a reply topic) is not run and is answered on
``<prefix>/status/reply`` (issue 13: never on a topic
made of a name from outside), ``{"id": 3, "ok": false, "error": "no board 'zz'; boards: xy",
"board": "zz", "op": "state"}``, QoS 1, not retained.

Never blocking the boards: the bridge observes each board through
:attr:`BoardService.observers`, and an observer only appends to a bounded queue (or notes that the
state changed); events and traffic are made into JSON and published by the bridge's own task,
and the state is looked at by a timer of its own, at most ``state_rate`` times a second. The
queue holds :data:`QUEUE_LIMIT` events, replies and traffic messages; when it is full the oldest
traffic message is dropped (the oldest event only when there is no traffic left to drop), logged
once. Of the state only the latest per board waits (a newer one replaces it), so the latest
state is never lost. At most :data:`WINDOW` publications are in flight.

Reconnection: a broker that cannot be reached or goes away is retried with exponential backoff
from :data:`BACKOFF_MIN` to :data:`BACKOFF_MAX` seconds; the log says once that it is away and
once that it is back (with the number of messages dropped meanwhile), never once per attempt.
Events and replies queued meanwhile are sent when it is back; those in flight when the
connection broke may be lost (QoS 1 without a persistent session). After every (re)connection
``online`` and each board's state are published again. At a clean stop the bridge sends what is
queued (for at most :data:`FAREWELL` seconds), publishes ``offline`` and disconnects; if the
daemon dies, the broker publishes the will, ``offline``.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
import math
import ssl
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import aiomqtt

from omsd.board.events import (
    Event,
)
from omsd.config import MqttConfig
from omsd.control.protocol import MAX_LINE, ControlError, decode
from omsd.control.server import ControlServer
from omsd.control.watch import event_record as event_payload  # one event format for both
from omsd.hostport import host_port
from omsd.service import BoardService
from omsd.telemetry.traffic import Traffic, TrafficLog

QUEUE_LIMIT = 1000
"""Events, replies and traffic messages waiting for the broker, at most."""

WINDOW = 32
"""Publications in flight (handed to the client library, not yet confirmed) at most."""

BACKOFF_MIN = 0.5
"""Seconds before the first retry after a failed or lost connection; doubled each time."""

BACKOFF_MAX = 30.0
"""The longest wait between two attempts."""

STABLE = 10.0
"""A connection that lasted this many seconds resets the backoff; a shorter one does not, so a
broker that accepts and drops at once (another client with our client_id) is not hammered."""

FAREWELL = 2.0
"""Seconds a clean stop may spend sending what is queued and ``offline``."""

TIMEOUT = 10.0
"""Seconds the broker has to answer a connection, a subscription or a QoS 1 publication."""

UNSPECIFIED = 128
"""The reason code paho gives a connection lost without a DISCONNECT of the broker's."""

MAX_TOPIC = 65535
"""Bytes of a topic name, at most (MQTT 3.1.1 §1.5.3: a UTF-8 string's length is two bytes).
A command's op on a topic that long makes a reply topic two bytes longer (reply, cmd)."""

QOS_TRAFFIC = 0  # a flood of it; each chunk is also in the traffic log
QOS_OTHER = 1


def _encode(message: dict[str, Any]) -> bytes:
    return json.dumps(message, separators=(",", ":"), allow_nan=False).encode()


@dataclass(slots=True)
class Message:
    """One publication waiting in the :class:`Outbox`; ``payload`` makes its bytes when it is
    sent (a message dropped unsent costs no JSON)."""

    seq: int
    kind: str  # "state", "event", "reply" or "traffic"
    topic: str
    payload: Callable[[], bytes]
    qos: int
    retain: bool = False


class Outbox:
    """The bridge's bounded queue: events and replies in order, traffic, and at most one state
    per board (a newer one replaces it). :meth:`pop` gives them back in the order they were
    put (by ``seq``), whatever their kind."""

    def __init__(self, limit: int, on_drop: Callable[[Message], None]) -> None:
        self.limit = limit
        self.on_drop = on_drop
        self.ordered: deque[Message] = deque()  # events and replies: dropped only as a last resort
        self.traffic: deque[Message] = deque()
        self.states: dict[str, Message] = {}
        self.dropped = 0
        self.wake = asyncio.Event()
        self._seq = itertools.count()

    def __len__(self) -> int:
        return len(self.ordered) + len(self.traffic) + len(self.states)

    def put(
        self,
        kind: str,
        topic: str,
        payload: Callable[[], bytes],
        qos: int,
        retain: bool = False,
        board: str | None = None,
    ) -> None:
        message = Message(next(self._seq), kind, topic, payload, qos, retain)
        if kind == "state":
            assert board is not None
            self.states.pop(board, None)
            self.states[board] = message
        else:
            if len(self.ordered) + len(self.traffic) >= self.limit:
                oldest = self.traffic.popleft() if self.traffic else self.ordered.popleft()
                self.dropped += 1
                self.on_drop(oldest)
            (self.traffic if kind == "traffic" else self.ordered).append(message)
        self.wake.set()

    def pop(self) -> Message | None:
        best: Message | None = None
        for head in (
            self.ordered[0] if self.ordered else None,
            self.traffic[0] if self.traffic else None,
            *self.states.values(),
        ):
            if head is not None and (best is None or head.seq < best.seq):
                best = head
        if best is None:
            return None
        if self.ordered and best is self.ordered[0]:
            self.ordered.popleft()
        elif self.traffic and best is self.traffic[0]:
            self.traffic.popleft()
        else:
            for board, message in self.states.items():
                if message is best:
                    del self.states[board]
                    break
        return best


class BoardTap:
    """The bridge's observer of one board (:class:`omsd.service.Observer`). Everything here runs
    inside the board's service call, so it only queues and schedules."""

    def __init__(self, bridge: MqttBridge, service: BoardService) -> None:
        self.bridge = bridge
        self.service = service
        base = f"{bridge.config.prefix}/{service.name}"
        self.state_topic = f"{base}/state"
        self.event_topic = f"{base}/event"
        self.traffic_topic = f"{base}/traffic"
        self.period = 1.0 / bridge.config.state_rate
        self.event_seq = 0
        self.traffic_seq = 0
        self.last_look = -math.inf  # loop time the state was last looked at
        self.last_key: bytes | None = None  # the last state published, times aside
        self.timer: asyncio.TimerHandle | None = None
        self.closed = False

    # -- the Observer protocol ------------------------------------------------------------------

    def traffic(self, service: BoardService, record: Traffic) -> None:
        if not self.bridge.config.traffic:
            return
        self.traffic_seq += 1
        seq = self.traffic_seq

        def payload() -> bytes:
            return _encode({**record.to_record(), "seq": seq})

        self.bridge.outbox.put("traffic", self.traffic_topic, payload, QOS_TRAFFIC)

    def event(self, service: BoardService, when: float, event: Event) -> None:
        self.event_seq += 1
        seq = self.event_seq
        wall = time.time()

        def payload() -> bytes:
            return _encode(event_payload(service, event, seq, wall))

        self.bridge.outbox.put("event", self.event_topic, payload, QOS_OTHER)

    def changed(self, service: BoardService) -> None:
        self.arm()

    # -- the state ------------------------------------------------------------------------------

    def arm(self) -> None:
        """Look at the board again as soon as the rate allows (only while connected: the state
        is taken fresh at every connection)."""
        if self.timer is not None or self.closed or not self.bridge.connected:
            return
        loop = self.service.loop
        at = max(loop.time(), self.last_look + self.period)
        self.timer = loop.call_at(at, self.look)

    def look(self) -> None:
        self.timer = None
        if self.closed or not self.bridge.connected:
            return
        self.last_look = self.service.loop.time()
        try:
            state = board_state(self.service)
            key = _encode({k: v for k, v in state.items() if k not in ("time", "t")})
        except Exception as exc:  # a bug in the engine must cost the state, not the daemon
            self.bridge.log.error(f"mqtt: cannot publish the state of {self.service.name}: {exc!r}")
            return
        if key != self.last_key:
            self.last_key = key
            payload = _encode(state)
            self.bridge.outbox.put(
                "state",
                self.state_topic,
                lambda: payload,
                QOS_OTHER,
                retain=True,
                board=self.service.name,
            )
        if any(axis["moving"] for axis in state["axes"].values()):
            self.arm()  # a move runs without waking the board: keep looking at the rate

    def republish(self) -> None:
        """A new connection: the state again, whatever was published before."""
        self.last_key = None
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        self.last_look = -math.inf
        self.arm()

    def close(self) -> None:
        self.closed = True
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        with contextlib.suppress(ValueError):
            self.service.observers.remove(self)


def board_state(service: BoardService) -> dict[str, Any]:
    """The retained state: the board's snapshot (what the control API's ``state`` shows of the
    board itself), with its name and the wall clock."""
    now = service.clock()
    state = service.board.snapshot(now)
    state["board"] = service.name
    state["t"] = time.time()
    return state


def tls_context(config: MqttConfig) -> ssl.SSLContext | None:
    """``tls = true``: the system's CA certificates; a path: that CA file. Built at start-up so a
    bad CA file is a start-up error, not a broker that seems to be down."""
    if config.tls is False:
        return None
    cafile = None if config.tls is True else str(config.tls)
    return ssl.create_default_context(cafile=cafile)


def _quiet_logger() -> logging.Logger:
    """The client library logs through ``logging``; the daemon's log is the TrafficLog, which
    the bridge feeds itself (once per outage), so the library's own lines go nowhere."""
    logger = logging.getLogger("omsd.mqtt.client")
    logger.propagate = False
    if not logger.handlers:
        logger.addHandler(logging.NullHandler())
    return logger


def _reason(exc: BaseException) -> str:
    """One line on why: the library's own cause when it wraps one ("Disconnected during message
    iteration" says less than "The connection was lost")."""
    if exc.__cause__ is not None:
        exc = exc.__cause__
    if (
        isinstance(exc, aiomqtt.MqttCodeError)
        and "Unexpected disconnection" in exc.args
        and getattr(exc.rc, "value", exc.rc) == UNSPECIFIED
    ):
        # MQTT 3.1.1 has no reason for a connection the broker drops (stopped, or another
        # client connected with our client_id): paho says 'Unspecified error', which says
        # nothing to whoever reads the log
        return "the broker closed the connection"
    text = str(exc) or type(exc).__name__
    return text.replace("\n", " ").replace("[Errno 111] ", "")


class MqttBridge:
    """Publishes the boards and takes commands; :meth:`start` returns at once (the connection
    is made in the background), :meth:`stop` within about :data:`FAREWELL` seconds."""

    def __init__(
        self,
        config: MqttConfig,
        services: list[BoardService],
        control: ControlServer,
        log: TrafficLog,
        queue_limit: int | None = None,
    ) -> None:
        self.config = config
        self.services = services
        self.control = control
        self.log = log
        self.where = host_port(config.host, config.port)
        self.status_topic = f"{config.prefix}/status"
        self.reply_topic = f"{config.prefix}/status/reply"  # for boards it does not serve
        self.outbox = Outbox(QUEUE_LIMIT if queue_limit is None else queue_limit, self._dropped)
        self.tls = tls_context(config)
        self.taps = [BoardTap(self, s) for s in services]
        self.connected = False
        self.attempts = 0  # connection attempts so far
        self.connections = 0  # successful ones
        self._task: asyncio.Task[None] | None = None
        self._commands: set[asyncio.Task[None]] = set()
        self._inflight: set[asyncio.Task[None]] = set()
        self._stopping = asyncio.Event()
        self._broken: asyncio.Future[None] | None = None
        self._drop_logged = False
        self._dropped_at_loss = 0  # outbox.dropped when the last connection was lost
        self._retained_warned: set[str] = set()
        self._bugs: set[str] = set()

    # -- life -----------------------------------------------------------------------------------

    def start(self) -> None:
        for tap in self.taps:
            tap.service.observers.append(tap)
        self._task = asyncio.get_running_loop().create_task(self._run(), name="mqtt bridge")

    async def stop(self) -> None:
        for tap in self.taps:
            tap.close()
        self._stopping.set()
        self.outbox.wake.set()
        task, self._task = self._task, None
        if task is not None:
            if not self.connected:
                task.cancel()  # connecting or waiting to retry: nothing to say goodbye to
            done, _ = await asyncio.wait({task}, timeout=FAREWELL + 1.0)
            if not done:
                task.cancel()
                await asyncio.wait({task}, timeout=1.0)
            if task.done() and not task.cancelled() and task.exception() is not None:
                self.log.error(f"mqtt: the bridge failed: {task.exception()!r}")
        for pending in (*self._commands, *self._inflight):
            pending.cancel()
        for pending in (*self._commands, *self._inflight):
            with contextlib.suppress(BaseException):
                await pending
        self.connected = False

    async def _run(self) -> None:
        delay = BACKOFF_MIN
        failed_logged = False  # "cannot reach" said for this outage
        ever = False
        while not self._stopping.is_set():
            self.attempts += 1
            started: float | None = None
            try:
                client = self._client()
                async with client:
                    started = time.monotonic()
                    await self._connected(client, ever)
                    ever = True
                    failed_logged = False
                    await self._session(client)
            except Exception as exc:  # MqttError, or a bug: either way, retry with backoff
                if not isinstance(exc, aiomqtt.MqttError) and repr(exc) not in self._bugs:
                    self._bugs.add(repr(exc))  # said once, not at every attempt
                    self.log.error(f"mqtt: the bridge failed: {exc!r}; retrying")
                lost = self.connected
                self.connected = False
                if self._stopping.is_set():
                    break
                if lost:
                    self._dropped_at_loss = self.outbox.dropped
                    self.log.warning(
                        f"mqtt: lost the broker at {self.where} ({_reason(exc)});"
                        " reconnecting with backoff"
                    )
                    failed_logged = True
                elif not failed_logged:
                    self.log.warning(
                        f"mqtt: cannot reach the broker at {self.where} ({_reason(exc)});"
                        " retrying in the background"
                    )
                    failed_logged = True
            finally:
                self.connected = False
            if self._stopping.is_set():
                break
            if started is not None and time.monotonic() - started >= STABLE:
                delay = BACKOFF_MIN
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._stopping.wait(), delay)
            delay = min(delay * 2.0, BACKOFF_MAX)

    def _client(self) -> aiomqtt.Client:
        config = self.config
        client = aiomqtt.Client(
            config.host,
            config.port,
            username=config.username,
            password=config.password,
            identifier=config.client_id,
            logger=_quiet_logger(),
            will=aiomqtt.Will(self.status_topic, b"offline", qos=QOS_OTHER, retain=True),
            keepalive=config.keepalive,
            timeout=TIMEOUT,
            tls_context=self.tls,
            max_inflight_messages=WINDOW,
        )
        client.pending_calls_threshold = WINDOW + 8  # the window is meant: no warning for it
        return client

    async def _connected(self, client: aiomqtt.Client, again: bool) -> None:
        self.connections += 1
        await client.publish(self.status_topic, b"online", qos=QOS_OTHER, retain=True)
        await client.subscribe(f"{self.config.prefix}/+/cmd/+", qos=QOS_OTHER)
        self.connected = True
        self._drop_logged = False
        dropped = self.outbox.dropped - self._dropped_at_loss  # since start, or the loss
        note = f"; {dropped} messages were dropped meanwhile" if dropped else ""
        if again:
            self.log.info(f"mqtt: the broker at {self.where} is back{note}")
        else:
            self.log.info(f"mqtt: connected to the broker at {self.where}{note}")
        for tap in self.taps:
            tap.republish()

    async def _session(self, client: aiomqtt.Client) -> None:
        """Publish and listen until the connection breaks (:class:`aiomqtt.MqttError`) or the
        bridge stops (then the queue is sent, ``offline`` published, and it returns)."""
        loop = asyncio.get_running_loop()
        self._broken = loop.create_future()
        sender = loop.create_task(self._sender(client))
        receiver = loop.create_task(self._receiver(client))
        stopping = loop.create_task(self._stopping.wait())
        tasks: set[asyncio.Future[Any]] = {sender, receiver, stopping, self._broken}
        try:
            done, _ = await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
            if stopping in done and not self._broken.done():
                receiver.cancel()
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._flush(sender), FAREWELL)
                with contextlib.suppress(aiomqtt.MqttError):
                    await client.publish(
                        self.status_topic, b"offline", qos=QOS_OTHER, retain=True, timeout=1.0
                    )
                return
            ended: tuple[asyncio.Future[Any], ...] = (self._broken, receiver, sender)
            for future in ended:
                if future.done() and not future.cancelled():
                    exc = future.exception()
                    if exc is not None:
                        raise exc
            raise aiomqtt.MqttError("the connection ended")
        finally:
            for task in (sender, receiver, stopping):
                task.cancel()
            for task in (sender, receiver, stopping):
                with contextlib.suppress(BaseException):
                    await task
            if not self._broken.done():
                self._broken.cancel()
            for pending in list(self._inflight):
                pending.cancel()

    async def _flush(self, sender: asyncio.Task[None]) -> None:
        """Let the sender empty the queue (it returns when stopping and empty), then wait for
        what is in flight."""
        self.outbox.wake.set()
        await asyncio.shield(sender)
        while self._inflight:
            await asyncio.gather(*list(self._inflight), return_exceptions=True)

    # -- publishing -----------------------------------------------------------------------------

    async def _sender(self, client: aiomqtt.Client) -> None:
        window = asyncio.Semaphore(WINDOW)
        loop = asyncio.get_running_loop()
        outbox = self.outbox
        while True:
            message = outbox.pop()
            if message is None:
                if self._stopping.is_set():
                    return
                outbox.wake.clear()
                await outbox.wake.wait()
                continue
            try:
                payload = message.payload()
            except (TypeError, ValueError) as exc:  # not JSON: a bug, not the broker's fault
                self.log.error(f"mqtt: cannot publish on {message.topic}: {exc}")
                continue
            await window.acquire()
            # tasks start in the order they are made, so the library gets them in queue order
            task = loop.create_task(self._publish(client, message, payload, window))
            self._inflight.add(task)
            task.add_done_callback(self._inflight.discard)

    async def _publish(
        self,
        client: aiomqtt.Client,
        message: Message,
        payload: bytes,
        window: asyncio.Semaphore,
    ) -> None:
        try:
            await client.publish(message.topic, payload, qos=message.qos, retain=message.retain)
        except aiomqtt.MqttError as exc:
            if self._broken is not None and not self._broken.done():
                self._broken.set_exception(exc)
        except (TypeError, ValueError) as exc:  # refused by the library: a bug, said once
            if repr(exc) not in self._bugs:
                self._bugs.add(repr(exc))
                self.log.error(f"mqtt: cannot publish on {message.topic[:100]}: {exc}")
        finally:
            window.release()

    def _dropped(self, message: Message) -> None:
        if not self._drop_logged:
            self._drop_logged = True
            state = "is slow" if self.connected else "is away"
            self.log.warning(
                f"mqtt: the broker at {self.where} {state} and {self.outbox.limit} messages are"
                f" queued; dropping the oldest {message.kind} messages (said once)"
            )

    # -- commands -------------------------------------------------------------------------------

    async def _receiver(self, client: aiomqtt.Client) -> None:
        async for message in client.messages:
            self._command(message)

    def _command(self, message: aiomqtt.Message) -> None:
        topic = str(message.topic)
        prefix = self.config.prefix + "/"
        if not topic.startswith(prefix):
            return
        parts = topic[len(prefix) :].split("/")
        if len(parts) != 3 or parts[1] != "cmd":
            return
        board, _, op = parts
        if message.retain:
            if topic not in self._retained_warned:
                self._retained_warned.add(topic)
                self.log.warning(f"mqtt: ignored a retained command on {topic} (clear it)")
            return
        task = asyncio.get_running_loop().create_task(self._execute(board, op, message.payload))
        self._commands.add(task)
        task.add_done_callback(self._commands.discard)

    async def _execute(self, board: str, op: str, payload: object) -> None:
        ident: object = None
        names = [s.name for s in self.services]
        if board not in names:
            self._refuse(board, op, payload, f"no board {board!r}; boards: {', '.join(names)}")
            return
        topic = f"{self.config.prefix}/{board}/reply/{op}"
        if len(topic.encode()) > MAX_TOPIC:  # an op of some 65,000 characters: no op's name
            self._refuse(board, op, payload, f"unknown op of {len(op)} characters")
            return
        try:
            request = _arguments(payload)
            ident = request.get("id")
            request["op"] = op
            request["board"] = board
            result = await self.control.run(request)
            reply: dict[str, Any] = {"id": ident, "ok": True, "result": result}
        except ControlError as exc:
            reply = {"id": ident, "ok": False, "error": str(exc)}
        except (TypeError, ValueError, KeyError) as exc:
            reply = {"id": ident, "ok": False, "error": f"bad request: {exc}"}
        try:
            data = _encode(reply)
        except (TypeError, ValueError) as exc:
            data = _encode({"id": None, "ok": False, "error": f"bad request: {exc}"})
        self.outbox.put("reply", topic, lambda: data, QOS_OTHER)

    def _refuse(self, board: str, op: str, payload: object, error: str) -> None:
        """A command for a board this daemon does not serve, or whose reply topic could not be
        made (longer than MQTT allows), is not run (whatever the op), and is answered on
        ``<prefix>/status/reply``, never on a topic made of the unknown name: ``{"id": 3,
        "ok": false, "error": "no board 'zz'; boards: xy", "board": "zz", "op": "state"}``."""
        ident: object = None
        with contextlib.suppress(ControlError):
            ident = _arguments(payload).get("id")
        reply = {
            "id": ident,
            "ok": False,
            "error": error,
            "board": board,
            "op": op,
        }
        try:
            data = _encode(reply)
        except (TypeError, ValueError):
            data = _encode({**reply, "id": None})
        self.outbox.put("reply", self.reply_topic, lambda: data, QOS_OTHER)


def _arguments(payload: object) -> dict[str, Any]:
    """A command's payload: a JSON object, or nothing at all for an operation without
    arguments. Read as the control socket reads a request (:func:`omsd.control.protocol.decode`:
    no NaN, Infinity or 1e999, which would make the command run and its reply, echoing the id,
    impossible to write) and bounded as it is (:data:`MAX_LINE` bytes: a payload of 100 MB held
    the boards up for seconds while it was read as JSON, and its id came back in the reply)."""
    if payload is None:
        return {}
    data = bytes(payload) if isinstance(payload, bytes | bytearray) else str(payload).encode()
    if len(data) > MAX_LINE:
        raise ControlError(f"payload: {len(data)} bytes, more than {MAX_LINE}")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise ControlError("payload: expected a JSON object in UTF-8") from None
    if not text.strip():
        return {}
    try:
        return decode(data)
    except ControlError as exc:
        if str(exc) == "not a JSON object":  # JSON, but not an object
            raise ControlError(
                "payload: expected a JSON object of the operation's arguments"
            ) from None
        raise ControlError(f"payload: {exc}") from None


__all__ = ["MqttBridge", "Outbox", "board_state", "event_payload"]
