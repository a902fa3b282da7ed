"""The command interpreter (PC48 §6.1, §6.2, §8.2).

"The commands from the PC/AT or compatible host computer are temporarily stored in a 124
character buffer until the 68332 microprocessor can parse them. The command is then executed
immediately or routed to separate command queues for each axis."

The interpreter takes characters from the input buffer one at a time and lexes them; each
complete command is checked against the personality's queue table for the current mode (single
axis, AA, AM, contour definition), and handed to its handler in :mod:`omsd.board.commands`. A
command that needs queue space the axes do not have, and WQ, *hold* the interpreter: it stops
taking characters, the input buffer fills, and the host is held off (§6.10: a loop larger than
the queue "will hang" the board until Control-D).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from decimal import Decimal
from typing import TYPE_CHECKING, TypeVar

from omsd.board import dialect
from omsd.board.contour import ContourDefinition
from omsd.board.events import ErrorKind
from omsd.board.macros import MacroCapture, MacroStore
from omsd.models.spec import Cell, CommandSpec, Kind
from omsd.protocol.lexer import Command, Garbage, Lexer, Syntax, Token
from omsd.protocol.operands import OperandError, parse_number, truncate
from omsd.protocol.ranges import OperandRange

if TYPE_CHECKING:
    from omsd.board.axis import Axis
    from omsd.board.board import Board
    from omsd.board.queue import Op

MAX_LOOP_DEPTH = 4
N = TypeVar("N", Decimal, float, int)

# Commands that only report or select an axis: they queue nothing, so the axes need not be run
# after them (the interpreter's hot path: a client polling QA/RP).
# (and every PCIx query ``?XX``, recognised by its first character).
_REPORTS = frozenset(
    {
        *("RP", "RE", "RA", "QA", "QI", "RI", "RV", "RC", "RU", "RQ", "WY", "BX", "EA", "RL"),
        *("PP", "PE", "QL", "#WS", "PM", "EG?", "PS?", "LT?", "CL?"),
        *("AX", "AY", "AZ", "AT", "AU", "AV", "AR", "AS", "AM"),
    }
)
MAX_MACRO_DEPTH = 8


class _SyntaxTable(dict[str, Syntax]):
    """Mnemonic -> syntax, UNKNOWN for anything else (looked up for every letter received)."""

    def __missing__(self, key: str) -> Syntax:
        return Syntax.UNKNOWN


def _syntax(spec: CommandSpec) -> Syntax:
    if spec.letter_operand:
        return Syntax.AXIS
    if spec.hex_operand:
        return Syntax.HEX
    if not spec.operand:
        return Syntax.BARE
    return Syntax.OPTIONAL if spec.optional else Syntax.REQUIRED


INT32 = range(-(2**31), 2**31)


def _check_32_bit(cmd: Command) -> None:
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


def _motor_fits(motor: str, axis: Axis) -> bool:
    """PCIx: the motor types a command applies to (servo, stepper with encoder, open loop)."""
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


class CommandFailed(Exception):
    def __init__(self, kind: ErrorKind) -> None:
        super().__init__(kind.message)
        self.kind = kind


class Blocked(Exception):
    """Not enough queue space: retry the same command later."""


@dataclass
class LoopMark:
    kind: str  # "LS", "WS", "WH"
    context: str  # axis letter, or "AA" for a loop entered in AA/AM


class Interpreter:
    def __init__(self, board: Board) -> None:
        self.board = board
        self.buffer: deque[int] = deque()
        self.capacity = board.model.input_buffer
        self.commands = dialect.commands(board.model)
        self.handlers = dialect.handlers(board.model)
        self.ranges = dialect.ranges(board.model)
        self._syntax = _SyntaxTable({m: _syntax(spec) for m, spec in self.commands.items()})
        self.lexer = self._lexer()
        self._bare = self.lexer.bare_pairs(list(self.commands))
        self.pending: deque[tuple[Token, int]] = deque()  # with the macro depth it came from
        self.macros = MacroStore()
        self.reset()

    def _lexer(self) -> Lexer:
        if self.board.model.dialect == "pcix":
            starts = dialect.prefixes(self.commands)
            return Lexer(self._syntax.__getitem__, starts.__contains__)
        return Lexer(self._syntax.__getitem__)

    def reset(self) -> None:
        """RS and power-up: interpreter state to defaults (the input buffer is kept)."""
        n = len(self.board.model.axes)
        self.echo = False
        self.mode = "single"
        self.axis_index = 0
        self.contour: ContourDefinition | None = None
        self.loops: list[list[LoopMark]] = [[] for _ in range(n)]
        self.while_flags: set[int] = set()
        self.wq: list[int] | None = None
        self.last_move: list[int] = []
        self.mt_blocked = False
        self.pa_entered: list[bool] = [False] * n
        self.se_entered: list[bool] = [False] * n
        self.ws_bits: dict[int, list[int]] = {}
        self.capture: MacroCapture | None = None  # PCIx MD: characters go to a macro
        self.depth = 0
        self.table: int | None = None  # PCIx DAR#: a custom ramp table being defined
        self.table_points: list[tuple[float, float]] = []
        self.macros.reset()
        self.lexer.reset()

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
        swallow the newcomer's commands is abandoned, a PCIx macro definition without its
        Control-Z (the macro keeps its old text) and a custom ramp table without its DAE (only
        DAB and DAE would be valid until then)."""
        self.capture = None
        self.table = None
        self.table_points = []

    def control_d(self, t: float) -> None:
        """Control-D: "the same functions as the KL command. It bypasses the command
        interpreter" (PC48 §6.9). Whatever the interpreter was stuck on is dropped."""
        from omsd.board.commands import kill_all

        self.discard_input()
        kill_all(self, t)
        self.board.settle(t)

    def clear_flags(self) -> None:
        """Control-Y: IC without the interpreter (PC48 §6.12)."""
        from omsd.board.commands import clear_flags

        clear_flags(self)

    # -- the main loop --------------------------------------------------------------------------

    def pump(self, t: float) -> bool:
        board = self.board
        board.talker = board.input_source  # what the interpreter says answers the input's sender
        progressed = False
        while True:
            if board.init_until is not None and t < board.init_until:
                return progressed
            if self.wq is not None:
                if not all(board.axes[i].queue.empty for i in self.wq):
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
                if isinstance(token, Command) and not (
                    token.mnemonic in _REPORTS or token.mnemonic[0] == "?"
                ):
                    for axis in board.axes:
                        board.executor.step(axis, t)
                progressed = True
                continue
            buffer = self.buffer
            if not buffer:
                return progressed
            progressed = True
            if self.echo or self.capture is not None:
                b = buffer.popleft()
                if self.echo:
                    board.reply(bytes([b]), t)
                if self.capture is not None:
                    self._capture(b, t)
                    continue
                tokens = self.lexer.feed(b)
                if tokens:
                    self.pending.extend((token, 0) for token in tokens)
                continue
            # the common case, in a tight loop: characters until one completes a command; an
            # operand-less two-letter command between commands (QA, RP ...) is taken whole
            lexer = self.lexer
            feed = lexer.feed
            bare = self._bare
            while buffer:
                if len(buffer) >= 2 and lexer.between_commands:
                    command = bare.get((buffer[0], buffer[1]))
                    if command is not None:
                        buffer.popleft()
                        buffer.popleft()
                        self.pending.append((command, 0))
                        break
                tokens = feed(buffer.popleft())
                if tokens:
                    self.pending.extend((token, 0) for token in tokens)
                    break

    def _capture(self, b: int, t: float) -> None:
        """PCIx MD: "Enter the commands ... then enter a control Z to end the macro definition.
        The control Z may be ASCII value 26 or the string “^Z”"."""
        capture = self.capture
        assert capture is not None
        if not capture.feed(b):
            return
        self.capture = None
        if not self.macros.define(capture.slot, capture.text):
            self.board.command_error(ErrorKind.MACRO_TOO_LONG, f"MD{capture.slot}", t)

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

    def _dispatch(self, token: Token, t: float) -> bool:
        """Execute one token; False if it must wait for queue space."""
        if isinstance(token, Garbage):
            self.board.command_error(token.kind, token.text, t)
            return True
        try:
            self._command(token, t)
        except Blocked:
            return False
        except (CommandFailed, OperandError) as exc:
            self.board.command_error(exc.kind, token.text, t)
        return True

    def _command(self, cmd: Command, t: float) -> None:
        model = self.board.model
        spec = self.commands[cmd.mnemonic]
        cell = spec.cell(self.column)
        if cell.kind is Kind.NOT_VALID:
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        if self.table is not None and cmd.mnemonic not in ("DAB", "DAE"):
            # PCIx DAR: "only the DAB and DAE commands will be valid" until DAE
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        single = self.mode == "single" and self.contour is None
        if spec.motor is not None and single and not _motor_fits(spec.motor, self.axis):
            raise CommandFailed(ErrorKind.WRONG_MOTOR)
        if spec.encoder_only:
            if self.mode == "single" and self.contour is None:
                if not self.axis.has_encoder:
                    raise CommandFailed(ErrorKind.NO_ENCODER)
            elif not model.encoder_option:
                raise CommandFailed(ErrorKind.NO_ENCODER)
        if spec.not_on_encoder_models and model.encoder_option:
            raise CommandFailed(ErrorKind.ENCODER_MODEL)
        if spec.single_axes is not None and self.axis.letter not in spec.single_axes:
            if spec.other_axes_ignored:
                return  # VS4 VS in AY-AT: "Ignored"
            raise CommandFailed(ErrorKind.NOT_VALID_IN_MODE)
        if cmd.error is not None:
            raise CommandFailed(cmd.error)
        if model.dialect == "pcix" and not spec.hex_operand:
            _check_32_bit(cmd)
        handler = self.handlers.get(cmd.mnemonic)
        if handler is None:  # a table row without behaviour must not take the board down
            raise CommandFailed(ErrorKind.UNKNOWN_COMMAND)
        handler(self, cmd, cell, t)

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
        return self.board.axes[self.axis_index]

    def context_axes(self) -> list[Axis]:
        """The axes a non-list command applies to: the current axis, or all in AA/AM."""
        if self.mode == "single":
            return [self.axis]
        return list(self.board.axes)

    def context_tag(self) -> str:
        return self.axis.letter if self.mode == "single" else "AA"

    # -- operands -------------------------------------------------------------------------------

    def one(self, cmd: Command, required: bool = True) -> Decimal | None:
        """The single operand of a single-axis command."""
        fields = cmd.fields
        if not fields or fields == (None,):
            if required:
                raise CommandFailed(ErrorKind.MISSING_PARAMETER)
            return None
        if len(fields) > 1:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        assert fields[0] is not None
        return parse_number(fields[0])

    def fields(self, cmd: Command, count: int) -> list[Decimal | None]:
        """Positional operands (VS#,#,#); missing ones are ``None``."""
        fields = list(cmd.fields or ())
        if len(fields) > count:
            raise CommandFailed(ErrorKind.TOO_MANY_PARAMETERS)
        fields += [None] * (count - len(fields))
        return [None if f is None else parse_number(f) for f in fields]

    def required(self, cmd: Command, count: int) -> list[Decimal]:
        """Positional operands that must all be given (ER#,#  MV#,#  CR#,#,#)."""
        values = self.fields(cmd, count)
        present = [v for v in values if v is not None]
        if len(present) < count:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        return present

    def items(self, cmd: Command) -> dict[int, Decimal]:
        """``XX#;`` for the current axis in single-axis mode (the operand required), the
        ``XX#,#,#,#;`` list in AA/AM (skipped fields leave their axis out)."""
        if self.mode == "single":
            value = self.one(cmd)
            assert value is not None
            return {self.axis_index: value}
        return self.per_axis(cmd)

    def per_axis(self, cmd: Command, axes: list[int] | None = None) -> dict[int, Decimal]:
        """AA-syntax operands: ``MRx#,y#,z#,...;`` with skipped fields. Fields beyond the
        fitted axes are ignored (the manual's own ``VL100,...`` of E55 has nine fields)."""
        order = axes if axes is not None else list(range(len(self.board.axes)))
        out: dict[int, Decimal] = {}
        for i, text in enumerate(cmd.fields or ()):
            if i >= len(order):
                break
            if text is not None:
                out[order[i]] = parse_number(text)
        return out

    def convert(self, axis: Axis, value: Decimal, kind: str) -> float:
        """User units (UU) and integer truncation. ``kind``: "dist" (whole counts), "vel" and
        "acc" (whole unless user units are on), "frac" (fractions kept: JF)."""
        scaled = value * axis.uu if axis.uu is not None else value
        if kind == "dist" or (kind in ("vel", "acc") and axis.uu is None):
            return float(truncate(scaled))
        return float(scaled)

    def operand_range(self, mnemonic: str, operand: int = 1, variant: str = "") -> OperandRange:
        """The row of the dialect's range table (:mod:`omsd.protocol.ranges`) for this model
        family: the one place a command's operand range is stated."""
        return self.ranges.lookup(mnemonic, operand, self.board.model.family, variant)

    def check(self, mnemonic: str, value: N, operand: int = 1, variant: str = "") -> N:
        """``value`` if its range row holds it, else a command error (``OUT_OF_RANGE``)."""
        row = self.operand_range(mnemonic, operand, variant)
        if not row.contains(value, len(self.board.axes)):
            raise CommandFailed(ErrorKind.OUT_OF_RANGE)
        return value

    def integer(
        self, value: Decimal | None, mnemonic: str, operand: int = 1, variant: str = ""
    ) -> int:
        """A whole-number operand: truncated toward zero (``MR100.9`` is 100), then checked
        against its range row."""
        if value is None:
            raise CommandFailed(ErrorKind.MISSING_PARAMETER)
        return self.check(mnemonic, truncate(value), operand, variant)

    # -- queueing -------------------------------------------------------------------------------

    def cost(self, cell: Cell, axis: Axis, contour_axes: int = 0) -> int:
        model = self.board.model
        feedback = axis.has_encoder if model.dialect == "pcix" else model.encoder_option
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
        for index, slots in need.items():
            q = self.board.axes[index].queue
            # zero-slot ops (WA, SW, CD) still hold a place: a queue never holds more entries
            # than it has slots, so a flood of them holds the host off like any other
            if q.free < slots or len(q.program) + count[index] > q.capacity:
                raise Blocked
        source = self.board.input_source
        for axis, op in items:
            op.source = source
            axis.queue.append(op)

    # -- loops ----------------------------------------------------------------------------------

    def in_loop(self, axes: list[Axis]) -> bool:
        return any(self.loops[a.index] for a in axes)

    def open_loop(self, kind: str, axes: list[Axis]) -> None:
        for a in axes:
            stack = self.loops[a.index]
            if len(stack) >= MAX_LOOP_DEPTH:
                raise CommandFailed(ErrorKind.LOOP_TOO_DEEP)
            if kind == "WH" and any(m.kind == "WH" for m in stack):
                raise CommandFailed(ErrorKind.LOOP_TOO_DEEP)

    def push_loop(self, kind: str, axes: list[Axis]) -> None:
        tag = self.context_tag()
        for a in axes:
            self.loops[a.index].append(LoopMark(kind, tag))

    def close_loop(self, kind: str, axes: list[Axis]) -> None:
        """LE/WD/WG must match the most recent LS/WS/WH entered in the same axis mode:
        "otherwise the matching loop termination command will not be found"; CMD_S flags "LS
        and LE commands are not in [matched] pairs"."""
        tag = self.context_tag()
        for a in axes:
            stack = self.loops[a.index]
            if not stack or stack[-1].kind != kind or stack[-1].context != tag:
                raise CommandFailed(ErrorKind.LOOP_MISMATCH)

    def pop_loop(self, axes: list[Axis]) -> None:
        for a in axes:
            self.loops[a.index].pop()

    def forget_loops(self, index: int) -> None:
        """The axis queue was flushed: its loops are gone with it."""
        self.loops[index].clear()
        self.while_flags.discard(index)

    def take_while_flag(self, index: int) -> bool:
        if index in self.while_flags:
            self.while_flags.discard(index)
            return True
        return False
