"""A review of the host-visible registers against the manuals: the status register, the done
flag register, the interrupt control register (and the VS4's vector register), driven through
the board's register methods (PC48 §3.4, VS4 §3.4, PCIx §3.7-3.9, the PC46's "PC/XT/AT
REGISTERS"). Each test quotes what it checks; the choices the manuals leave open are in
``docs/decisions.md`` ("Flags and registers")."""

from __future__ import annotations

import pytest

from omsd.board.board import Board
from omsd.engine.registers import DON_S, IBF_E, IBF_S, IRQ_E, IRQ_S, TBE_S
from omsd.models import get_model


@pytest.mark.parametrize("model", ["PC48-4E", "PC46-6", "VS4-040", "PCIX-400"])
def test_ibf_s_is_a_character_to_read_not_an_event(model: str) -> None:
    """PC48 Table 3-8 (L509): "IBF_S Input buffer full status. This high true bit indicates a
    character is available in the input buffer." (VS4 Table 3-6, PCIx Table 3-3 the same.) A
    done puts no byte on the data port (§3.3: the host learns of it through DON_S and the done
    flag register): after ``ID`` with nothing said, IBF_S is low, and with IBF_E enabled no
    interrupt is requested for it. Before the review IBF_S was high whenever the board held an
    event not yet taken, as if a character were waiting."""
    board = Board(get_model(model), 0.0)
    board.write_control_register(IRQ_E | IBF_E, 0.0)
    board.receive(b"AX;MR100;GO;ID;", 0.0)
    board.advance(1.0)
    assert board.take_bytes() == b""  # nothing to read; the done is the registers' news
    board.receive(b"AX;MR100;GO;ID;", 1.0)
    board.advance(2.0)
    status = board.read_status_register(2.0)
    assert status & DON_S
    assert not status & IBF_S
    if model.startswith("VS4"):
        # "Bit 7 is the logical OR of bits 4 through 6": DON_S and TBE_S are high here
        assert status & IRQ_S
    else:
        assert not status & IRQ_S  # IBF_E alone: nothing to read, no request
    # a reply is a character to read: IBF_S high, and with IBF_E an interrupt request
    board.receive(b"RP;", 2.0)
    status = board.status_register(2.0)
    assert status & IBF_S
    assert status & IRQ_S
    assert status & TBE_S
