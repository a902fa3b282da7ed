"""An address and port as people, URLs and omsd's own options write them: ``HOST:PORT``, and
``[IPv6]:PORT`` with the IPv6 address in brackets (RFC 3986 §3.2.2), which is what ``--tcp``,
``[control] tcp`` and ``omsd ctl --tcp`` take back. Every address:port omsd prints (endpoint
lines, log lines, the control API's listing, error messages) is written by :func:`host_port`."""

from __future__ import annotations


def host_port(host: str, port: int | str) -> str:
    """``127.0.0.1:7048``, ``localhost:7048``, ``[::1]:7048``."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
