"""Reading a configuration: a TOML file (:func:`load`) or the command line's one-board form
(:func:`single_board`), validated by the schema (:mod:`omsd.config.schema`), every error one
line (:class:`omsd.config_errors.ConfigError`)."""

import os
import re
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pydantic import ConfigDict, TypeAdapter, ValidationError

from omsd.config import DEFAULT_HOST, DEFAULT_TCP_PORT, DaemonConfig
from omsd.config.schema import option_paths, validate
from omsd.config.values import FilePath
from omsd.config.wording import config_error
from omsd.config_errors import ConfigError, show

MAX_CONFIG = 4 * 1024 * 1024
"""Bytes of a configuration file read at most (a file of a thousand boards is some 100 KB);
one longer is refused. ``--config /dev/zero``, read whole, took the machine's memory."""


def load(path: str | os.PathLike[str]) -> DaemonConfig:
    """Read and validate a TOML configuration file."""
    source = os.fspath(path)
    text, document = read(path)
    base = Path(source).expanduser().absolute().parent
    try:
        return validate(document, base).config(source)
    except ValidationError as exc:
        raise config_error(exc, document, source).locate(text) from None


def read(path: str | os.PathLike[str]) -> tuple[str, dict[str, Any]]:
    """A file's text and its TOML document, or the one-line error."""
    source = os.fspath(path)
    try:
        with Path(path).open("rb") as file:  # a pipe too: --config <(...)
            data = file.read(MAX_CONFIG + 1)
    except OSError as exc:
        raise ConfigError(source, None, f"cannot read the file: {exc.strerror or exc}") from None
    if len(data) > MAX_CONFIG:
        detail = f"expected a configuration of at most {MAX_CONFIG} bytes, got more"
        raise ConfigError(source, None, detail)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        byte = data[exc.start]
        detail = f"expected UTF-8 text, got byte {byte:#04x} at offset {exc.start}"
        raise ConfigError(source, None, detail) from None
    text = text.removeprefix("\ufeff")  # a byte order mark from a Windows editor is harmless
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        m = re.fullmatch(r"(.*) \(at line (\d+), column (\d+)\)", message)
        if m is None:  # "(at end of document)": said as it is
            raise ConfigError(source, None, f"invalid TOML: {message}") from None
        line, column = int(m.group(2)), int(m.group(3))
        detail = f"invalid TOML: {m.group(1)}"
        raise ConfigError(source, None, detail, line=line, column=column) from None
    except RecursionError:  # tomllib parses nesting by recursion: thousands of levels
        detail = "invalid TOML: arrays or inline tables nested too deeply"
        raise ConfigError(source, None, detail) from None
    return text, document


def single_board(
    board: str | None,
    tcp: Sequence[str],
    pty: Sequence[str],
    link: str | None,
    eos: str | None,
    log: str | None,
    terminal: bool,
    source: str,
    *,
    serial: Sequence[str] = (),
    rfc2217: Sequence[str] = (),
) -> DaemonConfig:
    """The command line's one board: a document whose keys the options fill, validated as a
    file would be (paths relative to the working directory). Without --tcp, --pty, --serial and
    --rfc2217, the default endpoints (TCP 127.0.0.1:7048 and the default pty link)."""
    entry: dict[str, Any] = {}
    for key, value in (("model", board), ("link", link), ("eos", eos)):
        if value is not None:
            entry[key] = value
    entry["tcp"] = list(tcp)
    entry["pty"] = list(pty)
    if serial:
        entry["serial_port"] = list(serial)
    if rfc2217:
        entry["rfc2217"] = list(rfc2217)
    if not tcp and not pty and not serial and not rfc2217:
        entry["tcp"] = [f"{DEFAULT_HOST}:{DEFAULT_TCP_PORT}"]
        entry["pty"] = [True]
    if terminal:
        entry["pty"] = [
            {"terminal": True} if p is True else {"link": p, "terminal": True} for p in entry["pty"]
        ]
    document: dict[str, Any] = {"board": [entry]}
    if log is not None:
        document["log"] = {"file": log}
    try:
        return validate(document, Path.cwd()).config(source)
    except ValidationError as exc:
        raise config_error(exc, document, source, option_paths()) from None


_PATH: TypeAdapter[Path] = TypeAdapter(FilePath, config=ConfigDict(strict=True))


def option_path(option: str, text: str) -> Path:
    """A path given on the command line (``--state``, ``--control``), relative to the working
    directory."""
    try:
        return _PATH.validate_python(text, context={"base": Path.cwd()})
    except ValidationError as exc:
        raise config_error(exc, text, option, {(): option}) from None


def not_the_log(option: str, path: Path) -> ConfigError:
    detail = f"expected a file other than the traffic log, got {show(str(path), shorten=False)}"
    return ConfigError(option, None, detail)


__all__ = [
    "load",
    "not_the_log",
    "option_path",
    "read",
    "single_board",
]
