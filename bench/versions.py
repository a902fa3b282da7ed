"""Python 3.12 and 3.13: the latency target under each interpreter.

For each version found (on the PATH as ``pythonX.Y``, or installed by pyenv), an environment
with omsd's dependencies is made once in the cache (:mod:`bench.envs`; omsd itself is this
checkout), and omsd as users run it (a PC48-4E on the raw link, default view) and the plain
``asyncio.Protocol`` echo are both started under that interpreter; ``RP`` round trips over TCP
alternate between them as in :mod:`bench.latency`. Target (issue 16): the same as Python 3.11's,
omsd's median <= 1.10x the echo's. Not run in ``--quick`` (it would install), nor where the
interpreter is missing: the row says so.
"""

from __future__ import annotations

from pathlib import Path

from bench import envs, procs
from bench.latency import RAW_REPLY, Contender, alternate, first_reply, median
from bench.ports import TcpPort
from bench.settings import Settings
from bench.table import Row, Target, skipped

VERSIONS = ("3.12", "3.13")


def one(version: str, settings: Settings, directory: Path) -> Row:
    name = f"RP tcp, median, Python {version}: omsd as users run it / Protocol echo"
    target = Target("ratio", "<=", 1.10)
    if settings.versions_samples == 0:
        return skipped(name, "µs", target, "--quick does not install interpreters' environments")
    try:
        python = procs.Python(str(envs.omsd_venv(version)), label=f"Python {version}")
    except envs.Unavailable as exc:
        return skipped(name, "µs", target, str(exc))
    board = procs.BoardSpec("versions", "PC48-4E", "raw")
    n = settings.versions_samples
    with (
        procs.omsd([board], directory, view="auto", python=python, loop="asyncio") as omsd,
        procs.echo(directory, tcp=1, reply=RAW_REPLY, python=python) as echo,
        TcpPort(omsd.tcp()) as ours,
        TcpPort(echo.tcp()) as theirs,
    ):
        if first_reply(ours) != RAW_REPLY:
            raise RuntimeError("omsd did not answer RP as expected")
        a = Contender("omsd", ours, RAW_REPLY)
        b = Contender("echo", theirs, RAW_REPLY)
        alternate([a, b], n)
    return Row(
        name,
        "µs",
        median(a.samples) * 1e6,
        median(b.samples) * 1e6,
        target,
        f"{n:,} round trips each, {python.executable}",
    )


def run(settings: Settings, directory: Path) -> list[Row]:
    return [one(version, settings, directory) for version in VERSIONS]
