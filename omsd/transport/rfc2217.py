"""RFC 2217 endpoints: a board on a telnet COM-port-control socket, as a serial device server
(a Moxa NPort, ser2net, pyserial's ``rfc2217_server.py``) would put the card's port on the
network.

A client (pyserial's ``serial_for_url("rfc2217://HOST:PORT")``, a Windows COM-port redirector,
``socat``'s or ``ser2net``'s) connects, negotiates the telnet options and sets the port as it
would a local one: baud rate, data bits, parity, stop bits, flow control, DTR and RTS, a break.
The telnet side is pyserial's own server code (``serial.rfc2217.PortManager``, as
:class:`omsd.transport.access_server.AccessServer` mends it): it answers the negotiation, takes
the telnet commands out of what the client sends (:meth:`Rfc2217Client._take`, before the bytes
reach the board) and is told the settings through a :class:`VirtualPort`, which keeps them, logs
each change (one line in the traffic log: ``line 19200 8N1``, ``DTR off``, ``break on``) and,
with ``pacing`` on, paces the board's output at the line the client set
(:class:`omsd.pacing.Pacer`). The modem lines it reports are those of a card that is there and
ready: CTS, DSR and CD on, RI off. The board's bytes are escaped on the way out (an IAC, 0xFF,
doubled), so any byte passes both ways. While the client has suspended the flow
(FLOWCONTROL-SUSPEND) what goes to it is held until it resumes. Telnet answers, like the
board's output, are dropped once :data:`omsd.transport.tcp.MAX_PENDING_OUTPUT` bytes wait
unsent (a client that asks and never reads).

Otherwise it is a TCP endpoint (:class:`omsd.transport.tcp.TcpClient`): one client at a time,
shared with the board's plain TCP endpoints (``second_client``), each connection a session of
the board's service, ``linger`` for a client that stops sending. Plain TCP endpoints are not
affected: they pass bytes untouched, 0xFF included.
"""

from __future__ import annotations

import asyncio
from typing import Any

from omsd.defaults import BAUD_MAX, BAUD_MIN
from omsd.hostport import host_port
from omsd.pacing import Line, Pacer
from omsd.service import BoardService
from omsd.transport import bound_address
from omsd.transport.tcp import MAX_PENDING_OUTPUT, READ_SIZE, TcpClient

IAC = b"\xff"

# The buffer every RFC 2217 connection reads into (see omsd.transport.tcp's, same reasoning: the
# loop calls get_buffer and buffer_updated back to back on its one thread).
_READ_BUFFER = memoryview(bytearray(READ_SIZE))


class VirtualPort:
    """The serial port a :class:`~serial.rfc2217.PortManager` manages: the settings the client
    made, kept, logged when they change, and given to the pacer. What PortManager reads and sets
    (pyserial 3.5): ``baudrate``, ``bytesize``, ``parity``, ``stopbits``, ``xonxoff``,
    ``rtscts``, ``dtr``, ``rts``, ``break_condition``; it reads ``cts``, ``dsr``, ``ri``,
    ``cd`` and calls ``reset_input_buffer`` / ``reset_output_buffer`` (a purge)."""

    def __init__(self, client: Rfc2217Client) -> None:
        self._client = client
        self._line = Line()
        self._xonxoff = False
        self._rtscts = False
        self._dtr = True  # a port just opened: DTR and RTS on
        self._rts = True
        self._break = False
        # the card is there and ready
        self.cts = True
        self.dsr = True
        self.cd = True
        self.ri = False

    @property
    def line(self) -> Line:
        return self._line

    def _say(self, what: str) -> None:
        client = self._client
        client.service.log.info(f"{client.service.name}: {client.label}: {what}")

    def _set_line(self, line: Line) -> None:
        if line != self._line:
            self._line = line
            self._say(f"line {line}")
            self._client.line_changed(line)

    # -- the line -------------------------------------------------------------------------------

    @property
    def baudrate(self) -> int:
        return self._line.baud

    @baudrate.setter
    def baudrate(self, value: int) -> None:
        # what a serial endpoint takes (a device server's UART): PortManager answers a rate
        # refused with the one the port keeps
        if not isinstance(value, int) or not BAUD_MIN <= value <= BAUD_MAX:
            raise ValueError(f"not a baud rate {BAUD_MIN}..{BAUD_MAX}: {value!r}")
        self._set_line(Line(value, self._line.bytesize, self._line.parity, self._line.stopbits))

    @property
    def bytesize(self) -> int:
        return self._line.bytesize

    @bytesize.setter
    def bytesize(self, value: int) -> None:
        if value not in (5, 6, 7, 8):
            raise ValueError(f"not a data size: {value!r}")
        self._set_line(Line(self._line.baud, value, self._line.parity, self._line.stopbits))

    @property
    def parity(self) -> str:
        return self._line.parity

    @parity.setter
    def parity(self, value: str) -> None:
        if value not in ("N", "E", "O", "M", "S"):
            raise ValueError(f"not a parity: {value!r}")
        self._set_line(Line(self._line.baud, self._line.bytesize, value, self._line.stopbits))

    @property
    def stopbits(self) -> float:
        stop = self._line.stopbits
        return int(stop) if stop == int(stop) else stop  # PortManager looks 1 and 2 up as ints

    @stopbits.setter
    def stopbits(self, value: float) -> None:
        if value not in (1, 1.5, 2):
            raise ValueError(f"not a number of stop bits: {value!r}")
        self._set_line(Line(self._line.baud, self._line.bytesize, self._line.parity, value))

    # -- flow control and the control lines ----------------------------------------------------

    @property
    def xonxoff(self) -> bool:
        return self._xonxoff

    @xonxoff.setter
    def xonxoff(self, value: bool) -> None:
        if value != self._xonxoff:
            self._xonxoff = value
            self._say(f"XON/XOFF flow control {'on' if value else 'off'}")

    @property
    def rtscts(self) -> bool:
        return self._rtscts

    @rtscts.setter
    def rtscts(self, value: bool) -> None:
        if value != self._rtscts:
            self._rtscts = value
            self._say(f"RTS/CTS flow control {'on' if value else 'off'}")

    @property
    def dtr(self) -> bool:
        return self._dtr

    @dtr.setter
    def dtr(self, value: bool) -> None:
        if value != self._dtr:
            self._dtr = value
            self._say(f"DTR {'on' if value else 'off'}")

    @property
    def rts(self) -> bool:
        return self._rts

    @rts.setter
    def rts(self, value: bool) -> None:
        if value != self._rts:
            self._rts = value
            self._say(f"RTS {'on' if value else 'off'}")

    @property
    def break_condition(self) -> bool:
        return self._break

    @break_condition.setter
    def break_condition(self, value: bool) -> None:
        if value != self._break:
            self._break = value
            self._say(f"break {'on' if value else 'off'}")

    def reset_input_buffer(self) -> None:
        """Purge what the port received and has not sent to the client: the board's paced
        output."""
        dropped = self._client.purge_output()
        if dropped:
            self._say(f"purged {dropped} bytes of the board's output not sent yet")

    def reset_output_buffer(self) -> None:
        """Purge what the client sent and the port has not passed on: what the board has not
        taken."""
        dropped = self._client.purge_input()
        if dropped:
            self._say(f"purged {dropped} bytes of its input the board had not taken")


class _Raw:
    """The connection PortManager writes its telnet answers to: the socket, unescaped (held,
    as the data is, while the client has suspended the flow)."""

    def __init__(self, client: Rfc2217Client) -> None:
        self._client = client

    def write(self, data: bytes) -> None:
        self._client.wire(data)


class _Logger:
    """PortManager's logger: its warnings and errors (an option refused, a bad setting) go to the
    daemon's log; its info and debug lines are left out (:class:`VirtualPort` logs the settings
    that change), but for the negotiation's success, said once."""

    def __init__(self, client: Rfc2217Client) -> None:
        self._client = client

    def _line(self, message: str) -> str:
        client = self._client
        return f"{client.service.name}: {client.label}: RFC 2217: {message}"

    def debug(self, message: str, *args: Any) -> None:
        pass

    def info(self, message: str, *args: Any) -> None:
        if message == "client accepts RFC 2217" and not self._client.negotiated:
            self._client.negotiated = True
            self._client.service.log.info(self._line("negotiated"))

    def warning(self, message: str, *args: Any) -> None:
        self._client.service.log.warning(self._line(message))

    error = warning


class Rfc2217Client(TcpClient):
    """One RFC 2217 connection: a :class:`TcpClient` whose bytes in go through the telnet filter
    before the board sees them and whose bytes out are escaped (and paced, with ``pacing``)."""

    def __init__(
        self, service: BoardService, endpoint: str, policy: str, pacing: bool = False
    ) -> None:
        super().__init__(service, endpoint, policy)
        self.port = VirtualPort(self)
        self.manager: Any = None  # an AccessServer (a PortManager), once connected
        self.negotiated = False
        self._held: bytearray | None = None  # the wire's bytes while the client suspends
        self._held_dropping = False
        self.pacer: Pacer | None = None
        self._pacing = pacing

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        super().connection_made(transport)
        if self.transport is None:  # refused, or the cable is cut
            return
        from omsd.transport.access_server import AccessServer

        if self._pacing:
            self.pacer = Pacer(asyncio.get_running_loop(), self.port.line.chars_per_second)
        # it sends its option requests at once
        service = self.service
        signature = f"omsd {service.name} {service.model.name}"
        self.manager = AccessServer(self.port, _Raw(self), _Logger(self), signature, self.suspend)

    def line_changed(self, line: Line) -> None:
        if self.pacer is not None:
            self.pacer.chars_per_second = line.chars_per_second

    # -- in: telnet commands out of the way ----------------------------------------------------

    def get_buffer(self, sizehint: int) -> memoryview:
        return _READ_BUFFER

    def buffer_updated(self, nbytes: int) -> None:
        self.data_received(bytes(_READ_BUFFER[:nbytes]))

    def _take(self, data: bytes) -> None:
        """What the client wrote, its telnet commands handled and taken out (every way in goes
        through here: a read, and a connection being taken over)."""
        manager = self.manager
        if manager is not None:
            data = self._filter(manager, data)
        super()._take(data)

    def _filter(self, manager: Any, data: bytes) -> bytes:
        filtered: bytes = manager.filter(data)  # as it came when there is no telnet in it
        return filtered

    # -- out: escaped, and paced --------------------------------------------------------------

    def send(self, data: bytes) -> None:
        if self.pacer is not None:
            self.pacer.send(self._write, data)
        else:
            self._write(data)

    def _write(self, data: bytes) -> None:
        data = data.replace(IAC, IAC + IAC)
        if self._held is not None:
            self.wire(data)
        else:
            super()._write(data)

    def wire(self, data: bytes) -> None:
        """Bytes for the socket as they are (telnet, or data escaped), held while the client
        has suspended the flow: RFC 2217's FLOWCONTROL-SUSPEND asks the receiver to "suspend
        transmission of both data and commands until the FLOWCONTROL-RESUME"."""
        held = self._held
        if held is None:
            # the socket's own bound: a client that asks (every query is answered) and never
            # reads has its answers dropped as the board's output is (TcpClient._write)
            super()._write(data)
        elif len(held) + len(data) <= MAX_PENDING_OUTPUT:
            held += data
        elif not self._held_dropping:
            self._held_dropping = True
            self.service.log.warning(
                f"{self.service.name}: {self.label} has suspended the flow too long; "
                "dropping output"
            )

    def suspend(self, suspended: bool) -> None:
        """FLOWCONTROL-SUSPEND (True) or FLOWCONTROL-RESUME (False) from the client."""
        held = self._held
        if suspended and held is None:
            self._held = bytearray()
        elif not suspended and held is not None:
            self._held = None
            self._held_dropping = False
            self.wire(bytes(held))

    # -- purges, and the end ------------------------------------------------------------------

    def purge_output(self) -> int:
        return self.pacer.clear() if self.pacer is not None else 0

    def purge_input(self) -> int:
        dropped = len(self._pending)
        self._pending.clear()
        self._flow()
        return dropped

    def connection_lost(self, exc: Exception | None) -> None:
        if self.pacer is not None:
            self.pacer.clear()
        self._held = None
        super().connection_lost(exc)


async def serve_rfc2217(
    service: BoardService, host: str, port: int, policy: str, pacing: bool = False
) -> tuple[asyncio.Server, str, int]:
    """Listen for RFC 2217 clients of the board; returns the server and the address bound (port
    0 asks the system for a free port)."""
    loop = asyncio.get_running_loop()
    label = [f"rfc2217:{host_port(host, port)}"]
    server = await loop.create_server(
        lambda: Rfc2217Client(service, label[0], policy, pacing), host, port, reuse_address=True
    )
    bound = bound_address(server, host)
    label[0] = f"rfc2217:{host_port(*bound)}"
    return server, *bound


__all__ = ["Rfc2217Client", "VirtualPort", "serve_rfc2217"]
