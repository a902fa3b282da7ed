"""Fixtures for the tests that run the real daemon (``python -m omsd``) as a subprocess."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from .process import Omsd


@pytest.fixture
def omsd(tmp_path: Path) -> Iterator[Omsd]:
    """Start daemons with ``omsd(*args, config=..., expect=...)``: each call waits for the
    endpoint lines and returns a :class:`~tests.daemon.process.Daemon`. On teardown every daemon
    still running gets SIGTERM and must exit 0 having removed its pty links; each is killed in a
    ``finally`` whatever happened, so none outlives the test."""
    starter = Omsd(tmp_path)
    try:
        yield starter
    finally:
        starter.close()
