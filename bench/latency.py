"""Reply latency: the ``RP`` round trip over TCP and over the pty, against the plainest servers.

All the servers run at once, each pinned to the servers' core(s) (the client on its own), and
the client sends ``RP`` and reads the whole reply, one request at a time, to each in turn in
blocks of :data:`BLOCK`, so they all see the same machine:

* omsd as users run it: a PC48-4E on the raw link, with the default live view (standard error
  in a file: the plain lines the journal gets) and a control socket;
* omsd with the view off (and no control socket), on the raw link and on the driver link;
* the baseline: the plainest server that can answer, an ``asyncio.Protocol`` whose
  ``data_received`` writes the fixed 5-byte reply omsd gives (``<LF><CR>0<LF><CR>``), on the
  same kind of loop; on the pty the same from an ``add_reader`` callback on a raw pty
  (:mod:`bench.echo` ``plain``);
* the same with an ``asyncio.BufferedProtocol`` reading into one reused buffer (``buffered``):
  what reading into a reused buffer buys, against asyncio's fresh 256 KiB per read;
* the floor: a blocking socket (a blocking pty) and a thread, no event loop (:mod:`bench.floor`);
* with uvloop (``--fast``, or when it can be imported): omsd as users run it with
  ``--loop uvloop`` (``pip install omsd[fast]``), and the plain echo on a uvloop loop
  (:mod:`bench.fastloop`).

omsd's own rows name asyncio's loop (``--loop asyncio``, what the default ``auto`` gives where
uvloop is not installed).

Targets (issue 16): omsd as users run it <= 1.10x the plain echo's median on TCP, <= 1.30x on
the pty; the driver link <= 1.10x the raw link; the default view <= 1.05x the view off. p99:
<= 2x (issue 7).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from bench import envs, procs
from bench.ports import Port, PtyPort, TcpPort
from bench.settings import Settings
from bench.table import Row, Target, skipped

REQUEST = b"RP"
BLOCK = 10
RAW_REPLY = b"\n\r0\n\r"
DRIVER_REPLY = b"0\n"
REPLY_SHAPE = {"raw": rb"\n\r-?\d+\n\r", "driver": rb"-?\d+\n"}


def percentile(samples: list[float], p: float) -> float:
    """Nearest-rank percentile: the smallest sample with at least ``p`` % of them at or below."""
    ordered = sorted(samples)
    rank = max(1, min(len(ordered), math.ceil(p / 100.0 * len(ordered) - 1e-9)))
    return ordered[rank - 1]


def median(samples: list[float]) -> float:
    ordered = sorted(samples)
    n = len(ordered)
    return ordered[n // 2] if n % 2 else (ordered[n // 2 - 1] + ordered[n // 2]) / 2.0


def first_reply(port: Port, link: str = "raw") -> bytes:
    """omsd's reply to ``RP``: PC48 §6.13 on the raw link, ``<LF><CR>n<LF><CR>``; the driver's
    ``n<LF>``."""
    port.write(REQUEST)
    reply = port.read_exact(2) if link == "raw" else b""
    reply += port.read_until(b"\n\r" if link == "raw" else b"\n")
    if not re.fullmatch(REPLY_SHAPE[link], reply):
        raise RuntimeError(f"unexpected reply to RP: {reply!r}")
    return reply


def round_trips(
    port: Port, reply: bytes, n: int, request: bytes = REQUEST, seconds: float = math.inf
) -> list[float]:
    """``n`` round trips (fewer if ``seconds`` run out), in seconds; every reply must be
    exactly ``reply``."""
    out: list[float] = []
    size = len(reply)
    clock = time.perf_counter
    stop = clock() + seconds
    for _ in range(n):
        t0 = clock()
        port.write(request)
        got = port.read_exact(size)
        t1 = clock()
        out.append(t1 - t0)
        if got != reply:
            raise RuntimeError(f"{request!r} answered {got!r}, expected {reply!r}")
        if t1 > stop:
            break
    return out


@dataclass
class Contender:
    """One endpoint under measurement and its round trips."""

    key: str
    port: Port
    reply: bytes
    request: bytes = REQUEST
    samples: list[float] = field(default_factory=list)

    @property
    def median(self) -> float:
        return median(self.samples)


def alternate(contenders: list[Contender], n: int, block: int = BLOCK) -> None:
    """``n`` round trips to each, in blocks of ``block`` taken in turn, after a warm-up."""
    for c in contenders:
        round_trips(c.port, c.reply, min(n, 50), c.request)
    while any(len(c.samples) < n for c in contenders):
        for c in contenders:
            k = min(block, n - len(c.samples))
            if k > 0:
                c.samples += round_trips(c.port, c.reply, k, c.request)


def us(seconds: float) -> float:
    return seconds * 1e6


def compare(
    name: str,
    a: Contender,
    b: Contender,
    target: Target | None,
    note: str = "",
    stat: Callable[[list[float]], float] = median,
) -> Row:
    return Row(name, "µs", us(stat(a.samples)), us(stat(b.samples)), target, note)


def p99(samples: list[float]) -> float:
    return percentile(samples, 99)


@dataclass
class Servers:
    """The servers of one latency run, by key (each with a TCP endpoint and a pty)."""

    started: dict[str, procs.Server] = field(default_factory=dict)
    replies: dict[str, bytes] = field(default_factory=dict)

    def ports(self, kind: str) -> list[Contender]:
        out = []
        for key, server in self.started.items():
            port: Port = TcpPort(server.tcp()) if kind == "tcp" else PtyPort(server.pty())
            out.append(Contender(key, port, self.replies[key]))
        return out


def fast_python(settings: Settings) -> tuple[procs.Python | None, str]:
    """This interpreter with uvloop on its path for the fast-loop rows (the baselines are run on
    uvloop by :mod:`bench.fastloop`, omsd by its own ``--loop uvloop``), or None and why not."""
    path = envs.uvloop_path()
    if path is None and settings.fast:
        try:
            path = envs.install_uvloop()
        except envs.Unavailable as exc:
            return None, str(exc)
    if path is None:
        return None, "uvloop is not installed (python -m bench --fast installs it in a cache)"
    return procs.Python(path=path, fast=True, label="uvloop"), ""


def start(settings: Settings, directory: Path, stack: contextlib.ExitStack) -> tuple[Servers, str]:
    s = Servers()

    def add(key: str, server: procs.Server, reply: bytes) -> None:
        s.started[key] = stack.enter_context(server)
        s.replies[key] = reply

    raw = procs.BoardSpec("latency", "PC48-4E", "raw", pty=True)
    driver = procs.BoardSpec("latency", "PC48-4E", "driver", pty=True)
    # asyncio's loop, named: what --loop auto gives where uvloop is not installed
    add("omsd", procs.omsd([raw], directory, view="auto", loop="asyncio"), RAW_REPLY)
    add("omsd-off", procs.omsd([raw], directory, loop="asyncio"), RAW_REPLY)
    add("omsd-driver", procs.omsd([driver], directory, loop="asyncio"), DRIVER_REPLY)
    for key, link in (("omsd", "raw"), ("omsd-off", "raw"), ("omsd-driver", "driver")):
        with TcpPort(s.started[key].tcp()) as port:
            got = first_reply(port, link)
        if got != s.replies[key]:
            raise RuntimeError(f"{key}: RP answered {got!r}, expected {s.replies[key]!r}")
    add("echo", procs.echo(directory, tcp=1, pty=1, reply=RAW_REPLY), RAW_REPLY)
    add(
        "buffered", procs.echo(directory, tcp=1, pty=1, reply=RAW_REPLY, mode="buffered"), RAW_REPLY
    )
    add("floor", procs.floor(directory, RAW_REPLY), RAW_REPLY)
    fast, why = fast_python(settings)
    if fast is not None:
        on_path = dataclasses.replace(fast, fast=False)  # omsd chooses uvloop itself
        add(
            "omsd-uvloop",
            procs.omsd([raw], directory, view="auto", python=on_path, loop="uvloop"),
            RAW_REPLY,
        )
        add(
            "echo-uvloop",
            procs.echo(directory, tcp=1, pty=1, reply=RAW_REPLY, python=fast),
            RAW_REPLY,
        )
    return s, why


def rows_for(kind: str, by: dict[str, Contender], n: int, fast_why: str) -> list[Row]:
    users, echo = by["omsd"], by["echo"]
    limit = 1.10 if kind == "tcp" else 1.30
    baseline = "Protocol echo" if kind == "tcp" else "add_reader echo"
    note = (
        f"{n:,} round trips to each of {len(by)} servers, in turn in blocks of {BLOCK};"
        f" medians: {', '.join(f'{k} {us(c.median):.1f}' for k, c in by.items())} µs"
    )
    rows = [
        compare(
            f"RP {kind}, median: omsd as users run it / {baseline}",
            users,
            echo,
            Target("ratio", "<=", limit),
            note,
        ),
        compare(
            f"RP {kind}, p99: omsd as users run it / {baseline}",
            users,
            echo,
            Target("ratio", "<=", 2.0),
            stat=p99,
        ),
        compare(f"RP {kind}, median: omsd view off / {baseline}", by["omsd-off"], echo, None),
        compare(
            f"RP {kind}, median: driver link / raw link (view off)",
            by["omsd-driver"],
            by["omsd-off"],
            Target("ratio", "<=", 1.10),
        ),
        compare(
            f"RP {kind}, median: default view / view off (the view's cost)",
            users,
            by["omsd-off"],
            Target("ratio", "<=", 1.05),
        ),
        compare(
            f"RP {kind}, median: {baseline} / the floor (blocking, no loop)",
            echo,
            by["floor"],
            None,
        ),
        compare(
            f"RP {kind}, median: reused buffer ("
            + ("BufferedProtocol" if kind == "tcp" else "os.readv")
            + f") / {baseline}",
            by["buffered"],
            echo,
            None,
        ),
    ]
    fast_names = (
        f"RP {kind}, median, uvloop: omsd as users run it / uvloop {baseline}",
        f"RP {kind}, median: omsd as users run it, uvloop / asyncio's loop",
    )
    if "omsd-uvloop" in by:
        rows += [
            compare(fast_names[0], by["omsd-uvloop"], by["echo-uvloop"], None),
            compare(fast_names[1], by["omsd-uvloop"], users, None),
        ]
    else:
        rows += [skipped(name, "µs", None, fast_why) for name in fast_names]
    return rows


def run(settings: Settings, directory: Path) -> list[Row]:
    n = settings.latency_samples
    rows: list[Row] = []
    with contextlib.ExitStack() as stack:
        servers, fast_why = start(settings, directory, stack)
        for kind in ("tcp", "pty"):
            contenders = servers.ports(kind)
            try:
                alternate(contenders, n)
            finally:
                for c in contenders:
                    c.port.close()
            rows += rows_for(kind, {c.key: c for c in contenders}, n, fast_why)
    return rows
