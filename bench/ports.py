"""Blocking clients of a board: a TCP socket or the pty's slave device, every read bounded.

Both wait with ``poll`` and read what is there, so the client does the same work whichever
server answers; nothing waits for ever (a missing reply is an error naming what did come).
"""

from __future__ import annotations

import os
import select
import socket
import termios
import time
import tty
from typing import Self

TIMEOUT = 10.0


class Port:
    """A byte stream to a server, with a receive buffer."""

    fd: int

    def __init__(self) -> None:
        self.buffer = bytearray()
        self.poller = select.poll()

    def _start(self, fd: int) -> None:
        self.fd = fd
        self.poller.register(fd, select.POLLIN)

    def write(self, data: bytes) -> None:
        raise NotImplementedError

    def _read(self) -> bytes:
        raise NotImplementedError

    def fill(self, deadline: float) -> None:
        """Wait for bytes until ``deadline`` and add them to the buffer."""
        left = deadline - time.monotonic()
        if left <= 0 or not self.poller.poll(left * 1000.0):
            raise TimeoutError(f"no reply; got {bytes(self.buffer)[-200:]!r}")
        data = self._read()
        if not data:
            raise ConnectionError(f"end of stream; got {bytes(self.buffer)[-200:]!r}")
        self.buffer += data

    def read_exact(self, n: int, timeout: float = TIMEOUT) -> bytes:
        deadline = time.monotonic() + timeout
        while len(self.buffer) < n:
            self.fill(deadline)
        data = bytes(self.buffer[:n])
        del self.buffer[:n]
        return data

    def read_until(self, end: bytes, timeout: float = TIMEOUT) -> bytes:
        deadline = time.monotonic() + timeout
        while (i := self.buffer.find(end)) < 0:
            self.fill(deadline)
        data = bytes(self.buffer[: i + len(end)])
        del self.buffer[: i + len(end)]
        return data

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class TcpPort(Port):
    def __init__(self, address: tuple[str, int]) -> None:
        super().__init__()
        self.sock = socket.create_connection(address, timeout=TIMEOUT)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._start(self.sock.fileno())

    def write(self, data: bytes) -> None:
        self.sock.sendall(data)

    def _read(self) -> bytes:
        try:
            return self.sock.recv(1 << 20)
        except ConnectionResetError:
            return b""

    def close(self) -> None:
        self.sock.close()


class PtyPort(Port):
    """The slave side of a pty, opened through its symlink and made raw."""

    def __init__(self, path: str) -> None:
        super().__init__()
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(fd, termios.TCSANOW)
        self._start(fd)

    def write(self, data: bytes) -> None:
        view = memoryview(data)
        while view:
            n = os.write(self.fd, view)
            view = view[n:]

    def _read(self) -> bytes:
        return os.read(self.fd, 65536)

    def close(self) -> None:
        os.close(self.fd)
