"""Run a module on uvloop: ``python -m bench.fastloop MODULE ARGS...``.

Installs uvloop's event loop policy, then runs ``python -m MODULE ARGS`` in this process, so
``asyncio.run`` (omsd's, the echo's) makes a uvloop loop: the optional fast loop of issue 16,
measured without changing the program under test.
"""

from __future__ import annotations

import asyncio
import runpy
import sys

import uvloop


def main() -> None:
    if len(sys.argv) < 2:
        raise SystemExit("usage: python -m bench.fastloop MODULE [ARGS...]")
    asyncio.set_event_loop_policy(uvloop.EventLoopPolicy())
    module = sys.argv[1]
    sys.argv = [module, *sys.argv[2:]]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
