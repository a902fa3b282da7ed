"""TCP endpoints: a board on a socket, as a terminal server would put a serial board on the
network (EPICS talks to ``drvOmsPC68`` boards through an asyn IP port this way).

Policy for a second client (``second_client`` in the configuration): a board has one data
port, so one TCP client at a time. With ``takeover`` (the default) a new connection replaces the
one already there, which is closed; a client that died without closing its socket can thus
always reconnect. With ``refuse`` the newcomer gets one line saying the board is busy and is
closed. The pty of a board is not a connection and is not affected.

Each connection is a session of the board's service (:mod:`omsd.service`): when it goes, what it
wrote and the board has not taken is dropped, and what the board still says for it is not the
next client's. A client that shuts down its sending side (``nc -N``, ``shutdown(SHUT_WR)``) is
kept open until what it sent is done, at most the board's ``linger`` seconds, then closed.

With ``terminal`` on (for a client that puts its terminal in raw mode, such as ``socat
-,rawer TCP:HOST:PORT``), the endpoint edits a line at a time, shows what is typed and gives the
board's line ends as CR LF (:mod:`omsd.transport.terminal`); off, bytes pass untouched.
"""

from __future__ import annotations

import asyncio
import itertools
import os
from typing import cast

from omsd.hostport import host_port
from omsd.service import BoardService
from omsd.transport import bound_address
from omsd.transport.terminal import Terminal, terminal_for

# Bytes queued for a client that does not read before further output is dropped (logged once).
MAX_PENDING_OUTPUT = 256 * 1024
#: What one read takes from a socket at most (the service takes FEED_BITE of it at a time).
READ_SIZE = 64 * 1024

_serial = itertools.count(1)

# The one buffer every connection reads into (issue 16). asyncio's Protocol gets a new bytes
# object for each read, made 256 KiB large and then shrunk to what came, which for the few
# bytes of a command costs more than the command (an mmap, a page fault, an munmap each time);
# a BufferedProtocol gives asyncio a buffer to read into instead. The loop calls get_buffer,
# reads into it and calls buffer_updated at once, in one callback on its one thread, so all
# connections share one buffer: what buffer_updated does not hand on at once, it copies.
_READ_BUFFER = memoryview(bytearray(READ_SIZE))


class TcpClient(asyncio.BufferedProtocol):
    def __init__(
        self, service: BoardService, endpoint: str, policy: str, terminal: bool = False
    ) -> None:
        self.service = service
        self.endpoint = endpoint
        self.policy = policy
        self.terminal: Terminal | None = None
        if terminal:
            board = service.board
            self.terminal = terminal_for(service.link, lambda: board.interpreter.echo)
        elif type(self).send is TcpClient.send:
            # with no line editing the board's output goes to the socket as it is: send is
            # _write itself, one call less on every reply (issue 16); a subclass with a send
            # of its own (RFC 2217's, which paces) keeps it
            self.send = self._write  # type: ignore[method-assign]
        self.label = endpoint
        self.session = 0
        self.transport: asyncio.Transport | None = None
        self._pending = bytearray()
        self._paused = False
        self._dropping = False
        self.lingering = False  # it shut down its sending side and waits for its answers

    # -- asyncio.Protocol -----------------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)
        peer = self.transport.get_extra_info("peername")
        peer_text = host_port(peer[0], peer[1]) if isinstance(peer, tuple) else str(peer)
        self.label = f"{self.endpoint} #{next(_serial)} ({peer_text})"
        service = self.service
        if not service.faults.cable:  # control API: the cable is cut, nobody gets through
            service.log.info(f"{service.name}: {self.label} closed: the cable is cut")
            self.transport.close()
            self.transport = None
            return
        others = [c for c in service.clients if isinstance(c, TcpClient)]
        # one that has stopped sending and only waits for its answers does not hold the board
        # against a newcomer: it is taken over whatever the policy
        if any(not c.lingering for c in others) and self.policy == "refuse":
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

    def get_buffer(self, sizehint: int) -> memoryview:
        return _READ_BUFFER

    def buffer_updated(self, nbytes: int) -> None:
        if self.transport is None:
            return
        data = bytes(_READ_BUFFER[:nbytes])
        if self._pending or self.terminal is not None:
            self._take(data)
            self._push()
            return
        # the fast path: nothing held back from before and no line editing, so the bytes go to
        # the board as they came, and only what it does not take is kept (as _push would)
        taken = self.service.feed(self, data)
        if taken < nbytes:
            self._pending += data[taken:]
            self._flow()

    def data_received(self, data: bytes) -> None:
        """Bytes the client wrote (what :meth:`buffer_updated` does, for a caller with bytes)."""
        if self.transport is None:
            return
        self._take(data)
        self._push()

    def _take(self, data: bytes) -> None:
        """What the client wrote, for the board (through the terminal's line editing)."""
        if self.terminal is not None:
            data, screen = self.terminal.typed(data)
            if screen:
                self._write(screen)
        self._pending += data

    def eof_received(self) -> bool:
        """The client shut down its sending side: keep the connection (True) while what it sent
        is still to be answered (``linger``); close our side too (False) when nothing is."""
        if self.transport is None:
            return False
        keep = self.service.half_closed(self)
        self.lingering = keep
        if keep:
            self.service.log.info(
                f"{self.service.name}: {self.label} stopped sending; kept open for its answers"
            )
        return keep

    def connection_lost(self, exc: Exception | None) -> None:
        if self.transport is not None:
            self.service.log.info(f"{self.service.name}: {self.label} disconnected")
        self.transport = None
        self.service.end_session(self, len(self._pending), "disconnected")
        self.service.detach(self)
        self._pending = bytearray()

    # -- the service's side ---------------------------------------------------------------------

    @property
    def unsent(self) -> int:
        return len(self._pending)

    def finish(self) -> None:
        """Close once what has been written to the socket has gone (asyncio flushes first)."""
        self.close()

    def _push(self) -> None:
        if self._pending:
            taken = self.service.feed(self, bytes(self._pending))
            del self._pending[:taken]
        self._flow()

    def _flow(self) -> None:
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
        """The board's output for the client (with the terminal option: as the terminal shows
        it). Without the option each connection's ``send`` is :meth:`_write` (see __init__)."""
        if self.terminal is not None:
            data = self.terminal.shown(data)
        self._write(data)

    def _write(self, data: bytes) -> None:
        transport = self.transport
        if transport is None or transport.is_closing() or not data:
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
        """Close this connection for a newcomer. Bytes already in the socket that asyncio has
        not read yet (the old client may have written and hung up in the same instant the new
        one connected) are offered to the board first, as this client's: what the board takes
        runs (as on the card, which had them on its wire), its answers are discarded with the
        session, and what it cannot take is dropped."""
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
                self._take(data)
        if self._pending:
            self._push()
        self.service.end_session(self, len(self._pending), "taken over")
        self.service.detach(self)
        self._pending = bytearray()
        self.close()

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()

    def cut(self) -> None:
        """The cable was cut (control API): the client sees EOF; what it wrote and the board has
        not taken is lost with the cable."""
        self.service.end_session(self, len(self._pending), "cut off")
        self.service.detach(self)
        self._pending = bytearray()
        self.close()


async def serve_tcp(
    service: BoardService, host: str, port: int, policy: str, terminal: bool = False
) -> tuple[asyncio.Server, str, int]:
    """Listen for the board; returns the server and the address actually bound (port 0 asks
    the system for a free port). ``terminal``: each client gets the terminal option."""
    loop = asyncio.get_running_loop()
    label = [f"tcp:{host_port(host, port)}"]
    server = await loop.create_server(
        lambda: TcpClient(service, label[0], policy, terminal), host, port, reuse_address=True
    )
    bound = bound_address(server, host)
    label[0] = f"tcp:{host_port(*bound)}"
    return server, *bound
