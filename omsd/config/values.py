"""The values of omsd's configuration that are more than a TOML type: paths relative to the
file, TCP addresses, serial devices and their lines, the driver's hex options, permissions,
board models, groups, the MQTT broker; each a type of :mod:`omsd.config.schema`'s keys with its
words (:class:`Says`)."""

import grp
import ipaddress
import os
import re
from pathlib import Path
from typing import Annotated

from pydantic import Field, ValidationInfo

from omsd.config import BAUD_MAX, BAUD_MIN, SerialEndpoint, TcpEndpoint
from omsd.config.syntax import (
    HOSTNAME,
    PATH_PATTERN,
    SERIAL_SYNTAX,
    TCP_PATTERN,
    TCP_SYNTAX,
    AddressProblem,
    hex_pattern,
    hex_value,
    resolve,
    serial_text,
    tcp_address,
    tcp_conflict,
)
from omsd.config.wording import Says, choices_json, problem
from omsd.config_errors import show
from omsd.models import MODELS, UnknownModel, get_model


def _context(info: ValidationInfo) -> Path:
    """The directory relative paths are taken from (the file's, or the working directory)."""
    context = info.context or {}
    base = context.get("base")
    return base if isinstance(base, Path) else Path.cwd()


def _resolve(text: str, info: ValidationInfo) -> Path:
    return resolve(text, _context(info))


def octal(raw: int | str) -> int:
    """Permissions: an integer (TOML ``0o660``) or an octal string (``"0660"``, ``"0o660"``)."""
    if isinstance(raw, int):
        return raw
    number = int(raw.strip().removeprefix("0o").removeprefix("0O"), 8)
    if number > 0o777:
        raise ValueError(f"{number:o} is out of range")
    return number


def _model_name(text: str) -> str:
    try:
        return get_model(text).name
    except UnknownModel:
        raise ValueError(text) from None


def _group(name: str) -> str:
    """The group a file the daemon creates is given (``[log] group``, ``[state] group``,
    ``[control] group``): an existing group that the daemon's user is in (a process can only
    give a file to a group it belongs to; root can give it to any), so that the mistake shows
    now and not at the first write."""
    try:
        gid = grp.getgrnam(name).gr_gid
    except KeyError:
        raise problem(expected="the name of an existing group") from None
    if os.geteuid() != 0 and gid != os.getegid() and gid not in os.getgroups():
        raise problem(expected=f"a group that omsd's user (uid {os.geteuid()}) belongs to")
    return name


# TCP addresses (omsd.config.syntax) ------------------------------------------------------------


def _tcp_address(raw: int | str) -> TcpEndpoint:
    """``PORT``, ``HOST:PORT`` or ``[IPv6]:PORT`` (:func:`omsd.config.syntax.tcp_address`), the
    address that cannot be used in the schema's words."""
    try:
        return tcp_address(raw)
    except AddressProblem as exc:
        raise problem(expected=exc.expected) from None


# serial devices (omsd.config.syntax) -------------------------------------------------------------


def _serial_text(raw: str, info: ValidationInfo) -> SerialEndpoint:
    """``PATH[,BAUD[,8N1]]`` (:func:`omsd.config.syntax.serial_text`), relative to the file."""
    try:
        return serial_text(raw, _context(info))
    except AddressProblem as exc:
        raise problem(expected=exc.expected) from None


PARITY_WORDS = {"none": "N", "even": "E", "odd": "O", "mark": "M", "space": "S"}


def _parity(raw: str) -> str:
    text = raw.strip().lower()
    return PARITY_WORDS.get(text, text.upper())


def _stopbits(raw: float) -> float:
    if raw not in (1, 1.5, 2):
        raise ValueError(raw)
    return int(raw) if float(raw).is_integer() else raw


def _is_address(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


def broker_host(host: str) -> str:
    if _is_address(host.strip("[]")) or (
        HOSTNAME.fullmatch(host) and not re.fullmatch(r"[0-9.]+", host)
    ):
        return host.strip("[]")
    raise ValueError(host)


def mqtt_client_id(text: str) -> str:
    if "\x00" in text or len(text.encode()) > 65535:
        raise problem(expected="an MQTT client identifier")
    return text


def _ca_file(path: Path) -> Path:
    if not path.is_file():
        raise problem(
            expected="true, false or a CA certificate file", got=show(str(path), shorten=False)
        )
    return path


# the types of the keys --------------------------------------------------------------------------

NAME_PATTERN = r"^(?:[A-Za-z0-9_.-]*[A-Za-z0-9_-][A-Za-z0-9_.-]*|\.{3,})$"  # not "." or ".."
SERIAL_PATTERN = r"[A-Za-z0-9-]{1,16}"
FIRMWARE_PATTERN = r"\d{1,2}\.\d{2}"
TOPIC_PATTERN = r"^[^/+#\x00$][^/+#\x00]*(?:/[^/+#\x00]+)*$"  # levels; no + # or a leading $

Flag = Annotated[bool, Says("true or false")]
Text = Annotated[str, Says("a non-empty string", accepts=Annotated[str, Field(min_length=1)])]
FilePath = Annotated[
    Path,
    Says(
        "a path",
        accepts=Annotated[str, Field(pattern=PATH_PATTERN)],
        convert=_resolve,
        with_info=True,
    ),
]
FileGroup = Annotated[
    str, Says("the name of a group omsd's user belongs to", accepts=Text, convert=_group)
]
TcpAddress = Annotated[
    TcpEndpoint,
    Says(
        TCP_SYNTAX,
        accepts=Annotated[int, Field(ge=0, le=65535)] | Annotated[str, Field(pattern=TCP_PATTERN)],
        convert=_tcp_address,
    ),
]
SerialText = Annotated[
    SerialEndpoint,
    Says(
        f"{SERIAL_SYNTAX} (a device path, a baud rate, 8N1)",
        accepts=Annotated[str, Field(pattern=PATH_PATTERN)],
        convert=_serial_text,
        with_info=True,
    ),
]
Baud = Annotated[
    int,
    Says(
        f"a baud rate {BAUD_MIN}..{BAUD_MAX}",
        accepts=Annotated[int, Field(ge=BAUD_MIN, le=BAUD_MAX)],
    ),
]
DataBits = Annotated[int, Says("data bits 5..8", accepts=Annotated[int, Field(ge=5, le=8)])]
Parity = Annotated[
    str,
    Says(
        '"N", "E", "O", "M" or "S" (or none, even, odd, mark, space)',
        accepts=Annotated[str, Field(pattern=r"^\s*(?i:[NEOMS]|none|even|odd|mark|space)\s*$")],
        convert=_parity,
    ),
]
StopBits = Annotated[
    float,
    Says(
        "stop bits 1, 1.5 or 2",
        accepts=Annotated[float, Field(allow_inf_nan=False)],
        convert=_stopbits,
        json={"enum": [1, 1.5, 2]},
    ),
]
Steps = Annotated[
    float,
    Says(
        "a number (motor steps)",
        by_type=(("finite_number", "a finite number"),),
        accepts=Annotated[float, Field(allow_inf_nan=False)],
    ),
]
CaFile = Annotated[
    Path, Says("true, false or a CA certificate file", accepts=FilePath, convert=_ca_file)
]
BoardModel = Annotated[
    str,
    Says(
        f"a board model ({', '.join(MODELS)})",
        convert=_model_name,
        json=choices_json(tuple(MODELS), padded=True),
    ),
]


__all__ = [
    "TCP_SYNTAX",
    "Baud",
    "BoardModel",
    "CaFile",
    "DataBits",
    "FileGroup",
    "FilePath",
    "Flag",
    "Parity",
    "SerialText",
    "Steps",
    "StopBits",
    "TcpAddress",
    "Text",
    "broker_host",
    "hex_pattern",
    "hex_value",
    "mqtt_client_id",
    "octal",
    "tcp_conflict",
]
