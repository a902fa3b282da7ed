"""The machine's state and what it says: axes, registers, the world, the output with its
sessions, general-purpose I/O and the flash store.

:class:`Core` is everything of one card except its sense of time: the
:class:`~omsd.engine.machine.Machine` adds the executor and the clock loop. The executor and its
ops work on a ``Core``; the machine that owns them is one.

Output. What the board says (replies, echo) and the events a host learns of through its
registers (done, limit, slip, command error) go into one list, in time order. Beside every item
is the session whose conversation produced it (``talker``; see ``docs/decisions.md``,
"Sessions"): the interpreter sets ``talker`` to ``input_source`` (whose bytes it reads), the
executor to the session that queued the op it runs, and the machine to the session that started
an axis's motion when it reports what happens to it; 0 is the board's own doing.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.clock import SampleClock
from omsd.engine.events import CommandErrorEvent, DoneEvent, ErrorKind, Event, Output, Reply
from omsd.engine.extensions import Framing, Front, Options, Silent
from omsd.engine.registers import CMD_S, DON_S, Registers
from omsd.engine.world import AxisWorld, WorldState
from omsd.models.spec import Model

if TYPE_CHECKING:  # contouring is imported when a contour is defined (start-up)
    from omsd.engine.contour import ContourDefinition

FlashWriter = Callable[[dict[str, Any] | None, dict[int, str]], None]


class Core:
    """One card's state; see the module docstring."""

    # attributes in slots (issue 16): Python 3.11 keeps no more than 30 attribute names shared
    # between the instances of a class; past that each instance has a dict of its own, slower to
    # read and larger (a poll of the load, 8% fewer instructions with the axes', the machine's
    # and the interpreter's in slots). Subclasses keep a dict for whatever else they set; a new
    # attribute is to be named here (tests/board/test_fast_paths.py finds one that is not).
    # Several names a line: one a line would make a long module longer than the rule allows.
    # fmt: off
    __slots__ = (
        "_by_letter", "_output", "_sources", "after_events", "axes", "clock", "contour",
        "contour_velocity", "deadline", "deadline_stale", "directions", "fast_paths",
        "flash_defaults", "flash_macros", "flash_writer", "framing", "front", "init_until",
        "input_source", "model", "now", "options", "outputs_low", "outside_epoch", "plain_sensing",
        "ramp_tables", "registers", "rest_epoch", "scurves", "settled", "talker", "wakeup",
        "wakeup_stale", "world",
    )
    # fmt: on

    def __init__(
        self,
        model: Model,
        now: float,
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None,
        framing: Framing,
        options: Options,
        fast_paths: bool = True,
    ) -> None:
        self.model = model
        # issue 16: the caches and fast paths of the hot path (Machine.advance, Machine.settle,
        # Board.receive) are on; False runs the straightforward code everywhere (the
        # differential tests, tests/board/test_fast_paths.py, compare the two)
        self.fast_paths = fast_paths
        # a motion's first-tick look at the sensors may be left out where it cannot find
        # anything (omsd.engine.sensing.first_look_needed); Machine turns it off for a dialect
        # with sensor hooks of its own
        self.plain_sensing = fast_paths
        # Machine.advance is running the settle after the events of one instant
        self.after_events = False
        # the machine's next deadline, cached (Machine._next_internal): stale whenever an axis
        # drops its own cached next event (AxisState.invalidate) or init_until changes
        self.deadline_stale = True
        self.deadline: float | None = None
        # when the board must next be run for its host (Machine.next_wakeup), cached: stale
        # whenever the deadline is found again or a settle runs
        self.wakeup_stale = True
        self.wakeup: float | None = None
        # a settle now would do nothing: the queues and the front ran to a standstill and only
        # time has passed since (Machine.settle sets it; see Machine.at_rest for who clears it)
        self.settled = False
        # how many times the machine may have changed otherwise than by time passing: bumped
        # by unsettle() (so wherever ``settled`` is cleared, every settle among them), a
        # register read or write and a report that changes something (Board._reports_at_rest);
        # the replies a board at rest keeps are good for one count (Board._replies)
        self.rest_epoch = 0
        # how many times the machine may have been changed from outside (a command, a change of
        # the world, a reset): bumped by unsettle() and by a settle that is not Machine.advance's
        # own; what an axis was found to be, quiet or heard, is known until it changes
        # (AxisState.quiet_known)
        self.outside_epoch = 0
        self.options = options
        self.framing = framing
        # the flash (non-volatile store) of a card that has one: saved power-up defaults (None:
        # never archived) and stored programs; ``flash_writer`` (set by whoever keeps them, e.g.
        # the daemon's state file) is called with both after every write
        self.flash_defaults: dict[str, Any] | None = None
        self.flash_macros: dict[int, str] = {}
        self.flash_writer: FlashWriter | None = None
        # ramp shapes defined on the card: custom ramp tables and S-curve profiles, by number
        self.ramp_tables: dict[int, list[tuple[float, float]]] = {}
        self.scurves: dict[int, pf.SCurve] = {}
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
        self.front: Front = Silent()
        worlds = _axis_worlds(model, world)
        self.axes = [Axis(self, i, letter, worlds[i]) for i, letter in enumerate(model.axes)]
        self._by_letter = {a.letter: a for a in self.axes}
        self.outputs_low = 0  # general-purpose outputs driven low
        self.directions = model.factory_outputs  # I/O bit directions, 1 = output
        self.contour_velocity = float(model.default_contour_velocity)
        self.contour: ContourDefinition | None = None
        self.init_until: float | None = None

    # -- settings of every axis ---------------------------------------------------------------

    @property
    def ramp(self) -> pf.RampShape:
        """The ramp of the first axis; setting it sets every axis's."""
        return self.axes[0].ramp

    @ramp.setter
    def ramp(self, shape: pf.RampShape) -> None:
        for axis in self.axes:
            axis.ramp = shape

    @property
    def soft_limits(self) -> bool:
        """The soft-limit mode (of the first axis); setting it sets every axis's."""
        return self.axes[0].soft_limit

    @soft_limits.setter
    def soft_limits(self, on: bool) -> None:
        for axis in self.axes:
            axis.soft_limit = on

    def axis_by_letter(self, letter: str) -> Axis | None:
        return self._by_letter.get(letter)

    # -- flash --------------------------------------------------------------------------------

    def flash_matches(self) -> bool:
        """Saved defaults are for this model (a board renamed onto another model in the config
        must not load a stranger's parameters)."""
        saved = self.flash_defaults
        return saved is None or saved.get("model", self.model.name) == self.model.name

    def write_flash(
        self, defaults: dict[str, Any] | None = None, macros: dict[int, str] | None = None
    ) -> None:
        """Write flash (the defaults and the stored programs given) and hand it to the keeper."""
        if defaults is not None:
            self.flash_defaults = defaults
        if macros is not None:
            self.flash_macros = macros
        if self.flash_writer is not None:
            self.flash_writer(self.flash_defaults, dict(self.flash_macros))

    def unsettle(self, outside: bool = True) -> None:
        """Something may have changed that no settle has seen yet: the machine is no longer
        at rest (``settled``), what a report said may no longer hold (``rest_epoch``), nor
        when the board must next be run (``wakeup_stale``); ``outside``: changed from outside,
        not by the machine going its own way (``outside_epoch``)."""
        self.settled = False
        self.rest_epoch += 1
        if outside:
            self.outside_epoch += 1
        self.wakeup_stale = True

    # -- output -------------------------------------------------------------------------------

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
        """A value, in the dialect's framing (PC48: "surrounded by line feeds and carriage
        returns", ``<LF><CR>text<LF><CR>``)."""
        # (reply_value and reply_status are the end of every query: written out, not shared)
        before, after = self.framing.value
        payload = text.encode("latin-1")  # a stored program may hold any byte
        self._output.append(Reply(t, before + payload + after, payload))
        self._sources.append(self.talker)

    def reply_number(self, value: int, t: float) -> None:
        """An integer value (``RP``, the query polled most), as :meth:`reply_value` gives
        ``str(value)``, formatted straight to bytes."""
        before, after = self.framing.value
        payload = b"%d" % value
        self._output.append(Reply(t, before + payload + after, payload))
        self._sources.append(self.talker)

    def reply_status(self, text: str, t: float) -> None:
        """An axis status, in the dialect's framing (PC48: "one line feed and two carriage
        returns on each end")."""
        before, after = self.framing.status
        payload = text.encode("latin-1")
        self._output.append(Reply(t, before + payload + after, payload))
        self._sources.append(self.talker)

    def command_error(self, kind: ErrorKind, command: str, t: float) -> None:
        """CMD_S (PC48 Table 3-8) and, with echo on, "an English readable error message"."""
        self.registers.status |= CMD_S | DON_S
        self.emit(CommandErrorEvent(t, kind, command))
        if self.front.echo:
            self.reply_value(f"{kind.message}: {command}", t)

    @property
    def has_output(self) -> bool:
        """Whether there is output to take (a link that finds none need not take it)."""
        return bool(self._output)

    def take_output(self) -> list[Output]:
        out, self._output = self._output, []
        self._sources = []
        return out

    def take_output_sourced(self) -> tuple[list[Output], list[int]]:
        """The output and, item by item, the session whose conversation produced it."""
        sources = self._sources
        out = self.take_output()
        return out, sources

    def take_bytes(self) -> bytes:
        """Reply bytes only, events dropped: what a raw data port would show."""
        return b"".join(o.data for o in self.take_output() if isinstance(o, Reply))

    # -- done flags ---------------------------------------------------------------------------

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

    def busy_axes(self) -> list[str]:
        """Axes that are moving or have commands queued (what a wait for done waits on)."""
        return [a.letter for a in self.axes if a.moving or not a.queue.empty]

    # -- registers ----------------------------------------------------------------------------

    @property
    def initializing(self) -> bool:
        return self.init_until is not None and self.now < self.init_until

    def status_register(self, now: float) -> int:
        """The status register without the side effect of a read. IBF_S "indicates a character
        is available in the input buffer" (PC48 Table 3-8): a reply or echoed characters not yet
        taken, not an event (a done, limit, slip or command error puts no byte on the data
        port; it is in the other bits)."""
        return self.registers.compose_status(
            self.initializing,
            self.front.room(),
            any(type(item) is Reply and item.data for item in self._output),
        )

    # -- general purpose I/O ------------------------------------------------------------------

    def input_high(self, bit: int, t: float) -> bool:
        """Level of a general-purpose line: outputs show what the board drives, inputs what the
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
        """A one in any binary position signals that bit as being low."""
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
