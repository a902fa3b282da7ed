"""The encoder option (PC48 chapter 5 and §6.15–§6.19): ratio, slip and stall detection,
position hold, tracking and encoder home, on the simulated encoder."""

from __future__ import annotations

import pytest

from omsd.board.events import SlipEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import DON_S, ENC_S


def test_encoder_follows_the_motor_one_to_one(pc48e: Harness) -> None:
    pc48e.send("AX MR12345 GO")
    pc48e.run()
    assert pc48e.query("RP RE") == b"\n\r12345\n\r\n\r12345\n\r"


def test_encoder_ratio_scales_moves_into_encoder_counts(pc48e: Harness) -> None:
    """§6.15 ER: "All distance, velocity and acceleration parameters are input in encoder counts
    when this mode is enabled. The correct number of motor counts are generated"."""
    pc48e.send("AX ER1,2 MR100 GO")
    pc48e.run()
    assert pc48e.query("RP RE") == b"\n\r200\n\r\n\r100\n\r"


def test_slip_beyond_tolerance_is_flagged_once(pc48e: Harness) -> None:
    """§6.16: ES "specifies tolerance before slip or stall is flagged in the status register and
    by the RL command"; IS: "If a slip occurs, slip detection must be re-enabled"."""
    b = pc48e.board
    pc48e.send("AZ ES5 IS ")
    pc48e.run()
    b.inject_slip("Z", 5, pc48e.t)
    pc48e.advance(0.01)
    assert not [e for e in pc48e.events() if isinstance(e, SlipEvent)]
    b.inject_slip("Z", 3, pc48e.t)
    pc48e.advance(0.01)
    slips = [e for e in pc48e.events() if isinstance(e, SlipEvent)]
    assert [e.axis for e in slips] == ["Z"]
    assert b.read_status_register(pc48e.t) & (ENC_S | DON_S) == ENC_S | DON_S
    assert pc48e.query("RL") == b"\n\rNNSN\n\r"
    # detection is now off: a further slip is not flagged
    b.inject_slip("Z", 50, pc48e.t)
    pc48e.advance(0.01)
    assert not [e for e in pc48e.events() if isinstance(e, SlipEvent)]
    # EA shows the slip once: "Slip or stall detected (reset by execution of EA command)"
    assert pc48e.query("EA") == b"\n\r\rDDSNNN\n\r\r"
    assert pc48e.query("EA") == b"\n\r\rDDNNNN\n\r\r"


def test_stall_during_a_move_is_detected_as_the_error_grows(pc48e: Harness) -> None:
    b = pc48e.board
    pc48e.send("AX VL1000 ES10 IS MR1000 GO ")
    pc48e.advance(0.1)  # 100 steps out
    b.set_stall("X", True, pc48e.t)
    at = pc48e.t
    pc48e.advance(0.1)
    (slip,) = [e for e in pc48e.events() if isinstance(e, SlipEvent)]
    # the encoder stopped at ~100; the error passes 10 counts ~10 ms later (1000 steps/s)
    assert slip.time - at == pytest.approx(0.011, abs=0.002)
    # the encoder stays where the carriage stopped while the pulses count on
    assert int(pc48e.query("RE").strip()) == pytest.approx(100, abs=1)
    assert int(pc48e.query("RP").strip()) == pytest.approx(200, abs=1)


def test_position_hold_corrects_a_slip_within_the_deadband(pc48e: Harness) -> None:
    """§6.15 HN: "that position is maintained within the 10 step deadband until commanded to a
    new position" (E92 parameters)."""
    b = pc48e.board
    pc48e.send("AX VL100000 AC500000 HV50000 HD10 HG2000 HN MR200000 GO ")
    pc48e.run()
    assert pc48e.query("RE") == b"\n\r200000\n\r"
    b.inject_slip("X", -300, pc48e.t)
    assert pc48e.query("RE") == b"\n\r199700\n\r"
    pc48e.run()
    encoder = int(pc48e.query("RE").strip())
    assert abs(encoder - 200000) <= 10
    # the position counter absorbed the correction
    assert int(pc48e.query("RP").strip()) == pytest.approx(200300, abs=10)
    assert pc48e.query("EA") == b"\n\r\rDEN" + b"PNN\n\r\r"


def test_ip_waits_for_the_deadband(pc48e: Harness) -> None:
    """§6.12 IP: "the interrupt is deferred until the stage is within the specified deadband"."""
    b = pc48e.board
    pc48e.send("AX HV1000 HG100 HD10 HN ")
    pc48e.run()
    b.set_stall("X", True, pc48e.t)
    pc48e.send("MR1000 GO IP")
    pc48e.advance(0.001)
    b.set_stall("X", False, pc48e.t)  # the encoder stayed behind by about one step
    b.inject_slip("X", -200, pc48e.t)
    pc48e.until(2.0)
    assert b.registers.done == 0b1  # done only once the correction brought it within 10
    encoder = int(pc48e.query("RE").strip())
    assert abs(encoder - 1000) <= 10


def test_ip_without_hold_acts_like_id(pc48e: Harness) -> None:
    pc48e.send("AX MR100 GO IP")
    pc48e.run()
    assert pc48e.board.registers.done == 0b1


def test_hf_turns_hold_and_slip_detection_off(pc48e: Harness) -> None:
    pc48e.send("AX HV1000 HG10 HN ES1 IS ")
    pc48e.run()
    assert pc48e.query("EA") == b"\n\r\rEEN" + b"PNN\n\r\r"
    pc48e.send("HF")
    pc48e.run()
    assert pc48e.query("EA") == b"\n\r\rDDNNNN\n\r\r"


@pytest.mark.parametrize("command", ["LP0 ", "ST", "KL"])
def test_load_position_stop_and_kill_disable_hold_and_slip(pc48e: Harness, command: str) -> None:
    """§6.15 HN: "Hold and slip detection are disabled if an LP, HM, HR, SA, ST or KL command is
    entered or if a limit is encountered." """
    pc48e.send("AX HV1000 HG10 HN ES1 IS ")
    pc48e.run()
    pc48e.send(command)
    pc48e.run()
    assert pc48e.query("AX EA")[3:5] == b"DD"


def test_tracking_follows_the_encoder_input(pc48e: Harness) -> None:
    """§6.17 ET: "The axis will duplicate the encoder input. The ER command allows the user to
    scale the motor's movements relative to the encoder." """
    pc48e.send("AX ER1,4 ET ")
    pc48e.run()
    pc48e.board.set_encoder_input("X", 250, pc48e.t)
    assert pc48e.query("RE RP") == b"\n\r250\n\r\n\r1000\n\r"


def test_encoder_home_uses_the_index_inside_the_home_window() -> None:
    """§6.18 HE: home is "the logical AND of the encoder index, the external home enable and the
    encoder quadrant"; with HS (default) the home switch alone."""
    world = {
        "X": AxisWorld(home_low=3990, home_high=4100, encoder_counts_per_rev=4000, encoder_index=0)
    }
    h = Harness("PC48-4E", world=world)
    h.send("AX VL1000 HE HM0 ")
    h.run()
    # the index at encoder count 4000 is inside the window; home found there, then the axis
    # decelerates from 1000 steps/s at AC 1,000,000 (0.5 step)
    assert h.axis("X").phys(h.t) == pytest.approx(4000, abs=1.5)
    assert abs(h.position("X")) <= 1
    h2 = Harness("PC48-4E", world=world)
    h2.send("AX VL1000 HS HM0 ")
    h2.run()
    assert h2.axis("X").phys(h2.t) == pytest.approx(3990, abs=1.5)


def test_encoder_commands_are_errors_without_an_encoder() -> None:
    h = Harness("PC48-6E")  # encoders on X and Y only
    h.send("AZ ER1,1 ")
    assert [e.kind.name for e in h.errors()] == ["NO_ENCODER"]
    h.send("AY ER1,1 ")
    assert h.errors() == []
