"""The baselines: the plainest asyncio servers that can answer, on the same transports as omsd.

``python -m bench.echo --mode MODE --tcp 127.0.0.1:0 --pty PATH [--reply-file F --every N]``

It serves TCP sockets and ptys the way omsd does (an asyncio protocol on the event loop; a raw
pty whose slave it keeps open, its master read with ``add_reader``), on the same kind of loop
(asyncio's default, or uvloop under :mod:`bench.fastloop`), prints the same endpoint lines, and
does the least a server can do with what comes in. ``MODE``:

* ``plain`` (the latency baseline): an ``asyncio.Protocol`` whose ``data_received`` writes the
  fixed reply (the bytes of ``F``), once per chunk received, whatever the chunk; on the pty the
  same from the ``add_reader`` callback (``os.read`` then ``os.write``). One request at a time,
  one chunk is one request;
* ``buffered``: the same with an ``asyncio.BufferedProtocol`` reading into one reused buffer
  (on the pty ``os.readv`` into it), instead of the fresh bytes object of every read;
* ``count``: the reply once for every ``N`` bytes received, whatever the chunks (pipelined
  requests of ``N`` bytes each: the throughput and load baselines). A ``divmod`` per chunk;
* ``replay``: answers every ``N`` bytes received with the bytes of ``F``, released in proportion
  as the bytes arrive (after ``n`` bytes it has sent ``len(F) * n / N`` bytes of the cycle): the
  mixed throughput benchmark gives it the whole reply stream omsd produced for the whole
  command stream, so it moves exactly the bytes omsd moved;
* ``echo``: every chunk sent back as it came;
* ``delay``: each line ``D<seconds>`` answered with ``!\\x01\\n`` that many seconds after it was
  read, by ``loop.call_at``: the timer omsd uses for the end of a move, without the board.

SIGTERM or SIGINT: close everything, remove the pty links, exit 0.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import signal
import sys
import termios
import tty
from collections.abc import Callable
from pathlib import Path
from typing import cast

DONE = b"!\x01\n"
MODES = ("plain", "buffered", "count", "replay", "echo", "delay")
BUFFER = 65536


class Answer:
    """``replay``: what to send back for the bytes of one connection."""

    def __init__(self, reply: bytes | None, every: int) -> None:
        self.reply = reply
        self.every = every
        self.received = 0

    def _mark(self, n: int) -> int:
        assert self.reply is not None
        cycles, part = divmod(n, self.every)
        return cycles * len(self.reply) + part * len(self.reply) // self.every

    def __call__(self, data: bytes) -> bytes:
        reply = self.reply
        if reply is None:
            return data
        start = self._mark(self.received)
        self.received += len(data)
        end = self._mark(self.received)
        size = len(reply)
        out = bytearray()
        p = start
        while p < end:
            offset = p % size
            take = min(size - offset, end - p)
            out += reply[offset : offset + take]
            p += take
        return bytes(out)


class Count:
    """``count``: the reply once per ``every`` bytes in."""

    def __init__(self, reply: bytes, every: int) -> None:
        self.reply = reply
        self.every = every
        self.rest = 0

    def __call__(self, data: bytes) -> bytes:
        n, self.rest = divmod(self.rest + len(data), self.every)
        return self.reply * n


class Delay:
    """``D<seconds>\\n`` lines: the done marker after that many seconds, from when it was read."""

    def __init__(self, send: Callable[[bytes], None]) -> None:
        self.send = send
        self.line = bytearray()
        self.loop = asyncio.get_running_loop()

    def __call__(self, data: bytes) -> bytes:
        now = self.loop.time()
        self.line += data
        while (i := self.line.find(b"\n")) >= 0:
            text = bytes(self.line[:i]).strip()
            del self.line[: i + 1]
            if text.startswith(b"D"):
                self.loop.call_at(now + float(text[1:]), self.send, DONE)
        return b""


def answerer(
    options: argparse.Namespace, send: Callable[[bytes], None]
) -> Callable[[bytes], bytes]:
    """What the non-plain modes send back for a chunk."""
    mode = options.mode
    if mode == "delay":
        return Delay(send)
    if mode == "count":
        return Count(options.reply, options.every)
    if mode == "replay":
        return Answer(options.reply, options.every)
    return lambda data: data  # echo


class PlainEcho(asyncio.Protocol):
    """The latency baseline: a fixed reply written from ``data_received``."""

    def __init__(self, reply: bytes) -> None:
        self.reply = reply
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)

    def data_received(self, data: bytes) -> None:
        assert self.transport is not None
        self.transport.write(self.reply)


class BufferedEcho(asyncio.BufferedProtocol):
    """The same, reading into one buffer reused for every read."""

    def __init__(self, reply: bytes) -> None:
        self.reply = reply
        self.buffer = bytearray(BUFFER)
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)

    def get_buffer(self, sizehint: int) -> bytearray:
        return self.buffer

    def buffer_updated(self, nbytes: int) -> None:
        assert self.transport is not None
        self.transport.write(self.reply)


class TcpEcho(asyncio.Protocol):
    """The other modes on TCP."""

    def __init__(self, options: argparse.Namespace) -> None:
        self.options = options
        self.transport: asyncio.Transport | None = None
        self.answer: Callable[[bytes], bytes] = lambda data: b""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)
        self.answer = answerer(self.options, self.send)

    def send(self, data: bytes) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(data)

    def data_received(self, data: bytes) -> None:
        out = self.answer(data)
        if out:
            self.send(out)

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None


class PtyEcho:
    """A raw pty whose slave this process keeps open, as omsd's pty endpoint does; its master
    read with ``add_reader`` and written with ``os.write`` (what does not fit waits for
    ``add_writer``)."""

    def __init__(self, link: Path, options: argparse.Namespace) -> None:
        self.loop = asyncio.get_running_loop()
        self.link = link
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave, termios.TCSANOW)
        os.set_blocking(self.master, False)
        self.device = os.ttyname(self.slave)
        link.parent.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(FileNotFoundError):
            link.unlink()
        os.symlink(self.device, link)
        self.backlog = bytearray()
        self.writing = False
        self.reply: bytes = options.reply or b""
        self.buffer = bytearray(BUFFER)
        self.answer = answerer(options, self.send)
        readable = {"plain": self._plain, "buffered": self._buffered}.get(options.mode)
        self.loop.add_reader(self.master, readable or self._readable)

    def _plain(self) -> None:
        try:
            os.read(self.master, BUFFER)
        except OSError:
            return
        self.send(self.reply)

    def _buffered(self) -> None:
        try:
            os.readv(self.master, [self.buffer])
        except OSError:
            return
        self.send(self.reply)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, BUFFER)
        except OSError:
            return
        out = self.answer(data)
        if out:
            self.send(out)

    def send(self, data: bytes) -> None:
        if not self.backlog:
            try:
                n = os.write(self.master, data)
            except BlockingIOError:
                n = 0
            if n == len(data):
                return
            data = data[n:]
        self.backlog += data
        self._flush()

    def _flush(self) -> None:
        while self.backlog:
            try:
                n = os.write(self.master, self.backlog)
            except BlockingIOError:
                break
            del self.backlog[:n]
        if self.backlog and not self.writing:
            self.loop.add_writer(self.master, self._flush)
            self.writing = True
        elif not self.backlog and self.writing:
            self.loop.remove_writer(self.master)
            self.writing = False

    def close(self) -> None:
        self.loop.remove_reader(self.master)
        if self.writing:
            self.loop.remove_writer(self.master)
        with contextlib.suppress(OSError):
            if os.readlink(self.link) == self.device:
                self.link.unlink()
        for fd in (self.master, self.slave):
            with contextlib.suppress(OSError):
                os.close(fd)


def protocol(options: argparse.Namespace) -> Callable[[], asyncio.BaseProtocol]:
    if options.mode == "plain":
        return lambda: PlainEcho(options.reply)
    if options.mode == "buffered":
        return lambda: BufferedEcho(options.reply)
    return lambda: TcpEcho(options)


async def serve(options: argparse.Namespace) -> None:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    servers: list[asyncio.Server] = []
    ptys: list[PtyEcho] = []
    lines: list[str] = []
    try:
        for i, address in enumerate(options.tcp):
            host, port = address.rsplit(":", 1)
            server = await loop.create_server(protocol(options), host, int(port))
            servers.append(server)
            bound = server.sockets[0].getsockname()
            lines.append(f"echo{i + 1} echo {options.mode} tcp {bound[0]}:{bound[1]}")
        for i, link in enumerate(options.pty):
            pty = PtyEcho(Path(link), options)
            ptys.append(pty)
            lines.append(f"echo{i + 1} echo {options.mode} pty {link} -> {pty.device}")
        print("\n".join(lines), flush=True)
        await stop.wait()
    finally:
        for server in servers:
            server.close()
        for pty in ptys:
            pty.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.echo", description=__doc__)
    parser.add_argument("--mode", choices=MODES, default="plain")
    parser.add_argument("--tcp", action="append", default=[], metavar="HOST:PORT")
    parser.add_argument("--pty", action="append", default=[], metavar="LINK")
    parser.add_argument("--reply-file", type=Path, metavar="FILE")
    parser.add_argument("--every", type=int, default=1, metavar="N")
    options = parser.parse_args(argv)
    options.reply = options.reply_file.read_bytes() if options.reply_file else None
    if options.every < 1 or (options.reply is not None and not options.reply):
        parser.error("--every must be positive and the reply file not empty")
    if options.mode in ("plain", "buffered", "count", "replay") and options.reply is None:
        parser.error(f"--mode {options.mode} needs --reply-file")
    asyncio.run(serve(options))
    return 0


if __name__ == "__main__":
    sys.exit(main())
