"""The PCIx's interpreter: the generic one with the PCIx's own state.

* Macros (§5.4.7, :mod:`~omsd.dialects.pcix.macros`): the 25 slots, the definition being
  recorded (MD: the characters go to it until Control-Z) and running a macro's commands next
  (MX), at most :data:`MAX_MACRO_DEPTH` deep.
* A custom ramp table being defined (DAR ... DAE): "until the DAE command is entered, only the
  DAB and DAE commands will be valid".
* Flash (§5.4.2, :mod:`~omsd.dialects.pcix.flash`): at power-up (and RD, each axis through
  its queue) the saved defaults over the factory values, and the permanent macros.
* §5.1: "numeric parameters must be within the range of a 32-bit signed integer"
  (:func:`check_32_bit`, the dialect's field check).
"""

from __future__ import annotations

from typing import Any

from omsd.dialects.interpreter import CommandFailed, Interpreter
from omsd.dialects.pcix import flash
from omsd.dialects.pcix.macros import MacroCapture, MacroStore
from omsd.dialects.registry import Dialect
from omsd.engine.axis import Axis
from omsd.engine.machine import Machine
from omsd.engine.queue import Op
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command, Token

MAX_MACRO_DEPTH = 8
#: the commands valid while a custom ramp table is being defined
TABLE_COMMANDS = frozenset({"DAB", "DAE"})

INT32 = range(-(2**31), 2**31)


def check_32_bit(cmd: Command) -> None:
    """PCIx §5.1: "numeric parameters must be within the range of a 32-bit signed integer ...
    For fixed point numeric parameters, the value without the decimal point must be within the
    range of a signed 32-bit integer. Entering parameter values outside the range of a signed
    32-bit integer will cause a Command Error" (whatever the command's own range)."""
    for text in cmd.fields or ():
        if text is None:
            continue
        digits = text.replace(".", "")
        try:
            n = int(digits)
        except ValueError:
            continue  # an axis letter (EGX), or not a number: the command's own parsing decides
        if n not in INT32:
            raise CommandFailed(ErrorKind.OUT_OF_RANGE)


class PcixInterpreter(Interpreter):
    def __init__(self, machine: Machine, dialect: Dialect) -> None:
        self.macros = MacroStore()
        super().__init__(machine, dialect)

    def reset(self) -> None:
        super().reset()
        self.table: int | None = None  # DAR#: a custom ramp table being defined
        self.table_points: list[tuple[float, float]] = []
        self.macros.reset()

    def power_up(self) -> None:
        self.reset()
        self.load_flash()

    def end_of_session(self) -> None:
        """Another session starts writing: a macro definition without its Control-Z (the macro
        keeps its old text) and a custom ramp table without its DAE are abandoned."""
        super().end_of_session()
        self.table = None
        self.table_points = []

    # -- custom ramp tables ---------------------------------------------------------------------

    def begin_table(self, number: int) -> None:
        self.table = number
        self.table_points = []
        self.only = TABLE_COMMANDS

    def end_table(self) -> None:
        self.table = None
        self.table_points = []
        self.only = None

    # -- macros ---------------------------------------------------------------------------------

    def record_macro(self, slot: int) -> None:
        """MD: what follows, up to Control-Z, is macro ``slot``: "Enter the macro number
        immediately after the MD command ... Next enter the command string". A letter that
        ended the number (``MD1VL1000;``) is the command string's first."""
        capture = MacroCapture(slot, done=self._macro_recorded)
        if self.depth == 0:  # typed by the host (not an MD inside a macro being run)
            for b in self.lexer.give_back():
                capture.feed(b)
        self.capture = capture

    def _macro_recorded(self, capture: MacroCapture, t: float) -> None:
        if not self.macros.define(capture.slot, capture.text):
            self.machine.command_error(ErrorKind.MACRO_TOO_LONG, f"MD{capture.slot}", t)

    def run_macro(self, text: bytes) -> None:
        """MX: the macro's commands run next, before anything received after MX. A macro that
        runs macros is followed :data:`MAX_MACRO_DEPTH` deep (a macro calling itself would
        otherwise never give the host back its board)."""
        if self.depth >= MAX_MACRO_DEPTH:
            raise CommandFailed(ErrorKind.MACRO_TOO_DEEP)
        lexer = self._lexer()
        tokens: list[Token] = []
        for b in text + b";":
            tokens.extend(lexer.feed(b))
        self.pending.extendleft((token, self.depth + 1) for token in reversed(tokens))

    # -- flash ----------------------------------------------------------------------------------

    def load_flash(self) -> list[str]:
        """Power-up: the saved defaults over the factory values, and the permanent macros
        (RD: :meth:`restore_defaults`). Returns the saved values skipped because they do not
        fit (``flash.apply``)."""
        machine = self.machine
        flash.factory(machine)
        problems: list[str] = []
        if machine.flash_defaults is not None and machine.flash_matches():
            problems = flash.apply(machine, machine.flash_defaults)
        for axis in machine.axes:
            axis.aux = axis.aux_default_high
        self.macros.load_permanent(machine.flash_macros)
        return problems

    def restore_defaults(self) -> None:
        """RD: "restores the motion parameters using power-up defaults"; "This command places
        entries in all axis command queues to set up the motion profile parameters", so each
        axis takes the saved values (the factory ones where AP was never used) when its queue
        reaches the entry, after what was queued before RD (an entry takes no units: the
        queue table says "RD AX – AT Immediate", "RD AA-AM Immediate"). The values are those
        in flash when RD is received. What has no axis queue, the custom ramp tables and
        S-curve profiles (DAR and AJ act at once) and the permanent macros, is restored at
        once."""
        machine = self.machine
        saved = machine.flash_defaults if machine.flash_matches() else None

        def restore(axis: Axis, t: float) -> None:
            flash.factory_axis(axis)
            if saved is not None:
                flash.apply_axis(machine, axis, saved, [])
            axis.aux = axis.aux_default_high

        self.enqueue([(a, Op("SET", ("RD", restore), 0)) for a in machine.axes])
        machine.ramp_tables.clear()
        machine.scurves.clear()
        if saved is not None:
            flash.apply_tables(machine, saved, [])
        self.macros.load_permanent(machine.flash_macros)

    def write_flash(self, defaults: dict[str, Any] | None = None) -> None:
        """AP / ADH / ADL (``defaults`` given) and PT: write flash (the permanent macros with
        it) and hand it to the keeper."""
        self.machine.write_flash(defaults, self.macros.permanent())
