"""The emulated boards' flash memory, kept in one JSON state file across daemon restarts.

A PCIx keeps two things in flash (PCIx manual §5.4.2 and §5.4.7):

* the user's power-up defaults: "The AP command stores the current parameter set as the power-up
  default set of values. This is done by writing the current parameter set to flash memory."
  ADH and ADL write it too: "This command will also archive all other parameter values as power
  up defaults."
* the permanent macros: "Macros are storage areas in the PCIX of which 5 are “temporary”; i.e.
  not saved at power-off, and 20 are “permanent”; i.e. stored in non-volatile flash RAM." PT
  fills them: "The non-volatile macro number [...] must be between 5 and 24."

This module stores that flash for every board of a daemon in one file, a section per board
name. It knows nothing of the parameters themselves: ``BoardFlash.defaults`` is whatever the
personality hands it (a JSON object of JSON values, per axis and board-wide), or ``None`` when
AP was never used; ``BoardFlash.macros`` maps the slots 5..24 to their text (at most 250
characters, "Be careful not to exceed 250 ASCII characters").

How a personality is meant to use it (the daemon makes one :class:`StateFile` from
``DaemonConfig.state``, calls :meth:`StateFile.load` once at start and logs its message)::

    power-up / reset   flash = state.board(name); parameters = flash.defaults or factory
    RD                 parameters = flash.defaults or factory ("restores the motion
                       parameters using power-up defaults")
    RF                 parameters = factory; flash unchanged ("This process does not alter
                       the parameters stored in flash via the AP command")
    AP, ADH, ADL       state.save_board(name, BoardFlash(current parameters, permanent macros))
    PT t,p             state.save_board(name, BoardFlash(saved defaults, macros | {p: text}))
    MX / PM 5..24      read from the board's copy of flash.macros

With no state file configured, the personality keeps the same BoardFlash in memory only: AP
and RD work within one run of the daemon, and a restart is a board fresh from the factory.

The file (``format`` is the version of this layout; a file of another version is not read)::

    {
      "format": 1,
      "boards": {
        "xy-stage": {
          "defaults": {"axes": {"X": {"VL": 50000}}, ...},   (or null: never archived)
          "macros": {"5": "VL1000;MR100;GO;", ...}
        }
      }
    }

Choices where the issue is silent:

* Reading never raises. A missing file is the normal first start (``ok`` true, a message
  saying the first save creates it); an unreadable, corrupt or newer-format file gives every
  board the factory defaults (``ok`` false, one line saying what was wrong). Such a file is
  not overwritten blindly: the first save keeps it as ``<name>.corrupt`` beside the new one.
* Values are checked loosely. A board section of the wrong shape (``defaults`` not an object,
  a macro slot outside 5..24, a macro that is not a string of at most 250 characters) is
  ignored with a message naming the board; the other boards are used. What a save does not
  replace (the other boards' sections, ignored ones included, and unknown top-level keys) is
  written back as it was read.
* Saving is atomic and durable: a temporary file in the same directory is written and fsynced,
  moved over the old file with ``os.replace``, and the directory fsynced. A failure at any
  step leaves the old file intact and no temporary file behind, and raises
  :class:`StateFileError` (one line); the saved state seen by :meth:`StateFile.board` is then
  unchanged. Missing parent directories are created. A new file gets mode 0600, or 0640 and
  the group given (``[state] group``); an existing one keeps its mode (and is given the group).
* A save cut short by a crash (SIGKILL, power) between creating the temporary file and the
  rename leaves it behind, ``.<name>.XXXXXXXX.tmp``: :meth:`StateFile.load` removes such files
  (regular files of this user, named exactly as :func:`tempfile.mkstemp` names them for this
  file) and says how many in its message. Nothing else in the directory is touched.
* One daemon owns the file: nothing locks it against a second process, and a second daemon
  writing the same file would overwrite the first one's boards with what it read at its start.
  Give each daemon its own file. Within a daemon, saves may run on worker threads
  (``asyncio.to_thread``, since fsync blocks): they are serialised by a lock.
* :meth:`StateFile.board` and :meth:`StateFile.save_board` before :meth:`StateFile.load` are
  a ``RuntimeError``: a save that had not read the file would drop the other boards.
* The defaults are the personality's to check: a board whose model changed in the
  configuration finds the old model's defaults under its name. Keep the model in them (say
  ``defaults["model"]``) and fall back to the factory values, with a log line, when it differs.
* NaN and infinities are not JSON: a file holding them is corrupt, and saving them is a
  ``ValueError``, as is a macro slot or text out of range.
"""

from __future__ import annotations

import contextlib
import copy
import json
import os
import re
import stat
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

from omsd.files import file_mode, group_id

FORMAT = 1
PERMANENT_MACROS = range(5, 25)  # PT: "must be between 5 and 24"
MACRO_LENGTH = 250  # MD: "Be careful not to exceed 250 ASCII characters"
NEW_FILE_MODE = 0o600  # 0o640 with a group (omsd.files.file_mode)
CORRUPT_SUFFIX = ".corrupt"


@dataclass
class BoardFlash:
    """The saved part of one board: power-up defaults (``None``: never archived, the factory
    values apply) and the permanent macros, slot (5..24) -> text."""

    defaults: dict[str, Any] | None = None
    macros: dict[int, str] = field(default_factory=dict)


@dataclass(frozen=True)
class LoadResult:
    """What :meth:`StateFile.load` found. ``ok``: the file was absent or wholly usable;
    ``message``: one line for the log, ``None`` when there is nothing to say."""

    ok: bool
    message: str | None = None


class StateFileError(Exception):
    """A save that did not happen. ``str()`` is one line naming the file."""


def _one_line(text: str) -> str:
    return text.replace("\r", "\\r").replace("\n", "\\n")


def _kind(value: object) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int | float):
        return "a number"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "an array"
    return "an object"


def _reject_constant(name: str) -> NoReturn:
    raise ValueError(f"{name} is not a JSON value")


class _Invalid(Exception):
    """A part of the file that cannot be used; the text says why."""


def _macros(value: object) -> dict[int, str]:
    if not isinstance(value, dict):
        raise _Invalid(f"macros: expected an object, got {_kind(value)}")
    macros: dict[int, str] = {}
    for key, text in value.items():
        if not (key.isascii() and key.isdigit()) or int(key) not in PERMANENT_MACROS:
            raise _Invalid(f"macros: expected slots 5..24, got {json.dumps(key)}")
        if not isinstance(text, str) or len(text) > MACRO_LENGTH:
            got = f"{len(text)} characters" if isinstance(text, str) else _kind(text)
            raise _Invalid(f"macros.{key}: expected a string of at most 250 characters, got {got}")
        macros[int(key)] = text
    return macros


def _board_flash(value: object) -> BoardFlash:
    if not isinstance(value, dict):
        raise _Invalid(f"expected an object, got {_kind(value)}")
    defaults = value.get("defaults")
    if defaults is not None and not isinstance(defaults, dict):
        raise _Invalid(f"defaults: expected an object or null, got {_kind(defaults)}")
    return BoardFlash(defaults, _macros(value.get("macros", {})))


def _encode(flash: BoardFlash) -> dict[str, Any]:
    """The JSON section of one board, after checking what the file could not hold."""
    if flash.defaults is not None and not isinstance(flash.defaults, dict):
        raise ValueError(f"defaults: expected a dict or None, got {type(flash.defaults).__name__}")
    macros: dict[str, str] = {}
    for slot, text in sorted(flash.macros.items()):
        if isinstance(slot, bool) or not isinstance(slot, int) or slot not in PERMANENT_MACROS:
            raise ValueError(f"macro slot {slot!r}: expected 5..24 (the permanent macros)")
        if not isinstance(text, str) or len(text) > MACRO_LENGTH:
            raise ValueError(f"macro {slot}: expected a string of at most 250 characters")
        macros[str(slot)] = text
    section = {"defaults": copy.deepcopy(flash.defaults), "macros": macros}
    json.dumps(section, allow_nan=False)  # TypeError/ValueError now, not halfway into a write
    return section


class StateFile:
    """The flash memory of every board of one daemon, in the file at ``path``."""

    def __init__(self, path: Path, group: str | None = None) -> None:
        self.path = Path(path)
        self.group = group  # a group to give the file to (then a new file is 0640)
        self._document: dict[str, Any] = {"format": FORMAT, "boards": {}}
        self._flash: dict[str, BoardFlash] = {}
        self._loaded = False
        self._set_aside = False  # the file on disk is unusable: keep it at the next save
        self._lock = threading.Lock()

    # -- reading --------------------------------------------------------------------------------

    def load(self) -> LoadResult:
        """Read the file. Never raises: whatever is wrong gives the factory defaults (an empty
        state) for the boards it concerns, and a one-line message."""
        with self._lock:
            self._loaded = True
            self._document = {"format": FORMAT, "boards": {}}
            self._flash = {}
            self._set_aside = False
            removed = self._remove_leftovers()
            result = self._read()
            if not removed:
                return result
            note = f"removed {removed} temporary file{'s' * (removed > 1)} left by a save cut short"
            if result.message is None:
                return LoadResult(result.ok, self._say(note))
            return LoadResult(result.ok, f"{result.message}; {note}")

    def _remove_leftovers(self) -> int:
        """Remove the temporary files of saves that a crash cut short (see the module text);
        how many were removed."""
        pattern = re.compile(re.escape(f".{self.path.name}.") + r"[a-z0-9_]{8}\.tmp")
        try:
            names = os.listdir(self.path.parent)
        except OSError:
            return 0
        removed = 0
        for name in names:
            if not pattern.fullmatch(name):
                continue
            leftover = self.path.parent / name
            try:
                st = os.lstat(leftover)
                if stat.S_ISREG(st.st_mode) and st.st_uid == os.geteuid():
                    os.unlink(leftover)
                    removed += 1
            except OSError:
                continue
        return removed

    def _read(self) -> LoadResult:
        """Read and check the file (for :meth:`load`, under its lock)."""
        try:
            data = self.path.read_bytes()
        except FileNotFoundError:
            return LoadResult(
                True, self._say("not found; using factory defaults (the first save creates it)")
            )
        except OSError as exc:
            self._set_aside = self.path.is_file()
            reason = exc.strerror or str(exc)
            return LoadResult(False, self._say(f"cannot read: {reason}; using factory defaults"))
        try:
            document = self._parse(data)
        except _Invalid as exc:
            self._set_aside = True
            kept = self.path.with_name(self.path.name + CORRUPT_SUFFIX)
            return LoadResult(
                False,
                self._say(f"{exc}; using factory defaults (the next save keeps it as {kept.name})"),
            )
        self._document = document
        bad: list[str] = []
        for name, section in document["boards"].items():
            try:
                self._flash[name] = _board_flash(section)
            except _Invalid as exc:
                bad.append(f"board {json.dumps(name)}: {exc}")
        if bad:
            which = "that board uses" if len(bad) == 1 else "those boards use"
            return LoadResult(False, self._say(f"{'; '.join(bad)}; {which} factory defaults"))
        return LoadResult(True, None)

    def _say(self, text: str) -> str:
        return _one_line(f"state file {self.path}: {text}")

    @staticmethod
    def _parse(data: bytes) -> dict[str, Any]:
        if not data.strip():
            raise _Invalid("empty")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise _Invalid(
                f"not UTF-8 text: byte {data[exc.start]:#04x} at offset {exc.start}"
            ) from None
        try:
            document = json.loads(text, parse_constant=_reject_constant)
        except json.JSONDecodeError as exc:
            raise _Invalid(
                f"not valid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}"
            ) from None
        except (ValueError, RecursionError) as exc:
            raise _Invalid(f"not valid JSON: {exc}") from None
        if not isinstance(document, dict):
            raise _Invalid(f'expected an object with "format" and "boards", got {_kind(document)}')
        version = document.get("format")
        if type(version) is not int or version != FORMAT:
            got = "none" if "format" not in document else json.dumps(version)
            raise _Invalid(f"format {got} is not one this omsd reads (it reads format {FORMAT})")
        if not isinstance(document.get("boards", {}), dict):
            raise _Invalid(f'"boards": expected an object, got {_kind(document["boards"])}')
        document.setdefault("boards", {})
        return document

    def board(self, name: str) -> BoardFlash:
        """The saved flash of one board: empty (no defaults, no macros) if none. A copy: the
        caller may change it freely."""
        with self._lock:
            if not self._loaded:
                raise RuntimeError("StateFile.board() before load()")
            return copy.deepcopy(self._flash.get(name, BoardFlash()))

    # -- writing --------------------------------------------------------------------------------

    def save_board(self, name: str, flash: BoardFlash) -> None:
        """Replace one board's section, atomically, keeping every other section as read.
        ``ValueError``/``TypeError`` for what the file cannot hold (nothing is written);
        :class:`StateFileError` when the file cannot be written (the old one is intact)."""
        if not isinstance(name, str) or not name:
            raise ValueError(f"board name: expected a non-empty string, got {name!r}")
        section = _encode(flash)
        with self._lock:
            if not self._loaded:
                raise RuntimeError("StateFile.save_board() before load()")
            boards = {**self._document["boards"], name: section}
            document = {**self._document, "format": FORMAT, "boards": boards}
            data = json.dumps(document, indent=2, sort_keys=True, allow_nan=False) + "\n"
            try:
                self._write(data.encode("utf-8"))
            except OSError as exc:
                reason = exc.strerror or str(exc)
                where = f" ({exc.filename})" if exc.filename else ""
                raise StateFileError(
                    self._say(f"cannot save board {json.dumps(name)}: {reason}{where}")
                ) from exc
            self._document = document
            self._flash[name] = _board_flash(section)
            self._set_aside = False

    def _write(self, data: bytes) -> None:
        directory = self.path.parent
        directory.mkdir(parents=True, exist_ok=True)
        try:
            mode = stat.S_IMODE(os.stat(self.path).st_mode)
        except OSError:
            mode = file_mode(self.group)
        fd, temporary = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=directory)
        try:
            try:
                if self.group is not None:
                    os.fchown(fd, -1, group_id(self.group))
                os.fchmod(fd, mode)
                view = memoryview(data)
                while view:
                    view = view[os.write(fd, view) :]
                os.fsync(fd)
            finally:
                os.close(fd)
            if self._set_aside and self.path.is_file():
                self._keep_aside()
            os.replace(temporary, self.path)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(temporary)
            raise
        _fsync_directory(directory)

    def _keep_aside(self) -> None:
        """Keep the unusable file as ``<name>.corrupt`` (replacing an older one). A second
        link, so that the state file stays in place until the new one replaces it; a rename
        where the filesystem has no hard links."""
        kept = self.path.with_name(self.path.name + CORRUPT_SUFFIX)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(kept)
        try:
            os.link(self.path, kept)
        except OSError:
            os.replace(self.path, kept)


def _fsync_directory(directory: Path) -> None:
    """Make the rename itself durable (a crash after ``os.replace`` may otherwise lose it).
    The file is already in place: a directory that cannot be fsynced (some filesystems refuse)
    only weakens that guarantee, so it is not an error."""
    try:
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


__all__ = [
    "FORMAT",
    "MACRO_LENGTH",
    "PERMANENT_MACROS",
    "BoardFlash",
    "LoadResult",
    "StateFile",
    "StateFileError",
]
