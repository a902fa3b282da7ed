"""The configuration's schema: every key of omsd's TOML file, described once (pydantic v2).

Each key is a field of a table model below, with its type, its default (the constants of
:mod:`omsd.config`, which the runtime objects share; an axis's are ``omsd.board.AxisWorld``'s),
what it means (``description``) and what an error about it says (:class:`~omsd.config.wording.
Says`, :mod:`omsd.config.wording`). Derived from these models:

* validation: :func:`validate`, which :mod:`omsd.config.reading` runs on a file and on the
  command line's one-board form (a document with one ``[[board]]`` whose keys the options fill,
  :func:`option_paths`), each error one line naming the file, the line and the key path;
* the runtime objects of :mod:`omsd.config` (:meth:`Document.config`), the defaults filled in;
* the JSON Schema ``omsd config schema`` prints and ``config/omsd.schema.json`` holds, the
  README's reference table and ``omsd config show`` (:mod:`omsd.config.render`).

Imported only where a configuration is read (pydantic takes ~0.1 s to import).
"""

import re
from dataclasses import replace as replace_dataclass
from pathlib import Path
from typing import Annotated, Any, Literal, Self

from pydantic import ConfigDict, Discriminator, Field, Tag, model_validator
from pydantic_core import PydanticCustomError

from omsd.board import AxisWorld, SwitchType
from omsd.config import (
    BUFFER_SIZE_MAX,
    BUFFER_SIZE_MIN,
    CONTROL_SOCKET_NAME,
    DEFAULT_BAUD,
    DEFAULT_BUFFER_SIZE,
    DEFAULT_BYTESIZE,
    DEFAULT_EOS,
    DEFAULT_FLOW,
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
    DEFAULT_VIEW,
    FLOWS,
    LINKS,
    MAX_LINGER,
    MAX_STATE_RATE,
    MQTT_PORT,
    MQTTS_PORT,
    SECOND_CLIENT_POLICIES,
    VIEWS,
    BoardConfig,
    ControlConfig,
    DaemonConfig,
    LogConfig,
    MqttConfig,
    PtyEndpoint,
    Rfc2217Endpoint,
    SerialEndpoint,
    TcpEndpoint,
    WebConfig,
    default_pty_link,
    is_loopback,
)
from omsd.config.syntax import tcp_address
from omsd.config.values import (
    FIRMWARE_PATTERN,
    NAME_PATTERN,
    SERIAL_PATTERN,
    TCP_SYNTAX,
    TOPIC_PATTERN,
    Baud,
    BoardModel,
    CaFile,
    DataBits,
    FileGroup,
    FilePath,
    Flag,
    Parity,
    SerialText,
    Steps,
    StopBits,
    TcpAddress,
    Text,
    broker_host,
    hex_pattern,
    hex_value,
    mqtt_client_id,
    octal,
    tcp_conflict,
)
from omsd.config.wording import (
    Default,
    Option,
    Required,
    Says,
    Table,
    choice,
    choices_json,
    integer,
    problem,
)
from omsd.config_errors import KeyPath, show
from omsd.defaults import DEFAULT_WEB, MIN_WEB_TOKEN
from omsd.models import MODELS, get_model, variant
from omsd.models.spec import Model

_AXIS = AxisWorld()  # the simulated stage's defaults
LimitWiring = type(_AXIS.limit_switches)


def _one_or_list(value: Any) -> str:
    return "<list>" if isinstance(value, list) else "<one>"


def _tcp_kind(value: Any) -> str:
    return "<table>" if isinstance(value, dict) else "<address>"


def _pty_kind(value: Any) -> str | None:
    if isinstance(value, dict):
        return "<table>"
    if isinstance(value, bool):
        return "<true>"
    if isinstance(value, str):
        return "<path>"
    return None  # pydantic: union_tag_not_found, worded by PtyEntry


def _socket_kind(value: Any) -> str:
    return "<off>" if isinstance(value, bool) else "<path>"


def _tls_kind(value: Any) -> str | None:
    if isinstance(value, bool):
        return "<flag>"
    return "<file>" if isinstance(value, str) else None


# -- the tables ---------------------------------------------------------------------------------


class TcpTable(Table):
    """A TCP endpoint as a table: `{ address = "127.0.0.1:7002", terminal = true }`."""

    address: Annotated[
        TcpAddress, Required(f"a table with an address ({TCP_SYNTAX})", at_table=True)
    ] = Field(description="[HOST:]PORT or PORT, as `tcp` takes it.")
    terminal: Flag = Field(
        False,
        description="For people at picocom, minicom or screen: what is typed is echoed and sent"
        " a line at a time, every line ends in CR LF (false: programs see the card's exact bytes).",
    )

    def endpoint(self) -> TcpEndpoint:
        return replace_dataclass(self.address, terminal=self.terminal)


class PtyTable(Table):
    """A pty endpoint as a table: `{ link = PATH, group = GROUP, mode = 0o660, terminal =
    false }`."""

    link: FilePath | None = Field(
        None,
        description="The symlink omsd creates to the pty device and removes at exit.",
    )
    group: Text | None = Field(
        None,
        description="The group the pty device is given to (omsd's user must be in it).",
    )
    mode: Annotated[
        int,
        Says(
            'permissions 0o000..0o777 (write 0o660 or "0660")',
            accepts=Annotated[int, Field(ge=0, le=0o777)]
            | Annotated[str, Field(pattern=r"^\s*(0[oO])?[0-7]{1,4}\s*$")],
            convert=octal,
        ),
        Default('0o660 (or "0660")'),
    ] = Field(DEFAULT_PTY_MODE, description="The pty device's permissions.")
    terminal: Flag = Field(False, description=TcpTable.model_fields["terminal"].description)


PACING = (
    "The board's output no faster than the line carries it: each character one character time"
    " (start, data, parity and stop bits at the baud rate) after the one before."
)


class SerialTable(Table):
    """A serial endpoint as a table: `{ path = "/dev/ttyUSB0", baud = 9600, bytesize = 8,
    parity = "N", stopbits = 1, flow = "none", pacing = false }`."""

    path: Annotated[
        FilePath, Required("a table with a path (the serial device)", at_table=True)
    ] = Field(description="The serial device: /dev/ttyUSB0, /dev/ttyS0, a /dev/serial/by-id link.")
    baud: Baud = Field(DEFAULT_BAUD, description="The line's baud rate.")
    bytesize: DataBits = Field(DEFAULT_BYTESIZE, description="Data bits.")
    parity: Parity = Field(DEFAULT_PARITY, description="Parity: none, even, odd, mark or space.")
    stopbits: StopBits = Field(DEFAULT_STOPBITS, description="Stop bits.")
    flow: Annotated[str, choice(FLOWS)] = Field(
        DEFAULT_FLOW,
        description="Flow control: none, rtscts (hardware) or xonxoff (software), as the"
        " application's port is set.",
    )
    pacing: Flag = Field(
        False,
        description=PACING + " A real UART paces by itself; this is for devices that do not.",
    )

    def endpoint(self) -> SerialEndpoint:
        return SerialEndpoint(
            self.path,
            self.baud,
            self.bytesize,
            self.parity,
            self.stopbits,
            self.flow,
            self.pacing,
        )


class Rfc2217Table(Table):
    """An RFC 2217 endpoint as a table: `{ address = "127.0.0.1:7148", pacing = true }`."""

    address: Annotated[
        TcpAddress, Required(f"a table with an address ({TCP_SYNTAX})", at_table=True)
    ] = Field(description="[HOST:]PORT or PORT, as `tcp` takes it.")
    pacing: Flag = Field(
        False, description=PACING + " The line is the one the client set (9600 8N1 until then)."
    )

    def endpoint(self) -> Rfc2217Endpoint:
        return Rfc2217Endpoint(self.address.host, self.address.port, self.pacing)


TcpEntry = Annotated[
    Annotated[TcpAddress, Tag("<address>")] | Annotated[TcpTable, Tag("<table>")],
    Discriminator(_tcp_kind),
    Says(TCP_SYNTAX, holds_tables=True),
]
PTY_WORDS = "a path, true (the default link) or a table {link, group, mode, terminal}"
PtyEntry = Annotated[
    Annotated[PtyTable, Tag("<table>")]
    | Annotated[Literal[True], Tag("<true>")]
    | Annotated[FilePath, Tag("<path>")],
    Discriminator(_pty_kind),
    Says(PTY_WORDS, holds_tables=True),
]


SERIAL_WORDS = (
    "a device path with its line (PATH[,BAUD[,8N1]]), a table {path, baud, bytesize, parity,"
    " stopbits, flow, pacing}, or a list of them"
)
SerialEntry = Annotated[
    Annotated[SerialText, Tag("<address>")] | Annotated[SerialTable, Tag("<table>")],
    Discriminator(_tcp_kind),
    Says(SERIAL_WORDS, holds_tables=True),
]
Rfc2217Entry = Annotated[
    Annotated[TcpAddress, Tag("<address>")] | Annotated[Rfc2217Table, Tag("<table>")],
    Discriminator(_tcp_kind),
    Says(TCP_SYNTAX, holds_tables=True),
]


class AxisTable(Table):
    """The simulated stage of one axis (omsd.board.AxisWorld), in motor steps from where the
    carriage was at power-up. X is any axis letter of the model; axes not listed keep the
    defaults."""

    start_position: Steps = Field(_AXIS.start_position, description="Where the carriage starts.")
    negative_limit: Steps = Field(
        _AXIS.negative_limit,
        description="The negative limit switch: active at or beyond this position.",
    )
    positive_limit: Steps = Field(
        _AXIS.positive_limit,
        description="The positive limit switch: active at or beyond this position.",
    )
    home_low: Steps = Field(
        _AXIS.home_low,
        description="The home switch is active while home_low <= position < home_high.",
    )
    home_high: Steps = Field(_AXIS.home_high, description="See home_low.")
    home_switch: Annotated[str, choice([s.value for s in SwitchType])] = Field(
        _AXIS.home_switch.value,
        description="normally_open grounds the line when active, what the power-up HL expects;"
        " normally_closed is for HH.",
    )
    limit_switches: Annotated[str, choice([w.value for w in LimitWiring])] = Field(
        _AXIS.limit_switches.value,
        description="How the limit switches drive their lines: matched (read as the board's"
        " limit level expects, whatever LH/LL say), normally_open (grounded when hit: what LL"
        " expects) or normally_closed (grounded until hit: what LH expects).",
    )
    encoder_counts_per_rev: Annotated[int, integer(1)] = Field(
        _AXIS.encoder_counts_per_rev,
        description="Encoder counts per revolution (axes with an encoder only).",
    )
    encoder_index: Annotated[int, integer(0), Default("the home window's middle")] | None = Field(
        None,
        description="The count, modulo a revolution, where the index pulse is (axes with an"
        " encoder only). Left out: the middle of the home window, modulo a revolution, so that"
        " an encoder home (HE) finds home.",
    )

    @model_validator(mode="after")
    def _windows(self) -> Self:
        """Limits and the home window that are not empty, an index inside a revolution."""
        given = self.model_fields_set
        if self.negative_limit >= self.positive_limit:
            key = "positive_limit" if "positive_limit" in given else "negative_limit"
            raise problem(
                detail=f"expected negative_limit below positive_limit, got"
                f" {self.negative_limit:g} and {self.positive_limit:g}",
                at=(key,),
            )
        if self.home_low >= self.home_high:
            key = "home_high" if "home_high" in given else "home_low"
            raise problem(
                detail=f"expected home_low below home_high, got {self.home_low:g} and"
                f" {self.home_high:g}",
                at=(key,),
            )
        if self.encoder_index is not None and self.encoder_index >= self.encoder_counts_per_rev:
            raise problem(
                expected=f"an integer 0..{self.encoder_counts_per_rev - 1} (below"
                " encoder_counts_per_rev)",
                at=("encoder_index",),
            )
        return self

    def world(self) -> AxisWorld:
        return AxisWorld(
            start_position=self.start_position,
            negative_limit=self.negative_limit,
            positive_limit=self.positive_limit,
            home_low=self.home_low,
            home_high=self.home_high,
            home_switch=SwitchType(self.home_switch),
            limit_switches=LimitWiring(self.limit_switches),
            encoder_counts_per_rev=self.encoder_counts_per_rev,
            encoder_index=self.encoder_index,
        )


ENCODER_KEYS = ("encoder_counts_per_rev", "encoder_index")
RAW_FRAMING = "is a driver link setting; a raw link keeps the board's own LF/CR framing"


class BoardTable(Table):
    """One emulated board, its endpoints, its link and its simulated world."""

    model_config = ConfigDict(json_schema_extra=lambda schema: _board_rules(schema))

    name: (
        Annotated[
            str,
            Says(
                "a name of letters, digits, '_', '.' and '-'",
                accepts=Annotated[str, Field(pattern=NAME_PATTERN)],
            ),
            Default("board1, board2, ... in file order"),
        ]
        | None
    ) = Field(
        None,
        description="Used in logs, in the default pty link, by omsd ctl --board and in MQTT"
        " topics.",
    )
    model: Annotated[BoardModel, Option("--board")] = Field(
        DEFAULT_MODEL, description="The personality, as `omsd models` lists them."
    )
    link: Annotated[str, choice(LINKS), Option("--link")] = Field(
        DEFAULT_LINK,
        description="driver: the DOS device driver's conventions (PC48 manual §7.3: replies end"
        " with eos; # @ $ ! markers for command error, limit, slip and done); raw: the board's"
        " own stream, replies framed <LF><CR>...<LF><CR>.",
    )
    eos: Annotated[
        int,
        Says(
            'a character code 00..FF in hex like the driver\'s E:XX ("0D")',
            accepts=Annotated[int, Field(ge=0, le=0xFF)]
            | Annotated[str, Field(pattern=hex_pattern(2))],
            convert=hex_value(0, 0xFF),
        ),
        Default(f'"{DEFAULT_EOS:02X}" (LF)'),
        Option("--eos"),
    ] = Field(
        DEFAULT_EOS,
        description="The driver's E:XX, the character that ends each reply: a string is"
        ' hexadecimal ("0D" is CR), an integer the code itself (13). Driver link only.',
    )
    buffer_size: Annotated[
        int,
        Says(
            'a buffer size 16..32767 (hex "0010".."7FFF" like the driver\'s B:XXXX)',
            accepts=Annotated[int, Field(ge=BUFFER_SIZE_MIN, le=BUFFER_SIZE_MAX)]
            | Annotated[str, Field(pattern=hex_pattern(4))],
            convert=hex_value(BUFFER_SIZE_MIN, BUFFER_SIZE_MAX),
        ),
    ] = Field(
        DEFAULT_BUFFER_SIZE,
        alias="buffer",
        description='The driver\'s B:XXXX, the "output to board" buffer: how many characters a'
        ' host can send at one time; an integer, or hexadecimal like the driver\'s ("0100").'
        " Driver link only.",
    )
    tcp: Annotated[
        Annotated[TcpEntry, Tag("<one>")] | Annotated[list[TcpEntry], Tag("<list>")],
        Discriminator(_one_or_list),
        Says(
            '"[HOST:]PORT" (no HOST: 127.0.0.1), PORT, a table {address, terminal}, or a list'
            " of them",
            holds_tables=True,
        ),
        Default("none"),
        Option("--tcp"),
    ] = Field(
        [],
        description="TCP listening sockets. 0.0.0.0:PORT for every IPv4 interface, IPv6 in"
        " brackets ([::1]:7001), port 0 lets the system choose.",
    )
    pty: Annotated[
        Annotated[PtyEntry, Tag("<one>")] | Annotated[list[PtyEntry], Tag("<list>")],
        Discriminator(_one_or_list),
        Says(
            "a path, true (the default link), a table {link, group, mode, terminal}, or a list"
            " of them",
            holds_tables=True,
        ),
        Default("none"),
        Option("--pty"),
    ] = Field(
        [],
        description="Pseudo-terminals, each reached through a symlink omsd creates and removes;"
        " the default link is $XDG_RUNTIME_DIR/omsd/NAME (or /tmp/omsd-UID/NAME).",
    )
    serial_port: Annotated[
        Annotated[SerialEntry, Tag("<one>")] | Annotated[list[SerialEntry], Tag("<list>")],
        Discriminator(_one_or_list),
        Says(SERIAL_WORDS, holds_tables=True),
        Default("none"),
        Option("--serial"),
    ] = Field(
        [],
        description="Serial devices (a USB adapter, /dev/ttyS0) the board is served on, each"
        " set as the legacy application's port is: 9600 baud 8N1, no flow control unless"
        " given. A device that goes away is opened again when it comes back.",
    )
    rfc2217: Annotated[
        Annotated[Rfc2217Entry, Tag("<one>")] | Annotated[list[Rfc2217Entry], Tag("<list>")],
        Discriminator(_one_or_list),
        Says(
            '"[HOST:]PORT" (no HOST: 127.0.0.1), PORT, a table {address, pacing}, or a list of'
            " them",
            holds_tables=True,
        ),
        Default("none"),
        Option("--rfc2217"),
    ] = Field(
        [],
        description="RFC 2217 (telnet COM port control) listening sockets: pyserial's"
        " rfc2217:// and other clients set the line, DTR, RTS and breaks (logged).",
    )
    second_client: Annotated[str, choice(SECOND_CLIENT_POLICIES)] = Field(
        DEFAULT_SECOND_CLIENT,
        description="A second TCP client: takeover (it replaces the connected one) or refuse"
        " (it is closed at once). The board's state survives either way.",
    )
    linger: Annotated[
        float,
        Says(
            f"a number of seconds 0..{MAX_LINGER:g}",
            accepts=Annotated[float, Field(ge=0, le=MAX_LINGER, allow_inf_nan=False)],
        ),
    ] = Field(
        DEFAULT_LINGER,
        description="Seconds a TCP client that shut down its sending side (nc -N) is kept for"
        " the answers its commands are yet to produce; 0 closes it at once.",
    )
    inputs: Annotated[
        dict[str, Annotated[bool, Says("true (high) or false (low)")]],
        Says("a table", holds_tables=True),
        Default("none driven"),
    ] = Field(
        {},
        description="Levels driven onto the general-purpose input lines, by bit number:"
        " { 0 = false }. Undriven lines are pulled up (high).",
    )
    axes: Annotated[dict[str, AxisTable], Says("a table", holds_tables=True), Default("none")] = (
        Field({}, description="The simulated stage of each axis, by letter: [board.axes.X].")
    )
    encoders: (
        Annotated[
            bool | str,
            Says(
                "true, false or axis letters of the model",
                accepts=bool | str,
            ),
            Default("the model's"),
        ]
        | None
    ) = Field(
        None,
        description="The axes fitted with encoders: true (the model's), false (none: a VS4"
        ' ordered without them) or their letters ("XY").',
    )
    serial: (
        Annotated[
            str,
            Says(
                f"a serial number like {SERIAL_PATTERN!r}",
                accepts=Annotated[str, Field(pattern=f"^{SERIAL_PATTERN}$")],
            ),
            Default("the model's"),
        ]
        | None
    ) = Field(None, description="The serial number WY reports (VS4).")
    firmware: (
        Annotated[
            str,
            Says(
                f"a version like {FIRMWARE_PATTERN!r}",
                accepts=Annotated[str, Field(pattern=f"^{FIRMWARE_PATTERN}$")],
            ),
            Default("the model's"),
        ]
        | None
    ) = Field(None, description="The firmware revision WY reports.")
    max_queries: Annotated[Flag, Default("true")] | None = Field(
        None,
        description="PCIx only: answer the MAX-family queries EPICS omsMAXnet sends (an"
        " extension beyond the PCIx manual); false makes them command errors.",
    )

    @model_validator(mode="after")
    def _fits(self) -> Self:
        """The rules that need several keys: the driver settings on a driver link, at least one
        endpoint, and what the model has (its axes, encoders, input bits, dialect)."""
        given = self.model_fields_set
        if self.link == "raw":
            for key, name in (("eos", "eos"), ("buffer", "buffer_size")):
                if name in given:
                    raise problem(detail=RAW_FRAMING, at=(key,))
        if not (
            self.tcp_endpoints()
            or self.pty_entries()
            or self.serial_endpoints()
            or self.rfc2217_endpoints()
        ):
            raise problem(
                detail="expected at least one endpoint (tcp, pty, serial_port or rfc2217), got none"
            )
        self.personality()
        return self

    def personality(self) -> Model:
        """The model as fitted and labelled, once its keys are checked against it."""
        model = get_model(self.model)
        encoders = self.encoder_axes(model)
        if self.max_queries is not None and model.dialect != "pcix":
            raise problem(
                detail=f"is a PCIx setting; a {model.name} speaks no MAX-family dialect",
                at=("max_queries",),
            )
        model = variant(model, encoders, self.serial, self.firmware, self.max_queries)
        seen: set[str] = set()
        for key, axis in self.axes.items():
            letter = key.upper()
            if len(letter) != 1 or letter not in model.axes:
                raise problem(
                    detail=f"{model.name} has axes {', '.join(model.axes)}", at=("axes", key)
                )
            if letter in seen:
                raise problem(detail=f"axis {letter} is given twice", at=("axes", key))
            seen.add(letter)
            for name in ENCODER_KEYS:
                if name in axis.model_fields_set and not model.has_encoder(letter):
                    where = (
                        f"encoders on {', '.join(model.encoder_axes)}"
                        if model.encoder_axes
                        else "no encoder option"
                    )
                    raise problem(
                        detail=f"{model.name} has no encoder on axis {letter} ({where})",
                        at=("axes", key, name),
                    )
        bits: set[int] = set()
        words = f"a general-purpose I/O bit 0..{model.io_bits - 1} of the {model.name}"
        for key in self.inputs:
            if not re.fullmatch(r"[0-9]{1,3}", key) or int(key) >= model.io_bits:
                raise problem(expected=words, at=("inputs", key), got=show(key))
            if int(key) in bits:
                raise problem(detail=f"input bit {int(key)} is given twice", at=("inputs", key))
            bits.add(int(key))
        return model

    def encoder_axes(self, model: Model) -> str | None:
        """``encoders`` as :func:`omsd.models.variant` takes it: ``None`` the model's, ``""``
        none, or the letters in the model's order."""
        if self.encoders is None or self.encoders is True:
            return None
        if self.encoders is False:
            return ""
        letters = self.encoders.upper()
        if not letters or not set(letters) <= set(model.axes):
            raise problem(
                expected=f"true, false or axis letters of {''.join(model.axes)}", at=("encoders",)
            )
        return "".join(a for a in model.axes if a in letters)

    def tcp_endpoints(self) -> list[tuple[TcpEndpoint, KeyPath]]:
        """Each TCP endpoint with its key path in the board (``("tcp", 1)`` in a list)."""
        entries = self.tcp if isinstance(self.tcp, list) else [self.tcp]
        found = []
        for i, entry in enumerate(entries):
            at: KeyPath = ("tcp", i) if isinstance(self.tcp, list) else ("tcp",)
            found.append((entry.endpoint() if isinstance(entry, TcpTable) else entry, at))
        return found

    def pty_entries(self) -> list[tuple[PtyTable | Literal[True] | Path, KeyPath]]:
        entries = self.pty if isinstance(self.pty, list) else [self.pty]
        return [
            (entry, ("pty", i) if isinstance(self.pty, list) else ("pty",))
            for i, entry in enumerate(entries)
        ]

    def pty_endpoints(self, name: str) -> list[tuple[PtyEndpoint, KeyPath]]:
        """Each pty endpoint, ``true`` and a table without ``link`` at the default link."""
        found = []
        for entry, at in self.pty_entries():
            if isinstance(entry, PtyTable):
                link = entry.link if entry.link is not None else default_pty_link(name)
                endpoint = PtyEndpoint(link, entry.group, entry.mode, entry.terminal)
            elif isinstance(entry, Path):
                endpoint = PtyEndpoint(entry)
            else:
                endpoint = PtyEndpoint(default_pty_link(name))
            found.append((endpoint, at))
        return found

    def serial_endpoints(self) -> list[tuple[SerialEndpoint, KeyPath]]:
        """Each serial endpoint with its key path in the board."""
        entries = self.serial_port if isinstance(self.serial_port, list) else [self.serial_port]
        return [
            (
                entry.endpoint() if isinstance(entry, SerialTable) else entry,
                ("serial_port", i) if isinstance(self.serial_port, list) else ("serial_port",),
            )
            for i, entry in enumerate(entries)
        ]

    def rfc2217_endpoints(self) -> list[tuple[Rfc2217Endpoint, KeyPath]]:
        """Each RFC 2217 endpoint with its key path in the board."""
        entries = self.rfc2217 if isinstance(self.rfc2217, list) else [self.rfc2217]
        found = []
        for i, entry in enumerate(entries):
            at: KeyPath = ("rfc2217", i) if isinstance(self.rfc2217, list) else ("rfc2217",)
            if isinstance(entry, Rfc2217Table):
                found.append((entry.endpoint(), at))
            else:
                found.append((Rfc2217Endpoint(entry.host, entry.port), at))
        return found

    def config(self, name: str) -> BoardConfig:
        model = self.personality()
        return BoardConfig(
            name=name,
            model=model.name,
            link=self.link,
            eos=self.eos,
            buffer_size=self.buffer_size,
            tcp=tuple(t for t, _ in self.tcp_endpoints()),
            pty=tuple(p for p, _ in self.pty_endpoints(name)),
            serial_port=tuple(p for p, _ in self.serial_endpoints()),
            rfc2217=tuple(r for r, _ in self.rfc2217_endpoints()),
            second_client=self.second_client,
            linger=self.linger,
            world={key.upper(): axis.world() for key, axis in self.axes.items()},
            inputs={int(bit): level for bit, level in self.inputs.items()},
            encoders=self.encoder_axes(get_model(self.model)),
            serial=self.serial,
            firmware=self.firmware,
            max_queries=self.max_queries,
        )


def _board_rules(schema: dict[str, Any]) -> None:
    """What a board's JSON Schema can say beyond its keys' types: at least one endpoint, no
    driver settings on a raw link, max_queries on a PCIx only."""
    pcix = [name for name, model in MODELS.items() if model.dialect == "pcix"]
    nonempty = {"not": {"type": "array", "maxItems": 0}}
    schema["allOf"] = [
        {
            "anyOf": [
                {"required": [key], "properties": {key: nonempty}}
                for key in ("tcp", "pty", "serial_port", "rfc2217")
            ],
        },
        {
            "if": {"required": ["link"], "properties": {"link": {"pattern": "^[Rr][Aa][Ww]$"}}},
            "then": {"not": {"anyOf": [{"required": ["eos"]}, {"required": ["buffer"]}]}},
        },
        {
            "if": {
                "not": {"required": ["model"], "properties": {"model": choices_json(pcix, True)}}
            },
            "then": {"not": {"required": ["max_queries"]}},
        },
    ]


class LogTable(Table):
    """The traffic log: every byte in and out, with time, board, endpoint and direction."""

    file: Annotated[FilePath | None, Option("--log")] = Field(
        None,
        description="A JSON-lines file the traffic and events are appended to (its directory"
        " must exist). SIGHUP reopens it.",
    )
    view: Annotated[str, choice(VIEWS)] = Field(
        DEFAULT_VIEW,
        description="The live view on standard error: auto (rich on a terminal, plain under"
        " systemd or a pipe), rich, plain or off.",
    )
    group: FileGroup | None = Field(
        None,
        description="A new log file is 0640 in this group (omsd's user must be in it);"
        " without one, 0600.",
    )


class StateTable(Table):
    """The boards' flash memory (a PCIx's AP defaults and permanent macros), one
    JSON file for the whole daemon with a section per board; without it, flash lasts as long
    as the daemon."""

    file: FilePath | None = Field(
        None, description="The state file (`omsd --state FILE` gives or overrides it)."
    )
    group: FileGroup | None = Field(
        None, description="The file is 0640 in this group; without one, 0600."
    )


class ControlTable(Table):
    """The control API (`omsd ctl`, the pytest plugin), a Unix socket for
    omsd's user only."""

    socket: (
        Annotated[
            Annotated[Literal[False], Tag("<off>")] | Annotated[FilePath, Tag("<path>")],
            Discriminator(_socket_kind),
            Says("a path, or false (no control socket)", holds_tables=True),
            Default(f"{CONTROL_SOCKET_NAME} in the runtime directory"),
        ]
        | None
    ) = Field(
        None,
        description="The socket's path; false: no control endpoint. A path in use is a"
        " start-up error.",
    )
    tcp: Annotated[TcpAddress, Default("none")] | None = Field(
        None, description="Also serve the control API on TCP (never on the network by default)."
    )
    group: FileGroup | None = Field(
        None, description="The socket is 0660 in this group, for its members' omsd ctl."
    )

    def config(self) -> ControlConfig:
        config = ControlConfig(tcp=self.tcp, group=self.group)
        if self.socket is not None:
            socket = None if self.socket is False else self.socket
            config = replace_dataclass(config, socket=socket, explicit=True)
        return config


class MqttTable(Table):
    """The MQTT bridge: each board's state, events and traffic published to a
    broker and control operations taken from it. Off without this table."""

    host: Annotated[
        str,
        Required("the broker's host name or address"),
        Says("a host name or address", convert=broker_host),
    ] = Field(description="The broker (required: a broker is never guessed).")
    port: (
        Annotated[int, integer(1, 65535), Default(f"{MQTT_PORT}, {MQTTS_PORT} with tls")] | None
    ) = Field(None, description="The broker's port.")
    username: Text | None = Field(None, description="The user to connect as.")
    password: (
        Annotated[str, Says("a string (the value given is not shown)", secret=True)] | None
    ) = Field(None, description="The user's password (never shown in a message).")
    tls: Annotated[
        Annotated[Flag, Tag("<flag>")] | Annotated[CaFile, Tag("<file>")],
        Discriminator(_tls_kind),
        Says("true, false or a CA certificate file", holds_tables=True),
    ] = Field(
        False,
        description="false: plain TCP; true: TLS with the system's CA certificates; a path: TLS"
        " verified with that CA file.",
    )
    client_id: Annotated[Text, Says("an MQTT client identifier", convert=mqtt_client_id)] | None = (
        Field(
            None, description="The MQTT client identifier; without one, the library makes one up."
        )
    )
    prefix: Annotated[
        str,
        Says(
            "topic levels joined by '/', without '+', '#', empty levels or a leading '$'",
            accepts=Annotated[str, Field(pattern=TOPIC_PATTERN)],
        ),
    ] = Field(
        DEFAULT_MQTT_PREFIX,
        description="The topics' first level(s): <prefix>/status, <prefix>/<board>/...",
    )
    keepalive: Annotated[int, integer(1, 65535)] = Field(
        DEFAULT_KEEPALIVE, description="Seconds between pings to the broker."
    )
    state_rate: Annotated[
        float,
        Says(
            f"publications per second, above 0 and at most {MAX_STATE_RATE:g}",
            accepts=Annotated[float, Field(gt=0, le=MAX_STATE_RATE, allow_inf_nan=False)],
        ),
    ] = Field(
        DEFAULT_STATE_RATE,
        description="Retained state publications per second per board, at most, while its axes"
        " move.",
    )
    traffic: Flag = Field(True, description="Publish the traffic as it flows.")

    @model_validator(mode="after")
    def _password(self) -> Self:
        if self.password is not None and self.username is None:
            raise problem(
                detail="expected a username with the password, got none", at=("password",)
            )
        return self

    def config(self) -> MqttConfig:
        default_port = MQTT_PORT if self.tls is False else MQTTS_PORT
        return MqttConfig(
            host=self.host,
            port=default_port if self.port is None else self.port,
            username=self.username,
            password=self.password,
            tls=self.tls,
            client_id=self.client_id,
            prefix=self.prefix,
            keepalive=self.keepalive,
            state_rate=self.state_rate,
            traffic=self.traffic,
        )


class WebTable(Table):
    """The web dashboard: every board live in a browser, its traffic, and
    with control = true the buttons of omsd ctl. Off without this table (or
    --web)."""

    listen: Annotated[TcpAddress, Default(DEFAULT_WEB)] = Field(
        default_factory=lambda: tcp_address(DEFAULT_WEB),
        description="Where the page is served. Loopback unless another address is named;"
        " any other address needs a token.",
    )
    control: Flag = Field(
        False,
        description="Buttons that act on the boards (switches, inputs, slips, faults, reset,"
        " time); false: the page only watches.",
    )
    token: (
        Annotated[
            str,
            Says(
                f"a string of at least {MIN_WEB_TOKEN} characters (the value given is not shown)",
                accepts=Annotated[str, Field(min_length=MIN_WEB_TOKEN)],
                secret=True,
            ),
        ]
        | None
    ) = Field(
        None,
        description="A secret the browser gives (open the page as /?token=...); required"
        " for an address that is not loopback.",
    )

    @model_validator(mode="after")
    def _token(self) -> Self:
        if self.token is None and not is_loopback(self.listen.host):
            raise problem(
                detail=f"expected a token with an address that is not loopback, got none for"
                f" {self.listen}",
                at=("token",),
            )
        return self

    def config(self) -> WebConfig:
        return WebConfig(self.listen, self.control, self.token)


class Document(Table):
    """An omsd configuration file: the boards, and the daemon's log, flash, control API and
    MQTT bridge."""

    model_config = ConfigDict(title="omsd configuration")

    log: LogTable = Field(default_factory=lambda: LogTable.model_validate({}))
    state: StateTable = Field(default_factory=lambda: StateTable.model_validate({}))
    control: ControlTable = Field(default_factory=lambda: ControlTable.model_validate({}))
    mqtt: MqttTable | None = Field(None)
    web: WebTable | None = Field(None)
    board: Annotated[
        list[BoardTable],
        Field(min_length=1),
        Required("at least one [[board]] table"),
        Says(
            "an array of tables, [[board]]",
            by_type=(("too_short", "at least one [[board]] table"),),
            holds_tables=True,
        ),
    ] = Field(description="One [[board]] table per emulated board.")

    @model_validator(mode="after")
    def _unique(self) -> Self:
        """Every board its own name, every endpoint its own address or link, the state file
        not the log."""
        if self.state.file is not None and self.state.file == self.log.file:
            raise not_the_log_problem(self.state.file, ("state", "file"))
        names: dict[str, KeyPath] = {}
        # by port: only endpoints on the same port other than 0 can conflict (tcp_conflict),
        # so 1,000 boards on port 0 take no check, not half a million
        tcps: dict[int, list[tuple[TcpEndpoint, KeyPath]]] = {}
        ptys: dict[Path, KeyPath] = {}
        serials: dict[Path, KeyPath] = {}
        for i, (name, board) in enumerate(self.named_boards()):
            at: KeyPath = ("board", i)
            if name in names:
                raise problem(
                    detail=f"expected a name no other board has, got {show(name)}",
                    at=(*at, "name"),
                    also=names[name],
                )
            names[name] = (*at, "name")
            listening = [
                *board.tcp_endpoints(),
                *((TcpEndpoint(r.host, r.port), at) for r, at in board.rfc2217_endpoints()),
            ]
            for endpoint, where in listening:
                if endpoint.port == 0:
                    continue
                same_port = tcps.setdefault(endpoint.port, [])
                for other, other_at in same_port:
                    if tcp_conflict(endpoint, other):
                        raise _duplicate((*at, *where), other_at, "an address", str(endpoint))
                same_port.append((endpoint, (*at, *where)))
            for pty, where in board.pty_endpoints(name):
                if pty.link in ptys:
                    raise _duplicate((*at, *where), ptys[pty.link], "a link", str(pty.link))
                ptys[pty.link] = (*at, *where)
            for serial, where in board.serial_endpoints():
                if serial.path in serials:
                    raise _duplicate(
                        (*at, *where), serials[serial.path], "a device", str(serial.path)
                    )
                serials[serial.path] = (*at, *where)
        return self

    def named_boards(self) -> list[tuple[str, BoardTable]]:
        """Each board with its name, or the one it is given: board1, board2, ... by place."""
        return [
            (board.name if board.name is not None else f"board{i + 1}", board)
            for i, board in enumerate(self.board)
        ]

    def config(self, source: str) -> DaemonConfig:
        return DaemonConfig(
            boards=tuple(board.config(name) for name, board in self.named_boards()),
            log=LogConfig(self.log.file, self.log.view, self.log.group),
            source=source,
            state=self.state.file,
            control=self.control.config(),
            mqtt=None if self.mqtt is None else self.mqtt.config(),
            web=None if self.web is None else self.web.config(),
            state_group=self.state.group,
        )


def _duplicate(at: KeyPath, other: KeyPath, what: str, got: str) -> PydanticCustomError:
    detail = f"expected {what} no other endpoint uses, got {show(got, shorten=False)}"
    return problem(detail=detail, at=at, also=other)


def not_the_log_problem(path: Path, at: KeyPath) -> PydanticCustomError:
    return problem(
        detail=f"expected a file other than the traffic log, got {show(str(path), shorten=False)}",
        at=at,
    )


def validate(document: dict[str, Any], base: Path) -> Document:
    """The document as the schema reads it, relative paths taken from ``base``."""
    return Document.model_validate(document, context={"base": base})


def option_paths() -> dict[KeyPath, str]:
    """The single-board command line: each option and the key of the one board (or of the
    file) it gives, as the schema marks them (:class:`Option`)."""
    found: dict[KeyPath, str] = {}
    for prefix, table in ((("board", 0), BoardTable), (("log",), LogTable)):
        for name, info in table.model_fields.items():
            for meta in info.metadata:
                if isinstance(meta, Option):
                    found[(*prefix, info.alias or name)] = meta.flag
    return found


__all__ = [
    "AxisTable",
    "BoardTable",
    "ControlTable",
    "Document",
    "LogTable",
    "MqttTable",
    "PtyTable",
    "Rfc2217Table",
    "SerialTable",
    "StateTable",
    "TcpTable",
    "WebTable",
    "not_the_log_problem",
    "option_paths",
    "validate",
]
