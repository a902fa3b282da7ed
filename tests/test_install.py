"""omsd installed as the README says, in new environments (issue 14: "Install as a user's
dependency", and the README's first command).

* A user's project: its ``pyproject.toml`` gets the README's ``[project.optional-dependencies]``
  table, its tests are the README's two fixture examples, and the README's two commands (a new
  venv, ``pip install -e '.[test]'``, ``pytest``) are run in it. omsd comes from a git URL, as
  the README shows: a git repository made of this checkout as it is now
  (``git+file://localhost/...``, the only change to the README's text; pip 23 refuses a
  ``git+file:///`` URL without a host). The tests must pass, with omsd's runtime dependencies and
  none of its own test tools.
* The README's first command, ``python3 -m venv .venv && .venv/bin/pip install -q -e '.[test]'
  && .venv/bin/omsd``, in a copy of the checkout: it installs, and the daemon starts, serves the
  default board and exits 0 on SIGTERM. (Its second command runs this test suite: ``.ci/run``
  runs it on a clean clone.)

These reach the package index (PyPI); everything else runs as the README tests do
(``tests/readme_blocks.py``). They take some twenty seconds each, mostly pip's.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from readme_blocks import Block, Sandbox, blocks, copy_checkout

SECTION = "### In your own tests: the pytest fixture"
# omsd's own test tools: a user's environment must not get them by depending on omsd
DEVELOPER_ONLY = {"mypy", "ruff", "amqtt", "hypothesis", "pytest-asyncio"}


def section_blocks(heading: str) -> list[Block]:
    return [b for b in blocks() if b.section == heading]


@pytest.fixture(scope="module")
def snapshot(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """This checkout as it is now, as a git repository of one commit (what a git URL gives)."""
    source = copy_checkout(tmp_path_factory.mktemp("omsd"))
    git = ["git", "-c", "user.name=omsd tests", "-c", "user.email=tests@localhost"]
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "snapshot"]):
        subprocess.run([*git, *args], cwd=source, check=True, capture_output=True, timeout=60)
    return source


def test_a_users_project_uses_the_fixture(tmp_path: Path, snapshot: Path) -> None:
    (table,) = [b for b in section_blocks(SECTION) if b.language == "toml"]
    (commands,) = [b for b in section_blocks(SECTION) if b.language == "sh"]
    tests = [b for b in section_blocks(SECTION) if b.language == "python"][:2]
    assert "[project.optional-dependencies]" in table.text and "omsd @ git+" in table.text
    assert commands.not_run and "test_install" in commands.not_run

    project = tmp_path / "my-lab"
    (project / "my_lab").mkdir(parents=True)
    (project / "my_lab" / "__init__.py").write_text('"""The lab\'s own code."""\n')
    dependency = re.sub(
        r"omsd @ git\+\S+?\"", f'omsd @ git+file://localhost{snapshot}"', table.text
    )
    assert dependency != table.text
    pyproject = (
        '[build-system]\nrequires = ["setuptools>=61"]\nbuild-backend = "setuptools.build_meta"\n\n'
        '[project]\nname = "my-lab"\nversion = "1.0"\n\n' + dependency
    )
    tomllib.loads(pyproject)
    (project / "pyproject.toml").write_text(pyproject)
    (project / "tests").mkdir()
    for n, block in enumerate(tests):
        assert "omsd_boards" in block.text
        (project / "tests" / f"test_readme_{n}.py").write_text(block.text)

    sandbox = Sandbox(tmp_path / "sandbox", project)
    try:
        run = sandbox.start(
            ["bash", "-e", "-o", "pipefail", "-c", commands.text],
            commands.id,
            host_network=True,
        )
        status = sandbox.finish(run)
        assert status == 0, run.report()
        assert re.search(rb"\b2 passed\b", run.stdout), run.report()
        installed = subprocess.run(
            [str(project / ".venv" / "bin" / "pip"), "list", "--format=freeze"],
            capture_output=True,
            text=True,
            check=True,
            timeout=60,
        ).stdout
        names = {line.split("==")[0].lower() for line in installed.split()}
        assert {"omsd", "rich", "aiomqtt", "pytest", "pyserial"} <= names, names
        assert not names & DEVELOPER_ONLY, names
    finally:
        sandbox.close()


def test_the_readmes_first_command(tmp_path: Path) -> None:
    """Installed in a copy of the checkout (on the machine's network, for the package index),
    then the daemon it starts, in a network namespace of its own where 7048 is free."""
    first = blocks()[0]
    assert first.language == "sh" and first.not_run and "test_install" in first.not_run
    line = first.text.splitlines()[0]
    install, daemon = line.rsplit(" && ", 1)
    assert install == "python3 -m venv .venv && .venv/bin/pip install -q -e '.[test]'", line
    assert daemon == ".venv/bin/omsd", line
    checkout = copy_checkout(tmp_path / "omsd")
    sandbox = Sandbox(tmp_path / "sandbox", checkout)
    try:
        run = sandbox.start(["bash", "-e", "-c", install], install, host_network=True)
        assert sandbox.finish(run) == 0, run.report()
        run = sandbox.wait_ready(sandbox.shell(daemon, daemon))
        lines = run.stdout.decode().splitlines()
        assert lines[0] == "board1 PC48-4E driver tcp 127.0.0.1:7048", lines
        assert lines[1].startswith(f"board1 PC48-4E driver pty {sandbox.runtime}/omsd/board1 -> ")
        assert sandbox.stop(run) == 0, run.report()
    finally:
        sandbox.close()
