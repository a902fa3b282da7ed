"""``omsd record`` and ``omsd replay`` as commands (``python -m omsd.recording``, what ``omsd
record|replay`` runs): the endpoint line, one client at a time, SIGTERM and SIGINT stop it with a
complete file, a card that goes away ends it with status 1, bad options and places exit 2 with one
line; ``omsd replay`` of what was recorded, in text and JSON."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from omsd.recording.record import BUSY
from omsd.testing import Connection, OmsdBoards

TIMEOUT = 10.0
ROOT = Path(__file__).resolve().parents[2]


def recording(*args: str, **kwargs: object) -> subprocess.Popen[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NOTIFY_SOCKET", "JOURNAL_STREAM")}
    env["PYTHONUNBUFFERED"] = "1"
    return subprocess.Popen(
        [sys.executable, "-m", "omsd.recording", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=kwargs.get("cwd", ROOT),  # type: ignore[arg-type]
        start_new_session=True,
    )


@pytest.fixture
def processes() -> Iterator[list[subprocess.Popen[str]]]:
    started: list[subprocess.Popen[str]] = []
    try:
        yield started
    finally:
        for process in started:
            if process.poll() is None:
                process.kill()
            process.communicate(timeout=TIMEOUT)


def endpoint(process: subprocess.Popen[str]) -> tuple[str, int]:
    """The recorder's endpoint line: ``card PC48-4E driver tcp 127.0.0.1:40123``."""
    assert process.stdout is not None
    line = process.stdout.readline()
    name, _, _, kind, address = line.split()
    assert (name, kind) == ("card", "tcp"), line
    host, _, port = address.rpartition(":")
    return host, int(port)


def test_record_then_replay_on_the_command_line(
    omsd_boards: OmsdBoards, tmp_path: Path, processes: list[subprocess.Popen[str]]
) -> None:
    card = omsd_boards(card="PC48-4E")["card"]
    log = tmp_path / "run.jsonl"
    recorder = recording(
        "record", "--to", f"tcp:{card.host}:{card.port}", "--tcp", "0", "--log", str(log)
    )
    processes.append(recorder)
    host, port = endpoint(recorder)
    with Connection(host, port) as client:
        assert client.ask(b"WY") == b"PC48 ver 3.00-4"
        client.send(b"AX VL20000 MR2000 GO ID")
        assert client.read_until(b"\n") == b"!\x01\n"
        assert client.ask(b"RP") == b"2000"
        with socket.create_connection((host, port), timeout=TIMEOUT) as second:
            assert second.recv(100) == BUSY  # one client at a time
        assert client.ask(b"XQ") == b"#"
    recorder.send_signal(signal.SIGTERM)
    _, err = recorder.communicate(timeout=TIMEOUT)
    assert recorder.returncode == 0, err
    assert "recording the card on tcp:" in err and "refused" in err
    lines = [json.loads(line) for line in log.read_text().splitlines()]
    assert lines[0]["kind"] == "header" and lines[0]["model"] == "PC48-4E"
    assert lines[0]["link"] == "driver"  # the default with tcp:
    assert lines[-1] == {"t": lines[-1]["t"], "kind": "info", "message": "stopped"}
    replay = recording_run("replay", str(log))
    assert replay.returncode == 0, replay.stdout + replay.stderr
    assert replay.stdout.startswith("no differences: 3 answers and 1 marker over ")
    other = ["--json", "--model", "VS4-040"]
    replay = recording_run("replay", str(log), *other)
    assert replay.returncode == 1  # a VS4 answers WY otherwise
    report = json.loads(replay.stdout)
    assert report["model"] == "VS4-040" and report["differences"][0]["command"] == "WY"
    assert report["differences"][0]["card"] == "PC48 ver 3.00-4<LF>"


def test_sigint_stops_it_and_the_pty_link_goes(
    omsd_boards: OmsdBoards, tmp_path: Path, processes: list[subprocess.Popen[str]]
) -> None:
    card = omsd_boards(card="PCIX-400")["card"]
    link = tmp_path / "oms"
    recorder = recording(
        "record",
        "--to",
        f"tcp:{card.host}:{card.port}",
        "--pty",
        str(link),
        "--log",
        str(tmp_path / "run.jsonl"),
        "--model",
        "PCIX-400",
    )
    processes.append(recorder)
    assert recorder.stdout is not None
    line = recorder.stdout.readline()
    assert line.startswith(f"card PCIX-400 driver pty {link} -> /dev/pts/"), line
    assert link.is_symlink()
    recorder.send_signal(signal.SIGINT)
    _, err = recorder.communicate(timeout=TIMEOUT)
    assert recorder.returncode == 0, err
    assert not os.path.lexists(link)


def test_a_card_that_goes_away_ends_it_with_status_1(
    tmp_path: Path, processes: list[subprocess.Popen[str]]
) -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def card() -> None:  # answers one chunk, then is unplugged
        connection, _ = server.accept()
        with connection:
            connection.recv(100)
            connection.sendall(b"PC48 ver 3.00-4\n")
            connection.recv(100)

    thread = threading.Thread(target=card, daemon=True)
    thread.start()
    log = tmp_path / "run.jsonl"
    recorder = recording("record", "--to", f"tcp:127.0.0.1:{port}", "--tcp", "0", "--log", str(log))
    processes.append(recorder)
    host, number = endpoint(recorder)
    with Connection(host, number) as client:
        assert client.ask(b"WY") == b"PC48 ver 3.00-4"
        client.send(b"RP")
        assert client.at_eof()  # the application sees its connection close
    _, err = recorder.communicate(timeout=TIMEOUT)
    thread.join(TIMEOUT)
    server.close()
    assert recorder.returncode == 1
    assert f"the card on tcp:127.0.0.1:{port} went away (closed)" in err
    last = json.loads(log.read_text().splitlines()[-1])
    assert last["kind"] == "error" and "went away" in last["message"]


@pytest.fixture
def full_log(tmp_path: Path) -> Path:
    path = tmp_path / "full.jsonl"
    path.write_text("{}\n")
    return path


BAD = [
    (["--to", "bogus", "--tcp", "0"], "omsd record: --to: expected serial:PATH[,BAUD[,8N1]] or"),
    (["--to", "serial:/dev/x,fast", "--tcp", "0"], "--to: expected a baud rate, got 'fast'"),
    (["--to", "serial:/dev/x,9600,9Q1", "--tcp", "0"], "expected data bits, parity and stop"),
    (["--to", "tcp:127.0.0.1:1", "--tcp", "0"], "--to: cannot reach the card on tcp:127.0.0.1:1:"),
    (["--to", "serial:/nonexistent/tty", "--tcp", "0"], "--to: cannot open the card on serial:"),
    (["--to", "tcp:127.0.0.1:1", "--tcp", "abc"], "--tcp: expected [HOST:]PORT with PORT"),
    (["--to", "tcp:127.0.0.1:1", "--tcp", "0", "--model", "PC99"], "--model: unknown board"),
    (["--to", "tcp:127.0.0.1:1", "--pty", "/nonexistent/dir/oms"], "--pty: no directory"),
    (["--to", "tcp:127.0.0.1:1", "--tcp", "0", "--pty", "x"], "not allowed with argument"),
    # a board whose world names an axis the model given does not have: the header it would
    # write replays as no board (it was written, and the recording started)
    (
        [
            *("--to", "tcp:127.0.0.1:1", "--tcp", "0", "--config", "config/omsd.toml"),
            *("--board", "slits", "--model", "PC48-4E"),
        ],
        "board slits as a PC48-4E: no axis ['U'] on a PC48-4E",
    ),
]


def recording_run(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m omsd.recording ARGS``, run to its end with nothing on standard input."""
    return subprocess.run(
        [sys.executable, "-m", "omsd.recording", *args],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
        stdin=subprocess.DEVNULL,
    )


@pytest.mark.parametrize(("args", "message"), BAD, ids=[m for _, m in BAD])
def test_what_keeps_it_from_starting_is_one_line_and_status_2(
    tmp_path: Path, args: list[str], message: str
) -> None:
    log = tmp_path / "run.jsonl"
    result = recording_run("record", *args, "--log", str(log))
    assert result.returncode == 2
    assert result.stdout == ""
    assert message in result.stderr
    assert result.stderr.count("\n") == 1 or "usage:" in result.stderr
    assert not log.exists()  # nothing left behind


def test_a_recording_is_never_overwritten(omsd_boards: OmsdBoards, full_log: Path) -> None:
    card = omsd_boards(card="PC48-4E")["card"]
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "omsd.recording",
            "record",
            "--to",
            f"tcp:{card.host}:{card.port}",
            "--tcp",
            "0",
            "--log",
            str(full_log),
        ],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert result.returncode == 2
    assert result.stderr == (
        f"omsd record: --log: {full_log} is not empty: a recording is one session; remove it or"
        " name another file\n"
    )
    assert full_log.read_text() == "{}\n"


def test_a_client_that_stops_sending_gets_its_answers_then_is_closed(
    omsd_boards: OmsdBoards, tmp_path: Path, processes: list[subprocess.Popen[str]]
) -> None:
    """``nc -N``: the recorder keeps the connection while the card talks, for --linger after."""
    card = omsd_boards(card="PC48-4E")["card"]
    recorder = recording(
        "record", "--to", f"tcp:{card.host}:{card.port}", "--tcp", "0", "--linger", "0.5",
        "--log", str(tmp_path / "run.jsonl"),
    )  # fmt: skip
    processes.append(recorder)
    host, port = endpoint(recorder)
    with socket.create_connection((host, port), timeout=TIMEOUT) as client:
        client.sendall(b"WY AX VL5000 MR1000 GO ID")  # done 0.2 s later
        client.shutdown(socket.SHUT_WR)
        received = b""
        while data := client.recv(100):
            received += data
    assert received == b"PC48 ver 3.00-4\n!\x01\n"
    # the next client is served as the first was
    with Connection(host, port) as again:
        assert again.ask(b"RP") == b"1000"
    recorder.send_signal(signal.SIGTERM)
    _, err = recorder.communicate(timeout=TIMEOUT)
    assert recorder.returncode == 0, err


def test_the_help_quotes_the_recorders_default_linger() -> None:
    from omsd.recording import cli, record

    assert cli.DEFAULT_LINGER == record.DEFAULT_LINGER


def test_a_replay_of_a_device_is_one_line_and_status_2() -> None:
    # omsd replay /dev/zero used to read without end (and without bound of memory)
    result = recording_run("replay", "/dev/zero")
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == "omsd replay: /dev/zero: not a recording: a device, not a file\n"
