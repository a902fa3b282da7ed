"""Where a configuration error is (issue 14): the line of a key path in a TOML text, the key path
named by board, the value shown as TOML writes it (:mod:`omsd.config_errors`)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from omsd.config import ConfigError, load_config
from omsd.config_errors import key_lines, key_text, lines_of, locate, show

TEXT = """\
# a comment with [brackets] and key = value
[log]
view = "plain"   # trailing comment

[[board]]
name = "xy"
tcp = ["127.0.0.1:7001",
       "127.0.0.1:7002"]
pty = { link = "/run/a", mode = "0660" }
description = \"\"\"
several lines, "quoted", [not a table]
name = "not a key"
\"\"\"
axes.X.home_low = 5

[board.axes.Y]
positive_limit = 1000
'odd key' = 1

[[board]]
pty = [
  { link = "b1" },   # first
  { link = "b2", group = "dialout" },
]
"quoted.key" = 'a # not a comment'

[board.axes.X]
negative_limit = -1
"""


@pytest.mark.parametrize(
    ("path", "line"),
    [
        (("log",), 2),
        (("log", "view"), 3),
        (("board",), 5),
        (("board", 0), 5),
        (("board", 0, "name"), 6),
        (("board", 0, "tcp"), 7),
        (("board", 0, "tcp", 0), 7),
        (("board", 0, "tcp", 1), 8),
        (("board", 0, "pty", "link"), 9),
        (("board", 0, "pty", "mode"), 9),
        (("board", 0, "description"), 10),
        (("board", 0, "axes", "X", "home_low"), 14),  # a dotted key, after a multi-line string
        (("board", 0, "axes"), 14),
        (("board", 0, "axes", "Y"), 16),
        (("board", 0, "axes", "Y", "positive_limit"), 17),
        (("board", 0, "axes", "Y", "odd key"), 18),
        (("board", 1), 20),
        (("board", 1, "pty", 0, "link"), 22),
        (("board", 1, "pty", 1), 23),
        (("board", 1, "pty", 1, "group"), 23),
        (("board", 1, "quoted.key"), 25),
        (("board", 1, "axes", "X"), 27),
        (("board", 1, "axes", "X", "negative_limit"), 28),
    ],
)
def test_the_line_of_each_key(path: tuple[str | int, ...], line: int) -> None:
    assert locate(path, key_lines(TEXT)) == line


def test_a_missing_key_is_at_its_table_and_nothing_else_is_guessed() -> None:
    lines = key_lines(TEXT)
    assert locate(("board", 1, "axes", "X", "home_high"), lines) == 27  # its table
    assert locate(("board", 0, "name", "oops"), lines) == 6
    assert locate(("mqtt", "host"), lines) is None  # no [mqtt] at all: no line
    assert locate(("board", 5), lines) == 5  # no sixth board: where the boards begin
    assert locate((), lines) is None


def test_text_the_scanner_cannot_read_gives_no_lines() -> None:
    assert lines_of("[[board]\nname = ") == {}


def test_crlf_and_keys_in_quotes() -> None:
    text = '[[board]]\r\nname = "a"\r\n"x y".z = 1\r\n'
    lines = key_lines(text)
    assert lines[("board", 0, "x y", "z")] == 3
    assert lines[("board", 0, "name")] == 2


def test_key_text() -> None:
    labels = {("board", 0): '[board "xy"]'}
    assert key_text(("board", 0, "axes", "X", "positive_limit"), labels) == (
        '[board "xy"] axes.X.positive_limit'
    )
    assert key_text(("board", 0), labels) == '[board "xy"]'
    assert key_text(("board", 0, "pty", 1, "mode"), labels) == '[board "xy"] pty[1].mode'
    assert key_text(("board", 1, "a b")) == 'board[1]."a b"'
    assert key_text(("log", "file")) == "log.file"
    assert key_text(()) is None


@pytest.mark.parametrize(
    ("value", "shown"),
    [
        ("5k", '"5k"'),
        ('say "hi"', '"say \\"hi\\""'),
        ("a\nb", '"a\\nb"'),
        (True, "true"),
        (False, "false"),
        (3, "3"),
        (1.5, "1.5"),
        (-math.inf, "-inf"),
        (math.nan, "nan"),
        ([1, "a"], '[1, "a"]'),
        ([1, 2, 3, 4, 5], "[1, 2, 3, 4, ...]"),
        ({"tcp": "7001"}, '{tcp = "7001"}'),
        ({}, "{}"),
        ("x" * 100, '"' + "x" * 28 + "..." + "x" * 28 + '"'),
    ],
)
def test_values_are_shown_as_toml_writes_them(value: object, shown: str) -> None:
    assert show(value) == shown


def test_the_issue_example(tmp_path: Path) -> None:
    """The form issue 14 asks for: file, line, the board by name, the key path, what was
    expected and what was found."""
    path = tmp_path / "omsd.toml"
    path.write_text('[[board]]\nname = "xy"\ntcp = 7001\n\n[board.axes.X]\npositive_limit = "5k"\n')
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == (
        f'{path}:6: [board "xy"] axes.X.positive_limit: expected a number (motor steps), got "5k"'
    )


def test_an_unnamed_board_is_named_by_the_name_it_is_given(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text('[[board]]\nname = "a"\ntcp = 7001\n[[board]]\ntcp = 7002\nlink = "x"\n')
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == (
        f'{path}:6: [board "board2" (unnamed)] link: expected "driver" or "raw", got "x"'
    )


def test_a_duplicate_names_both_places(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text('[[board]]\nname = "a"\ntcp = 7001\n\n[[board]]\nname = "b"\ntcp = 7001\n')
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == (
        f'{path}:7: [board "b"] tcp: expected an address no other endpoint uses, got'
        ' "127.0.0.1:7001" (also [board "a"] tcp, line 3)'
    )
    assert info.value.path == ("board", 1, "tcp") and info.value.also_path == ("board", 0, "tcp")


def test_errors_stay_one_line() -> None:
    error = ConfigError("f.toml", 'x."a\nb"', "expected a\rb", line=2)
    assert str(error) == 'f.toml:2: x."a\\nb": expected a\\rb'


@pytest.mark.parametrize("value", ["[" * 5000 + "]" * 5000, "{a = " * 2000 + "1" + "}" * 2000])
def test_values_nested_too_deeply_for_the_parser_are_one_line(tmp_path: Path, value: str) -> None:
    """tomllib parses nested arrays and inline tables by recursion: thousands of levels ran out
    of Python's stack, a RecursionError's traceback where a one-line error belongs."""
    path = tmp_path / "omsd.toml"
    path.write_text(f"[[board]]\ntcp = 7001\nname = {value}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == f"{path}: invalid TOML: arrays or inline tables nested too deeply"
