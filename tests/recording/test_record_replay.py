"""``omsd record`` in front of a second omsd standing in for the card, then ``omsd replay``
(issue 17): a session of moves, homes, limits, queued commands and errors on a PC48-4E and a
PCIX-400 replays with no difference; a recording edited to disagree is caught with exactly the
right row; the stand-in's own ``--log`` file replays with no difference; files that are no
recording exit 2 with one line.

The stand-in and the recorder run in this process, on the test's event loop, each on a free
port of 127.0.0.1 (:mod:`tests.recording.session`)."""

from __future__ import annotations

import argparse
import asyncio
import json
from pathlib import Path

import pytest

from omsd.recording.cli import add_replay_parser, run_replay
from omsd.recording.format import RecordingError
from omsd.recording.replay import replay_file
from omsd.testing import assert_replays

from .session import Rig, rig

MODELS = ("PC48-4E", "PCIX-400")

STAGE_TOML = """
[[board]]
name = "card"
model = "{model}"
tcp = "127.0.0.1:0"

[board.axes.X]
negative_limit = -500
positive_limit = 60500
home_low = 0
home_high = 100

[board.axes.Y]
negative_limit = -500
positive_limit = 60500
home_low = 0
home_high = 100
"""


async def poll(
    r: Rig, command: bytes, times: int, every: float = 0.03, answers: int = 1
) -> list[bytes]:
    """``command`` sent ``times`` times, ``every`` seconds apart (positions during a move)."""
    got = []
    for _ in range(times):
        await asyncio.sleep(every)
        got.append(await r.ask(command, answers))
    return got


async def session(r: Rig, model: str) -> None:
    """Moves polled while they run, an unknown command and a bad operand, a jog into the minus
    limit, a status, a home, queued moves with pipelined queries, the model's own queries."""
    assert (await r.ask(b"WY")).startswith(model.split("-")[0].encode())
    await r.send(b"AX VL10000 AC100000 MR2000 GO ID")
    positions = await poll(r, b"RP", 4)
    assert positions[0] != positions[-1]  # read during the move
    assert await r.marker() == b"!\x01\n"
    await asyncio.sleep(0.05)  # at rest, longer than the time tolerance
    assert await r.ask(b"RP") == b"2000\n"
    assert await r.ask(b"XQ") == b"#\n"  # an unknown command
    await r.send(b"AX JG-20000;")
    assert await r.marker() == b"@\n"  # the minus limit, 500 steps below
    assert await r.ask(b"AX QA") == b"MDLN\n"  # moving down, done, in the limit, no home
    await r.send(b"AX VL2000 HM0 ID")
    assert await r.marker() == b"!\x01\n"  # homed on the switch
    assert (await r.ask(b"AA RP")).endswith(b",0,0,0\n")
    await r.send(b"AX; VL30000 MR3000 GO MR-3000 GO ID")  # queued: out and back
    await poll(r, b"AX RP RV", 3, answers=2)
    assert await r.marker() == b"!\x01\n"
    # two axes, two markers: Y done 0.22 s after X (MR1500 was 5 ms: a stand-in card woken 5 ms
    # late read both in one read of the done register, one "!\x03", PC48 §7.3.3)
    await r.send(b"AY VL20000 MR6000 GO ID AX MR-200 GO ID")
    await poll(r, b"AA RP", 3)
    assert {await r.marker(), await r.marker()} == {b"!\x01\n", b"!\x02\n"}
    if model.startswith("PCIX"):
        for query in (b"AX ?VL", b"PP", b"AX ?AC", b"AX RU", b"AX RA"):
            assert await r.ask(query)
    else:
        for query in (b"AX RQ", b"AX RC", b"AX RU", b"AX RA", b"AX RE"):
            assert await r.ask(query)
    assert await r.ask(b"AX MR99999999999;") == b"#\n"  # out of range


def stage(tmp_path: Path, model: str) -> Path:
    config = tmp_path / "stage.toml"
    config.write_text(STAGE_TOML.format(model=model))
    return config


def replay_main(*argv: str) -> int:
    parser = argparse.ArgumentParser(prog="omsd")
    add_replay_parser(parser.add_subparsers(dest="command"))
    return run_replay(parser.parse_args(["replay", *argv]))


@pytest.mark.parametrize("model", MODELS)
async def test_a_recorded_session_replays_with_no_difference(tmp_path: Path, model: str) -> None:
    card_log = tmp_path / "card.jsonl"
    async with rig(tmp_path, model, card_log=card_log) as r:
        await session(r, model)
    result = replay_file(r.log)
    assert result.ok, result.report()
    assert (result.counts.answers, result.counts.events) == (24, 6)
    assert_replays(r.log)  # the one-line form of the same
    # the header names the card as the recorder was told, with its world
    header = json.loads(r.log.read_text().splitlines()[0])
    assert header["kind"] == "header" and header["model"] == model
    assert header["clock"] == "monotonic" and header["to"].startswith("tcp:127.0.0.1:")
    assert header["world"]["X"] == {"negative_limit": -500, "positive_limit": 60500,
                                    "home_low": 0, "home_high": 100}  # fmt: skip
    # the stand-in's own traffic log: the same session, seen by the card; the world from the
    # configuration (a log has no header), the model from its "serving" line
    result = replay_file(card_log, config=stage(tmp_path, model))
    assert result.ok, result.report()
    assert_replays(card_log, config=stage(tmp_path, model))


@pytest.mark.parametrize("model", MODELS)
async def test_the_recorder_passes_every_byte_unchanged(tmp_path: Path, model: str) -> None:
    """What the client read is exactly what the recording says the card sent, and what the card
    received (its own log) exactly what the client wrote."""
    card_log = tmp_path / "card.jsonl"
    async with rig(tmp_path, model, card_log=card_log) as r:
        await r.send(b"AX VL4000 MR400 GO ID \x00\xff\x19 WY")
        await r.marker()
        await r.ask(b"RP")
        await asyncio.sleep(0.05)
        received = bytes(r.received)
    lines = [json.loads(line) for line in r.log.read_text().splitlines()]
    out = b"".join(bytes.fromhex(x["hex"]) for x in lines if x.get("dir") == "out")
    sent = b"".join(bytes.fromhex(x["hex"]) for x in lines if x.get("dir") == "in")
    assert out == received
    assert sent == b"AX VL4000 MR400 GO ID \x00\xff\x19 WYRP"
    card = [json.loads(line) for line in card_log.read_text().splitlines()]
    assert b"".join(bytes.fromhex(x["hex"]) for x in card if x.get("dir") == "in") == sent
    assert b"".join(bytes.fromhex(x["hex"]) for x in card if x.get("dir") == "out") == out


def edit(path: Path, old: bytes, new: bytes, after: int = 0) -> Path:
    """A copy of the recording with the first card output ``old`` (after line ``after``)
    replaced by ``new``."""
    lines = path.read_text().splitlines()
    for i, line in enumerate(lines):
        record = json.loads(line)
        if i >= after and record.get("dir") == "out" and bytes.fromhex(record["hex"]) == old:
            record["data"] = new.decode("latin-1")
            record["hex"] = new.hex()
            lines[i] = json.dumps(record)
            break
    else:
        raise AssertionError(f"no {old!r} in {path}")
    edited = path.with_name("edited.jsonl")
    edited.write_text("\n".join(lines) + "\n")
    return edited


async def test_an_edited_recording_is_caught_with_the_right_row(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    async with rig(tmp_path, "PC48-4E") as r:
        await session(r, "PC48-4E")
    assert replay_main(str(r.log)) == 0
    capsys.readouterr()
    # a status changed: the limit flag gone from the QA after the jog
    edited = edit(r.log, b"MDLN\n", b"MDNN\n")
    assert replay_main(str(edited)) == 1
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 3, out  # the head, one row, the summary
    assert out[0].split() == ["time", "command", "card", "said", "omsd", "said"]
    assert out[1].split()[1:] == ["AX", "QA", "MDNN<LF>", "MDLN<LF>"]
    assert out[2].startswith("1 difference: ")
    # a done marker naming the wrong axis
    edited = edit(r.log, b"!\x01\n", b"!\x02\n")
    assert replay_main(str(edited), "--json") == 1
    report = json.loads(capsys.readouterr().out)
    assert not report["ok"] and len(report["differences"]) == 1
    row = report["differences"][0]
    assert (row["card"], row["omsd"], row["command"]) == ("!^B<LF>", "!^A<LF>", "RP")
    assert row["what"] == "text" and row["card_time"] == pytest.approx(row["omsd_time"], abs=0.02)
    # a position read at rest, off by one step: exact at rest
    lines = r.log.read_text().splitlines()
    done = next(i for i, line in enumerate(lines) if '"hex": "21010a"' in line)
    edited = edit(r.log, b"2000\n", b"2001\n", after=done)
    result = replay_file(edited)
    assert [(d.command, d.card, d.omsd) for d in result.differences] == [
        (b"RP", b"2001\n", b"2000\n")
    ]
    with pytest.raises(AssertionError, match="2001<LF>"):
        assert_replays(edited)


async def test_positions_read_during_motion_are_compared_within_the_tolerance(
    tmp_path: Path,
) -> None:
    async with rig(tmp_path, "PC48-4E") as r:
        await r.send(b"AX VL5000 AC50000 MR3000 GO ID")
        moving = await poll(r, b"RP", 4)
        await r.marker()
    value = moving[1]
    off = str(int(value) + 40).encode() + b"\n"  # 40 steps: within 2 + 0.02 s x 5000 steps/s
    assert replay_file(edit(r.log, value, off)).ok
    far = str(int(value) + 500).encode() + b"\n"  # beyond
    (row,) = replay_file(edit(r.log, value, far)).differences
    assert (row.command, row.card, row.omsd, row.what) == (b"RP", far, row.omsd, "number")
    assert abs(int(row.omsd or b"0") - int(value)) < 40


async def test_a_raw_link_session_replays(tmp_path: Path) -> None:
    """The board's own stream (EPICS' way): framed replies, a lone # for an error."""
    async with rig(tmp_path, "PC48-4E", link="raw") as r:
        assert await r.ask(b"WY") == b"\n\rPC48 ver 3.00-4\n\r"
        await r.send(b"AX VL5000 MR1000 GO")
        await poll(r, b"RP", 3)
        assert await r.ask(b"XQ") == b"#"
        await asyncio.sleep(0.25)
        assert await r.ask(b"AX QA") == b"\n\r\rPNNN\n\r\r"
    result = replay_file(r.log)
    assert result.ok and result.card.link == "raw", result.report()
    (row,) = replay_file(edit(r.log, b"\n\r\rPNNN\n\r\r", b"\n\r\rPDNN\n\r\r")).differences
    assert (row.command, row.card) == (b"AX QA", b"\n\r\rPDNN\n\r\r")


BAD_FILES = {
    "empty.jsonl": ("", "no traffic in the file"),
    "text.jsonl": ("WY\nPC48 ver 3.00-4\n", "text.jsonl:1: not a JSON object"),
    "list.jsonl": ("[1, 2]\n{}\n", "list.jsonl:1: not a record"),
    # json's recursion ran out of stack: a RecursionError's traceback, exit status 1
    "deep.jsonl": ("[" * 100000 + "\n{}\n", "deep.jsonl:1: not a JSON object: nested too deeply"),
    "untimed.jsonl": ('{"kind": "traffic", "dir": "in"}\n{}\n', "untimed.jsonl:1: traffic"),
    "header2.jsonl": (
        '{"t": 0, "kind": "info", "message": "x"}\n{"t": 0, "kind": "header", "format": 1}\n',
        "header2.jsonl:2: a header, but not on the first line",
    ),
    "future.jsonl": (
        '{"t": 0, "kind": "header", "format": 99, "clock": "monotonic", "model": "PC48-4E"}\n',
        "future.jsonl:1: a recording of format 99",
    ),
    "model.jsonl": (
        '{"t": 0, "kind": "header", "format": 1, "clock": "monotonic", "model": "PC99"}\n',
        "model.jsonl:1: header: unknown board model 'PC99'",
    ),
    "nomodel.jsonl": (
        '{"t": 0, "kind": "traffic", "board": "b", "endpoint": "e", "dir": "in", "data": "",'
        ' "hex": "5759"}\n',
        "no 'serving' line says the model of board b: give --model or --config",
    ),
}


@pytest.mark.parametrize("name", sorted(BAD_FILES))
def test_a_file_that_is_no_recording_exits_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    text, message = BAD_FILES[name]
    path = tmp_path / name
    path.write_text(text)
    assert replay_main(str(path)) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("omsd replay: ") and captured.err.count("\n") == 1
    assert message in captured.err


def test_options_that_make_no_replay_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "missing.jsonl"
    assert replay_main(str(path)) == 2
    assert "cannot read" in capsys.readouterr().err
    path.write_text(
        '{"t": 0, "kind": "traffic", "board": "b", "endpoint": "e", "dir": "in", "data": "WY",'
        ' "hex": "5759"}\n'
    )
    assert replay_main(str(path), "--model", "PC99") == 2
    assert "--model: unknown board model 'PC99'" in capsys.readouterr().err
    assert replay_main(str(path), "--model", "PC48-4E", "--board", "other") == 2
    assert "no traffic of board other (it has b)" in capsys.readouterr().err
    assert replay_main(str(path), "--model", "PC48-4E", "--eos", "zz") == 2
    assert "--eos: expected a character code in hex" in capsys.readouterr().err
    assert replay_main(str(path), "--config", str(tmp_path / "none.toml")) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert replay_main(str(path), "--model", "PC48-4E") == 1  # the card did not answer WY
    assert "(nothing)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("header", "options", "message"),
    [
        # a board of a configuration with a Z axis, replayed through a model without one
        ({"world": {"Z": {"positive_limit": 600}}}, ("--model", "PC48-2E"), "no axis ['Z']"),
        ({"inputs": {"40": True}}, ("--model", "PC48-2E"), "no I/O bit 40"),
        ({"encoders": "XYZT"}, ("--model", "PC48-2E"), "has no axis TZ"),
        ({"world": {"Q": {"home_low": 5}}}, (), "no axis ['Q']"),
    ],
)
def test_a_world_that_does_not_fit_the_model_exits_2_with_one_line(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    header: dict[str, object],
    options: tuple[str, ...],
    message: str,
) -> None:
    # A recording's header (or --config's board) describes the world of a PC48-4E; replayed as
    # another model (--model) whose axes or I/O bits it names do not exist. It used to end in a
    # ValueError traceback from the board's construction, exit status 1.
    path = tmp_path / "run.jsonl"
    first = {"t": 0.0, "kind": "header", "format": 1, "clock": "monotonic", "model": "PC48-4E"}
    path.write_text(
        json.dumps({**first, **header})
        + '\n{"t": 0.5, "kind": "traffic", "board": "card", "endpoint": "e", "dir": "in",'
        ' "data": "WY", "hex": "5759"}\n'
    )
    assert replay_main(str(path), *options) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and captured.err.count("\n") == 1
    assert captured.err.startswith("omsd replay: ") and message in captured.err


def test_a_daemon_restarted_on_the_same_log_replays_from_power_up(tmp_path: Path) -> None:
    # omsd appends to its --log: a daemon restarted (systemd's Restart= after a crash, or by
    # hand) on the same file starts its board at power-up, and its serving line says so. The
    # replay carried the first run's board on: 'AX RP' answered 0 by the new daemon was
    # replayed as 4000, one difference in a log omsd itself had written.
    import io

    from omsd.telemetry.traffic import Direction, TrafficLog

    path = tmp_path / "traffic.jsonl"
    first, second = "tcp:127.0.0.1:7001 #1 (a)", "tcp:127.0.0.1:7001 #1 (b)"
    for t, lines in (
        (100.0, [(first, b"AX LP4000 RP\n", b"4000\n")]),
        (200.0, [(second, b"AX RP\n", b"0\n"), (second, b"LP-7 RP\n", b"-7\n")]),
    ):
        with TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda t=t: t) as log:
            log.info("serving xy PC48-4E driver tcp 127.0.0.1:7001")
            for k, (endpoint, command, answer) in enumerate(lines):
                log.traffic(t + 1 + k, "xy", endpoint, Direction.IN, command)
                log.traffic(t + 1.001 + k, "xy", endpoint, Direction.OUT, answer)
            log.info("stopped")
    result = replay_file(path)
    assert result.ok, result.report()
    assert result.counts.answers == 3


def test_a_power_cycle_from_the_control_api_is_replayed(tmp_path: Path) -> None:
    # 'omsd ctl reset' power-cycles the board under a connected client and the log says so
    # ('xy: power cycled (control API)'); the replay went on with the board as it was: 'AX RP'
    # answered 0 after the reset was replayed as 4000
    import io

    from omsd.telemetry.traffic import Direction, TrafficLog

    path = tmp_path / "traffic.jsonl"
    client = "tcp:127.0.0.1:7001 #1 (a)"
    with TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda: 100.0) as log:
        log.info("serving xy PC48-4E driver tcp 127.0.0.1:7001")
        log.traffic(101.0, "xy", client, Direction.IN, b"AX LP4000 RP\n")
        log.traffic(101.001, "xy", client, Direction.OUT, b"4000\n")
    with TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda: 102.0) as log:
        log.warning("xy: power cycled (control API)")
        log.traffic(103.0, "xy", client, Direction.IN, b"AX RP\n")
        log.traffic(103.001, "xy", client, Direction.OUT, b"0\n")
    result = replay_file(path)
    assert result.ok, result.report()
    assert result.counts.answers == 2
    # the words the replay looks for are those the control server logs
    import inspect

    from omsd.control import server
    from omsd.recording.emulate import POWER_CYCLED

    assert f'log.warning(f"{{service.name}}: {POWER_CYCLED}")' in inspect.getsource(server)


def test_a_recording_replays_as_a_board_of_a_configuration_of_several(tmp_path: Path) -> None:
    # README: 'omsd replay FILE builds the board the header names (or --model, --config FILE
    # [--board NAME] ...)'. A card recorded without --config (its board is 'card') replayed as
    # board xy of the lab's file of two boards: --board xy was taken for the traffic's board
    # too, 'no traffic of board xy (it has card)', exit 2, and without it 'several boards'.
    path = tmp_path / "run.jsonl"
    head = {"t": 0.0, "kind": "header", "format": 1, "clock": "monotonic", "model": "PC48-4E"}
    path.write_text(
        json.dumps({**head, "board": "card"})
        + '\n{"t": 0.5, "kind": "traffic", "board": "card", "endpoint": "e", "dir": "in",'
        ' "data": "AX RP\\n", "hex": "41582052500a"}'
        + '\n{"t": 0.501, "kind": "traffic", "board": "card", "endpoint": "e", "dir": "out",'
        ' "data": "0\\n", "hex": "300a"}\n'
    )
    config = tmp_path / "lab.toml"
    config.write_text(
        '[[board]]\nname = "z"\nmodel = "PCIX-400"\ntcp = "127.0.0.1:0"\n'
        '[[board]]\nname = "xy"\nmodel = "PC48-4E"\ntcp = "127.0.0.1:0"\n'
        "[board.axes.X]\nstart_position = 5\n"
    )
    result = replay_file(path, config=config, board="xy")
    assert result.card.name == "xy" and result.card.model == "PC48-4E"
    assert result.card.world["X"].start_position == 5
    assert result.ok, result.report()
    # without --config, --board names the traffic's board, which a recording has one of
    with pytest.raises(RecordingError, match=r"no traffic of board xy \(it has card\)"):
        replay_file(path, board="xy")
