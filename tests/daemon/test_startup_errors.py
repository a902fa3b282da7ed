"""Issue 14: a daemon that cannot start says what and why in one line, exits with status 2 and
leaves nothing behind (no listening socket, pty link, control socket file or directory it made).

Each test runs the real daemon (``python -m omsd``) on free ports and in its own directories, and
looks afterwards: the first board's port refuses connections, the pty link and the control
socket are not there.
"""

from __future__ import annotations

import os
import re
import resource
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from .process import Omsd, daemon_env, run_omsd


@pytest.fixture(autouse=True)
def _runtime(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A runtime directory of the test's own (the default control socket and pty links)."""
    base = tmp_path / "xdg"
    base.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(base))
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    yield base / "omsd"


def failed(result: subprocess.CompletedProcess[str]) -> str:
    """The one line of a start that failed: status 2, nothing on standard output."""
    assert "Traceback" not in result.stderr, result.stderr
    assert result.returncode == 2, (result.returncode, result.stderr)
    assert result.stdout == "", result.stdout
    lines = result.stderr.splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {result.stderr!r}"
    return lines[0]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def refused(port: int) -> bool:
    """Nobody listens on ``port`` (a start that failed closed what it had opened)."""
    with socket.socket() as s:
        s.settimeout(2.0)
        try:
            s.connect(("127.0.0.1", port))
        except ConnectionRefusedError:
            return True
    return False


def nothing_left(tmp_path: Path, runtime: Path, port: int, *paths: Path) -> None:
    assert refused(port), f"something still listens on the first board's port {port}"
    for path in paths:
        assert not os.path.lexists(path), f"{path} was left behind"
    assert not os.path.lexists(runtime), f"the runtime directory {runtime} was left behind"


@pytest.fixture
def busy() -> Iterator[int]:
    """A port somebody else listens on."""
    with socket.socket() as holder:
        holder.bind(("127.0.0.1", 0))
        holder.listen()
        yield int(holder.getsockname()[1])


def test_a_port_in_use_on_a_later_board(tmp_path: Path, _runtime: Path, busy: int) -> None:
    """The first board is up (its port listens, its pty link exists, the control socket too in
    the daemon's order of things) when the second board's port turns out to be taken."""
    first, link, control = free_port(), tmp_path / "first", tmp_path / "control.sock"
    path = tmp_path / "two.toml"
    path.write_text(
        f'[[board]]\nname = "first"\npty = "{link}"\ntcp = "127.0.0.1:{first}"\n\n'
        f'[[board]]\nname = "second"\ntcp = "127.0.0.1:{busy}"\n'
    )
    line = failed(run_omsd("--config", str(path), "--control", str(control), cwd=tmp_path))
    assert line == f"omsd: second: cannot listen on tcp 127.0.0.1:{busy}: address already in use"
    nothing_left(tmp_path, _runtime, first, link, control)


def test_the_default_control_socket_and_runtime_directory_go_too(
    tmp_path: Path, _runtime: Path, busy: int
) -> None:
    """With the default control socket: neither it nor the runtime directory made for it stay."""
    first = free_port()
    line = failed(run_omsd("--tcp", f"127.0.0.1:{first}", "--tcp", f"127.0.0.1:{busy}"))
    assert line == f"omsd: board1: cannot listen on tcp 127.0.0.1:{busy}: address already in use"
    nothing_left(tmp_path, _runtime, first, _runtime / "control.sock")


def test_more_boards_than_file_descriptors(tmp_path: Path, _runtime: Path) -> None:
    """Out of file descriptors, asyncio's create_server skips the socket it cannot make without
    a word: the server listened nowhere and omsd died on an IndexError's traceback."""
    first = free_port()
    path = tmp_path / "many.toml"
    boards = "".join('[[board]]\ntcp = "127.0.0.1:0"\n' for _ in range(200))
    path.write_text(f'[[board]]\nname = "first"\ntcp = "127.0.0.1:{first}"\n{boards}')
    command = [sys.executable, "-m", "omsd", "--config", str(path), "--control", "off"]
    result = subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=30,
        env=daemon_env(),
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_NOFILE, (100, 100)),
    )
    line = failed(result)
    assert re.fullmatch(
        r"omsd: board\d+: cannot listen on tcp 127\.0\.0\.1:0: too many open files", line
    ), line
    nothing_left(tmp_path, _runtime, first)


def test_a_log_that_cannot_be_opened(tmp_path: Path, _runtime: Path) -> None:
    port, log, link = free_port(), tmp_path / "missing" / "traffic.jsonl", tmp_path / "b1"
    result = run_omsd("--tcp", f"127.0.0.1:{port}", "--pty", str(link), "--log", str(log))
    line = failed(result)
    assert line == f"omsd: cannot open traffic log {log}: No such file or directory"
    nothing_left(tmp_path, _runtime, port, link, log.parent)


def test_a_log_path_that_is_a_directory(tmp_path: Path, _runtime: Path) -> None:
    port = free_port()
    line = failed(run_omsd("--tcp", f"127.0.0.1:{port}", "--log", str(tmp_path)))
    assert line == f"omsd: cannot open traffic log {tmp_path}: Is a directory"
    nothing_left(tmp_path, _runtime, port)


def test_a_state_file_under_a_regular_file(tmp_path: Path, _runtime: Path) -> None:
    """A state file's missing directories are made at the first save (as before); one that
    cannot be made, a regular file in the way, stops the start."""
    port, link = free_port(), tmp_path / "b1"
    (tmp_path / "file").write_text("")
    state = tmp_path / "file" / "states" / "omsd.state"
    result = run_omsd("--tcp", f"127.0.0.1:{port}", "--pty", str(link), "--state", str(state))
    line = failed(result)
    assert line == (
        f"omsd: cannot use state file {state}: {tmp_path / 'file'} is a regular file, not a"
        " directory"
    )
    nothing_left(tmp_path, _runtime, port, link)


def test_a_state_file_that_is_a_directory(tmp_path: Path, _runtime: Path) -> None:
    port, state = free_port(), tmp_path / "omsd.state"
    state.mkdir()
    line = failed(run_omsd("--tcp", f"127.0.0.1:{port}", "--state", str(state)))
    assert line == f"omsd: cannot use state file {state}: it is a directory, not a file"
    nothing_left(tmp_path, _runtime, port)


def test_a_state_file_from_a_configuration_file(tmp_path: Path, _runtime: Path) -> None:
    """The same check for ``[state] file``: the path as the file resolves it."""
    port = free_port()
    path = tmp_path / "omsd.toml"
    path.write_text(f'[state]\nfile = "."\n[[board]]\ntcp = {port}\n')
    line = failed(run_omsd("--config", str(path)))
    assert line == f"omsd: cannot use state file {tmp_path}: it is a directory, not a file"
    nothing_left(tmp_path, _runtime, port)


def test_a_pty_link_whose_directory_is_missing(tmp_path: Path, _runtime: Path) -> None:
    """omsd makes no directory but its runtime directory: a typing mistake is not created."""
    port, link = free_port(), tmp_path / "missing" / "b1"
    line = failed(run_omsd("--tcp", f"127.0.0.1:{port}", "--pty", str(link)))
    assert line == f"omsd: board1: cannot create pty link {link}: no directory {link.parent}"
    nothing_left(tmp_path, _runtime, port, link.parent)


def test_a_pty_link_in_a_file_that_is_no_directory(tmp_path: Path, _runtime: Path) -> None:
    port, parent = free_port(), tmp_path / "file"
    parent.write_text("")
    link = parent / "b1"
    line = failed(run_omsd("--tcp", f"127.0.0.1:{port}", "--pty", str(link)))
    assert line == (
        f"omsd: board1: cannot create pty link {link}: {parent} is a regular file, not a directory"
    )
    nothing_left(tmp_path, _runtime, port)


def test_a_control_socket_in_use(omsd: Omsd, tmp_path: Path, _runtime: Path) -> None:
    """A configured control socket held by another daemon: the second daemon's boards, already
    listening by then, are closed again."""
    control = tmp_path / "c.sock"
    omsd("--tcp", "127.0.0.1:0", "--pty", str(tmp_path / "a"), "--control", str(control))
    port, link = free_port(), tmp_path / "b"
    result = run_omsd("--tcp", f"127.0.0.1:{port}", "--pty", str(link), "--control", str(control))
    assert failed(result) == f"omsd: control socket {control} is in use by another process"
    assert refused(port) and not os.path.lexists(link)
    assert control.exists()  # the first daemon's, untouched


def test_tcp_without_pty_says_that_no_pty_is_served(omsd: Omsd) -> None:
    """``--tcp`` alone replaces the default endpoints: the log says no pty is served."""
    daemon = omsd("--tcp", "127.0.0.1:0", "--view", "plain", expect=1)
    assert [e.kind for e in daemon.endpoints] == ["tcp"]
    assert daemon.stop() == 0
    assert "no pty: --tcp given without --pty serves TCP only (add --pty PATH)" in daemon.stderr


def test_pty_without_tcp_says_that_no_tcp_is_served(omsd: Omsd, tmp_path: Path) -> None:
    daemon = omsd("--pty", str(tmp_path / "p"), "--view", "plain")
    assert daemon.stop() == 0
    assert "no TCP: --pty given without --tcp serves the pty only" in daemon.stderr


def test_both_given_says_nothing_about_it(omsd: Omsd, tmp_path: Path) -> None:
    daemon = omsd("--tcp", "127.0.0.1:0", "--pty", str(tmp_path / "p"), "--view", "plain")
    assert daemon.stop() == 0
    assert "no pty" not in daemon.stderr and "no TCP" not in daemon.stderr


NOWHERE = "no-such-host.invalid"  # RFC 2606: .invalid never resolves


@pytest.mark.parametrize("where", ["tcp", "rfc2217", "control tcp"])
def test_a_host_name_that_does_not_resolve(tmp_path: Path, _runtime: Path, where: str) -> None:
    """A listening address whose host name does not resolve said ``unknown error -2``: the
    resolver's error (``socket.gaierror``) carries an EAI_* code where an errno would be, and
    ``os.strerror(-2)`` knows none. Now the resolver's own words, as ``getaddrinfo`` says them
    (``name or service not known``)."""
    try:
        socket.getaddrinfo(NOWHERE, 0)
    except socket.gaierror as exc:
        reason = str(exc.strerror).lower()
    else:  # pragma: no cover - a resolver that answers for .invalid
        pytest.skip(f"{NOWHERE} resolves here")
    port = free_port()
    path = tmp_path / "omsd.toml"
    board = f'[[board]]\nname = "b"\ntcp = "127.0.0.1:{port}"\n'
    if where == "tcp":
        path.write_text(f'[[board]]\nname = "b"\ntcp = "{NOWHERE}:{port}"\n')
        expected = f"omsd: b: cannot listen on tcp {NOWHERE}:{port}: {reason}"
    elif where == "rfc2217":
        path.write_text(f'{board}rfc2217 = "{NOWHERE}:0"\n')
        expected = f"omsd: b: cannot listen on rfc2217 {NOWHERE}:0: {reason}"
    else:
        path.write_text(f'[control]\ntcp = "{NOWHERE}:0"\n\n{board}')
        expected = f"omsd: cannot listen on control tcp {NOWHERE}:0: {reason}"
    line = failed(run_omsd("--config", str(path), "--control", "off", cwd=tmp_path))
    assert line == expected
    nothing_left(tmp_path, _runtime, port)


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        (
            ("--pty", "{same}", "--control", "{same}"),
            "omsd: board1: pty link {same} is the control socket's path too:"
            " give each a path of its own",
        ),
        (
            ("--tcp", "127.0.0.1:{port}", "--state", "{same}", "--control", "{same}"),
            "omsd: state file {same} is the control socket's path too: give each a path of its own",
        ),
        (
            ("--tcp", "127.0.0.1:{port}", "--pty", "{same}", "--state", "{same}"),
            "omsd: state file {same} is board1's pty link too: give each a path of its own",
        ),
    ],
)
def test_one_path_for_two_things_is_refused(
    tmp_path: Path, _runtime: Path, options: tuple[str, ...], expected: str
) -> None:
    """The pty link, the control socket and the state file at one path: each was made over the
    other. ``--pty X --control X`` served a control socket that the pty link replaced at once
    (``omsd ctl`` found a pty there); with ``--state X --control X`` the first save renamed
    the flash over the socket and the daemon's stop removed it with the socket: the flash was
    lost. Now refused before anything is made."""
    same, port = tmp_path / "same", free_port()
    args = [o.format(same=same, port=port) for o in options]
    line = failed(run_omsd(*args, cwd=tmp_path, timeout=10))
    assert line == expected.format(same=same)
    assert not os.path.lexists(same)


@pytest.mark.parametrize("spelling", ["relative", "through a symlinked directory"])
def test_one_path_spelt_two_ways_is_refused(tmp_path: Path, _runtime: Path, spelling: str) -> None:
    """The state file and the control socket at one place, named two ways: ``--state same``
    (relative) or ``--state alias/same`` (``alias`` a symlink to the directory) with
    ``--control DIR/same``. Through the symlink the daemon served: the socket was there, the
    stop's save replaced it and the socket's removal took the flash with it."""
    same, port = tmp_path / "same", free_port()
    (tmp_path / "alias").symlink_to(tmp_path)
    state = "same" if spelling == "relative" else str(tmp_path / "alias" / "same")
    args = ["--tcp", f"127.0.0.1:{port}", "--state", state, "--control", str(same)]
    line = failed(run_omsd(*args, cwd=tmp_path, timeout=10))
    named = same if spelling == "relative" else state  # a relative path is said absolute
    assert line == (
        f"omsd: state file {named} is the control socket's path too: give each a path of its own"
    )
    assert not os.path.lexists(same)


@pytest.mark.parametrize(
    ("other", "expected"),
    [
        ("--state", "the state file's path too"),
        ("--control", "the control socket's path too"),
        ("--pty", "board1's pty link too"),
    ],
)
def test_the_traffic_log_at_another_thing_s_path_is_refused(
    tmp_path: Path, _runtime: Path, other: str, expected: str
) -> None:
    """``--log X --state X``: the daemon served, the log written where the flash is kept; the
    state file read the log as a corrupt flash, and the first save (AP) renamed the log away to
    X.corrupt. ``--log X --control X`` made the log, then refused "a regular file, not a
    socket ... remove it": the file it had made itself. Refused, as the pty link, the control
    socket and the state file at one path are, before the log is opened (nothing made)."""
    same, port = tmp_path / "same", free_port()
    args = ["--tcp", f"127.0.0.1:{port}", "--log", str(same), other, str(same)]
    line = failed(run_omsd(*args, cwd=tmp_path, timeout=10))
    assert line == f"omsd: traffic log {same} is {expected}: give each a path of its own"
    assert not os.path.lexists(same)
