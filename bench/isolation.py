"""Isolation and churn: the figures the robustness tests used to assert, measured here instead.

Isolation (issue 7: "a board whose client misbehaves never delays another board's replies";
``tests/robustness/test_isolation.py`` and ``test_flood.py`` now check order, counts and
memory): one daemon, two PC48-4E boards, ``abused`` and ``good`` (driver link). The good client
asks ``AY RP`` (reply ``-777<LF>``) with 2 ms between requests, first with all quiet, then for
:attr:`Settings.isolation_seconds` while a misbehaving client (:mod:`bench.abuse`, a process of
its own on the client's core) works on the abused board. Figure: the worst round trip during the
abuse; baseline: the worst round trip over as long with all quiet; target: <= 500 ms, the bound
the tests asserted. The medians are in the notes.

Churn (``tests/robustness/test_churn.py`` sized its move from how fast the machine churned): a
cycle is connect (or open the pty), ``RP``, read the answer, close; milliseconds per cycle,
against the plain echo (the same cycle with nothing behind it).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from bench import procs
from bench.latency import median
from bench.ports import PtyPort, TcpPort
from bench.settings import Settings
from bench.table import Row, Target

ABUSES = (
    ("flood", "driver"),
    ("flood", "raw"),
    ("never-reads", "driver"),
    ("never-reads", "raw"),
    ("garbage", "driver"),
    ("churn", "driver"),
    ("pty-flood", "driver"),
    ("slow-reader", "driver"),
)
PAUSE = 0.002
ANSWER = b"-777\n"


def trips(port: TcpPort, seconds: float = 0.0, count: int = 0) -> list[float]:
    """``AY RP`` round trips for ``seconds`` (or ``count`` of them), each checked."""
    out: list[float] = []
    stop = time.monotonic() + seconds
    clock = time.perf_counter
    while (count and len(out) < count) or (not count and time.monotonic() < stop):
        t0 = clock()
        port.write(b"AY RP")
        got = port.read_exact(len(ANSWER))
        out.append(clock() - t0)
        if got != ANSWER:
            raise RuntimeError(f"the good board answered {got!r}")
        time.sleep(PAUSE)
    return out


def abused(kind: str, link: str, settings: Settings, directory: Path) -> Row:
    pty = kind == "pty-flood"
    boards = [
        procs.BoardSpec("abused", "PC48-4E", link, pty=pty),
        procs.BoardSpec("good", "PC48-4E", "driver"),
    ]
    with procs.omsd(boards, directory) as daemon, TcpPort(daemon.tcp(1)) as good:
        good.write(b"AY LP-777 RP")
        if good.read_until(b"\n") != ANSWER:
            raise RuntimeError("the good board did not take LP")
        quiet = trips(good, seconds=settings.isolation_seconds)
        target = daemon.pty() if pty else "{}:{}".format(*daemon.tcp(0))
        abuser = subprocess.Popen(
            [sys.executable, "-m", "bench.abuse", kind, target],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            env=procs.server_env(),
        )
        try:
            assert abuser.stdout is not None
            if abuser.stdout.readline() != b"started\n":
                raise RuntimeError(f"the {kind} client did not start")
            time.sleep(0.05)
            during = trips(good, seconds=settings.isolation_seconds)
            if daemon.proc.poll() is not None:
                raise RuntimeError(f"omsd exited: {daemon.stderr()[-500:]}")
        finally:
            abuser.terminate()
            out, _ = abuser.communicate(timeout=procs.TIMEOUT)
    sent = int(out.split()[-1]) if out.split() else 0
    return Row(
        f"isolation, {kind} ({link}) on one board: the other's worst RP / quiet",
        "ms",
        max(during) * 1e3,
        max(quiet) * 1e3,
        Target("figure", "<=", 500.0, "ms"),
        f"{len(during)} round trips in {settings.isolation_seconds:g} s ({len(quiet)} quiet);"
        f" median"
        f" {median(during) * 1e6:.0f} µs (quiet {median(quiet) * 1e6:.0f} µs);"
        f" the abuser got rid of {sent / 1024:,.0f} KiB",
    )


def run(settings: Settings, directory: Path) -> list[Row]:
    return [abused(kind, link, settings, directory) for kind, link in ABUSES]


def tcp_cycle(address: tuple[str, int], reply: bytes) -> None:
    with TcpPort(address) as port:
        port.write(b"RP")
        if port.read_exact(len(reply)) != reply:
            raise RuntimeError("wrong answer in a churn cycle")


def pty_cycle(path: str, reply: bytes) -> None:
    with PtyPort(path) as port:
        port.write(b"RP")
        got = port.read_exact(len(reply))
    if got != reply:
        raise RuntimeError(f"wrong answer in a churn cycle: {got!r}")


def cycles(cycle: object, n: int) -> float:
    assert callable(cycle)
    t0 = time.perf_counter()
    for _ in range(n):
        cycle()
    return (time.perf_counter() - t0) / n


def churn(settings: Settings, directory: Path) -> list[Row]:
    n = settings.churn_cycles
    reply = b"0\n"
    board = procs.BoardSpec("churn", "PC48-4E", "driver", pty=True)
    with (
        procs.omsd([board], directory) as omsd,
        procs.echo(directory, tcp=1, pty=1, reply=reply) as echo,
    ):
        rows = []
        for kind in ("tcp", "pty"):
            times: dict[str, float] = {}
            for key, server in (("omsd", omsd), ("echo", echo)):
                if kind == "tcp":
                    address = server.tcp()
                    times[key] = cycles(lambda a=address: tcp_cycle(a, reply), n)
                else:
                    path = os.path.realpath(server.pty())
                    times[key] = cycles(lambda p=path: pty_cycle(p, reply), n)
            rows.append(
                Row(
                    f"churn, {kind}: {'connect' if kind == 'tcp' else 'open'}, RP, close / echo",
                    "ms",
                    times["omsd"] * 1e3,
                    times["echo"] * 1e3,
                    None,
                    f"{n} cycles each, the driver link, view off" if kind == "tcp" else "",
                )
            )
    return rows
