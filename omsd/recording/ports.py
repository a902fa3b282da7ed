"""The recorder's byte pipes: non-blocking file descriptors on the event loop.

A serial port, a TCP socket and a pty's master are all file descriptors that ``read(2)`` and
``write(2)`` move bytes through; :class:`Port` reads one whenever the loop says it is readable
(``add_reader``) and writes to it at once, keeping what the descriptor cannot take yet and
writing it when it can (``add_writer``). No protocol object, no buffering beyond that: what
comes in is handed on in the same callback, so the recorder adds no latency of its own.

Flow control is passed through, not replaced: when more than :data:`HIGH_WATER` bytes wait to
go out of a port, the port the bytes come from is no longer read until they have gone (then the
sender's own flow control holds it back: TCP's window, a tty's buffer), so nothing is dropped
and nothing grows without bound.
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import os
from collections.abc import Callable

READ_SIZE = 65536
HIGH_WATER = 64 * 1024
"""Bytes waiting to go out of a port before its source is paused."""


class Port:
    """One descriptor on the loop. ``on_data(bytes)`` for what is read; ``on_gone(why)`` once,
    when the other side closed (``why``: ``"closed"``) or the descriptor failed (its error);
    ``closer`` closes the descriptor (the socket's or the serial port's own ``close``).
    ``on_eof``, if given, is called instead of ``on_gone`` when the other side has only stopped
    sending (a TCP client's ``shutdown(SHUT_WR)``): the port is no longer read, and can still be
    written until it is closed."""

    def __init__(
        self,
        loop: asyncio.AbstractEventLoop,
        fd: int,
        on_data: Callable[[bytes], None],
        on_gone: Callable[[str], None],
        closer: Callable[[], None],
        on_eof: Callable[[], None] | None = None,
    ) -> None:
        self.loop = loop
        self.fd = fd
        self.on_data = on_data
        self.on_gone = on_gone
        self.on_eof = on_eof
        self.eof = False
        self._closer = closer
        self._backlog = bytearray()
        self._reading = False
        self._writing = False
        self.source: Port | None = None
        """The port whose bytes this one writes: paused while too many wait here."""
        self.resume()

    # -- reading ------------------------------------------------------------------------------

    def pause(self) -> None:
        if self._reading:
            self.loop.remove_reader(self.fd)
            self._reading = False

    def resume(self) -> None:
        if not self._reading and self.fd >= 0 and not self.eof:
            self.loop.add_reader(self.fd, self._readable)
            self._reading = True

    def _readable(self) -> None:
        try:
            data = os.read(self.fd, READ_SIZE)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._gone(_reason(exc))
            return
        if not data:
            if self.on_eof is not None:
                self.eof = True
                self.pause()
                self.on_eof()
            else:
                self._gone("closed")
            return
        self.on_data(data)

    # -- writing ------------------------------------------------------------------------------

    def write(self, data: bytes) -> None:
        """Write ``data`` now, or as soon as the descriptor takes it (in order)."""
        if self.fd < 0 or not data:
            return
        if not self._backlog:
            try:
                n = os.write(self.fd, data)
            except (BlockingIOError, InterruptedError):
                n = 0
            except OSError as exc:
                self._gone(_reason(exc))
                return
            if n == len(data):
                return
            data = data[n:]
        self._backlog += data
        self._flush()

    def _flush(self) -> None:
        while self._backlog:
            try:
                n = os.write(self.fd, self._backlog)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:
                self._gone(_reason(exc))
                return
            del self._backlog[:n]
        if self._backlog and not self._writing:
            self.loop.add_writer(self.fd, self._flush)
            self._writing = True
        elif not self._backlog and self._writing:
            self.loop.remove_writer(self.fd)
            self._writing = False
        source = self.source
        if source is not None:
            if len(self._backlog) > HIGH_WATER:
                source.pause()
            elif not self._backlog:
                source.resume()

    @property
    def waiting(self) -> int:
        """Bytes written that the descriptor has not taken yet."""
        return len(self._backlog)

    # -- the end ------------------------------------------------------------------------------

    def _gone(self, why: str) -> None:
        if self.fd < 0:
            return
        self.close()
        self.on_gone(why)

    def close(self) -> None:
        """Stop reading and writing and close the descriptor (what waits to be written is
        dropped); later calls do nothing."""
        if self.fd < 0:
            return
        self.pause()
        if self._writing:
            self.loop.remove_writer(self.fd)
            self._writing = False
        self._backlog.clear()
        self.fd = -1
        with contextlib.suppress(OSError):
            self._closer()


def _reason(exc: OSError) -> str:
    if exc.errno in (errno.ECONNRESET, errno.EPIPE):
        return "connection reset"
    if exc.errno == errno.EIO:
        return "input/output error (the device is gone)"
    return (exc.strerror or str(exc)).lower()


__all__ = ["HIGH_WATER", "Port"]
