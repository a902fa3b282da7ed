"""VS4 against PC48: every difference of section 7 of the VS4 digest (``shared/reference/vs4.md``).

One test (or one parametrized test) per row of §7.1–§7.6 that a host can observe. Each test's
docstring quotes the digest row it checks; where the VS4 manual contradicts itself (digest §8)
the docstring says which reading the personality takes (``omsd/models/vs4.py``) and why. A PC48
is run beside the VS4 wherever that is what makes the difference visible.

Rows not tested because nothing a host can do shows them: the VME bus and addressing, IRQ levels,
the status bit's name (ENCODER vs ENC_S), the data port's buffering statement, the limit
polarity switch S4, the I/O direction jumpers, the sync line wording, and the PC48 DOS driver's
``! @ * # $`` conventions (a feature of the host driver, not of either board).

Timing used throughout: the VS4 samples 1024 times a second (ticks at k/1024 s), the PC48 2048;
a move starts on the first tick at or after its GO and is done on the first tick at or after its
analytic end. VS4 power-up VL is 200,000 and AC 2,000,000; every VS4 axis has an encoder, so the
ENCODER columns of the queue tables apply (GO takes 7 slots in single-axis mode).
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest

from omsd.board.board import Board
from omsd.board.events import DoneEvent, ErrorKind, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import CMD_S, DON_S, IBF_S, INIT, IRQ_S, TBE_S
from omsd.models import get_model, variant
from omsd.models.pc48 import PC48_COMMANDS
from omsd.models.vs4 import VS4_COMMANDS

from .support import errors, frame, status_frame
from .support import no_encoder_vs4 as vs4_without_encoders

VS4_RATE = 1024
PC48_RATE = 2048


def fields(reply: bytes) -> list[str]:
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    return reply[2:-2].decode("ascii").split(",")


def rq(h: Harness) -> list[int]:
    """RQ in the current mode: three digits a field (four inside a contour definition)."""
    reply = h.query("RQ")
    out = fields(reply)
    assert all(f.isdigit() for f in out), reply
    return [int(f) for f in out]


def ramp(h: Harness, shape: str) -> None:
    """Select a ramp while idle (CN is queued on a PC48: let it execute)."""
    h.send({"linear": "PF ", "parabolic": "PN;", "cosine": "CN "}[shape])
    h.run()
    assert h.errors() == []


def busy(model: str, mode: str = "AX", shape: str = "linear") -> Harness:
    """X (AX) or all four axes (AA, AM) on a 1000 s move: what is queued behind it does not
    execute during the test, so RQ shows exactly what a command costs."""
    h = Harness(model)
    ramp(h, shape)
    if mode == "AX":
        h.send("AX VL1000 MR1000000 GO")
    else:
        h.send("AA VL1000,1000,1000,1000; MR1000000,1000000,1000000,1000000; GO")
        if mode == "AM":
            h.send("AM")
    h.advance(0.01)
    assert h.errors() == []
    return h


def cost(h: Harness, command: str) -> list[int]:
    """Slots ``command`` takes in each queue of the current mode (RQ before minus after)."""
    before = rq(h)
    h.send(command)
    return [b - a for b, a in zip(before, rq(h), strict=True)]


# -- 7.1 hardware and host interface ---------------------------------------------------------------


@pytest.mark.parametrize(("model", "register"), [("VS4-040", 0x0F), ("VS4-020", 0x03)])
def test_done_register_bits_4_to_7_always_zero(model: str, register: int) -> None:
    """§7.1 "Done register | bits 0–3 = X,Y,Z,T; **bits 4–7 always 0** | bits 0–7 =
    X,Y,Z,T,U,V,R,S". Every axis moves with ID and the register is read: only X..T (X, Y on a
    VS4-020) are set, whatever the AA list asks of axes beyond them; a PC48-8 sets all eight."""
    h = Harness(model)
    h.send("AA MR100,100,100,100,100,100,100,100; GO ID")
    h.run()
    assert h.errors() == []
    assert h.board.read_done_register(h.t) == register
    pc48 = Harness("PC48-8")
    pc48.send("AA MR100,100,100,100,100,100,100,100; GO ID")
    pc48.run()
    assert pc48.board.read_done_register(pc48.t) == 0xFF


def test_status_and_done_registers_reset_when_read() -> None:
    """§7.1 "Register reset wording | "The status and Done Flag Registers are automatically
    reset after the Registers are read."". The latched bits (CMD_S, DON_S, done flags) go on a
    read; TBE_S, and IRQ_S which follows it on a VS4, do not (digest §8 item 19: "The TBE_S bit
    is reset by writing to the data register")."""
    h = Harness("VS4-040")
    b = h.board
    h.send("AX MR10 GO ID ZZ")
    h.run()
    assert b.read_status_register(h.t) == IRQ_S | TBE_S | DON_S | CMD_S
    assert b.read_status_register(h.t) == IRQ_S | TBE_S
    assert b.read_done_register(h.t) == 0x01
    assert b.read_done_register(h.t) == 0x00


def test_irq_s_is_the_literal_or_of_bits_4_to_6() -> None:
    """§7.1 "Status bit 7 | "logical OR of bits 4 through 6" | "Interrupt request status."".
    Digest §8 item 18 leaves open whether the enables gate it; the personality takes the
    sentence literally, so with every interrupt disabled an idle VS4 (TBE_S) already shows IRQ_S,
    and so does a reply waiting (IBF_S); a PC48 shows it only when an enabled source is true."""
    vs4 = Harness("VS4-040").board
    pc48 = Harness("PC48-4").board
    assert vs4.read_control_register(0.0) == 0
    assert vs4.status_register(0.0) == TBE_S | IRQ_S
    assert pc48.status_register(0.0) == TBE_S
    vs4.receive(b"RP", 0.0)
    pc48.receive(b"RP", 0.0)
    assert vs4.status_register(0.0) == IRQ_S | TBE_S | IBF_S
    assert pc48.status_register(0.0) == TBE_S | IBF_S
    # with the TBE interrupt enabled the PC48 asks too
    pc48.write_control_register(0x80 | 0x40, 0.0)
    assert pc48.status_register(0.0) & IRQ_S


def test_init_high_for_1_5_s_after_rs_and_irq_s_low_meanwhile() -> None:
    """§7.1 "INIT timing | "wait 1.5 seconds after reset or power up before reading the INIT
    bit" | "Monitor the INIT flag..." (no time given)". After RS the VS4 shows INIT (and nothing
    else: TBE_S is low, so the OR of bits 4-6 is 0) for 1.5 s; the PC48, for which the manual
    gives no time, is ready long before."""
    h = Harness("VS4-040")
    pc48 = Harness("PC48-4")
    h.send("RS")
    pc48.send("RS")
    assert h.board.status_register(h.t) == INIT
    for t in (0.75, 1.499):
        h.until(t)
        pc48.until(t)
        assert h.board.status_register(t) == INIT
        assert not pc48.board.status_register(t) & INIT
    h.until(1.5)
    assert h.board.status_register(1.5) == TBE_S | IRQ_S


def test_input_sent_during_init_is_executed_when_init_ends() -> None:
    """§7.1 INIT row: what the host writes while INIT is high waits in the input buffer; WY sent
    0.5 s after RS is answered when the 1.5 s are over."""
    h = Harness("VS4-040")
    h.send("RS")
    h.until(0.5)
    assert h.send("WY") == b""
    assert h.until(1.49) == b""
    assert h.until(1.5) == frame("VS4-040 ver 1.00 S/N 123456")


def test_control_register_bits_3_to_0_read_as_zero() -> None:
    """§7.1 "Control register low bits | bits 3–0 "Unused, always 0" | bits 3, 2 "Unused"
    (1, 0 not listed)"."""
    b = Harness("VS4-040").board
    b.write_control_register(0xFF, 0.0)
    assert b.read_control_register(0.0) == 0xF0
    b.write_control_register(0x0F, 0.0)
    assert b.read_control_register(0.0) == 0x00


def test_interrupt_vector_register_reads_back_what_was_written() -> None:
    """§7.1 "Register block | 16 bytes, odd offsets only: 1 data, 3 done, 5 control, 7 status,
    **9 interrupt vector** ... | 4 consecutive ports ...; no vector register" (Table 3-3:
    "Interrupt Vector", read/write byte). Writing it does not disturb the other registers."""
    h = Harness("VS4-040")
    b = h.board
    assert b.read_vector_register(0.0) == 0
    b.write_vector_register(0x5A, 0.0)
    assert b.read_vector_register(0.0) == 0x5A
    b.write_vector_register(0xC3, 0.0)
    assert b.read_vector_register(0.0) == 0xC3
    assert b.read_control_register(0.0) == 0
    assert b.status_register(0.0) == TBE_S | IRQ_S
    assert h.send("WY") == frame("VS4-040 ver 1.00 S/N 123456")


def test_pc48_has_no_interrupt_vector_register() -> None:
    """§7.1 Register block row, PC48 column: "no vector register"."""
    b = Harness("PC48-4").board
    with pytest.raises(ValueError):
        b.read_vector_register(0.0)
    with pytest.raises(ValueError):
        b.write_vector_register(0x5A, 0.0)


def test_gp_io_lines_0_to_13_with_outputs_8_to_13() -> None:
    """§7.1 "GP I/O count | 12 (I/O-0…I/O-11) | 14 (0–13)". Digest §8 item 15: the P2 connector
    carries 12 lines but the BH text says "Factory default output bits are 8 through 13"; the
    personality keeps the BH text, so the VS4 has the PC48's 14 lines: inputs 0–7, outputs 8–13.
    BL13 drives an output, BL7 is an input (command error), BL14 is no line at all."""
    h = Harness("VS4-040")
    b = h.board
    h.send("BL13;")
    h.run()
    assert h.errors() == []
    assert b.outputs_low == 1 << 13
    h.send("BL8;")
    h.run()
    assert b.outputs_low == (1 << 13) | (1 << 8)
    h.send("BH13;")
    h.run()
    assert b.outputs_low == 1 << 8
    h.send("BL7;")
    h.send("BL14;")
    assert errors(h) == [(ErrorKind.NOT_AN_OUTPUT, "BL7"), (ErrorKind.OUT_OF_RANGE, "BL14")]
    b.set_input(7, False, h.t)
    assert not b.input_high(7, h.t)
    with pytest.raises(ValueError):
        b.set_input(14, False, h.t)


# -- 7.2 capacities and rates ----------------------------------------------------------------------


def test_four_axes_x_y_z_t() -> None:
    """§7.2 "Axes | 4 max: X,Y,Z,T (AX, AY, AZ, AT) | 8 max: X,Y,Z,T,U,V,R,S (+AU, AV, AR,
    AS)". AX..AT select an axis; AA lists report four."""
    h = Harness("VS4-040")
    for letter in "XYZT":
        h.send(f"A{letter} MR{ord(letter)} GO")
    h.run()
    assert h.errors() == []
    assert h.send("AA RP") == frame("88,89,90,84")
    assert len(h.board.axes) == 4


def _timed_move(model: str, rate: int) -> tuple[Harness, float, float]:
    """``AX VL10000 AC100000 MR5000 GO ID`` sent between ticks at t=0.0012 s: a 0.1 s ramp
    (500 steps), 0.4 s at 10,000/s, a 0.1 s ramp down: 0.6 s. Returns the harness and the
    start and done tick times computed here."""
    t0 = 0.0012
    h = Harness(model)
    h.until(t0)
    h.send("AX VL10000 AC100000 MR5000 GO ID")
    start = math.ceil(t0 * rate)
    end = math.ceil(start + Fraction(6, 10) * rate)
    return h, start / rate, end / rate


def test_sample_rate_1024_visible_in_move_timing() -> None:
    """§7.2 "Velocity update | **1024/s** | 2048/s". The same move sent between ticks starts on
    tick 2/1024 on the VS4 (3/2048 on the PC48) and is done on tick 617/1024 (1232/2048)."""
    for model, rate, (k_start, k_end) in (
        ("VS4-040", VS4_RATE, (2, 617)),
        ("PC48-4", PC48_RATE, (3, 1232)),
    ):
        h, start, end = _timed_move(model, rate)
        assert (start, end) == (k_start / rate, k_end / rate)
        h.until(start - 1e-6)
        assert h.axis("X").velocity(h.t) == 0.0
        h.until(start + 1e-4)
        assert h.axis("X").velocity(h.t) > 0.0
        h.run()
        done = [e for e in h.events() if isinstance(e, DoneEvent)]
        assert [e.time for e in done] == [end], model
        assert h.position("X") == 5000


@pytest.mark.parametrize(("model", "capacity"), [("VS4-040", 256), ("PC48-4", 124)])
def test_input_buffer_holds_256_characters(model: str, capacity: int) -> None:
    """§7.2 "Input character buffer | **256** | 124". With the interpreter held by WQ behind a
    long move, Board.receive takes exactly a bufferful of a longer string."""
    h = Harness(model)
    b = h.board
    h.send("AX VL1000 MR100000 GO WQ")
    assert b.input_room() == capacity
    assert b.receive(b"RP" * 200, h.t) == capacity
    assert b.input_room() == 0
    assert b.receive(b"RP", h.t) == 0
    assert h.send("") == b""  # nothing is answered while WQ holds


@pytest.mark.parametrize(("model", "size"), [("VS4-040", 800), ("PC48-4", 200)])
def test_axis_queue_has_800_slots(model: str, size: int) -> None:
    """§7.2 "Axis queue | **800** (RQ 3 digits; empty = 800) | 200". Digest §8 item 2: the RQ
    example's 200 is the PC48's; the text's 800 is taken. Behind a move X's queue is filled with
    one-slot IDs until RQ reads 000; one more ID holds the interpreter (the RP behind it is not
    answered) until the move ends and the queue drains."""
    h = Harness(model)
    b = h.board
    assert rq(h) == [size]
    h.send("AX VL1000 MR2000 GO")
    free = rq(h)[0]
    assert size - 20 < free < size
    h.send("ID" * free)
    assert h.query("RQ") == frame("000")
    assert h.errors() == []
    assert h.send("IDRP") == b""
    h.advance(1.0)
    assert h.send("") == b""
    assert b.axes[0].queue.free == 0
    out = h.run()
    assert out == frame("2000")


def test_contour_queue_7160() -> None:
    """§7.2 "Contour queue | 1760 command words (text) / RQ max **7160** (4 digits) | RQ max
    1016". Digest §8 item 1: a digit swap; RQ's 7160 (and the §6.21 example) is taken. A
    two-axis MT takes 4 + 2 slots of it on both boards."""
    for model, empty in (("VS4-040", 7160), ("PC48-4", 1016)):
        h = Harness(model)
        h.send("AA CD0,0;")
        assert h.query("RQ") == frame(f"{empty:04d}")
        h.send("MT100,100;")
        assert h.query("RQ") == frame(f"{empty - 6:04d}")
        assert h.errors() == []


def test_vl_at_most_522000() -> None:
    """§7.2 "Max velocity (VL) | **522,000** | 1,044,000". VL522000 is taken, VL522001 is a
    command error that leaves VL as it was; the PC48 takes it."""
    h = Harness("VS4-040")
    h.send("AX VL522000;")
    assert h.errors() == []
    h.run()
    assert h.axis("X").vl == 522_000
    h.send("VL522001;")
    assert errors(h) == [(ErrorKind.OUT_OF_RANGE, "VL522001")]
    h.run()
    assert h.axis("X").vl == 522_000
    pc48 = Harness("PC48-4")
    pc48.send("AX VL522001; AY VL1044000;")
    pc48.run()
    assert pc48.errors() == []
    assert (pc48.axis("X").vl, pc48.axis("Y").vl) == (522_001, 1_044_000)


def test_jg_and_jf_up_to_1044000() -> None:
    """§7.2 "JG range | stated ±1,044,000 | not stated" and "JF range | stated ±1,044,000.000".
    Digest §8 item 3: VL stops at 522,000 but JG/JF have their own range line, which is taken.
    JG1044000 runs at 1,044,000/s once ramped (0.522 s at AC 2,000,000); 1,044,001 either way
    is a command error."""
    h = Harness("VS4-040")
    h.send("AX JG1044000;")
    assert h.errors() == []
    h.until(1.0)
    assert h.query("RV") == frame("1044000")
    h.send("ST")
    h.run()
    h.send("JG1044001; JG-1044001; JF1044000.5;")
    assert errors(h) == [
        (ErrorKind.OUT_OF_RANGE, "JG1044001"),
        (ErrorKind.OUT_OF_RANGE, "JG-1044001"),
        (ErrorKind.OUT_OF_RANGE, "JF1044000.5"),
    ]
    h.send("AY JG-1044000; AZ JF-1044000.000;")
    assert h.errors() == []
    h.until(h.t + 1.0)
    assert h.query("AY RV") == frame("-1044000")
    assert h.query("AZ RV") == frame("-1044000")


def _home_offset(model: str, vl: int) -> float:
    """HM0 at ``vl`` (AC 2,000,000) onto a switch whose edge is at 49,950, then MA0: where
    the carriage stands when the counter says 0 (the home position as loaded), minus 49,950."""
    world = {"X": AxisWorld(home_low=49_950, home_high=60_000)}
    h = Harness(model, world=world)
    h.send(f"AX AC2000000 VL{vl}; HM0;")
    h.run()
    h.send("VL1000; MA0 GO")
    h.run()
    assert h.errors() == []
    assert h.position("X") == 0
    return h.axis("X").phys(h.t) - 49_950


def test_homing_speed_limit_is_advice() -> None:
    """§7.2 "Homing speed limit | **1024** counts/s | 2048". The limit is advice, not a range:
    "The velocity should be less than 1024 counts per second to maintain accuracy of the home
    position loaded" and §5.5 "to avoid ambiguity of the home position if more than one pulse
    occurs per sample interval". HM at VL1000 loads home within one count of the edge; HM at
    VL100000 is no error but loads the position of the sample tick after the edge.

    Computed here: the stage reaches 49,950 at t = 0.05 + 47,450/100,000 = 0.5245 s (ramp of
    2,500 counts). The VS4 sees the switch on tick 538/1024 (89.06 counts later), the PC48 on
    tick 1075/2048 (40.23 counts later)."""
    assert 0 <= _home_offset("VS4-040", 1000) < 1.0 + 1e-9
    reach = 0.05 + (49_950 - 2_500) / 100_000
    for model, rate in (("VS4-040", VS4_RATE), ("PC48-4", PC48_RATE)):
        tick = math.ceil(reach * rate) / rate
        expected = 100_000 * (tick - reach)
        assert abs(_home_offset(model, 100_000) - expected) <= 1.0, model
    assert round(100_000 * (538 / 1024 - reach), 2) == 89.06


def test_default_ac_and_vl() -> None:
    """§7.2 "Default AC | **2,000,000** | 1,000,000" and "Default VL | **200,000** | 100,000".
    RC on an idle axis gives the acceleration at the start of a ramp; a default move cruises at
    VL; RS brings the defaults back."""
    h = Harness("VS4-040")
    pc48 = Harness("PC48-4")
    assert h.query("AX RC") == frame("2000000")
    assert pc48.query("AX RC") == frame("1000000")
    h.send("MR200000 GO")
    pc48.send("MR200000 GO")
    h.until(0.5)
    pc48.until(0.5)
    assert h.query("RV") == frame("200000")
    assert pc48.query("RV") == frame("100000")
    # 0.1 s ramps of 10,000 (VS4) and 5,000 (PC48) counts: 1.1 s and 2.1 s
    h.send("ID")
    pc48.send("ID")
    h.run()
    pc48.run()
    assert [e.time for e in h.events() if isinstance(e, DoneEvent)] == [1127 / 1024]
    assert [e.time for e in pc48.events() if isinstance(e, DoneEvent)] == [4301 / 2048]
    h.send("AC500000; VL1000; RS")
    h.until(h.t + 1.5)
    assert h.query("AX RC") == frame("2000000")
    assert (h.axis("X").vl, h.axis("X").ac) == (200_000, 2_000_000)


def test_contour_up_to_four_axes() -> None:
    """§7.2 "Contour axes (linear) | up to 4 | up to 8". A four-axis linear contour runs on the
    VS4; a fifth field in CD and MT is beyond the fitted axes and ignored (no error), while a
    PC48-8 runs the same text as a five-axis contour."""
    text = "AA CV1000; CD0,0,0,0,0; MT100,200,300,400,500; CE CX"
    h = Harness("VS4-040")
    h.send(text)
    h.run()
    assert h.errors() == []
    assert h.query("RP") == frame("100,200,300,400")
    pc48 = Harness("PC48-8")
    pc48.send(text)
    pc48.run()
    assert pc48.errors() == []
    assert pc48.query("RP") == frame("100,200,300,400,500,0,0,0")


def test_aa_lists_have_four_fields() -> None:
    """§7.2 "AA list length | `x,y,z,t` | `x,y,z,t,u,v,r,s`". Fields 5 to 8 of an AA list are
    beyond the VS4's axes and ignored; the PC48-8 moves U to S."""
    text = "AA MR1,2,3,4,5,6,7,8; GO"
    h = Harness("VS4-040")
    h.send(text)
    h.run()
    assert h.errors() == []
    assert h.query("RP") == frame("1,2,3,4")
    pc48 = Harness("PC48-8")
    pc48.send(text)
    pc48.run()
    assert pc48.query("RP") == frame("1,2,3,4,5,6,7,8")


# -- 7.3 replies -----------------------------------------------------------------------------------


def test_wy_reports_model_version_and_serial_number() -> None:
    """§7.3 "WY: VS4 `<LF><CR>VS4-040 ver 1.00 S/N 123456<LF><CR>`; PC48 `<LF><CR>PC48 ver
    3.00-2<LF><CR>` (no model suffix, no S/N)"; §7.2 "Firmware | ... WY shows 1.00 / 1.04": the
    §2.9 installation check shows ``VS4-040 ver 1.04 S/N 123456`` byte for byte (a board
    configured with firmware 1.04)."""
    assert Harness("VS4-040").send("WY") == frame("VS4-040 ver 1.00 S/N 123456")
    assert Harness("VS4-020").send("WY") == frame("VS4-020 ver 1.00 S/N 123456")
    assert Harness("PC48-2").send("WY") == frame("PC48 ver 3.00-2")
    h = Harness("VS4-040")
    h.board = Board(variant(get_model("VS4-040"), firmware="1.04"), now=0.0)
    reply = h.send(bytes([0x57, 0x59]))
    assert reply.hex(" ").upper() == (
        "0A 0D 56 53 34 2D 30 34 30 20 76 65 72 20 31 2E 30 34 20 53 2F 4E 20 31 32 33 34 35 "
        "36 0A 0D"
    )
    h.board = Board(variant(get_model("VS4-040"), serial="000217"), now=0.0)
    assert h.send("WY") == frame("VS4-040 ver 1.00 S/N 000217")


def test_rq_replies_800_and_7160() -> None:
    """§7.3 "RQ: VS4 empty axis queue 800 (example shows 200, §8), contour 7160; PC48 200 /
    1016". Three digits for the axis queues, four in a contour definition."""
    h = Harness("VS4-040")
    assert h.query("AX RQ") == frame("800")
    assert h.query("AA RQ") == frame("800,800,800,800")
    h.send("CD0,0;")
    assert h.query("RQ") == frame("7160")
    pc48 = Harness("PC48-4")
    assert pc48.query("AX RQ") == frame("200")
    pc48.send("AA CD0,0;")
    assert pc48.query("RQ") == frame("1016")


def test_status_lists_have_at_most_four_fields() -> None:
    """§7.3 "RI/QI/RL/RP/RC lists: at most 4 fields on VS4" (and RV, RQ)."""
    h = Harness("VS4-040", world={a: AxisWorld(home_low=10**6) for a in "XYZT"})
    h.send("AA")
    assert h.query("RP") == frame("0,0,0,0")
    assert h.query("RV") == frame("0,0,0,0")
    assert h.query("RC") == frame("2000000,2000000,2000000,2000000")
    assert h.query("RQ") == frame("800,800,800,800")
    assert h.query("QI") == status_frame("PNNN,PNNN,PNNN,PNNN")
    assert h.query("RI") == status_frame("PNNN,PNNN,PNNN,PNNN")
    assert h.query("RL") == frame("NNNN")
    assert Harness("VS4-020").query("AA RP") == frame("0,0")


# -- 7.4 commands present / absent -----------------------------------------------------------------


@pytest.mark.parametrize("model", ["VS4-040", "VS4-020"])
@pytest.mark.parametrize("mnemonic", ["AU", "AV", "AR", "AS", "BX", "RB"])
def test_absent_commands_are_command_errors(model: str, mnemonic: str) -> None:
    """§7.4 "Absent on VS4: **AU, AV, AR, AS, BX, RB** (PC48 has 107 summary commands; VS4 has
    101)". Each is an unknown command (CMD_S), nothing is replied, and the board goes on; a
    PC48-8 knows all six."""
    h = Harness(model)
    b = h.board
    assert h.send(f"AX {mnemonic} ") == b""
    assert errors(h) == [(ErrorKind.UNKNOWN_COMMAND, mnemonic)]
    assert b.read_status_register(h.t) & CMD_S
    # "Response: <LF><CR>VS4-040 ver 1.00 S/N 123456<LF><CR>"
    assert h.send("WY") == frame(f"{model} ver 1.00 S/N 123456")
    pc48 = Harness("PC48-8")
    pc48.send(f"AX {mnemonic} ")
    pc48.run()
    assert pc48.errors() == []


def test_the_vs4_has_the_pc48_commands_minus_six() -> None:
    """§7.4 "The VS4 has no extra commands beyond the PC48 set": 107 - 6 = 101."""
    assert set(VS4_COMMANDS) == set(PC48_COMMANDS) - {"AU", "AV", "AR", "AS", "BX", "RB"}
    assert len(VS4_COMMANDS) == 101


# -- 7.5 queue tables ------------------------------------------------------------------------------


def test_cn_is_immediate_in_single_axis_mode_even_behind_a_move() -> None:
    """§7.5 "CN | Imm / Imm / NV | 1 / NV / NV". Behind X's long move CN takes no slot and the
    ramp is cosine at once: an idle axis's RC (the acceleration at the start of a ramp) reads 0.
    On a PC48 CN waits in X's queue (1 slot) and Y still starts its ramps at AC."""
    h = busy("VS4-040")
    assert cost(h, "CN ") == [0]
    assert h.query("AY RC") == frame("0")
    pc48 = busy("PC48-4")
    assert cost(pc48, "CN ") == [1]
    assert pc48.query("AY RC") == frame("1000000")
    assert h.errors() == pc48.errors() == []


def test_cn_is_immediate_in_aa_mode() -> None:
    """§7.5 CN row, AA/AM column: VS4 "Imm", PC48 "NV"."""
    h = busy("VS4-040", "AA")
    assert cost(h, "CN ") == [0, 0, 0, 0]
    assert h.errors() == []
    assert h.query("AY RC") == frame("0")
    pc48 = busy("PC48-4", "AA")
    assert cost(pc48, "CN ") == [0, 0, 0, 0]
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "CN")]


def test_cn_is_not_valid_in_a_contour_definition() -> None:
    """§7.5 CN row, AA/CD column: "NV" on both."""
    h = Harness("VS4-040")
    h.send("AA CD0,0; CN ")
    assert errors(h) == [(ErrorKind.NOT_VALID_IN_MODE, "CN")]
    assert h.query("RQ") == frame("7160")


@pytest.mark.parametrize(("shape", "vs4_slots"), [("linear", 2), ("parabolic", 3), ("cosine", 3)])
@pytest.mark.parametrize("mode", ["AA", "AM"])
def test_bl_bh_slots_by_ramp_in_aa_and_am(shape: str, vs4_slots: int, mode: str) -> None:
    """§7.5 "BL, BH (§6.6) | AX-AT 2/2/2; AA 2/3/3; AM 2/3/3; AA/CD 2/2/2 (pf / pn,cn /
    custom) | 2 / 2 / NV". In AA (and in AM after an AA move of all four axes) every axis queue
    pays; the PC48 pays 2 whatever the ramp."""
    h = busy("VS4-040", mode, shape)
    assert cost(h, "BL8;") == [vs4_slots] * 4
    assert cost(h, "BH8;") == [vs4_slots] * 4
    pc48 = busy("PC48-4", mode, shape)
    assert cost(pc48, "BL8;") == [2] * 4
    assert h.errors() == pc48.errors() == []


@pytest.mark.parametrize("shape", ["linear", "parabolic", "cosine"])
def test_bl_bh_two_slots_in_single_axis_mode_and_in_a_contour(shape: str) -> None:
    """§7.5 BL/BH rows: "AX-AT 2/2/2 ... AA/CD 2/2/2" (and "(§6.21) same as §6.6")."""
    h = busy("VS4-040", "AX", shape)
    assert cost(h, "BL8;") == [2]
    assert cost(h, "BH8;") == [2]
    c = Harness("VS4-040")
    ramp(c, shape)
    c.send("AA CD0,0;")
    assert cost(c, "BL8;") == [2]
    assert cost(c, "BH8;") == [2]
    assert h.errors() == c.errors() == []


def test_ls_in_a_contour_definition_takes_two_slots_and_does_not_loop() -> None:
    """§7.5 "LS | 2 / 2 / **2** | 2 / 2 / NV". Digest §8 item 22: LS is valid in a contour but
    LE is not, so there is no loop to close: LS is accepted (2 contour slots) and the contour
    runs once. On a PC48 LS in a contour definition is a command error."""
    h = Harness("VS4-040")
    h.send("AA CV1000; CD0,0;")
    assert cost(h, "LS3;") == [2]
    h.send("LE")
    assert errors(h) == [(ErrorKind.NOT_VALID_IN_MODE, "LE")]
    h.send("MT100,100; CE CX")
    h.run()
    assert h.errors() == []
    assert h.query("RP") == frame("100,100,0,0")
    pc48 = Harness("PC48-4")
    pc48.send("AA CD0,0;")
    assert cost(pc48, "LS3;") == [0]
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "LS3")]


def test_ws_is_valid_in_am_with_two_slots() -> None:
    """§7.5 "WS | 2 / **2** / NV | AA 2; AM NV; AA/CD NV". AM after an AA move of all four
    axes: each of their queues pays 2; on a PC48 WS in AM is a command error."""
    h = busy("VS4-040", "AM")
    assert cost(h, "WS0;") == [2, 2, 2, 2]
    assert h.errors() == []
    pc48 = busy("PC48-4", "AM")
    assert cost(pc48, "WS0;") == [0, 0, 0, 0]
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "WS0")]


@pytest.mark.parametrize("mode", ["AX", "AA"])
def test_wh_takes_three_slots(mode: str) -> None:
    """§7.5 "WH | **3 / 3** / NV | 2 / 2 / NV"."""
    h = busy("VS4-040", mode)
    pc48 = busy("PC48-4", mode)
    n = 1 if mode == "AX" else 4
    assert cost(h, "WH") == [3] * n
    assert cost(pc48, "WH") == [2] * n
    assert h.errors() == pc48.errors() == []


def test_wa_not_valid_in_single_axis_mode_two_slots_in_aa() -> None:
    """§7.5 "WA | **NV / 2** / NV | Imm / NV / NV". Digest §8 item 25 (text "only valid in the
    AA mode" vs table "AA, AM 2"): both are honoured, AA (and AM) valid, 2 slots each queue.
    The PC48 reading (design decision): valid in AA/AM only, 0 slots."""
    h = busy("VS4-040")
    assert cost(h, "WA") == [0]
    assert errors(h) == [(ErrorKind.NOT_VALID_IN_MODE, "WA")]
    h = busy("VS4-040", "AA")
    assert cost(h, "WA") == [2, 2, 2, 2]
    assert h.errors() == []
    pc48 = busy("PC48-4", "AA")
    assert cost(pc48, "WA") == [0, 0, 0, 0]
    assert pc48.errors() == []


@pytest.mark.parametrize("mode", ["AX", "AA"])
def test_sw_takes_one_slot(mode: str) -> None:
    """§7.5 "SW | **1 / 1** / NV | Imm / Imm / NV"; the PC48's SW waits without a slot."""
    n = 1 if mode == "AX" else 4
    h = busy("VS4-040", mode)
    assert cost(h, "SW0;") == [1] * n
    pc48 = busy("PC48-4", mode)
    assert cost(pc48, "SW0;") == [0] * n
    assert h.errors() == pc48.errors() == []


def test_sw_waits_for_its_input_on_the_vs4() -> None:
    """§7.5 SW row: queued, it still waits "until the input is high": with input 2 driven low,
    a move behind ``SW2`` starts only when it is released."""
    h = Harness("VS4-040")
    h.board.set_input(2, False, 0.0)
    h.send("AX SW2; MR100 GO")
    h.until(0.5)
    assert h.position("X") == 0
    h.board.set_input(2, None, h.t)
    h.run()
    assert h.position("X") == 100


def test_rq_is_immediate_in_a_contour_definition() -> None:
    """§7.5 "RQ (§6.13) | Imm / Imm / **Imm** | Imm / Imm / NV" and "RQ (§6.21) | Imm / Imm /
    Imm | NV / 6 / NV": RQ answers in a contour definition and takes nothing from it."""
    h = Harness("VS4-040")
    h.send("AA CD0,0;")
    assert h.query("RQ") == frame("7160")
    assert h.query("RQ") == frame("7160")
    h.send("MT10,10;")
    assert h.query("RQ") == frame("7154")
    assert h.query("RQ") == frame("7154")
    assert h.errors() == []


def test_ip_is_valid_in_aa() -> None:
    """§7.5 "IP (§6.15) | 1 / **1** / NV | 1 (AU-AS NV) / NV / NV" against "IP (§6.12) | 1 /
    NV / NV". Digest §8 item 11: §6.12's table carries a PC48 leftover ("AZ - AV Not Valid"),
    so §6.15's is taken. AA IP takes one slot a queue and sets DON_S when every axis of the
    move is in position: X (100) and Y (200 counts, triangular at AC 2,000,000: 0.02 s) are,
    at tick 21/1024. A PC48-4E refuses it."""
    h = busy("VS4-040", "AA")
    assert cost(h, "IP") == [1, 1, 1, 1]
    assert h.errors() == []
    h = Harness("VS4-040")
    h.send("AA MR100,200; GO IP")
    h.until(20 / 1024)
    assert not h.board.status_register(h.t) & DON_S
    h.run()
    done = [e for e in h.events() if isinstance(e, DoneEvent)]
    assert [e.time for e in done] == [21 / 1024]
    assert h.board.status_register(h.t) & DON_S
    pc48 = busy("PC48-4E", "AA")
    assert cost(pc48, "IP") == [0, 0, 0, 0]
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "IP")]


@pytest.mark.parametrize(
    ("command", "vs4_slots", "pc48_slots"),
    [("HV1000;", 4, 2), ("HG10;", 4, 2), ("HD5;", 2, 1)],
)
def test_hv_hg_take_four_slots_hd_two(command: str, vs4_slots: int, pc48_slots: int) -> None:
    """§7.5 "HV | enc **4** | enc 2", "HG | enc **4** | enc 2", "HD | enc **2** | enc 1"."""
    h = busy("VS4-040")
    assert cost(h, command) == [vs4_slots]
    pc48 = busy("PC48-4E")
    assert cost(pc48, command) == [pc48_slots]
    assert h.errors() == pc48.errors() == []


@pytest.mark.parametrize("mnemonic", ["MP", "MM"])
def test_mp_mm_take_one_slot_in_single_axis_mode_and_are_not_valid_in_aa(mnemonic: str) -> None:
    """§7.5 "MP, MM | **1 / NV** / NV | NV / Imm / NV". The PC48 reading (design decision):
    immediate in single-axis and AA mode."""
    h = busy("VS4-040")
    assert cost(h, mnemonic) == [1]
    assert h.errors() == []
    h = busy("VS4-040", "AA")
    assert cost(h, mnemonic) == [0, 0, 0, 0]
    assert errors(h) == [(ErrorKind.NOT_VALID_IN_MODE, mnemonic)]
    pc48 = busy("PC48-4")
    assert cost(pc48, mnemonic) == [0]
    pc48 = busy("PC48-4", "AA")
    assert cost(pc48, mnemonic) == [0, 0, 0, 0]
    assert pc48.errors() == []


def test_mp_queued_behind_a_move_sets_the_direction_when_reached() -> None:
    """§7.5 MP/MM row: queued on the VS4, MP sent during a move in the minus direction takes
    effect when the queue reaches it, after the move: QA's direction reads P. On a PC48 MP is
    immediate and does nothing to a moving axis, so QA reads M."""
    for model, direction in (("VS4-040", "P"), ("PC48-4", "M")):
        h = Harness(model, world={"X": AxisWorld(home_low=10**6)})
        h.send("AX VL1000 MR-100 GO")
        h.until(0.01)
        h.send("MP")
        h.run()
        assert h.position("X") == -100
        assert h.query("QA") == status_frame(direction + "NNN"), model


@pytest.mark.parametrize("letter", ["Y", "Z", "T"])
def test_vs_on_y_z_t_is_ignored_without_error(letter: str) -> None:
    """§7.5 "VS | AX 5; AY-AT **"Ignored"** | AX 5; AY-AS "Not valid"". Digest §8 item 38
    leaves open whether "Ignored" sets CMD_S; the personality reads it as no error and no
    effect: no slot, no motion, no command error. A PC48 flags it."""
    h = Harness("VS4-040")
    h.send(f"A{letter}")
    assert cost(h, "VS1024,1000,1000;") == [0]
    h.run()
    assert h.errors() == []
    assert h.query("AA RP") == frame("0,0,0,0")
    assert not h.board.status_register(h.t) & CMD_S
    pc48 = Harness("PC48-4")
    pc48.send(f"A{letter} VS1024,1000,1000;")
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "VS1024,1000,1000")]


def test_vs_takes_five_slots_on_x() -> None:
    """§7.5 VS row: "AX 5" on both."""
    h = busy("VS4-040")
    assert cost(h, "VS1024,1000,1000;") == [5]
    assert h.errors() == []


def test_mo_only_on_a_vs4_without_encoders() -> None:
    """§7.5 "MO | 1 (pf/pn/custom columns) / AA NV, AM NV | 1 / NV", and "This command is not
    available in models with an encoder option". Digest §8 item 13: both VS4 models are listed
    with encoders, but the text speaks of boards without; the personality makes the option a
    per-board setting. With encoders MO is a command error; without, MO takes 1 slot and steps
    once in the current direction (MM first: minus); in AA it is not valid."""
    h = Harness("VS4-040")
    h.send("AX MO")
    assert errors(h) == [(ErrorKind.ENCODER_MODEL, "MO")]
    h = vs4_without_encoders()
    assert cost(h, "MO") == [1]
    h.run()
    assert h.position("X") == 1
    h.send("MM MO")
    h.run()
    assert h.position("X") == 0
    h.send("MO")
    h.run()
    assert h.position("X") == -1
    assert h.errors() == []
    h.send("AA MO")
    assert errors(h) == [(ErrorKind.NOT_VALID_IN_MODE, "MO")]


def test_encoder_commands_on_every_axis_x_to_t() -> None:
    """§7.5 "Encoder-only commands | AX-AT rows | AX-AT rows + "AU - AS Not valid" rows": every
    VS4 axis has its encoder, so RE answers on X..T; a VS4 without encoders refuses it."""
    h = Harness("VS4-040")
    h.send("AA MR10,20,30,40; GO")
    h.run()
    for letter, count in zip("XYZT", (10, 20, 30, 40), strict=True):
        assert h.query(f"A{letter} RE") == frame(str(count))
    assert h.errors() == []
    h = vs4_without_encoders()
    h.send("AT RE")
    assert errors(h) == [(ErrorKind.NO_ENCODER, "RE")]


# -- 7.6 behaviour and text differences ------------------------------------------------------------


def test_vs_moves_only_x_and_y() -> None:
    """§7.6 "VS4 VS: "Only axes X and Y will be set in motion."". VS1024,1000,-2000 runs X at
    1000/s and Y at -2000/s for 1024 samples of 1/1024 s; Z and T do not move, and there is no
    field for them."""
    h = Harness("VS4-040")
    h.send("AX VS1024,1000,-2000;")
    h.until(0.5)
    assert abs(h.position("X") - 500) <= 1
    assert abs(h.position("Y") + 1000) <= 1
    h.run()
    assert h.t == pytest.approx(1.0)
    assert h.query("AA RP") == frame("1000,-2000,0,0")
    h.send("AX VS1024,1000,1000,1000;")
    assert errors(h) == [(ErrorKind.TOO_MANY_PARAMETERS, "VS1024,1000,1000,1000")]


def test_wt_after_jg_starts_when_the_jog_is_at_speed() -> None:
    """§7.6 "VS4 WT: jog sentence (wait begins once at speed)". JG200000 at AC 2,000,000 is at
    speed at 0.1 s, seen on tick 103/1024; WT100 then waits 0.1 s and the AF behind it drives
    X's aux low at 103/1024 + 0.1 s, not at 0.1 s."""
    h = Harness("VS4-040")
    h.send("AX JG200000; WT100; AF ")
    low = 103 / 1024 + 0.1
    h.until(0.1001)
    assert h.axis("X").aux is True
    h.until(low - 1e-6)
    assert h.axis("X").aux is True
    h.until(low + 1e-6)
    assert h.axis("X").aux is False
    assert h.query("RV") == frame("200000")
    assert h.errors() == []


def test_example_form_aa_ln_picks_axes_by_field() -> None:
    """§7.6 "Example differences: ... LN (`AA LN,,,1;` vs `AT LN`)" and digest §8 item 5: the
    tables say "AA, AM Not valid" but the example uses the AA form; the personality accepts it.
    Limits off on Z and T, then ``AA LN,,,1;`` turns T's back on: T stops at its + limit (500),
    Z runs through; the PC48 flags the AA form and T runs through too."""
    world = {letter: AxisWorld(positive_limit=500, home_low=10**6) for letter in "XYZT"}
    for model, t_stop in (("VS4-040", True), ("PC48-4", False)):
        h = Harness(model, world=world)
        h.send("AZ LF AT LF AA LN,,,1; MR1000,1000,1000,1000; GO")
        h.run()
        limits = {e.axis for e in h.events() if isinstance(e, LimitEvent)}
        assert h.position("Z") == 1000
        if t_stop:
            assert limits == {"X", "Y", "T"}
            assert 500 <= h.position("T") < 520
        else:
            assert limits == {"X", "Y"}
            assert h.position("T") == 1000


def test_example_forms_aa_sf_and_aa_lp_accepted() -> None:
    """§7.6 example differences: "SF (VS4 adds `AA SF`)", "LP (`AA LP1000` vs `AX LP1000`)";
    §8 item 5: "`AA LP1000` ("would load the X axis position register with 1000")". AA SF takes
    one slot in each queue; AA LP1000 loads X only. Both are command errors on a PC48."""
    h = busy("VS4-040", "AA")
    assert cost(h, "SF ") == [1, 1, 1, 1]
    assert h.errors() == []
    h = Harness("VS4-040")
    h.send("AA LP1000;")
    h.run()
    assert h.errors() == []
    assert h.query("RP") == frame("1000,0,0,0")
    pc48 = Harness("PC48-4")
    pc48.send("AA SF LP1000;")
    assert errors(pc48) == [
        (ErrorKind.NOT_VALID_IN_MODE, "SF"),
        (ErrorKind.NOT_VALID_IN_MODE, "LP1000"),
    ]


def test_example_form_aa_uu_sets_user_units_per_axis() -> None:
    """§7.6 example differences: "UU (VS4 adds `AA UU10000,10000,10000;`)". X, Y and Z count
    10,000 steps a unit afterwards, T stays in steps; the PC48 flags the AA form."""
    h = Harness("VS4-040")
    h.send("AA UU10000,10000,10000; MR1,1,1,1; GO")
    h.run()
    assert h.errors() == []
    assert h.query("RP") == frame("10000,10000,10000,1")
    pc48 = Harness("PC48-4")
    pc48.send("AA UU10000,10000,10000; MR1,1,1,1; GO")
    pc48.run()
    assert errors(pc48) == [(ErrorKind.NOT_VALID_IN_MODE, "UU10000,10000,10000")]
    assert pc48.query("RP") == frame("1,1,1,1")


def test_control_x_clears_the_command_error_flag_and_nothing_else() -> None:
    """Not in the manual: EPICS' VS4 driver (drvOms, "Verified with firmware ... VS4-040 ver
    1.04") writes Control-X, "clears command errors only", from its interrupt routine at every
    command error. On a VS4 it clears CMD_S and is no command (were it an error, that routine
    would answer it with another Control-X for ever); the done flags stay. The PC48 has no such
    character: there it is a bad character, as before."""
    h = Harness("VS4-040")
    b = h.board
    h.send("AX MR10 GO ID ZZ")
    h.run()
    assert [kind for kind, _ in errors(h)] == [ErrorKind.UNKNOWN_COMMAND]
    assert b.status_register(h.t) & (CMD_S | DON_S) == CMD_S | DON_S
    assert h.send("\x18") == b""
    assert errors(h) == []  # no new error
    assert b.status_register(h.t) & (CMD_S | DON_S) == DON_S  # the done flag stays
    assert b.read_done_register(h.t) == 0x01
    assert h.send("AX RP\x18 RP") == frame("10") * 2  # within a line too, between commands
    assert errors(h) == []
    pc48 = Harness("PC48-4E")
    pc48.send("\x18")
    assert [kind for kind, _ in errors(pc48)] == [ErrorKind.BAD_CHARACTER]


@pytest.mark.parametrize(("mode", "end"), [("PN3", 1_400_000), ("PN9", 200_000), ("PN10", 200_000)])
def test_a_parabolic_ramp_ends_no_lower_than_ten_percent(mode: str, end: int) -> None:
    """VS4 PN: "decreases in steps of 10% of the initial acceleration down to as low as 10% ...
    3 to 10 corresponding to 70% and 10% acceleration at the peak respectively", and its own
    example is ``PN10;``. The VS4 manual has no ramp equation; the PC48's (§1.3, "10 times the
    ratio t/T2") makes PN10 end at 0 %, which the PC48 keeps (docs/decisions.md)."""
    h = Harness("VS4-040")
    h.send(f"{mode} AX VL100000 MR4000000 GO ")  # AC2000000 (power-up)
    h.until(1.0)
    assert h.send("RC") == frame(str(end))
    pc48 = Harness("PC48-4E")
    pc48.send(f"{mode} AX VL100000 AC2000000 MR4000000 GO ")
    pc48.until(1.0)
    assert pc48.send("RC") == frame(str({"PN3": 1_400_000, "PN9": 200_000}.get(mode, 0)))
