"""The done-flag, interrupt-control and status registers (PC48 §3.4, Tables 3-6 to 3-8)."""

from __future__ import annotations

from omsd.board.events import CommandErrorEvent, DoneEvent, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.registers import CMD_S, DON_E, DON_S, INIT, IRQ_E, IRQ_S, OVRT, TBE_S


def test_idle_status_is_transmit_buffer_empty_only(pc48: Harness) -> None:
    assert pc48.board.read_status_register(0.0) == TBE_S


def test_done_register_clears_on_read_but_ra_still_shows_done(pc48: Harness) -> None:
    """Table 3-6: "This register is cleared automatically after it is read." The RA 'D' flag is
    kept apart (docs/decisions.md): a polling client still sees the completion."""
    pc48.send("AY MR100 GO ID")
    pc48.run()
    assert pc48.board.read_done_register(pc48.t) == 0b10
    assert pc48.board.read_done_register(pc48.t) == 0
    assert pc48.query("AX QA") == b"\n\r\rPNNN\n\r\r"  # X untouched
    assert pc48.query("AY QA") == b"\n\r\rPDNN\n\r\r"


def test_status_done_and_error_bits_clear_on_read(pc48: Harness) -> None:
    """§3.4.4: DON_S "is automatically reset upon reading the status register"; "The error bits,
    CMD_S, ENC_S and OVRT are automatically reset after reading the register.\""""
    pc48.send("ZZ")
    status = pc48.board.read_status_register(pc48.t)
    assert status & (CMD_S | DON_S) == CMD_S | DON_S
    assert pc48.board.read_status_register(pc48.t) == TBE_S


def test_ic_and_control_y_clear_done_and_error_flags(pc48: Harness) -> None:
    pc48.send("AX MR10 GO ID")
    pc48.run()
    pc48.send("ZZ")
    assert pc48.board.status_register(pc48.t) & (CMD_S | DON_S)
    pc48.send("IC")
    assert pc48.board.status_register(pc48.t) == TBE_S
    assert pc48.board.registers.done == 0
    assert pc48.query("QA") == b"\n\r\rPNNN\n\r\r"
    pc48.send("MR10 GO ID")
    pc48.run()
    pc48.send(b"\x19")
    assert pc48.board.status_register(pc48.t) == TBE_S
    assert pc48.query("QA") == b"\n\r\rPNNN\n\r\r"


def test_ca_clears_only_the_addressed_axis() -> None:
    h = Harness("PC48-4")
    h.send("AA MR10,10,10,10; GO ID")
    h.run()
    assert h.board.registers.done == 0b1111
    h.send("AZ CA AA")
    assert h.board.registers.done == 0b1011
    assert h.query("QI") == b"\n\r\rPDNN,PDNN,PNNN,PDNN\n\r\r"


def test_aa_id_sets_bits_per_axis_and_don_s_after_the_last() -> None:
    """§6.12 ID: "the done flag register bits will be set as each axis encounters the ID in its
    command stream, but the done flag in the status register will not be set until all axes have
    executed the ID command." """
    h = Harness("PC48-2")
    h.send("AA VL1000,1000; MR1000; GO ID")
    h.advance(0.01)
    # Y has no move: it reached its ID already; X has not
    assert h.board.registers.done == 0b10
    assert not h.board.status_register(h.t) & DON_S
    assert not [e for e in h.events() if isinstance(e, DoneEvent)]
    h.run()
    assert h.board.registers.done == 0b11
    assert h.board.status_register(h.t) & DON_S
    assert [e.done_register for e in h.events() if isinstance(e, DoneEvent)] == [0b11]


def test_ra_resets_overtravel_unless_another_axis_is_in_limit() -> None:
    """§6.13 RA: "The limit flag in the hardware status register will be reset by the RA command,
    providing another axis is not in limit." """
    world = {"X": AxisWorld(positive_limit=100), "Y": AxisWorld(positive_limit=100)}
    h = Harness("PC48-2", world=world)
    h.send("AA VL1000,1000; MR500,500; GO")
    h.run()
    assert {type(e) for e in h.events()} == {LimitEvent}
    assert h.board.status_register(h.t) & OVRT
    h.send("AX RA")
    assert h.board.status_register(h.t) & OVRT  # Y is still in its limit
    h.send("AY MR-50 GO")
    h.run()
    h.send("AX RA")
    assert not h.board.status_register(h.t) & OVRT


def test_rs_raises_init_and_disables_interrupts(pc48: Harness) -> None:
    """§6.5 RS: "All interrupts are disabled"; "The "Initializing" in process bit goes high during
    the initialization process." Commands sent meanwhile are answered once it is over."""
    b = pc48.board
    b.write_control_register(IRQ_E | DON_E, 0.0)
    assert b.read_control_register(0.0) == IRQ_E | DON_E
    assert pc48.send("RS WY") == b""
    assert b.status_register(pc48.t) & INIT
    assert not b.status_register(pc48.t) & TBE_S
    assert b.read_control_register(pc48.t) == 0
    assert pc48.advance(0.2) == b"\n\rPC48 ver 3.00-4\n\r"
    assert not b.status_register(pc48.t) & INIT


def test_irq_status_follows_the_enables(pc48: Harness) -> None:
    b = pc48.board
    pc48.send("ID")
    assert b.status_register(pc48.t) & DON_S
    assert not b.status_register(pc48.t) & IRQ_S
    b.write_control_register(IRQ_E | DON_E, pc48.t)
    assert b.status_register(pc48.t) & IRQ_S
    b.read_status_register(pc48.t)
    assert not b.status_register(pc48.t) & IRQ_S


def test_pc48_6e_u_and_v_use_the_r_and_s_bits() -> None:
    """§5.4: on the PC48-6E "the U and V axes ... done flag register bit assignments ... are as
    defined in the manual for the R and S axes"."""
    h = Harness("PC48-6E")
    h.send("AU ID AV ID")
    assert h.board.read_done_register(h.t) == 0b1100_0000


def test_command_error_event_names_the_command(pc48: Harness) -> None:
    pc48.send("VL0 ")
    (event,) = [e for e in pc48.events() if isinstance(e, CommandErrorEvent)]
    assert event.command == "VL0"
    assert event.kind.name == "OUT_OF_RANGE"


def test_trailing_framing_for_the_pcix_dialect() -> None:
    """The PCIx and the MAX family answer ``text<LF><CR>`` with nothing before (a leading
    ``<LF><CR>`` reads as an empty reply to the omsMAXnet client)."""
    from dataclasses import replace

    from omsd.board.board import Board
    from omsd.models import get_model

    board = Board(replace(get_model("PC48-4"), framing="trailing"), 0.0)
    board.receive(b"WY AX QA RP", 0.0)
    assert board.take_bytes() == b"PC48 ver 3.00-4\n\rPNNN\n\r0\n\r"
