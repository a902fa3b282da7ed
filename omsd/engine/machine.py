"""The machine: a pure, clock-injected model of one card's mechanics, without a language.

Theory of operation (after PC48 §8.2): each axis executes its command queue concurrently,
moving its motor along analytic velocity profiles computed on a grid of samples (2048 a second
on the PC48); switches, encoders and input lines of the simulated world are watched on that grid
too. What fills the queues is the command language in front of the machine (its
:class:`~omsd.engine.extensions.Front`, a dialect's interpreter), which
:meth:`Machine.settle` runs whenever the queues have run.

The machine never reads a clock and never sleeps. Every entry point takes ``now`` (seconds, any
origin); :meth:`Machine.next_deadline` says when something will next change by itself (a move
ends, a switch is reached, a timed wait expires), so a caller can sleep until then, and a test
can step a ten-minute move in microseconds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from omsd.engine import profiles as pf
from omsd.engine import reactions
from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.executor import Executor, OpFunction, SensorHook
from omsd.engine.extensions import BARE, Framing, Options
from omsd.engine.follow_on import ends_that_follow_on, follow_on, follow_on_until
from omsd.engine.ops_flow import FLOW_OPS
from omsd.engine.ops_motion import MOTION_OPS
from omsd.engine.ops_parameters import PARAMETER_OPS
from omsd.engine.quiet import MOVE_BY, MOVE_TO, QUIET_OPS, quiet
from omsd.engine.states import Motion
from omsd.engine.world import AxisWorld
from omsd.models.spec import Model

MAX_EVENTS_PER_ADVANCE = 1_000_000
_IDLE = Motion.IDLE  # (a global: an Enum member read through its class costs more)
INF = float("inf")

#: How far before its next deadline a machine counts as at rest (:meth:`Machine.at_rest`): a
#: timed wait is over from ``until - 1e-12`` (``Executor.satisfied``), so a settle that close to
#: a deadline may already run something.
AT_REST_MARGIN = 1e-9

#: The ops every machine runs (the shared language's queued commands).
ENGINE_OPS: dict[str, OpFunction] = {**PARAMETER_OPS, **MOTION_OPS, **FLOW_OPS}


class Machine(Core):
    """One card's mechanics; see the module docstring. ``ops`` and ``sensor_hooks`` add a
    dialect's queued commands and sensor looks to the engine's own; ``framing`` and
    ``options`` are the dialect's."""

    # (Core's note on slots)
    __slots__ = (
        "_follow_on_codes",
        "_quiet_codes",
        "executor",
    )

    def __init__(
        self,
        model: Model,
        now: float = 0.0,
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None = None,
        *,
        framing: Framing = BARE,
        options: Options | None = None,
        ops: Mapping[str, OpFunction] | None = None,
        sensor_hooks: Sequence[SensorHook] = (),
        fast_paths: bool = True,
    ) -> None:
        super().__init__(model, now, world, framing, options or Options(), fast_paths)
        self.executor = Executor(self, {**ENGINE_OPS, **(ops or {})}, sensor_hooks)
        if sensor_hooks:
            self.plain_sensing = False  # (the PCIx: its hook looks at the home switch each time)
        # the quiet commands (omsd.engine.quiet) that run the engine's own code on this board
        own = ops or {}
        self._quiet_codes = frozenset(
            code for code in QUIET_OPS if own.get(code, ENGINE_OPS[code]) is ENGINE_OPS[code]
        )
        # the move commands a queued move may follow on with (omsd.engine.follow_on): the
        # engine's own, with its own GO
        quiet_codes = self._quiet_codes
        self._follow_on_codes = (
            quiet_codes & (MOVE_TO | MOVE_BY) if "GO" in quiet_codes else frozenset()
        )
        self.power_up(now)

    # -- power ----------------------------------------------------------------------------------

    def power_up(self, t: float) -> None:
        """Power-up defaults of the machine, then of its front (the language)."""
        self.ramp = pf.LINEAR
        self.soft_limits = False
        self.outputs_low = 0  # outputs driven low: "off at power up or reset"
        self.directions = self.model.factory_outputs
        self.contour_velocity = float(self.model.default_contour_velocity)
        self.contour = None
        self.registers.control = 0  # "All interrupts are disabled."
        self.registers.done = 0
        self.registers.status = 0
        self.init_until = None
        self.deadline_stale = True
        self.unsettle()
        self.front.power_up()

    def reset(self, t: float) -> None:
        """A reset (PC48 §6.5 RS): "All previously entered data and commands are lost. All
        internal parameters are initialized to defaults. All interrupts are disabled." The INIT
        status bit is high for ``model.init_time``; input received meanwhile waits."""
        for axis in self.axes:
            axis.reset(t)
        self.power_up(t)
        self.init_until = t + self.model.init_time
        self.deadline_stale = True

    # -- time -----------------------------------------------------------------------------------

    def advance(self, now: float) -> None:
        """Let everything that happens by itself happen, up to ``now``."""
        if now < self.now:
            now = self.now
        t = self._next_internal()
        if t is not None and t <= now and self.fast_paths:
            # fast path: the instants at which moves end and the next start, taken first
            # (omsd.engine.follow_on); the loop goes on from the first that is more than that
            follow_on_until(self.executor, self._follow_on_codes, now)
            t = self._next_internal()
        for _ in range(MAX_EVENTS_PER_ADVANCE):
            if t is None or t > now:
                break
            self.now = max(self.now, t)
            self._handle_due(t)
            self.after_events = True  # (a move begun now is looked at in this same loop)
            try:
                self.settle(t)
            finally:
                self.after_events = False
            t = self._next_internal()
        self.now = now

    def next_deadline(self) -> float | None:
        """When the machine next changes by itself; ``None`` if it never will on its own."""
        t = self._next_internal()
        if t is not None and t <= self.now:
            return self.now
        return t

    def next_wakeup(self) -> float | None:
        """When the board must next be run so that its host hears everything on time: the
        earliest deadline of the axes that are not quiet (:mod:`omsd.engine.quiet`), or INIT's
        end; ``None`` if nothing it does by itself can be heard until it is changed from
        outside. Deadlines before it may be left until the board is next run anyway (a command,
        a change of the world, a later wake-up): the board then lets them happen at their own
        times, with the same result. Without the fast paths, :meth:`next_deadline`."""
        if not self.fast_paths or not self.settled:
            # (not settled: something changed that no settle has seen yet, e.g. a rewiring of
            # the world; the next deadline may be where it shows)
            return self.next_deadline()
        deadline = self._next_internal()
        if self.wakeup_stale:
            self.wakeup = self._find_wakeup(deadline)
            self.wakeup_stale = False
        t = self.wakeup
        if t is not None and t <= self.now:
            return self.now
        return t

    def _find_wakeup(self, deadline: float | None) -> float | None:
        if (
            deadline is None
            or self.init_until is not None
            or self.executor.sensor_hooks
            or self.contour is not None
        ):
            return deadline
        axes = self.axes
        for axis in axes:
            if axis.gear is not None:
                return deadline
        codes = self._quiet_codes
        epoch = self.outside_epoch
        best: float | None = None
        for axis in axes:
            event = axis.event  # (read without a call where it is known, as _next_internal)
            if event is None:
                t = axis.next_event_time()
            else:
                t = event[0]
                if t == INF:
                    t = None
            if t is None or (best is not None and t >= best):
                continue
            # what each axis was found to be is known until it is changed from outside
            # (omsd.engine.quiet): a quiet axis stays quiet; one that is not may become quiet
            # as its queue goes on, and is taken as heard until then (woken for: the safe side)
            known = axis.quiet_known
            if known is None or known[0] != epoch:
                known = axis.quiet_known = (epoch, quiet(axis, codes))
            if known[1]:
                continue
            best = t
        return best

    def _next_internal(self) -> float | None:
        """The earliest of the axes' next events and the end of INIT. Cached: found again only
        when an axis has dropped its own cached next event (``deadline_stale``), so that a
        poll costs the same whatever the number of axes in motion."""
        if self.deadline_stale or not self.fast_paths:
            best = self.init_until
            for axis in self.axes:
                event = axis.event  # (read without a call where it is known)
                t = axis.next_event_time() if event is None else event[0]
                if t is not None and t != INF and (best is None or t < best):
                    best = t
            self.deadline = best
            self.deadline_stale = False
            self.wakeup_stale = True
        return self.deadline

    def at_rest(self, now: float) -> bool:
        """Fast path (issue 16): nothing would happen if the machine were run at ``now``: the
        last :meth:`settle` ran to a standstill with a front that holds nothing
        (``Front.holds_nothing``), nothing has changed since but the time, and nothing is due by
        ``now`` (with :data:`AT_REST_MARGIN`). Then a :meth:`settle` and an :meth:`advance` to
        ``now`` would change nothing but ``self.now``, and a caller may skip them
        (``Board.receive`` after a report).

        Why that holds: with no deadline passed, no axis queue can move on (a wait for time is
        a deadline; a wait for motion, a group, an input or "in position" ends only by what an
        event, a command or a change of the world does), and the front has nothing to read.
        ``settled`` is set by a settle that found nothing to do (and a front holding nothing:
        no input, no command held back, no echo), and cleared by whatever may change the
        machine without settling afterwards: a power-up or reset, a rewiring of the world
        (:meth:`wire_input_to_aux`), input taken the regular way (``Board.receive``), a load of
        the flash. Code that changes the machine's attributes directly must call :meth:`settle`
        afterwards (the public methods do)."""
        if not self.settled or self.deadline_stale:
            return False
        deadline = self.deadline
        return deadline is None or now < deadline - AT_REST_MARGIN

    def _handle_due(self, t: float) -> None:
        if self.init_until is not None and self.init_until <= t:
            self.init_until = None
            self.deadline_stale = True
        # fast path: moves that end, each with the next in its queue (omsd.engine.follow_on)
        if self.fast_paths and ends_that_follow_on(self.executor, self._follow_on_codes, t):
            self.talker = 0
            return
        ex = self.executor
        # (the reactions may change other axes than their own: no axis is known quiet after them)
        self.outside_epoch += 1
        for axis in self.axes:
            event = axis.event
            if event is not None and event[0] > t:
                continue  # nothing due (read without a call where it is known)
            self.talker = axis.source  # what happens to an axis is the business of its mover
            for _ in range(64):
                when = axis.next_event_time()
                if when is None or when > t:
                    break
                kind = axis.due()
                if kind == "end":
                    reactions.on_end(ex, axis, t)
                elif kind == "sensor":
                    reactions.on_sensor(ex, axis, t)
                elif kind == "in":
                    reactions.fire_in(ex, axis, t)
                elif kind == "aux":
                    reactions.on_aux_timer(ex, axis, t)
                elif kind == "output":
                    reactions.on_outputs(ex, axis, t)
                elif kind == "servo":
                    reactions.on_servo(ex, axis, t)
                elif kind == "wait" and not ex.step(axis, t):
                    if axis.wait is not None:
                        axis.wait.until = None
                    axis.invalidate()
                axis.invalidate()
        self.talker = 0

    def settle(self, t: float) -> None:
        """Run queues and the front until nothing more happens at ``t``."""
        step = self.executor.step
        front = self.front
        skip_idle = self.fast_paths
        codes = self._follow_on_codes
        # (the settle after an instant's events, Machine.advance's own, is the machine going
        # its own way, not a change from outside)
        self.unsettle(outside=not self.after_events)
        for _ in range(10_000):
            progressed = False
            for axis in self.axes:
                # fast paths: an axis with no wait and nothing left in its queue, or waiting for
                # its own motion to end while it still moves (and its mover is the waiting
                # command's sender, as Executor.step would make it), is not stepped:
                # Executor.step would return False at once, changing nothing. One whose motion
                # has ended, with a move and GO next in its queue, starts that move in
                # omsd.engine.follow_on, as Executor.step would
                if skip_idle:
                    wait = axis.wait
                    q = axis.queue
                    if wait is None:
                        if q.pc >= len(q.program):
                            continue
                    elif wait.kind == "motion":
                        if axis.motion is not _IDLE:
                            if q.pc < len(q.program) and q.program[q.pc].source == axis.source:
                                continue
                        elif follow_on(self, axis, codes, t):
                            # (not progress another round must look at: the front, pumped
                            # after the axes, sees the room it made in this round)
                            continue
                if step(axis, t):
                    progressed = True
            if front.pump(t):
                progressed = True
            if not progressed:
                self.settled = front.holds_nothing()
                return
            # (a queued command ran: it may change other axes than its own, so no axis is known
            # quiet after it; a move that follows on changes its own axis alone, and keeps it so)
            self.outside_epoch += 1

    # -- registers ------------------------------------------------------------------------------

    def read_status_register(self, now: float) -> int:
        """Read offset 3; DON_S, CMD_S, ENC_S and OVRT reset on read (PC48 §3.4.4)."""
        self.advance(now)
        self.rest_epoch += 1
        value = self.status_register(now)
        self.registers.clear_on_status_read()
        return value

    def read_done_register(self, now: float) -> int:
        """Read offset 1: "This register is cleared automatically after it is read.\""""
        self.advance(now)
        self.rest_epoch += 1
        return self.registers.read_done()

    def write_control_register(self, value: int, now: float) -> None:
        self.advance(now)
        self.rest_epoch += 1
        self.registers.control = value & 0xF0

    def read_control_register(self, now: float) -> int:
        return self.registers.control

    def write_vector_register(self, value: int, now: float) -> None:
        """VME boards (VS4): "Interrupt Vector", a read/write byte returned during IACK."""
        self._need_vector()
        self.rest_epoch += 1
        self.registers.vector = value & 0xFF

    def read_vector_register(self, now: float) -> int:
        self._need_vector()
        return self.registers.vector

    def _need_vector(self) -> None:
        if not self.model.vector_register:
            raise ValueError(f"a {self.model.name} has no interrupt vector register")

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
        self.unsettle()  # a wait for the input may be over: the next settle sees
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
        """Drive the encoder input from outside, as a handwheel or another device would. In
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
