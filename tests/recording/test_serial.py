"""``omsd record --to serial:...`` with a pty pair standing in for the serial port: the card is
an emulated board answering on the master side (what a card at the far end of the cable would
do), the recorder opens the slave with pyserial; the application talks to the recorder's own pty
(``--pty``). A session replays with no difference; unplugging the card (closing the master) ends
the recording with exit status 1 and says so."""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import os
import termios
import time
import tty
from collections.abc import AsyncIterator
from pathlib import Path

import pytest

from omsd.board import Board
from omsd.config import BoardConfig
from omsd.link import Link, make_link
from omsd.models import get_model
from omsd.recording.record import Recorder, parse_card
from omsd.recording.replay import replay_file

from .session import STAGE, WAIT

pytest.importorskip("serial")


class FakeCard:
    """A board on the master side of a pty pair, on the loop's clock (the monotonic one)."""

    def __init__(self, master: int, model: str, link: str) -> None:
        self.master = master
        self.loop = asyncio.get_running_loop()
        self.board = Board(get_model(model), now=time.monotonic(), world=STAGE)
        self.link: Link = make_link(link, self.board)
        self.timer: asyncio.TimerHandle | None = None
        os.set_blocking(master, False)
        self.loop.add_reader(master, self._readable)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except OSError:
            return
        self.link.from_host(data, time.monotonic(), 1)
        self._run()

    def _run(self) -> None:
        self.timer = None
        out = self.link.to_host(time.monotonic())
        if out.data:
            os.write(self.master, out.data)
        deadline = self.link.next_deadline()
        if deadline is not None:
            self.timer = self.loop.call_at(max(deadline, self.loop.time()), self._run)

    def unplug(self) -> None:
        if self.timer is not None:
            self.timer.cancel()
        self.loop.remove_reader(self.master)
        os.close(self.master)


class Client:
    """The application on the recorder's pty."""

    def __init__(self, path: Path) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(self.fd, termios.TCSANOW)
        self.buffer = bytearray()

    async def ask(self, command: bytes, end: bytes = b"\n") -> bytes:
        os.write(self.fd, command)
        return await self.until(end)

    async def until(self, end: bytes) -> bytes:
        async with asyncio.timeout(WAIT):
            while (i := self.buffer.find(end)) < 0:
                await asyncio.sleep(0.002)
                with contextlib.suppress(BlockingIOError):
                    self.buffer += os.read(self.fd, 4096)
        data = bytes(self.buffer[: i + len(end)])
        del self.buffer[: i + len(end)]
        return data

    def close(self) -> None:
        os.close(self.fd)


@contextlib.asynccontextmanager
async def serial_rig(tmp_path: Path) -> AsyncIterator[tuple[FakeCard, Recorder, Client]]:
    master, slave = os.openpty()
    tty.setraw(slave, termios.TCSANOW)
    device = os.ttyname(slave)
    os.close(slave)  # the recorder opens it by name, as a serial port
    card = FakeCard(master, "PC48-4E", "driver")
    board = BoardConfig(name="card", model="PC48-4E", link="driver", world=STAGE)
    recorder = Recorder(
        parse_card(f"serial:{device},115200"),
        board,
        tmp_path / "serial.jsonl",
        pty=tmp_path / "oms",
        out=io.StringIO(),
        err=io.StringIO(),
    )
    await recorder.start()
    client = Client(tmp_path / "oms")
    try:
        yield card, recorder, client
    finally:
        client.close()
        recorder.stop()
        await recorder.wait()
        with contextlib.suppress(OSError):
            card.unplug()


async def test_a_session_through_a_serial_port_replays(tmp_path: Path) -> None:
    async with serial_rig(tmp_path) as (_, recorder, client):
        assert await client.ask(b"WY") == b"PC48 ver 3.00-4\n"
        os.write(client.fd, b"AX VL8000 AC80000 MR1500 GO ID")
        for _ in range(4):
            await asyncio.sleep(0.03)
            await client.ask(b"RP")
        await client.until(b"!\x01\n")
        assert await client.ask(b"XQ") == b"#\n"
        assert await client.ask(b"AX JG-20000;", b"@\n") == b"@\n"
        assert await client.ask(b"AX QA") == b"MDLN\n"
        assert (tmp_path / "oms").is_symlink()
    assert not (tmp_path / "oms").exists()  # the recorder's pty link is gone with it
    assert recorder.status == 0
    header = json.loads((tmp_path / "serial.jsonl").read_text().splitlines()[0])
    assert header["line"] == {"baud": 115200, "bits": 10}
    assert header["to"].endswith(",115200,8N1") and header["listen"] == f"pty:{tmp_path / 'oms'}"
    result = replay_file(tmp_path / "serial.jsonl")
    assert result.ok, result.report()
    assert (result.counts.answers, result.counts.events) == (7, 2)


async def test_an_unplugged_card_ends_the_recording_with_status_1(tmp_path: Path) -> None:
    async with serial_rig(tmp_path) as (card, recorder, client):
        assert await client.ask(b"WY") == b"PC48 ver 3.00-4\n"
        card.unplug()
        async with asyncio.timeout(WAIT):
            assert await recorder.wait() == 1
    lines = [json.loads(x) for x in (tmp_path / "serial.jsonl").read_text().splitlines()]
    assert lines[-1]["kind"] == "error" and "went away" in lines[-1]["message"]
    assert "the recording in" in recorder.err.getvalue()  # type: ignore[attr-defined]
    assert replay_file(tmp_path / "serial.jsonl").ok
