"""``python -m bench.opcodes``: the daemon's bytecodes per poll, counted, by file and function.

:mod:`bench.instructions` counts the board engine alone; this counts everything the event loop's
thread runs for a poll: the daemon's own path (:mod:`omsd.service`, :mod:`omsd.transport.tcp`,
:mod:`omsd.telemetry.traffic`, :mod:`omsd.timebase`, :mod:`omsd.pacing`, :mod:`omsd.wakeups`),
asyncio's, and the engine's. The daemon is started in this process as ``omsd`` starts it
(:class:`omsd.daemon.Daemon`, the view off, no control socket) with ``-n`` boards of
:mod:`bench.cost`'s model, each on a TCP port of its own, on an event loop in a thread of its
own; each board is given a setup (``--variant``: the load, the board at rest, the jogs alone)
and then polled with ``QA RP`` by a client in the main thread, all boards a round, a round every
``--period`` seconds. The loop's thread alone is
traced (``sys.settrace`` with ``f_trace_opcodes``, set from a loop callback) and every opcode
counted; the sum is divided by the polls the boards answered (the calls of ``RP``'s handler).

The daemon's own files give the same count on every run (at rest: nothing else runs between
the polls); the engine's count under the load moves with the moves the real clock lets happen,
asyncio's with how many sockets one ``select`` finds ready. A developer's tool, not a row of
the table: tracing makes the daemon some ten times slower, so no time is measured.
"""

from __future__ import annotations

import argparse
import asyncio
import linecache
import os
import socket
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path
from types import CodeType, FrameType
from typing import Any

from bench.cost import BREAKDOWN, MODEL, PERIOD, SETUP, poll_request

VARIANTS = {"load": SETUP, **BREAKDOWN}
#: The daemon's own path, the files counted line by line with ``--lines``.
DAEMON_FILES = (
    "omsd/service.py",
    "omsd/transport/tcp.py",
    "omsd/telemetry/traffic.py",
    "omsd/timebase.py",
    "omsd/pacing.py",
    "omsd/wakeups.py",
)


def _group(code: CodeType) -> str:
    name = code.co_filename
    for path in DAEMON_FILES:
        if name.endswith(path):
            return path
    if f"{os.sep}omsd{os.sep}" in name:
        return "omsd, the rest (engine, link, board)"
    if f"{os.sep}asyncio{os.sep}" in name or name.endswith("selectors.py"):
        return "asyncio"
    return "other"


class Tracer:
    """Opcodes counted per code object (and per line of the daemon's files); calls of RP."""

    def __init__(self, lines: bool) -> None:
        from omsd.dialects.shared import reports

        self.rp = reports._rp.__code__
        self.polls = 0
        self.opcodes: Counter[CodeType] = Counter()
        self.lines: Counter[tuple[str, int]] = Counter()
        self._mine: dict[CodeType, bool] = {}
        self._by_line = lines

    def __call__(self, frame: FrameType, event: str, arg: Any) -> Any:
        if event != "call":
            return None
        if frame.f_code is self.rp:
            self.polls += 1
        frame.f_trace_opcodes = True
        return self._opcode

    def _opcode(self, frame: FrameType, event: str, arg: Any) -> Any:
        if event == "opcode":
            code = frame.f_code
            self.opcodes[code] += 1
            if self._by_line:
                mine = self._mine.get(code)
                if mine is None:
                    mine = self._mine[code] = code.co_filename.endswith(DAEMON_FILES)
                if mine:
                    self.lines[code.co_filename, frame.f_lineno] += 1
        return self._opcode


def _config(n: int, directory: Path) -> Path:
    lines = ['[log]\nview = "off"\n[control]\nsocket = false\n']
    for i in range(n):
        lines.append(
            f'[[board]]\nname = "board{i + 1}"\nmodel = "{MODEL}"\nlink = "driver"\n'
            'tcp = "127.0.0.1:0"\n'
        )
    path = directory / "omsd.toml"
    path.write_text("".join(lines))
    return path


def _read_lines(sock: socket.socket, count: int) -> None:
    got = b""
    while got.count(b"\n") < count:
        chunk = sock.recv(65536)
        if not chunk:
            raise RuntimeError("omsd closed the connection")
        got += chunk


def _in_loop(loop: asyncio.AbstractEventLoop, tracer: Tracer | None) -> None:
    """Trace the loop's thread with ``tracer`` from now on (None: no more)."""
    done = threading.Event()

    def settrace() -> None:
        sys.settrace(tracer)
        done.set()

    loop.call_soon_threadsafe(settrace)
    done.wait(10)


def count(n: int, rounds: int, setup: bytes, period: float, lines: bool) -> Tracer:
    """Start the daemon on ``n`` boards, give each ``setup``, poll them ``rounds`` times with
    the loop's thread traced."""
    from omsd.config import load_config
    from omsd.daemon import Daemon
    from omsd.telemetry.traffic import TrafficLog

    tracer = Tracer(lines)
    ports: list[int] = []
    ready = threading.Event()
    loop = asyncio.new_event_loop()
    stop = asyncio.Event()
    failed: list[BaseException] = []

    async def serve(config: Path) -> None:
        with open(os.devnull, "w") as null:
            daemon = Daemon(load_config(config), TrafficLog(view="off", stream=null), null)
            try:
                for endpoint in await daemon.start():
                    ports.append(int(endpoint.address.rsplit(":", 1)[1]))
            finally:
                ready.set()
            await stop.wait()
            await daemon.stop(quiet=True)

    def run(config: Path) -> None:
        try:
            loop.run_until_complete(serve(config))
        except BaseException as exc:  # said in the main thread
            failed.append(exc)
            ready.set()

    with tempfile.TemporaryDirectory() as directory:
        thread = threading.Thread(target=run, args=(_config(n, Path(directory)),))
        thread.start()
        try:
            ready.wait(60)
            if failed:
                raise failed[0]
            clients = [socket.create_connection(("127.0.0.1", port)) for port in ports]
            try:
                for client in clients:
                    client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    client.sendall(setup)
                    _read_lines(client, 1)  # WY: the version

                def poll(k: int) -> None:
                    for client in clients:
                        client.sendall(poll_request(k))
                    for client in clients:
                        _read_lines(client, 2)  # QA: the status; RP: the position
                    time.sleep(period)

                for k in range(3):  # every connection's path taken once before counting
                    poll(k)
                _in_loop(loop, tracer)
                for k in range(rounds):
                    poll(k)
                _in_loop(loop, None)
            finally:
                for client in clients:
                    client.close()
        finally:
            loop.call_soon_threadsafe(stop.set)
            thread.join(60)
            loop.close()
    return tracer


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.opcodes", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("-n", "--boards", type=int, default=16, help="boards (16)")
    parser.add_argument("-r", "--rounds", type=int, default=20, help="polls of each board (20)")
    parser.add_argument(
        "--variant", default="at rest", choices=VARIANTS, help="the boards' setup (at rest)"
    )
    parser.add_argument("--period", type=float, default=PERIOD, help="seconds between rounds")
    parser.add_argument("--top", type=int, default=30, help="functions listed (30)")
    parser.add_argument("--lines", action="store_true", help="the daemon's files line by line")
    args = parser.parse_args(argv)
    tracer = count(args.boards, args.rounds, VARIANTS[args.variant], args.period, args.lines)
    polls = tracer.polls
    if polls != args.boards * args.rounds:
        print(f"{polls} polls answered of {args.boards * args.rounds}", file=sys.stderr)
        return 1
    groups: Counter[str] = Counter()
    for code, opcodes in tracer.opcodes.items():
        groups[_group(code)] += opcodes
    own = sum(groups[path] for path in DAEMON_FILES)
    print(f"{args.boards} boards ({args.variant}), {polls} polls: bytecodes per poll")
    print(f"{sum(groups.values()) / polls:10.1f}  in all")
    print(f"{own / polls:10.1f}  the daemon's own path")
    for group, opcodes in groups.most_common():
        print(f"{opcodes / polls:10.1f}    {group}")
    root = str(Path.cwd()) + os.sep
    if args.top:
        print("functions:")
        for code, opcodes in tracer.opcodes.most_common(args.top):
            name = code.co_filename.removeprefix(root)
            print(f"{opcodes / polls:10.1f}  {name}:{code.co_name}")
    if args.lines:
        print("lines of the daemon's own path:")
        for (name, line), opcodes in sorted(tracer.lines.items()):
            text = linecache.getline(name, line).rstrip()
            print(f"{opcodes / polls:10.1f}  {name.removeprefix(root)}:{line} {text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
