"""Replies never cross connections (issue 13): a property over random command streams, random
disconnect points and both links.

Client A (session 1) writes a random command stream (the fuzzing host's command soup: every
command of the model, wait characters, comments, control characters) cut off at a random
point, in random bites at random moments, and goes (``Link.drop_input``, as the service does
when a client goes). Time passes: whatever A's commands still do (moves ending, limits,
done markers) happens, or only begins to. Then client B (session 2) asks ``WY`` three times
at once, with A's commands perhaps still running, and waits a minute; then it brings the board
to a known state (Control-D and the fuzzing host's recovery words) and asks ``WY`` three times.

What B is given (``LinkOutput.pieces`` of session 2, which the service sends to B's connection
only) must be its own: before its recovery, the answers to its WY and nothing but the echo of
its own characters and ``#`` for its own errors (A may have left echo on, or the board busy);
while it recovers, the same; then exactly the three answers to WY. Anything of A's (a
reply, a ``!``, ``@`` or ``$``) would show up there.

On a manual clock, through the links, so that hypothesis can try hundreds of streams; the
daemon's routing of those pieces to connections is tested end to end in
``tests/daemon/test_sessions.py``.
"""

from __future__ import annotations

import random
import re

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from omsd.board import Board
from omsd.link import DriverLink, RawLink
from omsd.link.base import LinkOutput
from omsd.models import get_model

from .fuzz import command_soup, recovery_words, who_are_you

A, B = 1, 2
KILL_PATIENCE = 30.0  # simulated seconds B waits for its Control-D to get in (as fuzz.py)
#: The most deadlines a host visits one by one. A board spinning in an endless loop (WH..WG with
#: nothing in it to wait for) has one every sample, 2,048 a second on the PCIx, and A's stream
#: may then go in a byte per half second for minutes: 640,000 visits in one example found
#: (a minute of the twin test in tests/board/test_fast_paths.py). Past this many, each wait goes
#: straight to its end, where the board lets what was due happen at its own times
#: (``Machine.advance``); only the link reads it in one piece rather than deadline by deadline.
VISITS = 20_000
MODELS = ["PC48-4E", "PC48-2", "VS4-040", "PC46-41", "PCIX-040", "PCIX-400"]


#: With echo on (EN, which A may have left on), a command error is also "an English readable
#: error message" naming the command (docs/decisions.md): ``<message>: <command>``.
MESSAGE = re.compile(rb"[A-Z][A-Za-z0-9 ]*: ([^\n\r]*)")


def heard_from_b(heard: bytes, sent: bytes) -> None:
    """What B was given is B's own: the echo of its characters, ``#`` for its errors and the
    messages naming its commands (with echo on), the framing; never anything of A's."""
    mine = set(sent) | {ord("#"), ord("\n"), ord("\r")}
    for found in MESSAGE.finditer(heard):
        assert set(found.group(1)) <= set(sent), f"B was told of {found.group(1)!r}: {heard!r}"
    rest = MESSAGE.sub(b"", heard)
    assert set(rest) <= mine, f"B was given {heard!r}"


class Host:
    """Both clients' view of one link on a manual clock."""

    def __init__(self, model: str, kind: str) -> None:
        self.model = get_model(model)
        self.board = Board(self.model, now=0.0)
        self.link: DriverLink | RawLink = (
            DriverLink(self.board) if kind == "driver" else RawLink(self.board)
        )
        self.t = 0.0
        self.visits = 0  # deadlines visited (VISITS)
        self.got: dict[int, bytearray] = {A: bytearray(), B: bytearray(), 0: bytearray()}

    def _take(self, out: LinkOutput) -> None:
        for session, data in out.pieces:
            self.got[session] += data
        assert b"".join(p[1] for p in out.pieces) == out.data

    def write(self, session: int, data: bytes, patience: float = 5.0) -> int:
        """Offer ``data``; wait (simulated) up to ``patience`` s for it to be taken."""
        taken = 0
        deadline = self.t + patience
        while taken < len(data):
            n = self.link.from_host(data[taken:], self.t, session)
            taken += n
            self._take(self.link.to_host(self.t))
            if taken == len(data) or (n == 0 and self.t >= deadline):
                break
            if n == 0:  # let the board take more
                self.run_until(min(deadline, self.t + 0.5))
        return taken

    def run_until(self, t: float) -> bool:
        """Let time pass to ``t``, visiting the board's deadlines (:data:`VISITS` of them in
        all, then straight to ``t``); True if anything was due."""
        due = False
        while True:
            d = self.link.next_deadline()
            if d is None or d > t:
                break
            due = True
            if self.visits >= VISITS:
                break
            self.visits += 1
            self.t = max(self.t, d)
            self._take(self.link.to_host(self.t))
        self.t = max(self.t, t)
        self._take(self.link.to_host(self.t))
        return due


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    model=st.sampled_from(MODELS),
    kind=st.sampled_from(["driver", "raw"]),
    seed=st.integers(0, 2**32 - 1),
    size=st.integers(1, 400),
    cut=st.floats(0.0, 1.0),
    bites=st.lists(st.integers(1, 64), min_size=1, max_size=20),
    gaps=st.lists(st.floats(0.0, 0.5), min_size=1, max_size=20),
    afterwards=st.floats(0.0, 5.0),
)
def test_replies_never_cross_sessions(
    model: str,
    kind: str,
    seed: int,
    size: int,
    cut: float,
    bites: list[int],
    gaps: list[float],
    afterwards: float,
) -> None:
    host = Host(model, kind)
    stream = command_soup(random.Random(seed), host.model, size)
    stream = stream[: int(len(stream) * cut)]
    # A writes in bites, with time passing between them, and goes at the cut
    pos = 0
    i = 0
    while pos < len(stream):
        bite = stream[pos : pos + bites[i % len(bites)]]
        pos += max(1, host.write(A, bite, patience=0.5))
        host.run_until(host.t + gaps[i % len(gaps)])
        i += 1
    host.link.drop_input(A)
    host.run_until(host.t + afterwards)
    assert host.got[B] == b"", "B has not written yet"

    # B asks at once, while what A started may still be running, then waits a minute: it may
    # find the board echoing or busy, but never hears anything of A's
    wy = b"WY;" if host.model.dialect == "pcix" else b"WY "
    host.write(B, b" " + wy * 3)
    host.run_until(host.t + 60.0)
    answer = who_are_you(host.model, kind)
    heard_from_b(bytes(host.got[B]).replace(answer, b""), b" " + wy)
    host.got[B].clear()

    # B recovers: Control-D (waiting for it to get in, or switching the card off and on, as the
    # fuzzing host does), then the recovery words
    got_in = host.write(B, b"\x04", patience=KILL_PATIENCE) == 1
    if got_in and host.link.held() is not None:  # in the driver's buffer, not in the board
        host.run_until(host.t + KILL_PATIENCE)
        got_in = host.link.held() is None
    if not got_in:  # "may clear this condition if the input character queue is not also filled"
        host.board.power_cycle(host.t)
        host.link.reset_input()
        assert host.write(B, b"\x04") == 1
    words = recovery_words(host.model)
    assert host.write(B, words, patience=KILL_PATIENCE) == len(words)
    host.run_until(host.t + 1.0)  # an RS of A's leaves the board initialising for 0.1 s
    heard_from_b(bytes(host.got[B]), b"\x04" + words)

    # with echo on (A may have left it on), "AX EF" was echoed: through the driver it is a
    # string, which the end character closes before the next one (docs/decisions.md, "Echo")
    ended = b"\n" if kind == "driver" and host.got[B].endswith(b"EF") else b""
    host.got[B].clear()
    assert host.write(B, wy * 3) == 3 * len(wy)
    host.run_until(host.t + 1.0)
    assert bytes(host.got[B]) == ended + answer * 3
