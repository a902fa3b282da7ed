"""A simulated PCIx servo axis: the board's PID position loop, its 16-bit DAC, and a motor.

The PCIx "utilizes a 16-bit DAC and outputs either +/- 10V or 0 to +10V", and "The servo update
rate of the PC1x is 488μs for four axes" (§2.7.2), i.e. the 2048-per-second sample of §7.2. The
manual names the terms of the filter but not its equation ("FIGURE 2-13 FEEDBACK LOOP" is an
image that was lost), so this module states one, in the discrete form such boards use, and makes
every coefficient the manual names act on it.

Units (chosen; the manual gives ranges, not units)
--------------------------------------------------
* Positions and errors are encoder counts; the sample period is ``T = 1/rate``.
* The filter output is in **DAC counts**, the signed 16-bit code: ±32,767 is ±10 V. One count is
  20 V / 65,536 = 0.000305 V, the manual's "approximate change in the output voltage of 0.0003
  volts" per DZ or KO step, and its examples come out right: DZ3277 is "near 1VDC", DZ250
  "~ +76mV", KO-2000 "~ -610mV". KO, DZ, KF and KU, whose ranges (±32,767, 0..32,767) are the
  DAC's, are therefore DAC counts too.
* With ``e[n] = setpoint[n] - position[n]`` (counts), the closed-loop output is::

      I[n]  = clamp(I[n-1] + KI * e[n], -KU, +KU)                 "integration sum upper limit"
      pid   = KP * e[n] + I[n] + KD * (e[n] - e[n-1])             P, I, D
            + KV * v[n] + KA * a[n] + KF * sign(v[n])             feedforwards, friction offset
      out   = clamp((-pid if SVI else pid) + KO, ±min(KB/10 * 32768, 32767))

  where ``v[n]`` and ``a[n]`` are the commanded (trajectory) velocity and acceleration in counts
  per sample and counts per sample², so KP is DAC counts per count of error, KD DAC counts per
  count of error change in one sample, KV DAC counts per count/sample. KU bounds the integral
  *term* (DAC counts), so it can never hold the output further than KU from where P and D put
  it: this is the only reading under which the factory KU200 and the 0..32,767 range are both
  sensible (bounding the raw error sum at 200 would leave KI0.04 at most 8 DAC counts, 2.4 mV).
  KF ("friction offset coefficient ... assists in the smooth start up motion ... and compensates
  for friction") is a constant push in the direction of commanded motion. Unless the caller
  passes the trajectory's own velocity and acceleration, ``v[n]`` and ``a[n]`` are the
  setpoint's backward differences, so the feedforwards act one sample late, as a board that
  differences its own profile would.
* KB "sets the servo axis PID output value upper bound limit from DAC", 0.0..10.0: a bound in
  volts on the magnitude of the closed-loop output (offset included, the voltage the amplifier
  sees). The KB page's "default value is 0.00" would leave a factory servo unable to move, so the
  §2.8 table's "10.0 ( KB10.0 )" is used. (The KB page's example calls 9 V "approximately half
  of its normal range"; that cannot be squared with a 10 V range and is not modelled.)
* HF "will open the loop and turn off the PID": the output is then DZ alone, "the offset
  coefficient needed to produce a zero voltage output or stationary position ... in the
  open-loop mode"; KO "is essentially the same as DZ, but used for closed-loop operation".
  DZ and KO are physical offsets at the amplifier input, so SVI does not invert them.
* SVI: "the PC1x will produce a negative voltage for positive motion"; the servo terms are
  negated before KO is added.
* BI: code ``c`` gives ``c * 10/32768`` V. UN: "0.0VDC and +10VDC ... To maintain position the
  board outputs 5VDC": the same 16-bit code read as offset binary, ``5 + c * 5/32768`` V, so full
  negative drive "approaches 0.0VDC". The simulated amplifier is assumed to be set up to match
  (its zero at 5 V in UN), so the motor sees the same signed drive either way.
* Runaway: "if the error is greater than 32768 then the controller will disable the PID so that
  you don't have a runaway motor" (§2.7.2); HN: the loop "is disabled when ... the servo error
  becomes too large". Past :data:`RUNAWAY_ERROR` the loop opens (output DZ) and
  :attr:`ServoLoop.tripped` is set until the next HN.

Factory gains
-------------
KP 10.00, KI 0.04, KD 20.00 from the KP/KI/KD pages and the RF list (the §2.8 table's KD160.0
and KI1.0 disagree with both); KU 200 and KB 10.0 from the §2.8 table (the only sources for KU;
see above for KB); KV, KA, KF, KO, DZ 0; BI; SVN.

The plant
---------
A velocity-mode ("voltage mode") amplifier and motor: the motor's velocity follows
``velocity_per_volt`` times the amplifier input with a first-order lag ``time_constant`` (the
load's inertia against the velocity loop's viscous damping, ``J/b``), plus an optional constant
disturbance ``bias_volts`` (a load torque or an unbalanced amplifier, what DZ, KO and KI are for)
and optional ``friction_volts`` of static friction (the amplifier input must exceed it before
the motor turns; what KF is for). The defaults, 200,000 counts/s per volt (a 3000 rpm motor with
a 10,000-line encoder at 10 V) and a 1.4 ms lag, make the factory gains well damped: a 100-count
step rises (10% to 90%) in about 3.4 ms and overshoots by about 2%; with KI0 (KP and KD alone)
the overshoot is 0.2%. Removing KD gives about 20% overshoot and ringing, KP25 about 20%,
KP100 KD0 a sustained oscillation of hundreds of counts. The integral's own slow mode (its time
constant is about KP / (KI * rate), 120 ms) makes a type-2 loop that must overshoot a little and
creep back; it dominates settling into a one-count band (about 0.1 s for a 100-count step), and
KU bounds that creep to KU / KP counts. Over one sample the plant is integrated exactly
(zero-order hold on the DAC), so any sample rate and any time constant are stable numerically;
only the loop itself can go unstable. At 200,000 counts/s (the factory VL) the KP-only following
error is about 330 counts, well within the quarter turn §2.7.2 calls acceptable for voltage mode
("(90°/360°) × (counts per revolution)"); KV ≈ 33.6 and KA ≈ 96 are the feedforwards that cancel
it (:meth:`Plant.ideal_kv`, :meth:`Plant.ideal_ka`), inside the manual's 0..249.99.

Neither the DAC's 0.3 mV step nor the encoder's one-count step is simulated inside the loop (each
would only add a sub-count dither); :attr:`ServoLoop.dac_counts` and
:attr:`ServoLoop.encoder_counts` report the quantized values.

The loop keeps its own time on the sample grid ``origin + k / rate``; :meth:`ServoLoop.run`
advances it sample by sample. When the loop is open (HF, or tripped) the output is constant and
the plant is advanced in closed form; when the setpoint is a constant and the loop has come to
rest, the rest of the interval is skipped.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from omsd.engine.clock import SampleClock

#: "The servo update rate of the PC1x is 488μs for four axes" (2048 per second).
SERVO_RATE = 2048
#: Largest DAC code magnitude (16 bits, signed).
DAC_MAX = 32767
#: Volts per DAC count: 20 V over 65,536 codes ("approximately ... 0.0003 volts").
VOLTS_PER_COUNT = 10.0 / 32768
#: "if the error is greater than 32768 then the controller will disable the PID".
RUNAWAY_ERROR = 32768.0

# The steady-state shortcut: closer to rest than this the loop is a fixed point in practice.
_REST_ERROR = 1e-6  # counts
_REST_VELOCITY = 1e-4  # counts per second
_REST_CHECK_EVERY = 64  # samples

Setpoint = float | Callable[[float], float]


def _clamp(value: float, limit: float) -> float:
    return -limit if value < -limit else limit if value > limit else value


@dataclass(frozen=True, slots=True)
class ServoGains:
    """The servo parameters of one axis (KP ... DZ, BI/UN, SVN/SVI), factory values by default.

    Units are in the module docstring: gains in DAC counts per count (per sample for KD, KV, KA),
    KF/KU/KO/DZ in DAC counts, KB in volts.
    """

    kp: float = 10.0
    ki: float = 0.04
    kd: float = 20.0
    kv: float = 0.0
    ka: float = 0.0
    kf: float = 0.0
    ku: float = 200.0
    kb: float = 10.0
    ko: float = 0.0
    dz: float = 0.0
    bipolar: bool = True
    inverted: bool = False


@dataclass(frozen=True, slots=True)
class Plant:
    """A velocity-mode amplifier and motor (see the module docstring).

    ``velocity_per_volt``: steady motor speed in counts/s per volt at the amplifier input.
    ``time_constant``: seconds for the speed to reach 63% of a step (0 = instant).
    ``bias_volts``: a constant disturbance at the amplifier input (load torque, amplifier offset).
    ``friction_volts``: static friction; the motor does not turn until the input exceeds it.
    ``reversed``: motor or encoder wired backwards (positive volts give negative counts).
    """

    velocity_per_volt: float = 200_000.0
    time_constant: float = 0.0014
    bias_volts: float = 0.0
    friction_volts: float = 0.0
    reversed: bool = False

    def velocity_for(self, volts: float) -> float:
        """The speed (counts/s) the motor settles at with ``volts`` at the amplifier input."""
        drive = (-volts if self.reversed else volts) + self.bias_volts
        if self.friction_volts > 0.0:
            if abs(drive) <= self.friction_volts:
                return 0.0
            drive -= math.copysign(self.friction_volts, drive)
        return self.velocity_per_volt * drive

    def ideal_kv(self, rate: int = SERVO_RATE) -> float:
        """The KV that supplies the whole constant-velocity drive, leaving P nothing to do."""
        return rate / (self.velocity_per_volt * VOLTS_PER_COUNT)

    def ideal_ka(self, rate: int = SERVO_RATE) -> float:
        """The KA that supplies the drive the lag needs while accelerating."""
        return self.time_constant * rate * rate / (self.velocity_per_volt * VOLTS_PER_COUNT)


class ServoLoop:
    """One servo axis: the PID filter at ``rate`` samples per second driving :class:`Plant`.

    The DAC output computed at sample ``k`` is held until sample ``k + 1`` (zero-order hold); the
    state the properties report is that at the last sample reached. The loop powers up open
    (HF, "the default mode at power up or reset"). What the caller does for each command:
    HN/HF set :attr:`closed` (a limit switch, which also disables the loop, sets it False);
    KP ... DZ, BI/UN and SVN/SVI replace the gains with :meth:`set_gains`; LP is
    :meth:`set_position`; the trajectory is the ``setpoint`` of :meth:`run`.
    """

    def __init__(
        self,
        gains: ServoGains | None = None,
        plant: Plant | None = None,
        rate: int = SERVO_RATE,
        position: float = 0.0,
        origin: float = 0.0,
    ) -> None:
        self.gains = gains if gains is not None else ServoGains()
        self.plant = plant if plant is not None else Plant()
        self.rate = rate
        self.clock = SampleClock(rate, origin)
        self.period = 1.0 / rate
        tau = self.plant.time_constant
        self._alpha = math.exp(-self.period / tau) if tau > 0.0 else 0.0
        self.position = float(position)
        self.velocity = 0.0
        self.tripped = False
        self._closed = False
        self._index = 0
        self._out = self._open_output()
        self._target = self.plant.velocity_for(self._out * VOLTS_PER_COUNT)
        self._integral = 0.0
        self._error = 0.0
        self._last_error: float | None = None
        self._last_setpoint: float | None = None
        self._last_feed = 0.0
        self._fresh = True  # no sample computed since the last change of gains, HN or LP

    # -- configuration ----------------------------------------------------------------------

    def set_gains(self, gains: ServoGains) -> None:
        """New parameters take effect from the next sample; the loop's state is kept."""
        self.gains = gains
        self._fresh = True
        if not self._closed:
            self._hold(self._open_output())

    @property
    def closed(self) -> bool:
        """HN (True) / HF (False). Closing starts the filter afresh and clears a trip."""
        return self._closed

    @closed.setter
    def closed(self, value: bool) -> None:
        if value and not self._closed:
            self._integral = 0.0
            self._last_error = None
            self._last_setpoint = None
            self._last_feed = 0.0
            self.tripped = False
            self._fresh = True
        self._closed = value
        if not value:
            self._hold(self._open_output())

    def set_position(self, position: float) -> None:
        """LP on a servo axis: the encoder (and the caller's commanded position) are loaded.

        "The LP0 command is used to set the position error to 0" (§2.7.2): the motor does not
        move; the filter's error history is cleared so the next sample sees no derivative kick.
        """
        self.position = float(position)
        self._error = 0.0
        self._last_error = None
        self._last_setpoint = None
        self._last_feed = 0.0
        self._fresh = True

    # -- what it reports --------------------------------------------------------------------

    @property
    def time(self) -> float:
        """The time of the last sample computed."""
        return self.clock.time_of(self._index)

    @property
    def following_error(self) -> float:
        """Commanded minus actual position (counts) at the last sample."""
        return self._error

    @property
    def encoder_counts(self) -> int:
        """The position as the encoder reports it (whole counts)."""
        return math.floor(self.position + 0.5)

    @property
    def integral(self) -> float:
        """The integral term, DAC counts (bounded by KU)."""
        return self._integral

    @property
    def output(self) -> float:
        """The signed drive being held on the DAC, in DAC counts (unrounded)."""
        return self._out

    @property
    def dac_counts(self) -> int:
        """The signed 16-bit DAC code being output."""
        return max(-DAC_MAX, min(DAC_MAX, math.floor(self._out + 0.5)))

    @property
    def dac_volts(self) -> float:
        """The voltage at the servo output pin: ±10 V (BI) or 0..10 V with 5 V at zero (UN)."""
        code = self.dac_counts
        if self.gains.bipolar:
            return code * VOLTS_PER_COUNT
        return 5.0 + code * VOLTS_PER_COUNT / 2.0

    def at_rest(self, tolerance: float = 0.5) -> bool:
        """Following error within ``tolerance`` counts and the motor slower than that per second."""
        return abs(self._error) <= tolerance and abs(self.velocity) <= tolerance

    # -- running ----------------------------------------------------------------------------

    def run(
        self,
        setpoint: Setpoint,
        t_to: float,
        feed_velocity: Callable[[float], float] | None = None,
        feed_acceleration: Callable[[float], float] | None = None,
    ) -> None:
        """Advance sample by sample from :attr:`time` to the last sample at or before ``t_to``.

        ``setpoint`` is the commanded position, a constant or a function of time (the
        trajectory). The commanded velocity and acceleration used by KV, KA and KF are
        ``feed_velocity`` / ``feed_acceleration`` (counts/s, counts/s²) when given, else the
        setpoint's first and second differences.
        """
        last = self.clock.index_at_or_before(t_to)
        n = last - self._index
        if n <= 0:
            return
        if callable(setpoint):
            func = setpoint
        else:
            constant = float(setpoint)

            def func(_t: float) -> float:
                return constant

        if not self._closed:
            self._coast(n)
            self._index = last
            self._error = func(self.time) - self.position
            return
        first = k = self._index
        while k < last:
            if (
                not callable(setpoint)
                and (k - first) % _REST_CHECK_EVERY == 0
                and self._settled(func(0.0))
            ):
                self._index = last
                return
            k += 1
            self._advance_plant()
            self._index = k
            t = self.clock.time_of(k)
            r = func(t)
            self._sample(t, r, feed_velocity, feed_acceleration)
            if not self._closed:  # tripped
                self._coast(last - k)
                self._index = last
                self._error = func(self.time) - self.position
                return

    # -- internals --------------------------------------------------------------------------

    def _open_output(self) -> float:
        return _clamp(self.gains.dz, DAC_MAX)

    def _hold(self, out: float) -> None:
        self._out = out
        self._target = self.plant.velocity_for(out * VOLTS_PER_COUNT)

    def _advance_plant(self) -> None:
        target = self._target
        alpha = self._alpha
        slip = self.velocity - target
        self.position += target * self.period + slip * self.plant.time_constant * (1.0 - alpha)
        self.velocity = target + slip * alpha

    def _coast(self, n: int) -> None:
        """``n`` samples with the output constant, in closed form."""
        if n <= 0:
            return
        target = self._target
        decay = self._alpha**n
        slip = self.velocity - target
        self.position += target * n * self.period + slip * self.plant.time_constant * (1 - decay)
        self.velocity = target + slip * decay

    def _settled(self, setpoint: float) -> bool:
        return (
            not self._fresh
            and abs(setpoint - self.position) <= _REST_ERROR
            and abs(self._error) <= _REST_ERROR
            and abs(self.velocity) <= _REST_VELOCITY
            and abs(self._target) <= _REST_VELOCITY
        )

    def _sample(
        self,
        t: float,
        r: float,
        feed_velocity: Callable[[float], float] | None,
        feed_acceleration: Callable[[float], float] | None,
    ) -> None:
        g = self.gains
        e = r - self.position
        self._error = e
        self._fresh = False
        if abs(e) > RUNAWAY_ERROR:
            self.tripped = True
            self._closed = False
            self._hold(self._open_output())
            return
        if feed_velocity is not None:
            v = feed_velocity(t) * self.period
        else:
            v = 0.0 if self._last_setpoint is None else r - self._last_setpoint
        if feed_acceleration is not None:
            a = feed_acceleration(t) * self.period * self.period
        else:
            a = v - self._last_feed
        self._last_setpoint = r
        self._last_feed = v
        de = 0.0 if self._last_error is None else e - self._last_error
        self._last_error = e
        self._integral = _clamp(self._integral + g.ki * e, g.ku)
        pid = g.kp * e + self._integral + g.kd * de + g.kv * v + g.ka * a
        if v != 0.0:
            pid += math.copysign(g.kf, v)
        out = (-pid if g.inverted else pid) + g.ko
        self._hold(_clamp(out, min(DAC_MAX, g.kb / 10.0 * 32768)))


@dataclass(frozen=True, slots=True)
class StepResponse:
    """How a closed loop answered a step of ``step`` counts (times in seconds from the step)."""

    step: float
    overshoot: float  # counts beyond the step at the peak (0 if none)
    rise_time: float  # 10% to 90% of the step
    settling_time: float  # after this the error stays within ``band``
    final_error: float
    zero_crossings: int  # sign changes of the error (ringing)
    tripped: bool

    @property
    def overshoot_fraction(self) -> float:
        return self.overshoot / abs(self.step)


def step_response(
    gains: ServoGains | None = None,
    plant: Plant | None = None,
    step: float = 100.0,
    duration: float = 1.0,
    band: float = 1.0,
    rate: int = SERVO_RATE,
) -> StepResponse:
    """Close the loop at rest at 0, command ``step`` counts, and measure the response."""
    loop = ServoLoop(gains, plant, rate=rate)
    loop.closed = True
    sign = 1.0 if step >= 0 else -1.0
    peak = 0.0
    t10 = t90 = math.nan
    settled_at = 0.0
    crossings = 0
    last_sign = 0.0
    samples = round(duration * rate)
    for k in range(1, samples + 1):
        t = k / rate
        loop.run(step, t)
        moved = sign * loop.position
        peak = max(peak, moved)
        if math.isnan(t10) and moved >= 0.1 * abs(step):
            t10 = t
        if math.isnan(t90) and moved >= 0.9 * abs(step):
            t90 = t
        e = loop.following_error
        if abs(e) > band:
            settled_at = t
        s = math.copysign(1.0, e) if abs(e) > 1e-9 else 0.0
        if s != 0.0:
            if last_sign != 0.0 and s != last_sign:
                crossings += 1
            last_sign = s
        if loop.tripped:
            break
    if loop.tripped or abs(loop.following_error) > band:
        settled_at = math.inf
    return StepResponse(
        step=step,
        overshoot=max(0.0, peak - abs(step)),
        rise_time=t90 - t10,
        settling_time=settled_at,
        final_error=loop.following_error,
        zero_crossings=crossings,
        tripped=loop.tripped,
    )
