"""The engine is pure: no I/O, no clock, no sleeping, no asyncio ("Time as an argument")."""

from __future__ import annotations

import ast
import pathlib

import pytest

import omsd

ROOT = pathlib.Path(omsd.__file__).parent
PURE = sorted(
    [
        *(ROOT / "engine").glob("*.py"),
        *(ROOT / "dialects").rglob("*.py"),
        *(ROOT / "board").glob("*.py"),
        *(ROOT / "protocol").glob("*.py"),
    ]
)
FORBIDDEN_MODULES = {"asyncio", "time", "socket", "select", "selectors", "threading", "os", "io"}


@pytest.mark.parametrize("path", PURE, ids=lambda p: p.name)
def test_engine_module_imports_nothing_impure(path: pathlib.Path) -> None:
    tree = ast.parse(path.read_text())
    imported: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            imported.add(node.module.split(".")[0])
    assert not imported & FORBIDDEN_MODULES, f"{path.name} imports {imported & FORBIDDEN_MODULES}"


def test_pure_modules_found() -> None:
    names = {p.name for p in PURE}
    assert {"board.py", "axis.py", "executor.py", "lexer.py", "profiles.py"} <= names
