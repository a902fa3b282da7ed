"""The daemon serves every personality: ``omsd models`` lists all twenty-three, and a VS4 and a
PC46 board answer WY through the driver link (issue 4: "Every model name is accepted by
``--board`` ... and listed by ``omsd models``, and the driver and raw links work with each")."""

from __future__ import annotations

import pytest

from .process import Omsd, run_omsd

ALL_MODELS = [
    "PC48-2",
    "PC48-4",
    "PC48-6",
    "PC48-8",
    "PC48-2E",
    "PC48-4E",
    "PC48-6E",
    "PC46-21",
    "PC46-22",
    "PC46-41",
    "PC46-42",
    "PC46-6",
    "PC46-2E",
    "PC46-4E",
    "VS4-020",
    "VS4-040",
    "PCIX-002",
    "PCIX-020",
    "PCIX-202",
    "PCIX-200",
    "PCIX-004",
    "PCIX-040",
    "PCIX-400",
]


def test_models_lists_every_model() -> None:
    result = run_omsd("models")
    assert result.returncode == 0, result.stderr
    listed = [line.split()[0] for line in result.stdout.splitlines() if line.strip()]
    assert sorted(listed) == sorted(ALL_MODELS)
    assert len(listed) == 23
    assert result.stderr == ""


@pytest.mark.parametrize(
    ("board", "model", "wy", "positions"),
    [
        ("VS4-040", "VS4-040", b"VS4-040 ver 1.00 S/N 123456", b"0,0,0,0"),
        ("pc46-21", "PC46-21", b"PC46 ver 1.00-2", b"0,0"),
    ],
)
def test_new_models_answer_wy_through_the_driver_link(
    omsd: Omsd, board: str, model: str, wy: bytes, positions: bytes
) -> None:
    daemon = omsd("--board", board, "--tcp", "127.0.0.1:0")
    (endpoint,) = daemon.endpoints
    assert (endpoint.model, endpoint.link, endpoint.kind) == (model, "driver", "tcp")
    with daemon.connect() as c:
        assert c.ask(b"WY") == wy
        assert c.ask(b"AA RP") == positions
        c.send(b"AU")  # no U axis on either: a command error, "#" and the end character
        c.expect(b"#\n")
        assert c.quiet(0.05) == b""
