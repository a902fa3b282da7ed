"""``omsd console`` with standard input a file or a pipe (issue 14): the commands are sent, the
replies printed, and it exits 0 at the end of the input once the board has answered; before,
a file on standard input raised a traceback (epoll cannot wait on a regular file)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from daemon.process import daemon_env

WY = b"\n\rPC48 ver 3.00-4\n\r"  # PC48 §6.13: the reply "surrounded by line feeds and returns"
COMMANDS = b"WY\nAX VL100000 MR2000 GO ID\nRP\n"


def console(*args: str, stdin: object, timeout: float = 20.0) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(
        [sys.executable, "-m", "omsd", "console", *args],
        stdin=stdin,  # type: ignore[arg-type]
        capture_output=True,
        timeout=timeout,
        env=daemon_env(),
    )


def test_commands_from_a_file(tmp_path: Path) -> None:
    path = tmp_path / "commands.txt"
    path.write_bytes(COMMANDS)
    with path.open("rb") as f:
        done = console(stdin=f)
    assert done.returncode == 0, done.stderr
    # RP is immediate: it answers before the move has run (PC48 §6.13 "not queued")
    assert done.stdout == WY + b"\n\r0\n\r"
    assert done.stderr == b"[done (register 01)]\n"  # the ID of the move, once it is done


def test_commands_from_a_pipe() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "omsd", "console"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=daemon_env(),
    )
    out, err = proc.communicate(COMMANDS, timeout=20)
    assert proc.returncode == 0, err
    assert out == WY + b"\n\r0\n\r"
    assert err == b"[done (register 01)]\n"


def test_a_pipe_is_answered_as_it_is_fed() -> None:
    """A pipe is read as it comes: WY is answered before the writer closes its end."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "omsd", "console"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=daemon_env(),
    )
    assert proc.stdin is not None and proc.stdout is not None
    try:
        proc.stdin.write(b"WY")
        proc.stdin.flush()
        assert os.read(proc.stdout.fileno(), 100) == WY  # WY needs no line end
        proc.stdin.close()
        assert proc.wait(timeout=20) == 0
    finally:
        proc.kill()
        proc.wait()


def test_empty_input_exits_at_once() -> None:
    started = time.monotonic()
    done = console(stdin=subprocess.DEVNULL)
    assert (done.returncode, done.stdout, done.stderr) == (0, b"", b"")
    assert time.monotonic() - started < 10


def test_motion_that_does_not_end_is_given_wait_seconds(tmp_path: Path) -> None:
    path = tmp_path / "jog.txt"
    path.write_bytes(b"AX JG1000\n")
    with path.open("rb") as f:
        done = console("--wait", "0.2", stdin=f)
    assert done.returncode == 0
    assert done.stderr == b"[end of input: stopped waiting after 0.2 s, axis X still moving]\n"


def test_a_command_error_is_noted_and_the_run_goes_on(tmp_path: Path) -> None:
    path = tmp_path / "bad.txt"
    path.write_bytes(b"PL WY\n")  # PL is not a PC48 command (the manual's §7.3.4 file)
    with path.open("rb") as f:
        done = console(stdin=f)
    assert done.returncode == 0
    assert done.stdout == WY
    assert done.stderr.count(b"\n") == 1 and done.stderr.startswith(b"[command error")


def test_an_unknown_board_is_one_line_and_status_2() -> None:
    done = console("--board", "PC99", stdin=subprocess.DEVNULL)
    assert done.returncode == 2
    assert done.stderr.decode().startswith("omsd: --board: unknown board model 'PC99'")
    assert done.stderr.count(b"\n") == 1
