"""Environments made on demand, outside the repository: other interpreters, uvloop, the peers.

All of them live under :func:`cache` (``$OMSD_BENCH_CACHE``, else ``~/.cache/omsd-bench``), made
once with the ordinary clients (``python -m venv``, ``pip install`` from the package index) and
reused by later runs; ``rm -r ~/.cache/omsd-bench`` removes them all. Nothing here runs in
``--quick`` (CI): a row that needs an environment says so instead.
"""

from __future__ import annotations

import glob
import os
import shutil
import subprocess
import sys
from importlib import metadata
from pathlib import Path

INSTALL_TIMEOUT = 900.0


class Unavailable(Exception):
    """What a row needs cannot be had here; the message says why."""


def cache() -> Path:
    return Path(os.environ.get("OMSD_BENCH_CACHE") or Path.home() / ".cache" / "omsd-bench")


def find_python(version: str) -> str | None:
    """An interpreter ``pythonX.Y`` on the PATH or installed by pyenv, else None."""
    found = shutil.which(f"python{version}")
    if found and _runs(found):
        return found
    root = os.environ.get("PYENV_ROOT") or str(Path.home() / ".pyenv")
    for candidate in sorted(glob.glob(f"{root}/versions/{version}.*/bin/python{version}")):
        if _runs(candidate):
            return candidate
    return None


def _runs(python: str) -> bool:
    try:
        subprocess.run([python, "-c", "pass"], check=True, capture_output=True, timeout=30)
    except (OSError, subprocess.SubprocessError):
        return False
    return True


def _pinned(names: list[str]) -> list[str]:
    """The running environment's versions of ``names`` (as close to it as can be), so that
    another interpreter runs omsd with what this one has."""
    out = []
    for name in names:
        try:
            out.append(f"{name}=={metadata.version(name)}")
        except metadata.PackageNotFoundError:
            out.append(name)
    return out


def venv(name: str, python: str, packages: list[str]) -> Path:
    """``cache()/name``: a virtual environment of ``python`` with ``packages``; made (or
    completed) on demand. Returns its interpreter. Raises :class:`Unavailable` on failure."""
    home = cache() / name
    exe = home / "bin" / "python"
    stamp = home / ".installed"
    wanted = "\n".join(packages)
    if exe.exists() and stamp.exists() and stamp.read_text() == wanted:
        return exe
    print(f"bench: making {home} ({', '.join(packages)})", file=sys.stderr, flush=True)
    try:
        if not exe.exists():
            home.parent.mkdir(parents=True, exist_ok=True)
            subprocess.run(
                [python, "-m", "venv", str(home)],
                check=True,
                capture_output=True,
                timeout=INSTALL_TIMEOUT,
            )
        subprocess.run(
            [str(exe), "-m", "pip", "install", "--disable-pip-version-check", "-q", *packages],
            check=True,
            capture_output=True,
            timeout=INSTALL_TIMEOUT,
        )
    except subprocess.CalledProcessError as exc:
        tail = (exc.stderr or b"").decode(errors="replace").strip().splitlines()[-3:]
        raise Unavailable(f"could not install {' '.join(packages)}: {' / '.join(tail)}") from None
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise Unavailable(f"could not install {' '.join(packages)}: {exc}") from None
    stamp.write_text(wanted)
    return exe


def omsd_venv(version: str) -> Path:
    """An environment of Python ``version`` with omsd's dependencies (omsd itself comes from
    this checkout, on ``PYTHONPATH``)."""
    python = find_python(version)
    if python is None:
        raise Unavailable(f"no python{version} here (PATH, pyenv)")
    return venv(f"python{version}", python, _pinned(runtime_dependencies()))


def runtime_dependencies() -> list[str]:
    """The names of omsd's runtime dependencies, as the installed checkout declares them
    (``pyproject.toml``'s ``dependencies``; no extras)."""
    import re

    names = []
    for requirement in metadata.requires("omsd") or []:
        if "extra ==" in requirement:
            continue
        match = re.match(r"[A-Za-z0-9._-]+", requirement)
        if match:
            names.append(match.group(0))
    return names


def uvloop_path() -> tuple[str, ...] | None:
    """Where this interpreter finds uvloop: () when it is installed already, else a ``pip
    install --target`` directory in the cache if one was made; None if neither."""
    try:
        metadata.version("uvloop")
        return ()
    except metadata.PackageNotFoundError:
        pass
    target = _uvloop_target()
    return (str(target),) if (target / "uvloop").is_dir() else None


def _uvloop_target() -> Path:
    return cache() / f"uvloop-cp{sys.version_info.major}{sys.version_info.minor}"


def install_uvloop() -> tuple[str, ...]:
    """uvloop for this interpreter, installed into the cache if it is not importable."""
    found = uvloop_path()
    if found is not None:
        return found
    target = _uvloop_target()
    print(f"bench: installing uvloop into {target}", file=sys.stderr, flush=True)
    try:
        subprocess.run(
            [
                sys.executable,
                "-m",
                "pip",
                "install",
                "--disable-pip-version-check",
                "-q",
                "--target",
                str(target),
                "uvloop",
            ],
            check=True,
            capture_output=True,
            timeout=INSTALL_TIMEOUT,
        )
    except subprocess.CalledProcessError as exc:
        tail = (exc.stderr or b"").decode(errors="replace").strip().splitlines()[-3:]
        raise Unavailable(f"could not install uvloop: {' / '.join(tail)}") from None
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise Unavailable(f"could not install uvloop: {exc}") from None
    return (str(target),)
