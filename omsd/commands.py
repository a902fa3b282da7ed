"""``omsd commands MODEL``: the commands a personality understands, one line each.

::

    $ omsd commands PC48-4E --grep home
    HE  HE     -                                      §6.18 p.6-64  Encoder home mode, set ...
    HM  HM[#]  -67000000 ≤ position ≤ 67000000 steps  §6.11 p.6-41  Home, find home and ...

Each line: the mnemonic; its operand form (``#`` a number, ``[#]`` one that may be left out,
``#,#,…;`` one per axis in the AA/AM modes, ``|`` between the single-axis and the AA forms);
the range of each operand, from the range tables the interpreter checks
(:mod:`omsd.dialects.pc48.ranges`, :mod:`omsd.dialects.pcix.ranges`; ``-`` for none); where the
manual describes it (section and page); what it does, in the words of the manual's command
summary (:mod:`omsd.models.summary`), with the limits of the personality in brackets (``[AA/AM
only]``, ``[encoder axes: X, Y]``, ``[servo axes]``...). The listing is what the personality
accepts: axis letters it does not have, encoder commands on a board without encoders, the
PCIx's servo commands on a board without servos are left out; the PCIx's MAX-family extension
(:mod:`omsd.models.max_family`) is listed while it is on, and says so.

``--grep TEXT`` keeps the lines whose mnemonic or description contains TEXT, whatever the case.
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass

from omsd.dialects import commands as command_table
from omsd.dialects import ranges as range_table
from omsd.models.spec import NV, CommandSpec, Model
from omsd.models.summary import (
    OMS_SECTIONS,
    PC48_SUMMARY,
    PCIX_SUMMARY,
    VS4_SUMMARY,
)
from omsd.protocol.ranges import OperandRange

#: The MAX-family extension (omsd/dialects/pcix/max_family.py): no PCIx manual page describes them.
MAX_FAMILY: dict[str, str] = {
    "PS?": "Report the axis's motor type (=O open loop, =E with encoder, =M servo)",
    "?PS": "Report the axis's motor type, as PS?",
    "PSO": "Select the open-loop stepper motor type (accepted; the fitting is the model's)",
    "PSE": "Select the stepper-with-encoder motor type (accepted; the fitting is the model's)",
    "PSM": "Select the servo motor type (accepted; the fitting is the model's)",
    "CL": "Close (CL1) or open (CL0) the loop: HN or HF",
    "CL?": "Report whether each axis's loop is closed (on/off)",
    "LPE": "Load position, as LP",
    "LT?": "Report the limit switches' active level (=l low, =h high)",
    "QL": "Report the limit switch inputs in hex (minus bits 0-7, plus bits 8-15)",
    "#WS": "Report the watchdog timeout counter (always =0)",
}
MAX_FAMILY_WHERE = "MAX extension"

_AXIS_SELECT = re.compile(r"A[XYZTUVRS]")


@dataclass(frozen=True)
class Listed:
    """One command of a personality, as ``omsd commands`` shows it."""

    mnemonic: str
    syntax: str
    range: str
    where: str
    description: str

    def matches(self, text: str) -> bool:
        wanted = text.casefold()
        return wanted in self.mnemonic.casefold() or wanted in self.description.casefold()


def listing(model: Model) -> list[Listed]:
    """Every command ``model`` accepts, sorted by mnemonic (``?XX`` queries after ``XX``)."""
    table = range_table(model)
    rows: dict[str, list[OperandRange]] = defaultdict(list)
    for row in table.for_family(model.family):
        rows[row.mnemonic].append(row)
    listed = []
    for mnemonic, spec in command_table(model).items():
        limits = _limits(model, spec)
        if limits is None:
            continue
        description, where = _summary(model, mnemonic)
        if limits:
            description += f" [{limits}]"
        listed.append(
            Listed(
                mnemonic,
                _syntax(spec, rows[mnemonic]),
                _ranges(rows[mnemonic], len(model.axes)),
                where,
                description,
            )
        )
    return sorted(listed, key=lambda c: (c.mnemonic.strip("?#"), c.mnemonic[0] in "?#", c.mnemonic))


#: Widest a column is padded to: a longer cell (VS's three ranges) pushes the rest of its line.
MAX_WIDTHS = (4, 20, 44, 18)


def format_listing(listed: list[Listed]) -> list[str]:
    """The lines, in columns: mnemonic, operand form, range, manual, description."""
    columns = [(c.mnemonic, c.syntax, c.range, c.where) for c in listed]
    widths = [
        min(cap, max((len(row[i]) for row in columns), default=0))
        for i, cap in enumerate(MAX_WIDTHS)
    ]
    return [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) + "  " + c.description
        for row, c in zip(columns, listed, strict=True)
    ]


def _summary(model: Model, mnemonic: str) -> tuple[str, str]:
    """What the manual's command summary says the command does, and where it is described."""
    if model.dialect == "pcix":
        if mnemonic in PCIX_SUMMARY:
            description, page, _ = PCIX_SUMMARY[mnemonic]
            return description, f"§5.13 p.{page}"
        return MAX_FAMILY[mnemonic], MAX_FAMILY_WHERE
    summary = VS4_SUMMARY if model.family == "VS4" else PC48_SUMMARY
    description, pages = summary[mnemonic]
    section = OMS_SECTIONS[mnemonic]
    return description, f"§{section} p.{pages.replace(', ', ',')}"


def _limits(model: Model, spec: CommandSpec) -> str | None:
    """Where the command applies on this model, in brackets after the description (``""``:
    everywhere); ``None``: nowhere on this model (it is not listed)."""
    notes: list[str] = []
    if _AXIS_SELECT.fullmatch(spec.mnemonic) and spec.mnemonic[1] not in model.axes:
        return None
    if spec.encoder_only:
        if not model.encoder_axes:
            return None
        if model.encoder_axes != model.axes:
            notes.append(f"encoder axes: {', '.join(model.encoder_axes)}")
    if spec.not_on_encoder_models and model.encoder_option:
        return None
    if spec.motor is not None:
        fits = [a for a in model.axes if _motor_fits(model, spec.motor, a)]
        if not fits:
            return None
        if fits != list(model.axes):
            notes.append(f"{_MOTORS[spec.motor]}: {', '.join(fits)}")
    if spec.single_axes is not None:
        letters = [a for a in spec.single_axes if a in model.axes]
        notes.append("A" + "/A".join(letters) + " only")
        return "; ".join(notes)
    modes = [
        name
        for name, cell in (("AX-A" + model.axes[-1], spec.single), ("AA/AM", spec.multi))
        if cell != NV
    ]
    if spec.contour != NV:
        modes.append("contour definition")
    if len(modes) < 3 and modes != [f"AX-A{model.axes[-1]}", "AA/AM"]:
        notes.append(" and ".join(modes) + " only" if modes else "never valid")
    return "; ".join(notes)


_MOTORS = {
    "servo": "servo axes",
    "feedback": "axes with encoder",
    "stepper_encoder": "steppers with encoder",
    "open_loop": "open-loop axes",
}


def _motor_fits(model: Model, motor: str, axis: str) -> bool:
    """As the interpreter decides (omsd.dialects.interpreter.motor_fits), from the model."""
    servo = model.is_servo(axis)
    encoder = model.has_encoder(axis)
    return {
        "servo": servo,
        "feedback": encoder,
        "stepper_encoder": encoder and not servo,
        "open_loop": not encoder,
    }[motor]


def _syntax(spec: CommandSpec, rows: list[OperandRange]) -> str:
    """The operand form: ``VL#``, ``HM[#]``, ``MV#,#``, ``AC# | AC#,#,…;``."""
    mn = spec.mnemonic
    if not spec.operand:
        return mn
    count = max((r.operand for r in rows), default=1)
    one = "#" if not spec.optional else "[#]"
    if spec.letter_operand:
        one = "<axis>#,#"
    elif spec.hex_operand:
        one = "<hex>"
    fixed = mn + ",".join([one] * count)
    per_axis = f"{mn}#,#,…;"
    single = spec.single != NV
    multi = spec.multi != NV
    if count > 1 or spec.letter_operand:
        return fixed
    if single and multi:
        return f"{fixed} | {per_axis}"
    if multi:
        return per_axis
    return fixed


def _ranges(rows: list[OperandRange], axes: int) -> str:
    """Each operand's range: ``0 < velocity ≤ 1044000 steps/s``; ``-`` where there is none."""
    if not rows:
        return "-"
    parts = []
    for row in sorted(rows, key=lambda r: (r.operand, r.variant)):
        if row.number == "flag":  # the value only picks an axis, or says whether
            parts.append(f"any ({row.units.split(':')[0] or 'flag'})")
            continue
        text = row.describe(axes)
        units = re.sub(r"\s*\(.*\)$", "", row.units)
        if units and units.split()[-1] not in (row.name or row.mnemonic).split():
            bounded = row.low is not None or row.high is not None or row.high_axes
            text += f" {units}" if bounded and units.startswith(_UNITS) else f" ({units})"
        if row.default is not None:
            text += f", else {row.default:g}"
        parts.append(text)
    return "; ".join(parts)


_UNITS = ("steps", "counts", "ms", "s", "1/", "radians", "samples", "%", "V")


__all__ = ["MAX_FAMILY", "Listed", "format_listing", "listing"]
