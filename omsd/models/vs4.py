"""The VS4 family (VME): VS4 user's manual, Oregon Micro Systems, 2001, document 3301-2600000 rev A.

The VS4 speaks the PC48's command language; its table is the PC48's with the differences of
section 7 of ``shared/reference/vs4.md``, each taken from the VS4 manual's own queue tables:

* No U, V, R, S axes (AU, AV, AR, AS), and no BX or RB: the VS4 manual defines neither.
* CN is immediate in single-axis and AA mode; MP and MM take one slot in single-axis mode and are
  not valid in AA; SW takes one slot; WA is valid in AA/AM only, with two slots; WH takes three;
  WS is valid in AM; IP is valid in AA (§6.15's table); HV and HG take four slots, HD two; BL and
  BH take 2 slots with linear ramps and 3 with parabolic or cosine ones in AA/AM; LS is accepted
  inside a contour definition (2 slots).
* VS in AY–AT is "Ignored" (no command error).
* The manual's own examples use AA forms its tables call "Not valid": ``AA LN,,,1;``, ``AA SF``,
  ``AA LP1000``, ``AA UU10000,10000,10000;``. An example shows what the firmware did; a table
  copied from the PC48 manual is the likelier slip, so these AA forms are accepted.

Where the VS4 manual contradicts itself (digest §8), the choices:

* Contour queue: RQ reports 7160 free when empty (§6.13 and the §6.21 example), not the "1760
  command words" of §6.21's text (a digit swap).
* Axis queue: 800 slots ("The maximum available space in each command queue is 800"); the RQ
  example's 200 is the PC48's.
* JG/JF: their own range line, ±1,044,000, although VL stops at 522,000.
* Status bit 7: "Bit 7 is the logical OR of bits 4 through 6. It is high when an interrupt is
  being requested or indicates a request for service in a polled mode": taken literally, without
  the enables (TBE_S alone makes it high).
* General-purpose I/O: "Factory default output bits are 8 through 13" (the BH command's text) is
  kept, with inputs 0–7, although the P2 connector carries I/O-0 to I/O-11 only.
* Encoders: both models are "Closed Loop (Encoder)" in appendix C, so every axis has one; the
  option can be switched off per board (configuration key ``encoders``), which also makes MO
  available, for users of a VS4 without encoders.
* Models: VS4-020 has two axes (X, Y), VS4-040 four: the middle digit is the axis count, as the
  user I/O counts of appendix C (14 = 12 + 2, 16 = 12 + 4) and WY's "number of controlled axes"
  suggest.
"""

from __future__ import annotations

from dataclasses import replace

from omsd.models.pc48 import PC48_COMMANDS
from omsd.models.spec import IMM, NV, Cell, CommandSpec, Model, q, qe, qr


def _bits() -> Cell:
    # BL/BH in AA/AM: 2 slots with PF, 3 with PN or CN ("pf / pn,cn / custom")
    return qr(2, 3, 3)


def _vs4_commands() -> dict[str, CommandSpec]:
    absent = {"AU", "AV", "AR", "AS", "BX", "RB"}
    table = {m: spec for m, spec in PC48_COMMANDS.items() if m not in absent}

    def set_(mnemonic: str, **changes: object) -> None:
        table[mnemonic] = replace(table[mnemonic], **changes)  # type: ignore[arg-type]

    set_("CN", single=IMM, multi=IMM)
    set_("MP", single=q(1), multi=NV)
    set_("MM", single=q(1), multi=NV)
    set_("SW", single=q(1), multi=q(1))
    set_("WA", single=NV, multi=q(2))
    set_("WH", single=q(3), multi=q(3))
    set_("WS", am=None)
    set_("IP", multi=q(1))
    set_("HV", single=qe(4, 4))
    set_("HG", single=qe(4, 4))
    set_("HD", single=qe(2, 2))
    set_("BL", multi=_bits(), contour=q(2))
    set_("BH", multi=_bits(), contour=q(2))
    set_("LS", contour=q(2))
    set_("VS", other_axes_ignored=True)
    # the AA forms of the VS4 examples (``AA LN,,,1;`` takes a list, so they take operands)
    for mnemonic in ("LN", "LF", "SF", "SL"):
        set_(mnemonic, multi=q(1), operand=True, optional=True)
    set_("LP", multi=qe(2, 4))
    set_("UU", multi=IMM)
    return table


VS4_COMMANDS = _vs4_commands()


def _vs4(name: str, axes: str) -> Model:
    return Model(
        name=name,
        family="VS4",
        description=f"VME, {len(axes)} stepper axes with encoder feedback",
        axes=axes,
        encoder_axes=axes,
        sample_rate=1024,
        input_buffer=256,
        queue_size=800,
        contour_queue=7160,
        commands=VS4_COMMANDS,
        firmware="1.00",
        wy_format="{model} ver {firmware} S/N {serial}",
        max_velocity=522_000,
        max_acceleration=8_000_000,
        default_velocity=200_000,
        default_acceleration=2_000_000,
        default_contour_velocity=1000,
        load_position_limit=33_554_431,
        position_limit=67_000_000,
        io_bits=14,
        factory_outputs=0x003F00,
        done_bits=tuple(range(len(axes))),
        init_time=1.5,  # "wait 1.5 seconds after reset or power up before reading the INIT bit"
        max_jog_velocity=1_044_000,
        serial="123456",
        vector_register=True,
        irq_status_or=True,
        control_x=True,
        parabolic_floor=0.1,
    )


VS4_MODELS: tuple[Model, ...] = (_vs4("VS4-020", "XY"), _vs4("VS4-040", "XYZT"))
