"""A board run only when its host could hear something says what a board run at every deadline
says, at the same times, and never late (issue 16: ``Machine.next_wakeup``,
:mod:`omsd.engine.quiet`).

Two boards are given the same random steps (the fuzzing host's command soup, runs of reports,
statements that move the axes, quietly or not, the world changed, registers read, the card
switched off and on, from two sessions, with time passing between them): the *punctual* one is
run at every deadline (``next_deadline``, what the daemon did before), the *lazy* one only at its
wake-ups (``next_wakeup``, what the daemon does now) and when a step reaches it. Whatever either
says is taken when it is run: nothing the lazy board says may be older than the moment it was
run (that would be a reply, a done or a limit heard late), the two must have said the same items
with the same times to the same sessions, and after every step that runs both to the same
instant they must be in the same state.

Then: the wake-ups are really later than the deadlines where the module says they may be (the
load benchmark's board), and exactly the deadlines where something can be heard.
"""

from __future__ import annotations

import random
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st
from robustness.conftest import stream_settings
from robustness.fuzz import ALL_MODELS, command_soup
from test_fast_paths import SEPARATORS, STATEMENTS, WORLD, report_run, world_change
from twin import state

from omsd.board import Board
from omsd.engine.events import Output
from omsd.models import get_model

#: Statements whose motion nobody hears (moves, jogs, timed waits; within reach of no switch,
#: or beyond one), then the ones that make an axis heard again.
QUIET = [
    "AZ;VL4000;AC40000;MR300;GO;MR-300;GO;MR300;GO;",
    "AT;MA500;GO;WT30;MA-200;GO;",
    "AZ;JG1500;",
    "AT;JG-2500;",
    "AZ;JG0;",
    "AX;MR600;GO;MR600;GO;MR600;GO;MR600;GO;MR600;GO;",  # the last ones reach X's switch
    "AX;MR-400;GO;MR400;GO;",
    "AY;MR-100;GO;MR100;GO;",
    "AX;LF;",
    "AX;LN;",
    "AZ;ID;",
    "AT;MR100;GO;ID;",
    "AA;MR100,100;GO;",
    "AZ;VL200;MR2000;GO;",
    "AZ;AF;",  # an aux output low (wired to an input by a world change, it holds it low)
    "AY;SW0;ID;",  # a wait for that input
]
STEPS = STATEMENTS + QUIET
SOURCE = st.sampled_from([1, 1, 1, 2, 0])
GAP = st.sampled_from([0.0, 0.0, 1e-4, 0.01, 0.3, 2.0])
STEP = st.one_of(
    st.tuples(st.just("soup"), st.integers(0, 2**32 - 1), st.integers(1, 40), SOURCE, GAP),
    st.tuples(st.just("reports"), st.integers(0, 2**32 - 1), st.integers(1, 20), SOURCE, GAP),
    st.tuples(st.just("statement"), st.integers(0, len(STEPS) - 1), SOURCE, GAP),
    st.tuples(st.just("statement"), st.integers(len(STATEMENTS), len(STEPS) - 1), SOURCE, GAP),
    st.tuples(st.just("run"), st.floats(0.0, 3.0)),
    st.tuples(st.just("world"), st.integers(0, 2**32 - 1)),
    st.tuples(st.just("registers"), st.just(0)),
    st.tuples(st.just("power"), st.just(0)),
)
#: Runs of a board between two steps; more means a wake-up that is never past.
MAX_RUNS = 100_000


class Late(AssertionError):
    """The lazy board said something later than it happened."""


class Pair:
    def __init__(self, model: str) -> None:
        spec = get_model(model)
        self.punctual = Board(spec, world=WORLD)
        self.lazy = Board(spec, world=WORLD)
        self.heard: dict[str, list[tuple[Output, int]]] = {"punctual": [], "lazy": []}
        self.runs = {"punctual": 0, "lazy": 0}
        self.steps: list[Any] = []

    def boards(self) -> list[tuple[str, Board]]:
        return [("punctual", self.punctual), ("lazy", self.lazy)]

    def take(self, name: str, board: Board, at: float) -> None:
        """What ``board`` said, taken at ``at`` (as the daemon sends it when it has run the
        board): none of it may be older."""
        out, sources = board.take_output_sourced()
        for item in out:
            if item.time < at - 1e-12:
                raise Late(f"{name}: {item!r} taken at {at}\nafter {self.steps}")
        self.heard[name] += zip(out, sources, strict=True)

    def run_until(self, until: float) -> None:
        """Time passes: the punctual board is run at every deadline, the lazy one at its
        wake-ups, up to ``until``."""
        for name, board, when in (
            ("punctual", self.punctual, self.punctual.next_deadline),
            ("lazy", self.lazy, self.lazy.next_wakeup),
        ):
            for _ in range(MAX_RUNS):
                t = when()
                if t is None or t > until:
                    break
                board.advance(t)
                self.runs[name] += 1
                self.take(name, board, t)
            else:
                raise AssertionError(f"{name}: run {MAX_RUNS} times before {until}")

    def both(self, at: float, call: str, *args: Any) -> None:
        """A step that runs both boards to ``at``: the same answer, and the same state after."""
        results = []
        for name, board in self.boards():
            try:
                results.append(repr(getattr(board, call)(*args)))
            except Exception as exc:  # the same refusal from both
                results.append(repr(exc))
            self.take(name, board, at)
        assert results[0] == results[1], f"{call}{args}: {results}\nafter {self.steps}"
        self.agree()

    def agree(self) -> None:
        assert self.heard["lazy"] == self.heard["punctual"], f"after {self.steps}"
        a, b = state(self.punctual), state(self.lazy)
        assert a == b, {k: (a[k], b[k]) for k in a if a[k] != b[k]}


def play(model: str, steps: list[tuple[Any, ...]]) -> Pair:
    pair = Pair(model)
    now = 0.0
    for step in steps:
        pair.steps.append(step)
        kind = step[0]
        if kind in ("soup", "reports", "statement"):
            source, gap = step[-2], step[-1]
            pair.run_until(now + gap)
            now += gap
            if kind == "soup":
                data = command_soup(random.Random(step[1]), pair.lazy.model, step[2])
            elif kind == "reports":
                data = report_run(pair.lazy, random.Random(step[1]), step[2])
            else:
                data = STEPS[step[1]].encode()
            pair.both(now, "receive", data, now, source)
        elif kind == "run":
            pair.run_until(now + step[1])
            now += step[1]
        elif kind == "world":
            seed = step[1]
            for name, board in pair.boards():
                world_change(board, random.Random(seed), now)  # a board has what a twin has
                pair.take(name, board, now)
            pair.both(now, "advance", now)
        elif kind == "registers":
            pair.both(now, "read_status_register", now)
        else:
            pair.both(now, "power_cycle", now)
    pair.run_until(now + 30.0)
    pair.both(now + 30.0, "advance", now + 30.0)
    return pair


@pytest.mark.parametrize("model", ALL_MODELS)
def test_a_board_run_at_its_wakeups_says_what_one_run_at_every_deadline_says(
    model: str, request: pytest.FixtureRequest
) -> None:
    """60 streams a model; ``pytest --long`` (or ``OMSD_LONG=1``): 1,500."""

    @stream_settings(request.config, 60, 1500)
    @given(steps=st.lists(STEP, min_size=4, max_size=30))
    def streams(steps: list[tuple[Any, ...]]) -> None:
        play(model, steps)

    streams()


@pytest.mark.parametrize("separator", SEPARATORS[1:3])
def test_quiet_moves_then_a_done_the_done_is_on_time(separator: str) -> None:
    """Quiet moves queued, then an ID after them while they run: from that moment the axis is
    heard, and its done comes at the end of the last move, not a moment later."""
    steps: list[tuple[Any, ...]] = [
        ("statement", STEPS.index(QUIET[0]), 1, 0.0),
        ("run", 0.05),
        ("statement", STEPS.index("AZ;ID;"), 1, 0.0),
        ("run", 5.0),
    ]
    pair = play("PC48-8", steps)
    assert any(type(item).__name__ == "DoneEvent" for item, _ in pair.heard["lazy"])


# -- the wake-ups are later than the deadlines where they may be -------------------------------


def load_board(model: str = "PC48-8") -> Board:
    """The load benchmark's board (bench/cost.py): four axes jogging, four running a queue of
    moves."""
    import sys
    from pathlib import Path

    root = str(Path(__file__).resolve().parents[2])
    if root not in sys.path:  # bench/ is a package of the repository, not of the install
        sys.path.insert(0, root)
    from bench.cost import SETUP

    board = Board(get_model(model))
    rest, t = SETUP, 0.0
    while rest:  # as the benchmark's client writes it: what the input buffer takes
        rest = rest[board.receive(rest, t, 1) :]
        t += 0.001
    board.advance(t)
    board.take_output()
    return board


def test_a_board_running_queued_moves_is_woken_only_for_what_can_be_heard() -> None:
    """The load's board: 30 moves on each of four axes and four jogs. The punctual board is run
    at each of the moves' deadlines; the lazy one only when its jogs reach full speed (a wait
    of theirs ends: a jog is heard, it will reach a switch some day), and then not until a
    jog could reach one, nearly an hour away."""
    pair = Pair("PC48-8")
    pair.punctual, pair.lazy = load_board(), load_board()
    pair.run_until(25.0)
    assert pair.runs["punctual"] >= 32  # the jogs at speed, then each move's end (together)
    assert pair.runs["lazy"] == 2  # the jogs at speed
    t = pair.lazy.next_wakeup()
    assert t is not None and t > 3000.0  # Z at 3000 steps/s to the switch at 10,000,000
    pair.both(25.0, "receive", b"AU RP AX RP", 25.0, 1)
    assert pair.heard["lazy"][-2][0].text == b"0"  # 15 back and forth: home again


def test_an_axis_found_quiet_is_not_asked_again_until_changed_from_outside(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Issue 16: the wake-up is found again after every instant's events, but an axis found
    quiet stays so while it goes its own way (its queued moves following on), so it is not
    asked again until the board is changed from outside (a command). The load's board: U, V,
    R, S run queued moves (quiet); X, Y, Z, T jog towards their switches (heard, and asked
    each time where their deadline is the earliest so far)."""
    import omsd.engine.machine as machine_module

    board = load_board()
    board.advance(1.0)  # the jogs at speed
    asked: list[str] = []
    real = machine_module.quiet

    def counting(axis: Any, codes: Any) -> bool:
        asked.append(axis.letter)
        return bool(real(axis, codes))

    monkeypatch.setattr(machine_module, "quiet", counting)
    board.receive(b"AX VL5000;", board.now, 1)  # a command: the quiet axes are asked again
    wakeup = board.next_wakeup()
    assert wakeup is not None and wakeup > 3000.0
    assert set("UVRS") <= set(asked)
    asked.clear()
    for _ in range(20):  # twenty instants of moves ending and the next starting
        deadline = board.next_deadline()
        assert deadline is not None and deadline < 20.0
        board.advance(deadline)
        assert board.next_wakeup() == wakeup
    assert not set("UVRS") & set(asked)
    board.receive(b"AX VL5000;", board.now, 1)
    assert board.next_wakeup() == wakeup
    assert set("UVRS") <= set(asked)


def test_an_axis_found_quiet_is_asked_again_after_another_axis_queue_changes_it() -> None:
    """What an axis was found to be (``AxisState.quiet_known``) is kept only while nothing
    changes it from outside its own queue of moves: here Y runs quiet moves and is found quiet;
    X's timed wait ends (a reaction, not a move that follows on) and X's queue runs VS, which
    sets Y streaming towards its switch (PC48 §6.8: "The parameters are time in 1/1024 second
    sample intervals, X velocity, and Y velocity"). Y is heard from then on: its limit comes at
    its own time, not when X's stream next wakes the board. (Fails if ``Machine._handle_due``
    does not bump ``outside_epoch``: the limit at 0.45 s taken at 1.2 s; the randomized streams
    above never found that.)"""
    pair = Pair("PC48-4")
    moves = b"AY VL2000 AC100000" + b" MR100 GO MR-100 GO" * 3
    pair.both(0.0, "receive", moves + b" AX WT200 VS1024,0,2000\r", 0.0, 1)
    pair.run_until(3.0)
    pair.both(3.0, "advance", 3.0)
    assert [type(item).__name__ for item, _ in pair.heard["lazy"]] == ["LimitEvent"]


def test_what_can_be_heard_is_woken_for_at_its_deadline() -> None:
    """A done, a limit: the wake-up is the deadline itself."""
    board = Board(get_model("PC48-4"), world=WORLD)
    board.receive(b"AZ VL4000 AC40000 MR300 GO MR-300 GO", 0.0)
    assert board.next_wakeup() is None  # nothing to hear
    assert board.next_deadline() is not None
    board.receive(b"AZ ID", 0.01)
    assert board.next_wakeup() == board.next_deadline()  # the axis is heard again
    board = Board(get_model("PC48-4"), world=WORLD)
    board.receive(b"AX VL4000 AC40000 MR3000 GO", 0.0)  # through X's switch at 2500
    assert board.next_wakeup() == board.next_deadline()
    board = Board(get_model("PC48-4"), world=WORLD)
    board.receive(b"AX VL4000 AC40000 MR300 GO MR300 GO", 0.0)
    assert board.next_wakeup() is None
    board.set_limit("X", 1, True, 0.01)  # a switch forced from outside: heard
    assert board.next_wakeup() == board.next_deadline()


def test_without_the_fast_paths_every_deadline_is_a_wakeup() -> None:
    board = Board(get_model("PC48-4"), fast_paths=False)
    board.receive(b"AZ VL4000 AC40000 MR300 GO MR-300 GO", 0.0)
    assert board.next_wakeup() == board.next_deadline() is not None


# -- through the links, as the service runs them -------------------------------------------------

#: What a host of the DOS driver writes besides commands: its wait characters (``!`` until a
#: done, ``@`` until a limit), a comment, the end-of-string character.
DRIVER_EXTRAS = ["!", "@", "*a comment\n", "\n", "AZ;MR300;GO;ID;!", "AX;MR3000;GO;@"]
LINK_STEP = st.one_of(
    st.tuples(st.just("soup"), st.integers(0, 2**32 - 1), st.integers(1, 40), SOURCE, GAP),
    st.tuples(st.just("statement"), st.integers(0, len(STEPS) - 1), SOURCE, GAP),
    st.tuples(st.just("statement"), st.integers(len(STATEMENTS), len(STEPS) - 1), SOURCE, GAP),
    st.tuples(st.just("extra"), st.integers(0, len(DRIVER_EXTRAS) - 1), SOURCE, GAP),
    st.tuples(st.just("run"), st.floats(0.0, 3.0)),
)


class LinkSide:
    """One board behind a link, run as :class:`omsd.service.BoardService` runs it: at its
    wake-ups (``punctual``: at every deadline), at every deadline while a client's bytes wait
    for room, and whenever a client writes. What it delivers is noted with the time."""

    def __init__(self, kind: str, model: str, punctual: bool) -> None:
        from omsd.link import make_link

        self.link = make_link(kind, Board(get_model(model), world=WORLD))
        self.punctual = punctual
        self.held: list[tuple[bytes, int]] = []  # bytes not taken yet, by session
        self.delivered: list[tuple[float, Any, Any]] = []

    def wakeup(self) -> float | None:
        if self.punctual or self.held:
            return self.link.next_deadline()
        return self.link.next_wakeup()

    def run(self, t: float) -> None:
        out = self.link.to_host(t)
        self.offer(t)
        out2 = self.link.to_host(t)
        pieces = out.pieces + out2.pieces
        events = out.events + out2.events
        if pieces or events:
            self.delivered.append((t, pieces, [repr(e) for e in events]))

    def offer(self, t: float) -> None:
        while self.held:
            data, session = self.held[0]
            taken = self.link.from_host(data, t, session)
            if taken < len(data):
                self.held[0] = (data[taken:], session)
                return
            self.held.pop(0)

    def run_until(self, until: float) -> None:
        for _ in range(MAX_RUNS):
            t = self.wakeup()
            if t is None or t > until:
                return
            self.run(t)
        raise AssertionError(f"run {MAX_RUNS} times before {until}")

    def write(self, data: bytes, session: int, t: float) -> None:
        self.held.append((data, session))
        self.run(t)


@pytest.mark.parametrize("kind", ["driver", "raw"])
@pytest.mark.parametrize("model", ["PC48-8", "PCIX-400", "VS4-040"])
def test_through_a_link_what_is_delivered_and_when_is_the_same(
    kind: str, model: str, request: pytest.FixtureRequest
) -> None:
    """Through either link, with the driver's wait characters and a client's bytes held back
    for room: the lazy side delivers the same bytes and events at the same instants. 40 streams;
    ``--long``: 1,000."""

    @stream_settings(request.config, 40, 1000)
    @given(steps=st.lists(LINK_STEP, min_size=4, max_size=30))
    def streams(steps: list[tuple[Any, ...]]) -> None:
        sides = [LinkSide(kind, model, punctual) for punctual in (True, False)]
        now = 0.0
        for step in steps:
            if step[0] == "run":
                now += step[1]
                for side in sides:
                    side.run_until(now)
                continue
            source, gap = step[-2], step[-1]
            now += gap
            for side in sides:
                side.run_until(now)
            if step[0] == "soup":
                data = command_soup(random.Random(step[1]), sides[0].link.board.model, step[2])
            elif step[0] == "statement":
                data = STEPS[step[1]].encode()
            else:
                data = DRIVER_EXTRAS[step[1]].encode()
            for side in sides:
                side.write(data, source, now)
            assert sides[1].delivered == sides[0].delivered, steps
        for side in sides:
            side.run_until(now + 30.0)
        assert sides[1].delivered == sides[0].delivered, steps
        assert [s.held for s in sides[1:]] == [sides[0].held]

    streams()


def test_a_queue_read_once_is_read_again_when_the_axis_is_moved_from_outside() -> None:
    """What the queue's moves reach is read once (``quiet.Plan``) and followed as the axis works
    through it, but only while the axis stands where the plan says: an encoder driven from
    outside in tracking mode puts the axis elsewhere, the same relative moves now reach X's
    switch at 2500, and the limit must be heard on time."""
    pair = Pair("PC48-4E")
    for _, board in pair.boards():
        board.receive(b"AX;ET;VL5000;AC50000;" + b"MR300;GO;" * 4, 0.0, 1)
    pair.run_until(0.2)  # the first move over (0.155 s), the second under way
    assert pair.lazy.next_wakeup() is None  # quiet: 1200 at most
    # tracking: the axis takes the encoder's count at once (and its queue the next move)
    pair.both(0.2, "set_encoder_input", "X", 2100, 0.2)
    assert pair.lazy.axes[0].traj.final == 2400  # this move stays clear of the switch...
    pair.run_until(5.0)  # ...the next one does not
    pair.both(5.0, "advance", 5.0)
    assert any(type(item).__name__ == "LimitEvent" for item, _ in pair.heard["lazy"])


def test_a_rewiring_of_the_world_makes_the_board_heard_again() -> None:
    """Found in review: an input released by unwiring an aux output lets a wait for it end at
    the board's next settle, here at a quiet deadline of another axis; the done after it must
    come then, not when the board is next run for another reason (T's wait, 2 s later)."""
    pair = Pair("PC48-4")
    steps = [b"AZ AF;", None, b"AY SW0 ID;", b"AX VL4000 AC40000 MR300 GO MR-300 GO MR300 GO;"]
    for data in [*steps, b"AT WT2000 ID;"]:
        if data is None:
            for _, board in pair.boards():
                board.wire_input_to_aux(0, "Z")  # input 0 held low by Z's aux output
        else:
            pair.both(0.0, "receive", data, 0.0, 1)
    pair.run_until(0.05)
    for _, board in pair.boards():
        board.wire_input_to_aux(0, None)  # released: Y's SW0 may end at the next settle
    pair.run_until(5.0)
    pair.both(5.0, "advance", 5.0)
    dones = [item for item, _ in pair.heard["lazy"] if type(item).__name__ == "DoneEvent"]
    assert len(dones) == 2 and dones[0].time < 0.2
