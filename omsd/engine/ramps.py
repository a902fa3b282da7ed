"""Ramps: how an axis gets up to speed and back, and the moves built from them.

The ramp shapes are those of PC48 §1.3 ("VELOCITY PROFILES"):

* linear: constant acceleration ``A_m``; triangular when the move is too short to reach speed;
  an optional base velocity (VB) is jumped to at the start and from at the end;
* parabolic: ``a = A_0 - A_0 t / T_2``, the PN parameter being "10 times the ratio t/T_2";
  a move too short to reach speed truncates the curve, keeping its shape;
* cosine: ``v = V_p/2 (1 - cos(2 A_m t / V_p))``; a short move keeps the full shape with a
  lower peak velocity, "360 degrees of a sine wave" of acceleration;

and two more a dialect may define shapes for (PCIx §5.8.3/§5.8.4, §5.12.1):

* custom: a table of breakpoints, piecewise constant acceleration ("Ramp at 10% of AC until
  5% of VL", breakpoint after breakpoint); see :func:`_custom_ramp`;
* S-curve: acceleration rising, flat, falling, in nine regions; see :func:`_scurve_ramp`.

:func:`move_pieces` builds a point-to-point move from a ramp; :func:`velocity_change`,
:func:`stop_at` and :func:`hold_correction` the other motions the executor starts.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

from omsd.engine.pieces import Chain, Cosine, Decay, Piece, Poly, cruise, mirrored, scaled
from omsd.engine.trajectory import Course

_BISECT_ITERATIONS = 80


class RampKind(Enum):
    LINEAR = "linear"
    PARABOLIC = "parabolic"
    COSINE = "cosine"
    CUSTOM = "custom"  # PCIx SR#: a DAR/DAB/DAE table
    SCURVE = "scurve"  # PCIx SS#: an AJ profile

    # hashed by identity, in C: a move's kept profile is looked up by its ramp (Motion's note)
    __hash__ = object.__hash__


@dataclass(frozen=True, slots=True)
class SCurve:
    """An AJ profile (PCIx §5.8.3), taken literally: ALOWER and APEAK are the flat (constant
    acceleration) shares of the lower and upper halves of the ramp up, ARADIUS stretches its
    curved (constant jerk) regions; DLOWER, DPEAK, DRADIUS the same for the ramp down. The AJ
    command fills in the manual's defaults (the ramp down mirrors the ramp up)."""

    alower: float = 0.0
    apeak: float = 0.0
    aradius: float = 1.0
    dlower: float = 0.0
    dpeak: float = 0.0
    dradius: float = 1.0


@dataclass(frozen=True, slots=True)
class RampShape:
    """An axis's ramp selection: PF/LA (linear), PN#/PR# (parabolic, # steps), CN/SC (cosine),
    SR# (custom table: ``breakpoints`` of (fraction of AC, fraction of VL)), SS# (S-curve)."""

    kind: RampKind = RampKind.LINEAR
    steps: int = 3
    table: int = 0  # SR# / SS#
    breakpoints: tuple[tuple[float, float], ...] = ()
    scurve: SCurve | None = None
    # the lowest acceleration a parabolic ramp falls to, as a fraction of AC: the PCIx's PN/PR
    # "down to as low as 10%" (so PN10 ends its ramp at 10% of AC, as PN9 does); 0 on the PC48
    floor: float = 0.0

    @property
    def segments(self) -> int:
        return len(self.breakpoints)

    @property
    def ratio(self) -> float:
        """t/T_2 at the end of a parabolic ramp: PC48 §1.3, "10 times the ratio t/T_2"."""
        return min(self.steps / 10.0, 1.0 - self.floor)


LINEAR = RampShape()


def _linear_ramp(vmax: float, accel: float, vbase: float) -> tuple[Poly, float]:
    vb = min(vbase, vmax) if vbase > 0.0 else 0.0
    ramp = Poly(vb, accel, 0.0, (vmax - vb) / accel)
    return ramp, ramp.x(ramp.duration)


def _parabolic_ramp(vmax: float, accel: float, ratio: float) -> Poly:
    t1 = vmax / (accel * (1.0 - ratio / 2.0))
    return Poly(0.0, accel, -accel * ratio / t1, t1)


_MIN_LEVEL = 1e-5  # the resolution of a DAB level as ?DA prints it


def _clamp(value: float, lo: float, hi: float) -> float:
    return min(max(value, lo), hi)


def _custom_ramp(
    vmax: float, accel: float, breakpoints: Sequence[tuple[float, float]]
) -> list[Poly]:
    """The ramp from rest to ``vmax`` of a custom table (PCIx SR#, defined by DAR/DAB/DAE).

    PCIx DAB: "the first specifies the acceleration level that should be used to achieve the
    second parameter, velocity level. Both levels are expressed in terms of percentage in
    decimal format; i.e. 1.00 is 100%"; DAR's example: "Ramp at 10% of AC until 5% of VL". So
    each breakpoint is one constant-acceleration segment at ``fa * AC`` from the velocity
    reached so far up to ``fv * VL``.

    Where the manual is silent or says "unpredictable" (choices, made so that the ramp always
    ends at VL in finite time):

    * a breakpoint whose velocity is not above the velocity already reached ("At no time should
      a DAB command be entered in which the velocity parameter is less than the velocity
      parameter of the prior DAB ... the results of such a ramp will be unpredictable") is
      skipped, and so is one with a zero acceleration level, which would never get there;
    * levels outside the DAB range "0.0 <= Parameter <= 1.0" are clamped into it, and an
      acceleration level below 0.00001 counts as zero: ?DA reports levels to five decimals
      ("DAB0.10000,0.20000"), and a smaller one would take practically forever (or overflow);
    * a table that ends below 100% of VL carries on at the acceleration level of the last
      breakpoint used, up to VL: VL stays the peak velocity ("VL = peak velocity") and the
      table's last level is the one in force. A table with no usable breakpoint ("A ramp table
      containing no breakpoints is invalid and will result unpredictably if used") ramps at
      the full AC, as a linear ramp (VB is not applied: "This mode is active only for linear
      ramps").
    """
    pieces: list[Poly] = []
    v = 0.0
    level = 1.0
    for fa, fv in breakpoints:
        frac = _clamp(fa, 0.0, 1.0)
        target = vmax * _clamp(fv, 0.0, 1.0)
        a = frac * accel
        if frac < _MIN_LEVEL or (target - v) / a <= 0.0:
            continue
        pieces.append(Poly(v, a, 0.0, (target - v) / a))
        v = target
        level = frac
        if v >= vmax:
            return pieces
    if v < vmax:
        a = level * accel
        pieces.append(Poly(v, a, 0.0, (vmax - v) / a))
    return pieces


def _scurve_ramp(vmax: float, accel: float, lower: float, peak: float, radius: float) -> list[Poly]:
    """The S-curve ramp from rest to ``vmax`` (PCIx AJ, SS#): regions 1 to 4 of the AJ page.

    The manual: "An S-curve acceleration profile is one that starts with increasing jerk, then
    transitions to constant jerk, then transitions to decreasing jerk until zero acceleration is
    reached at the desired velocity" (§5.12.1), and on the AJ page: "Region 1 = 1-ALOWER. It is
    the percentage of the lower half of the ramp up that S-curved. Region 2 = ALOWER. It is the
    percentage of the lower half of the ramp up that is flat. Region 3 = APEAK ... of the upper
    half ... that is flat. Region 4 = 1-APEAK ... of the upper half ... that S-curved. ARADIUS can
    "stretch" regions 1 and 4 in the time dimension."

    The manual does not say what is "flat", in what unit the percentages are, what shape the
    "S-curved" parts have or what the stretch acts against (its Figure 5-2 is not in the text).
    The model chosen (continuous velocity and acceleration, bounded jerk, peak AC, exact VL):

    * the *lower half* of the ramp takes the velocity from 0 to VL/2, the *upper half* from
      VL/2 to VL ("lower half"/"upper half" of the ramp up);
    * "flat" is the acceleration: regions 2 and 3 accelerate at AC (the programmed rate, as in
      every other ramp); the S-curved regions change the acceleration at constant jerk, 0 to AC
      in region 1 and AC to 0 in region 4 (the classic jerk-limited "S" of the velocity);
    * the percentages are shares of each half's time before stretching; ARADIUS multiplies the
      time of the S-curved region only, i.e. the half lasts ``tau (R (1 - f) + f)`` with
      ``(1 - f) R tau`` curved and ``f tau`` flat, and ``tau`` follows from the half's velocity
      change ``AC tau (R (1 - f) / 2 + f) = VL / 2``. A larger radius thus lowers the jerk and
      lengthens the curve at the expense of the flat part; with no flat part (f = 0) there is
      nothing to trade and the radius has no effect;
    * degenerate cases: ALOWER = APEAK = 1 is a linear ramp at AC; ALOWER = APEAK = 0 (the
      defaults) a pure S (triangular acceleration, twice the linear ramp time).

    Regions 2 and 3 are one constant-acceleration piece. Parameters outside the AJ ranges
    ("0 <= ALOWER <= 1.0", "1.0 <= ARADIUS <= 10.0") are clamped into them.
    """
    lower = _clamp(lower, 0.0, 1.0)
    peak = _clamp(peak, 0.0, 1.0)
    radius = _clamp(radius, 1.0, 10.0)
    tau_lower = vmax / (accel * (radius * (1.0 - lower) + 2.0 * lower))
    tau_upper = vmax / (accel * (radius * (1.0 - peak) + 2.0 * peak))
    t1 = radius * (1.0 - lower) * tau_lower  # region 1: jerk, 0 -> AC
    flat = lower * tau_lower + peak * tau_upper  # regions 2 and 3: AC
    t4 = radius * (1.0 - peak) * tau_upper  # region 4: jerk, AC -> 0
    pieces: list[Poly] = []
    v = 0.0
    if t1 > 0.0:
        pieces.append(Poly(0.0, 0.0, accel / t1, t1))
        v = accel * t1 / 2.0
    if flat > 0.0:
        pieces.append(Poly(v, accel, 0.0, flat))
        v += accel * flat
    if t4 > 0.0:
        pieces.append(Poly(v, accel, -accel / t4, t4))
    return pieces


def _scurve_sides(vmax: float, accel: float, sc: SCurve) -> tuple[list[Poly], list[Poly]]:
    """Ramp up (regions 1-4) and ramp down (regions 6-9) of an AJ profile.

    AJ: "Region 6 = 1-DPEAK ... upper half of the ramp down that S-curved. Region 7 = DPEAK ...
    flat. Region 8 = DLOWER ... lower half of the ramp down that is flat. Region 9 = 1-DLOWER
    ... S-curved. DRADIUS can "stretch" regions 6 and 9". The ramp down is therefore the ramp up
    built from (DLOWER, DPEAK, DRADIUS), run backwards in time: region 6 (1-DPEAK) leaves VL,
    region 9 (1-DLOWER) arrives at rest. The peak deceleration is AC ("All the following move
    commands ... will accelerate and decelerate at this rate"; DC is for GU only). The fields
    of :class:`SCurve` are taken as given: filling in the symmetrical defaults ("If the
    parameters are not given ... they will be symmetrical with regions 4, 3, 2, and 1") is the
    AJ command's job.
    """
    up = _scurve_ramp(vmax, accel, sc.alower, sc.apeak, sc.aradius)
    down = [
        mirrored(p) for p in reversed(_scurve_ramp(vmax, accel, sc.dlower, sc.dpeak, sc.dradius))
    ]
    return up, down


def _ramp_parts(vmax: float, accel: float, shape: RampShape) -> list[Poly]:
    if shape.kind is RampKind.CUSTOM:
        return _custom_ramp(vmax, accel, shape.breakpoints)
    sc = shape.scurve or SCurve()
    return _scurve_ramp(vmax, accel, sc.alower, sc.apeak, sc.aradius)


def ramp_up(vmax: float, accel: float, vbase: float, shape: RampShape) -> Piece:
    """The acceleration from rest to ``vmax`` (always positive).

    A custom or S-curve ramp is several segments, returned as one :class:`Chain`, so that
    ``a(0)`` and ``a(duration)`` are the accelerations at the start and the end of the ramp
    (RC). With ``vmax <= 0`` the ramp is empty but still starts at its shape's acceleration.
    """
    if shape.kind in (RampKind.CUSTOM, RampKind.SCURVE):
        if vmax <= 0.0:
            first = _ramp_parts(1.0, accel, shape)[0]
            return Poly(0.0, first.a(0.0), 0.0, 0.0)
        return Chain(_ramp_parts(vmax, accel, shape))
    if vmax <= 0.0:
        return Poly(0.0, 0.0 if shape.kind is RampKind.COSINE else accel, 0.0, 0.0)
    if shape.kind is RampKind.COSINE:
        omega = 2.0 * accel / vmax
        return Cosine(0.0, vmax, omega, math.pi / omega)
    if shape.kind is RampKind.PARABOLIC:
        return _parabolic_ramp(vmax, accel, shape.ratio)
    return _linear_ramp(vmax, accel, vbase)[0]


def _distance(pieces: Sequence[Piece]) -> float:
    return sum(p.x(p.duration) for p in pieces)


def _truncated(up: Sequence[Poly], reach: float) -> list[Poly]:
    """The constant-acceleration ramp ``up`` cut where it has covered ``reach``: the segment in
    which that happens is shortened to the root of ``v0 t + a t^2 / 2 = rest``."""
    out: list[Poly] = []
    covered = 0.0
    for p in up:
        s = p.x(p.duration)
        if covered + s < reach:
            out.append(p)
            covered += s
            continue
        rest = reach - covered
        if rest > 0.0:
            t = 2.0 * rest / (p.v0 + math.sqrt(p.v0 * p.v0 + 2.0 * p.a0 * rest))
            out.append(Poly(p.v0, p.a0, p.j, t))
        break
    return out


def _custom_move(d: float, vmax: float, accel: float, shape: RampShape) -> list[Piece]:
    """Rest-to-rest over ``d > 0`` with a custom table.

    The manual describes the table only as a ramp (SR "selects a previously defined custom ramp
    profile"); the deceleration is the ramp up in reverse, as for the other ramp types ("The
    deceleration is the same in reverse", VB). A move too short to reach VL truncates the ramp
    where it has covered half the distance and comes back down the same way, as the parabolic
    ramp does ("the curve is truncated, causing the shape of the velocity curve to remain the
    same", PC48 §1.3): the peak velocity is lower and the table's shape is kept up to it.
    """
    up = _custom_ramp(vmax, accel, shape.breakpoints)
    s_up = _distance(up)
    peak = vmax
    if 2.0 * s_up > d:
        up = _truncated(up, d / 2.0)
        s_up = d / 2.0
        peak = up[-1].v(up[-1].duration) if up else 0.0  # (no cruise: it is over half-way)
    return _assemble(d, up, s_up, [mirrored(p) for p in reversed(up)], s_up, peak)


def _scurve_move(d: float, vmax: float, accel: float, shape: RampShape) -> list[Piece]:
    """Rest-to-rest over ``d > 0`` with an S-curve.

    §5.12.1: "The S-curve profile is not truncated in moves that do not reach full velocity ...
    the controller calculates the entire profile and selects the velocity that will preserve
    selected S-curve profile, by limiting the velocity on short moves". With AC and the region
    shares fixed, every segment's duration is proportional to the peak velocity and both ramp
    distances to its square, so the reduced peak is ``VL sqrt(d / (s_up + s_down))`` exactly.
    """
    sc = shape.scurve or SCurve()
    up, down = _scurve_sides(vmax, accel, sc)
    s_up, s_down = _distance(up), _distance(down)
    peak = vmax
    if s_up + s_down > d:
        peak = vmax * math.sqrt(d / (s_up + s_down))
        up, down = _scurve_sides(peak, accel, sc)
        s_up, s_down = _distance(up), _distance(down)
    return _assemble(d, up, s_up, down, s_down, peak)


def _assemble(
    d: float, up: Sequence[Poly], s_up: float, down: Sequence[Poly], s_down: float, peak: float
) -> list[Piece]:
    """The ramp ``up`` to ``peak``, a cruise at ``peak`` over what is left of ``d``, the ramp
    ``down``."""
    pieces: list[Piece] = [*up]
    rest = d - s_up - s_down
    if rest > 1e-9 and up and peak > 0.0:
        pieces.append(cruise(peak, rest / peak))
    pieces.extend(down)
    return pieces


def _ramp_down(up: Piece) -> Piece:
    if isinstance(up, Cosine):
        return Cosine(up.v0 + up.dv, -up.dv, up.omega, up.duration)
    assert isinstance(up, Poly)
    return mirrored(up)


def move_pieces(
    distance: float, vmax: float, accel: float, vbase: float, shape: RampShape
) -> list[Piece]:
    """Rest-to-rest move over ``distance`` (:func:`profile_pieces`). Fast path (issue 16): a
    move's profile depends on nothing but these five values and its pieces are immutable, so
    the last :data:`PROFILES_KEPT` profiles are kept (a program or a client repeats the same
    moves); ``tests/board/test_fast_paths.py`` checks kept against computed."""
    return list(_kept_profile(distance, vmax, accel, vbase, shape))


#: How many move profiles :func:`move_pieces` keeps.
PROFILES_KEPT = 256


@functools.lru_cache(maxsize=PROFILES_KEPT)
def _kept_profile(
    distance: float, vmax: float, accel: float, vbase: float, shape: RampShape
) -> tuple[Piece, ...]:
    return tuple(profile_pieces(distance, vmax, accel, vbase, shape))


@functools.lru_cache(maxsize=PROFILES_KEPT)
def kept_course(
    distance: float, vmax: float, accel: float, vbase: float, shape: RampShape
) -> Course:
    """The :class:`~omsd.engine.trajectory.Course` of :func:`move_pieces`' profile (fast path,
    issue 16: a queued move that follows on, ``omsd.engine.follow_on``)."""
    return Course(_kept_profile(distance, vmax, accel, vbase, shape))


def profile_pieces(
    distance: float, vmax: float, accel: float, vbase: float, shape: RampShape
) -> list[Piece]:
    """Rest-to-rest move over ``distance`` (signed) with peak ``vmax`` and acceleration ``accel``.

    PC48 §1.2: "If the move parameters do not allow the motor to accelerate to the desired
    velocity in the desired distance, the PC48 will automatically generate an optimum triangular
    velocity profile." Custom (:func:`_custom_move`) and S-curve (:func:`_scurve_move`) ramps
    are PCIx only.
    """
    d = abs(distance)
    if d == 0.0 or vmax <= 0.0 or accel <= 0.0:
        return []
    sign = 1.0 if distance > 0 else -1.0
    if shape.kind is RampKind.CUSTOM:
        return [scaled(p, sign) for p in _custom_move(d, vmax, accel, shape)]
    if shape.kind is RampKind.SCURVE:
        return [scaled(p, sign) for p in _scurve_move(d, vmax, accel, shape)]
    up: Piece
    if shape.kind is RampKind.LINEAR:
        up, s_up = _linear_ramp(vmax, accel, vbase)
        if 2.0 * s_up > d:
            vb = up.v0
            vp = math.sqrt(vb * vb + accel * d)
            up = Poly(vb, accel, 0.0, (vp - vb) / accel)
            s_up = d / 2.0
    elif shape.kind is RampKind.PARABOLIC:
        up = _parabolic_ramp(vmax, accel, shape.ratio)
        s_up = up.x(up.duration)
        if 2.0 * s_up > d:
            # "the curve is truncated, causing the shape of the velocity curve to remain the same"
            lo, hi = 0.0, up.duration
            for _ in range(_BISECT_ITERATIONS):
                mid = (lo + hi) / 2.0
                if up.x(mid) < d / 2.0:
                    lo = mid
                else:
                    hi = mid
            up = Poly(up.v0, up.a0, up.j, hi)
            s_up = d / 2.0
    else:
        s_up = math.pi * vmax * vmax / (4.0 * accel)
        peak = vmax
        if 2.0 * s_up > d:
            # "360 degrees of a sine wave" at the programmed peak acceleration
            peak = math.sqrt(2.0 * accel * d / math.pi)
            s_up = d / 2.0
        omega = 2.0 * accel / peak
        up = Cosine(0.0, peak, omega, math.pi / omega)
    down = _ramp_down(up)
    pieces: list[Piece] = [up]
    rest = d - 2.0 * s_up
    if rest > 1e-9:
        # a ramp that leaves room for a cruise has reached VL: the cruise is at VL itself, not
        # at the ramp's last velocity, which floating point may leave a hair below it
        # (999.9999999999999 for VL1000 on a parabolic ramp, whose integer part RV gave as 999)
        pieces.append(cruise(vmax, rest / vmax))
    pieces.append(down)
    return [scaled(p, sign) for p in pieces]


def move_time(distance: float, vmax: float, accel: float, vbase: float, shape: RampShape) -> float:
    return sum(p.duration for p in move_pieces(distance, vmax, accel, vbase, shape))


def velocity_change(v0: float, v1: float, accel: float) -> list[Piece]:
    """Linear ramp from ``v0`` to ``v1`` at ``accel`` (split where it passes through zero)."""
    if accel <= 0.0 or v0 == v1:
        return []
    if v0 * v1 < 0.0:
        return velocity_change(v0, 0.0, accel) + velocity_change(0.0, v1, accel)
    a = accel if v1 > v0 else -accel
    return [Poly(v0, a, 0.0, (v1 - v0) / a)]


def stop_distance(v: float, accel: float) -> float:
    return v * v / (2.0 * accel) if accel > 0.0 else 0.0


def stop_at(distance: float, v0: float, accel: float, base: float = 0.0) -> list[Piece]:
    """Pieces that bring velocity ``v0`` to rest ``distance`` ahead (SP, FP), or as soon as
    possible at ``accel`` when that is too close or behind ("the axis will overshoot").

    A move with a base velocity ``base`` ramps down to it and drops to rest from there, as its
    own end does (VB: "The deceleration is the same in reverse"); at or below it there is no
    ramp: the axis runs on to the position and stops there at once (or at once, if passed)."""
    if v0 == 0.0:
        return []
    end = min(base, abs(v0))
    brake = stop_distance(v0, accel) - stop_distance(end, accel)
    ahead = distance * math.copysign(1.0, v0)
    pieces: list[Piece] = []
    if ahead > brake:
        pieces.append(cruise(v0, (ahead - brake) / abs(v0)))
    return pieces + velocity_change(v0, math.copysign(end, v0), accel)


def hold_correction(error: float, gain: float, vmax: float, deadband: float) -> list[Piece]:
    """Position-hold correction (HN): velocity ``gain * error`` capped at ``vmax`` (HV/HG),
    stopping once the remaining error is within ``deadband`` (HD)."""
    e = abs(error)
    stop = max(deadband, 0.5)
    if e <= stop or gain <= 0.0 or vmax <= 0.0:
        return []
    sign = math.copysign(1.0, error)
    pieces: list[Piece] = []
    knee = vmax / gain  # error below which the gain, not HV, limits the velocity
    if e > knee:
        pieces.append(cruise(vmax, (e - knee) / vmax))
        e = knee
    if e > stop:
        pieces.append(Decay(e, gain, math.log(e / stop) / gain))
    return [scaled(p, sign) for p in pieces]
