"""The subscription's cost (issue 18): ``omsd top`` left open on a daemon whose 8 boards move.

"With the page open and 8 boards moving, the daemon's CPU rises by <= 2 % of a core", and the
view "can be left open for an hour with bounded memory on both sides (measured and stated)".
The web page will use the same subscription ``omsd top`` uses, so the rows measure ``omsd top``
itself: run in a pty of 100 x 30 (drawing the live screen, as a person would see it), its
output read and thrown away.

The daemon serves 8 PC48-8 boards on the driver link, the view off, a control socket. On each,
X, Y, Z and T jog, and a client polls the board 10 times a second (``AX QA RP;``, ``AY QA
RP;``...) and, every 0.7 s, starts a move of 3,000 steps on U, V, R or S in turn with ``ID``
(a done event every 0.7 s per board): every board moves all the time, its state changes at
every look and its events never stop.

* CPU rise: the daemon's CPU over a window with ``omsd top`` open, less its CPU over a window
  as long without it (the same load, just before). Target: <= 2 % of a core.
* Memory: the daemon's and ``omsd top``'s resident memory (VmRSS) at the start and the end of
  the window with ``omsd top`` open, after a warm-up. Bounded memory shows as no growth.
* A subscriber that never reads (``traffic`` on, every chunk asked for) while a client floods
  a board with pipelined ``RP``: the daemon's memory once its queue for that subscriber is full,
  against the same flood without it. Its queue is bounded (:mod:`omsd.control.watch`): the
  difference is what it holds, and it stops growing.

``python -m bench.watch --minutes 60`` runs the first window for as long, printing the memory
and CPU of both sides every few minutes: the hour of the issue, measured rather than inferred.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import fcntl
import json
import os
import struct
import subprocess
import sys
import termios
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from bench import procs
from bench.settings import Settings
from bench.table import Row, Target

BOARDS = 8
MODEL = "PC48-8"
PERIOD = 0.1  # a poll every 0.1 s per board
MOVE_EVERY = 7  # polls between two moves: one every 0.7 s per board
SETUP = (
    b"AA VL5000,5000,5000,5000,5000,5000,5000,5000;"
    b" AC50000,50000,50000,50000,50000,50000,50000,50000;"
    b" AX JG2000; AY JG-2000; AZ JG3000; AT JG-3000; WY"
)
FLOOD = b"RP" * 200  # every 10 ms to one board while the stuck subscriber is measured
PREFIX = "subscription, 8 boards moving"
NAMES = (
    f"{PREFIX}: daemon CPU rise with omsd top open",
    f"{PREFIX}: daemon memory growth with omsd top open",
    f"{PREFIX}: omsd top's memory growth",
    f"{PREFIX}: daemon memory held for a subscriber that never reads",
)


def start_daemon(directory: Path) -> tuple[procs.Server, Path]:
    stamp = time.monotonic_ns()
    socket = directory / f"watch-{stamp}.sock"
    lines = ['[log]\nview = "off"\n', f'[control]\nsocket = "{socket}"\n']
    for i in range(BOARDS):
        lines.append(f'[[board]]\nname = "b{i + 1}"\nmodel = "{MODEL}"\ntcp = "127.0.0.1:0"\n')
    config = directory / f"watch-{stamp}.toml"
    config.write_text("".join(lines))
    return procs.Server("omsd", ["--config", str(config)], BOARDS, name="omsd"), socket


class Top:
    """``omsd top`` on a pty of its own, its output read and dropped by a thread."""

    def __init__(self, socket: Path, rate: float = 10.0) -> None:
        self.master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
        env = {k: v for k, v in procs.server_env().items() if k not in ("COLUMNS", "LINES")}
        env["TERM"] = "xterm-256color"
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "omsd", "top", "--socket", str(socket), "--rate", str(rate)],
            stdin=slave,
            stdout=slave,
            stderr=slave,
            env=env,
            start_new_session=True,
        )
        os.close(slave)
        self.bytes = 0
        self.drawn = threading.Event()
        self._tail = b""
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            self.bytes += len(data)
            if not self.drawn.is_set():
                self._tail = (self._tail + data)[-4096:]
                if b"q: quit" in self._tail:
                    self.drawn.set()

    def cpu(self) -> float:
        return procs.cpu_exact(self.proc.pid)

    def rss_kib(self) -> int:
        return procs.rss_kib(self.proc.pid)

    def quit(self) -> int:
        with contextlib.suppress(OSError):
            os.write(self.master, b"q")
        try:
            status = self.proc.wait(procs.TIMEOUT)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            status = self.proc.wait(procs.TIMEOUT)
        self._reader.join(procs.TIMEOUT)
        os.close(self.master)
        return status


@dataclass
class Sample:
    t: float
    cpu: float
    rss: int
    top_cpu: float = 0.0
    top_rss: int = 0


def sample(omsd: procs.Server, top: Top | None = None) -> Sample:
    return Sample(
        time.monotonic(),
        omsd.cpu(),
        omsd.rss_kib(),
        top.cpu() if top is not None else 0.0,
        top.rss_kib() if top is not None else 0,
    )


class Load:
    """The 8 boards kept moving and polled (see the module's docstring)."""

    def __init__(self, omsd: procs.Server) -> None:
        self.omsd = omsd
        self.tasks: list[asyncio.Task[None]] = []
        self.writers: list[asyncio.StreamWriter] = []

    async def start(self) -> None:
        for i in range(BOARDS):
            reader, writer = await asyncio.open_connection(*self.omsd.tcp(i))
            writer.write(SETUP)
            if b"PC48 ver" not in await asyncio.wait_for(reader.readuntil(b"\n"), 10.0):
                raise RuntimeError("the setup was refused")
            self.writers.append(writer)
            self.tasks.append(asyncio.ensure_future(self._drain(reader)))
            self.tasks.append(asyncio.ensure_future(self._poll(writer, i)))

    @staticmethod
    async def _drain(reader: asyncio.StreamReader) -> None:
        while await reader.read(65536):
            pass

    @staticmethod
    async def _poll(writer: asyncio.StreamWriter, board: int) -> None:
        loop = asyncio.get_running_loop()
        start = loop.time()
        k = 0
        while True:
            await asyncio.sleep(max(0.0, start + k * PERIOD - loop.time()))
            axis = "XYZTUVRS"[k % 8]
            request = f"A{axis} QA RP;"
            if k % MOVE_EVERY == board % MOVE_EVERY:
                move = (k // MOVE_EVERY) % 8
                sign = "-" if move >= 4 else ""
                request += f" A{'UVRS'[move % 4]} MR{sign}3000 GO ID;"
            writer.write(request.encode())
            k += 1

    async def flood(self, seconds: float) -> None:
        """Pipelined ``RP`` to the first board, read as it comes, for ``seconds``."""
        reader, writer = await asyncio.open_connection(*self.omsd.tcp(0))
        drain = asyncio.ensure_future(self._drain(reader))
        loop = asyncio.get_running_loop()
        stop = loop.time() + seconds
        while loop.time() < stop:
            writer.write(FLOOD)
            await writer.drain()
            await asyncio.sleep(0.01)
        writer.close()
        await asyncio.gather(drain, return_exceptions=True)

    async def stop(self) -> None:
        for task in self.tasks:
            task.cancel()
        await asyncio.gather(*self.tasks, return_exceptions=True)
        for writer in self.writers:
            writer.close()


async def stuck_subscriber(socket: Path) -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
    """A subscriber of every chunk of traffic that reads nothing (its stream reader holds at
    most 128 KiB before it stops taking more from the socket)."""
    reader, writer = await asyncio.open_unix_connection(str(socket), limit=64 * 1024)
    writer.write(b'{"id": 1, "op": "subscribe", "traffic": true}\n')
    await writer.drain()
    return reader, writer


async def unstick(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> dict[str, object]:
    """Read what waited, unsubscribe; what the daemon counted for this subscriber."""
    writer.write(b'{"id": 2, "op": "unsubscribe"}\n')
    await writer.drain()
    while True:
        line = await asyncio.wait_for(reader.readline(), 30.0)
        if not line:
            raise RuntimeError("the daemon closed the connection")
        if line.startswith(b'{"id":2,'):
            writer.close()
            result: dict[str, object] = json.loads(line)["result"]
            return result


async def measure(settings: Settings, omsd: procs.Server, socket: Path) -> list[Row]:
    window = settings.watch_seconds
    load = Load(omsd)
    await load.start()
    try:
        await asyncio.sleep(window / 10)
        a0 = sample(omsd)
        await asyncio.sleep(window)
        a1 = sample(omsd)
        top = Top(socket)
        try:
            if not await asyncio.to_thread(top.drawn.wait, procs.TIMEOUT):
                raise RuntimeError(f"omsd top drew nothing (exit status {top.proc.poll()})")
            await asyncio.sleep(window / 5)  # its first screens, the daemon's first looks
            b0 = sample(omsd, top)
            await asyncio.sleep(window)
            b1 = sample(omsd, top)
        finally:
            status = top.quit()
        if status != 0:
            raise RuntimeError(f"omsd top exited {status} after q")
        fill = max(1.0, window / 3)
        c0 = sample(omsd)
        await load.flood(fill + window)
        c1 = sample(omsd)
        reader, writer = await stuck_subscriber(socket)
        flood = asyncio.ensure_future(load.flood(fill + window))
        await asyncio.sleep(fill)
        d_mid = sample(omsd)
        await flood
        d1 = sample(omsd)
        stats = await unstick(reader, writer)
    finally:
        await load.stop()
    without = 100.0 * (a1.cpu - a0.cpu) / (a1.t - a0.t)
    with_top = 100.0 * (b1.cpu - b0.cpu) / (b1.t - b0.t)
    top_cpu = 100.0 * (b1.top_cpu - b0.top_cpu) / (b1.t - b0.t)
    polls = f"{BOARDS} boards polled 10 times a second, a move every 0.7 s on each"
    return [
        Row(
            NAMES[0],
            "% core",
            with_top - without,
            without,
            Target("figure", "<=", 2.0, "% core"),
            f"{polls}; daemon {with_top:.2f} % core with omsd top open (rate 10) and"
            f" {without:.2f} % without, over {window:.1f} s each; omsd top itself"
            f" {top_cpu:.2f} % core, {top.bytes / 1024:,.0f} KiB drawn",
            compare=False,
        ),
        Row(
            NAMES[1],
            "KiB",
            float(b1.rss - b0.rss),
            float(a1.rss - a0.rss),
            Target("figure", "<=", 512.0, "KiB"),
            f"VmRSS {b0.rss:,} -> {b1.rss:,} KiB over {window:.1f} s with omsd top open"
            f" (without: {a0.rss:,} -> {a1.rss:,} KiB); python -m bench.watch --minutes 60"
            " for the hour",
            compare=False,
        ),
        Row(
            NAMES[2],
            "KiB",
            float(b1.top_rss - b0.top_rss),
            float(b0.top_rss),
            None,  # a window of seconds sees rich's caches fill (to their bound, in minutes)
            f"VmRSS {b0.top_rss:,} -> {b1.top_rss:,} KiB over {window:.1f} s (the baseline is"
            " where it started); its first minutes fill rich's caches of string widths and"
            " escapes to their bound (about 2.5 MiB): python -m bench.watch --minutes 60 shows"
            " the plateau",
            compare=False,
        ),
        Row(
            NAMES[3],
            "KiB",
            float(d1.rss - c1.rss),
            float(c1.rss - c0.rss),
            Target("figure", "<=", 2048.0, "KiB"),
            f"pipelined RP flooding one board; with the stuck subscriber VmRSS {c1.rss:,} ->"
            f" {d_mid.rss:,} KiB once its queue is full ({fill:.1f} s) -> {d1.rss:,} KiB"
            f" {window:.1f} s later; the baseline is the same flood without it; the daemon"
            f" counted for it {stats}",
            compare=False,
        ),
    ]


def run(settings: Settings, directory: Path) -> list[Row]:
    omsd, socket = start_daemon(directory)
    with omsd:
        return asyncio.run(measure(settings, omsd, socket))


# -- the hour ------------------------------------------------------------------------------------


async def long_run(minutes: float, every: float, rate: float, directory: Path) -> None:
    omsd, socket = start_daemon(directory)
    with omsd:
        load = Load(omsd)
        await load.start()
        top = Top(socket, rate)
        try:
            if not await asyncio.to_thread(top.drawn.wait, procs.TIMEOUT):
                raise RuntimeError("omsd top drew nothing")
            print(
                f"omsd top open on {BOARDS} moving, polled boards, rate {rate:g}, for"
                f" {minutes:g} min; VmRSS KiB and % of a core over each interval",
                flush=True,
            )
            print("minute  daemon_rss  daemon_cpu  top_rss  top_cpu  top_drawn_KiB", flush=True)
            start = time.monotonic()
            last = first = sample(omsd, top)
            k = 0
            while time.monotonic() - start < minutes * 60:
                k += 1
                await asyncio.sleep(max(0.0, start + k * every * 60 - time.monotonic()))
                now = sample(omsd, top)
                span = now.t - last.t
                cpu = 100 * (now.cpu - last.cpu) / span
                top_cpu = 100 * (now.top_cpu - last.top_cpu) / span
                print(
                    f"{(now.t - start) / 60:6.1f}  {now.rss:10,}  {cpu:10.2f}  {now.top_rss:7,}"
                    f"  {top_cpu:7.2f}  {top.bytes / 1024:13,.0f}",
                    flush=True,
                )
                last = now
            print(
                f"growth from minute 0 to {(last.t - start) / 60:.1f}: daemon"
                f" {last.rss - first.rss:+,} KiB, omsd top {last.top_rss - first.top_rss:+,} KiB",
                flush=True,
            )
        finally:
            status = top.quit()
            await load.stop()
        if status != 0:
            raise RuntimeError(f"omsd top exited {status} after q")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.watch", description=__doc__)
    parser.add_argument("--minutes", type=float, default=60.0, help="how long (default 60)")
    parser.add_argument("--every", type=float, default=5.0, help="minutes between two lines")
    parser.add_argument("--rate", type=float, default=10.0, help="omsd top's --rate (10)")
    options = parser.parse_args(argv)
    procs.pin()
    import tempfile

    with tempfile.TemporaryDirectory(prefix="omsd-watch-") as tmp:
        asyncio.run(long_run(options.minutes, options.every, options.rate, Path(tmp)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
