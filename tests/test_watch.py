"""The control API's subscription (omsd.control.watch, issue 18): a snapshot, then the changes
at a bounded rate, nothing while idle, the events as they happen, bounded whatever the client.

The daemon runs in-process (omsd.daemon.Daemon on the test's event loop), its control socket in
the test's directory, so a test can look inside it: the subscriptions, their queues, their
timers, the boards' observers. The client is a plain asyncio connection speaking JSON lines.

No assertion is on speed. The rate limit is behavioural: the daemon stamps each message (``t``)
and the gaps between state messages are never below the period; over a move the count is never
above ``rate`` x its duration + 2.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import itertools
import json
import re
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

import omsd.mqtt
from omsd.board.events import CommandErrorEvent, DoneEvent, LimitEvent, ServoTripEvent, SlipEvent
from omsd.board.world import AxisWorld
from omsd.config import BoardConfig, ControlConfig, DaemonConfig, TcpEndpoint
from omsd.control.protocol import ControlError, merge
from omsd.control.server import ControlServer
from omsd.control.watch import QUEUE_LIMIT, TRAFFIC_BYTES, Outbox, event_record
from omsd.daemon import Daemon
from omsd.protocol.errors import ErrorKind
from omsd.service import BoardService
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog

WAIT = 5.0  # seconds anything expected may take


@dataclass
class Lab:
    daemon: Daemon
    socket: Path
    ports: dict[str, int]

    @property
    def control(self) -> ControlServer:
        assert self.daemon.control is not None
        return self.daemon.control

    def service(self, name: str) -> BoardService:
        return next(s for s in self.daemon.services if s.name == name)

    async def board(self, name: str) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
        return await asyncio.open_connection("127.0.0.1", self.ports[name])

    async def stream(self) -> Stream:
        return Stream(*await asyncio.open_unix_connection(str(self.socket)))


class Stream:
    """A control connection: requests out, JSON lines in."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer
        self.ids = 0

    async def send(self, op: str, **args: Any) -> int:
        self.ids += 1
        self.writer.write(json.dumps({"id": self.ids, "op": op, **args}).encode() + b"\n")
        await self.writer.drain()
        return self.ids

    async def next(self, timeout: float = WAIT) -> dict[str, Any] | None:
        try:
            line = await asyncio.wait_for(self.reader.readline(), timeout)
        except TimeoutError:
            return None
        assert line, "the daemon closed the connection"
        message: dict[str, Any] = json.loads(line)
        return message

    async def reply(self, ident: int) -> dict[str, Any]:
        """The reply to request ``ident`` (stream messages before it are skipped)."""
        while True:
            message = await self.next()
            assert message is not None, f"no reply to {ident}"
            if message.get("id") == ident and "ok" in message:
                return message

    async def subscribe(self, **args: Any) -> dict[str, Any]:
        reply = await self.reply(await self.send("subscribe", **args))
        assert reply["ok"], reply
        result: dict[str, Any] = reply["result"]
        return result

    async def until(self, check: Any, timeout: float = WAIT) -> list[dict[str, Any]]:
        """Messages up to and including the first that ``check`` accepts."""
        got: list[dict[str, Any]] = []
        deadline = time.monotonic() + timeout
        while True:
            message = await self.next(max(0.0, deadline - time.monotonic()))
            assert message is not None, f"not seen in {timeout} s; got {got[-5:]}"
            got.append(message)
            if check(message):
                return got

    async def quiet(self, seconds: float) -> list[dict[str, Any]]:
        """Every message of the next ``seconds``."""
        got = []
        deadline = time.monotonic() + seconds
        while (message := await self.next(max(0.0, deadline - time.monotonic()))) is not None:
            got.append(message)
        return got

    def close(self) -> None:
        self.writer.close()


@contextlib.asynccontextmanager
async def lab(tmp_path: Path, *boards: BoardConfig) -> AsyncIterator[Lab]:
    if not boards:
        boards = (BoardConfig(name="xy"),)
    boards = tuple(
        BoardConfig(**{**b.__dict__, "tcp": (TcpEndpoint("127.0.0.1", 0),)}) for b in boards
    )
    socket = tmp_path / "control.sock"
    config = DaemonConfig(boards=boards, control=ControlConfig(socket=socket, explicit=True))
    log = io.StringIO()
    daemon = Daemon(config, TrafficLog("plain", stream=log), out=io.StringIO())
    endpoints = await daemon.start()
    ports = {e.board: int(e.address.rsplit(":", 1)[1]) for e in endpoints if e.kind == "tcp"}
    try:
        yield Lab(daemon, socket, ports)
    finally:
        await daemon.stop()
    assert not re.findall(r"^\S+ error: .*", log.getvalue(), re.M), log.getvalue()


def states(messages: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [m for m in messages if m.get("kind") == "state"]


def events(messages: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [m["event"] for m in messages if m.get("kind") == "event"]


def done(message: dict[str, Any]) -> bool:
    return message.get("kind") == "event" and message["event"]["kind"] == "done"


# -- the snapshot -------------------------------------------------------------------------------


async def test_the_snapshot_has_every_board_as_the_state_op_gives_it(tmp_path: Path) -> None:
    xy = BoardConfig(name="xy", world={"X": AxisWorld(negative_limit=-500, positive_limit=800)})
    async with lab(tmp_path, xy, BoardConfig(name="servo", model="PCIX-400", link="raw")) as lab_:
        board_r, board_w = await lab_.board("xy")
        board_w.write(b"WY")
        await board_r.readuntil(b"\n")
        stream = await lab_.stream()
        snapshot = await stream.subscribe()
        assert snapshot["kind"] == "snapshot" and snapshot["rate"] == 10.0
        assert snapshot["traffic"] is False
        assert [b["name"] for b in snapshot["boards"]] == ["xy", "servo"]
        first, second = snapshot["boards"]
        assert first["model"] == "PC48-4E" and first["link"] == "driver"
        assert first["endpoints"] == [{"kind": "tcp", "address": f"127.0.0.1:{lab_.ports['xy']}"}]
        assert first["travel"] == {"X": [-500.0, 800.0]} and second["travel"] == {}
        assert len(first["state"]["clients"]) == 1  # the board's TCP client
        other = await lab_.stream()
        state = (await other.reply(await other.send("state", board="xy")))["result"]
        for key in ("time", "clock"):
            state.pop(key)
            first["state"].pop(key)
        assert first["state"] == state
        assert set(second["state"]["axes"]) == set("XYZT")
        board_w.close()
        stream.close()
        other.close()


async def test_a_subscription_to_some_boards(tmp_path: Path) -> None:
    async with lab(tmp_path, BoardConfig(name="a"), BoardConfig(name="b")) as lab_:
        stream = await lab_.stream()
        snapshot = await stream.subscribe(boards=["b"], traffic="b")
        assert [b["name"] for b in snapshot["boards"]] == ["b"]
        assert lab_.service("a").observers == [] and len(lab_.service("b").observers) == 1
        one = await lab_.stream()
        assert [b["name"] for b in (await one.subscribe(board="a"))["boards"]] == ["a"]
        stream.close()
        one.close()


@pytest.mark.parametrize(
    ("args", "error"),
    [
        ({"boards": ["zz"]}, "no board 'zz'; boards: xy"),
        ({"board": "zz"}, "no board 'zz'; boards: xy"),
        ({"boards": "xy"}, "boards: expected a list of board names"),
        ({"boards": []}, "boards: expected a list of board names"),
        ({"rate": 0}, "rate: expected messages a second above 0, at most 50"),
        ({"rate": 51}, "rate: expected messages a second above 0, at most 50"),
        ({"rate": True}, "rate: expected"),
        ({"rate": "10"}, "rate: expected"),
        ({"rates": {"zz": 5}}, "rates: no board 'zz' in this subscription"),
        ({"rates": {"xy": 0}}, "rates.xy: expected messages a second above 0, at most 50"),
        ({"rates": [5]}, "rates: expected an object of board names and rates"),
        ({"traffic": "zz"}, "traffic: expected true, false or a board's name (xy), got 'zz'"),
        ({"traffic": 1}, "traffic: expected true, false or a board's name"),
    ],
)
async def test_a_bad_subscription_is_refused(
    tmp_path: Path, args: dict[str, Any], error: str
) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        reply = await stream.reply(await stream.send("subscribe", **args))
        assert reply["ok"] is False and reply["error"].startswith(error), reply
        assert lab_.control.subscriptions == {} and lab_.service("xy").observers == []
        stream.close()


async def test_one_subscription_a_connection_and_unsubscribe_needs_one(tmp_path: Path) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        reply = await stream.reply(await stream.send("unsubscribe"))
        assert reply == {"id": 1, "ok": False, "error": "this connection has no subscription"}
        await stream.subscribe()
        again = await stream.reply(await stream.send("subscribe"))
        assert again["ok"] is False and "has a subscription already" in again["error"]
        # the operations that are not the connection's own: over MQTT, say
        with pytest.raises(ControlError, match="for a connection to the control socket only"):
            await lab_.control.run({"op": "subscribe"})
        stream.close()


# -- the changes --------------------------------------------------------------------------------


async def test_a_move_streams_at_most_rate_a_second_and_then_nothing(tmp_path: Path) -> None:
    rate = 10.0
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        snapshot = await stream.subscribe(rate=rate)
        state = snapshot["boards"][0]["state"]
        _, board = await lab_.board("xy")
        start = time.monotonic()
        board.write(b"AX VL10000 MR8000 GO ID")  # 0.81 s of motion
        got = await stream.until(done)
        got += await stream.quiet(0.5)  # the last look after the done, then nothing
        seconds = time.monotonic() - start
        looks = states(got)
        assert 3 <= len(looks) <= rate * seconds + 2, (len(looks), seconds)
        stamps = [m["t"] for m in looks]
        gaps = [b - a for a, b in itertools.pairwise(stamps)]
        assert min(gaps) >= 0.9 / rate, gaps
        for message in looks:
            merge(state, message["boards"]["xy"])
        x = state["axes"]["X"]
        assert (x["position"], x["moving"], x["motion"], x["done"]) == (8000, False, "idle", True)
        positions = [m["boards"]["xy"].get("axes", {}).get("X", {}).get("position") for m in looks]
        seen = [p for p in positions if p is not None]
        assert seen == sorted(seen) and len(seen) >= 3  # the move, as it goes
        assert await stream.quiet(0.5) == []  # at rest: nothing
        subscription = next(iter(lab_.control.subscriptions.values()))
        assert subscription.timer is None and subscription.moving == set()
        board.close()
        stream.close()


async def test_a_board_given_its_own_rate_is_looked_at_that_often(tmp_path: Path) -> None:
    """``rates``: the board a view shows in detail at its rate, the others at a slower one
    (the web dashboard's subscription). Looks are never closer than the fastest rate allows,
    and each board comes in them no more often than its own."""
    async with lab(tmp_path, BoardConfig(name="fast"), BoardConfig(name="slow")) as lab_:
        stream = await lab_.stream()
        snapshot = await stream.subscribe(rate=2, rates={"fast": 20})
        assert (snapshot["rate"], snapshot["rates"]) == (2.0, {"fast": 20.0})
        writers = []
        for name in ("fast", "slow"):
            _, board = await lab_.board(name)
            board.write(b"AX VL2000 JG2000;")
            writers.append(board)
        got = await stream.quiet(2.0)
        looks = states(got)
        stamps = [m["t"] for m in looks]
        assert min(b - a for a, b in itertools.pairwise(stamps)) >= 0.9 / 20
        fast = [m["t"] for m in looks if "X" in m["boards"].get("fast", {}).get("axes", {})]
        slow = [m["t"] for m in looks if "X" in m["boards"].get("slow", {}).get("axes", {})]
        assert len(fast) >= 20 and len(looks) <= 20 * 2.0 + 2, (len(fast), len(looks))
        assert 2 <= len(slow) <= 2 * 2.0 + 2, slow
        assert min(b - a for a, b in itertools.pairwise(slow)) >= 0.9 / 2
        for board in writers:
            board.close()
        stream.close()


async def test_an_idle_daemon_sends_nothing_and_runs_no_timer(tmp_path: Path) -> None:
    async with lab(tmp_path, BoardConfig(name="a"), BoardConfig(name="b")) as lab_:
        stream = await lab_.stream()
        await stream.subscribe(rate=50)
        assert await stream.quiet(0.5) == []
        subscription = next(iter(lab_.control.subscriptions.values()))
        assert subscription.timer is None and subscription.looks == 0
        stream.close()


async def test_stepped_time_is_looked_at_no_faster_than_the_rate(tmp_path: Path) -> None:
    """Each step of a paused clock runs the board; the looks stay within the rate."""
    rate = 20.0
    async with lab(tmp_path) as lab_:
        control = await lab_.stream()
        await control.reply(await control.send("time", action="pause"))
        _, board = await lab_.board("xy")
        board.write(b"AX VL1000 MR100000 GO")
        stream = await lab_.stream()
        state = (await stream.subscribe(rate=rate))["boards"][0]["state"]
        start = time.monotonic()
        for _ in range(60):
            await control.reply(await control.send("time", action="step", seconds=0.01))
        got = await stream.quiet(0.3)
        seconds = time.monotonic() - start
        looks = states(got)
        assert 1 <= len(looks) <= rate * seconds + 2
        for look in looks:
            merge(state, look["boards"]["xy"])
        assert state["axes"]["X"]["position"] > 0 and state["clock"]["paused"] is True
        # paused and moving: nothing is looked at until the time changes again
        subscription = lab_.control.subscriptions[next(iter(lab_.control.subscriptions))]
        assert subscription.timer is None and await stream.quiet(0.3) == []
        board.close()
        stream.close()
        control.close()


async def test_events_come_as_they_happen(tmp_path: Path) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        await stream.subscribe()
        _, board = await lab_.board("xy")
        board.write(b"XQ AX VL5000 MR100000 GO")
        control = await lab_.stream()
        await control.reply(await control.send("wait", until="position", axis="X", position=500))
        await control.reply(await control.send("limit", axis="X", direction=1, active=True))
        got = await stream.until(lambda m: m.get("kind") == "event" and m["event"]["seq"] == 2)
        error, limit = events(got)
        assert error["kind"] == "command_error" and error["command"] == "XQ"
        assert (limit["kind"], limit["axis"], limit["direction"]) == ("limit", "X", 1)
        assert limit["board"] == "xy" and limit["text"] == "limit X+"
        board.write(b"AY MR10 GO ID")
        (done_event,) = events(await stream.until(done))
        assert (done_event["seq"], done_event["axes"]) == (3, ["Y"])
        board.close()
        stream.close()
        control.close()


async def test_requests_are_answered_during_a_stream(tmp_path: Path) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        await stream.subscribe()
        reply = await stream.reply(await stream.send("slip", axis="X", steps=5))
        assert reply["ok"] and reply["result"]["axes"]["X"]["encoder"] == 5
        (look,) = states(await stream.until(lambda m: m.get("kind") == "state"))
        assert look["boards"]["xy"]["axes"]["X"]["encoder"] == 5
        stream.close()


async def test_traffic_is_counted_and_sent_for_the_board_asked(tmp_path: Path) -> None:
    async with lab(tmp_path, BoardConfig(name="a"), BoardConfig(name="b")) as lab_:
        stream = await lab_.stream()
        await stream.subscribe(traffic="a")
        for name in ("a", "b"):
            reader, writer = await lab_.board(name)
            writer.write(b"WY")
            await reader.readuntil(b"\n")
            writer.close()
        got = await stream.until(
            lambda m: m.get("kind") == "state" and set(m.get("traffic", {})) == {"a", "b"}
        )
        chunks = [m["traffic"] for m in got if m["kind"] == "traffic"]
        assert [(c["board"], c["dir"], c["data"], c["seq"]) for c in chunks] == [
            ("a", "in", "WY", 1),
            ("a", "out", "PC48 ver 3.00-4\n", 2),
        ]
        counts = states(got)[-1]["traffic"]
        assert counts == {"a": {"in": 2, "out": 16}, "b": {"in": 2, "out": 16}}
        stream.close()


# -- bounded -------------------------------------------------------------------------------------


async def test_a_subscriber_that_never_reads_costs_a_bounded_queue(tmp_path: Path) -> None:
    """The subscriber asks for every chunk of traffic and never reads a byte: its socket and
    the transport fill, then its queue, which drops the oldest and counts them. The board's
    own client is answered all the while."""
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        await stream.send("subscribe", traffic=True)  # and never read again
        reader, board = await lab_.board("xy")
        subscription = None
        worst = 0.0
        for _ in range(3000):
            start = time.monotonic()
            board.write(b"RP")
            await reader.readuntil(b"\n")
            worst = max(worst, time.monotonic() - start)
            subscription = next(iter(lab_.control.subscriptions.values()))
            outbox = subscription.outbox
            assert len(outbox) <= QUEUE_LIMIT + 1 and outbox.queued_bytes <= TRAFFIC_BYTES
            if outbox.dropped["traffic"] > 500:
                break
        assert subscription is not None
        assert subscription.outbox.dropped["traffic"] > 500, subscription.stats()
        assert subscription.outbox.peak == QUEUE_LIMIT
        transport = next(iter(lab_.control.subscriptions)).transport
        assert transport.get_write_buffer_size() <= 64 * 1024 + 64 * 4096
        assert worst < 0.5  # sanity: the board never waited for the subscriber
        board.close()
        stream.close()


def test_the_queue_drops_traffic_before_events_and_keeps_one_state() -> None:
    box = Outbox(limit=3, traffic_bytes=10)
    chunk = Traffic(0.0, "xy", "tcp", Direction.IN, b"123456")
    box.put_event({"n": 1})
    box.put_traffic(chunk, 1)
    box.put_traffic(chunk, 2)  # 12 bytes: the first chunk goes
    box.put_event({"n": 2})
    box.put_event({"n": 3})  # 3 messages: the second chunk goes
    box.put_event({"n": 4})  # no chunk left: the oldest event goes
    assert box.dropped == {"event": 1, "traffic": 2, "state": 0}
    box.put_state({"xy": {"axes": {"X": {"position": 1, "velocity": 5.0}}}}, {})
    box.put_state({"xy": {"axes": {"X": {"position": 2}}}, "ab": {"time": 1.0}}, {"xy": {}})
    assert box.dropped["state"] == 1 and len(box) == 4
    kinds = []
    while (item := box.pop()) is not None:
        kinds.append(item)
    assert kinds == [
        ("event", {"n": 2}),
        ("event", {"n": 3}),
        ("event", {"n": 4}),
        (
            "state",
            {
                "boards": {
                    "xy": {"axes": {"X": {"position": 2, "velocity": 5.0}}},
                    "ab": {"time": 1.0},
                },
                "traffic": {"xy": {}},
                "t": 0.0,
            },
        ),
    ]


# -- cleaning up ---------------------------------------------------------------------------------


async def test_unsubscribe_ends_the_stream_and_leaves_nothing_behind(tmp_path: Path) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        await stream.subscribe()
        subscription = next(iter(lab_.control.subscriptions.values()))
        _, board = await lab_.board("xy")
        board.write(b"AX VL10000 MR3000 GO")
        await stream.until(lambda m: m.get("kind") == "state")
        ident = await stream.send("unsubscribe")
        got = await stream.until(lambda m: m.get("id") == ident)
        assert got[-1]["ok"] and got[-1]["result"]["sent"] >= 1
        assert set(got[-1]["result"]["dropped"]) == {"event", "traffic", "state"}
        assert await stream.quiet(0.5) == []  # the move goes on; the stream does not
        assert lab_.control.subscriptions == {} and lab_.service("xy").observers == []
        assert subscription.timer is None and subscription.sender is None
        reply = await stream.reply(await stream.send("state"))  # requests and replies again
        assert reply["ok"]
        await stream.subscribe()  # and a new subscription on the same connection
        board.close()
        stream.close()


async def test_a_client_that_goes_leaves_nothing_behind(tmp_path: Path) -> None:
    async with lab(tmp_path, BoardConfig(name="a"), BoardConfig(name="b")) as lab_:
        stream = await lab_.stream()
        await stream.subscribe(traffic=True)
        subscription = next(iter(lab_.control.subscriptions.values()))
        _, board = await lab_.board("a")
        board.write(b"AA JG1000,1000,1000,1000")  # moves for ever: the timer is armed
        await stream.until(lambda m: m.get("kind") == "state")
        sender = subscription.sender
        assert sender is not None
        stream.close()
        async with asyncio.timeout(WAIT):
            while lab_.control.subscriptions or not sender.done():
                await asyncio.sleep(0.01)
        assert [s.observers for s in lab_.daemon.services] == [[], []]
        assert subscription.timer is None and subscription.closed
        board.close()


async def test_a_stopping_daemon_ends_its_streams(tmp_path: Path) -> None:
    async with lab(tmp_path) as lab_:
        stream = await lab_.stream()
        await stream.subscribe()
        subscription = next(iter(lab_.control.subscriptions.values()))
        await lab_.daemon.stop()
        assert subscription.closed and await stream.reader.read() == b""


# -- the events' form -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "event",
    [
        DoneEvent(1.5, 0b0101),
        LimitEvent(2.0, "Y", -1),
        SlipEvent(2.5, "Z"),
        ServoTripEvent(3.0, "X", 40000.0),
        CommandErrorEvent(3.5, ErrorKind.UNKNOWN_COMMAND, "XQ"),
    ],
)
async def test_an_event_reads_as_the_mqtt_bridge_publishes_it(tmp_path: Path, event: Any) -> None:
    async with lab(tmp_path) as lab_:
        service = lab_.service("xy")
        assert event_record(service, event, 7, 1.0) == omsd.mqtt.event_payload(
            service, event, 7, 1.0
        )
