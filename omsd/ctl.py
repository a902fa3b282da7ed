"""``omsd ctl``: the control API of a running daemon on the command line.

::

    omsd ctl boards                         # the boards and where they are served
    omsd ctl state                          # per axis, registers, link, clock, faults
    omsd ctl --board xy limit X + on        # close X's positive limit switch on board xy
    omsd ctl limit X + auto                 # let the carriage decide again
    omsd ctl input 3 low                    # drive general-purpose input 3 low ("true")
    omsd ctl slip X 20                      # the carriage slips 20 steps (the encoder sees it)
    omsd ctl fault --latency 0.2 --baud 9600
    omsd ctl fault --cut                    # pull the cable; --connect puts it back
    omsd ctl time pause; omsd ctl time step 0.5; omsd ctl time resume
    omsd ctl wait done X --timeout 5
    omsd ctl state --json                   # the operation's raw JSON result

It only parses arguments and prints; every operation is :class:`omsd.control.client.Control`
talking to the daemon's control socket (:mod:`omsd.control.protocol`). The words follow the
manuals: a limit or home switch is "on" when it is active (PC48 manual §2.2, J44: the axis "will
stop moving if the limit line, for the direction the axis is moving, is grounded"), and a
general-purpose input is "low" when it is driven to ground, which is what WS and SW call "true"
(§6.10: "while the specified general purpose input line is true, i.e. low"). "auto" hands a
switch back to the simulated carriage, an input back to its pull-up.

Exit status: 0 on success, 1 when the daemon refuses the operation (its one-line reason on
standard error, e.g. a wait that timed out), 2 for a usage error, 3 when the daemon cannot be
reached (no socket, connection refused, the connection dropped, no reply in time).

Where it looks (issue 14): ``--socket PATH`` or ``--tcp HOST:PORT`` when given; else the socket
of an omsd started by this user (:func:`omsd.control.client.default_socket`), and, if there is
none there, the systemd service's, :data:`SERVICE_SOCKET` (``RuntimeDirectory=omsd`` in
``systemd/omsd.service``), which the members of its ``[control] group`` may use. When it reaches
nothing it says, in one line, where it looked and how to point it elsewhere.

Choices where nothing prescribes the behaviour: the global options (``--socket``, ``--tcp``,
``--board``, ``--json``) are also accepted after the subcommand (``omsd ctl state --json``);
``fault`` with no option and ``time`` with no action show the faults and the clock; ``fault
--clear`` removes every fault at once.
"""

from __future__ import annotations

import argparse
import ipaddress
import json
import os
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from omsd.control.client import Control, default_socket
from omsd.control.protocol import ControlError
from omsd.helptext import HelpFormatter, examples
from omsd.hostport import host_port

EXIT_REFUSED = 1
EXIT_USAGE = 2
EXIT_UNREACHABLE = 3

DEFAULT_WAIT = 10.0  # seconds, as the daemon's own default for ``wait``

#: The control socket of the systemd service: ``$RUNTIME_DIRECTORY/control.sock`` with
#: ``RuntimeDirectory=omsd`` (systemd/omsd.service), where ``omsd ctl`` looks when no omsd of
#: this user is running.
SERVICE_SOCKET = Path("/run/omsd/control.sock")

_SWITCH = {"on": True, "off": False, "auto": None}
_LEVEL = {"high": True, "low": False, "auto": None}
_DIRECTION = {"+": 1, "-": -1, "pos": 1, "neg": -1}
_HOSTPORT = re.compile(r"(?:\[(?P<v6>[^\]]+)\]|(?P<host>[^:\[\]]+)):(?P<port>[0-9]{1,5})")


class UsageError(Exception):
    """A command line that cannot be right (exit 2)."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


# -- argument types ------------------------------------------------------------------------------


def _hostport(text: str) -> tuple[str, int]:
    """``HOST:PORT`` or ``[IPv6]:PORT``; a bare ``PORT`` is on 127.0.0.1 (as the daemon's
    ``[control] tcp``)."""
    if text.isdigit():
        host, port = "127.0.0.1", int(text)
    else:
        m = _HOSTPORT.fullmatch(text)
        if m is None:
            raise argparse.ArgumentTypeError(f"expected HOST:PORT, got {text!r}")
        host, port = m.group("v6") or m.group("host"), int(m.group("port"))
        if m.group("v6") is not None:
            try:
                ipaddress.IPv6Address(host)
            except ValueError:
                raise argparse.ArgumentTypeError(f"not an IPv6 address: {host!r}") from None
    if not 1 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"port must be 1..65535, got {port}")
    return host, port


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def _steps(text: str) -> float | int:
    """Steps or counts: an integer stays one in the JSON request."""
    try:
        return int(text)
    except ValueError:
        return _number(text)


def _integer(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def _baud(text: str) -> int | None:
    if text.lower() == "off":
        return None
    return _integer(text)


def _axis(text: str) -> str:
    if not re.fullmatch(r"[A-Za-z]", text):
        raise argparse.ArgumentTypeError(f"expected an axis letter, got {text!r}")
    return text.upper()


def _word(table: dict[str, Any]) -> Callable[[str], Any]:
    def convert(text: str) -> Any:
        try:
            return table[text.lower()]
        except KeyError:
            raise argparse.ArgumentTypeError(
                f"expected {' or '.join(table)}, got {text!r}"
            ) from None

    convert.__name__ = "/".join(table)
    return convert


# -- the parser ----------------------------------------------------------------------------------


def _globals(parser: argparse.ArgumentParser, default: Any) -> None:
    """The connection and output options; after the subcommand they default to SUPPRESS so they
    do not overwrite what was given before it."""
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--socket",
        metavar="PATH",
        type=Path,
        default=default,
        help="the daemon's control socket, its --control or [control] socket (default:"
        " $XDG_RUNTIME_DIR/omsd/control.sock, an omsd you started, else"
        f" {SERVICE_SOCKET}, the systemd service's)",
    )
    where.add_argument(
        "--tcp",
        metavar="HOST:PORT",
        type=_hostport,
        default=default,
        help="the daemon's control TCP endpoint ([control] tcp), instead of the socket"
        " (default: none)",
    )
    parser.add_argument(
        "--board",
        metavar="NAME",
        default=default,
        help="the board (default: the daemon's only board; needed with several)",
    )
    parser.add_argument(
        "--json",
        action="store_true",
        default=False if default is None else default,
        help="print the operation's JSON result as it is (default: off, a summary)",
    )


def parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="omsd ctl",
        description="Reach behind the boards of a running omsd: switches, inputs, slip,\n"
        "faults, time, power; watch their state. Options may also follow COMMAND.",
        epilog=examples(
            ("omsd ctl boards", "the boards and where they are served"),
            ("omsd ctl --board xy limit X + on", "close X's positive limit on board xy"),
            ("omsd ctl wait done X --timeout 5", "until X's done flag is set"),
        )
        + "\n\nexit status: 0 done, 1 refused by the daemon, 2 usage error, 3 daemon\n"
        "unreachable (it says where it looked).",
        formatter_class=HelpFormatter,
    )
    _globals(p, None)
    common = _Parser(add_help=False)
    _globals(common, argparse.SUPPRESS)
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    def command(name: str, help: str) -> argparse.ArgumentParser:
        return sub.add_parser(
            name,
            help=help,
            description=help[0].upper() + help[1:] + ".",
            parents=[common],
            epilog=examples(*EXAMPLES[name]),
            formatter_class=HelpFormatter,
        )

    command("boards", "list the boards and their endpoints")
    command("state", "a board's state: axes, registers, link, clock, faults")

    c = command("limit", "close (on) or open (off) a limit switch; auto: the carriage decides")
    c.add_argument("axis", type=_axis, metavar="AXIS")
    c.add_argument("direction", type=_word(_DIRECTION), metavar="+|-")
    c.add_argument("switch", type=_word(_SWITCH), metavar="on|off|auto")

    c = command("home", "activate (on) or release (off) the home switch; auto: as the carriage")
    c.add_argument("axis", type=_axis, metavar="AXIS")
    c.add_argument("switch", type=_word(_SWITCH), metavar="on|off|auto")

    c = command("input", "drive a general-purpose input high or low; auto: released (pulled up)")
    c.add_argument("bit", type=_integer, metavar="BIT")
    c.add_argument("level", type=_word(_LEVEL), metavar="high|low|auto")

    c = command("slip", "the carriage slips STEPS steps: the encoder sees it, the counter not")
    c.add_argument("axis", type=_axis, metavar="AXIS")
    c.add_argument("steps", type=_steps, metavar="STEPS")

    c = command("stall", "stall the motor (on) or let it follow its pulses again (off)")
    c.add_argument("axis", type=_axis, metavar="AXIS")
    c.add_argument("switch", type=_word({"on": True, "off": False}), metavar="on|off")

    c = command("encoder", "turn the encoder input to COUNTS (what ET tracks)")
    c.add_argument("axis", type=_axis, metavar="AXIS")
    c.add_argument("counts", type=_integer, metavar="COUNTS")

    c = command("fault", "change the cable's faults (none given: show them)")
    unchanged = " (default: unchanged; none at start)"
    c.add_argument(
        "--latency", type=_number, metavar="S", help="reply latency in seconds" + unchanged
    )
    c.add_argument(
        "--baud",
        type=_baud,
        metavar="N|off",
        default=argparse.SUPPRESS,
        help="pace the link at N/10 characters a second" + unchanged,
    )
    c.add_argument(
        "--drop", type=_number, metavar="P", help="probability a byte is lost" + unchanged
    )
    c.add_argument(
        "--garble", type=_number, metavar="P", help="probability a byte is garbled" + unchanged
    )
    c.add_argument(
        "--seed", type=_integer, metavar="N", help="seed of the drop/garble dice" + unchanged
    )
    cable = c.add_mutually_exclusive_group()
    cable.add_argument("--cut", action="store_true", help="cut the cable (clients see EOF)")
    cable.add_argument("--connect", action="store_true", help="connect the cable again")
    c.add_argument("--clear", action="store_true", help="no latency, pacing, loss; connected")

    c = command("time", "pause, resume, step or scale the board's clock (none: show it)")
    actions = c.add_subparsers(dest="action", metavar="ACTION", parser_class=_Parser)

    def action(name: str, help: str, *example: tuple[str, str]) -> argparse.ArgumentParser:
        return actions.add_parser(
            name,
            help=help,
            description=help[0].upper() + help[1:] + ".",
            parents=[common],
            epilog=examples(*example),
            formatter_class=HelpFormatter,
        )

    action(
        "pause",
        "stop the board's time",
        ("omsd ctl time pause", "the board does nothing by itself"),
        ("omsd ctl --board xy time pause", "board xy's clock"),
    )
    action(
        "resume",
        "let it run again",
        ("omsd ctl time resume", "real time again"),
        ("omsd ctl --board xy time resume", "board xy's clock"),
    )
    a = action(
        "step",
        "move paused time SECONDS forward",
        ("omsd ctl time step 0.5", "half a second of board time"),
        ("omsd ctl time step 0.0005", "about one sample (2048 a second)"),
    )
    a.add_argument("seconds", type=_number, metavar="SECONDS")
    a = action(
        "scale",
        "board seconds per real second",
        ("omsd ctl time scale 10", "ten times as fast"),
        ("omsd ctl time scale 1", "real time"),
    )
    a.add_argument("factor", type=_number, metavar="FACTOR")

    command("reset", "power-cycle the board")

    c = command("wait", "wait until an axis is done, the board idle or a position reached")
    until = c.add_subparsers(dest="until", metavar="CONDITION", parser_class=_Parser)
    until.required = True
    timeout = _Parser(add_help=False)
    timeout.add_argument(
        "--timeout",
        type=_number,
        metavar="S",
        default=DEFAULT_WAIT,
        help=f"give up after S seconds (default {DEFAULT_WAIT:g})",
    )

    def condition(name: str, help: str, *example: tuple[str, str]) -> argparse.ArgumentParser:
        return until.add_parser(
            name,
            help=help,
            description=f"Wait until {help}.",
            parents=[common, timeout],
            epilog=examples(*example),
            formatter_class=HelpFormatter,
        )

    a = condition(
        "done",
        "the axis's done flag is set",
        ("omsd ctl wait done X", "after AX MR1000 GO ID"),
        ("omsd ctl wait done Y --timeout 30", "a longer move"),
    )
    a.add_argument("axis", type=_axis, metavar="AXIS")
    condition(
        "idle",
        "every axis at rest, queues empty",
        ("omsd ctl wait idle", "everything sent has run"),
        ("omsd ctl --board xy wait idle --timeout 60", "board xy, a minute at most"),
    )
    a = condition(
        "position",
        "the axis's position reaches POS",
        ("omsd ctl wait position X 1000", "X at or past 1000"),
        ("omsd ctl wait position Y -500 --timeout 5", "Y at or past -500"),
    )
    a.add_argument("axis", type=_axis, metavar="AXIS")
    a.add_argument("position", type=_integer, metavar="POS")
    return p


# -- running -------------------------------------------------------------------------------------


def main(argv: Sequence[str] | None = None) -> int:
    try:
        args = parser().parse_args(argv)
        _check(args)
    except UsageError as exc:
        print(f"omsd ctl: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        ctl = _connect(args)
    except _Unreachable as exc:
        print(f"omsd ctl: {exc}", file=sys.stderr)
        return EXIT_UNREACHABLE
    where = ctl.address
    try:
        with ctl:
            result, text = _run(ctl, args)
    except ControlError as exc:
        print(f"omsd ctl: {exc}", file=sys.stderr)
        return EXIT_REFUSED
    except TimeoutError:
        print(f"omsd ctl: no reply from the daemon at {where}", file=sys.stderr)
        return EXIT_UNREACHABLE
    except OSError as exc:
        if exc.errno is None:  # the client's own words: the connection closed, not JSON
            print(f"omsd ctl: {exc}", file=sys.stderr)
            return EXIT_UNREACHABLE
        reason = exc.strerror or str(exc)
        print(f"omsd ctl: lost the daemon at {where}: {reason}", file=sys.stderr)
        return EXIT_UNREACHABLE
    try:
        print(json.dumps(result, indent=2) if args.json else text, flush=True)
    except BrokenPipeError:  # ``omsd ctl state | head``: the reader had enough
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


class _Unreachable(Exception):
    """No daemon where omsd ctl looked; ``str()`` says where, why, and how to look elsewhere."""


_ELSEWHERE = "point omsd ctl at the daemon's socket with --socket PATH (or --tcp HOST:PORT)"


def _connect(args: argparse.Namespace) -> Control:
    """A connection to the daemon: where the options say, else an omsd of this user's, else
    the systemd service's (:data:`SERVICE_SOCKET`)."""
    if args.tcp is not None:
        host, port = args.tcp
        try:
            return Control(tcp=args.tcp)
        except OSError as exc:
            raise _Unreachable(
                f"cannot reach the daemon at {host_port(host, port)}: {_reason(exc)}; --tcp takes"
                " the address of the daemon's [control] tcp"
            ) from None
    if args.socket is not None:
        try:
            return Control(args.socket)
        except OSError as exc:
            raise _Unreachable(
                f"cannot reach the daemon at {args.socket}: {_reason(exc)}; --socket takes the"
                " path of the daemon's --control or [control] socket (the systemd service's"
                f" is {SERVICE_SOCKET})"
            ) from None
    looked = []
    places = [(default_socket(), "an omsd you started"), (SERVICE_SOCKET, "the systemd service")]
    for path, whose in places[: 1 if places[0][0] == SERVICE_SOCKET else 2]:
        try:
            return Control(path)
        except (FileNotFoundError, ConnectionRefusedError) as exc:
            looked.append(f"{path} ({whose}): {_reason(exc)}")
        except PermissionError:
            raise _Unreachable(
                f"cannot reach the daemon at {path} ({whose}): permission denied; it is for"
                " the daemon's user and the members of its [control] group: ask to be added"
                " to that group, or use sudo"
            ) from None
        except OSError as exc:
            raise _Unreachable(
                f"cannot reach the daemon at {path} ({whose}): {_reason(exc)}; {_ELSEWHERE}"
            ) from None
    raise _Unreachable(f"no daemon found: {'; '.join(looked)}. Start omsd, or {_ELSEWHERE}")


def connect(socket: Path | None = None, tcp: tuple[str, int] | None = None) -> Control:
    """A connection to the daemon found where ``omsd ctl`` looks (``omsd top`` looks there too);
    :class:`Unreachable`, saying where it looked, when there is none."""
    return _connect(argparse.Namespace(socket=socket, tcp=tcp))


Unreachable = _Unreachable


def _reason(exc: OSError) -> str:
    if isinstance(exc, FileNotFoundError):
        return "no such socket"
    if isinstance(exc, ConnectionRefusedError):
        return "connection refused (nobody listens)"
    return exc.strerror or str(exc)


def _check(args: argparse.Namespace) -> None:
    if args.command == "fault" and args.clear:
        given = [f"--{k}" for k in ("latency", "baud", "drop", "garble", "seed") if _given(args, k)]
        if given or args.cut or args.connect:
            other = given[0] if given else "--cut" if args.cut else "--connect"
            raise UsageError(f"fault: --clear cannot be combined with {other}")
    if args.command == "wait" and args.timeout < 0:
        raise UsageError(f"wait: --timeout must not be negative, got {args.timeout:g}")


def _given(args: argparse.Namespace, key: str) -> bool:
    if key == "baud":
        return hasattr(args, "baud")
    return getattr(args, key) is not None


def _run(ctl: Control, args: argparse.Namespace) -> tuple[Any, str]:
    """Do the operation; returns its JSON result and the text to print."""
    board: str | None = args.board
    command: str = args.command
    if command == "boards":
        boards = ctl.boards()
        return boards, _boards(boards)
    if command == "state":
        state = ctl.state(board)
        return state, _summary(state)
    if command == "limit":
        state = ctl.set_limit(args.axis, args.direction, args.switch, board=board)
        return state, _axes(state, [args.axis])
    if command == "home":
        state = ctl.set_home(args.axis, args.switch, board=board)
        return state, _axes(state, [args.axis])
    if command == "input":
        state = ctl.set_input(args.bit, args.level, board=board)
        return state, _io(state)
    if command == "slip":
        state = ctl.slip(args.axis, args.steps, board=board)
        return state, _axes(state, [args.axis])
    if command == "stall":
        state = ctl.stall(args.axis, args.switch, board=board)
        return state, _axes(state, [args.axis])
    if command == "encoder":
        state = ctl.encoder(args.axis, args.counts, board=board)
        return state, _axes(state, [args.axis])
    if command == "fault":
        faults = ctl.fault(board, **_fault_changes(args))
        return faults, f"faults: {_faults(faults)}"
    if command == "time":
        return _time(ctl, args, board)
    if command == "reset":
        state = ctl.reset(board)
        return state, f"{state['board']}: power cycled\n{_axes(state, list(state['axes']))}"
    if command == "wait":
        if args.until == "done":
            state = ctl.wait_done(args.axis, args.timeout, board=board)
            return state, _axes(state, [args.axis])
        if args.until == "position":
            state = ctl.wait_position(args.axis, args.position, args.timeout, board=board)
            return state, _axes(state, [args.axis])
        state = ctl.wait_idle(args.timeout, board=board)
        return state, _axes(state, list(state["axes"]))
    raise AssertionError(command)  # pragma: no cover - argparse allows no other


def _fault_changes(args: argparse.Namespace) -> dict[str, Any]:
    if args.clear:
        return {"latency": 0.0, "baud": None, "drop": 0.0, "garble": 0.0, "cable": True}
    changes: dict[str, Any] = {}
    for key in ("latency", "drop", "garble", "seed"):
        if getattr(args, key) is not None:
            changes[key] = getattr(args, key)
    if hasattr(args, "baud"):
        changes["baud"] = args.baud
    if args.cut:
        changes["cable"] = False
    elif args.connect:
        changes["cable"] = True
    return changes


def _time(ctl: Control, args: argparse.Namespace, board: str | None) -> tuple[Any, str]:
    action = args.action
    if action is None:
        state = ctl.state(board)
    elif action == "pause":
        state = ctl.pause(board)
    elif action == "resume":
        state = ctl.resume(board)
    elif action == "step":
        state = ctl.step(args.seconds, board=board)
    else:
        state = ctl.scale(args.factor, board=board)
    return state, f"clock: {_clock(state['clock'])}"


# -- the human view ------------------------------------------------------------------------------

_COLUMNS = ("axis", "position", "encoder", "velocity", "motion", "done", "limits", "home", "queue")


def _boards(boards: list[dict[str, Any]]) -> str:
    lines = []
    for b in boards:
        where = ", ".join(f"{e['kind']} {e['address']}" for e in b["endpoints"]) or "no endpoint"
        lines.append(f"{b['name']}  {b['model']}  {b['link']}  {where}")
    return "\n".join(lines) if lines else "no boards"


def _limits(axis: dict[str, Any]) -> str:
    on = [s for s, key in (("+", "limit_positive"), ("-", "limit_negative")) if axis[key]]
    return " ".join(on) if on else "none"


def _yes(flag: object) -> str:
    return "yes" if flag else "no"


def _axes(state: dict[str, Any], letters: list[str]) -> str:
    rows = [list(_COLUMNS)]
    for letter in letters:
        a = state["axes"][letter]
        rows.append(
            [
                letter,
                str(a["position"]),
                "-" if a["encoder"] is None else str(a["encoder"]),
                f"{a['velocity']:.6g}",
                a["motion"],
                _yes(a["done"]),
                _limits(a),
                _yes(a["home"]),
                f"{a['queue_free']} free",
            ]
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(_COLUMNS))]
    return "\n".join(
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
        for row in rows
    )


def _io(state: dict[str, Any]) -> str:
    return f"I/O lines low 0x{state['io_low']:04X}, outputs driven low 0x{state['outputs_low']:04X}"


def _clock(clock: dict[str, Any]) -> str:
    how = "paused" if clock["paused"] else "running"
    scale = "" if clock["scale"] == 1.0 else f", scale {clock['scale']:g}"
    return f"{clock['now']:.6f} s, {how}{scale}"


def _faults(faults: dict[str, Any]) -> str:
    parts = []
    if faults["latency"]:
        parts.append(f"latency {faults['latency']:g} s")
    if faults["baud"] is not None:
        parts.append(f"baud {faults['baud']}")
    if faults["drop"]:
        parts.append(f"drop {faults['drop']:g}")
    if faults["garble"]:
        parts.append(f"garble {faults['garble']:g}")
    if faults["drop"] or faults["garble"]:
        parts.append(f"seed {faults['seed']}")
    if not faults["cable"]:
        parts.append("cable cut")
    return ", ".join(parts) if parts else "none"


def _summary(state: dict[str, Any]) -> str:
    link = state["link"]
    link_parts = [str(link["kind"]), f"room {link['room']}"]
    if link.get("pending") is not None:
        link_parts.append(f"pending {link['pending']}")
    if link.get("waiting") is not None:
        link_parts.append(f"held until {link['waiting']}")
    lines = [
        f"{state['board']}: {state['model']}, mode {state['mode']}",
        _axes(state, list(state["axes"])),
        f"registers: status 0x{state['status']:02X}, done 0x{state['done_register']:02X}, "
        f"control 0x{state['control']:02X}",
        _io(state),
        f"input buffer: {state['input_buffer']} characters",
        f"link: {', '.join(link_parts)}",
        f"clients: {', '.join(state['clients']) or 'none'}",
        f"clock: {_clock(state['clock'])}",
        f"faults: {_faults(state['faults'])}",
    ]
    return "\n".join(lines)


#: Two examples for each command's help.
EXAMPLES: dict[str, tuple[tuple[str, str], ...]] = {
    "boards": (
        ("omsd ctl boards", "names, models, endpoints"),
        (f"omsd ctl --socket {SERVICE_SOCKET} boards", "the service's"),
    ),
    "state": (
        ("omsd ctl state", "the only board's state"),
        ("omsd ctl --board xy state --json", "board xy's, as JSON"),
    ),
    "limit": (
        ("omsd ctl limit X + on", "X's positive limit switch closes"),
        ("omsd ctl --board xy limit Y - auto", "the carriage decides again"),
    ),
    "home": (
        ("omsd ctl home X on", "X's home switch active"),
        ("omsd ctl home X auto", "as the carriage is"),
    ),
    "input": (
        ("omsd ctl input 3 low", "input 3 grounded: true to WS and SW"),
        ("omsd ctl input 3 auto", "released, pulled up"),
    ),
    "slip": (
        ("omsd ctl slip X 20", "the encoder sees 20 steps, the counter not"),
        ("omsd ctl --board xy slip Y -5", "5 steps the other way"),
    ),
    "stall": (
        ("omsd ctl stall X on", "X's pulses count on, the carriage stays"),
        ("omsd ctl stall X off", "it follows its pulses again"),
    ),
    "encoder": (
        ("omsd ctl encoder Y 1500", "Y's encoder input reads 1500"),
        ("omsd ctl --board servo encoder X 0", "board servo's X"),
    ),
    "fault": (
        ("omsd ctl fault --latency 0.2 --baud 9600", "a slow serial line"),
        ("omsd ctl fault --cut", "pull the cable (--connect: back)"),
        ("omsd ctl fault --clear", "no faults"),
    ),
    "time": (
        ("omsd ctl time", "the clock"),
        ("omsd ctl time pause; omsd ctl time step 0.5", "half a second, exactly"),
    ),
    "reset": (
        ("omsd ctl reset", "power-cycle the only board"),
        ("omsd ctl --board xy reset", "board xy"),
    ),
    "wait": (
        ("omsd ctl wait done X --timeout 5", "until X's done flag is set"),
        ("omsd ctl wait idle", "until every axis is at rest"),
    ),
}


__all__ = ["SERVICE_SOCKET", "Unreachable", "connect", "main", "parser"]
