"""The readings a status poll makes on its fast path say what the straightforward ones say
(issue 16): ``Trajectory.position_velocity``, ``counter.count_at``, ``counter.count_velocity`` and
``axis_status.status_inputs``, to the last bit, around the switches and the ends of motion; and
a run of reports polled again and again, run by its kept plan, says what the straightforward
board says."""

from __future__ import annotations

import math
import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from twin import Twin

from omsd.board import Board
from omsd.board.world import AxisWorld
from omsd.engine.axis_state import AxisState
from omsd.engine.axis_status import status_inputs
from omsd.engine.counter import count_at, count_velocity, counted
from omsd.engine.pieces import cruise
from omsd.engine.ramps import RampShape, move_pieces
from omsd.engine.trajectory import Course, Trajectory
from omsd.engine.world import SwitchType
from omsd.models import MODELS, get_model


@settings(max_examples=300, deadline=None)
@given(
    distance=st.integers(-100_000, 100_000).filter(bool),
    jog=st.sampled_from([None, 2000.0, -3000.0]),
    t0=st.sampled_from([0.0, 0.1, 12.345]),
    x0=st.sampled_from([0.0, -40.12, 700.195, 1e6 + 0.5]),
    times=st.lists(st.floats(-0.5, 5.0), min_size=1, max_size=6),
    taken_over=st.sampled_from([None, -1, 0, 1]),
)
def test_position_velocity_and_the_kept_count_are_the_computed_ones(
    distance: int,
    jog: float | None,
    t0: float,
    x0: float,
    times: list[float],
    taken_over: int | None,
) -> None:
    """``taken_over``: the trajectory took over from a motion whose count was ``x0`` rounded
    plus this (``Trajectory.count``), or begins from rest (None)."""
    pieces = move_pieces(float(distance), 5000.0, 50000.0, 0.0, RampShape())
    if jog is not None:
        pieces = [*pieces, cruise(jog)]
    count = None if taken_over is None else round(x0) + taken_over
    final = None if jog is not None else x0 + distance
    traj = Trajectory(t0, x0, pieces, final, count)
    plain = Trajectory(t0, x0, pieces, traj.final, count)
    both = Trajectory(t0, x0, pieces, traj.final, count)  # (count_velocity's own kept count)
    ends = [0.0, traj.duration] if traj.is_finite else [0.0]
    for t in [t0 + dt for dt in times + ends + times[:1]]:  # (one instant twice: kept)
        assert traj.position_velocity(t) == (plain.position(t), plain.velocity(t))
        assert count_at(traj, t) == counted(plain, plain.position(t), t)
        assert count_velocity(both, t) == (count_at(traj, t), plain.velocity(t))
        assert count_at(both, t) == count_at(traj, t)
        assert traj.position(t) == plain.position(t)
        rest = Trajectory.at_rest(t0, x0 + distance)  # (no pieces)
        assert rest.position_velocity(t) == (rest.position(t), rest.velocity(t))


WORLDS = [
    AxisWorld(negative_limit=-50.0, positive_limit=50.0, home_low=-2.0, home_high=3.0),
    AxisWorld(
        negative_limit=-50.0,
        positive_limit=50.0,
        home_low=-2.0,
        home_high=3.0,
        home_switch=SwitchType.NORMALLY_CLOSED,
    ),
]


@pytest.mark.parametrize("world", WORLDS)
@pytest.mark.parametrize("setup", ["", "HH;", "LH;", "ER2,1;MR0;GO;LP5;"])
@pytest.mark.parametrize("motion", ["JG400;", "JG-400;", "MR80;GO;", "MR-80;GO;", "MR3;GO;"])
def test_a_status_read_in_a_plain_world_is_the_straightforward_one(
    world: AxisWorld, setup: str, motion: str
) -> None:
    """Through the home switch and onto a limit, either way, each home level and switch type,
    with the counter loaded away from the carriage: every 5 ms, the fast reading is the
    straightforward one (``fast_paths`` off for the reading only)."""
    board = Board(get_model("PC48-4"), world={"X": world})
    board.receive(f"AX;VL400;AC4000;{setup}{motion}".encode(), 0.0)
    axis = board.axes[0]
    for k in range(1, 80):
        t = k * 0.005 + (1e-9 if k % 7 == 0 else 0.0)
        board.advance(t)
        fast = status_inputs(axis, t)
        board.fast_paths = False
        try:
            plain = status_inputs(axis, t)
            straight = axis.heading(t), axis.limit_active(axis.heading(t), t), axis.home_sensed(t)
        finally:
            board.fast_paths = True
        assert fast == plain == straight


@pytest.mark.parametrize("model", sorted(MODELS))
def test_runs_of_reports_polled_again_and_again_say_the_same(model: str) -> None:
    """A few runs of reports and selections (any spelling, separators or none, an axis the
    model lacks, a word that fails its checks in the mode it is run in), each polled many times
    in whatever mode and on whatever axis the last left, among moves and jogs: the board runs
    them by its kept plans (``Board._plan``) and says what the straightforward board
    says."""
    rng = random.Random(model)
    twin = Twin(get_model(model))
    words = sorted(twin.interpreter.words.reports)
    pool = [
        b"".join(
            rng.choice(words) + rng.choice([b" ", b";", b""]) for _ in range(rng.randint(2, 5))
        )
        for _ in range(8)
    ]
    moves = [b"AX;VL2000;AC20000;JG1000;", b"AY;MR300;GO;", b"AA;ST;", b"AX;JG-500;", b"AM;"]
    now = 0.0
    for k in range(300):
        if k % 40 == 0:
            twin.receive(moves[k // 40 % len(moves)], now, 1)
        twin.receive(rng.choice(pool), now, 1)
        twin.take_output_sourced()
        now += rng.choice([0.0, 0.01, 0.1])
        if rng.random() < 0.2:
            twin.advance(now)
    assert any(twin.fast._plans.values())  # (the plans were run, not only made)


def test_a_limit_forced_and_let_go_leaves_the_status_on_its_fast_path(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A limit switch forced (the control socket's ``limit``, the dashboard) and let go again
    (``None``: "let the carriage position decide again") leaves no switch forced: the status
    reads the switches on its fast path again, as it did before (it kept an entry of two
    ``None`` for the axis, and every status of the board went the straightforward way from
    then on), and says the same."""
    board = Board(get_model("PC48-4"), world={"X": WORLDS[0]})
    board.receive(b"AX;VL400;AC4000;JG400;", 0.0)
    board.set_limit("X", 1, True, 0.01)
    board.set_limit("X", -1, False, 0.02)
    board.set_limit("X", 1, None, 0.03)
    board.set_limit("X", -1, None, 0.04)
    assert not board.world.forced_limits
    axis = board.axes[0]
    board.advance(0.05)
    expected = (
        axis.heading(0.05),
        axis.limit_active(axis.heading(0.05), 0.05),
        axis.home_sensed(0.05),
    )

    def straightforward(*_: object) -> None:
        raise AssertionError("the status read the axis the straightforward way")

    monkeypatch.setattr(AxisState, "carriage", straightforward)
    assert status_inputs(axis, 0.05) == expected


#: Polls and what is done between them, for the fast paths' own edges (the status's plain
#: world, a kept plan's mode and axis, the kept count of one instant).
EDGES = [
    # forced switches set and let go between polls, on a jog through home and onto a limit
    (
        "PC48-4",
        [
            "AX;VL400;AC4000;JG400;",
            ("limit", "X", 1, True),
            ("home", "X", True),
            ("limit", "X", 1, None),
            ("home", "X", None),
            ("stall", "X", True),
            ("stall", "X", False),
        ],
    ),
    # soft travel limits on and off, on an encoder axis with a ratio and user units
    (
        "PC48-4E",
        [
            "AX;ER1000,2000;UU0.5;VL400;AC4000;TL10,-10;MR40;GO;",
            "TL0,0;",
            "LP601;",
            "HM601;",
            "MA601;GO;",
        ],
    ),
    # a servo axis homing and loaded at one instant (a new trajectory where a count was kept)
    ("PCIX-202", ["AX;VL2000;AC20000;JG1000;", "LP7;", "HM5;", "AY;HR-3;", "AX;LP0;"]),
    # a plan made in one mode, the mode changed by a command not in it; RA in the plan
    ("PC48-4", ["AX;MR5;GO;", "AA;", "AY;MR-5;GO;", "AM;", "AX;"]),
    # a selection that fails (AZ on a two-axis board), echo on and off, a contour defined
    ("PC48-2", ["AX;MR5;GO;", "EN;", "EF;", "AA;CD100,0;", "CE;", "AX;"]),
    # AA meeting points in loops, the PCIx's groups
    ("PC48-4", ["AA;LS3;MR5,5,5,5;GO;WD;LE;", "AA;WH;MR2,2,2,2;GO;WG;", "AX;"]),
    ("PCIX-400", ["AA;LS3;MR5,5,5,5;GO;WD;LE;", "AA;WS0.05;MR1,1,1,1;GO;WD;", "AX;"]),
]
POLLS = [b"AX QA RP;", b"AZ QA RP;", b"QA RA QA;", b"AY;RA;RP;RE;", b"AM QA RP", b"QA"]


@pytest.mark.parametrize(("model", "steps"), EDGES)
def test_polls_around_the_fast_paths_edges_say_the_same(model: str, steps: list[object]) -> None:
    """Each step (a command string or a change of the world) followed by polls every few
    milliseconds, among the switches and the ends of the motions: the board with its fast
    paths says what the straightforward one says."""
    twin = Twin(get_model(model), world={"X": WORLDS[0], "Y": WORLDS[1]})
    now = 0.0
    for step in steps:
        if isinstance(step, str):
            twin.receive(step.encode(), now)
        else:
            what, *args = step  # type: ignore[misc]
            if what == "limit":
                twin.set_limit(*args, now)
            elif what == "home":
                twin.set_home(*args, now)
            else:
                twin.set_stall(*args, now)
        for k in range(12):
            twin.receive(POLLS[k % len(POLLS)], now)
            twin.take_output_sourced()
            now += 0.0 if k % 5 == 0 else 0.004
        twin.advance(now)


def test_a_move_in_its_last_instant_is_where_it_ends_not_where_its_last_piece_began() -> None:
    """A trajectory asked about an instant before ``end_time`` (``t0 + duration``, rounded)
    that is ``duration`` or more after ``t0`` (``t - t0``, rounded) is at its end, not at the
    start of its last piece: ``_locate`` finds no piece there. ``AX VL5000 AC50000`` and
    ``MR1000 GO`` at 0.17 s, ``RP`` at 0.47041015625 s (the move ends a bit later, at
    0.47041015625000004) answered 750, the point where the ramp down began; RP "returns the
    current position ... even if the axis is in motion" (PC48 §6.13): 1000. The status poll's
    ``position_velocity`` reads it as ``position`` does."""
    t0, duration = 1.2168333089732086, 4.776289942088841
    traj = Trajectory(t0, 0.0, [cruise(1000.0, duration)])
    t = math.nextafter(traj.end_time, 0.0)
    assert t - t0 >= duration  # (the instant this is about)
    assert traj.position(t) == traj.final
    assert traj.position_velocity(t) == (traj.final, 0.0)
    twin = Twin(get_model("PC48-4"))
    twin.receive(b"AX;VL5000;AC50000;", 0.0)
    twin.receive(b"MR1000;GO;", 0.17)
    end = twin.axes[0].traj.end_time
    twin.take_output()
    twin.receive(b"RP;", math.nextafter(end, 0.0))
    assert [reply.text for reply in twin.take_output()] == [b"1000"]


@pytest.mark.parametrize("distance", [3000.0, -3000.0, 0.4, None])
def test_a_course_from_rest_counts_as_the_trajectory_it_is(distance: float | None) -> None:
    """``Trajectory.one_way_from_rest`` of a trajectory along a kept course is the one its own
    pieces give (count_velocity's fast path counts by it), and so is the count; None: a course
    that turns."""
    if distance is None:
        pieces = [cruise(100.0, 0.3), cruise(-100.0, 0.4)]
        distance = -10.0
    else:
        pieces = move_pieces(distance, 5000.0, 50000.0, 0.0, RampShape())
    along = Trajectory.along(1.0, -40.12, Course(pieces), -40.12 + distance)
    plain = Trajectory(1.0, -40.12, pieces, -40.12 + distance)
    assert along.one_way_from_rest == (plain.count is None and not plain.turns)
    for t in (1.0, 1.01, 1.2, 1.5, along.end_time):
        assert count_velocity(along, t) == (counted(plain, plain.position(t), t), plain.velocity(t))
