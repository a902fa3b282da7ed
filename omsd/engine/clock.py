"""The board's sample clock.

PC48 §1.2: the board calculates "the optimum velocity 2048 times each second"; §8.2: "The
highest priority process calculates the desired pulse frequency 2048 times each second".
Everything the board *does* (start a move, notice that a move has ended, see a switch close,
fire a WT timeout) therefore happens on a sample tick. Positions between ticks follow the
analytic profile, because the pulse train itself comes from a crystal oscillator.

The clock never reads real time: the board is told ``now`` by its caller and this object only
rounds times onto the sample grid that started when the board was powered up.
"""

from __future__ import annotations

import math

# Times closer than this to a tick count as being on it (float noise from t0 + k/rate).
_EPS = 1e-9


class SampleClock:
    """Quantizes times onto the grid ``origin + k / rate``."""

    __slots__ = ("origin", "period", "rate")

    def __init__(self, rate: int, origin: float) -> None:
        self.rate = rate
        self.origin = origin
        self.period = 1.0 / rate

    def index_at_or_after(self, t: float) -> int:
        return math.ceil((t - self.origin) * self.rate - _EPS)

    def index_at_or_before(self, t: float) -> int:
        return math.floor((t - self.origin) * self.rate + _EPS)

    def time_of(self, index: int) -> float:
        return self.origin + index / self.rate

    def at_or_after(self, t: float) -> float:
        """The first tick at or after ``t``: ``time_of(index_at_or_after(t))``, written out (it
        is asked for every event an axis has; the same arithmetic, the same bits)."""
        origin = self.origin
        return origin + math.ceil((t - origin) * self.rate - _EPS) / self.rate

    def after(self, t: float) -> float:
        """The first tick strictly after ``t``."""
        return self.time_of(self.index_at_or_before(t) + 1)

    def at_or_before(self, t: float) -> float:
        return self.time_of(self.index_at_or_before(t))
