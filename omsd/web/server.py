"""The web dashboard's server (issue 18): one page, its files, and a WebSocket that speaks the
control protocol.

Off unless configured (``[web]``, ``--web``). It serves:

* ``/``: the page (``static/index.html``); its script, styles and the vendored uPlot under
  ``/static/`` (package data: no CDN, no build step);
* ``/ws``: a WebSocket on which the page is a control connection like ``omsd ctl``'s
  (:mod:`omsd.control.protocol`): each text frame from the page is one request (a binary frame
  gets an error line, :data:`BINARY`), each frame to it one or more JSON lines (replies, and
  the ``subscribe`` stream of :mod:`omsd.control.watch`, bounded as it is for the socket). The
  first frame says what the page may do: ``{"kind": "hello", "control": false, "version":
  "0.1.0", "boards": [...]}``. Without ``control = true`` only the ops of
  :data:`omsd.control.protocol.READ_ONLY_OPS` are answered (the others get an error reply).

Guards. The server listens on loopback unless another address is configured, and a token is
then required (the configuration refuses one without). With a token, ``/`` and ``/ws`` answer
only a request that gives it (``?token=...``; compared in constant time); the page passes it on
to its WebSocket. ``/ws`` also refuses a request whose ``Origin`` is not the page's own (another
site open in the same browser must not drive the boards), and on loopback one whose ``Host`` is
not a loopback name (DNS rebinding). Everything refused gets a one-line reason.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import importlib.resources
import json
import logging
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

from omsd.config import WebConfig, is_loopback
from omsd.control.protocol import MAX_LINE, READ_ONLY_OPS, encode
from omsd.control.server import ControlServer
from omsd.telemetry.traffic import TrafficLog
from omsd.transport import bound_address

STATIC = importlib.resources.files("omsd.web") / "static"
"""The page's files (package data)."""

POLICY = (
    "default-src 'self'; connect-src 'self'; img-src 'self' data:; style-src 'self';"
    " script-src 'self'; object-src 'none'; base-uri 'none'; frame-ancestors 'none'"
)
"""The page's Content-Security-Policy: its own files only (no inline script, nothing from
elsewhere), and not to be framed by another site."""

COALESCE = 0.05
"""Seconds what is written to a page may wait for more to go with it in one frame."""

COALESCE_BYTES = 64 * 1024
"""Bytes waiting for a page above which they go at once, and its writers wait for them."""

HEARTBEAT = 20.0
"""Seconds between WebSocket pings: a page that has gone (a laptop closed) is noticed."""

BINARY = "a binary frame: send each request as a text frame of JSON"
"""The error line a binary frame gets (the protocol is JSON text): a client that sent its
request as bytes waited for ever for a reply when the frame was dropped without a word."""

MAX_CONNECTIONS = 64
"""Connections the dashboard holds at once; a newcomer beyond them is told so and closed. A
browser opens six at most to one server, so this is many pages. Without a bound, anyone who
could reach the port (a token is asked for only once a request is made) could hold every file
descriptor of the daemon, and its boards could take no client."""

HEAD_TIMEOUT = 10.0
"""Seconds a new connection has to send its first request's head (the request line and the
headers), and a kept-alive one its next head after the last answer (aiohttp's
``keepalive_timeout``, 75 s or an hour by default): a client that sends a byte a second
(slowloris) is closed, not kept for ever. A WebSocket, once open, is not cut."""

BUSY = (
    b"HTTP/1.1 503 Service Unavailable\r\nContent-Type: text/plain; charset=utf-8\r\n"
    b"Connection: close\r\nContent-Length: 49\r\n\r\n"
    b"omsd: the dashboard has too many connections now\n"
)
"""What a connection beyond :data:`MAX_CONNECTIONS` is told before it is closed."""


class _OneLine(logging.Handler):
    """aiohttp's own complaints (a request it could not parse, a handler that raised: its
    ``aiohttp.server`` logger's ``exception``) as one line each in the daemon's log, instead of
    a traceback on standard error, past the log and its view (Python's last-resort handler)."""

    def __init__(self, log: TrafficLog) -> None:
        super().__init__(logging.WARNING)
        self.log = log

    def emit(self, record: logging.LogRecord) -> None:
        text = record.getMessage()
        exc = record.exc_info[1] if record.exc_info else None
        if exc is not None:
            reason = getattr(exc, "message", None) or str(exc) or type(exc).__name__
            text = f"{text}: {reason}"
        line = " ".join(str(text).split())
        self.log.warning(f"web dashboard: {line[:300]}")


_AIOHTTP = logging.getLogger("aiohttp")
"""The parent of aiohttp's loggers (``aiohttp.server``, ``aiohttp.websocket``...)."""


class SocketWriter:
    """A control connection's :class:`omsd.control.protocol.Writer` on a WebSocket.

    What is written goes out in one text frame at most :data:`COALESCE` seconds later, with
    whatever else was written meanwhile: a page that watches 8 moving boards would otherwise get
    a frame, a send and a wake-up of the browser for every event and every chunk of traffic
    (some 35 a second in ``bench/web.py``; coalesced, at most 20). ``drain`` waits only when
    :data:`COALESCE_BYTES` are waiting (or a frame is on its way and more than that is): a page
    that reads slowly holds up its own subscription, whose queue is bounded
    (:mod:`omsd.control.watch`), and nothing else."""

    def __init__(self, socket: web.WebSocketResponse) -> None:
        self.socket = socket
        self._pending: list[bytes] = []
        self._size = 0
        self._flushing: asyncio.Task[None] | None = None

    def write(self, data: bytes) -> None:
        self._pending.append(data)
        self._size += len(data)

    async def drain(self) -> None:
        if not self._pending or self.socket.closed:
            return
        if self._flushing is None or self._flushing.done():
            self._flushing = asyncio.get_running_loop().create_task(self._flush())
        if self._size >= COALESCE_BYTES:
            await asyncio.shield(self._flushing)

    async def _flush(self) -> None:
        if self._size < COALESCE_BYTES:
            await asyncio.sleep(COALESCE)
        try:
            while self._pending and not self.socket.closed:
                data = b"".join(self._pending)
                self._pending.clear()
                self._size = 0
                # send_str waits while the transport is above its high-water mark
                await self.socket.send_str(data.decode())
        except (ConnectionError, RuntimeError):
            self._pending.clear()  # the page has gone: the handler's loop ends and cleans up
            self._size = 0

    def is_closing(self) -> bool:
        return self.socket.closed

    def close(self) -> None:
        self._pending.clear()
        self._size = 0
        if self._flushing is not None:
            self._flushing.cancel()


class WebServer:
    """The dashboard for the boards of ``control``: the page's requests are its operations and
    its subscriptions. The daemon gives the dashboard a control server of its own, which
    :meth:`close` closes."""

    def __init__(
        self, config: WebConfig, control: ControlServer, log: TrafficLog, version: str
    ) -> None:
        self.config = config
        self.control = control
        self.log = log
        self.version = version
        self.runner: web.AppRunner | None = None
        self.sockets: set[web.WebSocketResponse] = set()
        self.address: tuple[str, int] | None = None
        self._handler: _OneLine | None = None
        self._listener: asyncio.Server | None = None

    def _protocol(self) -> asyncio.BaseProtocol:
        """A new connection's protocol: aiohttp's, with a deadline for its first request's head
        (:data:`HEAD_TIMEOUT`); beyond :data:`MAX_CONNECTIONS`, one that says so and closes."""
        assert self.runner is not None and self.runner.server is not None
        server = self.runner.server
        if len(server.connections) >= MAX_CONNECTIONS:
            return _Busy()
        handler = server()
        asyncio.get_running_loop().call_later(HEAD_TIMEOUT, _head_deadline, handler)
        return handler

    async def start(self) -> tuple[str, int]:
        """Listen; returns the host and port (the port the system chose for port 0). An
        address that cannot be used raises ``OSError``."""
        app = web.Application(client_max_size=MAX_LINE)
        app.router.add_get("/", self._page)
        # the page is a file of static/ too: under that name it has the page's guards (the
        # token), not only the static files' (it works there: its files are named from /)
        app.router.add_get("/static/index.html", self._page)
        app.router.add_get("/ws", self._socket)
        app.router.add_static("/static/", str(STATIC), follow_symlinks=False)
        app.on_response_prepare.append(_guard_headers)
        self._handler = _OneLine(self.log)
        _AIOHTTP.addHandler(self._handler)
        _AIOHTTP.propagate = False
        runner = web.AppRunner(
            app, access_log=None, handle_signals=False, keepalive_timeout=HEAD_TIMEOUT
        )
        await runner.setup()
        self.runner = runner
        try:
            loop = asyncio.get_running_loop()
            self._listener = await loop.create_server(
                self._protocol, self.config.listen.host, self.config.listen.port
            )
            host, port = bound_address(self._listener, self.config.listen.host)
        except BaseException:
            await self.close()
            raise
        self.address = (host, port)
        return host, port

    async def close(self) -> None:
        listener, self._listener = self._listener, None
        if listener is not None:
            listener.close()
        for socket in list(self.sockets):
            with contextlib.suppress(Exception):
                await socket.close()
        runner, self.runner = self.runner, None
        if runner is not None:
            await runner.cleanup()
        if self._handler is not None:
            _AIOHTTP.removeHandler(self._handler)
            _AIOHTTP.propagate = not _AIOHTTP.handlers
            self._handler = None
        await self.control.close()  # the dashboard's own control server: its subscriptions

    # -- guards ---------------------------------------------------------------------------------

    def _refusal(self, request: web.Request, websocket: bool) -> str | None:
        """Why ``request`` is refused, or None."""
        token = self.config.token
        if token is not None:
            given = request.query.get("token", "")
            if not hmac.compare_digest(given.encode(), token.encode()):
                return "this dashboard needs its token: open it as /?token=..."
        if self.config.loopback:
            host = _host_name(f"//{request.host}")
            if host is None or not is_loopback(host):
                return f"Host {request.host!r} is not this machine (the dashboard is on loopback)"
        if websocket:
            origin = request.headers.get("Origin")
            if origin is not None and _netloc(origin) != request.host:
                return f"Origin {origin!r} is not this dashboard's"
        return None

    # -- handlers -------------------------------------------------------------------------------

    async def _page(self, request: web.Request) -> web.StreamResponse:
        refusal = self._refusal(request, websocket=False)
        if refusal is not None:
            return web.Response(status=403, text=f"omsd: {refusal}\n")
        page = (STATIC / "index.html").read_bytes()
        return web.Response(
            body=page,
            content_type="text/html",
            charset="utf-8",
            headers={"Cache-Control": "no-store"},
        )

    async def _socket(self, request: web.Request) -> web.StreamResponse:
        refusal = self._refusal(request, websocket=True)
        if refusal is not None:
            return web.Response(status=403, text=f"omsd: {refusal}\n")
        # no permessage-deflate: the page is near (loopback, a LAN), and compressing every frame
        # would cost the daemon more than the bytes it saves
        socket = web.WebSocketResponse(heartbeat=HEARTBEAT, max_msg_size=MAX_LINE, compress=False)
        await socket.prepare(request)
        self.sockets.add(socket)
        writer = SocketWriter(socket)
        lock = asyncio.Lock()
        allowed = None if self.config.control else READ_ONLY_OPS
        try:
            hello = {
                "kind": "hello",
                "control": self.config.control,
                "version": self.version,
                "boards": list(self.control.services),
            }
            async with lock:
                await socket.send_str(json.dumps(hello) + "\n")
            async for message in socket:
                if message.type is WSMsgType.TEXT:
                    line = message.data.encode()
                    if line.strip():
                        self.control.request(line, writer, lock, allowed)
                        await self.control.backlog(writer)
                elif message.type is WSMsgType.BINARY:  # not the protocol's: said, not dropped
                    async with lock:
                        writer.write(encode({"id": None, "ok": False, "error": BINARY}))
                        await writer.drain()
                elif message.type is WSMsgType.ERROR:
                    break
        except ConnectionError:
            pass
        finally:
            self.sockets.discard(socket)
            self.control.forget(writer)
            with contextlib.suppress(Exception):
                await socket.close()
        return socket


GUARD_HEADERS = {
    "Content-Security-Policy": POLICY,
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}
"""The headers of every answer, the page's and its files' (a file served without them, the
page under /static/index.html, could be framed by another site)."""


async def _guard_headers(request: web.Request, response: web.StreamResponse) -> None:
    for name, value in GUARD_HEADERS.items():
        response.headers.setdefault(name, value)


class _Busy(asyncio.Protocol):
    """A connection beyond :data:`MAX_CONNECTIONS`: told so, and closed."""

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        transport.write(BUSY)
        transport.close()


def _head_deadline(handler: web.RequestHandler) -> None:
    """Close ``handler``'s connection if no request head has come on it yet (aiohttp counts
    the heads it has parsed in ``_request_count``)."""
    transport = handler.transport
    if transport is not None and getattr(handler, "_request_count", 1) == 0:
        transport.close()


def _host_name(url: str) -> str | None:
    """The host name of ``url``; None for what is no URL's (``//[::1``: urlsplit raises)."""
    try:
        return urlsplit(url).hostname
    except ValueError:
        return None


def _netloc(url: str) -> str | None:
    """The ``host:port`` of ``url``; None for what is no URL's."""
    try:
        return urlsplit(url).netloc
    except ValueError:
        return None


__all__ = ["STATIC", "SocketWriter", "WebServer"]
