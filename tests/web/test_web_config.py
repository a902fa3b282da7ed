"""The dashboard's configuration (issue 18): ``[web]`` and ``--web``/``--web-control``. Off by
default; loopback unless another address is named; a token required for any other address
(and never taken from the command line, which ``ps`` shows); read-only unless ``control``."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from omsd.config import (
    ConfigError,
    TcpEndpoint,
    WebConfig,
    from_options,
    is_loopback,
    load_config,
    with_web_option,
)

BOARD = '[[board]]\nmodel = "PC48-4E"\ntcp = 0\n'
TOKEN = "0123456789abcdef"
DEFAULT = from_options(None, None, None, None, None, None)


def config(tmp_path: Path, web: str) -> Path:
    path = tmp_path / "omsd.toml"
    path.write_text(f"{web}\n{BOARD}")
    return path


def test_off_unless_asked_for(tmp_path: Path) -> None:
    assert load_config(config(tmp_path, "")).web is None
    assert with_web_option(DEFAULT, None, False).web is None


def test_a_web_table_defaults_to_loopback_read_only(tmp_path: Path) -> None:
    web = load_config(config(tmp_path, "[web]")).web
    assert web == WebConfig(TcpEndpoint("127.0.0.1", 8048), control=False, token=None)
    assert web.loopback


def test_every_key(tmp_path: Path) -> None:
    text = f'[web]\nlisten = "0.0.0.0:9000"\ncontrol = true\ntoken = "{TOKEN}"'
    web = load_config(config(tmp_path, text)).web
    assert web == WebConfig(TcpEndpoint("0.0.0.0", 9000), control=True, token=TOKEN)
    assert TOKEN not in repr(web)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('listen = "0.0.0.0:8048"', "expected a token with an address that is not loopback"),
        ('listen = "[::]:8048"', "expected a token with an address that is not loopback"),
        ('listen = "myhost:8048"', "expected a token with an address that is not loopback"),
        ('token = "tiny-secret"', "expected a string of at least 16 characters"),
        ("control = 1", "expected true or false"),
        ('listen = "8048:x"', "web.listen: expected [HOST:]PORT"),
        ("colour = 1", "web.colour"),
    ],
)
def test_bad_tables(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message.replace("[", r"\[")) as caught:
        load_config(config(tmp_path, f"[web]\n{text}"))
    assert "\n" not in str(caught.value)
    assert "tiny-secret" not in str(caught.value)  # a token is never shown


@pytest.mark.parametrize(
    ("host", "loopback"),
    [
        ("127.0.0.1", True),
        ("127.3.2.1", True),
        ("::1", True),
        ("localhost", True),
        ("0.0.0.0", False),
        ("::", False),
        ("192.168.1.5", False),
        ("dashboard.example", False),
    ],
)
def test_loopback(host: str, loopback: bool) -> None:
    assert is_loopback(host) is loopback


def test_the_command_line(tmp_path: Path) -> None:
    base = DEFAULT
    assert with_web_option(base, "8049", False).web == WebConfig(TcpEndpoint("127.0.0.1", 8049))
    assert with_web_option(base, "localhost:0", True).web == WebConfig(
        TcpEndpoint("localhost", 0), control=True
    )
    with pytest.raises(ConfigError, match="needs a token there"):
        with_web_option(base, "0.0.0.0:8048", False)
    with pytest.raises(ConfigError, match=r"--web-control.*needs --web"):
        with_web_option(base, None, True)
    with pytest.raises(ConfigError, match="expected"):
        with_web_option(base, "nonsense:port", False)
    # a file's token and control carry over to --web's address
    filed = load_config(config(tmp_path, f'[web]\ntoken = "{TOKEN}"\ncontrol = true'))
    assert with_web_option(filed, "0.0.0.0:9001", False).web == WebConfig(
        TcpEndpoint("0.0.0.0", 9001), control=True, token=TOKEN
    )
    assert with_web_option(filed, None, False) is filed


def test_omsd_refuses_a_web_beyond_loopback_without_a_token() -> None:
    run = subprocess.run(
        [sys.executable, "-m", "omsd", "--web", "0.0.0.0:8048", "--tcp", "0"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert run.returncode == 2
    assert run.stderr.count("\n") == 1
    assert run.stderr.startswith("omsd: --web:") and "token" in run.stderr


@pytest.mark.parametrize("web", ["99999", "65536", "127.0.0.1:99999"])
def test_omsd_refuses_a_web_port_out_of_range_in_one_line(web: str) -> None:
    """``--web 99999`` was taken as a port (a number goes through as one, unchecked) and the
    daemon died with a traceback from ``bind()`` (``OverflowError: bind(): port must be
    0-65535``, exit status 1); ``--tcp 99999`` has always been refused in one line. Now the
    same line: ``omsd: --web: expected [HOST:]PORT with PORT 0..65535, got '99999'``."""
    run = subprocess.run(
        [sys.executable, "-m", "omsd", "--web", web, "--tcp", "0", "--control", "off"],
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert run.returncode == 2, run.stderr
    assert run.stderr.count("\n") == 1, run.stderr
    assert run.stderr.startswith("omsd: --web: expected [HOST:]PORT with PORT 0..65535")
