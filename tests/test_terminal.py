"""The terminal option's line editing and display (:mod:`omsd.transport.terminal`), and how it
is asked for (configuration keys, ``--terminal``). End to end with real terminal programs:
``tests/daemon/test_terminal.py``."""

from __future__ import annotations

from pathlib import Path

import pytest

from omsd.board import Board
from omsd.cli import main
from omsd.config import ConfigError, TcpEndpoint, from_options, load_config
from omsd.link import DriverLink, RawLink
from omsd.models import get_model
from omsd.transport.terminal import MAX_LINE, Terminal, terminal_for


def driver(echoing: bool = False, eos: int = 0x0A) -> Terminal:
    return Terminal(eos=eos, markers=True, echoing=lambda: echoing)


# -- typing ---------------------------------------------------------------------------------------


def test_a_line_is_shown_as_typed_and_sent_with_enter() -> None:
    t = driver()
    assert t.typed(b"W") == (b"", b"W")
    assert t.typed(b"Y") == (b"", b"Y")
    assert t.typed(b"\r") == (b"WY\r", b"\r\n")


@pytest.mark.parametrize("enter", [b"\r", b"\n", b"\r\n"])
def test_every_enter_key_is_one_cr(enter: bytes) -> None:
    t = driver()
    assert t.typed(b"RP" + enter + b"RP" + enter) == (b"RP\rRP\r", b"RP\r\nRP\r\n")


def test_enter_on_an_empty_line_sends_a_cr_and_shows_a_new_line() -> None:
    assert driver().typed(b"\r") == (b"\r", b"\r\n")


@pytest.mark.parametrize("erase", [b"\x08", b"\x7f"])
def test_backspace_and_del_erase_before_the_board_sees_it(erase: bytes) -> None:
    t = driver()
    board, screen = t.typed(b"WX" + erase + b"Y\r")
    assert board == b"WY\r"
    assert screen == b"WX\b \bY\r\n"
    assert t.typed(erase) == (b"", b"")  # nothing left to erase


def test_control_u_erases_the_line() -> None:
    t = driver()
    assert t.typed(b"AX MR\x15") == (b"", b"AX MR" + b"\b \b" * 5)
    assert t.typed(b"RP\r") == (b"RP\r", b"RP\r\n")


def test_control_characters_go_at_once_and_show_on_a_line_of_their_own() -> None:
    """Control-D, the kill, never waits for Enter; the line being typed stays and is shown
    again."""
    t = driver()
    assert t.typed(b"AX MR") == (b"", b"AX MR")
    assert t.typed(b"\x04") == (b"\x04", b"\r\n^D\r\nAX MR")
    assert t.typed(b"5\r") == (b"AX MR5\r", b"5\r\n")


def test_arrow_and_function_keys_are_ignored() -> None:
    t = driver()
    assert t.typed(b"R\x1b[A\x1b[1;5D\x1bOPP\r") == (b"RP\r", b"RP\r\n")


def test_a_tab_is_a_separator_shown_as_a_space() -> None:
    assert driver().typed(b"AX\tRP\r") == (b"AX\tRP\r", b"AX RP\r\n")


def test_a_line_has_a_bound() -> None:
    t = driver()
    board, screen = t.typed(b"A" * (MAX_LINE + 2))
    assert board == b"" and screen == b"A" * MAX_LINE + b"\x07\x07"


def test_with_the_boards_echo_on_characters_pass_straight_on() -> None:
    """EN: the board shows what it reads; Enter still starts a new line on the screen, once."""
    echo = [False]
    t = Terminal(eos=0x0A, markers=True, echoing=lambda: echo[0])
    assert t.typed(b"EN") == (b"", b"EN")
    echo[0] = True
    assert t.typed(b"\r") == (b"EN\r", b"\r\n")
    assert t.typed(b"W") == (b"W", b"")
    assert t.shown(b"W") == b"W"
    assert t.typed(b"Y") == (b"Y", b"")
    assert t.shown(b"Y\nPC48 ver 3.00-4\n") == b"Y\r\nPC48 ver 3.00-4\r\n"
    assert t.typed(b"\r") == (b"\r", b"")  # already on a new line


# -- what the board says --------------------------------------------------------------------------


def test_driver_replies_and_markers_get_cr_lf() -> None:
    t = driver()
    assert t.shown(b"0\n#\n@\n$\n") == b"0\r\n#\r\n@\r\n$\r\n"


@pytest.mark.parametrize("register", [0x01, 0x0A, 0x0D, 0x08, 0x1B, 0x21, 0xFF])
def test_the_done_byte_is_shown_in_hex(register: int) -> None:
    """The done-flag register is binary: a line feed, a backspace or an escape must not act
    on the screen. Split anywhere, it reads the same."""
    data = b"!" + bytes([register]) + b"\n"
    expected = b"!%02X\r\n" % register
    assert driver().shown(data) == expected
    t = driver()
    assert b"".join(t.shown(data[i : i + 1]) for i in range(len(data))) == expected


def test_an_end_character_of_the_configuration_is_a_line_end() -> None:
    t = driver(eos=0x0D)
    assert t.shown(b"0\r!\x01\r") == b"0\r\n!01\r\n"
    t = driver(eos=0x3B)  # ";"
    assert t.shown(b"0;1000;") == b"0\r\n1000\r\n"


def test_the_raw_links_framing_is_one_line_each() -> None:
    t = Terminal()
    assert t.shown(b"\n\r0\n\r\n\r\rPNNN\n\r\r") == b"0\r\nPNNN\r\n"
    assert t.shown(b"#") == b"#"
    assert t.typed(b"R") == (b"", b"\r\nR")  # not on the board's line
    assert t.shown(b"!\x01") == b"\r\n!^A"  # the raw link has no markers: just a character
    # typing on: a new line, and the line so far again; erasing too
    assert t.typed(b"P") == (b"", b"\r\nRP")
    assert t.shown(b"#") == b"\r\n#"
    assert t.typed(b"\x7f") == (b"", b"\r\nR")
    assert t.typed(b"\x7f") == (b"", b"\b \b")
    assert t.shown(b"#") == b"#"  # the erased line was a line start: no blank line


def test_the_board_never_writes_on_the_line_being_typed() -> None:
    t = driver()
    t.typed(b"AX MR1000 GO ID\r")
    assert t.typed(b"AX R") == (b"", b"AX R")
    assert t.shown(b"!\x01\n") == b"\r\n!01\r\nAX R"
    assert t.typed(b"P\r") == (b"AX RP\r", b"P\r\n")


def test_control_characters_and_high_bytes_from_the_board_are_shown_safely() -> None:
    assert driver().shown(b"a\x1bb\x07c\x85\n") == b"a^[b^Gc\\x85\r\n"


def test_reset_forgets_the_line_and_the_screen() -> None:
    t = driver()
    t.typed(b"AX MR")
    t.shown(b"!")
    t.reset()
    assert t.typed(b"\r") == (b"\r", b"\r\n")
    assert t.shown(b"!\x0a\n") == b"!0A\r\n"


def test_terminal_for_a_link() -> None:
    board = Board(get_model("PC48-4"), 0.0)
    t = terminal_for(DriverLink(board, eos=0x0D), lambda: False)
    assert (t.eos, t.markers) == (0x0D, True)
    t = terminal_for(RawLink(board), lambda: False)
    assert (t.eos, t.markers) == (None, False)


# -- asking for it --------------------------------------------------------------------------------


def test_terminal_keys_in_a_configuration_file(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(
        "[[board]]\n"
        'tcp = [7001, { address = "127.0.0.1:7002", terminal = true }, { address = 7003 }]\n'
        f'pty = [{{ link = "{tmp_path / "a"}", terminal = true }}, "{tmp_path / "b"}"]\n'
    )
    (board,) = load_config(path).boards
    assert board.tcp == (
        TcpEndpoint("127.0.0.1", 7001),
        TcpEndpoint("127.0.0.1", 7002, terminal=True),
        TcpEndpoint("127.0.0.1", 7003),
    )
    assert [p.terminal for p in board.pty] == [True, False]


@pytest.mark.parametrize(
    ("value", "key", "expected"),
    [
        ("{ terminal = true }", "tcp", "expected a table with an address"),
        ('{ address = 7001, terminal = "yes" }', "tcp.terminal", "expected true or false"),
        ("{ address = 7001, echo = true }", "tcp.echo", "unknown key"),
        ('{ address = "x:y" }', "tcp.address", "expected [HOST:]PORT"),
    ],
)
def test_terminal_key_mistakes(tmp_path: Path, value: str, key: str, expected: str) -> None:
    """One line naming the file, the key and what was expected."""
    path = tmp_path / "omsd.toml"
    path.write_text(f"[[board]]\ntcp = {value}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert message.startswith(str(path)) and "\n" not in message, message
    assert f"{key}: {expected}" in message, message


def test_the_command_line_flag_is_for_the_ptys(tmp_path: Path) -> None:
    (board,) = from_options(None, ["0"], [str(tmp_path / "p")], None, None, None, True).boards
    assert [p.terminal for p in board.pty] == [True]
    assert [t.terminal for t in board.tcp] == [False]
    (board,) = from_options(None, [], [], None, None, None, True).boards  # the defaults
    assert [p.terminal for p in board.pty] == [True]
    (board,) = from_options(None, [], [], None, None, None).boards
    assert [p.terminal for p in board.pty] == [False]


def test_the_flag_is_not_for_a_configuration_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text("[[board]]\ntcp = 7001\n")
    assert main(["--config", str(path), "--terminal"]) == 2
    assert "--terminal" in capsys.readouterr().err
