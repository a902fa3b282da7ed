"""The analytic pieces motion is made of.

Each piece knows its displacement, velocity and acceleration as closed-form functions of the
time since it began (``tau`` from 0 to ``duration``) and where its velocity changes sign. The
shapes: constant jerk (:class:`Poly`: linear and parabolic ramps, cruising), half-cosine
(:class:`Cosine`), exponential approach (:class:`Decay`: the position-hold correction), one
coordinate of circular motion (:class:`Sinusoid`: contour arcs), a chain of pieces seen as one
(:class:`Chain`: multi-segment ramps), and two views of another piece: its tail
(:class:`Shifted`) and a scaled window of it (:class:`Window`: following another axis).
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol


class Piece(Protocol):
    """One analytic segment of a trajectory; ``tau`` runs from 0 to ``duration``."""

    @property
    def duration(self) -> float: ...

    def x(self, tau: float) -> float: ...

    def v(self, tau: float) -> float: ...

    def a(self, tau: float) -> float: ...

    def turning_points(self) -> list[float]:
        """Times strictly inside the piece where the velocity changes sign."""
        ...


@dataclass(frozen=True, slots=True)
class Poly:
    """Constant jerk: ``x = v0 t + a0 t^2/2 + j t^3/6`` (linear and parabolic ramps, cruise)."""

    v0: float
    a0: float
    j: float
    duration: float

    def x(self, tau: float) -> float:
        return tau * (self.v0 + tau * (self.a0 / 2.0 + tau * self.j / 6.0))

    def v(self, tau: float) -> float:
        return self.v0 + tau * (self.a0 + tau * self.j / 2.0)

    def a(self, tau: float) -> float:
        return self.a0 + self.j * tau

    def turning_points(self) -> list[float]:
        a, b, c = self.j / 2.0, self.a0, self.v0
        if a == 0.0:  # a linear ramp or a cruise (most pieces): at most one root
            if b == 0.0:
                return []
            root = -c / b
            return [root] if 0.0 < root < self.duration else []
        disc = b * b - 4 * a * c
        if disc < 0.0:
            return []
        # the roots without cancellation: (-b -+ s) / 2a loses the small root when the jerk is
        # tiny beside the acceleration (j = 6e-293, a0 = -21, v0 = 7 gave 0.0, not 1/3)
        q = -0.5 * (b + math.copysign(math.sqrt(disc), b))
        if q == 0.0:  # b = 0 and c = 0: the velocity touches zero at the start, no sign change
            return []
        roots = (q / a, c / q)
        return sorted(r for r in roots if 0.0 < r < self.duration)


@dataclass(frozen=True, slots=True)
class Cosine:
    """Half-cosine velocity change: ``v = v0 + dv (1 - cos(w t)) / 2`` over ``0 <= w t <= pi``."""

    v0: float
    dv: float
    omega: float
    duration: float

    def x(self, tau: float) -> float:
        return self.v0 * tau + self.dv / 2.0 * (tau - math.sin(self.omega * tau) / self.omega)

    def v(self, tau: float) -> float:
        return self.v0 + self.dv * (1.0 - math.cos(self.omega * tau)) / 2.0

    def a(self, tau: float) -> float:
        return self.dv * self.omega * math.sin(self.omega * tau) / 2.0

    def turning_points(self) -> list[float]:
        if self.dv == 0.0:
            return []
        c = 1.0 + 2.0 * self.v0 / self.dv
        if -1.0 <= c <= 1.0:
            tau = math.acos(c) / self.omega
            if 0.0 < tau < self.duration:
                return [tau]
        return []


@dataclass(frozen=True, slots=True)
class Decay:
    """Exponential approach ``x = e0 (1 - exp(-k t))``: the position-hold correction (HG gain)."""

    e0: float
    k: float
    duration: float

    def x(self, tau: float) -> float:
        return self.e0 * -math.expm1(-self.k * tau)

    def v(self, tau: float) -> float:
        return self.e0 * self.k * math.exp(-self.k * tau)

    def a(self, tau: float) -> float:
        return -self.e0 * self.k * self.k * math.exp(-self.k * tau)

    def turning_points(self) -> list[float]:
        return []


@dataclass(frozen=True, slots=True)
class Sinusoid:
    """One coordinate of uniform circular motion: ``x = r (cos(p0 + w t) - cos p0)``."""

    r: float
    phase0: float
    omega: float
    duration: float

    def x(self, tau: float) -> float:
        return self.r * (math.cos(self.phase0 + self.omega * tau) - math.cos(self.phase0))

    def v(self, tau: float) -> float:
        return -self.r * self.omega * math.sin(self.phase0 + self.omega * tau)

    def a(self, tau: float) -> float:
        return -self.r * self.omega * self.omega * math.cos(self.phase0 + self.omega * tau)

    def turning_points(self) -> list[float]:
        if self.omega == 0.0 or self.r == 0.0:
            return []
        # sin(p0 + w t) == 0  <=>  p0 + w t == k pi
        lo, hi = sorted((self.phase0, self.phase0 + self.omega * self.duration))
        k = math.floor(lo / math.pi) + 1
        out = []
        while k * math.pi < hi:
            out.append((k * math.pi - self.phase0) / self.omega)
            k += 1
        return sorted(t for t in out if 0.0 < t < self.duration)


class Chain:
    """Consecutive pieces seen as one piece: a ramp made of several segments (a custom ramp
    table, an S-curve), as :func:`ramp_up` returns it. Trajectories are never built from a chain:
    :func:`move_pieces` hands out the segments themselves."""

    __slots__ = ("_offsets", "_starts", "duration", "parts")

    parts: tuple[Piece, ...]
    duration: float

    def __init__(self, parts: Sequence[Piece]) -> None:
        self.parts = tuple(p for p in parts if p.duration > 0.0)
        starts: list[float] = []
        offsets: list[float] = []
        t = x = 0.0
        for p in self.parts:
            starts.append(t)
            offsets.append(x)
            t += p.duration
            x += p.x(p.duration)
        self._starts = starts
        self._offsets = offsets
        self.duration = t

    def __repr__(self) -> str:
        return f"Chain({list(self.parts)!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Chain) and self.parts == other.parts

    def __hash__(self) -> int:
        return hash(self.parts)

    def _locate(self, tau: float) -> int:
        i = bisect.bisect_right(self._starts, tau) - 1
        return min(max(i, 0), len(self.parts) - 1)

    def x(self, tau: float) -> float:
        if not self.parts:
            return 0.0
        i = self._locate(tau)
        return self._offsets[i] + self.parts[i].x(tau - self._starts[i])

    def v(self, tau: float) -> float:
        if not self.parts:
            return 0.0
        i = self._locate(tau)
        return self.parts[i].v(tau - self._starts[i])

    def a(self, tau: float) -> float:
        if not self.parts:
            return 0.0
        i = self._locate(tau)
        return self.parts[i].a(tau - self._starts[i])

    def turning_points(self) -> list[float]:
        return [
            start + tp
            for start, p in zip(self._starts, self.parts, strict=True)
            for tp in p.turning_points()
        ]


def scaled(piece: Piece, k: float) -> Piece:
    """The same piece with every displacement multiplied by ``k`` (direction, axis share)."""
    if isinstance(piece, Chain):
        return Chain([scaled(p, k) for p in piece.parts])
    if isinstance(piece, Poly):
        return Poly(piece.v0 * k, piece.a0 * k, piece.j * k, piece.duration)
    if isinstance(piece, Cosine):
        return Cosine(piece.v0 * k, piece.dv * k, piece.omega, piece.duration)
    if isinstance(piece, Decay):
        return Decay(piece.e0 * k, piece.k, piece.duration)
    if isinstance(piece, Sinusoid):
        return Sinusoid(piece.r * k, piece.phase0, piece.omega, piece.duration)
    raise TypeError(piece)


def mirrored(piece: Poly) -> Poly:
    """The deceleration that retraces an acceleration piece backwards in time."""
    d = piece.duration
    return Poly(piece.v(d), -piece.a(d), piece.j, d)


def cruise(velocity: float, duration: float = math.inf) -> Poly:
    return Poly(velocity, 0.0, 0.0, duration)


@dataclass(frozen=True, slots=True)
class Shifted:
    """A piece observed from ``cut`` onwards."""

    inner: Piece
    cut: float
    duration: float

    def x(self, tau: float) -> float:
        return self.inner.x(self.cut + tau) - self.inner.x(self.cut)

    def v(self, tau: float) -> float:
        return self.inner.v(self.cut + tau)

    def a(self, tau: float) -> float:
        return self.inner.a(self.cut + tau)

    def turning_points(self) -> list[float]:
        return [tp - self.cut for tp in self.inner.turning_points() if tp > self.cut]


@dataclass(frozen=True, slots=True)
class Window:
    """``inner`` seen from ``cut`` on for ``duration`` seconds, every displacement times ``k``:
    the part of another axis's motion this axis copies (gearing, k = ratio) or keeps (a stop
    point, k = 1).
    """

    inner: Piece
    k: float
    cut: float
    duration: float
    x_cut: float

    def x(self, tau: float) -> float:
        return self.k * (self.inner.x(self.cut + tau) - self.x_cut)

    def v(self, tau: float) -> float:
        return self.k * self.inner.v(self.cut + tau)

    def a(self, tau: float) -> float:
        return self.k * self.inner.a(self.cut + tau)

    def turning_points(self) -> list[float]:
        end = self.cut + self.duration
        return [tp - self.cut for tp in self.inner.turning_points() if self.cut < tp < end]
