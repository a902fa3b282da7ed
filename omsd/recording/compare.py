"""What the card said against what omsd said: the rules of a replay's comparison.

Each side's stream is cut into units (:mod:`omsd.recording.units`): *answers* (replies, ``#``,
echo), which come in the order of the host's commands, and *events* (the driver's done, limit
and slip markers), which come when the motion does. Each kind is compared in order, separately:
a marker may come before or after a reply depending on a few microseconds, and that is no
difference.

Alignment: the two lists are walked together. Units that agree are paired. At a disagreement
the walk looks ahead, at most :data:`LOOKAHEAD` units on each side, for the nearest place where
the two agree again for :data:`CONFIRM` units in a row (or both end), preferring a unit changed
to one missing: ``(1, 1)`` (one unit each side differs) before ``(1, 0)`` (the card said one
unit more) before ``(2, 2)`` ... The units skipped are differences: paired while both sides have
one (``card said X, omsd said Y``), then alone (``omsd said nothing``, ``card said nothing``).
With no such place within reach, the two units at hand are one difference and the walk goes on.
So one reply changed is one row, one reply missing is one row, and a stream that goes wrong for
good is reported unit by unit rather than as one row.

Agreement:

* **Text and status, exactly.** Every answer is compared byte for byte, framing included, but
  for the numbers below.
* **Positions and velocities read during motion, within the tolerance.** When the command an
  answer follows names a position or velocity query (``RP RE RU RV PP PE``, the PC48 family's
  and the PCIx's), the answer is a list of numbers (``12345``, ``500,0,-3,0``, ``uu3.50000``) and
  the board was moving around then (:func:`omsd.recording.emulate.motion_at`), each number may
  differ by ``steps + seconds * speed``: ``steps`` for rounding and the sample grid, and as far
  as the fastest axis went in the time by which the card's clock and the recording's may differ
  (for ``RV``, as much as its velocity changed in that time: ``seconds * acceleration``).
  What is not a number (the commas, ``uu``, the framing) is exact.
  At rest they are exact.
* **Markers: the same byte, about the same time.** An event agrees with the card's when its
  bytes are the same (the done-flag register too) and it came within ``seconds`` of it. The
  emulator computes each move from the time the recording says its command was sent; the card
  heard it later by what the line and the recorder took (on a serial line the replay corrects
  for the characters' time on the wire), and its marker was recorded after it sent it. So
  ``seconds`` bounds the recording's timing error, and a marker further off than that is a
  difference of the emulator's timing: reported with both times.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from omsd.recording.units import Unit

LOOKAHEAD = 8
"""How many units on each side a realignment looks ahead."""

CONFIRM = 2
"""How many units in a row must agree for a realignment to be taken."""

DEFAULT_STEPS = 2.0
"""The default tolerance on a position or velocity read during motion, in steps (counts)."""

DEFAULT_SECONDS = 0.02
"""The default timing tolerance, seconds: USB serial adapters hold received bytes up to 16 ms
(the FTDI chips' default latency timer), and the recorder and the card's host add scheduling."""

POSITION_QUERIES = ("RP", "RE", "RU", "RV", "PP", "PE")
"""The commands whose answers are positions or velocities (PC48 §6.13, §6.19; PCIx §5.7.5,
§5.8.1)."""

_QUERY = re.compile(rb"RP|RE|RU|RV|PP|PE")
_VELOCITY = re.compile(rb"RV")
_NUMBER = re.compile(rb"[-+]?[0-9]+(?:\.[0-9]+)?")


@dataclass(frozen=True)
class Tolerance:
    """``steps``: how far a number read during motion may be off, plus ``seconds`` of the
    motion; ``seconds``: how far apart in time the card's and omsd's markers may be."""

    steps: float = DEFAULT_STEPS
    seconds: float = DEFAULT_SECONDS


@dataclass(frozen=True)
class Difference:
    """One row of the table. ``card`` / ``omsd`` are ``None`` where that side said nothing;
    ``what`` is ``text``, ``number`` (beyond the tolerance), ``missing`` (omsd said nothing),
    ``extra`` (the card said nothing) or ``time`` (a marker, too early or too late)."""

    stream: str
    time: float
    command: bytes | None
    card: bytes | None
    omsd: bytes | None
    card_time: float | None
    omsd_time: float | None
    what: str


@dataclass
class Counts:
    answers: int = 0
    events: int = 0


def is_position_query(command: bytes | None) -> bool:
    """Whether a host chunk names a position or velocity query (:data:`POSITION_QUERIES`)."""
    return command is not None and _QUERY.search(command.upper()) is not None


def allowance(command: bytes | None, unit: Unit, tolerance: Tolerance) -> float:
    """How far a number of ``unit``'s may be off: the steps, and what the fastest axis moved
    in ``seconds`` (a velocity, ``RV``: what it gained)."""
    rate = unit.speed
    if command is not None and _VELOCITY.search(command.upper()):
        rate = max(rate, unit.accel)
    return tolerance.steps + tolerance.seconds * rate


def numbers_agree(card: bytes, omsd: bytes, allowance: float) -> bool:
    """Whether two answers are the same list of numbers within ``allowance`` each, everything
    between the numbers exactly the same."""
    a, b = _NUMBER.split(card), _NUMBER.split(omsd)
    if a != b:
        return False
    x, y = _NUMBER.findall(card), _NUMBER.findall(omsd)
    if not x:
        return False
    return all(abs(float(p) - float(q)) <= allowance for p, q in zip(x, y, strict=True))


def align(
    n: int, m: int, same: Callable[[int, int], bool]
) -> Iterator[tuple[int | None, int | None]]:
    """Pairs of indices of two lists of ``n`` and ``m`` units (``None``: nothing on that side),
    in order, by the walk of the module text; ``same(i, j)``: unit ``i`` of the first agrees with
    unit ``j`` of the second."""

    def confirmed(p: int, q: int) -> bool:
        if p >= n or q >= m:  # a skip to the end of both sides, never past either
            return p == n and q == m
        for r in range(CONFIRM):
            if p + r >= n or q + r >= m:
                return True
            if not same(p + r, q + r):
                return False
        return True

    order = [
        (a, b)
        for d in range(1, LOOKAHEAD + 1)
        for a, b in sorted(
            {(d, d - k) for k in range(d + 1)} | {(d - k, d) for k in range(d + 1)},
            key=lambda ab: (abs(ab[0] - ab[1]), -ab[0]),
        )
    ]
    i = j = 0
    while i < n and j < m:
        if same(i, j):
            yield i, j
            i += 1
            j += 1
            continue
        found = next(((a, b) for a, b in order if confirmed(i + a, j + b)), None)
        if found is None:
            yield i, j
            i += 1
            j += 1
            continue
        a, b = found
        k = min(a, b)
        for x in range(k):
            yield i + x, j + x
        for x in range(k, a):
            yield i + x, None
        for x in range(k, b):
            yield None, j + x
        i += a
        j += b
    for x in range(i, n):
        yield x, None
    for x in range(j, m):
        yield None, x


def compare(
    stream: str,
    card: Sequence[Unit],
    omsd: Sequence[Unit],
    commands: Sequence[bytes],
    tolerance: Tolerance,
    counts: Counts,
) -> list[Difference]:
    """The differences between the units of one stream (the module text's rules); ``commands``
    are the host's chunks of the stream, which a unit's ``command`` indexes."""

    def command_of(unit: Unit | None) -> bytes | None:
        if unit is None or not 0 <= unit.command < len(commands):
            return None
        return commands[unit.command]

    def answers_agree(c: Unit, o: Unit) -> bool:
        if c.data == o.data:
            return True
        command = command_of(o) or command_of(c)
        if (o.speed <= 0.0 and o.accel <= 0.0) or not is_position_query(command):
            return False
        return numbers_agree(c.data, o.data, allowance(command, o, tolerance))

    rows: list[Difference] = []
    card_answers = [u for u in card if not u.event]
    omsd_answers = [u for u in omsd if not u.event]
    counts.answers += len(card_answers)
    pairs = align(
        len(card_answers),
        len(omsd_answers),
        lambda i, j: answers_agree(card_answers[i], omsd_answers[j]),
    )
    for i, j in pairs:
        c = None if i is None else card_answers[i]
        o = None if j is None else omsd_answers[j]
        if c is not None and o is not None:
            if answers_agree(c, o):
                continue
            what = "text"
            if is_position_query(command_of(o) or command_of(c)) and numbers_agree(
                c.data, o.data, float("inf")
            ):
                what = "number"
        else:
            what = "missing" if o is None else "extra"
        rows.append(_row(stream, c, o, command_of(o) or command_of(c), what))
    card_events = [u for u in card if u.event]
    omsd_events = [u for u in omsd if u.event]
    counts.events += len(card_events)

    def events_agree(c: Unit, o: Unit) -> bool:
        return c.data == o.data and abs(c.time - o.time) <= tolerance.seconds

    pairs = align(
        len(card_events),
        len(omsd_events),
        lambda i, j: events_agree(card_events[i], omsd_events[j]),
    )
    for i, j in pairs:
        c = None if i is None else card_events[i]
        o = None if j is None else omsd_events[j]
        if c is not None and o is not None:
            if events_agree(c, o):
                continue
            what = "time" if c.data == o.data else "text"
        else:
            what = "missing" if o is None else "extra"
        rows.append(_row(stream, c, o, command_of(c) or command_of(o), what))
    return rows


def _row(
    stream: str, c: Unit | None, o: Unit | None, command: bytes | None, what: str
) -> Difference:
    time = c.time if c is not None else o.time if o is not None else 0.0
    return Difference(
        stream=stream,
        time=time,
        command=command,
        card=None if c is None else c.data,
        omsd=None if o is None else o.data,
        card_time=None if c is None else c.time,
        omsd_time=None if o is None else o.time,
        what=what,
    )


__all__ = [
    "DEFAULT_SECONDS",
    "DEFAULT_STEPS",
    "POSITION_QUERIES",
    "Counts",
    "Difference",
    "Tolerance",
    "align",
    "allowance",
    "compare",
    "is_position_query",
    "numbers_agree",
]
