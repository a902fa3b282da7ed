"""Constant velocity contouring (PC48 §6.21).

"Constant velocity contouring provides another mode wherein the move parameters are predefined
by entering AA then CD#,#;. The PC48 will then calculate the move profile in advance and move at
constant velocity in the prescribed pattern. It can do linear interpolation on as many as 8 axes
between the predefined points or it can do circular interpolation mixed with linear on two axes."

A :class:`ContourDefinition` records what was entered between CD and CE/CK, charged against the
contour queue. :func:`plan` turns it into one trajectory per contour axis when CX runs:

* lead-in: "The contouring axes must be at positions which allow them to reach the specified
  contouring velocity by the specified position"; the axes accelerate along the straight line
  to the start so as to reach CV exactly there ("If the actual position of the stage is equal to
  the starting position ... the stage will jump to the contouring velocity with no ramp up");
* the path at constant vector speed CV, lines and arcs ("Positive radians equal counter
  clockwise movement");
* CE: ramp down along the direction of the last segment at AC ("The end of the contour should
  contain at least a short linear segment just prior to the CE command to initialize the
  parameters for the deceleration"); CK: "the pulses will stop abruptly".

AN/AF/BL/BH (and the PCIx's ID) inside the definition happen at their place on the path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from omsd.engine import profiles as pf


@dataclass(frozen=True)
class Line:
    target: tuple[float | None, ...]  # per contour axis; None keeps the coordinate


@dataclass(frozen=True)
class Arc:
    center: tuple[float, float]
    angle: float  # radians, positive counter-clockwise


@dataclass(frozen=True)
class Output:
    kind: str  # "aux", "bit" or "done" (the PCIx's ID in a contour)
    target: int  # axis index, bit number, or (done) the mask of the contour axes
    low: bool


Item = Line | Arc | Output


@dataclass
class ContourDefinition:
    axes: tuple[int, ...]
    start: tuple[float, ...]
    velocity: float
    capacity: int
    used: int = 0
    items: list[Item] = field(default_factory=list)
    end: str | None = None  # "CE" or "CK" once complete
    valid: bool = True

    @property
    def free(self) -> int:
        return self.capacity - self.used

    def add(self, item: Item | None, slots: int) -> bool:
        if slots > self.free:
            return False
        self.used += slots
        if item is not None:
            self.items.append(item)
        return True


@dataclass
class Plan:
    pieces: dict[int, list[pf.Piece]]
    finals: dict[int, float]
    outputs: list[tuple[float, Output]]  # time offsets from the start
    lead_in: dict[int, float]  # each axis's acceleration in the lead-in (RC in the contour)


def plan(defn: ContourDefinition, here: dict[int, float], decel: float) -> Plan:
    axes = defn.axes
    n = len(axes)
    cv = defn.velocity
    pieces: dict[int, list[pf.Piece]] = {a: [] for a in axes}
    cur = list(defn.start)
    elapsed = 0.0
    outputs: list[tuple[float, Output]] = []

    # lead-in: from where the stage is to the start, reaching CV exactly at the start
    delta = [defn.start[i] - here[a] for i, a in enumerate(axes)]
    length = math.sqrt(sum(d * d for d in delta))
    lead_accel = 0.0
    lead_in = dict.fromkeys(axes, 0.0)
    direction = [0.0] * n
    if length > 0.5:
        lead_accel = cv * cv / (2.0 * length)
        duration = 2.0 * length / cv
        for i, a in enumerate(axes):
            u = delta[i] / length
            direction[i] = u
            pieces[a].append(pf.Poly(0.0, lead_accel * u, 0.0, duration))
            lead_in[a] = abs(lead_accel * u)
        elapsed += duration

    for item in defn.items:
        if isinstance(item, Output):
            outputs.append((elapsed, item))
            continue
        if isinstance(item, Line):
            target = [cur[i] if v is None else v for i, v in enumerate(item.target)]
            d = [target[i] - cur[i] for i in range(n)]
            seg = math.sqrt(sum(x * x for x in d))
            if seg == 0.0:
                continue
            duration = seg / cv
            for i, a in enumerate(axes):
                pieces[a].append(pf.cruise(cv * d[i] / seg, duration))
                direction[i] = d[i] / seg
            cur = target
            elapsed += duration
            continue
        cx, cy = item.center
        r = math.hypot(cur[0] - cx, cur[1] - cy)
        if r == 0.0 or item.angle == 0.0:
            continue
        phase = math.atan2(cur[1] - cy, cur[0] - cx)
        omega = math.copysign(cv / r, item.angle)
        duration = r * abs(item.angle) / cv
        pieces[axes[0]].append(pf.Sinusoid(r, phase, omega, duration))
        pieces[axes[1]].append(pf.Sinusoid(r, phase - math.pi / 2.0, omega, duration))
        end = phase + item.angle
        cur = [cx + r * math.cos(end), cy + r * math.sin(end)]
        sense = math.copysign(1.0, item.angle)
        direction = [-sense * math.sin(end), sense * math.cos(end)]
        elapsed += duration

    finals = {a: cur[i] for i, a in enumerate(axes)}
    if defn.end == "CE" and decel > 0.0:
        duration = cv / decel
        run = cv * cv / (2.0 * decel)
        for i, a in enumerate(axes):
            pieces[a].append(pf.Poly(cv * direction[i], -decel * direction[i], 0.0, duration))
            finals[a] = cur[i] + run * direction[i]
    return Plan(
        pieces=pieces,
        finals={a: float(round(x)) for a, x in finals.items()},
        outputs=outputs,
        lead_in=lead_in,
    )
