"""A daemon served in the test's own event loop (for tests that reach into its endpoints)."""

from __future__ import annotations

import asyncio
import contextlib
import io
import re
from collections.abc import AsyncIterator

from omsd import wakeups
from omsd.config import BoardConfig, ControlConfig, DaemonConfig, TcpEndpoint
from omsd.daemon import Daemon
from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog

WAIT = 20.0
"""Seconds allowed for what should take a fraction of one (a hang detector, not a timing)."""


@contextlib.asynccontextmanager
async def serving(*boards: BoardConfig, out: io.StringIO | None = None) -> AsyncIterator[Daemon]:
    """The boards served until the block ends; then stopped, with nothing left behind (no
    endpoint, no wake-up timer) and nothing gone wrong on the way. ``out``: where the traffic
    log's plain view goes (the daemon's own lines among it), to read it meanwhile."""
    config = DaemonConfig(boards=boards, control=ControlConfig(socket=None, explicit=True))
    out = io.StringIO() if out is None else out
    daemon = Daemon(config, TrafficLog("plain", stream=out, env={}), out=io.StringIO())
    loop = asyncio.get_running_loop()
    try:
        await daemon.start()
        try:
            yield daemon
        finally:
            await daemon.stop()
    finally:
        release_wakeups(loop)
    assert not re.findall(r"^\S+ error: .*", out.getvalue(), re.M), out.getvalue()[-2000:]


def release_wakeups(loop: asyncio.AbstractEventLoop) -> None:
    """The loop's wake-up timerfd, closed (omsd.wakeups keeps it as long as the loop lives)."""
    timers = wakeups._BY_LOOP.pop(loop, None)
    if isinstance(timers, wakeups.TimerFdTimers):
        if timers._reading:
            loop.remove_reader(timers._timer.fd)
            timers._reading = False
        timers._timer.close()
        timers._timer.fd = -1  # its finalizer closes it again: not another file's number


def tcp_board(name: str) -> BoardConfig:
    """A PC48-4 on the driver link with a TCP endpoint on a free port."""
    return BoardConfig(
        name=name, model="PC48-4", link="driver", tcp=(TcpEndpoint("127.0.0.1", 0, False),)
    )


async def connect(daemon: Daemon, name: str) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    """A client of board ``name``'s TCP endpoint."""
    (endpoint,) = [e for e in daemon.endpoints if e.board == name and e.kind == "tcp"]
    port = int(endpoint.address.rsplit(":", 1)[1])
    return await asyncio.open_connection("127.0.0.1", port)


def service_of(daemon: Daemon, name: str) -> BoardService:
    (service,) = [s for s in daemon.services if s.name == name]
    return service


async def ask(
    reader: asyncio.StreamReader, writer: asyncio.StreamWriter, data: bytes, lines: int = 1
) -> bytes:
    """Write ``data``; the next ``lines`` lines the board answers."""
    writer.write(data)
    await writer.drain()
    out = b""
    for _ in range(lines):
        out += await asyncio.wait_for(reader.readline(), WAIT)
    return out
