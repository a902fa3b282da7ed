"""Pseudo-terminal endpoints: a board that looks like a serial port to any program.

A legacy application, a terminal emulator (picocom, minicom, screen) or ``cat`` opens the pty's
slave device through a stable symlink and talks to the board. The daemon:

* creates the pty raw (no echo, no CR/LF translation, no signal characters), so bytes pass
  through untouched whatever the client sets up;
* keeps the slave open for its whole life: otherwise the master sees EIO (and a read loop spins)
  every time the last client closes; with the slave held, clients open, close and reopen it any
  number of times and the board never notices;
* gives the slave device group permissions (mode 0660 by default, optionally another group) so
  users of that group can open it;
* points the symlink at the slave atomically (a new link is renamed over the old one) and
  removes it on exit if it still points at this pty.

Output written while no client has the pty open waits in the terminal's buffer like bytes on a
serial line nobody is reading; beyond what the kernel buffers, and a bounded backlog here, it
is dropped (a serial port would overwrite it too).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import grp
import os
import pathlib
import termios
import tty

from omsd.service import BoardService

MAX_BACKLOG = 64 * 1024


class PtyEndpoint:
    def __init__(
        self, service: BoardService, link: pathlib.Path, group: str | None = None, mode: int = 0o660
    ) -> None:
        self.service = service
        self.link = link
        self.group = group
        self.mode = mode
        self.label = f"pty:{link}"
        self.master = -1
        self.slave = -1
        self.device = ""
        self._pending = bytearray()
        self._backlog = bytearray()
        self._reading = False
        self._writing = False
        self._loop: asyncio.AbstractEventLoop | None = None

    def open(self) -> str:
        """Create the pty and its symlink; returns the slave device path."""
        self._loop = asyncio.get_running_loop()
        self.master, self.slave = os.openpty()
        try:
            tty.setraw(self.slave, termios.TCSANOW)
            os.set_blocking(self.master, False)
            self.device = os.ttyname(self.slave)
            gid = grp.getgrnam(self.group).gr_gid if self.group else -1
            os.chown(self.device, -1, gid)
            os.chmod(self.device, self.mode)
            self._place_link()
        except BaseException:
            self._close_fds()
            raise
        self._loop.add_reader(self.master, self._readable)
        self._reading = True
        self.service.attach(self)
        return self.device

    def _place_link(self) -> None:
        self.link.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.link.with_name(f".{self.link.name}.{os.getpid()}.tmp")
        if tmp.is_symlink() or tmp.exists():
            tmp.unlink()
        os.symlink(self.device, tmp)
        os.replace(tmp, self.link)

    # -- input ----------------------------------------------------------------------------------

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 4096)
        except BlockingIOError:
            return
        except OSError as exc:
            if exc.errno == errno.EIO:  # pragma: no cover - the slave is held open
                return
            raise
        if data:
            self._pending += data
            self._push()

    def _push(self) -> None:
        if self._pending:
            taken = self.service.feed(self, bytes(self._pending))
            del self._pending[:taken]
        loop = self._loop
        if loop is None or self.master < 0:
            return
        if self._pending and self._reading:
            loop.remove_reader(self.master)
            self._reading = False
        elif not self._pending and not self._reading:
            loop.add_reader(self.master, self._readable)
            self._reading = True

    def input_room(self) -> None:
        self._push()

    # -- output ---------------------------------------------------------------------------------

    def send(self, data: bytes) -> None:
        if self.master < 0:
            return
        self._backlog += data
        if len(self._backlog) > MAX_BACKLOG:
            del self._backlog[: len(self._backlog) - MAX_BACKLOG]
        self._flush()

    def _flush(self) -> None:
        while self._backlog:
            try:
                n = os.write(self.master, self._backlog)
            except BlockingIOError:
                break
            except OSError:
                self._backlog.clear()
                break
            del self._backlog[:n]
        loop = self._loop
        if loop is None:
            return
        if self._backlog and not self._writing:
            loop.add_writer(self.master, self._flush)
            self._writing = True
        elif not self._backlog and self._writing:
            loop.remove_writer(self.master)
            self._writing = False

    # -- life -----------------------------------------------------------------------------------

    def close(self) -> None:
        self.service.detach(self)
        loop = self._loop
        if loop is not None and self.master >= 0:
            if self._reading:
                loop.remove_reader(self.master)
            if self._writing:
                loop.remove_writer(self.master)
        self._reading = self._writing = False
        try:
            if self.link.is_symlink() and os.readlink(self.link) == self.device:
                self.link.unlink()
        except OSError:
            pass
        self._close_fds()

    def _close_fds(self) -> None:
        for fd in (self.master, self.slave):
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self.master = self.slave = -1
