"""The board's reactions to what happens by itself: a move ending, a look at the sensors, an
armed interrupt firing, a settling time running out, a contour's outputs, a servo loop's check.

Running into a limit (§6.5, §7.3.4: "When the board receives a limit signal from the platform,
it flushes its command queue"), finding home (§6.11), detecting slip (§6.16) and the
position-hold correction (§6.15) are here. The machine calls these when an axis's next event is
due (:meth:`omsd.engine.machine.Machine.advance`).
"""

from __future__ import annotations

import math

from omsd.engine.axis import Axis
from omsd.engine.backlash import take_up_backlash
from omsd.engine.events import LimitEvent, ServoTripEvent, SlipEvent
from omsd.engine.executor import Executor
from omsd.engine.registers import DON_S, ENC_S, OVRT
from omsd.engine.states import Motion


def on_end(ex: Executor, axis: Axis, t: float) -> None:
    """The trajectory has run out: the axis is at rest."""
    motion = axis.motion
    axis.settle(t)
    if motion is Motion.HOLD:
        # the correction's steps were sent to put the encoder back: from here the counter and
        # the encoder go on together, and the next move's goal counts from the held position
        # (HN: "that position is maintained ... until commanded to a new position"), not from
        # where in the dead band the correction stopped (§5.7.1: "within the dead band of the
        # motor's target position"), which would carry up to HD into every later target. Slip
        # detection's relation is the encoder's own (its tolerance may be below HD)
        axis.in_position = True
        axis.anchor_tracking(t)
        if not axis.slip_detect:
            axis.track_enc = axis.hold_goal
    else:
        axis.power_down(t)
        axis.hold_goal = axis.tracked_encoder(axis.position(t))
        axis.in_position = True
        ex.check_hold(axis, t)
    axis.invalidate()


def on_sensor(ex: Executor, axis: Axis, t: float) -> None:
    axis.sensor_check = None
    axis.invalidate()
    machine = ex.machine
    if axis.backlash:
        take_up_backlash(axis, t)
    for hook in ex.sensor_hooks:
        hook(ex, axis, t)
    limits = axis.limits_on or axis.travel_limits is not None
    if axis.motion is not Motion.IDLE and limits and not axis.limit_ramp:
        direction = axis.direction_at(t)
        if direction and _limit_seen(axis, direction, t):
            _limit(ex, axis, direction, t)
    if axis.home is not None and axis.motion is Motion.HOME:
        _look_for_home(axis, t)
    if axis.slip_detect and abs(_slip_seen(axis, t)) > axis.es:
        axis.slip_detect = False
        axis.slipped = True
        machine.registers.status |= ENC_S | DON_S
        machine.emit(SlipEvent(t, axis.letter))
        if axis.slip_kill:
            # "the PCIx will kill motion on the axis that slipped as though a KL command had been
            # issued to the axis" (TN)
            stopped = axis.motion
            axis.halt(t)
            ex.flush(axis, t)
            ex.cancel(axis, "KL")
            ex.stopped_at_once(axis, t, stopped)
    if axis.hold and axis.motion is Motion.IDLE:
        ex.check_hold(axis, t)


def _slip_seen(axis: Axis, t: float) -> float:
    """The slip error a look finds. A look on a home search's way that has not stopped it (the
    PC48 family's KM/KR keep slip detection on) comes at a switch's edge, mid-step: there the
    board compares whole counts, the encoder's and the one the pulses make, not the pulses'
    continuous count (which would be up to half a count off a whole encoder count, a slip at the
    PC48's tolerance of 0). A stalled carriage's looks, at the predicted crossings of the
    tolerance (``sensing._slip_crossing``), keep the continuous error they were predicted with."""
    error = axis.slip_error(t)
    if axis.motion is Motion.HOME and axis.stall_phys is None:
        encoder = axis.encoder(t)
        return encoder - math.floor(encoder - error + 0.5)
    return error


def _look_for_home(axis: Axis, t: float) -> None:
    """Home is met on the search's own way: HM "will cause the current axis to step in the
    positive direction at the predefined velocity, until the home input line goes true" (PC48
    §6.11; HR "exactly like the HM command, except it travels in the reverse direction"). A
    search that begins while the axis still moves the other way (out of a jog or a move) takes
    no home on its way back: an edge met then is the switch's far side, where a search from rest
    never loads the counter."""
    home = axis.home
    assert home is not None
    on_its_way = axis.direction_at(t) == home.direction
    if home.index_points:
        before, now = axis.home_last_phys, axis.phys(t)
        axis.home_last_phys = now
        lo, hi = sorted((before, now))
        found = any(lo <= p <= hi for p in home.index_points) and axis.home_line_low(t)
    else:
        cond = axis.home_sensed(t)
        found = cond and not home.prev
        home.prev = cond
    if not found or not on_its_way:
        return
    axis.home = None
    if home.kill:
        axis.halt(t)  # "The position counter is not cleared or reset."
        if axis.hold:  # (hold kept through it) what is held is where the pulses stopped
            axis.hold_goal = axis.tracked_encoder(axis.position(t))
        return
    # the parameter is in encoder counts under ER ("All distance ... parameters are input in
    # encoder counts", PC48 §6.15), so the counter gets it over the ratio in whole steps, as LP
    # loads it: HM's "move absolute to the same position as specified in the HM command" then
    # returns home
    axis.load_counter(t, float(math.trunc(axis.to_motor(home.position))))
    if axis.has_encoder and axis.host.options.home_loads_encoder:
        # PCIx HM: "position counters will be initialized"; HR, which "behaves exactly like the
        # HM command": "the position and encoder counters are loaded with the parameter(s)";
        # the encoder the parameter itself, as LP's. A servo's too: loading is not moving, and
        # a closed loop whose commanded position alone were loaded would drive the motor back
        # by the difference
        axis.anchor_encoder(t, float(math.trunc(home.position)))  # whole counts, as LP's
    axis.anchor_tracking(t)
    axis.decelerate(t)


def _limit_seen(axis: Axis, direction: int, t: float) -> bool:
    """A limit stops the axis, whatever its motion: "The limit switch closure will stop the
    associated pulse stream if the motor travels beyond its allowable limits and trips the
    switch" (PC48 §4.3); "if the axis encounters a limit switch in the course of executing any
    motion, the axis will be instructed to stop" (PCIx LN). A ramp down (ST, JG0, SP, the
    deceleration after home) runs into the switches; the travel limits are for moves and jogs
    (``sensing._travel_levels``). The soft-limit mode's own ramp down is not stopped again by
    the switch it is reacting to (``limit_ramp``). LF turns the switches off, not the PCIx's
    travel limits ("Software overtravel limits and physical limit switch inputs can be enabled
    at the same time"; "TL0,0; Turns software limits off")."""
    if not axis.limits_on:
        return axis.beyond_travel_limit(direction, t)
    if axis.motion is Motion.STOP:
        return axis.limit_switch_active(direction, t)
    return axis.limit_active(direction, t)


def _limit(ex: Executor, axis: Axis, direction: int, t: float) -> None:
    machine = ex.machine
    axis.limit_latched = direction
    ex.hold_off(axis)
    if axis.servo is not None and axis.servo.closed:
        # the loop "is disabled when ... a limit is encountered"
        axis.servo_sync(t)
        axis.servo.closed = False
    # the soft-limit mode: "ramp down instead of terminating immediately. The output queue is
    # not flushed except for the current move", for the motions the dialect names
    if axis.soft_limit and axis.motion in machine.options.soft_limit_motions:
        axis.decelerate(t)
        axis.limit_ramp = axis.moving  # (a ramp under way; none from rest)
    else:
        axis.halt(t)
        ex.flush(axis, t)
    machine.registers.status |= OVRT | DON_S
    machine.emit(LimitEvent(t, axis.letter, direction))


def on_aux_timer(ex: Executor, axis: Axis, t: float) -> None:
    """The settling time after a move in power-automatic mode has run out: the output goes
    back to its idle state ("a settling time ... to be used before the power is reduced", PC48
    §6.6 SE), whatever the axis does now. A motion PA drives that began since has cancelled the
    timer (:meth:`Executor.power_on`); any other (the hold's corrections, the PC48's jogs and
    home searches, the PCIx's streams) is no motion PA drives, and its end is no end of a move:
    the output does not wait for it."""
    axis.aux_timer = None
    if axis.pa is not None:
        axis.aux = not axis.pa
    axis.invalidate()


def on_outputs(ex: Executor, axis: Axis, t: float) -> None:
    machine = ex.machine
    while axis.outputs and axis.outputs[0][0] <= t + 1e-12:
        _, (what, target, low) = axis.outputs.pop(0)
        if what == "aux":
            ex.set_aux(machine.axes[target], not low, t)
        elif what == "done":
            done = [a for a in machine.axes if target >> a.index & 1]
            machine.set_done(done, t, interrupt=True)
        else:
            machine.set_output(target, low=low, t=t)
    axis.invalidate()


def fire_in(ex: Executor, axis: Axis, t: float) -> None:
    arm = axis.in_arm
    axis.in_fire = None
    axis.in_arm = None
    axis.invalidate()
    if arm is None:
        return
    group = arm[1]
    ex.machine.set_done([axis], t, interrupt=False)
    group.arrive(axis.index)
    ex.check_group(group, t)


def on_servo(ex: Executor, axis: Axis, t: float) -> None:
    """A look at a servo axis's loop: "if the error is greater than 32768 then the controller
    will disable the PID so that you don't have a runaway motor" (PCIx §2.7.2). The loop opens;
    the commanded motion stops at once and the axis's queue is flushed, as a limit does, so that
    nothing drives an axis nobody is holding."""
    loop = axis.servo
    assert loop is not None
    axis.servo_sync(t)
    if loop.tripped and not axis.servo_trip_reported:
        # moving or holding: either way the axis is no longer under control
        axis.servo_trip_reported = True
        if axis.motion is not Motion.IDLE:
            axis.halt(t)
        ex.flush(axis, t)
        ex.machine.emit(ServoTripEvent(t, axis.letter, loop.following_error))
    axis.servo_last = loop.position
    axis.invalidate()
