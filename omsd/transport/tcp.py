"""TCP endpoints: a board on a socket, as a terminal server would put a serial board on the
network (EPICS talks to ``drvOmsPC68`` boards through an asyn IP port this way).

Policy for a second client (``second_client`` in the configuration): a board has one data
port, so one TCP client at a time. With ``takeover`` (the default) a new connection replaces the
one already there, which is closed; a client that died without closing its socket can thus
always reconnect. With ``refuse`` the newcomer gets one line saying the board is busy and is
closed. The pty of a board is not a connection and is not affected.
"""

from __future__ import annotations

import asyncio
import itertools
import os
from typing import cast

from omsd.service import BoardService

# Bytes queued for a client that does not read before further output is dropped (logged once).
MAX_PENDING_OUTPUT = 256 * 1024

_serial = itertools.count(1)


class TcpClient(asyncio.Protocol):
    def __init__(self, service: BoardService, endpoint: str, policy: str) -> None:
        self.service = service
        self.endpoint = endpoint
        self.policy = policy
        self.label = endpoint
        self.transport: asyncio.Transport | None = None
        self._pending = bytearray()
        self._paused = False
        self._dropping = False

    # -- asyncio.Protocol -----------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)
        peer = self.transport.get_extra_info("peername")
        peer_text = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        self.label = f"{self.endpoint} #{next(_serial)} ({peer_text})"
        service = self.service
        if not service.faults.cable:  # control API: the cable is cut, nobody gets through
            service.log.info(f"{service.name}: {self.label} closed: the cable is cut")
            self.transport.close()
            self.transport = None
            return
        others = [c for c in service.clients if isinstance(c, TcpClient)]
        if others and self.policy == "refuse":
            service.log.warning(f"{service.name}: refused {self.label}: board busy")
            self.transport.write(
                f"omsd: board {service.name} is busy: another client is connected\r\n".encode()
            )
            self.transport.close()
            self.transport = None
            return
        for other in others:
            service.log.warning(f"{service.name}: {self.label} takes over from {other.label}")
            other.hand_over()
        service.log.info(f"{service.name}: {self.label} connected")
        service.attach(self)

    def data_received(self, data: bytes) -> None:
        if self.transport is None:
            return
        self._pending += data
        self._push()

    def eof_received(self) -> bool:
        return False  # close our side too

    def connection_lost(self, exc: Exception | None) -> None:
        if self.transport is not None:
            self.service.log.info(f"{self.service.name}: {self.label} disconnected")
        self.transport = None
        self.service.detach(self)
        # what the client wrote before it went is still the board's input
        if self._pending:
            self.service.orphan_input(bytes(self._pending))
            self._pending = bytearray()

    # -- the service's side ---------------------------------------------------------------------

    def _push(self) -> None:
        if self._pending:
            taken = self.service.feed(self, bytes(self._pending))
            del self._pending[:taken]
        transport = self.transport
        if transport is None:
            return
        # hold the client off while the board cannot take its bytes (TCP flow control does
        # the rest, as TBE_S would on the card)
        if self._pending and not self._paused:
            transport.pause_reading()
            self._paused = True
        elif not self._pending and self._paused:
            transport.resume_reading()
            self._paused = False

    def input_room(self) -> None:
        self._push()

    def send(self, data: bytes) -> None:
        transport = self.transport
        if transport is None or transport.is_closing():
            return
        if transport.get_write_buffer_size() > MAX_PENDING_OUTPUT:
            if not self._dropping:
                self.service.log.warning(
                    f"{self.service.name}: {self.label} is not reading; dropping output"
                )
            self._dropping = True
            return
        self._dropping = False
        transport.write(data)

    def hand_over(self) -> None:
        """Close this connection for a newcomer, keeping what it wrote: bytes already in the
        socket that asyncio has not read yet (the old client may have written and hung up in
        the same instant the new one connected) go to the board first."""
        transport = self.transport
        if transport is None:
            return
        sock = transport.get_extra_info("socket")
        if sock is not None:
            fd = sock.fileno()
            while fd >= 0:
                try:
                    data = os.read(fd, 65536)
                except OSError:  # BlockingIOError: nothing more now; others: the socket is gone
                    break
                if not data:
                    break
                self._pending += data
        self.service.detach(self)
        if self._pending:
            self.service.orphan_input(bytes(self._pending))
            self._pending = bytearray()
        self.close()

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()

    def cut(self) -> None:
        """The cable was cut (control API): the client sees EOF; what it wrote and the board has
        not taken is lost with the cable."""
        self._pending = bytearray()
        self.service.detach(self)
        self.close()


async def serve_tcp(
    service: BoardService, host: str, port: int, policy: str
) -> tuple[asyncio.Server, str, int]:
    """Listen for the board; returns the server and the address actually bound (port 0 asks
    the system for a free port)."""
    loop = asyncio.get_running_loop()
    label = [f"tcp:{host}:{port}"]
    server = await loop.create_server(
        lambda: TcpClient(service, label[0], policy), host, port, reuse_address=True
    )
    bound = server.sockets[0].getsockname()
    label[0] = f"tcp:{bound[0]}:{bound[1]}"
    return server, str(bound[0]), int(bound[1])
