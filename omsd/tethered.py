"""``python -m omsd.tethered ARGS``: ``omsd ARGS`` that lives no longer than the process that
started it, as the pytest plugin (:mod:`omsd.testing`) starts its daemons.

Its standard input is a pipe whose writing end only the parent holds. When that pipe reaches end
of file (the parent closed it, or is gone: a test run stopped by a CI timeout's SIGTERM or by
SIGKILL, whose fixtures' teardown never ran) the daemon sends itself SIGTERM, its clean stop at
any moment (exit status 0, its pty links and control socket removed: :mod:`omsd.cli`). A daemon
in a session of its own, as the plugin's are, would otherwise serve its ports for ever.

Standard input that is not a pipe (or a socket) says nothing of the parent: ``/dev/null``
(systemd's, ``< /dev/null``) ends at once, and a terminal is the user's typing (read in the
background, ``&``, it has the kernel stop the process: SIGTTIN). Either is refused, one line and
exit status 2, as omsd refuses what keeps it from starting; ``omsd`` itself is for those.

The tether's SIGTERM waits, blocked, until omsd has its own handler: a pipe that had ended
before start-up killed the process by SIGTERM's default action (status 143), where omsd's
SIGTERM is a clean stop at any moment (status 0).
"""

from __future__ import annotations

import os
import signal
import stat
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


def tether_problem(fd: int) -> str | None:
    """Why ``fd`` cannot be the tether (not a pipe or a socket: its end would not say that the
    parent is gone), or ``None``."""
    try:
        mode = os.fstat(fd).st_mode
    except OSError as exc:
        return f"standard input cannot be read: {exc.strerror or exc}"
    if stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
        return None
    what = "a terminal" if os.isatty(fd) else "not a pipe"
    return (
        f"standard input is {what}: omsd.tethered stops when a pipe from the process that "
        "started it ends; run omsd instead"
    )


def run() -> int:
    """``omsd`` with the command line's arguments, stopped when standard input ends."""
    problem = tether_problem(0)
    if problem is not None:
        print(f"omsd: {problem}", file=sys.stderr)
        return 2
    # SIGTERM blocked, in this thread and the tether's (which inherits the mask), until omsd's
    # main installs its handler and unblocks it (omsd.cli: "a signal pending since exec is taken
    # here"): the tether's SIGTERM is never met by the default action
    signal.pthread_sigmask(signal.SIG_BLOCK, (signal.SIGTERM,))
    threading.Thread(target=_watch, args=(0,), name="tether", daemon=True).start()
    return main()


if __name__ == "__main__":
    sys.exit(run())
