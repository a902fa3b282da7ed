"""The baseline: a bare asyncio server that answers with the same bytes on the same transport.

``python -m bench.echo --tcp 127.0.0.1:0 --pty PATH [--reply-file F --every N] [--delay]``

It serves TCP sockets and ptys the way omsd does (asyncio protocols on the event loop; a raw pty
whose slave it keeps open, its master read with ``add_reader``), prints the same endpoint lines,
and does the least a server can do with what comes in:

* by default it echoes every chunk back;
* with ``--reply-file F --every N`` it answers every ``N`` bytes received with the bytes of
  ``F``, released in proportion as the bytes arrive (after ``n`` bytes it has sent
  ``len(F) * n / N`` bytes of the cycle). So it moves exactly the bytes omsd moved: the latency
  benchmark gives it omsd's ``RP`` reply for the 2 bytes ``RP``, the throughput benchmark the
  whole reply stream omsd produced for the whole command stream;
* with ``--delay`` each line ``D<seconds>`` is answered with ``!\\x01\\n`` that many seconds after
  it was read, by ``loop.call_at``: the timer omsd uses for the end of a move, without the board.

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


class Answer:
    """What to send back for the bytes of one connection."""

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


class TcpEcho(asyncio.Protocol):
    def __init__(self, options: argparse.Namespace) -> None:
        self.options = options
        self.transport: asyncio.Transport | None = None
        self.answer: Callable[[bytes], bytes] = Answer(None, 1)

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.Transport, transport)
        if self.options.delay:
            self.answer = Delay(self.send)
        else:
            self.answer = Answer(self.options.reply, self.options.every)

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
    """A raw pty whose slave this process keeps open, as omsd's pty endpoint does."""

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
        self.answer: Callable[[bytes], bytes] = (
            Delay(self.send) if options.delay else Answer(options.reply, options.every)
        )
        self.loop.add_reader(self.master, self._readable)

    def _readable(self) -> None:
        try:
            data = os.read(self.master, 65536)
        except (BlockingIOError, OSError):
            return
        out = self.answer(data)
        if out:
            self.send(out)

    def send(self, data: bytes) -> None:
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


async def serve(options: argparse.Namespace) -> None:
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    servers: list[asyncio.Server] = []
    ptys: list[PtyEcho] = []
    try:
        for i, address in enumerate(options.tcp):
            host, port = address.rsplit(":", 1)
            server = await loop.create_server(lambda: TcpEcho(options), host, int(port))
            servers.append(server)
            bound = server.sockets[0].getsockname()
            print(f"echo{i + 1} echo raw tcp {bound[0]}:{bound[1]}", flush=True)
        for i, link in enumerate(options.pty):
            pty = PtyEcho(Path(link), options)
            ptys.append(pty)
            print(f"echo{i + 1} echo raw pty {link} -> {pty.device}", flush=True)
        await stop.wait()
    finally:
        for server in servers:
            server.close()
        for pty in ptys:
            pty.close()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.echo", description=__doc__)
    parser.add_argument("--tcp", action="append", default=[], metavar="HOST:PORT")
    parser.add_argument("--pty", action="append", default=[], metavar="LINK")
    parser.add_argument("--reply-file", type=Path, metavar="FILE")
    parser.add_argument("--every", type=int, default=1, metavar="N")
    parser.add_argument("--delay", action="store_true")
    options = parser.parse_args(argv)
    options.reply = options.reply_file.read_bytes() if options.reply_file else None
    if options.every < 1 or (options.reply is not None and not options.reply):
        parser.error("--every must be positive and the reply file not empty")
    asyncio.run(serve(options))
    return 0


if __name__ == "__main__":
    sys.exit(main())
