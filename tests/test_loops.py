"""The event loop the daemon runs on (``omsd.loops``, ``omsd --loop auto|asyncio|uvloop``).

uvloop is an optional extra (``omsd[fast]``): whether it is importable is decided here by
stubbing the import, so that the tests say the same with and without it installed.
"""

from __future__ import annotations

import asyncio
import importlib
import subprocess
import sys
import types
from collections.abc import Callable
from typing import Any

import pytest
from daemon.process import run_omsd

from omsd.loops import LOOPS, LoopUnavailable, loop_factory, run

REAL_IMPORT = importlib.import_module


def without_uvloop(monkeypatch: pytest.MonkeyPatch) -> None:
    def import_module(name: str, package: str | None = None) -> Any:
        if name == "uvloop":
            raise ModuleNotFoundError("No module named 'uvloop'", name="uvloop")
        return REAL_IMPORT(name, package)

    monkeypatch.setattr(importlib, "import_module", import_module)


class FakeUvloop(types.ModuleType):
    """What omsd takes of uvloop: ``new_event_loop`` (here asyncio's, counted)."""

    def __init__(self) -> None:
        super().__init__("uvloop")
        self.made: list[asyncio.AbstractEventLoop] = []

    def new_event_loop(self) -> asyncio.AbstractEventLoop:
        loop = asyncio.new_event_loop()
        self.made.append(loop)
        return loop


def with_uvloop(monkeypatch: pytest.MonkeyPatch) -> FakeUvloop:
    fake = FakeUvloop()

    def import_module(name: str, package: str | None = None) -> Any:
        return fake if name == "uvloop" else REAL_IMPORT(name, package)

    monkeypatch.setattr(importlib, "import_module", import_module)
    return fake


def test_the_choices() -> None:
    assert LOOPS == ("auto", "asyncio", "uvloop")


@pytest.mark.parametrize("uvloop", [False, True], ids=["without-uvloop", "with-uvloop"])
def test_asyncio_is_asyncios_own_loop_whatever_is_installed(
    uvloop: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    if uvloop:
        with_uvloop(monkeypatch)
    else:
        without_uvloop(monkeypatch)
    assert loop_factory("asyncio") == (None, "asyncio")


def test_uvloop_without_uvloop_is_a_one_line_error(monkeypatch: pytest.MonkeyPatch) -> None:
    without_uvloop(monkeypatch)
    with pytest.raises(LoopUnavailable) as info:
        loop_factory("uvloop")
    message = str(info.value)
    assert message == "--loop uvloop: uvloop is not installed (pip install 'omsd[fast]')"
    assert info.value.__cause__ is None and info.value.__suppress_context__


def test_auto_without_uvloop_falls_back_to_asyncio(monkeypatch: pytest.MonkeyPatch) -> None:
    without_uvloop(monkeypatch)
    assert loop_factory("auto") == (None, "asyncio")


@pytest.mark.parametrize("choice", ["auto", "uvloop"])
def test_auto_and_uvloop_take_uvloop_where_it_is(
    choice: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    fake = with_uvloop(monkeypatch)
    factory, name = loop_factory(choice)
    assert name == "uvloop"
    assert factory == fake.new_event_loop


@pytest.mark.parametrize("choice", ["bogus", "", "Asyncio", "uv", "AUTO"])
def test_an_unknown_choice_is_refused(choice: str) -> None:
    with pytest.raises(ValueError, match=r"unknown event loop .*: expected one of auto, asyncio"):
        loop_factory(choice)


def test_run_runs_on_the_factorys_loop(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = with_uvloop(monkeypatch)
    factory, _ = loop_factory("uvloop")
    seen: list[asyncio.AbstractEventLoop] = []

    async def main() -> None:
        seen.append(asyncio.get_running_loop())

    run(main(), factory)
    assert seen == fake.made and len(seen) == 1
    assert seen[0].is_closed()  # and closed after


def test_run_without_a_factory_runs_on_asyncios_loop() -> None:
    seen: list[asyncio.AbstractEventLoop] = []

    async def main() -> None:
        seen.append(asyncio.get_running_loop())

    run(main(), None)
    assert len(seen) == 1 and type(seen[0]).__module__.startswith("asyncio.")
    assert seen[0].is_closed()


def test_run_passes_an_exception_on() -> None:
    async def main() -> None:
        raise KeyError("x")

    with pytest.raises(KeyError):
        run(main(), None)


def test_importing_the_module_imports_no_event_loop() -> None:
    """The command line imports omsd.loops first of all (for ``--help``): it must not cost an
    asyncio or uvloop import."""
    code = "import sys, omsd.loops; print(sorted({'asyncio', 'uvloop'} & set(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=30
    )
    assert out.stdout.strip() == "[]"


def uvloop_installed() -> bool:
    try:
        REAL_IMPORT("uvloop")
    except ImportError:
        return False
    return True


def one_line_error(argv: list[str], expected: Callable[[str], bool]) -> None:
    done = run_omsd(*argv)
    assert done.returncode == 2, done
    assert done.stdout == ""
    assert len(done.stderr.splitlines()) == 1 and done.stderr.endswith("\n"), done.stderr
    assert expected(done.stderr), done.stderr


def test_the_command_line_refuses_an_unknown_loop_in_one_line() -> None:
    one_line_error(
        ["--loop", "bogus", "--tcp", "127.0.0.1:0", "--control", "off"],
        lambda err: (
            err.startswith("omsd: argument --loop: invalid choice: 'bogus'")
            and "auto" in err
            and "uvloop" in err
        ),
    )


@pytest.mark.skipif(uvloop_installed(), reason="uvloop is installed here")
def test_the_command_line_without_uvloop_refuses_loop_uvloop_in_one_line() -> None:
    one_line_error(
        ["--loop", "uvloop", "--tcp", "127.0.0.1:0", "--control", "off"],
        lambda err: (
            err == "omsd: --loop uvloop: uvloop is not installed (pip install 'omsd[fast]')\n"
        ),
    )
