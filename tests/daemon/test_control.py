"""Every control operation end to end: the real daemon (``python -m omsd``), its control socket
through :class:`omsd.control.client.Control`, and the board's TCP endpoint as the program under
test would see it (issue 6, "What it must show").

The driver link's markers are PC48 manual §7.3.3: "A limit interrupt causes an @ character
followed by the end character to be placed in the data stream, and an encoder slip interrupt
will place a $ and the end character into the stream. A DONE interrupt will place an ! into the
data stream followed by the byte read from the done flag register of the board, followed by the
end character."

Most tests pause the board's clock and step it (the ``time`` operation), so what happens between
two looks does not depend on how fast this machine is; real-time waits are bounded by deadlines
and only ever asserted from below (a reply "no earlier than" its latency).
"""

from __future__ import annotations

import json
import os
import random
import socket
import stat
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from omsd.board.events import DoneEvent
from omsd.board.harness import Harness
from omsd.control.client import Control
from omsd.control.protocol import MAX_LINE, ControlError

from .process import POLL, TIMEOUT, Conn, Daemon, Omsd, run_omsd, wait_for

WY = b"PC48 ver 3.00-4"


def control(path: Path) -> Control:
    """A client of the daemon's control socket. The daemon prints its endpoint lines before it
    has finished opening the control socket, so the first connection is retried for a moment."""
    deadline = time.monotonic() + TIMEOUT
    while True:
        try:
            return Control(path, timeout=TIMEOUT)
        except (FileNotFoundError, ConnectionRefusedError):
            if time.monotonic() > deadline:
                raise
            time.sleep(POLL)


@dataclass
class Bench:
    """A running daemon with one board, its control client and its TCP clients."""

    daemon: Daemon
    ctl: Control
    socket: Path
    conns: list[Conn] = field(default_factory=list)

    def connect(self) -> Conn:
        conn = self.daemon.connect()
        self.conns.append(conn)
        return conn

    def axis(self, letter: str = "X") -> dict[str, Any]:
        axis: dict[str, Any] = self.ctl.state()["axes"][letter]
        return axis


@pytest.fixture
def bench(omsd: Omsd, tmp_path: Path) -> Iterator[Callable[..., Bench]]:
    """``bench(*extra_args, board="PC48-4E")`` starts a daemon with a control socket in
    ``tmp_path``; its clients are closed before the daemon is stopped."""
    benches: list[Bench] = []

    def start(*extra: str, board: str = "PC48-4E") -> Bench:
        path = tmp_path / f"control-{len(benches)}.sock"
        daemon = omsd("--board", board, "--tcp", "127.0.0.1:0", "--control", str(path), *extra)
        made = Bench(daemon, control(path), path)
        benches.append(made)
        return made

    try:
        yield start
    finally:
        for made in benches:
            made.ctl.close()
            for conn in made.conns:
                conn.close()


def harness_twin(ctl: Control, model: str = "PC48-4E") -> Harness:
    """A manual-clock board in the state of the daemon's (paused) board: started at the daemon
    board's power-up, so both sample on the same 2048 Hz grid, and brought to its time."""
    state = ctl.state()
    assert state["clock"]["paused"]
    h = Harness(model, t=state["clock"]["origin"])
    h.until(state["time"])
    return h


# -- limits and slip: the driver link's @ and $ --------------------------------------------------


@pytest.mark.parametrize(("eos", "end"), [(None, b"\n"), ("0D", b"\r")])
def test_a_limit_closed_while_the_axis_moves_stops_it_and_the_driver_says_at(
    bench: Callable[..., Bench], eos: str | None, end: bytes
) -> None:
    b = bench(*(("--eos", eos) if eos else ()))
    c = b.connect()
    c.send(b"AX VL10000 MR1000000 GO ")  # 100 s of travel
    moving = b.ctl.wait_position("X", 1000, timeout=TIMEOUT)["axes"]["X"]
    assert moving["moving"] and moving["position"] >= 1000
    after = b.ctl.set_limit("X", +1, True)["axes"]["X"]
    assert after["limit_positive"] and not after["limit_negative"]
    c.expect(b"@" + end)
    stopped = b.ctl.wait_idle(timeout=TIMEOUT)["axes"]["X"]
    assert not stopped["moving"]
    assert 1000 <= stopped["position"] < 1_000_000
    assert b.axis()["position"] == stopped["position"]  # it stays stopped
    # the board goes on: the opposite direction is free, and "auto" hands the switch back
    assert c.ask(b"AX RP", end) == str(stopped["position"]).encode()
    c.send(b"AX MR-100 GO ID ")
    c.expect(b"!\x01" + end)
    assert b.axis()["position"] == stopped["position"] - 100
    assert not b.ctl.set_limit("X", +1, None)["axes"]["X"]["limit_positive"]
    assert c.quiet(0.05) == b""


def test_a_slip_on_an_axis_with_is_enabled_gives_dollar(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    c.send(b"AX IS VL10000 MR1000000 GO ")
    b.ctl.wait_position("X", 500, timeout=TIMEOUT)
    state = b.ctl.slip("X", 50)["axes"]["X"]
    c.expect(b"$\n")
    # the encoder saw the slip, the position counter did not
    assert state["encoder"] - state["position"] == pytest.approx(50, abs=1)


def test_a_slip_without_is_is_only_seen_by_the_encoder(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    state = b.ctl.slip("X", 50)["axes"]["X"]
    assert (state["position"], state["encoder"]) == (0, 50)
    assert c.ask(b"AX RP RE") == b"0"
    assert c.read_until(b"\n") == b"50\n"
    assert c.quiet(0.05) == b""


def test_a_slip_or_an_encoder_beyond_any_counter_is_refused_and_the_board_goes_on(
    bench: Callable[..., Bench],
) -> None:
    """Two slips of 1e308 steps took X's carriage to infinity: every later look at the board
    (``state``, ``AX RE``) raised OverflowError, the daemon answered nothing and closed the TCP
    client, for good. No counter of the card holds such a number (PC48 Appendix C: "Position
    range 134,000,000 pulses (+-67,000,000)"; a PCIx's LP is within +-33,554,431): a slip or
    an encoder count beyond a 32-bit counter is refused in one line, and the board goes on."""
    b = bench()
    for op in ("slip", "encoder"):
        key = "steps" if op == "slip" else "counts"
        for value in (1e308, -1e308, 2.0**31, -(2.0**31) - 1):
            with pytest.raises(ControlError, match=key) as refused:
                b.ctl.call(op, axis="X", **{key: value})
            assert "\n" not in str(refused.value)
    assert b.ctl.call("slip", axis="X", steps=2**31 - 1)["axes"]["X"]["encoder"] == 2**31 - 1
    assert b.ctl.call("encoder", axis="X", counts=-(2**31) + 1)["axes"]["X"]["encoder"] == (
        -(2**31) + 1
    )
    c = b.connect()
    assert c.ask(b"AX RE") == str(-(2**31) + 1).encode()
    assert c.ask(b"WY") == WY


# -- the cable ------------------------------------------------------------------------------------


def test_a_cut_cable_gives_eof_and_the_board_keeps_its_state(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    assert c.ask(b"AX RP") == b"0"
    b.ctl.pause()
    assert c.ask(b"AX VL1000 MR1000 GO ID WY") == WY  # 1 s of travel, nothing run yet
    b.ctl.step(0.25)
    before = b.axis()
    assert before["moving"] and 200 <= before["position"] <= 260
    assert b.ctl.cut_cable()["cable"] is False
    assert c.at_eof()
    # nobody gets through while it is cut
    late = b.connect()
    assert late.at_eof()
    state = b.ctl.state()
    assert state["faults"]["cable"] is False and state["clients"] == []
    assert state["axes"]["X"] == before  # paused: not a step lost or gained
    # the move goes on without the cable
    b.ctl.step(0.25)
    assert b.axis()["position"] == pytest.approx(before["position"] + 250, abs=1)
    assert b.ctl.connect_cable()["cable"] is True
    b.ctl.step(1.0)
    done = b.axis()
    assert (done["position"], done["done"], done["moving"]) == (1000, True, False)
    # a new client talks to the same board
    again = b.connect()
    assert again.ask(b"AX RP") == b"1000"
    assert again.quiet(0.05) == b""


# -- time -----------------------------------------------------------------------------------------


def test_paused_and_stepped_time_moves_the_axis_exactly_as_the_manual_clock(
    bench: Callable[..., Bench],
) -> None:
    b = bench()
    c = b.connect()
    b.ctl.pause()
    h = harness_twin(b.ctl)
    command = b"AX VL5000 AC20000 MR2000 GO ID WY"  # ramps of 0.25 s, 0.65 s in all
    assert c.ask(command) == WY
    h.send(command)
    seen = []
    steps = [0.01, 0.0237, 0.05, 0.001]
    t = h.t
    for i in range(40):  # 0.85 s in all
        state = b.ctl.step(steps[i % len(steps)])
        t += steps[i % len(steps)]
        assert state["time"] == t  # a step is exactly that much board time
        h.until(t)
        twin = h.board.snapshot(t)
        assert state["axes"] == twin["axes"], f"after {i + 1} steps, t = {t}"
        seen.append(state["axes"]["X"]["position"])
    assert seen == sorted(seen) and seen[0] < 100 and seen[-1] == 2000
    assert len(set(seen)) > 20  # it moved from step to step, not all at once
    assert [e for e in h.events() if isinstance(e, DoneEvent)]
    c.expect(b"!\x01\n")


def test_time_cannot_step_while_running_and_scale_is_bounded(bench: Callable[..., Bench]) -> None:
    b = bench()
    with pytest.raises(ControlError, match="paused"):
        b.ctl.step(0.1)
    with pytest.raises(ControlError, match="scale"):
        b.ctl.scale(0.0)
    with pytest.raises(ControlError, match="scale"):
        b.ctl.scale(1e6)
    b.ctl.pause()
    with pytest.raises(ControlError, match="forward"):
        b.ctl.step(-1.0)
    clock = b.ctl.resume()["clock"]
    assert (clock["paused"], clock["scale"]) == (False, 1.0)


def test_a_step_that_would_take_the_clock_past_its_precision_is_refused(
    bench: Callable[..., Bench],
) -> None:
    """A step of 1e300 s was taken: the board's clock, a float, then had no room left for its
    samples, and a move of 1000 steps reported done at once with RP still 0, for good."""
    b = bench()
    c = b.connect()
    b.ctl.pause()
    before = b.ctl.state()["time"]
    for seconds in (1e300, 1e17):
        with pytest.raises(ControlError, match="would pass"):
            b.ctl.step(seconds)
    assert b.ctl.state()["time"] == before
    assert b.ctl.step(1e6)["time"] == before + 1e6  # a long step is still a step
    b.ctl.scale(1000.0)
    b.ctl.resume()
    assert c.ask(b"AX VL100000 AC1000000 MR1000 GO ID WY") == WY
    c.expect(b"!\x01\n")
    assert c.ask(b"AX RP") == b"1000"


def test_scale_makes_board_time_run_ten_times_as_fast(bench: Callable[..., Bench]) -> None:
    b = bench()
    assert b.ctl.scale(10.0)["clock"]["scale"] == 10.0
    # the two looks happen inside [outer_start, outer_end] and around [inner_start, inner_end]
    outer_start = time.monotonic()
    first = b.ctl.state()["clock"]["now"]
    inner_start = time.monotonic()
    time.sleep(0.1)
    inner_end = time.monotonic()
    second = b.ctl.state()["clock"]["now"]
    outer_end = time.monotonic()
    board = second - first
    assert 10.0 * (inner_end - inner_start) - 1e-6 <= board <= 10.0 * (outer_end - outer_start)
    # a one-second move (board time) is done, at the right place
    c = b.connect()
    c.send(b"AX VL1000 MR1000 GO ID ")
    c.expect(b"!\x01\n")
    assert c.ask(b"AX RP") == b"1000"


# -- the world: home, inputs, encoder, stall ------------------------------------------------------


def test_home_switch_closed_mid_search_ends_the_home(bench: Callable[..., Bench]) -> None:
    """HM: the axis runs until the home switch is activated, and there the position counter is
    set (PC48 §6.11); the simulated switch is 1000 steps away, the forced one where we close
    it."""
    b = bench()
    c = b.connect()
    b.ctl.pause()
    assert c.ask(b"AX VL1000 HM0 ID WY") == WY
    b.ctl.step(0.1)
    assert b.axis()["moving"] and not b.axis()["home"]
    assert b.ctl.set_home("X", True)["axes"]["X"]["home"] is True
    b.ctl.step(0.1)
    c.expect(b"!\x01\n")
    axis = b.axis()
    assert not axis["moving"] and axis["done"]
    assert axis["physical"] == pytest.approx(100, abs=2)  # not the 1000 of the real switch
    assert abs(axis["position"]) <= 1  # HM0: home is position 0
    # released, the carriage (at ~100, outside the 1000..1100 window) decides: not home
    assert b.ctl.set_home("X", None)["axes"]["X"]["home"] is False
    assert b.ctl.set_home("X", True)["axes"]["X"]["home"] is True
    assert b.ctl.set_home("X", False)["axes"]["X"]["home"] is False


def test_sw_waits_until_the_input_is_released(bench: Callable[..., Bench]) -> None:
    """SW: "wait until the general purpose input is released (allowed to go high)"; inputs are
    pulled up, "input true" is low."""
    b = bench()
    c = b.connect()
    assert b.ctl.set_input(0, False)["io_low"] & 1
    b.ctl.pause()
    assert c.ask(b"AX SW0 MR100 GO ID WY") == WY
    b.ctl.step(2.0)
    assert b.axis()["position"] == 0 and not b.axis()["moving"]
    assert c.quiet(0.05) == b""
    assert not b.ctl.set_input(0, None)["io_low"] & 1  # released: pulled up
    b.ctl.step(0.2)
    c.expect(b"!\x01\n")
    assert b.axis()["position"] == 100


def test_ws_loops_while_the_input_is_low(bench: Callable[..., Bench]) -> None:
    """WS#...WD: "execute the commands between the WS and WD commands as a loop while the
    specified general purpose input line is true, i.e. low"."""
    b = bench()
    c = b.connect()
    b.ctl.set_input(3, False)
    b.ctl.pause()
    assert c.ask(b"AX WS3 MR10 GO WD ID WY") == WY
    b.ctl.step(0.5)
    looping = b.axis()["position"]
    assert looping > 100 and not b.axis()["done"]  # round and round, 10 steps at a time
    b.ctl.set_input(3, True)  # driven high: the loop ends
    b.ctl.step(0.2)
    c.expect(b"!\x01\n")
    final = b.axis()["position"]
    assert final >= looping and final % 10 == 0
    b.ctl.step(0.5)
    assert b.axis()["position"] == final


def test_input_bit_out_of_range_is_refused(bench: Callable[..., Bench]) -> None:
    b = bench()
    with pytest.raises(ControlError, match="bit"):
        b.ctl.set_input(99, False)
    with pytest.raises(ControlError, match="high"):
        b.ctl.call("input", bit=1, high="low")


def test_encoder_input_is_followed_in_et_tracking_mode(bench: Callable[..., Bench]) -> None:
    """§6.17 ET: "The axis will duplicate the encoder input. The ER command allows the user to
    scale the motor's movements relative to the encoder." """
    b = bench()
    c = b.connect()
    assert c.ask(b"AX ER1,4 ET WY") == WY
    state = b.ctl.encoder("X", 250)["axes"]["X"]
    assert (state["encoder"], state["position"]) == (250, 1000)
    assert c.ask(b"AX RE") == b"250"
    assert c.ask(b"AX RP") == b"1000"


def test_a_stalled_motor_is_seen_as_a_slip(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    b.ctl.pause()
    assert c.ask(b"AX VL1000 ES10 IS MR1000 GO WY") == WY
    b.ctl.step(0.1)
    b.ctl.stall("X", True)
    b.ctl.step(0.1)
    c.expect(b"$\n")
    axis = b.axis()
    assert axis["encoder"] == pytest.approx(100, abs=2)  # the carriage stayed
    assert axis["position"] == pytest.approx(200, abs=2)  # the pulses went on
    b.ctl.stall("X", False)
    b.ctl.step(0.1)
    axis = b.axis()
    assert axis["encoder"] - axis["physical"] == pytest.approx(0, abs=1)
    assert axis["physical"] == pytest.approx(200, abs=2)  # moving again from where it stood


# -- faults on the link ---------------------------------------------------------------------------


def test_latency_delays_every_reply(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    assert b.ctl.fault(latency=0.2)["latency"] == 0.2
    for _ in range(2):
        sent = time.monotonic()
        assert c.ask(b"WY") == WY
        assert time.monotonic() - sent >= 0.2
    b.ctl.clear_faults()
    assert b.ctl.state()["faults"]["latency"] == 0.0
    assert c.ask(b"WY") == WY


def test_baud_pacing_takes_a_character_time_per_byte(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    assert b.ctl.fault(baud=9600)["baud"] == 9600
    replies = WY + b"\n"
    sent = time.monotonic()
    c.send(b"WY WY WY WY")
    c.expect(replies * 4)
    assert time.monotonic() - sent >= len(replies * 4) / 960
    assert b.ctl.fault(baud=None)["baud"] is None
    with pytest.raises(ControlError, match="baud"):
        b.ctl.fault(baud=10)


def test_drop_one_loses_everything_both_ways(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    b.ctl.fault(drop=1.0)
    c.send(b"AX MR100 GO ID WY")
    assert c.quiet(0.3) == b""
    assert b.ctl.state()["axes"]["X"]["position"] == 0  # the board never heard it
    b.ctl.clear_faults()
    assert c.ask(b"WY") == WY


def noisy_cable(data: bytes, garble: float, dice: random.Random) -> bytes:
    """What omsd/faults.py says a cable with garbles (and no drops) does, worked out here with
    the seeded dice themselves rather than with omsd's ``Faults``: for each character one draw
    decides a drop (never, at probability 0), one a garble, and a garbled character has one
    bit, drawn from 0 to 7, flipped."""
    out = bytearray()
    for b in data:
        dice.random()  # the drop draw: never below a drop probability of 0
        if dice.random() < garble:
            b ^= 1 << dice.randrange(8)
        out.append(b)
    return bytes(out)


def test_garble_is_seeded_the_same_damage_twice(bench: Callable[..., Bench]) -> None:
    """The dice are seeded: the same bytes get the same damage, on the way in (the board hears
    the damaged command) and on the way back (the reply to it is damaged in turn)."""
    b = bench()
    c = b.connect()
    command = b"WY WY WY WY WY WY"
    dice = random.Random(7)  # seed 7, one stream for both directions, inbound first
    heard = noisy_cable(command, 0.05, dice)
    assert heard == b"WY WY WY W] WY WY"  # 'Y' (0x59) with bit 2 flipped is ']' (0x5D)
    # what the board answers to that, on a clean cable: W] is not a command
    c.send(heard)
    answer = (WY + b"\n") * 3 + b"#\n" + (WY + b"\n") * 2
    c.expect(answer)
    # and the way back: four characters each with one bit flipped, none lost
    expected = noisy_cable(answer, 0.05, dice)
    assert expected == (
        b"PC48 ver 3,00-4\n"  # '.' 0x2E ^ 0x02 = ',' 0x2C
        + (WY + b"\n") * 2
        + b"#\n"
        + b"PC48 ver 3>00-4\n"  # '.' 0x2E ^ 0x10 = '>' 0x3E
        + b"PC48 fer 3.00\r4\n"  # 'v' 0x76 ^ 0x10 = 'f' 0x66, '-' 0x2D ^ 0x20 = CR 0x0D
    )
    for _ in range(2):
        b.ctl.reset()  # the same interpreter state (no half command left) each time
        b.ctl.fault(garble=0.05, seed=7)
        c.send(command)
        c.expect(expected)
        assert c.quiet(0.05) == b""
        b.ctl.clear_faults()


def test_bad_fault_settings_are_refused(bench: Callable[..., Bench]) -> None:
    b = bench()
    for args, word in [
        ({"latency": -1}, "latency"),
        ({"latency": "x"}, "latency"),
        ({"drop": 2}, "drop"),
        ({"garble": None}, "garble"),
        ({"baud": "fast"}, "baud"),
        ({"seed": 1.5}, "seed"),
        ({"cable": "yes"}, "cable"),
    ]:
        with pytest.raises(ControlError, match=word) as info:
            b.ctl.call("fault", **args)
        assert "\n" not in str(info.value)
    assert b.ctl.fault() == {
        "latency": 0.0,
        "baud": None,
        "drop": 0.0,
        "garble": 0.0,
        "cable": True,
        "seed": 0,
    }


# -- power ----------------------------------------------------------------------------------------


def test_reset_is_a_power_cycle(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    c.send(b"AX MR1000 GO ID AY MR-500 GO ")
    c.expect(b"!\x01\n")
    b.ctl.wait_idle(timeout=TIMEOUT)
    assert c.ask(b"AA RP") == b"1000,-500,0,0"
    state = b.ctl.reset()
    assert [a["position"] for a in state["axes"].values()] == [0, 0, 0, 0]
    assert not any(a["done"] or a["moving"] for a in state["axes"].values())
    assert c.ask(b"WY") == WY
    assert c.ask(b"AA RP") == b"0,0,0,0"


# -- waiting --------------------------------------------------------------------------------------


def test_wait_for_done_and_idle_without_polling(bench: Callable[..., Bench]) -> None:
    b = bench()
    c = b.connect()
    c.send(b"AX VL2000 MR1000 GO ID ")
    done = b.ctl.wait_done("X", timeout=TIMEOUT)["axes"]["X"]
    assert (done["position"], done["done"]) == (1000, True)
    c.expect(b"!\x01\n")
    c.send(b"AY VL2000 MR-300 GO ")
    idle = b.ctl.wait_idle(timeout=TIMEOUT)["axes"]
    assert idle["Y"]["position"] == -300 and not any(a["moving"] for a in idle.values())
    # already there: at once
    assert b.ctl.wait_position("Y", -300, timeout=0)["axes"]["Y"]["position"] == -300


def test_wait_for_a_position_returns_when_stepped_time_gets_there(
    bench: Callable[..., Bench],
) -> None:
    """A wait on one connection while time is stepped on another: it answers at the step that
    brings the axis to the position (or at once if it came in after that step: the axis has
    passed the position on this motion), with the board as it is then."""
    b = bench()
    c = b.connect()
    b.ctl.pause()
    assert c.ask(b"AX VL1000 MR1000 GO ID WY") == WY
    results: dict[str, Any] = {}

    def wait(**args: Any) -> threading.Thread:
        def run() -> None:
            with control(b.socket) as other:
                try:
                    results["state"] = other.call("wait", **args)
                except ControlError as exc:
                    results["error"] = str(exc)

        results.clear()
        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        return thread

    thread = wait(until="position", axis="X", position=400, timeout=TIMEOUT)
    while (here := b.ctl.step(0.05)["axes"]["X"])["position"] < 400:
        assert here["moving"]
    thread.join(TIMEOUT)
    assert not thread.is_alive() and "error" not in results
    assert results["state"]["axes"]["X"] == here == b.axis()
    assert 400 <= here["position"] < 500 and here["moving"]

    thread = wait(until="done", axis="X", timeout=TIMEOUT)
    b.ctl.step(1.0)
    thread.join(TIMEOUT)
    assert not thread.is_alive() and "error" not in results
    assert results["state"]["axes"]["X"]["position"] == 1000
    assert results["state"]["axes"]["X"]["done"] is True
    c.expect(b"!\x01\n")


def test_a_position_already_passed_on_this_motion_is_reached(
    bench: Callable[..., Bench],
) -> None:
    """``wait position`` means "reaches (or passes)": asked a moment late, while the axis is
    still on its way past the target, it is satisfied at once rather than waiting for a return
    trip; a target not yet reached is not."""
    b = bench()
    c = b.connect()
    b.ctl.pause()
    assert c.ask(b"AX VL1000 MR1000 GO ID WY") == WY
    b.ctl.step(0.5)
    here = b.axis()["position"]
    assert 450 <= here <= 550
    assert b.ctl.wait_position("X", 300, timeout=0)["axes"]["X"]["position"] == here
    assert b.ctl.wait_position("X", here, timeout=0)["axes"]["X"]["position"] == here
    for target in (700, -5):  # ahead, and behind where the motion began
        with pytest.raises(ControlError, match="timed out"):
            b.ctl.wait_position("X", target, timeout=0)
    with pytest.raises(ControlError, match="timed out"):  # at rest elsewhere
        b.ctl.wait_position("Y", 5, timeout=0)


def test_a_wait_that_times_out_is_a_one_line_error(bench: Callable[..., Bench]) -> None:
    b = bench()
    sent = time.monotonic()
    with pytest.raises(ControlError, match="timed out") as info:
        b.ctl.wait_done("Y", timeout=0.2)
    assert time.monotonic() - sent >= 0.2
    assert "\n" not in str(info.value)
    with pytest.raises(ControlError, match="until"):
        b.ctl.call("wait", until="forever")
    with pytest.raises(ControlError, match="timeout"):
        b.ctl.call("wait", until="idle", timeout=-1)
    assert b.ctl.state()["board"] == "board1"  # the connection is still good


def cpu_seconds(pid: int) -> float:
    """User and system time the process has used (``/proc/<pid>/stat``)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def test_two_waits_on_an_idle_board_leave_the_daemon_idle(bench: Callable[..., Bench]) -> None:
    """Two ``wait``s on one board, nothing moving: each wait ran the board at every wake-up,
    which told every other wait that the board had changed, which ran the board...: the daemon
    spun at 100 % of a core for as long as they waited (and 20,000 of them sent in one go
    stopped every board answering, SIGTERM included). A wait now runs the board only when no
    change woke it."""
    b = bench()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        reader = s.makefile("rb")
        for ident in (1, 2):
            s.sendall(b'{"id":%d,"op":"wait","until":"done","axis":"X","timeout":60}\n' % ident)
        assert b.ctl.state()["board"] == "board1"  # both are in progress by now
        pid = b.daemon.proc.pid
        before = cpu_seconds(pid)
        time.sleep(1.0)
        assert cpu_seconds(pid) - before < 0.3
        c = b.connect()
        c.send(b"AX MR10 GO ID ")
        c.expect(b"!\x01\n")
        replies = [json.loads(reader.readline()) for _ in range(2)]
        assert sorted(r["id"] for r in replies) == [1, 2] and all(r["ok"] for r in replies)


def test_waits_are_bounded_and_end_with_their_connection(bench: Callable[..., Bench]) -> None:
    """Waits in progress are bounded (``MAX_WAITS``: one more gets a one-line error), and a
    connection's waits end when it goes: they went on to their timeout (an hour at most) after
    their client had gone, with nobody to answer. Also while another axis moves, the board
    changing all the time (Python 3.11's ``asyncio.wait_for`` swallowed a cancel that came as
    the board woke the wait)."""
    import omsd.control.server

    limit = getattr(omsd.control.server, "MAX_WAITS", 256)
    b = bench()
    request = b'{"id":%d,"op":"wait","until":"done","axis":"X","timeout":3600}\n'
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        reader = s.makefile("rb")
        s.sendall(b"".join(request % i for i in range(limit + 1)))
        refused = json.loads(reader.readline())
        assert refused["ok"] is False and "too many waits" in refused["error"], refused
        c = b.connect()
        c.send(b"AY VL20000 MR10000000 GO ")
        assert wait_for(lambda: int(c.ask(b"AY RP")) > 2000)
    # the connection has gone, and its waits with it: there is room for new ones
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        reader = s.makefile("rb")
        deadline = time.monotonic() + TIMEOUT
        while True:
            s.sendall(b'{"id":1,"op":"wait","until":"done","axis":"X","timeout":0.01}\n')
            reply = json.loads(reader.readline())
            if "timed out" in reply["error"] or time.monotonic() > deadline:
                break
        assert "timed out" in reply["error"], reply


def _accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT).close()
    except ConnectionRefusedError:
        return False
    return True


def test_the_socket_and_its_tcp_endpoint_share_one_bound_on_waits(
    omsd: Omsd, tmp_path: Path
) -> None:
    """``MAX_WAITS`` is the control server's, and the Unix socket and ``[control] tcp`` are one
    server: waits sent to both count together, so a client cannot have twice as many by using
    both. (The dashboard and the MQTT bridge each have a server and a bound of their own:
    docs/decisions.md, "Control, faults and time".)"""
    from omsd.control import server

    limit = server.MAX_WAITS
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = int(probe.getsockname()[1])
    path, config = tmp_path / "control.sock", tmp_path / "omsd.toml"
    config.write_text(
        f'[control]\ntcp = "127.0.0.1:{port}"\n\n[[board]]\nmodel = "PC48-4E"\ntcp = 0\n'
    )
    omsd("--config", str(config), "--control", str(path))
    control(path).close()  # the socket listens; the TCP endpoint may be a moment behind
    assert wait_for(lambda: _accepts(port)), "the control TCP endpoint does not listen"
    request = b'{"id":%d,"op":"wait","until":"done","axis":"X","timeout":3600}\n'
    with (
        socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as unix,
        socket.create_connection(("127.0.0.1", port), timeout=TIMEOUT) as tcp,
    ):
        unix.settimeout(TIMEOUT)
        unix.connect(str(path))
        unix.sendall(b"".join(request % i for i in range(limit)))
        state = b'{"id":"s","op":"state"}\n'  # answered once the waits before it are in place
        unix.sendall(state)
        assert json.loads(unix.makefile("rb").readline())["id"] == "s"
        tcp.sendall(request % limit)
        refused = json.loads(tcp.makefile("rb").readline())
        assert refused["ok"] is False and "too many waits" in refused["error"], refused


def rss_kib(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError("no VmRSS")


def test_a_client_that_asks_and_never_reads_is_held_off_not_buffered(
    bench: Callable[..., Bench],
) -> None:
    """Each request line became a task at once, whatever was still waiting to be answered: a
    client that sent ``state`` requests as fast as it could and read none of the answers took
    the daemon from 55 MB to 1.6 GB in 15 s (through the web dashboard, read-only as it was),
    and the board's round trips to a second. Now a connection with ``MAX_PENDING`` requests
    in progress is read no further until one is answered: the client is held off by its own
    socket, and the daemon's memory stays put."""
    b = bench()
    pid = b.daemon.proc.pid
    c = b.connect()
    before = rss_kib(pid)
    request = b'{"id":1,"op":"state"}\n' * 1000
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.settimeout(1.0)
        s.connect(str(b.socket))
        deadline = time.monotonic() + 4.0
        sent = 0
        while time.monotonic() < deadline:
            try:
                s.sendall(request)
            except TimeoutError:
                break  # held off
            sent += 1000
        grown = rss_kib(pid) - before
        assert c.ask(b"WY") == WY
        assert grown < 50_000, f"{grown} KiB more after {sent} requests"
        assert sent < 200_000


def test_a_wait_does_not_hold_up_other_requests_on_the_same_connection(
    bench: Callable[..., Bench],
) -> None:
    """Requests on one connection run side by side: a state answered while a wait is pending."""
    b = bench()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        s.sendall(b'{"id":1,"op":"wait","until":"done","axis":"X","timeout":5}\n')
        s.sendall(b'{"id":2,"op":"state"}\n')
        reader = s.makefile("rb")
        first = json.loads(reader.readline())
        assert (first["id"], first["ok"]) == (2, True)
        b.connect().send(b"AX ID ")
        second = json.loads(reader.readline())
        assert (second["id"], second["ok"]) == (1, True)
        assert second["result"]["axes"]["X"]["done"] is True


# -- looking: boards and state --------------------------------------------------------------------


TWO_BOARDS = """
[[board]]
name = "xy"
model = "PC48-4E"
tcp = ["127.0.0.1:0"]

[[board]]
name = "servo"
model = "PCIX-400"
link = "raw"
tcp = ["127.0.0.1:0"]
"""


def test_boards_lists_names_models_links_and_endpoints(omsd: Omsd, tmp_path: Path) -> None:
    path = tmp_path / "c.sock"
    daemon = omsd("--control", str(path), config=TWO_BOARDS, expect=2)
    with control(path) as ctl:
        boards = ctl.boards()
        assert [(b["name"], b["model"], b["link"]) for b in boards] == [
            ("xy", "PC48-4E", "driver"),
            ("servo", "PCIX-400", "raw"),
        ]
        for b in boards:
            (endpoint,) = b["endpoints"]
            assert endpoint == {"kind": "tcp", "address": "{}:{}".format(*daemon.tcp(b["name"]))}
        # with several boards one must be named
        with pytest.raises(ControlError, match="several boards"):
            ctl.state()
        with pytest.raises(ControlError, match="no board 'zz'"):
            ctl.state("zz")
        assert ctl.state("servo")["model"] == "PCIX-400"
        assert ctl.state("servo")["link"]["kind"] == "raw"
        ctl.set_limit("X", -1, True, board="servo")
        assert ctl.state("servo")["axes"]["X"]["limit_negative"] is True
        assert ctl.state("xy")["axes"]["X"]["limit_negative"] is False


def test_state_shows_registers_queue_space_and_the_link_buffers(
    bench: Callable[..., Bench],
) -> None:
    b = bench()
    state = b.ctl.state()
    assert state["board"] == "board1" and state["model"] == "PC48-4E"
    assert set(state["axes"]) == {"X", "Y", "Z", "T"}
    for key in ("position", "encoder", "velocity", "moving", "done", "limit_positive", "home"):
        assert key in state["axes"]["X"]
    assert (state["done_register"], state["control"], state["io_low"]) == (0, 0, 0)
    assert state["link"] == {
        "kind": "driver",
        "room": 256,
        "pending": 0,
        "waiting": None,
        "held": None,
    }
    assert state["faults"]["cable"] is True and state["clients"] == []
    empty = state["axes"]["X"]["queue_free"]

    c = b.connect()
    b.ctl.pause()
    # the driver's "!": it holds what follows until the board is done (§7.3.4)
    c.send(b"AX VL1000 MR800 GO ID ! RP")
    assert wait_for(lambda: b.ctl.state()["link"]["waiting"] == "done")
    state = b.ctl.state()
    assert state["link"]["pending"] > 0 and state["link"]["room"] < 256
    assert state["axes"]["X"]["queue_free"] < empty  # MR, GO and ID are in the queue
    assert len(state["clients"]) == 1 and "tcp:127.0.0.1" in state["clients"][0]
    b.ctl.step(1.0)
    c.expect(b"!\x01\n800\n")
    state = b.ctl.state()
    assert state["link"]["waiting"] is None and state["link"]["pending"] == 0
    assert state["axes"]["X"]["queue_free"] == empty
    # the done register was read by the driver's interrupt routine: clear again
    assert state["done_register"] == 0


# -- the protocol itself --------------------------------------------------------------------------


def raw_request(s: socket.socket, reader: Any, line: bytes) -> dict[str, Any]:
    s.sendall(line)
    reply: dict[str, Any] = json.loads(reader.readline())
    return reply


def test_a_client_that_stops_sending_still_gets_its_answers(bench: Callable[..., Bench]) -> None:
    """``printf '...' | nc -NU control.sock`` sends its requests and half-closes: the end of
    its input came with them, the daemon took it for the client gone and cancelled what it had
    just read, and the client read nothing but the end (the last line, without its newline,
    was never answered at all). Now what was asked is answered, a wait that does not end within
    ``GRACE`` seconds excepted (a client that has gone for good takes its waits with it)."""
    b = bench()
    requests = b"".join(b'{"id":%d,"op":"state"}\n' % i for i in range(20))
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        s.sendall(requests + b'{"id":20,"op":"boards"}')
        s.shutdown(socket.SHUT_WR)
        replies = [json.loads(line) for line in s.makefile("rb")]
    assert sorted(r["id"] for r in replies) == list(range(21))
    assert all(r["ok"] for r in replies)


def test_bad_requests_get_one_line_errors_and_the_connection_stays(
    bench: Callable[..., Bench],
) -> None:
    b = bench()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        reader = s.makefile("rb")
        for line, ident, word in [
            (b'{"id":1,"op":"nope"}\n', 1, "unknown op"),
            (b'{"id":2,"op":"state","board":"zz"}\n', 2, "no board"),
            (b'{"id":3,"op":"limit","axis":"Q","direction":1,"active":true}\n', 3, "no axis"),
            (b'{"id":4,"op":"limit","axis":"X","direction":2,"active":true}\n', 4, "direction"),
            (b'{"id":5,"op":"slip","axis":"X","steps":"many"}\n', 5, "steps"),
            (b'{"id":6,"op":"home","axis":"X","active":1}\n', 6, "active"),
            (b'{"id":7,"op":"time","action":"rewind"}\n', 7, "action"),
            (b"this is not json\n", None, "JSON"),
            (b"[1, 2]\n", None, "JSON"),
            (b'{"id":8}\n', 8, "unknown op"),
            # not JSON, and no reply at all before: the reply, echoing the id, could not be
            # written (NaN), or Python's stack ran out (a RecursionError)
            (b'{"id":NaN,"op":"boards"}\n', None, "NaN"),
            (b'{"id":10,"op":"slip","axis":"X","steps":-Infinity}\n', None, "Infinity"),
            (b"[" * 30000 + b"\n", None, "nested too deeply"),
            # a number beyond a float's range is read as infinity: no reply either, the client
            # waited for ever ("ValueError: Out of range float values are not JSON compliant")
            (b'{"id":1e999,"op":"boards"}\n', None, "1e999"),
            (b'{"id":15,"op":"wait","until":"idle","timeout":-1e400}\n', None, "-1e400"),
            # an integer beyond a float's range is JSON, and read whole: float() of it raised
            # OverflowError in the op, and the request was never answered either
            (b'{"id":16,"op":"slip","axis":"X","steps":1' + b"0" * 400 + b"}\n", 16, "steps"),
            (
                b'{"id":17,"op":"wait","until":"idle","timeout":-1' + b"0" * 400 + b"}\n",
                17,
                "timeout",
            ),
            # JSON's true is no number: it drove input 1 and closed X's positive limit
            (b'{"id":11,"op":"input","bit":true,"high":false}\n', 11, "bit"),
            (
                b'{"id":12,"op":"limit","axis":"X","direction":true,"active":true}\n',
                12,
                "direction",
            ),
            # nor is it a wait's timeout, nor is a string: they waited 1 s and 0.01 s
            (b'{"id":13,"op":"wait","until":"done","axis":"X","timeout":true}\n', 13, "timeout"),
            (b'{"id":14,"op":"wait","until":"done","axis":"X","timeout":"0.01"}\n', 14, "timeout"),
        ]:
            reply = raw_request(s, reader, line)
            assert reply["id"] == ident and reply["ok"] is False, reply
            assert word in reply["error"] and "\n" not in reply["error"], reply
        # blank lines are ignored; the connection still works
        ok = raw_request(s, reader, b'\n{"id":9,"op":"boards"}\n')
        assert ok["id"] == 9 and ok["ok"] is True and ok["result"][0]["name"] == "board1"
    # the board itself was not touched by any of it
    axis = b.axis()
    assert (axis["position"], axis["encoder"], axis["limit_positive"]) == (0, 0, False)
    assert b.ctl.state()["world"] == {"limits": {}, "home": {}, "stalled": [], "inputs": {}}


def test_an_overlong_line_is_refused_and_the_connection_closed(
    bench: Callable[..., Bench],
) -> None:
    b = bench()
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(TIMEOUT)
        s.connect(str(b.socket))
        reader = s.makefile("rb")
        s.sendall(b'{"id":1,"op":"state","pad":"' + b"x" * (MAX_LINE + 10) + b'"}\n')
        reply = json.loads(reader.readline())
        assert reply == {"id": None, "ok": False, "error": "line too long"}
        assert reader.readline() == b""  # closed
    with control(b.socket) as again:  # others are not affected
        assert again.state()["board"] == "board1"


# -- the socket -----------------------------------------------------------------------------------


def test_the_socket_is_owner_only_and_removed_at_stop(omsd: Omsd, tmp_path: Path) -> None:
    path = tmp_path / "private" / "deeper" / "c.sock"
    daemon = omsd("--tcp", "127.0.0.1:0", "--control", str(path))
    control(path).close()
    assert stat.S_ISSOCK(os.stat(path).st_mode)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o600
    assert stat.S_IMODE(os.stat(path.parent).st_mode) == 0o700  # a directory it made
    assert daemon.stop() == 0
    assert not os.path.lexists(path)


def test_a_second_daemon_on_the_same_socket_fails_with_one_line(omsd: Omsd, tmp_path: Path) -> None:
    path = tmp_path / "c.sock"
    omsd("--tcp", "127.0.0.1:0", "--control", str(path))
    with control(path) as ctl:
        second = run_omsd("--tcp", "127.0.0.1:0", "--control", str(path), "--view", "off")
        assert second.returncode == 2
        assert second.stderr == f"omsd: control socket {path} is in use by another process\n"
        # the first daemon keeps its socket
        assert ctl.state()["board"] == "board1"
    with control(path) as ctl:
        assert ctl.boards()[0]["name"] == "board1"


def test_a_stale_socket_file_is_replaced(omsd: Omsd, tmp_path: Path) -> None:
    """A daemon that was killed leaves its socket file; nobody listens there any more."""
    path = tmp_path / "c.sock"
    stale = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    stale.bind(str(path))
    stale.close()
    assert path.exists()
    omsd("--tcp", "127.0.0.1:0", "--control", str(path))
    with control(path) as ctl:
        assert ctl.state()["board"] == "board1"
