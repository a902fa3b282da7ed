"""Idle cost and load cost: CPU of omsd serving many eight-axis boards, per second of wall time.

CPU is the server process's time on the CPU over the window, as a percentage of one core: read
to the nanosecond from ``/proc/<pid>/task/*/schedstat`` (:func:`bench.procs.cpu_exact`), because
utime + stime from ``/proc/<pid>/stat`` count whole 10 ms clock ticks, which is all of one idle
board's cost over a 1 s window; utime + stime over the same window are given in the notes. The
baseline is the echo server with the same endpoints (a TCP port and a pty per board), the same
clients and the same traffic, measured over the same window at the same time.

* Idle: 8 PC48-8 boards, a TCP client on each, connected (each asked ``WY`` once, to be sure it
  is attached) and then silent. Target (issue 7): <= 0.5 % of a core.
* Load: 1, 8, 32 and 128 PC48-8 boards on the driver link. On each, X, Y, Z, T jog (``JG``, both
  directions) and U, V, R, S run a queue of 30 back-and-forth moves (``MR3000 GO MR-3000 GO``,
  0.7 s each at VL5000 AC50000: a move ends, and the next starts, every 0.7 s on each of them),
  and a client polls the board with ``QA RP`` 10 times a second, one axis after the other
  (``AX QA RP;``, ``AY QA RP;``...). Targets: <= 10 % of a core at 8 boards (issue 7), <= 5 %
  at 128 boards (issue 16); the cost should grow with the traffic (CPU per poll about the same
  at 1 and at the most boards) and not with time (the second half of the window costs what the
  first did). The baseline is the echo in ``count`` mode (the same reply for every poll).
* Where the load's cost goes, at the most boards: the same boards and polls with nothing moving
  (``at rest``) and with the jogs alone (no queued moves), each against the echo; what the
  queued moves add, per move.
"""

from __future__ import annotations

import asyncio
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from bench import procs
from bench.ports import TcpPort
from bench.settings import Settings
from bench.table import Row, Target

if TYPE_CHECKING:  # omsd is imported where a benchmark runs it in this process
    from omsd.link import Link

MODEL = "PC48-8"
AXES = "XYZTUVRS"
PERIOD = 0.1  # QA RP 10 times a second
PARAMETERS = (
    b"AA VL5000,5000,5000,5000,5000,5000,5000,5000;"
    b" AC50000,50000,50000,50000,50000,50000,50000,50000;"
)
JOGS = b" AX JG2000; AY JG-2000; AZ JG3000; AT JG-3000;"
MOVES_QUEUED = 30  # on each of U, V, R, S
MOVES = b"".join(
    b" A" + a.encode() + b" " + b"MR3000 GO MR-3000 GO " * (MOVES_QUEUED // 2) for a in "UVRS"
)
SETUP = PARAMETERS + JOGS + MOVES + b"WY"
#: The breakdown of the load's cost at the most boards: the same boards and polls with nothing
#: moving, and with the jogs alone (no queued moves).
BREAKDOWN = {"at rest": PARAMETERS + b"WY", "jogs alone": PARAMETERS + JOGS + b"WY"}
WHAT_MOVES = {"at rest": "nothing moving", "jogs alone": "X, Y, Z, T jogging, no queued moves"}
REPLY = re.compile(rb"[PM][ND][NL][NH]\n-?\d+\n")


def percent(cpu: float, seconds: float) -> float:
    return 100.0 * cpu / seconds


def boards(prefix: str, n: int) -> list[procs.BoardSpec]:
    return [procs.BoardSpec(f"{prefix}{i + 1}", MODEL, "driver", pty=True) for i in range(n)]


# -- idle ---------------------------------------------------------------------------------------


def idle(settings: Settings, directory: Path) -> list[Row]:
    n = 8
    with (
        procs.omsd(boards("idle", n), directory) as omsd,
        procs.echo(directory, tcp=n, pty=n, reply=b"\n") as echo,
    ):
        ours = [TcpPort(omsd.tcp(i)) for i in range(n)]
        theirs = [TcpPort(echo.tcp(i)) for i in range(n)]
        try:
            for port in ours:
                port.write(b"WY")
                if b"PC48 ver" not in port.read_until(b"\n"):
                    raise RuntimeError("WY did not answer")
            for port in theirs:
                port.write(b"WY")
                port.read_exact(1)
            time.sleep(0.2)
            a0, b0, t0, k0 = omsd.cpu(), echo.cpu(), time.monotonic(), omsd.cpu_ticks()
            time.sleep(settings.idle_seconds)
            a1, b1, t1, k1 = omsd.cpu(), echo.cpu(), time.monotonic(), omsd.cpu_ticks()
        finally:
            for port in ours + theirs:
                port.close()
    wall = t1 - t0
    return [
        Row(
            f"idle cost, {n} boards x 8 axes",
            "% core",
            percent(a1 - a0, wall),
            percent(b1 - b0, wall),
            Target("figure", "<=", 0.5, "% core"),
            f"{n} silent TCP clients and {n} ptys; {1e3 * (a1 - a0):.1f} ms CPU over {wall:.1f} s"
            f" (utime + stime {1e3 * (k1 - k0):.0f} ms; baseline {1e3 * (b1 - b0):.1f} ms)",
        )
    ]


# -- load ---------------------------------------------------------------------------------------


def poll_request(k: int) -> bytes:
    return f"A{AXES[k % len(AXES)]} QA RP;".encode()


@dataclass
class Poller:
    """One client polling one board."""

    reader: asyncio.StreamReader
    writer: asyncio.StreamWriter
    reply_size: int | None  # the baseline's fixed reply size; None: omsd's, checked
    sent: int = 0
    data: bytearray = field(default_factory=bytearray)

    async def poll(self, start: float, stop: float) -> None:
        loop = asyncio.get_running_loop()
        k = 0
        while (t := start + k * PERIOD) < stop:
            await asyncio.sleep(max(0.0, t - loop.time()))
            self.writer.write(poll_request(k))
            self.sent = k = k + 1

    async def read(self) -> None:
        while chunk := await self.reader.read(65536):
            self.data += chunk

    def answered(self) -> int:
        if self.reply_size is not None:
            return len(self.data) // self.reply_size
        return self.data.count(b"\n") // 2

    def check(self) -> None:
        if self.answered() != self.sent:
            raise RuntimeError(f"{self.answered()} replies to {self.sent} polls")
        if self.reply_size is None:
            bad = REPLY.sub(b"", bytes(self.data))
            if bad:
                raise RuntimeError(f"unexpected replies: {bad[:200]!r}")


@dataclass
class Window:
    cpu: list[float]  # omsd then baseline, at start, middle, end
    polls: list[int]  # polls sent by then, omsd's clients
    times: list[float]
    ticks: list[float]  # omsd's utime + stime


async def _traffic(
    omsd: procs.Server, echo: procs.Server, n: int, reply: bytes, seconds: float, settle: float
) -> Window:
    loop = asyncio.get_running_loop()
    ours: list[Poller] = []
    theirs: list[Poller] = []
    for i in range(n):
        ours.append(Poller(*await asyncio.open_connection(*omsd.tcp(i)), None))
        theirs.append(Poller(*await asyncio.open_connection(*echo.tcp(i)), len(reply)))
    start = loop.time() + 0.05
    stop = start + settle + seconds
    readers = [asyncio.ensure_future(p.read()) for p in ours + theirs]
    pollers = [asyncio.ensure_future(p.poll(start, stop)) for p in ours + theirs]
    window = Window([], [], [], [])
    for when in (start + settle, start + settle + seconds / 2, start + settle + seconds):
        await asyncio.sleep(max(0.0, when - loop.time()))
        window.times.append(time.monotonic())
        window.cpu += [omsd.cpu(), echo.cpu()]
        window.ticks.append(omsd.cpu_ticks())
        window.polls.append(sum(p.sent for p in ours))
    await asyncio.gather(*pollers)
    deadline = loop.time() + 10.0
    while any(p.answered() < p.sent for p in ours + theirs) and loop.time() < deadline:
        await asyncio.sleep(0.02)
    for p in ours + theirs:
        p.writer.close()
    await asyncio.gather(*readers, return_exceptions=True)
    for p in ours + theirs:
        p.check()
    return window


@dataclass(frozen=True)
class Load:
    boards: int
    ours: float  # % core
    theirs: float
    ours_halves: tuple[float, float]  # CPU seconds, first and second half
    theirs_halves: tuple[float, float]
    polls: int
    wall: float
    ticks: float  # omsd's utime + stime over the window, seconds

    def per_poll(self, ours: bool = True) -> float:
        halves = self.ours_halves if ours else self.theirs_halves
        return sum(halves) / self.polls


def load_once(n: int, settings: Settings, directory: Path, setup: bytes = SETUP) -> Load:
    with procs.omsd(boards("load", n), directory) as omsd:
        for i in range(n):
            with TcpPort(omsd.tcp(i)) as port:
                port.write(setup)
                answer = port.read_until(b"\n")
                if b"PC48 ver" not in answer:
                    raise RuntimeError(f"the setup was refused: {answer!r}")
                port.write(poll_request(0))
                reply = port.read_until(b"\n") + port.read_until(b"\n")
                if not REPLY.fullmatch(reply):
                    raise RuntimeError(f"unexpected reply to QA RP: {reply!r}")
        with procs.echo(
            directory, tcp=n, pty=n, reply=reply, every=len(poll_request(0)), mode="count"
        ) as echo:
            w = asyncio.run(
                _traffic(omsd, echo, n, reply, settings.load_seconds, settings.load_settle)
            )
    c = w.cpu
    wall = w.times[2] - w.times[0]
    return Load(
        n,
        percent(c[4] - c[0], wall),
        percent(c[5] - c[1], wall),
        (c[2] - c[0], c[4] - c[2]),
        (c[3] - c[1], c[5] - c[3]),
        w.polls[2] - w.polls[0],
        wall,
        w.ticks[2] - w.ticks[0],
    )


def engine_per_poll(seconds: float, setup: bytes = SETUP) -> float:
    """CPU seconds per poll of the board engine and link alone, in this process and with no I/O:
    one board of the load (the same setup, ``QA RP`` every 0.1 s, run at its wake-ups as the
    daemon runs it: the moves nobody hears happen when the next poll comes) simulated for
    ``seconds`` on the manual clock; the best of 3. What the load's boards cost before any
    transport, log or event loop: a floor for the load cost row."""
    best = float("inf")
    for _ in range(3):
        link, t = engine_board(setup)
        c0 = time.process_time()
        polls = run_engine(link, t, seconds)
        best = min(best, (time.process_time() - c0) / polls)
    return best


def engine_board(setup: bytes = SETUP) -> tuple[Link, float]:
    """One board of the load on the driver link, in this process, given ``setup``; and the time
    on its manual clock when the setup was taken."""
    from omsd.board import Board
    from omsd.link import make_link
    from omsd.models import get_model

    board = Board(get_model(MODEL), now=0.0)
    link = make_link("driver", board)
    rest, t = setup, 0.0
    while rest:
        rest = rest[link.from_host(rest, t, 1) :]
        link.to_host(t)
        t += 0.001
    return link, t


def run_engine(link: Link, t: float, seconds: float) -> int:
    """Poll the board with ``QA RP`` every 0.1 s for ``seconds`` from ``t`` on its manual clock,
    run at its wake-ups as the daemon runs it; returns the number of polls."""
    polls, next_poll, end = 0, t + PERIOD, t + seconds
    while t < end:
        deadline = link.next_wakeup()  # as the daemon wakes it (omsd.engine.quiet)
        if deadline is not None and deadline < next_poll:
            t = max(t, deadline)
            link.to_host(t)
            continue
        t, next_poll = next_poll, next_poll + PERIOD
        link.from_host(poll_request(polls), t, 1)
        link.to_host(t)
        polls += 1
    return polls


def move_seconds() -> float:
    """How long one of the load's queued moves takes (``MR3000`` at VL5000 AC50000, linear
    ramps: 0.7 s; the next begins on its last tick)."""
    from omsd.engine.ramps import RampShape, move_time

    return move_time(3000.0, 5000.0, 50000.0, 0.0, RampShape())


def load(settings: Settings, directory: Path) -> list[Row]:
    runs = [load_once(n, settings, directory) for n in settings.load_boards]
    most = settings.load_boards[-1]
    parts = {what: load_once(most, settings, directory, setup) for what, setup in BREAKDOWN.items()}
    rows: list[Row] = []
    for r in runs:
        target = {
            8: Target("figure", "<=", 10.0, "% core"),  # issue 7
            128: Target("figure", "<=", 5.0, "% core"),  # issue 16
        }.get(r.boards)
        rows.append(
            Row(
                f"load cost, {r.boards} board{'s' * (r.boards > 1)} in motion, polled",
                "% core",
                r.ours,
                r.theirs,
                target,
                f"{r.polls / r.wall:.0f} polls/s; {1e6 * r.per_poll():.0f} µs CPU per poll"
                f" (baseline {1e6 * r.per_poll(False):.0f}); halves of the {r.wall:.1f} s window"
                f" {1e3 * r.ours_halves[0]:.0f} ms and {1e3 * r.ours_halves[1]:.0f} ms CPU"
                f" (utime + stime {1e3 * r.ticks:.0f} ms in all)",
            )
        )
    for what, r in parts.items():
        rows.append(
            Row(
                f"load cost, {r.boards} boards polled, {what}",
                "% core",
                r.ours,
                r.theirs,
                None,
                f"{1e6 * r.per_poll():.0f} µs CPU per poll"
                f" (baseline {1e6 * r.per_poll(False):.0f}): the same boards and polls as the"
                f" load, {WHAT_MOVES[what]}",
            )
        )
    first, last = runs[0], runs[-1]
    jogs = parts["jogs alone"]
    moves = len("UVRS") / move_seconds() * PERIOD  # queued moves begun per poll of a board
    per_move = (last.per_poll() - jogs.per_poll()) / moves
    # (in process, within the queues' length: 30 moves an axis, then the queued axes stand still)
    window = min(max(2.0, settings.load_seconds * 2), 0.9 * MOVES_QUEUED * move_seconds())
    engine = engine_per_poll(window)
    engine_jogs = engine_per_poll(window, BREAKDOWN["jogs alone"])
    rows.append(
        Row(
            f"load cost, {last.boards} boards: one queued move, CPU in omsd / in the engine alone",
            "µs",
            1e6 * per_move,
            1e6 * (engine - engine_jogs) / moves,
            None,
            f"what the load's queued moves add per poll ({1e6 * last.per_poll():.0f} µs with them,"
            f" {1e6 * jogs.per_poll():.0f} µs with the jogs alone, a run of its own: a difference"
            f" of two timed runs, as noisy as both), per move ({moves:.2f} a poll);"
            " the baseline: the same in process, one board on the manual clock"
            f" ({1e6 * engine:.1f} and {1e6 * engine_jogs:.1f} µs per poll), its data in the"
            " processor's caches from one poll to the next",
        )
    )
    rows.append(
        Row(
            f"load cost, {last.boards} boards: the board engine alone / omsd as users run it",
            "% core",
            percent(engine * last.polls, last.wall),
            last.ours,
            None,
            f"{1e6 * engine:.1f} µs CPU per poll in process, no I/O (one board of the load on the"
            f" manual clock, moves included), at the {last.polls / last.wall:.0f} polls/s of"
            " the row above",
        )
    )
    rows.append(
        Row(
            f"load growth, CPU per poll, {last.boards} vs {first.boards} board(s)",
            "x",
            last.per_poll() / first.per_poll() if first.per_poll() else None,
            (
                last.per_poll(False) / first.per_poll(False)
                if first.per_poll(False) and last.per_poll(False)
                else None
            ),
            Target("figure", "<=", 1.5, "x"),
            "grows with the traffic: CPU per poll stays about the same as boards are added",
            compare=False,
        )
    )
    a, b = last.ours_halves
    a2, b2 = last.theirs_halves
    rows.append(
        Row(
            f"load over time, CPU 2nd / 1st half, {last.boards} boards",
            "x",
            b / a if a else None,
            b2 / a2 if a2 else None,
            Target("figure", "<=", 1.25, "x"),
            "not with time: the second half of the window costs what the first did",
            compare=False,
        )
    )
    return rows
