"""The pacer (omsd.pacing) on a manual clock: each character is handed on when the line has
carried it, one character time after the one before, never sooner; the line's settings give the
character time."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest

from omsd.pacing import Line, Pacer


class Handle:
    def __init__(self, clock: ManualClock, when: float, callback: Callable[[], None]) -> None:
        self.clock = clock
        self.when = when
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class ManualClock:
    """What a pacer asks of the event loop, with time moved by hand."""

    def __init__(self) -> None:
        self.now = 100.0
        self.timers: list[Handle] = []

    def time(self) -> float:
        return self.now

    def call_at(self, when: float, callback: Callable[..., Any], *args: Any) -> Handle:
        handle = Handle(self, when, lambda: callback(*args))
        self.timers.append(handle)
        return handle

    def scheduled(self) -> list[float]:
        return sorted(h.when for h in self.timers if not h.cancelled)

    def run_until(self, until: float) -> None:
        """Fire every timer due by ``until``, in time order, the clock at each one's time."""
        while True:
            due = [h for h in self.timers if not h.cancelled and h.when <= until]
            if not due:
                break
            handle = min(due, key=lambda h: h.when)
            self.timers.remove(handle)
            self.now = max(self.now, handle.when)
            handle.callback()
        self.now = until


def test_a_line_s_character_time() -> None:
    assert Line().bits == 10 and Line().chars_per_second == 960.0
    assert Line(19200, 7, "E", 2).bits == 11
    assert Line(9600, 8, "N", 1.5).frame == "8N1.5"
    assert str(Line(19200, 7, "E", 2)) == "19200 7E2"


def test_each_character_goes_one_character_time_after_the_one_before() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, Line(9600).chars_per_second)  # 960 characters a second
    got: list[tuple[float, bytes]] = []
    pacer.send(lambda data: got.append((clock.now, data)), b"PC48\n")
    assert got == []  # not even the first: it is through when its stop bit is
    assert clock.scheduled() == [pytest.approx(100.0 + 1 / 960)]
    clock.run_until(101.0)
    assert b"".join(d for _, d in got) == b"PC48\n"
    times = [t for t, _ in got]
    assert times == [pytest.approx(100.0 + k / 960) for k in range(1, 6)]
    assert pacer.waiting == 0


def test_a_late_wake_up_hands_on_what_the_line_carried_meanwhile_at_once() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, 100.0)
    got: list[bytes] = []
    pacer.send(got.append, b"0123456789")
    clock.timers.clear()  # the loop was busy: the first wake-up comes 45 ms late
    clock.now = 100.045
    pacer._due()
    assert got == [b"0123"]  # four characters are through by then, not five
    assert clock.scheduled() == [pytest.approx(100.05)]
    clock.run_until(100.2)
    assert b"".join(got) == b"0123456789"


def test_chunks_queue_behind_each_other_and_a_new_rate_applies_to_what_follows() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, 10.0)
    got: list[tuple[float, bytes]] = []
    pacer.send(lambda d: got.append((clock.now, d)), b"ab")
    pacer.chars_per_second = 100.0
    pacer.send(lambda d: got.append((clock.now, d)), b"cd")
    assert pacer.waiting == 4
    clock.run_until(200.0)
    assert [t for t, _ in got] == [
        pytest.approx(100.1),
        pytest.approx(100.2),
        pytest.approx(100.21),
        pytest.approx(100.22),
    ]


def test_an_idle_line_starts_when_given_a_busy_one_when_free() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, 10.0)
    got: list[float] = []
    pacer.send(lambda d: got.append(clock.now), b"a")
    clock.run_until(105.0)  # idle since 100.1
    pacer.send(lambda d: got.append(clock.now), b"b")
    clock.run_until(106.0)
    assert got == [pytest.approx(100.1), pytest.approx(105.1)]


def test_unpaced_with_a_time_to_wait_for() -> None:
    clock = ManualClock()
    pacer = Pacer(clock)
    got: list[tuple[float, bytes]] = []
    pacer.send(lambda d: got.append((clock.now, d)), b"now")
    assert got == [(100.0, b"now")]  # nothing to wait for: at once, no timer
    pacer.send(lambda d: got.append((clock.now, d)), b"late", at=100.25)
    pacer.send(lambda d: got.append((clock.now, d)), b"after")  # keeps its place behind
    clock.run_until(101.0)
    assert got[1:] == [(100.25, b"late"), (100.25, b"after")]


def test_clear_drops_what_waits() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, 10.0)
    got: list[bytes] = []
    pacer.send(got.append, b"abcdef")
    clock.run_until(100.25)
    assert got == [b"a", b"b"]
    assert pacer.clear() == 4
    clock.run_until(110.0)
    assert got == [b"a", b"b"]
    pacer.send(got.append, b"x")  # the line is free again
    clock.run_until(110.1)
    assert got[-1] == b"x"


def test_a_write_that_clears_the_pacer_stops_it() -> None:
    clock = ManualClock()
    pacer = Pacer(clock, 10.0)
    got: list[bytes] = []

    def write(data: bytes) -> None:
        got.append(data)
        pacer.clear()  # the client went while it was being written to

    pacer.send(write, b"abc")
    pacer.send(write, b"def")
    clock.run_until(101.0)
    assert got == [b"a"]
