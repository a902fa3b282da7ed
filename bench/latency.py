"""Reply latency: the ``RP`` round trip over TCP and over the pty, median and p99.

One PC48-4E on the raw link (reply ``<LF><CR>0<LF><CR>``: the motor never moves here) and the
baseline echo server answering the 2 bytes ``RP`` with those same 5 bytes, both running at once,
each with a TCP endpoint and a pty. The client sends ``RP`` and reads the whole reply, one
request at a time; requests go to omsd and to the baseline in alternate blocks, so both see the
same machine load. Targets (issue 7): median <= 1.5x the baseline, p99 <= 2x.
"""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

from bench import procs
from bench.ports import Port, PtyPort, TcpPort
from bench.settings import Settings
from bench.table import Row, Target

REQUEST = b"RP"
BLOCK = 10


def percentile(samples: list[float], p: float) -> float:
    """Nearest-rank percentile: the smallest sample with at least ``p`` % of them at or below."""
    ordered = sorted(samples)
    rank = max(1, min(len(ordered), math.ceil(p / 100.0 * len(ordered) - 1e-9)))
    return ordered[rank - 1]


def median(samples: list[float]) -> float:
    ordered = sorted(samples)
    n = len(ordered)
    return ordered[n // 2] if n % 2 else (ordered[n // 2 - 1] + ordered[n // 2]) / 2.0


def first_reply(port: Port) -> bytes:
    """omsd's reply to ``RP`` on the raw link: PC48 §6.13, ``<LF><CR>n<LF><CR>``."""
    port.write(REQUEST)
    reply = port.read_exact(2) + port.read_until(b"\n\r")
    if not re.fullmatch(rb"\n\r-?\d+\n\r", reply):
        raise RuntimeError(f"unexpected reply to RP: {reply!r}")
    return reply


def round_trips(port: Port, reply: bytes, n: int) -> list[float]:
    """``n`` round trips, in seconds; every reply must be exactly ``reply``."""
    out: list[float] = []
    size = len(reply)
    clock = time.perf_counter
    for _ in range(n):
        t0 = clock()
        port.write(REQUEST)
        got = port.read_exact(size)
        out.append(clock() - t0)
        if got != reply:
            raise RuntimeError(f"RP answered {got!r}, expected {reply!r}")
    return out


def side_by_side(ours: Port, theirs: Port, reply: bytes, n: int) -> tuple[list[float], list[float]]:
    round_trips(ours, reply, min(n, 50))  # warm up both
    round_trips(theirs, reply, min(n, 50))
    a: list[float] = []
    b: list[float] = []
    while len(a) < n:
        k = min(BLOCK, n - len(a))
        a += round_trips(ours, reply, k)
        b += round_trips(theirs, reply, k)
    return a, b


def rows_for(transport: str, a: list[float], b: list[float]) -> list[Row]:
    note = f"{len(a)} round trips each, alternating blocks of {BLOCK}"
    return [
        Row(
            f"latency RP {transport}, median",
            "µs",
            median(a) * 1e6,
            median(b) * 1e6,
            Target("ratio", "<=", 1.5),
            note,
        ),
        Row(
            f"latency RP {transport}, p99",
            "µs",
            percentile(a, 99) * 1e6,
            percentile(b, 99) * 1e6,
            Target("ratio", "<=", 2.0),
        ),
    ]


def run(settings: Settings, directory: Path) -> list[Row]:
    n = settings.latency_samples
    board = procs.BoardSpec("latency", "PC48-4E", "raw", pty=True)
    with procs.omsd([board], directory) as omsd:
        with TcpPort(omsd.tcp()) as port:
            reply = first_reply(port)
        with procs.echo(directory, tcp=1, pty=1, reply=reply, every=len(REQUEST)) as echo:
            rows: list[Row] = []
            with TcpPort(omsd.tcp()) as ours, TcpPort(echo.tcp()) as theirs:
                rows += rows_for("tcp", *side_by_side(ours, theirs, reply, n))
            with PtyPort(omsd.pty()) as ours, PtyPort(echo.pty()) as theirs:
                rows += rows_for("pty", *side_by_side(ours, theirs, reply, n))
    return rows
