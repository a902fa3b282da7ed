"""The I/O side's fast paths against the straightforward ones (issue 16), on random command
streams: the same bytes to every client and the same log lines, whichever path ran.

The fast paths, each a named place in the code:

* the raw link's one reply as it is (``RawLink.to_host``, against ``RawLink.output``);
* the driver link's bytes with nothing for the driver to do going straight to the board
  (``DriverLink._straight_through``, against ``DriverLink.through_buffer``) and its framed
  replies with no event among them (``DriverLink._collect``, against ``DriverLink.collect_all``);
* the service's whole cable (``BoardService._clean``: ``client.send`` instead of ``_deliver``)
  and its held log (the file's lines written per turn before the replies, the view's after
  them, against a log written at once);
* the TCP endpoint's reused buffer (``TcpClient.buffer_updated``, a BufferedProtocol, against
  ``data_received``, the Protocol's way) with its flow control;
* the pty endpoint's read into the shared buffer and its write without a backlog (against
  ``_take`` + ``_push`` and the backlog).

Time is a manual clock (the boards' timebases are paused and stepped), so both sides see the
same instants and any difference is the paths'.
"""

from __future__ import annotations

import asyncio
import fcntl
import io
import json
import os
import pathlib
import random
import re
import select
import struct
import termios
import time
import tty
from collections.abc import Iterator
from typing import Any

import pytest

from omsd.board import Board
from omsd.config import BoardConfig, load_config
from omsd.link import DriverLink, Link, LinkOutput, RawLink
from omsd.models import get_model
from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog
from omsd.timebase import Timebase
from omsd.transport.pty import PtyEndpoint
from omsd.transport.tcp import TcpClient

# -- the straightforward paths ------------------------------------------------------------------


class StraightRaw(RawLink):
    """The raw link without its fast path: every output item by item."""

    def to_host(self, now: float) -> LinkOutput:
        self.board.advance(now)
        out, sources = self.board.take_output_sourced()
        return self.output(out, sources)


class StraightDriver(DriverLink):
    """The driver link without its fast paths: every byte by the buffer, every output item by
    item."""

    def from_host(self, data: bytes, now: float, session: int = 0) -> int:
        return self.through_buffer(data, now, session)

    def _collect(self, now: float) -> bool:
        out, sources = self.board.take_output_sourced()
        return self.collect_all(out, sources, now)


class AtOnceLog(TrafficLog):
    """The log as it was: each line written when it is logged, never held."""

    def hold(self) -> None:
        pass

    def release(self) -> None:
        pass


# -- random command streams ---------------------------------------------------------------------

WORDS = [
    b"RP", b"QA", b"RE", b"WY", b"RS", b"AX", b"AY", b"AZ", b"AA", b"GO", b"ID", b"ST", b"KL",
    b"EN", b"EF", b"CA", b"SA", b"RA", b"QI", b"MA0", b"MR100", b"MR-250", b"MR3000", b"VL5000",
    b"VL200000", b"AC20000", b"AC400000", b"WT50", b"JG800", b"LP0", b"XQ", b"MR", b"VL-5",
    b"AX MR40 GO ID", b"AY MR-70 GO ID", b"! ", b"@ ", b"*a comment\r", b"\x04", b"\x19", b"!",
]  # fmt: skip
SEPARATORS = [b" ", b";", b"\r", b"\n", b"", b"\r\n"]


def stream(rnd: random.Random, n: int) -> bytes:
    out = bytearray()
    for _ in range(n):
        if rnd.random() < 0.03:
            out += bytes(rnd.randrange(256) for _ in range(rnd.randrange(1, 4)))
        else:
            out += rnd.choice(WORDS) + rnd.choice(SEPARATORS)
    return bytes(out)


def chunks(rnd: random.Random, data: bytes) -> Iterator[bytes]:
    """``data`` cut where a client's writes might cut it."""
    i = 0
    while i < len(data):
        n = rnd.choice([1, 2, 3, 5, 8, 20, 64, 300])
        yield data[i : i + n]
        i += n


CONFIG_TEXT = """\
[[board]]
name = "b1"
model = "{model}"
link = "{link}"
tcp = "127.0.0.1:0"
"""


def config(tmp_path: pathlib.Path, link: str, model: str = "PC48-4E") -> BoardConfig:
    path = tmp_path / f"{link}-{model}.toml"
    path.write_text(CONFIG_TEXT.format(link=link, model=model))
    return load_config(path).boards[0]


def manual_service(
    cfg: BoardConfig,
    log: TrafficLog,
    link_class: type[RawLink] | type[DriverLink] | None = None,
    *,
    straight: bool = False,
) -> BoardService:
    """A board service on a manual clock (paused at 0; :func:`step` moves it). ``straight``: the
    service's own fast path off (the faulty cable's way, with no fault on it)."""
    service = BoardService(cfg, asyncio.get_running_loop(), log)
    clock = [0.0]
    service.timebase = Timebase(lambda: clock[0])
    service.timebase.pause()
    service.clock = service.timebase.now
    service.board = Board(service.model, now=0.0, world=dict(cfg.world))
    link: Link
    if link_class is None:
        link_class = DriverLink if cfg.link == "driver" else RawLink
    if issubclass(link_class, DriverLink):
        link = link_class(service.board, eos=cfg.eos, buffer_size=cfg.buffer_size)
    else:
        link = link_class(service.board)
    service.link = link
    if straight:
        service._clean = False
    return service


def step(service: BoardService, seconds: float) -> None:
    service.timebase.step(seconds)
    service.service()  # what the wake-up at a deadline does


class Client:
    """A client of a service: keeps what the link did not take, as the endpoints do."""

    def __init__(self, service: BoardService, label: str) -> None:
        self.service = service
        self.label = label
        self.session = 0
        self.got = bytearray()
        self.pending = bytearray()
        service.attach(self)

    def send(self, data: bytes) -> None:
        self.got += data

    def write(self, data: bytes) -> None:
        self.pending += data
        self.input_room()

    def input_room(self) -> None:
        if self.pending:
            taken = self.service.feed(self, bytes(self.pending))
            del self.pending[:taken]


def log_lines(out: io.StringIO, path: pathlib.Path) -> tuple[list[str], list[dict[str, Any]]]:
    """The view's lines without their time of day, and the file's records without theirs (and
    without the TCP connections' serial numbers, which count every connection of the test)."""
    view = [SERIAL.sub("#N", line[13:]) for line in out.getvalue().splitlines()]
    records = [json.loads(SERIAL.sub("#N", line)) for line in path.read_text().splitlines()]
    for record in records:
        record.pop("t")
    return view, records


SERIAL = re.compile(r"#\d+(?= \()")


def unchunked(out: io.StringIO, path: pathlib.Path) -> tuple[list[str], list[object]]:
    """:func:`log_lines` as far as it does not depend on how the terminal cut the host's bytes
    into reads: the view's event and message lines, the file's other records in order, and
    each endpoint's bytes in and out, whole."""
    view, records = log_lines(out, path)
    others: list[object] = []
    streams: dict[tuple[str, str], str] = {}
    for record in records:
        if record.get("kind") == "traffic":
            key = (record["endpoint"], record["dir"])
            streams[key] = streams.get(key, "") + record["data"]
        else:
            others.append(record)
    others.append(sorted(streams.items()))
    return [line for line in view if " <- " not in line and " -> " not in line], others


async def settle() -> None:
    for _ in range(3):
        await asyncio.sleep(0)


# -- the links ----------------------------------------------------------------------------------


@pytest.mark.parametrize("link", ["raw", "driver"])
@pytest.mark.parametrize("seed", range(6))
def test_links_fast_and_straight_give_the_same_output(link: str, seed: int) -> None:
    rnd = random.Random(seed)
    model = get_model("PC48-4E")
    fast_board, straight_board = Board(model, now=0.0), Board(model, now=0.0)
    fast: Link = DriverLink(fast_board) if link == "driver" else RawLink(fast_board)
    straight: Link = (
        StraightDriver(straight_board) if link == "driver" else StraightRaw(straight_board)
    )
    t = 0.0
    said = 0
    for _ in range(400):
        session = rnd.choice([1, 2])  # two clients taking turns
        data = stream(rnd, rnd.randrange(1, 4))
        assert fast.from_host(data, t, session) == straight.from_host(data, t, session)
        out_a, out_b = fast.to_host(t), straight.to_host(t)
        assert (out_a.pieces, out_a.events) == (out_b.pieces, out_b.events)
        said += len(out_a.data)
        assert fast.held() == straight.held()
        assert fast.take_notes() == straight.take_notes()
        if rnd.random() < 0.05:
            assert fast.drop_input(session) == straight.drop_input(session)
        t += rnd.choice([0.0, 0.0005, 0.01, 0.1, 0.7])
        deadline = fast.next_deadline()
        assert deadline == straight.next_deadline()
        if deadline is not None and rnd.random() < 0.5:
            t = max(t, deadline)
    assert said


# -- the service and its log --------------------------------------------------------------------


@pytest.mark.parametrize("link", ["raw", "driver"])
@pytest.mark.parametrize("seed", range(5))
async def test_service_fast_and_straight_give_the_same_bytes_and_log(
    tmp_path: pathlib.Path, link: str, seed: int
) -> None:
    cfg = config(tmp_path, link)
    logs = []
    services = []
    for name, log_class, link_class, straight in (
        ("fast", TrafficLog, None, False),
        ("straight", AtOnceLog, StraightDriver if link == "driver" else StraightRaw, True),
    ):
        out = io.StringIO()
        log = log_class("plain", file=tmp_path / f"{name}.jsonl", stream=out, env={})
        logs.append((log, out, tmp_path / f"{name}.jsonl"))
        services.append(manual_service(cfg, log, link_class, straight=straight))
    clients = [[Client(s, f"c{i}") for i in range(2)] for s in services]
    rnd = random.Random(seed)
    for _ in range(60):
        who = rnd.randrange(2)
        for piece in chunks(rnd, stream(rnd, rnd.randrange(1, 6))):
            for side in clients:
                side[who].write(piece)
            await settle()  # the services' call_soon(input_room)
        if rnd.random() < 0.05:  # a client goes and comes back (a new session)
            for service, side in zip(services, clients, strict=True):
                service.end_session(side[who], len(side[who].pending), "gone")
                side[who].pending.clear()
                service.open_session(side[who])
        dt = rnd.choice([0.0, 0.001, 0.02, 0.3, 1.5])
        for service in services:
            step(service, dt)
        await settle()
    for a, b in zip(*clients, strict=True):
        assert a.got == b.got
        assert a.pending == b.pending
    for log, _, _ in logs:
        log.close()
    assert log_lines(*logs[0][1:]) == log_lines(*logs[1][1:])
    assert clients[0][0].got  # something was said
    for service in services:
        service.close()


# -- the TCP endpoint ---------------------------------------------------------------------------


class FakeTransport:
    """What a TCP client's protocol sees of asyncio's transport: what it wrote, and when it was
    paused and resumed."""

    def __init__(self) -> None:
        self.written = bytearray()
        self.calls: list[str] = []

    def write(self, data: bytes) -> None:
        self.written += data

    def is_closing(self) -> bool:
        return False

    def get_write_buffer_size(self) -> int:
        return 0

    def pause_reading(self) -> None:
        self.calls.append("pause")

    def resume_reading(self) -> None:
        self.calls.append("resume")

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        return ("127.0.0.1", 40000) if name == "peername" else default

    def close(self) -> None:
        self.calls.append("close")


@pytest.mark.parametrize("link", ["raw", "driver"])
@pytest.mark.parametrize("seed", range(4))
async def test_tcp_buffered_and_protocol_paths_give_the_same_bytes_and_log(
    tmp_path: pathlib.Path, link: str, seed: int
) -> None:
    """The same chunks through ``buffer_updated`` (asyncio's BufferedProtocol path, the shared
    buffer) and through ``data_received`` (the Protocol's), including the board's input buffer
    filling up (flow control: pause_reading until there is room)."""
    cfg = config(tmp_path, link)
    sides = []
    for name in ("buffered", "protocol"):
        out = io.StringIO()
        log = TrafficLog("plain", file=tmp_path / f"{name}.jsonl", stream=out, env={})
        service = manual_service(cfg, log)
        client = TcpClient(service, "tcp:127.0.0.1:7048", "takeover")
        transport = FakeTransport()
        client.connection_made(transport)  # type: ignore[arg-type]
        sides.append((client, transport, log, out, tmp_path / f"{name}.jsonl", service))
    rnd = random.Random(seed)
    buffered, protocol = sides[0][0], sides[1][0]
    unread = [bytearray(), bytearray()]  # what each socket holds while its reading is paused

    def deliver() -> None:
        if unread[0] and not buffered._paused:
            buffer = buffered.get_buffer(-1)
            n = min(len(unread[0]), len(buffer))
            buffer[:n] = unread[0][:n]
            del unread[0][:n]
            buffered.buffer_updated(n)
        if unread[1] and not protocol._paused:
            protocol.data_received(bytes(unread[1]))
            unread[1].clear()

    for _ in range(40):
        # long streams too, so that the board's buffer fills and the client is held off
        data = stream(rnd, rnd.choice([2, 10, 400]))
        for piece in chunks(rnd, data):
            unread[0] += piece
            unread[1] += piece
            deliver()
            await settle()
            deliver()
        dt = rnd.choice([0.0, 0.01, 0.3, 2.0])
        for side in sides:
            step(side[5], dt)
        await settle()
        deliver()
    assert sides[0][1].written == sides[1][1].written
    assert sides[0][1].calls == sides[1][1].calls
    for side in sides:
        side[2].close()
    assert log_lines(*sides[0][3:5]) == log_lines(*sides[1][3:5])
    for side in sides:
        side[5].close()


# -- the pty endpoint ---------------------------------------------------------------------------


class StraightPty(PtyEndpoint):
    """The pty endpoint's read and write as they were: a fresh bytes object per read, through
    ``_take`` and ``_push``; every write through the backlog."""

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except BlockingIOError:
            return
        if data:
            self._take(data)
            self._push()

    def _write(self, data: bytes) -> None:
        if self.master < 0 or not self.connected or not data:
            return
        self._backlog += data
        self._flush()


def bare_pty(
    cls: type[PtyEndpoint], service: BoardService, loop: asyncio.AbstractEventLoop
) -> tuple[PtyEndpoint, int]:
    """A pty endpoint on a pty of its own, connected, without its symlink or inotify watch;
    returns it and the slave's descriptor (the client's side)."""
    endpoint = cls(service, pathlib.Path("/nonexistent/pty"))
    endpoint._loop = loop
    endpoint.master, slave = os.openpty()
    tty.setraw(slave, termios.TCSANOW)
    tty.setraw(endpoint.master, termios.TCSANOW)
    os.set_blocking(endpoint.master, False)
    os.set_blocking(slave, False)
    service.attach(endpoint)
    endpoint.connected = True
    return endpoint, slave


def read_all(fd: int) -> bytes:
    out = bytearray()
    while True:
        try:
            data = os.read(fd, 65536)
        except (BlockingIOError, OSError):
            return bytes(out)
        if not data:
            return bytes(out)
        out += data


@pytest.mark.parametrize("link", ["raw", "driver"])
@pytest.mark.parametrize("seed", range(3))
async def test_pty_fast_and_straight_give_the_same_bytes_and_log(
    tmp_path: pathlib.Path, link: str, seed: int
) -> None:
    cfg = config(tmp_path, link)
    loop = asyncio.get_running_loop()
    sides = []
    for name, cls in (("fast", PtyEndpoint), ("straight", StraightPty)):
        out = io.StringIO()
        log = TrafficLog("plain", file=tmp_path / f"{name}.jsonl", stream=out, env={})
        service = manual_service(cfg, log)
        endpoint, slave = bare_pty(cls, service, loop)
        sides.append([endpoint, slave, log, out, tmp_path / f"{name}.jsonl", service, b""])
    rnd = random.Random(seed)
    try:
        for _ in range(40):
            data = stream(rnd, rnd.choice([1, 3, 30]))
            for piece in chunks(rnd, data):
                for side in sides:
                    os.write(side[1], piece)
                    # the piece has crossed the terminal (a kernel worker moves it): one read,
                    # as the loop's reader callback makes it
                    if side[0]._reading or not side[0]._pending:
                        arrived(side[0].master, len(piece))
                        side[0]._readable()
                await settle()
            dt = rnd.choice([0.0, 0.01, 0.3])
            for side in sides:
                step(side[5], dt)
            await settle()
            for side in sides:
                side[6] += read_all(side[1])
        for side in sides:
            readable(side[1], 0.2)
            side[6] += read_all(side[1])
        assert sides[0][6] == sides[1][6]
        assert sides[0][6]
        for side in sides:
            side[2].close()
        # the same records, but for how the terminal cut the host's bytes into reads: the
        # kernel moves what is written to a pty's slave across in its own time, and on a busy
        # machine one side may read a piece in two (what reached the clients is compared above)
        assert unchunked(*sides[0][3:5]) == unchunked(*sides[1][3:5])
    finally:
        for side in sides:
            endpoint = side[0]
            if endpoint._reading:
                loop.remove_reader(endpoint.master)
            if endpoint._writing:
                loop.remove_writer(endpoint.master)
            for fd in (endpoint.master, side[1]):
                os.close(fd)
            side[5].close()


def arrived(fd: int, n: int, timeout: float = 2.0) -> None:
    """Wait (at most ``timeout`` seconds) until ``n`` bytes can be read from ``fd`` at once:
    the kernel moves what was written to a pty's slave across in its own time, and one read of
    part of a piece would log it as two chunks on one side only (seen on a loaded machine)."""
    deadline = time.monotonic() + timeout
    while True:
        waiting = struct.unpack("i", fcntl.ioctl(fd, termios.FIONREAD, b"\0\0\0\0"))[0]
        if waiting >= n or time.monotonic() > deadline:
            return
        time.sleep(0.0005)


def readable(fd: int, timeout: float = 2.0) -> bool:
    """Wait (at most ``timeout`` seconds) until ``fd`` has something to read."""
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    return bool(poller.poll(timeout * 1000))
