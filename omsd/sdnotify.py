"""systemd readiness notification (``sd_notify``) without a dependency.

A unit with ``Type=notify`` (``systemd/omsd.service``) is "started" only when the daemon says so:
systemd passes the path of a datagram socket in ``$NOTIFY_SOCKET`` and the daemon sends it one
datagram of newline-separated ``VARIABLE=value`` assignments. From sd_notify(3):

    READY=1
        Tells the service manager that service startup is finished [...]. Since there is little
        value in signaling non-readiness, the only value services should send is "READY=1".

    STOPPING=1
        Tells the service manager that the service is beginning its shutdown.

    STATUS=...
        Passes a single-line UTF-8 status string back to the service manager that describes
        the service state. This is free-form and can be used for various purposes [...].

and on the socket: "These functions send a single datagram with the state string as payload to
the socket referenced in the $NOTIFY_SOCKET environment variable. If the first character of
$NOTIFY_SOCKET is "/" or "@", the string is understood as an AF_UNIX or Linux abstract namespace
socket (respectively), and in both cases the datagram is accompanied by the process credentials
of the sending service, using SCM_CREDENTIALS." The kernel attaches the credentials itself (the
receiving socket has SO_PASSCRED): a plain ``sendto`` is the whole protocol. Other forms
(``vsock:``, for virtual machines) are not supported: :func:`notify` returns False for them.

The packages that do this (``systemd-python``, which needs libsystemd and a compiler;
``sdnotify``) would be a runtime dependency for thirty lines of standard library, so omsd has its
own. Outside systemd (no ``$NOTIFY_SOCKET``) every call is a no-op returning False, so the
daemon calls these unconditionally. A notification is a courtesy to the service manager: a
failure to send it is reported as False, never raised, and never stops the daemon.
"""

from __future__ import annotations

import os
import socket
from collections.abc import Mapping

__all__ = ["SEND_TIMEOUT", "notify", "ready", "status", "stopping"]

#: Seconds a send may block (a full receive queue at the service manager) before giving up.
#: systemd's own receive buffer is large; this only bounds the pathological case.
SEND_TIMEOUT = 2.0


def _address(value: str) -> str | None:
    """The ``sendto`` address for a ``$NOTIFY_SOCKET`` value, or None when it is not AF_UNIX."""
    if value.startswith("/"):
        return value
    if value.startswith("@") and len(value) > 1:
        # Linux abstract namespace: the name starts with a NUL byte instead of the '@'.
        return "\0" + value[1:]
    return None


def notify(state: str, env: Mapping[str, str] | None = None) -> bool:
    """Send ``state`` (e.g. ``"READY=1\\nSTATUS=serving"``) to the service manager.

    ``env`` is the environment to read ``NOTIFY_SOCKET`` from (``os.environ`` when None).
    Returns True when the datagram was sent; False when there is no ``NOTIFY_SOCKET``, it names
    something other than an AF_UNIX socket, or sending failed (the error is swallowed).
    """
    environ = os.environ if env is None else env
    address = _address(environ.get("NOTIFY_SOCKET", ""))
    if address is None:
        return False
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM | socket.SOCK_CLOEXEC) as sock:
            sock.settimeout(SEND_TIMEOUT)
            sock.sendto(state.encode("utf-8"), address)
    except (OSError, ValueError):
        # OSError: no such socket, refused, timed out, permission. ValueError: a NUL inside
        # the path (an environment cannot carry one, but a passed Mapping can).
        return False
    return True


def _line(text: str) -> str:
    """``text`` as one line: STATUS= is "a single-line UTF-8 status string"."""
    return " ".join(text.splitlines())


def ready(status: str = "", env: Mapping[str, str] | None = None) -> bool:
    """Tell the service manager startup is finished (``READY=1``), with an optional status."""
    state = "READY=1"
    if status:
        state += f"\nSTATUS={_line(status)}"
    return notify(state, env)


def stopping(env: Mapping[str, str] | None = None) -> bool:
    """Tell the service manager the daemon is shutting down (``STOPPING=1``)."""
    return notify("STOPPING=1", env)


def status(text: str, env: Mapping[str, str] | None = None) -> bool:
    """Set the free-form status line ``systemctl status omsd`` shows (``STATUS=...``)."""
    return notify(f"STATUS={_line(text)}", env)
