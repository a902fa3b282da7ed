"""Where boards are served: TCP (:mod:`omsd.transport.tcp`), ptys (:mod:`omsd.transport.pty`),
serial devices (:mod:`omsd.transport.serial`) and RFC 2217 sockets
(:mod:`omsd.transport.rfc2217`)."""

from __future__ import annotations

import errno
import os
import socket
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import asyncio


@dataclass(frozen=True)
class Endpoint:
    """One place a board is served, as the daemon announces it (and the control API lists it)."""

    board: str
    model: str
    link: str
    kind: str  # "tcp", "pty", "serial" or "rfc2217"
    # "127.0.0.1:7048", "/run/omsd/board1 -> /dev/pts/3", "/dev/ttyUSB0,9600,8N1"
    address: str

    def line(self) -> str:
        return f"{self.board} {self.model} {self.link} {self.kind} {self.address}"


def bound_address(server: asyncio.Server, host: str) -> tuple[str, int]:
    """The address ``server`` listens at. asyncio's ``create_server`` skips, without a word, a
    socket it cannot make (out of file descriptors), and gave a server listening nowhere: then
    it is closed and the socket made again here, to raise the reason as an OSError."""
    if not server.sockets:
        server.close()
        socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET).close()
        raise OSError(errno.EADDRNOTAVAIL, os.strerror(errno.EADDRNOTAVAIL))
    address = server.sockets[0].getsockname()
    return str(address[0]), int(address[1])
