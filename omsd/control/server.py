"""The daemon's side of the control API (protocol: :mod:`omsd.control.protocol`).

It listens on a Unix socket, owner-only (mode 0600 in a directory it creates 0700), and on TCP
only if configured. Each request runs as its own task, so a ``wait`` does not hold up the
connection's other requests; a bad request gets a one-line error and the connection stays.
Everything an operation does to a board goes through the board's world API and the service, at
the board's own time (which the ``time`` operation may have paused or scaled). ``subscribe``
makes the connection a stream of the boards' life as well (:mod:`omsd.control.watch`), until
``unsubscribe`` or the connection ends.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import os
import socket
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

from omsd.control.protocol import (
    MAX_LINE,
    MAX_WAIT,
    OPS,
    STREAM_OPS,
    ControlError,
    Writer,
    decode,
    encode,
)
from omsd.control.waits import BoardWaits
from omsd.control.watch import Subscription, options
from omsd.faults import Faults
from omsd.files import group_id
from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog
from omsd.transport import Endpoint, bound_address

DEFAULT_WAIT = 10.0  # seconds of real time a wait may take unless told
MAX_PENDING = 512
"""Requests of one connection in progress at once (waits included: at most ``MAX_WAITS``); with
that many, the connection is read no further until one is answered. A client that asked and
never read the answers had every line it sent made a task at once: 1.6 GB in 15 s."""

GRACE = 1.0
"""Seconds the requests of a connection whose input has ended have to be answered before they
end: a client that half-closes after its last request (``printf ... | nc -NU``) had them
cancelled unanswered, the last line too; one that has gone for good has its waits end this
late at most."""

MAX_WAITS = 256
"""``wait`` operations in progress at once, of all the connections of one control server (the
socket's and its TCP endpoint's together; the dashboard and the MQTT bridge have one each, with
a bound of their own, so that neither can use up the socket's: docs/decisions.md); one more
is refused. A board's waits are looked at together, once at every change of the board
(:mod:`omsd.control.waits`); when each woke at every change on its own, 20,000 of them, sent in
one go, took the daemon's whole CPU, every board stopped answering and SIGTERM went unheard."""

MAX_CONNECTIONS = 64
"""Connections the TCP endpoint holds at once (``[control] tcp``: local, unauthenticated); a
newcomer beyond them is told so in one line and closed, as the web dashboard's are. Without a
bound, anyone who could reach the port could hold every file descriptor of the daemon, and its
boards could take no client. The Unix socket (owner-only, or a group's) has none."""

COUNTER = 2**31 - 1
"""The largest slip (steps) or encoder count the ``slip`` and ``encoder`` operations take, either
way: what a 32-bit counter holds, beyond every position range of the manuals (PC48 Appendix C:
"Position range 134,000,000 pulses (+-67,000,000)"). Two slips of 1e308 took the carriage to
infinity, and every later look at the board raised OverflowError."""


class SocketInUse(Exception):
    """The control socket's path is held by a live process."""


class ControlServer:
    def __init__(
        self,
        services: dict[str, BoardService],
        endpoints: Callable[[], list[Endpoint]],
        log: TrafficLog,
    ) -> None:
        self.services = services
        self.endpoints = endpoints
        self.log = log
        self.servers: list[asyncio.Server] = []
        self.paths: list[Path] = []
        self._tasks: set[asyncio.Task[None]] = set()
        self._writers: set[Writer] = set()
        self._requests: dict[Writer, set[asyncio.Task[None]]] = {}  # in progress, by connection
        self._waits = 0  # wait operations in progress
        self._board_waits: dict[str, BoardWaits] = {}  # those in progress, by board
        self._tcp = 0  # connections of the TCP endpoint
        self.subscriptions: dict[Writer, Subscription] = {}

    # -- listening ------------------------------------------------------------------------------

    async def listen_unix(self, path: Path, group: str | None = None) -> None:
        """Listen at ``path``; :class:`SocketInUse` if a live process holds it (a stale socket
        file left by a killed daemon is replaced). The socket is the daemon's user's alone
        (0600), or with ``group`` (``[control] group``) 0660 in that group, so that its members
        can use ``omsd ctl`` (the daemon must be a member: a process gives files only to its
        own groups)."""
        if path.exists() or path.is_symlink():
            if _alive(path):
                raise SocketInUse(str(path))
            path.unlink()
        if not path.parent.exists():
            path.parent.mkdir(parents=True, mode=0o700, exist_ok=True)
        old = os.umask(0o177)  # the socket is born 0600: no window for another user
        try:
            server = await asyncio.start_unix_server(self._connection, path, limit=MAX_LINE)
        finally:
            os.umask(old)
        self.servers.append(server)
        self.paths.append(path)
        if group is not None:
            os.chown(path, -1, group_id(group))
        os.chmod(path, 0o600 if group is None else 0o660)

    async def listen_tcp(self, host: str, port: int) -> tuple[str, int]:
        server = await asyncio.start_server(self._tcp_connection, host, port, limit=MAX_LINE)
        self.servers.append(server)
        return bound_address(server, host)

    async def close(self) -> None:
        for server in self.servers:
            server.close()
        for subscription in self.subscriptions.values():
            subscription.close_now()
        self.subscriptions.clear()
        for writer in list(self._writers):
            writer.close()
        for task in list(self._tasks):
            task.cancel()
        for server in self.servers:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(server.wait_closed(), timeout=2.0)
        for path in self.paths:
            with contextlib.suppress(OSError):
                path.unlink()
        self.servers.clear()
        self.paths.clear()

    # -- connections ----------------------------------------------------------------------------

    async def _tcp_connection(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter
    ) -> None:
        """A connection of the TCP endpoint: served, or beyond :data:`MAX_CONNECTIONS` told
        so and closed."""
        if self._tcp >= MAX_CONNECTIONS:
            error = f"too many control connections ({MAX_CONNECTIONS}): try again later"
            writer.write(encode({"id": None, "ok": False, "error": error}))
            writer.close()  # (the line goes out first)
            return
        self._tcp += 1
        try:
            await self._connection(reader, writer)
        finally:
            self._tcp -= 1

    async def _connection(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._writers.add(writer)
        lock = asyncio.Lock()
        try:
            while True:
                try:
                    line = await reader.readline()
                except (ValueError, asyncio.LimitOverrunError):
                    await self._send(
                        writer, lock, {"id": None, "ok": False, "error": "line too long"}
                    )
                    break
                except ConnectionError:
                    break
                if not line:
                    await self.answered(writer)
                    break
                if not line.strip():
                    continue
                self.request(line, writer, lock)
                await self.backlog(writer)
        finally:
            self.forget(writer)

    def request(
        self,
        line: bytes,
        writer: Writer,
        lock: asyncio.Lock,
        allowed: tuple[str, ...] | None = None,
    ) -> None:
        """Answer one request line of a connection whose replies go to ``writer`` (under
        ``lock``), as a task of its own; ``allowed``: the ops this connection may ask (any
        other gets an error reply), ``None``: every op."""
        self._writers.add(writer)
        task = asyncio.get_running_loop().create_task(self._request(line, writer, lock, allowed))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        mine = self._requests.setdefault(writer, set())
        mine.add(task)
        task.add_done_callback(mine.discard)

    async def backlog(self, writer: Writer) -> None:
        """Wait while the connection of ``writer`` has :data:`MAX_PENDING` requests in
        progress: what it sends next waits in its socket, and a client that never reads its
        answers is held off instead of buffered."""
        while len(mine := self._requests.get(writer, ())) >= MAX_PENDING:
            await asyncio.wait(set(mine), return_when=asyncio.FIRST_COMPLETED)

    async def answered(self, writer: Writer) -> None:
        """The client of ``writer`` has sent all it will (the end of its input: a half-close,
        as ``printf ... | nc -NU`` does, or gone): wait up to :data:`GRACE` for the answers to
        what it asked before the connection is forgotten."""
        mine = self._requests.get(writer)
        if mine:
            await asyncio.wait(set(mine), timeout=GRACE)

    def forget(self, writer: Writer) -> None:
        """A connection has ended: what it asked and is still in progress (its waits) ends, its
        subscription, if any, ends, and its writer is closed."""
        for task in self._requests.pop(writer, ()):
            task.cancel()
        self._writers.discard(writer)
        subscription = self.subscriptions.pop(writer, None)
        if subscription is not None:
            subscription.close_now()  # its sender ends at its next turn
        writer.close()

    async def _request(
        self,
        line: bytes,
        writer: Writer,
        lock: asyncio.Lock,
        allowed: tuple[str, ...] | None = None,
    ) -> None:
        ident: object = None
        subscription = None
        try:
            message = decode(line)
            ident = message.get("id")
            op = message.get("op")
            if allowed is not None and op not in allowed:
                raise ControlError(
                    f"{op!r} is not allowed here: this connection may only watch"
                    f" ({', '.join(allowed)})"
                )
            if op == "subscribe":
                subscription, result = self._subscribe(message, writer)
            elif op == "unsubscribe":
                result = await self._unsubscribe(writer)
            else:
                result = await self.run(message)
            reply: dict[str, Any] = {"id": ident, "ok": True, "result": result}
        except ControlError as exc:
            reply = {"id": ident, "ok": False, "error": str(exc)}
        except (TypeError, ValueError, KeyError) as exc:
            reply = {"id": ident, "ok": False, "error": f"bad request: {exc}"}
        await self._send(writer, lock, reply)
        if subscription is not None:
            subscription.start(writer, lock)  # the stream follows its snapshot

    def _subscribe(
        self, message: dict[str, Any], writer: Writer
    ) -> tuple[Subscription, dict[str, Any]]:
        """A subscription for this connection, and its snapshot."""
        if writer in self.subscriptions:
            raise ControlError("this connection has a subscription already (unsubscribe first)")
        names, rate, traffic, rates = options(message, list(self.services))
        services = [self.services[name] for name in names]
        subscription = Subscription(
            message.get("id"),
            services,
            self._state,
            self.log,
            rate=rate,
            traffic=traffic,
            rates=rates,
        )
        self.subscriptions[writer] = subscription
        return subscription, subscription.snapshot(
            [b for b in self._boards() if b["name"] in names]
        )

    async def _unsubscribe(self, writer: Writer) -> dict[str, Any]:
        subscription = self.subscriptions.pop(writer, None)
        if subscription is None:
            raise ControlError("this connection has no subscription")
        return await subscription.close()

    async def _send(self, writer: Writer, lock: asyncio.Lock, reply: dict[str, Any]) -> None:
        async with lock:
            if writer.is_closing():
                return
            try:
                writer.write(encode(reply))
                await writer.drain()
            except ConnectionError:
                pass

    # -- operations -----------------------------------------------------------------------------

    async def run(self, message: dict[str, Any]) -> Any:
        op = message.get("op")
        if op in STREAM_OPS:
            raise ControlError(f"{op} is for a connection to the control socket only")
        if op not in OPS:
            raise ControlError(f"unknown op {op!r}; known: {', '.join((*OPS, *STREAM_OPS))}")
        if op == "boards":
            return self._boards()
        service = self._service(message)
        if op == "wait":
            return await self._wait(service, message)
        handler: Callable[[BoardService, dict[str, Any]], Any] = getattr(self, f"_op_{op}")
        result = handler(service, message)
        service.service()
        return result if result is not None else self._state(service)

    def _service(self, message: dict[str, Any]) -> BoardService:
        name = message.get("board")
        if name is None:
            if len(self.services) == 1:
                return next(iter(self.services.values()))
            raise ControlError(f"several boards: say which ({', '.join(self.services)})")
        service = self.services.get(str(name))
        if service is None:
            raise ControlError(f"no board {name!r}; boards: {', '.join(self.services)}")
        return service

    def _boards(self) -> list[dict[str, Any]]:
        out = []
        endpoints = self.endpoints()
        for name, service in self.services.items():
            out.append(
                {
                    "name": name,
                    "model": service.model.name,
                    "link": service.config.link,
                    "endpoints": [
                        {"kind": e.kind, "address": e.address} for e in endpoints if e.board == name
                    ],
                }
            )
        return out

    def _state(self, service: BoardService) -> dict[str, Any]:
        now = service.clock()
        state = service.board.snapshot(now)
        link = service.link
        state["board"] = service.name
        # the clock as of this snapshot, and the board's sample grid (PC48 §1.2: the velocity
        # is calculated "2048 times each second"; the grid starts at power-up): with them a
        # manual-clock Board started at ``origin`` reproduces this board exactly
        state["clock"] = {
            **service.timebase.describe(),
            "now": now,
            "origin": service.board.clock.origin,
            "rate": service.board.clock.rate,
        }
        state["faults"] = service.faults.as_dict()
        held = link.held()
        state["link"] = {
            "kind": service.config.link,
            "room": link.room(),
            "pending": getattr(link, "pending", None),
            "waiting": getattr(link, "waiting", None),
            # what the link holds back from the board and why, in words and in parts
            "held": None
            if held is None
            else {
                "text": held.describe(),
                "bytes": held.count,
                "waiting": held.waiting,
                "axes": list(held.axes),
                "since": held.since,
            },
        }
        state["clients"] = [c.label for c in service.clients]
        state["world"] = self._world(service)
        return state

    @staticmethod
    def _world(service: BoardService) -> dict[str, Any]:
        """What is done to the board's world from outside and not undone: the switches forced
        (``limits``: per axis [negative, positive], each true, false or null for "follows the
        carriage"; ``home``: per axis true or false), the axes ``stalled``, the ``inputs``
        driven (per bit, high or low: by the configuration's ``inputs`` or an operation). A
        page or a test shows a switch as forced, and lets it follow the carriage again, from
        this."""
        board = service.board
        world = board.world
        letter = {a.index: a.letter for a in board.axes}
        return {
            "limits": {
                letter[i]: list(pair)
                for i, pair in sorted(world.forced_limits.items())
                if pair[0] is not None or pair[1] is not None
            },
            "home": {letter[i]: active for i, active in sorted(world.forced_home.items())},
            "stalled": [a.letter for a in board.axes if a.stall_phys is not None],
            "inputs": {str(bit): high for bit, high in sorted(world.input_levels.items())},
        }

    def _op_state(self, service: BoardService, m: dict[str, Any]) -> Any:
        return self._state(service)

    @staticmethod
    def _axis(service: BoardService, m: dict[str, Any]) -> str:
        letter = str(m.get("axis", "")).upper()
        if service.board.axis_by_letter(letter) is None:
            axes = service.model.axes
            raise ControlError(f"{service.name} has no axis {letter!r}; axes: {axes}")
        return letter

    @staticmethod
    def _flag(m: dict[str, Any], key: str) -> bool | None:
        value = m.get(key)
        if value is not None and not isinstance(value, bool):
            raise ControlError(f"{key}: expected true, false or null, got {value!r}")
        return value

    def _op_limit(self, service: BoardService, m: dict[str, Any]) -> Any:
        direction = m.get("direction")
        if direction in ("+", "positive"):
            direction = 1
        elif direction in ("-", "negative"):
            direction = -1
        if isinstance(direction, bool) or direction not in (1, -1):
            raise ControlError(f"direction: expected +1 or -1, got {direction!r}")
        axis = self._axis(service, m)
        service.board.set_limit(axis, int(direction), self._flag(m, "active"), service.clock())
        return None

    def _op_home(self, service: BoardService, m: dict[str, Any]) -> Any:
        axis = self._axis(service, m)
        service.board.set_home(axis, self._flag(m, "active"), service.clock())
        return None

    def _op_input(self, service: BoardService, m: dict[str, Any]) -> Any:
        bit = m.get("bit")
        if (
            isinstance(bit, bool)
            or not isinstance(bit, int)
            or not 0 <= bit < service.model.io_bits
        ):
            raise ControlError(f"bit: expected 0..{service.model.io_bits - 1}, got {bit!r}")
        service.board.set_input(bit, self._flag(m, "high"), service.clock())
        return None

    def _op_slip(self, service: BoardService, m: dict[str, Any]) -> Any:
        steps = _counter(m, "steps")
        service.board.inject_slip(self._axis(service, m), steps, service.clock())
        return None

    def _op_stall(self, service: BoardService, m: dict[str, Any]) -> Any:
        stalled = self._flag(m, "stalled")
        service.board.set_stall(self._axis(service, m), bool(stalled), service.clock())
        return None

    def _op_encoder(self, service: BoardService, m: dict[str, Any]) -> Any:
        counts = int(_counter(m, "counts"))
        service.board.set_encoder_input(self._axis(service, m), counts, service.clock())
        return None

    def _op_fault(self, service: BoardService, m: dict[str, Any]) -> Any:
        settings: dict[str, Any] = asdict(service.faults)
        settings.pop("_random", None)
        for key in ("latency", "drop", "garble"):
            if key in m:
                settings[key] = _number(m, key)
        if "baud" in m:
            baud = m["baud"]
            if baud is not None and (isinstance(baud, bool) or not isinstance(baud, int)):
                raise ControlError(f"baud: expected an integer or null, got {baud!r}")
            settings["baud"] = baud
        if "seed" in m:
            seed = m["seed"]
            if isinstance(seed, bool) or not isinstance(seed, int):
                raise ControlError(f"seed: expected an integer, got {seed!r}")
            settings["seed"] = seed
        if "cable" in m:
            cable = m["cable"]
            if not isinstance(cable, bool):
                raise ControlError(f"cable: expected true or false, got {cable!r}")
            settings["cable"] = cable
        try:
            faults = Faults(**settings)
        except (TypeError, ValueError) as exc:
            raise ControlError(str(exc)) from None
        was = service.faults.cable
        service.set_faults(faults)
        if was != faults.cable:
            self.log.warning(f"{service.name}: cable {'reconnected' if faults.cable else 'cut'}")
        return faults.as_dict()

    def _op_time(self, service: BoardService, m: dict[str, Any]) -> Any:
        clock = service.timebase
        action = m.get("action")
        try:
            if action == "pause":
                service.service()  # the board catches up to the moment of the pause
                clock.pause()
            elif action == "resume":
                clock.resume()
            elif action == "step":
                clock.step(_number(m, "seconds"))
            elif action == "scale":
                clock.set_scale(_number(m, "scale"))
            else:
                raise ControlError(f"action: expected pause, resume, step or scale, got {action!r}")
        except ValueError as exc:
            raise ControlError(str(exc)) from None
        return None

    def _op_reset(self, service: BoardService, m: dict[str, Any]) -> Any:
        service.power_cycle()
        self.log.warning(f"{service.name}: power cycled (control API)")
        return None

    # -- waiting --------------------------------------------------------------------------------

    async def _wait(self, service: BoardService, m: dict[str, Any]) -> Any:
        until = m.get("until")
        timeout = _number(m, "timeout") if "timeout" in m else DEFAULT_WAIT
        if not 0.0 <= timeout <= MAX_WAIT:
            raise ControlError(f"timeout: expected 0 to {MAX_WAIT} s, got {timeout}")
        # the board run to now first: the condition reads where the axis is and where its
        # motion began, which a board woken only when its host could hear something
        # (Machine.next_wakeup) may not have brought up to date
        service.service()
        check = self._condition(service, m, until)
        if check():
            return self._state(service)
        if self._waits >= MAX_WAITS:
            raise ControlError(f"too many waits in progress ({MAX_WAITS}): wait for one to end")
        waits = self._board_waits.get(service.name)
        if waits is None:

            def ended() -> None:
                del self._board_waits[service.name]

            waits = self._board_waits[service.name] = BoardWaits(service, ended)
        self._waits += 1
        try:
            if not await waits.until(check, timeout, position=until == "position"):
                raise ControlError(f"timed out after {timeout:g} s waiting for {until}")
        finally:
            self._waits -= 1
        return self._state(service)

    def _condition(
        self, service: BoardService, m: dict[str, Any], until: object
    ) -> Callable[[], bool]:
        board = service.board
        if until not in ("done", "idle", "position"):
            raise ControlError(f"until: expected done, idle or position, got {until!r}")
        if until == "idle":
            # every axis at rest with nothing queued
            return lambda: all(not a.moving and a.queue.empty for a in board.axes)
        axis = board.axis_by_letter(self._axis(service, m))
        assert axis is not None
        if until == "done":
            return lambda: axis.done
        if until == "position":
            # "reaches (or passes)": from where the axis is, the target is ahead on one side and
            # the wait ends once the counter is there or beyond. A moving axis that has already
            # passed it on this motion (it lies between where the motion began and here) has
            # reached it: a client that asks a moment late must not wait for a return trip.
            target = _number(m, "position")
            start = axis.counter(service.clock())
            if axis.moving and min(axis.traj.x0, start) <= target <= max(axis.traj.x0, start):
                return lambda: True
            side = math.copysign(1.0, target - start) if target != start else 0.0

            def reached() -> bool:
                here = axis.counter(service.clock())
                return here == target or (side != 0.0 and (here - target) * side >= 0)

            return reached
        raise AssertionError(until)  # pragma: no cover - checked above


def _number(m: dict[str, Any], key: str) -> float:
    value = m.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ControlError(f"{key}: expected a number, got {value!r}")
    try:
        number = float(value)  # JSON's integers are read whole: 1 and 400 zeros is one
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise ControlError(f"{key}: expected a number, got one beyond a float's range")
    return number


def _counter(m: dict[str, Any], key: str) -> float:
    """A number of steps or counts a board's counters can hold (:data:`COUNTER`)."""
    value = _number(m, key)
    if not -COUNTER <= value <= COUNTER:
        raise ControlError(f"{key}: expected -{COUNTER} to {COUNTER}, got {value:g}")
    return value


def _alive(path: Path) -> bool:
    """Whether a process listens at the Unix socket ``path``."""
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    probe.settimeout(0.5)
    try:
        probe.connect(str(path))
    except OSError:
        return False
    finally:
        probe.close()
    return True


__all__ = ["ControlServer", "SocketInUse"]
