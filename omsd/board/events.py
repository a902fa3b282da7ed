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
from enum import Enum


class ErrorKind(Enum):
    """Why the command-error flag (status bit CMD_S) was set, with the English message that EN
    mode prints (PC48 §6.5: "an English readable error message")."""

    UNKNOWN_COMMAND = "Unrecognized command"
    BAD_CHARACTER = "Invalid character"
    BAD_NUMBER = "Invalid number"
    OUT_OF_RANGE = "Parameter out of range"
    MISSING_PARAMETER = "Parameter required"
    TOO_MANY_PARAMETERS = "Too many parameters"
    NOT_VALID_IN_MODE = "Command not valid in this mode"
    NO_SUCH_AXIS = "Axis not installed"
    NO_ENCODER = "Encoder option required"
    ENCODER_MODEL = "Not available on encoder models"
    LOOP_MISMATCH = "LS and LE not in matched pairs"
    LOOP_TOO_DEEP = "Loops nested too deep"
    NOT_IN_LOOP = "Not valid in a loop"
    NOT_AN_OUTPUT = "Bit is not an output"
    NO_CONTOUR = "No contour defined"
    CIRCULAR_AXES = "Circular interpolation needs a 2 axis contour"
    CONTOUR_FULL = "Contour queue full"
    OVERLONG = "Input too long"

    @property
    def message(self) -> str:
        return self.value


@dataclass(frozen=True, slots=True)
class Reply:
    """Bytes the board writes to its data port (replies, echo, error text)."""

    time: float
    data: bytes


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
class CommandErrorEvent:
    """The command-error flag CMD_S was set."""

    time: float
    kind: ErrorKind
    command: str


Event = DoneEvent | LimitEvent | SlipEvent | CommandErrorEvent
Output = Reply | Event
