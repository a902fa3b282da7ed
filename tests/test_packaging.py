"""The deployment files: Dockerfile, .dockerignore and systemd/omsd.service.

No container engine or running systemd is needed: the Dockerfile and the unit are parsed and
checked for what they promise (a non-root user, a health check that cannot disturb a client,
exposed ports that are the ones served, Type=notify, the hardening, no private /dev), and the
parts that can run here do run: the image's default configuration and its HEALTHCHECK command
against the real daemon, and the daemon under the kernel's MemoryDenyWriteExecute.
"""

from __future__ import annotations

import asyncio
import configparser
import json
import os
import re
import select
import shlex
import shutil
import signal
import subprocess
import sys
import tomllib
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest

from omsd.config import load_config

ROOT = Path(__file__).resolve().parent.parent
DOCKERFILE = ROOT / "Dockerfile"
DOCKERIGNORE = ROOT / ".dockerignore"
UNIT = ROOT / "systemd" / "omsd.service"
CONTAINER_CONFIG = "/etc/omsd/container.toml"
CONFIG_ERROR_STATUS = 2  # what omsd exits with on a configuration error (omsd/cli.py)


# -- Dockerfile -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Instruction:
    keyword: str
    args: str


def instructions(text: str) -> list[Instruction]:
    """The instructions of a Dockerfile: comment lines dropped, continuation lines joined."""
    result: list[Instruction] = []
    pending = ""
    for raw in text.splitlines():
        line = raw.strip()
        if line.startswith("#") or (not line and not pending):
            continue
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        full = (pending + line).strip()
        pending = ""
        keyword, _, args = full.partition(" ")
        result.append(Instruction(keyword.upper(), args.strip()))
    assert not pending, "the Dockerfile ends inside a continued line"
    return result


def exec_form(args: str) -> list[str]:
    """A JSON-array argument (exec form); shell form is not used in this Dockerfile."""
    value = json.loads(args)
    assert isinstance(value, list) and all(isinstance(v, str) for v in value), args
    return value


@pytest.fixture(scope="module")
def dockerfile() -> list[Instruction]:
    return instructions(DOCKERFILE.read_text())


def only(items: list[Instruction], keyword: str) -> Instruction:
    found = [i for i in items if i.keyword == keyword]
    assert len(found) == 1, f"expected one {keyword}, found {len(found)}"
    return found[0]


def command_line(items: list[Instruction]) -> list[str]:
    """What the container runs by default: ENTRYPOINT followed by CMD."""
    return exec_form(only(items, "ENTRYPOINT").args) + exec_form(only(items, "CMD").args)


def written_file(items: list[Instruction], path: str) -> str:
    """The text a ``RUN printf '%s\\n' LINE... > path`` instruction writes."""
    for item in items:
        if item.keyword != "RUN" or path not in item.args:
            continue
        words = shlex.split(item.args)
        start = words.index("printf")
        assert words[start + 1] == "%s\\n", words[start + 1]
        end = words.index(">", start)
        assert words[end + 1] == path
        return "\n".join(words[start + 2 : end]) + "\n"
    raise AssertionError(f"no RUN writes {path}")


def health_command(items: list[Instruction]) -> list[str]:
    args = only(items, "HEALTHCHECK").args
    options, sep, command = args.partition("CMD ")
    assert sep, f"HEALTHCHECK without CMD: {args}"
    assert "NONE" not in options
    return exec_form(command)


def health_port(code: str) -> int:
    match = re.search(r"create_connection\(\('127\.0\.0\.1', (\d+)\)", code)
    assert match, f"the health check does not connect to a loopback port: {code}"
    return int(match.group(1))


def container_config(items: list[Instruction], tmp_path: Path) -> Path:
    path = tmp_path / "container.toml"
    path.write_text(written_file(items, CONTAINER_CONFIG))
    return path


def test_base_image_is_python_311_slim(dockerfile: list[Instruction]) -> None:
    assert only(dockerfile, "FROM").args == "python:3.11-slim"


def test_runs_as_a_non_root_user_before_the_command(dockerfile: list[Instruction]) -> None:
    keywords = [i.keyword for i in dockerfile]
    users = [i for i in dockerfile if i.keyword == "USER"]
    assert users, "no USER: the container would run as root"
    last = users[-1]
    user, _, group = last.args.partition(":")
    assert user not in ("root", "0") and group not in ("root", "0")
    last_index = max(n for n, i in enumerate(dockerfile) if i.keyword == "USER")
    assert last_index < keywords.index("ENTRYPOINT")
    assert last_index < keywords.index("CMD")
    # The numeric id is the one the image creates.
    created = [i for i in dockerfile if i.keyword == "RUN" and "useradd" in i.args]
    assert created and f"--uid {user}" in created[0].args


def test_installs_the_package_and_what_its_build_needs(dockerfile: list[Instruction]) -> None:
    copied = {
        Path(src).parts[0]
        for i in dockerfile
        if i.keyword == "COPY"
        for src in shlex.split(i.args)[:-1]
        if not src.startswith("--")
    }
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert {"pyproject.toml", "omsd", pyproject["project"]["readme"]} <= copied
    assert any(i.keyword == "RUN" and "pip install" in i.args for i in dockerfile)


def test_dockerignore_admits_exactly_what_is_copied(dockerfile: list[Instruction]) -> None:
    lines = [
        line.strip()
        for line in DOCKERIGNORE.read_text().splitlines()
        if line.strip() and not line.startswith("#")
    ]
    assert lines[0] == "*", "the context should be an allow-list"
    admitted = {line[1:].rstrip("/") for line in lines if line.startswith("!")}
    copied = {
        src.rstrip("/")
        for i in dockerfile
        if i.keyword == "COPY"
        for src in shlex.split(i.args)[:-1]
    }
    assert copied == admitted
    assert not admitted & {".git", ".venv", "tests", "bench"}
    for name in admitted:
        assert (ROOT / name).exists(), f".dockerignore admits {name}, which does not exist"


def test_default_command_serves_on_all_interfaces_the_exposed_port(
    dockerfile: list[Instruction], tmp_path: Path
) -> None:
    argv = command_line(dockerfile)
    assert argv[:3] == ["omsd", "--config", CONTAINER_CONFIG]
    config = load_config(container_config(dockerfile, tmp_path))
    served = {t.port for b in config.boards for t in b.tcp if t.host in ("0.0.0.0", "::")}
    exposed = {int(p.split("/")[0]) for p in only(dockerfile, "EXPOSE").args.split()}
    assert served == exposed == {7048}
    assert all(not b.pty for b in config.boards), "a pty in a container has no one to open it"


def test_health_check_has_a_board_of_its_own(dockerfile: list[Instruction], tmp_path: Path) -> None:
    """The check must not connect to a board a client uses: the newcomer would take it over."""
    argv = health_command(dockerfile)
    assert argv[:2] == ["python", "-c"]
    port = health_port(argv[2])
    config = load_config(container_config(dockerfile, tmp_path))
    owners = [b for b in config.boards if any(t.port == port for t in b.tcp)]
    assert len(owners) == 1
    health = owners[0]
    assert [(t.host, t.port) for t in health.tcp] == [("127.0.0.1", port)]
    assert health.link == "driver"  # the check reads one line ending with the default EOS, LF
    exposed = {int(p.split("/")[0]) for p in only(dockerfile, "EXPOSE").args.split()}
    assert port not in exposed
    options = only(dockerfile, "HEALTHCHECK").args
    for option in ("--interval=", "--timeout=", "--start-period=", "--retries="):
        assert option in options


def test_example_configs_named_in_the_dockerfile_exist() -> None:
    """The Dockerfile's usage comment runs ``--config /etc/omsd/ci.toml``; ``COPY config/
    /etc/omsd/`` puts every example there, so each must load. The image's own default,
    container.toml, is written by the Dockerfile (tested below)."""
    named = set(re.findall(r"/etc/omsd/([\w.-]+\.toml)", DOCKERFILE.read_text()))
    assert named == {"ci.toml", Path(CONTAINER_CONFIG).name}
    examples = sorted(path.name for path in (ROOT / "config").glob("*.toml"))
    assert "ci.toml" in examples and Path(CONTAINER_CONFIG).name not in examples
    for name in examples:
        load_config(ROOT / "config" / name)


# -- the image's configuration and health check, run here -----------------------------------------


async def endpoint_lines(proc: asyncio.subprocess.Process, count: int) -> list[str]:
    """The first ``count`` lines the daemon prints (one per endpoint)."""
    assert proc.stdout is not None
    lines = []
    for _ in range(count):
        line = await asyncio.wait_for(proc.stdout.readline(), timeout=10)
        assert line, "omsd exited before announcing its endpoints"
        lines.append(line.decode().strip())
    return lines


@asynccontextmanager
async def daemon(
    args: list[str],
    tmp_path: Path,
    endpoints: int,
    env: dict[str, str] | None = None,
    prefix: list[str] | None = None,
) -> AsyncIterator[tuple[asyncio.subprocess.Process, list[str]]]:
    """The real daemon as a subprocess, once it has announced ``endpoints`` endpoints."""
    stderr_path = tmp_path / "omsd.stderr"
    with stderr_path.open("wb") as stderr:
        proc = await asyncio.create_subprocess_exec(
            *(prefix or []),
            sys.executable,
            "-m",
            "omsd",
            *args,
            stdout=asyncio.subprocess.PIPE,
            stderr=stderr,
            env=env,
        )
        try:
            try:
                lines = await endpoint_lines(proc, endpoints)
            except (AssertionError, TimeoutError):
                raise AssertionError(
                    f"omsd did not announce {endpoints} endpoints: {stderr_path.read_text()}"
                ) from None
            yield proc, lines
        finally:
            if proc.returncode is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    await asyncio.wait_for(proc.wait(), timeout=10)
                except TimeoutError:
                    proc.kill()
                    await proc.wait()


def tcp_port(lines: list[str], board: str) -> int:
    for line in lines:
        match = re.match(rf"{re.escape(board)} .* tcp \S+:(\d+)$", line)
        if match:
            return int(match.group(1))
    raise AssertionError(f"no tcp endpoint for {board} in {lines}")


async def ask(port: int, command: bytes) -> bytes:
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    try:
        writer.write(command)
        return await asyncio.wait_for(reader.readline(), timeout=5)
    finally:
        writer.close()
        await writer.wait_closed()


async def run_health_check(code: str) -> int:
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-c", code, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    return await asyncio.wait_for(proc.wait(), timeout=15)


async def test_health_check_against_the_image_config(
    dockerfile: list[Instruction], tmp_path: Path
) -> None:
    """The HEALTHCHECK command, run as written against the image's default configuration (ports
    moved to free ones, everything on loopback): healthy while a client holds board1, and that
    client keeps its connection; unhealthy once the daemon is gone."""
    code = health_command(dockerfile)[2]
    port = health_port(code)
    text = written_file(dockerfile, CONTAINER_CONFIG)
    # the board the check talks to, whichever it is
    target = next(
        b.name
        for b in load_config(container_config(dockerfile, tmp_path)).boards
        if any(t.port == port for t in b.tcp)
    )
    text = re.sub(r'"(?:0\.0\.0\.0|127\.0\.0\.1):\d+"', '"127.0.0.1:0"', text)
    config = tmp_path / "moved.toml"
    config.write_text(text)
    async with daemon(["--config", str(config)], tmp_path, endpoints=2) as (proc, lines):
        moved = tcp_port(lines, target)
        check = code.replace(f"'127.0.0.1', {port})", f"'127.0.0.1', {moved})")
        reader, writer = await asyncio.open_connection("127.0.0.1", tcp_port(lines, "board1"))
        try:
            writer.write(b"WY")
            assert await asyncio.wait_for(reader.readline(), 5) == b"PC48 ver 3.00-4\n"
            assert await run_health_check(check) == 0
            assert await run_health_check(check) == 0
            writer.write(b"WY")  # still connected: the checks did not take board1 over
            assert await asyncio.wait_for(reader.readline(), 5) == b"PC48 ver 3.00-4\n"
        finally:
            writer.close()
            await writer.wait_closed()
    assert proc.returncode == 0
    assert await run_health_check(check) != 0


async def test_health_check_fails_on_a_wrong_answer(
    dockerfile: list[Instruction], tmp_path: Path
) -> None:
    """A server that answers something else than the board's WY line is not healthy."""
    code = health_command(dockerfile)[2]
    port = health_port(code)

    async def impostor(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        await reader.readexactly(2)
        writer.write(b"?\n")
        await writer.drain()
        writer.close()

    server = await asyncio.start_server(impostor, "127.0.0.1", 0)
    async with server:
        fake = server.sockets[0].getsockname()[1]
        check = code.replace(f"'127.0.0.1', {port})", f"'127.0.0.1', {fake})")
        assert await run_health_check(check) != 0


# -- systemd unit ---------------------------------------------------------------------------------


def unit_values(text: str) -> dict[tuple[str, str], list[str]]:
    """Every assignment of the unit, repeated keys kept in order (DeviceAllow=, Environment=)."""
    values: dict[tuple[str, str], list[str]] = {}
    section = ""
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        if line.startswith("["):
            section = line.strip("[]")
            continue
        key, _, value = line.partition("=")
        values.setdefault((section, key.strip()), []).append(value.strip())
    return values


@pytest.fixture(scope="module")
def unit() -> configparser.ConfigParser:
    parser = configparser.ConfigParser(strict=False, interpolation=None)
    parser.optionxform = str  # type: ignore[assignment,method-assign]
    parser.read_string(UNIT.read_text())
    return parser


def yes(value: str) -> bool:
    return value.lower() in ("1", "yes", "true", "on")


def test_unit_is_type_notify_running_the_config(unit: configparser.ConfigParser) -> None:
    service = unit["Service"]
    assert service["Type"] == "notify"
    assert shlex.split(service["ExecStart"]) == [
        "/usr/local/bin/omsd",
        "--config",
        "/etc/omsd/omsd.toml",
    ]
    assert service["Restart"] == "on-failure"
    assert service["RestartPreventExitStatus"] == str(CONFIG_ERROR_STATUS)
    assert unit["Install"]["WantedBy"] == "multi-user.target"


HARDENING = {
    "NoNewPrivileges": "yes",
    "ProtectSystem": "strict",
    "ProtectHome": "yes",
    "PrivateTmp": "yes",
    "ProtectKernelTunables": "yes",
    "ProtectKernelModules": "yes",
    "ProtectKernelLogs": "yes",
    "ProtectControlGroups": "yes",
    "ProtectClock": "yes",
    "ProtectHostname": "yes",
    "RestrictAddressFamilies": "AF_UNIX AF_INET AF_INET6",
    "RestrictNamespaces": "yes",
    "RestrictRealtime": "yes",
    "RestrictSUIDSGID": "yes",
    "LockPersonality": "yes",
    "MemoryDenyWriteExecute": "yes",
    "SystemCallArchitectures": "native",
    "CapabilityBoundingSet": "",
    "AmbientCapabilities": "",
    "DynamicUser": "yes",
    "RuntimeDirectory": "omsd",
}


@pytest.mark.parametrize(("key", "expected"), sorted(HARDENING.items()))
def test_unit_hardening(unit: configparser.ConfigParser, key: str, expected: str) -> None:
    assert unit["Service"].get(key) == expected, key


def test_unit_system_call_filter_keeps_chown() -> None:
    """@system-service, minus @resources; never ~@privileged, which would forbid the fchown
    that hands a pty to its group."""
    filters = unit_values(UNIT.read_text())[("Service", "SystemCallFilter")]
    assert filters[0] == "@system-service"
    denied = " ".join(f[1:] for f in filters if f.startswith("~")).split()
    assert "@privileged" not in denied and "@chown" not in denied


def test_unit_shares_the_hosts_ptys(unit: configparser.ConfigParser) -> None:
    """Other processes open the ptys: no private /dev, devpts or user namespace."""
    service = unit["Service"]
    assert not yes(service.get("PrivateDevices", "no"))
    assert not yes(service.get("PrivateUsers", "no"))
    assert not yes(service.get("PrivateNetwork", "no"))
    for key in ("TemporaryFileSystem", "BindPaths", "BindReadOnlyPaths", "InaccessiblePaths"):
        assert "/dev" not in service.get(key, ""), key
    if service.get("DevicePolicy", "auto") != "auto":
        allowed = unit_values(UNIT.read_text())[("Service", "DeviceAllow")]
        assert "/dev/ptmx rw" in allowed and "char-pts rw" in allowed


def test_unit_fits_the_example_config(
    unit: configparser.ConfigParser, monkeypatch: pytest.MonkeyPatch
) -> None:
    """config/systemd.toml, the file ExecStart= names once installed (the unit's comment and
    docs/deploy.md install it), works under this unit: pty links and the control socket in the
    RuntimeDirectory, pty groups among SupplementaryGroups, the log file in the LogsDirectory,
    the state file in the StateDirectory."""
    service = unit["Service"]
    assert "install -D -m 0644 config/systemd.toml /etc/omsd/omsd.toml" in UNIT.read_text()
    deploy = (ROOT / "docs" / "deploy.md").read_text()
    assert "install -D -m 0644 config/systemd.toml /etc/omsd/omsd.toml" in deploy
    monkeypatch.setenv("RUNTIME_DIRECTORY", "/run/" + service["RuntimeDirectory"])
    config = load_config(ROOT / "config" / "systemd.toml")
    groups = set(service.get("SupplementaryGroups", "").split())
    ptys = [p for b in config.boards for p in b.pty]
    assert ptys
    for pty in ptys:
        assert pty.link.parent == Path("/run/omsd"), pty.link
        assert pty.group is None or pty.group in groups, pty.group
    assert config.log.file is not None and config.state is not None
    assert config.log.file.parent == Path("/var/log") / service["LogsDirectory"]
    assert config.state.parent == Path("/var/lib") / service["StateDirectory"]
    assert config.control.socket is not None
    assert config.control.socket.parent == Path("/run") / service["RuntimeDirectory"]


@pytest.mark.skipif(shutil.which("systemd-analyze") is None, reason="no systemd-analyze")
def test_systemd_analyze_verify(tmp_path: Path) -> None:
    """systemd's own parser accepts every line (it reports problems but exits 0: any output
    about the unit is a failure). ExecStart= must exist, so the copy runs this Python."""
    copy = tmp_path / "omsd.service"
    copy.write_text(UNIT.read_text().replace("/usr/local/bin/omsd", sys.executable))
    result = subprocess.run(
        ["systemd-analyze", "verify", str(copy)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output
    assert "omsd.service" not in output, output


# -- MemoryDenyWriteExecute -----------------------------------------------------------------------

PR_SET_MDWE = 65
PR_MDWE_REFUSE_EXEC_GAIN = 1
NO_MDWE = 77

# Turns on the kernel's "memory-deny-write-execute" for itself and execs the rest of argv (the
# flag is inherited across execve): what MemoryDenyWriteExecute=yes imposes, minus systemd.
MDWE = f"""
import ctypes, os, sys
libc = ctypes.CDLL(None, use_errno=True)
if libc.prctl({PR_SET_MDWE}, {PR_MDWE_REFUSE_EXEC_GAIN}, 0, 0, 0) != 0:
    sys.exit({NO_MDWE})
os.execv(sys.argv[1], sys.argv[1:])
"""


def _kernel_has_mdwe() -> bool:
    result = subprocess.run(
        [sys.executable, "-c", MDWE, sys.executable, "-c", "pass"], check=False, timeout=30
    )
    return result.returncode == 0


async def test_daemon_runs_under_memory_deny_write_execute(tmp_path: Path) -> None:
    """The whole daemon (asyncio, pty, TCP, rich) under W^X: a board answers on both."""
    if not _kernel_has_mdwe():
        pytest.skip("kernel without PR_SET_MDWE (Linux < 6.3)")
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            MDWE,
            sys.executable,
            "-c",
            "import ctypes, mmap; mmap.mmap(-1, 4096, prot=7)",
        ],
        capture_output=True,
        check=False,
        timeout=30,
    )
    assert probe.returncode != 0, "W+X mapping allowed: MDWE is not in force"
    link = tmp_path / "pc48"
    args = ["--tcp", "127.0.0.1:0", "--pty", str(link)]
    async with daemon(args, tmp_path, endpoints=2, prefix=[sys.executable, "-c", MDWE]) as (
        _,
        lines,
    ):
        # the default board, a PC48-4E, on the driver link (end of string LF)
        assert await ask(tcp_port(lines, "board1"), b"WY") == b"PC48 ver 3.00-4\n"
        answer = await asyncio.to_thread(_ask_pty, link, b"WY")
        assert answer == b"PC48 ver 3.00-4\n"


def _ask_pty(link: Path, command: bytes) -> bytes:
    fd = os.open(link, os.O_RDWR | os.O_NOCTTY)
    try:
        os.write(fd, command)
        answer = b""
        while not answer.endswith(b"\n"):
            ready, _, _ = select.select([fd], [], [], 5)
            assert ready, f"no answer on the pty: {answer!r}"
            answer += os.read(fd, 256)
        return answer
    finally:
        os.close(fd)
