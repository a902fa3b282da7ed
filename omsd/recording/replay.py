"""``omsd replay``: a recorded session through the emulator, compared with what the card said.

:func:`replay_file` reads the file (:mod:`omsd.recording.format`), works out the board to emulate
(:func:`resolve_board`), runs the host's bytes through it in simulated time
(:mod:`omsd.recording.emulate`), cuts both sides into replies and markers
(:mod:`omsd.recording.units`) and compares them (:mod:`omsd.recording.compare`, which states the
rules and the tolerance). :class:`Result` prints the differences as a table, one row each
(time, command, card said, omsd said), and a summary, or as JSON.

The board to emulate, from the first of these that says: ``--config FILE`` (the board named by
``--board``, else the one with the recording's board name, else the file's only board: its model,
link, end character, world and inputs); the recording's header; a daemon log's ``serving`` line
for the board (model and link; the world is the default one); ``--model``. ``--model``,
``--link`` and ``--eos`` then override what was found, one key each.

The emulated board starts at power-up. A recording made while the card was in another state
(positions, parameters set by an earlier session) differs where that state shows: record from the
card's reset, or begin the session with the commands that set the card up.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from omsd.config import BoardConfig
from omsd.dialects import framing
from omsd.models import UnknownModel, get_model
from omsd.recording.compare import Counts, Difference, Tolerance, compare
from omsd.recording.emulate import ONE, emulate, sides
from omsd.recording.format import (
    Recording,
    RecordingError,
    board_from_record,
    config_board,
    fitted,
    parse_eos,
    read_recording,
)
from omsd.recording.units import Unit, cut, splitter
from omsd.telemetry.lines import visible

COMMAND_WIDTH = 28
"""Characters of a command shown in the table (the host's chunk, as the traffic log shows it)."""


@dataclass
class Result:
    """A replay's outcome: the differences, what was compared, how long it took."""

    recording: Recording
    card: BoardConfig
    tolerance: Tolerance
    differences: list[Difference]
    counts: Counts
    elapsed: float
    streams: list[str]

    @property
    def ok(self) -> bool:
        return not self.differences

    def summary(self) -> str:
        what = (
            f"{_plural(self.counts.answers, 'answer')} and {_plural(self.counts.events, 'marker')}"
            f" over {self.recording.duration:.1f} s"
        )
        board = f"{self.card.model}, {self.card.link} link"
        tolerance = (
            f"tolerance {self.tolerance.steps:g} steps + {self.tolerance.seconds:g} s of motion,"
            f" markers within {self.tolerance.seconds:g} s"
        )
        head = "no differences" if self.ok else f"{_plural(len(self.differences), 'difference')}"
        text = f"{head}: {what} ({board}; {tolerance}), replayed in {self.elapsed:.2f} s"
        cut = self.recording.cut
        if cut:
            which = f"line {cut[0]}" if len(cut) == 1 else f"lines {', '.join(map(str, cut))}"
            text += (
                f"\nnote: {which} of {self.recording.path} {'was' if len(cut) == 1 else 'were'}"
                " cut short (its writer stopped part way) and left out"
            )
        return text

    def table(self) -> str:
        """The differences, one row each, columns aligned ("" with none)."""
        if not self.differences:
            return ""
        several = len(self.streams) > 1
        head = ["time", "command", "card said", "omsd said"]
        if several:
            head.insert(0, "client")
        rows = [head]
        for d in self.differences:
            row = [f"{d.time:.3f}", _command(d.command), _said(d, "card"), _said(d, "omsd")]
            if several:
                row.insert(0, d.stream)
            rows.append(row)
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        lines = []
        for r in rows:
            cells = [r[0].rjust(widths[0]) if not several else r[0].ljust(widths[0])]
            cells += [c.ljust(w) for c, w in zip(r[1:], widths[1:], strict=True)]
            lines.append("  ".join(cells).rstrip())
        return "\n".join(lines)

    def report(self) -> str:
        """The table and the summary, as ``omsd replay`` prints them."""
        table = self.table()
        return f"{table}\n{self.summary()}" if table else self.summary()

    def to_json(self) -> dict[str, Any]:
        return {
            "file": self.recording.path,
            "board": self.recording.board,
            "model": self.card.model,
            "link": self.card.link,
            "duration": self.recording.duration,
            "elapsed": self.elapsed,
            "tolerance": {"steps": self.tolerance.steps, "seconds": self.tolerance.seconds},
            "answers": self.counts.answers,
            "markers": self.counts.events,
            "truncated": self.recording.truncated,
            "cut_lines": self.recording.cut,
            "ok": self.ok,
            "differences": [
                {
                    "client": d.stream or None,
                    "time": d.time,
                    "command": None if d.command is None else visible(d.command),
                    "card": None if d.card is None else visible(d.card),
                    "omsd": None if d.omsd is None else visible(d.omsd),
                    "card_hex": None if d.card is None else d.card.hex(),
                    "omsd_hex": None if d.omsd is None else d.omsd.hex(),
                    "card_time": d.card_time,
                    "omsd_time": d.omsd_time,
                    "what": d.what,
                }
                for d in self.differences
            ],
        }


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


def _command(command: bytes | None) -> str:
    if command is None:
        return "(none)"
    text = visible(command.strip(b" ")) or visible(command)
    return text if len(text) <= COMMAND_WIDTH else text[: COMMAND_WIDTH - 3] + "..."


def _said(d: Difference, side: str) -> str:
    data = d.card if side == "card" else d.omsd
    if data is None:
        return "(nothing)"
    text = visible(data)
    if d.what == "time":
        at = d.card_time if side == "card" else d.omsd_time
        text += f" at {at:.3f}"
    return text


def resolve_board(
    recording: Recording,
    *,
    model: str | None = None,
    link: str | None = None,
    eos: str | int | None = None,
    config: str | Path | None = None,
    board: str | None = None,
) -> BoardConfig:
    """The board to emulate (the module text's order); :class:`RecordingError` if none."""
    found: BoardConfig | None = None
    if config is not None:
        found = config_board(config, board, recording.board)
    elif recording.header is not None:
        found = board_from_record(recording.header, f"{recording.path}: header")
    elif recording.board in recording.served:
        served_model, served_link = recording.served[recording.board]
        found = board_from_record(
            {"board": recording.board, "model": served_model, "link": served_link},
            f"{recording.path}: serving line",
        )
    if found is None:
        if model is None:
            raise RecordingError(
                f"{recording.path}: no header, and no 'serving' line says the model of board"
                f" {recording.board}: give --model or --config"
            )
        found = BoardConfig(name=recording.board)
    changes: dict[str, Any] = {}
    if model is not None:
        try:
            changes["model"] = get_model(model).name
        except UnknownModel as exc:
            raise RecordingError(f"--model: {exc}") from None
    if link is not None:
        changes["link"] = link
    if eos is not None:
        changes["eos"] = parse_eos(eos)
    card = dataclasses.replace(found, **changes) if changes else found
    return fitted(card, f"{recording.path}: board {card.name} as a {card.model}")


def replay(recording: Recording, card: BoardConfig, tolerance: Tolerance) -> Result:
    """Replay ``recording`` through an emulated ``card`` and compare (module text)."""
    started = time.perf_counter()
    model = card.personality()
    split = splitter(card.link, card.eos, framing(model))
    line = recording.line
    char_time = line.char_time if line is not None else 0.0
    streams = sides(recording)
    card_units = {name: cut(pieces, split, char_time) for name, pieces in streams.card.items()}
    seen = {
        name: _markers_before(units, len(streams.host.get(name, ())))
        for name, units in card_units.items()
    }

    def markers(data: bytes) -> int:
        return sum(event for _, _, event in split(data))

    emulate(recording, card, tolerance.seconds, streams, markers, seen)
    counts = Counts()
    differences: list[Difference] = []
    names = list(dict.fromkeys([*streams.host, *streams.card, *streams.omsd]))
    for name in names:
        omsd_units = cut(streams.omsd.get(name, []), split)
        commands = [data for _, data in streams.host.get(name, [])]
        differences += compare(
            name, card_units.get(name, []), omsd_units, commands, tolerance, counts
        )
    differences.sort(key=lambda d: d.time)
    elapsed = time.perf_counter() - started
    shown = [n for n in names if n != ONE] or [ONE]
    return Result(recording, card, tolerance, differences, counts, elapsed, shown)


def _markers_before(units: list[Unit], chunks: int) -> list[int]:
    """How many markers the card had sent before each of the host's ``chunks``."""
    before = [0] * (chunks + 1)
    for unit in units:
        if unit.event:
            before[unit.command + 1] += 1
    for k in range(1, len(before)):
        before[k] += before[k - 1]
    return before[:chunks]


def replay_file(
    path: str | Path,
    *,
    model: str | None = None,
    link: str | None = None,
    eos: str | int | None = None,
    config: str | Path | None = None,
    board: str | None = None,
    tolerance: Tolerance | None = None,
) -> Result:
    """Read ``path`` and replay it (:class:`RecordingError` for a file or options that do not
    make a replay)."""
    recording = read_recording(path, board, renamed=config is not None)
    card = resolve_board(recording, model=model, link=link, eos=eos, config=config, board=board)
    return replay(recording, card, tolerance or Tolerance())


__all__ = ["Result", "replay", "replay_file", "resolve_board"]
