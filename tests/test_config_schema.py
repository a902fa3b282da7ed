"""The configuration described once (issue 15): the schema (omsd/config/schema.py) gives the
validation, the defaults, the command line's one-board form, the JSON Schema that omsd publishes
(config/omsd.schema.json) and the README's reference; each is checked against it here."""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import jsonschema
import pytest

import omsd.config
from omsd import cli
from omsd.board import AxisWorld
from omsd.config import (
    BoardConfig,
    ConfigError,
    ControlConfig,
    LogConfig,
    MqttConfig,
    PtyEndpoint,
    TcpEndpoint,
    load_config,
    render,
    schema,
)

ROOT = Path(__file__).resolve().parent.parent
CONFIG_DIR = ROOT / "config"
SCHEMA_FILE = CONFIG_DIR / render.SCHEMA_FILE
EXAMPLES = sorted(CONFIG_DIR.glob("*.toml"))
REGENERATE = "regenerate it with: .venv/bin/omsd config schema > config/omsd.schema.json"


@pytest.fixture(autouse=True)
def _runtime_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    runtime = tmp_path / "run"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    return runtime


def published() -> dict[str, Any]:
    loaded = json.loads(SCHEMA_FILE.read_text())
    assert isinstance(loaded, dict)
    return loaded


# -- the published JSON Schema ------------------------------------------------------------------


def test_the_published_schema_is_the_schemas() -> None:
    assert SCHEMA_FILE.read_text() == render.json_schema_text(), REGENERATE


def test_the_published_schema_is_a_draft_07_schema() -> None:
    """Draft-07, the newest draft taplo validates with."""
    document = published()
    assert document["$schema"] == "http://json-schema.org/draft-07/schema#"
    jsonschema.Draft7Validator.check_schema(document)
    assert "$defs" not in json.dumps(document)  # draft-07 says "definitions"
    assert "null" not in json.dumps(document)  # TOML has no null


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_the_published_schema_validates_the_example(path: Path) -> None:
    validator = jsonschema.Draft7Validator(published())
    errors = [f"{list(e.absolute_path)}: {e.message}" for e in validator.iter_errors(_toml(path))]
    assert errors == []


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_each_example_names_the_schema_on_its_first_line(path: Path) -> None:
    """taplo's directive, relative to the file: editors check and complete the keys."""
    assert path.read_text().splitlines()[0] == f"#:schema ./{render.SCHEMA_FILE}"


def _toml(path: Path) -> dict[str, Any]:
    return tomllib.loads(path.read_text())


@pytest.mark.parametrize(
    ("board", "valid"),
    [
        ({"tcp": 7001}, True),
        ({"tcp": "[::1]:7001", "model": "pc48-8", "link": "RAW", "pty": True}, True),
        ({"tcp": {"address": 7001, "terminal": True}, "pty": [{"mode": "0660"}, "p"]}, True),
        ({"tcp": 7001, "model": "PCIX-400", "max_queries": False}, True),
        ({"tcp": 7001, "axes": {"X": {"home_switch": "Normally_Closed"}}}, True),
        ({"tcp": 7001, "colour": 1}, False),  # unknown key
        ({}, False),  # no endpoint
        ({"tcp": [], "pty": []}, False),
        ({"tcp": 7001, "model": "PC99"}, False),
        ({"tcp": 7001, "link": "raw", "eos": "0D"}, False),  # a driver setting on a raw link
        ({"tcp": 7001, "link": "Raw", "buffer": 512}, False),
        ({"tcp": 7001, "max_queries": True}, False),  # PC48-4E: no MAX-family dialect
        ({"tcp": 70000}, False),
        ({"tcp": 7001, "eos": "GG"}, False),
        ({"tcp": 7001, "pty": False}, False),
        ({"tcp": 7001, "axes": {"X": {"home": 5}}}, False),
        ({"tcp": 7001, "name": ".."}, False),
    ],
)
def test_the_published_schema_says_what_omsd_says(board: dict[str, Any], valid: bool) -> None:
    """Where the JSON Schema can say it, it agrees with omsd."""
    document = {"board": [board]}
    assert jsonschema.Draft7Validator(published()).is_valid(document) is valid
    if valid:
        schema.validate(document, ROOT)
    else:
        with pytest.raises(Exception, match="omsd"):  # pydantic's ValidationError
            schema.validate(document, ROOT)


# -- the reference --------------------------------------------------------------------------------


def test_the_reference_lists_every_key() -> None:
    keys = {row[0] for row in render.reference_rows()}
    for prefix, table in render.TABLES:
        for key in table.key_names():
            assert f"`{prefix}.{key}`" in keys
    assert "`board.axes.X.home_high`" in keys and "`board.buffer`" in keys


def test_the_command_prints_the_schema_and_the_reference(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert cli.main(["config", "schema"]) == 0
    assert capsys.readouterr().out == SCHEMA_FILE.read_text()
    assert cli.main(["config", "schema", "--format", "markdown"]) == 0
    out = capsys.readouterr().out
    assert out == render.reference()
    assert out.startswith("| key | takes | default | what it does |\n")


# -- the defaults, in one place -------------------------------------------------------------------


def test_the_axis_keys_are_axis_world_with_its_defaults() -> None:
    """``[board.axes.X]`` takes every field of omsd.board.AxisWorld, whose defaults it has."""
    world = AxisWorld()
    assert schema.AxisTable.key_names() == [f.name for f in dataclasses.fields(AxisWorld)]
    assert schema.AxisTable.model_validate({}).world() == world


def test_the_objects_defaults_are_the_schemas(tmp_path: Path, _runtime_dir: Path) -> None:
    """A board, the log, the control API and MQTT with nothing but what is required: what the
    schema makes of them is what the runtime objects default to."""
    path = tmp_path / "minimal.toml"
    path.write_text('[mqtt]\nhost = "h"\n[[board]]\ntcp = 7001\n')
    config = load_config(path)
    (board,) = config.boards
    assert board == BoardConfig(name="board1", tcp=(TcpEndpoint(port=7001),))
    assert config.log == LogConfig()
    assert config.control == ControlConfig()
    assert config.mqtt == MqttConfig(host="h")
    assert (config.state, config.state_group) == (None, None)


def test_the_command_line_help_quotes_the_schemas_defaults() -> None:
    """The single-board options fill keys of the one board: their help says the default of the
    key (the help is built without the schema, so that ``omsd models`` stays fast)."""
    parser = cli._parser()
    options = {flag: a for a in parser._actions for flag in a.option_strings}
    fields = schema.BoardTable.model_fields
    expected = {
        "--board": fields["model"].default,
        "--link": fields["link"].default,
        "--eos": f"{fields['eos'].default:02X}",
    }
    for flag in schema.option_paths().values():
        assert flag in options, flag
        if flag in expected:
            help_text = " ".join((options[flag].help or "").split())
            assert f"(default: {expected[flag]}" in help_text, (flag, help_text)
    assert set(schema.option_paths().values()) == {
        "--board",
        "--tcp",
        "--pty",
        "--serial",
        "--rfc2217",
        "--link",
        "--eos",
        "--log",
    }
    tcp_help = " ".join((options["--tcp"].help or "").split())
    assert f"(default: {omsd.config.DEFAULT_HOST}:{omsd.config.DEFAULT_TCP_PORT}," in tcp_help
    assert isinstance(options["--link"], argparse.Action)
    assert tuple(options["--link"].choices or ()) == omsd.config.LINKS


def test_the_single_board_form_is_a_board_of_the_schema(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``--board --tcp --pty --link --eos --log`` give what the same keys of a file give."""
    monkeypatch.chdir(tmp_path)
    from_options = omsd.config.from_options(
        "pc48-2", ["7001"], ["p"], "Driver", "0d", "t.jsonl", False
    )
    path = tmp_path / "same.toml"
    path.write_text(
        '[log]\nfile = "t.jsonl"\n[[board]]\nmodel = "pc48-2"\ntcp = ["7001"]\npty = ["p"]\n'
        'link = "Driver"\neos = "0d"\n'
    )
    from_file = load_config(path)
    assert from_options.boards == from_file.boards
    assert from_options.log == from_file.log
    assert from_options.boards[0].pty == (PtyEndpoint(tmp_path / "p"),)


# -- every key is worded ------------------------------------------------------------------------


BAD = "1979-05-27"  # a date: no key takes one


def _bad(prefix: str, key: str) -> str:
    """A file with a date at ``key`` of the table ``prefix``, everything else valid."""
    if prefix in ("log", "state", "control", "web"):
        return f"[{prefix}]\n{key} = {BAD}\n[[board]]\ntcp = 7001\n"
    if prefix == "mqtt":
        host = "" if key == "host" else 'host = "h"\n'
        return f"[mqtt]\n{host}{key} = {BAD}\n[[board]]\ntcp = 7001\n"
    if prefix == "board":
        tcp = "" if key in ("tcp", "pty") else "tcp = 7001\n"
        return f"[[board]]\n{tcp}{key} = {BAD}\n"
    if prefix == "board.tcp":
        address = "" if key == "address" else "address = 7001, "
        return f"[[board]]\ntcp = {{ {address}{key} = {BAD} }}\n"
    if prefix == "board.pty":
        return f"[[board]]\ntcp = 7001\npty = {{ {key} = {BAD} }}\n"
    if prefix == "board.serial_port":
        path = "" if key == "path" else 'path = "/dev/ttyS0", '
        return f"[[board]]\nserial_port = {{ {path}{key} = {BAD} }}\n"
    if prefix == "board.rfc2217":
        address = "" if key == "address" else "address = 7148, "
        return f"[[board]]\nrfc2217 = {{ {address}{key} = {BAD} }}\n"
    assert prefix == "board.axes.X", prefix
    return f"[[board]]\ntcp = 7001\n[board.axes.X]\n{key} = {BAD}\n"


KEYS = [(prefix, key) for prefix, table in render.TABLES for key in table.key_names()]


@pytest.mark.parametrize(("prefix", "key"), KEYS, ids=[f"{p}.{k}" for p, k in KEYS])
def test_every_key_has_omsds_words(tmp_path: Path, prefix: str, key: str) -> None:
    """A value of the wrong type at any key is one line in omsd's words, never pydantic's:
    the file, the line, the key path, what the key takes, and the value."""
    path = tmp_path / "omsd.toml"
    path.write_text(_bad(prefix, key))
    with pytest.raises(ConfigError) as info:
        load_config(path)
    message = str(info.value)
    assert "\n" not in message and "Input should" not in message, message
    shown = f"{prefix}.{key}".removeprefix("board.")
    assert re.match(rf"{re.escape(str(path))}:\d+: .*\b{re.escape(shown)}: expected ", message)
    if key in ("password", "token"):
        assert message.endswith("(the value given is not shown)"), message
    else:
        assert message.endswith(f", got {BAD}"), message


# -- what stays light ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv", [["models"], ["ctl", "--help"], ["commands", "PC48-4E", "--grep", "WY"], ["--help"]]
)
def test_the_schema_is_imported_only_where_a_configuration_is_read(argv: list[str]) -> None:
    """pydantic takes ~0.1 s to import: ``omsd models``, ``omsd ctl``... never pay for it."""
    code = (
        "import sys\nfrom omsd import cli\n"
        f"try:\n    cli.main({argv!r})\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'pydantic'"
        " or m == 'omsd.config.schema'), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.stderr.strip().splitlines()[-1] == "[]", done.stderr


def test_the_hand_written_type_checks_are_gone() -> None:
    """The validators of before the schema (issue 15: "config.py's hand-written type checks
    are gone")."""
    old = ("_string", "_integer", "_number", "_boolean", "_choice", "_hex_or_int", "_table")
    for module in (omsd.config, schema):
        assert not [name for name in old if hasattr(module, name)], module
