"""The floor: blocking reads and writes, no event loop, a fixed reply for every read.

``python -m bench.floor --reply-file F [--tcp 127.0.0.1:0] [--pty PATH]``

A thread per endpoint (and per TCP connection) blocks in ``recv``/``read`` and answers each
read with the bytes of ``F`` (``sendall``/``os.write``). No server written in Python answers a
single request sooner on this machine: what is left is the kernel, the interpreter's call into
it and the client. Endpoint lines as :mod:`bench.echo`'s. SIGTERM or SIGINT: exit 0.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import socket
import sys
import termios
import threading
import tty
from pathlib import Path


def serve_tcp(listener: socket.socket, reply: bytes) -> None:
    while True:
        conn, _ = listener.accept()
        threading.Thread(target=answer_tcp, args=(conn, reply), daemon=True).start()


def answer_tcp(conn: socket.socket, reply: bytes) -> None:
    with conn:
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        recv, send = conn.recv, conn.sendall
        with contextlib.suppress(OSError):
            while recv(65536):
                send(reply)


def serve_pty(master: int, reply: bytes) -> None:
    read, write = os.read, os.write
    with contextlib.suppress(OSError):
        while read(master, 65536):
            write(master, reply)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.floor", description=__doc__)
    parser.add_argument("--reply-file", type=Path, required=True, metavar="FILE")
    parser.add_argument("--tcp", metavar="HOST:PORT")
    parser.add_argument("--pty", metavar="LINK")
    options = parser.parse_args(argv)
    reply = options.reply_file.read_bytes()
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    lines: list[str] = []
    link: Path | None = None
    if options.tcp:
        host, port = options.tcp.rsplit(":", 1)
        listener = socket.create_server((host, int(port)))
        bound = listener.getsockname()
        threading.Thread(target=serve_tcp, args=(listener, reply), daemon=True).start()
        lines.append(f"floor1 floor blocking tcp {bound[0]}:{bound[1]}")
    if options.pty:
        master, slave = os.openpty()
        tty.setraw(slave, termios.TCSANOW)
        device = os.ttyname(slave)
        link = Path(options.pty)
        with contextlib.suppress(FileNotFoundError):
            link.unlink()
        os.symlink(device, link)
        threading.Thread(target=serve_pty, args=(master, reply), daemon=True).start()
        lines.append(f"floor1 floor blocking pty {link} -> {device}")
    print("\n".join(lines), flush=True)
    stop.wait()
    if link is not None:
        with contextlib.suppress(OSError):
            link.unlink()
    return 0


if __name__ == "__main__":
    sys.exit(main())
