"""In-process endpoints for the transport tests: a board's service on the running loop with its
log in memory, and a pty pair standing in for a serial device (the test holds the master: the
far end of the cable; the endpoint opens the slave through a symlink, as it would
/dev/ttyUSB0)."""

from __future__ import annotations

import asyncio
import io
import os
import time
from pathlib import Path

from omsd.config import BoardConfig
from omsd.service import BoardService
from omsd.telemetry.traffic import Direction, Traffic, TrafficLog

TIMEOUT = 5.0


class Recorder:
    """An observer keeping the traffic a board sees."""

    def __init__(self) -> None:
        self.records: list[Traffic] = []

    def traffic(self, service: BoardService, record: Traffic) -> None:
        self.records.append(record)

    def event(self, service: BoardService, when: float, event: object) -> None:
        pass

    def changed(self, service: BoardService) -> None:
        pass

    def received(self) -> bytes:
        """What reached the board from its hosts."""
        return b"".join(r.data for r in self.records if r.direction == Direction.IN)


def make_service(**config: object) -> tuple[BoardService, io.StringIO, Recorder]:
    stream = io.StringIO()
    log = TrafficLog(view="plain", stream=stream)
    service = BoardService(
        BoardConfig(name="board1", **config),  # type: ignore[arg-type]
        asyncio.get_running_loop(),
        log,
    )
    recorder = Recorder()
    service.observers.append(recorder)
    return service, stream, recorder


async def until(condition: object, timeout: float = TIMEOUT) -> None:
    """Wait (the loop running) until ``condition()`` is true."""
    deadline = time.monotonic() + timeout
    while not condition():  # type: ignore[operator]
        if time.monotonic() > deadline:
            raise AssertionError("timed out")
        await asyncio.sleep(0.005)


class FarEnd:
    """The master of a pty pair: the old PC at the far end of the null-modem cable. The slave is
    reached through ``link``, a symlink, as a udev rule's /dev/serial/by-id name would be."""

    def __init__(self, link: Path) -> None:
        self.link = link
        self.master, slave = os.openpty()
        self.device = os.ttyname(slave)
        os.close(slave)
        os.set_blocking(self.master, False)
        tmp = link.with_name(link.name + ".tmp")
        os.symlink(self.device, tmp)
        os.replace(tmp, link)
        self.buffer = bytearray()

    def write(self, data: bytes) -> None:
        os.write(self.master, data)

    async def read_until(self, end: bytes, timeout: float = TIMEOUT) -> bytes:
        deadline = time.monotonic() + timeout
        while end not in self.buffer:
            try:
                self.buffer += os.read(self.master, 4096)
                continue
            except (BlockingIOError, OSError):
                pass
            if time.monotonic() > deadline:
                raise AssertionError(f"no {end!r} within {timeout} s; got {bytes(self.buffer)!r}")
            await asyncio.sleep(0.002)
        at = self.buffer.index(end) + len(end)
        data = bytes(self.buffer[:at])
        del self.buffer[:at]
        return data

    def unplug(self) -> None:
        """The device vanishes: the master closed (its slave hangs up, its node goes), the
        symlink removed."""
        os.close(self.master)
        self.master = -1
        self.link.unlink()

    def close(self) -> None:
        if self.master >= 0:
            os.close(self.master)
            self.master = -1
