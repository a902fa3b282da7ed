"""The real daemon over its pseudo-terminal, with pyserial as a legacy program would use it.

The issue: "Clients (pyserial, picocom, minicom, screen, ``cat``) open, close and reopen it any
number of times. The board's state survives every disconnect, as a card in a PC survives a
program exiting."
"""

from __future__ import annotations

import os
import stat
import subprocess
import termios
from pathlib import Path

import serial

from .process import TIMEOUT, Omsd, wait_for

SESSIONS = 20


def ask(port: serial.Serial, command: bytes) -> bytes:
    port.write(command)
    reply: bytes = port.read_until(b"\n")
    assert reply.endswith(b"\n"), f"{command!r}: no whole reply within {TIMEOUT} s: {reply!r}"
    return reply[:-1]


def test_pty_link_points_at_a_group_usable_raw_pty(omsd: Omsd, tmp_path: Path) -> None:
    link = tmp_path / "run" / "board1"
    link.parent.mkdir()  # omsd makes no directory for a link (issue 14: a missing one is refused)
    daemon = omsd("--pty", str(link))
    (endpoint,) = daemon.endpoints
    assert (endpoint.board, endpoint.model, endpoint.link, endpoint.kind) == (
        "board1",
        "PC48-4E",
        "driver",
        "pty",
    )
    assert endpoint.path == link
    assert link.is_symlink()
    assert os.readlink(link) == endpoint.device
    assert endpoint.device.startswith("/dev/pts/")
    mode = os.stat(endpoint.device).st_mode
    assert stat.S_IMODE(mode) & 0o660 == 0o660, oct(mode)
    # created raw: no echo, no line editing, no signal characters, no CR/LF translation
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        iflag, oflag, _, lflag, *_ = termios.tcgetattr(fd)
    finally:
        os.close(fd)
    assert lflag & (termios.ECHO | termios.ICANON | termios.ISIG | termios.IEXTEN) == 0
    assert iflag & (termios.ICRNL | termios.INLCR | termios.IGNCR | termios.IXON) == 0
    assert oflag & termios.OPOST == 0
    # no leftovers of the atomic replacement next to the link
    assert sorted(p.name for p in link.parent.iterdir()) == ["board1"]


def test_pty_opened_used_and_closed_twenty_times(omsd: Omsd, tmp_path: Path) -> None:
    link = tmp_path / "board1"
    daemon = omsd("--pty", str(link))
    with serial.Serial(str(link), timeout=TIMEOUT) as port:
        assert ask(port, b"WY") == b"PC48 ver 3.00-4"
        assert ask(port, b"AY LP-777 RP") == b"-777"
    x = 0
    for session in range(SESSIONS):
        with serial.Serial(str(link), timeout=TIMEOUT) as port:
            # the position loaded before the first session is still there
            assert ask(port, b"AY RP") == b"-777", f"session {session}"
            # the move started in the session before has finished and is visible now
            at_x = str(x).encode()
            assert wait_for(lambda: ask(port, b"AX RP") == at_x, 2.0), (  # noqa: B023
                f"session {session}: X never reached {x}"
            )
            x += 100
            if session % 2:
                # leave at once, with the move still running and its done unreported
                port.write(b"AX MR100 GO")
            else:
                port.write(b"AX MR100 GO ID")
                assert port.read_until(b"\n") == b"!\x01\n", f"session {session}"
        assert daemon.running, daemon.stderr[-2000:]
    with serial.Serial(str(link), timeout=TIMEOUT) as port:
        assert wait_for(lambda: ask(port, b"AA RP") == f"{x},-777,0,0".encode(), 2.0)
        assert x == SESSIONS * 100
    assert link.is_symlink()


def test_pty_write_larger_than_the_driver_buffer(omsd: Omsd, tmp_path: Path) -> None:
    """More than the driver's 256-character buffer in one write: held off, every command
    answered exactly once."""
    link = tmp_path / "board1"
    omsd("--pty", str(link))
    with serial.Serial(str(link), timeout=TIMEOUT) as port:
        port.write(b"AY LP3 " + b"AY RP " * 60)
        assert port.read(2 * 60) == b"3\n" * 60
        port.timeout = 0.1
        assert port.read(100) == b""


def _holds(pid: int, device: str) -> bool:
    """Process ``pid`` has ``device`` open."""
    fds = Path(f"/proc/{pid}/fd")
    try:
        return any(os.readlink(fd) == device for fd in fds.iterdir())
    except OSError:
        return False


def _cat_round(link: Path, position: int) -> None:
    reader = subprocess.Popen(["cat", str(link)], stdout=subprocess.PIPE)
    try:
        assert reader.stdout is not None
        # cat reads from its open on, as at a shell: the answers to a printf that came before
        # would be for nobody (a session of their own, flushed when it ends)
        device = os.path.realpath(link)
        assert wait_for(lambda: _holds(reader.pid, device)), "cat never opened the pty"
        out = reader.stdout
        os.set_blocking(out.fileno(), False)
        got = bytearray()

        def answered(text: bytes) -> bool:
            got.extend(out.read() or b"")
            return text in got

        subprocess.run(["sh", "-c", f"printf 'AX LP{position} RP' > '{link}'"], check=True)
        assert wait_for(lambda: answered(f"{position}\n".encode())), bytes(got)
        subprocess.run(["sh", "-c", f"printf 'WY' > '{link}'"], check=True)
        assert wait_for(lambda: answered(b"PC48 ver 3.00-4\n")), bytes(got)
    finally:
        reader.kill()
        reader.wait()


def test_cat_reads_what_the_board_answers_to_another_writer(omsd: Omsd, tmp_path: Path) -> None:
    """The shell way: ``cat`` on the pty in one process, ``printf ... > pty`` in others. They
    share one terminal, so the board's answers reach the reader; and cat can be stopped and
    started again any number of times."""
    link = tmp_path / "board1"
    omsd("--pty", str(link))
    for position in range(3):
        _cat_round(link, position)
