"""Where boards are served: TCP (:mod:`omsd.transport.tcp`), ptys (:mod:`omsd.transport.pty`),
serial devices (:mod:`omsd.transport.serial`) and RFC 2217 sockets
(:mod:`omsd.transport.rfc2217`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Endpoint:
    """One place a board is served, as the daemon announces it (and the control API lists it)."""

    board: str
    model: str
    link: str
    kind: str  # "tcp", "pty", "serial" or "rfc2217"
    # "127.0.0.1:7048", "/run/omsd/board1 -> /dev/pts/3", "/dev/ttyUSB0,9600,8N1"
    address: str

    def line(self) -> str:
        return f"{self.board} {self.model} {self.link} {self.kind} {self.address}"
