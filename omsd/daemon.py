"""The daemon: configuration → boards → links → endpoints, and its life cycle.

``Daemon.run`` brings every board up with its endpoints, prints one line per endpoint saying
where the board can be reached, tells systemd it is ready, and serves until SIGTERM or SIGINT;
then it stops accepting, closes its clients, removes its pty links and flushes the logs. SIGHUP
reopens the log file (logrotate) and the daemon goes on.

Before it creates anything it checks the places it is to create things in
(:func:`omsd.files.preflight`): a runtime directory another user could change, or a file at a
pty link's or the control socket's path that is not omsd's, is refused (:class:`StartupRefused`,
exit status 2) and nothing is served.
"""

from __future__ import annotations

import asyncio
import contextlib
import copy
import gc
import os
import signal
import socket
import ssl
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from omsd import sdnotify
from omsd.config import DaemonConfig, runtime_directory
from omsd.control.server import ControlServer, SocketInUse
from omsd.files import Refused, missing_directory, preflight, state_file_problem
from omsd.hostport import host_port
from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog
from omsd.transport import Endpoint
from omsd.transport.pty import PtyEndpoint
from omsd.transport.tcp import serve_tcp

if TYPE_CHECKING:
    from omsd.mqtt import MqttBridge
    from omsd.statefile import BoardFlash, StateFile
    from omsd.transport.serial import SerialEndpoint
    from omsd.web.server import WebServer


def same_terminal(a: TextIO, b: TextIO) -> bool:
    """Whether two streams are the same terminal (the daemon run by hand: its standard output
    and standard error on one screen)."""
    try:
        if not (a.isatty() and b.isatty()):
            return False
        return os.fstat(a.fileno()).st_rdev == os.fstat(b.fileno()).st_rdev
    except (OSError, ValueError, AttributeError):
        return False


def listen_error(exc: OSError) -> str:
    """Why a listening socket could not be made, in the system's words: asyncio's own message
    wraps them ("error while attempting to bind on address ..."), and a host name that does
    not resolve (``socket.gaierror``) carries a resolver's code where an errno would be, which
    ``os.strerror`` does not know ("unknown error -2")."""
    if isinstance(exc, socket.gaierror) or not exc.errno:
        return str(exc.strerror or exc)
    return os.strerror(exc.errno)


class StartupError(Exception):
    """The daemon cannot start: a port in use, a pty link or a state file that cannot be made,
    a directory that is missing. ``str()`` is one line naming what and why; ``status`` is the
    exit status the command line gives it: 2, like a configuration error, because starting
    again does not help (systemd's ``RestartPreventExitStatus=2`` stops there instead of
    looping). By the time it is raised, everything the daemon had opened is closed again."""

    status = 2


class StartupRefused(StartupError):
    """A place the daemon will not use: a runtime directory another user could change, a file
    at a pty link's or the control socket's path that is not omsd's (:mod:`omsd.files`)."""

    status = 2


class FlashSaver:
    """Writes the boards' flash (PCIx AP, ADH, ADL, PT) to the state file off the event loop,
    one save after another in the order the boards wrote, so a slow disk never delays a board
    and the file always ends with the last write. A failed save is logged (one line); the
    board goes on with the new values in memory."""

    def __init__(self, state: StateFile, log: TrafficLog) -> None:
        self.state = state
        self.log = log
        self._last: asyncio.Task[None] | None = None
        self._tasks: set[asyncio.Task[None]] = set()

    def writer(self, name: str) -> Callable[[dict[str, Any] | None, dict[int, str]], None]:
        from omsd.statefile import BoardFlash

        def write(defaults: dict[str, Any] | None, macros: dict[int, str]) -> None:
            self._queue(name, BoardFlash(copy.deepcopy(defaults), dict(macros)))

        return write

    def _queue(self, name: str, flash: BoardFlash) -> None:
        from omsd.statefile import StateFileError

        previous = self._last

        async def save() -> None:
            if previous is not None:
                with contextlib.suppress(BaseException):
                    await asyncio.shield(previous)
            try:
                await asyncio.to_thread(self.state.save_board, name, flash)
            except (StateFileError, ValueError, TypeError) as exc:
                self.log.error(str(exc))

        task = asyncio.get_running_loop().create_task(save())
        self._last = task
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def drain(self) -> None:
        """Wait for every save asked for so far."""
        while self._tasks:
            await asyncio.gather(*list(self._tasks), return_exceptions=True)


class Daemon:
    """The boards of ``config`` served. ``freeze``: the process is this daemon's (``omsd``'s
    command line), and what the start made is handed to ``gc.freeze()`` (see :meth:`start`)."""

    def __init__(
        self,
        config: DaemonConfig,
        log: TrafficLog,
        out: TextIO | None = None,
        *,
        freeze: bool = False,
    ) -> None:
        self.config = config
        self.log = log
        self.out = out if out is not None else sys.stdout
        self.freeze = freeze
        self.services: list[BoardService] = []
        self.servers: list[asyncio.Server] = []
        self.ptys: list[PtyEndpoint] = []
        self.serials: list[SerialEndpoint] = []
        self.endpoints: list[Endpoint] = []
        self._stop = asyncio.Event()
        self.ended = False  # run() has stopped everything and given the signals back
        self.saver: FlashSaver | None = None
        self.control: ControlServer | None = None
        self.mqtt: MqttBridge | None = None
        self.web: WebServer | None = None

    async def start(self) -> list[Endpoint]:
        # A fast path (issue 16: 1,000 boards ready within 2 s): a board is some thousand
        # objects, all kept as long as the daemon runs, and the cyclic garbage collector went
        # through all those made so far again and again while the boards were made (~0.5 s of
        # the start of 1,000 boards, and as long again in pauses once serving). It is paused
        # while the boards are made; in the daemon's own process (``freeze``, where omsd's
        # command line has paused it since it began) what the start made is then frozen
        # (gc.freeze: never scanned again, still freed when no longer referenced) and the
        # collector turned on.
        collecting = gc.isenabled()
        gc.disable()
        try:
            endpoints = await self._start()
        finally:
            if self.freeze:
                gc.freeze()
            if collecting or self.freeze:
                gc.enable()
        return endpoints

    async def _start(self) -> list[Endpoint]:
        loop = asyncio.get_running_loop()
        loop.set_exception_handler(self._loop_error)
        runtime = runtime_directory()
        made_runtime = not os.path.lexists(runtime)
        try:
            self._preflight()
            state = self._load_state()
        except BaseException:
            self._remove_made_directory(runtime, made_runtime)
            raise
        try:
            for board in self.config.boards:
                service = BoardService(board, loop, self.log)
                self.services.append(service)
                if state is not None and self.saver is not None:
                    self._attach_flash(service, state, self.saver)
                for tcp in board.tcp:
                    try:
                        server, host, port = await serve_tcp(
                            service, tcp.host, tcp.port, board.second_client, tcp.terminal
                        )
                    except OSError as exc:
                        reason = listen_error(exc)
                        raise StartupError(
                            f"{board.name}: cannot listen on tcp {tcp}: {reason.lower()}"
                        ) from None
                    self.servers.append(server)
                    self._announce(
                        Endpoint(board.name, board.model, board.link, "tcp", host_port(host, port))
                    )
                for pty in board.pty:
                    endpoint = PtyEndpoint(service, pty.link, pty.group, pty.mode, pty.terminal)
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
                await self._start_serial(service)
            await self._start_control()
            self._start_mqtt()
            await self._start_web()
            # the endpoint lines go out last: whoever reads them may use the control socket at
            # once, and a daemon that fails to start has announced nothing. On a terminal that
            # shows both standard output and the log, each endpoint is said once (the log file,
            # if any, still has it)
            view = not same_terminal(self.out, self.log.stream)
            for announced in self.endpoints:
                self.out.write(announced.line() + "\n")
                self.log.info(f"serving {announced.line()}", view=view)
            self.out.flush()
            self._say_what_is_not_served()
        except BaseException:
            await self.stop(quiet=True)
            self._remove_made_directory(runtime, made_runtime)
            raise
        return self.endpoints

    async def _start_serial(self, service: BoardService) -> None:
        """The board's serial devices (:mod:`omsd.transport.serial`) and RFC 2217 sockets
        (:mod:`omsd.transport.rfc2217`), imported for a board that has them."""
        board = service.config
        if board.serial_port:
            self._open_serial_ports(service)
        if board.rfc2217:
            await self._serve_rfc2217(service)

    def _open_serial_ports(self, service: BoardService) -> None:
        from omsd.pacing import Line
        from omsd.transport.serial import SerialEndpoint
        from omsd.transport.serial import reason as serial_reason

        board = service.config
        for serial in board.serial_port:
            line = Line(serial.baud, serial.bytesize, serial.parity, serial.stopbits)
            port = SerialEndpoint(service, serial.path, line, serial.flow, serial.pacing)
            try:
                address = port.open()
            except (OSError, ValueError) as exc:
                port.close()
                raise StartupError(
                    f"{board.name}: cannot open serial {serial.path}: {serial_reason(exc)}"
                ) from None
            self.serials.append(port)
            self._announce(Endpoint(board.name, board.model, board.link, "serial", address))

    async def _serve_rfc2217(self, service: BoardService) -> None:
        from omsd.transport.rfc2217 import serve_rfc2217

        board = service.config
        for rfc in board.rfc2217:
            try:
                server, host, port_number = await serve_rfc2217(
                    service, rfc.host, rfc.port, board.second_client, rfc.pacing
                )
            except OSError as exc:
                reason = listen_error(exc)
                raise StartupError(
                    f"{board.name}: cannot listen on rfc2217 {rfc}: {reason.lower()}"
                ) from None
            self.servers.append(server)
            self._announce(
                Endpoint(
                    board.name, board.model, board.link, "rfc2217", host_port(host, port_number)
                )
            )

    def _say_what_is_not_served(self) -> None:
        """``--tcp`` (or ``--pty``) alone replaces both default endpoints: say that no pty (no
        TCP port) is served, where a user expecting the default one will look (issue 14)."""
        board = self.config.boards[0]
        if self.config.source != "command line":
            return
        if board.tcp and not board.pty:
            self.log.info("no pty: --tcp given without --pty serves TCP only (add --pty PATH)")
        elif board.pty and not board.tcp:
            self.log.info(
                "no TCP: --pty given without --tcp serves the pty only (add --tcp [HOST:]PORT)"
            )

    @staticmethod
    def _remove_made_directory(path: Path, made: bool) -> None:
        """A start that failed leaves nothing behind: the runtime directory it made, if empty."""
        if made:
            with contextlib.suppress(OSError):
                path.rmdir()

    def _preflight(self) -> None:
        """Refuse, before anything is created, the places that are not omsd's to use, and those
        that cannot be used: a pty link whose directory is missing (omsd makes only its runtime
        directory), a state file that could not be read or saved."""
        runtime = runtime_directory()
        ptys = [(b.name, p.link) for b in self.config.boards for p in b.pty]
        for name, link in ptys:
            if not link.is_relative_to(runtime):
                problem = missing_directory(link.parent)
                if problem is not None:
                    raise StartupError(f"{name}: cannot create pty link {link}: {problem}")
        try:
            preflight(runtime, ptys, self.config.control.socket, self.config.state)
        except Refused as exc:
            raise StartupRefused(str(exc)) from None
        except OSError as exc:  # the runtime directory cannot be made, a path cannot be read
            reason = exc.strerror or str(exc)
            where = exc.filename or runtime
            raise StartupError(f"cannot use {where}: {reason}") from None
        if self.config.web is not None:
            import importlib.util

            if importlib.util.find_spec("aiohttp") is None:
                raise StartupError(
                    "the web dashboard needs aiohttp, which is not installed:"
                    " pip install 'omsd[web]'"
                )
        if self.config.state is not None:
            problem = state_file_problem(self.config.state)
            if problem is not None:
                raise StartupError(f"cannot use state file {self.config.state}: {problem}")

    async def _start_control(self) -> None:
        """The control endpoint: the Unix socket (owner-only), and TCP if configured. The
        default socket path held by another live omsd of this user costs a warning, not the
        start (that daemon keeps it); a configured one is an error."""
        config = self.config.control
        if config.socket is None and config.tcp is None:
            return
        services = {s.name: s for s in self.services}
        control = ControlServer(services, lambda: self.endpoints, self.log)
        self.control = control
        if config.socket is not None:
            try:
                await control.listen_unix(config.socket, config.group)
            except SocketInUse:
                if config.explicit:
                    raise StartupError(
                        f"control socket {config.socket} is in use by another process"
                    ) from None
                self.log.warning(
                    f"control socket {config.socket} is in use by another omsd; this one has"
                    " none (give it --control PATH)"
                )
            except OSError as exc:
                reason = exc.strerror or str(exc)
                raise StartupError(
                    f"cannot create control socket {config.socket}: {reason}"
                ) from None
            else:
                self.log.info(f"control socket {config.socket}")
        if config.tcp is not None:
            try:
                host, port = await control.listen_tcp(config.tcp.host, config.tcp.port)
            except OSError as exc:
                reason = listen_error(exc)
                raise StartupError(
                    f"cannot listen on control tcp {config.tcp}: {reason.lower()}"
                ) from None
            self.log.info(f"control tcp {host_port(host, port)}")

    def _start_mqtt(self) -> None:
        """The MQTT bridge (omsd.mqtt), if ``[mqtt]`` is configured, once the boards are up. It
        connects in the background: a broker that is down delays nothing here (issue 6: "A
        broker that is down or goes away never stops or slows the boards"). Its commands run
        through a ControlServer of their own, so they work with the control socket off."""
        config = self.config.mqtt
        if config is None:
            return
        from omsd.mqtt import MqttBridge  # a daemon without [mqtt] never loads the client

        services = {s.name: s for s in self.services}
        control = ControlServer(services, lambda: self.endpoints, self.log)
        try:
            bridge = MqttBridge(config, list(self.services), control, self.log)
        except (ssl.SSLError, OSError) as exc:
            raise StartupError(f"mqtt: cannot set up TLS with {config.tls}: {exc}") from None
        bridge.start()
        self.mqtt = bridge

    async def _start_web(self) -> None:
        """The web dashboard (omsd.web), if ``[web]`` or ``--web`` asks for it. Like the MQTT
        bridge it has a ControlServer of its own: it works with the control socket off."""
        config = self.config.web
        if config is None:
            return
        from omsd import __version__
        from omsd.web.server import WebServer  # a daemon without a dashboard never loads aiohttp

        services = {s.name: s for s in self.services}
        control = ControlServer(services, lambda: self.endpoints, self.log)
        web = WebServer(config, control, self.log, __version__)
        try:
            host, port = await web.start()
        except OSError as exc:
            reason = listen_error(exc)
            raise StartupError(
                f"cannot serve the web dashboard on {config.listen}: {reason.lower()}"
            ) from None
        self.web = web
        what = "control" if config.control else "read-only"
        token = "?token=..." if config.token is not None else ""
        self.log.info(f"web dashboard http://{host_port(host, port)}/{token} ({what})")

    def _load_state(self) -> StateFile | None:
        """The boards' flash: "a corrupt or missing state file gives the factory defaults and
        one clear log line"."""
        if self.config.state is None:
            return None
        from omsd.statefile import StateFile  # a daemon without a state file never loads it

        state = StateFile(self.config.state, self.config.state_group)
        result = state.load()
        if result.message is not None:
            (self.log.info if result.ok else self.log.warning)(result.message)
        self.saver = FlashSaver(state, self.log)
        return state

    @staticmethod
    def _attach_flash(service: BoardService, state: StateFile, saver: FlashSaver) -> None:
        """The board's flash from the state file; saved values that do not fit (a hand-edited
        file) are skipped, and said in one warning line."""
        board = service.board
        if service.model.dialect != "pcix":
            return  # the older boards keep nothing in flash
        flash = state.board(service.name)
        board.flash_defaults = flash.defaults
        board.flash_macros = dict(flash.macros)
        if not board.flash_matches():
            assert flash.defaults is not None
            service.log.warning(
                f"state file: board {service.name!r} was saved as a {flash.defaults.get('model')}"
                f", not a {service.model.name}; using factory defaults (AP replaces them)"
            )
        problems = board.load_flash()
        if problems:
            n = len(problems)
            service.log.warning(
                f"state file {state.path}: board {service.name!r}: ignored {n} saved"
                f" value{'s' * (n > 1)} that {'do' if n > 1 else 'does'} not fit, using the"
                f" factory value{'s' * (n > 1)}: {'; '.join(problems)}"
            )
        board.flash_writer = saver.writer(service.name)

    def _announce(self, endpoint: Endpoint) -> None:
        self.endpoints.append(endpoint)

    async def run(self) -> None:
        """Serve until SIGTERM/SIGINT (or :meth:`request_stop`)."""
        loop = asyncio.get_running_loop()
        # handlers first: a signal that comes as soon as the endpoints are announced must still
        # stop the daemon cleanly. They are unblocked: a parent that blocks them (a supervisor,
        # a thread) passes its mask on across exec, and the daemon would never see them
        signals = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
        previous = {sig: signal.getsignal(sig) for sig in signals}
        for sig in (signal.SIGTERM, signal.SIGINT):
            loop.add_signal_handler(sig, self.request_stop)
        loop.add_signal_handler(signal.SIGHUP, self.reopen_logs)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, signals)
        try:
            await self.start()  # on failure it has already cleaned up, quietly
            sdnotify.ready(f"serving {len(self.endpoints)} endpoint(s)")
            # while serving, the view's lines are written in batches, off the reply path
            self.log.batch_view(loop)
            try:
                await self._stop.wait()
            finally:
                self.log.unbatch_view()
                sdnotify.stopping()
                await self.stop()
        finally:
            # the handlers from before the loop's again (omsd.cli's for SIGTERM and SIGINT,
            # which ignore a signal once ``ended``), not the defaults remove_signal_handler
            # leaves: a SIGTERM while the process ends is a clean stop too
            # (blocked meanwhile: remove_signal_handler puts the default action in place, and
            # a SIGTERM or SIGINT in between killed omsd or raised KeyboardInterrupt)
            self.ended = True
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, signals)
            try:
                for sig in signals:
                    loop.remove_signal_handler(sig)
                    if previous[sig] is not None:
                        signal.signal(sig, previous[sig])
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)

    def reopen_logs(self) -> None:
        """SIGHUP: open the log file again (after logrotate renamed it, a new one), and say so.
        The daemon goes on serving. Standard error is not reopened: it is whatever the daemon
        was started with (the journal under systemd)."""
        path = self.log.path
        if path is None:
            self.log.info("SIGHUP: no log file to reopen")
        elif self.log.reopen():
            self.log.info(f"reopened log files on SIGHUP: {path}")

    def request_stop(self) -> None:
        self._stop.set()

    async def stop(self, quiet: bool = False) -> None:
        if self.mqtt is not None:  # first: "offline" goes out while the boards still run
            await self.mqtt.stop()
            self.mqtt = None
        if self.web is not None:
            await self.web.close()
            self.web = None
        if self.control is not None:
            await self.control.close()
            self.control = None
        for server in self.servers:
            server.close()
        for service in self.services:
            for client in list(service.clients):
                close = getattr(client, "close", None)
                if close is not None and not isinstance(client, PtyEndpoint):
                    close()
        for pty in self.ptys:
            pty.close()
        for serial in self.serials:
            serial.close()
        for server in self.servers:
            with contextlib.suppress(Exception):
                await asyncio.wait_for(server.wait_closed(), timeout=2.0)
        for service in self.services:
            service.close()
        if self.saver is not None:
            await self.saver.drain()
        self.servers.clear()
        self.ptys.clear()
        self.serials.clear()
        self.services.clear()
        if not quiet:
            self.log.info("stopped")

    def _loop_error(self, loop: asyncio.AbstractEventLoop, context: dict[str, Any]) -> None:
        exc = context.get("exception")
        message = context.get("message", "error in event loop")
        self.log.error(f"{message}: {exc!r}" if exc is not None else str(message))
