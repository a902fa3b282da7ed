"""How a board personality is described: one :class:`Model` row per product, sharing a command
table per family.

Every command table in the manuals has the same shape ("QUEUE REQUIREMENTS"): for each mode
(single axis AX…AS, synchronized AA/AM, contour definition AA/CD) the command is *Immediate*,
*Not valid*, *Flush + n*, or takes a number of queue slots that may depend on the ramp type
(LINEAR / PARABOLIC / COSINE columns) and on the encoder option (NO ENCODER / ENCODER columns).
:class:`Cell` holds one such entry; a :class:`CommandSpec` holds the three cells of a command.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import Enum

# the LINEAR / PARABOLIC / COSINE columns of the PC48 family's tables, and the PCIx's further
# CUSTOM (SR) and S-CURVE (AJ/SS) columns
RAMP_COLUMNS = ("linear", "parabolic", "cosine", "custom", "scurve")


class Kind(Enum):
    NOT_VALID = "not valid"
    IMMEDIATE = "immediate"
    QUEUED = "queued"
    FLUSH = "flush"  # "Flush + n": flush the queue(s), then queue n slots


Row = tuple[int, int, int, int, int]
_ZERO: Row = (0, 0, 0, 0, 0)


@dataclass(frozen=True)
class Cell:
    """One entry of a command's queue table: immediate, not valid, or the slots it takes."""

    kind: Kind
    # slots[encoder][ramp]: encoder 0 = NO ENCODER, 1 = ENCODER (PCIx: "If the axis is a
    # stepper and encoder or servo axis add ..."); ramp in RAMP_COLUMNS order
    slots: tuple[Row, Row] = (_ZERO, _ZERO)
    per_axis: int = 0  # extra slots per contour axis ("4 + number of axes")
    per_segment: int = 0  # custom ramps: "6 + 2 x segments", "3 + (No. of ramp segments + 12)"
    pa: int = 0  # PCIx: "If PA (power automatic) mode is active add ..."
    settle: int = 0  # PCIx: "If an auxiliary output bit settle time has been specified add ..."

    def cost(
        self,
        ramp: str,
        encoder: bool,
        axes: int = 0,
        segments: int = 0,
        pa: bool = False,
        settle: bool = False,
    ) -> int:
        """Slots for ramp column ``ramp`` (one of :data:`RAMP_COLUMNS`)."""
        col = RAMP_COLUMNS.index(ramp)
        n = self.slots[1 if encoder else 0][col] + self.per_axis * axes
        if ramp == "custom":
            n += self.per_segment * segments
        return n + (self.pa if pa else 0) + (self.settle if settle else 0)

    def __add__(self, other: Cell) -> Cell:
        rows = tuple(
            tuple(a + b for a, b in zip(r1, r2, strict=True))
            for r1, r2 in zip(self.slots, other.slots, strict=True)
        )
        return Cell(
            self.kind,
            rows,  # type: ignore[arg-type]
            self.per_axis + other.per_axis,
            self.per_segment + other.per_segment,
            self.pa + other.pa,
            self.settle + other.settle,
        )


NV = Cell(Kind.NOT_VALID)
IMM = Cell(Kind.IMMEDIATE)


def q(n: int) -> Cell:
    """A fixed number of slots."""
    return Cell(Kind.QUEUED, ((n,) * 5, (n,) * 5))


def qr(
    linear: int, parabolic: int, cosine: int, custom: int | None = None, scurve: int | None = None
) -> Cell:
    """Slots by ramp type (LINEAR / PARABOLIC / COSINE, and the PCIx's CUSTOM / S-CURVE)."""
    row = (
        linear,
        parabolic,
        cosine,
        parabolic if custom is None else custom,
        parabolic if scurve is None else scurve,
    )
    return Cell(Kind.QUEUED, (row, row))


def qe(no_encoder: int, encoder: int) -> Cell:
    """Slots by encoder option (NO ENCODER / ENCODER columns)."""
    return Cell(Kind.QUEUED, ((no_encoder,) * 5, (encoder,) * 5))


def encoder_version(cell: Cell) -> Cell:
    """``cell``'s slots charged on an encoder version of the board only, nothing without the
    option: PC48 §6.8 GO/GD, "If the board is an encoder version, add the value found in Table
    B to the value from Table A" (the VS4 manual titles it "ADDITIONAL ENCODER QUEUE
    REQUIREMENTS")."""
    return Cell(
        cell.kind, (_ZERO, cell.slots[1]), cell.per_axis, cell.per_segment, cell.pa, cell.settle
    )


def flush(n: int) -> Cell:
    return Cell(Kind.FLUSH, ((n,) * 5, (n,) * 5))


def per_axis(base: int, each: int) -> Cell:
    return Cell(Kind.QUEUED, ((base,) * 5, (base,) * 5), each)


def addons(encoder: int = 0, pa: int = 0, settle: int = 0, segments: int = 0) -> Cell:
    """The PCIx's ``*`` add-ons, to be added to a base cell: ``q(5) + addons(encoder=3, pa=2,
    settle=3)`` is GO's "5*" with "+3 enc/servo, +2 PA, +3 settle"."""
    return Cell(Kind.QUEUED, (_ZERO, (encoder,) * 5), 0, segments, pa, settle)


@dataclass(frozen=True)
class CommandSpec:
    """One command of a family's command set, with its queue table."""

    mnemonic: str
    operand: bool  # takes a numeric operand
    single: Cell  # AX - AS
    multi: Cell  # AA, AM
    contour: Cell = NV  # AA/CD
    optional: bool = False  # the operand may be left out (MA, HM, LP, PA, PN, AN, AF)
    am: Cell | None = None  # where AM differs from AA (WS)
    encoder_only: bool = False  # "AX - AT ... NO ENCODER Not valid"
    # encoder_only in single-axis mode alone: the AA,AM row's one cell spans both columns (RL:
    # "AA,AM Immediate" on a board without the encoder option too)
    encoder_only_single: bool = False
    not_on_encoder_models: bool = False  # MO
    single_axes: str | None = None  # VS: "You must be in the AX mode"
    other_axes_ignored: bool = False  # VS4 VS: "AY - AT Ignored" rather than "Not valid"
    letter_operand: bool = False  # PCIx EG: the operand starts with an axis letter (EGX1,2;)
    hex_operand: bool = False  # PCIx BS: a hexadecimal mask
    # PCIx: the motor types a single-axis command applies to (the manual's lost icons, read from
    # the prose): None = every axis; "servo" = servo axes; "feedback" = servo or stepper with
    # encoder; "stepper_encoder" = stepper with encoder only; "open_loop" = open-loop stepper only
    motor: str | None = None
    # PCIx ML/MT: "If this is not the master axis, then the acceleration and velocity values will
    # be modified, and the following queue requirements will be added" (by the axis's ramp type)
    follower: Cell | None = None

    def cell(self, mode: str) -> Cell:
        if mode == "single":
            return self.single
        if mode == "AM" and self.am is not None:
            return self.am
        if mode == "CD":
            return self.contour
        return self.multi


@dataclass(frozen=True)
class Model:
    """A board personality: everything the engine needs to behave as one product."""

    name: str  # e.g. "PC48-4E"
    family: str  # e.g. "PC48"
    description: str
    axes: str  # axis letters fitted, in register order, e.g. "XYZT"
    encoder_axes: str  # axes with encoder feedback ("" without the encoder option)
    sample_rate: int  # velocity calculations per second
    input_buffer: int  # characters
    queue_size: int  # slots per axis queue
    contour_queue: int  # slots in the contour queue, 0 without contouring
    commands: Mapping[str, CommandSpec]
    firmware: str
    wy_format: str  # str.format with model, family, firmware, axes (count), serial
    # The limits below describe the product; the interpreter checks operands against the range
    # tables (omsd/dialects/pc48/ranges/, omsd/dialects/pcix/ranges/), which tests hold these to.
    max_velocity: float
    max_acceleration: float  # exclusive upper bound
    default_velocity: float
    default_acceleration: float
    default_contour_velocity: float
    load_position_limit: int  # LP range
    position_limit: int  # travel range of absolute targets
    io_bits: int  # general-purpose I/O lines
    factory_outputs: int  # RB at the factory jumper setting (1 = output)
    done_bits: tuple[int, ...]  # done-flag register bit per axis, in ``axes`` order
    velocity_stream_rate: int = 1024  # VS time unit: "1/1024 second sample intervals"
    init_time: float = 0.1  # seconds the INIT bit stays high after RS
    max_jog_velocity: float | None = None  # JG/JF range where it differs from VL's
    serial: str = ""  # serial number, for a WY that reports one (VS4)
    vector_register: bool = False  # VME: the interrupt vector register (VS4 offset 9)
    irq_status_or: bool = False  # VS4: IRQ_S "is the logical OR of bits 4 through 6"
    # VS4: Control-X (0x18) clears the command error flag and is no command (EPICS drvOms,
    # "Verified with firmware ... VS4-040 ver 1.04": "Control-X, clears command errors only",
    # written by its interrupt routine at every command error; the manual has no word on it)
    control_x: bool = False
    # the lowest acceleration a PN ramp ends at, as a share of AC: 0 on the PC48 and PC46 (the
    # equation of PC48 §1.3 makes PN10 end at 0 %), 0.1 on the VS4, whose manual has only the
    # words, "down to as low as 10%" ("3 to 10 corresponding to 70% and 10%")
    parabolic_floor: float = 0.0
    # where a linear move starts when VB is above VL: None = at VL (the PC48 family: VB is
    # "less than the programmed velocity", nothing more said); the PCIx's 1: "the initial
    # velocity used at the start of a move will be the VL value minus one"
    base_above_peak: float | None = None
    # Reply framing: "surround" = <LF><CR>text<LF><CR> (<LF><CR><CR> for axis status), the
    # PC48/PC46/VS4 card; "trailing" = text<LF><CR>, as the PCIx and its MAX-family descendants
    # present it on a serial or network link (shared/interop/README.md)
    framing: str = "surround"
    aliases: tuple[str, ...] = field(default=())
    # "oms": the PC48/PC46/VS4 language; "pcix": the PCIx's (2- and 3-letter mnemonics, ?XX
    # queries answered ``xx<value>``, macros, flash defaults, servo axes)
    dialect: str = "oms"
    servo_axes: str = ""  # PCIx: axes closed by the PID loop (a subset of encoder_axes)
    # PCIx: answer the MAX-family queries EPICS omsMAXnet sends (PS? LT? CL? QL PP PE #WS),
    # an extension beyond the PCIx manual that a board's config can switch off
    max_queries: bool = False
    io_inputs: int = 0  # PCIx: factory input bits (RB 0 bits), the rest of io_bits outputs

    def is_servo(self, axis: str) -> bool:
        return axis in self.servo_axes

    @property
    def encoder_option(self) -> bool:
        return bool(self.encoder_axes)

    def has_encoder(self, axis: str) -> bool:
        return axis in self.encoder_axes

    @property
    def contouring(self) -> bool:
        return self.contour_queue > 0

    @property
    def jog_limit(self) -> float:
        return self.max_jog_velocity if self.max_jog_velocity is not None else self.max_velocity

    def who_are_you(self) -> str:
        return self.wy_format.format(
            model=self.name,
            family=self.family,
            firmware=self.firmware,
            axes=len(self.axes),
            serial=self.serial,
        )
