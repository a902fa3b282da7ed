"""The host-visible registers of the PC48 family (PC48 §3.4, Tables 3-4 to 3-8).

* Done flag register (offset 1, Table 3-6): one bit per axis. "This register is cleared
  automatically after it is read."
* Interrupt control register (offset 2, Table 3-7): IRQ_E, TBE_E, IBF_E, DON_E; read/write.
* Status register (offset 3, Table 3-8): IRQ_S, TBE_S, IBF_S, DON_S, OVRT, ENC_S, INIT, CMD_S.
  §3.4.4: "the DON_S bit (bit 4) ... is automatically reset upon reading the status register";
  "The error bits, CMD_S, ENC_S and OVRT are automatically reset after reading the register."

The done *flags* that RA/QA/RI/QI print as ``D`` are kept separately from the register latch:
reading the register (as a driver's interrupt service routine does) clears the latch but not the
flag, which only IC, Control-Y, CA, RA, RI, GD and SD reset. The manual never says whether a
register read clears RA's ``D``; keeping them apart is what lets a driver-attached host and a
polling client (EPICS drvOmsPC68 polls ``QA`` for ``D``) both see every completion.
"""

from __future__ import annotations

from dataclasses import dataclass

# Status register bits (Table 3-8)
CMD_S = 0x01
INIT = 0x02
ENC_S = 0x04
OVRT = 0x08
DON_S = 0x10
IBF_S = 0x20
TBE_S = 0x40
IRQ_S = 0x80
ERROR_BITS = CMD_S | ENC_S | OVRT

# Interrupt control register bits (Table 3-7)
DON_E = 0x10
IBF_E = 0x20
TBE_E = 0x40
IRQ_E = 0x80


@dataclass(eq=False)  # state, compared by identity (omsd.engine.states)
class Registers:
    """The registers' latched bits (the status register's others are computed when read)."""

    done: int = 0  # done flag register latch
    status: int = 0  # latched bits: CMD_S, ENC_S, OVRT, DON_S (INIT/TBE/IBF are computed)
    control: int = 0
    vector: int = 0  # VME interrupt vector (VS4 offset 9)
    irq_or: bool = False  # VS4: "Bit 7 is the logical OR of bits 4 through 6"

    def set_done(self, mask: int) -> None:
        self.done |= mask

    def read_done(self) -> int:
        value, self.done = self.done, 0
        return value

    def compose_status(self, initializing: bool, input_room: bool, output_pending: bool) -> int:
        value = self.status & (ERROR_BITS | DON_S)
        if initializing:
            value |= INIT
        if input_room and not initializing:
            value |= TBE_S
        if output_pending:
            value |= IBF_S
        if self.irq_or:
            if value & (DON_S | IBF_S | TBE_S):
                value |= IRQ_S
        elif self.irq_pending(input_room, output_pending):
            value |= IRQ_S
        return value

    def irq_pending(self, input_room: bool, output_pending: bool) -> bool:
        if not self.control & IRQ_E:
            return False
        return bool(
            (self.control & DON_E and self.status & DON_S)
            or (self.control & TBE_E and input_room)
            or (self.control & IBF_E and output_pending)
        )

    def clear_on_status_read(self) -> None:
        self.status &= ~(ERROR_BITS | DON_S)

    def clear_done_and_errors(self) -> None:
        """IC / Control-Y: "clear the done and error flags in the status register and the done
        flag register"."""
        self.done = 0
        self.status &= ~(ERROR_BITS | DON_S)
