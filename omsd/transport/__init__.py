"""Where boards are served: TCP (:mod:`omsd.transport.tcp`) and ptys (:mod:`omsd.transport.pty`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Endpoint:
    """One place a board is served, as the daemon announces it (and the control API lists it)."""

    board: str
    model: str
    link: str
    kind: str  # "tcp" or "pty"
    address: str  # "127.0.0.1:7048" or "/run/omsd/board1 -> /dev/pts/3"

    def line(self) -> str:
        return f"{self.board} {self.model} {self.link} {self.kind} {self.address}"
