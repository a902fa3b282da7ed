from __future__ import annotations

import pytest

from omsd.board.harness import Harness


def pytest_addoption(parser: pytest.Parser) -> None:
    """``pytest --long``: the long robustness variants (tests/robustness; issue 7's "long
    variants runnable by a flag"), from any directory."""
    parser.addoption(
        "--long",
        action="store_true",
        default=False,
        help="run the long robustness variants (10^6 fuzz inputs, 1,000 churn cycles, ...)",
    )


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
