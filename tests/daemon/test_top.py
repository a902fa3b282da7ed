"""``omsd top`` against the real daemon (issue 18): one snapshot as text when standard output is
not a terminal; on a terminal (a pty of the test's, 100 columns by 30 lines) the live screen,
the keys, and the terminal put back as it was however it ends (``q``, SIGTERM, the daemon
going away).

What the screen shows is read from what ``omsd top`` writes to the pty, its escape sequences
taken out: rich redraws the whole screen each time, so the latest frame's text is all there."""

from __future__ import annotations

import fcntl
import os
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from .process import TIMEOUT, Daemon, Omsd, daemon_env, run_omsd, wait_for

CONFIG = """
[control]
socket = "{socket}"

[[board]]
name = "xy"
tcp = "127.0.0.1:0"
[board.axes.X]
negative_limit = -50000
positive_limit = 50000

[[board]]
name = "servo"
model = "PCIX-400"
link = "raw"
tcp = "127.0.0.1:0"
"""
ESCAPES = re.compile(rb"\x1b(\[[0-9;?]*[ -/]*[@-~]|\][^\x07]*\x07|[()][0-9A-Za-z]|[=>78])")


@pytest.fixture
def lab(omsd: Omsd, tmp_path: Path) -> Iterator[tuple[Daemon, Path]]:
    socket = tmp_path / "control.sock"
    daemon = omsd(config=CONFIG.format(socket=socket), expect=2)
    assert wait_for(socket.exists)
    yield daemon, socket


# -- not a terminal: one snapshot ----------------------------------------------------------------


def test_a_snapshot_when_standard_output_is_not_a_terminal(lab: tuple[Daemon, Path]) -> None:
    daemon, socket = lab
    done = run_omsd("top", "--socket", str(socket))
    assert done.returncode == 0 and done.stderr == ""
    lines = done.stdout.splitlines()
    assert lines[0] == "omsd top: 2 boards (xy, servo)"
    assert lines[2] == f"xy  PC48-4E  driver  tcp {':'.join(map(str, daemon.tcp('xy')))}"
    assert lines[5].split()[0] == "X" and lines[5].split()[-1] == "-50000..50000"
    assert "servo  PCIX-400  raw" in done.stdout
    only = run_omsd("top", "--socket", str(socket), "--board", "servo")
    assert only.returncode == 0 and "xy  PC48-4E" not in only.stdout
    assert "servo  PCIX-400" in only.stdout


def test_a_snapshot_into_head(lab: tuple[Daemon, Path]) -> None:
    _, socket = lab
    done = subprocess.run(
        [
            "bash",
            "-o",
            "pipefail",
            "-c",
            f"{sys.executable} -m omsd top --socket {socket} | head -1",
        ],
        capture_output=True,
        text=True,
        env=daemon_env(),
        timeout=TIMEOUT,
        check=False,
    )
    assert done.stdout == "omsd top: 2 boards (xy, servo)\n" and done.stderr == ""


def test_what_top_refuses(lab: tuple[Daemon, Path], tmp_path: Path) -> None:
    _, socket = lab
    done = run_omsd("top", "--socket", str(socket), "--board", "zz")
    assert (done.returncode, done.stderr) == (1, "omsd top: no board 'zz'; boards: xy, servo\n")
    gone = run_omsd("top", "--socket", str(tmp_path / "none.sock"))
    assert gone.returncode == 3
    assert gone.stderr.startswith(f"omsd top: cannot reach the daemon at {tmp_path}/none.sock")
    bad = run_omsd("top", "--rate", "0")
    assert bad.returncode == 2 and "expected above 0 and at most 50" in bad.stderr


# -- a terminal: the live view -------------------------------------------------------------------


class Terminal:
    """``omsd top`` on a pty of 100 x 30; what it writes is collected by a thread."""

    def __init__(self, *args: str) -> None:
        self.master, self.slave = os.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
        self.before = termios.tcgetattr(self.slave)
        env = {k: v for k, v in daemon_env().items() if k not in ("COLUMNS", "LINES", "NO_COLOR")}
        env["TERM"] = "xterm-256color"
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "omsd", "top", *args],
            stdin=self.slave,
            stdout=self.slave,
            stderr=self.slave,
            env=env,
            start_new_session=True,
        )
        self.output = bytearray()
        self.seen = 0  # what has been looked at already
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        while True:
            ready, _, _ = select.select([self.master], [], [], 0.1)
            if not ready:
                if self.proc.poll() is not None:
                    return
                continue
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            self.output += data

    def text(self) -> str:
        return ESCAPES.sub(b"", bytes(self.output)).decode("utf-8", errors="replace")

    def expect(self, *texts: str) -> str:
        """Wait until everything of ``texts`` has been drawn since the last look."""
        deadline = time.monotonic() + TIMEOUT
        while True:
            fresh = ESCAPES.sub(b"", bytes(self.output[self.seen :])).decode(errors="replace")
            if all(t in fresh for t in texts):
                self.seen = len(self.output)
                return fresh
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise AssertionError(f"not drawn: {texts}; the screen's end: {fresh[-1500:]}")
            time.sleep(0.02)

    def resize(self, lines: int, columns: int) -> None:
        self.seen = len(self.output)
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", lines, columns, 0, 0))
        os.kill(self.proc.pid, signal.SIGWINCH)  # no controlling terminal to send it

    def press(self, keys: bytes) -> None:
        self.seen = len(self.output)
        os.write(self.master, keys)

    def wait(self) -> int:
        status = self.proc.wait(TIMEOUT)
        self._reader.join(TIMEOUT)
        return status

    def restored(self) -> bool:
        return termios.tcgetattr(self.slave) == self.before

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(TIMEOUT)
        os.close(self.master)
        os.close(self.slave)


@pytest.fixture
def terminal() -> Iterator[list[Terminal]]:
    made: list[Terminal] = []
    try:
        yield made
    finally:
        for t in made:
            t.close()


def test_the_live_view_draws_follows_a_move_and_answers_the_keys(
    lab: tuple[Daemon, Path], terminal: list[Terminal]
) -> None:
    daemon, socket = lab
    top = Terminal("--socket", str(socket))
    terminal.append(top)
    top.expect("omsd top", "xy", "servo", "PCIX-400", "travel", "last events", "q: quit")
    assert b"\x1b[?1049h" in top.output  # the alternate screen
    assert not top.restored()  # keys one at a time meanwhile
    with daemon.connect("xy") as board:
        board.send(b"AX VL20000 MR10000 GO ID XQ")
        top.expect("moving X")
        top.expect("xy  done (register 01)", "command error: Unrecognized command: XQ")
    top.press(b"2")
    top.expect("servo  PCIX-400  raw  tcp")
    top.press(b"\x1b[D")  # left: back to xy
    screen = top.expect("xy  PC48-4E  driver  tcp")
    assert re.search(r"X +10000 +10000 +0 +idle +yes", screen), screen[-2000:]
    top.press(b"p")
    top.expect("PAUSED")
    top.resize(24, 80)  # drawn again at once, the travel's ends left out
    screen = top.expect("PAUSED", "q: quit")
    assert "-50000..50000" not in screen and "├" in screen
    top.press(b"q")
    assert top.wait() == 0
    assert top.restored()
    assert top.output.rfind(b"\x1b[?1049l") > top.output.rfind(b"\x1b[?1049h")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_puts_the_terminal_back(
    lab: tuple[Daemon, Path], terminal: list[Terminal], sig: signal.Signals
) -> None:
    _, socket = lab
    top = Terminal("--socket", str(socket), "--board", "servo")
    terminal.append(top)
    top.expect("servo  PCIX-400")
    top.proc.send_signal(sig)
    assert top.wait() == 128 + sig
    assert top.restored()
    assert top.output.rfind(b"\x1b[?1049l") > top.output.rfind(b"\x1b[?1049h")


def test_the_daemon_going_away_ends_it_cleanly(
    lab: tuple[Daemon, Path], terminal: list[Terminal]
) -> None:
    daemon, socket = lab
    top = Terminal("--socket", str(socket))
    terminal.append(top)
    top.expect("last events")
    assert daemon.stop() == 0
    assert top.wait() == 3
    assert top.restored()
    assert f"omsd top: lost the daemon at {socket}" in top.text()
