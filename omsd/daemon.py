"""The daemon: configuration → boards → links → endpoints, and its life cycle.

``Daemon.run`` brings every board up with its endpoints, prints one line per endpoint saying
where the board can be reached, tells systemd it is ready, and serves until SIGTERM or SIGINT;
then it stops accepting, closes its clients, removes its pty links and flushes the logs.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import sys
from dataclasses import dataclass
from typing import Any, TextIO

from omsd import sdnotify
from omsd.config import DaemonConfig
from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog
from omsd.transport.pty import PtyEndpoint
from omsd.transport.tcp import serve_tcp


class StartupError(Exception):
    """A board could not be brought up (a port in use, a pty link that cannot be made)."""


@dataclass(frozen=True)
class Endpoint:
    board: str
    model: str
    link: str
    kind: str  # "tcp" or "pty"
    address: str  # "127.0.0.1:7048" or "/run/omsd/board1 -> /dev/pts/3"

    def line(self) -> str:
        return f"{self.board} {self.model} {self.link} {self.kind} {self.address}"


class Daemon:
    def __init__(self, config: DaemonConfig, log: TrafficLog, out: TextIO | None = None) -> None:
        self.config = config
        self.log = log
        self.out = out if out is not None else sys.stdout
        self.services: list[BoardService] = []
        self.servers: list[asyncio.Server] = []
        self.ptys: list[PtyEndpoint] = []
        self.endpoints: list[Endpoint] = []
        self._stop = asyncio.Event()

    async def start(self) -> list[Endpoint]:
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(self._loop_error)
        try:
            for board in self.config.boards:
                service = BoardService(board, loop, self.log)
                self.services.append(service)
                for tcp in board.tcp:
                    try:
                        server, host, port = await serve_tcp(
                            service, tcp.host, tcp.port, board.second_client
                        )
                    except OSError as exc:
                        reason = os.strerror(exc.errno) if exc.errno else str(exc)
                        raise StartupError(
                            f"{board.name}: cannot listen on tcp {tcp}: {reason.lower()}"
                        ) from None
                    self.servers.append(server)
                    self._announce(
                        Endpoint(board.name, board.model, board.link, "tcp", f"{host}:{port}")
                    )
                for pty in board.pty:
                    endpoint = PtyEndpoint(service, pty.link, pty.group, pty.mode)
                    try:
                        device = endpoint.open()
                    except (OSError, KeyError) as exc:
                        if isinstance(exc, OSError):
                            reason = exc.strerror or str(exc)
                        else:
                            reason = f"no group {exc}"
                        raise StartupError(
                            f"{board.name}: cannot create pty {pty.link}: {reason}"
                        ) from None
                    self.ptys.append(endpoint)
                    self._announce(
                        Endpoint(
                            board.name, board.model, board.link, "pty", f"{pty.link} -> {device}"
                        )
                    )
        except BaseException:
            await self.stop(quiet=True)
            raise
        return self.endpoints

    def _announce(self, endpoint: Endpoint) -> None:
        self.endpoints.append(endpoint)
        self.out.write(endpoint.line() + "\n")
        self.out.flush()
        self.log.info(f"serving {endpoint.line()}")

    async def run(self) -> None:
        """Serve until SIGTERM/SIGINT (or :meth:`request_stop`)."""
        loop = asyncio.get_running_loop()
        # handlers first: a signal that comes as soon as the endpoints are announced must still
        # stop the daemon cleanly
        for sig in (signal.SIGTERM, signal.SIGINT):
            loop.add_signal_handler(sig, self.request_stop)
        try:
            await self.start()  # on failure it has already cleaned up, quietly
            sdnotify.ready(f"serving {len(self.endpoints)} endpoint(s)")
            try:
                await self._stop.wait()
            finally:
                sdnotify.stopping()
                await self.stop()
        finally:
            for sig in (signal.SIGTERM, signal.SIGINT):
                loop.remove_signal_handler(sig)

    def request_stop(self) -> None:
        self._stop.set()

    async def stop(self, quiet: bool = False) -> None:
        for server in self.servers:
            server.close()
        for service in self.services:
            for client in list(service.clients):
                close = getattr(client, "close", None)
                if close is not None and not isinstance(client, PtyEndpoint):
                    close()
        for pty in self.ptys:
            pty.close()
        for server in self.servers:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(server.wait_closed(), timeout=2.0)
        for service in self.services:
            service.close()
        self.servers.clear()
        self.ptys.clear()
        self.services.clear()
        if not quiet:
            self.log.info("stopped")

    def _loop_error(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        exc = context.get("exception")
        message = context.get("message", "error in event loop")
        self.log.error(f"{message}: {exc!r}" if exc is not None else str(message))
