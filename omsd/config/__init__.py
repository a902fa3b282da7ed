"""The daemon's configuration: a TOML file, or the single-board command line, made into frozen
dataclasses.

Every key is described once, in :mod:`omsd.config.schema` (pydantic models): its type, default,
meaning and what an error says (:mod:`omsd.config.wording`, :mod:`omsd.config.values`).
Validation (:mod:`omsd.config.reading`), the single-board command line, ``omsd config schema``
(the JSON Schema, ``config/omsd.schema.json``), ``omsd config show`` and the README's reference
table (:mod:`omsd.config.render`) are derived from it. This module is what the rest of omsd
uses: the frozen dataclasses below, the defaults they share with the schema (defined in
:mod:`omsd.defaults`, re-exported here), and :func:`load_config` and :func:`from_options`, which
import the schema only when called (pydantic takes ~0.1 s to import; ``omsd models`` and ``omsd
ctl`` never pay for it, and a valid single-board command line does not either: a fast path,
:mod:`omsd.config.fastpath`, reads it, and the schema reads everything else).

A file describes one or more boards, each with its own endpoints, link settings and simulated
world (``config/omsd.toml`` shows and explains every key, README "Configuration reference" lists
them)::

    [log]
    file = "/var/log/omsd/traffic.jsonl"   # JSON-lines traffic log (relative: to this file)
    view = "auto"                          # auto | rich | plain | off

    [[board]]
    name = "xy-stage"          # [A-Za-z0-9_.-]+, default board1, board2, ...
    model = "PC48-4E"          # any personality of `omsd models`, case-insensitive
    link = "driver"            # driver | raw
    eos = "0A"                 # the driver's E:XX, hex string, or an integer character code
    tcp = ["127.0.0.1:7001"]   # "[HOST:]PORT" or PORT, {address, terminal}, or a list of them
    pty = "/run/omsd/xy"       # path, true (the default link), {link, group, mode, terminal},
                               # or a list
    serial_port = "/dev/ttyUSB0,9600,8N1"  # PATH[,BAUD[,8N1]], {path, baud, bytesize, parity,
                               # stopbits, flow, pacing}, or a list
    rfc2217 = "127.0.0.1:7148" # as tcp, or {address, pacing}, or a list

    [board.axes.X]             # any field of omsd.board.AxisWorld
    negative_limit = -50000

Every error is a :class:`ConfigError` whose text is one line, ``<file>:<line>: <key path>:
expected <what>, got <value>`` (``omsd.toml:14: [board "xy"] axes.X.positive_limit: expected a
number (motor steps), got "5k"``), or for a command-line option ``--tcp: expected [HOST:]PORT
with PORT 0..65535, got "abc"`` (:mod:`omsd.config_errors` formats and locates).

Choices where the issue is silent:

* Relative paths in a file are relative to the file's directory (the daemon may run from ``/``);
  on the command line, to the working directory. ``~`` is expanded. Paths are made absolute.
* A TCP endpoint without a host binds 127.0.0.1. ``:7001`` is refused as ambiguous (some tools
  read it as "every interface"): write ``0.0.0.0:7001``. IPv6 addresses go in brackets,
  ``[::1]:7001``. Port 0 asks the OS for a free port, and may appear any number of times.
* Two endpoints conflict if they are the same TCP address and port (plain TCP and RFC 2217
  alike), a wildcard (``0.0.0.0``, ``::``) and an address of its family on the same port, the
  same pty link, or the same serial device.
* A board in a file needs at least one endpoint; the command line falls back to the defaults
  (TCP 127.0.0.1:7048 and a pty at :func:`default_pty_link`) when none of --tcp, --pty,
  --serial and --rfc2217 is given.
* The serial endpoint's key is ``serial_port``: ``serial`` is the serial number WY reports.
* Encoder settings on an axis without an encoder are an error, as is a limit or home window that
  is empty (negative_limit >= positive_limit, home_low >= home_high).
* The boards' flash memory (a PCIx's AP power-up defaults and permanent macros, "stored in
  non-volatile flash RAM") is one state file for the whole daemon, ``[state] file``, with a
  section per board name (:mod:`omsd.statefile`); ``--state FILE`` gives or overrides it. None
  configured: flash lasts as long as the daemon runs. It may not be the traffic log's file.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

from omsd.config_errors import ConfigError

# The defaults and default places are defined in omsd.defaults (the schema gives them to its keys,
# the objects below to their fields, the command line's help quotes them) and re-exported here.
from omsd.defaults import (
    BAUD_MAX,
    BAUD_MIN,
    BUFFER_SIZE_MAX,
    BUFFER_SIZE_MIN,
    CONTROL_SOCKET_NAME,
    DEFAULT_BAUD,
    DEFAULT_BOARD_NAME,
    DEFAULT_BUFFER_SIZE,
    DEFAULT_BYTESIZE,
    DEFAULT_EOS,
    DEFAULT_FLOW,
    DEFAULT_HOST,
    DEFAULT_KEEPALIVE,
    DEFAULT_LINGER,
    DEFAULT_LINK,
    DEFAULT_MODEL,
    DEFAULT_MQTT_PREFIX,
    DEFAULT_PARITY,
    DEFAULT_PTY_MODE,
    DEFAULT_SECOND_CLIENT,
    DEFAULT_STATE_RATE,
    DEFAULT_STOPBITS,
    DEFAULT_TCP_PORT,
    DEFAULT_VIEW,
    FLOWS,
    LINKS,
    MAX_LINGER,
    MAX_STATE_RATE,
    MQTT_PORT,
    MQTTS_PORT,
    SECOND_CLIENT_POLICIES,
    VIEWS,
    default_pty_link,
    runtime_directory,
)
from omsd.hostport import host_port

if TYPE_CHECKING:
    from omsd.board import AxisWorld
    from omsd.models.spec import Model

# -- the configuration --------------------------------------------------------------------------


@dataclass(frozen=True)
class TcpEndpoint:
    """A listening TCP socket. ``port`` 0 lets the OS choose a free port."""

    host: str = DEFAULT_HOST
    port: int = DEFAULT_TCP_PORT
    terminal: bool = False  # for a person at a terminal program (omsd.transport.terminal)

    def __str__(self) -> str:
        return host_port(self.host, self.port)


@dataclass(frozen=True)
class PtyEndpoint:
    """A pseudo-terminal reached through the stable symlink ``link``."""

    link: Path
    group: str | None = None  # group to chown the pty device to; None: leave it
    mode: int = DEFAULT_PTY_MODE  # permissions of the pty device
    terminal: bool = False  # for a person at a terminal program (omsd.transport.terminal)

    def __str__(self) -> str:
        return str(self.link)


@dataclass(frozen=True)
class SerialEndpoint:
    """A serial device (``/dev/ttyUSB0``), its line set as the application's port is set:
    ``baud``, ``bytesize`` data bits, ``parity`` (N, E, O, M, S), ``stopbits`` (1, 1.5, 2),
    ``flow`` control (none, rtscts, xonxoff); ``pacing``: the board's output no faster than the
    line carries it (omsd.transport.serial)."""

    path: Path
    baud: int = DEFAULT_BAUD
    bytesize: int = DEFAULT_BYTESIZE
    parity: str = DEFAULT_PARITY
    stopbits: float = DEFAULT_STOPBITS
    flow: str = DEFAULT_FLOW
    pacing: bool = False

    def __str__(self) -> str:
        """``PATH,BAUD,8N1`` (and ``,rtscts`` or ``,xonxoff``), the ``--serial`` option's
        syntax."""
        text = f"{self.path},{self.baud},{self.bytesize}{self.parity}{self.stopbits:g}"
        return text if self.flow == "none" else f"{text},{self.flow}"


@dataclass(frozen=True)
class Rfc2217Endpoint:
    """A listening TCP socket for RFC 2217 (telnet COM port control) clients; ``pacing``: the
    board's output no faster than the line the client set carries it (omsd.transport.rfc2217)."""

    host: str = DEFAULT_HOST
    port: int = 0
    pacing: bool = False

    def __str__(self) -> str:
        return host_port(self.host, self.port)


def _no_world() -> Mapping[str, AxisWorld]:
    return MappingProxyType({})


def _no_inputs() -> Mapping[int, bool]:
    return MappingProxyType({})


@dataclass(frozen=True)
class BoardConfig:
    """One emulated board and how it is served."""

    name: str
    model: str = DEFAULT_MODEL  # canonical name, a key of omsd.models.MODELS
    link: str = DEFAULT_LINK  # "driver" or "raw"
    eos: int = DEFAULT_EOS  # the driver's E:XX
    buffer_size: int = DEFAULT_BUFFER_SIZE  # the driver's B:XXXX
    tcp: tuple[TcpEndpoint, ...] = ()
    pty: tuple[PtyEndpoint, ...] = ()
    serial_port: tuple[SerialEndpoint, ...] = ()
    rfc2217: tuple[Rfc2217Endpoint, ...] = ()
    second_client: str = DEFAULT_SECOND_CLIENT  # a new TCP client replaces the connected one
    linger: float = DEFAULT_LINGER  # s a half-closed TCP client waits for its answers
    world: Mapping[str, AxisWorld] = field(default_factory=_no_world)  # axis letter -> world
    inputs: Mapping[int, bool] = field(default_factory=_no_inputs)  # input bit -> high?
    encoders: str | None = None  # axes fitted with encoders, if not the model's (VS4 option)
    serial: str | None = None  # serial number WY reports (VS4), if not the model's
    firmware: str | None = None  # firmware revision WY reports, if not the model's
    max_queries: bool | None = None  # PCIx: answer the MAX-family queries (default on)

    def personality(self) -> Model:
        """The model as fitted and labelled on this board."""
        from omsd.models import get_model, variant  # not at the top: omsd --help needs no model

        return variant(
            get_model(self.model), self.encoders, self.serial, self.firmware, self.max_queries
        )

    def __post_init__(self) -> None:
        # Frozen all the way down, whatever the caller passed.
        object.__setattr__(self, "tcp", tuple(self.tcp))
        object.__setattr__(self, "pty", tuple(self.pty))
        object.__setattr__(self, "serial_port", tuple(self.serial_port))
        object.__setattr__(self, "rfc2217", tuple(self.rfc2217))
        object.__setattr__(self, "world", MappingProxyType(dict(self.world)))
        object.__setattr__(self, "inputs", MappingProxyType(dict(self.inputs)))


@dataclass(frozen=True)
class LogConfig:
    """The traffic log (``[log]``, ``--log``, ``--view``): a JSON-lines file, and what standard
    error shows."""

    file: Path | None = None  # JSON-lines traffic log
    view: str = DEFAULT_VIEW  # "auto", "rich", "plain" or "off"
    group: str | None = None  # a new log file is 0640 in this group; None: 0600


@dataclass(frozen=True)
class DaemonConfig:
    """Everything one daemon serves: its boards, and what they share (the log, the state file,
    the control endpoint, the MQTT bridge, the web dashboard); ``source`` says where it was
    read from."""

    boards: tuple[BoardConfig, ...]
    log: LogConfig = field(default_factory=LogConfig)
    source: str = "built-in default"  # "built-in default", "command line", or the file path
    state: Path | None = None  # the boards' flash (omsd.statefile); None: kept in memory only
    control: ControlConfig = field(default_factory=lambda: ControlConfig())
    mqtt: MqttConfig | None = None  # the MQTT bridge (omsd.mqtt); None: off
    web: WebConfig | None = None  # the web dashboard (omsd.web); None: off
    state_group: str | None = None  # the state file is 0640 in this group; None: 0600


@dataclass(frozen=True)
class ControlConfig:
    """The control endpoint (omsd.control): a Unix socket, owner-only, at ``socket`` (``None``:
    none); ``explicit`` when the path was configured (then a path in use is a start-up error;
    the default path in use only costs a warning: another omsd of this user has it); ``tcp``
    only if configured (no network exposure by default)."""

    socket: Path | None = field(default_factory=lambda: default_pty_link(CONTROL_SOCKET_NAME))
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
    prefix: str = DEFAULT_MQTT_PREFIX
    keepalive: int = DEFAULT_KEEPALIVE
    state_rate: float = DEFAULT_STATE_RATE
    traffic: bool = True


@dataclass(frozen=True)
class WebConfig:
    """The web dashboard (:mod:`omsd.web`), on only with ``[web]`` or ``--web``: served at
    ``listen``; ``control`` lets the page do what ``omsd ctl`` does (read-only without it);
    ``token`` must be given by a browser (``?token=``) and is required for an address that is
    not loopback (checked where the configuration is read)."""

    listen: TcpEndpoint
    control: bool = False
    token: str | None = field(default=None, repr=False)

    @property
    def loopback(self) -> bool:
        return is_loopback(self.listen.host)


def is_loopback(host: str) -> bool:
    """Whether ``host`` is this machine only: ``localhost`` or a loopback address."""
    if host == "localhost":
        return True
    import ipaddress

    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a host name: it may be anything


# -- reading a configuration (the schema is imported here, when it is needed) -------------------


def load_config(path: str | os.PathLike[str]) -> DaemonConfig:
    """Read and validate a TOML configuration file."""
    from omsd.config import reading

    return reading.load(path)


def from_options(
    board: str | None,
    tcp: list[str],
    pty: list[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool = False,
    serial: list[str] | None = None,
    rfc2217: list[str] | None = None,
) -> DaemonConfig:
    """The single-board form of the command line: ``--board MODEL --tcp [HOST:]PORT ...
    --pty PATH ... --serial PATH[,BAUD[,8N1]] ... --rfc2217 [HOST:]PORT ... --link driver|raw
    --eos HEX --log FILE``, validated by the schema as the one board of a file would be (paths
    relative to the working directory). Without --tcp, --pty, --serial and --rfc2217, the
    default endpoints; with any of them, only what is given. ``--terminal`` puts the ptys in
    terminal mode (TCP stays exact: terminal TCP endpoints are for a configuration file)."""
    return _single_board(
        board, tcp, pty, link, eos, log, terminal, "command line", serial or [], rfc2217 or []
    )


def default_config() -> DaemonConfig:
    """``omsd`` with no arguments: one PC48-4E on TCP 127.0.0.1:7048 and on a pty."""
    return _single_board(None, [], [], None, None, None, False, "built-in default")


def _single_board(
    board: str | None,
    tcp: list[str],
    pty: list[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool,
    source: str,
    serial: list[str] | None = None,
    rfc2217: list[str] | None = None,
) -> DaemonConfig:
    # the fast path (omsd.config.fastpath): options that are plainly valid without importing
    # pydantic (never a serial or RFC 2217 endpoint); anything else, and every error, from the
    # schema
    from omsd.config import fastpath

    serial, rfc2217 = serial or [], rfc2217 or []
    if not serial and not rfc2217:
        config = fastpath.single_board(board, tcp, pty, link, eos, log, terminal, source)
        if config is not None:
            return config
    from omsd.config import reading

    return reading.single_board(
        board, tcp, pty, link, eos, log, terminal, source, serial=serial, rfc2217=rfc2217
    )


def _option_path(option: str, text: str) -> Path:
    """``--state``/``--control``'s path: the fast path's (omsd.config.fastpath), else the
    schema's, which words the error."""
    from omsd.config import fastpath

    path = fastpath.option_path(text)
    if path is not None:
        return path
    from omsd.config import reading

    return reading.option_path(option, text)


def check_option_path(option: str, text: str) -> None:
    """``--config``/``--log``'s text is a path: an empty or blank one (``--config "$FILE"``
    with FILE unset) is the one-line error, not taken for the option left out."""
    _option_path(option, text)


def with_control_option(config: DaemonConfig, control: str | None) -> DaemonConfig:
    """``--control PATH`` (the control socket) or ``--control off``."""
    if control is None:
        return config
    if control == "off":
        return replace(config, control=replace(config.control, socket=None, explicit=True))
    path = _option_path("--control", control)
    return replace(config, control=replace(config.control, socket=path, explicit=True))


def with_web_option(config: DaemonConfig, web: str | None, control: bool) -> DaemonConfig:
    """``--web [HOST:]PORT`` (the dashboard, replacing ``[web] listen``) and ``--web-control``
    (its buttons). A token comes from a file's ``[web] token`` only (never a command line that
    ``ps`` shows), so ``--web`` beyond loopback needs that file."""
    if web is None and not control:
        return config
    from omsd.config.syntax import TCP_SYNTAX, AddressProblem, tcp_address

    current = config.web
    if web is None:
        if current is None:
            raise ConfigError("--web-control", None, "needs --web [HOST:]PORT or a [web] table")
        listen = current.listen
    else:
        try:
            listen = tcp_address(web)  # the text: a number is checked as --tcp's is
        except AddressProblem as exc:
            raise ConfigError("--web", None, f"expected {exc}, got {web!r}") from None
        except ValueError:
            raise ConfigError("--web", None, f"expected {TCP_SYNTAX}, got {web!r}") from None
    token = None if current is None else current.token
    if token is None and not is_loopback(listen.host):
        raise ConfigError(
            "--web",
            None,
            f"{listen} is not loopback: the dashboard needs a token there ([web] token in a"
            " configuration file)",
        )
    allowed = control or (current is not None and current.control)
    return replace(config, web=WebConfig(listen, allowed, token))


def with_state_option(config: DaemonConfig, state: str | None) -> DaemonConfig:
    """``--state FILE`` on either form of the command line: the state file (relative to the
    working directory), in place of a file's ``[state] file``. ``None``: the configuration as
    it is."""
    if state is None:
        return config
    path = _option_path("--state", state)
    if path == config.log.file:
        from omsd.config import reading

        raise reading.not_the_log("--state", path)
    return replace(config, state=path)


__all__ = [
    "BAUD_MAX",
    "BAUD_MIN",
    "BUFFER_SIZE_MAX",
    "BUFFER_SIZE_MIN",
    "CONTROL_SOCKET_NAME",
    "DEFAULT_BAUD",
    "DEFAULT_BOARD_NAME",
    "DEFAULT_BUFFER_SIZE",
    "DEFAULT_BYTESIZE",
    "DEFAULT_EOS",
    "DEFAULT_FLOW",
    "DEFAULT_HOST",
    "DEFAULT_KEEPALIVE",
    "DEFAULT_LINGER",
    "DEFAULT_LINK",
    "DEFAULT_MODEL",
    "DEFAULT_MQTT_PREFIX",
    "DEFAULT_PARITY",
    "DEFAULT_PTY_MODE",
    "DEFAULT_SECOND_CLIENT",
    "DEFAULT_STATE_RATE",
    "DEFAULT_STOPBITS",
    "DEFAULT_TCP_PORT",
    "DEFAULT_VIEW",
    "FLOWS",
    "LINKS",
    "MAX_LINGER",
    "MAX_STATE_RATE",
    "MQTTS_PORT",
    "MQTT_PORT",
    "SECOND_CLIENT_POLICIES",
    "VIEWS",
    "BoardConfig",
    "ConfigError",
    "ControlConfig",
    "DaemonConfig",
    "LogConfig",
    "MqttConfig",
    "PtyEndpoint",
    "Rfc2217Endpoint",
    "SerialEndpoint",
    "TcpEndpoint",
    "WebConfig",
    "check_option_path",
    "default_config",
    "default_pty_link",
    "from_options",
    "is_loopback",
    "load_config",
    "runtime_directory",
    "with_control_option",
    "with_state_option",
    "with_web_option",
]
