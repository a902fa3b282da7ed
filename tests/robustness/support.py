"""Helpers of the daemon-level robustness tests: what a process holds (/proc), round trips,
misbehaving clients.

Nothing here asserts a time, and neither do the tests (issue 16): round trips are measured,
returned and printed; the tests check order, counts and bounded memory, and ``python -m bench``
measures the times (the isolation and churn rows).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket
import statistics
import termios
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from daemon.process import TIMEOUT, Conn, Daemon, wait_for


def fd_count(pid: int) -> int:
    """File descriptors the process holds now."""
    return len(os.listdir(f"/proc/{pid}/fd"))


def rss_kib(pid: int) -> int:
    """Resident set size (``VmRSS`` in ``/proc/<pid>/status``), KiB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError(f"no VmRSS for {pid}")


def settled_fds(pid: int, expected: int, timeout: float = TIMEOUT) -> int:
    """The fd count once it is back to ``expected`` (the daemon closes a connection on its next
    turn of the loop), or what it is after ``timeout``."""
    wait_for(lambda: fd_count(pid) <= expected, timeout)
    return fd_count(pid)


def free_port() -> int:
    """A TCP port nobody listens on now (the system's pick, released at once)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def two_boards(link: str = "driver", pty: Path | None = None) -> str:
    """A daemon configuration: ``abused`` (whose client will misbehave; on ``link``, with a pty
    when given) and ``good`` (whose client behaves, on the driver link), both PC48-4E, TCP on
    free ports."""
    pty_line = f'pty = "{pty}"\n' if pty is not None else ""
    return (
        "[[board]]\n"
        'name = "abused"\n'
        'model = "PC48-4E"\n'
        f'link = "{link}"\n'
        'tcp = "127.0.0.1:0"\n'
        f"{pty_line}"
        "[[board]]\n"
        'name = "good"\n'
        'model = "PC48-4E"\n'
        'link = "driver"\n'
        'tcp = "127.0.0.1:0"\n'
    )


# -- round trips -----------------------------------------------------------------------------------


@dataclass
class RoundTrips:
    """``RP`` round trips of one well-behaved client, in seconds."""

    samples: list[float] = field(default_factory=list)

    @property
    def median(self) -> float:
        return statistics.median(self.samples)

    @property
    def worst(self) -> float:
        return max(self.samples, default=0.0)

    def p(self, q: float) -> float:
        ordered = sorted(self.samples)
        return ordered[min(len(ordered) - 1, int(q * len(ordered)))]

    def __str__(self) -> str:
        return (
            f"{len(self.samples)} RP round trips: median {self.median * 1e3:.2f} ms, "
            f"p95 {self.p(0.95) * 1e3:.2f} ms, worst {self.worst * 1e3:.2f} ms"
        )


def round_trips(
    conn: Conn, count: int, expected: bytes = b"-777", pause: float = 0.005
) -> RoundTrips:
    """``count`` ``AY RP`` round trips on the driver link (reply ``<position><LF>``), each
    checked; ``pause`` seconds between them so the abuser gets the daemon in between."""
    result = RoundTrips()
    for _ in range(count):
        start = time.perf_counter()
        reply = conn.ask(b"AY RP")
        result.samples.append(time.perf_counter() - start)
        assert reply == expected, f"RP answered {reply!r}"
        time.sleep(pause)
    return result


# -- misbehaving clients ---------------------------------------------------------------------------


class Abuser(threading.Thread):
    """A client doing something bad in a thread until :meth:`stop` (or its own end); counts the
    bytes it got rid of. Exceptions are kept and re-raised by :meth:`stop`."""

    def __init__(self, action: Callable[[Abuser], None]) -> None:
        super().__init__(daemon=True)
        self.action = action
        self.stopping = threading.Event()
        self.sent = 0
        self.received = bytearray()
        self.error: BaseException | None = None

    def run(self) -> None:
        try:
            self.action(self)
        except BaseException as exc:  # re-raised in the test's thread by stop()
            self.error = exc

    def stop(self) -> None:
        self.stopping.set()
        self.join(TIMEOUT)
        assert not self.is_alive(), "the misbehaving client did not stop"
        if self.error is not None:
            raise self.error


def flood_tcp(address: tuple[str, int], data: bytes) -> Callable[[Abuser], None]:
    """Write ``data`` (whole commands) over and over as fast as the daemon takes it, and never
    read, until stopped. When the daemon stops taking bytes (flow control) the writer waits for
    room."""

    def action(me: Abuser) -> None:
        with socket.create_connection(address, timeout=TIMEOUT) as sock:
            sock.setblocking(False)
            write_until_stopped(me, data, lambda chunk: sock.send(chunk), sock.fileno())

    return action


def write_until_stopped(me: Abuser, data: bytes, send: Callable[[bytes], int], fd: int) -> None:
    chunk = data * max(1, 65536 // len(data))
    pos = 0  # where in ``data`` the next byte is: a partial write is completed next time
    while not me.stopping.is_set():
        try:
            n = send(chunk[pos:])
        except BlockingIOError:
            select.select([], [fd], [], 0.05)
            continue
        except OSError as exc:  # the daemon may close an abuser: that is allowed
            if exc.errno in (errno.ECONNRESET, errno.EPIPE):
                return
            raise
        me.sent += n
        pos = (pos + n) % len(data)


def flood_pty(path: Path, data: bytes) -> Callable[[Abuser], None]:
    """Open the pty, write ``data`` (whole commands) over and over as fast as the daemon takes
    it, never read, until stopped."""

    def action(me: Abuser) -> None:
        fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        try:
            write_until_stopped(me, data, lambda chunk: os.write(fd, chunk), fd)
        finally:
            with contextlib.suppress(termios.error):
                termios.tcflush(fd, termios.TCIOFLUSH)
            os.close(fd)

    return action


def slow_reader(
    address: tuple[str, int], data: bytes, total: int, period: float = 1.0
) -> Callable[[Abuser], None]:
    """Write ``total`` bytes of ``data`` (queries with replies) at once, then read one byte
    every ``period`` seconds until stopped."""

    def action(me: Abuser) -> None:
        with socket.create_connection(address, timeout=TIMEOUT) as sock:
            sock.setblocking(False)
            payload = memoryview(data * (total // len(data)))
            while payload and not me.stopping.is_set():
                try:
                    n = sock.send(payload)
                except BlockingIOError:
                    select.select([], [sock], [], 0.05)
                    continue
                me.sent += n
                payload = payload[n:]
            while not me.stopping.wait(period):
                ready, _, _ = select.select([sock], [], [], 0)
                if ready:
                    byte = sock.recv(1)
                    if not byte:
                        return
                    me.received += byte

    return action


def never_reads(address: tuple[str, int], data: bytes, every: float) -> Callable[[Abuser], None]:
    """Write ``data`` (queries with long answers) every ``every`` seconds and never read: what
    backs up is the daemon's output to this client, not its input."""

    def action(me: Abuser) -> None:
        with socket.create_connection(address, timeout=TIMEOUT) as sock:
            sock.setblocking(False)
            while not me.stopping.wait(every):
                with contextlib.suppress(BlockingIOError):
                    me.sent += sock.send(data)

    return action


def garbage_tcp(address: tuple[str, int], seed: int) -> Callable[[Abuser], None]:
    """Random bytes (control characters, bytes above 0x7F, the driver's ``!``/``@``/``*``),
    written as fast as the daemon takes them, replies never read."""
    import random

    def action(me: Abuser) -> None:
        rng = random.Random(seed)
        with socket.create_connection(address, timeout=TIMEOUT) as sock:
            sock.setblocking(False)
            while not me.stopping.is_set():
                try:
                    me.sent += sock.send(rng.randbytes(4096))
                except BlockingIOError:
                    select.select([], [sock], [], 0.05)
                except OSError as exc:
                    if exc.errno in (errno.ECONNRESET, errno.EPIPE):
                        return
                    raise

    return action


def churn_tcp(address: tuple[str, int]) -> Callable[[Abuser], None]:
    """Connect, write half a command, hang up (sometimes with a reset), again and again."""

    def action(me: Abuser) -> None:
        i = 0
        while not me.stopping.is_set():
            sock = socket.create_connection(address, timeout=TIMEOUT)
            if i % 2:
                sock.sendall(b"AX MR1")
                me.sent += 6
            if i % 3 == 0:  # an abortive close: RST instead of FIN
                sock.setsockopt(
                    socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00"
                )
            sock.close()
            i += 1

    return action


def rss_watch(
    daemon: Daemon, samples: list[int], stop: threading.Event, every: float = 0.05
) -> threading.Thread:
    """Sample the daemon's RSS into ``samples`` until ``stop`` is set."""

    def run() -> None:
        while not stop.is_set() and daemon.running:
            with contextlib.suppress(OSError, AssertionError):
                samples.append(rss_kib(daemon.proc.pid))
            stop.wait(every)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread
