"""The single-board command line's fast path (``omsd/config/fastpath.py``, issue 16): it reads
valid options without pydantic, and for any options it gives ``None`` (the schema decides) or
exactly the configuration the schema gives; it never accepts what the schema refuses."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from serve_once import serve_once

from omsd.config import ConfigError, DaemonConfig, fastpath, reading

BOARDS = ["PC48-4E", "pc48-8", " PCIX-400 ", "VS4-040", "PC46-4", "PC99", "", "pc48-4e\n"]
TCP = [
    "7001",
    "0",
    "127.0.0.1:0",
    "127.0.0.1:7001",
    "0.0.0.0:7001",
    "localhost:7002",
    "oms-sim.lab.example:7003",
    "[::1]:7001",
    "[::]:7001",
    "[fe80::1%eth0]:7004",
    "65535",
    "65536",
    "007001",
    " 7001",
    "7001\n",
    ":7001",
    "[]:7001",
    "[1.2.3.4]:7001",
    "1.2.3.999:7001",
    "my host:7001",
    "-x:7001",
    "abc",
    "",
    "٧٠٠١",  # Arabic-Indic digits: not [0-9]
]
PTY = ["ttyOMS", "/tmp/omsd-fastpath/b", "./ttyOMS", "~/x", "a/../b", "", " ", "\t", "a\x00b"]
PTY += ["\u00a0", "\x1c", "x\n"]
LINKS = [None, "driver", "raw", "RAW", "Driver", "serial", ""]
EOS = [None, "0D", "0d", "0x0d", "0X0A", "D", "ff", "", "100", "0x", "GG", " 0D", "0D ", "\x1c0D"]
LOGS = [None, "traffic.jsonl", "/tmp/omsd-fastpath/t.jsonl", "", " ", "~/t.jsonl"]


VALID_TCP = TCP[:10]
VALID_PTY = PTY[:5]


def schema_config(*args: object) -> DaemonConfig | None:
    try:
        return reading.single_board(*args)  # type: ignore[arg-type]
    except ConfigError:
        return None


def same_or_nothing(*args: object) -> None:
    fast = fastpath.single_board(*args, "command line")  # type: ignore[arg-type]
    if fast is not None:
        assert fast == schema_config(*args, "command line")


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.sampled_from([None, *BOARDS]),
    st.lists(st.sampled_from(TCP), max_size=3),
    st.lists(st.sampled_from(PTY), max_size=3),
    st.sampled_from(LINKS),
    st.sampled_from(EOS),
    st.sampled_from(LOGS),
    st.booleans(),
)
@example(None, [], [], None, None, None, False)  # omsd
@example("PC48-4E", ["127.0.0.1:0"], ["ttyOMS"], None, None, None, False)  # the bench's
@example(None, ["7001", "127.0.0.1:7001"], [], None, None, None, False)  # the same port twice
@example(None, ["0.0.0.0:7001", "7001"], [], None, None, None, False)
@example(None, ["0", "0"], [], None, None, None, False)  # port 0 twice is allowed
@example(None, [], ["a/../b", "b"], None, None, None, True)  # the same link twice
@example(None, ["7001"], [], "raw", "0D", None, False)  # eos on a raw link
def test_the_fast_path_gives_the_schemas_configuration_or_nothing(
    board: str | None,
    tcp: list[str],
    pty: list[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool,
) -> None:
    same_or_nothing(board, tcp, pty, link, eos, log, terminal)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.sampled_from([None, *BOARDS[:5]]),
    st.lists(st.sampled_from(VALID_TCP), max_size=3),
    st.lists(st.sampled_from(VALID_PTY), max_size=3),
    st.sampled_from(LINKS[:5]),
    st.sampled_from(EOS[:7]),
    st.sampled_from(LOGS[:3]),
    st.booleans(),
)
def test_the_fast_path_on_valid_options(
    board: str | None,
    tcp: list[str],
    pty: list[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool,
) -> None:
    """Options drawn from valid ones only: most are taken by the fast path (two endpoints on
    one address, two links to one place, eos on a raw link are not)."""
    same_or_nothing(board, tcp, pty, link, eos, log, terminal)


@pytest.mark.parametrize(
    "text", ["c.sock", "/run/omsd/c.sock", "~/c.sock", "a/../b", "", " ", "\x00", "\u00a0", "x\n"]
)
def test_the_fast_paths_option_path_is_the_schemas_or_nothing(text: str) -> None:
    fast = fastpath.option_path(text)
    if fast is not None:
        assert fast == reading.option_path("--state", text)


@pytest.mark.parametrize(
    "args",
    [
        (None, [], [], None, None, None, False),
        ("PC48-4E", ["127.0.0.1:0"], ["/tmp/omsd-fastpath/b"], None, None, None, False),
        ("pcix-400", ["0"], [], "raw", None, None, False),
        (None, ["0.0.0.0:7001", "[::1]:7002"], ["ttyOMS"], "driver", "0D", "t.jsonl", True),
    ],
)
def test_common_command_lines_take_the_fast_path(args: tuple[object, ...]) -> None:
    """The forms users and the benchmark type are read without the schema (else the fast path
    has quietly stopped working)."""
    assert fastpath.single_board(*args, "command line") is not None  # type: ignore[arg-type]


def test_a_single_board_daemon_starts_without_pydantic(tmp_path: Path) -> None:
    """``omsd --board ... --tcp ... --pty ... --control ...`` from the command line to its
    endpoints up: neither pydantic nor the schema is imported, nor the MQTT client."""
    done = serve_once(
        tmp_path,
        ["--state", str(tmp_path / "state.json"), "--view", "plain"],
        "print(status, sorted(m for m in sys.modules if m.split('.')[0] in"
        " ('pydantic', 'pydantic_core', 'aiomqtt', 'paho') or m in ('omsd.config.schema',"
        " 'omsd.mqtt')), file=sys.stderr)\n",
    )
    assert done.stderr.strip().splitlines()[-1] == "0 []", done.stderr
    assert " tcp 127.0.0.1:" in done.stdout, done.stdout
