"""What each command imports (issue 16: ``omsd --help``, ``omsd models`` and ``omsd ctl`` within
3x ``python -c pass``, "import the engine only where it is used"). The commands import their
modules when they run (``omsd/cli.py``); these tests hold each to what it needs, by the modules
loaded once it has run. Timings are the benchmark's (``python -m bench --only startup``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from serve_once import serve_once

import omsd.config
import omsd.link
from omsd import defaults

#: Loaded by none of the light commands: asyncio, the engine and everything above the defaults.
HEAVY = (
    "asyncio",
    "pydantic",
    "rich",
    "aiomqtt",
    "omsd.board",
    "omsd.engine",
    "omsd.dialects",
    "omsd.protocol",
    "omsd.link",
    "omsd.service",
    "omsd.daemon",
    "omsd.config",
)


def loaded(argv: list[str]) -> list[str]:
    """The modules loaded after ``omsd ARGV`` ran, in a fresh interpreter."""
    code = (
        "import sys\nfrom omsd import cli\n"
        f"try:\n    cli.main({argv!r})\nexcept SystemExit:\n    pass\n"
        "print(' '.join(sorted(sys.modules)), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    return done.stderr.strip().splitlines()[-1].split()


def under(modules: list[str], packages: tuple[str, ...]) -> list[str]:
    return [m for m in modules if any(m == p or m.startswith(p + ".") for p in packages)]


@pytest.mark.parametrize(
    "argv",
    [
        ["--help"],
        ["--version"],
        ["config", "--help"],
        ["models"],
        ["ctl", "--help"],
        ["ctl", "--socket", "/nonexistent/omsd.sock", "boards"],
        ["top", "--help"],
        ["top", "--socket", "/nonexistent/omsd.sock"],
    ],
)
def test_light_commands_import_no_engine_nor_event_loop(argv: list[str]) -> None:
    modules = loaded(argv)
    assert "omsd.cli" in modules
    assert under(modules, HEAVY) == [], argv


def test_help_imports_only_the_parser_and_the_defaults() -> None:
    """``omsd --help`` needs argparse, the help texts and the defaults they quote."""
    omsd = [m for m in loaded(["--help"]) if m == "omsd" or m.startswith("omsd.")]
    assert omsd == [
        "omsd",
        "omsd.cli",
        "omsd.defaults",
        "omsd.helptext",
        "omsd.recording",
        "omsd.recording.cli",
        "omsd.topcli",
    ]


def test_models_lists_the_rows_without_their_dialects() -> None:
    modules = loaded(["models"])
    assert "omsd.models" in modules
    assert under(modules, ("omsd.dialects", "omsd.commands", "dataclasses")) == ["dataclasses"]


def test_the_defaults_are_the_configurations() -> None:
    """``omsd.defaults`` is where omsd.config's defaults are defined (one definition, re-exported
    there), and the command line's --link choices are the links omsd.link makes."""
    constants = [name for name in omsd.config.__all__ if name.isupper()]
    assert constants and set(constants) <= set(defaults.__all__)
    for name in set(defaults.__all__) & set(omsd.config.__all__):
        assert getattr(omsd.config, name) is getattr(defaults, name), name
    assert defaults.LINKS == omsd.link.KINDS


def test_a_board_loads_only_its_own_dialect() -> None:
    """Dialects are imported when a board first looks theirs up (``omsd.dialects.registry``):
    a daemon of PC48-family boards never loads the PCIx's language (start-up), and a PCIx board
    loads it."""
    code = (
        "import sys\n"
        "from omsd.board import Board\nfrom omsd.models import get_model\n"
        "import omsd.daemon\n"
        "def has(name): return name in sys.modules\n"
        "before = has('omsd.dialects.pc48'), has('omsd.dialects.pcix')\n"
        "Board(get_model('PC48-4E'), now=0.0); Board(get_model('VS4-040'), now=0.0)\n"
        "family = has('omsd.dialects.pc48'), has('omsd.dialects.pcix')\n"
        "Board(get_model('PCIX-400'), now=0.0)\n"
        "print(before, family, has('omsd.dialects.pcix'))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert done.stdout.split("\n")[0] == "(False, False) (True, False) True"


#: What a daemon serving one PC48-4E has no use for, so never imports (start-up, issue 16): the
#: servo loop (a PCIx's servo axes) and contouring (imported by the first CD), the serial and
#: RFC 2217 endpoints, the other families' model rows, the commands' own parsers, and
#: ctypes.util (the pty's inotify takes the C library as the process has it).
NOT_FOR_A_PC48 = (
    "omsd.engine.servo",
    "omsd.engine.contour",
    "omsd.transport.serial",
    "omsd.transport.rfc2217",
    "omsd.transport.access_server",
    "omsd.models.pc46",
    "omsd.models.vs4",
    "omsd.models.pcix",
    "omsd.recording",
    "omsd.topcli",
    "ctypes.util",
)


def test_a_pc48_daemon_loads_only_what_it_serves_with(tmp_path: Path) -> None:
    """``omsd --board PC48-4E --tcp ... --pty ... --control ...`` (the benchmark's start-up) from
    the command line to its endpoints up: nothing of NOT_FOR_A_PC48 is imported. Each is where it
    is used: a contour defined (CD) loads contouring, a PCIx board the servo loop."""
    done = serve_once(
        tmp_path,
        [],
        f"print(status, [m for m in {NOT_FOR_A_PC48!r} if m in sys.modules], file=sys.stderr)\n"
        "from omsd.board import Board, Harness\nfrom omsd.models import get_model\n"
        "Harness('PC48-4E').send('AA CD0,0; CE')\n"
        "Board(get_model('PCIX-400'), now=0.0)\n"
        "print(sorted(m for m in ('omsd.engine.contour', 'omsd.engine.servo') if m in"
        " sys.modules), file=sys.stderr)\n",
    )
    assert done.stderr.strip().splitlines()[-2:] == [
        "0 []",
        "['omsd.engine.contour', 'omsd.engine.servo']",
    ], done.stderr
