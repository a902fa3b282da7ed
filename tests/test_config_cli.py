"""``omsd config check FILE`` and ``omsd config show FILE`` (issue 15): a file validated without
starting anything, and the configuration omsd would serve, every default filled in."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from omsd import cli
from omsd.board import AxisWorld
from omsd.config import BoardConfig, DaemonConfig, load_config
from omsd.config.render import document_of

CONFIG_DIR = Path(__file__).resolve().parent.parent / "config"
EXAMPLES = sorted(CONFIG_DIR.glob("*.toml"))


@pytest.fixture(autouse=True)
def _runtime_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    runtime = tmp_path / "run"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    return runtime


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = cli.main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


# -- check ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_check_says_ok_in_one_line(capsys: pytest.CaptureFixture[str], path: Path) -> None:
    count = len(load_config(path).boards)
    status, out, err = run(capsys, "config", "check", str(path))
    assert status == 0 and err == ""
    assert out == f"{path}: {count} board{'s' if count > 1 else ''}, OK\n"


def test_check_names_the_file_as_given(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "lab.toml").write_text('[[board]]\ntcp = 7001\n[[board]]\npty = "p"\n')
    monkeypatch.chdir(tmp_path)
    assert run(capsys, "config", "check", "lab.toml") == (0, "lab.toml: 2 boards, OK\n", "")


@pytest.mark.parametrize(
    ("text", "error"),
    [
        (
            '[[board]]\nname = "xy"\ntcp = 7001\n\n[board.axes.X]\npositive_limit = "5k"\n',
            '{path}:6: [board "xy"] axes.X.positive_limit: expected a number (motor steps),'
            ' got "5k"',
        ),
        ("[[board]]\ntcp = 7001\ncolour = 1\n", '{path}:3: [board "board1" (unnamed)] colour:'),
        ("[[board]\n", "{path}:1:8: invalid TOML: "),
        ("", "{path}: board: expected at least one [[board]] table, got none"),
    ],
)
def test_check_gives_the_error_in_one_line_and_status_2(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, text: str, error: str
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(text)
    status, out, err = run(capsys, "config", "check", str(path))
    assert status == 2 and out == ""
    assert err.startswith(error.format(path=path)) and err.count("\n") == 1, err


def test_check_of_a_missing_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    status, out, err = run(capsys, "config", "check", str(tmp_path / "nope.toml"))
    assert (status, out) == (2, "")
    assert err == f"{tmp_path / 'nope.toml'}: cannot read the file: No such file or directory\n"


def test_check_starts_nothing(tmp_path: Path) -> None:
    """No socket, no pty, no runtime directory, no log: a check runs while the daemon it
    checks for is serving the same ports and links."""
    runtime = tmp_path / "run"
    path = tmp_path / "omsd.toml"
    path.write_text('[log]\nfile = "t.jsonl"\n[[board]]\ntcp = 7001\npty = true\n')
    done = subprocess.run(
        [sys.executable, "-m", "omsd", "config", "check", str(path)],
        capture_output=True,
        text=True,
        env={"XDG_RUNTIME_DIR": str(runtime), "PATH": "/usr/bin:/bin"},
        timeout=60,
        check=False,
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, f"{path}: 1 board, OK\n", "")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["omsd.toml"]


# -- show -----------------------------------------------------------------------------------------


def _effective(board: BoardConfig) -> BoardConfig:
    """``board`` with the world of every axis, the ones not configured at their defaults."""
    world = {a: board.world.get(a, AxisWorld()) for a in board.personality().axes}
    return dataclasses.replace(board, world=world)


def _same(a: DaemonConfig, b: DaemonConfig) -> None:
    """The same configuration, read from two files (``explicit``: a control socket shown is
    given)."""
    assert [_effective(x) for x in a.boards] == [_effective(x) for x in b.boards]
    assert [x.personality() for x in a.boards] == [x.personality() for x in b.boards]
    assert (a.log, a.state, a.state_group, a.mqtt) == (b.log, b.state, b.state_group, b.mqtt)
    assert dataclasses.replace(a.control, explicit=False) == dataclasses.replace(
        b.control, explicit=False
    )


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_show_prints_a_file_that_reads_as_the_same_configuration(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, path: Path
) -> None:
    status, out, err = run(capsys, "config", "show", str(path))
    assert status == 0 and err == ""
    assert out.startswith(f"# {path}: the effective configuration, every default filled in")
    shown = tmp_path / "shown.toml"
    shown.write_text(out)
    _same(load_config(shown), load_config(path))
    status, again, _ = run(capsys, "config", "show", str(shown))
    assert again.split("\n", 1)[1] == out.split("\n", 1)[1]  # a fixed point


def test_show_fills_in_every_default(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text('[mqtt]\nhost = "h"\n[[board]]\nmodel = "pc48-2"\npty = true\n')
    status, out, _ = run(capsys, "config", "show", str(path))
    assert status == 0
    document = tomllib.loads(out)
    (board,) = document["board"]
    assert board["name"] == "board1" and board["model"] == "PC48-2"
    assert (board["link"], board["eos"], board["buffer"]) == ("driver", "0A", 256)
    assert board["pty"] == [
        {"link": str(tmp_path / "run" / "omsd" / "board1"), "mode": "0660", "terminal": False}
    ]
    assert board["tcp"] == [] and board["second_client"] == "takeover"
    assert set(board["axes"]) == {"X", "Y"}  # every axis of the model
    assert board["axes"]["Y"]["home_low"] == 1000.0
    assert "encoder_index" not in board["axes"]["X"]  # a PC48-2 has no encoder
    assert document["log"] == {"view": "auto"}
    assert document["control"] == {"socket": str(tmp_path / "run" / "omsd" / "control.sock")}
    assert document["mqtt"]["port"] == 1883 and document["mqtt"]["prefix"] == "omsd"


def test_show_keeps_a_password_to_itself(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text('[mqtt]\nhost = "h"\nusername = "u"\npassword = "s3cret"\n[[board]]\ntcp = 0\n')
    status, out, _ = run(capsys, "config", "show", str(path))
    assert status == 0 and "s3cret" not in out and 'password = "(not shown)"' in out
    assert document_of(load_config(path))["mqtt"]["password"] == "(not shown)"


def test_show_of_an_invalid_file_is_the_error(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text('[[board]]\ntcp = 7001\nlink = "serial"\n')
    status, out, err = run(capsys, "config", "show", str(path))
    assert (status, out) == (2, "")
    assert (
        err
        == f'{path}:3: [board "board1" (unnamed)] link: expected "driver" or "raw", got "serial"\n'
    )


def test_config_needs_an_action(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        cli.main(["config"])
    assert info.value.code == 2
    assert "ACTION" in capsys.readouterr().err
