"""The MAX-family query extension of the PCIx personality: the rows the EPICS ``omsMAXnet``
client sends that the PCIx manual does not define.

The PCIx manual (document 3301-0800000 rev C, digest ``shared/reference/pcix.md`` §4) lists 203
commands. Its successors, the MAXv and MAXnet, added commands that EPICS's ``motorOmsAsyn``
driver (``omsAsynApp/src/omsBaseController.cpp``, ``omsMAXnet.cpp``) relies on when it talks to a
board whose ``WY`` reports firmware 1.30 or later. Every RX line of
``shared/interop/epics-omsMAXnet.trace`` was checked against digest §4; these are the mnemonics
the PCIx lacks:

========  ==================================================================================
``PSO``   the ``"AX LH PSO; AY LH PSO;"`` init string: select the open-loop stepper motor type
``PS?``   ``"A? PS?"`` at start-up: the axis's motor type
``LT?``   ``"A? LT?"`` at start-up: the limit switches' true level
``CL?``   ``"AM;CL?;"`` on every idle poll: closed-loop state per axis
``QL``    ``"AM;QL;"`` on every poll: the limit switch inputs, in hex
``#WS``   ``"#WS"`` on every poll (firmware 1.33 and later): the watchdog timeout counter
========  ==================================================================================

``PSE`` and ``PSM``, the other two motor types of the ``PS?`` answer (``"we expect any of "=O",
"=E","=M""``, omsBaseController.cpp), are added with ``PSO`` so that an init string written for
another axis type is accepted as well. ``PP`` and ``PE``, which the client also sends, are PCIx
commands (digest §4, §5.7.5) and stay in the PCIx table.

Queue cells (the MAX manuals are not in ``shared/``; the choices follow the PCIx's own rows):

* ``PS?`` and ``LT?`` are immediate in single-axis mode and not valid in AA/AM, like every PCIx
  per-axis query (``?LS``, ``EG?``: "AX–AT Imm; AA/AM NV"); the client only ever sends them
  after ``AX``…``AT``.
* ``CL?`` is immediate in single-axis mode (one axis) and in AA/AM (every axis, comma separated:
  the client sends ``AM;CL?;`` and splits the answer at commas).
* ``QL`` and ``#WS`` report the whole board, immediately, in any mode but a contour definition,
  as the PCIx's ``PP``/``PE`` do ("even in single-axis mode").
* ``PSO``/``PSE``/``PSM`` are immediate, single-axis commands: they configure the addressed axis
  (``"AX LH PSO;"``); the PCIx's motor types are fixed at the factory, see
  :mod:`omsd.dialects.pcix.max_family`.
"""

from __future__ import annotations

from omsd.models.spec import IMM, NV, Cell, CommandSpec, addons, q


def _row(mnemonic: str, single: Cell, multi: Cell) -> CommandSpec:
    """A command without operand, not valid inside a contour definition (AA/CD)."""
    return CommandSpec(mnemonic, False, single, multi, NV)


MAX_COMMANDS: dict[str, CommandSpec] = {
    c.mnemonic: c
    for c in (
        _row("PS?", IMM, NV),
        _row("?PS", IMM, NV),
        CommandSpec("CL", True, q(2), NV, NV, motor="feedback"),  # as HN/HF
        CommandSpec("LPE", True, q(2) + addons(encoder=2), NV, NV, motor="feedback"),  # as LP
        _row("LT?", IMM, NV),
        _row("CL?", IMM, IMM),
        _row("QL", IMM, IMM),
        _row("#WS", IMM, IMM),
        _row("PSO", IMM, NV),
        _row("PSE", IMM, NV),
        _row("PSM", IMM, NV),
    )
}
