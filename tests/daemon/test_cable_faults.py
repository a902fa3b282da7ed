"""A faulty cable (the control API's faults) on a daemon served in this process: what a client
writes is never stuck behind a full wire, and what is still on the wire when the cable is healed
keeps its order with what comes after (found in review; the fast paths take over once the cable
is whole and nothing is left on it)."""

from __future__ import annotations

import asyncio

import pytest

from omsd.faults import Faults

from .inprocess import WAIT, ask, connect, service_of, serving, tcp_board


async def test_a_client_held_back_by_a_full_wire_is_called_again_when_it_drains() -> None:
    """A driver ``!`` wait holds the board while the faulty wire fills up to its limit; when
    the done releases the wait, the board has room but the wire has none: the client must be
    called again once the wire drains, and every request answered."""
    polls = 30_000
    async with serving(tcp_board("c1")) as daemon:
        service = service_of(daemon, "c1")
        service.set_faults(Faults(garble=1e-15))  # "damaging", but damages nothing
        reader, writer = await connect(daemon, "c1")
        try:
            writer.write(b"AX MR60000 GO ID !\r" + b"AX RP\r" * 2000)
            await asyncio.sleep(0.1)
            writer.write(b"AX RP\r" * (polls - 2000) + b"WY\r")
            got = bytearray()
            while b"ver" not in got:
                got += await asyncio.wait_for(reader.read(65536), WAIT)
            assert got.count(b"0\n") == polls
        finally:
            writer.close()


@pytest.mark.parametrize(
    ("name", "faults"),
    [
        ("c2", Faults(latency=0.3)),  # the answer to WY is on its way out when healed
        ("c3", Faults(baud=300)),  # 30 characters a second: "Y\r" still on its way in
    ],
    ids=["reply-on-the-cable", "bytes-on-the-wire"],
)
async def test_what_is_on_the_cable_when_it_is_healed_keeps_its_order(
    name: str, faults: Faults
) -> None:
    async with serving(tcp_board(name)) as daemon:
        service = service_of(daemon, name)
        reader, writer = await connect(daemon, name)
        try:
            service.set_faults(faults)
            writer.write(b"WY\r")
            await writer.drain()
            await asyncio.sleep(0.05)
            assert service._inbound or not service._out.idle  # something is on the cable
            service.set_faults(Faults())
            assert await ask(reader, writer, b"AX RP\r", 2) == b"PC48 ver 3.00-4\n0\n"
        finally:
            writer.close()
