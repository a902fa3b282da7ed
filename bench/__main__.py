"""``python -m bench [--quick] [--only NAME,...]``: run the benchmarks, print the table.

Progress goes to standard error, the table (Markdown) to standard output, preceded by the
machine it ran on. The exit status is 0 when every row was measured (whatever the verdicts: the
figures depend on the machine), 1 when a benchmark failed (its error is in the notes).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from bench import cost, fidelity, latency, startup, throughput
from bench.settings import FULL, QUICK, Settings
from bench.table import Row, render

Benchmark = Callable[[Settings, Path], list[Row]]

BENCHMARKS: dict[str, Benchmark] = {
    "latency": latency.run,
    "throughput": throughput.run,
    "idle": cost.idle,
    "load": cost.load,
    "fidelity": fidelity.run,
    "startup": startup.run,
}


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
    return (
        f"{model}, {os.cpu_count()} cores, Python {platform.python_version()},"
        f" Linux {platform.release()}; load average at start {load[0]:.2f}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description=__doc__)
    parser.add_argument("--quick", action="store_true", help="the short version CI runs")
    parser.add_argument(
        "--only", metavar="NAME,...", help=f"run only these: {', '.join(BENCHMARKS)}"
    )
    options = parser.parse_args(argv)
    names = list(BENCHMARKS)
    if options.only:
        names = [n.strip() for n in options.only.split(",") if n.strip()]
        unknown = [n for n in names if n not in BENCHMARKS]
        if unknown:
            parser.error(
                f"unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(BENCHMARKS)}"
            )
    settings = QUICK if options.quick else FULL
    header = machine()
    rows: list[Row] = []
    ok = True
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="omsd-bench-") as tmp:
        for name in names:
            print(f"bench: {name}...", file=sys.stderr, flush=True)
            t0 = time.monotonic()
            try:
                rows += BENCHMARKS[name](settings, Path(tmp))
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
    ok = ok and all(r.figure is not None for r in rows)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
