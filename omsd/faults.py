"""Faults a test can put on a board's cable (control API ``fault``): what a real installation
does to a serial link now and then.

* ``latency``: every reply reaches the host this many seconds late (a slow terminal server).
* ``baud``: the link carries at most ``baud / 10`` characters a second each way (8N1 framing),
  as a serial line at that rate would; ``None`` is unpaced.
* ``drop`` / ``garble``: the probability that a character is lost / arrives with one bit
  flipped, on the way to the board and on the way back (seeded: a test sees the same damage
  every run).
* ``cable``: ``False`` cuts it: TCP clients are disconnected (they see EOF) and new connections
  are closed at once; on a pty nothing passes either way. The board keeps its state, and moves
  go on, as a card does when its cable is pulled.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field


@dataclass(eq=False)  # state, compared by identity (omsd.engine.states)
class Faults:
    """The faults on one board's cable (see the module's text)."""

    latency: float = 0.0
    baud: int | None = None
    drop: float = 0.0
    garble: float = 0.0
    cable: bool = True
    seed: int = 0
    _random: random.Random = field(default_factory=random.Random, repr=False)

    def __post_init__(self) -> None:
        self.check()
        self._random.seed(self.seed)

    def check(self) -> None:
        if not 0.0 <= self.latency <= 60.0:
            raise ValueError(f"latency must be 0 to 60 s, not {self.latency}")
        if self.baud is not None and not 50 <= self.baud <= 10_000_000:
            raise ValueError(f"baud must be 50 to 10000000, not {self.baud}")
        for name in ("drop", "garble"):
            p = getattr(self, name)
            if not 0.0 <= p <= 1.0:
                raise ValueError(f"{name} must be a probability 0 to 1, not {p}")

    @property
    def chars_per_second(self) -> float | None:
        return None if self.baud is None else self.baud / 10.0

    @property
    def damaging(self) -> bool:
        return self.drop > 0.0 or self.garble > 0.0

    def damage(self, data: bytes) -> bytes:
        """``data`` as it comes out of the far end of a noisy cable."""
        if not self.damaging:
            return data
        out = bytearray()
        rnd = self._random
        for b in data:
            if rnd.random() < self.drop:
                continue
            if rnd.random() < self.garble:
                b ^= 1 << rnd.randrange(8)
            out.append(b)
        return bytes(out)

    def as_dict(self) -> dict[str, object]:
        return {
            "latency": self.latency,
            "baud": self.baud,
            "drop": self.drop,
            "garble": self.garble,
            "cable": self.cable,
            "seed": self.seed,
        }
