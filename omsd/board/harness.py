"""A board on a manual clock, for tests and experiments.

::

    h = Harness("PC48-4")
    h.send("VL400000 AC500000 MR1000000 GO")
    h.run()                # until nothing is left to happen
    h.query("RP")          # b'\\n\\r1000000\\n\\r'
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from omsd.board.board import Board
from omsd.engine.axis import Axis
from omsd.engine.events import CommandErrorEvent, Event, Output, Reply
from omsd.engine.world import AxisWorld
from omsd.models import get_model


class Harness:
    def __init__(
        self,
        model: str = "PC48-4",
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None = None,
        t: float = 0.0,
    ) -> None:
        self.board = Board(get_model(model), now=t, world=world)
        self.t = t
        self.log: list[Output] = []

    # -- talking ------------------------------------------------------------------------------

    def send(self, data: str | bytes) -> bytes:
        """Send at the current time; return the reply bytes produced right away."""
        raw = data.encode("latin-1") if isinstance(data, str) else data
        taken = self.board.receive(raw, self.t)
        if taken != len(raw):
            raise BufferError(f"board took {taken} of {len(raw)} bytes (input buffer full)")
        return self._collect()

    def query(self, data: str | bytes) -> bytes:
        return self.send(data)

    def _collect(self) -> bytes:
        out = self.board.take_output()
        self.log.extend(out)
        return b"".join(o.data for o in out if isinstance(o, Reply))

    def events(self) -> list[Event]:
        """Events seen so far (and forget them)."""
        self._collect()
        events = [o for o in self.log if not isinstance(o, Reply)]
        self.log = []
        return events

    def errors(self) -> list[CommandErrorEvent]:
        return [e for e in self.events() if isinstance(e, CommandErrorEvent)]

    # -- time ---------------------------------------------------------------------------------

    def advance(self, seconds: float) -> bytes:
        return self.until(self.t + seconds)

    def until(self, t: float) -> bytes:
        """Let time pass to ``t``, visiting every deadline on the way."""
        if t < self.t:
            raise ValueError(f"time runs forward: {t} is before {self.t}")
        board = self.board
        while True:
            d = board.next_deadline()
            if d is None or d > t:
                break
            board.advance(d)
        board.advance(t)
        self.t = t
        return self._collect()

    def run(self, limit: float = 3600.0) -> bytes:
        """Let time pass until the board has nothing left to do by itself (or ``limit`` s)."""
        board = self.board
        end = self.t + limit
        while True:
            d = board.next_deadline()
            if d is None or d > end:
                break
            board.advance(d)
            self.t = max(self.t, d)
        return self._collect()

    # -- looking ------------------------------------------------------------------------------

    def position(self, axis: str = "X") -> int:
        a = self.board.axis_by_letter(axis)
        assert a is not None
        return a.counter(self.t)

    def axis(self, letter: str = "X") -> Axis:
        a = self.board.axis_by_letter(letter)
        assert a is not None
        return a
