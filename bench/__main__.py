"""``python -m bench [--quick] [--fast] [--peers] [--only NAME,...]``: run the benchmarks, print
the table.

Progress goes to standard error, the table (Markdown) to standard output, preceded by the
machine it ran on, the event loop and where client and servers were pinned. The exit status is
0 when every row was measured or says why it could not be here (whatever the verdicts: the
figures depend on the machine), 1 when a benchmark failed (its error is in the notes).
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from bench import (
    cost,
    fidelity,
    interp,
    isolation,
    latency,
    peers,
    procs,
    replay,
    scale,
    startup,
    throughput,
    versions,
    watch,
    web,
)
from bench.settings import FULL, QUICK, Settings
from bench.table import Row, render

Benchmark = Callable[[Settings, Path], list[Row]]

BENCHMARKS: dict[str, Benchmark] = {
    "latency": latency.run,
    "versions": versions.run,
    "interpreter": interp.run,
    "pipeline": throughput.pipelined,
    "throughput": throughput.run,
    "idle": cost.idle,
    "load": cost.load,
    "watch": watch.run,
    "web": web.run,
    "scale": scale.run,
    "fidelity": fidelity.run,
    "startup": startup.run,
    "isolation": isolation.run,
    "churn": isolation.churn,
    "replay": replay.run,
}
OPTIONAL: dict[str, Benchmark] = {"peers": peers.run}


def machine() -> str:
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load = os.getloadavg()
    loop = asyncio.new_event_loop()
    try:
        loop_name = f"{type(loop).__module__}.{type(loop).__name__}"
    finally:
        loop.close()
    return (
        f"{model}, {os.cpu_count()} cores, Python {platform.python_version()},"
        f" Linux {platform.release()}; load average at start {load[0]:.2f}\n"
        f"event loop: {loop_name} (asyncio's default; uvloop only in rows that say so)\n"
        f"placement: {procs.PINNING.describe()}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="the short version CI runs")
    parser.add_argument(
        "--fast",
        action="store_true",
        help="also measure omsd on uvloop (installed into ~/.cache/omsd-bench if need be)",
    )
    parser.add_argument(
        "--peers",
        action="store_true",
        help="also measure other simulators (installed into ~/.cache/omsd-bench; never in CI)",
    )
    parser.add_argument(
        "--no-pin", action="store_true", help="leave client and servers wherever they land"
    )
    known = [*BENCHMARKS, *OPTIONAL]
    parser.add_argument("--only", metavar="NAME,...", help=f"run only these: {', '.join(known)}")
    options = parser.parse_args(argv)
    names = list(BENCHMARKS) + (list(OPTIONAL) if options.peers else [])
    if options.only:
        names = [n.strip() for n in options.only.split(",") if n.strip()]
        unknown = [n for n in names if n not in known]
        if unknown:
            parser.error(f"unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(known)}")
    settings = QUICK if options.quick else FULL
    settings = dataclasses.replace(settings, fast=options.fast)
    procs.pin(not options.no_pin)
    header = machine()
    rows: list[Row] = []
    ok = True
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="omsd-bench-") as tmp:
        for name in names:
            print(f"bench: {name}...", file=sys.stderr, flush=True)
            t0 = time.monotonic()
            try:
                rows += {**BENCHMARKS, **OPTIONAL}[name](settings, Path(tmp))
            except Exception as exc:
                ok = False
                rows.append(Row(f"{name}: failed", "", None, note=f"{type(exc).__name__}: {exc}"))
            print(f"bench: {name} took {time.monotonic() - t0:.1f} s", file=sys.stderr, flush=True)
    mode = (
        "quick run (few samples: the figures are indicative only)" if settings.quick else "full run"
    )
    print(f"omsd benchmarks, {mode}, {time.monotonic() - started:.0f} s")
    print(f"machine: {header}")
    print()
    print(render(rows))
    ok = ok and all(r.figure is not None or r.skipped for r in rows)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
