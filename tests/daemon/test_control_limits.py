"""The control server's bounds on what one peer may hold (:mod:`omsd.control.server`): the TCP
endpoint's connections (it is local and unauthenticated, like the dashboard, which holds at
most ``omsd.web.server.MAX_CONNECTIONS``)."""

from __future__ import annotations

import asyncio
import json

import pytest

import omsd.control.server
from omsd.control.server import ControlServer

from .inprocess import WAIT, service_of, serving, tcp_board

BOARDS = b'{"id": 1, "op": "boards"}\n'


async def _answered(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> bool:
    writer.write(BOARDS)
    reply = json.loads(await asyncio.wait_for(reader.readline(), WAIT))
    return bool(reply["ok"])


async def test_a_tcp_connection_beyond_the_cap_is_told_so_in_one_line_and_closed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Without a cap, anyone who could reach the control port could hold every file descriptor
    of the daemon (each connection also a task and a stream buffer), and its boards could take
    no client. Now at most ``MAX_CONNECTIONS`` (shortened here to 3) at once: one more gets one
    JSON line saying so and is closed; once one has gone, there is room again."""
    monkeypatch.setattr(omsd.control.server, "MAX_CONNECTIONS", 3, raising=False)
    async with serving(tcp_board("b1")) as daemon:
        control = ControlServer({"b1": service_of(daemon, "b1")}, lambda: [], daemon.log)
        host, port = await control.listen_tcp("127.0.0.1", 0)
        try:
            held = [await asyncio.open_connection(host, port) for _ in range(3)]
            for reader, writer in held:
                assert await _answered(reader, writer)
            reader, writer = await asyncio.open_connection(host, port)
            line = await asyncio.wait_for(reader.readline(), WAIT)
            assert json.loads(line) == {
                "id": None,
                "ok": False,
                "error": "too many control connections (3): try again later",
            }
            assert await asyncio.wait_for(reader.read(), WAIT) == b""  # closed
            writer.close()
            for _, w in held:  # the three it holds are served on
                w.write(BOARDS)
            for r, _ in held:
                assert json.loads(await asyncio.wait_for(r.readline(), WAIT))["ok"]
            _, gone = held.pop()
            gone.close()
            await gone.wait_closed()
            # the daemon notices the one that went (its read ends) and makes room
            for _ in range(int(WAIT / 0.01)):
                reader, writer = await asyncio.open_connection(host, port)
                writer.write(BOARDS)
                reply = json.loads(await asyncio.wait_for(reader.readline(), WAIT))
                if reply["ok"]:
                    break
                writer.close()
                await asyncio.sleep(0.01)
            assert reply["ok"], reply
            writer.close()
            for _, w in held:
                w.close()
        finally:
            await control.close()
