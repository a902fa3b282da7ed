"""The README's examples, run as printed (issue 14: "A newcomer's first hour").

The README's conventions, which every block added to it follows:

* A fenced block tagged ```` ```sh ```` or ```` ```python ```` is run by this module, as
  printed, and must succeed (shell blocks with ``bash -e -o pipefail``).
* A block immediately preceded by an HTML comment line ``<!-- not run: REASON -->`` is not
  run; the reason must be given (say why, and what runs it instead if anything does).
* Untagged blocks and ```` ```text ````, ```` ```toml ````, ```` ```json ````,
  ```` ```console ```` blocks are shown output or file contents, not run. A ```` ```toml ````
  block with a ``[[board]]`` table is a complete configuration: it is loaded and must be valid.
  A shown session of ``omsd`` commands (lines ``$ omsd ...`` each followed by what it prints)
  is compared with what the commands print.
* A ```` ```text ```` block preceded by ``<!-- output of: COMMAND -->`` is generated: it must be
  what COMMAND prints now (``omsd --help``, whose text changes with the code).
  ``python tests/test_readme.py --write`` regenerates every such block.

How a block is run (``tests/readme_blocks.py`` has the machinery):

* Each block runs in a sandbox of its own: its own network namespace when the tests run as root
  (as in CI: the README's fixed ports, 7048, 7001 ..., are then always free), its own
  ``$HOME`` and ``$XDG_RUNTIME_DIR``, ``omsd`` and ``python3`` of this checkout's environment
  first on ``PATH``, and a copy of the checkout as its working directory (so relative paths
  such as ``config/omsd.toml`` work, and what a block writes goes to the copy).
* A block that starts the daemon (``omsd`` with no subcommand) is run until the daemon is ready
  (``READY=1``, as systemd sees it), then the daemon is sent SIGTERM: the block must exit 0, and
  the pty links it announced must be in the runtime directory or the checkout.
* Every other block runs while a daemon is running beside it, as it would for a reader who
  started one in another terminal: the one a block earlier in the same section starts (the
  section's ``omsd --config ...``), else ``omsd`` with no arguments (the README's first command:
  board1, a PC48-4E on 127.0.0.1:7048 and a pty). That daemon must still be running after the
  block and exit 0 on SIGTERM.
* In a Python block, an expression statement whose comment starts with a Python literal states
  its value, and the value is checked: ``port.read_until(b"\\n")  # b'1000000\\n'``. A comment
  that starts with a word (``# e.g. 40123``) states nothing. A block that defines ``test_*``
  functions is a test file: pytest runs it, with the ``omsd_boards`` fixture as a user gets it.
* What a shell block prints is checked where the README says it (``OUTPUTS`` below).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from readme_blocks import (
    BIN,
    COLUMNS,
    EXPECT,
    README,
    ROOT,
    Block,
    Sandbox,
    blocks,
    commands,
    copy_checkout,
    literal_prefix,
    starts_daemon,
    with_checks,
)

from omsd.config import load_config, runtime_directory

ALL = blocks()
RUN = [b for b in ALL if b.runs]
NOT_RUN = [b for b in ALL if b.marker_kind == "not run"]
GENERATED = [b for b in ALL if b.output_of is not None]
CONFIGS = [b for b in ALL if b.language == "toml" and "[[board]]" in b.text]
SESSIONS = [b for b in ALL if b.language in ("", "console") and b.text.startswith("$ omsd ")]

# The command file of the PC48 manual's §7.3.4 run against config/plotter.toml, and what the
# README says it answers: "#" (pl is no PC48 command), "@" "@" (the jogs into the minus limits),
# "!" and the done flags X, Y, X and Y (the homes and the centring move), one a line, as cat -v
# shows them.
PLOTTER_MARKERS = "#\n@\n@\n!^A\n!^B\n!^C\n"


def following_text(block: Block) -> str:
    """The shown output right after ``block`` (the next block, untagged or text)."""
    after = ALL[ALL.index(block) + 1]
    assert after.language in ("", "text"), f"no output shown after {block.id}"
    return after.text


# What a shell block prints, where the README says it: a substring that picks the block (exactly
# one), and the output (bytes: exactly; a pattern: found in it; NEXT: the block shown after it).
NEXT = object()
OUTPUTS: dict[str, object] = {
    "printf 'AX VL5000 MR1000 GO ID": b"!\x01\n",  # "prints !<0x01> when X is done"
    "nc -N 127.0.0.1 7010": NEXT,  # the command file's markers
    "~/omsd-env/bin/omsd --version": b"omsd 0.1.0\n",
    "omsd ctl boards": re.compile(rb"^xy +PC48-4E +driver +tcp 127\.0\.0\.1:7001", re.M),
}


# -- the sandbox ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def checkout(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return copy_checkout(tmp_path_factory.mktemp("checkout"))


@pytest.fixture
def sandbox(tmp_path: Path, checkout: Path) -> Iterator[Sandbox]:
    box = Sandbox(tmp_path, checkout)
    try:
        yield box
    finally:
        box.close()


def section_daemon(block: Block) -> Block | None:
    """The block that starts the daemon ``block`` talks to: the last one before it in its
    section, or None for the default daemon."""
    found = None
    for other in ALL:
        if other is block:
            return found
        if other.section_line == block.section_line and other.runs and other.starts_daemon():
            found = other
    raise AssertionError(block)


def check_endpoints(run_stdout: bytes, sandbox: Sandbox) -> None:
    """A daemon's endpoint lines: at least one, every pty link in the runtime directory or the
    checkout."""
    lines = run_stdout.decode().splitlines()
    endpoints = [s for s in lines if re.match(r"\S+ \S+ (driver|raw) (tcp|pty) ", s)]
    assert endpoints, f"no endpoint lines: {lines}"
    for line in endpoints:
        if " pty " in line:
            link = Path(line.split(" pty ", 1)[1].split(" -> ")[0])
            assert link.is_relative_to(sandbox.runtime) or link.is_relative_to(sandbox.cwd), line


def disk_usage(path: Path) -> int:
    """Bytes in the files under ``path``, as du counts them (allocated blocks)."""
    return sum(p.lstat().st_blocks * 512 for p in path.rglob("*") if not p.is_dir())


def check_the_stated_install(sandbox: Sandbox) -> None:
    """What the README says of the user's install (the block just run): how many packages it
    brings and how much room they take, next to a new environment's own (pip, setuptools)."""
    text = " ".join(README.read_text().split())
    stated = re.search(
        r"(\d+) packages with their own dependencies, (\d+) MB in the environment", text
    )
    assert stated, "the README no longer states the install's size"
    packages, megabytes = int(stated.group(1)), int(stated.group(2))
    env = sandbox.home / "omsd-env"
    listed = subprocess.run(
        [str(env / "bin" / "pip"), "list", "--format=freeze"],
        capture_output=True,
        text=True,
        check=True,
        timeout=60,
    ).stdout.split()
    names = {line.split("==")[0].lower() for line in listed} - {"pip", "setuptools"}
    assert {"omsd", "rich", "aiomqtt"} <= names and len(names) == packages, names
    empty = sandbox.root / "empty-env"
    subprocess.run([str(BIN / "python3"), "-m", "venv", str(empty)], check=True, timeout=120)
    size = (disk_usage(env) - disk_usage(empty)) / 1e6
    assert 0.7 * megabytes <= size <= 1.4 * megabytes, f"{size:.1f} MB, the README says {megabytes}"


# -- every block ------------------------------------------------------------------------------


def openbsd_nc() -> bool:
    """Whether ``nc`` is OpenBSD's, with ``-N`` (what the README's nc lines use)."""
    found = shutil.which("nc")
    if found is None:
        return False
    usage = subprocess.run([found, "-h"], capture_output=True, timeout=30, check=False)
    return b"-N" in usage.stdout + usage.stderr


@pytest.mark.parametrize("block", RUN, ids=lambda b: b.id)
def test_block_runs_as_printed(block: Block, sandbox: Sandbox) -> None:
    if any(words[:2] == ["nc", "-N"] for words in commands(block.text)) and not openbsd_nc():
        if os.environ.get("OMSD_NEED_NC"):
            pytest.fail("OpenBSD nc (netcat-openbsd) is required here and missing")
        pytest.skip("no OpenBSD nc with -N here (.ci/run installs netcat-openbsd)")
    if block.starts_daemon():
        run = sandbox.wait_ready(sandbox.block(block))
        check_endpoints(run.stdout, sandbox)
        status = sandbox.stop(run)
        assert status == 0, f"exit status {status} after SIGTERM:\n{run.report()}"
        return
    if block.installs:
        run = sandbox.block(block)
        assert sandbox.finish(run) == 0, run.report()
        if "~/omsd-env" in block.text:
            check_the_stated_install(sandbox)
    else:
        source = section_daemon(block)
        daemon = sandbox.wait_ready(
            sandbox.block(source) if source else sandbox.shell("omsd", "omsd (the default board)")
        )
        run = sandbox.block(block)
        status = sandbox.finish(run)
        assert status == 0, run.report()
        assert daemon.proc.poll() is None, f"the daemon died during the block:\n{daemon.report()}"
        assert sandbox.stop(daemon) == 0, daemon.report()
    expected = [v for k, v in OUTPUTS.items() if k in block.text]
    for value in expected:
        if value is NEXT:
            assert run.stdout.decode() == following_text(block), run.report()
        elif isinstance(value, bytes):
            assert run.stdout == value, run.report()
        else:
            assert isinstance(value, re.Pattern)
            assert value.search(run.stdout), run.report()


def test_the_outputs_named_here_pick_one_block_each() -> None:
    for key in OUTPUTS:
        assert len([b for b in RUN if key in b.text]) == 1, key


def test_blocks_are_found() -> None:
    """The collector sees the README's blocks (a broken fence would hide the rest)."""
    assert len([b for b in RUN if b.language == "sh"]) >= 4
    assert len([b for b in RUN if b.language == "python"]) >= 4
    assert any(b.starts_daemon() and "config/omsd.toml" in b.text for b in RUN)
    last = ALL[-1]
    assert last.line + last.text.count("\n") < len(README.read_text().splitlines()), (
        f"README.md line {last.line}: a fence that is never closed"
    )


def test_values_stated_in_comments_are_checked() -> None:
    """The rewrite that checks ``expr  # literal``: only a leading literal counts, the line
    numbers stay, and a wrong statement fails with the README's line."""
    source = (
        "x = [1]  # 2\n"
        "x + [2]  # [1, 2] and some words\n"
        "len(x)  # one, not checked\n"
        "x; len(x)  # 1\n"
        "if x:\n"
        "    b'a' + b'b'  # b'ab'\n"
    )
    checked_source, checked = with_checks(source, 10)
    assert checked == [11, 13, 15]
    assert len(checked_source.splitlines()) == len(source.splitlines())
    namespace: dict[str, object] = {"_readme_expect": expect}
    exec(compile(checked_source, "README.md", "exec"), namespace)
    wrong, _ = with_checks("1 + 1  # 3\n", 42)
    with pytest.raises(AssertionError, match=r"README\.md line 42: the comment says 3"):
        exec(compile(wrong, "README.md", "exec"), {"_readme_expect": expect})
    assert literal_prefix("# b'!\\x01\\n' 3.3 s later") == "b'!\\x01\\n'"
    assert literal_prefix("# [{'name': 'board1', ...}]") is None
    assert literal_prefix("# e.g. 40123") is None


def expect(value: object, expected: object, line: int) -> object:
    """What the sandbox defines as ``_readme_expect`` (readme_blocks.EXPECT)."""
    namespace: dict[str, object] = {}
    exec(EXPECT, namespace)
    check = namespace["_readme_expect"]
    assert callable(check)
    return check(value, expected, line)


def test_the_readmes_stated_values_are_checked() -> None:
    """The pyserial example's two replies and the Harness example's RA are checked."""
    python = [b for b in RUN if b.language == "python"]
    counts = {b.text.split("\n")[0]: len(with_checks(b.text, b.line + 1)[1]) for b in python}
    assert counts["import serial"] == 2
    assert counts["from omsd.board.harness import Harness"] == 1


@pytest.mark.parametrize("block", NOT_RUN, ids=lambda b: b.id)
def test_a_block_not_run_says_why(block: Block) -> None:
    assert block.not_run, f"README.md line {block.marker_line}: `not run:` without a reason"
    assert block.language in ("sh", "python"), (
        f"README.md line {block.marker_line}: `not run` before a {block.language or 'text'} "
        "block, which is never run anyway"
    )


def test_every_marker_is_in_front_of_a_block() -> None:
    """A ``not run`` or ``output of`` comment that is not right before a fence (a block moved
    or removed) marks nothing: an error, not a silent no-op."""
    used = {b.marker_line for b in ALL if b.marker is not None}
    for n, line in enumerate(README.read_text().splitlines(), 1):
        if re.match(r"\s*<!--\s*(not run|output of)\b", line):
            assert n in used, f"README.md line {n}: {line.strip()} is not in front of a block"


@pytest.mark.parametrize("block", CONFIGS, ids=lambda b: b.id)
def test_a_shown_configuration_is_valid(block: Block, tmp_path: Path) -> None:
    path = tmp_path / "shown.toml"
    path.write_text(block.text)
    assert load_config(path).boards


# -- generated output -------------------------------------------------------------------------


def output_of(command: str) -> str:
    """What ``command`` (an ``omsd`` command line) prints, at the README's width."""
    words = command.split()
    assert words[0] == "omsd", command
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_")}
    env["COLUMNS"] = COLUMNS
    result = subprocess.run(
        [str(BIN / "omsd"), *words[1:]],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


@pytest.mark.parametrize("block", GENERATED, ids=lambda b: b.id)
def test_generated_output_is_current(block: Block) -> None:
    assert block.output_of is not None
    expected = output_of(block.output_of)
    assert block.text == expected, (
        f"README.md line {block.line}: the output of `{block.output_of}` has changed; "
        "regenerate it with: .venv/bin/python tests/test_readme.py --write"
    )


def test_the_readme_shows_omsd_help() -> None:
    assert "omsd --help" in [b.output_of for b in GENERATED]


def write_generated(path: Path = README) -> int:
    """Regenerate every ``output of`` block of ``path``; the number of blocks changed."""
    lines = path.read_text().splitlines(keepends=True)
    changed = 0
    for block in reversed(blocks(path)):
        if block.output_of is None:
            continue
        fresh = output_of(block.output_of)
        end = block.line + block.text.count("\n")
        if "".join(lines[block.line : end]) != fresh:
            lines[block.line : end] = fresh.splitlines(keepends=True)
            changed += 1
    path.write_text("".join(lines))
    return changed


# -- shown sessions ---------------------------------------------------------------------------


def session_steps(text: str) -> list[tuple[str, str]]:
    """``$ COMMAND`` lines, each with what is shown after it."""
    steps: list[tuple[str, str]] = []
    for line in text.splitlines(keepends=True):
        if line.startswith("$ "):
            steps.append((line[2:].strip(), ""))
        else:
            command, shown = steps[-1]
            steps[-1] = (command, shown + line)
    return steps


@pytest.mark.parametrize("block", SESSIONS, ids=lambda b: b.id)
def test_a_shown_session_is_what_omsd_prints(block: Block, sandbox: Sandbox) -> None:
    """Run against the daemon of its section, as the blocks around it."""
    source = section_daemon(block)
    daemon = sandbox.wait_ready(
        sandbox.block(source) if source else sandbox.shell("omsd", "omsd (the default board)")
    )
    for command, shown in session_steps(block.text):
        assert not starts_daemon(command), command
        run = sandbox.shell(command, command)
        assert sandbox.finish(run) == 0, run.report()
        printed = "".join(s.rstrip() + "\n" for s in run.stdout.decode().splitlines())
        assert printed == "".join(s.rstrip() + "\n" for s in shown.splitlines()), run.report()
    assert sandbox.stop(daemon) == 0, daemon.report()


# -- the example configuration ----------------------------------------------------------------


def test_the_example_config_stays_in_the_checkout(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """config/omsd.toml, the README's ``omsd --config config/omsd.toml``, runs for any user from
    a checkout: each file it names is in config/ or in the runtime directory, no group is
    named (a user may belong to none), every TCP port is on the loopback and above 1023."""
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    config = load_config(ROOT / "config" / "omsd.toml")
    runtime = runtime_directory()
    assert runtime == tmp_path / "omsd"
    here = ROOT / "config"
    files = [config.log.file, config.state]
    if config.control.socket is not None:
        files.append(config.control.socket)
    files += [p.link for b in config.boards for p in b.pty]
    assert config.log.file is not None and config.state is not None  # shown, not left out
    for path in files:
        assert path is not None
        assert path.is_relative_to(here) or path.is_relative_to(runtime), path
    assert config.log.group is None and config.state_group is None
    assert all(p.group is None for b in config.boards for p in b.pty)
    for board in config.boards:
        for tcp in board.tcp:
            assert tcp.host in ("127.0.0.1", "::1") and tcp.port > 1023, tcp


def test_the_example_config_runs_in_the_checkout_and_stops_cleanly(
    sandbox: Sandbox,
) -> None:
    """As the README's block does, with the log and the flash written next to the file."""
    run = sandbox.wait_ready(sandbox.shell("omsd --config config/omsd.toml", "omsd.toml"))
    check_endpoints(run.stdout, sandbox)
    assert sandbox.stop(run) == 0, run.report()
    assert (sandbox.cwd / "config" / "traffic.jsonl").exists()
    assert not list(sandbox.runtime.glob("omsd/*")), "pty links or socket left behind"


def test_the_command_file_result_is_stated() -> None:
    """The README runs §7.3.4's file against config/plotter.toml and shows its markers."""
    (block,) = [b for b in RUN if "nc -N 127.0.0.1 7010" in b.text]
    assert "config/plotter.toml" in section_daemon(block).text  # type: ignore[union-attr]
    assert following_text(block) == PLOTTER_MARKERS
    manual = ROOT / "tests" / "daemon" / "test_command_file.py"
    assert "ax lp0 ay lp0" in block.text and manual.exists()
    plotter = tomllib.loads((ROOT / "config" / "plotter.toml").read_text())
    assert [b["tcp"] for b in plotter["board"]] == ["127.0.0.1:7010"]


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python tests/test_readme.py --write   (regenerates README's outputs)")
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    print(f"README.md: {write_generated()} generated block(s) rewritten")
