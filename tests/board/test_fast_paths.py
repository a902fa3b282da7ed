"""The fast paths change no reply (issue 16): differential tests.

A board with the fast paths and one without (``Board(model, fast_paths=False)``, the
straightforward code) are given the same random steps (:class:`twin.Twin`): command streams
(the fuzzing host's command soup, runs of reports, statements that move the axes), time passing
and deadlines visited (also a hair before and after one), the world changed, registers read,
output taken, the card switched off and on, from two sessions. After every step the two must
have said the same bytes and events, at the same times, to the same sessions, and be in the
same state. Then the sessions scenarios (``tests/board/test_sessions.py``, and the property of
``tests/robustness/test_sessions.py`` through both links) are run on twins.

Below them, the fast paths are shown to be taken where they are meant to be (a change that
quietly stopped taking them would still pass the rest), and the promise the receive fast path
rests on is checked for every model: a report leaves the interpreter holding nothing and
queues nothing.
"""

from __future__ import annotations

import importlib.util
import math
import random
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from robustness import test_sessions as robust_sessions
from robustness.conftest import stream_settings
from robustness.fuzz import ALL_MODELS, command_soup
from twin import Twin, state

from omsd.board import Board
from omsd.board.world import AxisWorld
from omsd.engine import follow_on, reactions, sensing
from omsd.engine import machine as machine_module
from omsd.engine.events import LimitEvent, SlipEvent
from omsd.engine.pieces import Cosine, Decay, Poly, Sinusoid, cruise
from omsd.engine.ramps import RampKind, RampShape, kept_course, move_pieces, profile_pieces
from omsd.engine.states import Motion
from omsd.engine.trajectory import Trajectory
from omsd.engine.world import LimitWiring
from omsd.models import MODELS, get_model

#: Statements that move the axes (and so make deadlines, waits and events), valid in both
#: languages (``;`` ends a PC48 word too); the ones a model lacks are command errors.
STATEMENTS = [
    "AX;VL5000;AC50000;MR3000;GO;ID;",
    "AY;VL2000;AC20000;JG2000;",
    "AZ;VL1000;AC10000;MR-500;GO;ID;",
    "AA;VL4000,4000;AC40000,40000;MR100,-200;GO;ID;",
    "AX;WT50;MR10;GO;",
    "AT;LS3;MR20;GO;LE;ID;",
    "AX;ST;",
    "AY;ST;",
    "KL;",
    "AX;HM;",
    "AX;MA0;GO;ID;",
    "AX;WQ;RP;",
    "AX;JG-3000;",
    "EN;",
    "EF;",
    "IC;",
    "AX;RA;",
    "\x19",
    "\x04",
    "AM;MR10,20;GO;",
    "AX;VL100000;AC1000000;MR1000000;GO;",
    # queues of moves that follow on (omsd.engine.follow_on), and some that may not: a move by
    # nothing, a move in AA mode (a group), in a loop, at a base velocity, near Y's switch
    "AX;VL5000;AC50000;MR300;GO;MR-300;GO;MA100;GO;MA100;GO;MR-100;GO;",
    "AY;VL2000;AC20000;VB200;MR400;GO;MR-400;GO;MR400;GO;",
    "AZ;LS2;MR40;GO;MR-40;GO;LE;MR0;GO;MR1;GO;",
    "AA;MR10,10;GO;MR-10,-10;GO;",
]
SEPARATORS = ["", " ", ";", "\r", "  ", "\n"]
#: A stage with its switches within reach of the moves above.
WORLD = {
    "X": AxisWorld(positive_limit=2_500.0, negative_limit=-2_500.0, home_low=40.0, home_high=60.0),
    "Y": AxisWorld(positive_limit=600.0),
}


def report_run(board: Board, rng: random.Random, count: int) -> bytes:
    """``count`` reports of the board's language (any spelling) with separators, or none,
    between them: what the receive fast path takes."""
    words = sorted(board.interpreter.words.reports)
    return b"".join(rng.choice(words) + rng.choice(SEPARATORS).encode() for _ in range(count))


def world_change(twin: Twin, rng: random.Random, now: float) -> None:
    model = twin.model
    axis = rng.choice(model.axes)
    kind = rng.randrange(7)
    if kind == 0:
        twin.set_limit(axis, rng.choice((1, -1)), rng.choice((True, False, None)), now)
    elif kind == 1:
        twin.set_home(axis, rng.choice((True, False, None)), now)
    elif kind == 2 and model.io_bits:
        twin.set_input(rng.randrange(model.io_bits), rng.choice((True, False, None)), now)
    elif kind == 3 and model.io_bits:
        twin.wire_input_to_aux(rng.randrange(model.io_bits), rng.choice((axis, None)))
    elif kind == 4:
        twin.inject_slip(axis, rng.choice((3.0, -40.0, 0.5)), now)
    elif kind == 5:
        twin.set_stall(axis, rng.choice((True, False)), now)
    else:
        twin.set_encoder_input(axis, rng.randrange(-500, 500), now)


SOURCE = st.sampled_from([1, 1, 1, 2, 0])
GAP = st.sampled_from([0.0, 0.0, 1e-4, 0.01, 0.3, 2.0])
STEP = st.one_of(
    st.tuples(st.just("soup"), st.integers(0, 2**32 - 1), st.integers(1, 40), SOURCE, GAP),
    st.tuples(st.just("reports"), st.integers(0, 2**32 - 1), st.integers(1, 90), SOURCE, GAP),
    # one report alone, as a client polls: the receive fast path's one lookup
    st.tuples(st.just("word"), st.integers(0, 2**32 - 1), SOURCE, GAP),
    st.tuples(st.just("statement"), st.integers(0, len(STATEMENTS) - 1), SOURCE, GAP),
    st.tuples(st.just("run"), st.floats(0.0, 3.0)),
    st.tuples(st.just("deadline"), st.sampled_from([-1e-9, -1e-12, 0.0, 1e-12, 1e-9])),
    st.tuples(st.just("world"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("take"), st.just(0)),
    st.tuples(st.just("registers"), st.just(0)),
    st.tuples(st.just("snapshot"), st.just(0)),
    st.tuples(st.just("power"), st.just(0)),
)


def play(model: str, steps: list[tuple[Any, ...]]) -> Twin:
    twin = Twin(get_model(model), world=WORLD)
    now = 0.0
    for step in steps:
        kind = step[0]
        if kind in ("soup", "reports", "word", "statement"):
            source, gap = step[-2], step[-1]
            now += gap
            if kind == "soup":
                data = command_soup(random.Random(step[1]), twin.model, step[2])
            elif kind == "reports":
                data = report_run(twin.fast, random.Random(step[1]), step[2])
            elif kind == "word":
                data = random.Random(step[1]).choice(sorted(twin.fast.interpreter.words.reports))
            else:
                data = STATEMENTS[step[1]].encode()
            twin.receive(data, now, source)  # what is not taken is dropped, by both
        elif kind == "run":
            until = now + step[1]
            while (d := twin.next_deadline()) is not None and d <= until:
                now = max(now, d)
                twin.advance(now)
            now = until
            twin.advance(now)
        elif kind == "deadline":
            d = twin.next_deadline()
            if d is not None:
                now = max(now, d + step[1])  # the next step comes just before, at or after it
        elif kind == "world":
            world_change(twin, random.Random(step[1]), now)
        elif kind == "take":
            twin.take_output_sourced()
        elif kind == "registers":
            twin.read_status_register(now)
            twin.read_done_register(now)
        elif kind == "snapshot":
            twin.snapshot(now)
        else:
            twin.power_cycle(now)
    twin.take_output_sourced()
    return twin


@pytest.mark.parametrize("model", ALL_MODELS)
def test_random_streams_say_the_same_with_and_without_fast_paths(
    model: str, request: pytest.FixtureRequest
) -> None:
    """60 streams a model; ``pytest --long`` (or ``OMSD_LONG=1``): 2,000."""

    @stream_settings(request.config, 60, 2000)
    @given(steps=st.lists(STEP, min_size=4, max_size=40))
    def streams(steps: list[tuple[Any, ...]]) -> None:
        play(model, steps)

    streams()


#: What changes a board at rest between two reports: an axis given a position of its own, a
#: jog with the switches off (motion with no deadline), its stop, a move, a flag reset.
AT_REST = [
    "AX;LP11;AY;LP-22;AZ;LP33;AT;LP-44;AX;",
    "AY;LF;VL300;AC3000;JG300;",
    "AY;ST;",
    "AZ;VL5000;AC50000;MR7;GO;ID;",
    "AX;RA;",
    "AA;",
    "AM;",
    "AT;",
]
REST_STEP = st.one_of(
    st.tuples(st.just("word"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("word"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("word"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("statement"), st.integers(0, len(AT_REST) - 1)),
    st.tuples(st.just("world"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("registers"), st.just(0)),
    st.tuples(st.just("time"), st.sampled_from([0.0, 1e-3, 0.05, 1.0])),
)


@pytest.mark.parametrize("model", ["PC48-4E", "PC48-8", "PCIX-400", "VS4-040", "PC46-4E"])
def test_replies_at_rest_say_what_the_board_says(
    model: str, request: pytest.FixtureRequest
) -> None:
    """Reports one at a time, as a client polls, on a board at rest whose axes stand at
    positions of their own, between axis selections, flag resets, a jog with no deadline,
    world changes and register reads: the replies a board at rest keeps
    (``Board._reports_at_rest``) must always be what the straightforward board says. 100
    streams a model; ``--long``: 2,000."""

    @stream_settings(request.config, 100, 2000)
    @given(steps=st.lists(REST_STEP, min_size=4, max_size=40))
    def streams(steps: list[tuple[Any, ...]]) -> None:
        twin = Twin(get_model(model), world=WORLD)
        now = 0.0
        twin.receive(AT_REST[0].encode(), now, 1)
        words = sorted(twin.fast.interpreter.words.reports)
        polled = [w for w in (b"RP", b"QA", b"RE", b"?KP") if w in words]
        for step in steps:
            kind = step[0]
            if kind == "word":
                rng = random.Random(step[1])
                twin.receive(rng.choice(polled if rng.random() < 0.6 else words), now, 1)
            elif kind == "statement":
                twin.receive(AT_REST[step[1]].encode(), now, 1)
            elif kind == "world":
                world_change(twin, random.Random(step[1]), now)
            elif kind == "registers":
                twin.read_status_register(now)
            else:
                now += step[1]
                while (d := twin.next_deadline()) is not None and d <= now:
                    twin.advance(d)
            twin.take_output_sourced()

    streams()


def test_a_reply_at_rest_is_kept_and_given_again() -> None:
    """The replies at rest are really kept (a change that stopped keeping them would pass the
    rest): asked again, a pure report is answered without its handler."""
    board = Board(get_model("PC48-4E"))
    board.receive(b"AY;LP-22;", 0.0)
    assert board.take_bytes() == b""
    board.receive(b"RP", 1.0)
    assert board.take_bytes() == b"\n\r-22\n\r"
    assert b"RP" in board._replies
    entry = board.interpreter.bare_reports()
    assert entry is not None
    handler_calls = []
    original = entry[b"RP"]
    entry[b"RP"] = (lambda *a: handler_calls.append(a), *original[1:])
    try:
        board.receive(b"RP", 2.0)
        assert board.take_bytes() == b"\n\r-22\n\r" and not handler_calls
        board.receive(b"AX", 2.0)  # another axis: not pure, nothing kept is good any more
        assert not board._replies or board._replies_epoch != board.rest_epoch
    finally:
        entry[b"RP"] = original


def test_an_axis_waiting_for_its_motion_is_stepped_when_its_mover_is_not_the_sender() -> None:
    """``Machine.settle`` does not step an axis waiting for its own motion while it moves,
    unless its mover is not the waiting command's sender: the reference's step makes the
    sender the mover again (whose session hears of the motion's end). No command does that
    today (a begin() by another session's talker while the wait holds); the mover is set by
    hand on both boards here, as such a begin would set it."""
    twin = Twin(get_model("PC48-4"))
    twin.receive(b"AX;VL1000;AC10000;MR5000;GO;ID;", 0.0, 1)
    twin.advance(0.5)
    for board in (twin.fast, twin.reference):
        assert board.axes[0].wait is not None and board.axes[0].wait.kind == "motion"
        board.axes[0].source = 7
    twin.settle(0.5)
    assert twin.fast.axes[0].source == 1


def test_no_reply_is_kept_while_an_axis_moves_with_no_deadline() -> None:
    """A jog with the switches off has no deadline at all: the board is at rest in
    ``at_rest``'s sense while the position runs on, so no reply of it may be kept."""
    twin = Twin(get_model("PC48-4E"))
    twin.receive(b"AY;LF;VL300;AC3000;JG300;", 0.0, 1)
    twin.advance(0.5)
    assert twin.next_deadline() is None
    answers = []
    for t in (1.0, 2.0, 2.0):
        twin.receive(b"RP", t, 1)
        answers.append(twin.take_bytes())
    assert answers == [b"\n\r285\n\r", b"\n\r585\n\r", b"\n\r585\n\r"]


@pytest.mark.parametrize("model", ["PC48-8", "PCIX-400"])
def test_a_polled_board_in_motion_says_the_same(model: str) -> None:
    """The load benchmark's traffic, deadline by deadline: axes jogging and running queued
    moves, each polled with ``QA RP`` in turn, ten times a second."""
    twin = Twin(get_model(model))
    axes = twin.model.axes
    twin.receive(b"AA;VL5000" + b",5000" * (len(axes) - 1) + b";", 0.0, 1)
    for i, letter in enumerate(axes):
        job = f"JG{2000 * (-1) ** i};" if i < 4 else "MR3000;GO;MR-3000;GO;" * 3
        twin.receive(f"A{letter};{job}".encode(), 0.0, 1)
    now = 0.0
    for k in range(80):
        now += 0.1
        while (d := twin.next_deadline()) is not None and d <= now:
            twin.advance(d)
        twin.receive(f"A{axes[k % len(axes)]} QA RP;".encode(), now, 1)
        twin.take_output_sourced()


@pytest.mark.parametrize("model", ["PC48-8", "PCIX-040"])  # (a servo's moves never follow on)
@pytest.mark.parametrize(
    "queue",
    [
        "MR3000;GO;MR-3000;GO;" * 3,
        # a command among the moves that is not one (the instant of its step is not a
        # follow-on's: the fast way stops before it, the straightforward way goes on)
        "MR3000;GO;MR-3000;GO;ID;MR3000;GO;MR-300;GO;",
        # a timed wait in the queue (an axis waiting for time is not passed by: not taken)
        "MR3000;GO;WT100;MR-3000;GO;MR3000;GO;",
        # the first move begun from a jog the other way: it turns round on its way, and where
        # it ends is counted the way it came (omsd.engine.counter)
        "JG-3000;MR3000;GO;MR-3000;GO;MR3000;GO;MR-3000;GO;",
    ],
)
def test_a_board_run_only_when_polled_says_the_same(
    model: str, queue: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The load benchmark's traffic as the daemon runs it: the board is run only when polled
    (no host hears the queued moves: it is not woken for them, ``omsd.engine.quiet``), so
    several moves end, and the next start, between two polls; the poll's advance takes those
    instants first (``follow_on_until``), more than one in one advance, where it can."""
    most = [0]
    until = follow_on.follow_on_until

    def counted(ex: Any, codes: Any, now: float) -> None:
        before = [(axis.traj, axis.queue.used) for axis in ex.machine.axes]
        until(ex, codes, now)
        after = [(axis.traj, axis.queue.used) for axis in ex.machine.axes]
        most[0] = max(most[0], sum(a != b for a, b in zip(after, before, strict=True)))

    monkeypatch.setattr(machine_module, "follow_on_until", counted)
    twin = Twin(get_model(model))
    axes = twin.model.axes
    twin.receive(b"AA;VL5000" + b",5000" * (len(axes) - 1) + b";", 0.0, 1)
    twin.receive(b"AC50000" + b",50000" * (len(axes) - 1) + b";", 0.0, 1)
    for i, letter in enumerate(axes):
        job = f"JG{2000 * (-1) ** i};" if i < len(axes) // 2 else queue
        twin.receive(f"A{letter};{job}".encode(), 0.0, 1)
    now = 0.0
    for k in range(60):
        now += 0.35  # (half a move: the queued axes' ends fall between the polls)
        twin.receive(f"A{axes[k % len(axes)]} QA RP;".encode(), now, 1)
        twin.take_output_sourced()
    assert most[0] >= 2  # (several axes' moves, in one advance)


def _load(path: Path, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_SESSIONS = _load(Path(__file__).parent / "test_sessions.py", "_twin_sessions")
_SCENARIOS = sorted(name for name in vars(_SESSIONS) if name.startswith("test_"))


@pytest.mark.parametrize("scenario", _SCENARIOS)
def test_sessions_scenarios_say_the_same(scenario: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """tests/board/test_sessions.py (two sessions on one board), on twins."""
    monkeypatch.setattr(_SESSIONS, "Board", Twin)
    getattr(_SESSIONS, scenario)()


def test_sessions_through_the_links_say_the_same(monkeypatch: pytest.MonkeyPatch) -> None:
    """tests/robustness/test_sessions.py's property (two clients through either link, one
    going mid-stream), on twins."""
    monkeypatch.setattr(robust_sessions, "Board", Twin)
    prop: Callable[[], None] = robust_sessions.test_replies_never_cross_sessions
    prop()


# -- the fast paths are taken -------------------------------------------------------------------


def counting(board: Board, monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Count the board's settles and the interpreter's pumps."""
    calls = {"settle": 0, "pump": 0}
    for owner, name in ((board, "settle"), (board.interpreter, "pump")):
        original = getattr(owner, name)

        def counted(*args: Any, _original: Any = original, _name: str = name) -> Any:
            calls[_name] += 1
            return _original(*args)

        monkeypatch.setattr(owner, name, counted)
    return calls


@pytest.mark.parametrize(
    ("model", "data", "reply"),
    [
        ("PC48-4E", b"RP", b"\n\r0\n\r"),
        ("PC48-4E", b"QA", b"\n\r\rPNNN\n\r\r"),
        ("PC48-8", b"AY QA RP;", b"\n\r\rPNNN\n\r\r\n\r0\n\r"),
        ("PCIX-400", b"?KP", b"kp10.00\n\r"),
        ("PCIX-400", b"AY;RP;", b"0\n\r"),
    ],
)
def test_a_report_on_a_board_at_rest_is_answered_without_a_settle(
    model: str, data: bytes, reply: bytes, monkeypatch: pytest.MonkeyPatch
) -> None:
    board = Board(get_model(model))
    board.receive(b"WY;", 0.0)
    board.take_output()
    calls = counting(board, monkeypatch)
    assert board.receive(data, 1.0) == len(data)
    assert board.take_bytes() == reply
    assert calls == {"settle": 0, "pump": 0}


def test_a_poll_of_a_board_in_motion_is_answered_without_a_settle(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    board = Board(get_model("PC48-8"))
    board.receive(b"AA VL5000,5000; AX JG2000; AY MR3000 GO MR-3000 GO ", 0.0)
    board.advance(0.3)
    board.take_output()
    calls = counting(board, monkeypatch)
    board.receive(b"AX QA RP;", 0.3)
    assert board.take_bytes() == b"\n\r\rPNNN\n\r\r\n\r598\n\r"  # 2000 steps/s, less the ramp
    assert calls == {"settle": 0, "pump": 0}


def test_the_fast_paths_step_aside(monkeypatch: pytest.MonkeyPatch) -> None:
    """Something due, a command that is not a report, another session's characters, or a board
    still initialising: the regular way."""
    board = Board(get_model("PC48-4"))
    board.receive(b"AX VL1000 AC10000 MR100 GO ", 0.0)
    calls = counting(board, monkeypatch)
    board.receive(b"RP", 5.0)  # the move ended meanwhile
    assert calls["settle"] > 0
    calls["settle"] = 0
    board.receive(b"RP MR1 ", 5.0)
    assert calls["settle"] > 0
    board.reset(6.0)
    calls["settle"] = calls["pump"] = 0
    board.receive(b"RP", 6.01)
    assert calls["pump"] > 0


def test_the_next_deadline_is_found_again_only_when_an_axis_changed() -> None:
    board = Board(get_model("PC48-8"))
    board.receive(b"AX VL1000 AC10000 MR1000 GO ", 0.0)
    first = board.next_deadline()
    assert first is not None and not board.deadline_stale
    board.receive(b"AY RP ", 0.1)
    assert not board.deadline_stale and board.next_deadline() == first
    board.receive(b"AY MR10 GO ", 0.1)  # another axis starts, and ends first: found again
    again = board.next_deadline()
    assert again is not None and again < first


@pytest.mark.parametrize(
    "world",
    [
        AxisWorld(limit_switches=LimitWiring.NORMALLY_CLOSED),  # a limit everywhere
        AxisWorld(positive_limit=0.0),  # resting on the switch
    ],
    ids=["normally-closed", "on-the-switch"],
)
def test_a_move_begun_where_a_limit_is_active_stops_at_its_first_tick(world: AxisWorld) -> None:
    """The first-tick look at the sensors is left out only where it cannot find anything
    (``omsd.engine.sensing.first_look_needed``): a move begun on the tick of its command with
    a limit active where it begins stops there, on both boards."""
    twin = Twin(get_model("PC48-4"), world={"X": world})
    twin.receive(b"AX;VL1000;AC10000;MR100;GO;", 0.0, 1)
    twin.advance(1.0)
    assert twin.fast.axes[0].position(1.0) == 0 and twin.fast.axes[0].motion is Motion.IDLE
    assert any(isinstance(item, LimitEvent) for item in twin.take_output())


def test_a_queued_move_begun_with_a_limit_forced_on_stops_at_its_first_tick() -> None:
    """A move queued behind another begins on the tick the first ends; a limit forced on from
    outside meanwhile (away from the switches) is found by the look on that tick."""
    twin = Twin(get_model("PC48-4"))
    twin.receive(b"AX;VL1000;AC10000;MR-100;GO;MR100;GO;", 0.0, 1)
    end = twin.next_deadline()
    assert end is not None
    twin.set_limit("X", 1, True, end / 2)  # the first move runs the other way: no limit
    twin.advance(end)
    twin.advance(end + 1.0)
    assert twin.fast.axes[0].position(end + 1.0) == -100  # the second move never went


def test_a_queued_move_begun_on_a_switch_stops_at_its_first_tick() -> None:
    """A move queued behind another begins where that one ended; a slip meanwhile put the
    carriage on the positive switch (the first move ran away from it, so no limit then): the
    look on the second move's first tick finds the limit."""
    twin = Twin(get_model("PC48-4"), world={"X": AxisWorld(positive_limit=30.0)})
    twin.receive(b"AX;VL1000;AC10000;MR-100;GO;MR100;GO;", 0.0, 1)
    end = twin.next_deadline()
    assert end is not None
    twin.inject_slip("X", 200.0, end / 2)
    twin.advance(end)
    twin.advance(end + 1.0)
    assert twin.fast.axes[0].position(end + 1.0) == -100  # the second move never went
    assert any(isinstance(item, LimitEvent) for item in twin.take_output())


@pytest.mark.parametrize("model", ["PC48-4", "PC46-21", "VS4-040"])
def test_a_jog_restarted_at_its_speed_and_a_position_loaded_on_its_tick_are_looked_at(
    model: str,
) -> None:
    """Found in review: a jog given again at its own speed begins on the tick of its command
    with its queue running on, and an ``LP`` on that tick moves the carriage's frame by the
    position's fraction of a step, onto a switch 0.05 steps away: the look on that tick finds
    the limit (the look is left out only for a move begun from rest)."""
    twin = Twin(get_model(model), world={"X": AxisWorld(positive_limit=50.05)})
    twin.receive(b"AX;AC10000;JG1000;JG1000;LP0;", 0.0, 1)
    twin.advance(1.0)
    assert any(isinstance(item, LimitEvent) for item in twin.take_output())


def test_a_move_begun_by_a_settle_outside_an_advance_is_looked_at() -> None:
    """Found in review: a queued move begun by the settle of a change of the world
    (``set_input`` ends a ``SW``) has its look pending when the call returns, as the reference
    has: the next deadline is that instant, and a settle there ends another axis's wait for an
    input released meanwhile without a settle (``wire_input_to_aux``)."""
    twin = Twin(get_model("PC48-4"))
    twin.set_input(0, False, 0.0)
    twin.receive(b"AZ;AF;", 0.0, 1)  # Z's aux output low, holding input 1 low
    twin.wire_input_to_aux(1, "Z")
    twin.receive(b"AY;SW1;MR100;GO;AX;SW0;MR100;GO;", 0.0, 1)
    twin.set_input(0, True, 0.5)  # 0.5 is a sample tick: X's move begins at once
    assert twin.next_deadline() == 0.5
    twin.wire_input_to_aux(1, None)
    twin.take_output()
    twin.receive(b"AY;RP;", 0.515, 1)
    assert twin.take_bytes() == b"\n\r87\n\r"


def test_a_queued_move_clear_of_the_switches_is_not_looked_at(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The look is really left out (a change that stopped leaving it out would pass the rest):
    a move queued behind another, clear of the switches, begins with no look at its first
    tick; the reference looks. A move begun by its command is looked at (it is not begun in
    the settle after an instant's events)."""
    looks: list[bool] = []
    on_sensor = reactions.on_sensor

    def counted(ex: Any, axis: Any, t: float) -> None:
        looks.append(ex.machine.fast_paths)
        on_sensor(ex, axis, t)

    monkeypatch.setattr(reactions, "on_sensor", counted)
    for fast in (True, False):
        board = Board(get_model("PC48-4"), fast_paths=fast)
        board.receive(b"AX;VL1000;AC10000;MR100;GO;MR-100;GO;", 0.0)
        end = board.next_deadline()
        assert end is not None
        board.advance(end)
        assert board.axes[0].motion is Motion.MOVE and board.axes[0].traj.t0 == end
    # the first move, begun by its command, is looked at by both; the second only by the reference
    assert looks.count(True) == 1 and looks.count(False) == 2


def started(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Count the moves the follow-on's fast path starts: at an instant's ends (``"ends"``:
    ``follow_on_until`` at the start of an advance, for the instants up to its time that are
    nothing else, or ``ends_that_follow_on`` before the reactions) and in a settle
    (``follow_on``). Each move started counts once, an axis that followed on more than once in
    one advance once (the tests here advance from deadline to deadline)."""
    taken = {"ends": 0, "settle": 0}
    ends, settle = follow_on.ends_that_follow_on, follow_on.follow_on
    until = follow_on.follow_on_until

    def counted_ends(ex: Any, codes: Any, t: float) -> bool:
        axes = ex.machine.axes
        before = [axis.traj for axis in axes]
        result = ends(ex, codes, t)
        taken["ends"] += sum(a.traj is not b for a, b in zip(axes, before, strict=True))
        return result

    def counted_until(ex: Any, codes: Any, now: float) -> None:
        axes = ex.machine.axes
        before = [axis.traj for axis in axes]
        until(ex, codes, now)
        taken["ends"] += sum(a.traj is not b for a, b in zip(axes, before, strict=True))

    monkeypatch.setattr(machine_module, "follow_on_until", counted_until)

    def counted_settle(*args: Any) -> bool:
        result = settle(*args)
        taken["settle"] += result
        return result

    monkeypatch.setattr(machine_module, "ends_that_follow_on", counted_ends)
    monkeypatch.setattr(machine_module, "follow_on", counted_settle)
    return taken


@pytest.mark.parametrize(
    ("model", "queue", "follow"),
    [
        ("PC48-8", "AU;VL5000;AC50000;MR3000;GO;MR-3000;GO;MA7;GO;MR2;GO;MA-9;GO;", 4),
        # encoder counts (MR in counts, divided by the ratio), a base velocity
        ("PC48-4E", "AX;ER2,1;VL900;AC9000;VB100;MR301;GO;MR-301;GO;MA-55;GO;", 2),
        ("PCIX-040", "AY;VL5000;AC50000;MR3000;GO;MR-3000;GO;MA7;GO;", 2),
        ("VS4-040", "AX;VL700;AC7000;MR100;GO;MR-100;GO;MR100;GO;", 2),
        # a loop: each pass's second move follows on; its first follows the loop's end
        ("PC46-4E", "AX;LS3;MR40;GO;MR-40;GO;LE;", 3),
        # a move that ends on its switch, and one that follows on from there: looked at on its
        # first tick, it finds the limit (the queue is flushed)
        ("PC48-4", "AX;VL5000;AC50000;MR3000;GO;MR10;GO;MR-10;GO;", 1),
    ],
)
def test_a_queued_move_follows_on_as_the_straightforward_board_does(
    model: str, queue: str, follow: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A queue of moves, run end by end (and polled between): the moves that follow on take the
    fast path (a change that quietly stopped taking it would pass the rest), and the twin boards
    agree in everything after every step (:class:`twin.Twin` compares them)."""
    taken = started(monkeypatch)
    twin = Twin(get_model(model), world={"X": AxisWorld(positive_limit=3000.0)})
    twin.receive(queue.encode(), 0.0, 1)
    now, deadlines = 0.0, 0
    while (d := twin.next_deadline()) is not None and deadlines < 40:
        twin.advance(now := d)
        twin.receive(b"RP;", now + 0.01, 1)
        deadlines += 1
    assert all(axis.queue.empty for axis in twin.fast.axes)
    assert sum(taken.values()) == follow


def test_a_move_that_cannot_follow_on_goes_the_straightforward_way(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A move by nothing, a move in a group (AA), a move with the aux output to set (PA), a
    servo axis's move: refused (the servo's refusal is caution, seen by the count alone), and
    the twins still agree."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-8"))
    twin.receive(b"AX;VL5000;AC50000;MR300;GO;MR0;GO;AA;MR10,10;GO;MR-10,-10;GO;", 0.0, 1)
    now = 0.0
    while (d := twin.next_deadline()) is not None:
        twin.advance(now := d)
    aux = Twin(get_model("PC48-8"))
    aux.receive(b"AX;PA1;VL5000;AC50000;MR300;GO;MR-300;GO;", 0.0, 1)
    while (d := aux.next_deadline()) is not None:
        aux.advance(d)
    servo = Twin(get_model("PCIX-400"))
    servo.receive(b"AY;VL5000;AC50000;MR3000;GO;MR-3000;GO;", 0.0, 1)
    now = 0.0
    while (d := servo.next_deadline()) is not None and now < 5.0:
        servo.advance(now := d)
    assert not any(taken.values())


def test_moves_that_end_together_follow_on_together_or_the_straightforward_way(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two axes whose moves end on the same tick: both follow on at the instant's ends; with a
    third whose queue then says something (``ID``), nothing takes that way (the reactions run
    in order), and the settle starts the moves that follow on. The twins agree after every
    step."""
    for queue, ends in (
        ("AA;VL5000,5000;AC50000,50000;AX;MR300;GO;MR-300;GO;AY;MR300;GO;MR7;GO;", 2),
        (
            "AA;VL5000,5000,5000;AC50000,50000,50000;AX;MR300;GO;MR-300;GO;"
            "AY;MR300;GO;MR7;GO;AZ;MR300;GO;ID;",
            0,
        ),
    ):
        taken = started(monkeypatch)
        twin = Twin(get_model("PC48-8"))
        twin.receive(queue.encode(), 0.0, 1)
        while (d := twin.next_deadline()) is not None:
            twin.advance(d)
        assert taken["ends"] == ends and taken["ends"] + taken["settle"] == 2


@pytest.mark.parametrize("slip", [0.0, 40.0])
def test_a_held_axis_corrects_before_its_next_move(
    slip: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Position maintenance (PC48 §6.15) on an encoder axis running a queue of moves: at a move's
    end the hold looks first (``reactions.on_end``), and corrects a slip before the queue goes
    on; the instant's ends are then not taken the fast way, and the twins agree."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4E"))
    twin.receive(b"AX;ER2,1;HV1000;HG10;HD1;HN;VL5000;AC50000;MR600;GO;MR-600;GO;MR60;GO;", 0.0, 1)
    twin.inject_slip("X", slip, 0.05)
    while (d := twin.next_deadline()) is not None:
        twin.advance(d)
    assert taken["ends"] == 0 and taken["settle"] == 2
    assert twin.fast.axes[0].in_position


def test_a_move_ending_with_a_look_due_then_is_ended_the_straightforward_way(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A slip a hair before a move's end (slip detection on, PC48 §6.16) makes a look at the
    sensors due on the end's own tick: the reactions run in order (the end, then the look, which
    finds the slip), not the fast way; the next move follows on in the settle after them."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4E"))
    twin.receive(b"AX;ER1,1;ES5;IS;VL5000;AC50000;MR300;GO;MR-300;GO;MR50;GO;", 0.0, 1)
    end = twin.next_deadline()
    while end is not None and twin.fast.axes[0].traj.t0 == 0.0:  # the first move's end
        twin.advance(end)
        end = twin.next_deadline()
    end = twin.fast.axes[0].traj.end_time
    before = dict(taken)  # (the first move's end was taken the fast way)
    twin.inject_slip("X", 40.0, end - 1e-9)
    while (d := twin.next_deadline()) is not None:
        twin.advance(d)
    assert taken["ends"] == before["ends"] == 1 and taken["settle"] == before["settle"] + 1
    assert any(isinstance(o, SlipEvent) for o in twin.fast.take_output())


def test_an_axis_that_steps_with_nothing_due_keeps_the_instant_in_order(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Found by review: an axis with nothing due may still step in the settle of a move's end,
    and its queued command may change the axis that follows on (``CN``: every axis's ramp;
    ``VS``: the Y axis's motion). Before its next move in the straightforward way: so the
    instant's ends are not taken the fast way then. X waits for an input that a rewiring, with
    no event, releases; or X's time wait ends a hair (within ``WAIT_SLACK``) after Y's end."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4"))
    twin.wire_input_to_aux(0, "Z")
    twin.receive(b"AZ;AF;AX;SW0;CN;AY;VL5000;AC50000;MR3000;GO;MR-100;GO;", 0.0, 1)
    assert twin.fast.axes[0].wait is not None and twin.fast.axes[0].wait.kind == "input"
    twin.wire_input_to_aux(0, None)
    while (d := twin.next_deadline()) is not None:
        twin.advance(d)
    assert taken["ends"] == 0 and taken["settle"] == 1

    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4"))
    twin.receive(b"AY;VL5000;AC50000;MR3000;GO;MR-3000;GO;", 0.0, 1)
    end = twin.fast.clock.at_or_after(twin.fast.axes[1].traj.end_time)
    twin.receive(b"AX;WT125;VS100,50,70;", end - 0.125 + 5e-13, 1)
    while (d := twin.next_deadline()) is not None and d < 10.0:
        twin.advance(d)
    assert taken["ends"] == 0


@pytest.mark.parametrize("shape", [RampShape(), RampShape(RampKind.PARABOLIC, 5)])
@settings(max_examples=200, deadline=None)
@given(
    distance=st.integers(-100_000, 100_000).filter(bool),
    speed=st.sampled_from([(5000.0, 50000.0, 0.0), (300.0, 1000.0, 50.0), (1e5, 1e6, 10.0)]),
    t0=st.floats(0.0, 1e4),
    x0=st.floats(-1e7, 1e7),
    times=st.lists(st.floats(-1.0, 30.0), min_size=1, max_size=5),
)
def test_a_trajectory_along_a_kept_course_is_the_computed_one(
    shape: RampShape,
    distance: int,
    speed: tuple[float, float, float],
    t0: float,
    x0: float,
    times: list[float],
) -> None:
    """``Trajectory.along`` a kept course (the follow-on's fast path) is, to the last bit, the
    trajectory ``Trajectory`` computes from the same pieces: its sums, its extent, and where it
    is when."""
    vmax, accel, vbase = speed
    pieces = move_pieces(float(distance), vmax, accel, vbase, shape)
    course = kept_course(float(distance), vmax, accel, vbase, shape)
    final = x0 + distance
    fast = Trajectory.along(t0, x0, course, final)
    plain = Trajectory(t0, x0, pieces, final)
    assert fast.pieces == plain.pieces
    assert (fast._starts, fast._offsets) == (plain._starts, plain._offsets)
    assert (fast.duration, fast.end_time, fast.final) == (plain.duration, plain.end_time, final)
    assert fast.extent() == plain.extent()
    for t in times:
        at = t0 + t
        assert (fast.position(at), fast.velocity(at)) == (plain.position(at), plain.velocity(at))


@settings(max_examples=300, deadline=None)
@given(
    start=st.sampled_from([0.0, 0.5, -7.25, 1234.0]),
    moves=st.lists(st.integers(-4000, 4000), min_size=1, max_size=3),
    speed=st.sampled_from([(5000, 50000), (300, 1000), (100000, 1000000)]),
    near=st.floats(-6.0, 6.0),
    far=st.floats(0.0, 3000.0),
    side=st.booleans(),
    load=st.sampled_from(["", "LP100;", "LP-2.5;"]),
    times=st.lists(st.floats(0.0, 1.0), min_size=1, max_size=4),
)
# a switch a hair beyond where the move ends, on either side: reached on its last tick
@example(0.0, [3000], (5000, 50000), 1e-12, 100.0, True, "", [0.25])
@example(0.0, [-3000], (5000, 50000), -1e-12, 100.0, False, "", [0.25])
def test_a_trajectory_clear_of_the_switches_crosses_none(
    start: float,
    moves: list[int],
    speed: tuple[int, int],
    near: float,
    far: float,
    side: bool,
    load: str,
    times: list[float],
) -> None:
    """``sensing._next_crossing`` leaves out the search for a trajectory whose whole extent stays
    clear of both switches: what it answers is what the search answers, with one switch a few
    steps (or a fraction of one) from where the moves end or begin and the other far, a counter
    loaded away from the carriage, at times before, during and after the moves. (With no margin
    at all, the examples fail.)"""
    stops = [start]
    for d in moves:
        stops.append(stops[-1] + d)
    edge = (max(stops) if side else min(stops)) + near
    world = AxisWorld(
        start_position=start,
        positive_limit=edge if side else max(stops) + far + 1.0,
        negative_limit=min(stops) - far - 1.0 if side else edge,
    )
    if not world.negative_limit < world.positive_limit:
        return
    board = Board(get_model("PC48-4"), world={"X": world})
    vl, ac = speed
    board.receive(
        f"AX;{load}VL{vl};AC{ac};".encode() + b"".join(f"MR{d};GO;".encode() for d in moves),
        0.0,
    )
    axis = board.axes[0]
    span = max(board.next_deadline() or 0.0, 0.01) * len(moves) * 2
    for at in sorted(times):
        board.advance(at * span)
        if axis.motion is Motion.IDLE:
            continue
        fast = sensing._next_crossing(axis)
        board.fast_paths = False
        try:
            plain = sensing._next_crossing(axis)
        finally:
            board.fast_paths = True
        assert fast == plain


def test_a_kept_move_profile_is_the_computed_one() -> None:
    """``move_pieces`` keeps the last profiles (``omsd.engine.ramps.PROFILES_KEPT``): asked
    again, the same pieces as computed afresh, in a new list (a caller may extend it)."""
    shapes = [RampShape(), RampShape(RampKind.PARABOLIC, 5), RampShape(RampKind.COSINE)]
    asked = [
        (d, v, a, b, shape)
        for d in (3000.0, -3000.0, 7.0, 0.0)
        for v, a, b in ((5000.0, 50000.0, 0.0), (100.0, 1000.0, 50.0))
        for shape in shapes
    ]
    for args in asked * 2:
        got = move_pieces(*args)
        assert got == profile_pieces(*args)
        got.append(cruise(0.0))
        assert move_pieces(*args) == profile_pieces(*args)


# -- what the receive fast path rests on --------------------------------------------------------


@pytest.mark.parametrize("model", sorted(MODELS))
def test_every_report_leaves_the_interpreter_holding_nothing(model: str) -> None:
    """``Board._reports_at_rest`` runs reports one after the other without the input buffer: each
    must queue nothing and leave nothing to read, whatever the mode (single, AA, AM)."""
    for mode in ("", "AA;", "AM;"):
        board = Board(get_model(model))
        board.receive(f"AX;{mode}".encode(), 0.0)
        board.take_output()
        for word, command in sorted(board.interpreter.words.reports.items()):
            board.receive(word, 1.0)
            assert board.interpreter.holds_nothing(), (word, mode)
            assert all(not a.queue.program for a in board.axes), (word, mode)
            assert board.at_rest(1.0) or board.deadline_stale, (word, mode)
            assert command.mnemonic in board.dialect.reports
            board.take_output()


#: States a pure report is run in: at rest, after moves and a slip, with limits and encoders.
PURE_SETUPS = [
    "",
    "AX;VL5000;AC50000;MR3000;GO;ID;AY;JG2000;",
    # a done flag and a limit (RA and RI reset them)
    "AX;VL5000;AC50000;MR10;GO;ID;AY;VL5000;AC50000;MR700;GO;AX;",
    # slip detected on X (EA resets it), an encoder ratio on Y
    "AX;ES5;IS;AY;ER3,2;LP30000;AZ;VL1000;MR-200;GO;AX;",
    "AA;",
    "AM;",
]


def _lasting(board: Board) -> dict[str, Any]:
    """The board's state but the time, who spoke last and what is kept only to be found
    faster (each axis's next event, found when asked)."""
    board.next_deadline()
    return {k: v for k, v in state(board).items() if k not in ("now", "talker")}


@pytest.mark.parametrize("model", sorted(MODELS))
def test_a_pure_report_changes_nothing(model: str) -> None:
    """A report the board calls pure (``Board.pure_reports``: what a board at rest may answer
    again from what it said) changes nothing but the time and what was said: the board's
    whole state is the same after it (a servo loop's too), and a second one says the same.
    (One refused in a state, a command error, says no reply: none is kept.)"""
    for setup in PURE_SETUPS:
        board = Board(get_model(model), world=WORLD)
        board.receive(setup.encode(), 0.0)
        board.advance(0.05)
        board.inject_slip(board.model.axes[0], 40.0, 0.06)
        board.advance(0.071)  # the reports come at 0.071: what is due by then has happened
        board.take_output()
        for word, command in sorted(board.interpreter.words.reports.items()):
            if command.mnemonic not in board.pure_reports:
                continue
            before = _lasting(board)
            board.receive(word, 0.071)  # (a servo loop it ran would be run to 0.071: a change)
            said = board.take_output()
            if [type(item).__name__ for item in said] != ["Reply"]:
                board.receive(b"\x19", 0.071)  # refused here (a command error): not kept
                board.take_output()
                continue
            after = _lasting(board)
            assert after == before, (setup, word)
            board.receive(word, 0.071)
            assert board.take_output() == said, (setup, word)


# -- a trajectory's extent ------------------------------------------------------------------------

_PIECE = st.one_of(
    st.builds(
        Poly,
        st.floats(-5e4, 5e4),
        st.floats(-1e6, 1e6),
        st.floats(-1e7, 1e7),
        st.floats(1e-4, 0.5),
    ),
    st.builds(
        Cosine, st.floats(-5e4, 5e4), st.floats(-5e4, 5e4), st.floats(1.0, 100.0), st.just(0.02)
    ),
    st.builds(Decay, st.floats(-100, 100), st.floats(0.5, 50.0), st.floats(1e-3, 1.0)),
    st.builds(
        Sinusoid,
        st.floats(-1e4, 1e4),
        st.floats(-4.0, 4.0),
        st.floats(-20.0, 20.0),
        st.floats(1e-3, 1.0),
    ),
)


@settings(max_examples=400, deadline=None)
@example(  # a jerk tiny beside the acceleration: Poly.turning_points lost the root at 1/3
    pieces=[Poly(7.0, -21.0, 6.045647143872433e-293, 0.5)],
    forever=None,
    x0=0.0,
    levels=[1.0],
    offsets=[0.0],
    start=0.25,
)
@given(
    pieces=st.lists(_PIECE, min_size=1, max_size=5),
    forever=st.sampled_from([None, 0.0, 3000.0, -3000.0]),
    x0=st.floats(-1e5, 1e5),
    levels=st.lists(st.floats(-3e5, 3e5), min_size=1, max_size=6),
    offsets=st.lists(st.sampled_from([0.0, 1e-9, -1e-9, 1e-4, -1e-4]), min_size=1, max_size=6),
    start=st.floats(-0.1, 3.0),
)
def test_first_time_says_the_same_with_and_without_the_extent(
    pieces: list[Any],
    forever: float | None,
    x0: float,
    levels: list[float],
    offsets: list[float],
    start: float,
) -> None:
    """``Trajectory.first_time`` answers "never" at once for a level beyond the trajectory's
    extent: the same answer the search gives, at the extremes too (levels at them and a hair
    beyond)."""
    if forever is not None:
        pieces = [*pieces, cruise(forever)]
    traj = Trajectory(0.0, x0, pieces)
    lowest, highest = traj.extent()
    candidates = [*levels, lowest, highest]
    questions = [
        (level + offset, above, start)
        for level in candidates
        for offset in offsets
        for above in (True, False)
    ]
    fast = [traj.first_time(*q) for q in questions]
    with pytest.MonkeyPatch.context() as m:
        m.setattr(Trajectory, "extent", lambda self: (-math.inf, math.inf))
        plain = [traj.first_time(*q) for q in questions]
    assert fast == plain


# -- the engine's attributes in slots ------------------------------------------------------------


#: What ``Board`` and the PCIx interpreter set of their own (they keep a dict for it).
BOARD_OWN = {
    "_plans",
    "_replies",
    "_replies_epoch",
    "_scans",
    "dialect",
    "interpreter",
    "pure_reports",
}
PCIX_OWN = {"macros", "table", "table_points"}


@pytest.mark.parametrize("model", sorted(MODELS))
def test_the_engine_keeps_its_attributes_in_slots(model: str) -> None:
    """``AxisState``, ``Core``, ``Machine`` and ``Interpreter`` declare their attributes in
    ``__slots__`` (Python 3.11 shares no more than 30 attribute names between the instances of a
    class; past that every instance has a slower dict of its own). A new attribute left out of
    them would land in the instance's dict: after a session of every kind of command (and a
    reset), an axis has nothing there, and a board and its interpreter only what their own
    classes (``Board``, a dialect's interpreter) set."""
    rng = random.Random(model)
    board = Board(get_model(model), world=WORLD)
    t = 0.0
    for statement in STATEMENTS * 2:
        board.receive(statement.encode(), t)
        t += 0.05
        board.advance(t)
    for _ in range(20):
        board.receive(command_soup(rng, board.model, 40), t)
        t += 0.05
        board.advance(t)
    board.receive(b"RS;", t)
    board.advance(t + 1.0)
    for axis in board.axes:
        assert vars(axis) == {}, (model, axis.letter)
    assert set(vars(board)) <= BOARD_OWN, sorted(set(vars(board)) - BOARD_OWN)
    assert set(vars(board.interpreter)) <= PCIX_OWN, sorted(set(vars(board.interpreter)) - PCIX_OWN)


def test_a_board_run_rarely_with_input_waiting_for_room_says_the_same(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Found by review (a mutation of ``follow_on_until`` no test saw): X's queue is full of
    moves, and the input buffer holds what waits for its room, another axis's ``ID`` behind it.
    The straightforward way reads the buffer in the settle of every instant a move of X ends
    (the room it made), so Y's ``ID`` is done at the end of X's first move; a board run only
    every 3 s must not take those instants together before reading (``holds_nothing``)."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4"))
    rest = b"AX;VL5000;AC50000;" + b"MR300;GO;MR-300;GO;" * 40 + b"AY;ID;AX;MR1;GO;"
    now = 0.0
    while rest:
        rest = rest[twin.receive(rest, now, 1) :]
        now += 3.0
        twin.advance(now)
    while (d := twin.next_deadline()) is not None:
        twin.advance(now := max(now + 3.0, d))
    assert taken["ends"] + taken["settle"] > 0


def test_moves_that_follow_on_from_between_two_steps_say_the_same(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Found by review (a mutation of ``follow_on_until`` no test saw): a move begun while the
    axis jogs starts between two steps; the moves after it start each where the last came to
    rest, on a whole step (``Axis.settle``), also when a board run only every 3 s takes their
    instants together. The move is MO's one pulse (an MR's target is the count's, a whole
    step: ``Executor.start_pending``), which ends between two steps as it began."""
    taken = started(monkeypatch)
    twin = Twin(get_model("PC48-4"))
    twin.receive(b"AY;VL5000;AC50000;JG-363;", 0.0, 1)
    twin.receive(b"AY;MO;MR-618;GO;MR737;GO;MR-5;GO;", 0.3, 1)
    twin.advance(0.3)  # (MO ends at -108.69, between two steps)
    assert twin.fast.axes[1].traj.final % 1.0
    twin.advance(0.3005)  # (MO's first look: its end is the next instant, and a follow-on's)
    for now in (3.0, 6.0):
        twin.receive(b"AY QA RP;", now, 1)
    assert taken["ends"] == 2  # (one axis, in each of the two advances)
