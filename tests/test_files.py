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
    h.send("AX;UF;JF0.5;")  # a velocity below VL's "1 ≤ VL" (?VL: vl0), which AP saves
    assert flash.apply(h.board, flash.board_parameters(h.board)) == []


@pytest.mark.parametrize(
    ("where", "value", "problem"),
    [
        # AC: "must be greater than zero (zero is not valid)", "RANGE: 1 ≤ AC ≤ 8,000,000"
        (("AC",), 0, "axes.X.AC: expected 1 ≤ acceleration ≤ 8000000, got 0"),
        # json.loads reads 1e400 as infinity: a number, but no acceleration
        (("AC",), 1e400, "axes.X.AC: expected 1 ≤ acceleration ≤ 8000000, got inf"),
        # VL: "RANGE: 1 ≤ VL ≤ 1044000" (a JF fraction below 1 is what AP may save)
        (("VL",), 0, "axes.X.VL: expected 0 < velocity ≤ 1044000, got 0"),
        (("VL",), 2e6, "axes.X.VL: expected 0 < velocity ≤ 1044000, got 2000000.0"),
        (("ES",), 0, "axes.X.ES: expected 0 < slip tolerance ≤ 65535, got 0"),
        (("HG",), 1e400, "axes.X.HG: expected 1 ≤ hold gain ≤ 32000, got inf"),
        (("HV",), 2e6, "axes.X.HV: expected 0 or 1 ≤ hold velocity ≤ 1039999, got 2000000.0"),
        (("ER",), 1e400, "axes.X.ER: expected a number > 0, got inf"),
        # UU: the UU command's own range (greater than zero, at most 1,000,000,000)
        (("UU",), "0", "axes.X.UU: expected 0 < multiplier ≤ 1000000000, got '0'"),
        (("UU",), "-5", "axes.X.UU: expected 0 < multiplier ≤ 1000000000, got '-5'"),
        (("UU",), "NaN", "axes.X.UU: expected 0 < multiplier ≤ 1000000000, got 'NaN'"),
        (("UU",), "Infinity", "axes.X.UU: expected 0 < multiplier ≤ 1000000000, got 'Infinity'"),
    ],
)
def test_a_saved_value_out_of_range_is_skipped(
    where: tuple[str, ...], value: object, problem: str
) -> None:
    """Saved values out of the command's own range are skipped as those of the wrong type are
    (docs/decisions.md: "a number out of range ... skipped one by one, the factory value
    staying"); before, anything >= 0 was taken, and AC0, UU "0", "NaN" or "Infinity" (or a
    1e400, which JSON reads as infinity) left a board that raised on its next move or query."""
    h = Harness("PCIX-040")
    saved = flash.board_parameters(h.board)
    saved["axes"]["X"][where[0]] = value
    assert flash.apply(h.board, saved) == [problem]
    factory = Harness("PCIX-040")
    x = h.board.axes[0]
    key = {"AC": "ac", "VL": "vl", "ES": "es", "HG": "hg", "HV": "hv", "ER": "ratio", "UU": "uu"}
    assert getattr(x, key[where[0]]) == getattr(factory.board.axes[0], key[where[0]])
    h.send("AX;?VL;?UU;MR1000;GO;")
    h.advance(1)
    assert h.send("AX;RP;") == b"1000\n\r"


def test_a_servo_gain_out_of_range_is_skipped() -> None:
    """The gains' own ranges (KB: "0 ≤ KB ≤ 10", KP "0.00 ≤ KP ≤ 32767.00")."""
    h = Harness("PCIX-400")
    saved = flash.board_parameters(h.board)
    saved["axes"]["X"]["servo"]["kb"] = 11
    saved["axes"]["X"]["servo"]["kp"] = 1e400
    saved["axes"]["X"]["servo"]["kd"] = 30
    assert flash.apply(h.board, saved) == [
        "axes.X.servo.kp: expected 0 ≤ coefficient ≤ 32767, got inf",
        "axes.X.servo.kb: expected 0 ≤ coefficient ≤ 10, got 11",
    ]
    gains = h.board.axes[0].servo.gains  # type: ignore[union-attr]
    assert (gains.kp, gains.kb, gains.kd) == (10.0, 10.0, 30.0)


def test_a_saved_uu1_is_user_units_off() -> None:
    """UU1 is "equivalent to" UF (the UF page: "equivalent to and preferred over UU1;"), as the
    UU command makes it: a saved "1" answers ?UU with uf."""
    h = Harness("PCIX-040")
    saved = flash.board_parameters(h.board)
    saved["axes"]["X"]["UU"] = "1"
    assert flash.apply(h.board, saved) == []
    assert h.send("AX;?UU;") == b"uf\n\r"


def test_a_negative_backlash_is_skipped_on_a_stepper() -> None:
    """BC: "0 ≤ BACKLASH ≤ +50 STEPPERS", "-50 ≤ BACKLASH ≤ +50 SERVOS"."""
    h = Harness("PCIX-202")  # X, Y servo; Z, T open loop
    saved = flash.board_parameters(h.board)
    saved["axes"]["X"]["BC"] = -5
    saved["axes"]["Z"]["BC"] = -5
    assert flash.apply(h.board, saved) == ["axes.Z.BC: expected an integer 0..50, got -5"]
    assert [a.backlash for a in h.board.axes[::2]] == [-5, 0]
