"""Serial endpoints: a board on a real serial device, as the card's own port would be.

A USB serial adapter (``/dev/ttyUSB0``) or a motherboard port (``/dev/ttyS0``), a null-modem
cable, and an old PC at the far end running the legacy application: the daemon opens the device
with pyserial, sets the line as the application's port is set (9600 baud 8N1 and no flow
control unless configured: :class:`omsd.pacing.Line`, ``flow`` ``none``, ``rtscts`` or
``xonxoff``), locks it (an advisory ``flock``, pyserial's ``exclusive``: a second omsd cannot
take it), and from then on uses its descriptor on the event loop: read when readable, written
at once, non-blocking, with a bounded backlog for what the device cannot take yet (as the pty
endpoint does, :mod:`omsd.transport.pty`). Bytes pass untouched both ways.

The device is one client of the board's service (:mod:`omsd.service`): from its opening to its
loss is one session. The daemon cannot see the far end's program open and close its port, so the
far end is one conversation for as long as the device is there.

**Unplugged.** When the device goes (a read or write fails with an error such as EIO, or the tty
hangs up: a read of nothing, the descriptor being read with VMIN 1), the endpoint logs it once,
closes it, ends its session (what it wrote that the board had not taken is dropped, what the
board still says for it discarded) and tries to open the path again every :data:`RETRY`
seconds, quietly, until it can; then it logs that and begins a new session. The board, the
daemon and its other endpoints go on meanwhile. At start-up a device that cannot be opened is an
error (the daemon does not start): a mistyped path is said at once rather than waited for.

**Pacing** (``pacing = true``): the board's output is handed to the device no faster than the
line carries it (:class:`omsd.pacing.Pacer`), so a device that does not pace (a pty standing in
for one, a network serial server) delivers it as a line at that rate would. A real UART paces by
itself; there pacing only keeps the kernel's output buffer short. The host's bytes are taken as
they come (on a real line they came at the line's pace already).
"""

from __future__ import annotations

import asyncio
import contextlib
import errno
import os
import termios
from pathlib import Path
from typing import Any

from omsd.defaults import FLOWS
from omsd.pacing import Line, Pacer
from omsd.service import BoardService

#: Seconds between two attempts to open a device that is gone.
RETRY = 1.0
#: Output bytes kept for a device that cannot take them yet; beyond, the oldest are dropped.
MAX_BACKLOG = 64 * 1024
#: What one read takes from the device at most.
READ_SIZE = 4096


def describe(path: Path | str, line: Line, flow: str = "none") -> str:
    """``/dev/ttyUSB0,9600,8N1`` (``,rtscts`` or ``,xonxoff`` with flow control): the endpoint's
    address as the daemon announces it, the ``--serial`` option's syntax."""
    text = f"{path},{line.baud},{line.frame}"
    return text if flow == "none" else f"{text},{flow}"


def open_device(path: Path | str, line: Line, flow: str = "none") -> Any:
    """The device opened with pyserial, set to ``line`` and ``flow``, locked against other
    openers and with VMIN 1 (a read of nothing is a hang-up); its descriptor non-blocking.
    ``OSError`` (pyserial's ``SerialException``) or ``ValueError`` with what went wrong."""
    import serial  # type: ignore[import-untyped]  # not at import: only a serial endpoint needs it

    port = serial.Serial(
        port=os.fspath(path),
        baudrate=line.baud,
        bytesize=line.bytesize,
        parity=line.parity,
        stopbits=line.stopbits,
        rtscts=flow == "rtscts",
        xonxoff=flow == "xonxoff",
        timeout=0,
        exclusive=True,
    )
    try:
        fd = port.fileno()
        # pyserial leaves VMIN 0, where a read with nothing waiting returns nothing, as a
        # read of a device that hung up does: VMIN 1 tells them apart (EAGAIN / nothing)
        attrs = termios.tcgetattr(fd)
        attrs[6][termios.VMIN] = 1
        attrs[6][termios.VTIME] = 0
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        os.set_blocking(fd, False)
    except BaseException:
        with contextlib.suppress(Exception):
            port.close()
        raise
    return port


def reason(exc: BaseException) -> str:
    """An error opening, reading or writing a device, in a few words."""
    number = getattr(exc, "errno", None)
    if number in (errno.EAGAIN, errno.EWOULDBLOCK) and "lock" in str(exc).lower():
        return "in use by another program (it is locked)"
    if number == errno.EIO:
        return "input/output error"
    if isinstance(number, int) and number > 0:
        return os.strerror(number).lower()
    text = str(exc)
    if "could not configure port" in text.lower():  # pyserial: tcgetattr failed
        return "not a serial device (it takes no line settings)"
    return text or type(exc).__name__


class SerialEndpoint:
    """A board on the serial device at ``path``. :meth:`open` at start (raises what
    :func:`open_device` raises), :meth:`close` at the end."""

    def __init__(
        self,
        service: BoardService,
        path: Path,
        line: Line | None = None,
        flow: str = "none",
        pacing: bool = False,
        retry: float = RETRY,
    ) -> None:
        if flow not in FLOWS:
            raise ValueError(f"flow control: expected one of {', '.join(FLOWS)}, got {flow!r}")
        self.service = service
        self.path = path
        self.line = line if line is not None else Line()
        self.flow = flow
        self.retry = retry
        self.label = f"serial:{path}"
        self.session = 0
        self.connected = False  # the device is open: a session is running
        self.port: Any = None  # pyserial's Serial
        self.fd = -1
        self.pacer: Pacer | None = None
        self._pacing = pacing
        self._pending = bytearray()
        self._backlog = bytearray()
        self._reading = False
        self._writing = False
        self._attached = False
        self._closed = False
        self._going = False  # a loss is about to be handled (see _lost)
        self._retry_timer: asyncio.TimerHandle | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    @property
    def address(self) -> str:
        return describe(self.path, self.line, self.flow)

    def open(self) -> str:
        """Open the device and serve the board on it; returns its address."""
        loop = self._loop = asyncio.get_running_loop()
        if self._pacing:
            self.pacer = Pacer(loop, self.line.chars_per_second)
        self._open_port()
        self.service.attach(self)
        self._attached = True
        self._start()
        return self.address

    def _open_port(self) -> None:
        port = open_device(self.path, self.line, self.flow)
        self.port = port
        self.fd = port.fileno()

    def _start(self) -> None:
        self.connected = True
        self._going = False
        loop = self._loop
        if loop is not None and not self._reading:
            loop.add_reader(self.fd, self._readable)
            self._reading = True

    # -- losing the device and finding it again -------------------------------------------------

    def _lost(self, why: str) -> None:
        """The device failed or hung up. Called from a write, which the service may be making
        from inside its own turn, the rest waits for the next turn of the loop."""
        if self._going or not self.connected:
            return
        self._going = True
        loop = self._loop
        if loop is not None:
            loop.call_soon(self._gone, why)

    def _gone(self, why: str) -> None:
        if self._closed or not self.connected:
            return
        unsent = len(self._pending)
        self._close_port()
        self.service.log.warning(
            f"{self.service.name}: {self.label} is gone ({why}); trying to open it again every"
            f" {self.retry:g} s"
        )
        self.service.end_session(self, unsent, "unplugged")
        self._schedule_retry()

    def _schedule_retry(self) -> None:
        if self._loop is not None and not self._closed:
            self._retry_timer = self._loop.call_later(self.retry, self._try_again)

    def _try_again(self) -> None:
        self._retry_timer = None
        if self._closed:
            return
        try:
            self._open_port()
        except (OSError, ValueError):
            self._schedule_retry()
            return
        self.service.open_session(self)
        self.service.log.info(f"{self.service.name}: {self.label} is back ({self.address})")
        self._start()

    def _close_port(self) -> None:
        loop = self._loop
        if loop is not None and self.fd >= 0:
            if self._reading:
                loop.remove_reader(self.fd)
            if self._writing:
                loop.remove_writer(self.fd)
        self._reading = self._writing = False
        self.connected = False
        self._pending.clear()
        self._backlog.clear()
        if self.pacer is not None:
            self.pacer.clear()
        port, self.port, self.fd = self.port, None, -1
        if port is not None:
            with contextlib.suppress(Exception):
                port.close()

    # -- input ----------------------------------------------------------------------------------

    def _readable(self) -> None:
        try:
            data = os.read(self.fd, READ_SIZE)
        except (BlockingIOError, InterruptedError):
            return
        except OSError as exc:
            self._going = True
            self._gone(reason(exc))
            return
        if not data:
            self._going = True
            self._gone("it hung up")
            return
        if self._pending:
            self._pending += data
            self._push()
            return
        # the fast path: nothing held back from before, the bytes go to the board as they
        # came, and only what it does not take is kept (as _push would)
        taken = self.service.feed(self, data)
        if taken < len(data):
            self._pending += data[taken:]
            self._flow()

    def _push(self) -> None:
        if self._pending:
            taken = self.service.feed(self, bytes(self._pending))
            del self._pending[:taken]
        self._flow()

    def _flow(self) -> None:
        """Read the device while the board can take what is read; stop while it cannot (the
        device's own buffer, and its flow control if it has any, hold the host back)."""
        loop = self._loop
        if loop is None or self.fd < 0:
            return
        if self._pending and self._reading:
            loop.remove_reader(self.fd)
            self._reading = False
        elif not self._pending and not self._reading:
            loop.add_reader(self.fd, self._readable)
            self._reading = True

    def input_room(self) -> None:
        self._push()

    # -- output ---------------------------------------------------------------------------------

    def send(self, data: bytes) -> None:
        if not self.connected or not data:
            return
        if self.pacer is not None:
            self.pacer.send(self._write, data)
        else:
            self._write(data)

    def _write(self, data: bytes) -> None:
        if not self.connected or self.fd < 0 or not data:
            return
        if not self._backlog:
            # the fast path: nothing waiting before it, so it goes to the device at once
            try:
                n = os.write(self.fd, data)
            except (BlockingIOError, InterruptedError):
                n = 0
            except OSError as exc:
                self._lost(reason(exc))
                return
            if n == len(data):
                return
            data = data[n:]
        self._backlog += data
        if len(self._backlog) > MAX_BACKLOG:
            del self._backlog[: len(self._backlog) - MAX_BACKLOG]
        self._flush()

    def _flush(self) -> None:
        while self._backlog and self.fd >= 0:
            try:
                n = os.write(self.fd, self._backlog)
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:
                self._backlog.clear()
                self._lost(reason(exc))
                break
            del self._backlog[:n]
        loop = self._loop
        if loop is None or self.fd < 0:
            return
        if self._backlog and not self._writing:
            loop.add_writer(self.fd, self._flush)
            self._writing = True
        elif not self._backlog and self._writing:
            loop.remove_writer(self.fd)
            self._writing = False

    # -- life -----------------------------------------------------------------------------------

    def close(self) -> None:
        """Stop serving: close the device, stop trying to open it again. Later calls do
        nothing."""
        if self._closed:
            return
        self._closed = True
        if self._retry_timer is not None:
            self._retry_timer.cancel()
            self._retry_timer = None
        if self._attached:
            self.service.detach(self)
        self._close_port()


__all__ = ["FLOWS", "RETRY", "SerialEndpoint", "describe", "open_device", "reason"]
