"""Executing the axis queues (PC48 §6.2, §6.7–§6.12, §6.15–§6.21, §8.2).

Each axis runs its own program: it executes queued ops one after another at the time they are
reached; an op that takes time (a move, a WT, a wait for other axes) leaves a :class:`Wait` on
the axis and the queue stays on that op, holding its slots, until the wait is over. Moves start
on the next sample tick. Ops shared by several axes (AA mode) meet in a
:class:`~omsd.board.queue.SyncGroup`.

This module also holds the board's reactions to the world: running into a limit (§6.5, §7.3.4:
"When the board receives a limit signal from the platform, it flushes its command queue"),
finding home (§6.11), detecting slip (§6.16) and the position-hold correction (§6.15).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from omsd.board import profiles as pf
from omsd.board.axis import Axis, HomeSearch, Motion, Pending, Wait
from omsd.board.events import LimitEvent, ServoTripEvent, SlipEvent
from omsd.board.queue import LoopFrame, Op, SyncGroup
from omsd.board.registers import DON_S, ENC_S, OVRT

if TYPE_CHECKING:
    from omsd.board.board import Board

Result = Wait | int | None  # None: done, int: jump to that program index

MAX_STEPS = 10_000  # ops one axis may run at one instant (a loop of zero-time ops)


class Executor:
    def __init__(self, board: Board) -> None:
        self.board = board
        self._ops: dict[str, Callable[[Axis, Op, float], Result]] = {
            name[4:]: getattr(self, name) for name in dir(self) if name.startswith("_op_")
        }
        if board.model.dialect == "pcix":
            from omsd.board.pcix_motion import MOTION_OPS

            for code, fn in MOTION_OPS.items():
                self._ops[code] = functools.partial(fn, self)

    def _op_SET(self, axis: Axis, op: Op, t: float) -> Result:
        """A queued parameter change: ``Op("SET", (mnemonic, apply), slots)`` runs
        ``apply(axis, t)`` when the axis reaches it (PCIx KP, DZ, BC, DBI, LH ...)."""
        apply = op.args[1]
        apply(axis, t)
        return None

    def on_servo(self, axis: Axis, t: float) -> None:
        """A look at a servo axis's loop: "if the error is greater than 32768 then the
        controller will disable the PID so that you don't have a runaway motor" (PCIx
        §2.7.2). The loop opens (HF); the commanded motion stops at once and the axis's queue is
        flushed, as a limit does, so that nothing drives an axis nobody is holding."""
        loop = axis.servo
        assert loop is not None
        axis.servo_sync(t)
        if loop.tripped and not axis.servo_trip_reported:
            # moving or holding: either way the axis is no longer under control
            axis.servo_trip_reported = True
            if axis.motion is not Motion.IDLE:
                axis.halt(t)
            self.flush(axis, t)
            self.board.emit(ServoTripEvent(t, axis.letter, loop.following_error))
        axis.servo_last = loop.position
        axis.invalidate()

    # -- the queue ----------------------------------------------------------------------------

    def step(self, axis: Axis, t: float) -> bool:
        """Run the axis's queue as far as it goes at ``t``; True if anything happened. What an
        op causes belongs to the session that sent it (``Op.source``)."""
        board = self.board
        saved = board.talker
        try:
            return self._step(axis, t)
        finally:
            board.talker = saved

    def _step(self, axis: Axis, t: float) -> bool:
        q = axis.queue
        board = self.board
        progressed = False
        for _ in range(MAX_STEPS):
            if axis.wait is not None:
                w = axis.wait
                held = q.current
                if held is not None:
                    board.talker = axis.source = held.source
                if not self._satisfied(axis, w, t):
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
            board.talker = axis.source = op.source
            result = self._ops[op.code](axis, op, t)
            progressed = True
            if isinstance(result, Wait):
                axis.wait = result
                axis.invalidate()
            elif isinstance(result, int):
                q.jump(result)
            else:
                q.advance()
        return progressed

    def _satisfied(self, axis: Axis, w: Wait, t: float) -> bool:
        if w.kind == "motion":
            return axis.motion is Motion.IDLE
        if w.kind == "time":
            return w.until is not None and t >= w.until - 1e-12
        if w.kind == "group":
            assert w.group is not None
            return w.group.released(w.round)
        if w.kind == "input":
            return self.board.input_high(w.bit, t) == w.high
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
            return self._op_SW(axis, op, t, grouped=False)
        if op.code in ("WD", "WG"):
            assert op.group is not None
            return self._loop_end(axis, op.group.data["again"], t)
        return None

    def drop_from_groups(self, axis: Axis, ops: list[Op], t: float) -> None:
        """A flushed axis no longer takes part in the groups of its dropped ops. A group that
        completes for it (an AA ID the others had reached) speaks for the session that sent
        it, not for whoever caused the flush."""
        board = self.board
        saved = board.talker
        groups = {id(op.group): op for op in ops if op.group is not None}
        for op in groups.values():
            g = op.group
            assert g is not None
            g.members.discard(axis.index)
            board.talker = op.source
            self.check_group(g, t)
        board.talker = saved

    def flush(self, axis: Axis, t: float) -> None:
        dropped = axis.queue.flush()
        axis.wait = None
        axis.pending = None
        axis.in_arm = None
        axis.in_fire = None
        self.board.interpreter.forget_loops(axis.index)
        self.drop_from_groups(axis, dropped, t)
        if axis.gear is not None:  # PCIx: FL, KL, KS, SA, SD, SI "also cancel electronic gearing"
            from omsd.board.pcix_motion import disengage

            disengage(axis, t)
        axis.invalidate()

    # -- parameter ops ------------------------------------------------------------------------

    def _op_NOP(self, axis: Axis, op: Op, t: float) -> Result:
        return None

    _op_CW = _op_NOP

    def _op_VL(self, axis: Axis, op: Op, t: float) -> Result:
        axis.vl = axis.to_motor(op.args[0])
        return None

    def _op_AC(self, axis: Axis, op: Op, t: float) -> Result:
        axis.ac = axis.to_motor(op.args[0])
        # PCIx DC: "The deceleration rate ... will take on whatever value is entered via the AC
        # command"
        axis.dc = axis.ac
        return None

    def _op_VB(self, axis: Axis, op: Op, t: float) -> Result:
        axis.vb = axis.to_motor(op.args[0])
        return None

    def _op_LP(self, axis: Axis, op: Op, t: float) -> Result:
        value = float(op.args[0])
        if axis.has_encoder:
            # "the parameter will be loaded into the encoder position register and the parameter
            # times the encoder ratio will be loaded into the position counter" (ER3,2 LP30000
            # gives 20,000: the motor/encoder ratio)
            axis.load_counter(t, axis.to_motor(value))
            axis.anchor_encoder(t, value)
            self.hold_off(axis)
        else:
            axis.load_counter(t, value)
        axis.hold_goal = float(axis.encoder(t))
        return None

    def _op_HH(self, axis: Axis, op: Op, t: float) -> Result:
        axis.home_high = True
        return None

    def _op_HL(self, axis: Axis, op: Op, t: float) -> Result:
        axis.home_high = False
        return None

    def _op_LN(self, axis: Axis, op: Op, t: float) -> Result:
        axis.limits_on = True
        axis.sensor_check = t
        axis.invalidate()
        return None

    def _op_LF(self, axis: Axis, op: Op, t: float) -> Result:
        axis.limits_on = False
        axis.invalidate()
        return None

    def _op_SL(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48: one mode for the board; PCIx ``SLb,b,b,b``: per axis
        if self.board.model.dialect == "pcix":
            axis.soft_limit = True
        else:
            self.board.soft_limits = True
        return None

    def _op_SF(self, axis: Axis, op: Op, t: float) -> Result:
        if self.board.model.dialect == "pcix":
            axis.soft_limit = False
        else:
            self.board.soft_limits = False
        return None

    def _op_DIR(self, axis: Axis, op: Op, t: float) -> Result:
        axis.direction = op.args[0]
        return None

    def _op_CN(self, axis: Axis, op: Op, t: float) -> Result:
        self.board.ramp = pf.RampShape(pf.RampKind.COSINE)
        return None

    def _op_RM(self, axis: Axis, op: Op, t: float) -> Result:
        # "An RM2000 command with a position counter of -4050 will return a position of 1950"
        n = op.args[0]
        x = axis.position(t)
        axis.load_counter(t, x - n * math.floor(axis.counter(t) / n))
        if self.board.model.dialect == "pcix" and axis.has_encoder:
            # PCIx RM: "The RM command has the same effect on the encoder position register"
            e = axis.encoder(t)
            axis.anchor_encoder(t, float(e - n * math.floor(e / n)))
        axis.anchor_tracking(t)
        return None

    def _op_ER(self, axis: Axis, op: Op, t: float) -> Result:
        axis.anchor_encoder(t)
        axis.ratio = op.args[0] / op.args[1]
        axis.anchor_encoder(t)
        return None

    def _op_HV(self, axis: Axis, op: Op, t: float) -> Result:
        axis.hv = axis.to_motor(op.args[0])
        return None

    def _op_HG(self, axis: Axis, op: Op, t: float) -> Result:
        axis.hg = float(op.args[0])
        return None

    def _op_HD(self, axis: Axis, op: Op, t: float) -> Result:
        axis.hd = float(op.args[0])
        return None

    def _op_ES(self, axis: Axis, op: Op, t: float) -> Result:
        axis.es = float(op.args[0])
        axis.invalidate()
        return None

    def _op_HF(self, axis: Axis, op: Op, t: float) -> Result:
        if axis.servo is not None:
            # "HF will open the loop and turn off the PID"
            axis.servo_sync(t)
            axis.servo.closed = False
            axis.invalidate()
            if axis.motion is Motion.JOG:  # HF stops a servo JG (PCIx JG)
                axis.decelerate(t)
            return None
        self.hold_off(axis)
        axis.tracking = False
        return None

    def _op_HN(self, axis: Axis, op: Op, t: float) -> Result:
        if axis.servo is not None:
            # "HN ... will close the loop and enable the PID". Closing is bumpless: an axis at
            # rest is commanded to hold where its motor is (an open loop may have drifted)
            loop = axis.servo
            axis.servo_sync(t)
            if not loop.closed and axis.motion is Motion.IDLE:
                axis.load_counter(t, float(loop.encoder_counts))
                loop.set_position(loop.position)
            loop.closed = True
            axis.servo_trip_reported = False
            axis.servo_last = None
            axis.invalidate()
            return None
        if not axis.hold:
            axis.hold = True
            x = axis.traj.final if axis.traj.is_finite else axis.position(t)
            axis.hold_goal = axis.track_enc + axis.ratio * (x - axis.track_counter)
            if not axis.slip_detect:
                axis.anchor_tracking(t)
        self.check_hold(axis, t)
        return None

    def _op_IS(self, axis: Axis, op: Op, t: float) -> Result:
        if not axis.slip_detect and not axis.hold:
            axis.anchor_tracking(t)
        axis.slip_detect = True
        axis.sensor_check = t
        axis.invalidate()
        return None

    def _op_ET(self, axis: Axis, op: Op, t: float) -> Result:
        axis.tracking = True
        axis.anchor_tracking(t)
        return None

    def _op_PA(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.6: "The auxiliary will be turned on, i.e. pulled high, upon the execution of the
        # GO or GD and off at the end of that move, if the parameter is zero or not specified"
        param = op.args[0]
        axis.pa = param is None or param == 0
        if axis.motion is not Motion.MOVE:
            axis.aux = not axis.pa  # "setting the master's X axis auxiliary line low until..."
        axis.aux_timer = None
        return None

    def _op_SE(self, axis: Axis, op: Op, t: float) -> Result:
        axis.se_ms = op.args[0]
        return None

    def _op_AN(self, axis: Axis, op: Op, t: float) -> Result:
        self.set_aux(axis, True, t)
        return None

    def _op_AF(self, axis: Axis, op: Op, t: float) -> Result:
        self.set_aux(axis, False, t)
        return None

    def set_aux(self, axis: Axis, high: bool, t: float) -> None:
        axis.aux = high
        axis.pa = None  # "can be turned off by using the AN or AF command"
        axis.aux_timer = None
        axis.invalidate()

    def _op_BL(self, axis: Axis, op: Op, t: float) -> Result:
        self.board.set_output(op.args[0], low=True, t=t)
        return None

    def _op_BH(self, axis: Axis, op: Op, t: float) -> Result:
        self.board.set_output(op.args[0], low=False, t=t)
        return None

    def _op_RB(self, axis: Axis, op: Op, t: float) -> Result:
        self.board.reply_value(f"{self.board.directions:06X}", t)
        return None

    # -- completion flags ---------------------------------------------------------------------

    def _op_ID(self, axis: Axis, op: Op, t: float) -> Result:
        if op.group is None:
            self.board.set_done([axis], t, interrupt=True)
            return None
        self.board.set_done([axis], t, interrupt=False)
        return self.arrive(axis, op, t)

    _op_II = _op_ID

    def _op_IP(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.12: "like the ID command, except the interrupt is deferred until the stage is
        # within the specified deadband ... If the position hold HN is not enabled for an axis,
        # the command will behave like an ID command for that axis."
        group = op.group

        def done(when: float) -> None:
            if group is None:
                self.board.set_done([axis], when, interrupt=True)
                return
            self.board.set_done([axis], when, interrupt=False)
            group.arrive(axis.index)
            self.check_group(group, when)

        if axis.hold and not (axis.in_position and axis.motion is Motion.IDLE):
            return Wait("inpos", then=done)
        done(t)
        return None

    def _op_IN(self, axis: Axis, op: Op, t: float) -> Result:
        assert op.group is not None
        axis.in_arm = (axis.to_motor(op.args[0]), op.group)
        return None

    def fire_in(self, axis: Axis, t: float) -> None:
        arm = axis.in_arm
        axis.in_fire = None
        axis.in_arm = None
        axis.invalidate()
        if arm is None:
            return
        group = arm[1]
        self.board.set_done([axis], t, interrupt=False)
        group.arrive(axis.index)
        self.check_group(group, t)

    def _arm_in(self, axis: Axis, target: float) -> None:
        """Schedule the IN interrupt of the move just started (PC48 §6.12 IN: "The test is only
        performed during deceleration. If the IN parameter is greater than the ramp down
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
        axis.in_fire = self.board.clock.at_or_after(min(fire, traj.end_time))
        axis.invalidate()

    # -- moves --------------------------------------------------------------------------------

    def _op_MA(self, axis: Axis, op: Op, t: float) -> Result:
        axis.pending = Pending("abs", op.args[0], op.group)
        return None

    def _op_MR(self, axis: Axis, op: Op, t: float) -> Result:
        axis.pending = Pending("rel", op.args[0], op.group)
        return None

    _op_MT = _op_MA
    _op_ML = _op_MR

    def _op_GO(self, axis: Axis, op: Op, t: float) -> Result:
        if op.group is not None:
            return self.arrive(axis, op, t)
        if op.code == "GD":
            self.board.clear_done([axis])
        self.start_pending([axis], t)
        return _motion_wait(axis)

    _op_GD = _op_GO

    def go_action(self, group: SyncGroup, t: float) -> None:
        """The moment every axis of an AA/AM GO has arrived: start them together."""
        axes = [self.board.axes[i] for i in sorted(group.members)]
        if group.data.get("gd"):
            self.board.clear_done(
                self.board.axes if group.data.get("all") else axes,
            )
        self.start_pending(axes, t)

    def start_pending(self, axes: list[Axis], t: float) -> None:
        """Start the moves set up by MA/MR/ML/MT (PC48 §6.8 GO) on the next sample tick."""
        tick = self.board.clock.at_or_after(t)
        targets: dict[int, float] = {}
        linear: list[Axis] = []
        for axis in axes:
            p = axis.pending
            if p is None:
                continue
            axis.pending = None
            here = axis.position(tick)
            value = axis.to_motor(p.value)
            target = float(math.trunc(value)) if p.kind == "abs" else here + math.trunc(value)
            targets[axis.index] = target
            if p.linear is not None:
                linear.append(axis)
        saved = {a.index: (a.vl, a.ac, a.vb) for a in linear}
        if linear:
            self._interpolate(linear, targets, tick)
        for axis in axes:
            if axis.index not in targets:
                continue
            target = targets[axis.index]
            distance = target - axis.position(tick)
            pieces = pf.move_pieces(distance, axis.vl, axis.ac, axis.vb, axis.ramp)
            if distance:
                axis.direction = 1 if distance > 0 else -1
            if axis.index in saved and self.board.model.dialect == "pcix":
                # PCIx ML/MT: "At the end of the move, all involved velocities and accelerations
                # will be restored" (the PC48 leaves the scaled values, and says so); the move
                # keeps its scaled profile, the registers get their values back at once
                axis.vl, axis.ac, axis.vb = saved[axis.index]
            axis.begin(tick, pieces, Motion.MOVE, final=target)
            axis.home = None
            if axis.motion is Motion.IDLE:
                continue
            if axis.pa is not None:
                axis.aux = axis.pa
                axis.aux_timer = None
            self._arm_in(axis, target)

    def _interpolate(self, axes: list[Axis], targets: dict[int, float], t: float) -> None:
        """ML/MT: "The velocity and acceleration parameters are scaled to allow the axes to move
        and finish together. All axes are scaled to the axis with the longest move time." The
        scaled values are left in the VL and AC registers, as the manual warns."""
        dist = {a.index: abs(targets[a.index] - a.position(t)) for a in axes}
        moving = [a for a in axes if dist[a.index] > 0]
        if not moving:
            return
        lead = max(moving, key=lambda a: pf.move_time(dist[a.index], a.vl, a.ac, a.vb, a.ramp))
        for a in moving:
            k = dist[a.index] / dist[lead.index]
            a.vl = lead.vl * k
            a.ac = lead.ac * k
            a.vb = lead.vb * k

    def _op_JG(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.8: "will accelerate to the programmed velocity and run until altered";
        # "Output events waiting for completion of JG will begin when JG is up to its requested
        # velocity". The ramp is linear in every ramp mode (its queue table: "Linear ramp").
        v = axis.to_motor(op.args[0])
        if self.board.model.dialect == "pcix":
            axis.slip_detect = False  # PCIx IS: disabled by "... JG ..."
        tick = self.board.clock.at_or_after(t)
        v0 = axis.velocity(tick)
        if v:
            axis.vl = abs(v)  # "This command modifies the move velocity parameter (VL)"; JG0 stops
        ramp = pf.velocity_change(v0, v, axis.ac)
        if v == 0.0:
            axis.begin(tick, ramp, Motion.STOP)
            return _motion_wait(axis)
        axis.direction = 1 if v > 0 else -1
        axis.begin(tick, [*ramp, pf.cruise(v)], Motion.JOG)
        axis.home = None
        at_speed = tick + sum(p.duration for p in ramp)
        return Wait("time", until=self.board.clock.at_or_after(at_speed))

    _op_JF = _op_JG

    def _op_VS(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.8: "generate a pulse train without acceleration or deceleration at the rates
        # specified. The parameters are time in 1/1024 second sample intervals, X velocity, and
        # Y velocity." If the stream runs dry the last rate continues ("slave mode").
        samples, vx, vy = op.args
        tick = self.board.clock.at_or_after(t)
        for a, v in ((axis, vx), (self.board.axis_by_letter("Y"), vy)):
            if a is None:
                continue
            if v:
                a.direction = 1 if v > 0 else -1
                a.begin(tick, [pf.cruise(a.to_motor(v))], Motion.STREAM)
            elif a.motion is Motion.STREAM or a is axis:
                a.halt(tick)
        until = tick + samples / self.board.model.velocity_stream_rate
        return Wait("time", until=until)

    def _op_MO(self, axis: Axis, op: Op, t: float) -> Result:
        # "will output one step pulse in the current direction ... in one sample interval"
        tick = self.board.clock.at_or_after(t)
        rate = self.board.model.sample_rate
        x = axis.position(tick)
        step = pf.cruise(axis.direction * rate, 1.0 / rate)
        axis.begin(tick, [step], Motion.MOVE, final=x + axis.direction)
        return Wait("motion")

    def _op_MV(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.20: run to the absolute position at the new velocity; control passes on when
        # it is reached; "If a new MV command is sent after the controller has already passed
        # the destination ... the controller will continue to move at the old velocity."
        dest = axis.to_motor(op.args[0])
        v = abs(axis.to_motor(op.args[1])) * axis.direction
        tick = self.board.clock.at_or_after(t)
        x = axis.position(tick)
        if (dest - x) * axis.direction <= 0:
            return None
        v0 = axis.velocity(tick)
        axis.begin(tick, [*pf.velocity_change(v0, v, axis.ac), pf.cruise(v)], Motion.STAIRCASE)
        when = axis.traj.first_time(dest, axis.direction > 0, tick)
        if when is None:
            return Wait("motion")
        return Wait("time", until=self.board.clock.at_or_after(when))

    def _op_SP(self, axis: Axis, op: Op, t: float) -> Result:
        # "stop at the specified position ... If there is insufficient distance to stop at the
        # previously specified deceleration ... the controller will stop as soon as possible"
        dest = float(math.trunc(axis.to_motor(op.args[0])))
        tick = self.board.clock.at_or_after(t)
        v0 = axis.velocity(tick)
        if v0 == 0.0:
            return None
        x = axis.position(tick)
        pieces = pf.stop_at(dest - x, v0, axis.ac)
        reach = sum(p.x(p.duration) for p in pieces)
        final = dest if abs(x + reach - dest) < 1e-6 else None
        axis.begin(tick, pieces, Motion.STOP, final=final)
        return _motion_wait(axis)

    _op_FP = _op_SP

    def _op_HM(self, axis: Axis, op: Op, t: float) -> Result:
        # PC48 §6.11: "step in the positive direction at the predefined velocity, until the home
        # input line goes true. The position counter will be initialized to the position
        # supplied ... The axis will not stop at home, but ... decelerates to a stop."
        position, kill, direction = op.args
        tick = self.board.clock.at_or_after(t)
        self.hold_off(axis)
        v0 = axis.velocity(tick)
        v = direction * axis.vl
        axis.direction = direction
        axis.begin(tick, [*pf.velocity_change(v0, v, axis.ac), pf.cruise(v)], Motion.HOME)
        points: tuple[float, ...] = ()
        if axis.home_encoder:
            points = self._index_points(axis, tick, direction)
        axis.home = HomeSearch(
            position=position,
            kill=kill,
            direction=direction,
            prev=axis.home_condition(tick),
            index_points=points,
        )
        axis.home_last_phys = axis.phys(tick)
        return Wait("motion")

    def _index_points(self, axis: Axis, t: float, direction: int) -> tuple[float, ...]:
        """HE mode: physical positions in the home window where the encoder index is."""
        w = axis.world
        cpr = w.encoder_counts_per_rev
        if cpr <= 0 or axis.ratio <= 0:
            return (math.inf * direction,)

        def enc_at(p: float) -> float:
            return axis.enc_base + axis.ratio * (p - axis.enc_phys)

        lo, hi = sorted((enc_at(w.home_low), enc_at(w.home_high)))
        first = math.ceil((lo - w.encoder_index) / cpr)
        points: list[float] = []
        k = first
        while k * cpr + w.encoder_index < hi and len(points) < 64:
            count = k * cpr + w.encoder_index
            points.append(axis.enc_phys + (count - axis.enc_base) / axis.ratio)
            k += 1
        return tuple(points) or (math.inf * direction,)

    def _op_STOP(self, axis: Axis, op: Op, t: float) -> Result:
        kill = bool(op.args and op.args[0])
        self.hold_off(axis)
        axis.home = None
        if kill:
            axis.halt(t)
            return None
        tick = self.board.clock.at_or_after(t)
        if axis.motion is Motion.IDLE:
            return None
        axis.decelerate(tick)
        return _motion_wait(axis)

    # -- loops and waits ----------------------------------------------------------------------

    def _op_LS(self, axis: Axis, op: Op, t: float) -> Result:
        axis.queue.loops.append(LoopFrame("LS", axis.queue.pc, op.args[0], t))
        return None

    def _op_WS(self, axis: Axis, op: Op, t: float) -> Result:
        axis.queue.loops.append(LoopFrame("WS", axis.queue.pc, 0, t))
        return None

    def _op_WH(self, axis: Axis, op: Op, t: float) -> Result:
        axis.queue.loops.append(LoopFrame("WH", axis.queue.pc, 0, t))
        return None

    def _op_LE(self, axis: Axis, op: Op, t: float) -> Result:
        frame = axis.queue.loops[-1] if axis.queue.loops else None
        if frame is None:
            return None
        frame.remaining -= 1
        return self._loop_end(axis, frame.remaining > 0, t)

    def _op_WD(self, axis: Axis, op: Op, t: float) -> Result:
        # "execute the commands between the WS and WD commands as a loop while the specified
        # general purpose input line is true, i.e. low ... The test is at the bottom"
        if op.group is not None:
            return self.arrive(axis, op, t)
        return self._loop_end(axis, not self.board.input_high(op.args[0], t), t)

    def _op_WG(self, axis: Axis, op: Op, t: float) -> Result:
        if op.group is not None:
            return self.arrive(axis, op, t)
        again = not self.board.interpreter.take_while_flag(axis.index)
        return self._loop_end(axis, again, t)

    def loop_decision(self, group: SyncGroup, t: float) -> None:
        """One decision for all axes of an AA WS/WD or WH/WG loop, so they stay together."""
        kind = group.data["kind"]
        if kind == "WD":
            group.data["again"] = not self.board.input_high(group.data["bit"], t)
        else:
            flags = [self.board.interpreter.take_while_flag(i) for i in group.members]
            group.data["again"] = not any(flags)

    def _loop_end(self, axis: Axis, again: bool, t: float) -> Result:
        q = axis.queue
        if not q.loops:
            return None
        frame = q.loops[-1]
        if again:
            target = frame.start + 1
            if t - frame.began < 1e-12:
                # a pass that took no time: the next one waits for the next sample, as the
                # board's command processor does at most a pass per sample of such a loop
                frame.began = self.board.clock.after(t)
                return Wait("time", until=frame.began, jump=target)
            frame.began = t
            return target
        q.loops.pop()
        return None

    def _op_WT(self, axis: Axis, op: Op, t: float) -> Result:
        if op.group is not None:
            return self.arrive(axis, op, t)
        return Wait("time", until=t + op.args[0] / 1000.0)

    def wt_action(self, group: SyncGroup, t: float) -> None:
        group.data["until"] = t + group.data["ms"] / 1000.0

    def _op_WA(self, axis: Axis, op: Op, t: float) -> Result:
        return self.arrive(axis, op, t)

    def _op_SW(self, axis: Axis, op: Op, t: float, grouped: bool = True) -> Result:
        # SW: until the input is high; PCIx BW (args (bit, False)): "waits for the input line
        # to reach a TTL low rather than a TTL high"
        if grouped and op.group is not None:
            return self.arrive(axis, op, t)
        high = op.args[1] if len(op.args) > 1 else True
        if self.board.input_high(op.args[0], t) == high:
            return None
        return Wait("input", bit=op.args[0], high=high)

    def _op_CX(self, axis: Axis, op: Op, t: float) -> Result:
        return self.arrive(axis, op, t)

    # -- reactions to the world ---------------------------------------------------------------

    def on_end(self, axis: Axis, t: float) -> None:
        """The trajectory has run out: the axis is at rest."""
        motion = axis.motion
        axis.settle(t)
        if motion is Motion.HOLD:
            axis.in_position = True
            if axis.slip_detect:
                axis.anchor_tracking(t)
        else:
            if axis.pa is not None and axis.aux == axis.pa:
                if axis.se_ms:
                    axis.aux_timer = t + axis.se_ms / 1000.0
                else:
                    axis.aux = not axis.pa
            axis.hold_goal = axis.track_enc + axis.ratio * (axis.position(t) - axis.track_counter)
            axis.in_position = True
            self.check_hold(axis, t)
        axis.invalidate()

    def check_hold(self, axis: Axis, t: float) -> None:
        """Position maintenance (PC48 §6.15 HN): correct toward the held position with velocity
        HG × error, at most HV, until within the HD deadband."""
        if not axis.hold or axis.motion is not Motion.IDLE:
            return
        error = axis.hold_goal - axis.encoder(t)
        if abs(error) <= axis.hd:
            axis.in_position = True
            return
        if axis.hv <= 0.0:
            return  # "some value must be set for position correction to occur at all"
        tick = self.board.clock.at_or_after(t)
        motor_error = error / axis.ratio
        pieces = pf.hold_correction(motor_error, axis.hg, axis.hv, axis.hd / axis.ratio)
        if not pieces:
            axis.in_position = True
            return
        x = axis.position(tick)
        remaining = math.copysign(min(abs(motor_error), axis.hd / axis.ratio), motor_error)
        axis.begin(tick, pieces, Motion.HOLD, final=float(round(x + motor_error - remaining)))
        axis.in_position = False

    def hold_off(self, axis: Axis) -> None:
        """ "Hold and slip detection are disabled if an LP, HM, HR, SA, ST or KL command is
        entered or if a limit is encountered.\""""
        axis.hold = False
        axis.slip_detect = False
        axis.in_position = True
        axis.invalidate()

    def on_sensor(self, axis: Axis, t: float) -> None:
        axis.sensor_check = None
        axis.invalidate()
        board = self.board
        if board.model.dialect == "pcix":  # backlash taken up, GS's home switch
            from omsd.board.pcix_motion import sensed

            sensed(axis, t)
        if axis.motion not in (Motion.IDLE, Motion.STOP) and axis.limits_on:
            direction = axis.direction_at(t)
            if direction and axis.limit_active(direction, t):
                self._limit(axis, direction, t)
        if axis.home is not None and axis.motion is Motion.HOME:
            self._look_for_home(axis, t)
        if axis.slip_detect and abs(axis.slip_error(t)) > axis.es:
            axis.slip_detect = False
            axis.slipped = True
            board.registers.status |= ENC_S | DON_S
            board.emit(SlipEvent(t, axis.letter))
            if axis.slip_kill:
                # PCIx TN: "the axis will be killed as though a KL command had been issued"
                axis.halt(t)
                self.flush(axis, t)
        if axis.hold and axis.motion is Motion.IDLE:
            self.check_hold(axis, t)

    def _look_for_home(self, axis: Axis, t: float) -> None:
        home = axis.home
        assert home is not None
        if home.index_points:
            before, now = axis.home_last_phys, axis.phys(t)
            axis.home_last_phys = now
            lo, hi = sorted((before, now))
            found = any(lo <= p <= hi for p in home.index_points) and axis.home_line_low(t)
        else:
            cond = axis.home_sensed(t)
            found = cond and not home.prev
            home.prev = cond
        if not found:
            return
        axis.home = None
        if home.kill:
            axis.halt(t)  # KM/KR: "The position counter is not cleared or reset."
            return
        axis.load_counter(t, home.position)
        axis.anchor_tracking(t)
        axis.decelerate(t)

    def _limit(self, axis: Axis, direction: int, t: float) -> None:
        board = self.board
        axis.limit_latched = direction
        self.hold_off(axis)
        if axis.servo is not None and axis.servo.closed:
            # PCIx HN: the loop "is disabled when ... a limit is encountered"
            axis.servo_sync(t)
            axis.servo.closed = False
        if board.model.dialect == "pcix":
            # PCIx SL: "effective for point to point and JG moves only", per axis
            ramp = axis.soft_limit and axis.motion in (Motion.MOVE, Motion.JOG)
        else:
            # SL: "ramp down instead of terminating immediately. The output queue is not
            # flushed except for the current move. This mode is effective for point to point
            # moves only."
            ramp = axis.soft_limit and axis.motion is Motion.MOVE
        if ramp:
            axis.decelerate(t)
        else:
            axis.halt(t)
            self.flush(axis, t)
        board.registers.status |= OVRT | DON_S
        board.emit(LimitEvent(t, axis.letter, direction))

    def on_aux_timer(self, axis: Axis, t: float) -> None:
        axis.aux_timer = None
        if axis.pa is not None and axis.motion is Motion.IDLE:
            axis.aux = not axis.pa
        axis.invalidate()

    def on_outputs(self, axis: Axis, t: float) -> None:
        while axis.outputs and axis.outputs[0][0] <= t + 1e-12:
            _, (what, target, low) = axis.outputs.pop(0)
            if what == "aux":
                self.set_aux(self.board.axes[target], not low, t)
            else:
                self.board.set_output(target, low=low, t=t)
        axis.invalidate()


def _motion_wait(axis: Axis) -> Wait | None:
    """Wait for the motion just started, if it did start."""
    return Wait("motion") if axis.moving else None
