"""The board: a pure, clock-injected model of one OMS motion control card.

Theory of operation (after PC48 §8.2): characters from the host land in a small input buffer,
an interpreter parses them and either executes a command at once (status requests, axis
selection) or places it in the command queue of each axis it concerns; each axis executes its
queue concurrently, moving its motor along analytic velocity profiles computed on a grid of
2048 samples per second; switches, encoders and input lines of the simulated world are watched
on that grid too.

The board never reads a clock and never sleeps. Every entry point takes ``now`` (seconds, any
origin); :meth:`Board.next_deadline` says when something will next change by itself (a move
ends, a switch is reached, a WT expires), so a caller can sleep until then, and a test can step
a ten-minute move in microseconds::

    board = Board(get_model("PC48-4E"), now=0.0)
    board.receive(b"VL400000 AC500000 MR1000000 GO", now=0.0)
    while (t := board.next_deadline()) is not None and t < 10:
        board.advance(t)
    board.receive(b"RP", now=10.0)
    board.take_bytes()  # b'\\n\\r1000000\\n\\r'
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

from omsd.board import profiles as pf
from omsd.board.axis import Axis, Motion
from omsd.board.clock import SampleClock
from omsd.board.contour import ContourDefinition
from omsd.board.events import (
    CommandErrorEvent,
    DoneEvent,
    ErrorKind,
    Event,
    Output,
    Reply,
)
from omsd.board.executor import Executor
from omsd.board.interpreter import Interpreter
from omsd.board.registers import CMD_S, DON_S, Registers
from omsd.board.world import AxisWorld, WorldState
from omsd.models.spec import Model

VALUE_FRAME = (b"\n\r", b"\n\r")
STATUS_FRAME = (b"\n\r\r", b"\n\r\r")

CONTROL_D = 0x04
CONTROL_Y = 0x19
MAX_EVENTS_PER_ADVANCE = 1_000_000


class Board:
    """One emulated board. See the module docstring."""

    def __init__(
        self,
        model: Model,
        now: float = 0.0,
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None = None,
    ) -> None:
        self.model = model
        # PCIx flash: saved power-up defaults (None: never archived) and the permanent macros;
        # ``flash_writer`` (set by whoever keeps them, e.g. the daemon's state file) is called
        # with both after every write (AP, ADH, ADL, PT)
        self.flash_defaults: dict[str, Any] | None = None
        self.flash_macros: dict[int, str] = {}
        self.flash_writer: Callable[[dict[str, Any] | None, dict[int, str]], None] | None = None
        self.ramp_tables: dict[int, list[tuple[float, float]]] = {}  # PCIx DAR/DAB/DAE
        self.scurves: dict[int, pf.SCurve] = {}  # PCIx AJ
        self.clock = SampleClock(model.sample_rate, now)
        self.now = now
        self.world = WorldState()
        self.registers = Registers(irq_or=model.irq_status_or)
        self._output: list[Output] = []
        # Sessions (the connections a link keeps apart, see omsd.link.base): whose bytes the
        # input buffer holds, whose conversation the output being produced belongs to (kept
        # beside every output item), 0 for the board's own doing
        self.input_source = 0
        self.talker = 0
        self._sources: list[int] = []
        self.executor = Executor(self)
        self.interpreter = Interpreter(self)
        worlds = _axis_worlds(model, world)
        self.axes = [Axis(self, i, letter, worlds[i]) for i, letter in enumerate(model.axes)]
        self._by_letter = {a.letter: a for a in self.axes}
        self._power_up(now)

    # -- power ----------------------------------------------------------------------------------

    @property
    def ramp(self) -> pf.RampShape:
        """The ramp of the first axis; PF, PN and CN set every axis's (PCIx LA, PR, SC, SR and
        SS set one axis's)."""
        return self.axes[0].ramp

    @ramp.setter
    def ramp(self, shape: pf.RampShape) -> None:
        for axis in self.axes:
            axis.ramp = shape

    @property
    def soft_limits(self) -> bool:
        """SL/SF: one mode for the whole PC48 (setting it sets every axis's); per axis on the
        PCIx (``SLb,b,b,b``)."""
        return self.axes[0].soft_limit

    @soft_limits.setter
    def soft_limits(self, on: bool) -> None:
        for axis in self.axes:
            axis.soft_limit = on

    def _power_up(self, t: float) -> None:
        self.ramp = pf.LINEAR
        self.soft_limits = False
        self.outputs_low = 0  # GP outputs driven low (BL); "off at power up or reset"
        self.directions = self.model.factory_outputs
        self.contour_velocity = float(self.model.default_contour_velocity)
        self.contour: ContourDefinition | None = None
        self.registers.control = 0  # RS: "All interrupts are disabled."
        self.registers.done = 0
        self.registers.status = 0
        self.init_until: float | None = None
        self.interpreter.reset()
        if self.model.dialect == "pcix":
            self.load_flash()

    def load_flash(self) -> list[str]:
        """PCIx power-up and RD: the saved defaults over the factory values, and the permanent
        macros. Returns the saved values skipped because they do not fit (``flash.apply``)."""
        from omsd.board import flash

        flash.factory(self)
        problems: list[str] = []
        if self.flash_defaults is not None and self.flash_matches():
            problems = flash.apply(self, self.flash_defaults)
        for axis in self.axes:
            axis.aux = axis.aux_default_high
        self.interpreter.macros.load_permanent(self.flash_macros)
        return problems

    def flash_matches(self) -> bool:
        """Saved defaults are for this model (a board renamed onto another model in the config
        must not load a stranger's parameters)."""
        saved = self.flash_defaults
        return saved is None or saved.get("model", self.model.name) == self.model.name

    def write_flash(self, defaults: dict[str, Any] | None = None) -> None:
        """AP / ADH / ADL (``defaults`` given) and PT: write flash and hand it to the keeper."""
        if defaults is not None:
            self.flash_defaults = defaults
        self.flash_macros = self.interpreter.macros.permanent()
        if self.flash_writer is not None:
            self.flash_writer(self.flash_defaults, dict(self.flash_macros))

    def reset(self, t: float) -> None:
        """RS (PC48 §6.5): "All previously entered data and commands are lost. All internal
        parameters are initialized to defaults. All interrupts are disabled." The INIT status bit
        is high for ``model.init_time``; input received meanwhile waits in the buffer."""
        for axis in self.axes:
            axis.reset(t)
        self._power_up(t)
        self.init_until = t + self.model.init_time

    def power_cycle(self, now: float) -> None:
        """Switch the card off and on: a reset that also empties the input buffer."""
        self.advance(now)
        self.interpreter.discard_input()
        self.reset(now)

    # -- the data port ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float, source: int = 0) -> int:
        """Bytes from the host. Returns how many were taken: a full input buffer (124
        characters on a PC48, while the interpreter is held by a full queue or WQ) takes no more,
        as the host would see TBE_S low; the caller keeps the rest and offers it again later.
        Control-D (kill) and Control-Y (clear flags) bypass the interpreter.

        ``source`` names the session the bytes come from (0: the only one). The input buffer
        holds one session's characters at a time: another session's bytes are not taken (0)
        until the characters already there have been read, so that what the board answers can
        be told apart (Control-D, which empties the buffer, is taken at once)."""
        self.advance(now)
        interp = self.interpreter
        buffer = interp.buffer
        if source != self.input_source:
            if buffer or interp.pending:
                # the characters of another session are still there: only a Control-D, which
                # throws them away, gets in (if there is room for it)
                if not (data and data[0] == CONTROL_D):
                    return 0
                interp.pump(now)
                if not interp.room():
                    return 0
            else:
                interp.end_of_session()
                if not interp.lexer.between_commands:
                    # the last session's unfinished command ends where its bytes ended (as
                    # the next character would end it on the card), and is that session's
                    buffer.append(0x0D)
                    interp.pump(now)
                    self.settle(now)
                    if buffer or interp.pending:
                        return 0
            self.input_source = source
        self.talker = source
        taken = 0
        n = len(data)
        while taken < n:
            b = data[taken]
            if b in (CONTROL_D, CONTROL_Y):
                interp.pump(now)
                if not interp.room():
                    break
                if b == CONTROL_D:
                    interp.control_d(now)
                else:
                    interp.clear_flags()
                taken += 1
                continue
            room = interp.capacity - len(buffer)
            if room <= 0:
                interp.pump(now)
                self.settle(now)
                room = interp.capacity - len(buffer)
                if room <= 0:
                    break
            # as many characters as there is room for, up to the next control character
            chunk = data[taken : taken + room]
            for control in (CONTROL_D, CONTROL_Y):
                cut = chunk.find(control)
                if cut >= 0:
                    chunk = chunk[:cut]
            buffer.extend(chunk)
            taken += len(chunk)
        interp.pump(now)
        self.settle(now)
        self.advance(now)
        return taken

    def input_room(self, source: int | None = None) -> int:
        """Characters the input buffer can take now (what a host sees as TBE_S); for
        ``source``, none while another session's characters are still in it."""
        interp = self.interpreter
        if source is not None and source != self.input_source and (interp.buffer or interp.pending):
            return 0
        return interp.capacity - len(interp.buffer)

    def take_output(self) -> list[Output]:
        out, self._output = self._output, []
        self._sources = []
        return out

    def take_output_sourced(self) -> tuple[list[Output], list[int]]:
        """The output and, item by item, the session whose conversation produced it."""
        sources = self._sources
        out = self.take_output()
        return out, sources

    def input_busy(self, source: int) -> bool:
        """Characters of ``source`` wait in the input buffer or the interpreter."""
        interp = self.interpreter
        return source == self.input_source and bool(interp.buffer or interp.pending)

    def session_busy(self, source: int) -> bool:
        """Something ``source`` sent is still to be done: characters not yet read, queued
        commands, or motion it started (which may yet end in a done, a limit or a slip)."""
        if self.input_busy(source):
            return True
        for axis in self.axes:
            if axis.moving and axis.source == source:
                return True
            q = axis.queue
            if any(op.source == source for op in q.program[q.pc :]):
                return True
        return False

    def busy_axes(self) -> list[str]:
        """Axes that are moving or have commands queued (what a wait for done waits on)."""
        return [a.letter for a in self.axes if a.moving or not a.queue.empty]

    def take_bytes(self) -> bytes:
        """Reply bytes only, events dropped: what a raw data port would show."""
        return b"".join(o.data for o in self.take_output() if isinstance(o, Reply))

    # -- time -----------------------------------------------------------------------------------

    def advance(self, now: float) -> None:
        """Let everything that happens by itself happen, up to ``now``."""
        if now < self.now:
            now = self.now
        for _ in range(MAX_EVENTS_PER_ADVANCE):
            t = self._next_internal()
            if t is None or t > now:
                break
            self.now = max(self.now, t)
            self._handle_due(t)
            self.settle(t)
        self.now = now

    def next_deadline(self) -> float | None:
        """When the board next changes by itself; ``None`` if it never will on its own."""
        t = self._next_internal()
        if t is not None and t <= self.now:
            return self.now
        return t

    def _next_internal(self) -> float | None:
        best = self.init_until
        for axis in self.axes:
            t = axis.next_event_time()
            if t is not None and (best is None or t < best):
                best = t
        return best

    def _handle_due(self, t: float) -> None:
        if self.init_until is not None and self.init_until <= t:
            self.init_until = None
        ex = self.executor
        for axis in self.axes:
            self.talker = axis.source  # what happens to an axis is the business of its mover
            for _ in range(64):
                when = axis.next_event_time()
                if when is None or when > t:
                    break
                kind = axis.due()
                if kind == "end":
                    ex.on_end(axis, t)
                elif kind == "sensor":
                    ex.on_sensor(axis, t)
                elif kind == "in":
                    ex.fire_in(axis, t)
                elif kind == "aux":
                    ex.on_aux_timer(axis, t)
                elif kind == "output":
                    ex.on_outputs(axis, t)
                elif kind == "servo":
                    ex.on_servo(axis, t)
                elif kind == "wait" and not ex.step(axis, t):
                    if axis.wait is not None:
                        axis.wait.until = None
                    axis.invalidate()
                axis.invalidate()
        self.talker = 0

    def settle(self, t: float) -> None:
        """Run queues and the interpreter until nothing more happens at ``t``."""
        for _ in range(10_000):
            progressed = False
            for axis in self.axes:
                if self.executor.step(axis, t):
                    progressed = True
            if self.interpreter.pump(t):
                progressed = True
            if not progressed:
                return

    @property
    def initializing(self) -> bool:
        return self.init_until is not None and self.now < self.init_until

    # -- registers ------------------------------------------------------------------------------

    def read_status_register(self, now: float) -> int:
        """Read offset 3; DON_S, CMD_S, ENC_S and OVRT reset on read (PC48 §3.4.4)."""
        self.advance(now)
        value = self.status_register(now)
        self.registers.clear_on_status_read()
        return value

    def status_register(self, now: float) -> int:
        """The status register without the side effect of a read."""
        return self.registers.compose_status(
            self.initializing, self.interpreter.room(), bool(self._output)
        )

    def read_done_register(self, now: float) -> int:
        """Read offset 1: "This register is cleared automatically after it is read.\""""
        self.advance(now)
        return self.registers.read_done()

    def write_control_register(self, value: int, now: float) -> None:
        self.advance(now)
        self.registers.control = value & 0xF0

    def read_control_register(self, now: float) -> int:
        return self.registers.control

    def write_vector_register(self, value: int, now: float) -> None:
        """VME boards (VS4): "Interrupt Vector", a read/write byte returned during IACK."""
        self._need_vector()
        self.registers.vector = value & 0xFF

    def read_vector_register(self, now: float) -> int:
        self._need_vector()
        return self.registers.vector

    def _need_vector(self) -> None:
        if not self.model.vector_register:
            raise ValueError(f"a {self.model.name} has no interrupt vector register")

    # -- used by the interpreter and the executor -----------------------------------------------

    def emit(self, event: Event) -> None:
        self._output.append(event)
        self._sources.append(self.talker)

    def reply(self, data: bytes, t: float) -> None:
        """Echoed characters: unframed, merged with echo just before them."""
        out = self._output
        last = out[-1] if out else None
        if (
            isinstance(last, Reply)
            and last.text is None
            and last.time == t
            and self._sources[-1] == self.talker
        ):
            out[-1] = Reply(t, last.data + data)
        else:
            out.append(Reply(t, data))
            self._sources.append(self.talker)

    def reply_value(self, text: str, t: float) -> None:
        """ "surrounded by line feeds and carriage returns": ``<LF><CR>text<LF><CR>``."""
        self._framed(text, b"\n\r", t)

    def reply_status(self, text: str, t: float) -> None:
        """RA, QA, RI, QI, EA: "one line feed and two carriage returns on each end"."""
        self._framed(text, b"\n\r\r", t)

    def _framed(self, text: str, frame: bytes, t: float) -> None:
        payload = text.encode("latin-1")  # a PCIx macro (PM) may hold any byte
        # PCIx / MAX family: text<LF><CR>, nothing before it
        trailing = self.model.framing == "trailing"
        data = payload + b"\n\r" if trailing else frame + payload + frame
        self._output.append(Reply(t, data, payload))
        self._sources.append(self.talker)

    def command_error(self, kind: ErrorKind, command: str, t: float) -> None:
        """CMD_S (PC48 Table 3-8) and, with echo on, "an English readable error message"."""
        self.registers.status |= CMD_S | DON_S
        self.emit(CommandErrorEvent(t, kind, command))
        if self.interpreter.echo:
            self.reply_value(f"{kind.message}: {command}", t)

    def set_done(self, axes: Iterable[Axis], t: float, interrupt: bool) -> None:
        for axis in axes:
            axis.done = True
            self.registers.set_done(axis.done_bit)
        if interrupt:
            self.signal_done(t)

    def signal_done(self, t: float) -> None:
        self.registers.status |= DON_S
        self.emit(DoneEvent(t, self.registers.done))

    def clear_done(self, axes: Iterable[Axis]) -> None:
        for axis in axes:
            axis.done = False
            self.registers.done &= ~axis.done_bit

    def axis_by_letter(self, letter: str) -> Axis | None:
        return self._by_letter.get(letter)

    # -- general purpose I/O --------------------------------------------------------------------

    def input_high(self, bit: int, t: float) -> bool:
        """Level of a general-purpose line: outputs show what BL/BH drive, inputs what the
        world drives (pulled up when nothing does), wire-ORed with an aux output wired to it."""
        if self.directions >> bit & 1:
            level = not (self.outputs_low >> bit & 1)
        else:
            level = self.world.input_levels.get(bit, True)
        wired = self.world.aux_wiring.get(bit)
        if wired is not None and wired < len(self.axes) and not self.axes[wired].aux:
            level = False
        return level

    def io_bits_low(self, t: float) -> int:
        """BX: "A one in any binary position signals that bit as being low.\""""
        value = 0
        for bit in range(self.model.io_bits):
            if not self.input_high(bit, t):
                value |= 1 << bit
        return value

    def set_output(self, bit: int, low: bool, t: float) -> None:
        if low:
            self.outputs_low |= 1 << bit
        else:
            self.outputs_low &= ~(1 << bit)

    # -- the simulated world (tests, control API) -----------------------------------------------

    def set_limit(self, axis: str, direction: int, active: bool | None, now: float) -> None:
        """Force a limit switch (``None``: let the carriage position decide again)."""
        self.advance(now)
        a = self._axis(axis)
        self.world.force_limit(a.index, direction, active)
        self._sensors_changed(a, now)

    def set_home(self, axis: str, activated: bool | None, now: float) -> None:
        self.advance(now)
        a = self._axis(axis)
        if activated is None:
            self.world.forced_home.pop(a.index, None)
        else:
            self.world.forced_home[a.index] = activated
        self._sensors_changed(a, now)

    def set_input(self, bit: int, high: bool | None, now: float) -> None:
        """Drive a general-purpose input line (``None``: release it to its pull-up)."""
        self.advance(now)
        if not 0 <= bit < self.model.io_bits:
            raise ValueError(f"no I/O bit {bit} on a {self.model.name}")
        if high is None:
            self.world.input_levels.pop(bit, None)
        else:
            self.world.input_levels[bit] = high
        self.settle(now)

    def wire_input_to_aux(self, bit: int, axis: str | None) -> None:
        """Wire an axis's open-collector auxiliary output to a general-purpose input."""
        if axis is None:
            self.world.aux_wiring.pop(bit, None)
        else:
            self.world.aux_wiring[bit] = self._axis(axis).index

    def inject_slip(self, axis: str, steps: float, now: float) -> None:
        """The load (and its encoder) jumps ``steps`` away from where the pulses put it."""
        self.advance(now)
        a = self._axis(axis)
        if a.stall_phys is not None:
            a.stall_phys += steps
        else:
            a.phys_offset += steps
        self._sensors_changed(a, now)

    def set_stall(self, axis: str, stalled: bool, now: float) -> None:
        """A stalled motor does not follow its pulses; the carriage stays where it is."""
        self.advance(now)
        a = self._axis(axis)
        if stalled and a.stall_phys is None:
            a.stall_phys = a.phys(now)
        elif not stalled and a.stall_phys is not None:
            a.phys_offset = a.stall_phys - a.position(now)
            a.stall_phys = None
        self._sensors_changed(a, now)

    def set_encoder_input(self, axis: str, counts: int, now: float) -> None:
        """Drive the encoder input from outside, as a handwheel or another device would. In ET
        tracking mode the axis follows it at once, with no ramps (PC48 §6.17: "The axis will
        duplicate the encoder input"); otherwise the encoder simply disagrees with the motor."""
        self.advance(now)
        a = self._axis(axis)
        delta = (counts - a.encoder(now)) / a.ratio
        if a.tracking:
            a.begin(now, [], Motion.IDLE, final=float(round(a.position(now) + delta)))
        else:
            a.phys_offset += delta
        self._sensors_changed(a, now)

    def _sensors_changed(self, axis: Axis, now: float) -> None:
        axis.sensor_check = self.clock.at_or_after(now)
        axis.invalidate()
        self.settle(now)

    def _axis(self, letter: str) -> Axis:
        a = self._by_letter.get(letter.upper())
        if a is None:
            raise ValueError(f"no axis {letter!r} on a {self.model.name}")
        return a

    # -- inspection -----------------------------------------------------------------------------

    def snapshot(self, now: float) -> dict[str, Any]:
        """Everything a test or the control API may want to see, without side effects."""
        self.advance(now)
        return {
            "model": self.model.name,
            "time": now,
            "mode": self.interpreter.mode_name,
            "status": self.status_register(now),
            "done_register": self.registers.done,
            "control": self.registers.control,
            "outputs_low": self.outputs_low,
            "io_low": self.io_bits_low(now),
            "input_buffer": len(self.interpreter.buffer),
            "axes": {
                a.letter: {
                    "position": a.counter(now),
                    "encoder": a.encoder(now) if a.has_encoder else None,
                    "velocity": a.velocity(now),
                    "physical": a.phys(now),
                    "moving": a.motion is not Motion.IDLE,
                    "motion": a.motion.name.lower(),
                    "done": a.done,
                    "direction": a.direction,
                    "limit_negative": a.limit_active(-1, now),
                    "limit_positive": a.limit_active(1, now),
                    "home": a.home_sensed(now),
                    "aux": a.aux,
                    "queue_free": a.queue.free,
                    "velocity_setting": a.vl,
                    "acceleration_setting": a.ac,
                }
                for a in self.axes
            },
        }


def _axis_worlds(
    model: Model, world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None
) -> list[AxisWorld]:
    if world is None:
        return [AxisWorld() for _ in model.axes]
    if isinstance(world, Mapping):
        unknown = set(world) - set(model.axes)
        if unknown:
            raise ValueError(f"no axis {sorted(unknown)} on a {model.name}")
        return [world.get(letter, AxisWorld()) for letter in model.axes]
    worlds = list(world)
    return worlds + [AxisWorld() for _ in range(len(model.axes) - len(worlds))]
