"""The MQTT bridge (omsd.mqtt) against a real broker: amqtt, in this process, on a free port.

The daemon runs in-process (omsd.daemon.Daemon on the test's event loop) with one board served
on TCP, so a test can read the board's clock directly and talk to the driver link over a real
socket; a fresh broker per test keeps retained messages from leaking between tests. The
subscriber is aiomqtt. The `[mqtt]` configuration is tested here too.

Times are compared on the board's clock, not the wall clock: a move "completes at the right
time" when its done event falls within the board-time window in which the command arrived, plus
the move's duration worked out from the PC48 manual (``MOVE_TIMES``), to the board's 2048 samples
a second.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import itertools
import json
import re
import socket
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import aiomqtt
import pytest
from amqtt.broker import Broker

import omsd.mqtt
from omsd.board.world import AxisWorld
from omsd.config import (
    BoardConfig,
    ConfigError,
    ControlConfig,
    DaemonConfig,
    MqttConfig,
    TcpEndpoint,
    load_config,
)
from omsd.control.protocol import OPS
from omsd.control.server import ControlServer
from omsd.daemon import Daemon, StartupError
from omsd.models import get_model
from omsd.mqtt import Message, Outbox
from omsd.service import BoardService
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog

ROOT = Path(__file__).resolve().parent.parent
WAIT = 5.0  # seconds anything expected may take (a move here lasts at most 2 s)
SAMPLE = 1.0 / 2048  # the board's motion quantum (PC48 §2: 2048 samples a second)
BOARD_CONFIG = """
[[board]]
name = "xy"
tcp = "127.0.0.1:0"
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


# -- configuration ------------------------------------------------------------------------------


def _load(tmp_path: Path, mqtt: str) -> DaemonConfig:
    path = tmp_path / "omsd.toml"
    path.write_text(mqtt + BOARD_CONFIG)
    return load_config(path)


def test_mqtt_is_off_without_its_table(tmp_path: Path) -> None:
    assert _load(tmp_path, "").mqtt is None


def test_mqtt_defaults(tmp_path: Path) -> None:
    config = _load(tmp_path, '[mqtt]\nhost = "broker.lab"\n').mqtt
    assert config == MqttConfig(host="broker.lab")
    assert (config.port, config.prefix, config.tls, config.state_rate) == (1883, "omsd", False, 10)
    assert config.traffic is True and config.keepalive == 60 and config.client_id is None


def test_mqtt_every_key(tmp_path: Path) -> None:
    (tmp_path / "ca.pem").write_text("not checked until the daemon starts\n")
    config = _load(
        tmp_path,
        """
[mqtt]
host = "10.0.0.5"
port = 8884
username = "omsd"
password = ""
tls = "ca.pem"
client_id = "omsd-lab-1"
prefix = "lab/omsd"
keepalive = 15
state_rate = 2.5
traffic = false
""",
    ).mqtt
    assert config == MqttConfig(
        host="10.0.0.5",
        port=8884,
        username="omsd",
        password="",
        tls=tmp_path / "ca.pem",
        client_id="omsd-lab-1",
        prefix="lab/omsd",
        keepalive=15,
        state_rate=2.5,
        traffic=False,
    )


def test_mqtt_tls_changes_the_default_port(tmp_path: Path) -> None:
    config = _load(tmp_path, '[mqtt]\nhost = "[::1]"\ntls = true\n').mqtt
    assert config is not None and (config.host, config.port, config.tls) == ("::1", 8883, True)


@pytest.mark.parametrize(
    ("text", "where", "detail"),
    [
        ("prefix = 'x'", "mqtt.host", "expected the broker's host name or address, got none"),
        ("host = 'a b'", "mqtt.host", 'expected a host name or address, got "a b"'),
        ("host = '1.2.3.999'", "mqtt.host", "expected a host name or address"),
        ("host = 'h'\nport = 0", "mqtt.port", "expected an integer 1..65535, got 0"),
        ("host = 'h'\nprefix = 'a/+/b'", "mqtt.prefix", "without '+', '#'"),
        ("host = 'h'\nprefix = 'a//b'", "mqtt.prefix", "empty levels"),
        ("host = 'h'\nprefix = '$SYS'", "mqtt.prefix", "a leading '$'"),
        ("host = 'h'\nprefix = ''", "mqtt.prefix", "topic levels"),
        ("host = 'h'\nstate_rate = 0", "mqtt.state_rate", "above 0 and at most 1000, got 0"),
        ("host = 'h'\nstate_rate = true", "mqtt.state_rate", "publications per second"),
        ("host = 'h'\ntraffic = 'yes'", "mqtt.traffic", 'expected true or false, got "yes"'),
        ("host = 'h'\npassword = 'secret'", "mqtt.password", "expected a username"),
        ("host = 'h'\nusername = 'u'\npassword = 5", "mqtt.password", "value given is not shown"),
        ("host = 'h'\ntls = 'missing.pem'", "mqtt.tls", "a CA certificate file"),
        ("host = 'h'\ntls = 1", "mqtt.tls", "expected true, false or a CA certificate file"),
        ("host = 'h'\nkeepalive = 0", "mqtt.keepalive", "expected an integer 1..65535, got 0"),
        ("host = 'h'\nclient_id = ''", "mqtt.client_id", "expected a non-empty string"),
        ("host = 'h'\nqos = 1", "mqtt.qos", "unknown key; expected one of host, port"),
        ("host = 'h'\nprefx = 'a'", "mqtt.prefx", "did you mean 'prefix'?"),
    ],
)
def test_mqtt_config_errors_are_one_line(
    tmp_path: Path, text: str, where: str, detail: str
) -> None:
    with pytest.raises(ConfigError) as info:
        _load(tmp_path, f"[mqtt]\n{text}\n")
    message = str(info.value)
    assert "\n" not in message
    # FILE:LINE: the key's line, or, for a missing key, its table's ([mqtt], line 1)
    line = 1 if "got none" in detail else text.count("\n") + 2
    assert message.startswith(f"{tmp_path / 'omsd.toml'}:{line}: {where}: "), message
    assert detail in message
    assert "secret" not in message


def test_mqtt_must_be_a_table(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r'mqtt: expected a table, got "broker"'):
        _load(tmp_path, 'mqtt = "broker"\n')


# -- the queue ----------------------------------------------------------------------------------


def _put(box: Outbox, kind: str, name: str, board: str | None = None) -> None:
    box.put(kind, f"t/{kind}", lambda: name.encode(), 1, board=board)


def _drain(box: Outbox) -> list[str]:
    out = []
    while (message := box.pop()) is not None:
        out.append(message.payload().decode())
    return out


def test_outbox_drops_the_oldest_traffic_and_keeps_the_latest_state() -> None:
    dropped: list[Message] = []
    box = Outbox(3, dropped.append)
    _put(box, "event", "e1")
    _put(box, "traffic", "t1")
    _put(box, "state", "s1", board="xy")
    _put(box, "traffic", "t2")
    _put(box, "traffic", "t3")  # full: t1 goes
    _put(box, "state", "s2", board="xy")  # replaces s1, not counted against the limit
    _put(box, "reply", "r1")  # full: t2 goes
    assert [m.payload() for m in dropped] == [b"t1", b"t2"]
    assert box.dropped == 2 and len(box) == 4
    assert _drain(box) == ["e1", "t3", "s2", "r1"]


def test_outbox_drops_events_only_when_there_is_no_traffic_left() -> None:
    dropped: list[Message] = []
    box = Outbox(2, dropped.append)
    for name in ("e1", "e2", "e3"):
        _put(box, "event", name)
    _put(box, "state", "a", board="a")
    _put(box, "state", "b", board="b")
    assert [m.payload() for m in dropped] == [b"e1"]
    assert _drain(box) == ["e2", "e3", "a", "b"]


# -- a daemon with the bridge -------------------------------------------------------------------


def _broker_config(port: int) -> dict[str, Any]:
    return {
        "listeners": {"default": {"type": "tcp", "bind": f"127.0.0.1:{port}"}},
        "plugins": {"amqtt.plugins.authentication.AnonymousAuthPlugin": {"allow_anonymous": True}},
    }


async def start_broker(port: int) -> Broker:
    broker = Broker(_broker_config(port))
    await broker.start()
    return broker


@pytest.fixture
async def broker() -> AsyncIterator[int]:
    """An amqtt broker on a free port; yields the port."""
    port = free_port()
    instance = await start_broker(port)
    try:
        yield port
    finally:
        await instance.shutdown()


@dataclass
class Received:
    topic: str
    payload: bytes
    retain: bool

    def json(self) -> Any:
        return json.loads(self.payload)


@dataclass
class Subscriber:
    """Everything published under ``<prefix>/#``, in the order it arrived."""

    client: aiomqtt.Client
    messages: list[Received] = field(default_factory=list)
    arrived: asyncio.Event = field(default_factory=asyncio.Event)

    async def pump(self) -> None:
        async for m in self.client.messages:
            payload = m.payload if isinstance(m.payload, bytes) else str(m.payload).encode()
            self.messages.append(Received(str(m.topic), payload, m.retain))
            self.arrived.set()

    def on(self, suffix: str) -> list[Received]:
        return [m for m in self.messages if m.topic.endswith(suffix)]

    async def wait(
        self, suffix: str, check: Callable[[Any], bool] = lambda _: True, start: int = 0
    ) -> Received:
        """The first message on a topic ending in ``suffix`` (from ``start`` on) whose JSON
        passes ``check``."""
        async with asyncio.timeout(WAIT):
            i = start
            while True:
                while i < len(self.messages):
                    m = self.messages[i]
                    i += 1
                    if m.topic.endswith(suffix) and check(_decode(m.payload)):
                        return m
                self.arrived.clear()
                await self.arrived.wait()

    async def publish(self, topic: str, payload: Any = None, retain: bool = False) -> None:
        data = payload if isinstance(payload, bytes) else json.dumps(payload).encode()
        await self.client.publish(topic, data, qos=1, retain=retain)


def _decode(payload: bytes) -> Any:
    try:
        return json.loads(payload)
    except ValueError:
        return payload.decode("latin-1")


@contextlib.asynccontextmanager
async def subscribed(port: int, prefix: str = "omsd") -> AsyncIterator[Subscriber]:
    async with aiomqtt.Client("127.0.0.1", port) as client:
        await client.subscribe(f"{prefix}/#", qos=1)
        sub = Subscriber(client)
        task = asyncio.get_running_loop().create_task(sub.pump())
        try:
            yield sub
        finally:
            task.cancel()
            with contextlib.suppress(BaseException):
                await task


@dataclass
class Running:
    daemon: Daemon
    log: io.StringIO
    reader: asyncio.StreamReader
    writer: asyncio.StreamWriter

    @property
    def service(self) -> BoardService:
        return self.daemon.services[0]

    @property
    def bridge(self) -> omsd.mqtt.MqttBridge:
        assert self.daemon.mqtt is not None
        return self.daemon.mqtt

    async def control(self, op: str, **args: Any) -> Any:
        """The control API's operation, as the control socket runs it."""
        server = ControlServer({"xy": self.service}, lambda: [], TrafficLog("off"))
        return await server.run({"op": op, "board": "xy", **args})

    async def send(self, text: str) -> None:
        self.writer.write(text.encode())
        await self.writer.drain()

    async def read_until(self, marker: bytes) -> bytes:
        async with asyncio.timeout(WAIT):
            return await self.reader.readuntil(marker)

    def lines(self, text: str) -> list[str]:
        return [line for line in self.log.getvalue().splitlines() if text in line]


@contextlib.asynccontextmanager
async def running(
    port: int,
    world: dict[str, AxisWorld] | None = None,
    model: str = "PC48-4E",
    link: str = "driver",
    **mqtt: Any,
) -> AsyncIterator[Running]:
    board = BoardConfig(
        name="xy",
        model=model,
        link=link,
        tcp=(TcpEndpoint("127.0.0.1", 0),),
        world=world or {},
    )
    config = DaemonConfig(
        boards=(board,),
        control=ControlConfig(socket=None, explicit=True),
        mqtt=MqttConfig(host="127.0.0.1", port=port, **mqtt),
    )
    log = io.StringIO()
    daemon = Daemon(config, TrafficLog("plain", stream=log), out=io.StringIO())
    endpoints = await daemon.start()
    try:
        reader, writer = await asyncio.open_connection(
            "127.0.0.1", int(endpoints[0].address.rsplit(":", 1)[1])
        )
        try:
            yield Running(daemon, log, reader, writer)
        finally:
            writer.close()
    finally:
        await daemon.stop()
    # nothing went wrong on the way: no task failed, no future's exception was lost
    assert not re.findall(r"^\S+ error: .*", log.getvalue(), re.M)


async def connected(run: Running) -> None:
    async with asyncio.timeout(WAIT):
        while not run.bridge.connected:
            await asyncio.sleep(0.01)


# Seconds from a move's GO, executed on a sample tick, to its done event: PC48 §1.3's linear ramp
# at the power-up AC of 1,000,000 steps/s^2 is a trapezoid taking d/VL + VL/AC when d >= VL^2/AC,
# and the move is done on the first 2048/s sample tick at or after that (docs/decisions.md).
MOVE_TIMES = {
    # 900/900 + 900/1e6 = 1.0009 s = 2049.84 ticks -> tick 2050
    "AX VL900 MR900 GO ID ": 2050 / 2048,
    # 2000/5000 + 5000/1e6 = 0.405 s = 829.44 ticks -> tick 830
    "AX VL5000 MR2000 GO ID ": 830 / 2048,
    # 4000/2000 + 2000/1e6 = 2.002 s = 4100.10 ticks -> tick 4101
    "AX VL2000 MR4000 GO ID ": 4101 / 2048,
}


def move_time(command: str) -> float:
    """Seconds from ``command`` to its done event (``MOVE_TIMES``)."""
    return MOVE_TIMES[command]


async def start_move(run: Running, command: str) -> tuple[float, float]:
    """Send ``command`` (ending in ``WY``, whose answer says the board has it) and return the
    board-time window in which it arrived."""
    before = run.service.clock()
    await run.send(command)
    await run.read_until(b"\n")  # the WY answer, LF-terminated by the driver
    return before, run.service.clock()


# -- what the bridge publishes ------------------------------------------------------------------


async def test_status_is_online_retained_and_offline_after_a_clean_stop(broker: int) -> None:
    async with running(broker) as run:
        await connected(run)
        async with subscribed(broker) as late:  # a subscriber that comes later: retained
            status = await late.wait("omsd/status")
            assert (status.payload, status.retain) == (b"online", True)
            assert run.lines("mqtt: connected to the broker at 127.0.0.1:")
    async with subscribed(broker) as after:
        status = await after.wait("omsd/status")
        assert (status.payload, status.retain) == (b"offline", True)


async def test_retained_state_matches_the_control_state(broker: int) -> None:
    async with running(broker) as run, subscribed(broker) as sub:
        await start_move(run, "AX VL5000 MR2000 GO ID WY ")
        idle = await run.control("wait", until="idle", timeout=WAIT)
        control = await run.control("state")
        assert control["axes"] == idle["axes"]
        keys = ("model", "mode", "status", "done_register", "control", "io_low", "input_buffer")

        def board(state: dict[str, Any]) -> bool:
            """The board as the control API shows it."""
            return state["axes"] == control["axes"] and all(state[k] == control[k] for k in keys)

        await sub.wait("xy/state", board)
        # a subscriber coming now gets it retained
        async with subscribed(broker) as late:
            retained = await late.wait("omsd/xy/state")
        state = retained.json()
        assert retained.retain and board(state)
        x = state["axes"]["X"]
        assert (x["position"], x["velocity"], x["moving"], x["done"]) == (2000, 0, False, True)
        assert state["board"] == "xy"


async def test_state_rate_is_bounded_while_moving_and_published_once_when_stopped(
    broker: int,
) -> None:
    async with running(broker, state_rate=5) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        start = len(sub.messages)
        await start_move(run, "AX VL900 MR900 GO ID WY ")  # short of the home switch
        done = await sub.wait("xy/event", lambda e: e["kind"] == "done", start)
        stopped = await sub.wait("xy/state", lambda s: not s["axes"]["X"]["moving"], start)
        # a change nobody sees (WY) publishes nothing; a visible one (the home switch) does
        await run.send("WY ")
        await run.read_until(b"\n")
        await run.control("home", axis="X", active=True)
        home = await sub.wait("xy/state", lambda s: s["axes"]["X"]["home"], start)
        states = [m.json() for m in sub.messages[start:] if m.topic == "omsd/xy/state"]
        moving = [s for s in states if s["axes"]["X"]["moving"]]
        duration = move_time("AX VL900 MR900 GO ID ")
        # at most 5 a second (board time = loop time here: nobody scaled it), and at least
        # one while it moved
        assert 2 <= len(moving) <= duration * 5 + 2
        times = [s["time"] for s in states]
        assert all(b - a >= 0.2 - 0.002 for a, b in itertools.pairwise(times))
        positions = [s["axes"]["X"]["position"] for s in moving]
        assert positions == sorted(positions) and 0 < positions[-1] < 900
        # once when it stopped, then nothing until the home switch closed
        assert states[len(moving) :] == [stopped.json(), home.json()]
        assert stopped.json()["axes"]["X"]["position"] == 900
        assert stopped.json()["time"] >= done.json()["time"]


async def test_events_arrive_in_order_with_their_board_times(broker: int) -> None:
    world = {"X": AxisWorld(positive_limit=300)}
    async with running(broker, world=world) as run, subscribed(broker) as sub:
        await connected(run)
        await run.send("AX VL5000 MR100 GO ID ")
        await run.read_until(b"!")
        await run.send("XX ")  # not a command
        await run.read_until(b"#")
        await run.send("AX MR1000 GO ")  # runs into the limit switch at 300
        await run.read_until(b"@")
        await run.send("AY ES5 IS ")  # Y: slip detection on (PC48 §6.16)
        await run.send("WY ")
        await run.read_until(b"\n")
        await sub.publish("omsd/xy/cmd/slip", {"axis": "Y", "steps": 8})
        await run.read_until(b"$")
        await sub.wait("xy/event", lambda e: e["kind"] == "slip")
        events = [m.json() for m in sub.on("xy/event")]
        assert [e["kind"] for e in events] == ["done", "command_error", "limit", "slip"]
        assert [e["seq"] for e in events] == [1, 2, 3, 4]
        times = [e["time"] for e in events]
        assert times == sorted(times)
        done, error, limit, slip = events
        assert (done["axes"], done["done_register"], done["text"]) == (
            ["X"],
            1,
            "done (register 01)",
        )
        assert (error["error"], error["command"]) == ("Unrecognized command", "XX")
        assert (limit["axis"], limit["direction"], limit["text"]) == ("X", 1, "limit X+")
        assert slip["axis"] == "Y"
        # the README's examples show what is published, key for key
        published = {e["kind"]: set(e) for e in events}
        published["traffic"] = set(sub.on("xy/traffic")[0].json())
        examples = readme_examples()
        assert {e["kind"] for e in examples} == {"done", "command_error", "limit", "traffic"}
        for example in examples:
            assert set(example) == published[example["kind"]], example
        state = await run.control("state")
        assert state["axes"]["X"]["limit_positive"] and not state["axes"]["X"]["moving"]


def readme_examples() -> list[dict[str, Any]]:
    """The JSON lines of the README section "MQTT"."""
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## MQTT\n", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```json\n(.*?)```", section, re.S)
    return [json.loads(line) for block in blocks for line in block.splitlines() if line.strip()]


def test_the_readme_names_every_operation() -> None:
    text = (ROOT / "README.md").read_text()
    section = text.split("\n## MQTT\n", 1)[1].split("\n## ", 1)[0]
    assert [op for op in OPS if f"`{op}`" not in section] == []


async def test_a_bad_ca_file_is_a_startup_error(tmp_path: Path) -> None:
    ca = tmp_path / "ca.pem"
    ca.write_text("-----BEGIN CERTIFICATE-----\nnot one\n-----END CERTIFICATE-----\n")
    board = BoardConfig(name="xy", tcp=(TcpEndpoint("127.0.0.1", 0),))
    config = DaemonConfig(
        boards=(board,),
        control=ControlConfig(socket=None, explicit=True),
        mqtt=MqttConfig(host="127.0.0.1", port=free_port(), tls=ca),
    )
    daemon = Daemon(config, TrafficLog("off"), out=io.StringIO())
    with pytest.raises(StartupError) as info:
        await daemon.start()
    assert str(info.value).startswith(f"mqtt: cannot set up TLS with {ca}: ")
    assert daemon.mqtt is None and not daemon.services  # cleaned up


async def test_a_command_topic_closes_a_limit_and_the_driver_emits_at(broker: int) -> None:
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await start_move(run, "AX VL5000 MR100000 GO WY ")
        await sub.wait("xy/state", lambda s: s["axes"]["X"]["moving"])
        start = len(sub.messages)
        await sub.publish(
            "omsd/xy/cmd/limit", {"id": "lim-1", "axis": "X", "direction": 1, "active": True}
        )
        assert await run.read_until(b"@\n") == b"@\n"  # "@" and the driver's end character
        reply = (await sub.wait("xy/reply/limit")).json()
        assert reply["id"] == "lim-1" and reply["ok"] is True
        assert reply["result"]["axes"]["X"]["limit_positive"] is True
        event = (await sub.wait("xy/event", lambda e: e["kind"] == "limit")).json()
        assert (event["axis"], event["direction"]) == ("X", 1)
        state = await sub.wait("xy/state", lambda s: not s["axes"]["X"]["moving"], start)
        x = state.json()["axes"]["X"]
        assert x["limit_positive"] and 0 < x["position"] < 100000
        assert x == (await run.control("state"))["axes"]["X"]


async def test_command_errors_come_back_on_the_reply_topic(broker: int) -> None:
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        await sub.publish("omsd/xy/cmd/limit", b"{not json")
        await sub.publish("omsd/xy/cmd/limit", [1, 2])
        await sub.publish("omsd/xy/cmd/nope", {"id": 2})
        await sub.publish("omsd/zz/cmd/state", {"id": 3})
        await sub.publish("omsd/xy/cmd/limit", {"id": 4, "axis": "Q", "direction": 1})
        await sub.publish("omsd/xy/cmd/home", {"id": 5, "axis": "X", "active": "yes"})
        await sub.publish("omsd/xy/cmd/state", {"id": 6, "board": "zz", "op": "reset"})
        await sub.wait("xy/reply/state")
        replies = [(m.topic, m.json()) for m in sub.messages if "/reply" in m.topic]
        assert [(t, r["id"], r["ok"]) for t, r in replies] == [
            ("omsd/xy/reply/limit", None, False),
            ("omsd/xy/reply/limit", None, False),
            ("omsd/xy/reply/nope", 2, False),
            ("omsd/status/reply", 3, False),  # no board zz: the daemon's topic (issue 13)
            ("omsd/xy/reply/limit", 4, False),
            ("omsd/xy/reply/home", 5, False),
            ("omsd/xy/reply/state", 6, True),  # the topic's board and op win
        ]
        errors = [r.get("error", "") for _, r in replies]
        assert errors[0].startswith("payload: not a JSON object")
        assert errors[1] == "payload: expected a JSON object of the operation's arguments"
        assert errors[2].startswith("unknown op 'nope'")
        assert errors[3] == "no board 'zz'; boards: xy"
        assert errors[4] == "xy has no axis 'Q'; axes: XYZT"
        assert errors[5] == "active: expected true, false or null, got 'yes'"
        assert all("\n" not in e for e in errors)
        assert replies[6][1]["result"]["board"] == "xy"


async def test_a_payload_nested_too_deeply_is_answered(broker: int) -> None:
    """Thousands of nested [ ran json's recursion out of stack: the command's task died on a
    RecursionError, and no reply came."""
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        await sub.publish("omsd/xy/cmd/limit", b"[" * 30000)
        reply = (await sub.wait("xy/reply/limit")).json()
        assert reply == {
            "id": None,
            "ok": False,
            "error": "payload: not a JSON object: nested too deeply",
        }


async def test_a_payload_that_is_not_json_is_refused_before_it_runs(broker: int) -> None:
    """NaN and 1e999 (which Python's json reads) closed the limit, then the reply, echoing the
    id, could not be written: it said ``ok: false``, ``bad request: Out of range float values
    are not JSON compliant``, of a command that had run. A payload of 100 MB was read as JSON
    while the boards waited (1.7 s), and its id came back in the reply. Both are now refused
    as the control socket refuses them, before anything runs."""
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        close = b'"axis": "X", "direction": 1, "active": true}'
        await sub.publish("omsd/xy/cmd/limit", b'{"id": NaN, ' + close)
        await sub.publish("omsd/xy/cmd/limit", b'{"id": 1e999, ' + close)
        huge = b'{"id": "' + b"a" * 70000 + b'", ' + close
        await sub.publish("omsd/xy/cmd/limit", huge)
        await sub.publish("omsd/xy/cmd/state", {"id": 4})
        await sub.wait("xy/reply/state")
        replies = [m.json() for m in sub.on("xy/reply/limit")]
        assert replies == [
            {"id": None, "ok": False, "error": "payload: not a JSON object: NaN is not JSON"},
            {
                "id": None,
                "ok": False,
                "error": "payload: not a JSON object: 1e999 is beyond a float's range",
            },
            {"id": None, "ok": False, "error": f"payload: {len(huge)} bytes, more than 65536"},
        ]
        assert (await run.control("state"))["axes"]["X"]["limit_positive"] is False


async def test_an_op_too_long_for_a_reply_topic_is_answered_on_the_status_reply_topic(
    broker: int,
) -> None:
    """A command topic of 65,535 bytes, MQTT's longest (3.1.1 §1.5.3), made a reply topic two
    bytes longer (reply, cmd): no reply came, and the log said 'error: Task exception was
    never retrieved: ValueError('Publish topic is too long.')'."""
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        op = "o" * (65535 - len("omsd/xy/cmd/"))
        await sub.publish(f"omsd/xy/cmd/{op}", {"id": 1})
        reply = (await sub.wait("omsd/status/reply")).json()
        assert reply == {
            "id": 1,
            "ok": False,
            "error": f"unknown op of {len(op)} characters",
            "board": "xy",
            "op": op,
        }


async def test_a_retained_command_is_ignored(broker: int) -> None:
    async with subscribed(broker) as sub:  # left on the broker before the daemon starts
        await sub.publish(
            "omsd/xy/cmd/limit", {"axis": "X", "direction": 1, "active": True}, retain=True
        )
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.publish("omsd/xy/cmd/state", {"id": 1})
        reply = (await sub.wait("xy/reply/state")).json()
        assert reply["result"]["axes"]["X"]["limit_positive"] is False
        assert not sub.on("xy/reply/limit")
        assert len(run.lines("mqtt: ignored a retained command on omsd/xy/cmd/limit")) == 1


async def test_a_wait_does_not_hold_up_other_commands(broker: int) -> None:
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await start_move(run, "AX VL5000 MR2000 GO ID WY ")
        await sub.publish("omsd/xy/cmd/wait", {"id": "w", "until": "done", "axis": "X"})
        await sub.publish("omsd/xy/cmd/state", {"id": "s"})
        await sub.wait("xy/reply/wait")
        replies = [m.json() for m in sub.messages if "/reply/" in m.topic]
        assert [r["id"] for r in replies] == ["s", "w"]
        assert replies[0]["result"]["axes"]["X"]["moving"] is True
        assert replies[1]["result"]["axes"]["X"]["position"] == 2000


async def test_traffic_flows_as_the_log_writes_it(broker: int) -> None:
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await run.send("WY\r")
        answer = await run.read_until(b"\n")
        await sub.wait("xy/traffic", lambda t: t["dir"] == "out")
        records = [m.json() for m in sub.on("xy/traffic")]
        chunks = [Traffic.from_record(r) for r in records]
        assert [(c.direction, c.data) for c in chunks] == [
            (Direction.IN, b"WY\r"),
            (Direction.OUT, answer),
        ]
        assert [r["seq"] for r in records] == [1, 2]
        assert all(c.board == "xy" and c.endpoint.startswith("tcp:127.0.0.1:") for c in chunks)


async def test_traffic_can_be_turned_off(broker: int) -> None:
    async with running(broker, traffic=False) as run, subscribed(broker) as sub:
        await connected(run)
        await run.send("XX ")  # a command error: an event published after the traffic
        await run.read_until(b"#")
        await sub.wait("xy/event")
        assert not sub.on("xy/traffic")


async def test_a_prefix_with_levels(broker: int) -> None:
    async with (
        running(broker, prefix="lab/omsd") as run,
        subscribed(broker, "lab/omsd") as sub,
    ):
        await connected(run)
        await sub.publish("lab/omsd/xy/cmd/boards", {})
        reply = (await sub.wait("lab/omsd/xy/reply/boards")).json()
        assert [b["name"] for b in reply["result"]] == ["xy"]
        assert (await sub.wait("lab/omsd/status")).payload == b"online"


# -- a broker that is away ----------------------------------------------------------------------


@pytest.fixture
def quick(monkeypatch: pytest.MonkeyPatch) -> None:
    """Retry every few milliseconds and queue little, so a short test sees many attempts and an
    overflowing queue."""
    monkeypatch.setattr(omsd.mqtt, "BACKOFF_MIN", 0.02)
    monkeypatch.setattr(omsd.mqtt, "BACKOFF_MAX", 0.05)
    monkeypatch.setattr(omsd.mqtt, "QUEUE_LIMIT", 20)


@pytest.mark.usefixtures("quick")
async def test_an_absent_broker_never_slows_the_board_and_is_logged_once() -> None:
    port = free_port()  # nobody listens here (yet)
    async with running(port) as run:
        window = await start_move(run, "AX VL5000 MR2000 GO ID WY ")
        for _ in range(30):  # 60 chunks of traffic for a queue of 20
            await run.send("RP ")
            assert await run.read_until(b"\n")
        done = await run.control("wait", until="done", axis="X", timeout=WAIT)
        assert done["axes"]["X"]["position"] == 2000
        assert await run.read_until(b"!") == b"!"  # the driver's done marker, on time
        bridge = run.bridge
        assert bridge.attempts >= 3 and not bridge.connected
        assert len(bridge.outbox) <= 20 and bridge.outbox.dropped >= 40
        assert len(run.lines("mqtt: cannot reach the broker at 127.0.0.1:")) == 1
        assert len(run.lines("dropping the oldest traffic messages")) == 1
        # the done event is still queued, with its exact board time
        (event,) = [json.loads(m.payload()) for m in bridge.outbox.ordered]
        expected = move_time("AX VL5000 MR2000 GO ID ")
        assert window[0] + expected - SAMPLE <= event["time"] <= window[1] + expected + SAMPLE

        # the broker comes: the queue goes out, the state is published, the log says so once
        instance = await start_broker(port)
        try:
            async with subscribed(port) as sub:
                await connected(run)
                state = await sub.wait("xy/state")
                assert state.json()["axes"]["X"]["position"] == 2000
                assert len(run.lines("mqtt: connected to the broker at 127.0.0.1:")) == 1
                line = run.lines("mqtt: connected")[0]
                assert f"{bridge.outbox.dropped} messages were dropped meanwhile" in line
        finally:
            await instance.shutdown()


@pytest.mark.usefixtures("quick")
async def test_a_broker_that_goes_away_mid_move_loses_nothing_and_comes_back() -> None:
    port = free_port()
    first: Broker | None = await start_broker(port)
    try:
        async with running(port) as run:
            await connected(run)
            command = "AX VL2000 MR4000 GO ID "  # two seconds
            window = await start_move(run, command + "WY ")
            assert first is not None
            await first.shutdown()
            first = None
            async with asyncio.timeout(WAIT):
                while not run.lines("mqtt: lost the broker at"):
                    await asyncio.sleep(0.01)
                attempts = run.bridge.attempts
                while run.bridge.attempts < attempts + 3:  # it tries, and says nothing more
                    await asyncio.sleep(0.01)
            second = await start_broker(port)
            try:
                async with subscribed(port) as sub:
                    # a fresh broker holds nothing: a state it has was published again
                    state = await sub.wait("xy/state")
                    assert state.json()["axes"]["X"]["moving"] is True
                    assert (await sub.wait("omsd/status")).payload == b"online"
                    done = (await sub.wait("xy/event", lambda e: e["kind"] == "done")).json()
                    stopped = await sub.wait("xy/state", lambda s: not s["axes"]["X"]["moving"])
                assert stopped.json()["axes"]["X"]["position"] == 4000
                expected = move_time(command)
                assert window[0] + expected - SAMPLE <= done["time"]
                assert done["time"] <= window[1] + expected + SAMPLE
                assert await run.read_until(b"\n") == b"!\x01\n"  # the driver's done marker
                await run.send("RP ")
                assert await run.read_until(b"\n") == b"4000\n"
                assert len(run.lines("mqtt: lost the broker at")) == 1
                assert len(run.lines("mqtt: the broker at 127.0.0.1:")) == 1  # "... is back"
                assert run.lines("is back") and not run.lines("cannot reach")
            finally:
                await second.shutdown()
    finally:
        if first is not None:
            await first.shutdown()


# -- issue 12: a limit after homing is seen everywhere ------------------------------------------

LIMITED = AxisWorld(negative_limit=-30000, positive_limit=30000, home_low=1000, home_high=1100)


def _status_reply(model: str, link: str, status: str) -> bytes:
    """RA/QA as each link shows it: the driver's text and end character; on the raw link the
    PC48's ``<LF><CR><CR>…<LF><CR><CR>`` (§6.13), the PCIx's ``text<LF><CR>``."""
    if link == "driver":
        return status.encode() + b"\n"
    if model.startswith("PCIX"):
        return status.encode() + b"\n\r"
    return b"\n\r\r" + status.encode() + b"\n\r\r"


@pytest.mark.parametrize("link", ["driver", "raw"])
@pytest.mark.parametrize("model", ["PC48-4E", "PCIX-040"])
async def test_a_homed_axis_run_into_each_limit_reads_it_everywhere(
    broker: int, model: str, link: str
) -> None:
    """Issue 12, done when: "A PCIx and a PC48 axis homed, then run into each limit, read the
    limit in every query, over both links, through the control API and in MQTT state." The
    issue's world (limits at +-30000, home 1000..1100) and commands: ``AX VL7000 AC50000 HM0``
    finds home between two steps (the counter and the carriage 0.234 step apart), then JG5000
    runs into the +30000 switch (before the fix: stopped at 28999 and read ``PNNN``) and JG-5000
    into the -30000 one. The board's time is paused and stepped (control API), so every move
    starts on the same sample ticks as on a manual clock."""
    pcix = model.startswith("PCIX")
    sep = ";" if pcix else " "

    async def ask(command: str, expected: bytes) -> None:
        await run.send(command + sep)
        got = b""
        while len(got) < len(expected):
            got += await run.read_until(expected[-1:])
        assert got == expected, (command, got)

    wy = get_model(model).who_are_you()
    if link == "driver":
        answer = wy.encode() + b"\n"
    else:
        answer = wy.encode() + b"\n\r" if pcix else b"\n\r" + wy.encode() + b"\n\r"

    async def run_for(seconds: float, *commands: str) -> None:
        """Send, know the board has it (WY's answer comes after it), let board time pass."""
        await ask(sep.join([*commands, "WY"]), answer)
        await run.control("time", action="step", seconds=seconds)

    async with running(broker, {"X": LIMITED}, model=model, link=link) as run:
        await connected(run)
        await run.control("time", action="pause")
        async with subscribed(broker) as sub:
            await run_for(2.0, "AX", "VL7000", "AC50000", "HM0")
            for direction, letter, key in ((1, "P", "limit_positive"), (-1, "M", "limit_negative")):
                await run_for(15.0, f"JG{direction * 5000}")
                if link == "driver":  # the limit interrupt's marker (§7.3.3)
                    assert await run.read_until(b"\n") == b"@\n"
                status = f"{letter}NLN"
                for query in ("RA", "QA"):
                    await ask(query, _status_reply(model, link, status))
                if pcix:
                    # QL: the limit input at its LL (active low) level, 0; the others high
                    bit = 0 if direction < 0 else 8
                    word = 0xFFFF & ~(1 << bit) & ~0xF0F0  # four axes: bits 0-3 and 8-11
                    ql = f"{word:04x}".encode()
                    await ask("QL", ql + (b"\n" if link == "driver" else b"\n\r"))
                control = await run.control("state")
                assert control["axes"]["X"][key] is True
                assert control["axes"]["X"]["moving"] is False
                published = await sub.wait(
                    "xy/state", lambda s, key=key: s["axes"]["X"][key] is True
                )
                assert published.json()["axes"]["X"]["moving"] is False


# -- issue 13: a command for a board that does not exist ----------------------------------------


async def test_a_command_for_an_unknown_board_is_answered_on_the_status_reply_topic(
    broker: int,
) -> None:
    """Issue 13: "MQTT requests for a board that does not exist are answered on the daemon's
    status topic, not on a topic built from the unknown name". Nothing is run (not even an op
    that needs no board) and nothing is published under the unknown name."""
    async with running(broker) as run, subscribed(broker) as sub:
        await connected(run)
        await sub.wait("xy/state")
        await sub.publish("omsd/zz/cmd/state", {"id": 3})
        await sub.publish("omsd/zz/cmd/boards", {"id": "b"})
        await sub.publish("omsd/status/cmd/reset", b"{not json")
        await sub.publish("omsd/xy/cmd/state", {"id": 4})  # a known board: its own topic
        await sub.wait("xy/reply/state")
        replies = [(m.topic, m.json(), m.retain) for m in sub.messages if "reply" in m.topic]
        assert replies == [
            (
                "omsd/status/reply",
                {
                    "id": 3,
                    "ok": False,
                    "error": "no board 'zz'; boards: xy",
                    "board": "zz",
                    "op": "state",
                },
                False,
            ),
            (
                "omsd/status/reply",
                {
                    "id": "b",
                    "ok": False,
                    "error": "no board 'zz'; boards: xy",
                    "board": "zz",
                    "op": "boards",
                },
                False,
            ),
            (
                "omsd/status/reply",
                {
                    "id": None,
                    "ok": False,
                    "error": "no board 'status'; boards: xy",
                    "board": "status",
                    "op": "reset",
                },
                False,
            ),
            ("omsd/xy/reply/state", replies[3][1], False),
        ]
        assert replies[3][1]["id"] == 4 and replies[3][1]["ok"] is True
        published = {m.topic for m in sub.messages} - {"omsd/zz/cmd/state", "omsd/zz/cmd/boards"}
        assert not {t for t in published if t.startswith("omsd/zz/")}
        assert not {t for t in published if t.startswith("omsd/status/") and "/cmd/" not in t} - {
            "omsd/status/reply"
        }
        # the retained status is still the daemon's own
        async with subscribed(broker) as late:
            status = await late.wait("omsd/status")
            assert (status.payload, status.retain) == (b"online", True)
