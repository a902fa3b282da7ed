"""What comes out of a board: reply bytes and the events the host learns of through registers.

PC48 §3.3: "Interrupts for input buffer full (IBF), transmit buffer empty (TBE), overtravel fault
and operation complete are provided." Done, limit, slip and command error produce *no bytes* on
the data port of a real card; the host sees them in the status and done-flag registers (Tables
3-6 to 3-8). The board reports them here as events, in time order with the reply bytes, so that
a link discipline can turn them into the DOS driver's ``! @ $ #`` markers (PC48 §7.3.3) and the
traffic log can show them.
"""

from __future__ import annotations

from dataclasses import dataclass

from omsd.protocol.errors import ErrorKind


@dataclass(slots=True)
class Reply:
    """Bytes the board writes to its data port.

    ``text`` is the payload of a framed reply (``data`` without its ``<LF><CR>`` or
    ``<LF><CR><CR>`` framing), or ``None`` for echoed characters, which are not framed. A link
    discipline that replaces the board's framing (the DOS driver's end-of-string character)
    uses it; the raw link sends ``data`` as it is.

    Treat it as a value: nobody changes a reply once it is made. It is not declared frozen
    because one is built for every reply the board gives (a frozen dataclass's ``__init__``
    goes through ``object.__setattr__`` for each field, three times the cost; issue 16).
    """

    time: float
    data: bytes
    text: bytes | None = None


@dataclass(frozen=True, slots=True)
class DoneEvent:
    """DON_S was set by a completion (ID, II, IN, IP); ``axes`` is the done-flag register then."""

    time: float
    done_register: int


@dataclass(frozen=True, slots=True)
class LimitEvent:
    """An axis ran into an enabled limit switch (status OVRT); ``direction`` is +1 or -1."""

    time: float
    axis: str
    direction: int


@dataclass(frozen=True, slots=True)
class SlipEvent:
    """Slip or stall detected with IS enabled (status ENC_S)."""

    time: float
    axis: str


@dataclass(frozen=True, slots=True)
class ServoTripEvent:
    """A servo axis's following error passed the runaway limit and its loop opened (PCIx
    §2.7.2). ``error`` is the following error, counts."""

    time: float
    axis: str
    error: float


@dataclass(frozen=True, slots=True)
class CommandErrorEvent:
    """The command-error flag CMD_S was set."""

    time: float
    kind: ErrorKind
    command: str


__all__ = [
    "CommandErrorEvent",
    "DoneEvent",
    "ErrorKind",
    "Event",
    "LimitEvent",
    "Output",
    "Reply",
    "ServoTripEvent",
    "SlipEvent",
    "describe",
]

Event = DoneEvent | LimitEvent | SlipEvent | ServoTripEvent | CommandErrorEvent
Output = Reply | Event


def describe(event: Event) -> str:
    """One line for logs and consoles."""
    if isinstance(event, DoneEvent):
        return f"done (register {event.done_register:02X})"
    if isinstance(event, LimitEvent):
        return f"limit {event.axis}{'+' if event.direction > 0 else '-'}"
    if isinstance(event, SlipEvent):
        return f"slip {event.axis}"
    if isinstance(event, ServoTripEvent):
        return f"servo {event.axis} tripped (following error {event.error:.0f})"
    return f"command error: {event.kind.message}: {event.command}"
