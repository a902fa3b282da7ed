"""The access server's side of RFC 2217 (Telnet Com Port Control Option): pyserial's
``PortManager`` (negotiation, the settings and their answers), with what it lacks for a client
that is not pyserial's own.

RFC 2217 calls the server the *access server*; it answers each command of the client with the
command's code plus 100. What :class:`AccessServer` changes of pyserial 3.5's ``PortManager``:

- Its filter (what the client sent, the telnet taken out) returns the data at once and never
  raises. PortManager's raised on an IAC SE with no IAC SB before it, and on a subnegotiation
  too short for its command (a baud rate of fewer than four octets, a mask left out), so asyncio
  closed the connection and the data of the same read was lost with it; an unknown parity or
  stop size dropped the read. A bad request is now logged as ignored (a setting: answered with
  the port's current one) and the data around it goes on to the board. A subnegotiation keeps
  its first ``MAX_SUBOPTION`` bytes, the rest up to IAC SE is dropped.
- The queries PortManager left unanswered are answered: SET-CONTROL's Request BREAK State,
  Request DTR Signal State, Request RTS Signal State and Request Com Port Flow Control Setting
  (inbound); SIGNATURE without text (a request for ours). The inbound, DCD, DTR and DSR flow
  controls it ignored are refused by answering the setting the port keeps. SET-LINESTATE-MASK
  and SET-MODEMSTATE-MASK are answered with the mask taken (110, 111). XON/XOFF and hardware
  flow control are two values of one setting: one set turns the other off.
- FLOWCONTROL-SUSPEND and FLOWCONTROL-RESUME from the client are passed to ``flow`` (the
  connection holds what it sends meanwhile, data and commands, as the RFC asks).
- A WILL or DO it does not expect is refused (DONT, WONT), quietly: PortManager left a client's
  WILL ECHO unanswered and gave a warning for each option it did not know. A telnet NOP (a
  keep-alive) is taken quietly.
- A client that refuses binary (IAC WONT BINARY) speaks the NVT: its CR NUL is a CR (RFC 854).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from serial import rfc2217  # type: ignore[import-untyped]

MAX_SUBOPTION = 1024
"""Bytes of one subnegotiation (IAC SB ... IAC SE) kept, at most: RFC 2217's are a few bytes
(a baud rate is four), and PortManager kept all a client sent until IAC SE, were it gigabytes."""

IAC = 0xFF
_SE = rfc2217.SE
_SB = rfc2217.SB
_NEGOTIATIONS = (rfc2217.DO, rfc2217.DONT, rfc2217.WILL, rfc2217.WONT)
_M_NORMAL = rfc2217.M_NORMAL
_M_IAC_SEEN = rfc2217.M_IAC_SEEN
_M_NEGOTIATE = rfc2217.M_NEGOTIATE

# RFC 2217's client commands (the access server answers with each plus 100)
SIGNATURE = 0
SET_BAUDRATE = 1
SET_DATASIZE = 2
SET_PARITY = 3
SET_STOPSIZE = 4
SET_CONTROL = 5
FLOWCONTROL_SUSPEND = 8
FLOWCONTROL_RESUME = 9
SET_LINESTATE_MASK = 10
SET_MODEMSTATE_MASK = 11
SERVER = 100

# SET-CONTROL's values
_FLOW_NONE, _FLOW_XONXOFF, _FLOW_HARDWARE = 1, 2, 3
_REQUEST_BREAK, _BREAK_ON, _BREAK_OFF = 4, 5, 6
_REQUEST_DTR, _DTR_ON, _DTR_OFF = 7, 8, 9
_REQUEST_RTS, _RTS_ON, _RTS_OFF = 10, 11, 12
_REQUEST_INBOUND, _INBOUND_NONE, _INBOUND_XONXOFF, _INBOUND_HARDWARE = 13, 14, 15, 16
_DCD_FLOW, _DTR_FLOW, _DSR_FLOW = 17, 18, 19

# the octets of value a command needs (SET-BAUD's "value is four octets", the others' one)
_LENGTHS = {
    SET_BAUDRATE: 4,
    SET_DATASIZE: 1,
    SET_PARITY: 1,
    SET_STOPSIZE: 1,
    SET_CONTROL: 1,
    SET_LINESTATE_MASK: 1,
    SET_MODEMSTATE_MASK: 1,
}


class AccessServer(rfc2217.PortManager):  # type: ignore[misc]
    """pyserial's PortManager for one connection, robust to any bytes (see the module)."""

    # PortManager's filter state: M_NORMAL, M_IAC_SEEN or M_NEGOTIATE; the subnegotiation being
    # read (None between them); the DO, DONT, WILL or WONT whose option comes next
    mode: int
    suboption: bytearray | None
    telnet_command: bytes | None

    def __init__(
        self,
        port: Any,
        connection: Any,
        logger: Any,
        signature: str,
        flow: Callable[[bool], None],
    ) -> None:
        self._signature = signature.encode("ascii", "replace")
        self._flow = flow
        self._nvt = False  # the client refused binary: its CR NUL is a CR
        self._after_cr = False  # an NVT client's last data byte was a CR
        super().__init__(port, connection, logger)
        self._they_binary = next(o for o in self._telnet_options if o.name == "they-BINARY")

    # -- in: the telnet out of the data -------------------------------------------------------

    def filter(self, data: bytes) -> bytes:
        """The data in what the client sent, its telnet commands handled (PortManager's filter,
        all of a read at once, a run of data at a time)."""
        if self.mode == _M_NORMAL and self.suboption is None and IAC not in data and not self._nvt:
            return data  # no telnet in it: the bytes are the data
        out = bytearray()
        at, size = 0, len(data)
        while at < size:
            if self.mode == _M_NORMAL:
                iac = data.find(IAC, at)
                end = size if iac < 0 else iac
                self._data(out, data[at:end])
                if iac < 0:
                    break
                self.mode = _M_IAC_SEEN
                at = iac + 1
                continue
            byte = data[at : at + 1]
            at += 1
            if self.mode == _M_NEGOTIATE:
                self.mode = _M_NORMAL
                self._safely(self._telnet_negotiate_option, self.telnet_command, byte)
                continue
            self.mode = _M_NORMAL
            if byte == rfc2217.IAC:  # doubled: a 0xFF of the data
                self._data(out, byte)
            elif byte == _SB:
                self.suboption = bytearray()
            elif byte == _SE:
                if self.suboption is None:
                    self._ignored("an IAC SE with no IAC SB before it")
                else:
                    suboption = bytes(self.suboption)
                    self.suboption = None
                    self._safely(self._telnet_process_subnegotiation, suboption)
            elif byte in _NEGOTIATIONS:
                self.telnet_command = byte
                self.mode = _M_NEGOTIATE
            elif byte != rfc2217.NOP:  # a keep-alive, nothing to say
                self._safely(self._telnet_process_command, byte)
        if self._nvt and out:
            # RFC 854: "CR NUL" where a carriage return alone is meant
            if self._after_cr and out[0] == 0:
                del out[0]
            out = out.replace(b"\r\x00", b"\r")
            self._after_cr = out.endswith(b"\r")
        return bytes(out)

    def _data(self, out: bytearray, data: bytes) -> None:
        suboption = self.suboption
        if suboption is None:
            out += data
        elif len(suboption) < MAX_SUBOPTION:  # the rest, up to IAC SE, is dropped
            suboption += data[: MAX_SUBOPTION - len(suboption)]

    def _safely(self, handle: Callable[..., None], *args: Any) -> None:
        try:
            handle(*args)
        except Exception as exc:  # a request a client got wrong ends nothing
            self._ignored(f"a bad request ({exc!r})")

    def _ignored(self, what: str) -> None:
        if self.logger:
            self.logger.warning(f"ignored {what}")

    # -- negotiation: an offer is always answered ---------------------------------------------

    def _telnet_negotiate_option(self, command: bytes, option: bytes) -> None:
        """A WILL, WONT, DO or DONT from the client. PortManager's options each answer the
        commands they expect; a WILL or DO none expects (the client's WILL ECHO: ECHO is ours
        only; an option PortManager does not know, such as a telnet client's terminal type or
        window size) is refused with DONT or WONT, without a warning: RFC 854 has every offer
        answered, and a telnet client makes several on every connection."""
        expected = any(
            item.option == option and command in (item.ack_yes, item.ack_no)
            for item in self._telnet_options
        )
        if expected:
            super()._telnet_negotiate_option(command, option)
            self._nvt = self._they_binary.state is rfc2217.INACTIVE  # refused, or ended
        elif command in (rfc2217.WILL, rfc2217.DO):
            refusal = rfc2217.DONT if command == rfc2217.WILL else rfc2217.WONT
            self.telnet_send_option(refusal, option)

    # -- the subnegotiations PortManager gets wrong or leaves out -----------------------------

    def _telnet_process_subnegotiation(self, suboption: bytes) -> None:
        if suboption[:1] != rfc2217.COM_PORT_OPTION or len(suboption) < 2:
            super()._telnet_process_subnegotiation(suboption)
            return
        command, value = suboption[1], suboption[2:]
        port = self.serial
        if len(value) < _LENGTHS.get(command, 0):
            self._ignored(f"a short request (command {command}, {len(value)} bytes of value)")
            self._answer_setting(command)
        elif command == SIGNATURE:
            if not value:  # with text, it is the client's own: nothing to answer
                self._answer(SIGNATURE, self._signature)
        elif command == SET_PARITY and value[0] not in (0, *rfc2217.RFC2217_REVERSE_PARITY_MAP):
            self._ignored(f"parity {value[0]}")
            self._answer_setting(command)
        elif command == SET_STOPSIZE and value[0] not in (0, *rfc2217.RFC2217_REVERSE_STOPBIT_MAP):
            self._ignored(f"stop size {value[0]}")
            self._answer_setting(command)
        elif command == SET_CONTROL and value[0] == _REQUEST_BREAK:
            self._answer(SET_CONTROL, bytes([_BREAK_ON if port.break_condition else _BREAK_OFF]))
        elif command == SET_CONTROL and value[0] == _REQUEST_DTR:
            self._answer(SET_CONTROL, bytes([_DTR_ON if port.dtr else _DTR_OFF]))
        elif command == SET_CONTROL and value[0] == _REQUEST_RTS:
            self._answer(SET_CONTROL, bytes([_RTS_ON if port.rts else _RTS_OFF]))
        elif command == SET_CONTROL and value[0] in (_REQUEST_INBOUND, *_INBOUND_FLOWS):
            if value[0] != _REQUEST_INBOUND:
                self._ignored(f"inbound flow control {value[0]}: the port's stays")
            self._answer(SET_CONTROL, bytes([self._inbound()]))
        elif command == SET_CONTROL and value[0] in (_DCD_FLOW, _DSR_FLOW):
            self._ignored(f"flow control {value[0]}: the port's stays")
            self._answer(SET_CONTROL, bytes([self._outbound()]))
        elif command == SET_CONTROL and value[0] in (_FLOW_XONXOFF, _FLOW_HARDWARE):
            # one setting of three values: the other one goes off (PortManager left it on)
            if value[0] == _FLOW_XONXOFF:
                port.rtscts = False
            else:
                port.xonxoff = False
            super()._telnet_process_subnegotiation(suboption)
        elif command in (FLOWCONTROL_SUSPEND, FLOWCONTROL_RESUME):
            self._flow(command == FLOWCONTROL_SUSPEND)
        elif command == SET_LINESTATE_MASK:
            self.linstate_mask = value[0]
            self._answer(SET_LINESTATE_MASK, value[:1])
        elif command == SET_MODEMSTATE_MASK:
            self.modemstate_mask = value[0]
            self._answer(SET_MODEMSTATE_MASK, value[:1])
        else:
            super()._telnet_process_subnegotiation(suboption)

    def _answer(self, command: int, value: bytes) -> None:
        self.rfc2217_send_subnegotiation(bytes([SERVER + command]), value)

    def _answer_setting(self, command: int) -> None:
        """Answer a setting that was not made with the port's current one."""
        port = self.serial
        if command == SET_BAUDRATE:
            self._answer(command, struct.pack("!I", port.baudrate))
        elif command == SET_DATASIZE:
            self._answer(command, bytes([port.bytesize]))
        elif command == SET_PARITY:
            self._answer(command, rfc2217.RFC2217_PARITY_MAP[port.parity].to_bytes(1, "big"))
        elif command == SET_STOPSIZE:
            self._answer(command, rfc2217.RFC2217_STOPBIT_MAP[port.stopbits].to_bytes(1, "big"))

    def _outbound(self) -> int:
        port = self.serial
        return _FLOW_XONXOFF if port.xonxoff else _FLOW_HARDWARE if port.rtscts else _FLOW_NONE

    def _inbound(self) -> int:
        return {_FLOW_XONXOFF: _INBOUND_XONXOFF, _FLOW_HARDWARE: _INBOUND_HARDWARE}.get(
            self._outbound(), _INBOUND_NONE
        )


_INBOUND_FLOWS = (_INBOUND_NONE, _INBOUND_XONXOFF, _INBOUND_HARDWARE, _DTR_FLOW)

__all__ = ["MAX_SUBOPTION", "AccessServer"]
