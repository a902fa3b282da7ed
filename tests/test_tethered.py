"""``python -m omsd.tethered``: ``omsd`` that stops when the pipe on its standard input ends
(:mod:`omsd.tethered`, the pytest plugin's daemons). Only a pipe says that: standard input that
is a terminal or ``/dev/null`` (run by hand, by systemd) is refused with one line, exit 2."""

from __future__ import annotations

import os
import pty
import subprocess
import sys
from pathlib import Path

import pytest

WAIT = 20.0


def config(tmp_path: Path) -> Path:
    path = tmp_path / "omsd.toml"
    path.write_text(
        '[[board]]\nname = "xy"\nmodel = "PC48"\ntcp = 0\n'
        f'[control]\nsocket = "{tmp_path / "ctl.sock"}"\n'
    )
    return path


def tethered(tmp_path: Path, stdin: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "omsd.tethered", "--config", str(config(tmp_path))],
        stdin=stdin,  # type: ignore[arg-type]
        capture_output=True,
        text=True,
        timeout=WAIT,
        start_new_session=True,
    )


def test_dev_null_is_refused_not_a_silent_clean_stop(tmp_path: Path) -> None:
    """Under systemd (standard input /dev/null) the daemon read end of file at once and stopped
    itself, exit status 0 and not a word: a unit that seemed to have done its work."""
    done = tethered(tmp_path, subprocess.DEVNULL)
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "standard input" in done.stderr, done.stderr
    assert done.stdout == ""


def test_a_terminal_is_refused_not_read(tmp_path: Path) -> None:
    """On a terminal the daemon read what was typed (and started in the background, ``&``, the
    kernel stopped it: SIGTTIN, "Stopped (tty input)", serving nothing)."""
    master, slave = pty.openpty()
    try:
        done = tethered(tmp_path, slave)
    finally:
        os.close(slave)
        os.close(master)
    assert done.returncode == 2
    assert "standard input" in done.stderr and done.stdout == ""


@pytest.mark.parametrize("attempt", range(8))
def test_a_pipe_ended_before_start_up_is_a_clean_stop(tmp_path: Path, attempt: int) -> None:
    """A pipe whose writer is already gone: SIGTERM, which omsd's docstring (omsd/cli.py) makes
    "a clean stop at any moment: 0", also before its own handler is there. The tether sent it
    before omsd installed that handler, and the daemon died by its default action (143)."""
    read, write = os.pipe()
    os.close(write)
    try:
        done = tethered(tmp_path, read)
    finally:
        os.close(read)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
