"""The PC46 (ISA): "PC46 Intelligent Motion Controller for PC" datasheet, Oregon Micro Systems.

The datasheet "summarizes some of the PC46 command set": it lists 105 of the PC48's 107 commands
(no AR or AS: the PC46 has at most six axes, X to V) and describes them in a few lines each. For
everything it leaves out (queue tables, ranges, replies, defaults, the details of every command)
the PC46 behaves as the PC48 manual describes: it is the same command language ("Over 150
commands, 'universal' to all OMS controllers") on the same kind of card.

Where the datasheet itself is silent or contradicts itself, the choices:

* Velocity: "0 to 522,000 pulses per second" (specifications) rather than "from 0 to 1,044,000
  steps per second" (features); JG and JF are held to the same limit.
* Sample rate: "calculating the optimum velocity 1024 times each second (512 times each second
  on the -21 and -41 models)".
* Contouring: "These commands are not available on the PC46-21 and PC46-41 models": CD, CE, CK,
  CR, CV and CX are unknown commands there, and MT, AN, AF, BL, BH have no contour form.
* Encoders: "Incremental encoder feedback is available as an option on up to 2 axes", on X and Y
  of the -2E and -4E (the encoder pins of the pin tables).
* General-purpose I/O: 16 lines, "8 general purpose inputs with 2.2k Ohm pull-up resistors and 8
  general purpose outputs", with the pull-ups "on I/O bits 0-7": inputs 0–7, outputs 8–15. (The
  -21/-22/-41/-42 pin table names them the other way round; the text about the pull-ups decides.)
  The sync inputs of the -22/-42 pin tables are not mapped to an I/O bit by the datasheet and
  are not emulated.
* WY: "returns the model and firmware revision"; no example is printed, so the PC48's form is
  used, ``PC46 ver 1.00-<axes>``.
* Everything else as the PC48: 124-character input buffer and 200-slot queues (both stated in
  the datasheet), PC48 defaults (AC 1,000,000, VL 100,000), the 1016-slot contour queue.
"""

from __future__ import annotations

from dataclasses import replace

from omsd.models.pc48 import PC48_COMMANDS
from omsd.models.spec import NV, CommandSpec, Model

CONTOUR_ONLY = ("CD", "CE", "CK", "CR", "CV", "CX")


def _table(contouring: bool) -> dict[str, CommandSpec]:
    table = {m: spec for m, spec in PC48_COMMANDS.items() if m not in {"AR", "AS"}}
    if not contouring:
        for m in CONTOUR_ONLY:
            del table[m]
        for m in ("MT", "AN", "AF", "BL", "BH", "RQ", "BX"):
            table[m] = replace(table[m], contour=NV)
    return table


PC46_COMMANDS = _table(contouring=True)
PC46_COMMANDS_NO_CONTOUR = _table(contouring=False)


def _pc46(
    name: str, axes: str, encoders: str = "", rate: int = 1024, description: str = ""
) -> Model:
    contouring = rate == 1024
    return Model(
        name=name,
        family="PC46",
        description=description,
        axes=axes,
        encoder_axes=encoders,
        sample_rate=rate,
        input_buffer=124,
        queue_size=200,
        contour_queue=1016 if contouring else 0,
        commands=PC46_COMMANDS if contouring else PC46_COMMANDS_NO_CONTOUR,
        firmware="1.00",
        wy_format="{family} ver {firmware}-{axes}",
        max_velocity=522_000,
        max_acceleration=8_000_000,
        default_velocity=100_000,
        default_acceleration=1_000_000,
        default_contour_velocity=1000,
        load_position_limit=33_554_431,
        position_limit=67_000_000,
        io_bits=16,
        factory_outputs=0x00FF00,
        done_bits=tuple(range(len(axes))),
    )


PC46_MODELS: tuple[Model, ...] = (
    _pc46("PC46-21", "XY", rate=512, description="2 stepper axes, 512 samples/s, no contouring"),
    _pc46("PC46-22", "XY", description="2 stepper axes"),
    _pc46("PC46-41", "XYZT", rate=512, description="4 stepper axes, 512 samples/s, no contouring"),
    _pc46("PC46-42", "XYZT", description="4 stepper axes"),
    _pc46("PC46-6", "XYZTUV", description="6 stepper axes"),
    _pc46("PC46-2E", "XY", "XY", description="2 stepper axes with encoder feedback"),
    _pc46("PC46-4E", "XYZT", "XY", description="4 stepper axes, encoder feedback on X and Y"),
)
