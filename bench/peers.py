"""Peers (``python -m bench --peers``, never in CI): other device simulators beside omsd.

Each peer is installed on demand into its own environment in the cache (:mod:`bench.envs`),
started on a free port on the servers' core(s), and measured in the same run as omsd as users
run it (a PC48-4E on the raw link, default view) and the plain ``asyncio.Protocol`` echo:

* sinstruments with the IcePAP simulator (``pip install icepap[simulator] sinstruments``;
  ``sinstruments-server`` with a JSON configuration of one axis), asked ``?POS 1<CR>``, answering
  ``?POS 0<LF>``;
* lewis's example motor (``pip install lewis``; ``lewis -k lewis.examples example_motor`` with
  its defaults), asked ``P?<CR><LF>``, answering ``0.0<CR><LF>``.

Round trips alternate in blocks between omsd, the echo and the peer (the peer's count capped so
that it takes about :data:`PEER_SECONDS`); then :data:`PIPELINED` requests are pipelined to each
(written back to back from one thread while another reads every reply). Targets (issue 16):
omsd as users run it answers faster than every peer (ratio <= 1) and pipelines more (>= 1). A
peer that cannot be installed or started gets rows that say why.
"""

from __future__ import annotations

import json
import socket
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from bench import envs, procs
from bench.latency import RAW_REPLY, Contender, alternate, first_reply, round_trips
from bench.ports import TcpPort
from bench.settings import Settings
from bench.table import Row, Target, skipped
from bench.throughput import pipeline

PEER_SECONDS = 5.0
PIPELINED = 20_000
CHUNK = 4096


@dataclass(frozen=True)
class Peer:
    name: str
    packages: list[str]
    request: bytes
    reply: bytes
    argv: Callable[[Path, int, Path], list[str]]  # (venv python, port, directory) -> argv


def icepap_argv(python: Path, port: int, directory: Path) -> list[str]:
    config = directory / f"icepap-{port}.json"
    device = {
        "class": "IcePAP",
        "name": "icepap",
        "package": "icepap.simulator",
        "transports": [{"type": "tcp", "url": f"127.0.0.1:{port}"}],
        "axes": [{"address": 1}],
    }
    config.write_text(json.dumps({"devices": [device]}))
    return [str(python.parent / "sinstruments-server"), "-c", str(config)]


def lewis_argv(python: Path, port: int, directory: Path) -> list[str]:
    return [
        str(python.parent / "lewis"),
        "-k",
        "lewis.examples",
        "example_motor",
        "-p",
        f"stream: {{bind_address: 127.0.0.1, port: {port}}}",
    ]


PEERS = (
    Peer(
        "sinstruments IcePAP",
        ["icepap[simulator]", "sinstruments"],
        b"?POS 1\r",
        b"?POS 0\n",
        icepap_argv,
    ),
    Peer("lewis example motor", ["lewis"], b"P?\r\n", b"0.0\r\n", lewis_argv),
)


def wait_accepting(server: procs.Server, port: int, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
            return
        except OSError:
            if server.proc.poll() is not None:
                raise RuntimeError(
                    f"exited {server.proc.returncode}: {server.stderr()[-300:]!r}"
                ) from None
            if time.monotonic() > deadline:
                raise RuntimeError(f"not accepting after {timeout:.0f} s") from None
            time.sleep(0.05)


def pipelined(address: tuple[str, int], request: bytes, reply: bytes, n: int) -> float:
    """Replies per second for ``n`` pipelined ``request``, each answered with ``reply``."""
    per_chunk = max(1, CHUNK // len(request))
    chunks = [request * per_chunk] * (n // per_chunk)
    if n % per_chunk:
        chunks.append(request * (n % per_chunk))
    with TcpPort(address) as port:
        elapsed, data = pipeline(port, chunks, n * len(reply))
    if data != reply * n:
        raise RuntimeError(f"{len(data)} bytes of replies, not {n} times {reply!r}")
    return n / elapsed


def names(peer: Peer) -> tuple[str, str]:
    request = peer.request.decode().strip()
    return (
        f"peer, round trip median: omsd as users run it (RP) / {peer.name} ({request})",
        f"peer, pipelined: omsd as users run it (RP) / {peer.name} ({request})",
    )


def measure(
    peer: Peer,
    settings: Settings,
    directory: Path,
    omsd: procs.Server,
    echo: procs.Server,
    counter: procs.Server,
) -> list[Row]:
    latency_name, pipelined_name = names(peer)
    faster = Target("ratio", "<=", 1.0)
    more = Target("ratio", ">=", 1.0)
    try:
        python = envs.venv(f"peers/{peer.name.split()[0]}", sys.executable, peer.packages)
    except envs.Unavailable as exc:
        return [
            skipped(latency_name, "µs", faster, str(exc)),
            skipped(pipelined_name, "replies/s", more, str(exc)),
        ]
    port = procs.free_port()
    argv = peer.argv(python, port, directory)
    with procs.Server(peer.name, [], 0, name=peer.name, argv=argv) as server:
        try:
            wait_accepting(server, port)
        except RuntimeError as exc:
            reason = f"{peer.name} did not start: {exc}"
            return [
                skipped(latency_name, "µs", faster, reason),
                skipped(pipelined_name, "replies/s", more, reason),
            ]
        with (
            TcpPort(omsd.tcp()) as a,
            TcpPort(echo.tcp()) as b,
            TcpPort(("127.0.0.1", port)) as c,
        ):
            warm = round_trips(c, peer.reply, 20, peer.request)
            each = sorted(warm)[len(warm) // 2]
            n = max(50, min(settings.peer_samples, int(PEER_SECONDS / each)))
            ours = Contender("omsd", a, RAW_REPLY)
            plain = Contender("echo", b, RAW_REPLY)
            theirs = Contender(peer.name, c, peer.reply, peer.request)
            alternate([ours, plain, theirs], n)
        m = PIPELINED if not settings.quick else 1_000
        rate_ours = pipelined(omsd.tcp(), b"RP", RAW_REPLY, m)
        rate_theirs = pipelined(("127.0.0.1", port), peer.request, peer.reply, m)
        rate_echo = pipelined(counter.tcp(), b"RP", RAW_REPLY, m)
    return [
        Row(
            latency_name,
            "µs",
            ours.median * 1e6,
            theirs.median * 1e6,
            faster,
            f"{n:,} round trips each; Protocol echo {plain.median * 1e6:.1f} µs;"
            f" {' '.join(peer.packages)} in {python.parent.parent}",
        ),
        Row(
            pipelined_name,
            "replies/s",
            rate_ours,
            rate_theirs,
            more,
            f"{m:,} requests in writes of about {CHUNK} bytes; count echo {rate_echo:,.0f}/s",
        ),
    ]


def run(settings: Settings, directory: Path) -> list[Row]:
    board = procs.BoardSpec("peers", "PC48-4E", "raw")
    rows: list[Row] = []
    with (
        procs.omsd([board], directory, view="auto") as omsd,
        procs.echo(directory, tcp=1, reply=RAW_REPLY) as echo,
        procs.echo(directory, tcp=1, reply=RAW_REPLY, every=2, mode="count") as counter,
    ):
        with TcpPort(omsd.tcp()) as port:
            first_reply(port)
        for peer in PEERS:
            rows += measure(peer, settings, directory, omsd, echo, counter)
    return rows
