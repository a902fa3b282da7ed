"""Queued motion: what an axis does when its queue reaches a move, a jog, a stream, a stop or a
home search (PC48 §6.7–§6.9, §6.11, §6.20). Each op is ``fn(executor, axis, op, t)``."""

from __future__ import annotations

import math

from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.executor import Executor, OpFunction, Result, motion_wait
from omsd.engine.queue import Op
from omsd.engine.states import HomeSearch, Motion, Pending, Wait


def _move_abs(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.pending = Pending("abs", op.args[0], op.group)
    return None


def _move_rel(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    axis.pending = Pending("rel", op.args[0], op.group)
    return None


def _go(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    if op.group is not None:
        return ex.arrive(axis, op, t)
    if op.code == "GD":
        ex.machine.clear_done([axis])
    ex.start_pending([axis], t)
    return motion_wait(axis)


def _jog(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.8: "will accelerate to the programmed velocity and run until altered";
    # "Output events waiting for completion of JG will begin when JG is up to its requested
    # velocity". The ramp is linear in every ramp mode (its queue table: "Linear ramp").
    machine = ex.machine
    v = axis.to_motor(op.args[0])
    ex.cancel(axis, "JG")  # JF too: it "will jog one or more axes ... like the JG command"
    tick = machine.clock.at_or_after(t)
    v0 = axis.velocity(tick)
    if v:
        axis.vl = abs(v)  # "This command modifies the move velocity parameter (VL)"; 0 stops
    ramp = pf.velocity_change(v0, v, axis.ac)
    if v == 0.0:
        # JG0 of the soft-limit mode's ramp down (a PCIx jog's) is that same ramp at AC, as an
        # ST's is (Axis.decelerate): it runs on past the switch it reacts to (limit_ramp)
        axis.begin(tick, ramp, Motion.STOP, limit_ramp=True)
        return motion_wait(axis)
    axis.direction = 1 if v > 0 else -1
    axis.begin(tick, [*ramp, pf.cruise(v)], Motion.JOG)
    axis.home = None
    ex.power_on(axis)
    at_speed = tick + sum(p.duration for p in ramp)
    return Wait("time", until=machine.clock.at_or_after(at_speed))


def _stream(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.8: "generate a pulse train without acceleration or deceleration at the rates
    # specified. The parameters are time in 1/1024 second sample intervals, X velocity, and
    # Y velocity." If the stream runs dry the last rate continues ("slave mode").
    # The unit is not the sample (the PC48 samples 2048 times a second, the PC46-21/-41 512): an
    # entry that follows on from one whose time ended between two samples counts from that end,
    # so a stream lasts the time its entries add up to; a rate changes on the sample at or after.
    # A stream stopped (ST, KL: _stop; a flush: a limit, SA) has nothing to follow on from.
    machine = ex.machine
    samples, vx, vy = op.args
    clock = machine.clock
    tick = clock.at_or_after(t)
    end = axis.stream_end
    start = end if end is not None and clock.at_or_after(end) == tick else tick
    for a, v in ((axis, vx), (machine.axis_by_letter("Y"), vy)):
        if a is None:
            continue
        if v:
            a.direction = 1 if v > 0 else -1
            a.begin(tick, [pf.cruise(a.to_motor(v))], Motion.STREAM)
        elif a.motion is Motion.STREAM or a is axis:
            a.halt(tick)
    axis.stream_end = start + samples / machine.model.velocity_stream_rate
    return Wait("time", until=clock.at_or_after(axis.stream_end))


def _one_step(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # "will output one step pulse in the current direction ... in one sample interval"
    machine = ex.machine
    tick = machine.clock.at_or_after(t)
    rate = machine.model.sample_rate
    x = axis.position(tick)
    step = pf.cruise(axis.direction * rate, 1.0 / rate)
    axis.begin(tick, [step], Motion.MOVE, final=x + axis.direction)
    return Wait("motion")


def _staircase(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.20: run to the absolute position at the new velocity; control passes on when
    # it is reached; "If a new MV command is sent after the controller has already passed
    # the destination ... the controller will continue to move at the old velocity."
    ex.cancel(axis, "MV")
    clock = ex.machine.clock
    dest = axis.to_motor(op.args[0])
    v = abs(axis.to_motor(op.args[1])) * axis.direction
    tick = clock.at_or_after(t)
    x = axis.position(tick)
    if (dest - x) * axis.direction <= 0:
        return None
    v0 = axis.velocity(tick)
    axis.begin(tick, [*pf.velocity_change(v0, v, axis.ac), pf.cruise(v)], Motion.STAIRCASE)
    ex.power_on(axis)
    when = axis.traj.first_time(dest, axis.direction > 0, tick)
    if when is None:
        return Wait("motion")
    return Wait("time", until=clock.at_or_after(when))


def _stop_at(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # "stop at the specified position ... If there is insufficient distance to stop at the
    # previously specified deceleration ... the controller will stop as soon as possible"
    ex.cancel(axis, op.code)  # SP or FP
    dest = float(math.trunc(axis.to_motor(op.args[0])))
    tick = ex.machine.clock.at_or_after(t)
    v0 = axis.velocity(tick)
    if v0 == 0.0:
        return None
    x = axis.position(tick)
    # a move with a base velocity ramps down to it and stops from there, as ST does
    pieces = pf.stop_at(dest - x, v0, axis.ac, axis.stop_base())
    if not pieces:  # (at or below the base velocity, the position passed: rest at once)
        # on the tick, as ST's (Axis.stop_on): until then the pulses go on and RP counts them
        stopped = axis.motion
        axis.stop_on(tick)
        if axis.moving:
            return motion_wait(axis)
        ex.stopped_at_once(axis, tick, stopped)
        return None
    reach = sum(p.x(p.duration) for p in pieces)
    final = dest if abs(x + reach - dest) < 1e-6 else None
    axis.begin(tick, pieces, Motion.STOP, final=final)
    return motion_wait(axis)


def _home(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # PC48 §6.11: "step in the positive direction at the predefined velocity, until the home
    # input line goes true. The position counter will be initialized to the position
    # supplied ... The axis will not stop at home, but ... decelerates to a stop."
    position, kill, direction = op.args
    tick = ex.machine.clock.at_or_after(t)
    # a home ends what its dialect's lists say by its own name: KM and KR are in none of them
    # (the PC48's HN/IS "LP, HM, HR, SA, ST or KL"; the PCIx's pages), so a kill home leaves
    # position hold and slip detection on
    name = ("KM", "KR") if kill else ("HM", "HR")
    ex.cancel(axis, name[0] if direction > 0 else name[1])
    v0 = axis.velocity(tick)
    v = direction * axis.vl
    axis.direction = direction
    axis.begin(tick, [*pf.velocity_change(v0, v, axis.ac), pf.cruise(v)], Motion.HOME)
    ex.power_on(axis)
    points: tuple[float, ...] = ()
    if axis.home_encoder:
        points = _index_points(axis, direction)
    axis.home = HomeSearch(
        position=position,
        kill=kill,
        direction=direction,
        prev=axis.home_condition(tick),
        index_points=points,
    )
    axis.home_last_phys = axis.phys(tick)
    return Wait("motion")


def _index_points(axis: Axis, direction: int) -> tuple[float, ...]:
    """Encoder home mode: physical positions in the home window where the encoder index is."""
    w = axis.world
    cpr = w.encoder_counts_per_rev
    if cpr <= 0 or axis.ratio <= 0:
        return (math.inf * direction,)

    def enc_at(p: float) -> float:
        return axis.enc_base + axis.ratio * (p - axis.enc_phys)

    lo, hi = sorted((enc_at(w.home_low), enc_at(w.home_high)))
    index = w.index_count
    first = math.ceil((lo - index) / cpr)
    points: list[float] = []
    k = first
    while k * cpr + index < hi and len(points) < 64:
        count = k * cpr + index
        points.append(axis.enc_phys + (count - axis.enc_base) / axis.ratio)
        k += 1
    return tuple(points) or (math.inf * direction,)


def _stop(ex: Executor, axis: Axis, op: Op, t: float) -> Result:
    # args: kill, and the motion a kill whose pulses stopped before this op ran had stopped
    # (KL, Control-D: Interpreter.kill_all), else None: what the axis is doing now
    kill, was = op.args
    stopped = was if was is not None else axis.motion
    ex.cancel(axis, "KL" if kill else "ST")
    axis.home = None
    axis.stream_end = None  # a VS after the stop begins a stream anew (_stream)
    if stopped is Motion.HOLD and axis.hold:
        # the hold's own correction, of a hold the stop leaves on (the PCIx's lists name no
        # stop): it goes on toward the same goal; a kill stops the pulses and the hold, still
        # on, starts them again
        if kill:
            axis.halt(t)
            ex.check_hold(axis, t)
        return None
    if kill:
        axis.halt(t)
        ex.stopped_at_once(axis, t, stopped)
        return None
    tick = ex.machine.clock.at_or_after(t)
    if axis.motion is Motion.IDLE:
        return None
    axis.decelerate(tick)
    if not axis.moving:
        ex.stopped_at_once(axis, tick, stopped)
        return None
    return Wait("motion")


MOTION_OPS: dict[str, OpFunction] = {
    "MA": _move_abs,
    "MT": _move_abs,
    "MR": _move_rel,
    "ML": _move_rel,
    "GO": _go,
    "GD": _go,
    "JG": _jog,
    "JF": _jog,
    "VS": _stream,
    "MO": _one_step,
    "MV": _staircase,
    "SP": _stop_at,
    "FP": _stop_at,
    "HM": _home,
    "STOP": _stop,
}
