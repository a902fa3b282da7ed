"""Why a command sets the command-error flag, with the English message EN mode prints."""

from __future__ import annotations

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
    WRONG_MOTOR = "Not valid for this axis's motor type"
    MACRO_TOO_LONG = "Macro longer than 250 characters"
    MACRO_TOO_DEEP = "Macros nested too deep"
    NO_MACRO = "Macro not defined"
    NO_TABLE = "Ramp table not defined"
    TABLE_FULL = "Ramp table full"
    GEARED = "Axis is geared"

    @property
    def message(self) -> str:
        return self.value
