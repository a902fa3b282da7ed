"""A fast path: the single-board command line read without the schema, when it is valid.

``omsd --board PC48-4E --tcp 7001 --pty /tmp/oms`` is validated by the schema as a one-board
document (:func:`omsd.config.reading.single_board`), but importing pydantic and building the
schema's models takes ~0.1 s, most of a daemon's start (issue 16: the first connection accepted
within 0.12 s). This module builds the same :class:`~omsd.config.DaemonConfig` from options it
is sure of, with the functions the schema's own types use (:mod:`omsd.config.syntax`, the model
lookup) and the same defaults (:mod:`omsd.defaults`), and says nothing about anything else:
:func:`single_board` and :func:`option_path` return ``None`` for every option they do not
accept as plainly valid, and the caller asks the schema, which gives the configuration or the
one-line error as before. So the schema stays the one place that says what is valid and how a
mistake is worded; this is a shortcut for the common, valid case only, and it never accepts
what the schema refuses.

Serial and RFC 2217 endpoints (``--serial``, ``--rfc2217``) never take this path: with either
option, :func:`omsd.config.from_options` asks the schema directly.

``tests/test_config_fastpath.py`` holds it to that: for option lists drawn from valid and
invalid fragments, it returns ``None`` or exactly what the schema makes of them.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from omsd.config import BoardConfig, DaemonConfig, LogConfig, PtyEndpoint, TcpEndpoint
from omsd.config.syntax import hex_value, resolve, tcp_address, tcp_conflict
from omsd.defaults import (
    DEFAULT_BOARD_NAME,
    DEFAULT_EOS,
    DEFAULT_HOST,
    DEFAULT_LINK,
    DEFAULT_MODEL,
    DEFAULT_TCP_PORT,
    LINKS,
    default_pty_link,
)
from omsd.models import UnknownModel, get_model

# What is surely valid, a subset of what the schema accepts (its patterns run on pydantic's
# regex engine, whose \s and $ differ from Python's at the edges: those edges go to the schema)
_EOS = re.compile(r"(?:0[xX])?[0-9A-Fa-f]{1,2}")  # hex_pattern(2), without the spaces
_VISIBLE = re.compile(r"[!-~]")  # PATH_PATTERN: a path that is not blank; here, one visible
_eos_value = hex_value(0, 0xFF)


def option_path(text: str) -> Path | None:
    """A path option (``--pty``, ``--log``, ``--state``, ``--control``) as the schema's
    ``FilePath`` makes it, relative to the working directory; ``None``: ask the schema."""
    if "\x00" in text or _VISIBLE.search(text) is None:
        return None
    try:
        return resolve(text, Path.cwd())
    except (RuntimeError, OSError, ValueError):  # ~user without a home: the schema's to say
        return None


def single_board(
    board: str | None,
    tcp: Sequence[str],
    pty: Sequence[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool,
    source: str,
) -> DaemonConfig | None:
    """The configuration :func:`omsd.config.reading.single_board` gives for these options, or
    ``None`` where it is not sure they are valid (the caller then asks the schema)."""
    try:
        model = get_model(board if board is not None else DEFAULT_MODEL).name
    except UnknownModel:
        return None
    kind = DEFAULT_LINK if link is None else link.lower()
    if kind not in LINKS:
        return None
    code = DEFAULT_EOS
    if eos is not None:
        if kind == "raw" or _EOS.fullmatch(eos) is None:
            return None
        code = _eos_value(eos)
    if not tcp and not pty:  # the default endpoints
        tcp = [f"{DEFAULT_HOST}:{DEFAULT_TCP_PORT}"]
        links: list[Path | None] = [None]
    else:
        links = []
        for text in pty:
            path = option_path(text)
            if path is None:
                return None
            links.append(path)
    tcps: list[TcpEndpoint] = []
    for text in tcp:
        try:
            endpoint = tcp_address(text)
        except ValueError:  # AddressProblem too
            return None
        if any(tcp_conflict(endpoint, other) for other in tcps):
            return None
        tcps.append(endpoint)
    ptys = [
        PtyEndpoint(
            default_pty_link(DEFAULT_BOARD_NAME) if link_path is None else link_path,
            terminal=terminal,
        )
        for link_path in links
    ]
    if len({p.link for p in ptys}) != len(ptys):
        return None
    log_file = None
    if log is not None:
        log_file = option_path(log)
        if log_file is None:
            return None
    return DaemonConfig(
        boards=(
            BoardConfig(
                name=DEFAULT_BOARD_NAME,
                model=model,
                link=kind,
                eos=code,
                tcp=tuple(tcps),
                pty=tuple(ptys),
            ),
        ),
        log=LogConfig(file=log_file),
        source=source,
    )


__all__ = ["option_path", "single_board"]
