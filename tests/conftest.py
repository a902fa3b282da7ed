from __future__ import annotations

import pytest

from omsd.board.harness import Harness


@pytest.fixture
def pc48() -> Harness:
    """A PC48-4 (four open-loop axes) at power-up, on a manual clock at t = 0."""
    return Harness("PC48-4")


@pytest.fixture
def pc48e() -> Harness:
    """A PC48-4E (four axes with encoders) at power-up."""
    return Harness("PC48-4E")


@pytest.fixture
def pc48_8() -> Harness:
    """A PC48-8 (eight open-loop axes) at power-up."""
    return Harness("PC48-8")
