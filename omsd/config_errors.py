"""Configuration errors as one line that says where: the file, the line, the key path.

This module knows nothing of omsd's keys: it formats a key path (a tuple of keys and list
indices, the shape of a pydantic error's ``loc``) and finds the line of a key in a TOML text;
:mod:`omsd.config.wording` turns the schema's errors into :class:`ConfigError` through it.

The line of an error reads::

    omsd.toml:14: [board "xy"] axes.X.positive_limit: expected an integer, got "5k"
    omsd.toml:3:9: invalid TOML: Invalid value
    omsd.toml: board: expected at least one [[board]] table, got none
    --tcp: expected [HOST:]PORT with PORT 0..65535, got "abc"

* ``<file>:<line>:`` as compilers write it (editors and terminals jump to it); the line is left
  out when it cannot be found, never guessed.
* A key under ``[[board]]`` is named by the board (``[board "xy"]``), not by its index: by its
  ``name`` as written (even one that is not valid), and a board without ``name`` by the name
  omsd gives it, ``board1``, ``board2``... in file order (the name it is served and controlled
  under), saying so: ``[board "board2" (unnamed)]``.
* A value is shown as TOML writes it (``"5k"``, ``true``, ``[1, 2]``), shortened past 60
  characters, so that what the message quotes is what the file says.

:func:`key_lines` is a small scanner, not a TOML parser: it runs on text that ``tomllib``
has already accepted and records the line where each key (``a.b = 1``, ``a = { b = 1 }``, an
element of ``a = [..]``) and each table header (``[a.b]``, ``[[a]]``) is. :func:`locate` takes the
key itself, else the nearest enclosing table or key written in the file (a key that is missing,
``host`` of ``[mqtt]``, is reported at its table), else nothing.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping

Key = str | int
"""One step of a key path: a table key, or an index into an array."""

KeyPath = tuple[Key, ...]

_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
MAX_SHOWN = 60  # characters of a value shown in a message
MAX_ITEMS = 4  # elements of an array or table shown


class ConfigError(Exception):
    """A configuration that cannot be served. ``str()`` is one line: where, then what.

    ``source`` is the file (or the command-line option), ``key`` the key path as shown
    (``[board "xy"] axes.X.home_low``) or ``None``, ``detail`` what is wrong, ``line`` and
    ``column`` the place in the file when known, ``also`` another key the error involves (a
    duplicate), shown as ``(also KEY, line N)``; ``path`` is the key path as data."""

    def __init__(
        self,
        source: str,
        key: str | None,
        detail: str,
        *,
        path: KeyPath = (),
        line: int | None = None,
        column: int | None = None,
        also: str | None = None,
        also_path: KeyPath | None = None,
        also_line: int | None = None,
    ) -> None:
        super().__init__(source, key, detail)
        self.source = source
        self.key = key
        self.detail = detail
        self.path = path
        self.line = line
        self.column = column
        self.also = also
        self.also_path = also_path
        self.also_line = also_line

    def locate(self, text: str) -> ConfigError:
        """Fill in the lines from the file's text (``self``, for ``raise exc.locate(text)``)."""
        lines = lines_of(text)
        if self.line is None and self.path:
            self.line = locate(self.path, lines)
        if self.also_line is None and self.also_path:
            self.also_line = locate(self.also_path, lines)
        return self

    def __str__(self) -> str:
        where = self.source
        if self.line is not None:
            where += f":{self.line}"
            if self.column is not None:
                where += f":{self.column}"
        parts = [where] if self.key is None else [where, self.key]
        text = ": ".join([*parts, self.detail])
        if self.also is not None:
            line = "" if self.also_line is None else f", line {self.also_line}"
            text += f" (also {self.also}{line})"
        return one_line(text)


def one_line(text: str) -> str:
    """``text`` with its line breaks spelled out, so that it stays one line."""
    out = []
    for ch in text:
        if ch == "\n":
            out.append("\\n")
        elif ch == "\r":
            out.append("\\r")
        elif ch.isprintable() or ch == "\t":
            out.append(ch)
        else:
            out.append(f"\\u{ord(ch):04x}")
    return "".join(out)


# -- showing keys and values --------------------------------------------------------------------


def key_name(key: str) -> str:
    """A key as TOML writes it: bare if it can be, else quoted."""
    return key if _BARE_KEY.fullmatch(key) else show(key)


def key_text(path: KeyPath, tables: Mapping[KeyPath, str] | None = None) -> str | None:
    """``path`` as a message shows it. ``tables`` names some tables by a label of their own
    (``("board", 0)`` → ``[board "xy"]``): the longest labelled prefix of the path is replaced
    by its label. ``None`` for the empty path (the document itself)."""
    labels = tables or {}
    head = ""
    rest = path
    for n in range(len(path), 0, -1):
        label = labels.get(path[:n])
        if label is not None:
            head, rest = label, path[n:]
            break
    text = ""
    for step in rest:
        if isinstance(step, int):
            text += f"[{step}]"
        else:
            text += f".{key_name(step)}" if text else key_name(step)
    if head and text:
        return f"{head} {text}"
    return head or text or None


def board_label(name: object, index: int) -> str:
    """How a ``[[board]]`` table is named in a message: by its ``name`` as written
    (``[board "xy"]``), or, without one, by the name omsd gives it, its place among the boards,
    and says so (``[board "board2" (unnamed)]``)."""
    if name is None:
        return f"[board {show(f'board{index + 1}')} (unnamed)]"
    return f"[board {show(name)}]"


def show(value: object, shorten: bool = True) -> str:
    """``value`` as TOML writes it, shortened (unless ``shorten`` is false: a path the message
    is about): ``"5k"``, ``true``, ``-inf``, ``[1, 2, ...]``."""
    if isinstance(value, str):
        if shorten and len(value) > MAX_SHOWN:
            half = (MAX_SHOWN - 3) // 2
            value = value[:half] + "..." + value[-half:]
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, int):
        text = str(value)
        return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN] + "..."
    if isinstance(value, list | tuple):
        items = [show(v) for v in value[:MAX_ITEMS]]
        if len(value) > MAX_ITEMS:
            items.append("...")
        return "[" + ", ".join(items) + "]"
    if isinstance(value, dict):
        pairs = [f"{key_name(str(k))} = {show(v)}" for k, v in list(value.items())[:MAX_ITEMS]]
        if len(value) > MAX_ITEMS:
            pairs.append("...")
        return "{" + ", ".join(pairs) + "}" if pairs else "{}"
    import datetime  # here: omsd.config imports this module, and a daemon needs no datetime

    if isinstance(value, datetime.date | datetime.time):
        return value.isoformat()
    return repr(value)


# -- finding the line ---------------------------------------------------------------------------


def locate(path: KeyPath, lines: Mapping[KeyPath, int]) -> int | None:
    """The line of ``path`` in a text scanned by :func:`key_lines`: the key's own line, else
    that of the nearest enclosing key or table that the text writes, else ``None``."""
    for n in range(len(path), 0, -1):
        line = lines.get(path[:n])
        if line is not None:
            return line
    return None


def key_lines(text: str) -> dict[KeyPath, int]:
    """The line (1-based) of every key and table header in ``text``, a valid TOML document."""
    return _Scanner(text).scan()


class _Scanner:
    def __init__(self, text: str) -> None:
        self.text = text
        self.i = 0
        self.line = 1
        self.found: dict[KeyPath, int] = {}
        self.arrays: dict[KeyPath, int] = {}  # array of tables (by its path as written) -> index

    def scan(self) -> dict[KeyPath, int]:
        table: KeyPath = ()
        while True:
            self._blank(newlines=True)
            if self.i >= len(self.text):
                return self.found
            if self.text.startswith("[[", self.i):
                self.i += 2
                line, keys = self.line, self._key()
                self._expect("]]")
                index = self.arrays.get(keys, -1) + 1
                self.arrays[keys] = index
                table = (*self._resolve(keys), index)
                self._note(table[:-1], line)
                self._note(table, line)
            elif self.text.startswith("[", self.i):
                self.i += 1
                line, keys = self.line, self._key()
                self._expect("]")
                table = self._resolve(keys)
                self._note(table, line)
            else:
                self._pair(table)

    def _resolve(self, keys: KeyPath) -> KeyPath:
        """A header's keys with the current index after every array of tables they pass."""
        path: KeyPath = ()
        for n, key in enumerate(keys, 1):
            path = (*path, key)
            if keys[:n] in self.arrays and n < len(keys):
                path = (*path, self.arrays[keys[:n]])
        return path

    def _note(self, path: KeyPath, line: int) -> None:
        self.found.setdefault(path, line)

    def _pair(self, table: KeyPath) -> None:
        line, keys = self.line, self._key()
        for n in range(1, len(keys) + 1):
            self._note((*table, *keys[:n]), line)
        self._blank()
        self._expect("=")
        self._value((*table, *keys))

    def _value(self, path: KeyPath) -> None:
        self._blank()
        ch = self.text[self.i : self.i + 1]
        if ch == "{":
            self.i += 1
            while True:
                self._blank()
                if self.text.startswith("}", self.i):
                    self.i += 1
                    return
                self._pair(path)
                self._blank()
                if self.text.startswith(",", self.i):
                    self.i += 1
        elif ch == "[":
            self.i += 1
            index = 0
            while True:
                self._blank(newlines=True)
                if self.text.startswith("]", self.i):
                    self.i += 1
                    return
                self._note((*path, index), self.line)
                self._value((*path, index))
                index += 1
                self._blank(newlines=True)
                if self.text.startswith(",", self.i):
                    self.i += 1
        elif ch in ('"', "'"):
            self._string()
        else:  # a number, a boolean, a date and time (which may hold a space)
            while self.i < len(self.text) and self.text[self.i] not in ",]}#\n":
                self.i += 1

    def _key(self) -> KeyPath:
        keys: list[str] = []
        while True:
            self._blank()
            if self.text[self.i : self.i + 1] in ('"', "'"):
                keys.append(self._string())
            else:
                m = _BARE_KEY.match(self.text, self.i)
                if m is None:
                    raise ValueError(f"no key at line {self.line}")
                keys.append(m.group())
                self.i = m.end()
            self._blank()
            if not self.text.startswith(".", self.i):
                return tuple(keys)
            self.i += 1

    def _string(self) -> str:
        text, start = self.text, self.i
        quote = text[start]
        if text.startswith(quote * 3, start):
            end = start + 3
            while True:
                end = text.index(quote * 3, end)
                if quote == "'" or not _escaped(text, end):
                    break
                end += 1
            while text.startswith(quote, end + 3):  # """a"""" ends with a quote in the string
                end += 1
            self.line += text.count("\n", start, end + 3)
            self.i = end + 3
            return text[start + 3 : end]
        end = start + 1
        while True:
            end = text.index(quote, end)
            if quote == "'" or not _escaped(text, end):
                break
            end += 1
        self.i = end + 1
        raw = text[start + 1 : end]
        if quote == "'":
            return raw
        try:
            value = json.loads(f'"{raw}"')
        except ValueError:  # a TOML escape JSON does not have (\U0001F600, \e)
            return raw
        return value if isinstance(value, str) else raw

    def _blank(self, newlines: bool = False) -> None:
        """Skip spaces and comments, and line breaks if ``newlines``."""
        text = self.text
        while self.i < len(text):
            ch = text[self.i]
            if ch in " \t":
                self.i += 1
            elif ch == "#":
                end = text.find("\n", self.i)
                self.i = len(text) if end < 0 else end
            elif newlines and ch in "\r\n":
                self.line += ch == "\n"
                self.i += 1
            else:
                return

    def _expect(self, token: str) -> None:
        self._blank()
        if not self.text.startswith(token, self.i):
            raise ValueError(f"expected {token!r} at line {self.line}")
        self.i += len(token)


def _escaped(text: str, at: int) -> bool:
    """Whether the character at ``at`` follows an odd number of backslashes."""
    n = 0
    while at - n - 1 >= 0 and text[at - n - 1] == "\\":
        n += 1
    return n % 2 == 1


def lines_of(text: str) -> dict[KeyPath, int]:
    """:func:`key_lines`, or nothing when the scanner cannot read the text (it never guesses)."""
    try:
        return key_lines(text)
    except (ValueError, IndexError):
        return {}


__all__ = [
    "ConfigError",
    "Key",
    "KeyPath",
    "board_label",
    "key_lines",
    "key_name",
    "key_text",
    "lines_of",
    "locate",
    "one_line",
    "show",
]
