"""The daemon's configuration: a TOML file, or the single-board command line, made into frozen,
validated dataclasses.

A file describes one or more boards, each with its own endpoints, link settings and simulated
world (``config/omsd.toml`` shows and explains every key)::

    [log]
    file = "/var/log/omsd/traffic.jsonl"   # JSON-lines traffic log (relative: to this file)
    view = "auto"                          # auto | rich | plain | off
    group = "adm"                          # a new log file: 0640 in this group (default 0600)

    [state]
    file = "/var/lib/omsd/omsd.state"      # the boards' flash memory (relative: to this file)
    group = "adm"                          # the state file: 0640 in this group (default 0600)

    [mqtt]                                 # the MQTT bridge (omsd.mqtt): off without this table
    host = "broker.lab"                    # required; port 1883 (8883 with tls) unless given
    prefix = "omsd"                        # topics <prefix>/status, <prefix>/<board>/...

    [[board]]
    name = "xy-stage"          # [A-Za-z0-9_.-]+, default board1, board2, ...
    model = "PC48-4E"          # any personality of `omsd models`, case-insensitive
    link = "driver"            # driver | raw
    eos = "0A"                 # the driver's E:XX, hex string, or an integer character code
    buffer = 256               # the driver's B:XXXX, integer, or hex string "0100"
    tcp = ["127.0.0.1:7001"]   # "[HOST:]PORT" or PORT, {address, terminal}, or a list of them
    pty = "/run/omsd/xy"       # path, true (the default link), {link, group, mode, terminal},
                               # or a list
    second_client = "takeover" # takeover | refuse
    linger = 60                # seconds a TCP client that shut down its sending side is kept
                               # for the answers to what it sent (0: closed at once)
    inputs = { 0 = false }     # general-purpose input bit -> level driven onto it (true = high)

    [board.axes.X]             # any field of omsd.board.world.AxisWorld
    negative_limit = -50000

The driver settings are the DOS device driver's command line options (PC48 manual §7.3.2):

    "B:XXXX where XXXX is a hexadecimal number from 0010 to 7fff (16 to 32767 decimal). This
    value defines the "output to board" BUFFER size. [...] The default value is 0100 hex (256
    decimal)."

    "E:XX where XX is the hexadecimal value of the ASCII character you want to use to show the
    END OF STRING from the board (like a response to an RP command). [...] The default value is
    an LF."

so a string is read as hexadecimal, as the driver reads it (``eos = "0D"``), and an integer is
the value itself (``eos = 13`` or ``eos = 0x0D``). Both options shape the driver link only: on a
``raw`` link, which keeps the board's own LF/CR framing, they are an error.

Every error is a :class:`ConfigError` whose text is one line, ``<file>:<line>: <key path>:
expected <what>, got <value>`` (``omsd.toml:14: [board "xy"] axes.X.positive_limit: expected a
number (motor steps), got "5k"``), or for a command-line option ``--tcp: expected [HOST:]PORT
with PORT 0..65535, got "abc"``. A board is named by its name, one without a name by the name it
is given (``[board "board2" (unnamed)]``); the line is found in the file's text and left out
when it cannot be (:mod:`omsd.config_errors`, which formats and locates, and knows nothing of
the keys here).

Choices where the issue is silent:

* Relative paths in a file are relative to the file's directory (the daemon may run from ``/``);
  on the command line, to the working directory. ``~`` is expanded. Paths are made absolute.
* A TCP endpoint without a host binds 127.0.0.1. ``:7001`` is refused as ambiguous (some tools
  read it as "every interface"): write ``0.0.0.0:7001``. IPv6 addresses go in brackets,
  ``[::1]:7001``. Port 0 asks the OS for a free port, and may appear any number of times.
* Two endpoints conflict if they are the same TCP address and port, a wildcard (``0.0.0.0``,
  ``::``) and an address of its family on the same port, or the same pty link.
* A board in a file needs at least one endpoint; the command line falls back to the defaults
  (TCP 127.0.0.1:7048 and a pty at :func:`default_pty_link`) when neither --tcp nor --pty is
  given.
* Encoder settings on an axis without an encoder are an error, as is a limit or home window that
  is empty (negative_limit >= positive_limit, home_low >= home_high).
* The boards' flash memory (a PCIx's AP power-up defaults and permanent macros, "stored in
  non-volatile flash RAM") is one state file for the whole daemon, ``[state] file``, with a
  section per board name (:mod:`omsd.statefile`); ``--state FILE`` gives or overrides it. None
  configured: flash lasts as long as the daemon runs. It may not be the traffic log's file.
"""

from __future__ import annotations

import difflib
import grp
import ipaddress
import math
import os
import re
import tomllib
import typing
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType

from omsd.board.world import AxisWorld, LimitWiring, SwitchType
from omsd.config_errors import ConfigError, KeyPath, board_label, key_text, show
from omsd.models import MODELS, UnknownModel, get_model, variant
from omsd.models.spec import Model

DEFAULT_TCP_PORT = 7048
DEFAULT_HOST = "127.0.0.1"
DEFAULT_MODEL = "PC48-4E"
DEFAULT_BOARD_NAME = "board1"
DEFAULT_EOS = 0x0A  # §7.3.2: "The default value is an LF."
DEFAULT_BUFFER_SIZE = 0x0100  # §7.3.2: "The default value is 0100 hex (256 decimal)."
#: How long a TCP client that has shut down its sending side (``nc -N``, ``shutdown(SHUT_WR)``)
#: is kept open for the answers, done markers and limits its commands are yet to produce.
DEFAULT_LINGER = 60.0
MAX_LINGER = 3600.0
BUFFER_SIZE_MIN = 0x0010  # §7.3.2: "from 0010 to 7fff (16 to 32767 decimal)"
BUFFER_SIZE_MAX = 0x7FFF
DEFAULT_PTY_MODE = 0o660
LINKS = ("driver", "raw")
SECOND_CLIENT_POLICIES = ("takeover", "refuse")
VIEWS = ("auto", "rich", "plain", "off")
MQTT_PORT = 1883  # IANA "mqtt"
MQTTS_PORT = 8883  # IANA "secure-mqtt"
MAX_STATE_RATE = 1000.0  # state publications per second per board, at most


# -- the configuration --------------------------------------------------------------------------


@dataclass(frozen=True)
class TcpEndpoint:
    """A listening TCP socket. ``port`` 0 lets the OS choose a free port."""

    host: str = DEFAULT_HOST
    port: int = DEFAULT_TCP_PORT
    terminal: bool = False  # for a person at a terminal program (omsd.transport.terminal)

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{host}:{self.port}"


@dataclass(frozen=True)
class PtyEndpoint:
    """A pseudo-terminal reached through the stable symlink ``link``."""

    link: Path
    group: str | None = None  # group to chown the pty device to; None: leave it
    mode: int = DEFAULT_PTY_MODE  # permissions of the pty device
    terminal: bool = False  # for a person at a terminal program (omsd.transport.terminal)

    def __str__(self) -> str:
        return str(self.link)


def _no_world() -> Mapping[str, AxisWorld]:
    return MappingProxyType({})


def _no_inputs() -> Mapping[int, bool]:
    return MappingProxyType({})


@dataclass(frozen=True)
class BoardConfig:
    """One emulated board and how it is served."""

    name: str
    model: str = DEFAULT_MODEL  # canonical name, a key of omsd.models.MODELS
    link: str = "driver"  # "driver" or "raw"
    eos: int = DEFAULT_EOS  # the driver's E:XX
    buffer_size: int = DEFAULT_BUFFER_SIZE  # the driver's B:XXXX
    tcp: tuple[TcpEndpoint, ...] = ()
    pty: tuple[PtyEndpoint, ...] = ()
    second_client: str = "takeover"  # a new TCP client replaces the connected one, or "refuse"
    linger: float = DEFAULT_LINGER  # s a half-closed TCP client waits for its answers
    world: Mapping[str, AxisWorld] = field(default_factory=_no_world)  # axis letter -> world
    inputs: Mapping[int, bool] = field(default_factory=_no_inputs)  # input bit -> high?
    encoders: str | None = None  # axes fitted with encoders, if not the model's (VS4 option)
    serial: str | None = None  # serial number WY reports (VS4), if not the model's
    firmware: str | None = None  # firmware revision WY reports, if not the model's
    max_queries: bool | None = None  # PCIx: answer the MAX-family queries (default on)

    def personality(self) -> Model:
        """The model as fitted and labelled on this board."""
        return variant(
            get_model(self.model), self.encoders, self.serial, self.firmware, self.max_queries
        )

    def __post_init__(self) -> None:
        # Frozen all the way down, whatever the caller passed.
        object.__setattr__(self, "tcp", tuple(self.tcp))
        object.__setattr__(self, "pty", tuple(self.pty))
        object.__setattr__(self, "world", MappingProxyType(dict(self.world)))
        object.__setattr__(self, "inputs", MappingProxyType(dict(self.inputs)))


@dataclass(frozen=True)
class LogConfig:
    file: Path | None = None  # JSON-lines traffic log
    view: str = "auto"  # "auto", "rich", "plain" or "off"
    group: str | None = None  # a new log file is 0640 in this group; None: 0600


@dataclass(frozen=True)
class DaemonConfig:
    boards: tuple[BoardConfig, ...]
    log: LogConfig = field(default_factory=LogConfig)
    source: str = "built-in default"  # "built-in default", "command line", or the file path
    state: Path | None = None  # the boards' flash (omsd.statefile); None: kept in memory only
    control: ControlConfig = field(default_factory=lambda: ControlConfig())
    mqtt: MqttConfig | None = None  # the MQTT bridge (omsd.mqtt); None: off
    state_group: str | None = None  # the state file is 0640 in this group; None: 0600


@dataclass(frozen=True)
class ControlConfig:
    """The control endpoint (omsd.control): a Unix socket, owner-only, at ``socket`` (``None``:
    none); ``explicit`` when the path was configured (then a path in use is a start-up error;
    the default path in use only costs a warning: another omsd of this user has it); ``tcp``
    only if configured (no network exposure by default)."""

    socket: Path | None = field(default_factory=lambda: default_pty_link("control.sock"))
    explicit: bool = False
    tcp: TcpEndpoint | None = None
    group: str | None = None  # the socket is 0660 in this group; None: 0600


@dataclass(frozen=True)
class MqttConfig:
    """The MQTT bridge (:mod:`omsd.mqtt`), on only when ``[mqtt]`` is given.

    ``tls`` is ``False`` (plain TCP), ``True`` (TLS, the system's CA certificates) or the path of
    a CA file to verify the broker with. ``port`` defaults to 1883, or 8883 with TLS (the
    IANA ports "mqtt" and "secure-mqtt"). ``client_id`` ``None`` lets the client library make
    one up. ``state_rate`` bounds the retained state publications per second per board while
    its axes move; ``traffic`` turns the traffic topic off.
    """

    host: str
    port: int = MQTT_PORT
    username: str | None = None
    password: str | None = None
    tls: bool | Path = False
    client_id: str | None = None
    prefix: str = "omsd"
    keepalive: int = 60
    state_rate: float = 10.0
    traffic: bool = True


# -- defaults -----------------------------------------------------------------------------------


def runtime_directory() -> Path:
    """The daemon's runtime directory, where the default pty links and the control socket go:
    ``$RUNTIME_DIRECTORY`` under a systemd unit with ``RuntimeDirectory=``, else
    ``$XDG_RUNTIME_DIR/omsd``, else ``/tmp/omsd-<uid>``. The daemon creates it (mode 0700) and
    refuses one that another user could change (:func:`omsd.files.check_runtime_directory`)."""
    runtime = os.environ.get("RUNTIME_DIRECTORY", "").split(":")[0]
    if os.path.isabs(runtime):
        return Path(runtime)
    xdg = os.environ.get("XDG_RUNTIME_DIR", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "omsd"
    return Path(f"/tmp/omsd-{os.getuid()}")


def default_pty_link(name: str) -> Path:
    """Where a board's pty link goes when none is configured: ``<name>`` in the
    :func:`runtime_directory`. The daemon creates the directory."""
    return runtime_directory() / name


def _default_board(model: str = DEFAULT_MODEL) -> BoardConfig:
    return BoardConfig(
        name=DEFAULT_BOARD_NAME,
        model=model,
        tcp=(TcpEndpoint(DEFAULT_HOST, DEFAULT_TCP_PORT),),
        pty=(PtyEndpoint(default_pty_link(DEFAULT_BOARD_NAME)),),
    )


def default_config() -> DaemonConfig:
    """``omsd`` with no arguments: one PC48-4E on TCP 127.0.0.1:7048 and on a pty."""
    return DaemonConfig(boards=(_default_board(),), log=LogConfig(), source="built-in default")


# -- where a value came from --------------------------------------------------------------------


@dataclass(frozen=True)
class _At:
    """A place in the configuration: a file (or an option), a key path inside it, and the labels
    that name some of its tables in messages (``("board", 0)`` → ``[board "xy"]``)."""

    source: str
    path: KeyPath = ()
    labels: Mapping[KeyPath, str] = field(default_factory=dict, compare=False, hash=False)

    def key(self, name: str) -> _At:
        return _At(self.source, (*self.path, name), self.labels)

    def index(self, i: int) -> _At:
        return _At(self.source, (*self.path, i), self.labels)

    def labelled(self, label: str) -> _At:
        return _At(self.source, self.path, {**self.labels, self.path: label})

    @property
    def shown(self) -> str | None:
        return key_text(self.path, self.labels)

    def error(self, detail: str, also: _At | None = None) -> ConfigError:
        return ConfigError(
            self.source,
            self.shown,
            detail,
            path=self.path,
            also=None if also is None else also.shown or also.source,
            also_path=None if also is None else also.path,
        )

    def expected(self, what: str, got: object) -> ConfigError:
        return self.error(f"expected {what}, got {show(got)}")


# -- values -------------------------------------------------------------------------------------


def _table(value: object, at: _At, allowed: Sequence[str] | None = None) -> dict[str, object]:
    if not isinstance(value, dict):
        raise at.expected("a table", value)
    if allowed is not None:
        for key in value:
            if key not in allowed:
                close = difflib.get_close_matches(key, allowed, n=1)
                hint = f" (did you mean {close[0]!r}?)" if close else ""
                raise at.key(key).error(f"unknown key{hint}; expected one of {', '.join(allowed)}")
    return value


def _string(value: object, at: _At) -> str:
    if not isinstance(value, str) or not value:
        raise at.expected("a non-empty string", value)
    return value


def _choice(value: object, choices: Sequence[str], at: _At) -> str:
    if isinstance(value, str) and value.lower() in choices:
        return value.lower()
    raise at.expected(" or ".join(show(c) for c in choices), value)


def _integer(value: object, at: _At, lo: int, hi: int | None = None) -> int:
    what = f"an integer {lo}..{hi}" if hi is not None else f"an integer >= {lo}"
    if isinstance(value, bool) or not isinstance(value, int):
        raise at.expected(what, value)
    if value < lo or (hi is not None and value > hi):
        raise at.expected(what, value)
    return value


def _number(value: object, at: _At) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise at.expected("a number (motor steps)", value)
    if not math.isfinite(value):
        raise at.expected("a finite number", value)
    return float(value)


def _boolean(value: object, at: _At, what: str) -> bool:
    if not isinstance(value, bool):
        raise at.expected(what, value)
    return value


def _hex_or_int(value: object, at: _At, digits: int, lo: int, hi: int, what: str) -> int:
    """A driver option: a string is hexadecimal (``"0D"``, ``"0x0d"``), an integer is itself."""
    if isinstance(value, str):
        m = re.fullmatch(rf"(?:0[xX])?([0-9A-Fa-f]{{1,{digits}}})", value.strip())
        if m is not None and lo <= int(m.group(1), 16) <= hi:
            return int(m.group(1), 16)
    elif isinstance(value, int) and not isinstance(value, bool) and lo <= value <= hi:
        return value
    raise at.expected(what, value)


def _eos(value: object, at: _At) -> int:
    return _hex_or_int(
        value, at, 2, 0, 0xFF, 'a character code 00..FF in hex like the driver\'s E:XX ("0D")'
    )


def _buffer_size(value: object, at: _At) -> int:
    return _hex_or_int(
        value,
        at,
        4,
        BUFFER_SIZE_MIN,
        BUFFER_SIZE_MAX,
        'a buffer size 16..32767 (hex "0010".."7FFF" like the driver\'s B:XXXX)',
    )


def _model(value: object, at: _At) -> Model:
    if isinstance(value, str):
        try:
            return get_model(value)
        except UnknownModel:
            pass
    raise at.expected(f"a board model ({', '.join(MODELS)})", value)


_NAME = re.compile(r"[A-Za-z0-9_.-]+")


def _name(value: object, at: _At) -> str:
    if not isinstance(value, str) or not _NAME.fullmatch(value) or value in (".", ".."):
        raise at.expected("a name of letters, digits, '_', '.' and '-'", value)
    return value


def _path(value: object, at: _At, base: Path) -> Path:
    if not isinstance(value, str) or not value.strip() or "\0" in value:
        raise at.expected("a path", value)
    path = Path(value).expanduser()
    return Path(os.path.normpath(base / path))


# -- TCP ----------------------------------------------------------------------------------------

TCP_SYNTAX = "[HOST:]PORT with PORT 0..65535"
_TCP = re.compile(r"(?:(?:\[(?P<v6>[^\]]*)\]|(?P<host>[^:\[\]]*)):)?(?P<port>[0-9]{1,5})")
_HOSTNAME = re.compile(r"[A-Za-z0-9_]([A-Za-z0-9_-]*[A-Za-z0-9_])?(\.[A-Za-z0-9_-]+)*")


def _tcp(value: object, at: _At) -> TcpEndpoint:
    """``PORT``, ``HOST:PORT`` or ``[IPv6]:PORT``; an integer is a port on 127.0.0.1."""
    if isinstance(value, int) and not isinstance(value, bool):
        if 0 <= value <= 65535:
            return TcpEndpoint(DEFAULT_HOST, value)
        raise at.expected(TCP_SYNTAX, value)
    if not isinstance(value, str):
        raise at.expected(TCP_SYNTAX, value)
    m = _TCP.fullmatch(value)
    if m is None or int(m.group("port")) > 65535:
        raise at.expected(TCP_SYNTAX, value)
    port = int(m.group("port"))
    v6, host = m.group("v6"), m.group("host")
    if v6 is not None:
        try:
            ipaddress.IPv6Address(v6)
        except ValueError:
            raise at.expected("[HOST:]PORT with an IPv6 address inside [ ]", value) from None
        return TcpEndpoint(v6, port)
    if host is None:
        return TcpEndpoint(DEFAULT_HOST, port)
    if host == "":
        raise at.expected(
            "[HOST:]PORT with a HOST before the colon (0.0.0.0 for every interface)", value
        )
    if re.fullmatch(r"[0-9.]+", host):
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise at.expected("[HOST:]PORT with a valid IPv4 address", value) from None
    elif not _HOSTNAME.fullmatch(host):
        raise at.expected("[HOST:]PORT with HOST an address or a host name", value)
    return TcpEndpoint(host, port)


def _family(host: str) -> int | None:
    try:
        return ipaddress.ip_address(host.split("%")[0]).version
    except ValueError:
        return None  # a host name: only the same name is known to collide


def _tcp_conflict(a: TcpEndpoint, b: TcpEndpoint) -> bool:
    if a.port != b.port or a.port == 0:
        return False
    if a.host == b.host:
        return True
    family = _family(a.host)
    wildcards = ("0.0.0.0", "::")
    return (
        family is not None
        and family == _family(b.host)
        and (a.host in wildcards or b.host in wildcards)
    )


# -- one board ----------------------------------------------------------------------------------

_BOARD_KEYS = (
    "name",
    "model",
    "link",
    "eos",
    "buffer",
    "tcp",
    "pty",
    "second_client",
    "linger",
    "inputs",
    "axes",
    "encoders",
    "serial",
    "firmware",
    "max_queries",
)
_PTY_KEYS = ("link", "group", "mode", "terminal")
_TCP_KEYS = ("address", "terminal")
_LOG_KEYS = ("file", "view", "group")
_STATE_KEYS = ("file", "group")
_CONTROL_KEYS = ("socket", "tcp", "group")
_MQTT_KEYS = (
    "host",
    "port",
    "username",
    "password",
    "tls",
    "client_id",
    "prefix",
    "keepalive",
    "state_rate",
    "traffic",
)
_TOP_KEYS = ("log", "state", "control", "mqtt", "board")
_WORLD_FIELDS = typing.get_type_hints(AxisWorld)
_WORLD_KEYS = tuple(f.name for f in fields(AxisWorld))
_ENCODER_KEYS = ("encoder_counts_per_rev", "encoder_index")


@dataclass
class _Parsed:
    """A board with the key path of each of its endpoints, for the duplicate checks."""

    board: BoardConfig
    at: _At
    tcp: list[tuple[TcpEndpoint, _At]]
    pty: list[tuple[PtyEndpoint, _At]]


def _items(value: object, at: _At) -> list[tuple[object, _At]]:
    """A single value or a list of them, each with its key path."""
    if isinstance(value, list):
        return [(item, at.index(i)) for i, item in enumerate(value)]
    return [(value, at)]


def _pty(value: object, at: _At, base: Path, name: str) -> PtyEndpoint:
    if value is True:
        return PtyEndpoint(default_pty_link(name))
    if isinstance(value, str):
        return PtyEndpoint(_path(value, at, base))
    if not isinstance(value, dict):
        raise at.expected("a path, true (the default link) or a table {link, group, mode}", value)
    table = _table(value, at, _PTY_KEYS)
    link = default_pty_link(name)
    if "link" in table:
        link = _path(table["link"], at.key("link"), base)
    group = _string(table["group"], at.key("group")) if "group" in table else None
    mode = DEFAULT_PTY_MODE
    if "mode" in table:
        mode = _hex_or_mode(table["mode"], at.key("mode"))
    terminal = _boolean(table.get("terminal", False), at.key("terminal"), "true or false")
    return PtyEndpoint(link, group, mode, terminal)


def _board_tcp(value: object, at: _At) -> TcpEndpoint:
    """A board's TCP endpoint: ``[HOST:]PORT``, ``PORT`` or ``{address, terminal}``."""
    if not isinstance(value, dict):
        return _tcp(value, at)
    table = _table(value, at, _TCP_KEYS)
    if "address" not in table:
        raise at.error(f"expected a table with an address ({TCP_SYNTAX}), got none")
    endpoint = _tcp(table["address"], at.key("address"))
    terminal = _boolean(table.get("terminal", False), at.key("terminal"), "true or false")
    return replace(endpoint, terminal=terminal)


def _hex_or_mode(value: object, at: _At) -> int:
    """Permissions: an integer (TOML ``0o660``) or an octal string (``"0660"``, ``"0o660"``)."""
    if isinstance(value, str):
        m = re.fullmatch(r"(?:0[oO])?([0-7]{1,4})", value.strip())
        if m is not None and int(m.group(1), 8) <= 0o777:
            return int(m.group(1), 8)
    elif isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 0o777:
        return value
    raise at.expected('permissions 0o000..0o777 (write 0o660 or "0660")', value)


def _axis_world(value: object, at: _At, model: Model, letter: str) -> AxisWorld:
    table = _table(value, at, _WORLD_KEYS)
    changes: dict[str, object] = {}
    for key, raw in table.items():
        kind = _WORLD_FIELDS[key]
        if key in _ENCODER_KEYS and not model.has_encoder(letter):
            if model.encoder_axes:
                where = f"encoders on {', '.join(model.encoder_axes)}"
            else:
                where = "no encoder option"
            raise at.key(key).error(f"{model.name} has no encoder on axis {letter} ({where})")
        if kind is float:
            changes[key] = _number(raw, at.key(key))
        elif kind is SwitchType:
            choices = tuple(s.value for s in SwitchType)
            changes[key] = SwitchType(_choice(raw, choices, at.key(key)))
        elif kind is LimitWiring:
            choices = tuple(s.value for s in LimitWiring)
            changes[key] = LimitWiring(_choice(raw, choices, at.key(key)))
        elif kind is int and key == "encoder_counts_per_rev":
            changes[key] = _integer(raw, at.key(key), 1)
        elif kind is int:
            changes[key] = _integer(raw, at.key(key), 0)
        else:  # pragma: no cover - a new AxisWorld field needs a rule here
            raise TypeError(f"AxisWorld.{key}: no configuration rule for {kind!r}")
    world = AxisWorld().with_changes(**changes)
    if world.negative_limit >= world.positive_limit:
        key = "positive_limit" if "positive_limit" in table else "negative_limit"
        raise at.key(key).error(
            f"expected negative_limit below positive_limit, got {world.negative_limit:g}"
            f" and {world.positive_limit:g}"
        )
    if world.home_low >= world.home_high:
        key = "home_high" if "home_high" in table else "home_low"
        raise at.key(key).error(
            f"expected home_low below home_high, got {world.home_low:g} and {world.home_high:g}"
        )
    if world.encoder_index >= world.encoder_counts_per_rev:
        raise at.key("encoder_index").expected(
            f"an integer 0..{world.encoder_counts_per_rev - 1} (below encoder_counts_per_rev)",
            world.encoder_index,
        )
    return world


def _worlds(value: object, at: _At, model: Model) -> dict[str, AxisWorld]:
    table = _table(value, at)
    worlds: dict[str, AxisWorld] = {}
    for key, raw in table.items():
        letter = key.upper()
        if letter not in model.axes or len(letter) != 1:
            raise at.key(key).error(f"{model.name} has axes {', '.join(model.axes)}")
        if letter in worlds:
            raise at.key(key).error(f"axis {letter} is given twice")
        worlds[letter] = _axis_world(raw, at.key(key), model, letter)
    return worlds


def _inputs(value: object, at: _At, model: Model) -> dict[int, bool]:
    table = _table(value, at)
    levels: dict[int, bool] = {}
    bits = f"a general-purpose I/O bit 0..{model.io_bits - 1} of the {model.name}"
    for key, raw in table.items():
        if not re.fullmatch(r"[0-9]{1,3}", key) or int(key) >= model.io_bits:
            raise at.key(key).expected(bits, key)
        if int(key) in levels:
            raise at.key(key).error(f"input bit {int(key)} is given twice")
        levels[int(key)] = _boolean(raw, at.key(key), "true (high) or false (low)")
    return levels


def _board(value: object, at: _At, index: int, base: Path) -> _Parsed:
    table = _table(value, at, _BOARD_KEYS)
    name = _name(table.get("name", f"board{index + 1}"), at.key("name"))
    model = _model(table.get("model", DEFAULT_MODEL), at.key("model"))
    link = _choice(table.get("link", "driver"), LINKS, at.key("link"))
    eos = _eos(table.get("eos", DEFAULT_EOS), at.key("eos"))
    buffer_size = _buffer_size(table.get("buffer", DEFAULT_BUFFER_SIZE), at.key("buffer"))
    if link == "raw":
        for key in ("eos", "buffer"):
            if key in table:
                raise at.key(key).error(
                    "is a driver link setting; a raw link keeps the board's own LF/CR framing"
                )
    tcp = [(_board_tcp(v, a), a) for v, a in _items(table.get("tcp", []), at.key("tcp"))]
    pty = [(_pty(v, a, base, name), a) for v, a in _items(table.get("pty", []), at.key("pty"))]
    if not tcp and not pty:
        raise at.error("expected at least one endpoint (tcp or pty), got none")
    second = _choice(
        table.get("second_client", "takeover"), SECOND_CLIENT_POLICIES, at.key("second_client")
    )
    linger = _linger(table.get("linger", DEFAULT_LINGER), at.key("linger"))
    encoders = _encoders(table.get("encoders"), at.key("encoders"), model)
    serial = _label(table.get("serial"), at.key("serial"), r"[A-Za-z0-9-]{1,16}", "a serial number")
    firmware = _label(table.get("firmware"), at.key("firmware"), r"\d{1,2}\.\d{2}", "a version")
    max_queries = None
    if "max_queries" in table:
        if model.dialect != "pcix":
            raise at.key("max_queries").error(
                f"is a PCIx setting; a {model.name} speaks no MAX-family dialect"
            )
        max_queries = _boolean(table["max_queries"], at.key("max_queries"), "true or false")
    model = variant(model, encoders, serial, firmware, max_queries)
    world = _worlds(table.get("axes", {}), at.key("axes"), model)
    inputs = _inputs(table.get("inputs", {}), at.key("inputs"), model)
    board = BoardConfig(
        name=name,
        model=model.name,
        link=link,
        eos=eos,
        buffer_size=buffer_size,
        tcp=tuple(t for t, _ in tcp),
        pty=tuple(p for p, _ in pty),
        second_client=second,
        linger=linger,
        world=world,
        inputs=inputs,
        encoders=encoders,
        serial=serial,
        firmware=firmware,
        max_queries=max_queries,
    )
    return _Parsed(board, at, tcp, pty)


def _linger(value: object, at: _At) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise at.expected(f"a number of seconds 0..{MAX_LINGER:g}", value)
    seconds = float(value)
    if not 0 <= seconds <= MAX_LINGER:
        raise at.expected(f"a number of seconds 0..{MAX_LINGER:g}", value)
    return seconds


def _encoders(value: object, at: _At, model: Model) -> str | None:
    """``true`` (the model's), ``false`` (none: a board ordered without the encoder option) or
    the letters of the axes that have one."""
    if value is None or value is True:
        return None
    if value is False:
        return ""
    if isinstance(value, str) and value and set(value.upper()) <= set(model.axes):
        return "".join(a for a in model.axes if a in value.upper())
    raise at.expected(f"true, false or axis letters of {''.join(model.axes)}", value)


def _label(value: object, at: _At, pattern: str, what: str) -> str | None:
    if value is None:
        return None
    if isinstance(value, str) and re.fullmatch(pattern, value):
        return value
    raise at.expected(f"{what} like {pattern!r}", value)


def _duplicate(at: _At, other: _At, what: str, got: str) -> ConfigError:
    detail = f"expected {what} no other endpoint uses, got {show(got, shorten=False)}"
    if at == other:  # the same option twice on the command line
        return at.error(detail + " twice")
    return at.error(detail, other)


def _check_unique(parsed: Iterable[_Parsed]) -> None:
    names: dict[str, _At] = {}
    tcps: list[tuple[TcpEndpoint, _At]] = []
    ptys: dict[Path, _At] = {}
    for p in parsed:
        at = p.at.key("name")
        if p.board.name in names:
            raise at.error(
                f"expected a name no other board has, got {show(p.board.name)}", names[p.board.name]
            )
        names[p.board.name] = at
        for endpoint, at in p.tcp:
            for other, other_at in tcps:
                if _tcp_conflict(endpoint, other):
                    raise _duplicate(at, other_at, "an address", str(endpoint))
            tcps.append((endpoint, at))
        for pty, at in p.pty:
            if pty.link in ptys:
                raise _duplicate(at, ptys[pty.link], "a link", str(pty.link))
            ptys[pty.link] = at


# -- a file -------------------------------------------------------------------------------------


def load_config(path: str | os.PathLike[str]) -> DaemonConfig:
    """Read and validate a TOML configuration file."""
    source = os.fspath(path)
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ConfigError(source, None, f"cannot read the file: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        byte = data[exc.start]
        detail = f"expected UTF-8 text, got byte {byte:#04x} at offset {exc.start}"
        raise ConfigError(source, None, detail) from None
    text = text.removeprefix("\ufeff")  # a byte order mark from a Windows editor is harmless
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        m = re.fullmatch(r"(.*) \(at line (\d+), column (\d+)\)", message)
        if m is None:  # "(at end of document)": said as it is
            raise ConfigError(source, None, f"invalid TOML: {message}") from None
        line, column = int(m.group(2)), int(m.group(3))
        detail = f"invalid TOML: {m.group(1)}"
        raise ConfigError(source, None, detail, line=line, column=column) from None
    base = Path(source).expanduser().absolute().parent
    try:
        return _document(document, _At(source), base)
    except ConfigError as exc:
        raise exc.locate(text) from None


def _document(document: dict[str, object], at: _At, base: Path) -> DaemonConfig:
    _table(document, at, _TOP_KEYS)
    log = _log(document.get("log", {}), at.key("log"), base)
    state, state_group = _state(document.get("state", {}), at.key("state"), base)
    if state is not None and state == log.file:
        raise _not_the_log(at.key("state").key("file"), state)
    boards = document.get("board")
    if boards is None or boards == []:
        raise at.key("board").error("expected at least one [[board]] table, got none")
    if not isinstance(boards, list):
        raise at.key("board").expected("an array of tables, [[board]]", boards)
    parsed = [_board(b, _board_at(at, b, i), i, base) for i, b in enumerate(boards)]
    _check_unique(parsed)
    control = _control(document.get("control", {}), at.key("control"), base)
    mqtt = _mqtt(document["mqtt"], at.key("mqtt"), base) if "mqtt" in document else None
    return DaemonConfig(
        tuple(p.board for p in parsed),
        log,
        at.source,
        state,
        control,
        mqtt,
        state_group=state_group,
    )


def _board_at(at: _At, value: object, index: int) -> _At:
    """Where the ``index``-th ``[[board]]`` is, named in messages by its name (or, without one,
    the name it is given: ``board1``, ...) rather than by its index."""
    name = value.get("name") if isinstance(value, dict) else None
    return at.key("board").index(index).labelled(board_label(name, index))


def _control(value: object, at: _At, base: Path) -> ControlConfig:
    """``[control] socket = "PATH"`` (or ``false``: no control endpoint), ``tcp = "[HOST:]PORT"``
    (off unless given), ``group = "NAME"`` (the socket 0660 in that group, for its members'
    ``omsd ctl``; default 0600, the daemon's user alone)."""
    table = _table(value, at, _CONTROL_KEYS)
    config = ControlConfig()
    if "socket" in table:
        raw = table["socket"]
        if raw is False:
            config = replace(config, socket=None, explicit=True)
        else:
            path = _path(raw, at.key("socket"), base)
            config = replace(config, socket=path, explicit=True)
    if "tcp" in table:
        config = replace(config, tcp=_tcp(table["tcp"], at.key("tcp")))
    if "group" in table:
        config = replace(config, group=_file_group(table["group"], at.key("group")))
    return config


_TOPIC_LEVEL = re.compile(r"[^/+#\x00]+")


def _mqtt(value: object, at: _At, base: Path) -> MqttConfig:
    """``[mqtt]``: the bridge is on when the table is there, and then ``host`` is required (a
    broker is never guessed: a bridge quietly publishing to a localhost broker nobody meant
    is worse than an error)."""
    table = _table(value, at, _MQTT_KEYS)
    if "host" not in table:
        raise at.key("host").error("expected the broker's host name or address, got none")
    host = table["host"]
    if not isinstance(host, str) or not (
        _is_address(host.strip("[]"))
        or (_HOSTNAME.fullmatch(host) and not re.fullmatch(r"[0-9.]+", host))
    ):
        raise at.key("host").expected("a host name or address", host)
    tls: bool | Path = False
    if "tls" in table:
        raw = table["tls"]
        if isinstance(raw, bool):
            tls = raw
        elif isinstance(raw, str):
            tls = _path(raw, at.key("tls"), base)
            if not tls.is_file():
                raise at.key("tls").expected("true, false or a CA certificate file", str(tls))
        else:
            raise at.key("tls").expected("true, false or a CA certificate file", raw)
    default_port = MQTT_PORT if tls is False else MQTTS_PORT
    port = _integer(table.get("port", default_port), at.key("port"), 1, 65535)
    username = password = None
    if "username" in table:
        username = _string(table["username"], at.key("username"))
    if "password" in table:
        if username is None:
            raise at.key("password").error("expected a username with the password, got none")
        raw = table["password"]
        if not isinstance(raw, str):
            raise at.key("password").error("expected a string (the value given is not shown)")
        password = raw
    client_id = None
    if "client_id" in table:
        client_id = _string(table["client_id"], at.key("client_id"))
        if "\x00" in client_id or len(client_id.encode()) > 65535:
            raise at.key("client_id").expected("an MQTT client identifier", client_id)
    prefix = table.get("prefix", "omsd")
    if (
        not isinstance(prefix, str)
        or prefix.startswith("$")
        or not all(_TOPIC_LEVEL.fullmatch(level) for level in prefix.split("/"))
    ):
        raise at.key("prefix").expected(
            "topic levels joined by '/', without '+', '#', empty levels or a leading '$'", prefix
        )
    keepalive = _integer(table.get("keepalive", 60), at.key("keepalive"), 1, 65535)
    rate = table.get("state_rate", 10.0)
    if (
        isinstance(rate, bool)
        or not isinstance(rate, int | float)
        or not 0 < rate <= MAX_STATE_RATE
    ):
        raise at.key("state_rate").expected(
            f"publications per second, above 0 and at most {MAX_STATE_RATE:g}", rate
        )
    traffic = _boolean(table.get("traffic", True), at.key("traffic"), "true or false")
    return MqttConfig(
        host=host.strip("[]"),
        port=port,
        username=username,
        password=password,
        tls=tls,
        client_id=client_id,
        prefix=prefix,
        keepalive=keepalive,
        state_rate=float(rate),
        traffic=traffic,
    )


def _is_address(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


def _log(value: object, at: _At, base: Path) -> LogConfig:
    table = _table(value, at, _LOG_KEYS)
    file = _path(table["file"], at.key("file"), base) if "file" in table else None
    view = _choice(table.get("view", "auto"), VIEWS, at.key("view"))
    group = _file_group(table["group"], at.key("group")) if "group" in table else None
    return LogConfig(file, view, group)


def _state(value: object, at: _At, base: Path) -> tuple[Path | None, str | None]:
    table = _table(value, at, _STATE_KEYS)
    file = _path(table["file"], at.key("file"), base) if "file" in table else None
    group = _file_group(table["group"], at.key("group")) if "group" in table else None
    return file, group


def _file_group(value: object, at: _At) -> str:
    """The group a file the daemon creates is given (``[log] group``, ``[state] group``): an
    existing group that the daemon's user is in (a process can only give a file to a group it
    belongs to; root can give it to any), so that the mistake shows now and not at the first
    write."""
    name = _string(value, at)
    try:
        gid = grp.getgrnam(name).gr_gid
    except KeyError:
        raise at.expected("the name of an existing group", value) from None
    if os.geteuid() != 0 and gid != os.getegid() and gid not in os.getgroups():
        raise at.expected(f"a group that omsd's user (uid {os.geteuid()}) belongs to", value)
    return name


def _not_the_log(at: _At, state: Path) -> ConfigError:
    return at.error(
        f"expected a file other than the traffic log, got {show(str(state), shorten=False)}"
    )


# -- the command line ---------------------------------------------------------------------------


def from_options(
    board: str | None,
    tcp: list[str],
    pty: list[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool = False,
) -> DaemonConfig:
    """The single-board form of the command line: ``--board MODEL --tcp [HOST:]PORT ...
    --pty PATH ... --link driver|raw --eos HEX --log FILE``. Without --tcp and --pty, the
    default endpoints; with either, only what is given. ``--terminal`` puts the ptys in
    terminal mode (TCP stays exact: terminal TCP endpoints are for a configuration file)."""
    cwd = Path.cwd()
    model = _model(DEFAULT_MODEL if board is None else board, _At("--board"))
    link_ = "driver" if link is None else _choice(link, LINKS, _At("--link"))
    eos_ = DEFAULT_EOS
    if eos is not None:
        if link_ == "raw":
            raise _At("--eos").error(
                "is a driver link setting; a raw link keeps the board's own LF/CR framing"
            )
        eos_ = _eos(eos, _At("--eos"))
    tcps = [(_tcp(t, _At("--tcp")), _At("--tcp")) for t in tcp]
    ptys = [(PtyEndpoint(_path(p, _At("--pty"), cwd)), _At("--pty")) for p in pty]
    if not tcp and not pty:
        default = _default_board()
        tcps = [(t, _At("--tcp")) for t in default.tcp]
        ptys = [(p, _At("--pty")) for p in default.pty]
    if terminal:
        ptys = [(replace(p, terminal=True), a) for p, a in ptys]
    config = BoardConfig(
        name=DEFAULT_BOARD_NAME,
        model=model.name,
        link=link_,
        eos=eos_,
        tcp=tuple(t for t, _ in tcps),
        pty=tuple(p for p, _ in ptys),
    )
    _check_unique([_Parsed(config, _At("--board"), tcps, ptys)])
    log_file = None if log is None else _path(log, _At("--log"), cwd)
    return DaemonConfig((config,), LogConfig(file=log_file), "command line")


def with_control_option(config: DaemonConfig, control: str | None) -> DaemonConfig:
    """``--control PATH`` (the control socket) or ``--control off``."""
    if control is None:
        return config
    if control == "off":
        return replace(config, control=replace(config.control, socket=None, explicit=True))
    path = _path(control, _At("--control"), Path.cwd())
    return replace(config, control=replace(config.control, socket=path, explicit=True))


def with_state_option(config: DaemonConfig, state: str | None) -> DaemonConfig:
    """``--state FILE`` on either form of the command line: the state file (relative to the
    working directory), in place of a file's ``[state] file``. ``None``: the configuration as
    it is."""
    if state is None:
        return config
    path = _path(state, _At("--state"), Path.cwd())
    if path == config.log.file:
        raise _not_the_log(_At("--state"), path)
    return replace(config, state=path)


__all__ = [
    "DEFAULT_MODEL",
    "DEFAULT_TCP_PORT",
    "BoardConfig",
    "ConfigError",
    "ControlConfig",
    "DaemonConfig",
    "LogConfig",
    "MqttConfig",
    "PtyEndpoint",
    "TcpEndpoint",
    "default_config",
    "default_pty_link",
    "from_options",
    "load_config",
    "runtime_directory",
    "with_state_option",
]
