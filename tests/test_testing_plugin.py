"""The pytest plugin ``omsd.testing``: the ``omsd_boards`` fixture as a user's test suite sees it.

Users' test files run in a pytest of their own (``pytester.runpytest_subprocess``), so start-up,
the failure messages, the report section and the teardown are observed from outside, the way a
user would meet them. The complete example of the README's section "In your own tests: the pytest
fixture" is read from README.md and run as it is. After every inner run no ``omsd`` process whose
command line points into the inner run's directory may be alive, and no socket or pty link may
be left there: teardown leaks nothing.

The plugin is found through the ``pytest11`` entry point once omsd is installed; in a checkout
whose installed metadata predates the entry point the inner runs load it with ``-p omsd.testing``
(both at once would register the module twice).
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import re
import shutil
import signal
import stat
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest
from ipv6 import needs_loopback

from omsd.control.client import Control
from omsd.testing import Omsd, OmsdBoards, _Plan, _toml_value

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
RUN_TIMEOUT = 120.0  # seconds for a whole inner pytest run (each of its waits is bounded too)
STOP = 10.0  # seconds a daemon may take to stop


# -- helpers ------------------------------------------------------------------------------------


def readme_block(heading: str, language: str = "python") -> str:
    """The first ``language`` code block of the README section ``heading`` (a whole line; the
    section ends at the next heading of its level or above, outside code blocks)."""
    lines = README.read_text().splitlines(keepends=True)
    level = len(heading.split(" ")[0])
    start = lines.index(heading + "\n")
    fenced = False
    block: list[str] | None = None
    for line in lines[start + 1 :]:
        if line.startswith("```"):
            if block is not None and fenced:
                return "".join(block)
            fenced = not fenced
            if fenced and line.strip() == f"```{language}":
                block = []
            continue
        if fenced:
            if block is not None:
                block.append(line)
        elif (m := re.match(r"(#+) ", line)) and len(m.group(1)) <= level:
            break
    raise AssertionError(f"no {language} block in README section {heading!r}")


def entry_point_installed() -> bool:
    return any(
        ep.value == "omsd.testing"
        for ep in importlib.metadata.entry_points(group="pytest11", name="omsd")
    )


def run_inner(pytester: pytest.Pytester, *args: str) -> pytest.RunResult:
    plugin = [] if entry_point_installed() else ["-p", "omsd.testing"]
    return pytester.runpytest_subprocess(
        *plugin, "-p", "no:cacheprovider", "-rA", *args, timeout=RUN_TIMEOUT
    )


def omsd_processes(under: Path) -> list[int]:
    """Live ``python -m omsd`` (or ``omsd.tethered``, the plugin's) processes with an argument
    inside ``under``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().decode(errors="replace").split("\0")
            state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue  # gone meanwhile
        if state == "Z":
            continue
        ours = any(a == "omsd" or a.startswith("omsd.") for a in argv)
        if ours and any(a.startswith(str(under)) for a in argv):
            found.append(int(entry.name))
    return found


def leftovers(under: Path) -> list[str]:
    """Sockets and pty links left in ``under``."""
    found = []
    for directory, dirs, files in os.walk(under):
        for name in dirs + files:
            path = Path(directory) / name
            mode = path.lstat().st_mode
            if stat.S_ISSOCK(mode) or (stat.S_ISLNK(mode) and "/dev/pts" in os.readlink(path)):
                found.append(str(path))
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def assert_clean(pytester: pytest.Pytester) -> None:
    assert omsd_processes(pytester.path) == []
    assert leftovers(pytester.path) == []


# -- the README's example, as a user runs it ------------------------------------------------------


def test_readme_example_passes_and_leaves_nothing(pytester: pytest.Pytester) -> None:
    example = readme_block("### In your own tests: the pytest fixture")
    assert "omsd_boards(" in example and "set_limit" in example and '== b"@\\n"' in example
    pytester.makepyfile(test_stage=example)
    result = run_inner(pytester)
    result.assert_outcomes(passed=1)
    assert_clean(pytester)


def test_readme_client_example_runs_against_a_daemon(tmp_path: Path) -> None:
    """The README's control-client example, pointed at a daemon's socket, runs through."""
    example = readme_block("## Reaching behind the board: the control API")
    assert example.count("Control()") == 1
    factory = OmsdBoards(tmp_path)
    try:
        daemon = factory()  # the one PC48-4E the example's calls without board= need
        code = example.replace("Control()", f"Control({str(daemon.control_socket)!r})")
        exec(compile(code, "README.md", "exec"), {})
        x = daemon.control.state()["axes"]["X"]
        y = daemon.control.state()["axes"]["Y"]
        assert not x["limit_positive"] and y["encoder"] == 200 and y["position"] == 0
        assert daemon.control.state()["io_low"] == 1 << 3
        assert daemon.control.state()["faults"]["cable"] is True
    finally:
        problems = factory.close()
    assert problems == []
    assert not alive(daemon.pid)


def test_readme_several_boards_example_runs(tmp_path: Path) -> None:
    """The README's second fixture example (a test with three boards) does what its comments
    say: its test function is called with the fixture's factory, and the daemon it made is
    looked at afterwards."""
    lines = README.read_text().splitlines()
    start = lines.index("### In your own tests: the pytest fixture")
    blocks = re.findall(r"^```python\n(.*?)^```$", "\n".join(lines[start:]) + "\n", re.M | re.S)
    example = blocks[1]
    assert "boards={" in example and "pty=True" in example
    factory = OmsdBoards(tmp_path)
    made: list[Omsd] = []

    def omsd_boards(*args: object, **kwargs: object) -> Omsd:
        made.append(factory(*args, **kwargs))  # type: ignore[arg-type]
        return made[-1]

    names: dict[str, object] = {}
    try:
        exec(compile(example, "README.md", "exec"), names)
        (test,) = [f for name, f in names.items() if name.startswith("test_") and callable(f)]
        test(omsd_boards)
        (boards,) = made
        assert list(boards.boards) == ["z-stage", "xy", "servo"]
        assert boards["servo"].host == "127.0.0.1" and boards["xy"].device.startswith("/dev/pts/")
        xy = boards.control.state("xy")
        assert xy["axes"]["Y"]["home"] and xy["io_low"] & 1
        assert boards.control.boards()[2]["link"] == "raw"
    finally:
        problems = factory.close()
    assert problems == []


# -- what the fixture offers --------------------------------------------------------------------

FEATURES = """
import json
import os
from pathlib import Path

RECORD = Path({record!r})


def test_boards_endpoints_links_and_worlds(omsd_boards):
    boards = omsd_boards(
        {{"model": "PC48-4", "axes": {{"X": {{"positive_limit": 3000}}}}}},
        servo={{"model": "PCIX-400", "link": "raw"}},
        boards={{"z-stage": {{"model": "VS4-040", "inputs": {{0: False}}}}}},
        pty=True,
        state=True,
    )
    RECORD.write_text(json.dumps({{
        "pid": boards.pid,
        "socket": str(boards.control_socket),
        "ptys": [str(b.pty) for b in boards.boards.values()],
    }}))
    assert list(boards.boards) == ["board1", "z-stage", "servo"]
    assert [b["name"] for b in boards.control.boards()] == list(boards.boards)
    assert (boards["board1"].model, boards["servo"].link) == ("PC48-4", "raw")
    for board in boards.boards.values():
        assert board.host == "127.0.0.1" and board.port > 0
        assert board.pty.parent == boards.directory
        assert os.readlink(board.pty) == board.device and board.device.startswith("/dev/pts/")

    with boards.connect("board1") as link:  # the driver link on TCP
        assert link.ask(b"WY") == b"PC48 ver 3.00-4"
        link.send(b"AX VL10000 MR10000 GO")  # the world: a + limit at 3000 steps
        assert link.read_until(b"\\n") == b"@\\n"
        x = boards.control.wait_idle(board="board1")["axes"]["X"]
        assert x["limit_positive"] and 3000 <= x["position"] < 3100
        boards.control.cut_cable(board="board1")
        assert link.at_eof()

    port = boards.serial("servo", pty=True)  # the raw PCIx link on its pty, through pyserial
    port.write(b"WY\\n")
    # the WY page: "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems", text<LF><CR> raw
    assert port.read_until(b"\\n\\r") == (
        b"PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems\\n\\r"
    )
    port = boards.serial("z-stage")  # pyserial on TCP
    port.write(b"WY")
    # VS4 WY: "<LF><CR>VS4-040 ver 1.00 S/N 123456<LF><CR>", LF-ended by the driver link
    assert port.read_until(b"\\n") == b"VS4-040 ver 1.00 S/N 123456\\n"
    assert boards.control.state("z-stage")["io_low"] & 1  # inputs = {{0 = false}}: driven low
    assert "state file" in boards.stderr  # state=True: the daemon has one
"""


def test_fixture_serves_what_was_asked_and_cleans_up(pytester: pytest.Pytester) -> None:
    record = pytester.path / "record.json"
    pytester.makepyfile(test_features=FEATURES.format(record=str(record)))
    result = run_inner(pytester)
    result.assert_outcomes(passed=1)
    seen = json.loads(record.read_text())
    assert not alive(seen["pid"]), "the daemon outlived its test"
    assert not os.path.lexists(seen["socket"])
    assert len(seen["ptys"]) == 3 and not any(os.path.lexists(p) for p in seen["ptys"])
    assert_clean(pytester)


# -- failures, as the user sees them --------------------------------------------------------------

FAILURES = """
import os
import signal


def test_bad_model(omsd_boards):
    omsd_boards(stage="PC99")


def test_daemon_dies(omsd_boards):
    boards = omsd_boards()
    os.kill(boards.pid, signal.SIGKILL)
    boards.process.wait()


def test_stopped_on_purpose(omsd_boards):
    boards = omsd_boards("PC46-4E")
    link = boards.connect()
    assert boards.stop() == 0
    assert not boards.running() and link.at_eof()


def test_failure_report(omsd_boards):
    boards = omsd_boards()
    with boards.connect() as link:
        link.ask(b"WY")
    assert False, "the test's own failure"
"""


def test_failures_are_one_line_and_reported_once(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(test_failures=FAILURES)
    result = run_inner(pytester)
    result.assert_outcomes(passed=2, failed=2, errors=1)  # test_daemon_dies: passed, then errored
    out = result.stdout.str()
    # the daemon's own one-line error, in the test's failure; not again at teardown
    result.stdout.fnmatch_lines(
        [
            "*omsd_boards: omsd did not start (0 of 1 endpoint lines, exit status 2): "
            'omsd: *omsd.toml:*: ?board "*"*? model: expected a board model (*), got "PC99"'
        ]
    )
    assert "ERROR at teardown of test_bad_model" not in out
    result.stdout.fnmatch_lines(
        [
            "*ERROR at teardown of test_daemon_dies*",
            "*omsd_boards teardown: omsd exited by itself during the test (status -9)*",
        ]
    )
    # the report of a failed test ends with the daemon's traffic
    result.stdout.fnmatch_lines(
        ["*__ test_failure_report __*", "*the test's own failure*", "*- omsd -*", "*<- WY*"]
    )
    assert_clean(pytester)


# -- the plugin itself --------------------------------------------------------------------------


def test_entry_point_is_declared() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["entry-points"]["pytest11"] == {"omsd": "omsd.testing"}
    installed = importlib.metadata.entry_points(group="pytest11", name="omsd")
    assert all(ep.value == "omsd.testing" for ep in installed)


def test_loading_the_plugin_starts_nothing() -> None:
    """Every pytest run of an installation loads the plugin: it must not start a daemon, a
    thread or import the daemon's modules."""
    code = (
        "import sys, threading, omsd.testing\n"
        "heavy = [m for m in ('omsd.control.client', 'omsd.config', 'omsd.daemon') "
        "if m in sys.modules]\n"
        "print(heavy, threading.active_count())\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=30, check=True
    )
    assert out.stdout.split() == ["[]", "1"]


def test_control_socket_moves_out_of_a_deep_directory(tmp_path: Path) -> None:
    """A Unix socket path has at most 107 bytes; a deep tmp_path gets a short directory."""
    deep = tmp_path / ("d" * 60) / ("e" * 60)
    factory = OmsdBoards(deep)
    try:
        daemon = factory(link="raw")
        assert not daemon.control_socket.is_relative_to(deep)
        assert len(os.fsencode(daemon.control_socket)) <= 100
        assert daemon.control.boards()[0]["link"] == "raw"
        with Control(daemon.control_socket) as other:  # the socket is usable by the user
            assert other.state()["model"] == "PC48-4E"
        scratch = daemon.control_socket.parent
    finally:
        problems = factory.close()
    assert problems == []
    assert not scratch.exists() and not alive(daemon.pid)


def test_config_values_are_written_as_toml() -> None:
    plan = _Plan()
    odd = 'a "quoted" \\ back\tslash\n\x01\x7f é 😀'
    plan.table("[[board]]", {"name": odd, "inputs": {0: False, 3: True}, "tcp": ["1", 2]})
    plan.table("[[board]]", {"axes": {"X": {"positive_limit": 2.5, "home_low": -3}}})
    document = tomllib.loads(plan.text)
    assert document["board"][0] == {
        "name": odd,
        "inputs": {"0": False, "3": True},
        "tcp": ["1", 2],
    }
    assert document["board"][1] == {"axes": {"X": {"positive_limit": 2.5, "home_low": -3}}}
    with pytest.raises(ValueError, match="finite"):
        _toml_value(float("nan"), "x")
    with pytest.raises(TypeError, match="cannot write"):
        _toml_value(object(), "x")


def test_stop_with_a_signal_is_not_a_teardown_problem(tmp_path: Path) -> None:
    factory = OmsdBoards(tmp_path)
    try:
        daemon = factory("PC48-2")
        assert daemon.stop(signal.SIGINT) == 0
    finally:
        problems = factory.close()
    assert problems == []


def test_a_daemon_not_ready_in_time_is_killed(tmp_path: Path) -> None:
    factory = OmsdBoards(tmp_path)
    try:
        with pytest.raises(pytest.fail.Exception, match="not ready in time, killed") as failed:
            factory(timeout=0.0)  # no Python starts in no time
        assert "\n" not in str(failed.value)
        (daemon,) = factory.daemons
        assert not alive(daemon.pid)
    finally:
        problems = factory.close()
    assert problems == []


@needs_loopback
def test_serial_reaches_a_board_served_on_ipv6(tmp_path: Path) -> None:
    """``serial()`` on a board served on [::1] opened ``socket://::1:PORT``, a URL with no
    host pyserial can read; it is ``socket://[::1]:PORT`` (RFC 3986 §3.2.2)."""
    pytest.importorskip("serial")
    factory = OmsdBoards(tmp_path)
    try:
        daemon = factory(xy={"model": "PC48-2", "tcp": "[::1]:0"})
        assert daemon.board("xy").tcp is not None and daemon.board("xy").tcp[0] == "::1"
        port = daemon.serial("xy")
        port.write(b"WY")
        assert port.read_until(b"\n") == b"PC48 ver 3.00-2\n"
    finally:
        problems = factory.close()
    assert problems == []


# -- a test run that dies -----------------------------------------------------------------------

ABANDONED = """
import json
import time
from pathlib import Path


def test_run_is_killed_here(omsd_boards):
    boards = omsd_boards(pty=True)
    link = boards["board1"].pty
    Path({record!r}).write_text(
        json.dumps({{"pid": boards.pid, "socket": str(boards.control_socket), "pty": str(link)}})
    )
    time.sleep(60)
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_a_killed_test_run_takes_its_daemons_with_it(
    pytester: pytest.Pytester, sig: signal.Signals
) -> None:
    """A run stopped by a CI timeout (SIGTERM: Python's default action, no teardown) or the
    OOM killer (SIGKILL) cannot tear down its fixtures; the daemon of its test, in a session of
    its own, lived on, serving its ports, socket and pty link for ever. It stops when the run
    that started it has gone: it reads its standard input, a pipe whose other end only the run
    holds, and the end of that file is SIGTERM, a clean stop."""
    record = pytester.path / "record.json"
    pytester.makepyfile(test_abandoned=ABANDONED.format(record=str(record)))
    plugin = [] if entry_point_installed() else ["-p", "omsd.testing"]
    run = pytester.popen(
        [sys.executable, "-m", "pytest", *plugin, "-p", "no:cacheprovider", "-q"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + RUN_TIMEOUT
        while not record.exists() or not record.read_text():
            assert run.poll() is None and time.monotonic() < deadline, "the daemon did not start"
            time.sleep(0.05)
        seen = json.loads(record.read_text())
        run.send_signal(sig)
        run.wait(STOP)
        deadline = time.monotonic() + STOP
        while alive(seen["pid"]) and time.monotonic() < deadline:
            time.sleep(0.05)
        orphan = alive(seen["pid"])
    finally:
        if run.poll() is None:
            run.kill()
            run.wait()
    if orphan:
        os.kill(seen["pid"], signal.SIGKILL)
    socket_path = Path(seen["socket"])
    left = os.path.lexists(socket_path)
    if not socket_path.is_relative_to(pytester.path):  # the short directory of a deep path:
        shutil.rmtree(socket_path.parent)  # the run that made it could not remove it
    assert not orphan, "the daemon outlived the test run that started it"
    assert not left and not os.path.lexists(seen["pty"])
    assert_clean(pytester)


def test_a_misspelt_option_is_named_as_one(tmp_path: Path) -> None:
    """``omsd_boards(ptty=True)`` took ``ptty`` for a board and said "board ptty: expected a
    model name or a table of [[board]] keys, got True": the user wrote an option. The message
    names the keyword and the options it might have meant; nothing is started."""
    factory = OmsdBoards(tmp_path)
    try:
        with pytest.raises(TypeError) as raised:
            factory(stage="PC48-4E", ptty=True)
        message = str(raised.value)
        assert message.startswith("omsd_boards(ptty=True): ptty is no option (")
        assert "pty" in message.split("(", 2)[2] and "[[board]]" in message
        with pytest.raises(TypeError, match=r"^board stage: expected a model name"):
            factory(boards={"stage": 42})  # not a keyword: a board, as before
        assert factory.daemons == []
    finally:
        assert factory.close() == []


def test_the_documented_switches(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    """README: "``-p no:omsd`` turns it off, and ``-p omsd`` on where
    ``PYTEST_DISABLE_PLUGIN_AUTOLOAD=1``"."""
    if not entry_point_installed():
        pytest.skip("omsd's installed metadata has no pytest11 entry point")
    pytester.makepyfile(test_one="def test_one(omsd_boards):\n    omsd_boards()\n")
    off = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-p", "no:omsd")
    off.assert_outcomes(errors=1)
    off.stdout.fnmatch_lines(["*fixture 'omsd_boards' not found*"])
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    on = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-p", "omsd")
    on.assert_outcomes(passed=1)
    assert_clean(pytester)


def test_every_endpoint_a_board_table_names_is_waited_for(tmp_path: Path) -> None:
    """A board's table passes any ``[[board]]`` key through, ``rfc2217`` and ``serial_port``
    too, and the daemon prints an endpoint line for each of them; the fixture counted the lines
    of ``tcp`` and ``pty`` only, so it returned early and parsed the first lines: here it said
    "no board 'z'; boards: xy". Every endpoint line is waited for."""
    factory = OmsdBoards(tmp_path)
    try:
        daemon = factory(
            xy={"model": "PC48-4E", "tcp": False, "rfc2217": ["127.0.0.1:0", "127.0.0.1:0"]},
            z="PC48-2",
        )
        assert daemon["xy"].tcp is None and len(daemon["xy"].rfc2217s) == 2
        assert daemon["z"].tcp is not None
        with daemon.connect("z") as link:
            assert link.ask(b"WY") == b"PC48 ver 3.00-2"
    finally:
        assert factory.close() == []
