"""The serial and RFC 2217 endpoints in the configuration (issue 17): ``serial_port`` and
``rfc2217`` in a file, ``--serial`` and ``--rfc2217`` on the command line, their defaults (a
legacy application's port: 9600 8N1, no flow control), their errors in omsd's words, the
duplicate checks, and ``omsd config show`` giving back what it read."""

from __future__ import annotations

from pathlib import Path

import pytest

from omsd import cli
from omsd.config import (
    BoardConfig,
    ConfigError,
    Rfc2217Endpoint,
    SerialEndpoint,
    TcpEndpoint,
    from_options,
    load_config,
)
from omsd.config.render import show_text


@pytest.fixture(autouse=True)
def _runtime_dir(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    monkeypatch.delenv("RUNTIME_DIRECTORY", raising=False)
    runtime = tmp_path / "run"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    return runtime


def _load(tmp_path: Path, board: str) -> BoardConfig:
    path = tmp_path / "omsd.toml"
    path.write_text(f"[[board]]\n{board}\n")
    return load_config(path).boards[0]


def test_a_path_alone_is_9600_8n1_without_flow_control(tmp_path: Path) -> None:
    board = _load(tmp_path, 'serial_port = "/dev/ttyUSB0"')
    assert board.serial_port == (SerialEndpoint(Path("/dev/ttyUSB0")),)
    (port,) = board.serial_port
    assert (port.baud, port.bytesize, port.parity, port.stopbits, port.flow, port.pacing) == (
        9600, 8, "N", 1, "none", False,
    )  # fmt: skip
    assert board.tcp == () and board.pty == ()


def test_the_string_form_and_the_table_form(tmp_path: Path) -> None:
    board = _load(
        tmp_path,
        'serial_port = ["ttyS0,19200,7e2", { path = "ttyS1", parity = "odd", stopbits = 1.5,'
        ' flow = "XONXOFF", pacing = true }]\n'
        'rfc2217 = [7148, { address = "0.0.0.0:7149", pacing = true }]',
    )
    assert board.serial_port == (
        SerialEndpoint(tmp_path / "ttyS0", 19200, 7, "E", 2),
        SerialEndpoint(tmp_path / "ttyS1", 9600, 8, "O", 1.5, "xonxoff", True),
    )
    assert board.rfc2217 == (
        Rfc2217Endpoint("127.0.0.1", 7148),
        Rfc2217Endpoint("0.0.0.0", 7149, True),
    )


def test_the_command_line_options(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    config = from_options(
        None, [], [], None, None, None, serial=["tty,1200,8N2"], rfc2217=["[::1]:7148"]
    )
    (board,) = config.boards
    assert board.serial_port == (SerialEndpoint(tmp_path / "tty", 1200, 8, "N", 2),)
    # what the daemon announces is taken back, flow control included
    announced = str(SerialEndpoint(Path("/dev/ttyS0"), 19200, 7, "E", 1, "rtscts"))
    assert announced == "/dev/ttyS0,19200,7E1,rtscts"
    again = from_options(None, [], [], None, None, None, serial=[announced]).boards[0]
    assert again.serial_port == (SerialEndpoint(Path("/dev/ttyS0"), 19200, 7, "E", 1, "rtscts"),)
    assert board.rfc2217 == (Rfc2217Endpoint("::1", 7148),)
    assert board.tcp == () and board.pty == ()  # given endpoints replace the defaults
    both = from_options(None, ["7001"], [], None, None, None, rfc2217=["7148"]).boards[0]
    assert both.tcp == (TcpEndpoint(port=7001),) and both.rfc2217 == (Rfc2217Endpoint(port=7148),)


@pytest.mark.parametrize(
    ("serial", "rfc2217", "says"),
    [
        (["x,49"], [], '--serial: expected PATH[,BAUD[,8N1]] with BAUD 50..10000000, got "x,49"'),
        (["x,9600,8X1"], [], "--serial: expected PATH[,BAUD[,8N1]] with data bits 5..8, parity"),
        (["x,9600,8N1,hw"], [], "--serial: expected PATH[,BAUD[,8N1]] and rtscts or xonxoff"),
        (["x,9600,8N1,rtscts,1"], [], "--serial: expected PATH[,BAUD[,8N1]] (a device path"),
        ([" "], [], "--serial: expected PATH[,BAUD[,8N1]] (a device path, a baud rate, 8N1), got"),
        (["x", "x,19200"], [], "--serial: expected a device no other endpoint uses, got"),
        ([], ["7148", "127.0.0.1:7148"], "--rfc2217: expected an address no other endpoint uses"),
        ([], ["x:y"], '--rfc2217: expected [HOST:]PORT with PORT 0..65535, got "x:y"'),
    ],
)
def test_option_errors_are_one_line(
    serial: list[str], rfc2217: list[str], says: str, tmp_path: Path
) -> None:
    with pytest.raises(ConfigError) as info:
        from_options(None, [], [], None, None, None, serial=serial, rfc2217=rfc2217)
    message = str(info.value)
    assert message.startswith(says) and "\n" not in message, message


@pytest.mark.parametrize(
    ("board", "says"),
    [
        ("serial_port = { baud = 9600 }", "serial_port: expected a table with a path"),
        ('serial_port = { path = "t", baud = 12 }', "serial_port.baud: expected a baud rate"),
        ('serial_port = { path = "t", bytesize = 4 }', "serial_port.bytesize: expected data bits"),
        ('serial_port = { path = "t", parity = "X" }', 'serial_port.parity: expected "N", "E"'),
        ('serial_port = { path = "t", stopbits = true }', "serial_port.stopbits: expected stop"),
        ('serial_port = { path = "t", flow = "hw" }', 'serial_port.flow: expected "none" or'),
        ('serial_port = { path = "t", speed = 9600 }', "serial_port.speed: "),
        ("rfc2217 = { address = 7148, pacing = 1 }", "rfc2217.pacing: expected true or false"),
        ("rfc2217 = 7148\ntcp = 7148", "rfc2217: expected an address no other endpoint uses"),
    ],
)
def test_file_errors_are_one_line_at_the_key(tmp_path: Path, board: str, says: str) -> None:
    with pytest.raises(ConfigError) as info:
        _load(tmp_path, board)
    message = str(info.value)
    assert says in message and "\n" not in message, message
    assert message.startswith(f"{tmp_path / 'omsd.toml'}:2: "), message


def test_a_board_with_only_a_serial_port_or_rfc2217_has_an_endpoint(tmp_path: Path) -> None:
    assert _load(tmp_path, "rfc2217 = 0").rfc2217 == (Rfc2217Endpoint(),)
    with pytest.raises(ConfigError, match=r"at least one endpoint \(tcp, pty, serial_port or"):
        _load(tmp_path, "serial_port = []\nrfc2217 = []")


def test_the_same_device_on_two_boards_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(
        '[[board]]\nname = "a"\nserial_port = "/dev/ttyS0"\n'
        '[[board]]\nname = "b"\nserial_port = { path = "/dev/ttyS0", baud = 19200 }\n'
    )
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert 'expected a device no other endpoint uses, got "/dev/ttyS0"' in str(info.value)


def test_config_show_gives_back_what_it_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "omsd.toml"
    path.write_text(
        '[[board]]\nserial_port = [{ path = "/dev/ttyUSB0", parity = "even", stopbits = 1.5,'
        ' flow = "rtscts", pacing = true }, "/dev/ttyS0,1200"]\n'
        'rfc2217 = [7148, { address = "0.0.0.0:7149", pacing = true }]\n'
    )
    assert cli.main(["config", "show", str(path)]) == 0
    shown = capsys.readouterr().out
    assert (
        'serial_port = [{ path = "/dev/ttyUSB0", baud = 9600, bytesize = 8, parity = "E",'
        ' stopbits = 1.5, flow = "rtscts", pacing = true }, { path = "/dev/ttyS0", baud = 1200,'
        ' bytesize = 8, parity = "N", stopbits = 1, flow = "none", pacing = false }]'
    ) in shown
    assert 'rfc2217 = ["127.0.0.1:7148", { address = "0.0.0.0:7149", pacing = true }]' in shown
    again = tmp_path / "shown.toml"
    again.write_text(shown)
    (read,), (back,) = load_config(path).boards, load_config(again).boards
    assert (back.serial_port, back.rfc2217) == (read.serial_port, read.rfc2217)
    assert show_text(load_config(again)).splitlines()[1:] == shown.splitlines()[1:]
