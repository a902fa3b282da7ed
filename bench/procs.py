"""The servers under measurement, as subprocesses: omsd itself, the baselines, the peers.

Each prints one line per endpoint on standard output, in omsd's format
(``<board> <model> <link> tcp 127.0.0.1:PORT`` and ``<board> <model> <link> pty PATH ->
/dev/pts/N``); :class:`Server` waits for those lines with a deadline and parses them. Standard
error goes to a file (shown if the server fails), so a chatty server never blocks on a pipe: a
server run "as users run it" writes its default view (plain lines, as under systemd or with
stderr redirected) to that file.

Placement: unpinned, two identical servers differ by up to 1.8x depending on the core they land
on (issue 16), so :func:`pin` puts this process (the client) on one core and every server on
the others (:data:`PINNING`), and says so in the table's header; with one core it cannot.

CPU cost is the process's time on the CPU: utime + stime from ``/proc/<pid>/stat``, and the
same to the nanosecond from ``/proc/<pid>/task/*/schedstat`` (:func:`cpu_exact`, what the
figures use: utime + stime only count 10 ms clock ticks).
"""

from __future__ import annotations

import contextlib
import os
import resource
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
ROOT = Path(__file__).resolve().parent.parent


@dataclass
class Pinning:
    """Which cores the client (this process and its threads) and the servers run on."""

    client: frozenset[int] | None = None
    servers: frozenset[int] | None = None
    why_not: str = "not pinned yet"

    def describe(self) -> str:
        if self.client is None or self.servers is None:
            return f"client and servers not pinned ({self.why_not})"
        return (
            f"client pinned to core {_cores(self.client)}, servers to core"
            f"{'s' * (len(self.servers) > 1)} {_cores(self.servers)} (sched_setaffinity)"
        )


def _cores(cores: frozenset[int]) -> str:
    return ",".join(str(c) for c in sorted(cores))


PINNING = Pinning()


def pin(enabled: bool = True) -> Pinning:
    """Pin this process to the first core it may use and leave the others to the servers
    started from now on (:func:`server_setup`). With one core, or ``enabled`` false, nothing
    is pinned and :data:`PINNING` says why."""
    allowed = sorted(os.sched_getaffinity(0))
    if not enabled:
        PINNING.why_not = "--no-pin"
    elif len(allowed) < 2:
        PINNING.why_not = f"only {len(allowed)} core available to this process"
    else:
        PINNING.client = frozenset(allowed[:1])
        PINNING.servers = frozenset(allowed[1:])
        os.sched_setaffinity(0, PINNING.client)
        PINNING.why_not = ""
    return PINNING


def server_setup() -> None:
    """In a server's child process before exec: its cores, and as many file descriptors as the
    hard limit allows (1,000 boards need more than the usual soft limit of 1,024)."""
    if PINNING.servers is not None:
        os.sched_setaffinity(0, PINNING.servers)
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if hard == resource.RLIM_INFINITY or hard > soft:
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))


def server_env(path: Sequence[str] = ()) -> dict[str, str]:
    """The environment of a server under test: never systemd's notify socket or journal; this
    checkout first on the module path (``python -m bench.echo``, and omsd from this tree under
    another interpreter), then ``path``."""
    env = dict(os.environ)
    for name in ("NOTIFY_SOCKET", "JOURNAL_STREAM", "WATCHDOG_USEC", "WATCHDOG_PID", "LISTEN_FDS"):
        env.pop(name, None)
    env["PYTHONUNBUFFERED"] = "1"
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), *path, env.get("PYTHONPATH")) if p)
    return env


@dataclass(frozen=True)
class Python:
    """An interpreter to run servers with, and what it needs on its module path: the running
    one by default; ``fast``: asyncio's loop replaced by uvloop (:mod:`bench.fastloop`)."""

    executable: str = sys.executable
    path: tuple[str, ...] = ()
    fast: bool = False
    label: str = ""

    def argv(self, module: str, args: Sequence[str]) -> list[str]:
        if self.fast:
            return [self.executable, "-m", "bench.fastloop", module, *args]
        return [self.executable, "-m", module, *args]


HERE = Python()


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


def rss_kib(pid: int) -> int:
    """Resident set size (``VmRSS`` in ``/proc/<pid>/status``), KiB."""
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError(f"no VmRSS for process {pid}")


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
    """A server subprocess (``python -m MODULE ARGS``, or any ``argv``) and its endpoints, on
    the servers' cores. ``started`` is when it was executed, ``ready`` when its last endpoint
    line came (``time.perf_counter``)."""

    def __init__(
        self,
        module: str,
        args: Sequence[str],
        expect: int,
        name: str = "",
        python: Python = HERE,
        argv: Sequence[str] | None = None,
        env: dict[str, str] | None = None,
        timeout: float = TIMEOUT,
    ) -> None:
        self.argv = list(argv) if argv is not None else python.argv(module, args)
        self.name = name or module
        self._err = tempfile.TemporaryFile()  # noqa: SIM115 - lives as long as the server
        self.started = time.perf_counter()
        self.proc = subprocess.Popen(
            self.argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self._err,
            env=env if env is not None else server_env(python.path),
            preexec_fn=server_setup,
        )
        try:
            self.endpoints = [Endpoint.parse(line) for line in self._lines(expect, timeout)]
            self.ready = time.perf_counter()
        except BaseException:
            self.kill()
            raise

    def _lines(self, n: int, timeout: float) -> list[str]:
        assert self.proc.stdout is not None
        fd = self.proc.stdout.fileno()
        data = b""
        deadline = time.monotonic() + timeout
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

    def rss_kib(self) -> int:
        """Resident memory now (``VmRSS``), KiB."""
        return rss_kib(self.proc.pid)

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
    tcp: bool = True


def omsd(
    boards: Sequence[BoardSpec],
    directory: Path,
    view: str = "off",
    python: Python = HERE,
    timeout: float = TIMEOUT,
    loop: str | None = None,
) -> Server:
    """Start omsd on ``boards``: each on a free TCP port (and a pty in ``directory`` if asked).
    ``view="off"``: no live view and no control socket, omsd stripped to its boards. Any other
    ``view`` (``"auto"``: omsd as users run it) keeps the default live view, which with standard
    error in a file is the plain lines systemd's journal gets, and a control socket in
    ``directory``, as the defaults have it. ``loop``: omsd's ``--loop`` (None: its default,
    auto, which is asyncio's loop unless uvloop can be imported)."""
    stamp = time.monotonic_ns()
    lines = [f'[log]\nview = "{view}"\n']
    if view == "off":
        lines.append("[control]\nsocket = false\n")
    else:
        lines.append(f'[control]\nsocket = "{directory / f"control-{stamp}.sock"}"\n')
    for b in boards:
        lines.append(f'[[board]]\nname = "{b.name}"\nmodel = "{b.model}"\nlink = "{b.link}"\n')
        if b.tcp:
            lines.append('tcp = "127.0.0.1:0"\n')
        if b.pty:
            lines.append(f'pty = "{directory / f"{b.name}-{stamp}"}"\n')
    config = directory / f"omsd-{len(boards)}-{stamp}.toml"
    config.write_text("".join(lines))
    expect = sum(b.tcp for b in boards) + sum(b.pty for b in boards)
    args = ["--config", str(config)] + (["--loop", loop] if loop is not None else [])
    return Server("omsd", args, expect, name="omsd", python=python, timeout=timeout)


def echo(
    directory: Path,
    tcp: int = 1,
    pty: int = 0,
    reply: bytes | None = None,
    every: int = 1,
    mode: str = "plain",
    python: Python = HERE,
    timeout: float = TIMEOUT,
) -> Server:
    """Start a baseline server (:mod:`bench.echo`) with ``tcp`` TCP endpoints and ``pty`` ptys
    in ``directory``, answering in ``mode`` (see there) with ``reply`` every ``every`` bytes."""
    args = ["--mode", mode]
    for _ in range(tcp):
        args += ["--tcp", "127.0.0.1:0"]
    stamp = time.monotonic_ns()
    for i in range(pty):
        args += ["--pty", str(directory / f"echo-{stamp}-{i}")]
    if reply is not None:
        path = directory / f"reply-{stamp}.bin"
        path.write_bytes(reply)
        args += ["--reply-file", str(path), "--every", str(every)]
    return Server(
        "bench.echo", args, tcp + pty, name=f"echo ({mode})", python=python, timeout=timeout
    )


def floor(directory: Path, reply: bytes, tcp: bool = True, pty: bool = True) -> Server:
    """Start the floor (:mod:`bench.floor`): blocking reads and writes, a thread per endpoint,
    no event loop."""
    stamp = time.monotonic_ns()
    path = directory / f"reply-{stamp}.bin"
    path.write_bytes(reply)
    args = ["--reply-file", str(path)]
    if tcp:
        args += ["--tcp", "127.0.0.1:0"]
    if pty:
        args += ["--pty", str(directory / f"floor-{stamp}")]
    return Server("bench.floor", args, tcp + pty, name="floor")
