"""The recording file (:mod:`omsd.recording.format`): written and read back, and the daemon's
own ``--log`` files read as recordings."""

from __future__ import annotations

import io
import json
import os
import stat
import threading
import time
from pathlib import Path

import pytest

from omsd.board import AxisWorld, LimitWiring, SwitchType
from omsd.config import BoardConfig
from omsd.recording import format as format_module
from omsd.recording.format import (
    Recording,
    RecordingError,
    RecordingWriter,
    board_from_record,
    board_record,
    cut_short,
    parse_eos,
    read_recording,
)
from omsd.telemetry.lines import traffic_json
from omsd.telemetry.traffic import Direction, TrafficLog

BOARD = BoardConfig(
    name="xy",
    model="PCIX-400",
    link="raw",
    eos=0x0D,
    buffer_size=512,
    world={
        "X": AxisWorld(negative_limit=-500, home_switch=SwitchType.NORMALLY_CLOSED),
        "Y": AxisWorld(limit_switches=LimitWiring.NORMALLY_CLOSED, encoder_index=7),
    },
    inputs={3: True},
    firmware="1.30",
    max_queries=False,
)


def test_a_board_goes_into_a_header_and_comes_back() -> None:
    record = board_record(BOARD)
    assert record["model"] == "PCIX-400" and record["eos"] == "0D"
    # only what differs from the default world is written, enums by value
    assert record["world"] == {
        "X": {"negative_limit": -500, "home_switch": "normally_closed"},
        "Y": {"limit_switches": "normally_closed", "encoder_index": 7},
    }
    back = board_from_record(json.loads(json.dumps(record)))
    assert back == BOARD
    assert board_from_record({"model": "pc48-4e"}) == BoardConfig(name="card", model="PC48-4E")


@pytest.mark.parametrize(
    ("record", "message"),
    [
        ({}, "header: no model"),
        ({"model": "PC99"}, "unknown board model 'PC99'"),
        ({"model": "PC48-4E", "link": "serial"}, "link 'serial': expected one of driver, raw"),
        ({"model": "PC48-4E", "eos": "GG"}, "expected a character code in hex"),
        ({"model": "PC48-4E", "buffer_size": 3}, "buffer_size 3: expected 16..32767"),
        ({"model": "PC48-4E", "world": {"X": {"colour": 1}}}, "world or inputs"),
    ],
)
def test_a_header_that_makes_no_board_is_one_line(record: dict[str, object], message: str) -> None:
    with pytest.raises(RecordingError, match=r"^header: .*") as info:
        board_from_record(record)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_eos_is_hex_or_a_number() -> None:
    assert parse_eos("0A") == parse_eos("0x0a") == parse_eos(10) == 10
    with pytest.raises(RecordingError, match=r"00\.\.FF"):
        parse_eos("100")


def write(path: Path) -> None:
    writer = RecordingWriter(path)
    writer.header(100.0, 1.7e9, BOARD, to="tcp:127.0.0.1:7048", line=None, listen="tcp:x:1")
    writer.traffic(100.5, "xy", "tcp:x:1 #1", Direction.IN, b"AX RP\x00\xff")
    writer.traffic(100.75, "xy", "tcp:x:1 #1", Direction.OUT, b"0\n\r")
    writer.message(101.0, "info", "stopped")
    writer.close()


def test_a_recording_is_written_and_read_back(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    write(path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    lines = [json.loads(line) for line in path.read_text().splitlines()]
    assert lines[0]["kind"] == "header" and lines[0]["clock"] == "monotonic"
    assert lines[1] == {
        "t": 100.5,
        "kind": "traffic",
        "board": "xy",
        "endpoint": "tcp:x:1 #1",
        "dir": "in",
        "data": "AX RP\x00\xff",
        "hex": "4158205250" + "00ff",
    }
    recording = read_recording(path)
    assert recording.header is not None and recording.one_stream
    assert board_from_record(recording.header) == BOARD
    assert [(c.time, c.direction, c.data) for c in recording.chunks] == [
        (0.0, Direction.IN, b"AX RP\x00\xff"),
        (0.25, Direction.OUT, b"0\n\r"),
    ]
    assert recording.notes == [(0.5, "info", "stopped")] and recording.duration == 0.5
    assert recording.line is None and not recording.truncated


def test_a_recording_is_one_session_a_full_file_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    write(path)
    with pytest.raises(FileExistsError, match="is not empty: a recording is one session"):
        RecordingWriter(path)
    empty = tmp_path / "empty.jsonl"
    empty.touch()
    RecordingWriter(empty).close()  # an empty file is fine


def test_a_last_line_cut_short_is_left_out_and_said(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    write(path)
    with path.open("a") as f:
        f.write('{"t": 102.0, "kind": "traff')
    recording = read_recording(path)
    assert recording.truncated and len(recording.chunks) == 2
    lines = path.read_text().splitlines()
    lines.insert(2, "{not json")
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"session.jsonl:3: not a JSON object"):
        read_recording(path)


def daemon_log(path: Path) -> None:
    """A daemon's --log file as the daemon writes it: wall-clock times, two boards, several
    clients, the serving lines and the session ends."""
    clock = iter([1.7e9 + i for i in range(100)])
    log = TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda: next(clock))
    log.info("serving xy PC48-4E driver tcp 127.0.0.1:7001")
    log.info("serving z PCIX-400 raw tcp 127.0.0.1:7002")
    log.traffic(1.7e9 + 10, "xy", "tcp:127.0.0.1:7001 #1 (a)", Direction.IN, b"WY")
    log.traffic(1.7e9 + 10.5, "z", "tcp:127.0.0.1:7002 #2 (b)", Direction.IN, b"RP")
    log.traffic(1.7e9 + 11, "xy", "tcp:127.0.0.1:7001 #1 (a)", Direction.OUT, b"PC48\n")
    log.info("xy: tcp:127.0.0.1:7001 #1 (a) disconnected")
    log.traffic(1.7e9 + 12, "xy", "(gone: tcp:127.0.0.1:7001 #1 (a))", Direction.OUT, b"!\x01\n")
    log.event(1.7e9 + 12, "xy", "done X")
    log.close()


def test_a_daemon_log_is_read_board_by_board(tmp_path: Path) -> None:
    path = tmp_path / "traffic.jsonl"
    daemon_log(path)
    with pytest.raises(RecordingError, match=r"several boards \(xy, z\): choose one with --board"):
        read_recording(path)
    with pytest.raises(RecordingError, match=r"no traffic of board q \(it has xy, z\)"):
        read_recording(path, "q")
    recording = read_recording(path, "xy")
    assert recording.header is None and not recording.one_stream
    assert recording.served == {"xy": ("PC48-4E", "driver"), "z": ("PCIX-400", "raw")}
    assert [(c.time, c.data, c.endpoint) for c in recording.chunks] == [
        (0.0, b"WY", "tcp:127.0.0.1:7001 #1 (a)"),
        (1.0, b"PC48\n", "tcp:127.0.0.1:7001 #1 (a)"),
        (2.0, b"!\x01\n", "(gone: tcp:127.0.0.1:7001 #1 (a))"),
    ]
    assert ("info", "xy: tcp:127.0.0.1:7001 #1 (a) disconnected") in [
        (kind, text) for _, kind, text in recording.notes
    ]
    assert [c.data for c in read_recording(path, "z").chunks] == [b"RP"]


def test_what_is_not_a_recording_file_is_refused_without_reading_it(tmp_path: Path) -> None:
    # a device or a directory is no recording: one line, at once; /dev/zero used to be read
    # without end
    for path, what in (("/dev/zero", "a device"), (tmp_path, "a directory")):
        with pytest.raises(RecordingError, match=f"not a recording: {what}, not a file") as caught:
            read_recording(path)
        assert "\n" not in str(caught.value)
    # a named pipe with no writer is opened without waiting for one, and reads as empty
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(RecordingError, match="no traffic in the file"):
        read_recording(fifo)


def through_pipe(*writes: bytes, pause: float = 0.0) -> Recording:
    """``read_recording`` of a pipe's /dev/fd path (``omsd replay <(zcat run.jsonl.gz)``), its
    writer writing ``writes`` one after the other, ``pause`` seconds apart, then closing it."""
    r, w = os.pipe()

    def write_all() -> None:
        for k, data in enumerate(writes):
            if k:
                time.sleep(pause)
            os.write(w, data)
        os.close(w)

    writer = threading.Thread(target=write_all)
    writer.start()
    try:
        return read_recording(f"/dev/fd/{r}")
    finally:
        writer.join()
        os.close(r)


def test_a_recording_through_a_pipe_is_read(tmp_path: Path) -> None:
    # ``omsd replay <(zcat run.jsonl.gz)``: the shell gives a pipe's /dev/fd path
    path = tmp_path / "session.jsonl"
    write(path)
    expected = read_recording(path)
    got = through_pipe(path.read_bytes())
    assert got.chunks == expected.chunks and got.header == expected.header


def test_a_line_longer_than_any_record_is_refused_without_reading_it_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # a huge file of NULs (or of anything without a line end) is read at most one longest line
    # far: the limit shortened here, the file a sparse 64 MiB of NULs
    monkeypatch.setattr(format_module, "MAX_LINE", 4096, raising=False)
    zeros = tmp_path / "zeros.jsonl"
    with zeros.open("wb") as f:
        f.truncate(64 << 20)
    with pytest.raises(RecordingError, match=r"zeros.jsonl:1: not a recording: a line longer"):
        read_recording(zeros)
    path = tmp_path / "session.jsonl"
    write(path)
    lines = path.read_text().splitlines()
    lines.insert(1, '{"t": 1.0, "kind": "info", "message": "' + "x" * 5000 + '"}')
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"session.jsonl:2: not a recording: a line longer"):
        read_recording(path)


def test_binary_garbage_is_one_line(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.bin"
    garbage.write_bytes(bytes(range(256)) * 64 + b"\n" + bytes(range(256)) * 64)
    with pytest.raises(RecordingError, match=r"garbage.bin:1: not a JSON object") as caught:
        read_recording(garbage)
    assert "\n" not in str(caught.value)
    # no line cut short of a record either: it said "no traffic in the file" (the one line taken
    # for the last line of a record, cut short)
    garbage.write_bytes(b"\xff\xfe\x00" * 1000)
    with pytest.raises(RecordingError, match=r"garbage.bin:1: not a JSON object"):
        read_recording(garbage)


def test_a_line_cut_by_a_crash_then_ended_by_the_next_daemon_is_left_out(tmp_path: Path) -> None:
    # A daemon killed while writing a line; the next one, appending to the same --log, ends the
    # cut line before its own (TrafficLog: "the first line ... of the next daemon is never glued
    # to a cut one"). The cut line is then in the middle of the file, with a line end: it used to
    # stop the replay, 'FILE:3: not a JSON object: Invalid control character at', exit 2.
    path = tmp_path / "traffic.jsonl"
    clock = iter([1.7e9 + i for i in range(100)])
    with TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda: next(clock)) as log:
        log.info("serving xy PC48-4E driver tcp 127.0.0.1:7001")
        log.traffic(1.7e9 + 10, "xy", "tcp:127.0.0.1:7001 #1 (a)", Direction.IN, b"WY")
        log.traffic(1.7e9 + 11, "xy", "tcp:127.0.0.1:7001 #1 (a)", Direction.OUT, b"PC48\n")
    with path.open("r+b") as f:
        f.truncate(path.stat().st_size - 9)  # killed 9 characters before the end of its line
    with TrafficLog("off", file=path, stream=io.StringIO(), clock=lambda: 1.7e9 + 20) as log:
        log.info("serving xy PC48-4E driver tcp 127.0.0.1:7001")
        log.traffic(1.7e9 + 21, "xy", "tcp:127.0.0.1:7001 #1 (b)", Direction.IN, b"RP")
    recording = read_recording(path)
    assert [c.data for c in recording.chunks] == [b"WY", b"RP"]
    assert recording.cut == [3] and recording.truncated
    from omsd.recording.replay import replay_file

    assert "note: line 3 of " in replay_file(path).summary()


def cut_prefixes() -> list[str]:
    """Every way a writer can be cut short in the middle of a record: each prefix of lines
    that hold escapes, negative numbers, exponents, null, true."""
    records = [
        traffic_json(1.7e9 + 0.125, "xy", "tcp #1", "out", bytes(range(256))),
        traffic_json(1e-05, "b", "pty", "in", b'\\"\n\r\xff'),
        json.dumps({"t": 1.5, "kind": "header", "format": 1, "line": None, "x": -1.5e-7}),
        json.dumps({"t": 2, "kind": "info", "message": "w", "flag": True, "other": False}),
    ]
    return [r.rstrip("\n")[:k] for r in records for k in range(1, len(r.rstrip("\n")))]


def test_every_prefix_of_a_record_is_a_line_cut_short() -> None:
    for prefix in cut_prefixes():
        for text in (prefix, prefix + "\n"):  # the last line, or one the next daemon ended
            with pytest.raises(json.JSONDecodeError) as caught:
                json.loads(text)
            assert cut_short(text, caught.value), text


@pytest.mark.parametrize("cut_at", ["middle", "end", "end without its line end"])
def test_a_line_cut_short_is_left_out_wherever_it_is(tmp_path: Path, cut_at: str) -> None:
    path = tmp_path / "session.jsonl"
    write(path)
    lines = path.read_text().splitlines(keepends=True)
    for prefix in cut_prefixes()[::37]:
        cut = prefix if cut_at == "end without its line end" else prefix + "\n"
        text = [*lines[:2], cut, *lines[2:]] if cut_at == "middle" else [*lines, cut]
        path.write_text("".join(text))
        recording = read_recording(path)
        assert len(recording.chunks) == 2, prefix
        assert recording.cut == [3 if cut_at == "middle" else 5], prefix


@pytest.mark.parametrize(
    "bad", ["{bad", "{not json", '{"t": 1} junk', "garbage", '{"t": 1,, }', "[]x", '{"t": 1.x}']
)
@pytest.mark.parametrize("line_end", ["\n", ""])
def test_a_line_that_is_not_json_is_an_error_even_the_last(
    tmp_path: Path, bad: str, line_end: str
) -> None:
    # only a prefix of a record is a line cut short; wrong JSON on the last line was taken for
    # one, left out with a note, and the replay went on with exit status 0
    path = tmp_path / "session.jsonl"
    write(path)
    with path.open("a") as f:
        f.write(bad + line_end)
    with pytest.raises(RecordingError, match=r"session.jsonl:5: not a JSON object"):
        read_recording(path)


def test_a_compressed_log_is_read_as_it_is(tmp_path: Path) -> None:
    # logrotate's compress leaves traffic.jsonl.1.gz: it was 'not a JSON object: Expecting
    # value' (the gzip bytes read as text), and only <(zcat FILE) replayed it
    import gzip

    path = tmp_path / "session.jsonl"
    write(path)
    expected = read_recording(path)
    packed = tmp_path / "session.jsonl.gz"
    packed.write_bytes(gzip.compress(path.read_bytes()))
    got = read_recording(packed)
    assert got.chunks == expected.chunks and got.header == expected.header and not got.cut
    # through a pipe too (cat session.jsonl.gz | omsd replay /dev/stdin)
    assert through_pipe(packed.read_bytes()).chunks == expected.chunks
    # a compressed file cut short (a copy or a compression that was stopped): what is there
    long = tmp_path / "long.jsonl"
    writer = RecordingWriter(long)
    writer.header(100.0, 1.7e9, BOARD, to="tcp:127.0.0.1:7048", line=None, listen="tcp:x:1")
    for k in range(400):
        writer.traffic(100.5 + k / 7, "xy", "tcp:x:1 #1", Direction.IN, b"AX MR%d GO" % k)
    writer.close()
    whole = gzip.compress(long.read_bytes())
    packed.write_bytes(whole[: len(whole) // 2])
    recording = read_recording(packed)
    assert 0 < len(recording.chunks) < 400 and recording.truncated
    # not gzip after its magic: one line
    packed.write_bytes(b"\x1f\x8b" + bytes(range(256)))
    with pytest.raises(RecordingError, match=r"^cannot read .*session.jsonl.gz: ") as caught:
        read_recording(packed)
    assert "\n" not in str(caught.value)


def test_a_compressed_pipe_whose_first_read_is_one_byte_is_read_as_gzip(tmp_path: Path) -> None:
    # a pipe gives what its writer has written so far: the magic's first byte alone (a writer
    # that flushes as it goes, a slow ssh) was taken for no gzip and the whole file read as text,
    # 'not a JSON object'. The magic is read in as many reads as it comes in.
    import gzip

    path = tmp_path / "session.jsonl"
    write(path)
    expected = read_recording(path)
    packed = gzip.compress(path.read_bytes())
    assert through_pipe(packed[:1], packed[1:], pause=0.3).chunks == expected.chunks
    # a file of one byte, that byte the magic's first: read as text (blank), not a gzip error
    one = tmp_path / "one.jsonl"
    one.write_bytes(b"\x1f")
    with pytest.raises(RecordingError, match=r"one.jsonl: no traffic in the file"):
        read_recording(one)
