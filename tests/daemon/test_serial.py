"""The daemon's serial and RFC 2217 endpoints (``--serial``, ``--rfc2217``, ``serial_port`` and
``rfc2217`` in a file), end to end: a pty pair stands in for the serial device (the daemon opens
the slave through a symlink; the test holds the master, the far end of the null-modem cable),
pyserial's own ``rfc2217://`` client talks to the RFC 2217 socket. The endpoint lines, ``omsd ctl
boards``, the device unplugged and plugged in again with the daemon up, and the one-line errors
(exit status 2) for what cannot be served."""

from __future__ import annotations

import os
import select
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from omsd.control.client import Control

from .process import TIMEOUT, Omsd, run_omsd, wait_for

serial = pytest.importorskip("serial")

# pyserial 3.5's client names its reader thread the old way
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:serial.rfc2217")


class FarEnd:
    """The master of a pty pair; the slave is reached through the symlink ``link``."""

    def __init__(self, link: Path) -> None:
        self.link = link
        self.master, slave = os.openpty()
        device = os.ttyname(slave)
        os.close(slave)
        tmp = link.with_name(link.name + ".new")
        os.symlink(device, tmp)
        os.replace(tmp, link)
        self.buffer = b""

    def ask(self, command: bytes, end: bytes = b"\n") -> bytes:
        os.write(self.master, command)
        deadline = time.monotonic() + TIMEOUT
        while end not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.master], [], [], left)[0]:
                raise AssertionError(f"no answer to {command!r}; got {self.buffer!r}")
            self.buffer += os.read(self.master, 4096)
        at = self.buffer.index(end) + len(end)
        answer, self.buffer = self.buffer[:at], self.buffer[at:]
        return answer

    def unplug(self) -> None:
        os.close(self.master)
        self.master = -1
        self.link.unlink()

    def close(self) -> None:
        if self.master >= 0:
            os.close(self.master)
            self.master = -1


@pytest.fixture
def far(tmp_path: Path) -> Iterator[FarEnd]:
    end = FarEnd(tmp_path / "ttyUSB0")
    try:
        yield end
    finally:
        end.close()


def test_a_board_on_a_serial_device_and_an_rfc2217_socket(
    omsd: Omsd, far: FarEnd, tmp_path: Path
) -> None:
    socket_path = tmp_path / "control.sock"
    daemon = omsd(
        "--serial", f"{far.link},19200", "--rfc2217", "127.0.0.1:0",
        "--control", str(socket_path),
    )  # fmt: skip
    serial_line, rfc_line = daemon.endpoints
    assert (serial_line.kind, serial_line.address) == ("serial", f"{far.link},19200,8N1")
    assert rfc_line.kind == "rfc2217"
    assert far.ask(b"WY") == b"PC48 ver 3.00-4\n"
    client = serial.serial_for_url(
        f"rfc2217://{rfc_line.host}:{rfc_line.port}", baudrate=2400, timeout=TIMEOUT
    )
    try:
        client.write(b"AX MR100 GO ID")
        assert client.read_until(b"\n") == b"!\x01\n"
        client.rts = False
    finally:
        client.close()
    assert far.ask(b"RP") == b"100\n"  # one board behind both
    assert wait_for(lambda: "RTS off" in daemon.stderr)
    assert "line 2400 8N1" in daemon.stderr
    assert f"serving board1 PC48-4E driver serial {far.link},19200,8N1" in daemon.stderr
    with Control(socket_path, timeout=TIMEOUT) as ctl:
        (board,) = ctl.boards()
        assert f"serial:{far.link}" in ctl.state()["clients"]
    kinds = [(e["kind"], e["address"]) for e in board["endpoints"]]
    assert kinds == [
        ("serial", f"{far.link},19200,8N1"),
        ("rfc2217", f"127.0.0.1:{rfc_line.port}"),
    ]


def test_unplugged_the_daemon_stays_up_and_serves_the_device_when_it_is_back(
    omsd: Omsd, far: FarEnd
) -> None:
    daemon = omsd("--serial", str(far.link), "--tcp", "127.0.0.1:0")
    assert far.ask(b"WY") == b"PC48 ver 3.00-4\n"
    far.unplug()
    assert wait_for(lambda: "is gone" in daemon.stderr), daemon.stderr
    with daemon.connect() as conn:  # the daemon and the board go on
        conn.send(b"WY")
        assert conn.read_until(b"\n") == b"PC48 ver 3.00-4\n"
    back = FarEnd(far.link)
    try:
        assert wait_for(lambda: "is back" in daemon.stderr, TIMEOUT), daemon.stderr
        assert back.ask(b"WY") == b"PC48 ver 3.00-4\n"
    finally:
        back.close()
    assert daemon.stderr.count("is gone") == 1
    assert daemon.running


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--serial", "/dev/ttyS0,12"], "omsd: --serial: expected PATH[,BAUD[,8N1]] with BAUD"),
        (["--serial", "/dev/ttyS0,9600,9N1"], "omsd: --serial: expected PATH[,BAUD[,8N1]] with"),
        (["--serial", "/nonexistent/tty"], "omsd: board1: cannot open serial /nonexistent/tty:"),
        (["--serial", "/dev/null"], "omsd: board1: cannot open serial /dev/null: not a serial"),
        (["--rfc2217", "host:port"], "omsd: --rfc2217: expected [HOST:]PORT"),
    ],
)
def test_what_cannot_be_served_is_one_line_and_exit_status_2(
    args: list[str], says: str, tmp_path: Path
) -> None:
    done = run_omsd(*args, "--control", "off", cwd=tmp_path)
    assert done.returncode == 2, done
    assert done.stderr.startswith(says) and done.stderr.count("\n") == 1, done.stderr
    assert done.stdout == ""


def test_a_configuration_file_s_serial_and_rfc2217_keys(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(
        '[[board]]\nserial_port = { path = "/dev/ttyUSB0", parity = "odd", stopbits = 3 }\n'
    )
    done = run_omsd("config", "check", str(path))
    assert done.returncode == 2
    assert done.stderr == (
        f'{path}:2: [board "board1" (unnamed)] serial_port.stopbits: expected stop bits 1, 1.5'
        " or 2, got 3\n"
    )
