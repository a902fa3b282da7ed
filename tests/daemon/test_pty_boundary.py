"""A pty session's boundary is exact (issue 13): a program that opens the pty while the daemon
is still seeing the last one go gets the answer to its own question, and only that.

The pty's master is one byte stream and its clients' opens and closes come apart from it
(inotify); the daemon must put every byte in the right session whatever the order in which
the kernel and the daemon's own steps interleave (``omsd/transport/pty.py``, "Whose bytes are
whose"). The churn test (``tests/robustness/test_churn.py``) found an order that lost a
newcomer's question, one run in three. Here the order is not left to chance: the daemon is
served in this process, and the newcomer opens the pty just before the daemon's k-th system
call after the last client closed (a read of the master or of the watch, an open, a close, a
flush), for every k until the daemon has nothing more to do, and asks its question at once or
a few of the daemon's calls later.

Client A loads nothing and asks ``AX RP`` (X was loaded with 111), then closes, having read
the answer or having left it unread in the terminal; client B asks ``AY RP`` (Y holds -777).
B must get exactly ``-777``: not nothing (its question taken for A's session and its answer
thrown away with A's), not ``111`` (A's answer). And the daemon must have seen each client
as a session of its own: one "opened" and one "closed" line each.
"""

from __future__ import annotations

import asyncio
import io
import os
import select
import termios
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from omsd.config import BoardConfig
from omsd.config import PtyEndpoint as PtyConfig

from .inprocess import WAIT, serving

LEFT_ALONE = 0.2
"""Seconds after which a daemon that made no k-th call is taken to have nothing left to do."""

QUIET = 0.05
"""Seconds B listens after its answer for anything more."""


class Interleave:
    """Runs actions just before given ones of the daemon's system calls from the moment it is
    armed (``os.readv``, ``os.read``, ``os.open``, ``os.close``, ``termios.tcflush``, counted
    from 0): the daemon and the test share one thread, so the calls counted are the daemon's."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.actions: list[tuple[int, Callable[[], None]]] = []
        self.count = 0
        self.inside = False
        for module, name in (
            (os, "readv"),
            (os, "read"),
            (os, "open"),
            (os, "close"),
            (termios, "tcflush"),
        ):
            monkeypatch.setattr(module, name, self._wrap(getattr(module, name)))

    def _wrap(self, call: Callable[..., Any]) -> Callable[..., Any]:
        def wrapped(*args: Any, **kwargs: Any) -> Any:
            if self.actions and not self.inside:
                while self.actions and self.actions[0][0] <= self.count:
                    self.fire()
                self.count += 1
            return call(*args, **kwargs)

        return wrapped

    def arm(self, *actions: tuple[int, Callable[[], None]]) -> None:
        self.count = 0
        self.actions = sorted(actions, key=lambda kv: kv[0])

    def fire(self) -> None:
        """The next action, now."""
        _, action = self.actions.pop(0)
        self.inside = True
        try:
            action()
        finally:
            self.inside = False

    @property
    def fired(self) -> bool:
        return not self.actions


async def read_line(fd: int) -> bytes:
    got = bytearray()
    async with asyncio.timeout(WAIT):
        while not got.endswith(b"\n"):
            try:
                got += os.read(fd, 256)
            except BlockingIOError:
                await asyncio.sleep(0.001)
    return bytes(got)


async def rest(fd: int) -> bytes:
    await asyncio.sleep(QUIET)
    try:
        return os.read(fd, 256)
    except BlockingIOError:
        return b""


@pytest.mark.parametrize("later", [0, 2, 5], ids=lambda j: f"B writes {j} calls after it opens")
@pytest.mark.parametrize("a_reads", [True, False], ids=["A read its answer", "A left it"])
async def test_a_newcomer_gets_its_own_answer_whenever_it_opens(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, a_reads: bool, later: int
) -> None:
    monkeypatch.setenv("RUNTIME_DIRECTORY", str(tmp_path / "run"))
    link = tmp_path / "run" / "p1"
    out = io.StringIO()
    async with serving(BoardConfig(name="p1", pty=(PtyConfig(link),)), out=out) as daemon:
        (endpoint,) = daemon.ptys

        def opened() -> int:
            return out.getvalue().count(" opened\n")

        def closed() -> int:
            return out.getvalue().count(" closed\n")

        async def settled(sessions: int) -> None:
            async with asyncio.timeout(WAIT):
                while endpoint.connected or closed() < sessions:
                    await asyncio.sleep(0.002)

        fd = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        os.write(fd, b"AX LP111 AY LP-777 RP")
        assert await read_line(fd) == b"-777\n"
        os.close(fd)
        sessions = 1
        await settled(sessions)

        interleave = Interleave(monkeypatch)
        loop = asyncio.get_running_loop()
        b: list[int] = []  # B's descriptor, once it has opened

        def opens() -> None:
            b.append(os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK))

        def asks() -> None:
            os.write(b[0], b"AY RP")

        k = 0
        beyond = 0  # rounds in which the daemon was done before the k-th call
        while beyond < 2:
            a = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
            os.write(a, b"AX RP")
            if a_reads:
                assert await read_line(a) == b"111\n", f"k={k}"
            else:
                async with asyncio.timeout(WAIT):
                    while not select.select([a], [], [], 0)[0]:
                        await asyncio.sleep(0.001)
            b.clear()
            os.close(a)
            interleave.arm((k, opens), (k + later, asks))
            deadline = loop.time() + LEFT_ALONE
            while not interleave.fired and loop.time() < deadline:
                await asyncio.sleep(0.001)
            if not interleave.fired:
                beyond += 1
                while not interleave.fired:
                    interleave.fire()
            (fd,) = b
            try:
                answer = await read_line(fd)
                more = await rest(fd)
            finally:
                os.close(fd)
            assert (answer, more) == (b"-777\n", b""), f"k={k}: B was given {answer + more!r}"
            sessions += 2
            await settled(sessions)
            assert (opened(), closed()) == (sessions, sessions), f"k={k}"
            k += 1
        assert k + later > 10  # the daemon's steps after a close were all tried
