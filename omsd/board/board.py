"""The board: one model row, its dialect and the engine's machine, joined.

``Board(model)`` looks up the dialect the model row names (:mod:`omsd.dialects`), builds the
engine's :class:`~omsd.engine.machine.Machine` with what the dialect gives it (options, ops,
sensor hooks; the framing the row names) and puts the dialect's interpreter in front of it. A
``Board`` *is* that machine (its axes, registers, clock and output are the board's attributes,
with no indirection on the hot path) plus the data port: :meth:`Board.receive` takes the
host's bytes into the interpreter's input buffer, keeping the sessions apart
(``docs/decisions.md``, "Sessions").

The board never reads a clock and never sleeps. Every entry point takes ``now`` (seconds, any
origin); :meth:`~omsd.engine.machine.Machine.next_deadline` says when something will next
change by itself, so a caller can sleep until then, and a test can step a ten-minute move in
microseconds::

    board = Board(get_model("PC48-4E"), now=0.0)
    board.receive(b"VL400000 AC500000 MR1000000 GO", now=0.0)
    while (t := board.next_deadline()) is not None and t < 10:
        board.advance(t)
    board.receive(b"RP", now=10.0)
    board.take_bytes()  # b'\\n\\r1000000\\n\\r'
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from omsd.dialects import framing, lookup
from omsd.dialects.interpreter import BareReport, Blocked, CommandFailed, Interpreter
from omsd.engine.axis import Axis
from omsd.engine.events import Reply
from omsd.engine.machine import Machine
from omsd.engine.registers import CMD_S
from omsd.engine.states import Motion
from omsd.engine.world import AxisWorld
from omsd.models.spec import Model
from omsd.protocol.lexer import SEPARATORS, Command
from omsd.protocol.operands import OperandError

#: How many runs of reports ``Board._reports_at_rest`` keeps what it found in (a poller asks
#: the same few again and again; a client that never repeats itself only refills it).
SCANS_KEPT = 64

CONTROL_D = 0x04
CONTROL_X = 0x18
CONTROL_Y = 0x19
#: The control characters that bypass the interpreter (kill, clear flags), and on a board whose
#: Control-X clears the command error flag (``Model.control_x``).
CONTROLS = (CONTROL_D, CONTROL_Y)
CONTROLS_X = (CONTROL_D, CONTROL_Y, CONTROL_X)


class Board(Machine):
    """One emulated board. See the module docstring."""

    def __init__(
        self,
        model: Model,
        now: float = 0.0,
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None = None,
        *,
        fast_paths: bool = True,
    ) -> None:
        dialect = lookup(model.dialect)
        super().__init__(
            model,
            now,
            world,
            framing=framing(model),
            options=dialect.options,
            ops=dialect.ops,
            sensor_hooks=dialect.sensor_hooks,
            fast_paths=fast_paths,
        )
        self.dialect = dialect
        self.interpreter: Interpreter = dialect.interpreter(self, dialect)
        self.front = self.interpreter
        # replies at rest (issue 16; _reports_at_rest): what each pure report said, by its
        # bytes, good while rest_epoch is _replies_epoch
        self.pure_reports: frozenset[str] = dialect.pure_reports
        """The reports that change nothing on this board (``Dialect.pure_reports``, less those
        that run a servo loop where there is one)."""
        if any(axis.servo is not None for axis in self.axes):
            self.pure_reports -= dialect.loop_reports
        self._replies: dict[bytes, tuple[bytes, bytes | None]] = {}
        # what _scan found in the runs of reports polled (the words of a language are fixed)
        self._scans: dict[bytes, list[tuple[int, Command]]] = {}
        # how _run_plan runs them, by their bytes and the mode and axis they begin in
        self._plans: dict[tuple[bytes, str, int], list[BareReport]] = {}
        self._replies_epoch = -1
        self.power_up(now)

    # -- power ----------------------------------------------------------------------------------

    def power_cycle(self, now: float) -> None:
        """Switch the card off and on: a reset that also empties the input buffer and loses what
        the host wrote to the bus interface's latches (a VS4's interrupt vector, which RS keeps:
        docs/decisions.md, "Flags and registers")."""
        self.advance(now)
        self.interpreter.discard_input()
        self.registers.vector = 0
        self.reset(now)

    def load_flash(self) -> list[str]:
        """Power-up and a restore: the saved defaults (``flash_defaults``) over the factory
        values, and the stored programs, as the dialect keeps them (the PCIx; the older boards
        keep nothing in flash). Returns the saved values skipped because they do not fit."""
        self.unsettle()
        return self.interpreter.load_flash()

    # -- the data port ------------------------------------------------------------------------

    def receive(self, data: bytes, now: float, source: int = 0) -> int:
        """Bytes from the host. Returns how many were taken: a full input buffer (124
        characters on a PC48, while the interpreter is held by a full queue or WQ) takes no more,
        as the host would see TBE_S low; the caller keeps the rest and offers it again later.
        Control-D (kill) and Control-Y (clear flags) bypass the interpreter, and on a VS4
        Control-X (clear the command error flag, ``Model.control_x``).

        ``source`` names the session the bytes come from (0: the only one). The input buffer
        holds one session's characters at a time: another session's bytes are not taken (0)
        until the characters already there have been read, so that what the board answers can
        be told apart (Control-D, which empties the buffer, is taken at once)."""
        if self.fast_paths and source == self.input_source and self._reports_at_rest(data, now):
            return len(data)
        self.unsettle()
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
        controls = CONTROLS_X if self.model.control_x else CONTROLS
        while taken < n:
            b = data[taken]
            if b in controls:
                interp.pump(now)
                if not interp.room():
                    break
                if b == CONTROL_D:
                    interp.control_d(now)
                elif b == CONTROL_Y:
                    interp.clear_flags()
                else:
                    self.registers.status &= ~CMD_S  # Control-X: "clears command errors only"
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
            for control in controls:
                cut = chunk.find(control)
                if cut >= 0:
                    chunk = chunk[:cut]
            buffer.extend(chunk)
            taken += len(chunk)
        interp.pump(now)
        self.settle(now)
        self.advance(now)
        return taken

    def _reports_at_rest(self, data: bytes, now: float) -> bool:
        """Fast path (issue 16): ``data`` is nothing but operand-less reports (``RP``, ``QA``,
        ``?KP``; separators between them), the machine is at rest (:meth:`at_rest`: nothing
        due, nothing to settle, the interpreter holding nothing) and not initialising, or is
        so once what is due by ``now`` has happened (a move that ended since the last poll:
        the regular way's first step, ``advance``, is taken here). The reports are run here,
        one after the other, and True returned; otherwise (False) nothing but that advance
        was done and ``receive`` takes the regular way.

        Equivalent to the regular way, which would: let time run to ``now`` (nothing is due:
        only the clock moves), put the bytes in the input buffer and ``pump`` them (each word
        is a command the lexer gives whole, run as the pending queue would run it:
        :meth:`Interpreter.run_bare`; a report queues nothing, so no axis is stepped after it,
        and it leaves the interpreter holding nothing), ``settle`` each time the buffer is
        full and more is to come, and at the end ``settle`` and ``advance`` to ``now``. Those
        settles and that advance are made here too, at the same points, unless the machine is
        still at rest there (then they would change nothing).

        **Replies at rest**: a pure report (``Dialect.pure_reports``: it changes nothing, so
        run again it says the same) run here on a board where nothing moves and nothing will
        happen by itself (no deadline, every axis idle: no answer depends on the time) is
        kept, by its bytes; asked again while nothing has changed (``rest_epoch``: every
        settle, every clearing of ``settled``, every register access and every report here
        that is not pure counts one), the same reply is given at once."""
        replies = self._replies
        if (
            replies
            and self._replies_epoch == self.rest_epoch
            and now >= self.now
            and (kept := replies.get(data)) is not None
        ):
            self.now = now
            self.talker = talker = self.input_source
            self.interpreter.depth = 0
            self._output.append(Reply(now, kept[0], kept[1]))
            self._sources.append(talker)
            return True
        if not (self.at_rest(now) and now >= self.now and self.init_until is None):
            # something is due by now (a move has ended since the last poll): let it happen
            # first, as the regular way's first step (``advance``) would; at rest after it,
            # the reports are run here all the same
            if not (self.settled and now >= self.now):
                return False
            self.advance(now)
            if not (self.at_rest(now) and self.init_until is None):
                return False
        interp = self.interpreter
        # a run of reports polled before, in this mode on this axis, is looked for first (the
        # poll of a board; a plan is never of one word: those are found in ``ready``); with no
        # contour or definition open, as ``bare_reports`` (None then) requires
        plan = (
            self._plans.get((data, interp.mode, interp.axis_index))
            if interp.contour is None and interp.only is None
            else None
        )
        ready = None if plan else interp.bare_reports()
        entry = ready.get(data) if ready is not None else None
        if plan:  # run by its plan
            self.now = now
            self.talker = self.input_source
            self.rest_epoch += 1
            self._run_plan(plan, now)
            if self.settled and not self.deadline_stale:
                return True  # still at rest: its deadline is the one at_rest looked at
        elif entry is not None:  # one word, ready to run (run_bare, written out)
            command = entry[2]
            self.now = now
            self.talker = self.input_source
            said = len(self._output)
            self._run_plan((entry,), now)  # (a plan of one word)
            if command.mnemonic not in self.pure_reports:
                self.rest_epoch += 1  # it may have changed what a report says
            elif self.settled and not self.deadline_stale and self.deadline is None:
                self._keep_reply(data, said)
            if self.settled and not self.deadline_stale:
                return True  # still at rest: its deadline is the one at_rest looked at
        elif (word := (words := interp.report_words).get(data)) is not None:
            # one word not ready here (a check fails: run_bare says why)
            self.now = now
            self.talker = self.input_source
            self.rest_epoch += 1
            if not interp.run_bare(word, now):
                raise AssertionError(f"{word.mnemonic}, a report, waited for queue space")
            if self.settled and not self.deadline_stale:
                return True
        else:
            scans = self._scans
            found = scans.get(data)
            if found is None:
                found = _scan(data, words, interp.words.longest)
                if len(scans) >= SCANS_KEPT:
                    scans.clear()
                scans[data] = found
            if not found:
                return False
            self.now = now
            self.talker = self.input_source
            self.rest_epoch += 1
            full = interp.capacity  # where the regular way finds the buffer full, and settles
            if ready is not None and found[-1][0] <= full:  # (no settle among them)
                self._plan(data, found, now)
                found = []
            for end, word in found:
                while full < end:
                    if not self.at_rest(now):
                        self.settle(now)
                    full += interp.capacity
                if not interp.run_bare(word, now):
                    raise AssertionError(f"{word.mnemonic}, a report, waited for queue space")
        if not self.at_rest(now):
            self.settle(now)
            self.advance(now)
        return True

    def _plan(self, data: bytes, found: list[tuple[int, Command]], now: float) -> None:
        """Run the words ``found`` in ``data`` (reports and selections of an axis, with no
        contour or table being defined) one by one (``Interpreter.run_bare``), and keep their
        plan for the next time ``data`` is run in this mode on this axis (:meth:`_run_plan`):
        the handler and cell the checks of each word give (``Interpreter.ready``). The checks
        of a word depend only on the mode and axis it is run in, and those only on the mode and
        axis the run began in: a report changes neither, and a selection sets them whatever
        they were (or fails, and changes nothing). A run with a word that fails its checks
        (``ready``: None) has an empty plan: it is run word by word each time."""
        interp = self.interpreter
        plans = self._plans
        key = (data, interp.mode, interp.axis_index)
        entries = []
        for _, word in found:
            entries.append(interp.ready(word))
            if not interp.run_bare(word, now):
                raise AssertionError(f"{word.mnemonic}, a report, waited for queue space")
        if key not in plans:
            if len(plans) >= SCANS_KEPT:
                plans.clear()
            plan = [(*e, w) for e, (_, w) in zip(entries, found, strict=True) if e is not None]
            plans[key] = plan if len(plan) == len(found) else []

    def _run_plan(self, plan: Sequence[BareReport], now: float) -> None:
        """Run a run of reports by its plan (:meth:`_plan`): each word's handler, as
        ``Interpreter.run_bare`` calls it."""
        interp = self.interpreter
        interp.depth = 0  # (once: a report or a selection runs no macro, and leaves it at 0)
        for handler, cell, command in plan:
            try:
                handler(interp, command, cell, now)
            except Blocked as exc:
                raise AssertionError(f"{command.mnemonic}, a report, waited") from exc
            except (CommandFailed, OperandError) as exc:
                self.command_error(exc.kind, command.text, now)

    def _keep_reply(self, data: bytes, said: int) -> None:
        """Keep the reply of the pure report ``data`` just run (see :meth:`_reports_at_rest`),
        if it was one reply and no answer can depend on the time."""
        out = self._output
        if len(out) != said + 1 or type(reply := out[-1]) is not Reply or self.interpreter.echo:
            return
        if any(axis.motion is not Motion.IDLE for axis in self.axes):
            return
        if self._replies_epoch != self.rest_epoch:
            self._replies = {}
            self._replies_epoch = self.rest_epoch
        self._replies[data] = (reply.data, reply.text)

    def input_room(self, source: int | None = None) -> int:
        """Characters the input buffer can take now (what a host sees as TBE_S); for
        ``source``, none while another session's characters are still in it."""
        interp = self.interpreter
        if source is not None and source != self.input_source and (interp.buffer or interp.pending):
            return 0
        return interp.capacity - len(interp.buffer)

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

    # -- inspection -----------------------------------------------------------------------------

    @staticmethod
    def _axis_snapshot(a: Axis, now: float) -> dict[str, Any]:
        # the switches see the carriage once (the control API's subscriptions take a snapshot
        # of every moving board 10 to 50 times a second)
        carriage = a.carriage(now)
        return {
            "position": a.counter(now),
            "encoder": a.encoder(now) if a.has_encoder else None,
            "velocity": a.velocity(now),
            "physical": a.phys(now),
            "moving": a.motion is not Motion.IDLE,
            "motion": a.motion.name.lower(),
            "done": a.done,
            "direction": a.direction,
            "limit_negative": a.limit_active(-1, now, carriage),
            "limit_positive": a.limit_active(1, now, carriage),
            "home": a.home_sensed(now, carriage),
            "aux": a.aux,
            "queue_free": a.queue.free,
            "velocity_setting": a.vl,
            "acceleration_setting": a.ac,
        }

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
            "axes": {a.letter: self._axis_snapshot(a, now) for a in self.axes},
        }


def _scan(data: bytes, words: Mapping[bytes, Command], longest: int) -> list[tuple[int, Command]]:
    """The commands of ``data`` if it is nothing but ``words`` and separators, each with where
    it ends; an empty list otherwise."""
    found: list[tuple[int, Command]] = []
    i = 0
    n = len(data)
    while i < n:
        if data[i] in SEPARATORS:
            i += 1
            continue
        for size in (2, 3) if longest > 2 else (2,):
            command = words.get(data[i : i + size])
            if command is not None:
                i += size
                found.append((i, command))
                break
        else:
            return []
    return found
