"""Second review of the omsMAXnet client on the PCIx: the sequences a motor record runs.

EPICS ``motorOmsAsyn`` (``omsBaseAxis.cpp``) sends, for each motor-record action, one line:

* move: ``"A%1c AC%d; VB%d; VL%d; %s%d; GO ID"`` (MA or MR);
* home: ``"A%1c AC%d; VL%d; %s; MA0 GO ID"`` (HM forwards, HR reverse, no parameter);
* jog and a jog changed in flight: ``"A%1c AC%d; JG%d;"``;
* stop: ``"A%1c AC%d; ST ID;"``;

and polls ``AM;RI;``, ``AM PP;``, ``AM PE;`` (when an axis has an encoder), ``AM;RV;``, ``AM;EA;``,
``AM;QL;`` (and ``AM;CL?;`` / ``?PM``, ``#WS``) every 0.2 s while anything moves
(``omsBaseController::omsPoller``). The earlier reviews (``test_omsmaxnet_trace.py``,
``test_reviewed_epics.py``, ``test_reviewed_max_family.py``) hold the poll's framing and shapes,
a move, HM0/HR0 with ID and a jog ended by ST or KL. This file holds what they did not drive:
the client's own lines (VB before VL, ``HM;`` without a parameter followed by ``MA0 GO ID``, an AC
in the stop line), a stop in the middle of a move and of a home search, a jog reversed while it
runs, a move and a jog into a limit and back out of it, a home search that ends in a limit, a
servo's loop opened by a limit, and EA's slip letter. Every reply is read as the client reads it
(five characters per RI field, ``RI[i*5+1] == 'D'``, ``+2 == 'L'``, ``+3 == 'H'``; QL's bit ``i``
low limit and ``i + 8`` high limit, exclusive-or'ed with "LT? said =l"; EA's third character
``S``).

All but the last test passed when the file was written: omsd already did what the PCIx manual
says there, and they pin the answers so that a later change shows. The last one found that
closing a servo's loop (HN, which the client sends before each move) after the commanded position
had run on with the loop open (the client's jog and home do not close it) left the limit and home
switches that far from the motor for good (``docs/decisions.md``, "The PCIx", "Servo").
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness
from omsd.engine.world import AxisWorld

from .max_client import Poll, poll, receive

# negative limit at -500, positive at 3000, home switch 1000..1100 (the default window)
STAGE = AxisWorld(negative_limit=-500, positive_limit=3000)
# the same stage with its home switch out of the way of the stops
FAR_HOME = AxisWorld(negative_limit=-500, positive_limit=30_000, home_low=50_000, home_high=50_100)
KINDS = ["PCIX-004", "PCIX-040", "PCIX-400"]  # open-loop stepper, stepper + encoder, servo


def board(model: str, stage: AxisWorld = STAGE) -> Harness:
    h = Harness(model, world=[stage] * 4)
    for line in ("WY\n", "IC;\n", "AM SA;\n", "AX LH PSO; AY LH PSO;\n"):
        h.send(line)
    return h


def x_limits(p: Poll) -> tuple[bool, bool]:
    """QL as the client decodes it for X, which the init line made active high (LT? =h)."""
    return p.limits(0)


def polls_until_done(h: Harness, limit: float = 20.0) -> tuple[list[Poll], Poll]:
    """Poll every 0.2 s until X's RI field shows D; the polls before it and the one with D."""
    before = []
    end = h.t + limit
    while h.t < end:
        h.advance(0.2)
        p = poll(h)
        if p.RI[0][1] == "D":
            return before, p
        before.append(p)
    raise AssertionError("no D in RI")


# -- stops ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", KINDS)
def test_stop_in_a_move_ramps_down_at_the_ac_in_force(model: str) -> None:
    """``AX AC200000; ST ID;`` during a move at AC2000 (at speed 1000 from 0.5 s, at 750 at
    1 s). AC is queued ("AC#; ... 6") behind the running move; ST "flushes the queue for the
    current axis ... and causes the axis ... to decelerate to a stop at the rate previously
    specified via the AC command" (PCIx ST): the ramp down is the move's AC, 0.5 s and 250 steps,
    the new AC is flushed with the queue, and ID, after ST, sets the done flag at the stop."""
    h = board(model, FAR_HOME)
    h.send("AX AC2000; VB0; VL1000; MR5000; GO ID\n")
    h.advance(1.0)
    h.send("AX AC200000; ST ID;\n")
    before, done = polls_until_done(h)
    assert before and all(p.RV[0] > 0 and p.RI[0][1] == "N" for p in before)
    assert done.RI[0] == "PDNN" and done.RV[0] == 0
    assert abs(done.PP[0] - 1000) <= 2, done
    assert receive(h, "AX ?AC") == "ac2000"
    assert poll(h).RI[0] == "PNNN"  # RI reset the done flag


def test_stop_in_a_jog_at_speed_takes_the_ac_of_its_line() -> None:
    """A jog at speed has left its queue ("Output events waiting for completion of JG will begin
    when JG is up to its requested velocity"), so the stop line's AC runs before the ST: the axis
    stops within a few milliseconds at AC200000, the done flag follows."""
    h = board("PCIX-004")
    h.send("AX AC2000; JG1000;\n")
    h.advance(1.0)
    h.send("AX AC200000; ST ID;\n")
    h.advance(0.01)
    p = poll(h)
    assert p.RI[0] == "PDNN" and p.RV[0] == 0, p
    assert receive(h, "AX ?AC") == "ac200000"


@pytest.mark.parametrize("model", KINDS)
def test_stop_during_the_home_search_flushes_the_return_and_sets_done(model: str) -> None:
    """``AX AC20000; VL500; HM; MA0 GO ID`` stopped at 0.5 s (position 243) by ``AC200000; ST
    ID;``: the search ramps down, "MA0 GO ID" is flushed with the queue, the stop's ID sets D,
    and no home was found (position as counted, H not shown)."""
    h = board(model)
    if model == "PCIX-400":
        h.send("AX HN\n")
    h.send("AX AC20000; VL500; HM; MA0 GO ID\n")
    h.advance(0.5)
    assert poll(h).RV[0] == 500
    h.send("AX AC200000; ST ID;\n")
    _, done = polls_until_done(h)
    assert done.RI[0] == "PDNN" and done.RV[0] == 0
    assert 243 <= done.PP[0] <= 260, done
    h.advance(1.0)
    assert poll(h).PP[0] == done.PP[0]  # nothing left in the queue to move it


# -- jogs -----------------------------------------------------------------------------------------


def test_jog_reversed_in_flight_ramps_through_zero_at_the_new_ac() -> None:
    """JG: "A change in direction between two JG commands will cause an axis to ramp to a stop then
    back up in the opposite direction"; the second line's AC runs first (the first jog is at
    speed), so 1000 to -1000 takes 0.1 s at AC20000. RI keeps N throughout (no ID), the direction
    letter follows the motion, and the stop's ID gives D."""
    h = board("PCIX-004")
    h.send("AX AC2000; JG1000;\n")
    h.advance(1.0)
    h.send("AX AC20000; JG-1000;\n")
    h.advance(0.02)
    p = poll(h)
    assert p.RI[0] == "PNNN" and 0 < p.RV[0] < 1000, p
    h.advance(0.06)
    p = poll(h)
    assert p.RI[0] == "MNNN" and -1000 < p.RV[0] < 0, p
    h.advance(0.1)
    p = poll(h)
    assert p.RI[0] == "MNNN" and p.RV[0] == -1000, p
    h.send("AX AC2000; ST ID;\n")
    before, done = polls_until_done(h)
    assert all(q.RV[0] < 0 for q in before)
    assert done.RI[0] == "MDNN"


# -- limits ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", KINDS)
def test_move_into_the_low_limit_then_out_of_it(model: str) -> None:
    """PCIx §5.5.4: "When a limit is encountered, the axis involved will cease motion and flush
    any pending motion commands for that axis". The client reads the end from RV 0 with ``L``
    (``statusBuffer[i*5+2] == 'L'``, direction M: the low limit), QL shows X's low input. A move
    or jog further in does not move; the stop's ID then shows D with the L; a move back out runs
    (RI N again, QL clear) and sets D at its end."""
    h = board(model)
    if model == "PCIX-400":
        h.send("AX HN\n")  # the client's move closes a servo's loop first
    h.send("AX AC20000; VB0; VL2000; MA-2000; GO ID\n")
    h.advance(0.15)
    p = poll(h)
    assert p.RI[0] == "MNNN" and p.RV[0] < 0
    h.advance(1.0)
    p = poll(h)
    assert p.RI[0] == "MNLN" and p.RV[0] == 0 and p.PP[0] == -500, p
    assert x_limits(p) == (True, False)
    for _ in range(5):  # never a D for the flushed ID
        h.advance(0.2)
        assert poll(h).RI[0] == "MNLN"
    h.send("AX AC20000; VB0; VL2000; MA-3000; GO ID\n")
    h.send("AX AC2000; JG-1000;\n")
    h.advance(0.2)
    p = poll(h)
    assert p.RI[0] == "MNLN" and p.RV[0] == 0 and p.PP[0] in (-500, -503), p
    h.send("AX AC2000; ST ID;\n")
    h.advance(0.2)
    assert poll(h).RI[0] == "MDLN"
    if model == "PCIX-400":
        h.send("AX HN\n")  # the client's move closes the servo loop the limit opened
    h.send("AX AC20000; VB0; VL2000; MA0; GO ID\n")
    h.advance(0.2)
    p = poll(h)
    assert p.RI[0] == "PNNN" and p.RV[0] > 0 and x_limits(p) == (False, False), p
    _, done = polls_until_done(h)
    assert done.RI[0] == "PDNN" and done.PP[0] == 0


def test_a_limit_opens_a_servo_loop_and_the_client_sees_it() -> None:
    """HN: "For servo axes, this mode is disabled when the HF command is entered, when the servo
    error becomes too large or a limit is encountered." After the limit, CL? says ``off``, EA's
    second letter ``D`` and ``?PM`` (asked by the client of firmware below 1.30) ``hf``; the
    client's next move sends HN (omsBaseAxis::move: "servo motor, closed loop NOT enabled,
    enable now"), which closes it again."""
    h = board("PCIX-400")
    h.send("AX HN\n")
    h.advance(0.1)
    p = poll(h)
    assert p.CL[0] == "on" and p.EA[0][:2] == "DE"
    h.send("AX AC20000; VB0; VL2000; MA-2000; GO ID\n")
    h.advance(1.5)
    p = poll(h)
    assert p.RI[0] == "MNLN" and p.CL[0] == "off" and p.EA[0][:2] == "DD", p
    assert receive(h, "AX ?PM") == "hf"
    h.send("AX HN\n")
    h.advance(0.1)
    assert poll(h).CL[0] == "on"
    assert receive(h, "AX ?PM") == "hn"


# -- homes ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("model", KINDS)
def test_the_clients_home_line_finds_home_and_returns_to_it(model: str) -> None:
    """``HM;``: "If no parameter is specified in single axis modes, the HM command will use zero
    as a default value"; the axis "will ramp to a stop ... beyond the home switch" and "The axis
    can be easily returned to the precise home position by using an MA command after the HM
    command": the client's ``MA0 GO ID``. RV is the search velocity while RI shows N; the first
    RI with D has H (home switch active), the position is 0 on the counter and, on an axis with
    an encoder, on the encoder (HR: "the position and encoder counters are loaded"), and EA's
    fifth letter is P ("Encoder is at home condition")."""
    h = board(model)
    if model == "PCIX-400":
        h.send("AX HN\n")
    h.send("AX AC20000; VL500; HM; MA0 GO ID\n")
    before, done = polls_until_done(h)
    assert before and all(p.RV[0] != 0 and p.RI[0][1] == "N" for p in before)
    assert all(p.RV[0] == 500 for p in before[:5])
    assert done.RI[0][1:] == "DNH" and done.RV[0] == 0 and done.PP[0] == 0, done
    if model != "PCIX-004":  # a servo settles within counts of its commanded position
        assert abs(done.PE[0]) <= 3 and done.EA[0][4] == "P", done
    assert poll(h).RI[0][1:] == "NNH"


@pytest.mark.parametrize("model", KINDS)
def test_a_home_search_past_the_switch_ends_in_the_limit_then_hr_finds_home(model: str) -> None:
    """From 2000 (beyond the switch at 1000..1100) HM runs on to the positive limit at 3000: RI
    ``PNLN`` with RV 0 and never a D (the limit flushes ``MA0 GO ID``), QL X's high input: the
    client ends the home on the high limit. ``HR; MA0 GO ID`` from there finds home coming down
    (the switch turns true at its upper edge) and returns to it: D with H, position 0."""
    h = board(model)
    if model == "PCIX-400":
        h.send("AX HN\n")
    h.send("AX AC20000; VB0; VL5000; MA2000; GO ID\n")
    polls_until_done(h)
    if model == "PCIX-400":
        h.send("AX HN\n")
    h.send("AX AC20000; VL500; HM; MA0 GO ID\n")
    h.advance(2.5)
    p = poll(h)
    assert p.RI[0] == "PNLN" and p.RV[0] == 0 and p.PP[0] == 3000, p
    assert x_limits(p) == (False, True)
    h.advance(1.0)
    assert poll(h).RI[0] == "PNLN"
    if model == "PCIX-400":
        h.send("AX HN\n")
    h.send("AX AC20000; VL500; HR; MA0 GO ID\n")
    before, done = polls_until_done(h)
    assert all(q.RV[0] == -500 for q in before[2:-2])
    assert done.RI[0][1:] == "DNH" and done.PP[0] == 0, done


# -- encoder status -------------------------------------------------------------------------------


def test_ea_reports_a_slip_once_and_the_poll_resets_it() -> None:
    """EA's third letter: "S Slip or stall detected (reset by execution of EA command)"; the client
    reads it as a following error (``encBuffer[2] == 'S'``). A stall of X (PCIX-040, IS on)
    during a move shows S in the next poll's EA and N in the one after; IS does not stop the move
    ("enables the PC1x to interrupt the host on slip or stall detection"), whose ID sets D."""
    h = board("PCIX-040")
    h.send("AX IS; ES10;\n")
    h.advance(0.01)
    assert poll(h).EA[0] == "EDNNN"
    h.send("AX AC20000; VB0; VL2000; MA4000; GO ID\n")
    h.advance(0.3)
    h.board.set_stall("X", True, h.t)
    h.advance(0.2)
    p = poll(h)
    assert p.EA[0][2] == "S" and p.RV[0] == 2000 and p.RI[0] == "PNNN", p
    h.advance(0.2)
    assert poll(h).EA[0][2] == "N"
    _, done = polls_until_done(h)
    assert done.PP[0] == 4000 and done.PE[0] < 4000


# -- a servo's loop closed after motion with it open ----------------------------------------------


@pytest.mark.parametrize(
    "line",
    [b"AX AC20000; VB0; VL5000; MA1050; GO ID\n", b"AX AC20000; VL500; HM; MA0 GO ID\n"],
)
def test_closing_a_servo_loop_keeps_the_switches_where_the_motor_is(line: bytes) -> None:
    """A PCIX-400 powers up with its loops open (HF: "This is the default mode at power up or
    reset"; "open the loop and turn off the PID"). omsMAXnet's jog (``"A%1c AC%d; JG%d;"``) and
    home do not close the loop, its move does (``"A? HN"`` first). A jog and a stop with the loop
    open run the commanded position (RP, "the motor's commanded position") to 2500 while the
    motor, undriven, stays at RE 0 ("the motor's actual position"). HN then commands the motor
    to hold where it is: RP becomes 0 with RE. The switches are on the stage, which is where the
    motor is: the home switch (1000..1100 from power-up) is at RE 1000 as before, so a move to
    1050 ends on it (RI ``H``) and a home search from 0 finds it 1000 counts on.

    Until this review HN kept the switches where the commanded position had been (2500) and
    gave that place the motor's count: the stage read 2500 counts beyond its encoder for good,
    the move to 1050 ended at ``PDNN`` and the home search ran on towards the far limit."""
    h = Harness("PCIX-400")
    h.send("AX AC20000; JG5000;\n")
    h.advance(0.5)
    h.send("AX AC20000; ST ID;\n")
    h.advance(0.5)
    assert receive(h, "AX RP") == "2500" and receive(h, "AX RE") == "0"
    assert receive(h, "AM;RI;")[:4] == "PDNN"
    h.send("AX HN\n")
    assert receive(h, "AX RP") == "0" and receive(h, "AX RE") == "0"
    h.send(line)
    _, done = polls_until_done(h, limit=10.0)
    assert done.RI[0] in ("PDNH", "MDNH"), done
    target = 1050 if b"MA1050" in line else 0
    assert done.PP[0] == target and abs(done.PE[0] - target) <= 3, done
