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

Values that do not fit (a hand-edited file: the wrong type, out of the command's own range in
:mod:`omsd.dialects.pcix.ranges`, or not finite: JSON reads ``1e400`` as infinity) are
skipped one by one: the factory value stays, and :func:`apply` returns where each was
(``axes.X.VL: expected a number >= 0, got a string``, ``axes.X.AC: expected 1 ≤ acceleration ≤
8000000, got 0``) for the daemon to report in one warning line. Keys it does not know are left
alone.
"""

from __future__ import annotations

import math
from dataclasses import asdict, fields, replace
from decimal import Decimal, InvalidOperation
from typing import Any

from omsd.dialects.pcix.ranges import PCIX_RANGES
from omsd.engine import profiles as pf
from omsd.engine.axis import Axis
from omsd.engine.core import Core
from omsd.engine.servo import ServoGains
from omsd.protocol.ranges import OperandRange

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


def board_parameters(board: Core) -> dict[str, Any]:
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


def _kind(value: object) -> str:
    """A JSON value's type, for a problem's text."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return repr(value) if len(value) <= 20 else "a string"
    return "an array" if isinstance(value, list) else "an object"


def _row(board: Core, mnemonic: str) -> OperandRange:
    return PCIX_RANGES.lookup(mnemonic, 1, board.model.family)


def _fits(board: Core, mnemonic: str, value: float | Decimal) -> bool:
    """Whether a saved value is one the command could have set: its range row, except where
    AP saves what the row does not hold. VL: a JF below 1 ("JF0.5": VL 0.5) is saved, so any
    velocity above zero; HV: 0 is the factory "no hold velocity" ("The factory default setting
    is zero"), below the row's 1."""
    if isinstance(value, float) and not math.isfinite(value):
        return False
    if mnemonic == "VL":
        high = _row(board, "VL").edges(len(board.axes))[1]
        return high is not None and 0 < value <= high
    if mnemonic == "HV" and value == 0:
        return True
    return _row(board, mnemonic).contains(value, len(board.axes))


def _describe(board: Core, mnemonic: str) -> str:
    """The range a saved value must be in, for a problem's text."""
    text = _row(board, mnemonic).describe(len(board.axes))
    if mnemonic == "VL":
        return "0 < " + text.split(" ≤ ", 1)[1]
    return "0 or " + text if mnemonic == "HV" else text


def _apply_axis(axis: Axis, p: dict[str, Any], board: Core, at: str, problems: list[str]) -> None:
    def bad(key: str, expected: str) -> None:
        problems.append(f"{at}.{key}: expected {expected}, got {_kind(p[key])}")

    numbers = (("AC", "ac"), ("VL", "vl"), ("VB", "vb"), ("ES", "es"), ("HD", "hd"))
    for key, attr in (*numbers, ("HG", "hg"), ("HV", "hv")):
        if key not in p:
            continue
        v = _number(p[key])
        if v is None:
            bad(key, "a number > 0" if key == "HG" else "a number >= 0")
        elif _fits(board, key, v):
            setattr(axis, attr, v)
        else:
            problems.append(f"{at}.{key}: expected {_describe(board, key)}, got {_kind(p[key])}")
    v = _number(p.get("ER"))
    if v is not None and 0 < v < math.inf:
        axis.ratio = v
    elif "ER" in p:
        bad("ER", "a number > 0")
    bc = p.get("BC")
    low = -50 if axis.servo is not None else 0  # "0 ≤ BACKLASH ≤ +50 STEPPERS", "-50 ... SERVOS"
    if isinstance(bc, int) and not isinstance(bc, bool) and low <= bc <= 50:
        axis.backlash = bc
    elif "BC" in p:
        bad("BC", f"an integer {low}..50")
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
        elif key in p:
            bad(key, "true or false")
    if p.get("PA") is None or isinstance(p.get("PA"), bool):
        axis.pa = p.get("PA")
    else:
        bad("PA", "true, false or null")
    se = p.get("SE")
    if isinstance(se, int) and not isinstance(se, bool) and 0 <= se <= 1000:
        axis.se_ms = se
    elif "SE" in p:
        bad("SE", "an integer 0..1000")
    uu = p.get("UU")
    if uu is None:
        axis.uu = None
    elif isinstance(uu, str):
        try:
            multiplier = Decimal(uu)
        except InvalidOperation:
            bad("UU", "a decimal number in a string or null")
        else:
            if multiplier.is_finite() and _fits(board, "UU", multiplier):
                axis.uu = None if multiplier == 1 else multiplier  # UU1 is UF, as the command
            else:
                bad("UU", _describe(board, "UU"))
    else:
        bad("UU", "a decimal number in a string or null")
    ramp = p.get("ramp")
    shape = ramp_from(ramp, board) if isinstance(ramp, dict) else None
    if shape is not None:
        axis.ramp = shape
    elif "ramp" in p:
        bad("ramp", "a ramp {kind, steps, table} this board can run")
    gains = p.get("servo")
    if axis.servo is not None and isinstance(gains, dict):
        known: dict[str, Any] = {}
        for name, value in gains.items():
            if name not in _GAIN_NAMES:
                continue
            flag = name in ("bipolar", "inverted")
            if flag and isinstance(value, bool):
                known[name] = value
            elif not flag and _number(value) is not None and _fits(board, name.upper(), value):
                known[name] = float(value)
            elif not flag and _number(value) is not None:
                what = _describe(board, name.upper())
                problems.append(f"{at}.servo.{name}: expected {what}, got {_kind(value)}")
            else:
                what = "true or false" if flag else "a number"
                problems.append(f"{at}.servo.{name}: expected {what}, got {_kind(value)}")
        axis.servo.set_gains(replace(ServoGains(), **known))
    elif axis.servo is not None and "servo" in p:
        bad("servo", "an object of gains")


def ramp_from(ramp: dict[str, Any], board: Core) -> pf.RampShape | None:
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
        return pf.RampShape(
            kind, steps, floor=0.1
        )  # the PCIx's PN/PR (omsd.dialects.pcix.ramps.parabolic)
    return pf.RampShape(kind, steps)


def custom_ramp(board: Core, table: int) -> pf.RampShape | None:
    points = board.ramp_tables.get(table)
    if not points:
        return None
    return pf.RampShape(pf.RampKind.CUSTOM, table=table, breakpoints=tuple(points))


def scurve_ramp(board: Core, profile: int) -> pf.RampShape | None:
    curve = board.scurves.get(profile)
    if curve is None:
        return None
    return pf.RampShape(pf.RampKind.SCURVE, table=profile, scurve=curve)


def apply(board: Core, saved: dict[str, Any]) -> list[str]:
    """Load a saved parameter set (power-up) over the factory values already in place.
    Returns the values skipped because they do not fit, each as ``where: expected ..., got
    ...`` (empty when everything was used)."""
    problems: list[str] = []
    apply_tables(board, saved, problems)
    axes = saved.get("axes")
    if isinstance(axes, dict):
        for axis in board.axes:
            apply_axis(board, axis, saved, problems)
    elif "axes" in saved:
        problems.append(f"axes: expected an object, got {_kind(axes)}")
    for axis in board.axes:
        axis.aux = axis.aux_default_high
    return problems


def apply_tables(board: Core, saved: dict[str, Any], problems: list[str]) -> None:
    """The board's part of a saved set: the custom ramp tables and S-curve profiles."""
    tables = saved.get("tables")
    if isinstance(tables, dict):
        for key, points in tables.items():
            try:
                n = int(key)
                board.ramp_tables[n] = [(float(a), float(v)) for a, v in points]
            except (TypeError, ValueError):
                problems.append(f"tables.{key}: expected [[a, v], ...], got {_kind(points)}")
    elif "tables" in saved:
        problems.append(f"tables: expected an object, got {_kind(tables)}")
    scurves = saved.get("scurves")
    if isinstance(scurves, dict):
        for key, values in scurves.items():
            try:
                board.scurves[int(key)] = pf.SCurve(*(float(v) for v in values))
            except (TypeError, ValueError):
                problems.append(f"scurves.{key}: expected an S-curve, got {_kind(values)}")
    elif "scurves" in saved:
        problems.append(f"scurves: expected an object, got {_kind(scurves)}")


def apply_axis(board: Core, axis: Axis, saved: dict[str, Any], problems: list[str]) -> None:
    """One axis's part of a saved set (``axes.X``), if the set has one."""
    axes = saved.get("axes")
    if not isinstance(axes, dict):
        return
    p = axes.get(axis.letter)
    if isinstance(p, dict):
        _apply_axis(axis, p, board, f"axes.{axis.letter}", problems)
    elif axis.letter in axes:
        problems.append(f"axes.{axis.letter}: expected an object, got {_kind(p)}")


def factory(board: Core) -> None:
    """RF: "Current parameters := factory defaults"; the flash is left as it is. Among them
    (the RF list): "Software over travel limits are disabled ( TL0,0; )"."""
    board.ramp_tables.clear()
    board.scurves.clear()
    for axis in board.axes:
        factory_axis(axis)


def factory_axis(axis: Axis) -> None:
    """One axis's part of :func:`factory`."""
    axis.factory_parameters()
    axis.travel_limits = None
    axis.invalidate()
