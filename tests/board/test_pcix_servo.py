"""PCIx servo axes through the board's commands, on the manual clock.

The loop itself (omsd/board/servo.py) has its own tests (tests/board/test_servo.py); these drive
it the way a user does, with commands, and look at it the way a user can: RP (the commanded
position) and RE (the encoder, where the motor really is), ?PM, QA, RQ and the gain queries.

PCIx manual §2.7.2 (tuning): "check the position error by sending the RE and RP commands ...
If they are the same then you are on the right track, if the error is greater than 32768 then
the controller will disable the PID so that you don't have a runaway motor"; HN: "For servo
axes, the HN command closes the loop, enabling the PID. For servo axes, this mode is disabled
when the HF command is entered, when the servo error becomes too large or a limit is
encountered"; KD: "If you are getting too much "ringing" in the motion profile, then increase
KD to help dampen the system's response"; DZ: "This command affects the offset only when in
open-loop mode. The KO command is used to set the offset when the loop is closed"; SVI: "the
PC1x will produce a negative voltage for positive motion".

Choices made here where the manual gives no numbers:

* Step responses are sampled at every servo sample (1/2048 s, "The servo update rate of the
  PC1x is 488μs") with ``RP`` and ``RE``. Settled means ``|RE - RP| <= 1`` count from then on.
* The gain comparisons (KP up, KD off) use a PD loop (``KI0``) and short, hard moves
  (``AC8000000`` "RANGE: 1 ≤ AC ≤ 8,000,000"). With the factory KI the integral winds up over
  the whole move by the following error, which shrinks as KP grows, so on a profiled move a
  larger KP *lowers* the overshoot and the KP/KD comparison measures the integrator instead of
  the damping. The manual's own procedure tunes KP and KD first and KI afterwards ("Once the KP
  term has been obtained, then continue executing the motion while raising the KI term").
* Only comparisons between runs are asserted for the tuning, and only what the documented
  model makes exact otherwise (the KO/KU offset, the DAC's volts per count).
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from omsd.board.events import ErrorKind, ServoTripEvent
from omsd.board.harness import Harness
from omsd.engine.axis import SERVO_CHECK
from omsd.engine.servo import RUNAWAY_ERROR, SERVO_RATE, VOLTS_PER_COUNT

T = 1.0 / SERVO_RATE
HARD = "AC8000000;VL1000000;"  # the fastest ramp the manual allows


def x_queue(h: Harness) -> int:
    """X's free queue units: RQ reports every axis ("800, 800, 800, 800")."""
    return int(h.send("RQ\n").split(b",")[0])


def numbers(reply: bytes) -> list[int]:
    """The integers of a reply ``a<LF><CR>b<LF><CR>...`` (PCIx framing)."""
    return [int(x) for x in reply.split(b"\n\r") if x]


def text(reply: bytes) -> list[str]:
    return [x.decode("ascii") for x in reply.split(b"\n\r") if x]


def rp_re(h: Harness) -> tuple[int, int]:
    rp, re = numbers(h.send("RP;RE;\n"))
    return rp, re


def ask(h: Harness, query: str) -> str:
    (reply,) = text(h.send(query + "\n"))
    return reply


def trips(h: Harness) -> list[ServoTripEvent]:
    return [e for e in h.events() if isinstance(e, ServoTripEvent)]


@dataclass
class Trace:
    """RP and RE at every servo sample from a move's GO on."""

    target: int
    times: list[float]
    rp: list[int]
    re: list[int]

    @property
    def sign(self) -> int:
        return 1 if self.target >= 0 else -1

    @property
    def end(self) -> int:
        """Index of the first sample at which the commanded motion is over (RP at the target
        from there on)."""
        k = len(self.rp)
        while k > 0 and self.rp[k - 1] == self.target:
            k -= 1
        assert k < len(self.rp), "the commanded move never ended"
        return k

    @property
    def overshoot(self) -> int:
        """Counts beyond the target at the encoder's furthest point (0 if none)."""
        return max(0, max(self.sign * (re - self.target) for re in self.re))

    @property
    def settle_samples(self) -> int:
        """Samples after the end of the commanded motion until |RE - RP| <= 1 for good."""
        last_out = max(
            (
                k
                for k, (rp, re) in enumerate(zip(self.rp, self.re, strict=True))
                if abs(re - rp) > 1
            ),
            default=-1,
        )
        assert last_out < len(self.rp) - 1, "never settled"
        return last_out + 1 - self.end


def step(setup: str, distance: int, seconds: float = 0.25, model: str = "PCIX-400") -> Trace:
    """Close X's loop with ``setup``, then ``MR<distance>;GO;`` and sample every servo tick."""
    h = Harness(model)
    assert h.send(f"AX;HN;{setup}\n") == b""
    assert h.errors() == []
    h.until(0.01)
    start = h.t
    h.send(f"MR{distance};GO;\n")
    trace = Trace(distance, [], [], [])
    for k in range(1, round(seconds * SERVO_RATE) + 1):
        h.until(start + k * T)
        rp, re = rp_re(h)
        trace.times.append(h.t)
        trace.rp.append(rp)
        trace.re.append(re)
    assert trips(h) == []
    return trace


# -- the loop at power-up and HN --------------------------------------------------------------


def test_power_up_is_open_loop_and_hn_closes_it() -> None:
    """HF: "This is the default mode at power up or reset"; HN closes the loop (E76)."""
    h = Harness("PCIX-400")
    assert [ask(h, f"A{a};?PM") for a in "XYZT"] == ["hf"] * 4
    h.send("AY;HN;\n")
    assert [ask(h, f"A{a};?PM") for a in "XYZT"] == ["hf", "hn", "hf", "hf"]
    h.send("AY;HF;\n")
    assert ask(h, "AY;?PM") == "hf"


def test_pcix_202_has_servos_on_x_and_y_only() -> None:
    """PCIX-202: X and Y servo, Z and T open-loop steppers: the servo commands are refused on
    Z ("Not valid" for the motor type), while a Y loop closes and holds."""
    h = Harness("PCIX-202")
    h.send("AY;HN;KP25;\n")
    assert h.errors() == []
    assert ask(h, "AY;?PM") == "hn"
    assert ask(h, "AY;?KP") == "kp25.00"
    h.send("AZ;KP25;\n")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.WRONG_MOTOR, "KP25")]
    h.send("AY;MR500;GO;\n")
    h.until(0.5)
    assert rp_re(h) == (500, 500)


# -- a step move with the factory gains -------------------------------------------------------


@pytest.mark.parametrize("distance", [100, -100, 1000])
def test_factory_gains_follow_a_move_then_settle_and_stay_settled(distance: int) -> None:
    """§2.7.2: after the move "check the position error by sending the RE and RP commands ...
    If they are the same then you are on the right track". The motor lags the commanded
    position while moving (a servo follows behind), overshoots by little, comes within a count
    soon after the commanded motion ends and stays there; at last RE equals RP exactly."""
    trace = step("", distance, seconds=1.0)
    end = trace.end
    assert trace.rp[end] == distance
    moving = range(end // 4, 3 * end // 4)
    assert all(trace.sign * (trace.rp[k] - trace.re[k]) > 0 for k in moving)  # lagging behind
    assert trace.overshoot <= abs(distance) // 20  # "without overshoot and oscillation"
    settle = trace.settle_samples
    # settled within a quarter second of the end of the commanded motion (the integral's slow
    # creep dominates this, servo.py: "about 0.1 s for a 100-count step")
    assert 0 <= settle < SERVO_RATE // 4
    assert all(abs(re - distance) <= 1 for re in trace.re[end + settle :])
    h = Harness("PCIX-400")
    h.send(f"AX;HN;MR{distance};GO;\n")
    h.until(3.0)
    assert rp_re(h) == (distance, distance)
    h.until(10.0)
    assert rp_re(h) == (distance, distance)
    assert trips(h) == []


def test_a_closed_loop_at_rest_holds_exactly() -> None:
    """LP0;HN "check the shaft of the motor to make sure it is stiff": nothing moves."""
    h = Harness("PCIX-400")
    h.send("AX;LP0;HN;\n")
    for t in (0.1, 1.0, 10.0):
        h.until(t)
        assert rp_re(h) == (0, 0)


# -- tuning: KP and KD ------------------------------------------------------------------------

DISTANCES = [100, 300, 1000, -1000]


@pytest.mark.parametrize("distance", DISTANCES)
def test_raising_kp_raises_overshoot(distance: int) -> None:
    """A higher proportional gain against the same KD is a less damped loop: more overshoot
    ("If the motor becomes unstable prior to obtaining the optimum KP term than increase the
    KD term")."""
    base = step(HARD + "KI0;", distance)
    stiff = step(HARD + "KI0;KP25;", distance)
    assert stiff.overshoot > base.overshoot
    assert stiff.re[-1] == base.re[-1] == distance


@pytest.mark.parametrize("distance", DISTANCES)
def test_removing_kd_raises_overshoot_and_lengthens_settling(distance: int) -> None:
    """KD "dampen[s] the system's response": without it the same move rings past the target
    and takes longer to come within a count."""
    damped = step(HARD + "KI0;", distance)
    bare = step(HARD + "KI0;KD0;", distance)
    assert bare.overshoot > damped.overshoot
    assert bare.settle_samples > damped.settle_samples
    assert bare.re[-1] == damped.re[-1] == distance


@pytest.mark.parametrize("distance", DISTANCES)
def test_more_kd_removes_the_overshoot_but_settles_more_slowly(distance: int) -> None:
    """ "If, instead, the system is over-damped and is reaching the final velocity too slowly,
    then reduce the KD parameter": doubling KD leaves no overshoot and a slower approach."""
    factory = step(HARD + "KI0;", distance)
    heavy = step(HARD + "KI0;KD40;", distance)
    assert heavy.overshoot == 0 < factory.overshoot
    assert heavy.settle_samples > factory.settle_samples


def test_the_same_move_gives_the_same_trace() -> None:
    """The loop is deterministic: two boards, one history, identical samples (what makes the
    comparisons above meaningful)."""
    a = step(HARD + "KI0;KD0;", 300)
    b = step(HARD + "KI0;KD0;", 300)
    assert (a.rp, a.re) == (b.rp, b.re)


# -- gains are queued, answered and archived ---------------------------------------------------


@pytest.mark.parametrize(
    ("command", "reply"),
    [
        ("KP25", "kp25.00"),
        ("KP45.6", "kp45.60"),  # E103
        ("KI3.42", "ki3.42"),  # E97
        ("KI1", "ki1.00"),  # E98
        ("KD5.12", "kd5.12"),  # E94
        ("KD56", "kd56.00"),  # E93
        ("KA10.5", "ka10.50"),  # E90
        ("KV35.3", "kv35.30"),  # E109
        ("KB5", "kb5.00"),  # E92
        ("KF12", "kf12"),  # E96
        ("KU150", "ku150"),  # E107/E108
        ("KO218", "ko218"),  # E102
        ("KO-2000", "ko-2000"),  # E101
    ],
)
def test_gain_queries_answer_the_value_set(command: str, reply: str) -> None:
    h = Harness("PCIX-400")
    query = "?" + command[:2]
    factory = FACTORY_REPLIES[command[:2]]
    assert ask(h, f"AY;{query}") == factory
    h.send(f"AY;{command};\n")
    assert h.errors() == []
    assert ask(h, f"AY;{query}") == reply
    assert ask(h, f"AX;{query}") == factory  # the other axes keep theirs


# E104 ``kp10.00``; KI 0.04 and KD 20.00 from their pages; KB 10.0 and KU 200 from the §2.8
# table (the KB page's "0.00" would leave a servo unable to move, see servo.py)
FACTORY_REPLIES = {
    "KP": "kp10.00",
    "KI": "ki0.04",
    "KD": "kd20.00",
    "KV": "kv0.00",
    "KA": "ka0.00",
    "KB": "kb10.00",
    "KF": "kf0",
    "KU": "ku200",
    "KO": "ko0",
}


def test_factory_gain_replies() -> None:
    """The factory gains (FACTORY_REPLIES), on every axis of a PCIX-400."""
    h = Harness("PCIX-400")
    for axis in "XYZT":
        replies = {m: ask(h, f"A{axis};?{m}") for m in FACTORY_REPLIES}
        assert replies == FACTORY_REPLIES, axis
    assert [ask(h, "AX;?SO"), ask(h, "AX;?SV")] == ["bi", "svn"]  # E187 "svn"


def test_gains_are_queued_behind_a_move() -> None:
    """KP's QUEUE REQUIREMENTS "AX-AT 2": a gain sent during a move takes two slots and takes
    effect when the axis reaches it; ?KP (immediate) answers the gain in force."""
    h = Harness("PCIX-400")
    h.send("AX;HN;MR200000;GO;\n")
    free = x_queue(h)
    h.send("KP25;\n")
    assert x_queue(h) == free - 2
    h.until(0.5)  # 200,000 counts at VL200000: still moving
    assert rp_re(h)[0] < 200_000
    assert ask(h, "?KP") == "kp10.00"
    h.until(3.0)
    assert ask(h, "?KP") == "kp25.00"
    assert x_queue(h) == 800  # E165: "800" per axis when empty


def test_ap_saves_the_servo_parameters_rf_and_rd() -> None:
    """AP "stores the current parameter set ... KA, KB, KD, KF, KI, KO, KP, KU, KV" (and BI/UN;
    SVI and DZ pages: AP preserves them). RF "restores the current parameter set to the factory
    default values" without touching flash; RD "restores the motion parameters using power-up
    defaults"."""
    h = Harness("PCIX-400")
    h.send("AY;KP25;KI0.5;KD40;KV12;KA3;KB9;KF7;KU150;KO218;DZ250;UN;SVI;AP;\n")
    assert h.errors() == []
    queries = ("?KP", "?KI", "?KD", "?KV", "?KA", "?KB", "?KF", "?KU", "?KO", "?SO", "?SV")
    saved = [ask(h, "AY;" + q) for q in queries]
    assert saved == [
        "kp25.00",
        "ki0.50",
        "kd40.00",
        "kv12.00",
        "ka3.00",
        "kb9.00",
        "kf7",
        "ku150",
        "ko218",
        "un",
        "svi",
    ]
    h.send("AY;KP60;KO-5;BI;SVN;\n")
    assert ask(h, "AY;?KP") == "kp60.00"
    h.send("RF;\n")
    factory = [ask(h, "AY;" + q) for q in queries]
    assert factory[0] == "kp10.00" and factory[-2:] == ["bi", "svn"]
    h.send("RD;\n")
    assert [ask(h, "AY;" + q) for q in queries] == saved
    # DZ has no query; it is in the archive
    assert h.board.flash_defaults is not None
    assert h.board.flash_defaults["axes"]["Y"]["servo"]["dz"] == 250


# -- the runaway trip -------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("setup", "move"),
    [
        ("KB0;", "MR100000"),  # the output bound at 0 V: no drive at all
        ("KB0;", "MR-100000"),
        ("KP0;KI0;KD0;", "MR100000"),  # no gain: no drive
        (HARD + "KP0.2;KI0;KD0;", "MR300000"),  # a following error of VL/gain > 32768
    ],
)
def test_a_servo_that_cannot_follow_trips_and_the_move_stops(setup: str, move: str) -> None:
    """§2.7.2: "if the error is greater than 32768 then the controller will disable the PID so
    that you don't have a runaway motor"; HN: the loop "is disabled when ... the servo error
    becomes too large". The loop opens (?PM hf), the commanded motion stops, the queue is
    flushed (the ID and the move behind the GO never run: QA shows no done, RQ is empty) and
    a ServoTripEvent is reported. The board looks at a moving loop every SERVO_CHECK."""
    h = Harness("PCIX-400")
    h.send(f"AX;HN;{setup}\n")
    assert h.errors() == []
    h.send(f"{move};GO;ID;MR7;GO;\n")
    first_over: float | None = None
    event: ServoTripEvent | None = None
    while event is None:
        assert h.t < 5.0, "no trip"
        h.advance(T)
        rp, re = rp_re(h)
        if first_over is None and abs(rp - re) > RUNAWAY_ERROR:
            first_over = h.t
        found = trips(h)
        if found:
            (event,) = found
    assert first_over is not None
    assert event.axis == "X"
    assert abs(event.error) > RUNAWAY_ERROR
    assert first_over - 2 * T <= event.time <= first_over + SERVO_CHECK + 2 * T
    assert ask(h, "?PM") == "hf"
    stopped_at, _ = rp_re(h)
    assert abs(stopped_at) < abs(int(move[2:]))
    h.advance(1.0)
    assert rp_re(h)[0] == stopped_at  # RP stopped changing; MR7 never ran
    assert ask(h, "QA")[1] == "N"  # the ID was flushed: no done
    assert x_queue(h) == 800
    assert trips(h) == []  # one trip, one event
    # HN closes the loop again, bumplessly: the axis is commanded to where its motor is
    h.send("HN;\n")
    assert ask(h, "?PM") == "hn"
    rp, re = rp_re(h)
    assert rp == re


def test_with_the_loop_open_nothing_trips() -> None:
    """HF "will open the loop and turn off the PID": a move runs on the commanded position
    only; the motor is not driven (DZ0), so RE stays where it was, and with no PID there is
    nothing to disable however far RP gets."""
    h = Harness("PCIX-400")
    assert ask(h, "AX;?PM") == "hf"
    h.send("MR100000;GO;ID;\n")
    h.until(2.0)
    assert rp_re(h) == (100_000, 0)
    assert ask(h, "QA")[1] == "D"
    assert ask(h, "?PM") == "hf"
    assert trips(h) == []


def test_hf_after_a_move_leaves_the_motor_where_it_is() -> None:
    h = Harness("PCIX-400")
    h.send("AX;HN;MR1000;GO;\n")
    h.until(1.0)
    assert rp_re(h) == (1000, 1000)
    h.send("HF;MR5000;GO;\n")
    h.until(2.0)
    assert rp_re(h) == (6000, 1000)
    assert trips(h) == []


def test_svi_with_a_normal_motor_runs_away_and_trips() -> None:
    """SVI: "a negative voltage for positive motion". With a motor wired the normal way the
    loop pushes the motor away from the commanded position (positive feedback): RE runs the
    wrong way until the error passes 32768 and the loop opens."""
    h = Harness("PCIX-400")
    h.send("AX;HN;SVI;\n")
    assert ask(h, "?SV") == "svi"
    h.send("MR100000;GO;\n")
    went_wrong = False
    while not (found := trips(h)):
        assert h.t < 2.0, "no trip"
        h.advance(T)
        rp, re = rp_re(h)
        went_wrong = went_wrong or (rp > 0 and re < 0)
    assert went_wrong
    assert found[0].axis == "X"
    assert ask(h, "?PM") == "hf"
    stopped_at, _ = rp_re(h)
    assert 0 < stopped_at < 100_000
    h.advance(0.5)
    assert rp_re(h)[0] == stopped_at


def test_svn_again_follows_normally() -> None:
    h = Harness("PCIX-400")
    h.send("AX;SVI;SVN;HN;MR1000;GO;\n")
    assert ask(h, "?SV") == "svn"
    h.until(1.0)
    assert rp_re(h) == (1000, 1000)
    assert trips(h) == []


# A loop that runs away while holding position (after its move is over, or while its queue waits)
# is reported and its queue flushed, as a trip during a move is.


@pytest.mark.parametrize(
    "commands",
    [
        "AX;HN;SVI;KO100;",  # held at rest, pushed off by KO, then run away by SVI
        "AX;HN;SVI;" + HARD + "MR10;GO;",  # a move short enough to end before the trip
    ],
)
def test_a_trip_while_holding_position_is_reported(commands: str) -> None:
    h = Harness("PCIX-400")
    h.send(commands + "\n")
    assert h.errors() == []
    h.until(1.0)
    rp, re = rp_re(h)
    assert abs(rp - re) > RUNAWAY_ERROR
    assert ask(h, "?PM") == "hf"  # the loop did open ...
    assert [e.axis for e in trips(h)] == ["X"]  # ... and that is reported


def test_a_trip_while_waiting_flushes_the_queue() -> None:
    h = Harness("PCIX-400")
    h.send("AX;HN;SVI;" + HARD + "MR10;GO;WT500;MR1000;GO;\n")
    h.until(2.0)
    assert ask(h, "?PM") == "hf"
    assert rp_re(h)[0] == 10  # the MR1000 behind the WT was flushed with the trip


# -- open loop: DZ; closed loop: KO -----------------------------------------------------------


def drift(dz: int, seconds: float = 0.2, extra: str = "") -> tuple[int, int, int]:
    """RE at 0.1 s and at ``seconds`` after DZ with the loop open, and RP at the end."""
    h = Harness("PCIX-400")
    h.send(f"AX;{extra}DZ{dz};\n")
    assert h.errors() == []
    h.until(0.1)
    _, early = rp_re(h)
    h.until(0.1 + seconds)
    rp, late = rp_re(h)
    assert trips(h) == []
    return early, late, rp


def test_open_loop_with_dz0_the_motor_stays() -> None:
    early, late, rp = drift(0)
    assert (early, late, rp) == (0, 0, 0)


@pytest.mark.parametrize("dz", [3277, -3277, 250])
def test_dz_drives_an_open_loop_motor_in_its_direction(dz: int) -> None:
    """DZ "defines the offset coefficient needed to produce a zero voltage output or stationary
    position", 0.0003 V per count (DZ3277 "near 1VDC", E46 DZ250 "~ +76mV"): with the loop
    open the offset alone drives the motor, in the offset's direction, at the speed the
    simulated amplifier gives that voltage; RP does not move."""
    early, late, rp = drift(dz)
    assert rp == 0
    sign = 1 if dz > 0 else -1
    assert sign * early > 0 and sign * (late - early) > 0
    speed = (late - early) / 0.2
    h = Harness("PCIX-400")
    loop = h.axis("X").servo
    assert loop is not None
    plant = loop.plant
    volts = speed / plant.velocity_per_volt
    assert volts == pytest.approx(dz * VOLTS_PER_COUNT, rel=1e-3, abs=2 / plant.velocity_per_volt)
    if dz == 3277:
        assert volts == pytest.approx(1.0, abs=0.01)  # "near 1VDC"


def test_dz_speed_is_proportional_to_dz() -> None:
    """A velocity-mode amplifier: twice the offset, twice the drift."""
    a_early, a_late, _ = drift(3277)
    b_early, b_late, _ = drift(6554)
    assert b_early == pytest.approx(2 * a_early, abs=2)
    assert b_late - b_early == pytest.approx(2 * (a_late - a_early), abs=2)


def test_dz_is_not_inverted_by_svi() -> None:
    """Choice in servo.py: DZ and KO are offsets at the amplifier input ("used in lieu of the
    balance adjustment on the servo amplifier"), so SVI, which inverts the servo output "for
    positive motion", leaves them as they are."""
    assert drift(3277, extra="SVI;")[:2] == drift(3277)[:2]


def test_dz_does_nothing_with_the_loop_closed() -> None:
    """ "This command affects the offset only when in open-loop mode"."""
    h = Harness("PCIX-400")
    h.send("AX;HN;DZ3277;\n")
    h.until(1.0)
    assert rp_re(h) == (0, 0)


def test_hn_after_a_drift_holds_where_the_motor_is() -> None:
    """Closing the loop on a drifting motor: HN commands the axis to where its motor is (the
    bumpless choice in executor.py) and the loop brings the motor back there and holds it."""
    h = Harness("PCIX-400")
    h.send("AX;DZ3277;\n")
    h.until(0.1)
    h.send("HN;\n")
    held, re = rp_re(h)
    assert held == re > 0
    h.until(2.0)
    assert rp_re(h) == (held, held)
    assert trips(h) == []


@pytest.mark.parametrize("ko", [3000, -3000])
def test_ko_offsets_the_closed_loop_output(ko: int) -> None:
    """KO "is used to set the offset when the loop is closed" (E101 KO-2000 "~ -610mV"). An
    offset the integral (bounded by KU, servo.py) cannot cancel pushes the held motor off RP in
    KO's direction, until KP times the error balances what is left: (KO - KU) / KP counts."""
    h = Harness("PCIX-400")
    h.send(f"AX;HN;KO{ko};\n")
    h.until(3.0)
    rp, re = rp_re(h)
    sign = 1 if ko > 0 else -1
    assert rp == 0
    assert re == sign * (abs(ko) - 200) / 10  # KU200, KP10
    assert ask(h, "?PM") == "hn"
    assert trips(h) == []


def test_ko_within_ku_is_cancelled_by_the_integral() -> None:
    h = Harness("PCIX-400")
    h.send("AX;HN;KO100;\n")
    h.until(0.05)
    assert rp_re(h)[1] > 0  # pushed off first
    h.until(5.0)
    assert rp_re(h) == (0, 0)


def test_ko_does_nothing_with_the_loop_open() -> None:
    early, late, rp = drift(0, extra="KO3000;")
    assert (early, late, rp) == (0, 0, 0)


# -- BI / UN ----------------------------------------------------------------------------------


def test_un_changes_the_reported_output_mode_not_the_motion() -> None:
    """UN: "0.0VDC and +10VDC ... To maintain position the board outputs 5VDC"; ?SO answers
    ``un`` (E183). The simulated amplifier is set up to match, so the motor moves the same."""
    h = Harness("PCIX-400")
    assert ask(h, "AX;?SO") == "bi"
    h.send("UN;\n")
    assert ask(h, "?SO") == "un"
    assert ask(h, "AY;?SO") == "bi"
    h.send("AX;BI;\n")
    assert ask(h, "AX;?SO") == "bi"
    bipolar = step("", 300, seconds=0.1)
    unipolar = step("UN;", 300, seconds=0.1)
    assert (unipolar.rp, unipolar.re) == (bipolar.rp, bipolar.re)
