"""The PCIx's user defaults in flash (§5.4.2): what AP saves, what RD and power-up restore and
what RF resets.

AP: "The parameters are: AC, BI/UN, BRER, ES, HD, HG, HH/HL, HV, KA, KB, KD, KF, KI, KO, KP, KU,
KV, LA/SC/PR/SS/AJ, LH/LL, LN/LF, PA0/PA1, SE, SF/SL, VB, VL, and UU". "BRER" is read as BC and
ER (the backlash and encoder-ratio pages both say AP saves them). The other command pages add
DBI/DBN, DZ, CN, PN, PF, SVI/SVN and the auxiliary power-up state (ADH/ADL), all saved too. The
ramp tables (DAR) and S-curve profiles (AJ) the saved ramps refer to are saved with them: a
saved ``SR2`` without table 2 would be a ramp the next power-up cannot run. DC is not in any
list and is not saved ("defaults to 200,000").

The saved set is a JSON object (``omsd.statefile.BoardFlash.defaults``)::

    {"axes": {"X": {"VL": 200000.0, "AC": ..., "servo": {"kp": 10.0, ...}, ...}, ...},
     "tables": {"2": [[0.1, 0.2], ...]}, "scurves": {"1": [...]}}

Values that do not fit (a hand-edited file) are skipped one by one: the factory value stays.
"""

from __future__ import annotations

import contextlib
from dataclasses import asdict, fields, replace
from decimal import Decimal, InvalidOperation
from typing import TYPE_CHECKING, Any

from omsd.board import profiles as pf
from omsd.board.servo import ServoGains

if TYPE_CHECKING:
    from omsd.board.axis import Axis
    from omsd.board.board import Board

_GAIN_NAMES = tuple(f.name for f in fields(ServoGains))


def _ramp(shape: pf.RampShape) -> dict[str, Any]:
    return {"kind": shape.kind.value, "steps": shape.steps, "table": shape.table}


def axis_parameters(axis: Axis) -> dict[str, Any]:
    out: dict[str, Any] = {
        "AC": axis.ac,
        "VL": axis.vl,
        "VB": axis.vb,
        "ES": axis.es,
        "HD": axis.hd,
        "HG": axis.hg,
        "HV": axis.hv,
        "ER": axis.ratio,
        "BC": axis.backlash,
        "home_high": axis.home_high,
        "limit_high": axis.limit_high,
        "limits_on": axis.limits_on,
        "PA": axis.pa,
        "SE": axis.se_ms,
        "SL": axis.soft_limit,
        "UU": None if axis.uu is None else str(axis.uu),
        "aux_high": axis.aux_default_high,
        "direction_inverted": axis.direction_inverted,
        "ramp": _ramp(axis.ramp),
    }
    if axis.servo is not None:
        out["servo"] = asdict(axis.servo.gains)
    return out


def board_parameters(board: Board) -> dict[str, Any]:
    """The parameter set AP writes."""
    return {
        "model": board.model.name,
        "axes": {a.letter: axis_parameters(a) for a in board.axes},
        "tables": {str(n): [list(p) for p in table] for n, table in board.ramp_tables.items()},
        "scurves": {str(n): list(asdict(s).values()) for n, s in board.scurves.items()},
    }


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _apply_axis(axis: Axis, p: dict[str, Any], board: Board) -> None:
    for key, attr in (("AC", "ac"), ("VL", "vl"), ("VB", "vb"), ("ES", "es"), ("HD", "hd")):
        v = _number(p.get(key))
        if v is not None and v >= 0:
            setattr(axis, attr, v)
    for key, attr in (("HG", "hg"), ("HV", "hv"), ("ER", "ratio")):
        v = _number(p.get(key))
        if v is not None and v > 0:
            setattr(axis, attr, v)
    bc = p.get("BC")
    if isinstance(bc, int) and not isinstance(bc, bool) and -50 <= bc <= 50:
        axis.backlash = bc
    for key, attr in (
        ("home_high", "home_high"),
        ("limit_high", "limit_high"),
        ("limits_on", "limits_on"),
        ("aux_high", "aux_default_high"),
        ("direction_inverted", "direction_inverted"),
        ("SL", "soft_limit"),
    ):
        if isinstance(p.get(key), bool):
            setattr(axis, attr, p[key])
    if p.get("PA") is None or isinstance(p.get("PA"), bool):
        axis.pa = p.get("PA")
    se = p.get("SE")
    if isinstance(se, int) and not isinstance(se, bool) and 0 <= se <= 1000:
        axis.se_ms = se
    uu = p.get("UU")
    if uu is None:
        axis.uu = None
    elif isinstance(uu, str):
        with contextlib.suppress(InvalidOperation):
            axis.uu = Decimal(uu)
    ramp = p.get("ramp")
    if isinstance(ramp, dict):
        shape = ramp_from(ramp, board)
        if shape is not None:
            axis.ramp = shape
    gains = p.get("servo")
    if axis.servo is not None and isinstance(gains, dict):
        known = {k: v for k, v in gains.items() if k in _GAIN_NAMES}
        with contextlib.suppress(TypeError):
            axis.servo.set_gains(replace(ServoGains(), **known))


def ramp_from(ramp: dict[str, Any], board: Board) -> pf.RampShape | None:
    try:
        kind = pf.RampKind(ramp.get("kind"))
    except ValueError:
        return None
    steps = ramp.get("steps", 3)
    table = ramp.get("table", 0)
    if not isinstance(steps, int) or not isinstance(table, int):
        return None
    if kind is pf.RampKind.CUSTOM:
        return custom_ramp(board, table)
    if kind is pf.RampKind.SCURVE:
        return scurve_ramp(board, table)
    if kind is pf.RampKind.PARABOLIC:
        return pf.RampShape(kind, steps, floor=0.1)  # the PCIx's PN/PR (pcix_commands.parabolic)
    return pf.RampShape(kind, steps)


def custom_ramp(board: Board, table: int) -> pf.RampShape | None:
    points = board.ramp_tables.get(table)
    if not points:
        return None
    return pf.RampShape(pf.RampKind.CUSTOM, table=table, breakpoints=tuple(points))


def scurve_ramp(board: Board, profile: int) -> pf.RampShape | None:
    curve = board.scurves.get(profile)
    if curve is None:
        return None
    return pf.RampShape(pf.RampKind.SCURVE, table=profile, scurve=curve)


def apply(board: Board, saved: dict[str, Any]) -> None:
    """Load a saved parameter set (RD, power-up) over the factory values already in place."""
    tables = saved.get("tables")
    if isinstance(tables, dict):
        for key, points in tables.items():
            try:
                n = int(key)
                board.ramp_tables[n] = [(float(a), float(v)) for a, v in points]
            except (TypeError, ValueError):
                continue
    scurves = saved.get("scurves")
    if isinstance(scurves, dict):
        for key, values in scurves.items():
            try:
                board.scurves[int(key)] = pf.SCurve(*(float(v) for v in values))
            except (TypeError, ValueError):
                continue
    axes = saved.get("axes")
    if isinstance(axes, dict):
        for axis in board.axes:
            p = axes.get(axis.letter)
            if isinstance(p, dict):
                _apply_axis(axis, p, board)
    for axis in board.axes:
        axis.aux = axis.aux_default_high


def factory(board: Board) -> None:
    """RF: "Current parameters := factory defaults"; the flash is left as it is."""
    board.ramp_tables.clear()
    board.scurves.clear()
    for axis in board.axes:
        axis.factory_parameters()
