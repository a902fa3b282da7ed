"""Start-up: the daemon's first accepted connection, and the commands a user types.

* First accept: ``omsd --board PC48-4E --tcp 127.0.0.1:PORT --pty LINK --control SOCKET`` (as
  users run it: default link and view, standard error in a file) is started on a port known to
  be free, and a client tries to connect every millisecond from the moment before ``exec`` until
  it is accepted. The baseline is the echo server started the same way (a Python interpreter
  that imports asyncio and listens): the cost of Python itself. Starts of omsd and of the
  baseline alternate; the figure is the median. Target (issue 16): <= 0.12 s.
* Commands: ``omsd models``, ``omsd ctl --help`` and ``omsd --help`` (the installed ``omsd``
  script next to this interpreter, else ``python -m omsd``), from exec to exit, against
  ``python -c pass``; runs alternate, medians. Target (issue 16): <= 3x ``python -c pass``.

Before either, omsd's bytecode is brought up to date (:func:`current_bytecode`), as installing
it does: with ``PYTHONDONTWRITEBYTECODE`` set and a source newer than its ``.pyc``, every start
would compile that module again, and the figure would be the compiler's.
"""

from __future__ import annotations

import compileall
import contextlib
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench import procs
from bench.latency import median
from bench.settings import Settings
from bench.table import Row, Target

TIMEOUT = 15.0


def current_bytecode() -> None:
    """Write the ``.pyc`` of every omsd module whose source changed since (``pip install``
    does it for a user; ``python -m compileall omsd`` by hand)."""
    compileall.compile_dir(procs.ROOT / "omsd", quiet=1)


def time_to_accept(argv: list[str], port: int) -> float:
    """Seconds from just before exec to the first accepted connection on ``port``."""
    with tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=err,
            env=procs.server_env(),
            preexec_fn=procs.server_setup,
        )
        try:
            deadline = time.monotonic() + TIMEOUT
            while True:
                try:
                    with socket.create_connection(("127.0.0.1", port), timeout=1.0):
                        elapsed = time.perf_counter() - t0
                    break
                except ConnectionRefusedError:
                    if proc.poll() is not None:
                        err.seek(0)
                        raise RuntimeError(
                            f"{' '.join(argv)} exited {proc.returncode} before accepting:"
                            f" {err.read()[-500:]!r}"
                        ) from None
                    if time.monotonic() > deadline:
                        raise RuntimeError(
                            f"{' '.join(argv)} did not accept in {TIMEOUT} s"
                        ) from None
                    time.sleep(0.001)
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(TIMEOUT)
            except subprocess.TimeoutExpired:
                proc.kill()
                with contextlib.suppress(subprocess.TimeoutExpired):
                    proc.wait(TIMEOUT)
    return elapsed


def omsd_command() -> list[str]:
    """``omsd`` as a user types it: the console script of this environment."""
    script = Path(sys.executable).parent / "omsd"
    return [str(script)] if script.exists() else [sys.executable, "-m", "omsd"]


def wall(argv: list[str]) -> float:
    """Seconds from just before exec to exit; the command must succeed."""
    t0 = time.perf_counter()
    result = subprocess.run(
        argv,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=procs.server_env(),
        preexec_fn=procs.server_setup,
        timeout=TIMEOUT,
    )
    elapsed = time.perf_counter() - t0
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {result.returncode}: {result.stderr[-300:]!r}")
    return elapsed


def first_accept(settings: Settings, directory: Path) -> list[Row]:
    ours: list[float] = []
    theirs: list[float] = []
    reply = directory / "startup-reply.bin"
    reply.write_bytes(b"\n")
    for i in range(settings.startup_runs):
        port = procs.free_port()
        ours.append(
            time_to_accept(
                [
                    *omsd_command(),
                    "--board",
                    "PC48-4E",
                    "--tcp",
                    f"127.0.0.1:{port}",
                    "--pty",
                    str(directory / f"startup-{i}"),
                    "--control",
                    str(directory / f"startup-{i}.sock"),
                ],
                port,
            )
        )
        port = procs.free_port()
        theirs.append(
            time_to_accept(
                [
                    sys.executable,
                    "-m",
                    "bench.echo",
                    "--reply-file",
                    str(reply),
                    "--tcp",
                    f"127.0.0.1:{port}",
                    "--pty",
                    str(directory / f"startup-echo-{i}"),
                ],
                port,
            )
        )
    return [
        Row(
            "start-up, exec to first TCP accept, one board as users run it / echo",
            "s",
            median(ours),
            median(theirs),
            Target("figure", "<=", 0.12, "s"),
            f"median of {len(ours)} starts each; omsd {min(ours):.3f} to {max(ours):.3f} s",
        )
    ]


COMMANDS = (
    ("omsd models", ["models"]),
    ("omsd ctl --help", ["ctl", "--help"]),
    ("omsd --help", ["--help"]),
)


def commands(settings: Settings) -> list[Row]:
    omsd = omsd_command()
    base = [sys.executable, "-c", "pass"]
    times: dict[str, list[float]] = {name: [] for name, _ in COMMANDS}
    floor: list[float] = []
    wall(base)  # the first run reads the interpreter from disk
    for _name, args in COMMANDS:
        wall([*omsd, *args])
    for _ in range(settings.cli_runs):
        floor.append(wall(base))
        for name, args in COMMANDS:
            times[name].append(wall([*omsd, *args]))
    return [
        Row(
            f"command, exec to exit: {name} / python -c pass",
            "s",
            median(times[name]),
            median(floor),
            Target("ratio", "<=", 3.0),
            f"median of {settings.cli_runs} runs each ({' '.join(omsd)})" if i == 0 else "",
        )
        for i, (name, _) in enumerate(COMMANDS)
    ]


def run(settings: Settings, directory: Path) -> list[Row]:
    current_bytecode()
    return commands(settings) + first_accept(settings, directory)
