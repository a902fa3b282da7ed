"""Helpers shared by the conformance tests: reply framing, sample-tick timing, §1.3 move times
and a few ways of looking at a board.

Where the models differ the helpers take the difference as a parameter; the defaults are the
PC48's (2048 samples a second, power-up VL 100,000 and AC 1,000,000), and a test file for another
board binds its own values (``functools.partial``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from typing import cast

from omsd.board.board import Board
from omsd.board.events import DoneEvent, ErrorKind, Event
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld
from omsd.engine.axis import Motion
from omsd.models import get_model, variant

PC48_RATE = 2048  # PC48 sample ticks per second (§1.2, §8.2)
PC48_AC0 = 1_000_000.0  # PC48 power-up acceleration
PC48_VL0 = 100_000.0  # PC48 power-up velocity

# A stage whose home switch is far from every move of these examples, so RA/QA/EA print N for
# home unless a test wants otherwise (the default world has home at 1000..1100).
NO_HOME = AxisWorld(home_low=5_000_000.0, home_high=5_000_100.0)


# -- replies --------------------------------------------------------------------------------------


def frame(text: str) -> bytes:
    """A reply "surrounded by line feeds and carriage returns"."""
    return b"\n\r" + text.encode("ascii") + b"\n\r"


def status_frame(text: str) -> bytes:
    """An RA/QA/RI/QI/EA reply: "one line feed and two carriage returns on each end"."""
    return b"\n\r\r" + text.encode("ascii") + b"\n\r\r"


def number(reply: bytes) -> int:
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    return int(reply[2:-2])


def numbers(reply: bytes) -> list[int]:
    assert reply.startswith(b"\n\r") and reply.endswith(b"\n\r"), reply
    return [int(f) for f in reply[2:-2].split(b",")]


def enter(h: Harness, text: str) -> bytes:
    """Type an ``Enter:`` line: the text and the Enter key (CR). A command that may take an
    operand (AF, LP, JG...) is complete only once its operand is terminated (§6.1)."""
    return h.send(text + "\r")


def errors(h: Harness) -> list[tuple[ErrorKind, str]]:
    return [(e.kind, e.command.strip()) for e in h.errors()]


def done_events(source: Harness | Iterable[Event]) -> list[DoneEvent]:
    """The done events among ``source``: a list of events, or a harness's events so far (which
    the harness then forgets)."""
    events = source.events() if isinstance(source, Harness) else source
    return [e for e in events if isinstance(e, DoneEvent)]


# -- timing ---------------------------------------------------------------------------------------


def tick(n: float, rate: int = PC48_RATE) -> float:
    """The time of sample tick ``n``."""
    return n / rate


def end_tick(start_tick: int, duration: float, rate: int = PC48_RATE) -> int:
    """First sample tick at or after the analytic end of a move started on ``start_tick``."""
    return math.ceil(start_tick + duration * rate - 1e-9)


def linear_move_time(distance: float, vl: float = PC48_VL0, ac: float = PC48_AC0) -> float:
    """§1.3 linear ramp: trapezoid, or triangle when the move is too short to reach VL."""
    d = abs(distance)
    if d >= vl * vl / ac:
        return d / vl + vl / ac
    return 2.0 * math.sqrt(d / ac)


def soft_stop_bounds(limit: float, ac: float, rate: int) -> tuple[float, float]:
    """Where a linear move still accelerating at ``ac`` when it meets a soft limit at ``limit``
    comes to rest: it reaches the limit at v = sqrt(2 * limit * AC), is seen there up to one
    tick later, then decelerates at AC over v^2 / (2 AC)."""
    v0 = math.sqrt(2 * limit * ac)
    v1 = v0 + ac / rate
    return limit + v0 * v0 / (2 * ac), limit + v1 / rate + v1 * v1 / (2 * ac)


def path_times(vertices: list[tuple[int, int]], lead: float, cv: float) -> list[float]:
    """When a contour at constant velocity ``cv`` reaches each vertex, the first at ``lead``."""
    times = [lead]
    for (x0, y0), (x1, y1) in itertools.pairwise(vertices):
        times.append(times[-1] + math.hypot(x1 - x0, y1 - y0) / cv)
    return times


def at(h: Harness, t: float) -> bytes:
    """Let time pass up to ``t`` (never backwards); return the replies produced meanwhile."""
    assert t >= h.t - 1e-12, f"time would go backwards: {t} < {h.t}"
    return h.until(t)


def first_time(h: Harness, predicate: Callable[[], bool], step: float, limit: float) -> float:
    """Step the clock by ``step`` until ``predicate`` holds; return the time it first did."""
    end = h.t + limit
    while not predicate():
        assert h.t < end, "condition not reached in time"
        h.advance(step)
    return h.t


# -- boards and axes ------------------------------------------------------------------------------


def quiet(model: str, **worlds: AxisWorld) -> Harness:
    """A board whose axes all have their home switch out of the way (unless given)."""
    world = {letter: worlds.get(letter, NO_HOME) for letter in get_model(model).axes}
    return Harness(model, world=world)


def no_encoder_vs4() -> Harness:
    """A VS4-040 ordered without the encoder option (MO is then valid; digest §8 item 13)."""
    h = Harness("VS4-040")
    h.board = Board(variant(get_model("VS4-040"), encoders=""), now=0.0)
    return h


def moving(h: Harness, letter: str) -> bool:
    return h.axis(letter).motion is not Motion.IDLE


def velocity(h: Harness, letter: str) -> float:
    return h.axis(letter).velocity(h.t)


def physical(h: Harness, letter: str) -> float:
    """Where the carriage of axis ``letter`` is now (the axis's own view)."""
    return h.axis(letter).phys(h.t)


def snapshot_physical(h: Harness, letter: str) -> float:
    """Where the carriage of axis ``letter`` is now, read from a board snapshot."""
    return cast(float, h.board.snapshot(h.t)["axes"][letter]["physical"])
