"""The control server's bounds on what one peer may hold (:mod:`omsd.control.server`): the TCP
endpoint's connections (it is local and unauthenticated, like the dashboard, which holds at
most ``omsd.web.server.MAX_CONNECTIONS``)."""

from __future__ import annotations

import asyncio
import json

import pytest

import omsd.control.server
from omsd.control.server import ControlServer

from .inprocess import WAIT, ask, connect, service_of, serving, tcp_board

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


async def test_the_waits_on_a_board_are_looked_at_together() -> None:
    """Each wait watched its board on its own: an observer of its own, woken at every change,
    and a wait for a position also ran the board and looked every 2 ms by itself. 256 waits for
    a position on a moving axis took 77-82 % of a core. A board's waits are now one observer
    (and one poll), whatever their number and kind; the waits still end each when its own
    condition holds, and when the last has gone the board has no observer left."""
    async with serving(tcp_board("b1")) as daemon:
        service = service_of(daemon, "b1")
        control = ControlServer({"b1": service}, lambda: [], daemon.log)
        await control.run({"op": "time", "board": "b1", "action": "pause"})
        await control.run({"op": "boards"})
        reader, writer = await connect(daemon, "b1")
        try:
            await ask(reader, writer, b"AX VL1000 AC100000 MR1000 GO ID WY\n")
            far = {"op": "wait", "board": "b1", "axis": "X", "timeout": WAIT}
            waits = [
                asyncio.create_task(control.run({**far, "until": "position", "position": p}))
                for p in range(100, 1000, 20)
            ]
            waits += [
                asyncio.create_task(control.run({**far, "until": u})) for u in ("done", "idle")
            ]
            for _ in range(10):
                await asyncio.sleep(0)
            assert not any(w.done() for w in waits)  # time is paused: the axis stands at 0
            assert len(service.observers) == 1, service.observers
            await control.run({"op": "time", "board": "b1", "action": "step", "seconds": 0.5})
            for _ in range(10):
                await asyncio.sleep(0)
            ended = [w for w in waits if w.done()]
            assert 0 < len(ended) < len(waits) - 2  # those it has passed, not the others
            assert len(service.observers) == 1
            await control.run({"op": "time", "board": "b1", "action": "step", "seconds": 2.0})
            states = await asyncio.wait_for(asyncio.gather(*waits), WAIT)
            assert all(s["axes"]["X"]["position"] >= 100 for s in states)
            assert service.observers == []  # the last wait gone, nothing watches the board
        finally:
            writer.close()
            await control.close()
