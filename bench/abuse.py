"""A misbehaving client, as a process of its own: ``python -m bench.abuse KIND TARGET``.

``KIND`` is one of :data:`KINDS`; ``TARGET`` is ``HOST:PORT`` (or the pty's path for
``pty-flood``). It misbehaves until SIGTERM, then prints the bytes it got rid of and exits 0. A
process, not a thread of the measuring client, so that the good client's round trips never wait
for the abuser's share of one interpreter lock.

* ``flood``: ``AY RP`` written as fast as the daemon takes bytes, never a read;
* ``never-reads``: ``AA RP`` (four positions) 100 times every 20 ms, the answers never read;
* ``garbage``: random bytes (control characters, bytes above 0x7F, ``!``, ``@``, ``*``) as fast
  as the daemon takes them;
* ``churn``: connect, half a command, hang up (every third time with a reset), again and again;
* ``pty-flood``: ``AY RP`` written to the pty as fast as it takes them, never a read;
* ``slow-reader``: 40,000 ``AY RP`` at once, then one byte read a second.
"""

from __future__ import annotations

import contextlib
import os
import random
import select
import signal
import socket
import struct
import sys
import threading

KINDS = ("flood", "never-reads", "garbage", "churn", "pty-flood", "slow-reader")
stopping = threading.Event()


def address(text: str) -> tuple[str, int]:
    host, port = text.rsplit(":", 1)
    return host, int(port)


def write_until_stopped(send: object, fd: int, data: bytes) -> int:
    assert callable(send)
    chunk = data * max(1, 65536 // len(data))
    sent = pos = 0
    while not stopping.is_set():
        try:
            n = send(chunk[pos:])
        except BlockingIOError:
            select.select([], [fd], [], 0.05)
            continue
        except (ConnectionResetError, BrokenPipeError):
            return sent
        sent += n
        pos = (pos + n) % len(data)
    return sent


def flood(target: str) -> int:
    with socket.create_connection(address(target)) as sock:
        sock.setblocking(False)
        return write_until_stopped(sock.send, sock.fileno(), b"AY RP ")


def never_reads(target: str) -> int:
    sent = 0
    with socket.create_connection(address(target)) as sock:
        sock.setblocking(False)
        while not stopping.wait(0.02):
            with contextlib.suppress(BlockingIOError):
                sent += sock.send(b"AA RP " * 100)
    return sent


def garbage(target: str) -> int:
    rng = random.Random(7)
    sent = 0
    with socket.create_connection(address(target)) as sock:
        sock.setblocking(False)
        while not stopping.is_set():
            try:
                sent += sock.send(rng.randbytes(4096))
            except BlockingIOError:
                select.select([], [sock], [], 0.05)
            except (ConnectionResetError, BrokenPipeError):
                return sent
    return sent


def churn(target: str) -> int:
    sent = i = 0
    while not stopping.is_set():
        sock = socket.create_connection(address(target))
        if i % 2:
            sock.sendall(b"AX MR1")
            sent += 6
        if i % 3 == 0:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        sock.close()
        i += 1
    return sent


def pty_flood(target: str) -> int:
    fd = os.open(target, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        return write_until_stopped(lambda b: os.write(fd, b), fd, b"AY RP ")
    finally:
        os.close(fd)


def slow_reader(target: str) -> int:
    with socket.create_connection(address(target)) as sock:
        sock.setblocking(False)
        payload = memoryview(b"AY RP " * 40_000)
        sent = 0
        while payload and not stopping.is_set():
            try:
                n = sock.send(payload)
            except BlockingIOError:
                select.select([], [sock], [], 0.05)
                continue
            sent += n
            payload = payload[n:]
        while not stopping.wait(1.0):
            if select.select([sock], [], [], 0)[0] and not sock.recv(1):
                break
    return sent


ACTIONS = {
    "flood": flood,
    "never-reads": never_reads,
    "garbage": garbage,
    "churn": churn,
    "pty-flood": pty_flood,
    "slow-reader": slow_reader,
}


def main(argv: list[str]) -> int:
    if len(argv) != 2 or argv[0] not in ACTIONS:
        print(f"usage: python -m bench.abuse {{{','.join(KINDS)}}} TARGET", file=sys.stderr)
        return 2
    signal.signal(signal.SIGTERM, lambda *_: stopping.set())
    print("started", flush=True)
    sent = ACTIONS[argv[0]](argv[1])
    stopping.wait()
    print(sent, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
