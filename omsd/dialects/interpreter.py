"""The command interpreter (PC48 §6.1, §6.2, §8.2), generic over dialects.

"The commands from the PC/AT or compatible host computer are temporarily stored in a 124
character buffer until the 68332 microprocessor can parse them. The command is then executed
immediately or routed to separate command queues for each axis."

The interpreter takes characters from the input buffer one at a time and lexes them; each
complete command is checked against the personality's queue table for the current mode (single
axis, AA, AM, contour definition), and handed to its handler in the dialect's table
(:mod:`omsd.dialects.registry`). A command that needs queue space the axes do not have, and WQ,
*hold* the interpreter: it stops taking characters, the input buffer fills, and the host is held
off (§6.10: a loop larger than the queue "will hang" the board until Control-D).

A dialect with state of its own (stored programs, a table being defined) subclasses
:class:`Interpreter`; what the generic one offers such a dialect: characters diverted to a
:class:`Capture` instead of the lexer, and ``only``, the commands valid until a definition ends.
"""

from __future__ import annotations

from collections import deque
from typing import TYPE_CHECKING, Protocol

from omsd.dialects.loopstack import LoopMark, LoopStacks
from omsd.dialects.operands import CommandFailed, Operands
from omsd.dialects.registry import AnyHandler, Dialect, prefixes
from omsd.dialects.words import SyntaxTable, syntax, words_of
from omsd.engine.axis import Axis
from omsd.engine.machine import Machine
from omsd.engine.queue import Op
from omsd.engine.states import Motion
from omsd.models.spec import Cell, Kind
from omsd.protocol.errors import ErrorKind
from omsd.protocol.lexer import Command, Garbage, Lexer, Token
from omsd.protocol.operands import OperandError

if TYPE_CHECKING:  # contouring is imported when a contour is defined (start-up)
    from omsd.engine.contour import ContourDefinition

__all__ = ["Blocked", "Capture", "CommandFailed", "Interpreter", "LoopMark"]


def motor_fits(motor: str, axis: Axis) -> bool:
    """The motor types a command applies to (servo, stepper with encoder, open loop)."""
    servo = axis.is_servo
    if motor == "servo":
        return servo
    if motor == "feedback":
        return axis.has_encoder
    if motor == "stepper_encoder":
        return axis.has_encoder and not servo
    if motor == "open_loop":
        return not axis.has_encoder
    raise ValueError(motor)


#: What :meth:`Interpreter.ready` keeps for a command: its handler and queue-table cell.
Ready = tuple[AnyHandler, Cell]
#: A report ready to run whole (:meth:`Interpreter.bare_reports`): its handler, cell, command.
BareReport = tuple[AnyHandler, Cell, Command]


class Blocked(Exception):
    """Not enough queue space: retry the same command later."""


class Capture(Protocol):
    """Characters diverted from the lexer (a definition being recorded) until it says done."""

    def feed(self, b: int) -> bool:
        """Take one character; True once the capture has ended."""

    def finish(self, t: float) -> None:
        """The capture ended (and the interpreter reads commands again)."""


class Interpreter(Operands, LoopStacks):
    # (omsd.engine.core.Core's note on slots)
    # fmt: off
    __slots__ = (
        "_bare", "_check_fields", "_fast", "_feedback_per_axis", "_ready", "_reports", "_syntax",
        "axis_index", "buffer", "capacity", "capture", "commands", "contour", "contour_lead",
        "depth", "dialect",
        "echo", "handlers", "last_move", "lexer", "loops", "machine", "mode", "mt_blocked", "only",
        "pa_entered", "pending", "ranges", "report_words", "se_entered", "while_flags", "words",
        "wq", "ws_bits",
    )
    # fmt: on

    def __init__(self, machine: Machine, dialect: Dialect) -> None:
        model = machine.model
        self.machine = machine
        self.dialect = dialect
        self.buffer: deque[int] = deque()
        self.capacity = model.input_buffer
        self.commands = dialect.commands(model)
        self.handlers = dialect.handlers(model)
        self.ranges = dialect.ranges
        self._reports = dialect.reports
        self._check_fields = dialect.check_fields
        self._feedback_per_axis = dialect.feedback_per_axis
        self._syntax = SyntaxTable({m: syntax(spec) for m, spec in self.commands.items()})
        self.lexer = self._lexer()
        self._fast = machine.fast_paths
        self.words = words_of(self.lexer, self._syntax, dialect.long_mnemonics, self._reports)
        self.report_words = self.words.reports
        # per mode and axis: the operand-less commands that pass every check there (ready)
        self._ready: dict[tuple[str, int], dict[str, Ready | None]] = {}
        # per mode and axis: the reports among them, by their bytes (bare_reports)
        self._bare: dict[tuple[str, int], dict[bytes, BareReport]] = {}
        self.pending: deque[tuple[Token, int]] = deque()  # with the nesting depth it came from
        self.reset()

    def _lexer(self) -> Lexer:
        if self.dialect.long_mnemonics:
            starts = prefixes(self.commands)
            return Lexer(self._syntax.__getitem__, starts.__contains__)
        return Lexer(self._syntax.__getitem__)

    def reset(self) -> None:
        """A reset and power-up: interpreter state to defaults (the input buffer is kept)."""
        n = len(self.machine.model.axes)
        self.echo = False
        self.mode = "single"
        self.axis_index = 0
        self.contour: ContourDefinition | None = None
        # the lead-in acceleration of each axis of the contour that runs (RC: "While a contour
        # is executing, the value computed to generate the appropriate lead in will be returned")
        self.contour_lead: dict[int, float] = {}
        self.loops: list[list[LoopMark]] = [[] for _ in range(n)]
        self.while_flags: set[int] = set()
        self.wq: list[int] | None = None
        self.last_move: list[int] = []
        self.mt_blocked = False
        self.pa_entered: list[bool] = [False] * n
        self.se_entered: list[bool] = [False] * n
        self.ws_bits: dict[int, list[tuple[int, bool]]] = {}  # (bit, loop while high)
        self.capture: Capture | None = None  # characters go to a recording, not the lexer
        self.only: frozenset[str] | None = None  # the only commands valid (a definition)
        self.depth = 0
        self.lexer.reset()

    def power_up(self) -> None:
        """Power-up and reset of the machine: the interpreter's too (the machine's front)."""
        self.reset()

    def load_flash(self) -> list[str]:
        """Load what the dialect keeps in flash; nothing here (a dialect with flash says what
        it skipped)."""
        return []

    # -- input ----------------------------------------------------------------------------------

    def room(self) -> bool:
        return len(self.buffer) < self.capacity

    def accept(self, b: int) -> None:
        self.buffer.append(b)

    def discard_input(self) -> None:
        self.buffer.clear()
        self.pending.clear()
        self.lexer.reset()
        self.wq = None
        self.capture = None

    def end_of_session(self) -> None:
        """Another session starts writing: what the last one left half-entered and would
        swallow the newcomer's commands is abandoned (a capture, a definition)."""
        self.capture = None
        self.only = None

    def control_d(self, t: float) -> None:
        """Control-D: "the same functions as the KL command. It bypasses the command
        interpreter" (PC48 §6.9). Whatever the interpreter was stuck on is dropped."""
        self.discard_input()
        self.kill_all(t)
        self.machine.settle(t)

    def clear_flags(self) -> None:
        """IC and Control-Y (PC48 §6.12): "clear the done and error flags in the status register
        and the done flag register"."""
        machine = self.machine
        machine.registers.clear_done_and_errors()
        for axis in machine.axes:
            axis.done = False

    def kill_all(self, t: float) -> None:
        """KL and Control-D: "flush the command queue and terminate pulse generation of all axes
        immediately" (PC48 §6.9); also leaves contour definition and the WQ wait."""
        # what each axis was doing, for its stop to read (Executor.stopped_at_once): the pulses
        # stop here, before the queued stop runs
        stopped = {axis.index: axis.motion for axis in self.machine.axes}
        for axis in self.machine.axes:
            axis.halt(t)  # (a settling time under way runs on: the kill ends no power mode)
        self.stop(list(self.machine.axes), t, kill=True, stopped=stopped)
        self.contour = None
        self.wq = None

    def stop(
        self,
        axes: list[Axis],
        t: float,
        kill: bool = False,
        cell: Cell | None = None,
        stopped: dict[int, Motion] | None = None,
    ) -> None:
        """Flush the axes' queues and queue their stop (a kill stops the pulses at once);
        ``stopped``: the motion of each axis whose pulses were stopped already (KL)."""
        machine = self.machine
        for axis in axes:
            machine.executor.flush(axis, t)
        for axis in axes:
            # "Flush + 2" (PC48); the PCIx's tables give their own numbers (+PA, +settle)
            slots = self.cost(cell, axis) if cell is not None and cell.kind is Kind.FLUSH else 2
            was = stopped.get(axis.index) if stopped is not None else None
            axis.queue.append(Op("STOP", (kill, was), slots, source=machine.input_source))
        self.mt_blocked = False

    # -- the main loop --------------------------------------------------------------------------

    def pump(self, t: float) -> bool:
        machine = self.machine
        machine.talker = machine.input_source  # what the interpreter says answers the sender
        reports = self._reports
        progressed = False
        while True:
            if machine.init_until is not None and t < machine.init_until:
                return progressed
            if self.wq is not None:
                if not all(machine.axes[i].queue.empty for i in self.wq):
                    return progressed
                self.wq = None
                progressed = True
            if self.pending:
                token, depth = self.pending.popleft()
                self.depth = depth
                if not self._dispatch(token, t):
                    self.pending.appendleft((token, depth))
                    return progressed
                # let the axes run what was queued before the next command is read; a report or
                # an axis selection queues nothing and leaves them as they were
                if isinstance(token, Command) and token.mnemonic not in reports:
                    machine.executor.run_queues(t)
                progressed = True
                continue
            buffer = self.buffer
            if not buffer:
                return progressed
            progressed = True
            if self.echo or self.capture is not None:
                b = buffer.popleft()
                if self.echo:
                    machine.reply(bytes([b]), t)
                if self.capture is not None:
                    self._capture(b, t)
                    continue
                tokens = self.lexer.feed(b)
                if tokens:
                    self.pending.extend((token, 0) for token in tokens)
                continue
            # the common case, in a tight loop: characters until one completes a command
            lexer = self.lexer
            feed = lexer.feed
            if self._fast:
                # fast path: an operand-less command between commands (QA, RP, ?KP ...) is
                # taken whole and run at once, where the lexer would have given that command
                # to the pending queue and the loop would have run it next (Words, run_bare)
                words = self.words.packed
                three = self.words.longest > 2
                while buffer:
                    if len(buffer) >= 2 and lexer.between_commands:
                        command = words.get(0x10000 | buffer[0] << 8 | buffer[1])  # pack2
                        if command is None and three and len(buffer) >= 3:
                            command = words.get(  # pack3
                                0x1000000 | buffer[0] << 16 | buffer[1] << 8 | buffer[2]
                            )
                        if command is not None:
                            for _ in command.mnemonic:
                                buffer.popleft()
                            if not self.run_bare(command, t):
                                return progressed
                            if command.mnemonic not in reports:
                                machine.executor.run_queues(t)
                            break
                    tokens = feed(buffer.popleft())
                    if tokens:
                        self.pending.extend((token, 0) for token in tokens)
                        break
                continue
            while buffer:
                tokens = feed(buffer.popleft())
                if tokens:
                    self.pending.extend((token, 0) for token in tokens)
                    break

    def _capture(self, b: int, t: float) -> None:
        capture = self.capture
        assert capture is not None
        if not capture.feed(b):
            return
        self.capture = None
        capture.finish(t)

    def _dispatch(self, token: Token, t: float) -> bool:
        """Execute one token; False if it must wait for queue space."""
        if isinstance(token, Garbage):
            self.machine.command_error(token.kind, token.text, t)
            return True
        try:
            self._command(token, t)
        except Blocked:
            return False
        except (CommandFailed, OperandError) as exc:
            self.machine.command_error(exc.kind, token.text, t)
        return True

    def _command(self, cmd: Command, t: float) -> None:
        checked = self._check(cmd)
        if checked is not None:
            handler, cell = checked
            handler(self, cmd, cell, t)

    def _check(self, cmd: Command) -> Ready | None:
        """Every check of a command before its handler runs: its handler and queue-table cell;
        None for a command that is ignored; :class:`CommandFailed` for one that fails."""
        model = self.machine.model
        spec = self.commands[cmd.mnemonic]
        cell = spec.cell(self.column)
        if cell.kind is Kind.NOT_VALID:
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        if self.only is not None and cmd.mnemonic not in self.only:
            # a definition in progress: only its own commands are valid until it ends
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        single = self.mode == "single" and self.contour is None
        if spec.motor is not None and single and not motor_fits(spec.motor, self.axis):
            raise CommandFailed(ErrorKind.WRONG_MOTOR)
        if spec.encoder_only:
            if self.mode == "single" and self.contour is None:
                if not self.axis.has_encoder:
                    raise CommandFailed(ErrorKind.NO_ENCODER)
            elif not model.encoder_option and not spec.encoder_only_single:
                raise CommandFailed(ErrorKind.NO_ENCODER)
        if spec.not_on_encoder_models and model.encoder_option:
            raise CommandFailed(ErrorKind.ENCODER_MODEL)
        if spec.single_axes is not None and self.axis.letter not in spec.single_axes:
            if spec.other_axes_ignored:
                return None  # VS4 VS in AY-AT: "Ignored"
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        if cmd.error is not None:
            raise CommandFailed(cmd.error)
        if self._check_fields is not None and not spec.hex_operand:
            self._check_fields(cmd)
        handler = self.handlers.get(cmd.mnemonic)
        if handler is None:  # a table row without behaviour must not take the board down
            raise CommandFailed(ErrorKind.UNKNOWN_COMMAND)
        return handler, cell

    # -- the fast path of operand-less commands (issue 16) --------------------------------------

    def holds_nothing(self) -> bool:
        """Nothing is waiting to be read or run, and the next character is read afresh: no
        input, no pending command, no WQ, no echo, no capture, the lexer between commands."""
        return (
            not self.buffer
            and not self.pending
            and self.wq is None
            and self.capture is None
            and not self.echo
            and self.lexer.between_commands
        )

    def run_bare(self, command: Command, t: float) -> bool:
        """Run an operand-less command read whole (:class:`~omsd.dialects.words.Words`), as
        the loop of :meth:`pump` runs the next command of the pending queue (``_dispatch``),
        with the checks of :meth:`_check` known in advance where it can (:meth:`ready`). False
        if it must wait for queue space: it is then first in the pending queue, as it would
        have been."""
        self.depth = 0
        entry = self.ready(command)
        if entry is None:
            if self._dispatch(command, t):
                return True
        else:
            handler, cell = entry
            try:
                handler(self, command, cell, t)
                return True
            except Blocked:
                pass
            except (CommandFailed, OperandError) as exc:
                self.machine.command_error(exc.kind, command.text, t)
                return True
        self.pending.appendleft((command, 0))
        return False

    def bare_reports(self) -> dict[bytes, BareReport] | None:
        """The reports (:attr:`report_words`) that pass every check in the current mode and
        on the current axis (:meth:`ready`), by the bytes that spell them, each with its handler
        and cell: what ``Board._reports_at_rest`` runs in one lookup (issue 16). None while a
        contour or a definition is open (every command is checked again then, as ``ready``
        says)."""
        if self.contour is not None or self.only is not None:
            return None
        key = (self.mode, self.axis_index)
        table = self._bare.get(key)
        if table is None:
            table = {}
            for word, command in self.report_words.items():
                entry = self.ready(command)
                if entry is not None:
                    table[word] = (entry[0], entry[1], command)
            self._bare[key] = table
        return table

    def ready(self, command: Command) -> Ready | None:
        """:meth:`_check` of an operand-less command (a :class:`~omsd.dialects.words.Words`
        command), kept: for a command without operand the checks depend only on the mode and
        the axis (motor types and encoders are fixed at the factory), so the answer is kept per
        mode and axis, with no contour or table being defined (else None, as for a command that
        fails a check or is ignored: then ``_dispatch`` checks it again, and says what fails)."""
        if self.contour is not None or self.only is not None:
            return None
        try:
            return self._ready[self.mode, self.axis_index][command.mnemonic]
        except KeyError:
            try:
                entry = self._check(command)
            except (CommandFailed, OperandError):
                entry = None
            self._ready.setdefault((self.mode, self.axis_index), {})[command.mnemonic] = entry
            return entry

    # -- context --------------------------------------------------------------------------------

    @property
    def column(self) -> str:
        if self.contour is not None:
            return "CD"
        return self.mode

    @property
    def mode_name(self) -> str:
        if self.contour is not None:
            return "AA/CD"
        if self.mode == "single":
            return "A" + self.axis.letter
        return self.mode

    @property
    def axis(self) -> Axis:
        return self.machine.axes[self.axis_index]

    def context_axes(self) -> list[Axis]:
        """The axes a non-list command applies to: the current axis, or all in AA/AM."""
        if self.mode == "single":
            return [self.axis]
        return list(self.machine.axes)

    def context_tag(self) -> str:
        return self.axis.letter if self.mode == "single" else "AA"

    # -- queueing -------------------------------------------------------------------------------

    def cost(self, cell: Cell, axis: Axis, contour_axes: int = 0) -> int:
        model = self.machine.model
        feedback = axis.has_encoder if self._feedback_per_axis else model.encoder_option
        return cell.cost(
            axis.ramp.kind.value,
            feedback,
            contour_axes,
            segments=axis.ramp.segments,
            pa=axis.pa is not None,
            settle=axis.se_ms > 0,
        )

    def enqueue(self, items: list[tuple[Axis, Op]]) -> None:
        """Place ops in their axis queues, all or nothing; :class:`Blocked` if any queue is
        short of space (the interpreter then waits, PC48 §6.10)."""
        need: dict[int, int] = {}
        count: dict[int, int] = {}
        for axis, op in items:
            need[axis.index] = need.get(axis.index, 0) + op.slots
            count[axis.index] = count.get(axis.index, 0) + 1
        machine = self.machine
        for index, slots in need.items():
            q = machine.axes[index].queue
            # zero-slot ops (WA, SW, CD) still hold a place: a queue never holds more entries
            # than it has slots, so a flood of them holds the host off like any other
            if q.free < slots or len(q.program) + count[index] > q.capacity:
                raise Blocked
        source = machine.input_source
        for axis, op in items:
            op.source = source
            axis.queue.append(op)
