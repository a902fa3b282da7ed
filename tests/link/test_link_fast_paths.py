"""The links' fast paths (issue 16) against their straightforward paths: differential tests.

* ``DriverLink.from_host``: bytes with nothing for the driver to do (nothing held, no comment
  open, no ``*``, ``!`` or ``@``) go to the board at once (``_straight_through``), against the
  driver's way by its buffer (``through_buffer``);
* ``DriverLink._collect``: nothing, or one framed reply, straight to the pieces, against
  ``collect_all``, item by item;
* ``RawLink.to_host``: nothing, or one reply, as it is, against ``RawLink.output``.

Two boards are given the same random steps, one through a link with its fast paths and one
through the same link with them off (``from_host`` calling ``through_buffer``, ``_collect``
calling ``collect_all``, ``to_host`` calling ``output``): the fuzzing host's command soup for
each model, the driver's comments, waits and Control-D, reports, moves, floods that fill the
driver's buffer and the board's, several sessions, time passing and deadlines visited, a session
going, the card switched off and on, the driver reloaded with another end character or buffer
size. After every step the two must have returned the same, said the same (pieces, by session,
and events), hold the same and be in the same state, the boards down to what each axis will do
next (``tests/board/twin.py``'s ``state``).

Below, the fast paths are shown to be taken where they are meant to be, so that a change that
quietly stopped taking them fails here.
"""

from __future__ import annotations

import importlib.util
import random
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from robustness.fuzz import ALL_MODELS, command_soup

from omsd.board import Board
from omsd.board.events import Output
from omsd.link import DriverLink, Link, LinkOutput, RawLink, make_link
from omsd.models import MODELS, get_model


def _load_twin() -> ModuleType:
    """``tests/board/twin.py`` (not a package here), for its ``state`` of a board."""
    path = Path(__file__).resolve().parents[1] / "board" / "twin.py"
    spec = importlib.util.spec_from_file_location("_link_twin", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


board_state = _load_twin().state


# -- the straightforward paths ------------------------------------------------------------------


class StraightDriver(DriverLink):
    """The driver link with its fast paths off: every byte by the buffer, every output item by
    item."""

    def from_host(self, data: bytes, now: float, session: int = 0) -> int:
        return self.through_buffer(data, now, session)

    def _collect(self, now: float) -> bool:
        out, sources = self.board.take_output_sourced()
        return self.collect_all(out, sources, now)

    def to_host(self, now: float) -> LinkOutput:
        self.board.advance(now)
        self._pass_on(now)
        pieces, self._pieces = self._pieces, []
        events, self._events = self._events, []
        return LinkOutput(pieces, events)


class StraightRaw(RawLink):
    """The raw link with its fast path off: every output item by item."""

    def to_host(self, now: float) -> LinkOutput:
        self.board.advance(now)
        out, sources = self.board.take_output_sourced()
        return self.output(out, sources)


def driver_state(link: Link) -> Any:
    if not isinstance(link, DriverLink):
        return None
    return (
        bytes(link._pending),
        [list(run) for run in link._runs],
        link._comment,
        link._waiting,
        link._wait_session,
        link._wait_since,
        sorted(link._echoing),
        sorted(link._unclaimed.items()),
        link._done_read_at,
        list(link._pieces),
        list(link._events),
        link.eos,
        link.buffer_size,
    )


class Trickle(Board):
    """A board that takes at most a few bytes at a time (as a slow serial line would hand them
    over): the driver offers the rest again at once, whichever path it took."""

    def receive(self, data: bytes, now: float, source: int = 0) -> int:
        return super().receive(data[:7], now, source)


class Pair:
    """Two boards and two links given the same steps; every answer compared."""

    def __init__(
        self,
        model: str,
        kind: str,
        eos: int = 0x0A,
        buffer_size: int = 256,
        board: type[Board] = Board,
    ) -> None:
        self.model = get_model(model)
        self.kind = kind
        self.fast_board = board(self.model, now=0.0)
        self.straight_board = board(self.model, now=0.0)
        self.now = 0.0
        self.steps: list[str] = []
        self.said = bytearray()
        self.unsent: dict[int, bytes] = {}  # what a session's host still has to write
        self.reload(eos, buffer_size)

    def reload(self, eos: int, buffer_size: int) -> None:
        """A new driver (another E:XX or B:XXXX; the raw link: a new link) on the same boards:
        what the old one held is gone, as when the DOS driver is loaded again."""
        self.fast: Link
        self.straight: Link
        if self.kind == "driver":
            self.fast = DriverLink(self.fast_board, eos=eos, buffer_size=buffer_size)
            self.straight = StraightDriver(self.straight_board, eos=eos, buffer_size=buffer_size)
        else:
            self.fast = RawLink(self.fast_board)
            self.straight = StraightRaw(self.straight_board)
        self.unsent.clear()

    def both(self, what: str, *args: Any) -> Any:
        self.steps.append(f"{what}{args!r}"[:200])
        a = getattr(self.fast, what)(*args)
        b = getattr(self.straight, what)(*args)
        if isinstance(a, LinkOutput):
            assert (a.pieces, a.events) == (b.pieces, b.events), self.steps[-30:]
            self.said += a.data
        else:
            assert a == b, (a, b, self.steps[-30:])
        self.agree()
        return a

    def agree(self) -> None:
        sessions = (0, 1, 2, 3)
        fast, straight = self.fast, self.straight
        assert fast.held() == straight.held(), self.steps[-30:]
        assert [fast.room(s) for s in sessions] == [straight.room(s) for s in sessions]
        assert [fast.busy(s) for s in sessions] == [straight.busy(s) for s in sessions]
        assert fast.next_deadline() == straight.next_deadline(), self.steps[-30:]
        assert driver_state(fast) == driver_state(straight), self.steps[-30:]
        assert board_state(self.fast_board) == board_state(self.straight_board), self.steps[-30:]

    def write(self, data: bytes, session: int) -> None:
        """A host writes ``data`` (after what it could not write before), and reads."""
        data = self.unsent.pop(session, b"") + data
        taken = self.both("from_host", data, self.now, session)
        if taken < len(data):
            self.unsent[session] = data[taken:][:4096]  # a host gives up beyond that
        self.both("take_notes")
        self.both("to_host", self.now)

    def run(self, seconds: float) -> None:
        """Time passes; the host reads at every deadline on the way, and what it has not
        written yet is offered again."""
        until = self.now + seconds
        for _ in range(300):
            deadline = self.fast.next_deadline()
            if deadline is None or deadline > until:
                break
            self.now = max(self.now, deadline)
            self.both("to_host", self.now)
            self.offer_again()
        self.now = until
        self.both("to_host", self.now)
        self.offer_again()
        held = self.fast.held()
        if held is not None and held.waiting and self.now - held.since > 0.5:
            # a wait that nothing releases (random input): the host gives up with a Control-D
            self.write(b"\x04", held.session)

    def offer_again(self) -> None:
        for session in sorted(self.unsent):
            if self.fast.room(session) > 0:
                self.write(b"", session)


#: Words of both languages: reports, moves (done interrupts), Control-D and Control-Y, echo,
#: command errors; and the ones the driver itself acts on (waits and comments).
PLAIN_WORDS = [
    b"RP", b"AX RP", b"AY QA", b"WY", b"AA RP", b"RE", b"QA", b"?KP", b"AX;RP;", b"XQ ", b"ZZ;",
    b"AX VL5000 AC50000 MR300 GO ID", b"AY MR-40 GO ID", b"AX;VL2000;MR100;GO;ID;",
    b"AZ JG500", b"AX ST", b"KL", b"ID", b"\r", b"\x04", b"\x19", b"EN", b"EF", b"WT20",
    b"LP100", b"AX LP-7 RP", b"IC", b"AM MR10,20 GO ID",
]  # fmt: skip
DRIVER_WORDS = [
    b"! ", b"@ ", b"!", b"@", b"*a comment\r", b"*comment", b"AX MR5 GO !RP", b"*x!@*\nRP",
]  # fmt: skip
WORDS = PLAIN_WORDS * 3 + DRIVER_WORDS
SEPARATORS = [b"", b" ", b";", b"\r", b"\n", b"\r\n", b"\t"]
SESSION = st.sampled_from([1, 1, 2, 3, 0])
GAP = st.sampled_from([0.0, 0.0, 0.0, 1e-4, 0.003, 0.05, 0.4])
EOS = st.sampled_from([0x0A, 0x0D, 0x00, 0x21, 0x23, 0x04, 0xFF])
BUFFER = st.sampled_from([16, 17, 64, 256])
STEP = st.one_of(
    st.tuples(st.just("soup"), st.integers(0, 2**32 - 1), st.integers(1, 30), SESSION, GAP),
    st.tuples(
        st.just("words"),
        st.lists(st.tuples(st.sampled_from(WORDS), st.sampled_from(SEPARATORS)), max_size=8),
        SESSION,
        GAP,
    ),
    st.tuples(st.just("flood"), st.integers(10, 300), SESSION, GAP),
    st.tuples(st.just("bytes"), st.binary(max_size=20), SESSION, GAP),
    st.tuples(st.just("run"), st.sampled_from([0.0, 0.001, 0.02, 0.3, 2.0])),
    st.tuples(st.just("deadline"), st.sampled_from([-1e-9, 0.0, 1e-9])),
    st.tuples(st.just("drop"), SESSION),
    st.tuples(st.just("power"), st.just(0)),
    st.tuples(st.just("reload"), EOS, BUFFER),
    st.tuples(st.just("bytes"), st.just(b"\x04"), SESSION, GAP),  # Control-D: a wait ends
)


def play(
    model: str,
    kind: str,
    eos: int,
    buffer_size: int,
    steps: list[tuple[Any, ...]],
    board: type[Board] = Board,
) -> Pair:
    pair = Pair(model, kind, eos, buffer_size, board)
    for step in steps:
        what = step[0]
        if what in ("soup", "words", "flood", "bytes"):
            session, gap = step[-2], step[-1]
            pair.now += gap
            if what == "soup":
                rnd = random.Random(step[1])
                data = command_soup(rnd, pair.model, step[2])
                if rnd.random() < 0.7:  # without the driver's own characters: its fast path's
                    data = data.replace(b"!", b"").replace(b"@", b"").replace(b"*", b"")
            elif what == "words":
                data = b"".join(word + sep for word, sep in step[1])
            elif what == "flood":
                data = b"RP " * step[1]
            else:
                data = step[1]
            pair.write(data, session)
        elif what == "run":
            pair.run(step[1])
        elif what == "deadline":
            deadline = pair.fast.next_deadline()
            if deadline is not None:
                pair.now = max(pair.now, deadline + step[1])
                pair.both("to_host", pair.now)
        elif what == "drop":
            pair.unsent.pop(step[1], None)
            pair.both("drop_input", step[1])
        elif what == "power":
            for card in (pair.fast_board, pair.straight_board):
                card.power_cycle(pair.now)
            pair.both("reset_input")
            pair.unsent.clear()
        else:
            pair.reload(step[1], step[2])
        pair.agree()
    pair.run(3.0)
    return pair


FAMILIES = ["PC48-4E", "PC46-4E", "VS4-040", "PCIX-400"]
assert {get_model(m).family for m in FAMILIES} == {m.family for m in MODELS.values()}
SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.parametrize("kind", ["driver", "raw"])
@pytest.mark.parametrize("model", FAMILIES)
@SETTINGS
@given(eos=EOS, buffer_size=BUFFER, steps=st.lists(STEP, min_size=1, max_size=25))
def test_fast_and_straight_links_say_the_same(
    model: str, kind: str, eos: int, buffer_size: int, steps: list[tuple[Any, ...]]
) -> None:
    play(model, kind, eos, buffer_size, steps)


@pytest.mark.parametrize("model", FAMILIES)
@SETTINGS
@given(eos=EOS, buffer_size=BUFFER, steps=st.lists(STEP, min_size=1, max_size=25))
def test_a_board_that_takes_a_few_bytes_at_a_time_says_the_same(
    model: str, eos: int, buffer_size: int, steps: list[tuple[Any, ...]]
) -> None:
    """The driver passes on what the board did not take at once, on either path."""
    play(model, "driver", eos, buffer_size, steps, Trickle)


@pytest.mark.parametrize("kind", ["driver", "raw"])
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    model=st.sampled_from(ALL_MODELS),
    eos=EOS,
    buffer_size=BUFFER,
    steps=st.lists(STEP, min_size=1, max_size=20),
)
def test_every_model_through_either_link_says_the_same(
    kind: str, model: str, eos: int, buffer_size: int, steps: list[tuple[Any, ...]]
) -> None:
    play(model, kind, eos, buffer_size, steps)


@pytest.mark.parametrize("kind", ["driver", "raw"])
@pytest.mark.parametrize("model", FAMILIES)
@pytest.mark.parametrize("seed", range(3))
def test_long_random_conversations_say_the_same(model: str, kind: str, seed: int) -> None:
    """Longer than hypothesis' examples: 150 steps, moves running, sessions taking turns."""
    rnd = random.Random(seed)
    pair = Pair(model, kind, rnd.choice([0x0A, 0x0D]), rnd.choice([16, 256]))
    for _ in range(150):
        r = rnd.random()
        session = rnd.choice([1, 1, 2])
        if r < 0.45:
            data = command_soup(rnd, pair.model, rnd.randrange(1, 25))
            if rnd.random() < 0.7:  # without the driver's own characters: its fast path's
                data = data.replace(b"!", b"").replace(b"@", b"").replace(b"*", b"")
            pair.write(data, session)
        elif r < 0.8:
            words = [rnd.choice(WORDS) + rnd.choice(SEPARATORS) for _ in range(rnd.randrange(6))]
            pair.write(b"".join(words), session)
        elif r < 0.97:
            pair.run(rnd.choice([0.0, 0.002, 0.05, 0.5]))
        else:
            pair.unsent.pop(session, None)
            pair.both("drop_input", session)
    pair.run(5.0)
    assert pair.said


# -- the fast paths are taken -------------------------------------------------------------------


def spy(monkeypatch: pytest.MonkeyPatch, owner: object, *names: str) -> dict[str, int]:
    """Count the calls of ``owner``'s methods ``names`` (still calling them)."""
    calls = dict.fromkeys(names, 0)
    for name in names:
        original = getattr(owner, name)

        def counted(*args: Any, _original: Any = original, _name: str = name, **kw: Any) -> Any:
            calls[_name] += 1
            return _original(*args, **kw)

        monkeypatch.setattr(owner, name, counted)
    return calls


def ready(model: str, kind: str) -> Link:
    """A link to a board that has answered a WY (so it is past its start)."""
    link = make_link(kind, Board(get_model(model), now=0.0))
    link.from_host(b"WY;" if get_model(model).dialect == "pcix" else b"WY ", 0.0, 1)
    link.to_host(0.0)
    return link


@pytest.mark.parametrize("model", FAMILIES)
def test_the_driver_passes_a_report_straight_through_and_its_reply_in_one(
    model: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    link = ready(model, "driver")
    assert isinstance(link, DriverLink)
    calls = spy(monkeypatch, link, "_straight_through", "through_buffer", "collect_all", "_pass_on")
    report = b"AX;RP;" if get_model(model).dialect == "pcix" else b"AX RP "
    for i in range(5):
        assert link.from_host(report, 1.0 + i, 1) == len(report)
        out = link.to_host(1.0 + i)
        assert out.pieces == [(1, b"0\n")] and out.events == []
    # from_host did not need _pass_on, nor did to_host, with nothing held and nothing said
    assert calls == {"_straight_through": 5, "through_buffer": 0, "collect_all": 0, "_pass_on": 0}
    link.from_host(b"AX;MR1;GO;" if get_model(model).dialect == "pcix" else b"AX MR1 GO ", 7.0, 1)
    link.to_host(8.0)  # nothing held, nothing said: the move ended unheard (no ID)
    assert calls["_pass_on"] == 0


def test_a_poll_at_rest_neither_runs_the_board_nor_asks_its_deadline(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # issue 16: at rest, _straight_through serves nothing and to_host (the board already at the
    # link's time) advances nothing; the two framed replies are one piece
    link = ready("PC48-4E", "driver")
    assert isinstance(link, DriverLink)
    calls = spy(monkeypatch, link.board, "advance", "next_deadline")
    for i in range(3):
        assert link.from_host(b"AX QA RP;", 1.0 + i, 1) == 9
        out = link.to_host(1.0 + i)
        assert out.pieces == [(1, b"PNNN\n0\n")] and out.events == []
    assert calls == {"advance": 0, "next_deadline": 0}
    link.to_host(5.0)  # a later time: the board is run to it
    assert calls["advance"] == 1


@pytest.mark.parametrize(
    ("data", "why"),
    [
        (b"*note\rRP ", "a comment"),
        (b"RP !", "a wait for done"),
        (b"RP @", "a wait for a limit"),
    ],
)
def test_the_driver_goes_by_its_buffer_when_it_has_something_to_do(
    data: bytes, why: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    link = ready("PC48-4E", "driver")
    assert isinstance(link, DriverLink)
    calls = spy(monkeypatch, link, "_straight_through", "through_buffer")
    link.from_host(data, 1.0, 1)
    assert calls == {"_straight_through": 0, "through_buffer": 1}, why


def test_the_driver_goes_by_its_buffer_while_it_holds_bytes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    link = ready("PC48-4E", "driver")
    assert isinstance(link, DriverLink)
    link.from_host(b"AX VL1000 MR1000 GO ! RP ", 1.0, 1)  # RP waits for the done
    assert link.waiting == "done" and link.pending
    calls = spy(monkeypatch, link, "_straight_through", "through_buffer")
    link.from_host(b"RP ", 1.1, 1)
    assert calls == {"_straight_through": 0, "through_buffer": 1}


def test_the_driver_collects_events_item_by_item(monkeypatch: pytest.MonkeyPatch) -> None:
    link = ready("PC48-4E", "driver")
    calls = spy(monkeypatch, link, "collect_all")
    link.from_host(b"XQ ", 1.0, 1)  # a command error: an event and its marker
    out = link.to_host(1.0)
    assert out.data == b"#\n" and len(out.events) == 1
    assert calls["collect_all"] >= 1


@pytest.mark.parametrize("model", FAMILIES)
def test_the_raw_link_hands_one_reply_on_as_it_is(
    model: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    link = ready(model, "raw")
    calls = spy(monkeypatch, link, "output")
    report = b"AX;RP;" if get_model(model).dialect == "pcix" else b"AX RP "
    for i in range(3):
        link.from_host(report, 1.0 + i, 1)
        out = link.to_host(1.0 + i)
        assert len(out.pieces) == 1 and out.pieces[0][0] == 1 and out.events == []
        assert link.to_host(1.0 + i) == LinkOutput()  # nothing: the fast path's too
    assert calls["output"] == 0
    pcix = get_model(model).dialect == "pcix"
    link.from_host(b"XQ;RP;" if pcix else b"XQ RP ", 5.0, 1)
    out = link.to_host(5.0)
    # a command error: a lone '#' in the PC48 family's stream, nothing in the PCIx's (CMD_S)
    assert out.data == (b"0\n\r" if pcix else b"#\n\r0\n\r") and len(out.events) == 1
    assert calls["output"] == 1


def test_the_fast_paths_give_what_the_straight_ones_give_for_each_kind_of_output() -> None:
    """The one-item fast paths and the item-by-item paths on each kind of item there is, given
    directly (so that a new kind cannot slip through the fast path unseen)."""
    board = Board(get_model("PC48-4E"), now=0.0)
    board.receive(b"WY AX VL1000 MR10 GO ID XQ EN RP EF AY MR1 GO ", 0.0, 1)
    board.advance(1.0)
    out, sources = board.take_output_sourced()
    kinds = {type(item).__name__ for item in out}
    assert {"Reply", "DoneEvent", "CommandErrorEvent"} <= kinds, kinds
    for item, source in zip(out, sources, strict=True):
        single: list[Output] = [item]
        raw = RawLink(Board(get_model("PC48-4E"), now=0.0))
        assert raw.output(list(single), [source]) == raw_one(item, source)
        for eos in (0x0A, 0x0D):
            fast = DriverLink(Board(get_model("PC48-4E"), now=0.0), eos=eos)
            straight = StraightDriver(Board(get_model("PC48-4E"), now=0.0), eos=eos)
            for link in (fast, straight):
                link.board.take_output_sourced = given_output(item, source)  # type: ignore[method-assign]
            assert fast._collect(1.0) == straight._collect(1.0)
            assert fast._pieces == straight._pieces and fast._events == straight._events


def given_output(item: Output, source: int) -> Callable[[], tuple[list[Output], list[int]]]:
    """A board's ``take_output_sourced`` that gives ``item`` from ``source``."""
    return lambda: ([item], [source])


def raw_one(item: Output, source: int) -> LinkOutput:
    """What the raw link's to_host makes of the one item (its fast path where it has one)."""
    board = Board(get_model("PC48-4E"), now=0.0)
    board.take_output_sourced = given_output(item, source)  # type: ignore[method-assign]
    board.advance = lambda now: None  # type: ignore[method-assign]
    return RawLink(board).to_host(1.0)
