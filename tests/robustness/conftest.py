"""Fixtures of the robustness tests, and the switch between the short and the long pass.

The issue (7) asks for "long variants runnable by a flag": ``pytest --long`` (the option is
registered in ``tests/conftest.py``, so it works from any directory) or ``OMSD_LONG=1`` in the
environment. The
default is the short pass CI runs, a few seconds per test.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import TypeVar

import pytest
from daemon.process import Omsd
from hypothesis import HealthCheck, settings

T = TypeVar("T")


def long_pass(config: pytest.Config) -> bool:
    """Whether the long variants were asked for (``--long`` or ``OMSD_LONG=1``)."""
    flag = os.environ.get("OMSD_LONG", "").strip().lower() not in ("", "0", "no", "false")
    try:
        option = bool(config.getoption("--long"))
    except ValueError:  # the option is not registered (this conftest was not loaded early)
        option = False
    return flag or option


def stream_settings(config: pytest.Config, short: int, long: int) -> settings:
    """Hypothesis's settings for a test of random streams: ``short`` examples in the short pass,
    ``long`` in the long one (:func:`long_pass`), no deadline, slow examples allowed."""
    return settings(
        max_examples=long if long_pass(config) else short,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )


class Scale:
    """Picks a count for the pass being run: ``scale(100, 1000)``."""

    def __init__(self, long: bool) -> None:
        self.long = long

    def __call__(self, short: T, long: T) -> T:
        return long if self.long else short


@pytest.fixture
def scale(request: pytest.FixtureRequest) -> Scale:
    return Scale(long_pass(request.config))


@pytest.fixture
def omsd(tmp_path: Path) -> Iterator[Omsd]:
    """Start real daemons with ``omsd(*args, config=..., expect=...)`` (see
    ``tests/daemon/process.py``); every daemon still running is stopped with SIGTERM on
    teardown (it must exit 0 and leave no pty link) and killed in a ``finally``."""
    starter = Omsd(tmp_path)
    try:
        yield starter
    finally:
        starter.close()
