"""The configuration layer: TOML files and the single-board command line into frozen dataclasses,
and every error as one line that names the file (or option) and the key."""

from __future__ import annotations

import dataclasses
import grp
import json
import os
import re
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from omsd import cli
from omsd.board import AxisWorld, SwitchType
from omsd.config import (
    DEFAULT_TCP_PORT,
    BoardConfig,
    ConfigError,
    DaemonConfig,
    LogConfig,
    PtyEndpoint,
    TcpEndpoint,
    default_config,
    default_pty_link,
    from_options,
    load_config,
    runtime_directory,
    with_state_option,
)

CONFIG_DIR = Path(__file__).resolve().parent.parent / "config"

MINIMAL = '[[board]]\ntcp = "7001"\n'


@pytest.fixture(autouse=True)
def _runtime_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """Default pty links under a known directory, whatever the environment running the tests."""
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    runtime = tmp_path / "run"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    return runtime


def write(tmp_path: Path, text: str, name: str = "omsd.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def load_error(tmp_path: Path, text: str) -> str:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert "\n" not in message and "\r" not in message
    assert message.startswith(f"{path}:"), message
    return message


def options(**given: object) -> dict[str, object]:
    """from_options' arguments: nothing given on the command line, except ``given``."""
    args: dict[str, object] = {
        "board": None,
        "tcp": [],
        "pty": [],
        "link": None,
        "eos": None,
        "log": None,
    }
    args.update(given)
    return args


def option_error(**given: object) -> str:
    with pytest.raises(ConfigError) as info:
        from_options(**options(**given))  # type: ignore[arg-type]
    message = str(info.value)
    assert "\n" not in message
    return message


def board(**given: object) -> BoardConfig:
    config = from_options(**options(**given))  # type: ignore[arg-type]
    assert config.source == "command line"
    (only,) = config.boards
    return only


# -- defaults -----------------------------------------------------------------------------------


def test_default_config_is_one_pc48_4e_on_tcp_7048_and_a_pty(_runtime_dir: Path) -> None:
    config = default_config()
    assert config.source == "built-in default"
    assert config.log == LogConfig(file=None, view="auto")
    (b,) = config.boards
    assert b.name == "board1"
    assert b.model == "PC48-4E"
    assert (b.link, b.eos, b.buffer_size, b.second_client) == ("driver", 0x0A, 256, "takeover")
    assert b.tcp == (TcpEndpoint("127.0.0.1", 7048),)
    assert b.pty == (PtyEndpoint(_runtime_dir / "omsd" / "board1", None, 0o660),)
    assert dict(b.world) == {} and dict(b.inputs) == {}
    assert DEFAULT_TCP_PORT == 7048


def test_default_pty_link_in_xdg_runtime_dir(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", "/run/user/1234")
    assert default_pty_link("xy") == Path("/run/user/1234/omsd/xy")


def test_default_pty_link_without_runtime_dir_is_per_user_in_tmp(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    assert default_pty_link("xy") == Path(f"/tmp/omsd-{os.getuid()}/xy")
    monkeypatch.setenv("XDG_RUNTIME_DIR", "relative/dir")  # not a usable runtime dir
    assert default_pty_link("xy") == Path(f"/tmp/omsd-{os.getuid()}/xy")


def test_default_pty_link_under_a_systemd_runtime_directory(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("RUNTIME_DIRECTORY", "/run/omsd:/run/other")
    assert default_pty_link("xy") == Path("/run/omsd/xy")


def test_configuration_is_frozen() -> None:
    config = default_config()
    b = config.boards[0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        b.name = "other"  # type: ignore[misc]
    with pytest.raises(TypeError):
        b.world["X"] = AxisWorld()  # type: ignore[index]
    given = {"X": AxisWorld()}
    made = BoardConfig(name="b", world=given)
    given["Y"] = AxisWorld()
    assert list(made.world) == ["X"]  # a copy, not a view of the caller's dict


# -- the example files --------------------------------------------------------------------------

EXAMPLES = sorted(CONFIG_DIR.glob("*.toml"))


def test_the_three_example_files_exist() -> None:
    assert {p.name for p in EXAMPLES} >= {"omsd.toml", "epics-pc48.toml", "ci.toml"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_file_loads(path: Path) -> None:
    config = load_config(path)
    assert config.source == str(path)
    assert config.boards


def test_example_lab_setup_shows_every_key() -> None:
    text = (CONFIG_DIR / "omsd.toml").read_text()
    keys = [
        *("file", "view", "name", "model", "link", "eos", "buffer", "tcp", "pty"),
        *("group", "mode", "second_client", "linger", "inputs", "encoders", "serial"),
        "firmware",
        *(f.name for f in dataclasses.fields(AxisWorld)),
    ]
    # a key is shown set, or in a comment where setting it needs the system (a group)
    for key in keys:
        assert re.search(rf"^#?\s*(\S.*[{{,]\s*)?{key} = ", text, re.M), key
    config = load_config(CONFIG_DIR / "omsd.toml")
    xy, slits, crate, servo = config.boards
    assert xy.world["X"].home_switch is SwitchType.NORMALLY_CLOSED
    assert xy.pty[0].group is None and xy.pty[0].mode == 0o600
    assert slits.model == "PC48-8" and slits.eos == 0x0D and slits.buffer_size == 0x800
    assert crate.personality().who_are_you() == "VS4-040 ver 1.04 S/N 000217"
    assert crate.personality().encoder_axes == "XY"
    assert servo.personality().who_are_you() == (
        "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems"
    )
    assert servo.personality().max_queries
    assert config.state == CONFIG_DIR / "omsd.state"


def test_max_queries_is_a_pcix_setting(tmp_path: Path) -> None:
    """``max_queries`` switches the MAX-family extension of a PCIx; on another board it is an
    error (the key means nothing there)."""
    good = tmp_path / "good.toml"
    good.write_text('[[board]]\nmodel = "PCIX-004"\ntcp = 7100\nmax_queries = false\n')
    (board,) = load_config(good).boards
    assert board.personality().max_queries is False
    bad = tmp_path / "bad.toml"
    bad.write_text('[[board]]\nmodel = "PC48-4"\ntcp = 7100\nmax_queries = false\n')
    with pytest.raises(ConfigError, match="max_queries"):
        load_config(bad)


def test_example_epics_board_is_a_pc48_4_on_the_raw_link() -> None:
    (b,) = load_config(CONFIG_DIR / "epics-pc48.toml").boards
    assert (b.model, b.link, b.pty) == ("PC48-4", "raw", ())
    assert b.tcp == (TcpEndpoint("127.0.0.1", 7048),)


def test_example_ci_boards_are_tcp_only_on_every_interface() -> None:
    """Every board for clients is on every interface; the container's health-check board is on
    its loopback only (see the Dockerfile)."""
    config = load_config(CONFIG_DIR / "ci.toml")
    for b in config.boards:
        assert b.pty == ()
        hosts = [t.host for t in b.tcp]
        assert hosts == (["127.0.0.1"] if b.name == "health" else ["0.0.0.0"])
        for world in b.world.values():
            assert world.positive_limit - world.negative_limit <= 20_000


# -- a full file --------------------------------------------------------------------------------

FULL = """
[log]
file = "logs/traffic.jsonl"
view = "Plain"

[[board]]
name = "xy-stage"
model = "pc48-4e"
link = "driver"
eos = "0x0d"
buffer = "0800"
tcp = ["127.0.0.1:7001", 7002, "[::1]:7001", "localhost:7003", "0.0.0.0:0", "[::]:0"]
pty = ["ttyOMS0", true, { link = "/run/omsd/xy", group = "dialout", mode = "0640" }]
second_client = "refuse"
inputs = { 0 = false, 13 = true }

[board.axes.X]
start_position = 12.5
negative_limit = -50000
positive_limit = 50000
home_low = 0
home_high = 100
home_switch = "normally_closed"
encoder_counts_per_rev = 2000
encoder_index = 1999

[board.axes.t]
positive_limit = 3e4

[[board]]
model = "PC48-2"
link = "raw"
tcp = 8001
pty = { link = "~/oms2", mode = 0o600 }
"""


def test_full_file(tmp_path: Path, _runtime_dir: Path) -> None:
    path = write(tmp_path, FULL)
    config = load_config(path)
    assert config.source == str(path)
    assert config.log == LogConfig(tmp_path / "logs" / "traffic.jsonl", "plain")
    xy, second = config.boards
    assert xy.name == "xy-stage" and xy.model == "PC48-4E"
    assert (xy.link, xy.eos, xy.buffer_size, xy.second_client) == ("driver", 13, 2048, "refuse")
    assert xy.tcp == (
        TcpEndpoint("127.0.0.1", 7001),
        TcpEndpoint("127.0.0.1", 7002),
        TcpEndpoint("::1", 7001),
        TcpEndpoint("localhost", 7003),
        TcpEndpoint("0.0.0.0", 0),
        TcpEndpoint("::", 0),
    )
    assert [str(t) for t in xy.tcp[2:4]] == ["[::1]:7001", "localhost:7003"]
    assert xy.pty == (
        PtyEndpoint(tmp_path / "ttyOMS0"),  # relative to the file's directory
        PtyEndpoint(_runtime_dir / "omsd" / "xy-stage"),  # true: the default link
        PtyEndpoint(Path("/run/omsd/xy"), "dialout", 0o640),
    )
    assert dict(xy.inputs) == {0: False, 13: True}
    assert set(xy.world) == {"X", "T"}
    x = xy.world["X"]
    assert x == AxisWorld(
        start_position=12.5,
        negative_limit=-50000,
        positive_limit=50000,
        home_low=0,
        home_high=100,
        home_switch=SwitchType.NORMALLY_CLOSED,
        encoder_counts_per_rev=2000,
        encoder_index=1999,
    )
    assert isinstance(x.negative_limit, float)
    assert xy.world["T"] == AxisWorld(positive_limit=30000.0)  # the rest keep their defaults
    assert second.name == "board2" and second.model == "PC48-2" and second.link == "raw"
    assert second.tcp == (TcpEndpoint("127.0.0.1", 8001),)
    assert second.pty == (PtyEndpoint(Path.home() / "oms2", None, 0o600),)
    assert (second.eos, second.buffer_size) == (0x0A, 256)


def test_a_default_link_given_twice_is_a_duplicate(tmp_path: Path) -> None:
    """``true`` and a table without ``link`` both mean the default link."""
    message = load_error(tmp_path, FULL.replace('0640" }]', '0640" }, {}]'))
    assert '[board "xy-stage"] pty[3]: expected a link no other endpoint uses' in message
    assert '(also [board "xy-stage"] pty[1], line ' in message


def test_eos_and_buffer_as_integers(tmp_path: Path) -> None:
    text = "[[board]]\ntcp = 7001\neos = 0x0D\nbuffer = 16\n[[board]]\ntcp = 7002\neos = 0\n"
    a, b = load_config(write(tmp_path, text)).boards
    assert (a.eos, a.buffer_size, b.eos) == (13, 16, 0)


def test_empty_endpoint_list_is_allowed_beside_the_other_kind(tmp_path: Path) -> None:
    (b,) = load_config(write(tmp_path, '[[board]]\ntcp = []\npty = "p"\n')).boards
    assert b.tcp == () and b.pty == (PtyEndpoint(tmp_path / "p"),)


# -- file errors --------------------------------------------------------------------------------

#: How a message names the first and second [[board]] when they have no name
B1 = '[board "board1" (unnamed)]'
B2 = '[board "board2" (unnamed)]'

FILE_ERRORS = [
    # unknown keys anywhere, with the allowed ones
    (
        "colour = 1\n" + MINIMAL,
        "1: colour: unknown key; expected one of log, state, control, mqtt, web, board",
    ),
    (
        MINIMAL + "modle = 'PC48-4'\n",
        f"3: {B1} modle: unknown key (did you mean 'model'?); expected one of name, model,",
    ),
    (MINIMAL + "[board.axes.X]\nhome = 5\n", f"4: {B1} axes.X.home: unknown key"),
    ("[log]\nlevel = 'debug'\n" + MINIMAL, "2: log.level: unknown key; expected one of file, view"),
    (
        '[[board]]\npty = { lnk = "p" }\n',
        f"2: {B1} pty.lnk: unknown key (did you mean 'link'?); expected one of link, group, mode",
    ),
    # the document's shape
    ("", "board: expected at least one [[board]] table, got none"),
    ("board = []\n", "1: board: expected at least one [[board]] table, got none"),
    ('[board]\ntcp = "7001"\n', "1: board: expected an array of tables, [[board]], got {"),
    ("board = [1]\n", f"1: {B1}: expected a table, got 1"),
    ("log = 'x'\n" + MINIMAL, '1: log: expected a table, got "x"'),
    (
        "[[board]]\nname = 'a'\n",
        '1: [board "a"]: expected at least one endpoint (tcp, pty, serial_port or rfc2217),'
        " got none",
    ),
    ("[[board]]\ntcp = []\npty = []\n", f"1: {B1}: expected at least one endpoint"),
    # names
    (MINIMAL + "name = 'x y'\n", '3: [board "x y"] name: expected a name of letters, digits'),
    (MINIMAL + "name = '..'\n", '3: [board ".."] name: expected a name of letters, digits'),
    (MINIMAL + "name = 3\n", "3: [board 3] name: expected a name of letters, digits, '_', '.' and"),
    (
        MINIMAL + "name = 'a'\n" + '[[board]]\nname = "a"\ntcp = 7002\n',
        '5: [board "a"] name: expected a name no other board has, got "a" (also [board "a"] '
        "name, line 3)",
    ),
    (
        '[[board]]\nname = "board2"\ntcp = 7001\n[[board]]\ntcp = 7002\n',
        f'4: {B2} name: expected a name no other board has, got "board2"',
    ),
    # model
    (
        MINIMAL + "model = 'PC99'\n",
        f"3: {B1} model: expected a board model (PC48-2, PC48-4, ",
    ),
    (MINIMAL + "model = 4\n", f"3: {B1} model: expected a board model"),
    # link and driver settings
    (MINIMAL + "link = 'serial'\n", f'3: {B1} link: expected "driver" or "raw", got "serial"'),
    (MINIMAL + "eos = 'GG'\n", f"3: {B1} eos: expected a character code 00..FF in hex"),
    (MINIMAL + "eos = '100'\n", f"3: {B1} eos: expected a character code 00..FF"),
    (MINIMAL + "eos = 256\n", f"3: {B1} eos: expected a character code 00..FF in hex like the"),
    (MINIMAL + "eos = -1\n", f"3: {B1} eos: expected"),
    (MINIMAL + "eos = true\n", f"3: {B1} eos: expected a character code 00..FF in hex"),
    (MINIMAL + "buffer = 15\n", f"3: {B1} buffer: expected a buffer size 16..32767"),
    (MINIMAL + "buffer = 32768\n", f"3: {B1} buffer: expected a buffer size 16..32767"),
    (MINIMAL + "buffer = '8000'\n", f"3: {B1} buffer: expected a buffer size 16..32767"),
    (MINIMAL + "buffer = 256.0\n", f"3: {B1} buffer: expected a buffer size 16..32767"),
    (
        MINIMAL + "link = 'raw'\neos = '0D'\n",
        f"4: {B1} eos: is a driver link setting; a raw link keeps the board's own LF/CR framing",
    ),
    (MINIMAL + "link = 'raw'\nbuffer = 512\n", f"4: {B1} buffer: is a driver link setting"),
    (
        MINIMAL + "second_client = 'queue'\n",
        f'3: {B1} second_client: expected "takeover" or "refuse", got "queue"',
    ),
    # TCP
    ("[[board]]\ntcp = true\n", f"2: {B1} tcp: expected [HOST:]PORT with PORT 0..65535, got true"),
    ("[[board]]\ntcp = 65536\n", f"2: {B1} tcp: expected [HOST:]PORT with PORT 0..65535"),
    ("[[board]]\ntcp = [7001, 'x']\n", f"2: {B1} tcp[1]: expected [HOST:]PORT with PORT"),
    (
        "[[board]]\ntcp = ['7001', '7001']\n",
        f'2: {B1} tcp[1]: expected an address no other endpoint uses, got "127.0.0.1:7001" (also '
        f"{B1} tcp[0], line 2)",
    ),
    (
        "[[board]]\ntcp = '0.0.0.0:7001'\n[[board]]\ntcp = '127.0.0.1:7001'\n",
        f'4: {B2} tcp: expected an address no other endpoint uses, got "127.0.0.1:7001" (also '
        f"{B1} tcp, line 2)",
    ),
    (
        "[[board]]\ntcp = '[::1]:7001'\n[[board]]\ntcp = '[::]:7001'\n",
        f'4: {B2} tcp: expected an address no other endpoint uses, got "[::]:7001"',
    ),
    # pty
    ("[[board]]\npty = ''\n", f'2: {B1} pty: expected a path, got ""'),
    ("[[board]]\npty = false\n", f"2: {B1} pty: expected a path, true (the default link) or a"),
    ("[[board]]\npty = [3]\n", f"2: {B1} pty[0]: expected a path, true"),
    ("[[board]]\npty = { mode = '0666x' }\n", f"2: {B1} pty.mode: expected permissions 0o000.."),
    ("[[board]]\npty = { mode = 660 }\n", f"2: {B1} pty.mode: expected permissions"),
    ("[[board]]\npty = { mode = '1777' }\n", f"2: {B1} pty.mode: expected permissions"),
    ("[[board]]\npty = { group = '' }\n", f"2: {B1} pty.group: expected a non-empty string"),
    ("[[board]]\npty = { group = 20 }\n", f"2: {B1} pty.group: expected a non-empty string"),
    (
        "[[board]]\npty = 'a/b'\n[[board]]\npty = 'a/./b'\n",
        f"4: {B2} pty: expected a link no other endpoint uses, got ",
    ),
    # log
    ("[log]\nview = 'color'\n" + MINIMAL, '2: log.view: expected "auto" or "rich" or "plain" or'),
    ("[log]\nfile = 5\n" + MINIMAL, "2: log.file: expected a path, got 5"),
    # inputs
    (MINIMAL + "inputs = { 14 = true }\n", f"3: {B1} inputs.14: expected a general-purpose I/O"),
    (MINIMAL + "inputs = { a = true }\n", f"3: {B1} inputs.a: expected a general-purpose I/O"),
    (MINIMAL + "inputs = { 0 = 'low' }\n", f"3: {B1} inputs.0: expected true (high) or false"),
    (MINIMAL + "inputs = { 0 = true, 00 = false }\n", f"3: {B1} inputs.00: input bit 0 is given"),
    (MINIMAL + "inputs = [0]\n", f"3: {B1} inputs: expected a table, got [0]"),
    # axes
    (MINIMAL + "[board.axes.U]\n", f"3: {B1} axes.U: PC48-4E has axes X, Y, Z, T"),
    (MINIMAL + "model = 'PC48-2'\n[board.axes.XY]\n", f"4: {B1} axes.XY: PC48-2 has axes X, Y"),
    (MINIMAL + "[board.axes.X]\n[board.axes.x]\n", f"4: {B1} axes.x: axis X is given twice"),
    (MINIMAL + "axes = { X = 1 }\n", f"3: {B1} axes.X: expected a table, got 1"),
    (
        MINIMAL + "[board.axes.X]\nhome_low = 'zero'\n",
        f'4: {B1} axes.X.home_low: expected a number (motor steps), got "zero"',
    ),
    (MINIMAL + "[board.axes.X]\nhome_low = true\n", f"4: {B1} axes.X.home_low: expected a number"),
    (
        MINIMAL + "[board.axes.X]\nnegative_limit = -inf\n",
        f"4: {B1} axes.X.negative_limit: expected a finite number, got -inf",
    ),
    (
        MINIMAL + "[board.axes.X]\nstart_position = nan\n",
        f"4: {B1} axes.X.start_position: expected a finite number, got nan",
    ),
    (
        MINIMAL + "[board.axes.X]\nhome_switch = 'closed'\n",
        f'4: {B1} axes.X.home_switch: expected "normally_open" or "normally_closed", got "closed"',
    ),
    (
        MINIMAL + "[board.axes.X]\npositive_limit = -20000000\n",
        f"4: {B1} axes.X.positive_limit: expected negative_limit below positive_limit, got -1e+07 "
        "and -2e+07",
    ),
    (
        MINIMAL + "[board.axes.X]\nnegative_limit = 20000000\n",
        f"4: {B1} axes.X.negative_limit: expected negative_limit below positive_limit",
    ),
    (
        MINIMAL + "[board.axes.X]\nhome_low = 5\nhome_high = 5\n",
        f"5: {B1} axes.X.home_high: expected home_low below home_high, got 5 and 5",
    ),
    (
        MINIMAL + "[board.axes.X]\nencoder_counts_per_rev = 0\n",
        f"4: {B1} axes.X.encoder_counts_per_rev: expected an integer >= 1, got 0",
    ),
    (
        MINIMAL + "[board.axes.X]\nencoder_counts_per_rev = 1.5\n",
        f"4: {B1} axes.X.encoder_counts_per_rev: expected an integer >= 1, got 1.5",
    ),
    (
        MINIMAL + "[board.axes.X]\nencoder_index = 4000\n",
        f"4: {B1} axes.X.encoder_index: expected an integer 0..3999 (below "
        "encoder_counts_per_rev), got 4000",
    ),
    (
        MINIMAL + "[board.axes.X]\nencoder_index = -1\n",
        f"4: {B1} axes.X.encoder_index: expected an integer >= 0",
    ),
    (
        MINIMAL + "model = 'PC48-4'\n[board.axes.X]\nencoder_index = 0\n",
        f"5: {B1} axes.X.encoder_index: PC48-4 has no encoder on axis X (no encoder option)",
    ),
    (
        MINIMAL + "model = 'PC48-6E'\n[board.axes.U]\nencoder_counts_per_rev = 500\n",
        f"5: {B1} axes.U.encoder_counts_per_rev: PC48-6E has no encoder on axis U (encoders on X, "
        "Y)",
    ),
    # invalid TOML
    (MINIMAL + "model = \n", "3:9: invalid TOML: Invalid value"),
    (MINIMAL + 'tcp = "7002"\n', "3:13: invalid TOML: Cannot overwrite a value"),
    ('[[board]]\nname = "open\n', "2:13: invalid TOML: Illegal character '\\n'"),
]


@pytest.mark.parametrize(("text", "expected"), FILE_ERRORS)
def test_file_error_is_one_line_naming_file_and_key(
    tmp_path: Path, text: str, expected: str
) -> None:
    message = load_error(tmp_path, text)
    # FILE:LINE: KEY: ..., or FILE: KEY: ... where the file does not write the key
    where = f"{tmp_path / 'omsd.toml'}{':' if expected[0].isdigit() else ': '}"
    assert message.startswith(f"{where}{expected}"), message


def test_file_error_names_the_key_first(tmp_path: Path) -> None:
    """The key path comes right after the file, so ``omsd: FILE: KEY: ...`` reads in order."""
    message = load_error(tmp_path, MINIMAL + "[board.axes.U]\n")
    where = f"{tmp_path / 'omsd.toml'}:3"
    assert message == f'{where}: [board "board1" (unnamed)] axes.U: PC48-4E has axes X, Y, Z, T'


def test_error_attributes(tmp_path: Path) -> None:
    path = write(tmp_path, MINIMAL + "link = 'serial'\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    error = info.value
    assert (error.source, error.key) == (str(path), '[board "board1" (unnamed)] link')
    assert (error.line, error.path) == (3, ("board", 0, "link"))


def test_odd_keys_are_quoted_and_stay_on_one_line(tmp_path: Path) -> None:
    message = load_error(tmp_path, MINIMAL + '"a\\nb" = 1\n')
    assert '[board "board1" (unnamed)] "a\\nb": unknown key' in message


def test_long_values_are_shortened(tmp_path: Path) -> None:
    message = load_error(tmp_path, f"[[board]]\ntcp = '{'9' * 500}'\n")
    assert len(message) < 200 + len(str(tmp_path))


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "nope.toml"
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == f"{path}: cannot read the file: No such file or directory"


def test_directory_instead_of_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as info:
        load_config(tmp_path)
    assert str(info.value) == f"{tmp_path}: cannot read the file: Is a directory"


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files whatever their permissions")
def test_unreadable_file(tmp_path: Path) -> None:
    path = write(tmp_path, MINIMAL)
    path.chmod(0)
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == f"{path}: cannot read the file: Permission denied"


def test_file_that_is_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / "latin1.toml"
    path.write_bytes(b"# caf\xe9\n" + MINIMAL.encode())
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value) == f"{path}: expected UTF-8 text, got byte 0xe9 at offset 5"


def test_source_is_the_path_as_given(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write(tmp_path, MINIMAL + "link = 'x'\n")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ConfigError) as info:
        load_config("omsd.toml")
    assert str(info.value).startswith('omsd.toml:3: [board "board1" (unnamed)] link: ')
    assert load_config(write(tmp_path, MINIMAL, "ok.toml")).source == str(tmp_path / "ok.toml")


def test_port_zero_may_repeat_and_different_families_do_not_collide(tmp_path: Path) -> None:
    text = (
        "[[board]]\ntcp = [0, '0.0.0.0:0', '0.0.0.0:7001']\n"
        "[[board]]\ntcp = [0, '[::]:7001', 'localhost:7002']\n"
        "[[board]]\ntcp = ['127.0.0.1:7002', '[::1]:7003', '127.0.0.1:7003']\n"
    )
    boards = load_config(write(tmp_path, text)).boards
    assert [len(b.tcp) for b in boards] == [3, 3, 3]


# -- the command line ---------------------------------------------------------------------------


def test_no_options_give_the_default_endpoints(_runtime_dir: Path) -> None:
    config = from_options(None, [], [], None, None, None)
    assert config.boards == default_config().boards
    assert config.log == LogConfig()
    assert config.source == "command line"


@pytest.mark.parametrize(
    ("text", "endpoint"),
    [
        ("7001", TcpEndpoint("127.0.0.1", 7001)),
        ("0", TcpEndpoint("127.0.0.1", 0)),
        ("65535", TcpEndpoint("127.0.0.1", 65535)),
        ("0.0.0.0:7001", TcpEndpoint("0.0.0.0", 7001)),
        ("192.168.1.20:7001", TcpEndpoint("192.168.1.20", 7001)),
        ("localhost:7001", TcpEndpoint("localhost", 7001)),
        ("oms-sim.lab.example:7001", TcpEndpoint("oms-sim.lab.example", 7001)),
        ("[::1]:7001", TcpEndpoint("::1", 7001)),
        ("[::]:7001", TcpEndpoint("::", 7001)),
        ("[fe80::1%eth0]:7001", TcpEndpoint("fe80::1%eth0", 7001)),
        ("007001", None),  # more than five digits
    ],
)
def test_tcp_option(text: str, endpoint: TcpEndpoint | None) -> None:
    if endpoint is None:
        assert "--tcp: expected [HOST:]PORT" in option_error(tcp=[text])
        return
    b = board(tcp=[text])
    assert b.tcp == (endpoint,)
    assert b.pty == ()  # only the kind given


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("abc", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "abc"'),
        ("", '--tcp: expected [HOST:]PORT with PORT 0..65535, got ""'),
        ("65536", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "65536"'),
        ("-1", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "-1"'),
        ("+7001", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "+7001"'),
        (" 7001", '--tcp: expected [HOST:]PORT with PORT 0..65535, got " 7001"'),
        ("7_001", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "7_001"'),
        ("localhost", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "localhost"'),
        ("localhost:", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "localhost:"'),
        ("::1:7001", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "::1:7001"'),
        ("[::1:7001", '--tcp: expected [HOST:]PORT with PORT 0..65535, got "[::1:7001"'),
        (
            ":7001",
            "--tcp: expected [HOST:]PORT with a HOST before the colon (0.0.0.0 for every "
            'interface), got ":7001"',
        ),
        ("[]:7001", '--tcp: expected [HOST:]PORT with an IPv6 address inside [ ], got "[]:7001"'),
        (
            "[1.2.3.4]:7001",
            '--tcp: expected [HOST:]PORT with an IPv6 address inside [ ], got "[1.2.3.4]:7001"',
        ),
        (
            "1.2.3.999:7001",
            '--tcp: expected [HOST:]PORT with a valid IPv4 address, got "1.2.3.999:7001"',
        ),
        (
            "my host:7001",
            '--tcp: expected [HOST:]PORT with HOST an address or a host name, got "my host:7001"',
        ),
        (
            "-x:7001",
            '--tcp: expected [HOST:]PORT with HOST an address or a host name, got "-x:7001"',
        ),
    ],
)
def test_tcp_option_errors(text: str, expected: str) -> None:
    assert option_error(tcp=[text]) == expected


def test_tcp_option_given_twice_is_an_error() -> None:
    assert option_error(tcp=["7001", "127.0.0.1:7001"]) == (
        '--tcp: expected an address no other endpoint uses, got "127.0.0.1:7001" twice'
    )
    assert "twice" in option_error(tcp=["0.0.0.0:7001", "7001"])


def test_pty_option_only(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    b = board(pty=["ttyOMS", "/run/omsd/b", "~/x"])
    assert b.tcp == ()
    assert b.pty == (
        PtyEndpoint(tmp_path / "ttyOMS"),  # made absolute against the working directory
        PtyEndpoint(Path("/run/omsd/b")),
        PtyEndpoint(Path.home() / "x"),
    )
    assert option_error(pty=[""]) == '--pty: expected a path, got ""'
    assert option_error(pty=["a", "./a"]).startswith(
        "--pty: expected a link no other endpoint uses, got "
    )


def test_tcp_and_pty_options_together() -> None:
    b = board(tcp=["7001"], pty=["/tmp/x"])
    assert b.tcp == (TcpEndpoint("127.0.0.1", 7001),)
    assert b.pty == (PtyEndpoint(Path("/tmp/x")),)


def test_board_option_is_case_insensitive() -> None:
    assert board(board="pc48-6e").model == "PC48-6E"
    assert board(board=" PC48-2 ").model == "PC48-2"
    assert board().model == "PC48-4E"
    assert option_error(board="PC99").startswith(
        "--board: expected a board model (PC48-2, PC48-4, "
    )
    assert option_error(board="PC99").endswith('got "PC99"')


def test_link_option() -> None:
    assert board().link == "driver"
    assert board(link="raw").link == "raw"
    assert board(link="RAW").link == "raw"
    assert option_error(link="serial") == '--link: expected "driver" or "raw", got "serial"'


@pytest.mark.parametrize(
    ("text", "value"),
    [("0D", 0x0D), ("0d", 0x0D), ("0x0d", 0x0D), ("0X0A", 0x0A), ("D", 0x0D), ("ff", 0xFF)],
)
def test_eos_option_is_hex_like_the_drivers_e_option(text: str, value: int) -> None:
    assert board(eos=text).eos == value


@pytest.mark.parametrize("text", ["", "100", "0x", "GG", "13h", "-1", "0x100"])
def test_eos_option_errors(text: str) -> None:
    assert option_error(eos=text) == (
        '--eos: expected a character code 00..FF in hex like the driver\'s E:XX ("0D"), '
        f"got {json.dumps(text)}"
    )


def test_eos_option_on_a_raw_link_is_an_error() -> None:
    assert option_error(link="raw", eos="0D") == (
        "--eos: is a driver link setting; a raw link keeps the board's own LF/CR framing"
    )


def test_log_option(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    config = from_options(None, ["7001"], [], None, None, "traffic.jsonl")
    assert config.log == LogConfig(tmp_path / "traffic.jsonl", "auto")
    assert option_error(log="") == '--log: expected a path, got ""'


def test_option_errors_come_before_defaults_are_used() -> None:
    """An error in one option is reported even when the others are valid."""
    assert option_error(tcp=["7001"], board="x").startswith("--board: ")
    assert option_error(tcp=["x"], board="pc48-4").startswith("--tcp: ")


def test_file_with_a_byte_order_mark_loads(tmp_path: Path) -> None:
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + MINIMAL.encode())
    assert load_config(path).boards[0].tcp == (TcpEndpoint("127.0.0.1", 7001),)


# -- the board as fitted: encoders, serial number, firmware ---------------------------------------


def test_encoder_option_serial_and_firmware(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(
        "[[board]]\nmodel = 'VS4-040'\ntcp = 0\nencoders = false\nserial = '000217'\n"
        "firmware = '1.04'\n\n[[board]]\nmodel = 'VS4-040'\ntcp = 0\nencoders = 'zx'\n"
        "[board.axes.Z]\nencoder_index = 5\n"
    )
    plain, partial = load_config(path).boards
    model = plain.personality()
    assert model.encoder_axes == ""
    assert model.who_are_you() == "VS4-040 ver 1.04 S/N 000217"
    assert partial.personality().encoder_axes == "XZ"
    assert partial.personality().who_are_you() == "VS4-040 ver 1.00 S/N 123456"


@pytest.mark.parametrize(
    ("line", "key"),
    [
        ("encoders = 'XU'", "encoders"),
        ("encoders = 3", "encoders"),
        ("serial = 'a b'", "serial"),
        ("firmware = 'v1'", "firmware"),
    ],
)
def test_bad_encoder_serial_firmware(tmp_path: Path, line: str, key: str) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(f"[[board]]\nmodel = 'VS4-040'\ntcp = 0\n{line}\n")
    with pytest.raises(ConfigError) as err:
        load_config(path)
    assert f':4: [board "board1" (unnamed)] {key}: expected' in str(err.value)
    assert "\n" not in str(err.value)


def test_encoder_settings_follow_the_fitted_encoders(tmp_path: Path) -> None:
    """With ``encoders = false`` an axis has no encoder, so its encoder settings are a mistake."""
    path = tmp_path / "omsd.toml"
    path.write_text(
        "[[board]]\nmodel = 'VS4-040'\ntcp = 0\nencoders = false\n"
        "[board.axes.X]\nencoder_index = 5\n"
    )
    with pytest.raises(ConfigError, match="has no encoder on axis X"):
        load_config(path)


# -- the state file (the boards' flash) ---------------------------------------------------------


def test_no_state_file_unless_configured(tmp_path: Path) -> None:
    assert default_config().state is None
    assert load_config(write(tmp_path, MINIMAL)).state is None
    assert load_config(write(tmp_path, "[state]\n" + MINIMAL)).state is None
    assert from_options(None, ["7001"], [], None, None, None).state is None


@pytest.mark.parametrize(
    ("value", "expected"),
    [
        ('"omsd.state"', "{dir}/omsd.state"),  # relative to the file's directory
        ('"../lib/./omsd.state"', "{parent}/lib/omsd.state"),
        ('"/var/lib/omsd/omsd.state"', "/var/lib/omsd/omsd.state"),
        ('"~/omsd.state"', "{home}/omsd.state"),
    ],
)
def test_state_file_in_a_file(tmp_path: Path, value: str, expected: str) -> None:
    config = load_config(write(tmp_path, f"[state]\nfile = {value}\n" + MINIMAL))
    where = expected.format(dir=tmp_path, parent=tmp_path.parent, home=Path.home())
    assert config.state == Path(where)
    assert config.state.is_absolute()


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ('state = "omsd.state"\n', '1: state: expected a table, got "omsd.state"'),
        ("[state]\nfile = 5\n", "2: state.file: expected a path, got 5"),
        ('[state]\nfile = ""\n', '2: state.file: expected a path, got ""'),
        (
            '[state]\npath = "x"\n',
            "2: state.path: unknown key; expected one of file, group",
        ),
        (
            '[state]\nfiles = "x"\n',
            "2: state.files: unknown key (did you mean 'file'?); expected one of file, group",
        ),
        (
            '[log]\nfile = "same"\n[state]\nfile = "./same"\n',
            '4: state.file: expected a file other than the traffic log, got "{dir}/same"',
        ),
    ],
)
def test_state_file_errors(tmp_path: Path, text: str, expected: str) -> None:
    message = load_error(tmp_path, text + MINIMAL)
    assert message == f"{tmp_path / 'omsd.toml'}:{expected.format(dir=tmp_path)}"


def test_state_option(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """--state is relative to the working directory, and wins over the file's [state]."""
    monkeypatch.chdir(tmp_path)
    single = from_options(None, ["7001"], [], None, None, None)
    assert with_state_option(single, None) is single
    assert with_state_option(single, "omsd.state").state == tmp_path / "omsd.state"
    configured = load_config(write(tmp_path, '[state]\nfile = "a.state"\n' + MINIMAL))
    assert configured.state == tmp_path / "a.state"
    assert with_state_option(configured, None).state == tmp_path / "a.state"
    overridden = with_state_option(configured, "/var/lib/omsd/b.state")
    assert overridden.state == Path("/var/lib/omsd/b.state")
    assert overridden.boards == configured.boards and overridden.source == configured.source


@pytest.mark.parametrize(
    ("state", "log", "expected"),
    [
        ("", None, '--state: expected a path, got ""'),
        ("t.jsonl", "t.jsonl", '--state: expected a file other than the traffic log, got "{dir}'),
    ],
)
def test_state_option_errors(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, state: str, log: str | None, expected: str
) -> None:
    monkeypatch.chdir(tmp_path)
    config = from_options(None, ["7001"], [], None, None, log)
    with pytest.raises(ConfigError) as info:
        with_state_option(config, state)
    assert str(info.value).startswith(expected.format(dir=tmp_path))


def _serve(monkeypatch: pytest.MonkeyPatch, argv: list[str]) -> DaemonConfig:
    """The configuration ``omsd ARGV`` would serve (the daemon is replaced by a stand-in)."""
    from omsd import daemon

    served: list[DaemonConfig] = []

    class Daemon:
        def __init__(self, config: DaemonConfig, log: object, **options: object) -> None:
            served.append(config)

        async def run(self) -> None:
            return None

    monkeypatch.setattr(daemon, "Daemon", Daemon)
    assert cli.main([*argv, "--view", "off"]) == 0
    (config,) = served
    return config


def test_state_command_line_option_reaches_the_daemon(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert _serve(monkeypatch, ["--tcp", "0"]).state is None
    assert _serve(monkeypatch, ["--tcp", "0", "--state", "s"]).state == tmp_path / "s"
    path = write(tmp_path, '[state]\nfile = "f.state"\n' + MINIMAL)
    assert _serve(monkeypatch, ["--config", str(path)]).state == tmp_path / "f.state"
    config = _serve(monkeypatch, ["--config", str(path), "--state", "/x/o.state"])
    assert config.state == Path("/x/o.state")


def test_state_command_line_error_is_a_configuration_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert cli.main(["--tcp", "0", "--state", ""]) == 2
    assert capsys.readouterr().err == 'omsd: --state: expected a path, got ""\n'


# -- linger: how long a half-closed TCP client is kept for its answers -------------------------


def test_linger_defaults_to_a_minute_and_takes_seconds(tmp_path: Path) -> None:
    (default,) = load_config(write(tmp_path, "[[board]]\ntcp = 7001\n")).boards
    assert default.linger == 60.0
    (given,) = load_config(write(tmp_path, "[[board]]\ntcp = 7001\nlinger = 2.5\n")).boards
    assert given.linger == 2.5
    (off,) = load_config(write(tmp_path, "[[board]]\ntcp = 7001\nlinger = 0\n")).boards
    assert off.linger == 0.0


@pytest.mark.parametrize("value", ["-1", "3601", '"60"', "true", "nan"])
def test_linger_out_of_range_or_not_a_number_is_refused(tmp_path: Path, value: str) -> None:
    message = load_error(tmp_path, f"[[board]]\ntcp = 7001\nlinger = {value}\n")
    expected = '3: [board "board1" (unnamed)] linger: expected a number of seconds 0..3600, got'
    assert expected in message, message


# -- issue 13: the group of the log and state files -----------------------------------------


def _my_group() -> str:
    return grp.getgrgid(os.getegid()).gr_name


def test_log_and_state_groups(tmp_path: Path) -> None:
    group = _my_group()
    config = load_config(
        write(
            tmp_path,
            f'[log]\nfile = "t.jsonl"\ngroup = "{group}"\n'
            f'[state]\nfile = "s.state"\ngroup = "{group}"\n' + MINIMAL,
        )
    )
    assert (config.log.group, config.state_group) == (group, group)
    plain = load_config(write(tmp_path, MINIMAL))
    assert (plain.log.group, plain.state_group) == (None, None)


@pytest.mark.parametrize("table", ["log", "state", "control"])
@pytest.mark.parametrize(
    ("value", "expected"),
    [
        (
            '"no-such-group-omsd"',
            'expected the name of an existing group, got "no-such-group-omsd"',
        ),
        ("0", "expected a non-empty string, got 0"),
        ('""', 'expected a non-empty string, got ""'),
    ],
)
def test_a_bad_group_is_one_line_naming_the_key(
    tmp_path: Path, table: str, value: str, expected: str
) -> None:
    message = load_error(tmp_path, f"[{table}]\ngroup = {value}\n" + MINIMAL)
    assert message == f"{tmp_path / 'omsd.toml'}:2: {table}.group: {expected}"


def test_a_group_the_daemon_is_not_in_is_refused(tmp_path: Path) -> None:
    if os.geteuid() == 0:
        pytest.skip("root may give a file to any group")
    mine = {os.getegid(), *os.getgroups()}
    other = next((g for g in grp.getgrall() if g.gr_gid not in mine), None)
    if other is None:
        pytest.skip("this user is in every group")
    message = load_error(tmp_path, f'[log]\ngroup = "{other.gr_name}"\n' + MINIMAL)
    assert f"log.group: expected a group that omsd's user (uid {os.geteuid()})" in message


def test_the_runtime_directory_holds_the_default_links(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", "/run/user/1234")
    assert runtime_directory() == Path("/run/user/1234/omsd")
    assert default_pty_link("xy").parent == runtime_directory()


def test_the_default_encoder_index_is_in_the_middle_of_the_home_window(tmp_path: Path) -> None:
    """Left out, the index is at the middle of the home window, modulo a revolution (so that an
    encoder home finds it in any window); given, it must be below a revolution."""
    path = tmp_path / "omsd.toml"
    cases = [
        ("encoder_counts_per_rev = 500\n", 50),  # 1050, the default window's middle, mod 500
        ("encoder_counts_per_rev = 8000\n", 1050),
        ("home_low = 0\nhome_high = 100\n", 50),
        ("home_low = -7990\nhome_high = -7890\n", 60),  # -7940 mod 4000
        ("encoder_index = 7\n", 7),
    ]
    for keys, index in cases:
        path.write_text(MINIMAL + "[board.axes.X]\n" + keys)
        (board,) = load_config(path).boards
        assert board.world["X"].index_count == index, keys
    assert "encoder_index: expected an integer 0..499" in load_error(
        tmp_path, MINIMAL + "[board.axes.X]\nencoder_counts_per_rev = 500\nencoder_index = 500\n"
    )


def test_a_file_without_end_is_refused_not_read_for_ever(tmp_path: Path) -> None:
    """``omsd --config /dev/zero`` read until memory ran out (1.7 GB in 3 s, the machine's
    whole memory soon after): the file was read whole before a byte of it was looked at. A
    configuration is read up to ``MAX_CONFIG`` bytes; one longer is refused in one line. A
    pipe (``--config <(...)``) is read as before."""
    from omsd.config.reading import MAX_CONFIG

    limit = lambda: resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))  # noqa: E731
    command = [sys.executable, "-m", "omsd", "--config", "/dev/zero", "--control", "off"]
    run = subprocess.run(
        command, capture_output=True, text=True, timeout=60, preexec_fn=limit, cwd=tmp_path
    )
    assert run.returncode == 2, run.stderr[-500:]
    assert run.stderr == (
        f"omsd: /dev/zero: expected a configuration of at most {MAX_CONFIG} bytes, got more\n"
    )
    read, write = os.pipe()
    with os.fdopen(write, "w") as out:
        out.write(MINIMAL)
    try:
        assert load_config(f"/dev/fd/{read}").boards[0].model == "PC48-4E"
    finally:
        os.close(read)
