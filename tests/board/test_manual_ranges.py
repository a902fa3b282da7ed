"""Operand ranges where the emulator used to differ from the manuals, each with the manual's
words (the generated edge tests of every row are in ``test_operand_ranges.py``), and the PCIx's
hexadecimal BS mask.
"""

from __future__ import annotations

import pytest

from omsd.board.events import ErrorKind
from omsd.board.harness import Harness

OUT = ErrorKind.OUT_OF_RANGE


def kinds(h: Harness) -> list[ErrorKind]:
    return [e.kind for e in h.errors()]


def accepted(model: str, *commands: str) -> None:
    for command in commands:
        h = Harness(model)
        h.send(command)
        assert kinds(h) == [], command


def refused(model: str, *commands: str) -> None:
    for command in commands:
        h = Harness(model)
        h.send(command)
        assert kinds(h) == [OUT], command


# -- PCIx: the command pages' RANGE lines -------------------------------------------------------


def test_pcix_es() -> None:
    """ES page: "STEPPER RANGE: 0 < ES ≤ 65,535"."""
    accepted("PCIX-040", "AX;ES1;", "AX;ES65535;")
    refused("PCIX-040", "AX;ES0;", "AX;ES65536;", "AX;ES-1;")
    h = Harness("PCIX-040")
    h.send("AX;ES65535;ES0;")
    assert h.query("AX;?ES;") == b"es65535\n\r"


def test_pcix_hd() -> None:
    """HD page: "RANGE: 0 ≤ HD ≤ 64,000"."""
    accepted("PCIX-040", "AX;HD0;", "AX;HD64000;")
    refused("PCIX-040", "AX;HD64001;", "AX;HD-1;")


def test_pcix_hv() -> None:
    """HV page: "RANGE: 1 ≤ HV ≤ 1,039,999"."""
    accepted("PCIX-040", "AX;HV1;", "AX;HV1039999;")
    refused("PCIX-040", "AX;HV0;", "AX;HV1040000;", "AX;HV1044000;")


def test_pcix_wt() -> None:
    """WT page: "RANGE: 1 ≤ WT ≤ 200,000" (the PC48's is "between 1 and 32,000")."""
    accepted("PCIX-040", "AX;WT1;", "AX;WT32001;", "AX;WT200000;")
    refused("PCIX-040", "AX;WT0;", "AX;WT200001;")
    refused("PC48-4", "AX WT32001 ")


def test_pcix_ls() -> None:
    """LS page: "RANGE: 1 ≤ LS ≤ 32,767"."""
    accepted("PCIX-040", "AX;LS32767;")
    refused("PCIX-040", "AX;LS0;", "AX;LS32768;")


def test_pcix_vs() -> None:
    """VS page: "1 ≤ Parameter 1 (Time in 1 update rate of a second) ≤ 1,043,999", the
    velocities "≤ 1,043,999" (signed, as the page's own ``VS1024,-1000,1000`` streams)."""
    accepted("PCIX-040", "AX;VS1043999,0,0;", "AX;VS10,-1043999,1043999;")
    refused("PCIX-040", "AX;VS0,0,0;", "AX;VS1044000,0,0;", "AX;VS10,1044000,0;")
    refused("PCIX-040", "AX;VS10,0,-1044000;")


def test_pcix_mv_velocity() -> None:
    """MV page: "1 ≤ Parameter 2 (Velocity) ≤ 1,043,999" (the direction is MP/MM's)."""
    accepted("PCIX-040", "AX;MP;MV1000,1;", "AX;MP;MV1000,1043999;")
    refused("PCIX-040", "AX;MV1000,0;", "AX;MV1000,-5;", "AX;MV1000,1044000;")


def test_pcix_cv() -> None:
    """CV page: "RANGE: 1 ≤ CV ≤ 1,043,999"."""
    accepted("PCIX-040", "AA;CV1;", "AA;CV1043999;")
    refused("PCIX-040", "AA;CV0.5;", "AA;CV1044000;")


def test_pcix_in_may_be_negative() -> None:
    """IN page: "-33,544,431 ≤ Parameter (Distance Before End of Move) ≤ 33,544,431"; a negative
    distance interrupts at the end of the move, as IN0 does."""
    h = Harness("PCIX-040")
    h.send("AX;VL100000;IN-100;MR1000;GO;")
    assert kinds(h) == []
    h.run()
    assert h.axis("X").done
    refused("PCIX-040", "AX;IN33554432;", "AX;IN-33554432;")


def test_pcix_jf_fraction_at_the_top() -> None:
    """JF page: "RANGE: -1,043,999.999 ≤ JF ≤ 1,043,999.995"."""
    accepted("PCIX-040", "AX;JF1043999.995;", "AX;JF-1043999.999;")
    refused("PCIX-040", "AX;JF1043999.996;", "AX;JF-1044000;")


def test_pcix_ws_inputs() -> None:
    """WS page: "#RANGE : 0 ≤ Parameter1 ≤ 3" (SW and BW: "0 ≤ Bit Number ≤ 7")."""
    accepted("PCIX-040", "AX;WS3;", "AX;SW7;", "AX;BW7;")
    refused("PCIX-040", "AX;WS4;", "AX;SW8;", "AX;BW8;")


def test_vb_below_the_velocity_limit() -> None:
    """VB: "0 ≤ VB < VL value" (PCIx), "less than the programmed velocity" (PC48): never the
    largest VL itself."""
    accepted("PCIX-040", "AX;VB0;", "AX;VB1043999;")
    refused("PCIX-040", "AX;VB1044000;")
    accepted("PC48-4", "AX VB0 ", "AX VB1043999 ")
    refused("PC48-4", "AX VB1044000 ")
    refused("VS4-040", "AX VB522000 ")


def test_contour_positions() -> None:
    """CR (PCIx): "Min Pos. Value ≤ Parameter 1 (First Coordinate for Center of Circle) ≤ Max
    Pos. Value"; the PC48's contour positions are held to Appendix C's "±67,000,000"."""
    refused("PCIX-040", "AA;CD0,0;CR33554432,0,1;", "AA;CD33554432,0;")
    refused("PC48-4", "AA CD0,0; CR67000001,0,1 ", "AA CD67000001,0; ", "AA CD0,0; MT67000001,0; ")
    accepted("PC48-4", "AA CD0,0; CR67000000,0,1 ", "AA CD-67000000,0; ")


def test_whole_numbers_are_truncated_before_the_check() -> None:
    """A fraction of a whole-number operand is dropped first (``MR100.9`` moves 100): SR4.9 is
    SR4 ("1 ≤ SR ≤ 4"), KF32767.5 is KF32767 ("0 ≤ KF ≤ 32,767")."""
    h = Harness("PCIX-040")
    h.send("DAR4;DAB1,1;DAE;AX;SR4.9;")
    assert kinds(h) == []
    assert h.query("AX;?RT;") == b"sr4\n\r"
    accepted("PCIX-400", "AX;KF32767.5;")


# -- PCIx BS: a hexadecimal mask -----------------------------------------------------------------


@pytest.mark.parametrize(
    ("mask", "bx"),
    [
        # outputs are bits 4-7 (factory S3); inputs 0-3 read high: "Data written to input bits
        # has no effect"
        ("71", "7f"),  # the page's example, "71 = (hex) 01110001"
        ("A5", "af"),
        ("a5", "af"),
        ("FF", "ff"),
        ("ff", "ff"),
        ("F0", "ff"),
        ("0F", "0f"),
        ("C3", "cf"),
        ("00", "0f"),
        ("B", "0f"),
        ("DE", "df"),
    ],
)
def test_bs_mask_is_hexadecimal(mask: str, bx: str) -> None:
    """BS page: "The mask must be in ASCII hex format where the least significant bit (bit 0)
    is on the right. To set a line low, the corresponding bit in the hex mask must be a 0. A
    one (1) in any bit position will set the corresponding bit high." "Range: 00 ≤ Hex number
    ≤ FF"."""
    h = Harness("PCIX-040")
    h.send(f"AX;BS{mask};")
    assert kinds(h) == []
    assert h.query("BX;") == f"{bx}\n\r".encode()


def test_bs_mask_beyond_ff_is_out_of_range() -> None:
    h = Harness("PCIX-040")
    h.send("AX;BS71;BS1FF;BS100;")
    assert kinds(h) == [OUT, OUT]
    assert h.query("BX;") == b"7f\n\r"
