"""Pseudo-terminal endpoints: a board that looks like a serial port to any program.

A legacy application, a terminal emulator (picocom, minicom, screen) or ``cat`` opens the pty's
slave device through a stable symlink and talks to the board. The daemon:

* creates the pty raw (no echo, no CR/LF translation, no signal characters), so bytes pass
  through untouched whatever the client sets up;
* follows its clients: from the first open of the slave to the last close is one session of
  the board's service (:mod:`omsd.service`). inotify reports every open and close
  (:mod:`omsd.transport.inotify`), and the master's hang-up (POLLHUP, EIO: nobody has the
  slave open) tells a last close from the close of one of several programs; the master is read
  only while somebody has the pty open, so nothing spins and no timer runs while nobody does.
  When a session ends, what its clients wrote before they closed is read and offered to the
  board, what the board has not taken is dropped, what they left unread in the terminal is
  flushed, and nothing is written to the pty until it is opened again: the next program starts
  clean, even when it opened the pty before the daemon saw the last one close.

  Whose bytes are whose: the master is one stream, so the daemon orders what it reads by what
  the kernel guarantees. A program's open is reported before its open returns, so before it
  can write; its close is reported after its last write. Every read of the master is therefore
  followed, not preceded, by a look at the opens and closes: bytes read before a newcomer's
  open was reported cannot be the newcomer's, and bytes read once the master has hung up
  (until it reads EIO) are the last session's. The one case the stream cannot split is a
  program that writes and closes at once while a newcomer opens and writes before the daemon
  has read the first one's bytes: what is unread then goes to the newcomer, who is there to
  read the answer (docs/decisions.md). A program that reopens the pty and reads within the
  moment the daemon takes to see the last close can still find the last answers (the kernel
  gives no way to flush at the close itself). Without inotify (not Linux) the daemon holds the
  slave open and the pty is one session for its life;
* gives the slave device group permissions (mode 0660 by default, optionally another group) so
  users of that group can open it;
* points the symlink at the slave atomically (a new link is renamed over the old one) and
  removes it on exit if it still points at this pty.

With ``terminal`` on, the endpoint edits a line at a time, shows what is typed and gives the
board's line ends as CR LF (:mod:`omsd.transport.terminal`); off, bytes pass untouched.

Output for a client that does not read waits in the terminal's buffer; beyond what the kernel
buffers, and a bounded backlog here, it is dropped (a serial port would overwrite it too).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import grp
import os
import pathlib
import select
import termios
import tty

from omsd.service import BoardService
from omsd.transport.inotify import CLOSED_READER, OPENED, OpenWatch, watch_opens
from omsd.transport.terminal import Terminal, terminal_for

MAX_BACKLOG = 64 * 1024
#: When the count of opens and closes says nobody has the pty but the master has not hung up
#: and is not being read, how soon to look again (s): the kernel lets the pty go a moment
#: after it reports the close.
UNSETTLED_LOOK = 0.001
#: What one read takes from the master at most.
READ_SIZE = 4096

# The one buffer every pty's master is read into (os.readv), as the TCP endpoints share theirs
# (omsd.transport.tcp): a read of a few bytes makes no 4 KiB bytes object. The event loop calls
# one reader at a time and the bytes are copied out at once.
_READ_BUFFER = memoryview(bytearray(READ_SIZE))


class PtyEndpoint:
    def __init__(
        self,
        service: BoardService,
        link: pathlib.Path,
        group: str | None = None,
        mode: int = 0o660,
        terminal: bool = False,
    ) -> None:
        self.service = service
        self.link = link
        self.group = group
        self.mode = mode
        self.terminal: Terminal | None = None
        if terminal:
            board = service.board
            self.terminal = terminal_for(service.link, lambda: board.interpreter.echo)
        self.label = f"pty:{link}"
        self.session = 0
        self.connected = False  # a session is running: someone has the slave open
        self.openers = 0  # clients with the slave open, as inotify counted them (a guess)
        self._watch: OpenWatch | None = None
        self._sessions = 0  # sessions begun (the first is the one attach() opens)
        self.master = -1
        self.slave = -1
        self.device = ""
        self._pending = bytearray()
        self._unread = bytearray()  # read from the master, not yet known whose (_readable)
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
            # before the link exists, so that no client's open can come unseen
            self._watch = watch_opens(self.device, self._opened_or_closed)
            self._place_link()
        except BaseException:
            self._close_fds()
            raise
        self.service.attach(self)
        if self._watch is None:  # no inotify: hold the slave, one session for ever
            self.connected = True
            self._loop.add_reader(self.master, self._readable)
            self._reading = True
        else:
            os.close(self.slave)  # nobody has it open: the master hangs up until somebody does
            self.slave = -1
            self._loop.add_reader(self._watch.fd, self._watch.readable)
        return self.device

    # -- sessions -------------------------------------------------------------------------------

    def _hung_up(self) -> bool:
        """Nobody has the slave open (the master polls POLLHUP)."""
        poller = select.poll()
        poller.register(self.master, select.POLLIN)
        return any(ev & select.POLLHUP for _, ev in poller.poll(0))

    def _opened_or_closed(self, events: list[str]) -> None:
        """inotify's opens and closes, in order. A session ends when nobody has the pty open
        (the master hangs up), or when the count of opens and closes says nobody had it open
        and another open follows (the last client went and another came before the daemon
        looked). A close that leaves the count at zero while the master has not hung up is
        not taken as the end yet: a close is reported just before the kernel lets the pty go,
        and two opens may have been merged into one event; the master's EIO, or the next
        open, settles it."""
        i = 0
        while i < len(events):
            event = events[i]
            i += 1
            if event == OPENED:
                if self.connected and not self.openers:
                    # an open after the count said nobody had the pty: a newcomer
                    events.extend(self._session_over(reopened=True, upcoming=events[i - 1 :]))
                self.openers += 1
                if not self.connected:
                    self._connect()
                continue
            self.openers = max(0, self.openers - 1)
            if not self.connected:
                continue
            if self._hung_up():  # nobody has it open, whatever the count says
                events.extend(self._session_over(reopened=False, upcoming=events[i:]))
                continue
            if self.openers:
                continue
            watch = self._watch
            if OPENED not in events[i:] and watch is not None:
                events.extend(watch.pending())  # an open that came since is queued by now
            if OPENED in events[i:]:
                # reopened: what is unread may be the newcomer's already
                events.extend(self._session_over(reopened=True, upcoming=events[i:]))
            elif not self._reading and self._loop is not None:
                # the master's EIO cannot tell while it is not read: look again in a moment
                self._loop.call_later(UNSETTLED_LOOK, self._look_again)
        if self._unread and self.connected:
            # read before these events were seen: the bytes of whoever has the pty now, the
            # last to open it (the module docstring)
            self._give_unread()

    def _give_unread(self) -> None:
        data = bytes(self._unread)
        self._unread.clear()
        self._take(data)
        self._push()

    def _look_again(self) -> None:
        if self.connected and not self.openers and self.master >= 0 and self._hung_up():
            self._opened_or_closed(self._session_over(reopened=False, upcoming=[]))

    def _connect(self) -> None:
        self.connected = True
        if self.terminal is not None:
            self.terminal.reset()
        if self._sessions:
            self.service.open_session(self)
        self._sessions += 1
        self.service.log.info(f"{self.service.name}: {self.label} opened")
        if not self._reading and self._loop is not None and not self._pending:
            self._loop.add_reader(self.master, self._readable)
            self._reading = True

    def _session_over(self, reopened: bool, upcoming: list[str]) -> list[str]:
        """The last client closed the pty: what it wrote before it closed is read (as a TCP
        client's last bytes are) and offered to the board; then its session ends, and nothing
        of it is left for the next one. ``reopened``: somebody opened the pty since, so what is
        unread may be theirs and is left for them (the module docstring says which bytes are
        whose). Returns the opens and closes queued meanwhile (to be taken in order); a client
        that opened while the watch was paused for the flush is found by the master no longer
        hanging up."""
        if not reopened:
            reopened = not self._read_all()
        if not reopened and self._unread:
            self._give_unread()
        self.connected = False
        self.openers = 0
        unsent = len(self._pending)
        self._pending.clear()
        self._backlog.clear()
        loop = self._loop
        if loop is not None:
            if self._writing:
                loop.remove_writer(self.master)
                self._writing = False
            if self._reading:
                loop.remove_reader(self.master)
                self._reading = False
        queued = self._flush_terminal()
        self.service.log.info(f"{self.service.name}: {self.label} closed")
        self.service.end_session(self, unsent, "closed")
        if self._watch is not None:
            queued += self._watch.pending()
        if OPENED not in upcoming + queued:
            if not self._hung_up():
                self.openers = 1
                self._connect()
            else:
                self._unread.clear()  # nobody to give them to (a client that came and went)
        return queued

    def _flush_terminal(self) -> list[str]:
        """Throw away what the last clients left unread in the terminal. Only the slave's side
        can flush its input, so the daemon opens it for a moment; returns the opens and closes
        of others queued meanwhile (in order), without the daemon's own. It opens the slave to
        read only, so that its close is of the other kind than a client's and cannot be merged
        with one (:data:`~omsd.transport.inotify.CLOSED_READER`); its open may be merged with a
        client's, which :meth:`_session_over` finds by the master no longer hanging up."""
        watch = self._watch
        if watch is None:
            with contextlib.suppress(OSError, termios.error):
                termios.tcflush(self.slave, termios.TCIFLUSH)
            return []
        before = watch.pending()  # so that the daemon's own open follows nothing unread
        try:
            fd = os.open(self.device, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)
        except OSError:
            return before
        with contextlib.suppress(termios.error):
            termios.tcflush(fd, termios.TCIFLUSH)
        os.close(fd)
        after = watch.pending()
        if OPENED in after:  # the daemon's own open, and its close after it
            at = after.index(OPENED)
            del after[at]
            if CLOSED_READER in after[at:]:
                del after[after.index(CLOSED_READER, at)]
        return before + after

    def _read_all(self) -> bool:
        """Read what is in the master into ``_unread``; whether nobody has the pty open once
        all is read (EIO: what was read is the last session's). False (EAGAIN): somebody has
        opened it since the daemon saw it hang up, and what was read may be theirs."""
        while True:
            try:
                n = os.readv(self.master, [_READ_BUFFER])
            except BlockingIOError:
                return False
            except OSError:  # EIO: nobody has it open and nothing is left
                return True
            if not n:
                return True
            self._unread += _READ_BUFFER[:n]

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
            n = os.readv(self.master, [_READ_BUFFER])
        except BlockingIOError:
            n = 0
        except OSError as exc:
            if exc.errno != errno.EIO:
                raise
            # nobody has the slave open and nothing is left to read: the session is over
            if self.connected:
                self._opened_or_closed(self._session_over(reopened=False, upcoming=[]))
            return
        watch = self._watch
        if watch is not None and watch.queued():
            # the opens and closes are looked at after the read, so that a newcomer's bytes
            # among what was read come with its open (it opened before it wrote): they are
            # kept in _unread until the events say whose they are
            self._unread += _READ_BUFFER[:n]
            watch.drain()
            if not self._unread or not self.connected:
                return
            data = bytes(self._unread)
            self._unread.clear()
            n = len(data)
        elif not n:
            return
        else:
            data = bytes(_READ_BUFFER[:n])
        if self._pending or self.terminal is not None:
            self._take(data)
            self._push()
            return
        # the fast path: nothing held back from before and no line editing, so the bytes go to
        # the board as they came, and only what it does not take is kept (as _push would)
        taken = self.service.feed(self, data)
        if taken < n:
            self._pending += data[taken:]
            self._flow()

    def _take(self, data: bytes) -> None:
        """What the client wrote, for the board (through the terminal's line editing)."""
        if self.terminal is not None:
            data, screen = self.terminal.typed(data)
            if screen:
                self._write(screen)
        self._pending += data

    def _push(self) -> None:
        if self._pending:
            taken = self.service.feed(self, bytes(self._pending))
            del self._pending[:taken]
        self._flow()

    def _flow(self) -> None:
        """Read the master while the board can take what is read; stop while it cannot."""
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
        if self.terminal is not None:
            data = self.terminal.shown(data)
        self._write(data)

    def _write(self, data: bytes) -> None:
        if self.master < 0 or not self.connected or not data:
            return
        if not self._backlog:
            # the fast path: nothing waiting before it, so it goes to the terminal at once
            try:
                n = os.write(self.master, data)
            except BlockingIOError:
                n = 0
            except OSError:
                return  # as _flush does: what cannot be written is dropped
            if n == len(data):
                return
            data = data[n:]
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
        self.connected = False
        if self._watch is not None:
            if loop is not None and self._watch.fd >= 0:
                loop.remove_reader(self._watch.fd)
            self._watch.close()
            self._watch = None
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
