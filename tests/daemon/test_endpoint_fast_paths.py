"""The endpoints' fast paths (issue 16), end to end on a daemon served in this process.

* TCP (``omsd.transport.tcp``): every connection reads into one module-level buffer
  (``TcpClient`` is an ``asyncio.BufferedProtocol``), and ``buffer_updated`` hands what came
  straight to the board when nothing is held back from before (else ``_take`` + ``_push``, as
  ``data_received`` does). Many clients writing at once must each get exactly their own
  replies (nothing of one connection's bytes may reach another's board through the shared
  buffer); a client writing far more than one read (``READ_SIZE``) and one bite of the
  service (``FEED_BITE``) at once must get every reply, in order; a terminal client (the
  line-editing way) still works; and however a stream is cut into writes, the replies are the
  same.
* The pty (``omsd.transport.pty``): output goes to the master at once when nothing waits before
  it, else to a backlog written as the terminal takes it. A client that stops reading makes the
  backlog build; when it reads again every byte comes, in order.

Replies are checked against the board and link themselves, sans-I/O, given the same bytes
(:func:`reference`); the streams make no moves, so no reply depends on when it is asked for.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import random
import select
from pathlib import Path
from typing import Any

import pytest

from omsd.board import Board
from omsd.config import BoardConfig, TcpEndpoint
from omsd.config import PtyEndpoint as PtyConfig
from omsd.daemon import Daemon
from omsd.link import make_link
from omsd.models import get_model
from omsd.service import FEED_BITE
from omsd.transport import tcp
from omsd.transport.terminal import terminal_for

from .inprocess import WAIT, serving

# -- the reference ------------------------------------------------------------------------------


def reference(model: str, link: str, data: bytes, eos: int = 0x0A) -> bytes:
    """What a host reads, given ``data`` through ``link`` to a new board ``model`` (one
    session; time moves only while the board is still starting up)."""
    board = Board(get_model(model), now=0.0)
    through = make_link(link, board, eos=eos)
    out = bytearray()
    t = 0.0
    rest = data
    for _ in range(100_000):
        if not rest:
            break
        taken = through.from_host(rest, t, 1)
        rest = rest[taken:]
        out += through.to_host(t).data
        if not taken:
            t += 0.01
    assert not rest, "the reference board stopped taking bytes"
    out += through.to_host(t + 1.0).data
    return bytes(out)


WORDS = [b"AX", b"AY", b"AZ", b"AT", b"RP", b"AA RP", b"WY", b"XQ", b"QA", b"RE", b"AX RP"]
SEPARATORS = [b" ", b";", b"\r", b"  "]


def stream(rnd: random.Random, client: int, n: int) -> bytes:
    """``n`` commands: reports, and positions loaded with numbers of this client's own (so that
    a byte of another client's would show)."""
    out = bytearray()
    for k in range(n):
        if rnd.random() < 0.3:
            out += b"A%s LP%d" % (rnd.choice(b"XYZT").to_bytes(1, "big"), client * 100_000 + k)
        else:
            out += rnd.choice(WORDS)
        out += rnd.choice(SEPARATORS)
    return bytes(out)


# -- a daemon in this process -------------------------------------------------------------------


@pytest.fixture(autouse=True)
def _runtime(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("RUNTIME_DIRECTORY", str(tmp_path / "run"))


def tcp_board(name: str, model: str = "PC48-4E", link: str = "driver", **kw: Any) -> BoardConfig:
    terminal = kw.pop("terminal", False)
    return BoardConfig(
        name=name,
        model=model,
        link=link,
        tcp=(TcpEndpoint("127.0.0.1", 0, terminal),),
        **kw,
    )


def port_of(daemon: Daemon, board: str) -> int:
    (endpoint,) = [e for e in daemon.endpoints if e.board == board and e.kind == "tcp"]
    return int(endpoint.address.rsplit(":", 1)[1])


class Client:
    """A TCP client of the daemon (asyncio streams, in the daemon's own loop)."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer

    @classmethod
    async def connect(cls, port: int) -> Client:
        reader, writer = await asyncio.open_connection("127.0.0.1", port, limit=2**22)
        return cls(reader, writer)

    async def write(self, data: bytes, rnd: random.Random | None = None) -> None:
        """``data``, in one write, or cut where ``rnd`` says, with turns of the loop between."""
        if rnd is None:
            self.writer.write(data)
            await self.writer.drain()
            return
        i = 0
        while i < len(data):
            n = rnd.choice([1, 2, 3, 7, 16, 64, 300, 1500, 5000])
            self.writer.write(data[i : i + n])
            i += n
            await self.writer.drain()
            for _ in range(rnd.choice([0, 0, 1, 3])):
                await asyncio.sleep(0)
            if rnd.random() < 0.05:
                await asyncio.sleep(0.002)

    async def read(self, n: int) -> bytes:
        try:
            return await asyncio.wait_for(self.reader.readexactly(n), WAIT)
        except asyncio.IncompleteReadError as exc:
            raise AssertionError(f"the connection ended after {exc.partial!r}") from None

    async def quiet(self, seconds: float = 0.05) -> bytes:
        """Whatever more comes within ``seconds`` (nothing, if all is well)."""
        try:
            return await asyncio.wait_for(self.reader.read(65536), seconds)
        except TimeoutError:
            return b""

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(OSError):
            await self.writer.wait_closed()


# -- TCP ----------------------------------------------------------------------------------------

BOARDS = [
    ("PC48-4E", "driver"),
    ("PC48-8", "raw"),
    ("PC46-4E", "driver"),
    ("PC48-2", "raw"),
    ("VS4-040", "driver"),
    ("PC48-4E", "raw"),
]


async def test_clients_writing_at_once_get_exactly_their_own_replies() -> None:
    """Twelve clients, each on its board, each writing its own stream in random pieces at the
    same time as the others: every read of every connection goes through the one buffer."""
    boards = [tcp_board(f"b{i}", *BOARDS[i % len(BOARDS)]) for i in range(12)]
    async with serving(*boards) as daemon:
        clients = [await Client.connect(port_of(daemon, b.name)) for b in boards]
        try:

            async def talk(i: int) -> None:
                rnd = random.Random(i)
                data = stream(rnd, i + 1, 600)
                expected = reference(boards[i].model, boards[i].link, data)
                client = clients[i]
                await client.write(data, rnd)
                got = await client.read(len(expected))
                assert got == expected, f"client {i}"
                assert await client.quiet() == b"", f"client {i}"

            await asyncio.gather(*(talk(i) for i in range(len(clients))))
        finally:
            for client in clients:
                await client.close()


@pytest.mark.parametrize("link", ["driver", "raw"])
async def test_a_write_far_larger_than_a_read_gets_every_reply_in_order(link: str) -> None:
    """About 200 KB of commands in one write: more than READ_SIZE for one read and FEED_BITE for
    one bite of the board, and more than the board and driver can hold, so the client is held
    off (flow control) and its reads are taken again and again."""
    commands = [b"AX LP%d RP " % k for k in range(15_000)]
    data = b"".join(commands)
    assert len(data) > 3 * tcp.READ_SIZE and len(data) > 40 * FEED_BITE
    expected = reference("PC48-4E", link, data)
    if link == "driver":
        assert expected == b"".join(b"%d\n" % k for k in range(15_000))
    async with serving(tcp_board("big", link=link)) as daemon:
        client = await Client.connect(port_of(daemon, "big"))
        try:
            await client.write(data)
            assert await client.read(len(expected)) == expected
            assert await client.quiet() == b""
            # the connection is not left paused: it still answers
            await client.write(b"AY LP7 RP ")
            tail = reference("PC48-4E", link, b"AY LP7 RP ")
            assert await client.read(len(tail)) == tail
        finally:
            await client.close()


async def test_the_same_stream_cut_in_any_way_gets_the_same_replies() -> None:
    """One stream of 2,000 commands, cut into writes eight different ways (one board each,
    all at once): eight times the reference's replies."""
    data = stream(random.Random(99), 7, 2000)
    expected = reference("PC48-4E", "driver", data)
    boards = [tcp_board(f"cut{i}") for i in range(8)]
    async with serving(*boards) as daemon:
        clients = [await Client.connect(port_of(daemon, b.name)) for b in boards]
        try:

            async def talk(i: int) -> bytes:
                # 0: all at once; 1: a byte at a time (first 3,000 bytes); others: random cuts
                client = clients[i]
                if i == 0:
                    await client.write(data)
                elif i == 1:
                    for j in range(len(data)):
                        client.writer.write(data[j : j + 1])
                        if j < 3000:
                            await client.writer.drain()
                            await asyncio.sleep(0)
                    await client.writer.drain()
                else:
                    await client.write(data, random.Random(i))
                got = await client.read(len(expected))
                assert await client.quiet() == b""
                return got

            results = await asyncio.gather(*(talk(i) for i in range(len(clients))))
        finally:
            for client in clients:
                await client.close()
    assert all(got == expected for got in results)


async def test_a_terminal_client_still_works() -> None:
    """``terminal = true``: the line-editing way (no fast path). What the client sees is what
    the terminal and the link make of the same keys, sans-I/O."""
    keys = [b"WY", b"\r", b"AX LP42 R", b"P\r", b"XQ\r", b"AX RPX\x7f\r\n", b"AA RP\r"]
    board = Board(get_model("PC48-4E"), now=0.0)
    link = make_link("driver", board)
    terminal = terminal_for(link, lambda: board.interpreter.echo)
    expected = []
    for key in keys:
        to_board, screen = terminal.typed(key)
        assert link.from_host(to_board, 1.0, 1) == len(to_board)
        expected.append(screen + terminal.shown(link.to_host(1.0).data))
    assert expected[1] == b"\r\nPC48 ver 3.00-4\r\n"
    async with serving(tcp_board("tty", terminal=True)) as daemon:
        client = await Client.connect(port_of(daemon, "tty"))
        try:
            for key, shown in zip(keys, expected, strict=True):
                await client.write(key)
                assert await client.read(len(shown)) == shown, key
            assert await client.quiet() == b""
        finally:
            await client.close()


async def test_clients_taking_over_a_board_in_turn_get_only_their_own_replies() -> None:
    """Connections one after the other on one board (each takes over from the last): every
    read still lands in the shared buffer, and each connection gets its own answers."""
    async with serving(tcp_board("one")) as daemon:
        port = port_of(daemon, "one")
        for i in range(10):
            client = await Client.connect(port)
            try:
                data = b"AX LP%d RP AY LP%d RP " % (i, -i)
                await client.write(data, random.Random(i))
                assert await client.read(len(b"%d\n%d\n" % (i, -i))) == b"%d\n%d\n" % (i, -i)
            finally:
                await client.close()


# -- the pty --------------------------------------------------------------------------------------


async def test_a_pty_client_that_stops_reading_gets_everything_in_order(tmp_path: Path) -> None:
    """The client writes commands and reads nothing: the terminal's buffers fill, the daemon's
    backlog builds (the write fast path steps aside), then the client reads and every reply
    comes, in order, and the backlog is gone."""
    link = tmp_path / "run" / "p1"
    config = BoardConfig(name="p1", pty=(PtyConfig(link),))
    loop = asyncio.get_running_loop()
    async with serving(config) as daemon:
        (endpoint,) = daemon.ptys
        fd = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            async with asyncio.timeout(WAIT):
                while not endpoint.connected:
                    await asyncio.sleep(0.005)
            sent = bytearray()
            k = 0

            async def write_commands(n: int) -> None:
                nonlocal k
                chunk = b"".join(b"AX LP%d RP " % (k + j) for j in range(n))
                k += n
                sent.extend(chunk)
                view = memoryview(chunk)
                async with asyncio.timeout(WAIT):
                    while view:
                        try:
                            view = view[os.write(fd, view) :]
                        except BlockingIOError:
                            await asyncio.sleep(0.002)
                # until the daemon has read and answered it all (or holds it off)
                async with asyncio.timeout(WAIT):
                    while unread(endpoint.master) or endpoint._pending:
                        await asyncio.sleep(0.002)

            backlog_seen = 0
            for _ in range(2000):
                await write_commands(100)
                if endpoint._backlog:
                    backlog_seen = len(endpoint._backlog)
                    break
            assert backlog_seen, "the terminal took everything: no backlog to test"
            assert endpoint._writing  # waiting for the terminal to take more
            for _ in range(10):  # 10 more KiB or so behind it: well within MAX_BACKLOG
                await write_commands(100)
            assert len(endpoint._backlog) > backlog_seen
            # the client reads again, a little at a time, and writes more commands meanwhile:
            # their answers must wait behind the backlog
            got = bytearray()
            async with asyncio.timeout(WAIT):
                for _ in range(100):
                    while True:
                        try:
                            got += os.read(fd, 1024)
                            break
                        except BlockingIOError:
                            await asyncio.sleep(0.001)
                    await write_commands(3)
            expected = reference("PC48-4E", "driver", bytes(sent))
            assert expected == b"".join(b"%d\n" % j for j in range(k))
            async with asyncio.timeout(WAIT):
                while len(got) < len(expected):
                    try:
                        got += os.read(fd, 65536)
                    except BlockingIOError:
                        await asyncio.sleep(0.001)
            assert bytes(got) == expected
            await asyncio.sleep(0.02)
            assert not endpoint._backlog and not endpoint._writing
            with contextlib.suppress(BlockingIOError):
                assert os.read(fd, 65536) == b""
            # with nothing waiting any more, an answer goes at once again
            os.write(fd, b"AY LP5 RP ")
            async with asyncio.timeout(WAIT):
                while True:
                    try:
                        assert os.read(fd, 100) == b"5\n"
                        break
                    except BlockingIOError:
                        await asyncio.sleep(0.001)
        finally:
            os.close(fd)
        async with asyncio.timeout(WAIT):
            while endpoint.connected:
                await asyncio.sleep(0.005)
    assert loop.is_running()


def unread(fd: int) -> bool:
    """There is something to read on ``fd`` (the client's bytes the daemon has not read)."""
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    return any(event & select.POLLIN for _, event in poller.poll(0))
