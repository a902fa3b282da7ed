"""Being told when a file is opened and closed (Linux inotify), for the pty endpoints.

A pty master learns that the last client closed the slave (POLLHUP, reads fail with EIO) but
not that a client opened it, nor that the last client closed it and another opened it again
before the master looked. ``inotify(7)`` reports opens and closes of the slave device on devpts
like those of any file, in the order they happened, so a pty endpoint can follow its clients
without a timer.

Identical events that follow each other unread are merged by the kernel ("coalesced"), so two
programs opening the pty in the same instant may be reported as one open; the caller checks
its count against POLLHUP where it matters. A close is reported as one of two kinds (a
descriptor that could write, or one that could only read): events of different kinds are never
merged, which lets the pty endpoint tell its own read-only flush from its clients.

The standard library has no inotify; this is the three calls it needs, through ``ctypes``. Where
they are missing (not Linux) :func:`watch_opens` returns ``None`` and the caller does without.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import os
import select
import struct
from collections.abc import Callable

IN_CLOSE_WRITE = 0x00000008
IN_CLOSE_NOWRITE = 0x00000010
IN_OPEN = 0x00000020
OPENED = "open"
CLOSED = "close"
#: A close of a descriptor opened without write access (IN_CLOSE_NOWRITE): a reader such as
#: ``cat``, or the pty endpoint's own moment on the slave to flush it. Reported apart so that
#: it is never merged with a close of a program that opened the pty to write (IN_CLOSE_WRITE).
CLOSED_READER = "close-reader"
_EVENT = struct.Struct("iIII")  # wd, mask, cookie, len (then len bytes of name)
_MASK = IN_OPEN | IN_CLOSE_WRITE | IN_CLOSE_NOWRITE


class OpenWatch:
    """Calls ``on_events`` (from the event loop's reader, or :meth:`drain`) with the opens and
    closes of the watched file since the last call, in order (:data:`OPENED`, :data:`CLOSED`,
    :data:`CLOSED_READER`)."""

    def __init__(
        self, fd: int, libc: ctypes.CDLL, path: str, on_events: Callable[[list[str]], None]
    ) -> None:
        self.fd = fd
        self._libc = libc
        self._path = os.fsencode(path)
        self._wd = -1
        self.on_events = on_events
        # is anything queued? one poll(2) of the descriptor, no read and no exception (issue 16:
        # the pty asks before every read of its master)
        self._poller = select.poll()
        self._poller.register(fd, select.POLLIN)

    def start(self) -> bool:
        """Start watching; False if the system refuses."""
        self._wd = int(self._libc.inotify_add_watch(self.fd, self._path, _MASK))
        return self._wd >= 0

    def readable(self) -> None:
        self.drain()

    def queued(self) -> bool:
        """Whether opens or closes are waiting to be read (cheap: no read, no exception)."""
        return bool(self._poller.poll(0))

    def drain(self) -> None:
        events = self._read()
        if events:
            self.on_events(events)

    def _read(self) -> list[str]:
        events: list[str] = []
        while self.fd >= 0:
            try:
                data = os.read(self.fd, 4096)
            except OSError:  # BlockingIOError: nothing more now
                break
            if not data:
                break
            offset = 0
            while offset + _EVENT.size <= len(data):
                _wd, mask, _cookie, length = _EVENT.unpack_from(data, offset)
                offset += _EVENT.size + length
                if mask & IN_OPEN:
                    events.append(OPENED)
                if mask & IN_CLOSE_WRITE:
                    events.append(CLOSED)
                if mask & IN_CLOSE_NOWRITE:
                    events.append(CLOSED_READER)
        return events

    def pending(self) -> list[str]:
        """Read what has been queued since, without handing it on (the caller takes it)."""
        return self._read()

    def close(self) -> None:
        if self.fd >= 0:
            with contextlib.suppress(OSError):
                os.close(self.fd)
            self.fd = -1


@functools.cache  # once per process (issue 16)
def _libc() -> ctypes.CDLL | None:
    # the C library's calls as the process already has them (dlopen(NULL), as omsd.wakeups):
    # ctypes.util.find_library("c") would run ldconfig for its name, ~2.5 ms at start-up
    try:
        libc = ctypes.CDLL(None, use_errno=True)
    except OSError:
        return None
    for name in ("inotify_init1", "inotify_add_watch"):
        if not hasattr(libc, name):
            return None
    return libc


def watch_opens(path: str, on_events: Callable[[list[str]], None]) -> OpenWatch | None:
    """An inotify descriptor (non-blocking) watching ``path`` for opens and closes, or ``None``
    if this system cannot; add :meth:`OpenWatch.readable` as its reader on the event loop."""
    libc = _libc()
    if libc is None:
        return None
    fd = int(libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC))
    if fd < 0:
        return None
    watch = OpenWatch(fd, libc, path, on_events)
    if not watch.start():
        watch.close()
        return None
    return watch
