"""``omsd record --to serial:...`` with a pty pair standing in for the serial port: the card is
an emulated board answering on the master side (what a card at the far end of the cable would
do), the recorder opens the slave with pyserial; the application talks to the recorder's own pty
(``--pty``). A session replays with no difference; unplugging the card (closing the master) ends
the recording with exit status 1 and says so.

The pty pair is not a wire: Linux hands what one side writes to the other through a kernel worker
(the tty layer's flip buffer), which on a busy machine runs tens of milliseconds later, and the
stand-in card's own timers run late with the event loop. The recorder times each chunk as it
reads it, as it must; so the rig measures how far it put the recording's times off the card's
own clock (:meth:`FakeCard.lag`) and the replay is allowed that much on top of its tolerance:
with the rig on time (all but always), the replay is held to the tolerance as it stands."""

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
from omsd.recording.compare import DEFAULT_SECONDS, Tolerance
from omsd.recording.format import read_recording
from omsd.recording.record import Recorder, parse_card
from omsd.recording.replay import replay_file
from omsd.recording.units import driver_splitter
from omsd.telemetry.traffic import Direction

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
        self.heard: list[tuple[float, int]] = []  # (when read, bytes read by then)
        self.said: list[tuple[float, int]] = []  # (when the board said it, bytes written by then)
        os.set_blocking(master, False)
        self.loop.add_reader(master, self._readable)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except OSError:
            return
        now = time.monotonic()
        self.heard.append((now, len(data) + (self.heard[-1][1] if self.heard else 0)))
        self.link.from_host(data, now, 1)
        self._run()

    def _run(self, due: float | None = None) -> None:
        self.timer = None
        now = time.monotonic()
        out = self.link.to_host(now)
        if out.data:
            n = os.write(self.master, out.data)
            when = now if due is None else min(due, now)  # a marker is due at its deadline
            self.said.append((when, n + (self.said[-1][1] if self.said else 0)))
        deadline = self.link.next_deadline()
        if deadline is not None:
            self.timer = self.loop.call_at(max(deadline, self.loop.time()), self._run, deadline)

    def lag(self, path: Path) -> float:
        """How far the rig put the times of the recording at ``path`` off this card's clock
        (the same, monotonic, clock): the longest a command took from the recorder to the card,
        plus the longest anything the card said took from when it was due (a marker: its
        deadline) to the recorder."""
        recording = read_recording(path)
        heard = sent = 0.0
        read = written = 0
        for chunk in recording.chunks:
            at = recording.origin + chunk.time
            if chunk.direction is Direction.IN:
                read += len(chunk.data)
                when = next(t for t, total in self.heard if total >= read)
                heard = max(heard, when - at)
            else:
                written += len(chunk.data)
                when = next(t for t, total in self.said if total >= written)
                sent = max(sent, at - when)
        return heard + sent

    def unplug(self) -> None:
        if self.timer is not None:
            self.timer.cancel()
        self.loop.remove_reader(self.master)
        os.close(self.master)


class Client:
    """The application on the recorder's pty. What it reads is cut into answers and markers as
    the replay cuts it (:func:`omsd.recording.units.driver_splitter`): a done marker comes when
    the move ends, before or after the reply to a command sent about then ("If the board is
    returning a message when an interrupt occurs, the interrupt symbol will be delayed until
    after the end of the message string", PC48 manual §7.3.3: never inside one, no more)."""

    def __init__(self, path: Path) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(self.fd, termios.TCSANOW)
        self.pending = b""
        self.answers: list[bytes] = []
        self.markers: list[bytes] = []
        self.split = driver_splitter(0x0A)

    def send(self, command: bytes) -> None:
        os.write(self.fd, command)

    async def ask(self, command: bytes) -> bytes:
        """Send ``command``; the next answer."""
        self.send(command)
        return await self._next(self.answers)

    async def marker(self) -> bytes:
        """The next done, limit or slip marker."""
        return await self._next(self.markers)

    async def _next(self, kind: list[bytes]) -> bytes:
        async with asyncio.timeout(WAIT):
            while not kind:
                await asyncio.sleep(0.002)
                with contextlib.suppress(BlockingIOError):
                    self.pending += os.read(self.fd, 4096)
                cuts = self.split(self.pending)
                if not self.pending.endswith(b"\n"):
                    cuts = cuts[:-1]  # the last unit is still coming
                for start, end, event in cuts:
                    (self.markers if event else self.answers).append(self.pending[start:end])
                self.pending = self.pending[cuts[-1][1] :] if cuts else self.pending
        return kind.pop(0)

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


# the move takes 0.29 s: polled every 0.03 s, all four positions are read during it; every 0.1 s
# (or every 0.03 s on a busy machine), the done marker comes before the last replies
@pytest.mark.parametrize("every", [0.03, 0.1])
async def test_a_session_through_a_serial_port_replays(tmp_path: Path, every: float) -> None:
    async with serial_rig(tmp_path) as (card, recorder, client):
        assert await client.ask(b"WY") == b"PC48 ver 3.00-4\n"
        client.send(b"AX VL8000 AC80000 MR1500 GO ID")
        for _ in range(4):
            await asyncio.sleep(every)
            await client.ask(b"RP")
        assert await client.marker() == b"!\x01\n"
        assert await client.ask(b"XQ") == b"#\n"
        client.send(b"AX JG-20000;")
        assert await client.marker() == b"@\n"
        assert await client.ask(b"AX QA") == b"MDLN\n"
        assert (tmp_path / "oms").is_symlink()
    assert not (tmp_path / "oms").exists()  # the recorder's pty link is gone with it
    assert recorder.status == 0
    header = json.loads((tmp_path / "serial.jsonl").read_text().splitlines()[0])
    assert header["line"] == {"baud": 115200, "bits": 10}
    assert header["to"].endswith(",115200,8N1") and header["listen"] == f"pty:{tmp_path / 'oms'}"
    lag = card.lag(tmp_path / "serial.jsonl")
    result = replay_file(
        tmp_path / "serial.jsonl", tolerance=Tolerance(seconds=DEFAULT_SECONDS + lag)
    )
    assert result.ok, f"{result.report()}\n(the rig's lag: {lag * 1000:.1f} ms)"
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
