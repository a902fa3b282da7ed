"""A daemon started and stopped once in a fresh interpreter, for the tests of what serving imports
(``tests/test_import_boundaries.py``, ``tests/test_config_fastpath.py``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

_ONCE = (
    "import sys\n"
    "import omsd.daemon\n"
    "class Once(omsd.daemon.Daemon):\n"
    "    async def run(self):\n"
    "        await self.start()\n"
    "        await self.stop(quiet=True)\n"
    "omsd.daemon.Daemon = Once\n"
    "from omsd import cli\n"
)


def serve_once(tmp_path: Path, extra: list[str], then: str) -> subprocess.CompletedProcess[str]:
    """``omsd --board PC48-4E --tcp 127.0.0.1:0 --pty TMP/b --control TMP/c.sock EXTRA`` from
    the command line to its endpoints up and down again, then the Python code ``then``, in a
    fresh interpreter (``status`` is what ``cli.main`` returned, ``sys`` is imported)."""
    argv = ["--board", "PC48-4E", "--tcp", "127.0.0.1:0", "--pty", str(tmp_path / "b")]
    argv += ["--control", str(tmp_path / "c.sock"), *extra]
    code = f"{_ONCE}status = cli.main({argv!r})\n{then}"
    env = {k: v for k, v in os.environ.items() if k != "NOTIFY_SOCKET"}
    return subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=env,
        cwd=tmp_path,
    )
