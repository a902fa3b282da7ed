"""A board's clock on the event loop: real time by default; paused, stepped or scaled by the
control API.

The board engine takes time as an argument; the service asks :meth:`Timebase.now` for it. While
running, board time advances ``scale`` seconds per second of the loop's monotonic clock; paused,
it stands still and only :meth:`Timebase.step` moves it, exactly as a test's manual clock does.
:meth:`Timebase.to_loop` turns a board deadline into the loop time to wake up at (``None`` while
paused: nothing happens by itself).

A fresh timebase is the loop's clock itself (board time = loop time), so nothing changes for a
board nobody touches.
"""

from __future__ import annotations

from collections.abc import Callable

MIN_SCALE = 1e-3
MAX_SCALE = 1e3
MAX_TIME = 1e12
"""Board seconds a stepped clock may reach (31,700 years): the clock is a float, and from about
1e16 s on it has no room left for the sample grid (a move reported done without moving)."""


class Timebase:
    def __init__(self, source: Callable[[], float]) -> None:
        self.source = source
        self._real = source()
        self._board = self._real
        self.scale = 1.0
        self.paused = False

    def now(self) -> float:
        if self.paused:
            return self._board
        return self._board + (self.source() - self._real) * self.scale

    def _rebase(self) -> None:
        self._board = self.now()
        self._real = self.source()

    def pause(self) -> None:
        self._rebase()
        self.paused = True

    def resume(self) -> None:
        self._rebase()
        self.paused = False

    def set_scale(self, scale: float) -> None:
        """Board seconds per real second, from 0.001 to 1000."""
        if not MIN_SCALE <= scale <= MAX_SCALE:
            raise ValueError(f"time scale must be between {MIN_SCALE} and {MAX_SCALE}, not {scale}")
        self._rebase()
        self.scale = scale

    def step(self, seconds: float) -> None:
        """Move a paused clock ``seconds`` forward."""
        if not self.paused:
            raise ValueError("time must be paused to step it")
        if not seconds >= 0.0:
            raise ValueError(f"time steps forward: {seconds} s")
        if self._board + seconds > MAX_TIME:
            raise ValueError(
                f"a step of {seconds} s would pass the clock's limit, {MAX_TIME:g} s of board time"
            )
        self._board += seconds
        self._real = self.source()

    def to_loop(self, board_time: float) -> float | None:
        """The loop time at which board time reaches ``board_time``; None while paused."""
        if self.paused:
            return None
        return self._real + (board_time - self._board) / self.scale

    def describe(self) -> dict[str, float | bool]:
        return {"now": self.now(), "paused": self.paused, "scale": self.scale}
