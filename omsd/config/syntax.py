"""The values of the configuration that have a syntax of their own, without pydantic: TCP
addresses, serial devices with their line (``PATH[,BAUD[,8N1]]``), the driver's hexadecimal
options, paths, and when two endpoints collide.

One definition each, used twice: :mod:`omsd.config.values` makes the schema's types of them
(pydantic, with omsd's words for every error), and :mod:`omsd.config.fastpath` reads a valid
single-board command line with them without importing pydantic (issue 16: a daemon's start).
Errors here carry no wording of their own: :class:`AddressProblem` holds the schema's words for
what the address should have been, and every other mistake is a ``ValueError`` the schema words.
"""

from __future__ import annotations

import ipaddress
import os
import re
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from omsd.config import SerialEndpoint, TcpEndpoint
from omsd.defaults import BAUD_MAX, BAUD_MIN, DEFAULT_HOST

PATH_PATTERN = r"^[^\x00]*[^\x00\s][^\x00]*$"  # not empty or blank, no NUL
TCP_PATTERN = r"^(?:(?:\[[^\]]*\]|[^:\[\]]*):)?[0-9]{1,5}$"
TCP_SYNTAX = "[HOST:]PORT with PORT 0..65535"
_TCP = re.compile(r"(?:(?:\[(?P<v6>[^\]]*)\]|(?P<host>[^:\[\]]*)):)?(?P<port>[0-9]{1,5})")
SERIAL_SYNTAX = "PATH[,BAUD[,8N1]]"
_FRAME = re.compile(r"(?P<bytesize>[5-8])(?P<parity>[NEOMSneoms])(?P<stopbits>1|1\.5|2)")
HOSTNAME = re.compile(r"[A-Za-z0-9_]([A-Za-z0-9_-]*[A-Za-z0-9_])?(\.[A-Za-z0-9_-]+)*")


class AddressProblem(ValueError):
    """A TCP address of the right shape that cannot be used; ``expected`` says what it should
    have been (the schema's words: ``[HOST:]PORT with a valid IPv4 address``)."""

    def __init__(self, expected: str) -> None:
        super().__init__(expected)
        self.expected = expected


def resolve(text: str, base: Path) -> Path:
    """A path as the configuration takes it: ``~`` expanded, relative to ``base``, normalized."""
    return Path(os.path.normpath(base / Path(text).expanduser()))


def hex_value(lo: int, hi: int) -> Callable[[int | str], int]:
    """A driver option: a string is hexadecimal (``"0D"``, ``"0x0d"``), an integer is itself."""

    def value(raw: int | str) -> int:
        if isinstance(raw, int):
            return raw
        number = int(raw.strip().removeprefix("0x").removeprefix("0X"), 16)
        if not lo <= number <= hi:
            raise ValueError(f"{number} is out of range")
        return number

    return value


def hex_pattern(digits: int) -> str:
    return rf"^\s*(0[xX])?[0-9A-Fa-f]{{1,{digits}}}\s*$"


def tcp_address(raw: int | str) -> TcpEndpoint:
    """``PORT``, ``HOST:PORT`` or ``[IPv6]:PORT``; an integer is a port on 127.0.0.1. A text not
    of this shape is a ``ValueError``; one of this shape that cannot be used an
    :class:`AddressProblem`."""
    if isinstance(raw, int):
        if not 0 <= raw <= 65535:
            raise ValueError(raw)
        return TcpEndpoint(DEFAULT_HOST, raw)
    m = _TCP.fullmatch(raw)
    if m is None or int(m.group("port")) > 65535:
        raise ValueError(raw)
    port = int(m.group("port"))
    v6, host = m.group("v6"), m.group("host")
    if v6 is not None:
        try:
            ipaddress.IPv6Address(v6)
        except ValueError:
            raise AddressProblem("[HOST:]PORT with an IPv6 address inside [ ]") from None
        return TcpEndpoint(v6, port)
    if host is None:
        return TcpEndpoint(DEFAULT_HOST, port)
    if host == "":
        raise AddressProblem(
            "[HOST:]PORT with a HOST before the colon (0.0.0.0 for every interface)"
        )
    if re.fullmatch(r"[0-9.]+", host):
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise AddressProblem("[HOST:]PORT with a valid IPv4 address") from None
    elif not HOSTNAME.fullmatch(host):
        raise AddressProblem("[HOST:]PORT with HOST an address or a host name")
    return TcpEndpoint(host, port)


def serial_text(text: str, base: Path) -> SerialEndpoint:
    """``PATH``, ``PATH,BAUD`` or ``PATH,BAUD,8N1`` (data bits 5-8, parity N E O M S, stop bits
    1, 1.5 or 2), and ``,rtscts`` or ``,xonxoff`` after it for flow control (as the daemon
    announces a port that has it), the path relative to ``base``; an :class:`AddressProblem`
    with the words for what it should have been."""
    path, *settings = text.split(",")
    if not path.strip() or "\x00" in path or len(settings) > 3:
        raise AddressProblem(f"{SERIAL_SYNTAX} (a device path, a baud rate, 8N1)")
    endpoint = SerialEndpoint(resolve(path, base))
    if settings:
        baud = settings[0].strip()
        if not baud.isdigit() or not BAUD_MIN <= int(baud) <= BAUD_MAX:
            raise AddressProblem(f"{SERIAL_SYNTAX} with BAUD {BAUD_MIN}..{BAUD_MAX}")
        endpoint = SerialEndpoint(endpoint.path, int(baud))
    if len(settings) >= 2:
        m = _FRAME.fullmatch(settings[1].strip())
        if m is None:
            raise AddressProblem(
                f"{SERIAL_SYNTAX} with data bits 5..8, parity N, E, O, M or S and stop bits 1,"
                " 1.5 or 2 (8N1)"
            )
        stop = float(m.group("stopbits"))
        endpoint = SerialEndpoint(
            endpoint.path,
            endpoint.baud,
            int(m.group("bytesize")),
            m.group("parity").upper(),
            int(stop) if stop.is_integer() else stop,
        )
    if len(settings) == 3:  # what the daemon announces after 8N1 when the port has flow control
        flow = settings[2].strip().lower()
        if flow not in ("rtscts", "xonxoff"):
            raise AddressProblem(f"{SERIAL_SYNTAX} and rtscts or xonxoff after the 8N1")
        endpoint = replace(endpoint, flow=flow)
    return endpoint


def _family(host: str) -> int | None:
    try:
        return ipaddress.ip_address(host.split("%")[0]).version
    except ValueError:
        return None  # a host name: only the same name is known to collide


def tcp_conflict(a: TcpEndpoint, b: TcpEndpoint) -> bool:
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


__all__ = [
    "HOSTNAME",
    "PATH_PATTERN",
    "SERIAL_SYNTAX",
    "TCP_PATTERN",
    "TCP_SYNTAX",
    "AddressProblem",
    "hex_pattern",
    "hex_value",
    "resolve",
    "serial_text",
    "tcp_address",
    "tcp_conflict",
]
