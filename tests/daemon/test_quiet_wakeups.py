"""The daemon wakes a board only when its host could hear something (issue 16: the services
arm their timers at ``link.next_wakeup``; :mod:`omsd.engine.quiet`), on a daemon served in this
process.

A client's queue of plain moves arms no wake-up: the moves run at their own times, and a poll
afterwards finds the axis where the manual's profiles put it. An ID queued after them arms one
at once, for the end of the last move, and the done comes then. Someone watching the board (an
observer: the MQTT bridge, a control client's subscription) is woken at every deadline, as
before.
"""

from __future__ import annotations

import asyncio
import dataclasses
import io

from omsd.config import BoardConfig
from omsd.control.server import ControlServer
from omsd.service import BoardService

from .inprocess import WAIT, ask, connect, service_of, serving, tcp_board


async def test_queued_moves_arm_no_wakeup_and_a_done_after_them_does() -> None:
    async with serving(tcp_board("q1")) as daemon:
        service = service_of(daemon, "q1")
        reader, writer = await connect(daemon, "q1")
        try:
            # 0.18 s a move: 300 steps with AC40000 never reach VL4000 (a triangle, 0.087 s up
            # and as long down)
            await ask(reader, writer, b"AZ VL4000 AC40000 MR300 GO MR-300 GO MR300 GO WY\n")
            assert service.link.next_deadline() is not None  # the moves' ends...
            assert service._timer is None  # ...wake nobody
            await asyncio.sleep(1.0)  # the three moves are over
            assert await ask(reader, writer, b"AZ RP\n") == b"300\n"
            assert service._timer is None
            await ask(reader, writer, b"AZ MR-300 GO MR300 GO WY\n")
            assert service._timer is None
            loop = asyncio.get_running_loop()
            await ask(reader, writer, b"AZ ID WY\n")  # from now on the axis is heard
            end = service.link.next_deadline()
            assert service._timer is not None and end is not None
            assert service._timer_at == service.timebase.to_loop(end)
            # the done: the driver's "!" and the done flag register's byte, when the last
            # move ends (the timing itself is the benchmark's: bench/fidelity.py)
            marker = await asyncio.wait_for(reader.readline(), WAIT)
            assert marker == b"!\x04\n"  # Z's done flag
            assert loop.time() >= service.timebase.to_loop(end)
            assert await ask(reader, writer, b"AZ RP\n") == b"300\n"
        finally:
            writer.close()


async def test_an_observer_wakes_the_board_at_every_deadline() -> None:
    class Watcher:
        changes = 0

        def traffic(self, service: BoardService, record: object) -> None:
            pass

        def event(self, service: BoardService, when: float, event: object) -> None:
            pass

        def changed(self, service: BoardService) -> None:
            self.changes += 1

    async with serving(tcp_board("q2")) as daemon:
        service = service_of(daemon, "q2")
        watcher = Watcher()
        service.observers.append(watcher)  # type: ignore[arg-type]
        reader, writer = await connect(daemon, "q2")
        try:
            await ask(reader, writer, b"AZ VL4000 AC40000 MR300 GO MR-300 GO WY\n")
            deadline = service.link.next_deadline()
            assert deadline is not None
            assert service._timer_at == service.timebase.to_loop(deadline)
            seen = watcher.changes
            await asyncio.sleep(1.0)
            assert watcher.changes >= seen + 2  # each move's end, as it came
        finally:
            service.observers.remove(watcher)  # type: ignore[arg-type]
            writer.close()


# -- who reads the board between its wake-ups runs it first (found in review) --------------------

LINGER = 60.0  # far longer than any wait below: a close that comes is the move's end, not this


def lingering(name: str) -> BoardConfig:
    return dataclasses.replace(tcp_board(name), linger=LINGER)


async def closed(reader: asyncio.StreamReader) -> bool:
    """The daemon closed the connection (EOF) within the tests' wait; False if it kept it."""
    try:
        return await asyncio.wait_for(reader.read(), WAIT) == b""
    except TimeoutError:
        return False


async def test_a_client_that_stops_sending_after_its_quiet_moves_ended_is_closed() -> None:
    """The moves ended while no wake-up ran the board: the half-close runs it first, finds the
    session idle, and closes at once (it used to see the last move still running and keep the
    client for the whole linger time)."""
    out = io.StringIO()
    async with serving(lingering("q3"), out=out) as daemon:
        service = service_of(daemon, "q3")
        reader, writer = await connect(daemon, "q3")
        await ask(reader, writer, b"AZ VL4000 AC40000 MR300 GO MR-300 GO WY\n")
        assert service._timer is None
        await asyncio.sleep(0.6)  # both moves are over; nothing has run the board since
        writer.write_eof()
        assert await closed(reader)
        writer.close()
    assert "after it stopped sending" not in out.getvalue()


async def test_a_client_that_stops_sending_during_its_quiet_moves_is_closed_when_they_end() -> None:
    """Kept open for its answers while the moves run, the client makes the board woken at every
    deadline: it is closed when the last move ends, not when the linger time runs out."""
    out = io.StringIO()
    async with serving(lingering("q4"), out=out) as daemon:
        service = service_of(daemon, "q4")
        reader, writer = await connect(daemon, "q4")
        await ask(reader, writer, b"AZ VL4000 AC40000 MR300 GO MR-300 GO WY\n")
        writer.write_eof()
        assert await closed(reader)
        assert not service.board.axes[2].moving
        writer.close()
    assert "after it stopped sending" not in out.getvalue()


async def test_a_control_wait_for_a_position_sees_the_move_under_way() -> None:
    """``wait until=position`` reads where the axis is and where its motion began: the board is
    run to now first. Here the first of two queued moves ended while nothing ran the board; the
    second, heading back down through 500, has not passed it yet, so the wait must not end at
    once (it used to see the first move, which had passed 500)."""
    async with serving(tcp_board("q5")) as daemon:
        service = service_of(daemon, "q5")
        reader, writer = await connect(daemon, "q5")
        try:
            # 0 to 1000 in about 1.01 s, then back to 0: at 1.3 s the axis is near 700, going down
            await ask(reader, writer, b"AZ VL1000 AC100000 MR1000 GO MR-1000 GO WY\n")
            assert service._timer is None
            await asyncio.sleep(1.3)
            control = ControlServer({"q5": service}, lambda: [], daemon.log)
            state = await control._wait(
                service, {"until": "position", "axis": "Z", "position": 500, "timeout": WAIT}
            )
            assert state["axes"]["Z"]["position"] <= 500
        finally:
            writer.close()
