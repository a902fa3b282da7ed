"""Talk to one emulated board from a terminal, in real time.

The board engine is pure; this module is the smallest real-time shell around it: it feeds what
you type to the board with the wall-clock time, sleeps until the board's next deadline, prints
the board's replies as they come and shows the events a host would see in the status register
(done, limit, slip, command error) as bracketed notes on standard error.
"""

from __future__ import annotations

import os
import selectors
import sys
import time
from typing import BinaryIO, TextIO

from omsd.board import Board, Reply
from omsd.board.events import describe
from omsd.models import Model


def run(model: Model, stdin: BinaryIO, stdout: BinaryIO, notes: TextIO) -> int:
    clock = time.monotonic
    board = Board(model, now=clock())
    notes.write(f"omsd console: {model.name} ({model.description}); Ctrl-D ends input\n")
    notes.flush()
    fd = stdin.fileno()
    sel = selectors.DefaultSelector()
    sel.register(fd, selectors.EVENT_READ)
    backlog = b""
    eof = False
    while True:
        deadline = board.next_deadline()
        timeout = None if deadline is None else max(0.0, deadline - clock())
        if backlog:
            timeout = 0.01
        if eof and deadline is None and not backlog:
            break
        if eof:
            time.sleep(timeout if timeout is not None else 0.05)
            ready = False
        else:
            ready = bool(sel.select(timeout))
        now = clock()
        if ready:
            data = os.read(fd, 4096)
            if not data:
                eof = True
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
        if eof and deadline is None:
            break
    return 0


def main(model: Model) -> int:
    try:
        return run(model, sys.stdin.buffer, sys.stdout.buffer, sys.stderr)
    except KeyboardInterrupt:
        return 130
