"""The boards' wake-ups (``omsd.wakeups``): one timerfd per loop and a heap of deadlines
(:class:`TimerFdTimers`), against the loop's own timers where there is no timerfd
(:class:`LoopTimers`). Each behaviour is tested on both: a call never comes before its time
(``time.monotonic``), calls come in the order of their times, a cancelled call never comes
(also one cancelled by a call before it in the same wake-up, and many cancelled: the heap is
swept), a call that raises goes to the loop's exception handler and the others still come. The
timerfd's own: a far deadline approached in two steps (:data:`LEAD`), and nothing armed and
nothing watched once nothing waits (an idle daemon sleeps).

Timings are not asserted (the machine decides them): only order and never-early.
"""

from __future__ import annotations

import asyncio
import gc
import math
import os
import random
import time
import weakref
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest

from omsd import wakeups
from omsd.wakeups import LEAD, LoopTimers, TimerFdTimers, Timers, wakeups_for

KINDS = ["timerfd", "loop"]


def has_timerfd() -> bool:
    try:
        wakeups._TimerFd().close()
    except (OSError, AttributeError):
        return False
    return True


@pytest.fixture(params=KINDS)
async def timers(request: pytest.FixtureRequest) -> AsyncIterator[Timers]:
    """A timers object of each kind on the test's loop; the timerfd closed at the end."""
    loop = asyncio.get_running_loop()
    if request.param == "loop":
        yield LoopTimers(loop)
        return
    if not has_timerfd():
        pytest.skip("no timerfd here")
    made = TimerFdTimers(loop, wakeups._TimerFd())
    try:
        yield made
    finally:
        let_go(loop, made)


def let_go(loop: asyncio.AbstractEventLoop, timers: TimerFdTimers) -> None:
    """No longer watched, and the timerfd closed (and forgotten: the timers' finalizer closes
    it again, which must not close another file that got its number)."""
    if timers._reading:
        loop.remove_reader(timers._timer.fd)
        timers._reading = False
    timers._timer.close()
    timers._timer.fd = -1


def slack(timers: Timers) -> float:
    """How early a call may come: never, on the timerfd; the loop's own timers run what is due
    within the clock's resolution (asyncio's ``_run_once``)."""
    if isinstance(timers, TimerFdTimers):
        return 0.0
    return time.get_clock_info("monotonic").resolution + 1e-9


class Calls:
    """Calls made at given times, and when each came."""

    def __init__(self, timers: Timers) -> None:
        self.timers = timers
        self.came: list[tuple[Any, float, float]] = []  # (name, when, came at)
        self.expected = 0
        self.done = asyncio.Event()

    def at(self, when: float, name: Any, then: Callable[[], None] | None = None) -> Any:
        self.expected += 1

        def call() -> None:
            self.came.append((name, when, time.monotonic()))
            if then is not None:
                then()
            if len(self.came) >= self.expected:
                self.done.set()

        return self.timers.call_at(when, call)

    async def wait(self, timeout: float = 5.0) -> None:
        await asyncio.wait_for(self.done.wait(), timeout)

    def names(self) -> list[Any]:
        return [name for name, _, _ in self.came]

    def never_early(self) -> None:
        margin = slack(self.timers)
        early = [(n, when - at) for n, when, at in self.came if at < when - margin]
        assert not early, f"early by {early}"


# -- every kind -----------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
async def test_calls_come_in_order_and_never_early(timers: Timers, seed: int) -> None:
    rnd = random.Random(seed)
    now = time.monotonic()
    offsets = rnd.sample(range(1, 40), 12)  # milliseconds, all different
    calls = Calls(timers)
    for i, ms in enumerate(offsets):
        calls.at(now + ms / 1000 + rnd.choice([0.0, 1e-7, 3e-4]), i)
    await calls.wait()
    calls.never_early()
    assert calls.names() == sorted(range(len(offsets)), key=lambda i: offsets[i])


@pytest.mark.parametrize("seed", range(3))
async def test_calls_close_together_never_come_early(timers: Timers, seed: int) -> None:
    """Calls tens of microseconds apart: one wake-up may be late for the next, never early.
    (In order, on the timerfd; the loop's timers work each call's time out from two clocks
    read a moment apart, which a busy machine may stretch beyond the gap.)"""
    rnd = random.Random(seed)
    at = time.monotonic() + 0.002
    calls = Calls(timers)
    for i in range(40):
        at += rnd.choice([50e-6, 80e-6, 150e-6, 400e-6])
        calls.at(at, i)
    await calls.wait()
    calls.never_early()
    if isinstance(timers, TimerFdTimers):
        assert calls.names() == list(range(40))
    else:
        assert sorted(calls.names()) == list(range(40))


async def test_calls_already_due_all_come_and_a_later_one_after_them(timers: Timers) -> None:
    now = time.monotonic()
    calls = Calls(timers)
    for i, offset in enumerate([-1.0, -0.001, 0.0, -1e-9]):
        calls.at(now + offset, i)
    calls.at(now + 0.005, "later")
    await calls.wait()
    calls.never_early()
    assert sorted(calls.names()[:4]) == [0, 1, 2, 3] and calls.names()[4] == "later"


async def test_calls_due_at_once_come_in_the_order_they_were_made(
    timerfd: TimerFdTimers,
) -> None:
    """(The loop's timers keep no such order: each call's time on the loop's clock is worked
    out from ``time.monotonic`` read a moment apart.)"""
    when = time.monotonic() + 0.003
    calls = Calls(timerfd)
    for i in range(20):
        calls.at(when, i)
    await calls.wait()
    assert calls.names() == list(range(20))
    calls.never_early()


async def test_a_cancelled_call_never_comes_and_a_late_cancel_is_harmless(timers: Timers) -> None:
    now = time.monotonic()
    calls = Calls(timers)
    gone = calls.at(now + 0.002, "cancelled")
    calls.at(now + 0.004, "kept")
    gone.cancel()
    gone.cancel()
    calls.expected -= 1
    await calls.wait()
    await asyncio.sleep(0.01)
    assert calls.names() == ["kept"]


async def test_a_call_cancelled_by_one_before_it_at_the_same_wakeup_never_comes(
    timers: Timers,
) -> None:
    """Two calls due together (both already due: one wake-up runs both, on either kind): the
    first cancels the second (a board's service that takes a wake-up back while another runs):
    the second must not run, as with the loop's timers."""
    now = time.monotonic()
    came: list[str] = []
    handles: dict[str, Any] = {}

    def first() -> None:
        came.append("first")
        handles["second"].cancel()

    handles["first"] = timers.call_at(now - 0.002, first)
    handles["second"] = timers.call_at(now - 0.001, lambda: came.append("second"))
    timers.call_at(now + 0.004, lambda: came.append("third"))
    await asyncio.sleep(0.03)
    assert came == ["first", "third"]
    if isinstance(timers, TimerFdTimers):
        assert timers._cancelled == 0 and not timers._heap  # the count is right again


async def test_a_call_may_make_and_cancel_calls(timers: Timers) -> None:
    now = time.monotonic()
    calls = Calls(timers)
    later: list[Any] = []

    def first() -> None:
        calls.at(time.monotonic() - 1.0, "due at once")  # already due
        calls.at(now + 0.006, "made")
        later[0].cancel()
        calls.expected -= 1

    calls.at(now + 0.002, "first", first)
    later.append(calls.at(now + 0.004, "cancelled by first"))
    await calls.wait()
    await asyncio.sleep(0.01)
    assert calls.names() == ["first", "due at once", "made"]
    calls.never_early()


async def test_an_earlier_call_comes_first(timers: Timers) -> None:
    now = time.monotonic()
    calls = Calls(timers)
    calls.at(now + 0.02, "late")
    calls.at(now + 0.002, "early")
    await calls.wait()
    assert calls.names() == ["early", "late"]
    calls.never_early()


async def test_many_cancelled_calls_are_swept_and_the_rest_still_come(timers: Timers) -> None:
    now = time.monotonic()
    calls = Calls(timers)
    rnd = random.Random(3)
    handles = []
    for i in range(300):
        handles.append((i, calls.at(now + 60 + rnd.random(), ("far", i))))
    kept = [calls.at(now + (1 + i) / 1000, ("near", i)) for i in range(5)]
    for _, handle in handles:
        handle.cancel()
    calls.expected -= len(handles)
    if isinstance(timers, TimerFdTimers):
        assert len(timers._heap) < 100  # swept: not 305 entries
        assert timers._cancelled == sum(1 for _, _, w in timers._heap if w.cancelled)
    await calls.wait()
    assert calls.names() == [("near", i) for i in range(5)] and len(kept) == 5
    calls.never_early()
    if isinstance(timers, TimerFdTimers):
        assert timers._cancelled == sum(1 for _, _, w in timers._heap if w.cancelled)


async def test_a_failing_call_goes_to_the_exception_handler_and_the_others_come(
    timers: Timers,
) -> None:
    loop = asyncio.get_running_loop()
    errors: list[BaseException] = []
    loop.set_exception_handler(lambda _loop, context: errors.append(context["exception"]))
    try:
        now = time.monotonic()
        calls = Calls(timers)

        def fail() -> None:
            raise RuntimeError("boom")

        calls.at(now + 0.001, "failing", fail)
        calls.at(now + 0.001 + 1e-5, "after")
        calls.at(now + 0.01, "later")
        await calls.wait()
        assert calls.names() == ["failing", "after", "later"]
        assert [str(e) for e in errors] == ["boom"]
    finally:
        loop.set_exception_handler(None)


# -- the timerfd's own ----------------------------------------------------------------------------


@pytest.fixture
async def timerfd() -> AsyncIterator[TimerFdTimers]:
    if not has_timerfd():
        pytest.skip("no timerfd here")
    loop = asyncio.get_running_loop()
    made = TimerFdTimers(loop, wakeups._TimerFd())
    try:
        yield made
    finally:
        let_go(loop, made)


def watched(fd: int) -> bool:
    """The loop watches ``fd`` (a reader is registered)."""
    loop = asyncio.get_running_loop()
    selector = getattr(loop, "_selector", None)
    if selector is None:
        pytest.skip("not a selector loop")
    try:
        selector.get_key(fd)
    except KeyError:
        return False
    return True


def counting_fires(timers: TimerFdTimers, monkeypatch: pytest.MonkeyPatch) -> list[float]:
    """When the timerfd woke the loop (each ``_fire``)."""
    fires: list[float] = []
    fire = timers._fire

    def counted() -> None:
        fires.append(time.monotonic())
        fire()

    monkeypatch.setattr(timers, "_fire", counted)
    return fires


async def test_nothing_is_armed_or_watched_until_a_call_waits(timerfd: TimerFdTimers) -> None:
    assert not timerfd._reading and not watched(timerfd._timer.fd)
    await asyncio.sleep(0.005)
    assert not timerfd._reading


async def test_once_nothing_waits_the_timerfd_is_no_longer_watched(
    timerfd: TimerFdTimers,
) -> None:
    calls = Calls(timerfd)
    now = time.monotonic()
    for i in range(3):
        calls.at(now + i / 1000, i)
    assert watched(timerfd._timer.fd)
    await calls.wait()
    await asyncio.sleep(0)
    assert not timerfd._reading and not watched(timerfd._timer.fd)
    assert timerfd._armed is None and not timerfd._heap


async def test_after_every_call_is_cancelled_the_timerfd_is_let_go(
    timerfd: TimerFdTimers, monkeypatch: pytest.MonkeyPatch
) -> None:
    fires = counting_fires(timerfd, monkeypatch)
    now = time.monotonic()
    handles = [timerfd.call_at(now + 0.003 + i / 1000, lambda: None) for i in range(5)]
    for handle in handles:
        handle.cancel()
    await asyncio.sleep(0.03)
    assert len(fires) == 1  # the wake-up it was armed for, finding nothing: no more
    assert not timerfd._reading and not watched(timerfd._timer.fd)
    assert not timerfd._heap and timerfd._cancelled == 0


def counting_arms(timers: TimerFdTimers, monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """The times (ns) the timerfd was armed for (0: disarmed)."""
    arms: list[int] = []
    arm = timers._timer.arm

    def counted(ns: int) -> None:
        arms.append(ns)
        arm(ns)

    monkeypatch.setattr(timers._timer, "arm", counted)
    return arms


async def test_a_far_deadline_is_approached_in_two_steps(
    timerfd: TimerFdTimers, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Armed LEAD before the deadline, then at it: the first wake-up calls nothing (unless it
    came late, at the deadline or after: then it makes the call, and there is no second)."""
    fires = counting_fires(timerfd, monkeypatch)
    arms = counting_arms(timerfd, monkeypatch)
    calls = Calls(timerfd)
    when = time.monotonic() + 0.05
    calls.at(when, "far")
    await calls.wait()
    await asyncio.sleep(0)
    calls.never_early()
    assert arms[0] == math.ceil((when - LEAD) * 1e9) < math.ceil(when * 1e9)
    assert fires[0] >= when - LEAD
    if fires[0] < when:
        assert arms[1:] == [math.ceil(when * 1e9), 0] and len(fires) == 2
        assert fires[0] < calls.came[0][2]  # the call came at the second
    else:
        assert arms[1:] == [0] and len(fires) == 1


async def test_a_near_deadline_is_armed_once(
    timerfd: TimerFdTimers, monkeypatch: pytest.MonkeyPatch
) -> None:
    fires = counting_fires(timerfd, monkeypatch)
    arms = counting_arms(timerfd, monkeypatch)
    calls = Calls(timerfd)
    when = time.monotonic() + LEAD / 4
    calls.at(when, "near")
    await calls.wait()
    await asyncio.sleep(0)
    calls.never_early()
    assert arms == [math.ceil(when * 1e9), 0] and len(fires) == 1


# -- one per loop, and without a timerfd ----------------------------------------------------------


async def test_one_timers_object_per_loop() -> None:
    loop = asyncio.get_running_loop()
    try:
        assert wakeups_for(loop) is wakeups_for(loop)
    finally:
        release(loop)


def release(loop: asyncio.AbstractEventLoop) -> None:
    timers = wakeups._BY_LOOP.pop(loop, None)
    if isinstance(timers, TimerFdTimers):
        let_go(loop, timers)


def test_without_a_timerfd_the_loops_timers_are_used(monkeypatch: pytest.MonkeyPatch) -> None:
    def no_timerfd() -> None:
        raise OSError("no timerfd here")

    monkeypatch.setattr(wakeups, "_TimerFd", no_timerfd)
    loop = asyncio.new_event_loop()
    try:
        timers = wakeups_for(loop)
        assert isinstance(timers, LoopTimers)

        async def wait() -> None:
            calls = Calls(timers)
            calls.at(time.monotonic() + 0.005, "x")
            await calls.wait()
            calls.never_early()

        loop.run_until_complete(wait())
    finally:
        wakeups._BY_LOOP.pop(loop, None)
        loop.close()


def test_a_dropped_loop_takes_its_timers_and_timerfd_with_it() -> None:
    if not has_timerfd():
        pytest.skip("no timerfd here")
    loop = asyncio.new_event_loop()
    timers = wakeups_for(loop)
    assert isinstance(timers, TimerFdTimers)
    fd = timers._timer.fd
    gone = weakref.ref(loop)
    loop.close()
    del loop, timers
    gc.collect()
    try:
        assert gone() is None
        with pytest.raises(OSError):
            os.fstat(fd)
    finally:
        kept = gone()
        if kept is not None:
            release(kept)
