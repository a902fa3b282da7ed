"""``omsd record`` and ``omsd replay``: their options, and running them.

``omsd``'s command line (:mod:`omsd.cli`) builds both parsers with :func:`add_record_parser`
and :func:`add_replay_parser` and runs them with :func:`run_record` and :func:`run_replay`;
``python -m omsd.recording record|replay ...`` does the same on its own (:func:`main`). This
module imports only argparse and the help's helpers at its top, so that ``omsd --help`` stays
light (issue 16); each command imports what it uses when it runs.

Exit statuses, as ``omsd``'s (one line on standard error for anything that keeps a command
from doing its work, status 2):

* ``omsd record``: 0 stopped by SIGINT or SIGTERM, the recording complete; 1 the card went away
  (or the recording could not be written): the recording is complete up to then; 2 not started
  (bad options, a card that cannot be reached, an endpoint or a file that cannot be used); 130
  interrupted while starting.
* ``omsd replay``: 0 no difference, 1 differences (the table), 2 a file or options that make
  no replay.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from omsd.defaults import DEFAULT_EOS, DEFAULT_MODEL, LINKS
from omsd.helptext import HelpFormatter, examples

# the comparison's defaults, quoted by the help (omsd.recording.compare has the same numbers;
# tests/recording/test_cli.py holds them together)
DEFAULT_LINGER = 1.0  # omsd.recording.record.DEFAULT_LINGER
DEFAULT_TOLERANCE_STEPS = 2.0
DEFAULT_TOLERANCE_SECONDS = 0.02


def add_record_parser(subparsers: argparse._SubParsersAction[Any]) -> argparse.ArgumentParser:
    """``omsd record``'s parser, added to ``subparsers``; its options' ``dest`` start with
    ``record_``."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "record",
        help="pass an application's traffic to a real card unchanged, and record it",
        description="Stand between an application and a real card: the application talks to\n"
        "the pty or TCP port given here, every byte goes to the card and back\n"
        "unchanged, and both directions are written to FILE (JSON lines, monotonic\n"
        "times, a header naming the card) for omsd replay. One client at a time.\n"
        "Ctrl-C or SIGTERM stops it.",
        epilog=examples(
            ("omsd record --to serial:/dev/ttyS0 --pty oms --log a.jsonl", "a serial card"),
            ("omsd record --to tcp:10.0.0.5:4001 --tcp 7100 --log a.jsonl", "terminal server"),
        )
        + "\n\nexit status: 0 stopped by a signal; 1 the card went away (the recording is\n"
        "complete up to then); 2 not started (one line on standard error).",
        formatter_class=HelpFormatter,
    )
    p.add_argument(
        "--to",
        dest="record_to",
        metavar="CARD",
        required=True,
        help="where the card is: serial:PATH[,BAUD[,8N1]] (9600 baud, 8N1 unless given) or"
        " tcp:HOST:PORT",
    )
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument(
        "--tcp",
        dest="record_tcp",
        metavar="[HOST:]PORT",
        help="serve the application on TCP (HOST 127.0.0.1 unless given; PORT 0: a free one)"
        " (no default: --tcp or --pty)",
    )
    where.add_argument(
        "--pty",
        dest="record_pty",
        metavar="PATH",
        help="serve the application on a pty, with a symlink at PATH (no default: --tcp or --pty)",
    )
    p.add_argument(
        "--log",
        dest="record_log",
        metavar="FILE",
        required=True,
        help="the recording: a new file, or an empty one (created 0600; no default)",
    )
    _board_options(p, "record", "for the header, which the replay reads")
    p.add_argument(
        "--linger",
        dest="record_linger",
        metavar="S",
        type=_number("seconds"),
        default=DEFAULT_LINGER,
        help="a TCP client that stops sending (nc -N) is closed once the card has said nothing"
        " to it for S seconds (default: %(default)s)",
    )
    return p


def add_replay_parser(subparsers: argparse._SubParsersAction[Any]) -> argparse.ArgumentParser:
    """``omsd replay``'s parser, added to ``subparsers``; its options' ``dest`` start with
    ``replay_``."""
    p: argparse.ArgumentParser = subparsers.add_parser(
        "replay",
        help="replay a recorded session through the emulator and compare the answers",
        description="Feed the host's bytes of FILE (omsd record's recording, or omsd's own\n"
        "--log) to an emulated board at their recorded times, in simulated time, and\n"
        "compare what it answers with what the card answered: text and status exactly,\n"
        "positions and velocities read during motion within the tolerance, done, limit\n"
        "and slip markers within the time tolerance. Prints the differences (time,\n"
        "command, card said, omsd said) and a summary.",
        epilog=examples(
            ("omsd replay run.jsonl", "the card its header names"),
            ("omsd replay log.jsonl --board xy --config c.toml", "a daemon's log"),
            ("omsd replay run.jsonl --json | jq .differences", "for a program"),
        )
        + "\n\nexit status: 0 no difference; 1 differences; 2 a file or options that make\n"
        "no replay (one line on standard error).",
        formatter_class=HelpFormatter,
    )
    p.add_argument("replay_file", metavar="FILE", help="the recording, or an omsd --log file")
    _board_options(p, "replay", "instead of what FILE says")
    p.add_argument(
        "--tolerance",
        dest="replay_steps",
        metavar="STEPS",
        type=_number("steps"),
        default=DEFAULT_TOLERANCE_STEPS,
        help="how far a position or velocity read during motion may differ, in steps, beyond"
        " what the fastest axis covers in the time tolerance (default:"
        f" {DEFAULT_TOLERANCE_STEPS:g})",
    )
    p.add_argument(
        "--time-tolerance",
        dest="replay_seconds",
        metavar="S",
        type=_number("seconds"),
        default=DEFAULT_TOLERANCE_SECONDS,
        help="how far apart in time the card's and omsd's markers may be, and the time the"
        " numbers above may be read apart (default: %(default)s s)",
    )
    p.add_argument(
        "--json",
        dest="replay_json",
        action="store_true",
        help="print the result as one JSON object",
    )
    return p


def _board_options(p: argparse.ArgumentParser, prefix: str, why: str) -> None:
    p.add_argument(
        "--model",
        dest=f"{prefix}_model",
        metavar="MODEL",
        help=f"the card's model, {why} (default: "
        + (f"{DEFAULT_MODEL})" if prefix == "record" else "what FILE says)"),
    )
    p.add_argument(
        "--link",
        dest=f"{prefix}_link",
        choices=LINKS,
        help="raw: the board's own stream; driver: the DOS driver's conventions (default: "
        + ("raw with serial:, driver with tcp:)" if prefix == "record" else "what FILE says)"),
    )
    p.add_argument(
        "--eos",
        dest=f"{prefix}_eos",
        metavar="HEX",
        help="the driver link's end character (default: "
        + (f"{DEFAULT_EOS:02X})" if prefix == "record" else "what FILE says)"),
    )
    p.add_argument(
        "--config",
        dest=f"{prefix}_config",
        metavar="FILE",
        help="an omsd configuration file: the card is its board (model, link, world, inputs;"
        " the options above override) (default: none)",
    )
    p.add_argument(
        "--board",
        dest=f"{prefix}_board",
        metavar="NAME",
        help="the board of --config"
        + (", and the board whose traffic to replay in a log of several" * (prefix == "replay"))
        + " (default: the only one)",
    )


def _number(unit: str) -> Any:
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {unit}, got {text!r}") from None
        if not 0 <= value < float("inf"):
            raise argparse.ArgumentTypeError(f"expected {unit} 0 or more, got {text!r}")
        return value

    return parse


# -- running ------------------------------------------------------------------------------------


def run_record(args: argparse.Namespace) -> int:
    """``omsd record``: record until a signal or the card goes (the module text's statuses)."""
    import asyncio
    from pathlib import Path

    from omsd.recording.format import RecordingError, fitted
    from omsd.recording.record import Recorder, StartError, parse_card, record

    def fail(message: str) -> int:
        print(f"omsd record: {message}", file=sys.stderr)
        return 2

    try:
        card = parse_card(args.record_to)
    except ValueError as exc:
        return fail(f"--to: {exc}")
    tcp = None
    if args.record_tcp is not None:
        from omsd.config.syntax import TCP_SYNTAX, tcp_address

        try:
            tcp = tcp_address(args.record_tcp)
        except ValueError as exc:
            expected = str(exc) if type(exc) is not ValueError else TCP_SYNTAX
            return fail(f"--tcp: expected {expected}, got {args.record_tcp!r}")
    link = args.record_link or ("raw" if card.kind == "serial" else "driver")
    try:
        board = _board(
            args.record_config,
            args.record_board,
            None,
            args.record_model or (None if args.record_config else DEFAULT_MODEL),
            args.record_link if args.record_config else link,
            args.record_eos,
        )
        fitted(board, f"board {board.name} as a {board.model}")
    except RecordingError as exc:
        return fail(str(exc))
    pty = Path(args.record_pty).absolute() if args.record_pty is not None else None
    recorder = Recorder(
        card, board, Path(args.record_log), tcp=tcp, pty=pty, linger=args.record_linger
    )
    try:
        return asyncio.run(record(recorder))
    except StartError as exc:
        return fail(str(exc))
    except KeyboardInterrupt:
        return 130


def _board(
    config: str | None,
    name: str | None,
    fallback: str | None,
    model: str | None,
    link: str | None,
    eos: str | None,
) -> Any:
    """The card as a :class:`omsd.config.BoardConfig`: a board of ``config``, or ``card``, with
    the options over it."""
    import dataclasses

    from omsd.config import BoardConfig
    from omsd.models import UnknownModel, get_model
    from omsd.recording.format import RecordingError, config_board, parse_eos

    base = config_board(config, name, fallback) if config else BoardConfig(name=name or "card")
    changes: dict[str, Any] = {}
    if model is not None:
        try:
            changes["model"] = get_model(model).name
        except UnknownModel as exc:
            raise RecordingError(f"--model: {exc}") from None
    if link is not None:
        changes["link"] = link
    if eos is not None:
        changes["eos"] = parse_eos(eos)
    return dataclasses.replace(base, **changes)


def run_replay(args: argparse.Namespace) -> int:
    """``omsd replay``: 0 no difference, 1 differences, 2 a bad file or options."""
    import json

    from omsd.recording.compare import Tolerance
    from omsd.recording.format import RecordingError
    from omsd.recording.replay import replay_file

    try:
        result = replay_file(
            args.replay_file,
            model=args.replay_model,
            link=args.replay_link,
            eos=args.replay_eos,
            config=args.replay_config,
            board=args.replay_board,
            tolerance=Tolerance(args.replay_steps, args.replay_seconds),
        )
    except RecordingError as exc:
        print(f"omsd replay: {exc}", file=sys.stderr)
        return 2
    try:
        if args.replay_json:
            print(json.dumps(result.to_json(), indent=2))
        else:
            print(result.report())
        sys.stdout.flush()
    except BrokenPipeError:  # omsd replay ... | head
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0 if result.ok else 1


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: {message}\n")


def main(argv: list[str] | None = None) -> int:
    """``python -m omsd.recording record|replay ...``: what ``omsd record|replay`` does."""
    parser = _Parser(prog="omsd", formatter_class=HelpFormatter)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    add_record_parser(sub)
    add_replay_parser(sub)
    args = parser.parse_args(argv)
    return run_record(args) if args.command == "record" else run_replay(args)


__all__ = ["add_record_parser", "add_replay_parser", "main", "run_record", "run_replay"]
