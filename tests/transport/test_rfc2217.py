"""The RFC 2217 endpoint (omsd.transport.rfc2217) in process, with pyserial's own client
(``serial_for_url("rfc2217://...")``, in a thread): it negotiates, sets the line, DTR, RTS and a
break (each logged), talks to the board, and 0xFF passes both ways (escaped as IAC IAC on the
wire). With pacing, the line the client set paces the board's output."""

from __future__ import annotations

import asyncio
import contextlib
import socket
import time
from collections.abc import Callable
from typing import Any, TypeVar

import pytest

from omsd.pacing import Line
from omsd.transport.rfc2217 import VirtualPort, serve_rfc2217
from omsd.transport.tcp import serve_tcp

from .helpers import make_service, until

serial = pytest.importorskip("serial")

# pyserial 3.5's client names its reader thread the old way
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning:serial.rfc2217")

T = TypeVar("T")


async def in_thread(work: Callable[[], T]) -> T:
    return await asyncio.wait_for(asyncio.to_thread(work), timeout=20)


def connect(port: int, **settings: Any) -> Any:
    return serial.serial_for_url(f"rfc2217://127.0.0.1:{port}", timeout=3, **settings)


async def test_pyserial_negotiates_sets_the_port_and_talks_to_the_board() -> None:
    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def session() -> list[bytes]:
        client = connect(port, baudrate=9600)
        try:
            client.write(b"WY")
            first = client.read_until(b"\n")
            client.baudrate = 19200
            client.bytesize = serial.SEVENBITS
            client.parity = serial.PARITY_EVEN
            client.dtr = False
            client.rts = False
            client.send_break(0.05)
            client.write(b"RP")
            second = client.read_until(b"\n")
            return [first, second, bytes([client.cts, client.dsr, client.cd, client.ri])]
        finally:
            client.close()

    try:
        first, second, lines = await in_thread(session)
        assert first == b"PC48 ver 3.00-4\n"
        assert second == b"0\n"
        assert lines == b"\x01\x01\x01\x00"  # CTS, DSR, CD on; RI off
        await until(lambda: "disconnected" in log.getvalue())
        text = log.getvalue()
        label = f"rfc2217:127.0.0.1:{port} #"
        for said in (
            "RFC 2217: negotiated",
            "line 19200 8N1",
            "line 19200 7N1",
            "line 19200 7E1",
            "DTR off",
            "RTS off",
            "break on",
            "break off",
        ):
            assert said in text, said
            assert any(label in line and said in line for line in text.splitlines()), said
        assert "line 9600" not in text  # the client's 9600 8N1 is what the port had
        assert "WY" in text and "PC48 ver 3.00-4" in text  # traffic, without telnet in it
    finally:
        server.close()
        service.close()


async def test_0xff_passes_both_ways_escaped_on_the_wire() -> None:
    """With the board's echo on (EN) it sends back what it is sent: 0xFF from the client reaches
    the board as one byte and comes back as one; and an end-of-string character 0xFF ends every
    reply with one."""
    service, _, recorder = make_service(link="raw")
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def session() -> bytes:
        client = connect(port)
        try:
            client.write(b"EN\xff\r")
            echoed: bytes = client.read_until(b"#\r")
            return echoed
        finally:
            client.close()

    try:
        echoed = await in_thread(session)
        assert b"\xff" in echoed and b"\xff\xff" not in echoed
        assert recorder.received() == b"EN\xff\r"  # no telnet, one 0xFF
    finally:
        server.close()
        service.close()
    service, _, _ = make_service(eos=0xFF)
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def ask() -> bytes:
        client = connect(port)
        try:
            client.write(b"WY")
            reply: bytes = client.read_until(b"\xff")
            return reply
        finally:
            client.close()

    try:
        assert await in_thread(ask) == b"PC48 ver 3.00-4\xff"
    finally:
        server.close()
        service.close()


async def test_on_the_wire_the_board_s_0xff_is_doubled() -> None:
    service, _, _ = make_service(eos=0xFF)
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def raw() -> bytes:
        with socket.create_connection(("127.0.0.1", port), timeout=3) as sock:
            sock.sendall(b"WY")
            got = b""
            while not got.endswith(b"\xff\xff"):
                got += sock.recv(4096)
            return got

    try:
        got = await in_thread(raw)
        # the telnet option requests first (IAC WILL/DO ...), then the reply, its 0xFF doubled
        assert got.endswith(b"PC48 ver 3.00-4\xff\xff")
        assert got.startswith(b"\xff")
    finally:
        server.close()
        service.close()


async def test_a_subnegotiation_that_never_ends_is_held_to_a_bound() -> None:
    """pyserial's PortManager keeps what follows IAC SB until IAC SE: a client that sent IAC SB
    and then megabytes had every one of them kept (the daemon grew by what it was sent). Only
    the first bytes are kept; what is inside the subnegotiation still never reaches the board,
    and the board answers what follows it."""
    service, _, recorder = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def kept() -> int:
        managers = [getattr(client, "manager", None) for client in service.clients]
        return max(len(getattr(m, "suboption", None) or b"") for m in managers)

    with socket.create_connection(("127.0.0.1", port), timeout=10) as sock:

        def send() -> None:
            sock.sendall(b"\xff\xfa\x2c\x01")  # IAC SB COM-PORT SET-BAUDRATE ...
            for _ in range(64):
                sock.sendall(b"A" * 65536)

        def finish() -> bytes:
            sock.sendall(b"\xff\xf0WY")  # IAC SE
            got = b""
            while not got.endswith(b"PC48 ver 3.00-4\n"):
                got += sock.recv(4096)
            return got

        try:
            await in_thread(send)
            await until(lambda: kept() > 0)
            await asyncio.sleep(0.2)  # the rest of the 4 MiB read
            assert 0 < kept() <= 2 * 65536, kept()  # not the 4 MiB sent
            got = await in_thread(finish)
            assert got.endswith(b"PC48 ver 3.00-4\n")
            assert recorder.received() == b"WY"
        finally:
            server.close()
            service.close()


async def test_plain_tcp_stays_byte_transparent() -> None:
    service, _, recorder = make_service(eos=0xFF)
    server, _, port = await serve_tcp(service, "127.0.0.1", 0, "takeover")

    def raw() -> bytes:
        with socket.create_connection(("127.0.0.1", port), timeout=3) as sock:
            sock.sendall(b"\xff\xfa\x2cWY")  # what telnet would read as IAC SB COM-PORT
            got = b""
            while not got.endswith(b"PC48 ver 3.00-4\xff"):
                got += sock.recv(4096)
            return got

    try:
        got = await in_thread(raw)
        assert got.endswith(b"PC48 ver 3.00-4\xff") and b"\xff\xff" not in got
        assert recorder.received().startswith(b"\xff\xfa\x2c")
    finally:
        server.close()
        service.close()


async def test_pacing_follows_the_baud_rate_the_client_sets() -> None:
    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover", pacing=True)

    def session() -> tuple[bytes, float]:
        client = connect(port, baudrate=1200)  # 120 characters a second
        try:
            client.write(b"WY")
            began = time.monotonic()
            reply = client.read_until(b"\n")
            return reply, time.monotonic() - began
        finally:
            client.close()

    try:
        reply, took = await in_thread(session)
        assert reply == b"PC48 ver 3.00-4\n"
        assert took >= (len(reply) - 1) / 120  # a lower bound: the pacer's times are tested
        assert "line 1200 8N1" in log.getvalue()  # on a manual clock (test_pacing.py)
    finally:
        server.close()
        service.close()


async def test_a_second_client_takes_over_across_tcp_and_rfc2217() -> None:
    service, log, _ = make_service()
    tcp, _, tcp_port = await serve_tcp(service, "127.0.0.1", 0, "takeover")
    rfc, _, rfc_port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")

    def session() -> bytes:
        with socket.create_connection(("127.0.0.1", tcp_port), timeout=3) as sock:
            sock.sendall(b"WY")
            sock.recv(100)
            client = connect(rfc_port)
            try:
                client.write(b"WY")
                reply: bytes = client.read_until(b"\n")
            finally:
                client.close()
            assert sock.recv(100) == b""  # closed: taken over
            return reply

    try:
        assert await in_thread(session) == b"PC48 ver 3.00-4\n"
        assert "takes over from tcp:127.0.0.1:" in log.getvalue()
    finally:
        tcp.close()
        rfc.close()
        service.close()


class _Client:
    """What a VirtualPort needs of its connection, for the unit tests below."""

    def __init__(self, service: Any) -> None:
        self.service = service
        self.label = "rfc2217:test"
        self.lines: list[Line] = []

    def line_changed(self, line: Line) -> None:
        self.lines.append(line)

    def purge_output(self) -> int:
        return 3

    def purge_input(self) -> int:
        return 0


async def test_the_virtual_port_keeps_checks_and_logs_the_settings() -> None:
    service, log, _ = make_service()
    client = _Client(service)
    port = VirtualPort(client)  # type: ignore[arg-type]
    port.baudrate = 9600  # what it had: nothing said
    assert log.getvalue() == "" and client.lines == []
    port.baudrate = 38400
    port.stopbits = 2
    assert client.lines == [Line(38400), Line(38400, stopbits=2)]
    with pytest.raises(ValueError):
        port.bytesize = 9
    with pytest.raises(ValueError):
        port.parity = "X"
    port.rtscts = True
    port.reset_input_buffer()
    text = log.getvalue()
    assert "rfc2217:test: line 38400 8N1" in text and "line 38400 8N2" in text
    assert "RTS/CTS flow control on" in text
    assert "purged 3 bytes of the board's output not sent yet" in text
    service.close()


def test_escaping_matches_pyserial_s() -> None:
    from serial.rfc2217 import PortManager  # type: ignore[import-untyped]

    data = bytes(range(256)) * 2
    escaped = b"".join(PortManager.escape(None, data))
    assert escaped == data.replace(b"\xff", b"\xff\xff")


# -- a raw telnet client: what the RFC asks of the access server ------------------------------

IAC_SB_COM = b"\xff\xfa\x2c"  # IAC SB COM-PORT-OPTION
IAC_SE = b"\xff\xf0"
NEGOTIATION = b"\xff\xfb\x01\xff\xfb\x03\xff\xfd\x00\xff\xfb\x2c"  # what the server asks first
WY = b"PC48 ver 3.00-4\n"


def exchange(port: int, *sends: bytes, wait: float = 0.3) -> tuple[bytes, bool]:
    """Send each of ``sends`` (``wait`` seconds apart, then ``wait`` more) on a raw socket that
    negotiates nothing; return what came back and whether the server closed the connection."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        sock.settimeout(0.05)
        got = b""
        closed = False
        for data in (*sends, b""):
            if data:
                sock.sendall(data)
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline and not closed:
                try:
                    chunk = sock.recv(4096)
                except TimeoutError:
                    continue
                closed = not chunk
                got += chunk
        return got.removeprefix(NEGOTIATION), closed


@pytest.mark.parametrize(
    ("request_", "answer"),
    [
        (b"\xff\xf0", b""),  # IAC SE with no IAC SB before it
        (IAC_SB_COM + b"\x01\x00\x25" + IAC_SE, IAC_SB_COM + b"\x65\x00\x00\x25\x80" + IAC_SE),
        (IAC_SB_COM + b"\x03\x09" + IAC_SE, IAC_SB_COM + b"\x67\x01" + IAC_SE),  # parity 9
        (IAC_SB_COM + b"\x04\x04" + IAC_SE, IAC_SB_COM + b"\x68\x01" + IAC_SE),  # stop size 4
        (IAC_SB_COM + b"\x02" + IAC_SE, IAC_SB_COM + b"\x66\x08" + IAC_SE),  # no data size
        (IAC_SB_COM + b"\x0a" + IAC_SE, b""),  # SET-LINESTATE-MASK without its mask
        (IAC_SB_COM + b"\x0b" + IAC_SE, b""),  # SET-MODEMSTATE-MASK without its mask
        (IAC_SB_COM + b"\x05" + IAC_SE, b""),  # SET-CONTROL without its value
    ],
)
async def test_a_malformed_request_keeps_the_connection_and_the_commands_around_it(
    request_: bytes, answer: bytes
) -> None:
    """RFC 2217: SET-BAUD's "value is four octets", SET-PARITY's values are 0 to 5, SET-STOPSIZE's
    0 to 3. pyserial's PortManager raised on a short baud rate (struct.error), on an IAC SE with
    no IAC SB (TypeError) and on a mask left out (TypeError): asyncio closed the connection, and
    the WY before it in the same read was lost with it; an unknown parity or stop size (KeyError)
    dropped the whole read, the commands before and after it too, and got no answer. Now the
    request is ignored (a setting: answered with the port's current one, 9600 8N1), the
    connection stays, and both WY are answered."""
    service, log, recorder = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    try:
        got, closed = await in_thread(lambda: exchange(port, b"WY" + request_ + b"WY"))
        assert not closed
        assert got.count(WY) == 2 and got.replace(WY, b"") == answer  # in either order
        assert recorder.received() == b"WYWY"
        assert "RFC 2217: ignored" in log.getvalue()
        assert "Fatal error" not in log.getvalue()
    finally:
        server.close()
        service.close()


@pytest.mark.parametrize(
    ("request_", "answer"),
    [
        (b"\x05\x04", b"\x69\x06"),  # Request BREAK State: off
        (b"\x05\x07", b"\x69\x08"),  # Request DTR Signal State: on
        (b"\x05\x0a", b"\x69\x0b"),  # Request RTS Signal State: on
        (b"\x05\x0d", b"\x69\x0e"),  # Request Com Port Flow Control Setting (inbound): none
        (b"\x05\x11", b"\x69\x01"),  # Use DCD Flow Control: not done, the setting stays none
        (b"\x0a\x10", b"\x6e\x10"),  # SET-LINESTATE-MASK, echoed
        (b"\x0b\xff\xff", b"\x6f\xff\xff"),  # SET-MODEMSTATE-MASK 0xFF, IAC doubled both ways
        (b"\x00", b"\x64omsd board1 PC48-4E"),  # SIGNATURE without text: a request for ours
    ],
)
async def test_queries_are_answered_as_the_rfc_says(request_: bytes, answer: bytes) -> None:
    """RFC 2217, SET-CONTROL: "The command can also be sent to query the current option value"
    (4 Request BREAK State, 7 Request DTR Signal State, 10 Request RTS Signal State, 13 Request
    Com Port Flow Control Setting (inbound)); SIGNATURE: "If the command is sent without <text>
    it is a request from the sender to receive the signature text of the receiver". The access
    server answers with the command's code plus 100. pyserial's PortManager logged "not
    implemented" and answered nothing, so a client waiting for the answer waited for ever."""
    service, _, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    try:
        got, closed = await in_thread(lambda: exchange(port, IAC_SB_COM + request_ + IAC_SE))
        assert not closed
        assert got == IAC_SB_COM + answer + IAC_SE
    finally:
        server.close()
        service.close()


async def test_flowcontrol_suspend_holds_the_board_s_output_until_resume() -> None:
    """RFC 2217, FLOWCONTROL-SUSPEND: "The sender of this command is requesting that the receiver
    suspend transmission of both data and commands until the FLOWCONTROL-RESUME is transmitted
    by the sender." pyserial's PortManager noted it and nothing held the board's output back:
    the reply to WY came while suspended. Now it is held (nothing lost) and sent on resume."""
    service, _, recorder = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    suspend = IAC_SB_COM + b"\x08" + IAC_SE
    resume = IAC_SB_COM + b"\x09" + IAC_SE
    baud = IAC_SB_COM + b"\x01\x00\x00\x00\x00" + IAC_SE  # a query: its answer is held too

    def session() -> tuple[bytes, bytes]:
        with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
            sock.sendall(suspend + b"WY" + baud)
            time.sleep(0.5)
            sock.settimeout(0.05)
            before = b""
            with contextlib.suppress(TimeoutError):
                while True:
                    before += sock.recv(4096)
            sock.settimeout(5)
            sock.sendall(resume)
            after = b""
            while WY not in after or IAC_SE not in after:
                after += sock.recv(4096)
            return before, after

    try:
        before, after = await in_thread(session)
        assert before == NEGOTIATION  # nothing after the suspend
        assert after.replace(WY, b"") == IAC_SB_COM + b"\x65\x00\x00\x25\x80" + IAC_SE
        assert recorder.received() == b"WY"
    finally:
        server.close()
        service.close()


async def test_telnet_answers_to_a_client_that_never_reads_are_bounded() -> None:
    """Every query is answered (SIGNATURE's request, 6 bytes, with some 20), and the answers went
    to the socket whatever it held: a client that sent queries and never read them had the
    daemon's memory grow without end (70 MB in 8 s). Past MAX_PENDING_OUTPUT unsent, they are
    dropped, as the board's output is (omsd.transport.tcp: "is not reading; dropping output")."""
    from omsd.transport.tcp import MAX_PENDING_OUTPUT

    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    signature = IAC_SB_COM + b"\x00" + IAC_SE
    sock = socket.socket()
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    sock.setblocking(False)
    try:
        await asyncio.get_running_loop().sock_connect(sock, ("127.0.0.1", port))
        await until(lambda: bool(service.clients))
        client = service.clients[0]
        burst = signature * 20_000
        for _ in range(40):  # 4.8 MB of queries, some 16 MB of answers
            await asyncio.get_running_loop().sock_sendall(sock, burst)
        await until(lambda: "dropping output" in log.getvalue())
        await asyncio.sleep(0.2)
        transport = client.transport
        assert transport is not None
        assert transport.get_write_buffer_size() <= MAX_PENDING_OUTPUT + 4096
    finally:
        sock.close()
        server.close()
        service.close()


@pytest.mark.parametrize("baud", [1, 49, 10_000_001, 0xFFFFFFFF])
async def test_a_baud_rate_no_line_runs_at_is_refused_with_the_current_one(baud: int) -> None:
    """RFC 2217, SET-BAUD: "the value is the baud rate being requested"; the access server answers
    with the rate the port has. The OMS manuals know no serial line (no "baud" in any of them);
    a serial endpoint takes 50 to 10000000 baud (BAUD_MIN, BAUD_MAX), what a UART of a device
    server runs at. Any positive rate was taken, so 1 baud with pacing on gave the board's output
    ten seconds a character; now the port keeps 9600 and says so (101 00 00 25 80)."""
    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    request = IAC_SB_COM + b"\x01" + baud.to_bytes(4, "big").replace(b"\xff", b"\xff\xff")
    try:
        got, closed = await in_thread(lambda: exchange(port, request + IAC_SE + b"WY"))
        assert not closed
        assert got.replace(WY, b"") == IAC_SB_COM + b"\x65\x00\x00\x25\x80" + IAC_SE
        assert "line " not in log.getvalue()  # no change of the line
    finally:
        server.close()
        service.close()


async def test_the_flow_control_set_last_is_the_one_the_port_has() -> None:
    """RFC 2217, SET-CONTROL: 1 Use No Flow Control, 2 Use XON/XOFF Flow Control, 3 Use HARDWARE
    Flow Control (outbound/both): three values of one setting, and value 0 asks which it is.
    pyserial's PortManager set XON/XOFF on for 2 and RTS/CTS on for 3 without turning the other
    off: after 2 then 3 the port had both, logged both on, and answered the query with 2."""
    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    control = [IAC_SB_COM + b"\x05" + bytes([value]) + IAC_SE for value in (2, 3, 0)]
    try:
        got, _ = await in_thread(lambda: exchange(port, b"".join(control)))
        answers = [IAC_SB_COM + b"\x69" + bytes([value]) + IAC_SE for value in (2, 3, 3)]
        assert got == b"".join(answers)
        text = log.getvalue()
        assert "XON/XOFF flow control on" in text and "RTS/CTS flow control on" in text
        assert "XON/XOFF flow control off" in text
    finally:
        server.close()
        service.close()


@pytest.mark.parametrize(
    ("offer", "refusal"),
    [
        (b"\xff\xfb\x01", b"\xff\xfe\x01"),  # WILL ECHO: DONT ECHO
        (b"\xff\xfd\x01\xff\xfb\x01", b"\xff\xfe\x01"),  # DO ECHO accepts (no answer)
        (b"\xff\xfb\x18", b"\xff\xfe\x18"),  # WILL TERMINAL-TYPE (unknown): DONT
        (b"\xff\xfd\x1f", b"\xff\xfc\x1f"),  # DO NAWS (unknown): WONT
    ],
)
async def test_an_option_offered_that_is_not_wanted_is_refused(
    offer: bytes, refusal: bytes
) -> None:
    """RFC 854 (and RFC 1143): a WILL or a DO is answered, DO or WILL to accept, DONT or WONT to
    refuse; a telnet client that offers an option waits for the answer. The access server asks
    WILL ECHO (it echoes, the client need not); pyserial's PortManager knew ECHO only as its
    own, so a client's WILL ECHO (the client would echo) got no answer at all. Unknown options
    were refused already, each with a warning: a telnet client offers half a dozen (terminal
    type, window size, speed...) on every connection, which is not something wrong."""
    service, log, _ = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    try:
        got, _ = await in_thread(lambda: exchange(port, offer))
        assert got == refusal
        assert "warning" not in log.getvalue()
    finally:
        server.close()
        service.close()


@pytest.mark.parametrize(
    ("binary", "received"),
    [
        (b"\xff\xfc\x00", b"WY\rRP\r\x00\r"),  # WONT BINARY: NVT, CR NUL is a CR
        (b"\xff\xfb\x00", b"WY\r\x00RP\r\x00\x00\r\x00"),  # WILL BINARY: every byte is data
        (b"", b"WY\r\x00RP\r\x00\x00\r\x00"),  # nothing negotiated: as it was, every byte
    ],
)
async def test_a_client_that_refuses_binary_has_its_cr_nul_taken_as_cr(
    binary: bytes, received: bytes
) -> None:
    """RFC 854, the NVT: "the sequence "CR NUL" must be used where a carriage return alone is
    actually desired". The access server asks the client for binary (IAC DO BINARY); a client
    that refuses (IAC WONT BINARY) sends its line ends as CR NUL, and the NUL reached the board
    as a character ("command error: Invalid character: <00>", its error marker in the reply).
    Now, for such a client, CR NUL is CR, also when the two come in two reads; a client in
    binary, or one that negotiates nothing, has every byte passed as before."""
    service, _, recorder = make_service()
    server, _, port = await serve_rfc2217(service, "127.0.0.1", 0, "takeover")
    try:
        await in_thread(lambda: exchange(port, binary + b"WY\r\x00RP\r", b"\x00\x00\r\x00"))
        assert recorder.received() == received
    finally:
        server.close()
        service.close()
