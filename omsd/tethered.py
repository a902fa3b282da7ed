"""``python -m omsd.tethered ARGS``: ``omsd ARGS`` that lives no longer than the process that
started it, as the pytest plugin (:mod:`omsd.testing`) starts its daemons.

Its standard input is a pipe whose writing end only the parent holds. When that pipe reaches end
of file (the parent closed it, or is gone: a test run stopped by a CI timeout's SIGTERM or by
SIGKILL, whose fixtures' teardown never ran) the daemon sends itself SIGTERM, its clean stop at
any moment (exit status 0, its pty links and control socket removed: :mod:`omsd.cli`). A daemon
in a session of its own, as the plugin's are, would otherwise serve its ports for ever.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

from omsd.cli import main


def _watch(fd: int) -> None:
    """Read ``fd`` until end of file (what is written is ignored), then SIGTERM this process."""
    try:
        while os.read(fd, 4096):
            pass
    except OSError:
        pass  # closed or unreadable: the parent is not there to hold it either
    os.kill(os.getpid(), signal.SIGTERM)


def run() -> int:
    """``omsd`` with the command line's arguments, stopped when standard input ends."""
    threading.Thread(target=_watch, args=(sys.stdin.fileno(),), name="tether", daemon=True).start()
    return main()


if __name__ == "__main__":
    sys.exit(run())
