"""The ``omsd`` command line.

``omsd`` alone serves the built-in default (one PC48-4E on TCP 127.0.0.1:7048 and on a pty);
``--board/--tcp/--pty/--serial/--rfc2217/--link/--eos/--log`` describe one board without a file
(any endpoint given replaces both defaults: ``--tcp`` alone serves no pty, and the daemon says so
in its log); ``--config FILE`` describes several. ``--state FILE`` keeps the boards' flash memory
(AP defaults, permanent macros) across restarts, with either form. ``omsd models`` lists the
personalities; ``omsd commands MODEL`` the commands one understands (:mod:`omsd.commands`);
``omsd console`` talks to one board on this terminal without serving it, or runs a command
file through it (:mod:`omsd.console`); ``omsd ctl`` reaches behind the boards of a running
daemon (:mod:`omsd.ctl`, which has its own options and exit statuses). ``omsd config check
FILE`` validates a configuration without starting anything, ``omsd config show FILE`` prints it
with every default filled in, ``omsd config schema`` prints its JSON Schema
(:mod:`omsd.config.schema`, imported by these and by serving only: ``omsd models`` and ``omsd
ctl`` stay fast).

Every help text shows each option's default and a few examples (issue 14).

Exit status: 0 after a clean stop, 2 for anything that keeps the daemon from starting, each one
line on standard error naming what and why, with nothing left behind: a configuration error, a
place the daemon refuses to use (a runtime directory another user could change, a file at a pty
link's path that is not omsd's: :mod:`omsd.files`), or one it cannot use (a port in use, a log
or state file that cannot be opened, a pty link whose directory is missing). A restart cannot
fix any of them, and systemd's ``RestartPreventExitStatus=2`` stops there. 130 after Ctrl-C
during start-up. SIGTERM is a clean stop at any moment: 0, like a serving daemon's, also before
the daemon's own handler is installed (the first ~0.2 s: imports, the configuration read), where
it is handled by :func:`main`'s (nothing has been made then, and nothing is printed); after the
daemon has stopped (asyncio closing its loop, the process ending) SIGTERM and SIGINT are ignored:
nothing is left to stop. Started by
a parent that blocks SIGINT or SIGTERM (the mask is inherited across exec), omsd unblocks them.
"""

from __future__ import annotations

import argparse
import gc
import os
import signal
import sys
from typing import TYPE_CHECKING

from omsd import __version__
from omsd.defaults import (
    CONSOLE_WAIT,
    DEFAULT_BAUD,
    DEFAULT_EOS,
    DEFAULT_HOST,
    DEFAULT_LINK,
    DEFAULT_MODEL,
    DEFAULT_TCP_PORT,
    DEFAULT_VIEW,
    DEFAULT_WEB,
    LINKS,
    LOOPS,
    VIEWS,
)
from omsd.helptext import HelpFormatter, examples

if TYPE_CHECKING:
    from omsd.daemon import Daemon

# Each command imports what it uses when it runs (issue 16: ``omsd --help``, ``omsd models`` and
# ``omsd ctl`` within 3x ``python -c pass``): the parser needs argparse and the defaults it
# quotes (omsd.defaults); ``omsd models`` the model rows; ``omsd ctl`` the control client;
# ``omsd config`` and serving the configuration (omsd.config), and serving asyncio, the engine
# and the daemon; a command line that serves is read without the commands' parsers at all
# (_serving_args). tests/test_import_boundaries.py holds each command to what it may import.


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: {message}\n")


class _NotServing(Exception):
    """The command line is not one :func:`_serving_args` reads."""


class _ServingParser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        raise _NotServing


def _serving_args(argv: list[str]) -> argparse.Namespace | None:
    """The arguments of a command line that serves (no COMMAND, no --help, no --version, no
    error), as the whole parser would give them, read without building the commands' parsers
    and importing what they need (start-up); None for any other, which :func:`_parser` reads
    (and says what is wrong with). It knows the same option strings, so that abbreviations are
    read alike."""
    p = _ServingParser(prog="omsd", add_help=False)
    p.add_argument("-h", "--help", action="store_true")
    p.add_argument("--version", action="store_true")
    _serving_options(p)
    try:
        args, rest = p.parse_known_args(argv)
    except _NotServing:
        return None
    if rest or args.help or args.version:
        return None
    del args.help, args.version
    args.command = None
    return args


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="omsd",
        usage="omsd [--config FILE | --board MODEL --tcp [HOST:]PORT ...] [OPTIONS]\n"
        "       omsd {models,commands,console,config,ctl,top} ...\n"
        "       omsd {record,replay} ...",
        description="Virtual Oregon Micro Systems motion controllers (PC48, PC46, VS4,\n"
        "PCIx), served over pty, TCP, serial devices and RFC 2217. With no COMMAND,\n"
        "serve the boards until Ctrl-C or SIGTERM: one line per endpoint on standard\n"
        "output (board, model, link, kind, address), the traffic on standard error.",
        epilog=examples(
            ("omsd", "a PC48-4E on 127.0.0.1:7048 and a pty"),
            ("omsd --board PCIX-400 --tcp 0", "a PCIx on a free port, no pty"),
            ("omsd --config config/omsd.toml", "the boards of a file"),
        )
        + "\n\nexit status: 0 stopped; 2 not started (a configuration error, a port in\n"
        "use, a file or directory that cannot be used: one line on standard error);\n"
        "130 interrupted.",
        formatter_class=HelpFormatter,
    )
    p.add_argument("--version", action="version", version=f"omsd {__version__}")
    _serving_options(p)
    sub = p.add_subparsers(dest="command", metavar="COMMAND", title="commands", prog="omsd")
    sub.add_parser(
        "models",
        help="list the board personalities",
        description="List the board personalities: model name and what is fitted.",
        epilog=examples(
            ("omsd models", "PC48-2 ... PCIX-400, one a line"),
            ("omsd models | grep PCIX", "the PCIx models"),
        ),
        formatter_class=HelpFormatter,
    )
    commands = sub.add_parser(
        "commands",
        help="list the commands a model understands, with operands, ranges and manual pages",
        description="List the commands MODEL understands, one a line: the mnemonic, its\n"
        "operand form (# a number, [#] one that may be left out, #,#,…; one per axis\n"
        "in AA/AM), the range of each operand, the manual's section and page, and\n"
        "what it does (the manual's command summary; where it applies in brackets).",
        epilog=examples(
            (f"omsd commands {DEFAULT_MODEL}", "every command of the default board"),
            ("omsd commands PCIX-400 --grep home", "the homing commands of a PCIx"),
            ("omsd commands VS4-040 --grep VL", "VL and the commands that mention it"),
        ),
        formatter_class=HelpFormatter,
    )
    commands.add_argument(
        "model",
        metavar="MODEL",
        nargs="?",
        default=DEFAULT_MODEL,
        help=f"a model of omsd models, case-insensitive (default: {DEFAULT_MODEL})",
    )
    commands.add_argument(
        "--grep",
        metavar="TEXT",
        help="only the commands whose mnemonic or description contains TEXT, whatever the case"
        " (default: all)",
    )
    console = sub.add_parser(
        "console",
        help="talk to one board on this terminal, or run a command file through it",
        description="Talk to one board without serving it: what you type goes to the board\n"
        "(its own stream, no driver link), its replies come back, and its events\n"
        "(done, limit, slip, command error) are shown in brackets on standard error.\n"
        "With standard input a file or a pipe, every command in it is sent, the\n"
        "replies are printed, and it exits 0 at the end of the input once the board\n"
        "has taken everything and its axes are at rest (at most --wait seconds).",
        epilog=examples(
            ("omsd console", "type WY, Enter: PC48 ver 3.00-4"),
            ("omsd console --board PCIX-400 < cmds.txt", "run a command file"),
            ("printf 'MR1000 GO ID RP\\n' | omsd console", "[done X], 1000"),
        ),
        formatter_class=HelpFormatter,
    )
    console.add_argument(
        "--board",
        dest="console_board",
        default=DEFAULT_MODEL,
        metavar="MODEL",
        help="the board's model",
    )
    console.add_argument(
        "--wait",
        type=_seconds,
        default=CONSOLE_WAIT,
        metavar="S",
        help="at the end of a file or pipe, how long motion still running may take"
        f" (default: {CONSOLE_WAIT:g} s)",
    )
    _config_parser(sub)
    from omsd.recording.cli import add_record_parser, add_replay_parser  # (argparse only)

    add_record_parser(sub)
    add_replay_parser(sub)
    # listed for --help only: main() hands everything after "ctl" to omsd.ctl unparsed
    ctl = sub.add_parser("ctl", help="control a running daemon (omsd ctl --help)", add_help=False)
    ctl.add_argument("ctl_args", nargs=argparse.REMAINDER)
    from omsd.topcli import add_top_parser  # (argparse only)

    add_top_parser(sub)
    return p


def _serving_options(p: argparse.ArgumentParser) -> None:
    """The options of serving: ``omsd`` without a COMMAND."""
    p.add_argument(
        "--config",
        metavar="FILE",
        help="TOML file describing the boards (default: none, one board from the options below;"
        " config/omsd.toml explains every key)",
    )
    p.add_argument(
        "--board",
        metavar="MODEL",
        help=f"model of the one board (default: {DEFAULT_MODEL}; omsd models lists them)",
    )
    p.add_argument(
        "--tcp",
        metavar="[HOST:]PORT",
        action="append",
        default=[],
        help="serve on TCP; repeatable; PORT 0 picks a free port (default: "
        f"{DEFAULT_HOST}:{DEFAULT_TCP_PORT}, with the default pty). Given without --pty, it"
        " replaces the"
        " defaults: no pty",
    )
    p.add_argument(
        "--pty",
        metavar="PATH",
        action="append",
        default=[],
        help="serve on a pty with a symlink at PATH; repeatable (default:"
        " $XDG_RUNTIME_DIR/omsd/board1, with the default TCP port). Given without --tcp: no TCP",
    )
    p.add_argument(
        "--serial",
        metavar="PATH[,BAUD[,8N1]]",
        action="append",
        default=[],
        help="serve on a serial device (a USB adapter) set to BAUD, data bits, parity and stop"
        " bits, and ,rtscts or ,xonxoff after them for flow control; repeatable (default: none;"
        f" {DEFAULT_BAUD},8N1 without flow control when not given). Replaces the default"
        " endpoints",
    )
    p.add_argument(
        "--rfc2217",
        metavar="[HOST:]PORT",
        action="append",
        default=[],
        help="serve RFC 2217 (telnet COM port control) clients such as pyserial's rfc2217://;"
        " repeatable (default: none). Replaces the default endpoints",
    )
    p.add_argument(
        "--link",
        choices=LINKS,
        help="driver: the DOS driver's conventions (markers # @ $ !, end character); raw: the"
        f" board's own stream (default: {DEFAULT_LINK})",
    )
    p.add_argument(
        "--eos",
        metavar="HEX",
        help="the driver link's end-of-string character, like the driver's E:XX (default:"
        f" {DEFAULT_EOS:02X})",
    )
    p.add_argument(
        "--terminal",
        action="store_true",
        help="the ptys are for picocom, minicom or screen: show what is typed, CR LF line ends",
    )
    p.add_argument(
        "--log",
        metavar="FILE",
        help="append the traffic and events to FILE as JSON lines (default: none, or [log] file)",
    )
    p.add_argument(
        "--view",
        choices=VIEWS,
        help=f"the traffic on standard error (default: {DEFAULT_VIEW}: rich on a terminal, else"
        " plain)",
    )
    p.add_argument(
        "--control",
        metavar="PATH",
        help="the control socket for omsd ctl, or off (default: $XDG_RUNTIME_DIR/omsd/"
        "control.sock; $RUNTIME_DIRECTORY/control.sock under systemd)",
    )
    p.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help=f"serve the web dashboard there, e.g. {DEFAULT_WEB} (default: none, or [web]"
        " listen); read-only unless --web-control",
    )
    p.add_argument(
        "--web-control",
        action="store_true",
        help="the dashboard's buttons act on the boards (default: it only watches)",
    )
    p.add_argument(
        "--state",
        metavar="FILE",
        help="keep the boards' flash (AP defaults, macros 5-24) in FILE across restarts"
        " (default: none, flash lasts as long as the daemon)",
    )
    p.add_argument(
        "--loop",
        choices=LOOPS,
        default="auto",
        help="the event loop: auto is uvloop where it is installed (pip install 'omsd[fast]'),"
        " else asyncio's own (default: auto)",
    )


def _config_parser(sub: argparse._SubParsersAction[_Parser]) -> None:
    config = sub.add_parser(
        "config",
        help="check a configuration file, show it with its defaults, print its JSON Schema",
        description="The configuration file (config/omsd.toml explains every key): check it\n"
        "without starting anything, show it as omsd reads it, or print the JSON Schema\n"
        "that editors check and complete its keys with.",
        epilog=examples(
            ("omsd config check config/omsd.toml", "config/omsd.toml: 4 boards, OK"),
            ("omsd config show config/omsd.toml", "every key, defaults filled in"),
            ("omsd config schema > omsd.schema.json", "for #:schema ./omsd.schema.json"),
        ),
        formatter_class=HelpFormatter,
    )
    actions = config.add_subparsers(
        dest="config_command", metavar="ACTION", title="actions", required=True
    )
    check = actions.add_parser(
        "check",
        help="validate FILE without starting anything",
        description="Validate FILE as omsd --config FILE would, without starting anything:\n"
        "one line, FILE: N boards, OK (exit status 0), or the error, FILE:LINE: KEY:\n"
        "expected ..., got ... (exit status 2).",
        epilog=examples(
            ("omsd config check config/omsd.toml", "config/omsd.toml: 4 boards, OK"),
            ("omsd config check lab.toml || exit 2", "stop a script at a bad file"),
        ),
        formatter_class=HelpFormatter,
    )
    check.add_argument("file", metavar="FILE", help="the TOML configuration file")
    show = actions.add_parser(
        "show",
        help="print FILE as omsd reads it, every default filled in (TOML)",
        description="Print the configuration FILE gives, as TOML: every key with the value\n"
        "omsd uses (defaults filled in, paths absolute, every axis of each board). A\n"
        "password is not shown. Exit status 2 and one line for an invalid FILE.",
        epilog=examples(
            ("omsd config show config/omsd.toml", "every key of the four boards"),
            ("omsd config show lab.toml | grep -A3 'axes.X'", "the X axis of each board"),
        ),
        formatter_class=HelpFormatter,
    )
    show.add_argument("file", metavar="FILE", help="the TOML configuration file")
    schema = actions.add_parser(
        "schema",
        help="print the configuration's JSON Schema (for editors), or its key reference",
        description="Print the JSON Schema (draft-07) of omsd's configuration files, which\n"
        "taplo-based editors use to check and complete keys when a file starts with\n"
        "#:schema ./omsd.schema.json (config/omsd.schema.json is this output); or, with\n"
        "--format markdown, the reference table of every key (README.md).",
        epilog=examples(
            ("omsd config schema > config/omsd.schema.json", "what config/ holds"),
            ("omsd config schema --format markdown", "the README's key reference"),
        ),
        formatter_class=HelpFormatter,
    )
    schema.add_argument(
        "--format",
        choices=("json", "markdown"),
        default="json",
        help="json: the JSON Schema; markdown: a table of every key, with its default",
    )


def _config(args: argparse.Namespace) -> int:
    """``omsd config check|show|schema``: 0, or 2 and one line for an invalid file."""
    from omsd.config import ConfigError, load_config, render

    if args.config_command == "schema":
        text = render.json_schema_text() if args.format == "json" else render.reference()
        sys.stdout.write(text)
        return 0
    try:
        config = load_config(args.file)
    except ConfigError as exc:
        print(exc, file=sys.stderr)
        return 2
    if args.config_command == "check":
        count = len(config.boards)
        print(f"{args.file}: {count} board{'s' if count != 1 else ''}, OK")
    else:
        sys.stdout.write(render.show_text(config))
    return 0


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seconds, got {text!r}") from None
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"expected seconds 0 or more, got {text!r}")
    return value


class _Terminated(BaseException):
    """SIGTERM before the daemon's event loop handles it (see :func:`main`)."""


def _terminated(signum: int, frame: object) -> None:
    raise _Terminated


def _after_the_daemon(daemon: Daemon) -> None:
    """In omsd's own process, serving: SIGTERM and SIGINT outside the daemon's loop handlers.
    Before them (the loop being made) they stop omsd as before (status 0, 130); after them (the
    daemon has stopped everything, asyncio is closing its loop) they are ignored: there is
    nothing left to stop, and an exception raised by a handler there came out of whatever
    callback asyncio ran, as its "Exception in callback" traceback."""

    def handler(signum: int, frame: object) -> None:
        if daemon.ended:
            return
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise _Terminated

    if signal.getsignal(signal.SIGTERM) is not _terminated:
        return  # main() called with a command line (a test): its signals stay its caller's
    signal.signal(signal.SIGTERM, handler)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # (not an ignored one)
        signal.signal(signal.SIGINT, handler)


def _ending() -> None:
    """omsd's own process returns from :func:`main`: a SIGTERM or SIGINT from here on (atexit
    functions, the interpreter's finalization, which gives Python's handlers back to the
    default action) is ignored, not a traceback or death by the signal."""
    for sig in (signal.SIGTERM, signal.SIGINT):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, signal.SIG_IGN)


def _sigterm_default() -> None:
    """A command that does not serve dies by SIGTERM, as a command does."""
    if signal.getsignal(signal.SIGTERM) is _terminated:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def main(argv: list[str] | None = None) -> int:
    """The ``omsd`` command (``argv`` None: the process's own command line, and the process is
    omsd's: then SIGTERM is handled from here on, and SIGINT and SIGTERM unblocked)."""
    try:
        return _run_main(argv)
    finally:
        if argv is None:
            _ending()


def _run_main(argv: list[str] | None) -> int:
    try:
        if argv is None:
            # first thing: a SIGTERM before the daemon's loop handles it (imports, the file
            # read) is a clean stop, status 0 as when serving, not death by its default action;
            # a mask inherited from the parent that blocks them is lifted once the handler is
            # there (a signal pending since exec is taken here)
            signal.signal(signal.SIGTERM, _terminated)
            signal.pthread_sigmask(signal.SIG_UNBLOCK, (signal.SIGINT, signal.SIGTERM))
        return _main(sys.argv[1:] if argv is None else argv)
    except KeyboardInterrupt:  # Ctrl-C before the daemon's own handler (imports, the file)
        return 130
    except _Terminated:  # SIGTERM before the daemon's own handler: nothing made yet
        return 0


def _main(argv: list[str]) -> int:
    if argv[:1] == ["ctl"]:
        _sigterm_default()
        from omsd.ctl import main as ctl_main

        return ctl_main(argv[1:])
    args = _serving_args(argv) or _parser().parse_args(argv)
    if args.command is not None:
        _sigterm_default()
    if args.command == "ctl":
        print("omsd: ctl must come first: omsd ctl [OPTIONS] COMMAND", file=sys.stderr)
        return 2
    if args.command == "models":
        from omsd.models import MODELS

        for model in MODELS.values():
            print(f"{model.name:<10} {model.description}")
        return 0
    if args.command == "commands":
        return _commands(args.model, args.grep)
    if args.command == "config":
        return _config(args)
    if args.command == "record":
        from omsd.recording.cli import run_record

        return run_record(args)
    if args.command == "replay":
        from omsd.recording.cli import run_replay

        return run_replay(args)
    if args.command == "top":
        from omsd.topcli import run_top

        return run_top(args)
    if args.command == "console":
        from omsd.models import UnknownModel, get_model

        try:
            model = get_model(args.console_board)
        except UnknownModel as exc:
            print(f"omsd: --board: {exc}", file=sys.stderr)
            return 2
        from omsd.console import main as console_main

        return console_main(model, args.wait)
    return _serve(args)


def _commands(name: str, grep: str | None) -> int:
    """``omsd commands MODEL [--grep TEXT]``: 0, or 1 when nothing matches (as grep), 2 for an
    unknown model."""
    from omsd.commands import format_listing, listing
    from omsd.models import UnknownModel, get_model

    try:
        model = get_model(name)
    except UnknownModel as exc:
        print(f"omsd commands: {exc}", file=sys.stderr)
        return 2
    listed = listing(model)
    if grep is not None:
        listed = [c for c in listed if c.matches(grep)]
        if not listed:
            print(f"omsd commands: no {model.name} command matches {grep!r}", file=sys.stderr)
            return 1
    try:
        for line in format_listing(listed):
            print(line)
        sys.stdout.flush()
    except BrokenPipeError:  # omsd commands PC48-4E | head
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


def _serve(args: argparse.Namespace) -> int:
    # no cyclic garbage collection while omsd starts (imports, configuration, boards: nearly
    # everything made is kept); Daemon(freeze=True) turns it back on once the boards are up
    collecting = gc.isenabled()
    gc.disable()
    try:
        return _start_and_serve(args)
    finally:
        if collecting:
            gc.enable()


def _start_and_serve(args: argparse.Namespace) -> int:
    from omsd.config import (
        ConfigError,
        check_option_path,
        from_options,
        load_config,
        with_control_option,
        with_state_option,
        with_web_option,
    )
    from omsd.daemon import Daemon, StartupError
    from omsd.loops import LoopUnavailable, run
    from omsd.loops import loop_factory as event_loop
    from omsd.telemetry.traffic import TrafficLog

    try:
        for option, text in (("--config", args.config), ("--log", args.log)):
            if text is not None:
                check_option_path(option, text)
        if args.config is not None:
            single = [
                o
                for o in ("board", "tcp", "pty", "serial", "rfc2217", "link", "eos", "terminal")
                if getattr(args, o)
            ]
            if single:
                raise ConfigError(f"--{single[0]}", None, "cannot be combined with --config")
            config = load_config(args.config)
        else:
            config = from_options(
                args.board,
                args.tcp,
                args.pty,
                args.link,
                args.eos,
                None,
                args.terminal,
                serial=args.serial,
                rfc2217=args.rfc2217,
            )
        config = with_state_option(config, args.state)
        config = with_control_option(config, args.control)
        config = with_web_option(config, args.web, args.web_control)
    except ConfigError as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return 2
    try:
        loop_factory, _ = event_loop(args.loop)
    except LoopUnavailable as exc:
        print(f"omsd: {exc}", file=sys.stderr)
        return 2
    log_file = args.log if args.log is not None else config.log.file
    if log_file is not None:
        from omsd.files import log_shared_path

        ptys = [(b.name, p.link) for b in config.boards for p in b.pty]
        problem = log_shared_path(log_file, ptys, config.control.socket, config.state)
        if problem is not None:
            print(f"omsd: {problem}", file=sys.stderr)
            return 2
    view = args.view or config.log.view
    try:
        log = TrafficLog(view=view, file=log_file, group=config.log.group)
    except OSError as exc:  # TrafficLogError: "cannot open traffic log PATH: REASON"
        print(f"omsd: {exc}", file=sys.stderr)
        return 2
    daemon = Daemon(config, log, freeze=True)
    _after_the_daemon(daemon)
    try:
        run(daemon.run(), loop_factory)
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
