"""The defaults of omsd's configuration, the places it puts things by default, and the other
defaults the command line's help quotes.

One definition each: the schema (:mod:`omsd.config.schema`) gives them to its keys, the
configuration's objects (:mod:`omsd.config`, which re-exports them) to their fields, and the
command line's help texts quote them. They live here, outside :mod:`omsd.config`, so that ``omsd
--help`` and ``omsd ctl`` quote them without defining the configuration's dataclasses (issue 16:
a command within 3x ``python -c pass``); this module imports nothing of omsd's.
"""

from __future__ import annotations

import os
from pathlib import Path

DEFAULT_TCP_PORT = 7048
DEFAULT_HOST = "127.0.0.1"
DEFAULT_MODEL = "PC48-4E"
DEFAULT_BOARD_NAME = "board1"
LINKS = ("driver", "raw")
DEFAULT_LINK = "driver"
DEFAULT_EOS = 0x0A  # §7.3.2: "The default value is an LF."
DEFAULT_BUFFER_SIZE = 0x0100  # §7.3.2: "The default value is 0100 hex (256 decimal)."
BUFFER_SIZE_MIN = 0x0010  # §7.3.2: "from 0010 to 7fff (16 to 32767 decimal)"
BUFFER_SIZE_MAX = 0x7FFF
SECOND_CLIENT_POLICIES = ("takeover", "refuse")
DEFAULT_SECOND_CLIENT = "takeover"
#: How long a TCP client that has shut down its sending side (``nc -N``, ``shutdown(SHUT_WR)``)
#: is kept open for the answers, done markers and limits its commands are yet to produce.
DEFAULT_LINGER = 60.0
MAX_LINGER = 3600.0
DEFAULT_PTY_MODE = 0o660
#: A serial endpoint's line unless configured, as a legacy application's port is set: 9600 baud,
#: 8 data bits, no parity, 1 stop bit (8N1), no flow control
DEFAULT_BAUD = 9600
BAUD_MIN = 50
BAUD_MAX = 10_000_000
DEFAULT_BYTESIZE = 8
DEFAULT_PARITY = "N"
DEFAULT_STOPBITS = 1
FLOWS = ("none", "rtscts", "xonxoff")
DEFAULT_FLOW = "none"
VIEWS = ("auto", "rich", "plain", "off")
LOOPS = ("auto", "asyncio", "uvloop")  # --loop (omsd.loops)
DEFAULT_VIEW = "auto"
CONTROL_SOCKET_NAME = "control.sock"
MQTT_PORT = 1883  # IANA "mqtt"
MQTTS_PORT = 8883  # IANA "secure-mqtt"
DEFAULT_MQTT_PREFIX = "omsd"
DEFAULT_KEEPALIVE = 60
DEFAULT_STATE_RATE = 10.0
DEFAULT_WEB = "127.0.0.1:8048"  # the web dashboard's address ([web] listen; --web)
MIN_WEB_TOKEN = 16  # characters of a [web] token, at least
MAX_STATE_RATE = 1000.0  # state publications per second per board, at most
#: ``omsd console --wait``: at the end of a file or pipe, how long motion still running may take
CONSOLE_WAIT = 30.0


# -- places -------------------------------------------------------------------------------------


def runtime_directory() -> Path:
    """The daemon's runtime directory, where the default pty links and the control socket go:
    ``$RUNTIME_DIRECTORY`` under a systemd unit with ``RuntimeDirectory=``, else
    ``$XDG_RUNTIME_DIR/omsd``, else ``/tmp/omsd-<uid>``. The daemon creates it (mode 0700) and
    refuses one that another user could change (:func:`omsd.files.check_runtime_directory`)."""
    runtime = os.environ.get("RUNTIME_DIRECTORY", "").split(":")[0]
    if os.path.isabs(runtime):
        return Path(runtime)
    xdg = os.environ.get("XDG_RUNTIME_DIR", "")
    if os.path.isabs(xdg):
        return Path(xdg) / "omsd"
    return Path(f"/tmp/omsd-{os.getuid()}")


def default_pty_link(name: str) -> Path:
    """Where a board's pty link goes when none is configured: ``<name>`` in the
    :func:`runtime_directory`. The daemon creates the directory."""
    return runtime_directory() / name


__all__ = [
    "BAUD_MAX",
    "BAUD_MIN",
    "BUFFER_SIZE_MAX",
    "BUFFER_SIZE_MIN",
    "CONSOLE_WAIT",
    "CONTROL_SOCKET_NAME",
    "DEFAULT_BAUD",
    "DEFAULT_BOARD_NAME",
    "DEFAULT_BUFFER_SIZE",
    "DEFAULT_BYTESIZE",
    "DEFAULT_EOS",
    "DEFAULT_FLOW",
    "DEFAULT_HOST",
    "DEFAULT_KEEPALIVE",
    "DEFAULT_LINGER",
    "DEFAULT_LINK",
    "DEFAULT_MODEL",
    "DEFAULT_MQTT_PREFIX",
    "DEFAULT_PARITY",
    "DEFAULT_PTY_MODE",
    "DEFAULT_SECOND_CLIENT",
    "DEFAULT_STATE_RATE",
    "DEFAULT_STOPBITS",
    "DEFAULT_TCP_PORT",
    "DEFAULT_VIEW",
    "DEFAULT_WEB",
    "FLOWS",
    "LINKS",
    "MAX_LINGER",
    "MAX_STATE_RATE",
    "MIN_WEB_TOKEN",
    "MQTTS_PORT",
    "MQTT_PORT",
    "SECOND_CLIENT_POLICIES",
    "VIEWS",
    "default_pty_link",
    "runtime_directory",
]
