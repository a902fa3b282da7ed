"""Cutting streams into replies and markers (:mod:`omsd.recording.units`) and the comparison's
rules (:mod:`omsd.recording.compare`), without I/O; and a replay of sessions made here on the
manual clock, with the card's clock late, early or jittering against the recording's."""

from __future__ import annotations

import random
import time
from pathlib import Path

import pytest

from omsd.board import Board
from omsd.config import BoardConfig
from omsd.dialects.pc48 import FRAMING as PC48
from omsd.dialects.pcix import FRAMING as PCIX
from omsd.link import make_link
from omsd.models import get_model
from omsd.recording import cli
from omsd.recording.compare import (
    DEFAULT_SECONDS,
    DEFAULT_STEPS,
    Tolerance,
    align,
    compare,
    numbers_agree,
)
from omsd.recording.format import RecordingWriter
from omsd.recording.replay import replay_file
from omsd.recording.units import Unit, cut, driver_splitter, raw_splitter
from omsd.telemetry.traffic import Direction


def pieces(data: bytes, split: object) -> list[bytes]:
    return [data[a:b] for a, b, _ in split(data)]  # type: ignore[operator]


def test_the_driver_link_is_cut_at_its_end_character_markers_apart() -> None:
    split = driver_splitter(0x0A)
    # the done byte may be the end character itself (axes Y and T: 0x0A)
    stream = b"PC48 ver 3.00-4\n!\n\n#\n@\n$\n12,0\n!\x01\n WY\n"
    assert pieces(stream, split) == [
        b"PC48 ver 3.00-4\n",
        b"!\n\n",
        b"#\n",
        b"@\n",
        b"$\n",
        b"12,0\n",
        b"!\x01\n",
        b" WY\n",
    ]
    assert [event for _, _, event in split(stream)] == [0, 1, 0, 1, 1, 0, 1, 0]
    assert pieces(b"1234\r!\x03\r", driver_splitter(0x0D)) == [b"1234\r", b"!\x03\r"]
    assert pieces(b"12", split) == [b"12"]  # cut short


def test_the_raw_link_is_cut_by_its_framing() -> None:
    split = raw_splitter(PC48)
    stream = b"\n\r0\n\r\n\r\rPNNN\n\r\r#\n\r1,2\n\r WY\r\n\rPC48\n\r"
    assert pieces(stream, split) == [
        b"\n\r0\n\r",
        b"\n\r\rPNNN\n\r\r",
        b"#",
        b"\n\r1,2\n\r",
        b" WY\r",
        b"\n\rPC48\n\r",
    ]
    assert not any(event for _, _, event in split(stream))
    split = raw_splitter(PCIX)
    assert pieces(b"0\n\r#PNNN\n\rvl200000\n\r#", split) == [
        b"0\n\r",
        b"#",
        b"PNNN\n\r",
        b"vl200000\n\r",
        b"#",
    ]


def test_a_unit_has_the_time_of_its_first_byte_and_on_a_line_when_it_left() -> None:
    split = driver_splitter(0x0A)
    units = cut([(1.0, b"12\n!", 0, 0.0, 0.0), (2.0, b"\x01\n", 1, 0.0, 0.0)], split)
    assert [(u.time, u.data, u.event, u.command) for u in units] == [
        (1.0, b"12\n", False, 0),
        (1.0, b"!\x01\n", True, 0),
    ]
    # 10 bits a character at 1000 baud: 10 ms a byte; the chunk's last byte came at 1.0
    units = cut([(1.0, b"12\n34\n", 0, 0.0, 0.0)], split, char_time=0.01)
    assert [round(u.time, 6) for u in units] == [0.94, 0.97]


def test_numbers_agree_within_the_allowance_the_rest_exactly() -> None:
    assert numbers_agree(b"100,-5\n", b"102,-4\n", 2)
    assert not numbers_agree(b"100,-5\n", b"103,-5\n", 2)
    assert numbers_agree(b"uu3.50000\n", b"uu3.50100\n", 0.01)
    assert not numbers_agree(b"uu3.5\n", b"vv3.5\n", 10)
    assert not numbers_agree(b"PNNN\n", b"PDNN\n", 10)  # no numbers: never within


def pairs(card: str, omsd: str) -> list[tuple[int | None, int | None]]:
    return list(align(len(card), len(omsd), lambda i, j: card[i] == omsd[j]))


def test_alignment_changed_missing_extra_each_one_row() -> None:
    assert pairs("abcd", "abcd") == [(0, 0), (1, 1), (2, 2), (3, 3)]
    assert pairs("abXd", "abcd") == [(0, 0), (1, 1), (2, 2), (3, 3)]  # one changed
    assert pairs("abcd", "acd") == [(0, 0), (1, None), (2, 1), (3, 2)]  # one missing
    assert pairs("acd", "abcd") == [(0, 0), (None, 1), (1, 2), (2, 3)]  # one extra
    assert pairs("aaaX", "aaaa") == [(0, 0), (1, 1), (2, 2), (3, 3)]  # changed, not shifted
    assert pairs("ab", "") == [(0, None), (1, None)]
    # a stream gone wrong for good: unit by unit
    assert pairs("abcdefghijklmnopq", "ABCDEFGHIJKLMNOPQ") == [(i, i) for i in range(17)]


def test_alignment_never_pairs_past_the_end_of_either_side() -> None:
    """A recording whose card said one thing (``AX RP`` -> ``5``) where omsd said two made
    ``omsd replay`` die with a traceback (IndexError in compare): a skip that took both sides
    past their ends was taken as a match, and the pairs named units that are not there. Every
    unit is now paired once, and only units that exist."""
    for card, omsd in [("a", "bc"), ("ab", "c"), ("a", "xyz"), ("xyz", "a"), ("ab", "cdefg")]:
        got = pairs(card, omsd)
        assert sorted(i for i, _ in got if i is not None) == list(range(len(card))), got
        assert sorted(j for _, j in got if j is not None) == list(range(len(omsd))), got
    assert pairs("a", "bc") == [(0, 0), (None, 1)]


def unit(t: float, data: bytes, command: int = 0, speed: float = 0.0) -> Unit:
    return Unit(t, data, data[:1] in (b"!", b"@", b"$"), command, speed)


def test_positions_during_motion_and_markers_have_a_tolerance_the_rest_none() -> None:
    tolerance = Tolerance(steps=2, seconds=0.02)
    commands = [b"AX RP", b"AX QA", b"AX MR100 GO ID"]
    card = [unit(1.0, b"1000\n", 0), unit(1.1, b"PNNN\n", 1), unit(2.0, b"!\x01\n", 2)]
    moving = [unit(1.0, b"1030\n", 0, 5000.0), unit(1.1, b"PNNN\n", 1), unit(2.015, b"!\x01\n", 2)]
    assert compare("", card, moving, commands, tolerance, cli_counts()) == []
    # at rest the position is exact; a marker 30 ms off is a difference of time
    still = [unit(1.0, b"1001\n", 0), unit(1.1, b"PNNN\n", 1), unit(2.03, b"!\x01\n", 2)]
    rows = compare("", card, still, commands, tolerance, cli_counts())
    assert [(r.command, r.card, r.omsd, r.what) for r in rows] == [
        (b"AX RP", b"1000\n", b"1001\n", "number"),
        (b"AX MR100 GO ID", b"!\x01\n", b"!\x01\n", "time"),
    ]
    # a status is never within a tolerance; a number that answers no position query neither
    rows = compare(
        "",
        [unit(1.0, b"200\n", 1)],
        [unit(1.0, b"199\n", 1, 5000.0)],
        commands,
        tolerance,
        cli_counts(),
    )
    assert [r.what for r in rows] == ["text"]


def cli_counts() -> object:
    from omsd.recording.compare import Counts

    return Counts()


def test_the_help_quotes_the_comparisons_defaults() -> None:
    assert cli.DEFAULT_TOLERANCE_STEPS == DEFAULT_STEPS
    assert cli.DEFAULT_TOLERANCE_SECONDS == DEFAULT_SECONDS


# -- sessions on the manual clock -----------------------------------------------------------


def session(path: Path, model: str, link: str, skew: object, seed: int = 1) -> None:
    """A recording made here: the card a Board on the manual clock hearing each command at the
    recorded time plus ``skew()`` and answering ``skew()`` later still; moves polled at 20 Hz,
    a jog into the limit, errors."""
    from omsd.board import AxisWorld

    rng = random.Random(seed)
    world = {"X": AxisWorld(negative_limit=-500, home_low=0, home_high=100)}
    config = BoardConfig(name="card", model=model, link=link, world=world)
    board = Board(get_model(model), now=0.0, world=world)
    wire = make_link(link, board)
    writer = RecordingWriter(path)
    writer.header(0.0, time.time(), config, to="tcp:test:1", line=None)
    delay = skew  # type: ignore[assignment]

    def run(until: float) -> None:
        while (d := wire.next_deadline()) is not None and d <= until:
            out = wire.to_host(d)
            if out.data:
                writer.traffic(d + delay(rng), "card", "e", Direction.OUT, out.data)  # type: ignore[operator]
            if wire.next_deadline() == d:
                break

    script: list[tuple[float, bytes]] = [(0.0, b"WY"), (0.1, b"AX VL5000 AC20000 MR4000 GO ID")]
    script += [(0.15 + 0.05 * i, b"RP") for i in range(24)]
    script += [(1.5, b"XQ"), (1.6, b"AX JG-8000;")]
    script += [(1.7 + 0.05 * i, b"AX RP RV") for i in range(10)]
    script += [(2.6, b"AX QA"), (2.7, b"AX VL1000 HM0 ID"), (3.4, b"AA RP")]
    for at, command in script:
        heard = at + delay(rng)  # type: ignore[operator]
        run(heard)
        writer.traffic(at, "card", "e", Direction.IN, command)
        wire.from_host(command, heard, 1)
        out = wire.to_host(heard)
        if out.data:
            writer.traffic(heard + delay(rng), "card", "e", Direction.OUT, out.data)  # type: ignore[operator]
    run(4.0)
    writer.close()


@pytest.mark.parametrize("model", ["PC48-4E", "PCIX-400"])
@pytest.mark.parametrize("link", ["driver", "raw"])
def test_a_card_whose_clock_jitters_within_the_tolerance_replays(
    tmp_path: Path, model: str, link: str
) -> None:
    path = tmp_path / "jitter.jsonl"
    session(path, model, link, lambda rng: rng.uniform(0.0, 0.004))
    result = replay_file(path)
    assert result.ok, result.report()
    # (the XQ's command error is an answer, but for the PCIx's raw stream, which has no byte for it)
    answers = 47 if (link, model) == ("raw", "PCIX-400") else 48
    assert result.counts.answers == answers
    assert result.counts.events == (3 if link == "driver" else 0)


def test_a_card_late_beyond_the_tolerance_is_reported_at_its_markers(tmp_path: Path) -> None:
    path = tmp_path / "late.jsonl"
    # each command heard 30 ms late, each answer 30 ms later still: markers 60 ms late
    session(path, "PC48-4E", "driver", lambda rng: 0.03)
    result = replay_file(path)
    assert {d.what for d in result.differences} == {"time"}
    assert [d.card for d in result.differences] == [b"!\x01\n", b"@\n", b"!\x01\n"]
    assert replay_file(path, tolerance=Tolerance(2, 0.07)).ok
