"""``omsd replay`` of a ten-minute session (issue 17: "replaying a 10-minute recorded session
takes under 5 s").

The session is made here, as ``omsd record`` would have written it in front of a card: a
PC48-4E on the DOS driver link, polled at 10 Hz (``AX RP`` and ``AA RP`` in turn, with an
``AX QA`` every second), with a move of X or Y every ten seconds (``MR`` ... ``GO ID``, its done
marker) and an unknown command now and then; the card is an emulated board on the manual clock
that hears each command up to 2 ms after the recorded time and answers up to 1 ms later (a card
behind a recorder, with jitter). The figure is the wall time of :func:`omsd.recording.replay.
replay_file` on that file (reading, emulating, comparing), the best of :data:`REPEATS` (one with
``--quick``); the baseline is the session's own length, ten minutes. Target: <= 5 s. A replay
that finds a difference fails the benchmark: it would time the wrong thing.
"""

from __future__ import annotations

import random
import time
from pathlib import Path

from bench.settings import Settings
from bench.table import Row, Target

MINUTES = 10
REPEATS = 3
NAME = f"replay of a {MINUTES}-minute recorded session"


def script(minutes: int = MINUTES) -> list[tuple[float, bytes]]:
    """The host's commands and when it sent them."""
    commands: list[tuple[float, bytes]] = [(0.0, b"WY"), (0.05, b"AX VL200000 AC400000;")]
    commands.append((0.07, b"AY VL200000 AC400000;"))
    ticks = int(minutes * 60 * 10)
    for i in range(1, ticks):
        t = i / 10
        if i % 100 == 0:
            axis = "X" if i % 200 == 0 else "Y"
            sign = "" if i % 400 < 200 else "-"
            commands.append((t, f"A{axis} MR{sign}150000 GO ID".encode()))
        elif i % 10 == 0:
            commands.append((t, b"AX QA"))
        elif i % 97 == 0:
            commands.append((t, b"XQ"))
        else:
            commands.append((t, b"AX RP" if i % 2 else b"AA RP"))
    return commands


def make_session(path: Path, minutes: int = MINUTES, seed: int = 17) -> int:
    """Write the session's recording to ``path``; the number of host chunks."""
    from omsd.board import Board
    from omsd.config import BoardConfig
    from omsd.link import make_link
    from omsd.models import get_model
    from omsd.recording.format import RecordingWriter
    from omsd.telemetry.traffic import Direction

    rng = random.Random(seed)
    config = BoardConfig(name="card", model="PC48-4E")
    board = Board(get_model(config.model), now=0.0)
    link = make_link("driver", board)
    writer = RecordingWriter(path)
    writer.header(0.0, time.time(), config, to="tcp:bench:1", line=None, listen="tcp:bench:2")
    endpoint = "tcp:127.0.0.1:7100 #1 (127.0.0.1:50000)"

    def answer(t: float) -> None:
        out = link.to_host(t)
        if out.data:
            writer.traffic(t + rng.uniform(0, 0.001), "card", endpoint, Direction.OUT, out.data)

    commands = script(minutes)
    for at, command in commands:
        heard = at + rng.uniform(0, 0.002)
        while (d := link.next_deadline()) is not None and d <= heard:
            answer(d)
            if link.next_deadline() == d:
                break
        writer.traffic(at, "card", endpoint, Direction.IN, command)
        link.from_host(command, heard, 1)
        answer(heard)
    writer.close()
    return len(commands)


def run(settings: Settings, directory: Path) -> list[Row]:
    from omsd.recording.replay import replay_file

    path = directory / "replay-session.jsonl"
    path.unlink(missing_ok=True)
    t0 = time.perf_counter()
    chunks = make_session(path)
    made = time.perf_counter() - t0
    best = float("inf")
    result = None
    for _ in range(1 if settings.quick else REPEATS):
        t0 = time.perf_counter()
        result = replay_file(path)
        best = min(best, time.perf_counter() - t0)
    assert result is not None
    if not result.ok:
        raise RuntimeError(f"the session does not replay:\n{result.report()}")
    note = (
        f"PC48-4E, driver link: {chunks:,} commands at 10 Hz with a move every 10 s,"
        f" {result.counts.answers:,} answers and {result.counts.events} markers compared;"
        f" {path.stat().st_size / 1e6:.1f} MB; the recording made in {made:.1f} s; best of"
        f" {1 if settings.quick else REPEATS}; baseline: the session's own length"
    )
    return [
        Row(NAME, "s", best, MINUTES * 60.0, Target("figure", "<=", 5.0, "s"), note),
    ]
