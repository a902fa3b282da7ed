"""AM tasks, power automatic and settling time, where a review against the manuals found omsd
wrong (2026-11-27).

* WT, SW, BL and BH in AM wait for the axes of the task only, as an AM GO, ID and CX already
  did. The WT page: "In the AA mode, all axes will wait" (PC48 §6.12; the VS4's and the PCIx's
  the same), naming AA alone; AM "allows several tasks to be managed simultaneously. For
  instance, a task may be performing coordination motion on 2 axes, while a second task is
  performing unrelated but simultaneous motion on another axis" (PC48 §6.4). They used to wait
  for every axis, so an X task's `WT100` waited for an unrelated Z task's 5 s move to end.
* A move in power-automatic mode stopped by a kill (KL, Control-D, the PCIx's KS) puts the
  auxiliary output back to its idle state, as a move's end does: PA turns it on "upon the
  execution of the GO or GD and off at the end of that move" (PC48 §6.6); the PCIx: "the
  auxiliary line will invert at the beginning of every motion and return to normal at the end".
  With SE the settling time comes first ("to be used before the power is reduced"); a settling
  time under way when the kill comes runs on. The output stayed in its moving state for good.
* SE's 3 slots are charged on every GO and GD once a settling time is given, PA or not: "The use
  of this command requires 3 queue slots with the execution of each GO or GD command" (PC48 and
  VS4 §6.6 SE). They were charged only while PA was on.
"""

from __future__ import annotations

import pytest

from omsd.board.harness import Harness

from .support import frame, number

# X, Y, Z, T at 1000 steps/s and 10,000 steps/s²: a 1000-step move takes 1.1 s (0.1 s ramps)
SETUP = ["AA", "VL1000,1000,1000,1000;", "AC10000,10000,10000,10000;"]
MODELS = [("PC48-4", " "), ("VS4-040", " "), ("PCIX-004", ";")]


def _two_tasks(model: str, sep: str, between: str) -> Harness:
    """A Z task on a 5 s move, then an X task: ``MR1000; GO <between> MR1000; GO``."""
    h = Harness(model)
    cmds = [*SETUP, "AM", "MR,,5000;", "GO", "MR1000;", "GO", between, "MR1000;", "GO", ""]
    h.send(sep.join(cmds))
    return h


@pytest.mark.parametrize(("model", "sep"), MODELS)
@pytest.mark.parametrize("between", ["WT100", "SW0"])
def test_an_am_wait_holds_its_own_task_only(model: str, sep: str, between: str) -> None:
    """WT: "In the AA mode, all axes will wait" (AA named, not AM); SW: "causes the axes to wait
    until the general purpose input line has been released" (input 0 is released here). X's
    first move ends at 1.1 s, the WT ends at 1.2 s, the second move at 2.3 s; Z's move (5 s)
    runs on untouched. Before, X's second move waited for Z: X was still at 1000 at 3 s."""
    h = _two_tasks(model, sep, between)
    h.until(3.0)
    assert h.position("X") == 2000
    assert 2900 < h.position("Z") < 5000
    h.run()
    assert (h.position("X"), h.position("Z")) == (2000, 5000)
    assert h.errors() == []


def test_an_am_wt_lasts_its_time_from_the_task_s_arrival() -> None:
    """The X task's WT100 starts when X gets there (1.1 s) and the next move 0.1 s later."""
    h = _two_tasks("PC48-4", " ", "WT100")
    h.until(1.19)
    assert h.position("X") == 1000
    h.until(1.25)
    assert h.position("X") > 1000


@pytest.mark.parametrize(("model", "sep"), MODELS)
def test_an_aa_wt_still_holds_every_axis(model: str, sep: str) -> None:
    """In AA the WT is a meeting of every axis ("all axes will wait"), as before: an AA WT
    between the AM tasks' moves holds X's second move until 0.1 s after Z's has ended."""
    h = _two_tasks(model, sep, sep.join(["AA", "WT100", "AM"]))
    h.until(4.9)
    assert h.position("X") == 1000
    h.run()
    assert h.position("X") == 2000


@pytest.mark.parametrize("model", ["PC48-4", "VS4-040"])
@pytest.mark.parametrize(("bit", "low"), [("BL8;", True), ("BH8;", False)])
def test_an_am_output_bit_waits_for_its_own_task_only(model: str, bit: str, low: bool) -> None:
    """BL/BH ("AA - AM 2"), as in the manual's ``AX MA1000 GO BL10;``, set the bit after the
    task's move: at 1.1 s, when X's move ends, not when Z's unrelated move does (5 s)."""
    h = Harness(model)
    if not low:
        h.send("BL8;")
    cmds = [*SETUP, "AM", "MR,,5000;", "GO", "MR1000;", "GO", bit, ""]
    h.send(" ".join(cmds))
    h.until(1.0)
    assert bool(h.board.outputs_low >> 8 & 1) is not low
    h.until(1.2)
    assert bool(h.board.outputs_low >> 8 & 1) is low
    assert h.position("Z") < 5000
    if model == "PC48-4":
        assert h.query("BX") == frame("000100" if low else "000000")


@pytest.mark.parametrize(("model", "sep"), MODELS)
@pytest.mark.parametrize("kill", ["KL", "\x04"])
def test_a_killed_power_automatic_move_powers_down(model: str, sep: str, kill: str) -> None:
    """``AX PA MR100000 GO``: the output goes high with the move; killed at 0.2 s, the move has
    ended and the output goes low at once, as at a move's own end. Before: high for good."""
    h = Harness(model)
    h.send(sep.join(["AX", "PA", "MR100000", "GO", ""]))
    h.until(0.2)
    assert h.axis("X").aux is True
    h.send(kill + sep if kill == "KL" else kill)
    h.until(0.21)
    assert h.position("X") < 100000
    assert h.axis("X").aux is False


@pytest.mark.parametrize(("model", "sep"), MODELS)
def test_a_killed_move_settles_before_it_powers_down(model: str, sep: str) -> None:
    """E27's ``AZ PA SE500;`` ("remain on for 500 milliseconds after the move is complete"),
    with the move killed at 0.2 s: the output stays high until 0.7 s, then goes low."""
    h = Harness(model)
    h.send(sep.join(["AZ", "PA", "SE500", "MR100000", "GO", ""]))
    h.until(0.2)
    h.send("KL" + sep)
    h.until(0.69)
    assert h.axis("Z").aux is True
    h.until(0.71)
    assert h.axis("Z").aux is False


@pytest.mark.parametrize(("model", "sep"), MODELS)
def test_a_kill_during_the_settling_time_lets_it_run_out(model: str, sep: str) -> None:
    """``AZ PA SE500 MR1000 GO``: the move ends at 0.0635 s on the PC48 (tick 130; 0.045 s at
    the VS4's and PCIx's power-up AC), the output goes low 0.5 s later. A KL at 0.2 s, the axis
    at rest, ends no motion and leaves the settling time to run out. Before, the KL cancelled it
    and the output stayed high."""
    h = Harness(model)
    h.send(sep.join(["AZ", "PA", "SE500", "MR1000", "GO", ""]))
    h.until(0.2)
    assert h.position("Z") == 1000 and h.axis("Z").aux is True
    h.send("KL" + sep)
    h.until(0.53)
    assert h.axis("Z").aux is True
    h.until(0.58)
    assert h.axis("Z").aux is False


@pytest.mark.parametrize("model", ["PC48-4", "PC48-4E", "VS4-040"])
def test_se_is_charged_on_every_go_without_pa(model: str) -> None:
    """SE: "The use of this command requires 3 queue slots with the execution of each GO or GD
    command" (no word of PA). ``AX SE500`` without PA, then a GO held behind a WT: its table's
    cost (4; 7 with encoders) plus 3. Before, 4 (7): SE was charged only while PA was on."""
    h = Harness(model)
    h.send("AX SE500; WT1000 ")
    go = 4 if model == "PC48-4" else 7
    before = number(h.query("RQ"))
    h.send("MR1000 GO ")
    assert before - number(h.query("RQ")) == 2 + go + 3
    before = number(h.query("RQ"))
    h.send("SE0; MR1000 GO ")
    assert before - number(h.query("RQ")) == 3 + 2 + go
