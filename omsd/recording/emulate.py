"""The recorded host bytes through an emulated board, in simulated time.

The board engine never reads a clock (:mod:`omsd.board.board`): every call takes the time. So
the replay does what :class:`omsd.service.BoardService` does for a client, with the recorded
times instead of the clock, and without waiting between them: a one-hour session runs in
seconds.

* The board is made at time 0, the time of the file's first traffic record, at power-up, with
  the recording's world and inputs, behind the recording's link (:func:`omsd.link.make_link`).
* Each host chunk is given to the link at its recorded time (on a serial line, when its last
  character reached the card: :attr:`omsd.recording.format.Line.char_time` per byte later),
  in its session; what the link does not take yet waits, in order, and is offered again each
  time the board has run, as the service offers a waiting client's bytes.
* Between two chunks the board runs from deadline to deadline (``link.next_deadline()``, a
  move's end, a switch, a wait), as the service's wake-ups run it, so that a done marker is
  produced at the time the move ends and a driver's ``!`` wait releases the bytes it holds then.
* **Cause before effect.** A host chunk recorded after the card had sent a done, limit or slip
  marker was sent by a host that may have been waiting for it (``ID`` then the next command once
  ``!`` is read; ``JG`` until ``@``). When the emulator has not given that marker yet by the
  chunk's time, it runs on, from deadline to deadline and at most the time tolerance further,
  until it has, and the chunk goes in then. Without this, a marker the emulator gives a fraction
  of a millisecond after the recorded time of the command that followed the card's (the
  recorded times are those of the bytes passing the recorder, or the daemon's log, not of the
  card's clock) would put that command before the marker, and change what it answers.
* What the link gives the host is kept, per stream, with the time it was given, the index of the
  host chunk it follows, and how fast the board's axes were moving then (:func:`motion_at`).
* The run ends ``margin`` seconds after the file's last record: what the card did after the
  recording stopped is not in the file, so the emulator's output after it is not compared.

Streams: a recording is one (the card hears one byte stream, whoever the client is). A daemon's
log is one per endpoint label, each client's session as it was in the daemon: what the board
said for a client that has gone (the log's ``(gone: ...)``) belongs to that client's stream;
the board's own output (session 0) to the last client that wrote, as the service routes it. The
log's ``disconnected`` / ``closed`` / ``takes over`` lines end a session (its held input is
dropped, :meth:`omsd.link.Link.drop_input`).

A daemon's log that goes on after a restart (omsd appends to its ``--log``; a new ``serving``
line of the board after its traffic, :attr:`omsd.recording.format.Recording.restarts`) has the
board at power-up again at that time, behind a new link, with every session of the old run
ended, as the new daemon had it. ``BOARD: power cycled (control API)`` (``omsd ctl reset``)
power-cycles it as the daemon did, the sessions going on.
"""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from omsd.board import Board
from omsd.config import BoardConfig
from omsd.link import Link, make_link
from omsd.recording.format import NO_CLIENT, Recording
from omsd.telemetry.traffic import Direction

ONE = ""
"""The stream of a recording (one conversation)."""

_GONE = "(gone: "

POWER_CYCLED = "power cycled (control API)"
"""What a daemon's log says, after ``BOARD: ``, when ``omsd ctl reset`` power-cycled the board."""

#: A piece of one side's output: (time, bytes, index of the host chunk it follows, speed,
#: acceleration).
Piece = tuple[float, bytes, int, float, float]


@dataclass
class Streams:
    """Both sides, per stream: the host's chunks (time, bytes), the card's output and the
    emulator's, as :data:`Piece` lists."""

    host: dict[str, list[tuple[float, bytes]]]
    card: dict[str, list[Piece]]
    omsd: dict[str, list[Piece]]


def stream_of(endpoint: str, one: bool) -> str:
    """The stream a traffic record's endpoint belongs to."""
    if one:
        return ONE
    if endpoint.startswith(_GONE) and endpoint.endswith(")"):
        return endpoint[len(_GONE) : -1]
    return endpoint


def motion_at(board: Board, t: float, window: float) -> tuple[float, float]:
    """How fast anything moved around ``t``: the largest speed (steps/s) and acceleration
    (steps/s²) of any axis at ``t - window``, ``t`` and ``t + window`` (the card may have heard
    each command up to ``window`` later or earlier than the recording says). (0, 0) when all
    was still."""
    speed = accel = 0.0
    for axis in board.axes:
        if not axis.moving and axis.traj.end_time < t - window:
            continue
        for s in (t - window, t, t + window):
            speed = max(speed, abs(axis.velocity(s)))
            accel = max(accel, abs(axis.acceleration(s)))
    return speed, accel


class _Run:
    def __init__(self, recording: Recording, card: BoardConfig, window: float) -> None:
        self.card = card
        self.power_up(0.0)
        self.window = window
        self.out: dict[str, list[Piece]] = {}
        self.label: dict[int, str] = {}
        self.active = ONE
        self.command: dict[str, int] = {}
        self.given: dict[str, int] = {}  # markers given to the host, per stream
        self.markers: Callable[[bytes], int] = lambda data: 0
        self.now = 0.0
        # (time, speed, acceleration) of the motion just before each run: a move that ends at a
        # deadline is gone from the axes once run, but was there within the window
        self.recent: deque[tuple[float, float, float]] = deque()

    def power_up(self, t: float) -> None:
        """A board at power-up at ``t``, behind a new link: what the host had not yet had taken
        is gone with the old one."""
        card = self.card
        self.board = Board(card.personality(), now=t, world=dict(card.world))
        for bit, high in card.inputs.items():
            self.board.set_input(bit, high, t)
        self.link: Link = make_link(
            card.link, self.board, eos=card.eos, buffer_size=card.buffer_size
        )
        self.pending: deque[list[object]] = deque()  # [session, bytes]

    def motion(self, t: float) -> tuple[float, float]:
        """The motion around ``t``: now, and just before the runs of the last ``window``."""
        speed, accel = motion_at(self.board, t, self.window)
        recent = self.recent
        while recent and recent[0][0] < t - self.window:
            recent.popleft()
        for _, s, a in recent:
            speed, accel = max(speed, s), max(accel, a)
        return speed, accel

    def step(self, t: float) -> None:
        """Run the board to ``t``; keep what the host is given; offer the waiting bytes."""
        link = self.link
        before = motion_at(self.board, t, self.window)
        if before != (0.0, 0.0):
            self.recent.append((t, *before))
        for _ in range(64):
            out = link.to_host(t)
            for session, data in out.pieces:
                stream = self.label.get(session, self.active) if session else self.active
                speed, accel = self.motion(t)
                piece = (t, data, self.command.get(stream, -1), speed, accel)
                self.out.setdefault(stream, []).append(piece)
                self.given[stream] = self.given.get(stream, 0) + self.markers(data)
            if not self.pending or not self._feed(t):
                break
        self.now = t

    def _feed(self, t: float) -> bool:
        """Offer the waiting bytes in order; whether any were taken."""
        taken_any = False
        while self.pending:
            item = self.pending[0]
            session = item[0]
            data = item[1]
            assert isinstance(session, int) and isinstance(data, bytes)
            taken = self.link.from_host(data, t, session)
            if taken:
                taken_any = True
            if taken < len(data):
                item[1] = data[taken:]
                break
            self.pending.popleft()
        return taken_any

    def catch_up(self, stream: str, count: int, limit: float) -> float:
        """Run from deadline to deadline, up to ``limit``, until ``stream`` has been given
        ``count`` markers; the time reached."""
        last = None
        while self.given.get(stream, 0) < count:
            d = self.link.next_deadline()
            if d is None or d > limit:
                break
            d = max(d, self.now)
            if d == last:
                break
            self.step(d)
            last = d
        return self.now

    def until(self, t: float) -> None:
        """Run from deadline to deadline up to ``t``."""
        link = self.link
        last = None
        while True:
            d = link.next_deadline()
            if d is None or d > t:
                break
            d = max(d, self.now)
            if d == last:
                break  # nothing moved on at this deadline: leave it to the run to t
            self.step(d)
            last = d
        self.step(max(t, self.now))


def sides(recording: Recording) -> Streams:
    """The recorded sides per stream: the host's chunks, and the card's output as pieces whose
    command is the index of the host chunk before it (the emulator's still empty)."""
    one = recording.one_stream
    host: dict[str, list[tuple[float, bytes]]] = {}
    card_out: dict[str, list[Piece]] = {}
    last_writer = ONE
    for chunk in recording.chunks:
        stream = stream_of(chunk.endpoint, one)
        if chunk.direction is Direction.IN:
            host.setdefault(stream, []).append((chunk.time, chunk.data))
            last_writer = stream
        else:
            if not one and chunk.endpoint == NO_CLIENT:
                stream = last_writer
            index = len(host.get(stream, ())) - 1
            card_out.setdefault(stream, []).append((chunk.time, chunk.data, index, 0.0, 0.0))
    return Streams(host, card_out, {})


def emulate(
    recording: Recording,
    card: BoardConfig,
    margin: float,
    streams: Streams,
    markers: Callable[[bytes], int],
    card_markers: Mapping[str, Sequence[int]],
) -> None:
    """Run the host's chunks of ``streams`` through the emulator, into ``streams.omsd`` (module
    text). ``markers(data)`` counts the done, limit and slip markers in the emulator's output;
    ``card_markers[stream][k]`` how many the card had sent in that stream before the host's
    chunk ``k``: a chunk the host sent after a marker the emulator has not yet given waits for
    it, at most ``margin`` seconds (the host had read it: it came first)."""
    run = _Run(recording, card, margin)
    run.markers = markers
    char_time = recording.line.char_time if recording.line is not None else 0.0
    # the host's actions in time order: (time, order, kind, stream, data)
    actions: list[tuple[float, int, str, str, bytes]] = []
    order = itertools.count()
    for stream, chunks in streams.host.items():
        for t, data in chunks:
            actions.append((t + len(data) * char_time, next(order), "in", stream, data))
    if not recording.one_stream:
        for t, kind, message in recording.notes:
            ended = _session_end(recording.board, kind, message)
            if ended is not None:
                actions.append((t, next(order), "end", ended, b""))
            elif kind == "warning" and message == f"{recording.board}: {POWER_CYCLED}":
                actions.append((t, next(order), "power cycle", ONE, b""))
        for t in recording.restarts:  # before any chunk of the same time: those are the new run's
            actions.append((t, -1, "restart", ONE, b""))
    actions.sort(key=lambda a: (a[0], a[1]))
    sessions: dict[str, int] = {}
    numbers = itertools.count(1)
    for at, _, kind, stream, data in actions:
        run.until(at)
        if kind == "restart":
            run.power_up(at)
            sessions.clear()
            continue
        if kind == "power cycle":  # as BoardService.power_cycle: the sessions go on
            run.board.power_cycle(at)
            run.link.reset_input()
            run.pending.clear()
            run.step(at)
            continue
        if kind == "end":
            session = sessions.pop(stream, None)
            if session is not None:
                run.link.drop_input(session)
                run.pending = deque(p for p in run.pending if p[0] != session)
            continue
        index = run.command.get(stream, -1) + 1
        seen = card_markers.get(stream, ())
        if index < len(seen) and run.given.get(stream, 0) < seen[index]:
            at = run.catch_up(stream, seen[index], at + margin)
        session = sessions.get(stream)
        if session is None:
            session = sessions[stream] = next(numbers)
            run.label[session] = stream
        run.command[stream] = index
        run.active = stream
        run.pending.append([session, data])
        run._feed(at)
        run.step(at)
    run.until(max(recording.duration + margin, run.now))
    streams.omsd.update(run.out)


def _session_end(board: str, kind: str, message: str) -> str | None:
    """The endpoint label whose session a daemon's log line ends, if it ends one."""
    prefix = f"{board}: "
    if not message.startswith(prefix):
        return None
    rest = message[len(prefix) :]
    if kind == "info":
        for word in (" disconnected", " closed"):
            if rest.endswith(word) and " closed: " not in rest:
                return rest[: -len(word)]
    if kind == "warning" and " takes over from " in rest:
        return rest.split(" takes over from ", 1)[1]
    return None


__all__ = ["ONE", "Piece", "Streams", "emulate", "motion_at", "sides", "stream_of"]
