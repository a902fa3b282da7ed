"""The PC48 family (PC48, VS4, PC46) where a review against the manuals (2026-11-28) found small
gaps, each pinned with the manual's words.

* HH and HL are a command error in the encoder home mode: "The external enable is low true,
  i.e. the HH and HL commands are not valid in this mode" (PC48 §6.18 HE; the VS4's HE the
  same). They were accepted silently.
* HM and HR load the position counter only, on a board with encoders too (kept, now pinned):
  "The position counter will be initialized to the position supplied as a parameter" (§6.11),
  where LP names both registers.
* RC between the end of a profile and the sample tick that makes the axis idle (up to one
  sample) is the stopped stage's, "the acceleration at the beginning of a ramp" (§6.13), as
  before the end and after that tick; it was 0.
* KM and KR leave position hold and slip detection on: "Hold and slip detection are disabled
  if an LP, HM, HR, SA, ST or KL command is entered or if a limit is encountered" (§6.15 HN,
  §6.16 IS) names neither, and their own pages say nothing of it. They switched both off.
"""

from __future__ import annotations

import pytest

from omsd.board import Board
from omsd.board.events import ErrorKind, SlipEvent
from omsd.board.harness import Harness
from omsd.link import DriverLink
from omsd.models import get_model

from .support import frame, number, status_frame


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PC46-2E"])
@pytest.mark.parametrize("level", ["HH", "HL"])
def test_hh_and_hl_are_not_valid_in_the_encoder_home_mode(model: str, level: str) -> None:
    """PC48 §6.18 HE: "Home is defined as the logical AND of the encoder index, the external
    home enable and the encoder quadrant ... The external enable is low true, i.e. the HH and HL
    commands are not valid in this mode." (the VS4's HE: the same words; the PC46 datasheet,
    silent, behaves as the PC48). A command error, as every command "Not valid" in a mode; the
    level is left as it was. HS (the switch mode, whose level "may be controlled by the HH and
    HL commands") makes them valid again."""
    h = Harness(model)
    h.send(f"AX HE {level} ")
    assert [(e.kind, e.command) for e in h.errors()] == [(ErrorKind.NOT_VALID_IN_MODE, level)]
    h.until(0.01)
    assert h.axis("X").home_high is False  # the power-up level (HL), untouched
    h.send("HS HH ")
    h.until(0.02)
    assert h.errors() == []
    assert h.axis("X").home_high is True


def test_hh_in_the_encoder_home_mode_is_a_hash_through_the_driver() -> None:
    """§7.3.3: "When a command error occurs it places a # symbol followed by the "E:" specified
    end character"."""
    link = DriverLink(Board(get_model("PC48-4E"), 0.0))
    link.from_host(b"AX HE HH WY", 0.0)
    assert link.to_host(0.0).data == b"#\nPC48 ver 3.00-4\n"


@pytest.mark.parametrize("model", ["PC48-4E", "VS4-040", "PC46-2E"])
def test_a_home_loads_the_position_counter_and_leaves_the_encoder(model: str) -> None:
    """PC48 §6.11 HM: "The position counter will be initialized to the position supplied as a
    parameter ... The axis will not stop at home, but will initialize the position counter when
    the home switch becomes true"; HR "behaves exactly like the HM command" (the VS4's HM/HR and
    the PC46 datasheet: "initialize the position counter" too). LP, by contrast, names both: "In
    models with the encoder option, the parameter will be loaded into the encoder position
    register and the parameter times the encoder ratio will be loaded into the position
    counter" (§6.7). So the encoder (RE) keeps counting the carriage through a home (the
    PCIx's HR, "the position and encoder counters are loaded", is another board), and position
    maintenance afterwards holds the counter's position, with no correction toward RE = RP."""
    h = Harness(model)
    h.send("AX VL1000 LP-200 HM0 ")  # the encoder is 200 behind the carriage; home at 1000
    h.until(5.0)
    assert number(h.send("RP")) == 0
    re = number(h.send("RE"))
    assert re in (800, 801)  # where the home's deceleration left the carriage, less 200: not 0
    h.send("HV1000 HG10 HN ")
    h.until(8.0)
    assert (number(h.send("RP")), number(h.send("RE"))) == (0, re)  # nothing to correct
    h.send("HF MA3000 GO ")
    h.until(15.0)
    h.send("HR7 ")  # down into the window from above: its top step, 1099
    h.until(25.0)
    assert number(h.send("RP")) == 7
    assert number(h.send("RE")) in (899, 900)  # the carriage's count, 200 behind: not 7


@pytest.mark.parametrize("model", ["PC48-4", "VS4-040"])
@pytest.mark.parametrize("ramp", ["", "PN "])
def test_rc_after_the_profile_ends_is_the_stopped_stages(model: str, ramp: str) -> None:
    """PC48 §6.13 RC (the VS4's the same): "When the stage is stopped, the parameter returned
    will be the acceleration at the beginning of a ramp." A move's profile ends between two
    sample ticks; until the next tick the axis is not yet idle, but the stage is stopped (RP
    reads the end, RV 0). RC read 0 there, for up to one sample, while just before the end
    (the end of the ramp down, where the deceleration is the beginning of the ramp's, "the same
    in reverse") and from the tick on it reads AC; a poll then sees AC throughout."""
    h = Harness(model)
    h.send(f"{ramp}AX VL1000 AC10000 MR1000 GO ")
    axis = h.axis("X")
    end = axis.traj.end_time
    rate = get_model(model).sample_rate
    assert end * rate != int(end * rate), "precondition: the end falls between two ticks"
    h.until(end + 1e-6)
    assert axis.motion.name != "IDLE", "precondition: before the done tick"
    assert h.send("RP RV") == frame("1000") + frame("0")
    assert h.send("RC") == frame("10000")
    h.until(end + 1.0 / rate)
    assert axis.motion.name == "IDLE"
    assert h.send("RC") == frame("10000")


KILL_HOME_MODELS = ["PC48-4E", "VS4-040", "PC46-2E"]


@pytest.mark.parametrize("model", KILL_HOME_MODELS)
def test_km_and_kr_leave_hold_and_slip_detection_on(model: str) -> None:
    """PC48 §6.15 HN and §6.16 IS (the VS4's the same words): "Hold and slip detection are
    disabled if an LP, HM, HR, SA, ST or KL command is entered or if a limit is encountered."
    KM ("will find home and stop generating pulses immediately ... The position counter is not
    cleared or reset") and KR are not in the list, and their pages say nothing of hold or slip.
    EA: char 4 "E Slip detection enabled", char 5 "E Position maintenance enabled", char 7 "P
    Position Maintenance within deadband". What is held after a KM is where it stopped the
    pulses, not where the axis was held before it. HM, in the list, still switches both off."""
    h = Harness(model)
    h.send("AX VL1000 HV1000 HG10 HN IS KM ")  # from 0 to the home switch at 1000
    h.until(3.0)
    assert h.send("EA") == status_frame("EENPHN")
    h.until(6.0)
    assert (number(h.send("RP")), number(h.send("RE"))) == (1000, 1000)  # held there, not at 0
    h.send("MR500 GO ")
    h.until(8.0)
    h.send("KR ")  # down to the top of the window (1099 from above)
    h.until(12.0)
    assert h.send("EA") == status_frame("EENPHN")
    assert h.errors() == []
    h.send("HM ")
    h.until(20.0)
    assert h.send("EA")[:5] == b"\n\r\rDD"


@pytest.mark.parametrize("model", KILL_HOME_MODELS)
def test_a_kill_home_leaving_the_home_window_is_no_slip(model: str) -> None:
    """Slip detection on through a KR that starts inside the home window (the look at the
    window's edge, mid-step): no slip at the power-up tolerance of 0, as in a move (ES: "the
    tolerance before slip or stall is flagged"); detection stays on ("If a slip occurs, slip
    detection must be re-enabled": none occurred)."""
    h = Harness(model)
    h.send("AX VL1000 MA1000 GO ")
    h.until(5.0)
    h.send("IS KR ")  # away from home below: it runs on
    h.until(8.0)
    assert h.send("EA") == status_frame("EDNNNN")
    assert not [e for e in h.events() if isinstance(e, SlipEvent)]


def test_a_stall_during_a_kill_home_is_flagged() -> None:
    """IS: "enables the PC48 to interrupt the host on slip or stall detection"; through a KM
    too, now that it leaves detection on."""
    h = Harness("PC48-4E")
    h.send("AX VL1000 ES10 IS KM ")
    h.until(0.5)
    h.board.set_stall("X", True, h.t)
    at = h.t
    h.until(1.0)
    (slip,) = [e for e in h.events() if isinstance(e, SlipEvent)]
    assert slip.time - at == pytest.approx(0.011, abs=0.002)  # 10 counts at 1000 steps/s
    assert h.send("EA") == status_frame("DDSNNN")
