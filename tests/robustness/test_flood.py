"""Flood and slow readers (issue 7): "a client that writes megabytes and never reads, and one that
reads one byte a second: memory stays bounded, other boards and clients are not slowed."

A real daemon with two PC48-4E boards on the DOS-driver link: ``abused``, whose client
misbehaves, and ``good``, whose client asks ``AY RP`` over and over while it does. Measured and
checked:

* the daemon's resident memory (``VmRSS``), sampled every 50 ms, never exceeds what it was before
  the abuse by :data:`RSS_BOUND_KIB`: what the abuser writes is held off by flow control (the
  board takes bytes as its input buffer frees, as TBE_S would), and what it does not read is
  capped (``MAX_PENDING_OUTPUT`` of ``omsd/transport/tcp.py``, ``MAX_BACKLOG`` of
  ``omsd/transport/pty.py``) and then dropped;
* the good client is answered throughout, each answer right (its own ``-777``), at least
  :data:`AT_LEAST` times during the abuse: order and counts, never a time (how long the answers
  take meanwhile is measured by ``python -m bench``, the isolation rows);
* the abused board itself is still usable afterwards by a client that behaves.

Short pass: :data:`FLOOD_SECONDS` [0] seconds of flood (megabytes) and a few seconds of slow
reading; long pass (``--long`` / ``OMSD_LONG=1``): a minute of each.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from pathlib import Path

from daemon.process import TIMEOUT, Conn, Daemon, Omsd

from .conftest import Scale
from .support import (
    Abuser,
    RoundTrips,
    flood_pty,
    flood_tcp,
    rss_kib,
    rss_watch,
    slow_reader,
    two_boards,
)

FLOOD_SECONDS = (3, 60)
SLOW_SECONDS = (4, 60)
MEGABYTE = 1 << 20
RSS_BOUND_KIB = 8 * 1024
"""Resident memory the daemon may gain while abused (KiB): asyncio's reads (256 KiB each), the
output caps, allocator slack. Without flow control and the caps it would gain what the flood
wrote (megabytes in the short pass, tens of megabytes in the long one)."""
AT_LEAST = 10
"""Answers the good client gets while the other board is abused."""


def start(omsd: Omsd, pty: Path | None = None) -> Daemon:
    expect = 3 if pty is not None else 2
    return omsd("--control", "off", "--view", "off", config=two_boards(pty=pty), expect=expect)


def good_client(daemon: Daemon) -> Conn:
    conn = daemon.connect("good")
    assert conn.ask(b"AY LP-777 RP") == b"-777"
    return conn


def abuse(daemon: Daemon, abuser: Abuser, good: Conn, seconds: float) -> tuple[RoundTrips, int]:
    """Run ``abuser`` for ``seconds`` while the good client measures round trips; returns them
    and the daemon's largest resident memory growth meanwhile (KiB)."""
    pid = daemon.proc.pid
    rss_before = rss_kib(pid)
    samples: list[int] = []
    stop = threading.Event()
    watcher = rss_watch(daemon, samples, stop)
    trips = RoundTrips()
    abuser.start()
    try:
        started = time.monotonic()
        while time.monotonic() - started < seconds or len(trips.samples) < AT_LEAST:
            begin = time.perf_counter()
            reply = good.ask(b"AY RP")
            trips.samples.append(time.perf_counter() - begin)
            assert reply == b"-777", f"the good board answered {reply!r}"
            time.sleep(0.002)
            assert daemon.running, daemon.stderr
    finally:
        stop.set()
        watcher.join(TIMEOUT)
        abuser.stop()
    samples.append(rss_kib(pid))
    return trips, max(samples) - rss_before


def still_usable(daemon: Daemon) -> None:
    """A client that behaves gets the abused board back, and only its own answer: the answers
    to what the abuser wrote, and the error of the command it left cut short (closing a socket
    with unread data resets the connection, and the kernel discards what the daemon had not
    read yet), are the abuser's (issue 13; docs/decisions.md "Sessions")."""
    with daemon.connect("abused") as conn:
        conn.send(b"AZ LP42 AZ RP")
        data = conn.read_until(b"42\n", timeout=5 * TIMEOUT)
        assert data == b"42\n", data[-200:]
        assert conn.quiet(0.2) == b""


def report(label: str, trips: RoundTrips, grown: int, sent: int) -> None:
    print(f"{label}: {sent / MEGABYTE:.1f} MiB written; good board {trips}; RSS {grown:+} KiB")
    assert grown < RSS_BOUND_KIB, f"{label}: the daemon's memory grew by {grown} KiB"
    assert len(trips.samples) >= AT_LEAST, f"{label}: the good board was answered {trips}"


def test_tcp_flood_that_never_reads(omsd: Omsd, scale: Scale) -> None:
    daemon = start(omsd)
    with good_client(daemon) as good:
        abuser = Abuser(flood_tcp(daemon.tcp("abused"), b"AY RP "))
        trips, grown = abuse(daemon, abuser, good, scale(*FLOOD_SECONDS))
        report("TCP flood", trips, grown, abuser.sent)
    assert abuser.sent >= MEGABYTE
    still_usable(daemon)


def test_pty_flood_that_never_reads(omsd: Omsd, scale: Scale, tmp_path: Path) -> None:
    link = tmp_path / "abused"
    daemon = start(omsd, pty=link)
    with good_client(daemon) as good:
        abuser = Abuser(flood_pty(link, b"AY RP "))
        trips, grown = abuse(daemon, abuser, good, scale(*FLOOD_SECONDS))
        report("pty flood", trips, grown, abuser.sent)
    # a terminal takes a few KiB at a time: the flood is slower than on TCP, and still real
    assert abuser.sent >= MEGABYTE // 4
    still_usable(daemon)


def test_slow_reader(omsd: Omsd, scale: Scale) -> None:
    """The slow reader asks ``AY RP`` 40,000 times at once and then reads one byte a second. What
    it reads is the beginning of its answers, whole and in order (``0<LF>`` each); the output it
    cannot take is capped, not buffered without end."""
    daemon = start(omsd)
    seconds = scale(*SLOW_SECONDS)
    with good_client(daemon) as good:
        abuser = Abuser(slow_reader(daemon.tcp("abused"), b"AY RP ", 40_000 * 6, period=1.0))
        trips, grown = abuse(daemon, abuser, good, seconds)
        report("slow reader", trips, grown, abuser.sent)
    assert abuser.sent == 40_000 * 6
    got = bytes(abuser.received)
    assert len(got) >= seconds - 2, got
    assert (b"0\n" * len(got)).startswith(got), got
    still_usable(daemon)


def test_newcomers_are_held_off_not_buffered_while_a_wait_holds_the_board(
    omsd: Omsd, tmp_path: Path
) -> None:
    """Issue 13: "A random ``!`` or ``@`` ... locks the board for every later client ...; while
    locked, every newcomer's input is buffered without limit (40 clients x 2 MB took the daemon
    from 31 to 163 MB). Input held for a wait is bounded (the driver's buffer size)". A program on
    the pty starts a move of days and waits for its done (``!``), with a command behind it; then
    40 TCP clients each try to write 2 MB. The driver holds its 256 bytes, each connection one
    read at most (the rest stays in the kernel, which stops the sender), a newcomer takes over
    from the last: the daemon's memory stays within the flood bound, and the pty's wait is still
    there, still its own."""
    link = tmp_path / "abused"
    daemon = start(omsd, pty=link)
    pid = daemon.proc.pid
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"AX VL1 MR1000000 GO ID ! AY RP")
        rss_before = rss_kib(pid)
        grown = 0
        sent = 0
        chunk = b"AY RP " * (MEGABYTE // 6)
        for _ in range(40):
            sock = socket.create_connection(daemon.tcp("abused"), timeout=TIMEOUT)
            sock.setblocking(False)
            deadline = time.monotonic() + 0.1
            view = memoryview(chunk * 2)
            while view and time.monotonic() < deadline:
                try:
                    n = sock.send(view)
                except BlockingIOError:
                    time.sleep(0.005)
                    continue
                sent += n
                view = view[n:]
            grown = max(grown, rss_kib(pid) - rss_before)
            sock.close()
        assert daemon.running, daemon.stderr
        print(f"40 newcomers: {sent / MEGABYTE:.1f} MiB taken by the kernel; RSS {grown:+} KiB")
        assert grown < RSS_BOUND_KIB, f"the daemon's memory grew by {grown} KiB"
    finally:
        os.close(fd)
    still_usable(daemon)
