"""The pieces the recording tests share: a stand-in card (an omsd daemon in this process, on a
free port), ``omsd record`` in front of it (in this process too), and a client that drives a
session through the recorder, waiting for each answer with a deadline."""

from __future__ import annotations

import asyncio
import contextlib
import io
from collections.abc import AsyncIterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from omsd.board import AxisWorld
from omsd.config import BoardConfig, ControlConfig, DaemonConfig, TcpEndpoint
from omsd.daemon import Daemon
from omsd.dialects import framing
from omsd.recording.record import Card, Recorder
from omsd.recording.units import splitter
from omsd.telemetry.traffic import TrafficLog

WAIT = 10.0
"""Seconds any one answer may take (a move's done marker included)."""

#: A stage whose limits and home switch are a few hundred steps from where X starts, as
#: config/plotter.toml's: a jog reaches the minus limit in a tenth of a second and a home finds
#: the switch's lower edge soon after.
STAGE = {
    "X": AxisWorld(negative_limit=-500, positive_limit=60500, home_low=0, home_high=100),
    "Y": AxisWorld(negative_limit=-500, positive_limit=60500, home_low=0, home_high=100),
}


@dataclass
class Rig:
    """The client's side: what it reads is cut into answers and markers as the replay cuts it
    (:mod:`omsd.recording.units`), by a task reading all the time."""

    card: Daemon
    recorder: Recorder
    board: BoardConfig
    log: Path
    reader: asyncio.StreamReader
    writer: asyncio.StreamWriter
    err: io.StringIO = field(default_factory=io.StringIO)
    answers: list[bytes] = field(default_factory=list)
    markers: list[bytes] = field(default_factory=list)
    received: bytearray = field(default_factory=bytearray)
    changed: asyncio.Event = field(default_factory=asyncio.Event)

    def start_reading(self) -> asyncio.Task[None]:
        model = self.board.personality()
        split = splitter(self.board.link, self.board.eos, framing(model))

        async def read() -> None:
            pending = b""
            while data := await self.reader.read(65536):
                self.received += data
                pending += data
                cuts = split(pending)
                if not _complete(pending):
                    cuts = cuts[:-1]  # the last unit is still coming
                for start, end, event in cuts:
                    (self.markers if event else self.answers).append(pending[start:end])
                    self.changed.set()
                pending = pending[cuts[-1][1] :] if cuts else pending

        return asyncio.create_task(read())

    async def _next(self, kind: list[bytes]) -> bytes:
        async with asyncio.timeout(WAIT):
            while not kind:
                self.changed.clear()
                await self.changed.wait()
        return kind.pop(0)

    async def ask(self, command: bytes, answers: int = 1) -> bytes:
        """Send ``command``; its ``answers`` next answers, joined."""
        await self.send(command)
        return b"".join([await self._next(self.answers) for _ in range(answers)])

    async def marker(self) -> bytes:
        """The next done, limit or slip marker."""
        return await self._next(self.markers)

    async def send(self, command: bytes) -> None:
        self.writer.write(command)
        await self.writer.drain()


def _complete(data: bytes) -> bool:
    """Whether what was read ends where a unit ends (a line end, or the raw link's ``#``)."""
    return bool(data) and data[-1] in (0x0A, 0x0D, 0x23)


@contextlib.asynccontextmanager
async def rig(
    tmp_path: Path,
    model: str,
    *,
    link: str = "driver",
    world: Mapping[str, AxisWorld] | None = None,
    card_log: Path | None = None,
    name: str = "card",
) -> AsyncIterator[Rig]:
    """A stand-in card (an omsd daemon serving ``model`` on a free port, with ``world``, its
    traffic in ``card_log`` if given), ``omsd record`` in front of it recording into
    ``tmp_path / "session.jsonl"``, and a client connected to the recorder."""
    board = BoardConfig(name=name, model=model, link=link, world=dict(world or STAGE))
    served = BoardConfig(
        name=name,
        model=model,
        link=link,
        world=board.world,
        tcp=(TcpEndpoint("127.0.0.1", 0),),
    )
    config = DaemonConfig(boards=(served,), control=ControlConfig(socket=None, explicit=True))
    traffic = TrafficLog("off", file=card_log)
    card = Daemon(config, traffic, out=io.StringIO())
    endpoints = await card.start()
    port = int(endpoints[0].address.rsplit(":", 1)[1])
    log = tmp_path / "session.jsonl"
    err = io.StringIO()
    recorder = Recorder(
        Card("tcp", host="127.0.0.1", port=port),
        board,
        log,
        tcp=TcpEndpoint("127.0.0.1", 0),
        out=io.StringIO(),
        err=err,
    )
    try:
        await recorder.start()
        host, _, number = recorder.address.rpartition(":")
        reader, writer = await asyncio.open_connection(host, int(number))
        client = Rig(card, recorder, board, log, reader, writer, err)
        task = client.start_reading()
        try:
            yield client
        finally:
            task.cancel()
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()
    finally:
        recorder.stop()
        await recorder.wait()
        await card.stop(quiet=True)
        traffic.close()
