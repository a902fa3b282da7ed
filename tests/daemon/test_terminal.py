"""The terminal is a first-class client (issue 14).

"picocom, minicom and screen on the pty: with the defaults a user sees nothing of what they type
and replies land on top of each other. Offer a terminal-friendly option on an endpoint (local
echo of typed characters and line endings a terminal shows cleanly; off by default so that
programs see the card's exact bytes), document it with the three programs, and test it by
driving a real terminal program on the pty."

"On a terminal each endpoint is announced once (today the standard-output line and the log's
"serving" line both show, so every endpoint appears twice)."

The terminal programs run inside tmux, a real terminal emulator: what is checked is the screen
a person would see (``tmux capture-pane``), not only the bytes. CI installs picocom, minicom and
screen (``.ci/run``, ``OMSD_NEED_PICOCOM`` and the like make a missing one a failure there);
elsewhere a missing program is a skip that says so.
"""

from __future__ import annotations

import contextlib
import os
import select
import shlex
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from .process import TIMEOUT, Conn, Omsd, daemon_env, wait_for

WY = "PC48 ver 3.00-4"
PROGRAMS = {
    # program: (its command line for a pty PATH, the keys that quit it)
    "picocom": (["picocom", "-q", "{path}"], [["C-a", "C-x"]]),
    "minicom": (["minicom", "-o", "-D", "{path}"], [["C-a", "x"], ["Enter"]]),
    "screen": (["screen", "-S", "omsd-test", "{path}"], [["C-a", "k"], ["y"]]),
}


def _need(program: str) -> str:
    found = shutil.which(program)
    if found is None:
        if os.environ.get(f"OMSD_NEED_{program.upper()}"):
            pytest.fail(f"{program} is required here and missing (.ci/run installs it)")
        pytest.skip(f"{program} is not installed (`apt-get install {program}`, as .ci/run does)")
    return found


class Tmux:
    """A tmux server of the test's own (its own socket), one window of a fixed size, running
    one program; :meth:`close` kills the server and whatever it runs."""

    def __init__(self, tmp_path: Path, argv: list[str], env: dict[str, str]) -> None:
        self.socket = tmp_path / "tmux.sock"
        self.env = env
        self._run(
            "new-session", "-d", "-s", "t", "-x", "100", "-y", "40", shlex.join(argv), check=True
        )
        self._run("set-option", "-t", "t", "remain-on-exit", "on")

    def _run(self, *args: str, check: bool = False) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            ["tmux", "-S", str(self.socket), *args],
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
            env=self.env,
            check=check,
        )

    def keys(self, *keys: str) -> None:
        """tmux key names (``Enter``, ``C-a``, ``BSpace``); text is typed with :meth:`type`."""
        self._run("send-keys", "-t", "t", *keys, check=True)

    def type(self, text: str) -> None:
        """Type ``text`` a key at a time, as a person would."""
        for ch in text:
            self._run("send-keys", "-t", "t", "-l", ch, check=True)

    def screen(self) -> list[str]:
        """The lines of the window as shown, trailing blanks stripped."""
        out = self._run("capture-pane", "-p", "-t", "t", check=True).stdout
        return [line.rstrip() for line in out.splitlines()]

    def dead(self) -> bool:
        out = self._run("list-panes", "-t", "t", "-F", "#{pane_dead}").stdout
        return out.strip() in ("1", "")

    def close(self) -> None:
        self._run("kill-server")


def _follows(screen: list[str], lines: list[str]) -> bool:
    """``lines`` appear on the screen one after the other, each on a line of its own."""
    n = len(lines)
    return any(screen[i : i + n] == lines for i in range(len(screen) - n + 1))


@pytest.fixture
def terminal(tmp_path: Path) -> Iterator[TermProgram]:
    term = TermProgram(tmp_path)
    try:
        yield term
    finally:
        term.close()


class TermProgram:
    """A terminal program on a pty, inside tmux."""

    def __init__(self, tmp_path: Path) -> None:
        self.tmp_path = tmp_path
        self.tmux: Tmux | None = None
        self.program = ""

    def start(self, program: str, pty: Path) -> Tmux:
        _need(program)
        _need("tmux")
        argv, _ = PROGRAMS[program]
        env = dict(daemon_env())
        home = self.tmp_path / "home"
        home.mkdir(exist_ok=True)
        screendir = self.tmp_path / "screens"
        screendir.mkdir(mode=0o700, exist_ok=True)
        env.update(HOME=str(home), SCREENDIR=str(screendir), TERM="xterm", LANG="C.UTF-8")
        env.pop("TMUX", None)
        self.program = program
        self.tmux = Tmux(self.tmp_path, [a.format(path=pty) for a in argv], env)
        return self.tmux

    def quit(self) -> None:
        """Leave the program with its own keys; it must exit."""
        assert self.tmux is not None
        for keys in PROGRAMS[self.program][1]:
            time.sleep(0.2)
            self.tmux.keys(*keys)
        assert wait_for(self.tmux.dead), f"{self.program} did not quit: {self.tmux.screen()}"

    def close(self) -> None:
        if self.tmux is not None:
            if self.program == "screen":  # a screen session left detached, if any
                subprocess.run(
                    ["screen", "-S", "omsd-test", "-X", "quit"],
                    capture_output=True,
                    timeout=TIMEOUT,
                    env=self.tmux.env,
                )
            self.tmux.close()


def _shows(tmux: Tmux, lines: list[str]) -> None:
    assert wait_for(lambda: _follows(tmux.screen(), lines)), (
        f"expected the lines {lines} one after the other; the screen:\n" + "\n".join(tmux.screen())
    )


@pytest.mark.parametrize("program", list(PROGRAMS))
def test_a_terminal_program_shows_what_is_typed_and_each_answer_on_its_own_line(
    omsd: Omsd, tmp_path: Path, terminal: TermProgram, program: str
) -> None:
    """The README's session with ``--terminal``: ``WY`` Enter shows the typed characters, then
    the answer, each on its own line; ``AX MR1000 GO ID`` Enter shows the done marker (``!`` and
    the done-flag register in hex, ``01``: X) on its own line when the move is done. Backspace
    erases a typing mistake before it reaches the board. With the board's echo on (EN), what
    shows is the board's echo, with each answer on its own line, and the English error message
    of a bad command, then its ``#``."""
    link = tmp_path / "board1"
    daemon = omsd("--terminal", "--pty", str(link), "--control", "off")
    tmux = terminal.start(program, link)
    wait_for(lambda: "pty:" in daemon.stderr and "opened" in daemon.stderr)
    tmux.type("WY")
    _shows(tmux, ["WY"])  # shown as it is typed; the line goes to the board with Enter
    tmux.keys("Enter")
    _shows(tmux, ["WY", WY])
    tmux.type("AX MR1000 GO ID")
    tmux.keys("Enter")
    _shows(tmux, ["WY", WY, "AX MR1000 GO ID", "!01"])
    tmux.type("AX RQ")
    tmux.keys("BSpace")
    tmux.type("P")
    tmux.keys("Enter")
    _shows(tmux, ["AX MR1000 GO ID", "!01", "AX RP", "1000"])
    tmux.type("EN")
    tmux.keys("Enter")
    # with the board's echo on, what shows is the board's echo: a person sees it come back
    # before pressing Enter (pressed before the echo is back, the new line comes first and the
    # late echo after it, as on the card through PC4XCOMM), so the test waits for it too
    tmux.type("WY")
    _shows(tmux, ["EN", "WY"])
    tmux.keys("Enter")
    _shows(tmux, ["EN", "WY", WY])
    tmux.type("XQ")
    _shows(tmux, ["EN", "WY", WY, "XQ"])
    tmux.keys("Enter")
    _shows(tmux, ["EN", "WY", WY, "XQ", "Unrecognized command: XQ", "#"])
    terminal.quit()
    # the board heard exactly what was sent, line by line (the traffic log shows the board's side)
    for sent in ("<- WY<CR>", "<- AX MR1000 GO ID<CR>", "<- AX RP<CR>", "<- EN<CR>"):
        assert sent in daemon.stderr


def test_without_the_option_programs_get_the_exact_bytes(omsd: Omsd, tmp_path: Path) -> None:
    """Off by default: a program on the pty gets the driver's exact bytes and no echo."""
    link = tmp_path / "board1"
    omsd("--pty", str(link), "--control", "off")
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"WY\r")
        got = b""
        deadline = time.monotonic() + TIMEOUT
        while not got.endswith(b"\n") and time.monotonic() < deadline:
            if select.select([fd], [], [], 0.1)[0]:
                got += os.read(fd, 256)
        assert got == WY.encode() + b"\n"
    finally:
        os.close(fd)


def _read_until(fd: int, end: bytes) -> bytes:
    got = b""
    deadline = time.monotonic() + TIMEOUT
    while not got.endswith(end) and time.monotonic() < deadline:
        if select.select([fd], [], [], 0.1)[0]:
            got += os.read(fd, 256)
    return got


def test_a_line_not_ended_is_not_the_next_sessions(omsd: Omsd, tmp_path: Path) -> None:
    """A line typed without Enter never reached the board: when the program closes the pty it
    goes with its session, and the next program starts on a clean line."""
    link = tmp_path / "board1"
    daemon = omsd("--terminal", "--pty", str(link), "--control", "off")
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"AX MR50")
        assert _read_until(fd, b"MR50") == b"AX MR50"
    finally:
        os.close(fd)
    assert wait_for(lambda: "closed" in daemon.stderr)
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, b"0 GO\rRP\r")
        got = _read_until(fd, b"0\r\n")
        # "0 GO" alone: "0" starts no command (#), and X did not move
        assert got == b"0 GO\r\nRP\r\n#\r\n0\r\n", got
    finally:
        os.close(fd)
    assert "AX MR50" not in daemon.stderr  # never sent to the board


def test_a_terminal_tcp_endpoint_of_a_configuration_file(omsd: Omsd) -> None:
    """``tcp = { address = ..., terminal = true }`` (here on the raw link, whose own framing
    becomes CR LF); the board's other TCP endpoint stays exact."""
    daemon = omsd(
        "--control",
        "off",
        config=(
            '[[board]]\nlink = "raw"\n'
            'tcp = [{ address = "127.0.0.1:0", terminal = true }, "127.0.0.1:0"]\n'
        ),
        expect=2,
    )
    friendly, exact = daemon.endpoints
    with Conn(friendly.host, friendly.port) as conn:
        conn.send(b"WY")
        conn.expect(b"WY")  # shown as typed
        conn.send(b"\r")
        conn.expect(b"\r\n" + WY.encode() + b"\r\n")
    with Conn(exact.host, exact.port) as conn:
        conn.send(b"WY\r")
        conn.expect(b"\n\r" + WY.encode() + b"\n\r")


# -- announced once --------------------------------------------------------------------------------


def _run_on_a_terminal(argv: list[str], tmp_path: Path, stdout_too: bool) -> tuple[str, str]:
    """Start omsd with its standard error (and standard output if ``stdout_too``) on a new
    pseudo-terminal, as when it is run by hand; stop it once it is serving. Returns what the
    terminal showed and what went to the standard-output pipe."""
    master, slave = os.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "omsd", *argv],
        stdin=subprocess.DEVNULL,
        stdout=slave if stdout_too else subprocess.PIPE,
        stderr=slave,
        env=daemon_env(),
        cwd=tmp_path,
    )
    os.close(slave)
    shown = bytearray()
    try:

        def read(timeout: float) -> None:
            while select.select([master], [], [], timeout)[0]:
                try:
                    data = os.read(master, 4096)
                except OSError:  # EIO: the daemon has gone
                    return
                if not data:
                    return
                shown.extend(data)

        deadline = time.monotonic() + TIMEOUT
        while shown.count(b"127.0.0.1:") < 1 and time.monotonic() < deadline:
            read(0.1)
        read(0.5)  # anything else it has to say about its endpoints
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=TIMEOUT)
        read(0.2)
        assert proc.returncode == 0
    finally:
        with contextlib.suppress(ProcessLookupError):
            proc.kill()
        proc.wait(TIMEOUT)
        os.close(master)
    return shown.decode(errors="replace"), (out or b"").decode()


@pytest.mark.parametrize("view", ["auto", "plain"])
def test_each_endpoint_is_announced_once_on_a_terminal(tmp_path: Path, view: str) -> None:
    """Standard output and standard error on one terminal: each endpoint's line shows once
    (the log's "serving" line would repeat it); the log file still has it."""
    log = tmp_path / "traffic.jsonl"
    argv = ["--tcp", "127.0.0.1:0", "--pty", str(tmp_path / "b1"), "--control", "off"]
    argv += ["--view", view, "--log", str(log)]
    shown, _ = _run_on_a_terminal(argv, tmp_path, stdout_too=True)
    assert shown.count("driver tcp 127.0.0.1:") == 1, shown
    assert shown.count(f"driver pty {tmp_path / 'b1'} -> ") == 1, shown
    assert "serving" not in shown, shown
    assert log.read_text().count('"message": "serving board1 PC48-4E driver ') == 2


def test_the_log_still_says_serving_when_standard_output_is_not_the_terminal(
    tmp_path: Path,
) -> None:
    """Standard output to a pipe (a script reads it) and the log on the terminal (or the
    journal): the log keeps its "serving" lines."""
    argv = ["--tcp", "127.0.0.1:0", "--control", "off", "--view", "plain"]
    shown, out = _run_on_a_terminal(argv, tmp_path, stdout_too=False)
    assert out.count("driver tcp 127.0.0.1:") == 1, out
    assert shown.count("serving board1 PC48-4E driver tcp 127.0.0.1:") == 1, shown
