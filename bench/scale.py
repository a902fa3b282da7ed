"""Many boards in one daemon: ready time, resident memory, idle CPU, the memory of one board.

omsd as users run it (default view, standard error in a file, a control socket) with
:attr:`Settings.scale_boards` PC48-8 boards on the driver link, each with a TCP port and a pty
(the file descriptor limit raised to its hard limit, :func:`bench.procs.server_setup`):

* ready: from exec to the last endpoint line (omsd prints them once every endpoint listens);
* resident memory (``VmRSS``) once ready, and per board: (RSS with N boards - RSS with one) /
  (N - 1), the one-board daemon started the same way;
* idle CPU: the process's time on the CPU over :attr:`Settings.scale_idle_seconds`, after the
  last board was asked ``WY`` (so the boards are known to answer) and a short settle.

The baseline is the plain echo with as many TCP endpoints and ptys, measured the same way, one
after the other (not at once: two thousand ptys each). Targets (issue 16): ready <= 2 s, <= 200
MiB, idle CPU 0.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from bench import procs
from bench.ports import TcpPort
from bench.settings import Settings
from bench.startup import current_bytecode
from bench.table import Row, Target

MODEL = "PC48-8"
READY_TIMEOUT = 120.0
SETTLE = 0.5


@dataclass(frozen=True)
class Measured:
    ready: float  # s
    rss: int  # KiB
    cpu: float  # % core over the idle window
    window: float  # s


def measure(server: procs.Server, seconds: float, ask: bytes, answer: bytes) -> Measured:
    ready = server.ready - server.started
    with TcpPort(server.tcp(len([e for e in server.endpoints if e.kind == "tcp"]) - 1)) as port:
        port.write(ask)
        if answer not in port.read_until(answer):
            raise RuntimeError(f"{server.name}: the last board did not answer {ask!r}")
    time.sleep(SETTLE)
    c0, t0 = server.cpu(), time.monotonic()
    time.sleep(seconds)
    c1, t1 = server.cpu(), time.monotonic()
    return Measured(ready, server.rss_kib(), 100.0 * (c1 - c0) / (t1 - t0), t1 - t0)


def boards(n: int) -> list[procs.BoardSpec]:
    return [procs.BoardSpec(f"b{i + 1}", MODEL, "driver", pty=True) for i in range(n)]


def run(settings: Settings, directory: Path) -> list[Row]:
    current_bytecode()
    n = settings.scale_boards
    seconds = settings.scale_idle_seconds
    with procs.omsd(boards(n), directory, view="auto", timeout=READY_TIMEOUT) as server:
        ours = measure(server, seconds, b"WY", b"PC48 ver")
    with procs.omsd(boards(1), directory, view="auto") as server:
        one = measure(server, 0.0, b"WY", b"PC48 ver")
    with procs.echo(directory, tcp=n, pty=n, reply=b"\n", timeout=READY_TIMEOUT) as server:
        theirs = measure(server, seconds, b"WY", b"\n")
    with procs.echo(directory, tcp=1, pty=1, reply=b"\n") as server:
        their_one = measure(server, 0.0, b"WY", b"\n")
    what = f"{n:,} boards in one daemon"
    return [
        Row(
            f"{what}: ready, exec to last endpoint line / echo",
            "s",
            ours.ready,
            theirs.ready,
            Target("figure", "<=", 2.0, "s"),
            f"{n:,} {MODEL} boards on the driver link, each a TCP port and a pty, default view;"
            f" the echo with {n:,} TCP endpoints and {n:,} ptys; one board ready in"
            f" {one.ready:.3f} s (echo {their_one.ready:.3f} s)",
        ),
        Row(
            f"{what}: resident memory / echo",
            "MiB",
            ours.rss / 1024,
            theirs.rss / 1024,
            Target("figure", "<=", 200.0, "MiB"),
            f"one board {one.rss / 1024:.1f} MiB (echo with one TCP port and pty"
            f" {their_one.rss / 1024:.1f} MiB)",
        ),
        Row(
            f"{what}: memory of one board / echo's per TCP port and pty",
            "KiB",
            (ours.rss - one.rss) / (n - 1),
            (theirs.rss - their_one.rss) / (n - 1),
            None,
            f"(RSS with {n:,} - RSS with 1) / {n - 1:,}",
        ),
        Row(
            f"{what}: idle CPU / echo",
            "% core",
            ours.cpu,
            theirs.cpu,
            Target("figure", "<=", 0.0, "% core"),
            f"over {ours.window:.1f} s, {SETTLE} s after the last board answered WY",
        ),
    ]
