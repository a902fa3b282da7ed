"""The package's shape (issue 15, ``docs/architecture.md``): no import circles, layers that only
import downwards, an engine that knows no dialect, modules of a few hundred lines.

Every import counts: module level, inside functions and under ``if TYPE_CHECKING:``, read with
``ast`` from the source (nothing is imported to find them). ``from X import a`` is an edge to the
module ``X.a`` when there is one, else to ``X``; ``import X.Y`` is an edge to ``X.Y``. As in
``shared/tools/import_circles.py``, a module's imports of its own ancestor packages are not
edges (Python has run ``X/__init__.py`` before any ``X.y``, and a package's imports of its own
children are what make it a package).
"""

from __future__ import annotations

import ast
import re
from collections.abc import Iterator
from pathlib import Path

import pytest

import omsd
from omsd.models import MODELS
from omsd.models.max_family import MAX_COMMANDS

ROOT = Path(omsd.__file__).parent

#: The layers, lowest first: a module may import modules of its own layer and the ones before
#: it. Modules not listed (configuration, files, telemetry, faults, the command-line helpers)
#: serve the service layer and above; the layers below the service import none of them.
LAYERS: list[tuple[str, ...]] = [
    ("omsd.protocol", "omsd.models"),
    ("omsd.engine",),
    ("omsd.dialects",),
    ("omsd.board",),
    ("omsd.link",),
    ("omsd.service",),
    ("omsd.transport",),
    ("omsd.control", "omsd.mqtt", "omsd.testing"),
    ("omsd.daemon",),
    ("omsd.cli",),
]
SERVICE = 5  # the first layer that may use the unlisted modules

#: The dialect-free core and the modules every dialect shares: no dialect's own mnemonics in
#: their code. Docstrings and comments are not searched: they may cite the manual page that
#: defines a mechanism ("PCIx §5.12.5 EG"); what is checked is what the code does (its names and
#: its strings).
DIALECT_FREE = [
    *sorted((ROOT / "engine").glob("*.py")),
    *sorted((ROOT / "board").glob("*.py")),
    ROOT / "dialects" / "interpreter.py",
    ROOT / "dialects" / "operands.py",
    ROOT / "dialects" / "registry.py",
    *sorted((ROOT / "dialects" / "shared").glob("*.py")),
]
#: The dialect names a model row gives: the engine and the shared modules never test them.
DIALECT_NAMES = {m.dialect for m in MODELS.values()}

MAX_LINES = 500
SIZED = ("engine", "dialects", "board")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES: dict[str, Path] = {_module_name(p): p for p in sorted(ROOT.rglob("*.py"))}


def _imports(name: str, path: Path) -> set[str]:
    """The omsd modules ``name`` imports (see the module docstring)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                found.add(sub if sub in MODULES else module)
    out = set()
    for module in found:
        while module and module not in MODULES:
            module = module.rpartition(".")[0]
        if module and module != name and not name.startswith(module + "."):
            out.add(module)
    return out


GRAPH: dict[str, set[str]] = {name: _imports(name, path) for name, path in MODULES.items()}


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in graph:
        if root in index:
            continue
        work: list[tuple[str, Iterator[str]]] = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, edges = work[-1]
            for w in edges:
                if w not in graph:
                    continue
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))
    return found


def _layer(module: str) -> int | None:
    for i, layer in enumerate(LAYERS):
        if any(module == top or module.startswith(top + ".") for top in layer):
            return i
    return None


# -- circles and layers ---------------------------------------------------------------------------


def test_the_walk_finds_the_package() -> None:
    assert {"omsd.engine.machine", "omsd.dialects.interpreter", "omsd.board.board"} <= set(GRAPH)
    assert "omsd.engine.core" in GRAPH["omsd.engine.machine"]
    assert "omsd.dialects.registry" in GRAPH["omsd.dialects.pcix"]


def test_no_import_circles() -> None:
    assert _circles(GRAPH) == []


def test_the_circle_finder_finds_a_circle() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _circles(graph) == [["a", "b", "c"]]


def test_layers_import_only_downwards() -> None:
    upward = []
    for module, deps in GRAPH.items():
        mine = _layer(module)
        if mine is None:
            continue
        for dep in deps:
            theirs = _layer(dep)
            if theirs is None:
                if mine < SERVICE and dep != "omsd":
                    upward.append(f"{module} -> {dep} (a module for the service and above)")
            elif theirs > mine:
                upward.append(f"{module} -> {dep}")
    assert upward == []


def test_the_engine_imports_no_dialect() -> None:
    below = ("omsd.engine", "omsd.protocol", "omsd.models")
    wrong = {
        module: sorted(d for d in deps if not d.startswith(below))
        for module, deps in GRAPH.items()
        if module.startswith("omsd.engine")
    }
    assert {module: deps for module, deps in wrong.items() if deps} == {}


# -- dialect-free code ----------------------------------------------------------------------------


def _families() -> tuple[set[str], set[str]]:
    pc48: set[str] = set()
    pcix: set[str] = set(MAX_COMMANDS)
    for model in MODELS.values():
        (pcix if model.dialect == "pcix" else pc48).update(model.commands)
    return pc48 - pcix, pcix - pc48


PC48_ONLY, PCIX_ONLY = _families()
OWN_MNEMONICS = PC48_ONLY | PCIX_ONLY


def _docstrings(tree: ast.AST) -> set[int]:
    """ids of the docstring constants of a module, its classes and functions."""
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def _code_words(path: Path) -> Iterator[tuple[int, str, str]]:
    """(line, kind, text) of every identifier and every string of the code (docstrings and
    comments left out)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docs = _docstrings(tree)
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            yield node.lineno, "string", node.value
        elif isinstance(node, ast.Name):
            yield node.lineno, "name", node.id
        elif isinstance(node, ast.Attribute):
            yield node.lineno, "attribute", node.attr
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            yield node.lineno, "definition", node.name
        elif isinstance(node, ast.arg):
            yield node.lineno, "argument", node.arg
        elif isinstance(node, ast.keyword) and node.arg is not None:
            yield node.value.lineno, "keyword", node.arg
        elif isinstance(node, ast.alias):
            yield node.lineno, "import", node.asname or node.name


def _mnemonics_in(text: str) -> set[str]:
    """The dialect-only mnemonics a string spells as a word of its own (``"?TL"``, ``MD{n}``,
    ``("BC", apply)``), not inside a longer word."""
    found = set()
    for m in OWN_MNEMONICS:
        if re.search(r"(?<![A-Za-z0-9?#])" + re.escape(m) + r"(?![A-Za-z?])", text):
            found.add(m)
    return found


def test_the_dialect_only_mnemonics_are_known() -> None:
    assert {"EN", "EF", "RS"} <= PC48_ONLY
    assert {"EG", "TL", "BC", "GU", "NV", "MD", "?TL", "DC", "KP", "QL", "#WS"} <= PCIX_ONLY
    assert not {"GO", "ID", "WT", "RP", "QA", "MR", "SW"} & OWN_MNEMONICS  # shared language


def test_the_search_sees_code_not_prose(tmp_path: Path) -> None:
    probe = tmp_path / "probe.py"
    probe.write_text(
        '"""The PCIx TL page: travel limits."""\n'
        "# comments may say EG\n"
        "def f(x):\n"
        '    """Docstrings may say BC too."""\n'
        '    return ("BC", x.travel_limits, f"MD{x}")\n'
    )
    found = {
        m for _, kind, text in _code_words(probe) if kind == "string" for m in _mnemonics_in(text)
    }
    assert found == {"BC", "MD"}


@pytest.mark.parametrize("path", DIALECT_FREE, ids=lambda p: str(p.relative_to(ROOT)))
def test_dialect_free_code_names_no_dialect_mnemonic(path: Path) -> None:
    """The engine, the board's façade, the generic interpreter and the shared language never
    spell a command only one dialect has: such a command's behaviour is its dialect's (a
    handler, an op, a hook, an option), and these modules offer the mechanism."""
    found = []
    for line, kind, text in _code_words(path):
        hits = _mnemonics_in(text) if kind == "string" else {text} & OWN_MNEMONICS
        found.extend(f"{path.name}:{line} {kind} {text!r}: {sorted(hits)}" for _ in hits)
    assert found == []


@pytest.mark.parametrize(
    "path",
    [p for p in DIALECT_FREE if p.parent.name != "board"],
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_dialect_free_code_never_asks_which_dialect(path: Path) -> None:
    """Only the board, which joins a model row to its dialect, reads ``Model.dialect``."""
    for line, kind, text in _code_words(path):
        assert not (kind == "attribute" and text == "dialect" and "engine" in path.parts), line
        assert not (kind == "string" and text in DIALECT_NAMES), (path.name, line, text)
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr == "dialect":
            base = node.value
            assert not (isinstance(base, ast.Attribute) and base.attr == "model"), (
                path,
                node.lineno,
            )


def test_every_model_row_names_a_registered_dialect() -> None:
    from omsd import dialects

    assert dialects.registered() == sorted(DIALECT_NAMES)
    for model in MODELS.values():
        assert dialects.lookup(model.dialect).name == model.dialect


# -- size -----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "path",
    [p for top in SIZED for p in sorted((ROOT / top).rglob("*.py"))],
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_modules_of_a_few_hundred_lines(path: Path) -> None:
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= MAX_LINES, f"{path.relative_to(ROOT)}: {lines} lines"


# -- the public paths -----------------------------------------------------------------------------


def test_the_board_keeps_its_public_paths() -> None:
    """``omsd.board`` is the API the daemon, configurations and users import; the engine's types
    it re-exports are the engine's own (one class, two names)."""
    from omsd.board import AxisWorld, Board, Harness, SwitchType
    from omsd.board.harness import Harness as HarnessThere
    from omsd.board.world import AxisWorld as AxisWorldThere
    from omsd.engine.machine import Machine
    from omsd.engine.world import AxisWorld as EngineAxisWorld

    assert Harness is HarnessThere and AxisWorld is AxisWorldThere is EngineAxisWorld
    assert issubclass(Board, Machine) and SwitchType.NORMALLY_OPEN.value == "normally_open"
    assert Harness("PCIX-400").send("WY;").startswith(b"PCIX-400 ver:")


def test_the_old_profiles_path_warns() -> None:
    import importlib
    import sys

    sys.modules.pop("omsd.board.profiles", None)
    with pytest.warns(DeprecationWarning, match="omsd.engine.profiles"):
        old = importlib.import_module("omsd.board.profiles")
    from omsd.engine import profiles

    assert old.move_pieces is profiles.move_pieces and old.LINEAR is profiles.LINEAR
