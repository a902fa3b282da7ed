"""The web dashboard's server (omsd.web.server, issue 18), without a browser: its guards (token,
Host, Origin), the WebSocket as a control connection (read-only unless ``control``), the
subscription stream on it (live while a move runs, nothing while idle), and its clean-up when
a page goes.

The daemon runs in-process (omsd.daemon.Daemon on the test's event loop) with the dashboard on
a free port; the client is aiohttp's. The page itself is tested in Chromium
(tests/web/test_browser.py).
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import socket
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import aiohttp
import pytest

from omsd.board.world import AxisWorld
from omsd.config import BoardConfig, ControlConfig, DaemonConfig, TcpEndpoint, WebConfig
from omsd.control.protocol import READ_ONLY_OPS
from omsd.daemon import Daemon, StartupError
from omsd.telemetry.traffic import TrafficLog
from omsd.web.server import STATIC, WebServer

WAIT = 5.0
TOKEN = "s3cret-token-0123456789"


@dataclass
class Dash:
    daemon: Daemon
    url: str
    ports: dict[str, int]
    log: io.StringIO

    @property
    def web(self) -> WebServer:
        assert self.daemon.web is not None
        return self.daemon.web


@contextlib.asynccontextmanager
async def dashboard(
    tmp_path: Path, *, control: bool = False, token: str | None = None
) -> AsyncIterator[Dash]:
    world = {"X": AxisWorld(negative_limit=-30_000, positive_limit=30_000)}
    boards = (
        BoardConfig(name="xy", world=world, tcp=(TcpEndpoint("127.0.0.1", 0),)),
        BoardConfig(name="servo", model="PCIX-400", link="raw", tcp=(TcpEndpoint("127.0.0.1", 0),)),
    )
    config = DaemonConfig(
        boards=boards,
        control=ControlConfig(socket=None, explicit=True),
        web=WebConfig(TcpEndpoint("127.0.0.1", 0), control, token),
    )
    log = io.StringIO()
    daemon = Daemon(config, TrafficLog("plain", stream=log), out=io.StringIO())
    endpoints = await daemon.start()
    ports = {e.board: int(e.address.rsplit(":", 1)[1]) for e in endpoints if e.kind == "tcp"}
    assert daemon.web is not None and daemon.web.address is not None
    host, port = daemon.web.address
    try:
        yield Dash(daemon, f"http://{host}:{port}", ports, log)
    finally:
        await daemon.stop()
    assert " error: " not in log.getvalue(), log.getvalue()


class Page:
    """A page's WebSocket: requests out, JSON lines in."""

    def __init__(self, socket: aiohttp.ClientWebSocketResponse) -> None:
        self.socket = socket
        self.lines: list[dict[str, Any]] = []
        self.ids = iter(range(1, 1_000_000))
        self.frames = 0

    async def next(self, timeout: float = WAIT) -> dict[str, Any] | None:
        while not self.lines:
            try:
                frame = await asyncio.wait_for(self.socket.receive(), timeout)
            except TimeoutError:
                return None
            if frame.type is not aiohttp.WSMsgType.TEXT:
                return None
            self.frames += 1
            self.lines.extend(json.loads(line) for line in frame.data.splitlines() if line)
        return self.lines.pop(0)

    async def ask(self, op: str, **args: Any) -> dict[str, Any]:
        ident = next(self.ids)
        await self.socket.send_str(json.dumps({"id": ident, "op": op, **args}))
        deadline = time.monotonic() + WAIT
        while True:
            message = await self.next(max(0.0, deadline - time.monotonic()))
            assert message is not None, f"no reply to {op}"
            if message.get("id") == ident and "ok" in message:
                return message

    async def until(self, check: Any, timeout: float = WAIT) -> list[dict[str, Any]]:
        got = []
        deadline = time.monotonic() + timeout
        while True:
            message = await self.next(max(0.0, deadline - time.monotonic()))
            assert message is not None, f"not seen in {timeout} s; got {got[-3:]}"
            got.append(message)
            if check(message):
                return got


@contextlib.asynccontextmanager
async def page(dash: Dash, query: str = "") -> AsyncIterator[Page]:
    async with (
        aiohttp.ClientSession() as session,
        session.ws_connect(f"{dash.url}/ws{query}") as socket,
    ):
        yield Page(socket)


async def board_says(port: int, command: bytes, until: bytes = b"\n") -> bytes:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write(command)
        return await asyncio.wait_for(reader.readuntil(until), WAIT)
    finally:
        writer.close()


# -- what is served -------------------------------------------------------------------------------


async def test_the_page_its_files_and_the_vendored_chart_library_are_served(
    tmp_path: Path,
) -> None:
    async with dashboard(tmp_path) as dash, aiohttp.ClientSession() as session:
        async with session.get(f"{dash.url}/") as response:
            assert response.status == 200
            assert response.content_type == "text/html"
            assert await response.read() == (STATIC / "index.html").read_bytes()
            assert "default-src 'self'" in response.headers["Content-Security-Policy"]
        for name in ("vendor/uPlot.iife.min.js", "vendor/uPlot.min.css", "app.js", "style.css"):
            async with session.get(f"{dash.url}/static/{name}") as response:
                assert response.status == 200, name
                assert await response.read() == (STATIC / name).read_bytes()
        async with session.get(f"{dash.url}/static/../server.py") as response:
            assert response.status in (403, 404)


async def test_the_page_under_static_has_the_pages_guards(tmp_path: Path) -> None:
    """/static/index.html served the whole working page (its script and styles are named from
    the root) without the token, without the Content-Security-Policy and its frame-ancestors
    'none': another site could frame it and have the user click its buttons (the page in the
    frame is the dashboard's own origin, so its WebSocket passed the Origin check). Every file
    now goes with the page's headers, and the page under that name asks for the token too."""
    async with (
        dashboard(tmp_path, token=TOKEN) as dash,
        aiohttp.ClientSession() as session,
    ):
        async with session.get(f"{dash.url}/static/index.html") as response:
            assert response.status == 403
            assert "token" in await response.text()
        async with session.get(f"{dash.url}/static/index.html?token={TOKEN}") as response:
            assert response.status == 200
            assert "frame-ancestors 'none'" in response.headers["Content-Security-Policy"]
        for name in ("app.js", "style.css", "vendor/uPlot.iife.min.js", "nonexistent"):
            async with session.get(f"{dash.url}/static/{name}") as response:
                assert "frame-ancestors 'none'" in response.headers["Content-Security-Policy"]
                assert response.headers["X-Content-Type-Options"] == "nosniff"


def test_the_page_loads_nothing_from_elsewhere() -> None:
    """Works offline: no CDN, no URL to another host in the page or its own files."""
    for name in ("index.html", "app.js", "style.css"):
        text = (STATIC / name).read_text()
        assert "http://" not in text and "https://" not in text and "//cdn" not in text, name


# -- guards ---------------------------------------------------------------------------------------


async def test_a_token_is_asked_for_by_the_page_and_its_socket(tmp_path: Path) -> None:
    async with (
        dashboard(tmp_path, token=TOKEN) as dash,
        aiohttp.ClientSession() as session,
    ):
        for query in ("", "?token=wrong", f"?token={TOKEN[:-1]}"):
            async with session.get(f"{dash.url}/{query}") as response:
                assert response.status == 403
                assert "token" in await response.text()
            async with session.get(f"{dash.url}/ws{query}") as response:
                assert response.status == 403
        async with session.get(f"{dash.url}/?token={TOKEN}") as response:
            assert response.status == 200
        async with page(dash, f"?token={TOKEN}") as p:
            hello = await p.next()
            assert hello is not None and hello["kind"] == "hello"


async def test_another_sites_page_and_a_rebound_host_name_are_refused(tmp_path: Path) -> None:
    """A page of another site open in the same browser must not reach the boards (Origin), nor
    a host name rebound to 127.0.0.1 (Host)."""
    async with dashboard(tmp_path, control=True) as dash, aiohttp.ClientSession() as session:
        bad_origin = {"Origin": "http://evil.example"}
        async with session.get(f"{dash.url}/ws", headers=bad_origin) as response:
            assert response.status == 403
            assert "Origin" in await response.text()
        port = dash.url.rsplit(":", 1)[1]
        async with session.get(f"{dash.url}/", headers={"Host": f"evil.example:{port}"}) as r:
            assert r.status == 403
        own = {"Origin": dash.url}
        async with session.ws_connect(f"{dash.url}/ws", headers=own) as socket:
            hello = json.loads((await socket.receive()).data)
            assert hello["control"] is True
        localhost = dash.url.replace("127.0.0.1", "localhost")
        async with session.get(f"{dash.url}/", headers={"Host": localhost[7:]}) as response:
            assert response.status == 200


async def test_read_only_unless_control_is_on(tmp_path: Path) -> None:
    async with dashboard(tmp_path) as dash, page(dash) as p:
        hello = await p.next()
        assert hello == {
            "kind": "hello",
            "control": False,
            "version": hello["version"],
            "boards": ["xy", "servo"],
        }
        for op, args in (
            ("limit", {"board": "xy", "axis": "X", "direction": 1, "active": True}),
            ("reset", {"board": "xy"}),
            ("time", {"board": "xy", "action": "pause"}),
        ):
            reply = await p.ask(op, **args)
            assert reply["ok"] is False and "only watch" in reply["error"]
        state = dash.daemon.services[0].board.snapshot(dash.daemon.services[0].clock())
        assert state["axes"]["X"]["limit_positive"] is False
        for op in READ_ONLY_OPS[:2]:
            assert (await p.ask(op, board="xy"))["ok"] is True


async def test_a_binary_frame_gets_a_one_line_error_not_silence(tmp_path: Path) -> None:
    """The protocol is JSON text (one request a text frame). A binary frame, a JSON request
    sent as bytes included, was dropped without a word, and a client waiting for its reply
    waited for ever. Now it gets one error line, and the socket goes on."""
    async with dashboard(tmp_path) as dash, page(dash) as p:
        assert (await p.next() or {})["kind"] == "hello"
        await p.socket.send_bytes(b'{"id":1,"op":"boards"}')
        reply = await p.next()
        assert reply == {
            "id": None,
            "ok": False,
            "error": "a binary frame: send each request as a text frame of JSON",
        }
        assert (await p.ask("boards"))["ok"] is True


async def test_with_control_the_page_acts_like_omsd_ctl(tmp_path: Path) -> None:
    async with dashboard(tmp_path, control=True) as dash, page(dash) as p:
        assert (await p.next() or {})["control"] is True
        reply = await p.ask("limit", board="xy", axis="X", direction=1, active=True)
        assert reply["ok"] is True
        assert await board_says(dash.ports["xy"], b"AX RA", b"N\n") == b"PNLN\n"
        await p.ask("stall", board="xy", axis="Y", stalled=True)
        await p.ask("home", board="xy", axis="Z", active=False)
        world = (await p.ask("state", board="xy"))["result"]["world"]
        assert world == {
            "limits": {"X": [None, True]},
            "home": {"Z": False},
            "stalled": ["Y"],
            "inputs": {},
        }
        reply = await p.ask("limit", board="xy", axis="X", direction=1, active=None)
        assert reply["ok"] is True
        assert await board_says(dash.ports["xy"], b"AX RA", b"N\n") == b"PNNN\n"


async def test_a_number_beyond_a_doubles_range_is_answered_and_nothing_runs(
    tmp_path: Path,
) -> None:
    """json reads 1e999 as infinity: the limit closed, the reply echoing the id could not be
    written, none came, and the log said 'Task exception was never retrieved'."""
    async with dashboard(tmp_path, control=True) as dash, page(dash) as p:
        assert (await p.next() or {})["control"] is True
        await p.socket.send_str(
            '{"id":1e999,"op":"limit","board":"xy","axis":"X","direction":1,"active":true}'
        )
        assert await p.next() == {
            "id": None,
            "ok": False,
            "error": "not a JSON object: 1e999 is beyond a float's range",
        }
        state = dash.daemon.services[0].board.snapshot(dash.daemon.services[0].clock())
        assert state["axes"]["X"]["limit_positive"] is False


# -- the stream -----------------------------------------------------------------------------------


async def test_a_move_streams_at_the_rate_and_an_idle_daemon_sends_nothing(tmp_path: Path) -> None:
    async with dashboard(tmp_path) as dash, page(dash) as p:
        await p.next()
        reply = await p.ask("subscribe", rate=20, traffic="xy")
        snapshot = reply["result"]
        assert [b["name"] for b in snapshot["boards"]] == ["xy", "servo"]
        xy = snapshot["boards"][0]
        assert xy["switches"]["X"] == {"home": [1000.0, 1100.0], "limits": [-30000.0, 30000.0]}
        assert xy["switches"]["Y"] == {"home": [1000.0, 1100.0]}
        assert await p.next(0.5) is None  # idle: nothing
        _, writer = await asyncio.open_connection("127.0.0.1", dash.ports["xy"])
        try:
            writer.write(b"AX VL20000 AC200000 MR20000 GO ID")
            start = time.monotonic()
            got = await p.until(lambda m: m.get("kind") == "event" and m["event"]["kind"] == "done")
            took = time.monotonic() - start
        finally:
            writer.close()
        states = [m for m in got if m.get("kind") == "state" and "xy" in m["boards"]]
        positions = [
            m["boards"]["xy"]["axes"]["X"]["position"]
            for m in states
            if "position" in m["boards"]["xy"].get("axes", {}).get("X", {})
        ]
        assert positions == sorted(positions) and len(positions) >= 10 * took - 3
        traffic = [m["traffic"] for m in got if m.get("kind") == "traffic"]
        assert traffic and traffic[0]["dir"] == "in" and traffic[0]["board"] == "xy"
        # the board's client has gone (the finally above): the page is told, then nothing more
        await p.until(
            lambda m: m.get("kind") == "state" and m["boards"].get("xy", {}).get("clients") == []
        )
        assert await p.next(0.6) is None  # idle again: nothing


async def test_a_page_that_goes_leaves_nothing_behind(tmp_path: Path) -> None:
    async with dashboard(tmp_path) as dash:
        for _ in range(3):
            async with page(dash) as p:
                await p.next()
                await p.ask("subscribe", traffic=True)
                web_control = dash.web.control
                assert len(web_control.subscriptions) == 1
        deadline = time.monotonic() + WAIT
        while web_control.subscriptions or dash.web.sockets:
            assert time.monotonic() < deadline, "a gone page's subscription is still there"
            await asyncio.sleep(0.01)
        for service in dash.daemon.services:
            assert service.observers == []


async def raw_http(url: str, request: bytes) -> bytes:
    """The status line and headers the dashboard answers to ``request``, sent as it is on a
    socket of its own."""
    host, port = url[len("http://") :].rsplit(":", 1)
    reader, writer = await asyncio.open_connection(host, int(port))
    try:
        writer.write(request)
        return await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), WAIT)
    finally:
        writer.close()


async def test_malformed_requests_get_a_status_and_one_line_never_a_traceback(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """Anyone who reaches the port can send anything. A Host or an Origin that is no URL's
    (``[::1`` without its bracket) made the guard raise ValueError: a 500, and a traceback on
    standard error; a header longer than aiohttp's 8,190 bytes, or ten thousand of them, got
    their 400 but printed a traceback each on standard error too, past the daemon's log and
    its ``view = "off"``. Each now gets its status and at most one line in the daemon's log."""
    async with dashboard(tmp_path, control=True) as dash:
        here = dash.url[len("http://") :]
        for request, status in [
            (b"GET / HTTP/1.1\r\nHost: [::1\r\n\r\n", b"403"),
            (
                f"GET /ws HTTP/1.1\r\nHost: {here}\r\nOrigin: http://[::1\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n".encode(),
                b"403",
            ),
            (b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-A: " + b"a" * 100_000 + b"\r\n\r\n", b"400"),
            (b"GET /" + b"a" * 100_000 + b" HTTP/1.1\r\n\r\n", b"400"),
            (
                b"GET / HTTP/1.1\r\n" + b"".join(b"X-%d: a\r\n" % i for i in range(10_000)),
                b"400",
            ),
        ]:
            answer = await raw_http(dash.url, request)
            assert answer.split(b" ", 2)[1] == status, answer[:200]
            assert b"Traceback" not in answer
        async with page(dash) as p:  # the dashboard goes on
            assert (await p.next() or {}).get("kind") == "hello"
        said = dash.log.getvalue()
    out, err = capfd.readouterr()
    assert "Traceback" not in out + err and "Error handling" not in err, err[-2000:]
    web_lines = [line for line in said.splitlines() if "web dashboard:" in line]
    assert 1 <= len(web_lines) <= 3, said
    assert all("Traceback" not in line and len(line) < 400 for line in web_lines), web_lines


async def test_a_slow_request_is_closed_and_connections_are_bounded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A client that sends its request's head a byte a second (slowloris) was kept for good
    (still open after 150 s), and there was no bound on such connections: with the daemon's
    descriptors held by them (1,100 against a limit of 200), board a's TCP endpoint could
    take no client ('socket.accept() out of system resource'). Now a head must come within
    HEAD_TIMEOUT, and beyond MAX_CONNECTIONS a newcomer is told so in one line and closed;
    the boards are served throughout."""
    import omsd.web.server as module

    monkeypatch.setattr(module, "HEAD_TIMEOUT", 0.5, raising=False)
    monkeypatch.setattr(module, "MAX_CONNECTIONS", 5, raising=False)
    async with dashboard(tmp_path) as dash:
        host, port = dash.url[len("http://") :].rsplit(":", 1)
        slow = []
        for _ in range(5):
            reader, writer = await asyncio.open_connection(host, int(port))
            writer.write(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ")
            slow.append((reader, writer))
        await asyncio.sleep(0.1)
        busy = await raw_http(dash.url, b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
        assert busy.startswith(b"HTTP/1.1 503 "), busy
        assert await board_says(dash.ports["xy"], b"WY\n") == b"PC48 ver 3.00-4\n"
        started = time.monotonic()
        for reader, writer in slow:  # a byte now and then does not keep them
            reset = False  # (closed with the client's last byte unread: a reset, not an EOF)
            for _ in range(50):
                with contextlib.suppress(ConnectionError):
                    writer.write(b"a")
                if reader.at_eof() or time.monotonic() - started > WAIT:
                    break
                try:
                    await asyncio.wait_for(reader.read(), 0.1)
                except TimeoutError:
                    continue
                except ConnectionError:
                    reset = True
                    break
            assert reset or reader.at_eof(), "a slow request head was kept past HEAD_TIMEOUT"
            writer.close()
        async with page(dash) as p:  # room again
            assert (await p.next() or {}).get("kind") == "hello"
            await asyncio.sleep(0.8)  # a page, once its request came, is not cut at the deadline
            assert (await p.ask("boards"))["ok"] is True


async def test_a_page_that_asks_and_never_reads_is_held_off(tmp_path: Path) -> None:
    """A page (read-only: ``state`` is a watcher's op) that sent requests as fast as it could
    and read none of the answers had every frame made a task at once: the daemon went from
    55 MB to 1.6 GB in 15 s. Now its WebSocket is read no further while ``MAX_PENDING`` of its
    requests are in progress."""
    from omsd.control.server import MAX_PENDING

    async with dashboard(tmp_path) as dash:
        host, port = dash.url[len("http://") :].rsplit(":", 1)
        reader, writer = await asyncio.open_connection(host, int(port), limit=4096)
        sock = writer.get_extra_info("socket")
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        writer.write(
            f"GET /ws HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
            "Connection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
            "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n".encode()
        )
        await reader.readuntil(b"\r\n\r\n")
        text = b'{"id":1,"op":"state","board":"xy"}'
        frame = bytes([0x81, 0x80 | len(text)]) + b"\0\0\0\0" + text  # masked with zeros
        most = 0
        for _ in range(200):
            writer.write(frame * 200)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(writer.drain(), 0.05)
            most = max(most, len(dash.web.control._tasks))
        assert most <= MAX_PENDING + 1, most
        assert await board_says(dash.ports["xy"], b"WY\n") == b"PC48 ver 3.00-4\n"
        writer.transport.abort()


# -- start-up -------------------------------------------------------------------------------------


async def test_an_address_in_use_is_a_start_up_error(tmp_path: Path) -> None:
    async with dashboard(tmp_path) as dash:
        _, port = dash.web.address or ("", 0)
        config = DaemonConfig(
            boards=(BoardConfig(name="b"),),
            control=ControlConfig(socket=None, explicit=True),
            web=WebConfig(TcpEndpoint("127.0.0.1", port)),
        )
        daemon = Daemon(config, TrafficLog("off"), out=io.StringIO())
        with pytest.raises(StartupError, match=r"cannot serve the web dashboard on 127\.0\.0\.1:"):
            await daemon.start()
        assert daemon.web is None and not daemon.services


async def test_without_aiohttp_omsd_says_what_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The dashboard is the ``web`` extra: a daemon asked for it without aiohttp refuses to
    start, in one line, before it opens anything."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "aiohttp" else real(name, *a)
    )
    config = DaemonConfig(
        boards=(BoardConfig(name="b", tcp=(TcpEndpoint("127.0.0.1", 0),)),),
        control=ControlConfig(socket=None, explicit=True),
        web=WebConfig(TcpEndpoint("127.0.0.1", 0)),
    )
    daemon = Daemon(config, TrafficLog("off"), out=io.StringIO())
    with pytest.raises(StartupError, match=r"pip install 'omsd\[web\]'") as caught:
        await daemon.start()
    assert "\n" not in str(caught.value)
    assert not daemon.services and not daemon.servers


async def test_a_later_request_head_on_a_kept_alive_connection_is_bounded_too(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """HEAD_TIMEOUT covered a connection's first request head only: a client that sent one
    request on a kept-alive connection, then its second head a byte now and then, was kept
    as long as aiohttp's keep-alive timeout (75 s in aiohttp 3.9, an hour in 3.14). Now a
    kept-alive connection must send its next head within HEAD_TIMEOUT of the last answer
    (shortened here to 0.5 s) or it is closed."""
    import omsd.web.server as module

    monkeypatch.setattr(module, "HEAD_TIMEOUT", 0.5, raising=False)
    async with dashboard(tmp_path) as dash:
        host, port = dash.url[len("http://") :].rsplit(":", 1)
        reader, writer = await asyncio.open_connection(host, int(port))
        try:
            writer.write(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
            head = await asyncio.wait_for(reader.readuntil(b"\r\n\r\n"), WAIT)
            assert head.startswith(b"HTTP/1.1 200 "), head
            fields = dict(line.split(b": ", 1) for line in head.split(b"\r\n")[1:] if b": " in line)
            assert fields.get(b"Connection", b"keep-alive").lower() != b"close", head
            await asyncio.wait_for(reader.readexactly(int(fields[b"Content-Length"])), WAIT)
            writer.write(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ")
            started = time.monotonic()
            closed = False
            while not closed and time.monotonic() - started < WAIT:
                with contextlib.suppress(ConnectionError):
                    writer.write(b"a")
                try:
                    closed = await asyncio.wait_for(reader.read(), 0.1) == b""
                except TimeoutError:
                    continue
                except ConnectionError:  # closed with the client's last byte unread: a reset
                    closed = True
            assert closed, "a slow second request head was kept past HEAD_TIMEOUT"
        finally:
            writer.close()
        assert await board_says(dash.ports["xy"], b"WY\n") == b"PC48 ver 3.00-4\n"
