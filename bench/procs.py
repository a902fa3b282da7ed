"""The servers under measurement, as subprocesses: omsd itself and the baseline echo server.

Both print one line per endpoint on standard output, in omsd's format
(``<board> <model> <link> tcp 127.0.0.1:PORT`` and ``<board> <model> <link> pty PATH ->
/dev/pts/N``); :class:`Server` waits for those lines with a deadline and parses them. Standard
error goes to a file (shown if the server fails), so a chatty server never blocks on a pipe.

CPU cost is the process's time on the CPU: utime + stime from ``/proc/<pid>/stat``, and the
same to the nanosecond from ``/proc/<pid>/task/*/schedstat`` (:func:`cpu_exact`, what the
figures use: utime + stime only count 10 ms clock ticks).
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Self

TIMEOUT = 15.0
"""Seconds allowed for a server to start or stop (it normally takes a fraction of one)."""

CLOCK_TICK = os.sysconf("SC_CLK_TCK")


def server_env() -> dict[str, str]:
    """The environment of a server under test: never systemd's notify socket or journal."""
    env = dict(os.environ)
    for name in ("NOTIFY_SOCKET", "JOURNAL_STREAM", "WATCHDOG_USEC", "WATCHDOG_PID", "LISTEN_FDS"):
        env.pop(name, None)
    env["PYTHONUNBUFFERED"] = "1"
    # ``python -m bench.echo`` from wherever the benchmark was started
    root = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return env


def cpu_seconds(pid: int) -> float:
    """utime + stime of process ``pid`` so far, in seconds (``/proc/<pid>/stat`` fields 14 and
    15, counted in clock ticks of 1/SC_CLK_TCK s)."""
    with open(f"/proc/{pid}/stat", "rb") as f:
        text = f.read()
    fields = text[text.rindex(b")") + 2 :].split()  # fields[0] is field 3 (state)
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICK


def cpu_exact(pid: int) -> float:
    """The same CPU time to the nanosecond: the kernel's on-CPU time of each live thread
    (``/proc/<pid>/task/*/schedstat``, first field). utime + stime are this, rounded to clock
    ticks (10 ms), too coarse for a one-second window or a single idle board. Falls back on
    :func:`cpu_seconds` where the kernel has no schedstat."""
    total = 0
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/schedstat", "rb") as f:
                total += int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return cpu_seconds(pid)
    return total / 1e9


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nobody listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass(frozen=True)
class Endpoint:
    """One endpoint line."""

    board: str
    model: str
    link: str
    kind: str  # "tcp" or "pty"
    address: str

    @classmethod
    def parse(cls, line: str) -> Endpoint:
        parts = line.rstrip("\n").split(" ", 4)
        if len(parts) != 5 or parts[3] not in ("tcp", "pty"):
            raise RuntimeError(f"not an endpoint line: {line!r}")
        return cls(*parts)

    @property
    def tcp(self) -> tuple[str, int]:
        host, port = self.address.rsplit(":", 1)
        return host.strip("[]"), int(port)

    @property
    def pty(self) -> str:
        """The pty's symlink."""
        return self.address.split(" -> ")[0]


class Server:
    """A server subprocess (``python -m MODULE ARGS``) and its endpoints."""

    def __init__(self, module: str, args: Sequence[str], expect: int, name: str = "") -> None:
        self.argv = [sys.executable, "-m", module, *args]
        self.name = name or module
        self._err = tempfile.TemporaryFile()  # noqa: SIM115 - lives as long as the server
        self.proc = subprocess.Popen(
            self.argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self._err,
            env=server_env(),
        )
        try:
            self.endpoints = [Endpoint.parse(line) for line in self._lines(expect)]
        except BaseException:
            self.kill()
            raise

    def _lines(self, n: int) -> list[str]:
        assert self.proc.stdout is not None
        fd = self.proc.stdout.fileno()
        data = b""
        deadline = time.monotonic() + TIMEOUT
        while data.count(b"\n") < n:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([fd], [], [], max(left, 0.0))
            chunk = os.read(fd, 65536) if ready else b""
            if not chunk:
                got = data.count(b"\n")
                raise RuntimeError(
                    f"{self.name}: {got} of {n} endpoint lines"
                    f" (exit status {self.proc.poll()}); stderr: {self.stderr()[-2000:]!r}"
                )
            data += chunk
        return data.decode().splitlines()[:n]

    def stderr(self) -> str:
        self._err.seek(0)
        return self._err.read().decode(errors="replace")

    @property
    def pid(self) -> int:
        return self.proc.pid

    def cpu(self) -> float:
        """CPU seconds used so far (:func:`cpu_exact`)."""
        return cpu_exact(self.proc.pid)

    def cpu_ticks(self) -> float:
        """CPU seconds used so far, from utime + stime (:func:`cpu_seconds`)."""
        return cpu_seconds(self.proc.pid)

    def tcp(self, i: int = 0) -> tuple[str, int]:
        """The address of the ``i``-th TCP endpoint."""
        return [e for e in self.endpoints if e.kind == "tcp"][i].tcp

    def pty(self, i: int = 0) -> str:
        """The symlink of the ``i``-th pty endpoint."""
        return [e for e in self.endpoints if e.kind == "pty"][i].pty

    def stop(self) -> None:
        """SIGTERM, then SIGKILL if it does not exit in time."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(TIMEOUT)
        self.kill()

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(TIMEOUT)
        if self.proc.stdout is not None:
            self.proc.stdout.close()
        self._err.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


@dataclass(frozen=True)
class BoardSpec:
    """One ``[[board]]`` of an omsd configuration."""

    name: str
    model: str
    link: str = "raw"
    pty: bool = False


def omsd(boards: Sequence[BoardSpec], directory: Path) -> Server:
    """Start omsd on ``boards``: each on a free TCP port (and a pty in ``directory`` if asked),
    no live view, no control socket."""
    lines = ['[log]\nview = "off"\n', "[control]\nsocket = false\n"]
    for b in boards:
        lines.append(
            f'[[board]]\nname = "{b.name}"\nmodel = "{b.model}"\nlink = "{b.link}"\n'
            'tcp = "127.0.0.1:0"\n'
        )
        if b.pty:
            lines.append(f'pty = "{directory / b.name}"\n')
    config = directory / f"omsd-{len(boards)}-{time.monotonic_ns()}.toml"
    config.write_text("".join(lines))
    expect = len(boards) + sum(b.pty for b in boards)
    return Server("omsd", ["--config", str(config)], expect, name="omsd")


def echo(
    directory: Path,
    tcp: int = 1,
    pty: int = 0,
    reply: bytes | None = None,
    every: int = 1,
    delay: bool = False,
) -> Server:
    """Start the baseline server (:mod:`bench.echo`) with ``tcp`` TCP endpoints and ``pty`` ptys
    in ``directory``. ``reply``/``every``: answer every ``every`` bytes in with ``reply`` (spread
    in proportion as the bytes come); without ``reply`` it echoes. ``delay``: the done-marker
    timer of the fidelity benchmark."""
    args: list[str] = []
    for _ in range(tcp):
        args += ["--tcp", "127.0.0.1:0"]
    stamp = time.monotonic_ns()
    for i in range(pty):
        args += ["--pty", str(directory / f"echo-{stamp}-{i}")]
    if reply is not None:
        path = directory / f"reply-{stamp}.bin"
        path.write_bytes(reply)
        args += ["--reply-file", str(path), "--every", str(every)]
    if delay:
        args.append("--delay")
    return Server("bench.echo", args, tcp + pty, name="echo")
