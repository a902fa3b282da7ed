"""``Control.subscribe`` against the real daemon (``python -m omsd``) with several boards, the
way ``omsd top`` and the web dashboard use it (issue 18): the snapshot, a move as it goes,
nothing while idle, the events, the traffic of one board, a client that does not read, and the
connection back to operations once it unsubscribes.

The rate limit itself, the queue's bounds and the cleaning up are tested in-process, where the
daemon's insides can be looked at (tests/test_watch.py)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from omsd.control.client import Control
from omsd.control.protocol import ControlError

from .process import TIMEOUT, Daemon, Omsd, wait_for

CONFIG = """
[control]
socket = "{socket}"

[[board]]
name = "xy"
tcp = "127.0.0.1:0"
[board.axes.X]
negative_limit = -5000
positive_limit = 5000

[[board]]
name = "servo"
model = "PCIX-400"
link = "raw"
tcp = "127.0.0.1:0"
"""


@pytest.fixture
def lab(omsd: Omsd, tmp_path: Path) -> Iterator[tuple[Daemon, Path]]:
    socket = tmp_path / "control.sock"
    daemon = omsd(config=CONFIG.format(socket=socket), expect=2)
    assert wait_for(socket.exists)
    yield daemon, socket


def test_the_snapshot_then_a_move_then_nothing(lab: tuple[Daemon, Path]) -> None:
    daemon, socket = lab
    with Control(socket, timeout=TIMEOUT) as ctl, daemon.connect("xy") as board:
        watch = ctl.subscribe(rate=20, timeout=TIMEOUT)
        assert [b["name"] for b in watch.snapshot["boards"]] == ["xy", "servo"]
        assert watch.snapshot["boards"][0]["travel"] == {"X": [-5000.0, 5000.0]}
        assert watch.read(0.3) is None  # idle: nothing
        board.send(b"AX VL10000 MR3000 GO ID")
        kinds = []
        for message in watch:
            kinds.append(message["kind"])
            if message["kind"] == "event":
                break
        assert message["event"]["text"] == "done (register 01)"
        assert kinds.count("state") >= 2 and "traffic" not in kinds
        while watch.read(0.5) is not None:  # the look after the done
            pass
        x = watch.states["xy"]["axes"]["X"]
        assert (x["position"], x["moving"], x["done"]) == (3000, False, True)
        assert watch.states["xy"]["clients"] == [
            f"tcp:{':'.join(map(str, daemon.tcp('xy')))} #1"
            f" ({board.sock.getsockname()[0]}:"
            f"{board.sock.getsockname()[1]})"
        ]
        stats = watch.close()
        assert stats is not None and stats["sent"] >= 3
        assert ctl.state("servo")["model"] == "PCIX-400"  # operations again


def test_the_traffic_of_one_board(lab: tuple[Daemon, Path]) -> None:
    daemon, socket = lab
    with Control(socket, timeout=TIMEOUT) as ctl:
        watch = ctl.subscribe(traffic="servo", timeout=TIMEOUT)
        for name, ask in (("xy", b"WY"), ("servo", b"WY\r")):
            with daemon.connect(name) as board:
                board.send(ask)
                board.read_until(b"\n")
        chunks = []
        for message in watch:
            if message["kind"] == "traffic":
                chunks.append(message["traffic"])
            counted = message["kind"] == "state" and "servo" in message.get("traffic", {})
            if counted and len(chunks) == 2:
                break
        assert [(c["board"], c["dir"]) for c in chunks] == [("servo", "in"), ("servo", "out")]
        assert all(c["board"] == "servo" for c in chunks)


def test_a_refused_subscription(lab: tuple[Daemon, Path]) -> None:
    _, socket = lab
    with Control(socket, timeout=TIMEOUT) as ctl:
        with pytest.raises(ControlError, match="no board 'zz'; boards: xy, servo"):
            ctl.subscribe("zz")
        with pytest.raises(ControlError, match="rate: expected"):
            ctl.subscribe(rate=100)
        assert ctl.boards()[0]["name"] == "xy"


def test_a_subscriber_that_does_not_read_holds_up_nobody(lab: tuple[Daemon, Path]) -> None:
    """Every chunk of traffic asked for, and nothing read for a while: the board's client is
    answered as always; the daemon drops what does not fit and says how much."""
    daemon, socket = lab
    with Control(socket, timeout=TIMEOUT) as ctl, daemon.connect("xy") as board:
        watch = ctl.subscribe(traffic=True)
        worst = 0.0
        for _ in range(4000):
            start = time.monotonic()
            board.send(b"RP")
            board.read_until(b"\n")
            worst = max(worst, time.monotonic() - start)
        assert worst < 0.5  # sanity: no round trip waited for the subscriber
        dropped = None
        while (message := watch.read(0.5)) is not None:  # the backlog, then quiet
            dropped = message.get("dropped", dropped)
        assert dropped is not None and dropped["traffic"] > 0
        stats = watch.close()
        assert stats is not None and stats["dropped"]["traffic"] >= dropped["traffic"]
        assert stats["peak"] <= 1000


def test_a_board_of_its_own_rate(lab: tuple[Daemon, Path]) -> None:
    """``rates``: the board a view shows in detail at its rate, the others at ``rate`` (the web
    dashboard asks 12 and 2); the snapshot says so."""
    daemon, socket = lab
    with Control(socket, timeout=TIMEOUT) as ctl, daemon.connect("xy") as board:
        watch = ctl.subscribe(rate=2, rates={"xy": 20}, timeout=TIMEOUT)
        assert (watch.snapshot["rate"], watch.snapshot["rates"]) == (2.0, {"xy": 20.0})
        board.send(b"AX VL1000 JG1000;")
        start = time.monotonic()
        looks = 0
        while time.monotonic() - start < 1.0:
            message = watch.read(0.5)
            if message is not None and message["kind"] == "state" and "xy" in message["boards"]:
                looks += 1
        assert looks >= 12, looks  # 20 a second asked; not the 2 of the others
        board.send(b"AX ST;")
        watch.close()
