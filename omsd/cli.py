"""The ``omsd`` command line.

``omsd`` alone serves the built-in default (one PC48-4E on TCP 127.0.0.1:7048 and on a pty);
``--board/--tcp/--pty/--link/--eos/--log`` describe one board without a file; ``--config FILE``
describes several. ``--state FILE`` keeps the boards' flash memory (AP defaults, permanent
macros) across restarts, with either form. ``omsd models`` lists the personalities; ``omsd
console`` talks to one board on this terminal without serving it; ``omsd ctl`` reaches behind
the boards of a running daemon (:mod:`omsd.ctl`, which has its own options and exit statuses).

Exit status: 0 after a clean stop, 2 for a configuration error or a place the daemon refuses to
use (a runtime directory another user could change, a file at a pty link's path that is not
omsd's: :mod:`omsd.files`), 1 when the daemon cannot start (a port in use, a pty link that
cannot be made). Errors are one line on standard error.
"""

from __future__ import annotations

import argparse
import asyncio
import sys

from omsd import __version__
from omsd.config import (
    DEFAULT_MODEL,
    VIEWS,
    ConfigError,
    from_options,
    load_config,
    with_control_option,
    with_state_option,
)
from omsd.link import KINDS
from omsd.models import MODELS, UnknownModel, get_model


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"omsd: {message}\n")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="omsd",
        description="Virtual Oregon Micro Systems motion controllers, served over pty and TCP.",
    )
    p.add_argument("--version", action="version", version=f"omsd {__version__}")
    p.add_argument("--config", metavar="FILE", help="TOML file describing the boards")
    p.add_argument(
        "--board", metavar="MODEL", help=f"model of the one board (default {DEFAULT_MODEL})"
    )
    p.add_argument(
        "--tcp",
        metavar="[HOST:]PORT",
        action="append",
        default=[],
        help="serve on TCP (repeatable; PORT 0 picks a free port)",
    )
    p.add_argument(
        "--pty",
        metavar="PATH",
        action="append",
        default=[],
        help="serve on a pty with a symlink at PATH (repeatable)",
    )
    p.add_argument("--link", choices=KINDS, help="driver (DOS driver conventions, default) or raw")
    p.add_argument("--eos", metavar="HEX", help="driver end-of-string character, like E:XX (0A)")
    p.add_argument("--log", metavar="FILE", help="append the traffic to FILE as JSON lines")
    p.add_argument("--view", choices=VIEWS, help="traffic on standard error (default auto)")
    p.add_argument(
        "--control",
        metavar="PATH",
        help="the control socket (default $XDG_RUNTIME_DIR/omsd/control.sock; off: none)",
    )
    p.add_argument(
        "--state",
        metavar="FILE",
        help="keep the boards' flash (AP defaults, macros 5-24) in FILE across restarts",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    sub.add_parser("models", help="list the board personalities")
    console = sub.add_parser("console", help="talk to one board on this terminal")
    console.add_argument("--board", dest="console_board", default=DEFAULT_MODEL, metavar="MODEL")
    # listed for --help only: main() hands everything after "ctl" to omsd.ctl unparsed
    ctl = sub.add_parser("ctl", help="control a running daemon (omsd ctl --help)", add_help=False)
    ctl.add_argument("ctl_args", nargs=argparse.REMAINDER)
    return p


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["ctl"]:
        from omsd.ctl import main as ctl_main

        return ctl_main(argv[1:])
    args = _parser().parse_args(argv)
    if args.command == "ctl":
        print("omsd: ctl must come first: omsd ctl [OPTIONS] COMMAND", file=sys.stderr)
        return 2
    if args.command == "models":
        for model in MODELS.values():
            print(f"{model.name:<10} {model.description}")
        return 0
    if args.command == "console":
        try:
            model = get_model(args.console_board)
        except UnknownModel as exc:
            print(f"omsd: --board: {exc}", file=sys.stderr)
            return 2
        from omsd.console import main as console_main

        return console_main(model)
    return _serve(args)


def _serve(args: argparse.Namespace) -> int:
    from omsd.daemon import Daemon, StartupError
    from omsd.telemetry.traffic import TrafficLog

    try:
        if args.config:
            single = [o for o in ("board", "tcp", "pty", "link", "eos") if getattr(args, o)]
            if single:
                raise ConfigError(f"--{single[0]}", None, "cannot be combined with --config")
            config = load_config(args.config)
        else:
            config = from_options(args.board, args.tcp, args.pty, args.link, args.eos, None)
        config = with_state_option(config, args.state)
        config = with_control_option(config, args.control)
    except ConfigError as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return 2
    log_file = args.log if args.log else config.log.file
    view = args.view or config.log.view
    try:
        log = TrafficLog(view=view, file=log_file, group=config.log.group)
    except OSError as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return 1
    try:
        asyncio.run(Daemon(config, log).run())
    except StartupError as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return exc.status
    except KeyboardInterrupt:
        return 130
    finally:
        log.close()
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
