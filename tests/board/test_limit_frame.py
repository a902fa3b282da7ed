"""A carriage stopped by a limit switch is on the switch (issue 12, item 1).

The switches and the stop point are taken in one frame (``Axis.carriage``: the physical position
of the last whole step emitted), so whatever fraction of a step HM, LP, ER or BC put between
the position counter and the carriage, an axis that a limit stopped reads that limit in every
query (RA, QA; on the PCIx also the MAX family's QL), in the state the control API and MQTT
publish (``Board.snapshot``), until it moves back off the switch.

PC48 §6.5 (the limit inputs): an axis "will stop moving if the limit line, for the direction the
axis is moving, is grounded"; RA/QA character 3 is "L" for "Overtravel (limit) detected in the
direction of travel" (§6.13). Before the fix, ``AX VL7000 AC50000 HM0`` then ``JG5000`` against
a limit at 30000 stopped at 28999 on the counter with RA ``PNNN``: the carriage a fraction of
a step short of the switch.
"""

from __future__ import annotations

from dataclasses import dataclass

from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

LIMIT = 30_000.0


def _pc48_status(text: str) -> bytes:
    return b"\n\r\r" + text.encode() + b"\n\r\r"


def _pcix_reply(text: str) -> bytes:
    return text.encode() + b"\n\r"


def test_issue_example_pc48_limit_after_home_reads_l() -> None:
    """The issue's own case: limits at +-30000, home window 1000..1100."""
    world = AxisWorld(negative_limit=-LIMIT, positive_limit=LIMIT, home_low=1000, home_high=1100)
    h = Harness("PC48-4", world={"X": world})
    h.send("AX VL7000 AC50000 HM0 JG5000 ")
    h.run(limit=60.0)
    assert not h.axis().moving
    assert h.query("RA") == _pc48_status("PNLN")
    assert h.query("QA") == _pc48_status("PNLN")
    snap = h.board.snapshot(h.t)["axes"]["X"]
    assert snap["limit_positive"] is True
    assert snap["physical"] >= LIMIT


def test_issue_example_pcix_limit_after_home_reads_l() -> None:
    world = AxisWorld(negative_limit=-LIMIT, positive_limit=LIMIT, home_low=1000, home_high=1100)
    h = Harness("PCIX-040", world={"X": world})
    h.send("AX; VL7000; AC50000; HM0; JG5000;")
    h.run(limit=60.0)
    assert not h.axis().moving
    assert h.query("QA;") == _pcix_reply("PNLN")
    # QL (MAX family): X's positive limit input at its LL (active low) level, every other
    # input inactive (high)
    assert h.query("QL;") == _ql_expected({("X", 1)}, axes=4)


def _ql_expected(active: set[tuple[str, int]], axes: int) -> bytes:
    """QL with the factory LL (active low): an input reads 1 (high) unless its limit is active.
    Bit i: axis i's negative limit; bit i + 8: its positive limit (omsd/board/max_family.py)."""
    word = 0
    for i, letter in enumerate("XYZTUVRS"[:axes]):
        if (letter, -1) not in active:
            word |= 1 << i
        if (letter, 1) not in active:
            word |= 1 << (i + 8)
    return _pcix_reply(f"{word:04x}")


@dataclass(frozen=True)
class Case:
    model: str
    pcix: bool
    encoder: bool
    servo: bool


CASES = [
    Case("PC48-4", pcix=False, encoder=False, servo=False),
    Case("PC48-4E", pcix=False, encoder=True, servo=False),
    Case("PCIX-004", pcix=True, encoder=False, servo=False),
    Case("PCIX-040", pcix=True, encoder=True, servo=False),
    Case("PCIX-400", pcix=True, encoder=True, servo=True),
]


def _send(h: Harness, case: Case, *commands: str) -> None:
    if case.pcix:
        h.send("".join(f"{c};" for c in commands))
    else:
        h.send(" ".join(commands) + " ")
    assert h.errors() == [], commands


def _status(h: Harness, case: Case, query: str) -> str:
    raw = h.query(f"{query};" if case.pcix else f"{query} ")
    text = raw.decode().strip("\n\r")
    assert len(text) == 4, raw
    return text


def _reads_limit(h: Harness, case: Case, direction: int, active: bool) -> None:
    """Every view of the limit in ``direction`` agrees with ``active``."""
    flag = "L" if active else "N"
    for query in ("RA", "QA"):
        status = _status(h, case, query)
        assert status[0] == ("P" if direction > 0 else "M"), status
        assert status[2] == flag, (query, status)
    key = "limit_positive" if direction > 0 else "limit_negative"
    snap = h.board.snapshot(h.t)["axes"]["X"]
    assert snap[key] is active, snap
    if case.pcix:
        expected = {("X", direction)} if active else set()
        assert h.query("QL;") == _ql_expected(expected, axes=4)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    case=st.sampled_from(CASES),
    start=st.floats(min_value=-500.0, max_value=500.0, allow_nan=False),
    home_from_below=st.booleans(),
    home_value=st.integers(min_value=-20_000, max_value=20_000),
    lp=st.one_of(st.none(), st.integers(min_value=-20_000, max_value=20_000)),
    ratio=st.sampled_from([(1, 1), (3, 2), (2, 3), (4, 1), (1, 4)]),
    backlash=st.integers(min_value=0, max_value=50),
    direction=st.sampled_from([1, -1]),
    velocity=st.integers(min_value=200, max_value=60_000),
    acceleration=st.integers(min_value=2_000, max_value=2_000_000),
    by_move=st.booleans(),
    soft=st.booleans(),
)
@example(  # the issue's case
    case=CASES[0],
    start=0.0,
    home_from_below=True,
    home_value=0,
    lp=None,
    ratio=(1, 1),
    backlash=0,
    direction=1,
    velocity=5000,
    acceleration=50_000,
    by_move=False,
    soft=False,
)
def test_a_limit_stop_reads_active_until_the_axis_moves_back(
    case: Case,
    start: float,
    home_from_below: bool,
    home_value: int,
    lp: int | None,
    ratio: tuple[int, int],
    backlash: int,
    direction: int,
    velocity: int,
    acceleration: int,
    by_move: bool,
    soft: bool,
) -> None:
    """Any home offset, LP, encoder ratio, backlash, direction, velocity and acceleration: the
    limit stop reads active in RA, QA (and QL on the PCIx) and the snapshot, stays so while the
    axis rests there, and a move back out clears it."""
    home_low = start + (1000.3 if home_from_below else -1000.7)
    world = AxisWorld(
        start_position=start,
        negative_limit=-LIMIT,
        positive_limit=LIMIT,
        home_low=home_low,
        home_high=home_low + 100.0,
    )
    h = Harness(case.model, world={"X": world})
    _send(h, case, "AX", "VL7000", "AC50000", f"{'HM' if home_from_below else 'HR'}{home_value}")
    h.run(limit=30.0)
    assert not h.axis().moving
    if case.encoder and not case.servo:
        _send(h, case, f"ER{ratio[0]},{ratio[1]}")
    if lp is not None:
        _send(h, case, f"LP{lp}")
    if case.pcix and backlash and not case.servo:
        _send(h, case, f"BC{backlash}")
    if soft:
        _send(h, case, "SL")
        # keep SL's ramp past the switch short of the other end of the travel
        acceleration = max(acceleration, velocity**2 // 10_000 + 1)
    _send(h, case, f"VL{velocity}", f"AC{acceleration}")
    if by_move:
        _send(h, case, f"MR{direction * 200_000}", "GO")
    else:
        _send(h, case, f"JG{direction * velocity}")
    h.run(limit=1000.0)
    axis = h.axis()
    assert not axis.moving
    assert axis.limit_latched == direction  # the limit is what stopped it
    _reads_limit(h, case, direction, active=True)

    h.advance(2.0)  # resting on the switch: still there
    _reads_limit(h, case, direction, active=True)

    # back out: further than the axis can have gone past the switch (a sample's travel, and
    # with SL the ramp down), in user counts (encoder counts on an encoder axis)
    step = max(1.0, ratio[0] / ratio[1]) if case.encoder and not case.servo else 1.0
    overshoot = velocity / 2048 + 2 * step + (velocity**2 / (2 * acceleration) if soft else 0)
    back = int(2 * overshoot + 60 * step)
    _send(h, case, "VL2000", "AC100000", f"MR{-direction * back}", "GO")
    h.run(limit=30.0)
    assert not h.axis().moving
    _reads_limit(h, case, -direction, active=False)
    key = "limit_positive" if direction > 0 else "limit_negative"
    assert h.board.snapshot(h.t)["axes"]["X"][key] is False
