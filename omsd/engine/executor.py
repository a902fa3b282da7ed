"""Executing the axis queues (PC48 §6.2, §6.7–§6.12, §8.2).

Each axis runs its own program: it executes queued ops one after another at the time they are
reached; an op that takes time (a move, a timed wait, a wait for other axes) leaves a
:class:`~omsd.engine.states.Wait` on the axis and the queue stays on that op, holding its slots,
until the wait is over. Moves start on the next sample tick. Ops shared by several axes (AA mode)
meet in a :class:`~omsd.engine.queue.SyncGroup`.

What each op does is a function of the op table the executor is given: the engine's own
(:mod:`omsd.engine.ops_parameters`, :mod:`omsd.engine.ops_motion`, :mod:`omsd.engine.ops_flow`)
and those of the board's dialect. This module holds what ops and the machine's reactions to
the world (:mod:`omsd.engine.reactions`) share: groups, flushing, starting specified moves,
position maintenance.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence

from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.gearing import disengage
from omsd.engine.queue import Op, SyncGroup
from omsd.engine.states import Motion, Wait

Result = Wait | int | None  # None: done, int: jump to that program index

#: What an op does when an axis reaches it: ``fn(executor, axis, op, t)``.
OpFunction = Callable[["Executor", Axis, Op, float], Result]
#: A dialect's look at an axis's sensors, ``hook(executor, axis, t)``: at every sensor check,
#: after backlash is taken up and before limits are checked.
SensorHook = Callable[["Executor", Axis, float], None]

MAX_STEPS = 10_000  # ops one axis may run at one instant (a loop of zero-time ops)
#: A time wait is over this early (float noise in times made of ticks and milliseconds).
WAIT_SLACK = 1e-12
_IDLE = Motion.IDLE  # a global: an Enum member read through its class costs 70 ns in 3.11


class Executor:
    def __init__(
        self,
        machine: Core,
        ops: Mapping[str, OpFunction],
        sensor_hooks: Sequence[SensorHook] = (),
    ) -> None:
        self.machine = machine
        self._ops = dict(ops)
        self.sensor_hooks = tuple(sensor_hooks)

    # -- the queue ----------------------------------------------------------------------------

    def step(self, axis: Axis, t: float) -> bool:
        """Run the axis's queue as far as it goes at ``t``; True if anything happened. What an
        op causes belongs to the session that sent it (``Op.source``)."""
        machine = self.machine
        saved = machine.talker
        try:
            return self._step(axis, t)
        finally:
            machine.talker = saved

    def _step(self, axis: Axis, t: float) -> bool:
        q = axis.queue
        machine = self.machine
        progressed = False
        for _ in range(MAX_STEPS):
            if axis.wait is not None:
                w = axis.wait
                held = q.current
                if held is not None:
                    machine.talker = axis.source = held.source
                if not self.satisfied(axis, w, t):
                    return progressed
                axis.wait = None
                axis.invalidate()
                if w.then is not None:
                    w.then(t)
                if w.jump is not None:
                    q.jump(w.jump)
                    progressed = True
                    continue
                op = q.current
                if w.kind == "group" and op is not None:
                    nxt = self._after_group(axis, op, t)
                    if isinstance(nxt, Wait):
                        axis.wait = nxt
                        axis.invalidate()
                        progressed = True
                        continue
                    if isinstance(nxt, int):
                        q.jump(nxt)
                        progressed = True
                        continue
                q.advance()
                progressed = True
                continue
            op = q.current
            if op is None:
                return progressed
            machine.talker = axis.source = op.source
            result = self._ops[op.code](self, axis, op, t)
            progressed = True
            if isinstance(result, Wait):
                axis.wait = result
                axis.invalidate()
            elif isinstance(result, int):
                q.jump(result)
            else:
                q.advance()
        return progressed

    def run_queues(self, t: float) -> None:
        """Let every axis run what was queued, as the interpreter does before it reads the next
        command. An AA meeting point (an AA GO, WD, WG) that the last of its axes reaches in
        this pass lets the ones that reached it before go on at this same instant ("The
        synchronized modes (AA) insert special wait opcodes that allow the axes to be
        synchronized", PC48 §6.1): they are stepped again, so that a report typed next (RQ)
        sees every axis past it."""
        step = self.step
        axes = self.machine.axes
        for _ in range(10_000):  # (a bound: each pass frees a meeting point, or it returns)
            for axis in axes:
                step(axis, t)
            for axis in axes:
                w = axis.wait
                if w is not None and w.kind == "group" and w.group and w.group.released(w.round):
                    break
            else:
                return

    def satisfied(self, axis: Axis, w: Wait, t: float) -> bool:
        """The wait ``w`` of the axis's queue is over at ``t`` (and its step goes on)."""
        if w.kind == "motion":
            return axis.motion is _IDLE
        if w.kind == "time":
            return w.until is not None and t >= w.until - WAIT_SLACK
        if w.kind == "group":
            assert w.group is not None
            return w.group.released(w.round)
        if w.kind == "input":
            return self.machine.input_high(w.bit, t) == w.high
        if w.kind == "inpos":
            return axis.in_position and axis.motion is Motion.IDLE
        raise AssertionError(w.kind)

    # -- sync groups --------------------------------------------------------------------------

    def arrive(self, axis: Axis, op: Op, t: float) -> Result:
        g = op.group
        assert g is not None
        r = g.arrive(axis.index)
        self.check_group(g, t)
        if g.barrier and not g.released(r):
            return Wait("group", group=g, round=r)
        if g.barrier:
            return self._after_group(axis, op, t)
        return None

    def check_group(self, g: SyncGroup, t: float) -> None:
        while g.ready_round() > g.completed_round:
            g.completed_round += 1
            if g.action is not None:
                g.action(g, t)

    def _after_group(self, axis: Axis, op: Op, t: float) -> Result:
        """What a member does once its barrier is released."""
        if op.code in ("GO", "GD", "CX"):
            return Wait("motion") if axis.motion is not Motion.IDLE else None
        if op.code == "WT":
            return Wait("time", until=op.group.data["until"] if op.group else t)
        if op.code == "SW":
            return self.wait_for_input(axis, op, t)
        if op.code in ("WD", "WG"):
            assert op.group is not None
            return self.loop_end(axis, op.group.data["again"], t)
        return None

    def drop_from_groups(self, axis: Axis, ops: list[Op], t: float) -> None:
        """A flushed axis no longer takes part in the groups of its dropped ops
        (``flushed_from`` in the group's data: the first round it did not reach): the others
        are not held at a meeting it will never reach. A
        group that completes for it speaks for the session that sent it, not for whoever
        caused the flush."""
        machine = self.machine
        saved = machine.talker
        groups = {id(op.group): op for op in ops if op.group is not None}
        for op in groups.values():
            g = op.group
            assert g is not None
            g.members.discard(axis.index)
            # the first round of the group the axis will not reach (in a loop, the rounds it
            # did reach before the flush stand)
            missed = g.arrivals.get(axis.index, 0) + 1
            g.data["flushed_from"] = min(g.data.get("flushed_from", missed), missed)
            machine.talker = op.source
            self.check_group(g, t)
        machine.talker = saved

    def flush(self, axis: Axis, t: float) -> None:
        dropped = axis.queue.flush()
        axis.wait = None
        axis.stream_end = None  # a VS after it begins a stream anew (ops_motion._stream)
        axis.pending = None
        axis.in_arm = None
        axis.in_fire = None
        self.machine.front.forget_loops(axis.index)
        self.drop_from_groups(axis, dropped, t)
        if axis.gear is not None:  # a flush of a geared axis's queue also ends the gearing
            disengage(axis, t)
        axis.invalidate()

    # -- group actions and waits ops share ----------------------------------------------------

    def go_action(self, group: SyncGroup, t: float) -> None:
        """The moment every axis of an AA/AM start has arrived: start them together."""
        machine = self.machine
        axes = [machine.axes[i] for i in sorted(group.members)]
        if group.data.get("gd"):
            machine.clear_done(machine.axes if group.data.get("all") else axes)
        self.start_pending(axes, t)

    def done_action(self, group: SyncGroup, t: float) -> None:
        """The done of an AA/AM ID (IN, IP, the PCIx's GN): the done flag in the status
        register "will not be set until all axes have executed the ID command" (PC48 §6.12);
        so never for a round of the group that an axis left by a flush (SA, KL, a limit) did
        not reach: it will not execute that ID. The rounds of a loop that every axis finished
        before the flush had theirs; the axes that got there keep their own done flags."""
        missed = group.data.get("flushed_from")
        if missed is None or group.completed_round < missed:
            self.machine.signal_done(t)

    def wt_action(self, group: SyncGroup, t: float) -> None:
        group.data["until"] = t + group.data["ms"] / 1000.0

    def loop_decision(self, group: SyncGroup, t: float) -> None:
        """One decision for all axes of an AA input or while loop, so they stay together."""
        machine = self.machine
        if group.data["kind"] == "WD":
            high = machine.input_high(group.data["bit"], t)
            group.data["again"] = high == group.data["while_high"]
        else:
            flags = [machine.front.take_while_flag(i) for i in group.members]
            group.data["again"] = not any(flags)

    def loop_end(self, axis: Axis, again: bool, t: float) -> Result:
        q = axis.queue
        if not q.loops:
            return None
        frame = q.loops[-1]
        if again:
            target = frame.start + 1
            if t - frame.began < WAIT_SLACK:
                # a pass that took no time: the next one waits for the next sample, as the
                # board's command processor does at most a pass per sample of such a loop.
                # The next sample after t + WAIT_SLACK: a t a hair before a tick (within the
                # slack) would otherwise find the wait for that tick over at once, and pass
                # after pass would run at the same instant, for ever
                frame.began = self.machine.clock.after(t + WAIT_SLACK)
                return Wait("time", until=frame.began, jump=target)
            frame.began = t
            return target
        q.loops.pop()
        return None

    def wait_for_input(self, axis: Axis, op: Op, t: float) -> Result:
        """Until input ``op.args[0]`` is at the level ``op.args[1]`` (high if not given)."""
        high = op.args[1] if len(op.args) > 1 else True
        if self.machine.input_high(op.args[0], t) == high:
            return None
        return Wait("input", bit=op.args[0], high=high)

    # -- moves --------------------------------------------------------------------------------

    def start_pending(self, axes: list[Axis], t: float) -> None:
        """Start the moves set up by the move commands (PC48 §6.8 GO) on the next sample tick."""
        machine = self.machine
        tick = machine.clock.at_or_after(t)
        targets: dict[int, float] = {}
        linear: list[Axis] = []
        for axis in axes:
            p = axis.pending
            if p is None:
                continue
            axis.pending = None
            value = axis.to_motor(p.value)
            if p.kind == "abs":
                target = float(math.trunc(value))
            else:
                # MR: "relative from the current position at the time the move is executed"
                # (PC48 §6.7), the position RP returns: the steps emitted, not the carriage,
                # which a move reached while a jog runs finds between two steps (-150.278,
                # counted -150: MR100 goes to -50, not -50.278 and to rest on -51)
                target = float(axis.counter(tick) + math.trunc(value))
            targets[axis.index] = target
            if p.linear is not None:
                linear.append(axis)
        saved = {a.index: (a.vl, a.ac, a.vb) for a in linear} if linear else {}
        shapes = self._interpolate(linear, targets, tick) if linear else {}
        restore = machine.options.linear_moves_restore
        for axis in axes:
            if axis.index not in targets:
                continue
            target = targets[axis.index]
            distance = target - axis.position(tick)
            # (the kept profiles are a fast path: the straightforward board computes each)
            profile = pf.move_pieces if machine.fast_paths else pf.profile_pieces
            shape = shapes.get(axis.index, axis.ramp)
            pieces = profile(distance, axis.vl, axis.ac, axis.base_velocity, shape)
            if distance:
                axis.direction = 1 if distance > 0 else -1
            if axis.index in saved and restore:
                # "At the end of the move, all involved velocities and accelerations will be
                # restored" (PCIx; the PC48 leaves the scaled values, and says so); the move
                # keeps its scaled profile, the registers get their values back at once
                axis.vl, axis.ac, axis.vb = saved[axis.index]
            axis.begin(tick, pieces, Motion.MOVE, final=target)
            axis.home = None
            if axis.motion is Motion.IDLE:
                continue
            self.power_on(axis)
            self.arm_in(axis, target)

    def _interpolate(
        self, axes: list[Axis], targets: dict[int, float], t: float
    ) -> dict[int, pf.RampShape]:
        """Linear interpolation: "The velocity and acceleration parameters are scaled to allow
        the axes to move and finish together. All axes are scaled to the axis with the longest
        move time." The scaled values are left in the registers (unless restored).

        Every axis of the move takes the master's ramp shape as well (returned by axis index):
        on a board whose ramps are chosen per axis (the PCIx's LA, PR, SR, SS) an axis keeping
        its own shape with the scaled VL and AC would end at another time and leave the
        "straight line" (PCIx ML; MT: "to ensure all involved axes arrive at their targets
        simultaneously"). Each axis's profile is then the master's scaled by its share of the
        distance."""
        dist = {a.index: abs(targets[a.index] - a.position(t)) for a in axes}
        moving = [a for a in axes if dist[a.index] > 0]
        if not moving:
            return {}
        lead = max(
            moving,
            key=lambda a: pf.move_time(dist[a.index], a.vl, a.ac, a.base_velocity, a.ramp),
        )
        base = lead.base_velocity  # the lead's own start (PCIx: VL - 1 under a VB above VL)
        for a in moving:
            k = dist[a.index] / dist[lead.index]
            a.vl = lead.vl * k
            a.ac = lead.ac * k
            a.vb = base * k
        return {a.index: lead.ramp for a in moving}

    def arm_in(self, axis: Axis, target: float) -> None:
        """Schedule the armed interrupt of the move just started (PC48 §6.12 IN: "The test is
        only performed during deceleration. If the IN parameter is greater than the ramp down
        distance, the interrupt will be generated when the control starts decelerating.")"""
        if axis.in_arm is None:
            return
        traj = axis.traj
        distance = axis.in_arm[0]
        decel_start = traj.end_time - traj.pieces[-1].duration if traj.pieces else traj.t0
        when: float | None = traj.end_time
        if distance > 0:
            above = target >= traj.x0
            level = target - distance if above else target + distance
            when = traj.first_time(level, above, traj.t0)
        fire = max(when if when is not None else traj.end_time, decel_start)
        axis.in_fire = self.machine.clock.at_or_after(min(fire, traj.end_time))
        axis.invalidate()

    def power_on(self, axis: Axis) -> None:
        """Power automatic: a motion the axis has just begun turns the auxiliary output to its
        moving state, if the dialect's PA drives it for that motion (the PC48's for the moves
        of GO and GD; the PCIx's "at the beginning of every motion"). The end of the motion
        turns it back (:meth:`Axis.power_down`)."""
        if axis.pa is None or not axis.moving:
            return
        if axis.motion not in self.machine.options.power_automatic_motions:
            return
        axis.aux = axis.pa
        axis.aux_timer = None

    def set_aux(self, axis: Axis, high: bool, t: float) -> None:
        axis.aux = high
        axis.pa = None  # "can be turned off by using the AN or AF command"
        axis.aux_timer = None
        axis.invalidate()

    # -- position maintenance -----------------------------------------------------------------

    def check_hold(self, axis: Axis, t: float) -> None:
        """Position maintenance (PC48 §6.15): correct toward the held position with velocity
        gain × error, at most the hold velocity, until within the deadband."""
        if not axis.hold or axis.motion is not Motion.IDLE:
            return
        error = axis.hold_goal - axis.encoder(t)
        if abs(error) <= axis.hd:
            axis.in_position = True
            return
        if axis.hv <= 0.0:
            return  # "some value must be set for position correction to occur at all"
        tick = self.machine.clock.at_or_after(t)
        motor_error = error / axis.ratio
        pieces = pf.hold_correction(motor_error, axis.hg, axis.hv, axis.hd / axis.ratio)
        if not pieces:
            axis.in_position = True
            return
        x = axis.position(tick)
        remaining = math.copysign(min(abs(motor_error), axis.hd / axis.ratio), motor_error)
        axis.begin(tick, pieces, Motion.HOLD, final=float(round(x + motor_error - remaining)))
        axis.in_position = False

    def end_correction(self, axis: Axis, t: float) -> None:
        """A hold's correction stops where it is once the hold is off (HF; the PC48's LP): the
        correction's velocity is HG × the error, which only position maintenance computes ("This
        gain parameter is multiplied by the position error in determining the velocity during
        correction"). It began with no ramp and ends the same way."""
        if axis.motion is Motion.HOLD and not axis.hold:
            axis.halt(t)

    def hold_off(self, axis: Axis) -> None:
        """Position hold and slip detection off, as HF and a limit turn them off on every board
        (and as the PC48's "LP, HM, HR, SA, ST or KL" do)."""
        axis.hold = False
        axis.slip_detect = False
        axis.in_position = True
        axis.invalidate()

    def stopped_at_once(self, axis: Axis, t: float, stopped: Motion) -> None:
        """A stop that left the axis at rest at once (a kill, a slip kill, a stop with no speed
        to ramp down from) ends the motion it stopped, ``stopped``, as a motion's end does: in
        position, and a hold the stop left on (the PCIx's: neither of its lists names a stop)
        holds where a commanded motion was stopped, not where the axis was before it. An axis
        at rest, or the hold's own correction, keeps the goal it had: the hold goes on toward
        it (a kill of a standing axis does not move what is held)."""
        axis.in_position = True
        if axis.hold:
            if stopped is not Motion.IDLE and stopped is not Motion.HOLD:
                axis.hold_goal = axis.tracked_encoder(axis.position(t))
            self.check_hold(axis, t)

    def cancel(self, axis: Axis, command: str) -> None:
        """What executing ``command`` ends, as the dialect lists it (:class:`Options`
        ``hold_cancelled_by``, ``slip_cancelled_by``): on the PC48 and VS4 both ("Hold and slip
        detection are disabled if an LP, HM, HR, SA, ST or KL command is entered"); on the
        PCIx one list for each (its HN page and its IS page)."""
        options = self.machine.options
        hold = command in options.hold_cancelled_by
        slip = command in options.slip_cancelled_by
        if hold and slip:
            self.hold_off(axis)
            return
        if hold and not axis.is_servo:
            # PCIx HN: "For stepper axes with encoders, this mode will be canceled" (a servo's
            # HN is its closed loop, which these commands leave alone)
            axis.hold = False
            axis.in_position = True
            axis.invalidate()
        if slip:
            axis.slip_detect = False
            axis.invalidate()


def motion_wait(axis: Axis) -> Wait | None:
    """Wait for the motion just started, if it did start."""
    return Wait("motion") if axis.moving else None
