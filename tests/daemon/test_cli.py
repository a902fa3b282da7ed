"""The command line of the real daemon: ``omsd models``, and the errors that stop it before it
serves: each is one clear line on standard error, no traceback, and exit status 2 (a
configuration error, or a daemon that cannot start: tests/daemon/test_startup_errors.py)."""

from __future__ import annotations

import os
import socket
import subprocess
from pathlib import Path

import pytest

from omsd import cli
from omsd.models import MODELS

from .process import Omsd, run_omsd


def one_line(result: subprocess.CompletedProcess[str]) -> str:
    """The single line a failed run printed on standard error (and nothing on standard out)."""
    assert "Traceback" not in result.stderr, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {result.stderr!r}"
    assert result.stdout == "", result.stdout
    return lines[0]


def test_models_lists_every_pc48_personality() -> None:
    result = run_omsd("models")
    assert result.returncode == 0, result.stderr
    listed = [line.split()[0] for line in result.stdout.splitlines() if line.strip()]
    assert listed == list(MODELS)
    for name in ("PC48-2", "PC48-4", "PC48-6", "PC48-8", "PC48-2E", "PC48-4E", "PC48-6E"):
        assert name in listed
    assert result.stderr == ""


def test_unknown_board_model_is_one_line_and_status_2() -> None:
    result = run_omsd("--board", "nosuch", "--tcp", "127.0.0.1:0")
    assert result.returncode == 2
    line = one_line(result)
    assert "--board" in line and "nosuch" in line
    assert "PC48-4E" in line  # says what was expected


@pytest.mark.parametrize(
    ("text", "key", "bad"),
    [
        (
            '[[board]]\ntcp = "127.0.0.1:0"\nmodle = "PC48-4"\n',
            ':3: [board "board1" (unnamed)] modle: ',
            "modle",
        ),
        (
            '[[board]]\ntcp = "127.0.0.1:0"\n[board.axes.X]\nnegative_limit = "far"\n',
            ':4: [board "board1" (unnamed)] axes.X.negative_limit: ',
            '"far"',
        ),
        (
            '[[board]]\nname = "a"\ntcp = "127.0.0.1:0"\n\n'
            '[[board]]\nname = "b"\ntcp = "127.0.0.1:0"\nsecond_client = "maybe"\n',
            ':8: [board "b"] second_client: ',
            '"maybe"',
        ),
        (
            '[[board]]\ntcp = "127.0.0.1:0"\nlink = "raw"\neos = "0D"\n',
            ':4: [board "board1" (unnamed)] eos: ',
            "raw",
        ),
    ],
    ids=["unknown-key", "wrong-type", "bad-choice", "eos-on-raw"],
)
def test_bad_config_file_is_one_line_naming_file_and_key(
    tmp_path: Path, text: str, key: str, bad: str
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(text)
    result = run_omsd("--config", str(path), "--view", "plain", cwd=tmp_path)
    assert result.returncode == 2
    line = one_line(result)
    assert line.startswith(f"omsd: {path}{key}"), line
    assert bad in line, line


def test_toml_syntax_error_is_one_line_with_the_place(tmp_path: Path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text('[[board]]\ntcp = "127.0.0.1:0\n')
    result = run_omsd("--config", str(path))
    assert result.returncode == 2
    line = one_line(result)
    assert line.startswith(f"omsd: {path}:2:19: invalid TOML: "), line


def test_missing_config_file_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "absent.toml"
    result = run_omsd("--config", str(path))
    assert result.returncode == 2
    assert str(path) in one_line(result)


def _busy_port() -> socket.socket:
    holder = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    holder.bind(("127.0.0.1", 0))
    holder.listen()
    return holder


def test_port_already_in_use_is_one_line_and_status_2(tmp_path: Path) -> None:
    with _busy_port() as holder:
        port = holder.getsockname()[1]
        result = run_omsd("--tcp", f"127.0.0.1:{port}", cwd=tmp_path)
    assert result.returncode == 2
    line = one_line(result)
    assert f"127.0.0.1:{port}" in line, line
    assert "in use" in line.lower(), line


def test_port_in_use_on_a_later_board_undoes_the_earlier_ones(omsd: Omsd, tmp_path: Path) -> None:
    """The first board's pty is made before the second board's port turns out to be taken: the
    daemon exits 2 with the error as the one ``omsd:`` line, and leaves no pty link behind."""
    link = tmp_path / "first"
    with _busy_port() as holder:
        port = holder.getsockname()[1]
        path = tmp_path / "two.toml"
        path.write_text(
            f'[[board]]\nname = "first"\npty = "{link}"\ntcp = "127.0.0.1:0"\n\n'
            f'[[board]]\nname = "second"\ntcp = "127.0.0.1:{port}"\n'
        )
        result = run_omsd("--config", str(path), cwd=tmp_path)
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("omsd:")]
    assert len(errors) == 1, result.stderr
    assert "second" in errors[0] and f"127.0.0.1:{port}" in errors[0]
    assert result.stderr.splitlines()[-1] == errors[0]
    assert not os.path.lexists(link)


SERVING = [
    [],
    ["--board", "PC48-4E", "--tcp", "127.0.0.1:0", "--pty", "/tmp/b", "--control", "/tmp/c"],
    ["--board", "models"],  # a command's name as an option's value
    ["--tcp", "0", "--tcp", "7001", "--terminal", "--view", "plain", "--loop", "asyncio"],
    ["--config", "omsd.toml", "--state", "s.json", "--web", "8080", "--web-control"],
    ["--boa", "PC48-4E", "--vie", "off", "--conf=f.toml"],  # abbreviations
]


@pytest.mark.parametrize(
    "argv",
    [
        *SERVING,
        ["models"],
        ["--board", "PC48-4E", "commands"],
        ["ctl", "--help"],
        ["--help"],
        ["-h"],
        ["--h"],
        ["--version"],
        ["--vers"],
        ["--v", "plain"],  # --version or --view
        ["--ve", "plain"],
        ["--co", "x"],  # --config or --control
        ["--bogus"],
        ["--tcp"],
        ["--loop", "nosuch"],
        ["stray"],
        ["--", "models"],
    ],
)
def test_serving_is_read_as_the_whole_parser_reads_it(
    argv: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    """A command line that serves is read without the commands' parsers (start-up): to the same
    arguments as the whole parser gives, and anything else is left to the whole parser (which
    answers --help and --version, and words the errors)."""
    quick = cli._serving_args(argv)
    assert (quick is not None) == (argv in SERVING)
    try:
        whole = cli._parser().parse_args(argv)
    except SystemExit:
        assert quick is None
        return
    finally:
        capsys.readouterr()
    if quick is not None:
        assert vars(quick) == vars(whole)


@pytest.mark.parametrize("option", ["--config", "--log"])
def test_an_empty_path_is_one_line_not_taken_for_none(tmp_path: Path, option: str) -> None:
    """``--config ""`` (``--config "$FILE"`` with FILE unset) was taken for no --config at all:
    the daemon served the default board on the default port instead of the file's boards;
    ``--log ""`` served without the log asked for. Now each is refused as ``--state ""`` and
    ``--control ""`` are: ``omsd: --config: expected a path, got ""``, status 2."""
    result = run_omsd(
        option, "", "--tcp", "127.0.0.1:0", "--control", "off", cwd=tmp_path, timeout=10
    )
    assert one_line(result) == f'omsd: {option}: expected a path, got ""'
    assert result.returncode == 2
