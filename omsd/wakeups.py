"""Waking a board at its deadline on time: a timerfd instead of asyncio's millisecond timer.

A board's deadline (a move's end, a ``WT`` running out) is exact on its clock; the service wakes
up then and lets the board run to the time it reads, so what the board says never comes early.
How late it comes is the wake-up's doing. ``loop.call_at`` wakes late: asyncio's loop waits in
``epoll_wait``, whose timeout is whole milliseconds (``selectors`` rounds it up), and the kernel
lets a sleeping process oversleep by its timer slack (0.1 % of the wait, at least 50 µs), so a
done marker went out 1 to 2 ms after the end of the move's profile (issue 16; uvloop's timers
are milliseconds too).

On Linux a timerfd armed at the absolute time on ``CLOCK_MONOTONIC`` (the clock of
``time.monotonic``, which the services run on) becomes readable when that time has come: an
hrtimer, with no rounding and no slack, and never before the deadline. One timerfd serves every
board of a loop (:func:`wakeups_for`): the deadlines wait in a heap and the timerfd is armed for
the first of them.

A processor that has been idle long wakes slowly (on the machine of the README's benchmarks
about 130 µs after a timer of a few hundred milliseconds, against 40 µs after one of a
millisecond: the idle state it chose was deeper). So a deadline more than :data:`LEAD` away is
approached in two steps: the timerfd is armed :data:`LEAD` before it, and when that comes,
armed again at the deadline itself, a short wait from which the processor wakes fast. That is
one more wake-up per deadline, and no spinning: nothing runs between the two, and nothing is
armed while no board has a deadline, so an idle daemon stays asleep.

``os.timerfd_create`` is Python 3.13's; before, the two calls are made through ``ctypes``. Where
there is no timerfd (not Linux) :class:`LoopTimers` uses ``loop.call_later`` as before.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import heapq
import itertools
import math
import os
import time
import weakref
from collections.abc import Callable
from typing import Protocol

CLOCK_MONOTONIC = 1
TFD_TIMER_ABSTIME = 1
#: How long before a far deadline the timerfd first wakes the loop (see the module text).
LEAD = 0.001


class Handle(Protocol):
    def cancel(self) -> None: ...


class Timers(Protocol):
    """Calls at ``time.monotonic()`` times, as ``loop.call_at`` does at ``loop.time()``."""

    def call_at(self, when: float, callback: Callable[[], None]) -> Handle: ...


class LoopTimers:
    """The event loop's own timers (no timerfd here): late by up to a few milliseconds."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = weakref.ref(loop)  # (weak: see wakeups_for)

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        return _alive(self._loop)

    def call_at(self, when: float, callback: Callable[[], None]) -> Handle:
        return self.loop.call_later(max(0.0, when - time.monotonic()), callback)


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


class _Itimerspec(ctypes.Structure):
    _fields_ = [("it_interval", _Timespec), ("it_value", _Timespec)]


def _alive(ref: weakref.ref[asyncio.AbstractEventLoop]) -> asyncio.AbstractEventLoop:
    loop = ref()
    if loop is None:
        raise RuntimeError("the event loop of these timers is gone")
    return loop


class _TimerFd:
    """A non-blocking ``CLOCK_MONOTONIC`` timerfd, armed at absolute times in nanoseconds."""

    def __init__(self) -> None:
        flags = os.O_NONBLOCK | os.O_CLOEXEC
        self._libc: ctypes.CDLL | None = None
        # Python 3.13's own calls (looked up by name: the type checker reads 3.11's os)
        create = getattr(os, "timerfd_create", None)
        self._settime_ns = getattr(os, "timerfd_settime_ns", None)
        if create is not None and self._settime_ns is not None:
            self.fd: int = create(CLOCK_MONOTONIC, flags=flags)
            return
        libc = ctypes.CDLL(None, use_errno=True)
        fd = int(libc.timerfd_create(CLOCK_MONOTONIC, flags))
        if fd < 0:
            raise OSError(ctypes.get_errno(), "timerfd_create")
        self._libc = libc
        self._spec = _Itimerspec()
        self.fd = fd

    def arm(self, ns: int) -> None:
        """Readable from ``CLOCK_MONOTONIC`` time ``ns`` on (at once if it has passed); 0
        disarms."""
        if self._libc is None:
            assert self._settime_ns is not None
            self._settime_ns(self.fd, flags=TFD_TIMER_ABSTIME, initial=ns)
            return
        value = self._spec.it_value
        value.tv_sec, value.tv_nsec = divmod(ns, 1_000_000_000)
        if self._libc.timerfd_settime(self.fd, TFD_TIMER_ABSTIME, ctypes.byref(self._spec), None):
            raise OSError(ctypes.get_errno(), "timerfd_settime")

    def take(self) -> None:
        """Read the expiry count (so the descriptor is no longer readable)."""
        with contextlib.suppress(BlockingIOError):
            os.read(self.fd, 8)

    def close(self) -> None:
        with contextlib.suppress(OSError):
            os.close(self.fd)


class Wakeup:
    """One call waiting in :class:`TimerFdTimers`."""

    __slots__ = ("callback", "cancelled", "when")

    def __init__(self, when: float, callback: Callable[[], None]) -> None:
        self.when = when
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class TimerFdTimers:
    """The deadlines of every board on one loop, waiting on one timerfd."""

    def __init__(self, loop: asyncio.AbstractEventLoop, timer: _TimerFd) -> None:
        self._loop = weakref.ref(loop)  # (weak: see wakeups_for)
        self._timer = timer
        self._heap: list[tuple[float, int, Wakeup]] = []
        self._order = itertools.count()
        self._armed: float | None = None  # the time the timerfd is armed for
        self._reading = False
        self._cancelled = 0  # cancelled calls still in the heap
        weakref.finalize(self, timer.close)

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        return _alive(self._loop)

    def call_at(self, when: float, callback: Callable[[], None]) -> Handle:
        wakeup = Wakeup(when, callback)
        heapq.heappush(self._heap, (when, next(self._order), wakeup))
        if self._armed is None or when < self._armed:
            self._arm(when)
        return _Cancel(self, wakeup)

    def _cancelled_one(self) -> None:
        self._cancelled += 1
        if self._cancelled > 64 and self._cancelled * 2 > len(self._heap):
            self._heap = [entry for entry in self._heap if not entry[2].cancelled]
            heapq.heapify(self._heap)
            self._cancelled = 0

    def _arm(self, when: float) -> None:
        """Wake for the call at ``when``: :data:`LEAD` before it if it is further away than
        that, else at ``when`` (rounded up to the nanosecond: never before it)."""
        if when - time.monotonic() > LEAD:
            when -= LEAD
        self._timer.arm(max(1, math.ceil(when * 1e9)))
        self._armed = when
        if not self._reading:
            self.loop.add_reader(self._timer.fd, self._fire)
            self._reading = True

    def _fire(self) -> None:
        self._timer.take()
        self._armed = None
        heap = self._heap
        now = time.monotonic()
        due: list[Wakeup] = []
        while heap and (heap[0][2].cancelled or heap[0][0] <= now):
            wakeup = heapq.heappop(heap)[2]
            if wakeup.cancelled:
                self._cancelled -= 1
            else:
                due.append(wakeup)
        try:
            for wakeup in due:
                if wakeup.cancelled:  # cancelled by a call before it: out of the heap already
                    self._cancelled -= 1
                    continue
                wakeup.cancelled = True  # done: a late cancel() changes nothing
                try:
                    wakeup.callback()
                except Exception as exc:  # as the loop does for a failing callback
                    self.loop.call_exception_handler(
                        {"message": "exception in a wake-up callback", "exception": exc}
                    )
        finally:
            self._rearm()

    def _rearm(self) -> None:
        heap = self._heap
        while heap and heap[0][2].cancelled:
            heapq.heappop(heap)
            self._cancelled -= 1
        if heap:
            if self._armed is None or heap[0][0] < self._armed:
                self._arm(heap[0][0])
        elif self._armed is None and self._reading:
            self._timer.arm(0)
            self.loop.remove_reader(self._timer.fd)
            self._reading = False


class _Cancel:
    """What :meth:`TimerFdTimers.call_at` returns: ``cancel()`` takes the call back."""

    __slots__ = ("_timers", "_wakeup")

    def __init__(self, timers: TimerFdTimers, wakeup: Wakeup) -> None:
        self._timers = timers
        self._wakeup = wakeup

    def cancel(self) -> None:
        wakeup = self._wakeup
        if not wakeup.cancelled:
            wakeup.cancelled = True
            self._timers._cancelled_one()


_BY_LOOP: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, Timers] = weakref.WeakKeyDictionary()


def wakeups_for(loop: asyncio.AbstractEventLoop) -> Timers:
    """The timers of ``loop``'s boards: one timerfd for all of them where there is one.

    The timers hold their loop by a weak reference, so that a loop that is closed and dropped
    (one per test, one per ``asyncio.run``) takes its timers and their timerfd with it."""
    timers = _BY_LOOP.get(loop)
    if timers is None:
        try:
            timers = TimerFdTimers(loop, _TimerFd())
        except (OSError, AttributeError):  # not Linux: no timerfd
            timers = LoopTimers(loop)
        _BY_LOOP[loop] = timers
    return timers
