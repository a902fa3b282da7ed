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
* every round trip of the good client stays under :data:`support.RP_BOUND` (half a second,
  against well under a millisecond normally) and each answer is right;
* the abused board itself is still usable afterwards by a client that behaves.

Short pass: :data:`FLOOD_SECONDS` [0] seconds of flood (megabytes) and a few seconds of slow
reading; long pass (``--long`` / ``OMSD_LONG=1``): a minute of each.
"""

from __future__ import annotations

import re
import threading
import time
from pathlib import Path

from daemon.process import TIMEOUT, Conn, Daemon, Omsd

from .conftest import Scale
from .support import (
    RP_BOUND,
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
        while time.monotonic() - started < seconds:
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
    """A client that behaves gets the abused board back. Its line starts with a separator: the
    abuser's last command may be cut short (closing a socket with unread data resets the
    connection, and the kernel discards what the daemon had not read yet), and the board reads
    one stream, as on a serial line. Before its own answer it may get the answers to what the
    abuser wrote (``0``: ``test_churn.test_answers_to_a_vanished_client_do_not_go_to_the_next_one``)
    and one command error for the cut command."""
    with daemon.connect("abused") as conn:
        conn.send(b" \rAZ LP42 AZ RP")
        data = conn.read_until(b"42\n", timeout=5 * TIMEOUT)
        assert re.fullmatch(rb"(?:0\n)*(?:#\n)?42\n", data), data[-200:]


def report(label: str, trips: RoundTrips, grown: int, sent: int) -> None:
    print(f"{label}: {sent / MEGABYTE:.1f} MiB written; good board {trips}; RSS {grown:+} KiB")
    assert grown < RSS_BOUND_KIB, f"{label}: the daemon's memory grew by {grown} KiB"
    assert trips.worst < RP_BOUND, f"{label}: the good board was slowed: {trips}"


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
