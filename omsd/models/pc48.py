"""The PC48 family (PC48 user's manual, Oregon Micro Systems, 2001, document 3301-0400000 rev D).

Every command of chapter 6 with the queue table printed under it. Where the manual prints two
different tables for one command, the choice is noted beside the row:

* BH/BL: §6.6 says "AX - AS 2, AA - AM 2, AA/CD Not valid"; §6.21 says "1, 1, 2". §6.6 is the
  command's own section, so 2 slots outside a contour; inside a contour §6.21's 2 slots.
* BX: §6.6 "AA/CD Not valid", §6.13 "AA/CD Immediate": immediate everywhere (a status read
  cannot hurt a contour definition).
* RQ: §6.13 "Immediate", §6.21 "AX - AS Not valid, AA,AM 6". The §6.21 example issues RQ
  inside a contour definition and gets the contour queue, so RQ is immediate in every mode.
* MP/MM: the table says "AX - AS Not valid, AA,AM Immediate" but every example uses them in
  single-axis mode (``AY MM``, ``AZ MM MO``, ``MP MV…``): immediate in both.
* WA: the table reads "AX - AS Immediate, AA,AM Not valid" but the text says "only valid in the
  AA mode"; the table is taken to be transposed. WA and SW are marked "Immediate" (they take no
  queue space) but make the axes wait, so they are queued with 0 slots.
* SE: "available in single axis mode only" but the table gives "AA - AM 3": the table wins.
* GO/GD: Table A by encoder option; Table B (by ramp type) is added on encoder versions only:
  "To find the total queue requirements for a specific application, find the appropriate value
  in Table A. If the board is an encoder version, add the value found in Table B to the value
  from Table A" (the VS4 manual's Table B is titled "ADDITIONAL ENCODER QUEUE REQUIREMENTS").
  So a board without encoders is charged GO 4 / 5 and GD 5 / 6 (single axis / AA,AM) whatever
  the ramp; an encoder version GO 7 / 8 + 6, 15, 15 and GD 8 / 9 + 6, 15, 15 (AA,AM linear,
  parabolic, cosine).
"""

from __future__ import annotations

from omsd.models.spec import (
    IMM,
    NV,
    CommandSpec,
    Model,
    encoder_version,
    flush,
    per_axis,
    q,
    qe,
    qr,
)


def _c(
    mnemonic: str, operand: bool, single: object, multi: object, contour: object = NV, **kw: object
) -> CommandSpec:
    return CommandSpec(mnemonic, operand, single, multi, contour, **kw)  # type: ignore[arg-type]


def _o(mnemonic: str, single: object, multi: object, contour: object = NV) -> CommandSpec:
    """A command whose operand may be left out: a space after it ends the command."""
    return CommandSpec(mnemonic, True, single, multi, contour, optional=True)  # type: ignore[arg-type]


_ENC = {"encoder_only": True}

PC48_COMMANDS: dict[str, CommandSpec] = {
    c.mnemonic: c
    for c in (
        # 6.4 axis specification
        _c("AA", False, IMM, q(2)),
        _c("AM", False, IMM, IMM),
        *(_c(f"A{letter}", False, IMM, IMM) for letter in "XYZTUVRS"),
        # 6.5 system control
        _c("EN", False, IMM, NV),
        _c("EF", False, IMM, NV),
        _c("HH", False, q(1), NV),
        _c("HL", False, q(1), NV),
        _c("LF", False, q(1), NV),
        _c("LN", False, q(1), NV),
        _c("SL", False, q(1), NV),
        _c("SF", False, q(1), NV),
        _c("CN", False, q(1), NV),
        _o("PN", IMM, IMM),
        _c("PF", False, IMM, IMM),
        _c("RS", False, IMM, IMM),
        # 6.6 user I/O (and their contour forms, 6.21)
        _o("AN", q(1), q(1), q(2)),
        _o("AF", q(1), q(1), q(2)),
        _o("PA", q(2), q(2)),
        _c("SE", True, q(3), q(3)),
        _c("BL", True, q(2), q(2), q(2)),
        _c("BH", True, q(2), q(2), q(2)),
        _c("BX", False, IMM, IMM, IMM),
        _c("RB", False, q(1), NV),
        # 6.7 move specification
        _c("AC", True, qr(4, 15, 15), qr(4, 15, 15)),
        _c("VL", True, qr(2, 13, 13), qr(2, 13, 13)),
        _c("VB", True, q(2), q(2)),
        _o("LP", qe(2, 4), NV),
        _o("MA", q(2), q(2)),
        _c("MR", True, q(2), q(2)),
        _c("ML", True, NV, qr(6, 30, 30)),
        _c("MT", True, NV, qr(6, 30, 30), per_axis(4, 1)),
        _c("MO", False, q(1), NV, not_on_encoder_models=True),
        _c("RM", True, q(1), NV),
        # 6.8 move execution
        # Table A (NO ENCODER / ENCODER) + Table B (LINEAR / PARABOLIC / COSINE, encoder
        # versions only; its AX - AS row is 0 0 0)
        _c("GO", False, qe(4, 7), qe(5, 8) + encoder_version(qr(6, 15, 15))),
        _c("GD", False, qe(5, 8), qe(6, 9) + encoder_version(qr(6, 15, 15))),
        _c("JG", True, q(2), NV),
        _c("JF", True, qe(2, 3), NV),
        _c("VS", True, q(5), NV, single_axes="X"),
        # 6.9 move termination
        _c("ST", False, flush(2), flush(2)),
        _c("SA", False, flush(2), flush(2)),
        _c("SD", False, flush(2), flush(2)),
        _c("KL", False, flush(2), flush(2)),
        # 6.10 loop control
        _c("LS", True, q(2), q(2)),
        _c("LE", False, q(2), q(2)),
        _c("WS", True, q(2), q(2), am=NV),
        _c("WD", False, q(2), q(2)),
        _c("WH", False, q(2), q(2)),
        _c("WG", False, q(2), q(2)),
        _c("CW", False, q(1), q(1)),
        # 6.11 home and initialization
        _o("HM", qe(4, 6), NV),
        _o("HR", qe(4, 6), NV),
        _c("KM", False, q(2), NV),
        _c("KR", False, q(2), NV),
        # 6.12 move synchronization
        _c("ID", False, q(1), q(1)),
        _c("II", False, q(1), q(1)),
        _c("IN", True, q(2), q(2)),
        _c("IP", False, q(1), NV, **_ENC),
        _c("IC", False, IMM, IMM),
        _c("CA", False, IMM, NV),
        _c("WA", False, NV, q(0)),
        _c("WQ", False, IMM, IMM),
        _c("SW", True, q(0), q(0)),
        _c("WT", True, q(3), q(3)),
        # 6.13 system status requests
        _c("WY", False, IMM, IMM),
        _c("RP", False, IMM, IMM),
        _c("RQ", False, IMM, IMM, IMM),
        _c("RA", False, IMM, NV),
        _c("RI", False, NV, IMM),
        _c("QA", False, IMM, NV),
        _c("QI", False, NV, IMM),
        _c("RC", False, IMM, IMM),
        _c("RV", False, IMM, IMM),
        _c("RU", False, IMM, NV),
        # 6.14 user units
        _c("UU", True, IMM, NV),
        _c("UF", False, IMM, NV),
        # 6.15 - 6.19 encoder option
        _c("ER", True, q(1), NV, **_ENC),
        _c("HV", True, q(2), NV, **_ENC),
        _c("HG", True, q(2), NV, **_ENC),
        _c("HD", True, q(1), NV, **_ENC),
        _c("HF", False, q(2), NV, **_ENC),
        _c("HN", False, q(2), NV, **_ENC),
        _c("ES", True, q(2), NV, **_ENC),
        _c("IS", False, q(1), NV, **_ENC),
        # (its AA,AM row, "Immediate", spans both columns, as IS's "Not valid" does)
        _c("RL", False, IMM, IMM, encoder_only=True, encoder_only_single=True),
        _c("ET", False, q(2), NV, **_ENC),
        _c("HE", False, IMM, NV, **_ENC),
        _c("HS", False, IMM, NV, **_ENC),
        _c("EA", False, IMM, NV, **_ENC),
        _c("RE", False, IMM, NV, **_ENC),
        # 6.20 velocity staircase
        _c("MP", False, IMM, IMM),
        _c("MM", False, IMM, IMM),
        _c("MV", True, qe(4, 5), NV),
        _c("SP", True, qe(3, 4), NV),
        _c("FP", True, flush(4), NV),
        # 6.21 constant velocity contouring
        _c("CD", True, NV, q(0)),
        _c("CE", False, NV, NV, q(1)),
        _c("CK", False, NV, NV, q(1)),
        _c("CR", True, NV, NV, q(8)),
        _c("CV", True, NV, IMM),
        _c("CX", False, NV, q(6)),
    )
}


def _pc48(
    name: str,
    axes: str,
    encoders: str,
    done_bits: tuple[int, ...] | None = None,
    description: str = "",
) -> Model:
    return Model(
        name=name,
        family="PC48",
        description=description,
        axes=axes,
        encoder_axes=encoders,
        sample_rate=2048,
        input_buffer=124,
        queue_size=200,
        contour_queue=1016,
        commands=PC48_COMMANDS,
        firmware="3.00",
        wy_format="{family} ver {firmware}-{axes}",
        max_velocity=1_044_000,
        max_acceleration=8_000_000,
        default_velocity=100_000,
        default_acceleration=1_000_000,
        default_contour_velocity=1000,
        load_position_limit=33_554_431,
        position_limit=67_000_000,
        io_bits=14,
        factory_outputs=0x003F00,
        done_bits=done_bits or tuple(range(len(axes))),
    )


PC48_MODELS: tuple[Model, ...] = (
    _pc48("PC48-2", "XY", "", description="2 open-loop stepper axes"),
    _pc48("PC48-4", "XYZT", "", description="4 open-loop stepper axes"),
    _pc48("PC48-6", "XYZTUV", "", description="6 open-loop stepper axes"),
    _pc48("PC48-8", "XYZTUVRS", "", description="8 open-loop stepper axes"),
    _pc48("PC48-2E", "XY", "XY", description="2 stepper axes with encoder feedback"),
    _pc48("PC48-4E", "XYZT", "XYZT", description="4 stepper axes with encoder feedback"),
    # PC48 §5.4: "the U and V axes limit select jumpers (J47) and done flag register bit
    # assignments on the PC48-6E version controllers are as defined in the manual for the R and
    # S axes": U reports in bit 6 and V in bit 7.
    _pc48(
        "PC48-6E",
        "XYZTUV",
        "XY",
        done_bits=(0, 1, 2, 3, 6, 7),
        description="6 stepper axes, encoder feedback on X and Y",
    ),
)
