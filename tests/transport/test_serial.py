"""The serial endpoint (omsd.transport.serial) in process, with a pty pair standing in for the
device: the endpoint opens the slave through a symlink and sets it as the application's port is
set; the test, at the master, is the far end of the cable. Queries are answered, the line's
settings are on the device, pacing holds the output to the line's rate, and the device going and
coming back is logged, retried and served again while the board goes on."""

from __future__ import annotations

import asyncio
import os
import termios
import time
from pathlib import Path
from typing import Any

import pytest

from omsd.pacing import Line
from omsd.transport.serial import SerialEndpoint, describe, open_device

from .helpers import FarEnd, make_service, until

pytest.importorskip("serial")


def _settings(path: Path) -> list[Any]:
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        return termios.tcgetattr(fd)
    finally:
        os.close(fd)


async def test_a_board_on_a_serial_device_answers_and_its_line_is_9600_8n1(
    tmp_path: Path,
) -> None:
    far = FarEnd(tmp_path / "ttyUSB0")
    service, log, _ = make_service()
    endpoint = SerialEndpoint(service, far.link)
    try:
        assert endpoint.open() == f"{far.link},9600,8N1"
        far.write(b"WY")
        assert await far.read_until(b"\n") == b"PC48 ver 3.00-4\n"
        far.write(b"AX MR100 GO ID")
        assert await far.read_until(b"\n") == b"!\x01\n"
        iflag, _, cflag, _, ispeed, ospeed, cc = _settings(far.link)
        assert (ispeed, ospeed) == (termios.B9600, termios.B9600)
        assert cflag & termios.CSIZE == termios.CS8
        assert not cflag & (termios.PARENB | termios.CSTOPB | termios.CRTSCTS)
        assert not iflag & (termios.IXON | termios.IXOFF)
        assert cc[termios.VMIN] == 1
        assert f"serial:{far.link} -> PC48 ver 3.00-4<LF>" in log.getvalue()
    finally:
        endpoint.close()
        far.close()
        service.close()


async def test_the_line_and_flow_control_as_configured(tmp_path: Path) -> None:
    far = FarEnd(tmp_path / "ttyS0")
    service, _, _ = make_service()
    endpoint = SerialEndpoint(service, far.link, Line(19200, 7, "E", 2), flow="rtscts")
    try:
        assert endpoint.open() == f"{far.link},19200,7E2,rtscts"
        _, _, cflag, _, ispeed, _, _ = _settings(far.link)
        assert ispeed == termios.B19200
        assert cflag & termios.CSTOPB and cflag & termios.CRTSCTS
        # a pty keeps 8 bits without parity whatever it is told (Linux's pty_set_termios): the
        # data bits and parity are checked as pyserial set them
        assert (endpoint.port.bytesize, endpoint.port.parity) == (7, "E")
    finally:
        endpoint.close()
        far.close()
        service.close()
    far = FarEnd(tmp_path / "ttyS1")
    port = open_device(far.link, Line(), "xonxoff")
    try:
        iflag = termios.tcgetattr(port.fileno())[0]
        assert iflag & termios.IXON and iflag & termios.IXOFF
    finally:
        port.close()
        far.close()


def test_the_address_is_the_option_s_syntax() -> None:
    assert describe("/dev/ttyUSB0", Line()) == "/dev/ttyUSB0,9600,8N1"
    assert describe("/dev/ttyS0", Line(1200, 7, "O", 2), "xonxoff") == "/dev/ttyS0,1200,7O2,xonxoff"


async def test_a_device_that_cannot_be_opened_is_an_error_at_start(tmp_path: Path) -> None:
    service, _, _ = make_service()
    endpoint = SerialEndpoint(service, tmp_path / "nothing")
    with pytest.raises(OSError):
        endpoint.open()
    assert service.clients == []
    endpoint.close()
    service.close()


async def test_a_device_in_use_is_locked(tmp_path: Path) -> None:
    far = FarEnd(tmp_path / "ttyUSB0")
    service, _, _ = make_service()
    first = SerialEndpoint(service, far.link)
    second = SerialEndpoint(service, far.link)
    try:
        first.open()
        with pytest.raises(OSError) as caught:
            second.open()
        from omsd.transport.serial import reason

        assert reason(caught.value) == "in use by another program (it is locked)"
    finally:
        first.close()
        second.close()
        far.close()
        service.close()


async def test_pacing_holds_the_output_to_the_line_s_rate(tmp_path: Path) -> None:
    """A lower bound only: the pacer's own times are tested on a manual clock
    (tests/transport/test_pacing.py); here, that the endpoint's output goes through it."""
    far = FarEnd(tmp_path / "ttyUSB0")
    service, _, _ = make_service()
    endpoint = SerialEndpoint(service, far.link, Line(1200), pacing=True)  # 120 characters/s
    try:
        endpoint.open()
        assert endpoint.pacer is not None
        far.write(b"WY")
        began = time.monotonic()
        reply = await far.read_until(b"\n")
        took = time.monotonic() - began
        assert reply == b"PC48 ver 3.00-4\n"
        assert took >= (len(reply) - 1) / 120  # 16 characters: at least 125 ms
    finally:
        endpoint.close()
        far.close()
        service.close()


async def test_unplugged_logged_retried_and_served_again(tmp_path: Path) -> None:
    far = FarEnd(tmp_path / "ttyUSB0")
    service, log, _ = make_service()
    endpoint = SerialEndpoint(service, far.link, retry=0.02)
    try:
        endpoint.open()
        far.write(b"WY")
        assert await far.read_until(b"\n") == b"PC48 ver 3.00-4\n"
        first = endpoint.session
        far.write(b"AX VL1000 MR100000 GO")
        await until(lambda: service.board.axes[0].moving)
        far.unplug()
        await until(lambda: not endpoint.connected)
        assert "is gone (it hung up); trying to open it again every 0.02 s" in log.getvalue()
        await asyncio.sleep(0.1)  # several attempts, none logged
        assert log.getvalue().count("is gone") == 1
        assert "is back" not in log.getvalue()
        assert service.board.axes[0].moving  # the board went on
        far = FarEnd(far.link)  # plugged in again
        await until(lambda: endpoint.connected)
        assert endpoint.session != first
        assert f"serial:{far.link} is back ({far.link},9600,8N1)" in log.getvalue()
        far.write(b"WY")
        assert await far.read_until(b"\n") == b"PC48 ver 3.00-4\n"
    finally:
        endpoint.close()
        far.close()
        service.close()
