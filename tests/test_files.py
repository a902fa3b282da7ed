"""Files and permissions (omsd/files.py, issue 13) and the saved values that do not fit
(omsd/board/flash.py), without a daemon: the checks themselves, case by case. The real daemon's
refusals are in tests/daemon/test_files.py."""

from __future__ import annotations

import os
import socket
import stat
from pathlib import Path

import pytest

from omsd.board.harness import Harness
from omsd.dialects.pcix import flash
from omsd.files import (
    Refused,
    check_runtime_directory,
    is_pty_device,
    open_log,
    preflight,
    pty_link_refusal,
    socket_refusal,
)
from omsd.models import MODELS


def mode(path: Path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


# -- the runtime directory ----------------------------------------------------------------------


@pytest.mark.parametrize("umask", [0o022, 0o077, 0o002])
def test_a_missing_runtime_directory_is_made_0700(tmp_path: Path, umask: int) -> None:
    runtime = tmp_path / "run" / "omsd"
    old = os.umask(umask)
    try:
        check_runtime_directory(runtime)
    finally:
        os.umask(old)
    assert runtime.is_dir() and mode(runtime) == 0o700


def test_an_existing_private_directory_is_used_as_it_is(tmp_path: Path) -> None:
    runtime = tmp_path / "omsd"
    runtime.mkdir()
    runtime.chmod(0o755)  # readable by others is fine: systemd's RuntimeDirectoryMode=0755
    check_runtime_directory(runtime)
    assert mode(runtime) == 0o755


@pytest.mark.parametrize("bits", [0o777, 0o775, 0o757, 0o1777])
def test_a_directory_others_can_write_is_refused(tmp_path: Path, bits: int) -> None:
    runtime = tmp_path / "omsd"
    runtime.mkdir()
    runtime.chmod(bits)
    with pytest.raises(Refused, match=rf"writable by its group or by anyone \(mode {bits:04o}\)"):
        check_runtime_directory(runtime)
    assert mode(runtime) == bits


def test_a_symlink_is_refused_even_to_a_good_directory(tmp_path: Path) -> None:
    target = tmp_path / "real"
    target.mkdir(mode=0o700)
    runtime = tmp_path / "omsd"
    runtime.symlink_to(target)
    with pytest.raises(Refused) as info:
        check_runtime_directory(runtime)
    message = str(info.value)
    assert message.startswith(f"runtime directory {runtime} is a symlink (to {target}): ")
    assert "\n" not in message


def test_a_directory_of_another_user_is_refused(tmp_path: Path) -> None:
    if os.geteuid() != 0:
        pytest.skip("only root can make a directory owned by another user")
    runtime = tmp_path / "omsd"
    runtime.mkdir(mode=0o700)
    os.chown(runtime, 65534, -1)
    with pytest.raises(Refused, match="is owned by uid 65534, not by this user"):
        check_runtime_directory(runtime)


def test_preflight_checks_the_runtime_directory_only_when_it_is_used(tmp_path: Path) -> None:
    runtime = tmp_path / "omsd"
    preflight(runtime, [("b", tmp_path / "elsewhere")], None)
    assert not runtime.exists()
    preflight(runtime, [], runtime / "control.sock")
    assert mode(runtime) == 0o700


# -- what may be replaced -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("target", "ours"),
    [
        ("/dev/pts/4", True),
        ("/dev/pts/1234", True),
        ("/dev/ttys004", True),
        ("/dev/pts/", False),
        ("/dev/pts/4/../../sda", False),
        ("pts/4", False),
        ("/dev/ttyS0", False),
        ("/home/me/notes.txt", False),
    ],
)
def test_a_pty_device_is_what_os_ttyname_gives(target: str, ours: bool) -> None:
    assert is_pty_device(target) is ours


def test_what_a_pty_link_may_replace(tmp_path: Path) -> None:
    assert pty_link_refusal(tmp_path / "nothing") is None
    stale = tmp_path / "stale"
    stale.symlink_to("/dev/pts/77777")
    assert pty_link_refusal(stale) is None
    regular = tmp_path / "file"
    regular.write_text("x")
    assert pty_link_refusal(regular) == (
        f"{regular} is a regular file, not a pty link; refusing to replace it"
        " (remove it, or choose another path)"
    )
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    assert f"{fifo} is a named pipe, not a pty link" in str(pty_link_refusal(fifo))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.symlink_to("/etc/passwd")
    assert f"{elsewhere} is a symlink to /etc/passwd, not to a pty" in str(
        pty_link_refusal(elsewhere)
    )


def test_what_the_control_socket_may_replace(tmp_path: Path) -> None:
    assert socket_refusal(tmp_path / "nothing") is None
    path = tmp_path / "s"
    with socket.socket(socket.AF_UNIX) as s:
        s.bind(str(path))
    assert socket_refusal(path) is None  # a stale socket: the control server replaces it
    link = tmp_path / "link"
    link.symlink_to(path)
    assert f"control socket {link} is a symlink to {path}, not a socket" in str(
        socket_refusal(link)
    )


# -- a log file ---------------------------------------------------------------------------------


def test_open_log_appends_to_an_existing_file_without_touching_it(tmp_path: Path) -> None:
    path = tmp_path / "t.jsonl"
    path.write_text("old\n")
    path.chmod(0o604)
    fd = open_log(path)
    try:
        os.write(fd, b"new\n")
    finally:
        os.close(fd)
    assert path.read_text() == "old\nnew\n" and mode(path) == 0o604


# -- saved values that do not fit ---------------------------------------------------------------


def test_apply_says_what_it_skipped_and_uses_the_rest() -> None:
    h = Harness("PCIX-202")  # X, Y servo; Z, T open loop
    saved = {
        "model": "PCIX-202",
        "axes": {
            "X": {"VL": "fast", "AC": 12345, "servo": {"kp": "high", "kd": 30, "bipolar": 1}},
            "Y": {"BC": 99, "limits_on": "yes", "UU": 2, "unknown_key": "left alone"},
            "Z": [1, 2],
        },
        "tables": {"2": [[0.5, "x"]]},
        "scurves": [],
    }
    problems = flash.apply(h.board, saved)
    assert problems == [
        "tables.2: expected [[a, v], ...], got an array",
        "scurves: expected an object, got an array",
        "axes.X.VL: expected a number >= 0, got 'fast'",
        "axes.X.servo.kp: expected a number, got 'high'",
        "axes.X.servo.bipolar: expected true or false, got 1",
        "axes.Y.BC: expected an integer -50..50, got 99",
        "axes.Y.limits_on: expected true or false, got 'yes'",
        "axes.Y.UU: expected a decimal number in a string or null, got 2",
        "axes.Z: expected an object, got an array",
    ]
    x = h.board.axes[0]
    assert x.ac == 12345  # what fits is used
    assert x.servo is not None
    assert x.servo.gains.kd == 30.0 and x.servo.gains.kp == 10.0  # the factory KP stays
    assert flash.apply(h.board, flash.board_parameters(h.board)) == []  # AP's own set fits


@pytest.mark.parametrize("model", [m for m in MODELS if m.startswith("PCIX")])
def test_what_ap_saves_always_fits(model: str) -> None:
    """No warning for a file omsd wrote itself: the factory set (HV 0 included: "no hold
    velocity") and a set with values changed."""
    h = Harness(model)
    assert flash.apply(h.board, flash.board_parameters(h.board)) == []
    h.send("AX;HV5000;HG2;UU2.5;BC3;SE10;AY;SVI;")
    assert flash.apply(h.board, flash.board_parameters(h.board)) == []
