"""Start-up: from exec to the first endpoint accepting a TCP connection.

``python -m omsd --board PC48-4E --tcp 127.0.0.1:PORT --pty LINK --link raw --control off
--view off`` is started on a port known to be free, and a client tries to connect every
millisecond from the moment before ``exec`` until it is accepted. The baseline is the echo
server started the same way (a Python interpreter that imports asyncio and listens): the cost
of Python itself. Starts of omsd and of the baseline alternate; the figure is the median.
Target (issue 7): <= 0.5 s.
"""

from __future__ import annotations

import contextlib
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

from bench import procs
from bench.latency import median
from bench.settings import Settings
from bench.table import Row, Target

TIMEOUT = 15.0


def time_to_accept(argv: list[str], port: int) -> float:
    """Seconds from just before exec to the first accepted connection on ``port``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        argv,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=procs.server_env(),
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
                    raise RuntimeError(
                        f"{' '.join(argv)} exited {proc.returncode} before accepting"
                    ) from None
                if time.monotonic() > deadline:
                    raise RuntimeError(f"{' '.join(argv)} did not accept in {TIMEOUT} s") from None
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


def run(settings: Settings, directory: Path) -> list[Row]:
    ours: list[float] = []
    theirs: list[float] = []
    for i in range(settings.startup_runs):
        port = procs.free_port()
        ours.append(
            time_to_accept(
                [
                    sys.executable,
                    "-m",
                    "omsd",
                    "--board",
                    "PC48-4E",
                    "--tcp",
                    f"127.0.0.1:{port}",
                    "--pty",
                    str(directory / f"startup-{i}"),
                    "--link",
                    "raw",
                    "--control",
                    "off",
                    "--view",
                    "off",
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
            "start-up, exec to first TCP accept",
            "s",
            median(ours),
            median(theirs),
            Target("figure", "<=", 0.5, "s"),
            f"median of {len(ours)} starts each; omsd {min(ours):.3f} to {max(ours):.3f} s",
        )
    ]
