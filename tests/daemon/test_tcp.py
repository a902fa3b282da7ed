"""The real daemon over TCP: a plain socket and pyserial's ``socket://``, the driver's end
character (``--eos``, the DOS driver's E:XX), several boards from one file, and the policy for a
second client on a busy board.

PC48 manual §7.3.2: "The response to an RP command when talking straight to the board is
"<LF><CR>0<LF><CR>" ... The response from an RP command using the driver would be "0<LF>"";
§7.3.3: "When a command error occurs it places a # symbol followed by the "E:" specified end
character ... A DONE interrupt will place an ! into the data stream followed by the byte read from
the done flag register of the board, followed by the end character."
"""

from __future__ import annotations

import signal
import socket
import time
from pathlib import Path

import serial
from ipv6 import needs_loopback

from .process import POLL, TIMEOUT, Conn, Omsd, run_omsd, wait_for

WY_PC48_4 = b"PC48 ver 3.00-4"


def test_board_model_is_case_insensitive_and_the_endpoint_line_says_where(omsd: Omsd) -> None:
    daemon = omsd("--board", "pc48-2e", "--tcp", "127.0.0.1:0")
    (endpoint,) = daemon.endpoints
    assert (endpoint.board, endpoint.model, endpoint.link, endpoint.kind) == (
        "board1",
        "PC48-2E",
        "driver",
        "tcp",
    )
    assert endpoint.host == "127.0.0.1"
    assert 0 < endpoint.port < 65536
    with daemon.connect() as c:
        assert c.ask(b"WY AA RP") == b"PC48 ver 3.00-2"
        assert c.read_until(b"\n") == b"0,0\n"


def test_socket_wy_rp_move_done_and_command_error(omsd: Omsd) -> None:
    daemon = omsd("--board", "PC48-4E", "--tcp", "127.0.0.1:0")
    (endpoint,) = daemon.endpoints
    assert (endpoint.board, endpoint.model, endpoint.link, endpoint.kind) == (
        "board1",
        "PC48-4E",
        "driver",
        "tcp",
    )
    with daemon.connect() as c:
        c.send(b"WY")
        c.expect(WY_PC48_4 + b"\n")
        c.send(b"AX RP")
        c.expect(b"0\n")
        # 1000 steps at 10000 steps/s take at least 0.1 s: the done marker comes after the move,
        # never before (the daemon's clock starts no earlier than this send)
        sent = time.monotonic()
        c.send(b"AX VL10000 MR1000 GO ID")
        assert c.quiet(0.05) == b""
        c.expect(b"!\x01\n")
        assert time.monotonic() - sent >= 0.1
        c.send(b"AX RP")
        c.expect(b"1000\n")
        # a command error: "#" and the end character, and the board goes on
        c.send(b"ZZ")
        c.expect(b"#\n")
        c.send(b"AY MR5 GO ID")
        c.expect(b"!\x02\n")
        c.send(b"AA RP")
        c.expect(b"1000,5,0,0\n")
        assert c.quiet(0.05) == b""


def test_pyserial_socket_url(omsd: Omsd) -> None:
    daemon = omsd("--tcp", "127.0.0.1:0")
    host, port = daemon.tcp()
    link = serial.serial_for_url(f"socket://{host}:{port}", timeout=TIMEOUT)
    try:
        link.write(b"WY")
        assert link.read_until(b"\n") == WY_PC48_4 + b"\n"
        link.write(b"AX LP-250 RP")
        assert link.read_until(b"\n") == b"-250\n"
        link.write(b"AY MR200 GO ID")
        assert link.read_until(b"\n") == b"!\x02\n"
        link.write(b"AA RP")
        assert link.read_until(b"\n") == b"-250,200,0,0\n"
        link.write(b"XX")
        assert link.read_until(b"\n") == b"#\n"
    finally:
        link.close()
    # a new connection finds the board as it was left
    link = serial.serial_for_url(f"socket://{host}:{port}", timeout=TIMEOUT)
    try:
        link.write(b"AA RP")
        assert link.read_until(b"\n") == b"-250,200,0,0\n"
    finally:
        link.close()


def test_eos_changes_the_end_character(omsd: Omsd) -> None:
    """E:0D "(changes end of string char to a <CR>)": replies and every marker end with CR."""
    daemon = omsd("--tcp", "127.0.0.1:0", "--eos", "0D")
    with daemon.connect() as c:
        c.send(b"WY RP ZZ AX MR10 GO ID")
        c.expect(WY_PC48_4 + b"\r0\r#\r!\x01\r")
        c.send(b"AX RP")
        c.expect(b"10\r")
        assert c.quiet(0.05) == b""


def test_several_boards_from_one_file_are_independent(omsd: Omsd, tmp_path: Path) -> None:
    xy_pty = tmp_path / "pty" / "xy"
    xy_pty.parent.mkdir()  # omsd makes no directory for a link (issue 14)
    config = f"""
[[board]]
name = "xy"
model = "PC48-4E"
tcp = "127.0.0.1:0"
pty = "{xy_pty}"

[[board]]
name = "slits"
model = "pc48-8"
eos = "0D"
tcp = "127.0.0.1:0"

[[board]]
name = "epics"
model = "PC48-2"
link = "raw"
tcp = "127.0.0.1:0"
"""
    daemon = omsd(config=config, expect=4)
    assert sorted((e.board, e.model, e.link, e.kind) for e in daemon.endpoints) == [
        ("epics", "PC48-2", "raw", "tcp"),
        ("slits", "PC48-8", "driver", "tcp"),
        ("xy", "PC48-4E", "driver", "pty"),
        ("xy", "PC48-4E", "driver", "tcp"),
    ]
    assert daemon.pty("xy") == xy_pty
    ports = {e.port for e in daemon.endpoints if e.kind == "tcp"}
    assert len(ports) == 3
    with (
        daemon.connect("xy") as xy,
        daemon.connect("slits") as slits,
        daemon.connect("epics") as epics,
    ):
        xy.send(b"WY")
        slits.send(b"WY")
        epics.send(b"WY")
        xy.expect(WY_PC48_4 + b"\n")
        slits.expect(b"PC48 ver 3.00-8\r")
        epics.expect(b"\n\rPC48 ver 3.00-2\n\r")
        xy.send(b"AX LP111 AX RP")
        slits.send(b"AX LP222 AX RP")
        epics.send(b"AX LP333 AX RP")
        xy.expect(b"111\n")
        slits.expect(b"222\r")
        epics.expect(b"\n\r333\n\r")
        # a move on one board moves nothing on the others
        slits.send(b"AY MR50 GO ID")
        slits.expect(b"!\x02\r")
        xy.send(b"AA RP")
        xy.expect(b"111,0,0,0\n")
        epics.send(b"AA RP")
        epics.expect(b"\n\r333,0\n\r")
        slits.send(b"AA RP")
        slits.expect(b"222,50,0,0,0,0,0,0\r")
    # the pty of a board reaches the same board as its TCP port
    with serial.Serial(str(xy_pty), timeout=TIMEOUT) as port:
        port.write(b"AX RP")
        assert port.read_until(b"\n") == b"111\n"


def test_second_client_takes_over_by_default(omsd: Omsd) -> None:
    daemon = omsd("--tcp", "127.0.0.1:0")
    first = daemon.connect()
    try:
        assert first.ask(b"AX LP42 RP") == b"42"
        with daemon.connect() as second:
            assert first.at_eof(), "the first client's connection should be closed"
            assert first.buffer == b""
            assert second.ask(b"AX RP") == b"42"  # the board's state survives the takeover
            assert second.ask(b"WY") == WY_PC48_4
    finally:
        first.close()


def _try_client(host: str, port: int) -> bytes | None:
    """Connect and ask WY; the reply, or None when the board refused the connection."""
    try:
        with Conn(host, port) as c:
            reply = c.ask(b"WY")
    except (OSError, AssertionError):
        return None
    return None if b"busy" in reply else reply


def test_second_client_refused_when_configured(omsd: Omsd) -> None:
    config = """
[[board]]
name = "solo"
tcp = "127.0.0.1:0"
second_client = "refuse"
"""
    daemon = omsd(config=config, expect=1)
    first = daemon.connect()
    try:
        assert first.ask(b"WY") == WY_PC48_4  # the first client is attached
        with daemon.connect() as second:
            assert second.at_eof(), "the refused client should be closed"
            said = bytes(second.buffer)
        lines = said.splitlines()
        assert len(lines) == 1, said
        assert b"busy" in lines[0] and b"solo" in lines[0], said
        assert said.endswith(b"\n")
        # the first client did not notice
        assert first.ask(b"AX LP7 RP") == b"7"
        assert first.quiet(0.05) == b""
    finally:
        first.close()
    # once the first client has gone, the board takes a new one
    host, port = daemon.tcp()
    replies: list[bytes] = []

    def admitted() -> bool:
        reply = _try_client(host, port)
        if reply is None:
            time.sleep(POLL)
            return False
        replies.append(reply)
        return True

    assert wait_for(admitted)
    assert replies == [WY_PC48_4]


def test_what_a_taken_over_client_wrote_still_reaches_the_board(omsd: Omsd) -> None:
    """A client writes and disconnects, and a new client connects before the daemon has read
    the first one's bytes (here made certain by pausing the daemon with SIGSTOP): the takeover
    must not lose them, as a serial line would deliver bytes already sent (``TcpClient.
    hand_over``). Their answers are the first client's, and the newcomer gets none of them
    (issue 13: "everything the board produces in answer to a connection's bytes belongs to that
    connection")."""
    daemon = omsd("--tcp", "127.0.0.1:0")
    host, port = daemon.tcp()
    daemon.proc.send_signal(signal.SIGSTOP)
    try:
        gone = socket.create_connection((host, port), timeout=TIMEOUT)
        gone.sendall(b"AX LP9 RP WY ")
        gone.close()
        second = Conn(host, port)
    finally:
        daemon.proc.send_signal(signal.SIGCONT)
    with second:
        assert second.ask(b"AX RP") == b"9"  # its own answer first: LP9 ran before it
        assert second.ask(b"WY") == WY_PC48_4
        assert second.quiet(0.2) == b""


def test_more_than_the_driver_buffer_at_once_is_passed_on_exactly_once(omsd: Omsd) -> None:
    """§7.3.2, B:XXXX "defines the "output to board" BUFFER size. This value determines how many
    characters you can send to the device buffer at one time" (default 256). A host that writes
    more at once is held off, as a full DOS device would hold it, and every command reaches the
    board exactly once, in order."""
    daemon = omsd("--tcp", "127.0.0.1:0")
    with daemon.connect() as c:
        c.send(b"AX RP " * 60)  # 360 characters
        c.expect(b"0\n" * 60)
        assert c.quiet(0.1) == b""
        # the same behind a "!" that holds everything back until the move is done
        c.send(b"AX VL10000 MR500 GO ID ! " + b"AX RP " * 60)
        c.expect(b"!\x01\n" + b"500\n" * 60)
        assert c.quiet(0.1) == b""


@needs_loopback
def test_ipv6_addresses_are_printed_in_brackets_everywhere(omsd: Omsd, tmp_path: Path) -> None:
    """An IPv6 address with its port is written [::1]:PORT (RFC 3986 §3.2.2), as omsd's own
    --tcp, [control] tcp and omsd ctl --tcp take it: the endpoint lines printed ::1:PORT,
    which those refuse ("expected [HOST:]PORT") and a user pasting it into a client could not
    use. The endpoint lines, the log's serving, control tcp and connection lines, the control
    API's listing and omsd ctl boards all say [::1]:PORT."""
    config = (
        '[control]\nsocket = "off"\ntcp = "[::1]:0"\n\n'
        '[[board]]\nname = "b6"\ntcp = "[::1]:0"\nrfc2217 = "[::1]:0"\n'
    )
    daemon = omsd(config=config, expect=2)
    tcp, rfc = daemon.endpoints
    assert tcp.kind == "tcp" and tcp.address == f"[::1]:{tcp.port}", tcp
    assert rfc.kind == "rfc2217" and rfc.address == f"[::1]:{rfc.port}", rfc
    assert wait_for(lambda: "control tcp" in daemon.stderr)
    (control_line,) = [line for line in daemon.stderr.splitlines() if "control tcp" in line]
    control = control_line.rsplit(" ", 1)[1]
    assert control.startswith("[::1]:"), control_line  # and omsd ctl --tcp takes it as printed
    with daemon.connect() as c:
        assert c.ask(b"WY") == WY_PC48_4
        here = c.sock.getsockname()[1]
    assert wait_for(lambda: " connected" in daemon.stderr)
    assert f"b6: tcp:[::1]:{tcp.port} #1 ([::1]:{here}) connected" in daemon.stderr
    assert f"serving b6 PC48-4E driver tcp [::1]:{tcp.port}" in daemon.stderr
    listed = run_omsd("ctl", "--tcp", control, "boards")
    assert listed.returncode == 0, listed.stderr
    assert f"tcp [::1]:{tcp.port}, rfc2217 [::1]:{rfc.port}" in listed.stdout
