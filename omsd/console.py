"""Talk to one emulated board from a terminal, in real time, or run a command file through it.

The board engine is pure; this module is the smallest real-time shell around it: it feeds what
comes in on standard input to the board with the wall-clock time, sleeps until the board's next
deadline, prints the board's replies as they come and shows the events a host would see in the
status register (done, limit, slip, command error) as bracketed notes on standard error.

Standard input may be a terminal, a pipe or a file (``omsd console < commands.txt``). A terminal
or a pipe is read as it comes (a pipe fed slowly is answered as it is fed); a regular file, which
cannot be waited on like a terminal (``epoll`` refuses it), is read at once. At the end of the
input (Ctrl-D on a terminal) the console goes on until the board has taken every character and
run everything queued, every axis at rest, so that the replies, done flags and limits of what
was sent are printed; then it exits 0. Motion that does not end by itself (a jog, a servo
holding against a moving target) is given at most ``wait`` seconds, and the console says so.
"""

from __future__ import annotations

import os
import selectors
import stat
import sys
import time
from typing import BinaryIO, TextIO

from omsd.board import Board, Reply
from omsd.board.events import describe
from omsd.defaults import CONSOLE_WAIT
from omsd.models import Model

DEFAULT_WAIT = CONSOLE_WAIT  # seconds after the end of the input, at most, for the board to rest


def _selectable(fd: int) -> bool:
    """Whether ``fd`` can be waited on (a terminal, a pipe, a socket): not a regular file."""
    try:
        return not stat.S_ISREG(os.fstat(fd).st_mode)
    except OSError:
        return False


def _at_rest(board: Board) -> bool:
    """Every character taken and run: nothing in the input buffer, every queue empty, every
    axis at rest."""
    if board.interpreter.buffer:
        return False
    return all(not axis.moving and axis.queue.empty for axis in board.axes)


def run(
    model: Model, stdin: BinaryIO, stdout: BinaryIO, notes: TextIO, wait: float = DEFAULT_WAIT
) -> int:
    clock = time.monotonic
    board = Board(model, now=clock())
    fd = stdin.fileno()
    if os.isatty(fd):
        notes.write(f"omsd console: {model.name} ({model.description}); Ctrl-D ends input\n")
        notes.flush()
    sel: selectors.BaseSelector | None = None
    backlog = b""
    eof_at: float | None = None
    if _selectable(fd):
        sel = selectors.DefaultSelector()
        try:
            sel.register(fd, selectors.EVENT_READ)
        except (PermissionError, ValueError):  # nothing to wait on: read it all now
            sel.close()
            sel = None
    if sel is None:
        backlog = _read_all(fd)
        eof_at = clock()
    try:
        while True:
            deadline = board.next_deadline()
            timeout = None if deadline is None else max(0.0, deadline - clock())
            if backlog:
                timeout = 0.01  # the board's input buffer is full: look again soon
            if eof_at is not None:
                timeout = 0.05 if timeout is None else min(timeout, 0.05)
            if sel is not None and eof_at is None:
                ready = bool(sel.select(timeout))
            else:
                time.sleep(timeout if timeout is not None else 0.05)
                ready = False
            now = clock()
            if ready:
                data = os.read(fd, 4096)
                if not data:
                    eof_at = now
                backlog += data
            if backlog:
                taken = board.receive(backlog, now)
                backlog = backlog[taken:]
            board.advance(now)
            for item in board.take_output():
                if isinstance(item, Reply):
                    stdout.write(item.data)
                    stdout.flush()
                else:
                    notes.write(f"[{describe(item)}]\n")
                    notes.flush()
            if eof_at is not None and not backlog and _at_rest(board):
                return 0
            if eof_at is not None and now - eof_at >= wait:
                moving = "".join(a.letter for a in board.axes if a.moving)
                axes = "axes" if len(moving) > 1 else "axis"
                what = f"{axes} {moving} still moving" if moving else "commands still queued"
                notes.write(f"[end of input: stopped waiting after {wait:g} s, {what}]\n")
                notes.flush()
                return 0
    finally:
        if sel is not None:
            sel.close()


def _read_all(fd: int) -> bytes:
    chunks = []
    while chunk := os.read(fd, 65536):
        chunks.append(chunk)
    return b"".join(chunks)


def main(model: Model, wait: float = DEFAULT_WAIT) -> int:
    try:
        return run(model, sys.stdin.buffer, sys.stdout.buffer, sys.stderr, wait)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # omsd console < commands.txt | head
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
