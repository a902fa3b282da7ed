"""Whether this machine has an IPv6 loopback, for the tests that serve on ``[::1]``."""

from __future__ import annotations

import socket

import pytest


def loopback() -> bool:
    """``::1`` can be bound (a container without IPv6 cannot)."""
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
    except OSError:
        return False
    return True


needs_loopback = pytest.mark.skipif(not loopback(), reason="no IPv6 loopback here")
