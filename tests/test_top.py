"""``omsd top``'s pieces without a daemon (issue 18): the keys, the view kept from the
subscription's messages (bounded), the position bar, the traffic rate, the snapshot text and
the live screen at 80 columns. The command against a real daemon, in a pty, is
tests/daemon/test_top.py."""

from __future__ import annotations

import copy
import io
from typing import Any

import pytest
from rich.console import Console

from omsd import topcli
from omsd.control import protocol
from omsd.top import keys
from omsd.topview import BAR, EVENTS, Meter, View, bar, plain, screen


def axis(position: int = 0, **changes: Any) -> dict[str, Any]:
    a = {
        "position": position,
        "encoder": position,
        "velocity": 0.0,
        "physical": float(position),
        "moving": False,
        "motion": "idle",
        "done": False,
        "direction": 1,
        "limit_negative": False,
        "limit_positive": False,
        "home": False,
        "aux": False,
        "queue_free": 200,
        "velocity_setting": 5000.0,
        "acceleration_setting": 1e6,
    }
    a.update(changes)
    return a


def snapshot(*names: str, axes: str = "XYZT") -> dict[str, Any]:
    return {
        "kind": "snapshot",
        "t": 1700000000.0,
        "rate": 10.0,
        "traffic": False,
        "boards": [
            {
                "name": name,
                "model": "PC48-8" if len(axes) > 4 else "PC48-4E",
                "link": "driver",
                "endpoints": [{"kind": "tcp", "address": f"127.0.0.1:{7001 + i}"}],
                "travel": {"X": [-1000.0, 1000.0]} if i == 0 else {},
                "state": {"clients": [], "axes": {letter: axis() for letter in axes}},
            }
            for i, name in enumerate(names)
        ],
    }


def view(*names: str, axes: str = "XYZT", select: str | None = None) -> View:
    snap = snapshot(*names, axes=axes)
    states = {b["name"]: copy.deepcopy(b["state"]) for b in snap["boards"]}
    return View(snap, states, "/run/omsd/control.sock", select, now=0.0)


# -- keys ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("typed", "meant"),
    [
        ("q", ["quit"]),
        ("p2\t", ["pause", "2", "next"]),
        ("\x1b[C\x1b[D\x1b[A\x1b[B", ["next", "previous", "previous", "next"]),
        ("\x1bOC\x1bOD", ["next", "previous"]),  # application cursor keys
        ("\x1b[Z", ["previous"]),  # Shift-Tab
        ("\x1b\x1b[5~x0Q", ["quit"]),  # a lone Escape, Page Up, keys of no use, Q
    ],
)
def test_keys(typed: str, meant: list[str]) -> None:
    assert keys(typed) == meant


def test_the_keys_pick_boards_pause_and_quit() -> None:
    v = view("a", "b", "c", select="b")
    assert v.board == "b"
    for key, board in (("next", "c"), ("next", "a"), ("previous", "c"), ("1", "a"), ("9", "a")):
        assert v.key(key) is True
        assert v.board == board, key
    v.key("pause")
    assert v.paused
    v.key("pause")
    assert not v.paused
    assert v.key("quit") is False


# -- the bar and the rate ------------------------------------------------------------------------


def test_the_bar_places_the_carriage_within_the_travel() -> None:
    assert bar(-1000, (-1000, 1000), ascii=True) == "[#-------]"
    assert bar(1000, (-1000, 1000), ascii=True) == "[-------#]"
    assert bar(5000, (-1000, 1000), ascii=True) == "[-------#]"  # beyond: at the end
    assert bar(0, (-1000, 1000)) == "├────●───┤"
    assert bar(0, None, ascii=True) == "[--------]"
    assert all(len(bar(x, (0, 100))) == BAR for x in range(-10, 120, 7))


def test_the_bar_spans_the_configured_travel_else_the_range_seen() -> None:
    v = view("a")
    assert v.span("a", "X") == (-1000.0, 1000.0)  # the configuration's limit switches
    assert v.span("a", "Y") is None  # one position seen: no range yet
    for position in (-300, 700, 200):
        v.states["a"]["axes"]["Y"]["physical"] = position
        v.apply({"kind": "state", "boards": {"a": {}}}, 1.0)
    assert v.span("a", "Y") == (-300, 700)


def test_the_traffic_rate_is_the_last_second() -> None:
    meter = Meter(0.0)
    assert meter.rate(0.5) == (0.0, 0.0)
    meter.add(0.5, 100, 10)  # totals since the subscription
    assert meter.rate(0.6) == (100.0, 10.0)
    meter.add(1.2, 300, 10)
    assert meter.rate(1.3) == (300.0, 10.0)  # 0..1.3: the totals at 0.3 were (0, 0)
    assert meter.rate(1.6) == (200.0, 0.0)  # at 0.6 they were (100, 10)
    assert meter.rate(2.5) == (0.0, 0.0)
    for k in range(1000):
        meter.add(3.0 + k * 0.1, 300 + k, 10)
    assert len(meter.samples) <= 12  # a second of samples at 10 a second, and the base


def test_the_view_keeps_a_bounded_history() -> None:
    v = view("a", "b")
    for k in range(10 * EVENTS):
        v.apply({"kind": "event", "event": {"t": 1.0, "board": "a", "text": f"limit {k}"}}, 1.0)
        v.apply({"kind": "state", "boards": {}, "traffic": {"a": {"in": k, "out": k}}}, k * 0.1)
    assert len(v.events) == EVENTS and v.events[-1]["text"] == f"limit {10 * EVENTS - 1}"
    assert len(v.meters["a"].samples) <= 12
    v.apply({"kind": "state", "boards": {}, "dropped": {"event": 3, "traffic": 0}}, 0.0)
    assert v.dropped == {"event": 3, "traffic": 0}


# -- the text ------------------------------------------------------------------------------------


def test_the_snapshot_text() -> None:
    v = view("xy", "slits")
    x = v.states["xy"]["axes"]["X"]
    x.update(position=-500, encoder=-500, physical=-500.0, limit_negative=True)
    v.states["xy"]["clients"] = ["tcp:127.0.0.1:7001 #1 (127.0.0.1:40000)"]
    text = plain(v)
    lines = text.splitlines()
    assert lines[0] == "omsd top: 2 boards (xy, slits)"
    assert lines[2] == "xy  PC48-4E  driver  tcp 127.0.0.1:7001"
    assert lines[3] == "clients: tcp:127.0.0.1:7001 #1 (127.0.0.1:40000)"
    assert lines[4].split() == [
        *("axis", "position", "encoder", "velocity", "motion", "done", "limits", "home"),
        *("queue", "travel"),
    ]
    assert lines[5].split() == [
        *("X", "-500", "-500", "0", "idle", "no", "-", "no", "200", "free"),
        *("[--#-----]", "-1000..1000"),
    ]
    assert lines[6].split()[-1] == "-"  # Y: no travel configured
    assert "slits  PC48-4E" in text
    only = plain(v, "slits")
    assert "xy  PC48-4E" not in only and "slits  PC48-4E" in only


@pytest.mark.parametrize(("width", "ends"), [(80, False), (100, True)])
def test_the_screen_fits_the_terminal(width: int, ends: bool) -> None:
    """Eight boards of eight axes at 80 columns: every column of the axes whole."""
    names = [f"board{i}" for i in range(1, 9)]
    v = view(*names, axes="XYZTUVRS", select="board1")
    v.states["board1"]["axes"]["X"].update(
        position=-12345678, encoder=-12345678, velocity=-1044000.0, motion="jog", moving=True
    )
    v.states["board1"]["clients"] = ["pty:/run/user/1000/omsd/board1", "tcp:127.0.0.1:7001 #3"]
    for k in range(20):
        v.apply({"kind": "event", "event": {"t": 1.0e9, "board": "b", "text": f"done {k}"}}, 1.0)
    v.apply({"kind": "state", "boards": {}, "traffic": {"board1": {"in": 999999, "out": 5}}}, 1.0)
    out = io.StringIO()
    console = Console(file=out, width=width, height=40, color_system=None)
    console.print(screen(v, 1.5, width, 40))
    lines = out.getvalue().splitlines()
    assert max(len(line) for line in lines) <= width
    header = next(line for line in lines if line.startswith("axis"))
    assert header.split() == [
        *("axis", "position", "encoder", "velocity", "motion", "done", "limits", "home"),
        *("queue", "travel"),
    ]
    row = next(line for line in lines if line.startswith("X "))
    assert row.split()[:5] == ["X", "-12345678", "-12345678", "-1.044e+06", "jog"]
    assert ("-1000..1000" in row) is ends
    board_row = next(line for line in lines if line.startswith("1 "))
    assert "moving X" in board_row and "977 KiB/s" in board_row and "+1" in board_row
    assert len(lines) <= 40 and "done 19" in lines[-2]  # the last events that fit


def test_the_help_quotes_the_protocols_rates() -> None:
    assert (topcli.DEFAULT_RATE, topcli.MAX_RATE) == (protocol.DEFAULT_RATE, protocol.MAX_RATE)
