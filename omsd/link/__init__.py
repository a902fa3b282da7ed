"""Link disciplines: what sits between a host program and a board (pure)."""

from __future__ import annotations

from omsd.board import Board
from omsd.link.base import Link, LinkOutput
from omsd.link.driver import DriverLink
from omsd.link.raw import RawLink

KINDS = ("driver", "raw")


def make_link(kind: str, board: Board, eos: int = 0x0A, buffer_size: int = 256) -> Link:
    if kind == "driver":
        return DriverLink(board, eos=eos, buffer_size=buffer_size)
    if kind == "raw":
        return RawLink(board)
    raise ValueError(f"unknown link {kind!r}; expected one of {', '.join(KINDS)}")


__all__ = ["KINDS", "DriverLink", "Link", "LinkOutput", "RawLink", "make_link"]
