"""``omsd top``: a running daemon's boards, live, in a terminal (issue 18).

It subscribes to the control API (:meth:`omsd.control.client.Control.subscribe`: the snapshot,
then what changes, at most ``--rate`` times a second, and nothing while nothing changes) and
draws :mod:`omsd.topview`'s screen with rich's ``Live`` on the terminal's alternate screen, so
it works wherever a terminal does (over ssh, in tmux). Keys: a digit picks a board, Tab and the
arrow keys the next or the previous one, ``p`` pauses the screen (the stream is still read, so
the daemon never waits for it), ``q`` quits.

Standard output not a terminal (a pipe, a file): it prints one snapshot as text and exits 0.

The terminal: the keys are read one at a time (``tty.setcbreak``: no line editing, no echo, but
the terminal still turns a line end into CR LF for rich and Ctrl-C still interrupts), without
blocking, from a selector that waits on the keyboard and the daemon's socket at once (no thread,
no event loop: nothing runs while neither has anything; the screen is drawn at most ``--rate``
times a second, and once a second while a traffic rate falls to zero). Whatever ends it (``q``,
Ctrl-C, SIGTERM, SIGHUP when the ssh session goes, an error), the terminal's settings are put
back and the alternate screen left.

Exit status: 0 after ``q`` (and after a snapshot), 1 for a board the daemon does not have, 3
when the daemon cannot be reached or goes away (as ``omsd ctl``), 130 after Ctrl-C, 128 + the
signal's number after SIGTERM or SIGHUP.
"""

from __future__ import annotations

import contextlib
import os
import selectors
import signal
import sys
import termios
import time
import tty
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING

from omsd.control.client import Subscription
from omsd.control.protocol import DEFAULT_RATE, ControlError
from omsd.ctl import Unreachable, connect
from omsd.topview import View, plain, screen

if TYPE_CHECKING:
    from rich.console import Console
    from rich.live import Live

EXIT_REFUSED = 1
EXIT_UNREACHABLE = 3

#: Escape sequences of the keys that pick a board (normal and application cursor modes).
_SEQUENCES = {
    "\x1b[A": "previous",
    "\x1b[B": "next",
    "\x1b[C": "next",
    "\x1b[D": "previous",
    "\x1bOA": "previous",
    "\x1bOB": "next",
    "\x1bOC": "next",
    "\x1bOD": "previous",
    "\x1b[Z": "previous",  # Shift-Tab
}
_KEYS = {"\t": "next", "p": "pause", "P": "pause", "q": "quit", "Q": "quit"}


def keys(text: str) -> list[str]:
    """The keys in what the terminal sent: ``next``, ``previous``, ``pause``, ``quit``, or a
    digit ``1``-``9``; anything else is left out."""
    out = []
    i = 0
    while i < len(text):
        if text[i] == "\x1b":
            end = i + 1
            if text.startswith("[", end):  # a control sequence: up to its final byte
                end += 1
                while end < len(text) and not "@" <= text[end] <= "~":
                    end += 1
                end += 1
            elif text.startswith("O", end):  # a cursor key in application mode
                end += 2
            name = _SEQUENCES.get(text[i:end])
            if name is not None:
                out.append(name)
            i = end  # a lone Escape, or a sequence of no use here, is passed over
            continue
        char = text[i]
        if char in _KEYS:
            out.append(_KEYS[char])
        elif "1" <= char <= "9":
            out.append(char)
        i += 1
    return out


def main(socket: Path | None = None, board: str | None = None, rate: float = DEFAULT_RATE) -> int:
    try:
        ctl = connect(socket)
    except Unreachable as exc:
        text = str(exc).replace("omsd ctl", "omsd top").replace(" (or --tcp HOST:PORT)", "")
        print(f"omsd top: {text}", file=sys.stderr)
        return EXIT_UNREACHABLE
    where = ctl.address
    try:
        with ctl:
            subscription = ctl.subscribe(rate=rate)
            view = View(subscription.snapshot, subscription.states, where, board)
            if board is not None and board not in view.names:
                print(
                    f"omsd top: no board {board!r}; boards: {', '.join(view.names)}",
                    file=sys.stderr,
                )
                return EXIT_REFUSED
            if not sys.stdout.isatty():
                return _snapshot(view, board)
            return _live(subscription, view)
    except ControlError as exc:
        print(f"omsd top: {exc}", file=sys.stderr)
        return EXIT_REFUSED
    except OSError as exc:
        reason = str(exc) if exc.errno is None else (exc.strerror or str(exc))
        print(f"omsd top: lost the daemon at {where}: {reason}", file=sys.stderr)
        return EXIT_UNREACHABLE


def _snapshot(view: View, board: str | None) -> int:
    try:
        print(plain(view, board), flush=True)
    except BrokenPipeError:  # omsd top | head
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


class _Signalled(BaseException):
    def __init__(self, signum: int) -> None:
        self.signum = signum


def _raise(signum: int, frame: FrameType | None) -> None:
    raise _Signalled(signum)


@contextlib.contextmanager
def terminal(fd: int | None) -> Iterator[None]:
    """Keys one at a time on ``fd`` (None: no keyboard), SIGTERM and SIGHUP turned into an
    exception, and everything put back as it was, however the block ends."""
    saved = termios.tcgetattr(fd) if fd is not None else None
    handlers = {sig: signal.signal(sig, _raise) for sig in (signal.SIGTERM, signal.SIGHUP)}
    try:
        if fd is not None:
            tty.setcbreak(fd)
        yield
    finally:
        if fd is not None and saved is not None:
            termios.tcsetattr(fd, termios.TCSADRAIN, saved)
        for sig, handler in handlers.items():
            signal.signal(sig, handler)


def _live(subscription: Subscription, view: View) -> int:
    from rich.console import Console
    from rich.live import Live

    stdin = sys.stdin.fileno() if sys.stdin.isatty() else None
    console = Console()
    interval = 1.0 / view.rate if view.rate > 0 else 0.1
    selector = selectors.DefaultSelector()
    selector.register(subscription.fileno(), selectors.EVENT_READ, "daemon")
    if stdin is not None:
        selector.register(stdin, selectors.EVENT_READ, "keys")
    # a resized terminal is drawn again at once: SIGWINCH writes a byte the selector sees
    resized, resize = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
    selector.register(resized, selectors.EVENT_READ, "resized")
    winch = signal.signal(signal.SIGWINCH, lambda signum, frame: _poke(resize))
    try:
        with (
            terminal(stdin),
            Live(console=console, screen=True, auto_refresh=False, transient=True) as live,
        ):
            return _loop(live, console, selector, subscription, view, interval, stdin)
    except _Signalled as exc:
        return 128 + exc.signum
    except KeyboardInterrupt:
        return 130
    finally:
        signal.signal(signal.SIGWINCH, winch)
        selector.close()
        os.close(resized)
        os.close(resize)


def _poke(fd: int) -> None:
    with contextlib.suppress(OSError):  # full: a redraw is due anyway
        os.write(fd, b"!")


def _loop(
    live: Live,
    console: Console,
    selector: selectors.BaseSelector,
    subscription: Subscription,
    view: View,
    interval: float,
    stdin: int | None,
) -> int:
    drawn = -float("inf")
    for message in subscription.pending():  # what came with the snapshot's reply
        view.apply(message, time.monotonic())
    dirty = force = True
    while True:
        now = time.monotonic()
        if (force or (dirty and not view.paused)) and now - drawn >= interval:
            size = console.size
            live.update(screen(view, now, size.width, size.height), refresh=True)
            drawn, dirty, force = now, False, False
        if force or (dirty and not view.paused):
            timeout: float | None = max(0.0, drawn + interval - now)
        elif not view.paused and view.busy(now):
            timeout = 1.0  # a rate falls to zero without a message: look again in a second
        else:
            timeout = None
        ready = selector.select(timeout)
        if not ready and timeout == 1.0:
            dirty = True
        for key, _ in ready:
            if key.data == "daemon":
                now = time.monotonic()
                for message in subscription.pending():
                    view.apply(message, now)
                    dirty = True
            elif key.data == "resized":
                with contextlib.suppress(OSError):
                    os.read(key.fd, 64)
                force = True
            else:
                assert stdin is not None
                text = os.read(stdin, 64).decode("utf-8", errors="replace")
                for name in keys(text):
                    if not view.key(name):
                        return 0
                    force = True


__all__ = ["keys", "main", "terminal"]
