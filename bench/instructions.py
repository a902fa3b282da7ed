"""``python -m bench.instructions``: the board engine's instructions per poll, counted.

Timed figures on a shared machine move by 15 % within the hour, more than most changes to the
engine are worth; the number of machine instructions the engine runs does not move at all. This
counts them with valgrind (``callgrind``): one board of the load of :mod:`bench.cost`, in this
process's interpreter, polled with ``QA RP`` every 0.1 s as the daemon runs it, once for
``SHORT`` and once for ``LONG`` seconds on its manual clock; the difference over the difference
in polls is the instructions of one poll, without the start-up and the setup. Hash seeds are
fixed (``PYTHONHASHSEED=0``), but objects hashed by their address (the engine's enums) are not:
two runs of the same tree differ by a few hundred instructions (a thousandth).

Variants: the load itself (``load``: 4 axes jogging, 4 running queues of moves), the same board
``at rest`` and with the ``jogs alone``. A developer's tool, not a row of the table: it needs
valgrind (``apt install valgrind``), runs for about a minute, and says nothing of the I/O.
Comparing two trees: run it in each (``cd OTHER && python -m bench.instructions``: the tree
first on the module path is the one counted).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from bench.cost import BREAKDOWN, SETUP

SHORT, LONG = 5.0, 20.0
VARIANTS = {"load": SETUP, **BREAKDOWN}
#: The child: one board of the load, set up, then polled for argv[2] seconds.
CHILD = """
import sys
from bench.cost import engine_board, run_engine
from bench.instructions import VARIANTS
link, t = engine_board(VARIANTS[sys.argv[1]])
print(run_engine(link, t, float(sys.argv[2])))
"""
COLLECTED = re.compile(r"Collected : (\d+)")


def count(variant: str, seconds: float, root: Path) -> tuple[int, int]:
    """Instructions of the whole child run, and its polls."""
    path = os.pathsep.join(p for p in (str(root), os.environ.get("PYTHONPATH")) if p)
    env = {**os.environ, "PYTHONHASHSEED": "0", "PYTHONPATH": path}
    result = subprocess.run(
        [
            "valgrind",
            "--tool=callgrind",
            "--callgrind-out-file=/dev/null",
            sys.executable,
            "-c",
            CHILD,
            variant,
            str(seconds),
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=root,
        check=True,
    )
    found = COLLECTED.search(result.stderr)
    if found is None:
        raise RuntimeError(f"callgrind said no count:\n{result.stderr[-2000:]}")
    return int(found[1]), int(result.stdout.split()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.instructions", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "variants", nargs="*", metavar="VARIANT", help=f"of {', '.join(VARIANTS)} (all by default)"
    )
    args = parser.parse_args(argv)
    unknown = [v for v in args.variants if v not in VARIANTS]
    if unknown:
        parser.error(f"no variant {unknown[0]!r} (of {', '.join(VARIANTS)})")
    if shutil.which("valgrind") is None:
        print("python -m bench.instructions: valgrind is not installed", file=sys.stderr)
        return 2
    root = Path.cwd()
    for variant in args.variants or VARIANTS:
        a, polls_a = count(variant, SHORT, root)
        b, polls_b = count(variant, LONG, root)
        print(f"{variant:12s} {(b - a) / (polls_b - polls_a):12,.0f} instructions per poll")
    return 0


if __name__ == "__main__":
    sys.exit(main())
