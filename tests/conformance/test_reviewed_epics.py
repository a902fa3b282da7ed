"""Review of what real EPICS motor drivers need from omsd, beyond the recorded traffic.

``shared/interop/README.md`` states what the two EPICS clients require; the traces hold one
start-up, one move, one jog, one home, one stop and one LP each. The drivers send more than
that (a home in either direction, a jog ended by ``ST ID``, a zero-length move, the same polls
on every board of the family), so the sequences below drive omsd through the raw link, as the
clients reach it, and read the replies as the README says the clients parse them:

* drvOmsPC68 (PC48 / PC46 / VS4 dialect): "Replies use the board's native framing:
  ``\\n\\r<value>\\n\\r``, and ``\\n\\r\\r<status>\\n\\r\\r`` for RA/QA/RI/QI/EA. Several replies
  may follow one line (``QA RP`` gives two framed replies)." "A command error must be visible in
  the stream as a lone ``#``." "It must not receive ``!``, ``@`` or ``$`` bytes on this link."
* omsMAXnet (PCIx): "Replies are ``text\\n\\r`` with **no leading LF/CR**"; "It polls
  ``AM;RI;`` ..., ``AM PP;``, ``AM;RV;`` (velocities; non-zero while moving), ``AM;EA;``,
  ``AM;QL;``, ``AM;CL?;``, and ``#WS``"; "Every query that gets no answer costs the client a 2 s
  timeout"; "the done flag must appear in ``RI`` when the move completes, or the client flags the
  axis as a problem after five polls."

None of these failed before this file was written: they hold requirements no test held yet.
"""

from __future__ import annotations

import re

import pytest

from omsd.board.board import Board
from omsd.board.harness import Harness
from omsd.link import make_link
from omsd.models import get_model

PC48_FAMILY = ["PC48-4", "PC48-4E", "PC46-4E", "VS4-040"]
PCIX_MODELS = ["PCIX-400", "PCIX-040", "PCIX-004", "PCIX-202"]

VALUE = re.compile(rb"\n\r(-?\d+(?:,-?\d+)*)\n\r")
STATUS = re.compile(rb"\n\r\r([PM][DN][LN][HN](?:,[PM][DN][LN][HN])*)\n\r\r")


class Client:
    """A board behind the raw link, on a manual clock, as an EPICS client reaches it."""

    def __init__(self, model: str) -> None:
        self.board = Board(get_model(model), now=0.0)
        self.link = make_link("raw", self.board)
        self.t = 0.0
        self.stream = bytearray()  # every byte the client received

    def wait(self, t: float) -> None:
        """Let the board run to ``t``; nothing may arrive unasked."""
        while (d := self.link.next_deadline()) is not None and d <= t:
            self.t = max(self.t, d)
            self.stream += self.link.to_host(self.t).data
        self.t = t
        data = self.link.to_host(t).data
        self.stream += data
        assert data == b"", data

    def send(self, line: bytes, at: float | None = None) -> bytes:
        """Send one line; what came back at once (one read of the link: no gap inside it)."""
        if at is not None:
            self.wait(at)
        assert self.link.from_host(line, self.t) == len(line)
        data = self.link.to_host(self.t).data
        self.stream += data
        return data


def pc68_poll(c: Client, at: float) -> tuple[str, int]:
    """drvOmsPC68's poll ``AX QA RP``: exactly a status frame and a value frame."""
    data = c.send(b"AX QA RP", at)
    m = re.fullmatch(STATUS.pattern + VALUE.pattern, data)
    assert m, data
    return m[1].decode(), int(m[2])


# -- drvOmsPC68: the PC48 family ------------------------------------------------------------------


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_start_up_polls_answer_on_every_board_of_the_family(model: str) -> None:
    """The trace's start-up on each board drvOmsPC68 drives: EA is a status frame of six letters
    (PC48 §6.19: E/D, E/D, S/N, P/N, H/N, N) on an axis with an encoder and a lone ``#`` on one
    without; ``?KP`` is a lone ``#`` (no servo loop on this family)."""
    c = Client(model)
    model_axes = c.board.model.axes
    assert VALUE.fullmatch(c.send(b"EFICAA SAAA RP"))
    for letter in "XYZT"[: len(model_axes)]:
        ea = c.send(f"A{letter} EA".encode())
        axis = c.board.axis_by_letter(letter)
        assert axis is not None
        if axis.has_encoder:
            assert re.fullmatch(rb"\n\r\r[ED][ED][SN][PN][HN]N\n\r\r", ea), ea
        else:
            assert ea == b"#", ea
        assert c.send(f"A{letter} ?KP".encode()) == b"#"
        assert pc68_poll(c, c.t) == ("PNNN", 0)


@pytest.mark.parametrize("model", PC48_FAMILY)
@pytest.mark.parametrize("command", ["HM0", "HR0"])
def test_pc68_home_either_way_shows_home_and_done_in_qa(model: str, command: str) -> None:
    """devOmsCom's home, as the trace sends it (``VL101 VB100 AC200 CA HM0 GD ID``), from rest on
    either side of the switch (the default stage: home from 1000 to 1100). RA/QA char 5: "D Done
    (ID, II or IN command has been executed ...)"; char 7: "H Home switch active". The counter
    is loaded at the switch (HM: "The position counter will be initialized to the position
    supplied") and the axis decelerates past it (VL101 at AC200: 25.5 steps)."""
    c = Client(model)
    if command == "HR0":  # start beyond the switch
        c.send(b"AX VL5000 AC20000 MA2000 GD ID")
        assert pc68_poll(c, 2.0) == ("PDNN", 2000)
    c.send(f"AX  VL101 VB100 AC200 CA {command} GD ID".encode(), c.t + 0.1)
    status, _ = pc68_poll(c, c.t + 0.5)
    assert status[1] == "N" and status[0] == ("P" if command == "HM0" else "M"), status
    c.wait(c.t + 40.0)
    status, position = pc68_poll(c, c.t)
    assert status[1] == "D", status
    assert abs(position) <= 26, position  # 0 at the switch's edge, then the ramp down
    assert b"!" not in c.stream and b"@" not in c.stream and b"$" not in c.stream


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_jog_stopped_by_st_id_shows_done(model: str) -> None:
    """The trace's jog (``VB100 AC2000 CA JG-1000;``) ended by the trace's stop (``AC1800 ST
    ID``, from rest of the queue): QA shows M and no D while jogging, RV the jog speed, and D once
    the ramp down ends (the ID after ST runs when the stop is over); no ``!@$`` ever."""
    c = Client(model)
    c.send(b"AX  VB100 AC2000 CA JG-1000;")
    status, position = pc68_poll(c, 1.0)
    assert status == "MNNN" and position < 0, (status, position)
    assert c.send(b"AX RV") == b"\n\r-1000\n\r"
    c.send(b"AX  AC1800 ST ID", 1.5)
    c.wait(3.0)
    status, _ = pc68_poll(c, 3.0)
    assert status == "MDNN", status
    assert c.send(b"AX RV") == b"\n\r0\n\r"
    assert not set(c.stream) & set(b"!@$"), bytes(c.stream)


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_move_of_no_distance_still_sets_done(model: str) -> None:
    """The motor record may ask for a move to where the motor already is; the client then waits
    for D like after any move, so ``MA<here> GD ID`` and ``MR0 GD ID`` must set it."""
    c = Client(model)
    c.send(b"AX  VL1000 VB100 AC1800 MA0 GD ID")
    assert pc68_poll(c, 0.01) == ("PDNN", 0)
    c.send(b"AX  VL1000 VB100 AC1800 CA MR0 GD ID")
    assert pc68_poll(c, 0.02) == ("PDNN", 0)


def test_pc68_replies_of_one_line_come_in_one_piece() -> None:
    """README: "over TCP a reply must begin within about 3 ms, with no gap over about 1 ms inside
    it": every reply of a line (status, value, and a ``#`` among them) is in the link's output
    at the instant the line arrives, in the order of the commands."""
    c = Client("PC48-4")
    assert c.send(b"AX QA RP") == b"\n\r\rPNNN\n\r\r\n\r0\n\r"
    assert c.send(b"AX QA RP RE") == b"\n\r\rPNNN\n\r\r\n\r0\n\r#"
    assert c.send(b"AX EA RP") == b"#\n\r0\n\r"


# -- omsMAXnet: the PCIx --------------------------------------------------------------------------


POLL = [b"AM;RI;\n", b"AM PP;\n", b"AM;CL?;\n", b"AM;RV;\n", b"AM;EA;\n", b"AM;QL;\n", b"#WS\n"]


def max_poll(c: Client, at: float) -> dict[str, list[str]]:
    """One round of the omsMAXnet poller: each query one ``text\\n\\r`` answer, nothing before."""
    out = {}
    c.wait(at)
    n = len(c.board.model.axes)
    for line in POLL:
        data = c.send(line)
        assert data.endswith(b"\n\r") and data.count(b"\n\r") == 1, (line, data)
        assert data[:1] not in (b"\n", b"\r"), (line, data)
        fields = data[:-2].decode().split(",")
        key = line.strip(b"\n;").split(b";")[-1].split(b" ")[-1].decode()
        if key not in ("QL", "#WS"):
            assert len(fields) == n, (line, data)
        out[key] = fields
    return out


def max_start(model: str) -> Client:
    c = Client(model)
    for line in (b"WY\n", b"IC;\n", b"AM SA;\n", b"AX LH PSO; AY LH PSO;\n"):
        c.send(line)
    assert c.send(b"AA RP;\n") == b",".join([b"0"] * len(c.board.model.axes)) + b"\n\r"
    return c


@pytest.mark.parametrize("model", PCIX_MODELS)
def test_max_polls_are_answered_on_every_pcix(model: str) -> None:
    """README: "Every query that gets no answer costs the client a 2 s timeout; ten failed status
    reads in a row make it drop the connection": the poll answers on servo, stepper-with-encoder and
    open-loop boards alike, and so do the per-axis start-up queries."""
    c = max_start(model)
    for letter in c.board.model.axes:
        assert re.fullmatch(rb"=[OEM]\n\r", c.send(f"A{letter} PS?\n".encode()))
        assert re.fullmatch(rb"=[lh]\n\r", c.send(f"A{letter} LT?\n".encode()))
    poll = max_poll(c, 0.1)
    assert set(poll["RI"]) == {"PNNN"} and set(poll["PP"]) == {"0"}
    assert set(poll["RV"]) == {"0"} and poll["#WS"] == ["=0"]


@pytest.mark.parametrize("model", PCIX_MODELS)
@pytest.mark.parametrize(
    ("line", "direction"),
    [
        (b"AX;AC2000;VL1000;VB0;MR-300;GO;ID;\n", "M"),
        (b"AX;AC2000;VL1000;VB0;HM0;ID;\n", "P"),
        (b"AX;AC2000;VL1000;VB0;HR0;ID;\n", "M"),
    ],
)
def test_max_done_shows_once_in_the_first_ri_after_the_end(
    model: str, line: bytes, direction: str
) -> None:
    """A move and a home either way, polled every 0.2 s as the client does while moving: RV is
    non-zero while RI shows no D, the first RI after the end shows D (with the direction of
    travel), the next one N (PCIx RI: "done flags reset")."""
    c = max_start(model)
    if b"HR0" in line:  # start on the far side of the home switch (1000..1100)
        c.send(b"AX;AC20000;VL5000;MA2000;GO;\n")
        c.wait(2.0)
    c.send(line, c.t)
    t = c.t
    seen_moving = False
    for _ in range(100):
        t += 0.2
        poll = max_poll(c, t)
        if poll["RI"][0][1] == "D":
            break
        assert poll["RV"][0] != "0", poll  # not done: still moving
        seen_moving = True
    else:
        raise AssertionError("no done in RI")
    assert seen_moving
    assert poll["RI"][0][0] == direction and poll["RV"][0] == "0", poll
    assert max_poll(c, t + 0.2)["RI"][0][1] == "N"


@pytest.mark.parametrize("stop", [b"AX;ST;ID;\n", b"AX;KL;ID;\n"])
def test_max_jog_stopped_shows_done(stop: bytes) -> None:
    """A jog (``JG``) ended by a stop with ``ID``: RV shows the jog speed, then D in RI."""
    c = max_start("PCIX-400")
    c.send(b"AX;AC2000;JG-500;\n")
    poll = max_poll(c, 1.0)
    assert poll["RV"][0] == "-500" and poll["RI"][0] == "MNNN", poll
    c.send(stop, 1.0)
    poll = max_poll(c, 1.5)
    assert poll["RI"][0] == "MDNN" and poll["RV"][0] == "0", poll


def test_max_move_of_no_distance_still_sets_done() -> None:
    c = max_start("PCIX-400")
    c.send(b"AX;AC2000;VL1000;VB0;MA0;GO;ID;\n")
    assert max_poll(c, 0.01)["RI"][0] == "PDNN"


def test_max_lower_case_poll() -> None:
    """README: "Other real clients send lower-case commands": the poll answers the same."""
    c = max_start("PCIX-400")
    assert c.send(b"am;ri;\n") == b"PNNN,PNNN,PNNN,PNNN\n\r"
    assert c.send(b"am pp;\n") == b"0,0,0,0\n\r"


@pytest.mark.parametrize("model", ["PCIX-400", "PCIX-040", "PCIX-004", "PCIX-202"])
def test_pm_is_answered_on_every_pcix_axis(model: str) -> None:
    """omsMAXnet on firmware below 1.30 (the PCIx's WY says 1.26) asks ``A? ?PM`` of every axis
    whenever none is moving (omsBaseController::getClosedLoopStatus); an unanswered query costs
    it 2 s. "REPORT HOLD STATE": hn/hf on servos, on steppers with encoders (their HN), hf on
    an open-loop axis."""
    h = Harness(model)
    answers = [h.send(f"A{a};?PM;") for a in "XYZT"]
    assert answers == [b"hf\n\r"] * 4
    assert h.errors() == []
    if model == "PCIX-040":
        h.send("AX;HV1000;HG10;HN;")
        h.run()
        assert h.send("AX;?PM;") == b"hn\n\r"


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_stop_read_at_once_counts_no_step_ahead(model: str) -> None:
    """A stop and a read in one write (``AX ST RP``, or drvOmsPC68's ``AC1800 ST ID`` with its
    ``AX QA RP`` poll in the same instant) while the axis runs the negative way between two
    steps. RP: "returns the current position"; the counter counts the steps emitted ("the
    position counter may not accurately reflect the true position of the motor following this
    command" is said of KL's inertia, §6.9, not of the pulses). At 0.2003 s a jog at -1000 from
    AC2000 is at -40.12: 40 steps emitted, RP -40. The ST began a ramp down from there and the
    counter read -41 at that instant (the new ramp's start taken as travel the positive way,
    rounded down), then -40 a sample later and on: a step counted that was never emitted. A KL in
    the same instant (``AX ST KL``) kept it for good."""
    c = Client(model)
    c.send(b"AX AC2000 JG-1000;")
    assert c.send(b"AX RP", 0.2003) == b"\n\r-40\n\r"
    assert c.send(b"AX ST RP") == b"\n\r-40\n\r"
    assert c.send(b"AX KL RP") == b"\n\r-40\n\r"
    c.wait(0.5)
    assert pc68_poll(c, 0.5) == ("MNNN", -40)


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_counter_after_a_turn_counts_the_steps_emitted(model: str) -> None:
    """A jog turned round by a jog of the other sign (JG: "another JG command"; omsd ramps down
    through zero and up the other way), as drvOmsPC68's ``HM0`` sent while its ``JG-1000`` runs
    turns it round: after the turn RP counts the steps emitted the new way. ``JG-1000`` at
    AC2000, then ``JG1000``: the axis turns at -500 at 1.0 s and is at -488.975 at 1.105 s,
    eleven steps up from -500: RP -489. It read -488 (the step ahead, as if still travelling the
    way the motion began), and a KL there (as a limit would) kept -488 for good."""
    c = Client(model)
    c.send(b"AX AC2000 JG-1000;")
    c.send(b"AX JG1000;", 0.3)
    assert c.send(b"AX RP", 1.105) == b"\n\r-489\n\r"
    assert c.send(b"AX KL RP") == b"\n\r-489\n\r"
    assert pc68_poll(c, 1.5) == ("PNNN", -489)


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_stop_just_after_a_turn_counts_no_step_ahead(model: str) -> None:
    """A stop given just after a jog turned round, before the way back has emitted a step.
    ``JG1000`` at AC2000, then ``JG-1000``: the axis turns at 700.195 at 1.2002 s and is at
    700.099 at 1.21 s, the counter at 700 (RP "returns the current position", PC48 §6.13: the
    steps emitted; 701 was never reached). The stop there began a new motion the negative way
    from 700.099 and counted it as if the motion had come down from above: RP 701, and a KL in
    the same write (as a limit would) kept 701 for good."""
    c = Client(model)
    c.send(b"AX AC2000 JG1000;")
    c.send(b"AX JG-1000;", 0.70013)
    assert c.send(b"AX RP", 1.21) == b"\n\r700\n\r"
    assert c.send(b"AX ST KL RP") == b"\n\r700\n\r"
    assert pc68_poll(c, 1.5) == ("MNNN", 700)


@pytest.mark.parametrize("model", PC48_FAMILY)
def test_pc68_move_begun_from_a_jog_the_other_way_counts_no_step_back(model: str) -> None:
    """A move queued behind a jog starts from rest where the jog is once it is up to speed
    (docs/decisions.md, a GO during a jog). ``JG-1000`` at AC3333 has emitted 150 steps when
    it reaches its speed at -150.278 (RP -150), and ``MR100 GO`` sets off the positive way from
    there. The move counted from -150.278 as if it had come up from below: RP -151 at once, a
    step the negative way that was never emitted, while the axis moved the positive way. RP
    "returns the current position" (PC48 §6.13); the counter counts the steps emitted, and moves
    with the axis, never against it."""
    c = Client(model)
    c.send(b"AX AC3333 JG-1000 MR100 GO;")
    assert c.send(b"AX RP", 0.2999) == b"\n\r-149\n\r"
    reads = [int(c.send(b"AX RP", 0.3 + k * 0.0005).strip()) for k in range(1, 40)]
    assert reads[0] == -150
    assert reads == sorted(reads)
