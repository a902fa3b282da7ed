"""A trajectory: where one axis is, as a function of time, and cuts of one.

A :class:`Trajectory` is a start time, a start position and a sequence of pieces
(:mod:`omsd.engine.pieces`). The board never integrates: asking where an axis is at any instant
is a function call, and so is asking when it will reach a switch (:meth:`Trajectory.first_time`).
The functions after the class cut trajectories into pieces again: the motion between two times
(:func:`segment`, :func:`pieces_between`), the same motion with its positions shifted
(:func:`rebased`).
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence
from dataclasses import replace

from omsd.engine.pieces import Cosine, Decay, Piece, Poly, Shifted, Sinusoid, Window, cruise

_BISECT_ITERATIONS = 80

#: How far beyond a trajectory's extent a level must be for :meth:`Trajectory.first_time` to
#: answer "never" without looking (far more than the rounding of any position it computes).
_REACH_MARGIN = 1e-3


#: ``Trajectory._seen`` before any position is found (no time is NaN); ``count_seen`` before
#: any count is.
_NOT_SEEN = (math.nan, math.nan)
_NOT_COUNTED = (math.nan, 0)


class Trajectory:
    """Position of one axis as a function of time: ``x0`` at ``t0``, then the pieces in turn.

    After the last (finite) piece the axis rests at ``final``; it defaults to the sum of the
    displacements but is normally given exactly (an integer step count), so that float noise in
    the pieces never shows in the position counter.

    ``count`` is the position counter at ``t0`` when the trajectory takes over from a motion
    (the steps that motion had emitted: ``x0`` may lie between two steps, on either side of the
    count); None when it begins from rest, where the count is ``x0`` rounded the way it leaves
    in (:func:`omsd.engine.counter.counted`).
    """

    __slots__ = (
        "_extent",
        "_offsets",
        "_seen",
        "_starts",
        "_turns",
        "count",
        "count_seen",
        "duration",
        "end_time",
        "final",
        "one_way_from_rest",
        "pieces",
        "t0",
        "x0",
    )

    def __init__(
        self,
        t0: float,
        x0: float,
        pieces: Sequence[Piece] = (),
        final: float | None = None,
        count: int | None = None,
    ) -> None:
        self.t0 = t0
        self.x0 = x0
        self.count = count
        self.pieces = tuple(p for p in pieces if p.duration > 0.0) if pieces else ()
        starts: list[float] = []
        offsets: list[float] = []
        t = 0.0
        x = x0
        for p in self.pieces:
            starts.append(t)
            offsets.append(x)
            t += p.duration
            if math.isfinite(p.duration):
                x += p.x(p.duration)
        self._starts = starts
        self._offsets = offsets
        self.duration = t
        self.end_time = t0 + t
        if final is None:
            final = x if math.isfinite(t) else math.nan
        self.final = final
        self._extent: tuple[float, float] | None = None
        self._turns: bool | None = None
        self._seen = _NOT_SEEN
        # the last position counter found (omsd.engine.counter.count_at), kept as _seen is
        self.count_seen: tuple[float, int] = _NOT_COUNTED
        # from rest (no count taken over) and never turning: counted by the start alone
        # (omsd.engine.counter.count_velocity); None until asked
        self.one_way_from_rest: bool | None = None if count is None else False

    @classmethod
    def at_rest(cls, t0: float, x: float) -> Trajectory:
        return cls(t0, x, (), final=x)

    @classmethod
    def along(cls, t0: float, x0: float, course: Course, final: float) -> Trajectory:
        """``Trajectory(t0, x0, course.pieces, final)``, from what the course has worked out
        already (see :class:`Course`): the same numbers, to the last bit."""
        traj = cls.__new__(cls)
        traj.t0 = t0
        traj.x0 = x0
        traj.count = None
        traj.pieces = course.pieces
        traj._starts = course.starts
        # the same sums, in the same order, as __init__'s; and with them, the extent as extent()
        # finds it (_bounds: a sum of floats never decreases as a term grows, so the lowest of
        # ``base + point`` over a piece is ``base`` plus its lowest point, ``course.spans``)
        offsets: list[float] = []
        x = x0
        for step in course.steps:
            offsets.append(x)
            x += step
        traj._offsets = offsets
        # a course one way (Course.way): each piece's lowest and highest points are its ends,
        # so the extent is where it begins and where it ends (the sums are monotonic)
        if course.way > 0.0:
            lowest, highest = x0, (x if x > x0 else x0)
        elif course.way < 0.0:
            lowest, highest = (x if x < x0 else x0), x0
        else:
            lowest = highest = x0
            for base, (low, high) in zip(offsets, course.spans, strict=True):
                if (y := base + low) < lowest:
                    lowest = y
                if (y := base + high) > highest:
                    highest = y
        traj.duration = course.duration
        traj.end_time = t0 + course.duration
        traj.final = final
        if course.pieces:  # (a course is finite: no piece without end)
            lowest, highest = min(lowest, final), max(highest, final)
        traj._extent = (lowest, highest)
        traj._turns = course.turns
        traj.one_way_from_rest = not course.turns
        traj._seen = _NOT_SEEN
        traj.count_seen = _NOT_COUNTED
        return traj

    @property
    def is_finite(self) -> bool:
        return math.isfinite(self.duration)

    def _locate(self, t: float) -> tuple[int, float]:
        """Index of the piece running at ``t`` and the time into it; (-1, 0) before or after.
        At ``t0`` itself the first piece is running: a trajectory may begin in motion."""
        rel = t - self.t0
        if rel < 0.0 or not self.pieces or rel >= self.duration:
            return -1, 0.0
        i = bisect.bisect_right(self._starts, rel) - 1
        return i, rel - self._starts[i]

    def position(self, t: float) -> float:
        if t <= self.t0:
            return self.x0
        if t >= self.end_time:
            return self.final
        # the last position found, kept (issue 16): a poll asks for one instant's position more
        # than once (QA's carriage, RP's counter), and a trajectory never changes
        seen = self._seen
        if seen[0] == t:
            return seen[1]
        i, tau = self._locate(t)
        if i < 0:
            # past its last piece, though before end_time: t - t0 rounded to duration or more,
            # where t0 + duration rounded up (the last piece's start is no answer here)
            return self.final
        x = self._offsets[i] + self.pieces[i].x(tau)
        self._seen = (t, x)
        return x

    def velocity(self, t: float) -> float:
        i, tau = self._locate(t)
        return 0.0 if i < 0 else self.pieces[i].v(tau)

    def position_velocity(self, t: float) -> tuple[float, float]:
        """``(position(t), velocity(t))``, the piece running at ``t`` found once (a status
        asks for both): the same numbers, to the last bit."""
        pieces = self.pieces
        if not pieces:  # (at rest: x0 up to t0, then final)
            return (self.x0 if t <= self.t0 else self.final), 0.0
        rel = t - self.t0
        if 0.0 < rel < self.duration and t < self.end_time:
            # fast path (issue 16): within a piece, where position() computes the position
            # itself (no end to rest at; a kept position, if any, is the same number). Not
            # kept: a status's count is (counter.count_velocity), and RP reads that
            starts = self._starts
            i = bisect.bisect_right(starts, rel) - 1
            piece = pieces[i]
            tau = rel - starts[i]
            return self._offsets[i] + piece.x(tau), piece.v(tau)
        i, tau = self._locate(t)
        if i < 0:
            return self.position(t), 0.0
        piece = self.pieces[i]
        if t <= self.t0 or t >= self.end_time or self._seen[0] == t:
            return self.position(t), piece.v(tau)
        x = self._offsets[i] + piece.x(tau)
        self._seen = (t, x)
        return x, piece.v(tau)

    def acceleration(self, t: float) -> float:
        i, tau = self._locate(t)
        return 0.0 if i < 0 else self.pieces[i].a(tau)

    @property
    def way(self) -> float:
        """The way the motion leaves its start in: its first velocity, or acceleration from
        rest (0.0: at rest, or a wait before it moves)."""
        return _way(self.pieces)

    @property
    def turns(self) -> bool:
        """Whether the travel changes its way somewhere (a jog turned round, a contour's arc).
        Found once (a course's own, for a trajectory along one)."""
        if self._turns is None:
            self._turns = _turns(self.pieces)
        return self._turns

    def legs(self, t: float) -> list[tuple[float, float]]:
        """The travel up to ``t`` as legs each one way: where each begins and its way (+1.0 or
        -1.0), in turn (the ways alternate; nothing before the axis first moves). A leg ends
        where the velocity changes sign: between two pieces (a jog ramped round through zero,
        a move begun from rest where a jog the other way was), or within one at its turning
        points (a ramp through zero, a contour's arc)."""
        out: list[tuple[float, float]] = []
        rel = t - self.t0
        way = 0.0
        for i, piece in enumerate(self.pieces):
            start = self._starts[i]
            if start >= rel:
                break
            end = min(piece.duration, rel - start)
            cuts = [0.0, *(tp for tp in piece.turning_points() if tp < end), end]
            for a, b in itertools.pairwise(cuts):
                if b <= a:
                    continue
                v = piece.v((a + b) / 2.0)  # (one sign between two turning points)
                if v == 0.0:
                    continue
                sign = 1.0 if v > 0.0 else -1.0
                if sign != way:
                    out.append((self._offsets[i] + piece.x(a), sign))
                    way = sign
        return out

    def moving_at(self, t: float) -> bool:
        return self.t0 <= t < self.end_time and bool(self.pieces)

    def first_time(self, level: float, above: bool, t_from: float) -> float | None:
        """Earliest time ``>= t_from`` at which the position reaches ``level`` from the side
        opposite to ``above`` (``above=True``: first time ``x >= level``).

        The answer is the analytic instant; callers quantize it onto the sample grid.
        """

        def hit(x: float) -> bool:
            return x >= level if above else x <= level

        # fast path: a level beyond everywhere the trajectory goes is never reached (a switch
        # far from a short move, looked for each time the axis's next event is found)
        lowest, highest = self.extent()
        reach = _REACH_MARGIN + 1e-9 * abs(level)
        if (level > highest + reach) if above else (level < lowest - reach):
            return None
        t_from = max(t_from, self.t0)
        if hit(self.position(t_from)):
            return t_from
        rel_from = t_from - self.t0
        for i, piece in enumerate(self.pieces):
            start = self._starts[i]
            end = start + piece.duration
            if end <= rel_from:
                continue
            base = self._offsets[i]
            lo = max(0.0, rel_from - start)
            if math.isinf(piece.duration):
                v = piece.v(lo)
                x_lo = base + piece.x(lo)
                if v == 0.0 or (v > 0) != above:
                    return None
                return self.t0 + start + lo + (level - x_lo) / v
            bounds = [lo, *[tp for tp in piece.turning_points() if tp > lo], piece.duration]
            for a, b in itertools.pairwise(bounds):
                if not hit(base + piece.x(b)):
                    continue
                for _ in range(_BISECT_ITERATIONS):
                    mid = (a + b) / 2.0
                    if hit(base + piece.x(mid)):
                        b = mid
                    else:
                        a = mid
                    if b - a < 1e-13:
                        break
                return self.t0 + start + b
        if self.pieces and self.is_finite and hit(self.final):
            return self.end_time
        return None

    def extent(self) -> tuple[float, float]:
        """The lowest and the highest position of the whole trajectory, at rest before and
        after included (``-inf``/``inf`` on the side a piece without end heads to). Found once:
        at the ends of each piece and where its velocity changes sign (its turning points), the
        only places a piece's position can be extreme."""
        if self._extent is None:
            final = self.final if self.pieces and self.is_finite else None
            lowest, highest = _bounds(self.x0, self._offsets, self._points(), final)
            for piece in self.pieces:  # a cruise without end (first_time's own rule)
                if math.isinf(piece.duration):
                    v = piece.v(0.0)
                    if v > 0.0:
                        highest = math.inf
                    elif v < 0.0:
                        lowest = -math.inf
            self._extent = (lowest, highest)
        return self._extent

    def _points(self) -> list[tuple[float, ...]]:
        """Each piece's positions (from its start) where it can be extreme: its ends and its
        turning points; a piece without end, its start."""
        points: list[tuple[float, ...]] = []
        for piece in self.pieces:
            duration = piece.duration
            times: Sequence[float] = (
                (0.0,) if math.isinf(duration) else (0.0, duration, *piece.turning_points())
            )
            points.append(tuple(piece.x(tau) for tau in times))
        return points


def _way(pieces: Sequence[Piece]) -> float:
    """:attr:`Trajectory.way` of ``pieces``."""
    if not pieces:
        return 0.0
    first = pieces[0]
    return first.v(0.0) or first.a(0.0)


def _turns(pieces: Sequence[Piece]) -> bool:
    """:attr:`Trajectory.turns` of ``pieces``: whether their velocity has both signs."""
    ways: set[bool] = set()
    for p in pieces:
        end = p.duration if math.isfinite(p.duration) else 1.0
        cuts = [0.0, *(tp for tp in p.turning_points() if tp < end), end]
        for a, b in itertools.pairwise(cuts):
            if b > a and (v := p.v((a + b) / 2.0)) != 0.0:
                ways.add(v > 0.0)
        if len(ways) > 1:
            return True
    return False


def _bounds(
    x0: float, offsets: list[float], points: list[tuple[float, ...]], final: float | None
) -> tuple[float, float]:
    """The lowest and the highest of ``x0``, of each piece's ``points`` from where it begins
    (``offsets``) and of ``final`` (if given): :meth:`Trajectory.extent`'s, with a course or
    without."""
    lowest = highest = x0
    for base, xs in zip(offsets, points, strict=True):
        for point in xs:
            x = base + point
            if x < lowest:
                lowest = x
            elif x > highest:
                highest = x
    if final is not None:
        lowest, highest = min(lowest, final), max(highest, final)
    return lowest, highest


class Course:
    """A finite motion's pieces and what a :class:`Trajectory` works out from them that does
    not depend on where or when the motion starts: when each piece starts, how far each takes
    the axis, how long it all lasts, and where within each piece the position can be extreme
    (its ends and turning points, :meth:`Trajectory.extent`). Fast path (issue 16): kept with a
    kept move profile (``omsd.engine.ramps.kept_course``), so that a move a queue repeats costs
    a trajectory the sums that depend on its start alone (:meth:`Trajectory.along`). The numbers
    are those ``Trajectory`` computes, in the same order: the same results to the last bit
    (``tests/board/test_fast_paths.py``)."""

    __slots__ = ("duration", "extremes", "pieces", "spans", "starts", "steps", "turns", "way")

    def __init__(self, pieces: Sequence[Piece]) -> None:
        self.pieces = tuple(p for p in pieces if p.duration > 0.0)
        starts: list[float] = []
        steps: list[float] = []
        extremes: list[tuple[float, ...]] = []
        t = 0.0
        for p in self.pieces:
            if not math.isfinite(p.duration):
                raise ValueError("a course is a finite motion")
            starts.append(t)
            t += p.duration
            steps.append(p.x(p.duration))
            extremes.append(tuple(p.x(tau) for tau in (0.0, p.duration, *p.turning_points())))
        self.starts = starts
        self.steps = steps
        self.extremes = extremes
        self.spans = [(min(xs), max(xs)) for xs in extremes]  # (Trajectory.extent, along)
        self.turns = _turns(self.pieces)  # (Trajectory.turns)
        self.duration = t
        # 1.0: every piece goes up from its start to its end, which are its lowest and highest
        # points (spans); -1.0: every one down; 0.0: neither (Trajectory.along)
        ends = list(zip(steps, self.spans, strict=True))
        if all(step >= 0.0 and low == 0.0 and high == step for step, (low, high) in ends):
            self.way = 1.0
        elif all(step <= 0.0 and high == 0.0 and low == step for step, (low, high) in ends):
            self.way = -1.0
        else:
            self.way = 0.0


def segment(traj: Trajectory, a: float, b: float) -> list[Piece]:
    """The motion of ``traj`` from ``a`` to ``b`` as pieces (rest included)."""
    out: list[Piece] = []
    span = b - a
    acc = 0.0
    rel = a - traj.t0
    start = 0.0
    for piece in traj.pieces:
        end = start + piece.duration
        if end <= rel:
            start = end
            continue
        cut = max(0.0, rel - start)
        rest = tail(piece, cut)
        length = min(rest.duration, span - acc)
        out.append(replace(rest, duration=length))  # type: ignore[type-var]
        acc += length
        start = end
        if acc >= span:
            return out
    if acc < span:
        out.append(cruise(0.0, span - acc))
    return out


def rebased(traj: Trajectory, t: float, shift: float) -> Trajectory:
    """The same motion continued from ``t`` with every position shifted by ``shift``."""
    rel = t - traj.t0
    pieces: list[Piece] = []
    acc = 0.0
    for piece in traj.pieces:
        if acc + piece.duration <= rel:
            acc += piece.duration
            continue
        cut = max(0.0, rel - acc)
        pieces.append(tail(piece, cut))
        acc += piece.duration
    final = traj.final + shift if math.isfinite(traj.final) else None
    return Trajectory(t, traj.position(t) + shift, pieces, final)


def tail(piece: Piece, cut: float) -> Piece:
    """The part of ``piece`` after ``cut``, as a piece of its own."""
    if cut == 0.0:
        return piece
    rest = piece.duration - cut
    if isinstance(piece, Poly):
        return Poly(piece.v(cut), piece.a(cut), piece.j, rest)
    if isinstance(piece, Cosine):
        return Shifted(piece, cut, rest)
    if isinstance(piece, Decay):
        return Decay(piece.e0 * math.exp(-piece.k * cut), piece.k, rest)
    if isinstance(piece, Sinusoid):
        return Sinusoid(piece.r, piece.phase0 + piece.omega * cut, piece.omega, rest)
    return Shifted(piece, cut, rest)


def window(piece: Piece, k: float, cut: float, duration: float) -> Piece:
    if k == 1.0 and cut == 0.0 and duration == piece.duration:
        return piece
    return Window(piece, k, cut, duration, piece.x(cut))


def pieces_between(traj: Trajectory, a: float, b: float, k: float = 1.0) -> list[Piece]:
    """The motion of ``traj`` from time ``a`` to ``b`` (``b`` may be infinite), scaled by ``k``;
    nothing for the time it is at rest after its end."""
    out: list[Piece] = []
    start = traj.t0
    for piece in traj.pieces:
        end = start + piece.duration
        lo, hi = max(a, start), min(b, end)
        if hi > lo:
            out.append(window(piece, k, lo - start, hi - lo))
        start = end
        if start >= b:
            break
    return out
