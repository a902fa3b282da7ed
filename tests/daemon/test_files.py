"""Issue 13, "Nothing outside omsd's own files is touched", through the real daemon.

- The runtime directory (``$XDG_RUNTIME_DIR/omsd`` here) is created 0700, and one that is a
  symlink, owned by another user or writable by its group or anyone is refused: one line, exit
  status 2, nothing created.
- ``--pty PATH`` over anything but omsd's own stale link (a symlink to a pty device) is refused
  the same way, and so is ``--control PATH`` over anything but a socket; the file is left as it
  was, and no board's endpoint is left behind.
- The traffic log and the state file are created 0600 (0640 in a configured group).
- SIGHUP reopens the log file (logrotate renamed it: a new one is made) and the daemon goes on.
- Temporary files of a save cut short are removed at the next start; a saved value of the wrong
  type is reported in one warning line.

Every daemon here gets its own runtime directory: ``XDG_RUNTIME_DIR`` points into the test's
directory (the daemons inherit the test's environment, ``process.daemon_env``).
"""

from __future__ import annotations

import grp
import json
import os
import signal
import stat
import subprocess
from pathlib import Path

import pytest

from .process import Omsd, run_omsd, wait_for

REFUSED = 2  # the exit status of a refusal


@pytest.fixture(autouse=True)
def runtime(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """This test's runtime directory, ``$XDG_RUNTIME_DIR/omsd`` (not made: the daemon makes
    it)."""
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    xdg = tmp_path / "xdg"
    xdg.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(xdg))
    return xdg / "omsd"


def refusal(result: subprocess.CompletedProcess[str]) -> str:
    """The one line of a refused start: exit status 2, nothing on standard output."""
    assert result.returncode == REFUSED, (result.returncode, result.stderr)
    assert "Traceback" not in result.stderr, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {result.stderr!r}"
    assert result.stdout == "", result.stdout
    assert lines[0].startswith("omsd: "), lines[0]
    return lines[0]


def mode(path: Path) -> int:
    return stat.S_IMODE(os.lstat(path).st_mode)


def a_group() -> grp.struct_group:
    """A group this process may give its files to, other than its own if it can (root: any)."""
    if os.geteuid() == 0:
        candidates = [g.gr_gid for g in grp.getgrall() if g.gr_gid != os.getegid()]
    else:
        candidates = [g for g in os.getgroups() if g != os.getegid()]
    return grp.getgrgid(candidates[0] if candidates else os.getegid())


# -- the runtime directory ----------------------------------------------------------------------


def test_the_runtime_directory_is_created_0700(omsd: Omsd, runtime: Path) -> None:
    old = os.umask(0o022)  # the usual umask: the daemon sets the mode itself
    try:
        daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(runtime / "board1"))
    finally:
        os.umask(old)
    assert mode(runtime) == 0o700
    assert (runtime / "control.sock").is_socket()
    assert (runtime / "board1").is_symlink()
    assert daemon.stop() == 0


def test_a_runtime_directory_that_is_a_symlink_is_refused(runtime: Path, tmp_path: Path) -> None:
    planted = tmp_path / "planted"  # another user's directory, say
    planted.mkdir(mode=0o700)
    runtime.symlink_to(planted)
    result = run_omsd("--tcp", "127.0.0.1:0", "--pty", str(runtime / "board1"), cwd=tmp_path)
    line = refusal(result)
    assert f"runtime directory {runtime} is a symlink (to {planted})" in line, line
    assert "refusing to use it" in line
    assert list(planted.iterdir()) == []  # no control socket, no pty link
    assert runtime.is_symlink()


@pytest.mark.parametrize("bits", [0o777, 0o770, 0o1777], ids=["0777", "0770", "sticky-1777"])
def test_a_runtime_directory_others_can_write_is_refused(
    runtime: Path, tmp_path: Path, bits: int
) -> None:
    runtime.mkdir()
    runtime.chmod(bits)
    result = run_omsd("--tcp", "127.0.0.1:0", cwd=tmp_path)  # the default control socket
    line = refusal(result)
    assert f"runtime directory {runtime} is writable by its group or by anyone" in line, line
    assert f"(mode {bits:04o})" in line
    assert list(runtime.iterdir()) == []
    assert mode(runtime) == bits  # left as it was


def test_a_runtime_directory_owned_by_another_user_is_refused(
    runtime: Path, tmp_path: Path
) -> None:
    if os.geteuid() != 0:
        pytest.skip("only root can make a directory owned by another user")
    runtime.mkdir(mode=0o700)
    other = 65534 if os.geteuid() != 65534 else 65533  # nobody
    os.chown(runtime, other, -1)
    result = run_omsd("--tcp", "127.0.0.1:0", "--pty", str(runtime / "board1"), cwd=tmp_path)
    line = refusal(result)
    assert f"runtime directory {runtime} is owned by uid {other}, not by this user" in line
    assert list(runtime.iterdir()) == []


def test_a_runtime_directory_that_is_a_file_is_refused(runtime: Path, tmp_path: Path) -> None:
    runtime.write_text("not a directory")
    line = refusal(run_omsd("--tcp", "127.0.0.1:0", cwd=tmp_path))
    assert f"runtime directory {runtime} is a regular file, not a directory" in line
    assert runtime.read_text() == "not a directory"


def test_the_runtime_directory_is_not_checked_when_nothing_goes_in_it(
    omsd: Omsd, runtime: Path, tmp_path: Path
) -> None:
    """A runtime directory nobody uses (every path given elsewhere) is not the daemon's
    business: it is neither made nor refused."""
    runtime.mkdir()
    runtime.chmod(0o777)
    daemon = omsd(
        "--tcp", "127.0.0.1:0", "--pty", str(tmp_path / "b1"), "--control", str(tmp_path / "c")
    )
    assert daemon.stop() == 0


# -- what is at a path the daemon is to create ----------------------------------------------


def test_pty_over_a_regular_file_is_refused_and_the_file_kept(tmp_path: Path) -> None:
    """It used to be replaced by the link, and the link deleted at exit: the file was lost."""
    victim = tmp_path / "notes.txt"
    victim.write_text("precious\n")
    line = refusal(run_omsd("--tcp", "127.0.0.1:0", "--pty", str(victim), cwd=tmp_path))
    assert line == (
        f"omsd: board1: {victim} is a regular file, not a pty link; refusing to replace it"
        " (remove it, or choose another path)"
    )
    assert victim.read_text() == "precious\n"


def test_pty_over_a_directory_or_a_foreign_symlink_is_refused(tmp_path: Path) -> None:
    directory = tmp_path / "dir"
    directory.mkdir()
    line = refusal(run_omsd("--tcp", "127.0.0.1:0", "--pty", str(directory), cwd=tmp_path))
    assert f"{directory} is a directory, not a pty link" in line
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "notes.txt")  # dangling or not, it is not a pty's
    line = refusal(run_omsd("--tcp", "127.0.0.1:0", "--pty", str(link), cwd=tmp_path))
    assert f"{link} is a symlink to {tmp_path / 'notes.txt'}, not to a pty" in line
    assert os.readlink(link) == str(tmp_path / "notes.txt")


def test_omsds_own_stale_link_is_replaced(omsd: Omsd, tmp_path: Path) -> None:
    """What a daemon that died leaves: a symlink to a pty device that is gone."""
    link = tmp_path / "board1"
    link.symlink_to("/dev/pts/99999")
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(link))
    assert os.readlink(link) == daemon.endpoints[1].device
    assert daemon.stop() == 0
    assert not os.path.lexists(link)


def test_a_refused_pty_on_a_later_board_leaves_nothing_behind(tmp_path: Path) -> None:
    first = tmp_path / "first"
    victim = tmp_path / "second"
    victim.write_text("precious\n")
    path = tmp_path / "two.toml"
    path.write_text(
        f'[[board]]\nname = "first"\npty = "{first}"\ntcp = "127.0.0.1:0"\n\n'
        f'[[board]]\nname = "second"\npty = "{victim}"\ntcp = "127.0.0.1:0"\n'
    )
    line = refusal(run_omsd("--config", str(path), "--view", "plain", cwd=tmp_path))
    assert line.startswith(f"omsd: second: {victim} is a regular file"), line
    assert not os.path.lexists(first)
    assert victim.read_text() == "precious\n"


def test_control_over_a_regular_file_is_refused_and_the_file_kept(tmp_path: Path) -> None:
    victim = tmp_path / "notes.txt"
    victim.write_text("precious\n")
    line = refusal(run_omsd("--tcp", "127.0.0.1:0", "--control", str(victim), cwd=tmp_path))
    assert line == (
        f"omsd: control socket {victim} is a regular file, not a socket; refusing to replace it"
        " (remove it, or give another --control path)"
    )
    assert victim.read_text() == "precious\n"


# -- the files the daemon creates ---------------------------------------------------------------

PCIX = """
{head}
[[board]]
name = "servo"
model = "PCIX-400"
link = "raw"
tcp = "127.0.0.1:0"
"""


def _save(omsd: Omsd, head: str) -> None:
    """Start a PCIx, have it save its flash (AP), log some traffic, stop."""
    old = os.umask(0o022)
    try:
        daemon = omsd(config=PCIX.format(head=head), expect=1)
    finally:
        os.umask(old)
    with daemon.connect() as c:
        c.send(b"AX;VL1234;AP;?VL\n")
        assert c.read_until(b"\n\r") == b"vl1234\n\r"
    assert daemon.stop() == 0, daemon.stderr


def test_the_log_and_the_state_file_are_created_0600(omsd: Omsd, tmp_path: Path) -> None:
    log, state = tmp_path / "traffic.jsonl", tmp_path / "omsd.state"
    _save(omsd, f'[log]\nfile = "{log}"\n[state]\nfile = "{state}"\n')
    assert wait_for(lambda: state.exists())
    assert (mode(log), mode(state)) == (0o600, 0o600)


def test_with_a_group_they_are_0640_in_it(omsd: Omsd, tmp_path: Path) -> None:
    group = a_group()
    log, state = tmp_path / "traffic.jsonl", tmp_path / "omsd.state"
    _save(
        omsd,
        f'[log]\nfile = "{log}"\ngroup = "{group.gr_name}"\n'
        f'[state]\nfile = "{state}"\ngroup = "{group.gr_name}"\n',
    )
    for path in (log, state):
        st = os.stat(path)
        assert (stat.S_IMODE(st.st_mode), st.st_gid) == (0o640, group.gr_gid), path


# -- SIGHUP -------------------------------------------------------------------------------------


def test_sighup_reopens_the_log_after_a_rotation(omsd: Omsd, tmp_path: Path) -> None:
    """What logrotate does (without copytruncate): rename the file, send SIGHUP. The daemon
    writes a new file at the path, says so, and goes on; it used to die at once, leaving its pty
    link and control socket behind."""
    log, rotated = tmp_path / "traffic.jsonl", tmp_path / "traffic.jsonl.1"
    link = tmp_path / "board1"
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(link), "--log", str(log))
    with daemon.connect() as c:
        assert c.ask(b"WY") == b"PC48 ver 3.00-4"
        log.rename(rotated)
        daemon.proc.send_signal(signal.SIGHUP)
        assert wait_for(lambda: "reopened log files on SIGHUP" in daemon.stderr), daemon.stderr
        assert log.exists() and mode(log) == 0o600
        assert c.ask(b"RP") == b"0"  # the same client, still connected
    assert daemon.running and os.path.islink(link)
    assert daemon.stop() == 0
    assert not os.path.lexists(link)
    lines = [line for line in daemon.stderr.splitlines() if "SIGHUP" in line]
    assert len(lines) == 1 and lines[0].endswith(f"reopened log files on SIGHUP: {log}"), lines

    def records(path: Path) -> list[dict[str, object]]:
        return [json.loads(line) for line in path.read_text().splitlines()]

    def sent(path: Path) -> bytes:
        return b"".join(
            bytes.fromhex(str(r["hex"]))
            for r in records(path)
            if r["kind"] == "traffic" and r["dir"] == "in"
        )

    assert sent(rotated) == b"WY"
    assert sent(log) == b"RP"
    messages = [r.get("message") for r in records(log)]
    assert messages[0] == f"reopened log files on SIGHUP: {log}"
    assert messages[-1] == "stopped"


def test_sighup_without_a_log_file_changes_nothing(omsd: Omsd, tmp_path: Path) -> None:
    link = tmp_path / "board1"
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(link))
    daemon.proc.send_signal(signal.SIGHUP)
    assert wait_for(lambda: "SIGHUP: no log file to reopen" in daemon.stderr), daemon.stderr
    with daemon.connect() as c:
        assert c.ask(b"WY") == b"PC48 ver 3.00-4"
    assert daemon.running and os.path.islink(link)
    assert daemon.stop() == 0
    assert daemon.stderr.splitlines()[-1].endswith(" stopped")


# -- the state file at start --------------------------------------------------------------------


def test_temporary_files_of_a_save_cut_short_are_removed_at_start(
    omsd: Omsd, tmp_path: Path
) -> None:
    """A SIGKILL during a save leaves ``.omsd.state.XXXXXXXX.tmp`` (18 in 50 kills, says the
    issue); the next start removes it, and only it."""
    state = tmp_path / "omsd.state"
    leftovers = [tmp_path / ".omsd.state.k3_9xq2a.tmp", tmp_path / ".omsd.state.abcdefgh.tmp"]
    kept = tmp_path / ".omsd.state.backup"
    for path in (*leftovers, kept):
        path.write_text('{"format": 1, "bo')
    daemon = omsd(config=PCIX.format(head=f'[state]\nfile = "{state}"\n'), expect=1)
    assert not any(p.exists() for p in leftovers)
    assert kept.exists()
    said = [line for line in daemon.stderr.splitlines() if "temporary file" in line]
    assert len(said) == 1 and said[0].endswith(
        "removed 2 temporary files left by a save cut short"
    ), said
    assert daemon.stop() == 0


def test_a_saved_value_of_the_wrong_type_is_one_warning(omsd: Omsd, tmp_path: Path) -> None:
    """It used to be dropped without a word (the factory value stays, rightly)."""
    state = tmp_path / "omsd.state"
    axes = {"X": {"VL": "fast", "AC": 123456, "SE": 5.5}, "Y": {"VL": 2222}}
    state.write_text(
        json.dumps(
            {
                "format": 1,
                "boards": {"servo": {"defaults": {"model": "PCIX-400", "axes": axes}}},
            }
        )
    )
    daemon = omsd(config=PCIX.format(head=f'[state]\nfile = "{state}"\n'), expect=1)
    with daemon.connect() as c:
        c.send(b"AX;?VL;?AC;AY;?VL\n")
        replies = [c.read_until(b"\n\r")[:-2] for _ in range(3)]
    factory_vl = b"vl200000"
    assert replies == [factory_vl, b"ac123456", b"vl2222"]  # the rest of the file is used
    warnings = [line for line in daemon.stderr.splitlines() if "warning" in line]
    assert warnings == [warnings[0]] and warnings[0].endswith(
        f"warning: state file {state}: board 'servo': ignored 2 saved values that do not fit,"
        " using the factory values: axes.X.VL: expected a number >= 0, got 'fast';"
        " axes.X.SE: expected an integer 0..1000, got 5.5"
    ), warnings
    assert daemon.stop() == 0
