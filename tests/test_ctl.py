"""``omsd ctl`` as a user runs it: a subprocess against a real daemon (also a subprocess), each
subcommand once, its output checked against the board (through the typed client or the board's
TCP endpoint), and its errors: one line on standard error, exit 1 when the daemon refuses, 2 for
a usage error, 3 when the daemon cannot be reached."""

from __future__ import annotations

import grp
import json
import os
import re
import socket
import stat
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from daemon.process import POLL, TIMEOUT, Conn, Daemon, Omsd, daemon_env, run_omsd, wait_for

from omsd import ctl as ctl_module
from omsd.control.client import Control
from omsd.ctl import main as ctl_main

WY = b"PC48 ver 3.00-4"


@dataclass
class Running:
    daemon: Daemon
    socket: Path
    ctl: Control
    started: list[subprocess.Popen[str]] = field(default_factory=list)

    def run(self, *args: str) -> subprocess.CompletedProcess[str]:
        """``omsd ctl --socket SOCKET ARGS``."""
        return run_omsd("ctl", "--socket", str(self.socket), *args)

    def start(self, *args: str) -> subprocess.Popen[str]:
        """``omsd ctl --socket SOCKET ARGS`` running on while the test goes on."""
        proc = subprocess.Popen(
            [sys.executable, "-m", "omsd", "ctl", "--socket", str(self.socket), *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=daemon_env(),
        )
        self.started.append(proc)
        return proc

    def ok(self, *args: str) -> str:
        done = self.run(*args)
        assert (done.returncode, done.stderr) == (0, ""), done
        return done.stdout

    def fails(self, status: int, *args: str) -> str:
        """The one line on standard error of a command that must fail with ``status``."""
        done = self.run(*args)
        assert done.returncode == status, done
        assert done.stdout == "", done
        assert done.stderr.startswith("omsd ctl: ") and done.stderr.count("\n") == 1, done
        return done.stderr

    def axis(self, letter: str = "X") -> dict[str, Any]:
        axis: dict[str, Any] = self.ctl.state()["axes"][letter]
        return axis


def connect_control(path: Path) -> Control:
    """The daemon prints its endpoints before its control socket listens: retry a moment."""
    deadline = time.monotonic() + TIMEOUT
    while True:
        try:
            return Control(path, timeout=TIMEOUT)
        except (FileNotFoundError, ConnectionRefusedError):
            if time.monotonic() > deadline:
                raise
            time.sleep(POLL)


@pytest.fixture
def omsd(tmp_path: Path) -> Iterator[Omsd]:
    starter = Omsd(tmp_path)
    try:
        yield starter
    finally:
        starter.close()


@pytest.fixture
def running(omsd: Omsd, tmp_path: Path) -> Iterator[Running]:
    path = tmp_path / "c.sock"
    daemon = omsd("--board", "PC48-4E", "--tcp", "127.0.0.1:0", "--control", str(path))
    ctl = connect_control(path)
    made = Running(daemon, path, ctl)
    try:
        yield made
    finally:
        ctl.close()
        for proc in made.started:
            if proc.poll() is None:
                proc.kill()
            proc.communicate(timeout=TIMEOUT)


def row(text: str, letter: str) -> list[str]:
    """The cells of axis ``letter`` in an axis table (the limits cell may be "+ -")."""
    for line in text.splitlines():
        if line.startswith(f"{letter} "):
            return line.replace("+ -", "+-").split()
    raise AssertionError(f"no row for {letter} in {text!r}")


COLUMNS = ["axis", "position", "encoder", "velocity", "motion", "done", "limits", "home", "queue"]


# -- looking --------------------------------------------------------------------------------------


def test_boards_and_state(running: Running) -> None:
    host, port = running.daemon.tcp()
    assert running.ok("boards") == f"board1  PC48-4E  driver  tcp {host}:{port}\n"
    with running.daemon.connect() as c:
        c.send(b"AX MR1234 GO ID ")
        c.expect(b"!\x01\n")
        text = running.ok("state")
    lines = text.splitlines()
    assert lines[0] == "board1: PC48-4E, mode AX"
    assert lines[1].split() == COLUMNS
    assert row(text, "X") == ["X", "1234", "1234", "0", "idle", "yes", "none", "no", "200", "free"]
    assert row(text, "Y") == ["Y", "0", "0", "0", "idle", "no", "none", "no", "200", "free"]
    assert "registers: status 0x" in text and ", done 0x00, control 0x00" in text
    assert "I/O lines low 0x0000, outputs driven low 0x0000" in lines
    assert "input buffer: 0 characters" in lines
    assert "link: driver, room 256, pending 0" in lines
    assert re.search(r"^clients: tcp:127\.0\.0\.1:[0-9]+ #[0-9]+ ", text, re.M)
    assert re.search(r"^clock: [0-9.]+ s, running$", text, re.M)
    assert "faults: none" in lines


def test_json_gives_the_operations_result(running: Running) -> None:
    state = json.loads(running.ok("--json", "state"))
    assert state["board"] == "board1" and set(state["axes"]) == {"X", "Y", "Z", "T"}
    assert state["axes"]["X"] == running.ctl.state()["axes"]["X"]
    # the global options may also follow the subcommand
    boards = json.loads(running.ok("boards", "--json"))
    assert boards == running.ctl.boards()
    assert json.loads(running.ok("fault", "--json")) == running.ctl.fault()
    clock = json.loads(running.ok("time", "pause", "--json"))["clock"]
    assert clock["paused"] is True and clock == running.ctl.state()["clock"]


# -- the world ------------------------------------------------------------------------------------


def test_limit_while_moving_gives_at_on_the_driver_link(running: Running) -> None:
    with running.daemon.connect() as c:
        c.send(b"AX VL10000 MR1000000 GO ")
        running.ctl.wait_position("X", 500, timeout=TIMEOUT)
        out = running.ok("limit", "X", "+", "on")
        c.expect(b"@\n")
    assert out.splitlines()[0].split() == COLUMNS
    assert row(out, "X")[6] == "+"
    assert running.axis()["limit_positive"] is True
    assert row(running.ok("limit", "x", "-", "on"), "X")[6] == "+-"
    assert row(running.ok("limit", "X", "+", "off"), "X")[6] == "-"
    assert row(running.ok("limit", "X", "-", "auto"), "X")[6] == "none"
    assert running.axis()["limit_negative"] is False


def test_home_input_slip_encoder(running: Running) -> None:
    assert row(running.ok("home", "Y", "on"), "Y")[7] == "yes"
    assert running.axis("Y")["home"] is True
    assert row(running.ok("home", "Y", "auto"), "Y")[7] == "no"
    assert running.ok("input", "2", "low") == "I/O lines low 0x0004, outputs driven low 0x0000\n"
    assert running.ctl.state()["io_low"] == 0x0004
    assert running.ok("input", "2", "auto") == "I/O lines low 0x0000, outputs driven low 0x0000\n"
    assert row(running.ok("slip", "Z", "-20"), "Z")[1:3] == ["0", "-20"]
    assert running.axis("Z")["encoder"] == -20
    with running.daemon.connect() as c:
        assert c.ask(b"AT ER1,2 ET WY") == WY
        assert row(running.ok("encoder", "T", "300"), "T")[1:3] == ["600", "300"]
        assert c.ask(b"AT RP") == b"600"


def test_stall_and_time(running: Running) -> None:
    assert re.fullmatch(r"clock: [0-9]+\.[0-9]{6} s, running\n", running.ok("time"))
    assert re.fullmatch(r"clock: [0-9.]+ s, paused\n", running.ok("time", "pause"))
    with running.daemon.connect() as c:
        assert c.ask(b"AX VL1000 MR1000 GO WY") == WY
        before = running.ctl.state()["clock"]["now"]
        running.ok("time", "step", "0.1")
        assert running.ctl.state()["clock"]["now"] == pytest.approx(before + 0.1, abs=1e-9)
        assert row(running.ok("stall", "X", "on"), "X")[0] == "X"
        running.ok("time", "step", "0.1")
        axis = running.axis()
        assert axis["encoder"] == pytest.approx(100, abs=2)  # stalled where it was
        assert axis["position"] == pytest.approx(200, abs=2)
        running.ok("stall", "X", "off")
    assert re.fullmatch(r"clock: [0-9.]+ s, paused, scale 10\n", running.ok("time", "scale", "10"))
    assert re.fullmatch(r"clock: [0-9.]+ s, running, scale 10\n", running.ok("time", "resume"))
    clock = running.ctl.state()["clock"]
    assert (clock["paused"], clock["scale"]) == (False, 10.0)
    running.ok("time", "scale", "1")


# -- faults ---------------------------------------------------------------------------------------


def test_fault_options(running: Running) -> None:
    assert running.ok("fault") == "faults: none\n"
    assert running.ok("fault", "--latency", "0.25") == "faults: latency 0.25 s\n"
    assert running.ok("fault", "--baud", "9600") == "faults: latency 0.25 s, baud 9600\n"
    out = running.ok("fault", "--drop", "0.1", "--garble", "0.2", "--seed", "5")
    assert out == "faults: latency 0.25 s, baud 9600, drop 0.1, garble 0.2, seed 5\n"
    assert running.ctl.fault() == {
        "latency": 0.25,
        "baud": 9600,
        "drop": 0.1,
        "garble": 0.2,
        "cable": True,
        "seed": 5,
    }
    assert running.ok("fault", "--baud", "off", "--drop", "0", "--garble", "0") == (
        "faults: latency 0.25 s\n"
    )
    assert running.ok("fault", "--clear") == "faults: none\n"
    with running.daemon.connect() as c:
        assert c.ask(b"WY") == WY
        assert running.ok("fault", "--cut") == "faults: cable cut\n"
        assert c.at_eof()
    with Conn(*running.daemon.tcp()) as late:
        assert late.at_eof()
    assert running.ok("fault", "--connect") == "faults: none\n"
    with running.daemon.connect() as c:
        assert c.ask(b"WY") == WY


# -- power and waiting ----------------------------------------------------------------------------


def test_reset(running: Running) -> None:
    with running.daemon.connect() as c:
        c.send(b"AX MR300 GO ID ")
        c.expect(b"!\x01\n")
        out = running.ok("reset")
        assert out.splitlines()[0] == "board1: power cycled"
        assert [row(out, a)[1] for a in "XYZT"] == ["0", "0", "0", "0"]
        assert c.ask(b"AX RP") == b"0"


def test_wait(running: Running) -> None:
    """The board's time is paused and stepped here, so where the axis is when ``wait`` answers
    does not depend on how long the command takes to start."""
    running.ctl.pause()
    with running.daemon.connect() as c:
        assert c.ask(b"AX VL1000 MR1000 GO ID WY") == WY
        waiting = running.start("wait", "position", "X", "300", "--timeout", "5")
        while (here := running.ctl.step(0.05)["axes"]["X"])["position"] < 300:
            assert here["moving"]
        out, err = waiting.communicate(timeout=TIMEOUT)
        assert (waiting.returncode, err) == (0, "")
        assert row(out, "X")[1:5] == [str(here["position"]), str(here["encoder"]), "1000", "move"]
        waiting = running.start("wait", "done", "X", "--timeout", "5")
        running.ctl.step(1.0)
        out, err = waiting.communicate(timeout=TIMEOUT)
        assert (waiting.returncode, err) == (0, "")
        assert row(out, "X")[1:6] == ["1000", "1000", "0", "idle", "yes"]
        c.expect(b"!\x01\n")
    running.ctl.resume()
    with running.daemon.connect() as c:
        c.send(b"AY VL2000 MR-200 GO ")
        out = running.ok("wait", "idle")
    assert [row(out, a)[4] for a in "XYZT"] == ["idle"] * 4
    assert row(out, "Y")[1] == "-200"
    started = time.monotonic()
    error = running.fails(1, "wait", "done", "Y", "--timeout", "0.2")
    assert time.monotonic() - started >= 0.2
    assert error == "omsd ctl: timed out after 0.2 s waiting for done\n"


# -- errors ---------------------------------------------------------------------------------------


def test_refused_by_the_daemon_exit_1(running: Running) -> None:
    assert "no axis 'Q'" in running.fails(1, "limit", "Q", "+", "on")
    assert "no board 'zz'" in running.fails(1, "--board", "zz", "state")
    assert "paused" in running.fails(1, "time", "step", "0.5")
    assert "scale" in running.fails(1, "time", "scale", "0")
    assert "baud" in running.fails(1, "fault", "--baud", "10")
    assert "bit" in running.fails(1, "input", "99", "low")
    assert "no axis 'Q'" in running.fails(1, "encoder", "Q", "5")
    # a timeout past the daemon's bound: the client's own socket timeout overflowed (a
    # traceback, exit status 1) before the daemon could refuse it
    assert "timeout: expected 0 to 3600.0 s" in running.fails(
        1, "wait", "idle", "--timeout", "1e99"
    )


@pytest.mark.parametrize(
    "args",
    [
        [],
        ["nope"],
        ["limit", "X", "*", "on"],
        ["limit", "X", "+", "maybe"],
        ["limit", "XY", "+", "on"],
        ["home", "X"],
        ["input", "two", "low"],
        ["slip", "X", "lots"],
        ["stall", "X", "auto"],
        ["encoder", "X", "1.5"],
        ["fault", "--clear", "--cut"],
        ["fault", "--cut", "--connect"],
        ["fault", "--latency", "nan"],
        ["time", "step"],
        ["time", "rewind"],
        ["wait"],
        ["wait", "position", "X"],
        ["wait", "done", "X", "--timeout", "-1"],
        ["--tcp", "nowhere", "state"],
        ["--tcp", "127.0.0.1:0", "state"],
    ],
)
def test_usage_errors_exit_2(args: list[str], tmp_path: Path) -> None:
    done = run_omsd("ctl", "--socket", str(tmp_path / "none.sock"), *args)
    assert done.returncode == 2, done
    assert done.stderr.startswith("omsd ctl: ") and done.stderr.count("\n") == 1, done


def test_socket_and_tcp_together_is_a_usage_error(tmp_path: Path) -> None:
    done = run_omsd("ctl", "--socket", str(tmp_path / "x"), "--tcp", "127.0.0.1:9", "state")
    assert done.returncode == 2 and "not allowed with" in done.stderr


def test_daemon_options_before_ctl_are_a_usage_error() -> None:
    done = run_omsd("--view", "plain", "ctl", "state")
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done


def test_unreachable_exit_3(tmp_path: Path) -> None:
    missing = tmp_path / "none.sock"
    done = run_omsd("ctl", "--socket", str(missing), "state")
    assert done.returncode == 3
    assert done.stderr == (
        f"omsd ctl: cannot reach the daemon at {missing}: no such socket; --socket takes the"
        " path of the daemon's --control or [control] socket (the systemd service's is"
        " /run/omsd/control.sock)\n"
    )
    # nobody listening at a TCP port: port 9 (discard) is not served here
    done = run_omsd("ctl", "--tcp", "127.0.0.1:9", "boards")
    assert done.returncode == 3
    assert done.stderr == (
        "omsd ctl: cannot reach the daemon at 127.0.0.1:9: connection refused (nobody listens);"
        " --tcp takes the address of the daemon's [control] tcp\n"
    )


def _ctl_in_process(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    status = ctl_main(list(args))
    out, err = capsys.readouterr()
    return status, out, err


def test_without_a_daemon_it_says_where_it_looked(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """No --socket: the socket of an omsd of this user, then the systemd service's; the one
    line names both and how to point omsd ctl elsewhere (issue 14)."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    service = tmp_path / "service" / "control.sock"
    monkeypatch.setattr(ctl_module, "SERVICE_SOCKET", service)
    status, out, err = _ctl_in_process(capsys, "state")
    assert (status, out) == (3, "")
    assert err == (
        f"omsd ctl: no daemon found: {tmp_path}/omsd/control.sock (an omsd you started): no"
        f" such socket; {service} (the systemd service): no such socket. Start omsd, or point"
        " omsd ctl at the daemon's socket with --socket PATH (or --tcp HOST:PORT)\n"
    )


def test_without_a_daemon_of_ones_own_the_service_is_used(
    running: Running,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A user with no omsd of their own reaches the service's socket without --socket."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path / "nothing-here"))
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    monkeypatch.setattr(ctl_module, "SERVICE_SOCKET", running.socket)
    status, out, err = _ctl_in_process(capsys, "boards")
    assert (status, err) == (0, "")
    assert out.startswith("board1  PC48-4E  driver  tcp 127.0.0.1:")


def test_a_stale_socket_of_ones_own_is_passed_over(
    running: Running,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A socket file left by an omsd that is gone (connection refused) is looked past too."""
    mine = tmp_path / "mine"
    (mine / "omsd").mkdir(parents=True)
    stale = socket.socket(socket.AF_UNIX)
    stale.bind(str(mine / "omsd" / "control.sock"))
    stale.close()  # bound, never listened: connecting is refused
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(mine))
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    monkeypatch.setattr(ctl_module, "SERVICE_SOCKET", running.socket)
    status, out, err = _ctl_in_process(capsys, "boards")
    assert (status, err) == (0, "") and out.startswith("board1  ")


def test_the_service_socket_is_the_units() -> None:
    """SERVICE_SOCKET is $RUNTIME_DIRECTORY/control.sock of systemd/omsd.service."""
    unit = (Path(__file__).resolve().parent.parent / "systemd" / "omsd.service").read_text()
    (directory,) = re.findall(r"^RuntimeDirectory=(\S+)$", unit, re.M)
    assert Path("/run") / directory / "control.sock" == ctl_module.SERVICE_SOCKET


def test_a_control_group_makes_the_socket_the_groups(omsd: Omsd, tmp_path: Path) -> None:
    """[control] group: the socket is 0660 in that group, for its members' omsd ctl."""
    group = grp.getgrgid(os.getegid()).gr_name
    path = tmp_path / "c.sock"
    omsd(
        config=f'[control]\nsocket = "{path}"\ngroup = "{group}"\n[[board]]\ntcp = "127.0.0.1:0"\n',
        expect=1,
    )
    connect_control(path).close()
    st = os.stat(path)
    assert stat.S_IMODE(st.st_mode) == 0o660 and st.st_gid == os.getegid()


def test_a_board_port_is_not_a_control_endpoint(running: Running) -> None:
    host, port = running.daemon.tcp()
    done = run_omsd("ctl", "--tcp", f"{host}:{port}", "boards")
    assert done.returncode == 3
    assert done.stderr == (
        f"omsd ctl: {host}:{port} is not an omsd control endpoint (its reply is not JSON)\n"
    )


def test_help_exits_0() -> None:
    done = run_omsd("ctl", "--help")
    assert done.returncode == 0 and "omsd ctl" in done.stdout
    for command in ("boards", "state", "limit", "home", "input", "slip", "stall", "encoder"):
        assert command in done.stdout
    assert "ctl" in run_omsd("--help").stdout


# -- several boards and the TCP control endpoint --------------------------------------------------

TWO_BOARDS = """
[control]
tcp = "127.0.0.1:0"

[[board]]
name = "xy"
model = "PC48-4E"
tcp = ["127.0.0.1:0"]

[[board]]
name = "servo"
model = "PCIX-400"
link = "raw"
tcp = ["127.0.0.1:0"]
"""


def test_board_option_and_the_tcp_control_endpoint(omsd: Omsd, tmp_path: Path) -> None:
    path = tmp_path / "c.sock"
    daemon = omsd("--control", str(path), config=TWO_BOARDS, expect=2)
    connect_control(path).close()
    found: list[str] = []

    def logged() -> bool:
        found[:] = re.findall(r"control tcp (127\.0\.0\.1:[0-9]+)", daemon.stderr)
        return bool(found)

    assert wait_for(logged), daemon.stderr
    address = found[0]
    done = run_omsd("ctl", "--tcp", address, "boards")
    assert done.returncode == 0, done
    assert [line.split()[:3] for line in done.stdout.splitlines()] == [
        ["xy", "PC48-4E", "driver"],
        ["servo", "PCIX-400", "raw"],
    ]
    done = run_omsd("ctl", "--socket", str(path), "state")
    assert done.returncode == 1
    assert done.stderr == "omsd ctl: several boards: say which (xy, servo)\n"
    done = run_omsd("ctl", "--tcp", address, "--board", "servo", "limit", "Y", "-", "on")
    assert done.returncode == 0, done
    with Control(path) as ctl:
        assert ctl.state("servo")["axes"]["Y"]["limit_negative"] is True
        assert ctl.state("xy")["axes"]["Y"]["limit_negative"] is False
    done = run_omsd("ctl", "--socket", str(path), "state", "--board", "xy")
    assert done.returncode == 0 and done.stdout.startswith("xy: PC48-4E, mode AX\n"), done
