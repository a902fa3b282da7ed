"""``omsd top``'s options, and running it.

``omsd``'s command line (:mod:`omsd.cli`) builds the parser with :func:`add_top_parser` and runs
the command with :func:`run_top`. This module imports only argparse and the help's helpers at
its top, so that ``omsd --help`` stays light (issue 16); :mod:`omsd.top` is imported when the
command runs.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from omsd.helptext import HelpFormatter, examples

# the subscription's rate (omsd.control.protocol has the same numbers; tests/test_top.py holds
# them together)
DEFAULT_RATE = 10.0
MAX_RATE = 50.0


def add_top_parser(subparsers: argparse._SubParsersAction[Any]) -> argparse.ArgumentParser:
    """``omsd top``'s parser, added to ``subparsers``; its options' ``dest`` start with
    ``top_``."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "top",
        help="watch a running daemon's boards live: axes, travel, events, traffic",
        description="A running daemon's boards, live, over its control socket: each board's\n"
        "axes (position, encoder, velocity, motion, done, limits, home, queue space),\n"
        "a bar of each carriage within its travel, the last events, the traffic\n"
        "rate. Keys: 1-9, Tab, arrows pick a board; p pauses; q quits. Standard\n"
        "output not a terminal: one snapshot as text.",
        epilog=examples(
            ("omsd top", "the boards of the omsd you started"),
            ("omsd top --board xy --rate 20", "board xy first, 20 looks a second"),
            ("omsd top | head", "one snapshot, as text"),
        )
        + "\n\nexit status: 0 quit; 1 no such board; 3 daemon unreachable; 130 Ctrl-C.",
        formatter_class=HelpFormatter,
    )
    p.add_argument(
        "--socket",
        dest="top_socket",
        metavar="PATH",
        type=Path,
        help="the daemon's control socket, as omsd ctl's (default: $XDG_RUNTIME_DIR/omsd/"
        "control.sock, else /run/omsd/control.sock)",
    )
    p.add_argument(
        "--board",
        dest="top_board",
        metavar="NAME",
        help="the board shown first, or the only one in a snapshot (default: the first)",
    )
    p.add_argument(
        "--rate",
        dest="top_rate",
        type=_rate,
        default=DEFAULT_RATE,
        metavar="N",
        help=f"looks at the boards a second while they change (default: {DEFAULT_RATE:g}; at"
        f" most {MAX_RATE:g})",
    )
    return p


def _rate(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value <= MAX_RATE:
        raise argparse.ArgumentTypeError(f"expected above 0 and at most {MAX_RATE:g}, got {text!r}")
    return value


def run_top(args: argparse.Namespace) -> int:
    from omsd.top import main

    return main(args.top_socket, args.top_board, args.top_rate)


__all__ = ["DEFAULT_RATE", "MAX_RATE", "add_top_parser", "run_top"]
