"""The README's code blocks, found and run as a newcomer would run them.

Used by ``tests/test_readme.py`` (every block) and ``tests/test_install.py`` (the installs); the
conventions are stated at the top of ``tests/test_readme.py``. This module has the machinery:

* :func:`blocks` reads the fenced blocks of a Markdown file, each with its language, its section
  (the heading above it), its line and the HTML comment in front of it (``<!-- not run: reason
  -->``, ``<!-- output of: COMMAND -->``).
* :func:`with_checks` turns the values a Python block states in its comments
  (``port.read_until(b"\\n")  # b'1000000\\n'``) into checks, without moving a line.
* :class:`Sandbox` runs shell and Python blocks: as root, in a network namespace of their own
  (so the README's fixed ports, 7048, 7001 ..., are free whatever else runs on the machine, and
  nothing the blocks start can be reached from outside), with ``omsd`` of this checkout first on
  ``PATH``, a home and a runtime directory of their own (``$HOME``, ``$XDG_RUNTIME_DIR``) and a
  copy of the checkout as the working directory. A daemon is seen to be ready as systemd sees it:
  ``READY=1`` on ``$NOTIFY_SOCKET`` (``omsd/sdnotify.py``), with the sender's pid from the
  socket's credentials, so that it is stopped with SIGTERM by pid and its exit status checked.
  Without root (no network namespace) the blocks run on this machine's loopback: the fixed ports
  must then be free.
"""

from __future__ import annotations

import ast
import contextlib
import io
import os
import re
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import sys
import time
import tokenize
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
BIN = Path(sys.executable).parent  # this venv's bin: omsd, python3, pip
COLUMNS = "100"  # the README's width, for generated help texts

RUN_LANGUAGES = ("sh", "python")
NOT_RUN = re.compile(r"<!--\s*not run\s*:?(?P<reason>.*?)-->\s*$")
OUTPUT_OF = re.compile(r"<!--\s*output of\s*:\s*(?P<command>.*?)\s*-->\s*$")
HEADING = re.compile(r"(#{1,6})\s+(.*)")

STARTUP = 20.0  # seconds for a daemon to say READY=1
BLOCK_TIMEOUT = 180.0  # seconds for a whole block (the installs take the longest)
STOP = 10.0  # seconds for a daemon to exit after SIGTERM


# -- finding the blocks -----------------------------------------------------------------------


@dataclass(frozen=True)
class Block:
    """One fenced code block of a Markdown file."""

    path: Path
    line: int  # the line of the opening fence (1-based); the text starts on the next one
    language: str  # the info string's first word; "" for an untagged fence
    text: str
    section: str  # the heading above the block ("" above the first heading)
    section_line: int
    marker: str | None  # the HTML comment line just before the fence, if any
    marker_line: int = 0

    @property
    def not_run(self) -> str | None:
        """The reason given by a ``<!-- not run: reason -->`` in front of the block ("" when
        the marker gives none), or None when there is no such marker."""
        if self.marker is None:
            return None
        m = NOT_RUN.match(self.marker)
        return None if m is None else m.group("reason").strip()

    @property
    def output_of(self) -> str | None:
        """The command of an ``<!-- output of: COMMAND -->`` in front of the block."""
        if self.marker is None:
            return None
        m = OUTPUT_OF.match(self.marker)
        return None if m is None else m.group("command")

    @property
    def runs(self) -> bool:
        return self.language in RUN_LANGUAGES and self.marker_kind != "not run"

    @property
    def marker_kind(self) -> str | None:
        if self.marker is None:
            return None
        if NOT_RUN.match(self.marker):
            return "not run"
        if OUTPUT_OF.match(self.marker):
            return "output of"
        return "other"

    @property
    def id(self) -> str:
        first = next((s for s in self.text.splitlines() if s.strip()), "").strip()
        words = re.sub(r"[^A-Za-z0-9_.:/-]+", " ", first).split()
        return f"{self.path.name}:{self.line + 1}:{self.language or 'text'}:{'-'.join(words[:4])}"

    def starts_daemon(self) -> bool:
        return self.language == "sh" and starts_daemon(self.text)

    @property
    def installs(self) -> bool:
        """A block that installs packages needs the package index: it runs on the machine's
        network (not in a namespace of its own), with no daemon beside it."""
        return self.language == "sh" and any(
            Path(words[0]).name.startswith("pip") and "install" in words[1:2]
            for words in commands(self.text)
        )


def blocks(path: Path = README) -> list[Block]:
    """Every fenced block of ``path``, in order."""
    lines = path.read_text().splitlines()
    found: list[Block] = []
    section, section_line = "", 0
    i = 0
    while i < len(lines):
        line = lines[i]
        fence = re.match(r" {0,3}(`{3,}|~{3,})\s*([^`\s]*)", line)
        if fence is None:
            heading = HEADING.match(line)
            if heading:
                section, section_line = line.strip(), i + 1
            i += 1
            continue
        ticks, language = fence.group(1), fence.group(2).lower()
        j = i + 1
        while j < len(lines) and not (
            lines[j].strip().startswith(ticks) and not lines[j].strip().strip(ticks[0])
        ):
            j += 1
        marker, marker_line = None, 0
        k = i - 1
        while k >= 0 and not lines[k].strip():
            k -= 1
        if k >= 0 and lines[k].strip().startswith("<!--") and lines[k].strip().endswith("-->"):
            marker, marker_line = lines[k].strip(), k + 1
        text = "".join(s + "\n" for s in lines[i + 1 : j])
        found.append(Block(path, i + 1, language, text, section, section_line, marker, marker_line))
        i = j + 1
    return found


SUBCOMMANDS = frozenset(
    {
        "models",
        "console",
        "ctl",
        "commands",
        "config",
        "record",
        "replay",
        "top",
        "-h",
        "--help",
        "--version",
    }
)


def commands(script: str) -> Iterator[list[str]]:
    """The simple commands of a shell script, as words (comments dropped; a here-document's
    lines come out as words of their own, which is harmless for what they are used for)."""
    script = script.replace("\\\n", " ")
    for line in script.splitlines():
        lexer = shlex.shlex(line, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = "#"
        try:
            words = list(lexer)
        except ValueError:
            continue
        command: list[str] = []
        for word in [*words, ";"]:
            if word and set(word) <= set(";&|()<>"):
                if command:
                    yield command
                command = []
            else:
                command.append(word)


def starts_daemon(script: str) -> bool:
    """Whether a shell script runs the daemon: ``omsd`` (any path to it, or ``python -m
    omsd``) with no subcommand and neither ``--help`` nor ``--version``."""
    for words in commands(script):
        if Path(words[0]).name == "omsd":
            args = words[1:]
        elif Path(words[0]).name.startswith("python") and words[1:3] == ["-m", "omsd"]:
            args = words[3:]
        else:
            continue
        if not SUBCOMMANDS & set(args):
            return True
    return False


# -- the values Python blocks state in their comments ------------------------------------------


def literal_prefix(comment: str) -> str | None:
    """The Python literal a comment starts with (``b'!\\x01\\n' 3.3 s later`` gives
    ``b'!\\x01\\n'``), or None. A comment that starts with a word, or with something that is not
    a whole literal (``[{'name': 'board1', ...}]``), states no value."""
    text = comment.lstrip("#").strip()
    for end in range(len(text), 0, -1):
        candidate = text[:end]
        if end < len(text) and not text[end].isspace():
            continue
        try:
            ast.literal_eval(candidate)
        except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
            continue
        return candidate
    return None


def with_checks(source: str, first_line: int = 1) -> tuple[str, list[int]]:
    """``source`` with each expression statement whose comment starts with a literal wrapped in
    ``_readme_expect(EXPR, LITERAL, LINE)``, line for line (LINE counts from ``first_line``).
    Returns the new source and the lines checked."""
    tree = ast.parse(source)
    comments: dict[int, str] = {}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            comments[token.start[0]] = token.string
    lines = source.splitlines(keepends=True)
    todo: dict[int, ast.Expr] = {}
    for node in ast.walk(tree):
        # the last statement of a line is the one its comment speaks of
        if (
            isinstance(node, ast.Expr)
            and node.lineno == node.end_lineno
            and node.lineno in comments
            and not (isinstance(node.value, ast.Constant) and isinstance(node.value.value, str))
            and (node.lineno not in todo or node.col_offset > todo[node.lineno].col_offset)
        ):
            todo[node.lineno] = node
    checked = []
    for lineno, node in sorted(todo.items()):
        literal = literal_prefix(comments[lineno])
        if literal is None:
            continue
        assert node.end_col_offset is not None
        raw = lines[lineno - 1].encode()
        start, end = node.col_offset, node.end_col_offset
        readme_line = first_line + lineno - 1
        wrapped = (
            raw[:start]
            + f"_readme_expect({raw[start:end].decode()}, {literal}, {readme_line})".encode()
            + raw[end:]
        )
        lines[lineno - 1] = wrapped.decode()
        checked.append(readme_line)
    return "".join(lines), checked


EXPECT = '''
import builtins


def _readme_expect(value, expected, line):
    """README line LINE states the value of its expression in a comment: check it."""
    if value != expected:
        raise AssertionError(
            f"README.md line {line}: the comment says {expected!r}, the code gives {value!r}"
        )
    return value


builtins._readme_expect = _readme_expect
'''

RUN_SCRIPT = (
    EXPECT
    + """
import runpy, sys
sys.argv = sys.argv[1:]
runpy.run_path(sys.argv[0], run_name="__main__")
"""
)


def defines_tests(source: str) -> bool:
    """A Python block that defines ``test_*`` functions is a test file: pytest runs it."""
    return any(
        isinstance(node, ast.FunctionDef) and node.name.startswith("test_")
        for node in ast.parse(source).body
    )


# -- the sandbox ------------------------------------------------------------------------------

HOLDER = """
import fcntl, socket, struct, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
ifreq = fcntl.ioctl(s, 0x8913, struct.pack("16sH22x", b"lo", 0))       # SIOCGIFFLAGS
flags = struct.unpack("16sH22x", ifreq)[1]
fcntl.ioctl(s, 0x8914, struct.pack("16sH22x", b"lo", flags | 1))      # SIOCSIFFLAGS: IFF_UP
print("up", flush=True)
sys.stdin.read()
"""


class NetNamespace:
    """A network namespace with only a loopback interface, up: kept alive by a holder process
    (until :meth:`close`); ``prefix`` runs a command in it."""

    def __init__(self) -> None:
        self.holder = subprocess.Popen(
            ["unshare", "--net", "--", sys.executable, "-c", HOLDER],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        assert self.holder.stdout is not None
        if self.holder.stdout.readline().strip() != "up":
            self.close()
            raise OSError("no network namespace")

    @property
    def prefix(self) -> list[str]:
        return ["nsenter", f"--net=/proc/{self.holder.pid}/ns/net", "--"]

    def close(self) -> None:
        with contextlib.suppress(OSError):
            assert self.holder.stdin is not None
            self.holder.stdin.close()
        try:
            self.holder.wait(STOP)
        except subprocess.TimeoutExpired:
            self.holder.kill()
            self.holder.wait()
        for pipe in (self.holder.stdout, self.holder.stderr):
            if pipe is not None:
                pipe.close()


def network_namespace() -> NetNamespace | None:
    if os.geteuid() != 0 or shutil.which("unshare") is None or shutil.which("nsenter") is None:
        return None
    try:
        return NetNamespace()
    except OSError:
        return None


def copy_checkout(dest: Path) -> Path:
    """The checkout's files as they are now (tracked and new, not ignored ones) copied to
    ``dest``: what a clone with this work in it would hold."""
    files: list[str]
    try:
        listed = subprocess.run(
            ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            cwd=ROOT,
            capture_output=True,
            check=True,
            timeout=60,
        ).stdout.decode()
        files = [f for f in listed.split("\0") if f]
    except (OSError, subprocess.SubprocessError):
        skip = {".git", ".venv", "__pycache__", ".mypy_cache", ".pytest_cache", ".ruff_cache"}
        files = [
            str(p.relative_to(ROOT))
            for p in ROOT.rglob("*")
            if p.is_file() and not skip & set(p.relative_to(ROOT).parts)
        ]
    for name in files:
        source = ROOT / name
        if not source.is_file():
            continue  # deleted in the work tree
        target = dest / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, target)
    return dest


@dataclass
class Run:
    """One script running in a sandbox."""

    proc: subprocess.Popen[bytes]
    what: str
    out: Path
    err: Path
    daemons: list[int] = field(default_factory=list)  # pids that said READY=1

    @property
    def stdout(self) -> bytes:
        return self.out.read_bytes()

    @property
    def stderr(self) -> str:
        return self.err.read_text(errors="replace")

    def report(self) -> str:
        return (
            f"{self.what}\n--- exit status: {self.proc.returncode}\n"
            f"--- stdout:\n{self.stdout.decode(errors='replace')[-4000:]}\n"
            f"--- stderr:\n{self.stderr[-6000:]}"
        )


class Sandbox:
    """Where README blocks run: see the module's docstring."""

    def __init__(self, root: Path, checkout: Path) -> None:
        self.root = root
        root.mkdir(parents=True, exist_ok=True)
        self.cwd = checkout
        self.home = root / "home"
        self.home.mkdir()
        self.runtime = root / "run"
        self.runtime.mkdir(mode=0o700)
        os.chmod(self.runtime, 0o700)
        self.scratch = root / "blocks"
        self.scratch.mkdir()
        self._netns: NetNamespace | bool | None = False  # made at first use
        self.notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM | socket.SOCK_CLOEXEC)
        self.notify.setsockopt(socket.SOL_SOCKET, socket.SO_PASSCRED, 1)
        self.notify_path = root / "notify.sock"
        self.notify.bind(str(self.notify_path))
        self.runs: list[Run] = []
        self.count = 0
        env = {
            k: v
            for k, v in os.environ.items()
            if not k.startswith(("PYTEST_", "WATCHDOG_", "LISTEN_", "OMSD_"))
            and k not in ("RUNTIME_DIRECTORY", "JOURNAL_STREAM", "PYTHONPATH", "COLUMNS")
        }
        env.update(
            PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '/usr/bin:/bin')}",
            HOME=str(self.home),
            XDG_RUNTIME_DIR=str(self.runtime),
            NOTIFY_SOCKET=str(self.notify_path),
            PYTHONUNBUFFERED="1",
            PYTHONDONTWRITEBYTECODE="1",
            COLUMNS=COLUMNS,
        )
        self.env = env

    @property
    def netns(self) -> NetNamespace | None:
        if self._netns is False:
            self._netns = network_namespace()
        assert self._netns is not True
        return self._netns

    # -- running ----------------------------------------------------------------------------------

    def start(
        self, argv: list[str], what: str, cwd: Path | None = None, host_network: bool = False
    ) -> Run:
        self.count += 1
        out = self.scratch / f"{self.count}.out"
        err = self.scratch / f"{self.count}.err"
        with out.open("wb") as stdout, err.open("wb") as stderr:
            proc = subprocess.Popen(
                [*(self.netns.prefix if self.netns and not host_network else []), *argv],
                stdin=subprocess.DEVNULL,
                stdout=stdout,
                stderr=stderr,
                cwd=cwd or self.cwd,
                env=self.env,
                start_new_session=True,
            )
        run = Run(proc, what, out, err)
        self.runs.append(run)
        return run

    def shell(self, script: str, what: str, host_network: bool = False) -> Run:
        argv = ["bash", "-e", "-o", "pipefail", "-c", script]
        return self.start(argv, what, host_network=host_network)

    def python(self, block: Block) -> Run:
        """A Python block as a script, or with pytest when it defines tests; its lines keep the
        README's line numbers, and values stated in comments are checked."""
        source, _ = with_checks(block.text, block.line + 1)
        padded = "\n" * block.line + source
        if defines_tests(block.text):
            directory = self.scratch / f"pytest-{block.line}"
            directory.mkdir()
            (directory / "conftest.py").write_text(EXPECT)
            (directory / f"test_readme_line_{block.line + 1}.py").write_text(padded)
            plugin = [] if plugin_registered() else ["-p", "omsd.testing"]
            argv = [str(BIN / "python3"), "-m", "pytest", *plugin, "-p", "no:cacheprovider"]
            return self.start([*argv, "-q", "-rA", str(directory)], block.id, cwd=directory)
        script = self.scratch / f"readme_line_{block.line + 1}.py"
        script.write_text(padded)
        return self.start([str(BIN / "python3"), "-c", RUN_SCRIPT, str(script)], block.id)

    def block(self, block: Block) -> Run:
        if block.language == "python":
            return self.python(block)
        return self.shell(block.text, block.id, host_network=block.installs)

    # -- readiness and stopping -------------------------------------------------------------------

    def ready_pids(self, timeout: float) -> list[int]:
        """The pids that have sent ``READY=1``: those waiting already, or the first to come
        within ``timeout``."""
        pids: list[int] = []
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            self.notify.settimeout(min(left, 0.1) if left > 0 and not pids else 0)
            try:
                data, ancillary, _, _ = self.notify.recvmsg(4096, socket.CMSG_SPACE(12))
            except (TimeoutError, BlockingIOError):
                if pids or left <= 0:
                    return pids
                continue
            for level, kind, value in ancillary:
                if level == socket.SOL_SOCKET and kind == socket.SCM_CREDENTIALS:
                    pid = struct.unpack("iII", value[:12])[0]
                    if b"READY=1" in data.split(b"\n"):
                        pids.append(pid)

    def wait_ready(self, run: Run, timeout: float = STARTUP) -> Run:
        """Wait until a daemon started by ``run`` says READY=1; fail with what it said if it
        exits first or takes too long."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            pids = self.ready_pids(0.1)
            if pids:
                run.daemons += pids
                return run
            if run.proc.poll() is not None:
                raise AssertionError(f"the daemon exited before it was ready:\n{run.report()}")
        raise AssertionError(f"no READY=1 within {timeout} s:\n{run.report()}")

    def stop(self, run: Run, timeout: float = STOP) -> int:
        """SIGTERM to the daemons ``run`` started, then wait for ``run`` to end; its exit
        status (killed, with the report, if it does not end in time)."""
        for pid in run.daemons:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        try:
            return run.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill(run)
            raise AssertionError(
                f"still running {timeout} s after SIGTERM:\n{run.report()}"
            ) from None

    def finish(self, run: Run, timeout: float = BLOCK_TIMEOUT) -> int:
        """Wait for ``run`` to end by itself; then stop any daemon it left behind."""
        try:
            status = run.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.kill(run)
            raise AssertionError(f"did not finish within {timeout} s:\n{run.report()}") from None
        # a daemon it left running in the background: stopped, and waited for
        run.daemons += self.ready_pids(0)
        for pid in run.daemons:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        for pid in run.daemons:
            if not gone(pid, STOP):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
        return status

    def kill(self, run: Run) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(run.proc.pid, signal.SIGKILL)
        for pid in run.daemons:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            run.proc.wait(STOP)

    def close(self) -> None:
        """Everything still running is stopped: SIGTERM, then SIGKILL."""
        try:
            for run in self.runs:
                if run.proc.poll() is None:
                    with contextlib.suppress(ProcessLookupError, PermissionError):
                        os.killpg(run.proc.pid, signal.SIGTERM)
                    try:
                        run.proc.wait(STOP)
                    except subprocess.TimeoutExpired:
                        self.kill(run)
                # what the run's process group still holds (a daemon in the background)
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.killpg(run.proc.pid, signal.SIGKILL)
        finally:
            self.notify.close()
            if isinstance(self._netns, NetNamespace):
                self._netns.close()


def gone(pid: int, timeout: float) -> bool:
    """Whether process ``pid`` has ended (or is a zombie) within ``timeout``."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            return True
        if state in ("Z", "X"):
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.02)


def plugin_registered() -> bool:
    import importlib.metadata

    return any(
        ep.value == "omsd.testing"
        for ep in importlib.metadata.entry_points(group="pytest11", name="omsd")
    )
