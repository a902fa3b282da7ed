"""systemd readiness notification (omsd/sdnotify.py) against real AF_UNIX datagram sockets.

A test plays the service manager: it binds the socket, passes its name in NOTIFY_SOCKET and
reads what the daemon sent, as systemd would; the last test does so for the real daemon.
"""

from __future__ import annotations

import asyncio
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from omsd import sdnotify


@pytest.fixture
def manager(tmp_path: Path) -> Iterator[tuple[socket.socket, dict[str, str]]]:
    """A bound datagram socket on a path in tmp_path, and an environment naming it."""
    path = tmp_path / "notify"
    if len(os.fsencode(path)) >= 104:  # sun_path holds 108 bytes; pytest's tmp dirs can be deep
        pytest.skip(f"tmp_path too long for an AF_UNIX address: {path}")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(str(path))
    sock.settimeout(2.0)
    try:
        yield sock, {"NOTIFY_SOCKET": str(path)}
    finally:
        sock.close()


def test_ready_sends_ready_and_status(manager: tuple[socket.socket, dict[str, str]]) -> None:
    sock, env = manager
    assert sdnotify.ready("serving PC48-4E on 127.0.0.1:7048", env=env) is True
    assert sock.recv(4096) == b"READY=1\nSTATUS=serving PC48-4E on 127.0.0.1:7048"


def test_ready_without_status_is_one_line(manager: tuple[socket.socket, dict[str, str]]) -> None:
    sock, env = manager
    assert sdnotify.ready(env=env)
    assert sock.recv(4096) == b"READY=1"


def test_stopping_and_status(manager: tuple[socket.socket, dict[str, str]]) -> None:
    sock, env = manager
    assert sdnotify.status("2 boards, 1 client", env=env)
    assert sdnotify.stopping(env=env)
    assert sock.recv(4096) == b"STATUS=2 boards, 1 client"
    assert sock.recv(4096) == b"STOPPING=1"


def test_status_is_a_single_utf8_line(manager: tuple[socket.socket, dict[str, str]]) -> None:
    """STATUS= is "a single-line UTF-8 status string": a newline would start a new variable."""
    sock, env = manager
    assert sdnotify.status("pty /run/omsd/pc48\nREADY=1 µ", env=env)
    assert sock.recv(4096) == "STATUS=pty /run/omsd/pc48 READY=1 µ".encode()


def test_notify_sends_state_verbatim(manager: tuple[socket.socket, dict[str, str]]) -> None:
    sock, env = manager
    assert sdnotify.notify("READY=1\nMAINPID=4711", env)
    assert sock.recv(4096) == b"READY=1\nMAINPID=4711"


def test_abstract_namespace_socket() -> None:
    """'@name' in NOTIFY_SOCKET is the abstract socket whose name is NUL + 'name'."""
    name = f"omsd-test-{os.getpid()}-{time.monotonic_ns()}"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as sock:
        sock.bind("\0" + name)
        sock.settimeout(2.0)
        assert sdnotify.ready("up", env={"NOTIFY_SOCKET": "@" + name}) is True
        assert sock.recv(4096) == b"READY=1\nSTATUS=up"


def test_reads_os_environ_by_default(
    manager: tuple[socket.socket, dict[str, str]], monkeypatch: pytest.MonkeyPatch
) -> None:
    sock, env = manager
    monkeypatch.setenv("NOTIFY_SOCKET", env["NOTIFY_SOCKET"])
    assert sdnotify.ready()
    assert sock.recv(4096) == b"READY=1"


@pytest.mark.parametrize("env", [{}, {"NOTIFY_SOCKET": ""}, {"NOTIFY_SOCKET": "@"}])
def test_no_socket_is_false(env: dict[str, str]) -> None:
    assert sdnotify.notify("READY=1", env) is False
    assert sdnotify.ready("x", env=env) is False
    assert sdnotify.stopping(env=env) is False
    assert sdnotify.status("x", env=env) is False


def test_no_socket_in_os_environ_is_false(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("NOTIFY_SOCKET", raising=False)
    assert sdnotify.ready() is False


@pytest.mark.parametrize("value", ["vsock:2:1234", "relative/path", "notify"])
def test_unsupported_address_is_false(value: str) -> None:
    assert sdnotify.notify("READY=1", {"NOTIFY_SOCKET": value}) is False


def test_missing_socket_is_false(tmp_path: Path) -> None:
    assert sdnotify.ready(env={"NOTIFY_SOCKET": str(tmp_path / "absent")}) is False


def test_stale_socket_file_is_false(tmp_path: Path) -> None:
    """A socket file nobody listens on any more (the manager went away): ECONNREFUSED."""
    path = tmp_path / "stale"
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as sock:
        sock.bind(str(path))
    assert path.exists()
    assert sdnotify.ready(env={"NOTIFY_SOCKET": str(path)}) is False


def test_regular_file_is_false(tmp_path: Path) -> None:
    path = tmp_path / "not-a-socket"
    path.write_text("")
    assert sdnotify.stopping(env={"NOTIFY_SOCKET": str(path)}) is False


def test_unreachable_abstract_socket_is_false() -> None:
    name = f"@omsd-test-nobody-{os.getpid()}-{time.monotonic_ns()}"
    assert sdnotify.ready(env={"NOTIFY_SOCKET": name}) is False


def test_path_too_long_is_false(tmp_path: Path) -> None:
    assert sdnotify.ready(env={"NOTIFY_SOCKET": "/" + "x" * 200}) is False


def test_nul_in_path_is_false() -> None:
    assert sdnotify.ready(env={"NOTIFY_SOCKET": "/run/sys\0temd/notify"}) is False


def test_full_receive_queue_gives_up(
    manager: tuple[socket.socket, dict[str, str]], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A manager that stops reading cannot hang the daemon: the send times out, False."""
    _, env = manager
    with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as filler:
        filler.setblocking(False)
        for _ in range(100_000):
            try:
                filler.sendto(b"x" * 1024, env["NOTIFY_SOCKET"])
            except BlockingIOError:
                break
        else:
            pytest.fail("the receive queue never filled")
        monkeypatch.setattr(sdnotify, "SEND_TIMEOUT", 0.05)
        results: list[bool] = []
        start = time.monotonic()
        sender = threading.Thread(target=lambda: results.append(sdnotify.ready(env=env)))
        sender.start()
        sender.join(timeout=2.0)
        elapsed = time.monotonic() - start
    # Leaving the block closed the filler; closing the receiver (fixture) frees a hung sender.
    assert not sender.is_alive(), "notify blocked on a full queue"
    assert results == [False]
    assert elapsed > 0.04  # it waited for room, then gave up


async def test_daemon_notifies_ready_then_stopping(
    manager: tuple[socket.socket, dict[str, str]], tmp_path: Path
) -> None:
    """omsd, started as systemd would start a Type=notify unit, says READY=1 once its endpoint
    is up (so a client can connect at once) and STOPPING=1 on SIGTERM, then exits 0."""
    sock, env = manager
    sock.setblocking(False)
    loop = asyncio.get_running_loop()
    with (tmp_path / "stderr").open("wb") as stderr:
        proc = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "omsd",
            "--tcp",
            "127.0.0.1:0",
            stdout=asyncio.subprocess.PIPE,
            stderr=stderr,
            env={**os.environ, **env},
        )
        try:
            ready = await asyncio.wait_for(loop.sock_recv(sock, 4096), timeout=10)
            assert ready.split(b"\n")[0] == b"READY=1"
            assert proc.stdout is not None
            line = (await asyncio.wait_for(proc.stdout.readline(), timeout=5)).decode()
            port = int(line.split(":")[-1])
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            writer.write(b"WY")
            assert await asyncio.wait_for(reader.readline(), 5) == b"PC48 ver 3.00-4\n"
            writer.close()
            await writer.wait_closed()
            proc.send_signal(signal.SIGTERM)
            stopping = await asyncio.wait_for(loop.sock_recv(sock, 4096), timeout=10)
            assert stopping == b"STOPPING=1"
            assert await asyncio.wait_for(proc.wait(), timeout=10) == 0
        finally:
            if proc.returncode is None:
                proc.kill()
                await proc.wait()
