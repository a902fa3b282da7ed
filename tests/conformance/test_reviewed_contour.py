"""Contouring and linear interpolation where a review against the manuals found omsd wrong.

* PCIx RC inside a contour: "While a contour is executing, the value computed to generate the
  appropriate lead in will be returned" (PCIx §5, RC REPORT ACCELERATION), as the PC48 already
  does; it used to report the acceleration of the moment (0 on the constant-velocity path).
* CX (and the PCIx's CG) in AM mode meets and takes queue units on the contour's axes only, as an
  AM GO does on its move's: AM "allows several tasks to be managed simultaneously ... a task may
  be performing coordination motion on 2 axes, while a second task is performing unrelated but
  simultaneous motion on another axis". It used to wait for every axis, as in AA.
"""

from __future__ import annotations

import pytest

from omsd.board.events import DoneEvent
from omsd.board.harness import Harness


def number(reply: bytes) -> int:
    return int(reply.strip(b"\n\r"))


@pytest.mark.parametrize("start", ["CX;", "CG;"])
def test_pcix_rc_reports_the_lead_in_for_the_whole_contour(start: str) -> None:
    """RC: "When the stage is running at programmed speed; i.e. not accelerating, the parameter
    returned will be zero (0). While a contour is executing, the value computed to generate the
    appropriate lead in will be returned." X goes 1000 steps from 0 to the start (1000,0) to
    reach CV1000 there: 1000² / (2 × 1000) = 500 steps/s² over the 2 s lead-in; then a line at
    constant speed (2 s to 3 s), a quarter circle (3 s to 4.57 s) and the CE ramp down. RC is
    500 all along (it was 0 on the line and the arc's centripetal share on the arc), and 0 once
    the axis is at rest."""
    h = Harness("PCIX-004")
    h.send(f"AA;CV1000;CD1000,0;MT2000,0;CR2000,1000,1.5707963;MT3000,2000;CE;{start}")
    for t in (0.5, 2.5, 3.5, 4.2):
        h.until(t)
        assert number(h.send("AX;RC;")) == 500, t
        assert number(h.send("AY;RC;")) == 0, t  # Y has no share of the lead-in (along X)
    h.run()
    assert number(h.send("AX;RC;")) == 0
    assert h.errors() == []


def queues(h: Harness, rq: str) -> list[int]:
    return [int(n) for n in h.send(rq).strip(b"\n\r").split(b",")]


@pytest.mark.parametrize(
    ("model", "sep", "start", "units"),
    [("PC48-4", " ", "CX", 6), ("VS4-040", " ", "CX", 6), ("PCIX-004", ";", "CG", 17)],
)
def test_am_contour_runs_beside_another_task(model: str, sep: str, start: str, units: int) -> None:
    """AM (PC48 §6.3, PCIx AM page): "The AM mode allows several tasks to be managed
    simultaneously. For instance, a task may be performing coordination motion on 2 axes, while
    a second task is performing unrelated but simultaneous motion on another axis." Z is sent on
    a 5 s move first; the contour on X and Y, executed in AM, starts at once (CX "AA,AM 6" in X's
    and Y's queues; the PCIx's CG "9*" + "Linear ( PF, LA ) 8"), leaving Z's queue alone. Before,
    the contour waited for Z's move to end (X still at 0 after 3 s)."""
    h = Harness(model)
    cmds = ["AA", "VL1000,1000,1000,1000;", "AC10000,10000,10000,10000;", "AM", "MR0,0,5000;"]
    cmds += ["GO", "AA", "CV1000", "CD1000,0;", "MT2000,0;", "CE", "AM", ""]
    h.send(sep.join(cmds))
    rq = "RQ" + sep
    before = queues(h, rq)
    h.send(start + sep)
    after = queues(h, rq)
    assert [b - a for b, a in zip(before, after, strict=True)] == [units, units, 0, 0]
    h.until(1.0)  # half way through the 2 s lead-in (1000 steps to reach 1000 steps/s)
    assert h.position("X") == 250 and 900 < h.position("Z") < 1000
    h.until(3.0)
    assert h.position("X") == 2000 and h.position("Z") < 5000
    h.run()
    assert (h.position("X"), h.position("Y"), h.position("Z")) == (2050, 0, 5000)
    assert h.errors() == []


def test_aa_contour_still_waits_for_every_axis() -> None:
    """In AA, CX stays a meeting point of every axis, as an AA GO ("Each axis programmed to move
    will start together upon executing the GO command"; docs/decisions.md, Synchronisation)."""
    h = Harness("PC48-4")
    h.send("AA VL1000,1000,1000,1000; AC10000,10000,10000,10000; MR0,0,5000; GO ")
    h.send("CV1000 CD1000,0; MT2000,0; CE CX ")
    h.until(3.0)
    assert h.position("X") == 0
    h.run()
    assert h.position("X") == 2050


@pytest.mark.parametrize(
    ("model", "sep", "start"), [("PC48-4", " ", "CX"), ("PCIX-004", ";", "CG")]
)
def test_an_am_contour_is_the_task_an_id_after_it_reports(model: str, sep: str, start: str) -> None:
    """ID (PC48 §6.12): "In the AM mode, only the axes active in the most recent move will set
    their done flags." Once CX runs as the contour axes' own task, the contour is that most
    recent move: an ID after it sets X's and Y's done flags when the contour ends (3.05 s: the
    2 s lead-in, the 1 s line, CE's ramp down), not Z's when the earlier task's move ends (it
    went to Z's queue and reported Z at 5.1 s)."""
    h = Harness(model)
    cmds = ["AA", "VL1000,1000,1000,1000;", "AC10000,10000,10000,10000;", "AM", "MR,,5000;"]
    cmds += ["GO", "AA", "CV1000", "CD1000,0;", "MT2000,0;", "CE", "AM", start, "ID", ""]
    h.send(sep.join(cmds))
    h.run()
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert [e.done_register for e in done] == [0b0011]
    assert 3.0 < done[0].time < 3.2
    assert h.errors() == []


@pytest.mark.parametrize(("model", "sep"), [("PC48-4", " "), ("PCIX-004", ";")])
def test_rc_of_an_am_contour_is_kept_while_another_starts(model: str, sep: str) -> None:
    """RC: "While a contour is executing, the value computed to generate the appropriate lead in
    will be returned." In AM a second contour, on Z, starts while X's runs (AM: "a task may be
    performing coordination motion on 2 axes, while a second task is performing unrelated but
    simultaneous motion on another axis"): X's RC stays its lead-in's 500 (1000 steps to reach
    CV1000), Z's is its own 1000 (500 steps). It was 0 for X once Z's contour began."""
    h = Harness(model)
    h.send(sep.join(["AA", "CV1000", "CD1000,0;", "MT5000,0;", "CE", "AM", "CX", ""]))
    h.until(0.5)
    h.send(sep.join(["AA", "CV1000", "CD,,500,0;", "MT,,2000,0;", "CE", "AM", "CX", ""]))
    h.until(0.7)
    assert [number(h.send(f"A{a}{sep}RC{sep}")) for a in "XZ"] == [500, 1000]
    assert h.errors() == []


def test_pcix_rc_in_a_contour_is_the_whole_number_meant() -> None:
    """The lead-in to (100,100) at CV1000: 1000² / (2 × 141.42…) along the diagonal, 2500 steps/s²
    on each axis, which floating point computes as 2499.9999999999995. RC reports the number
    meant, as the PC48 does and as RC and RV do elsewhere (docs/decisions.md, "RV and RC are
    whole numbers of the value meant"); the PCIx's gave 2499 for the whole contour."""
    h = Harness("PCIX-004")
    h.send("AA;CV1000;CD100,100;MT200,100;CE;CX;")
    h.until(0.1)
    assert h.send("RC;") == b"2500, 2500, 0, 0\n\r"
    assert h.errors() == []


#: The PC48's CD example at a radius of 100, and a start from where X can reach CV
CIRCLE = ["AA", "CV200", "CD0,0", "CR0,50,3.1415926", "CR0,0,6.2831853", "MT100,-10", "CE"]
CIRCLE += ["MT-10,0", "GO", "CX", ""]

#: (when, axis, RP) on the PC48-4's circle below, and where the axis is then
ON_THE_CIRCLE = [
    (0.962, "Y", 100),  # Y at 99.015 going down, turned at 100 (between two arcs): 100, not 99
    (1.748, "X", -99),  # X at -98.998 going up, turned at -100 within the arc: -99, not -98
    (2.534, "Y", -99),  # Y at -98.981 going up, its second turn (-100): -99, not -98
    (3.318, "X", 100),  # X at 99.020 going down, its third turn (100): 100, not 50
    (4.378, "Y", 49),  # Y at 48.994 going down, after the line's turn at 100: 49, not 48
]


@pytest.mark.parametrize("model", ["PC48-4", "VS4-040", "PCIX-004"])
def test_the_counters_on_a_circle_count_the_steps_emitted_the_way_back(model: str) -> None:
    """The PC48's CD example (§6.21, "cutting a hole ... with circular interpolation"), at a
    radius of 100: a half circle up to (0,100), then a full circle round (0,0), then a line.
    Each axis turns round within an arc (X at 50, -100 and 100, Y at -100) or between two
    (Y at 100). RP "returns the current position" (§6.13): the steps emitted, so the counter is
    within a step of the carriage and, on the way back from a turn, moves only as the axis
    passes a whole step. The counter took only the first turn of a motion, and only one it
    knew the way before (Y's motion begins at rest while X ramps up to the contour): X at 99
    on its way down after its third turn read 50 (the step of its first), Y after its turns
    read a step ahead; a KL there kept it for good."""
    h = Harness(model)
    sep = ";" if model.startswith("PCIX") else " "
    h.send(sep.join(CIRCLE))
    axes = [h.axis("X"), h.axis("Y")]
    for k in range(1, 2300):
        h.until(k * 0.002)
        counts = [int(v) for v in h.send(f"RP{sep}").strip(b"\n\r").split(b",")[:2]]
        for axis, count in zip(axes, counts, strict=True):
            x = axis.traj.position(h.t)
            assert abs(count - x) < 1.0, (h.t, axis.letter, x, count)
    if model != "PC48-4":
        return  # (the instants below are the PC48's)
    for when, letter, count in ON_THE_CIRCLE:
        h = Harness(model)
        h.send(sep.join(CIRCLE))
        h.until(when)
        assert number(h.send(f"A{letter} RP ")) == count, when
        h.send("KL ")
        h.run()
        assert number(h.send(f"A{letter} RP ")) == count, when
