"""The typed Python client of the control API (blocking; one socket per client).

::

    from omsd.control.client import Control

    with Control() as ctl:                      # $XDG_RUNTIME_DIR/omsd/control.sock
        ctl.set_limit("X", +1, True, board="xy")    # close X's positive limit switch
        ctl.wait_done("X", board="xy")              # until X's done flag is set
        ctl.state("xy")["axes"]["X"]["position"]

Every method raises :class:`~omsd.control.protocol.ControlError` (one line) when the daemon
refuses the operation, and :class:`OSError` when it cannot be reached.

:meth:`Control.subscribe` makes the connection a stream of the boards' life (the snapshot, then
what changes, at most ``rate`` times a second, and the events as they happen): a
:class:`Subscription`, iterated for its messages, which keeps each board's state up to date.
Until it is closed the connection is the stream's; use another :class:`Control` for the
operations meanwhile.
"""

from __future__ import annotations

import itertools
import select
import socket
import time
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import Any

from omsd.control.protocol import (
    DEFAULT_RATE,
    MAX_LINE,
    MAX_WAIT,
    ControlError,
    decode,
    encode,
    merge,
)
from omsd.defaults import default_pty_link
from omsd.hostport import host_port

_UNSET: Any = object()


def default_socket() -> Path:
    """Where a daemon started without ``--control`` listens."""
    return default_pty_link("control.sock")


class Control:
    def __init__(
        self,
        path: str | Path | None = None,
        *,
        tcp: tuple[str, int] | None = None,
        timeout: float = 30.0,
    ) -> None:
        if tcp is not None:
            self.sock = socket.create_connection(tcp, timeout=timeout)
            self.address = host_port(*tcp)
        else:
            target = Path(path) if path is not None else default_socket()
            self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            self.sock.settimeout(timeout)
            try:
                self.sock.connect(str(target))
            except OSError:
                self.sock.close()
                raise
            self.address = str(target)
        self.timeout = timeout
        self._ids = itertools.count(1)
        self._buffer = bytearray()

    def __enter__(self) -> Control:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self.sock.close()

    # -- the wire -------------------------------------------------------------------------------

    def call(self, op: str, *, reply_within: float | None = None, **args: Any) -> Any:
        """Send one operation and return its result (``reply_within``: seconds to wait for
        the reply, the client's timeout by default)."""
        ident = next(self._ids)
        request = {"id": ident, "op": op, **{k: v for k, v in args.items() if v is not _UNSET}}
        self.sock.settimeout(reply_within if reply_within is not None else self.timeout)
        self.sock.sendall(encode(request))
        while True:
            try:
                reply = decode(self._line())
            except ControlError:
                # something else listens there (a board's data port, say): not the daemon
                raise ConnectionError(
                    f"{self.address} is not an omsd control endpoint (its reply is not JSON)"
                ) from None
            if reply.get("id") != ident:
                continue  # a reply to an earlier request given up on
            if reply.get("ok"):
                return reply.get("result")
            raise ControlError(str(reply.get("error", "error")))

    def _line(self) -> bytes:
        while (end := self._buffer.find(b"\n")) < 0:
            if len(self._buffer) > MAX_LINE:
                raise ControlError("reply too long")
            self._receive()
        line = bytes(self._buffer[:end])
        del self._buffer[: end + 1]
        return line

    def _receive(self) -> None:
        data = self.sock.recv(65536)
        if not data:
            raise ConnectionError(f"the daemon at {self.address} closed the connection")
        self._buffer += data

    # -- the stream -----------------------------------------------------------------------------

    def subscribe(
        self,
        board: str | None = None,
        *,
        boards: list[str] | None = None,
        rate: float = DEFAULT_RATE,
        traffic: bool | str = False,
        timeout: float | None = None,
        rates: dict[str, float] | None = None,
    ) -> Subscription:
        """The boards' life as a stream (every board unless ``board`` or ``boards`` says): the
        snapshot (:attr:`Subscription.snapshot`), then, iterating, each message: ``state``
        changes at most ``rate`` times a second (``rates``: a rate of their own for the boards
        it names), ``event`` as they happen, ``traffic`` chunks with ``traffic`` true (or a
        board's name). ``timeout``: seconds an iteration waits for a message before
        :class:`TimeoutError` (None: as long as it takes; an idle daemon sends nothing)."""
        ident = next(self._ids)
        request: dict[str, Any] = {"id": ident, "op": "subscribe", "rate": rate}
        if rates:
            request["rates"] = rates
        if boards is not None:
            request["boards"] = boards
        elif board is not None:
            request["board"] = board
        if traffic is not False:
            request["traffic"] = traffic
        self.sock.settimeout(self.timeout)
        self.sock.sendall(encode(request))
        while True:
            reply = decode(self._line())
            if reply.get("id") != ident:
                continue
            if not reply.get("ok"):
                raise ControlError(str(reply.get("error", "error")))
            return Subscription(self, ident, reply["result"], timeout)

    # -- looking --------------------------------------------------------------------------------

    def boards(self) -> list[dict[str, Any]]:
        """Every board: name, model, link and endpoints (kind, address)."""
        result: list[dict[str, Any]] = self.call("boards")
        return result

    def state(self, board: str | None = None) -> dict[str, Any]:
        """The board's full state: per axis position, encoder, velocity, flags and switches;
        registers; queue space; the link's buffers; the clock and the cable's faults."""
        result: dict[str, Any] = self.call("state", board=board)
        return result

    # -- the world ------------------------------------------------------------------------------

    def set_limit(
        self, axis: str, direction: int, active: bool | None = True, board: str | None = None
    ) -> dict[str, Any]:
        """Close (True) or open (False) a limit switch; None lets the carriage decide again."""
        result: dict[str, Any] = self.call(
            "limit", board=board, axis=axis, direction=direction, active=active
        )
        return result

    def set_home(
        self, axis: str, active: bool | None = True, board: str | None = None
    ) -> dict[str, Any]:
        result: dict[str, Any] = self.call("home", board=board, axis=axis, active=active)
        return result

    def set_input(self, bit: int, high: bool | None, board: str | None = None) -> dict[str, Any]:
        """Drive a general-purpose input high or low; None releases it (pulled up)."""
        result: dict[str, Any] = self.call("input", board=board, bit=bit, high=high)
        return result

    def slip(self, axis: str, steps: float, board: str | None = None) -> dict[str, Any]:
        """The carriage slips ``steps`` steps against the motor: the encoder (and the switches)
        see the carriage move, the position counter does not."""
        result: dict[str, Any] = self.call("slip", board=board, axis=axis, steps=steps)
        return result

    def stall(self, axis: str, stalled: bool = True, board: str | None = None) -> dict[str, Any]:
        result: dict[str, Any] = self.call("stall", board=board, axis=axis, stalled=stalled)
        return result

    def encoder(self, axis: str, counts: int, board: str | None = None) -> dict[str, Any]:
        """Turn an external encoder to ``counts`` (what ET tracks)."""
        result: dict[str, Any] = self.call("encoder", board=board, axis=axis, counts=counts)
        return result

    # -- faults ---------------------------------------------------------------------------------

    def fault(
        self,
        board: str | None = None,
        *,
        latency: float = _UNSET,
        baud: int | None = _UNSET,
        drop: float = _UNSET,
        garble: float = _UNSET,
        cable: bool = _UNSET,
        seed: int = _UNSET,
    ) -> dict[str, Any]:
        """Change the cable's faults (those not given stay as they are); see
        :mod:`omsd.faults`. Returns the faults now in force."""
        result: dict[str, Any] = self.call(
            "fault",
            board=board,
            latency=latency,
            baud=baud,
            drop=drop,
            garble=garble,
            cable=cable,
            seed=seed,
        )
        return result

    def cut_cable(self, board: str | None = None) -> dict[str, Any]:
        return self.fault(board, cable=False)

    def connect_cable(self, board: str | None = None) -> dict[str, Any]:
        return self.fault(board, cable=True)

    def clear_faults(self, board: str | None = None) -> dict[str, Any]:
        return self.fault(board, latency=0.0, baud=None, drop=0.0, garble=0.0, cable=True)

    # -- time and power -------------------------------------------------------------------------

    def pause(self, board: str | None = None) -> dict[str, Any]:
        result: dict[str, Any] = self.call("time", board=board, action="pause")
        return result

    def resume(self, board: str | None = None) -> dict[str, Any]:
        result: dict[str, Any] = self.call("time", board=board, action="resume")
        return result

    def step(self, seconds: float, board: str | None = None) -> dict[str, Any]:
        """Move a paused board's time ``seconds`` forward (all that happens in them happens)."""
        result: dict[str, Any] = self.call("time", board=board, action="step", seconds=seconds)
        return result

    def scale(self, scale: float, board: str | None = None) -> dict[str, Any]:
        """Board seconds per real second (0.001 to 1000)."""
        result: dict[str, Any] = self.call("time", board=board, action="scale", scale=scale)
        return result

    def reset(self, board: str | None = None) -> dict[str, Any]:
        """Power-cycle the board."""
        result: dict[str, Any] = self.call("reset", board=board)
        return result

    # -- waiting --------------------------------------------------------------------------------

    def _wait(self, board: str | None, timeout: float, **args: Any) -> dict[str, Any]:
        result: dict[str, Any] = self.call(
            # the daemon refuses a timeout past MAX_WAIT at once (and 1e99 s is more than a
            # socket's timeout can be)
            "wait",
            reply_within=min(timeout, MAX_WAIT) + 5.0,
            board=board,
            timeout=timeout,
            **args,
        )
        return result

    def wait_done(
        self, axis: str, timeout: float = 10.0, board: str | None = None
    ) -> dict[str, Any]:
        """Until the axis's done flag is set (ID, GD, GN ...); returns the state then."""
        return self._wait(board, timeout, until="done", axis=axis)

    def wait_idle(self, timeout: float = 10.0, board: str | None = None) -> dict[str, Any]:
        """Until every axis is at rest with an empty queue."""
        return self._wait(board, timeout, until="idle")

    def wait_position(
        self, axis: str, position: int, timeout: float = 10.0, board: str | None = None
    ) -> dict[str, Any]:
        """Until the axis's position counter reaches (or passes) ``position``; an axis still
        on a motion that has already carried it past ``position`` has reached it."""
        return self._wait(board, timeout, until="position", axis=axis, position=position)


class Subscription:
    """A stream from :meth:`Control.subscribe`. ``snapshot`` is its first message; ``states``
    is each board's state (the snapshot's) with every ``state`` message read so far merged
    in (:func:`omsd.control.protocol.merge`). Iterating gives the messages as they come; a
    program with other things to wait on (``omsd top``) waits on :meth:`fileno` and takes what
    has come with :meth:`pending`."""

    def __init__(
        self, control: Control, ident: int, snapshot: dict[str, Any], timeout: float | None
    ) -> None:
        self.control = control
        self.ident = ident
        self.snapshot = snapshot
        self.timeout = timeout
        self.states: dict[str, dict[str, Any]] = {b["name"]: b["state"] for b in snapshot["boards"]}
        self.closed = False

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return self

    def __next__(self) -> dict[str, Any]:
        message = self.read(self.timeout)
        if message is None:
            raise TimeoutError(f"no message from the daemon in {self.timeout:g} s")
        return message

    def fileno(self) -> int:
        return self.control.sock.fileno()

    def read(self, timeout: float | None = None) -> dict[str, Any] | None:
        """The next message, or None when none came within ``timeout`` seconds (None: wait as
        long as it takes)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            message = self._buffered()
            if message is not None:
                return message
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([self.fileno()], [], [], left)
            if not ready:
                return None
            self.control._receive()

    def pending(self) -> list[dict[str, Any]]:
        """The messages that have come, without waiting."""
        out: list[dict[str, Any]] = []
        while True:
            message = self._buffered()
            if message is None:
                ready, _, _ = select.select([self.fileno()], [], [], 0.0)
                if not ready:
                    return out
                self.control._receive()
                continue
            out.append(message)

    def _buffered(self) -> dict[str, Any] | None:
        """The next whole message already received, if any (replies to other requests are
        skipped)."""
        buffer = self.control._buffer
        while (end := buffer.find(b"\n")) >= 0:
            line = bytes(buffer[:end])
            del buffer[: end + 1]
            message = decode(line)
            if message.get("id") != self.ident or "kind" not in message:
                continue
            if message["kind"] == "state":
                for name, changes in message.get("boards", {}).items():
                    if name in self.states:
                        merge(self.states[name], changes)
            return message
        if len(buffer) > MAX_LINE:
            raise ControlError("message too long")
        return None

    def close(self) -> dict[str, Any] | None:
        """Unsubscribe: the connection takes operations again. Returns what the daemon counted
        (``sent``, ``dropped`` by kind, ``peak``), or None if the connection is gone."""
        if self.closed:
            return None
        self.closed = True
        try:
            result: dict[str, Any] = self.control.call("unsubscribe")
        except (OSError, ControlError):
            return None
        return result

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


__all__ = ["Control", "ControlError", "Subscription", "default_socket"]
