"""The state file: the boards' flash (AP defaults, permanent macros 5..24) across restarts,
read without ever raising and written atomically."""

from __future__ import annotations

import errno
import grp
import json
import os
import stat
import tempfile
import threading
from pathlib import Path
from typing import Any

import pytest

from omsd.statefile import BoardFlash, LoadResult, StateFile, StateFileError

DEFAULTS: dict[str, Any] = {
    "axes": {"X": {"VL": 50000, "AC": 200000, "KP": 10.5, "LH": True}, "Y": {"VL": 1}},
    "board": {"UU": None, "note": "opaque to the state file"},
}
MACROS = {5: "VL1000;MR100;GO;", 24: "AX;PA1;\n"}


def loaded(path: Path) -> tuple[StateFile, LoadResult]:
    state = StateFile(path)
    return state, state.load()


def saved_file(path: Path) -> StateFile:
    """A file holding board ``a`` (defaults and macros), loaded afresh."""
    state, _ = loaded(path)
    state.save_board("a", BoardFlash(DEFAULTS, MACROS))
    fresh, result = loaded(path)
    assert result == LoadResult(True, None)
    return fresh


def only_the_state_file(directory: Path, name: str = "omsd.state") -> None:
    assert sorted(p.name for p in directory.iterdir()) == [name]


def one_line(result: LoadResult, path: Path) -> str:
    assert result.message is not None
    assert "\n" not in result.message and "\r" not in result.message
    assert result.message.startswith(f"state file {path}: ")
    return result.message.removeprefix(f"state file {path}: ")


# -- round trips --------------------------------------------------------------------------------


def test_round_trip_through_a_restart(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    state = saved_file(path)
    assert state.board("a") == BoardFlash(DEFAULTS, MACROS)
    document = json.loads(path.read_text())
    assert document["format"] == 1
    assert document["boards"]["a"]["macros"] == {"5": "VL1000;MR100;GO;", "24": "AX;PA1;\n"}
    only_the_state_file(tmp_path)


def test_a_board_never_saved_is_empty(tmp_path: Path) -> None:
    state = saved_file(tmp_path / "omsd.state")
    assert state.board("b") == BoardFlash(None, {})


def test_macros_without_defaults_and_defaults_without_macros(tmp_path: Path) -> None:
    """PT before any AP keeps defaults None (the factory values still apply at power-up)."""
    path = tmp_path / "omsd.state"
    state, _ = loaded(path)
    state.save_board("pt-only", BoardFlash(None, {19: "MR5;GO;"}))
    state.save_board("ap-only", BoardFlash({"axes": {}}, {}))
    fresh, _ = loaded(path)
    assert fresh.board("pt-only") == BoardFlash(None, {19: "MR5;GO;"})
    assert fresh.board("ap-only") == BoardFlash({"axes": {}}, {})


def test_every_permanent_slot_and_the_longest_macro(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    macros = {slot: chr(ord("A") + slot) * 250 for slot in range(5, 25)}
    macros[7] = "VL\x01\x7f;\r\n;é"  # whatever bytes MD stored come back verbatim
    state, _ = loaded(path)
    state.save_board("a", BoardFlash(None, macros))
    assert loaded(path)[0].board("a").macros == macros


def test_two_boards_saved_in_turn_keep_each_other(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    state, _ = loaded(path)
    state.save_board("a", BoardFlash({"v": 1}, {5: "A"}))
    state.save_board("b", BoardFlash({"v": 2}, {6: "B"}))
    state.save_board("a", BoardFlash({"v": 3}, {}))
    fresh, _ = loaded(path)
    assert fresh.board("a") == BoardFlash({"v": 3}, {})
    assert fresh.board("b") == BoardFlash({"v": 2}, {6: "B"})
    # and a second daemon run keeps the first run's other board
    fresh.save_board("c", BoardFlash({"v": 4}, {}))
    assert set(json.loads(path.read_text())["boards"]) == {"a", "b", "c"}


def test_board_returns_a_copy_and_save_takes_one(tmp_path: Path) -> None:
    state, _ = loaded(tmp_path / "omsd.state")
    defaults: dict[str, Any] = {"axes": {"X": {"VL": 1}}}
    flash = BoardFlash(defaults, {5: "A"})
    state.save_board("a", flash)
    defaults["axes"]["X"]["VL"] = 2
    flash.macros[6] = "B"
    got = state.board("a")
    assert got == BoardFlash({"axes": {"X": {"VL": 1}}}, {5: "A"})
    assert got.defaults is not None
    got.defaults["axes"]["X"]["VL"] = 3
    got.macros.clear()
    assert state.board("a") == BoardFlash({"axes": {"X": {"VL": 1}}}, {5: "A"})


def test_missing_parent_directories_are_created(tmp_path: Path) -> None:
    path = tmp_path / "var" / "lib" / "omsd" / "omsd.state"
    state, result = loaded(path)
    assert result.ok
    assert not path.parent.exists()  # reading creates nothing
    state.save_board("a", BoardFlash({"v": 1}, {}))
    assert loaded(path)[0].board("a") == BoardFlash({"v": 1}, {})


def test_a_new_file_is_0600_and_an_existing_one_keeps_its_mode(tmp_path: Path) -> None:
    """Issue 13: the state file was created world-readable (0644); it is private now, whatever
    the umask. A mode the operator gave it stays."""
    path = tmp_path / "omsd.state"
    state, _ = loaded(path)
    old = os.umask(0o022)
    try:
        state.save_board("a", BoardFlash())
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    path.chmod(0o644)
    state.save_board("a", BoardFlash({"v": 1}, {}))
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


def test_saves_from_several_threads_lose_no_board(tmp_path: Path) -> None:
    """The daemon may save from worker threads (fsync blocks); each save reads the others."""
    path = tmp_path / "omsd.state"
    state, _ = loaded(path)

    def save(name: str) -> None:
        for i in range(5):
            state.save_board(name, BoardFlash({"i": i}, {}))

    threads = [threading.Thread(target=save, args=(f"b{n}",)) for n in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    fresh, _ = loaded(path)
    for n in range(6):
        assert fresh.board(f"b{n}") == BoardFlash({"i": 4}, {})
    only_the_state_file(tmp_path)


# -- atomicity ----------------------------------------------------------------------------------


def _fail_midway(real: Any) -> Any:
    """os.write that writes a few bytes of the temporary file, then finds the disk full."""

    def write(fd: int, data: Any) -> int:
        real(fd, bytes(data[:7]))
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    return write


def _fail(err: int) -> Any:
    def fail(*args: object) -> None:
        raise OSError(err, os.strerror(err))

    return fail


@pytest.mark.parametrize(
    ("function", "make", "reason"),
    [
        ("write", lambda: _fail_midway(os.write), "No space left on device"),
        ("fsync", lambda: _fail(errno.EIO), "Input/output error"),
        ("replace", lambda: _fail(errno.EXDEV), "Invalid cross-device link"),
    ],
)
def test_a_failed_save_leaves_the_old_file_intact_and_no_temporary_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, function: str, make: Any, reason: str
) -> None:
    path = tmp_path / "omsd.state"
    state = saved_file(path)
    before = path.read_bytes()
    monkeypatch.setattr(os, function, make())
    with pytest.raises(StateFileError) as info:
        state.save_board("a", BoardFlash({"new": True}, {}))
    monkeypatch.undo()
    message = str(info.value)
    assert message.startswith(f'state file {path}: cannot save board "a": {reason}')
    assert "\n" not in message
    assert path.read_bytes() == before
    only_the_state_file(tmp_path)
    assert state.board("a") == BoardFlash(DEFAULTS, MACROS)  # what is on disk
    state.save_board("b", BoardFlash({"v": 1}, {}))  # and the next save works
    assert loaded(path)[0].board("a") == BoardFlash(DEFAULTS, MACROS)


def test_the_file_and_then_its_directory_are_fsynced(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "omsd.state"
    state, _ = loaded(path)
    synced: list[str] = []
    real_fsync = os.fsync

    def fsync(fd: int) -> None:
        mode = os.fstat(fd).st_mode
        synced.append("directory" if stat.S_ISDIR(mode) else f"file of {path.exists()}")
        real_fsync(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    state.save_board("a", BoardFlash())
    # the temporary file is synced before it replaces the (not yet existing) state file
    assert synced == ["file of False", "directory"]


def test_a_directory_that_cannot_be_created_is_a_clear_error(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("not a directory")
    path = tmp_path / "file" / "omsd.state"
    state, result = loaded(path)
    assert not result.ok
    assert one_line(result, path) == "cannot read: Not a directory; using factory defaults"
    with pytest.raises(StateFileError) as info:
        state.save_board("a", BoardFlash())
    assert str(info.value).startswith(f'state file {path}: cannot save board "a": ')


# -- a missing, unreadable or corrupt file ------------------------------------------------------


def test_a_missing_file_is_the_first_start(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    state, result = loaded(path)
    assert result.ok
    assert one_line(result, path) == (
        "not found; using factory defaults (the first save creates it)"
    )
    assert state.board("a") == BoardFlash(None, {})
    assert not path.exists()


def test_a_message_stays_on_one_line_whatever_the_path(tmp_path: Path) -> None:
    path = tmp_path / "odd\ndir" / "omsd.state"
    _, result = loaded(path)
    assert result.message is not None
    assert "\n" not in result.message and "odd\\ndir" in result.message


CORRUPT = [
    (b"", "empty"),
    (b" \n", "empty"),
    (
        b'{"format": 1,\n "boards": {\n  "a": }}',
        "not valid JSON at line 3, column 8: Expecting value",
    ),
    (b'{"format": 1, "boards": {}', "not valid JSON at line 1, column 27: Expecting ',' delimiter"),
    (b'{"format": 1, "boards": {"a": {"defaults": {"x": NaN}}}}', "not valid JSON: NaN is not"),
    (b'{"format": 1, "boards": {"a": {"defaults": {"x": -Infinity}}}}', "not valid JSON: -Inf"),
    (b"\xef\xbb\xbf{}", "not valid JSON at line 1, column 1: Unexpected UTF-8 BOM"),
    (b'{"format": 1, "boards": {"caf\xe9": {}}}', "not UTF-8 text: byte 0xe9 at offset 29"),
    (b"[1, 2]", 'expected an object with "format" and "boards", got an array'),
    (b"null", 'expected an object with "format" and "boards", got null'),
    (b'{"boards": {}}', "format none is not one this omsd reads (it reads format 1)"),
    (b'{"format": 2, "boards": {}}', "format 2 is not one this omsd reads (it reads format 1)"),
    (b'{"format": "1", "boards": {}}', 'format "1" is not one this omsd reads'),
    (b'{"format": true, "boards": {}}', "format true is not one this omsd reads"),
    (b'{"format": 1.0, "boards": {}}', "format 1.0 is not one this omsd reads"),
    (b'{"format": 1, "boards": []}', '"boards": expected an object, got an array'),
    (b"[" * 100_000 + b"]" * 100_000, "not valid JSON"),
]


@pytest.mark.parametrize(("data", "expected"), CORRUPT, ids=range(len(CORRUPT)))
def test_a_corrupt_file_gives_factory_defaults_and_one_line(
    tmp_path: Path, data: bytes, expected: str
) -> None:
    path = tmp_path / "omsd.state"
    path.write_bytes(data)
    state, result = loaded(path)
    assert not result.ok
    text = one_line(result, path)
    assert text.startswith(expected), text
    assert text.endswith("; using factory defaults (the next save keeps it as omsd.state.corrupt)")
    assert state.board("a") == BoardFlash(None, {})
    assert path.read_bytes() == data  # reading changes nothing


def test_the_first_save_keeps_a_corrupt_file_aside(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    newer = b'{"format": 2, "boards": {"a": {"flash": "of a newer omsd"}}}'
    path.write_bytes(newer)
    state, _ = loaded(path)
    state.save_board("b", BoardFlash({"v": 1}, {}))
    assert (tmp_path / "omsd.state.corrupt").read_bytes() == newer
    assert loaded(path)[0].board("b") == BoardFlash({"v": 1}, {})
    state.save_board("b", BoardFlash({"v": 2}, {}))  # only the first save
    assert (tmp_path / "omsd.state.corrupt").read_bytes() == newer


def test_an_empty_file_from_a_crash_is_kept_aside_too(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.write_bytes(b"")
    (tmp_path / "omsd.state.corrupt").write_bytes(b"an older one")
    state, _ = loaded(path)
    state.save_board("a", BoardFlash())
    assert (tmp_path / "omsd.state.corrupt").read_bytes() == b""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["omsd.state", "omsd.state.corrupt"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files whatever their permissions")
def test_an_unreadable_file(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.write_text('{"format": 1, "boards": {}}')
    path.chmod(0)
    state, result = loaded(path)
    assert not result.ok
    assert one_line(result, path) == "cannot read: Permission denied; using factory defaults"
    assert state.board("a") == BoardFlash(None, {})


def test_a_read_error_gives_factory_defaults_and_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same as a chmod 000 file, for a test run as root."""
    path = tmp_path / "omsd.state"
    path.write_text('{"format": 1, "boards": {"a": {"defaults": {"v": 1}}}}')

    def read_bytes(self: Path) -> bytes:
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))

    monkeypatch.setattr(Path, "read_bytes", read_bytes)
    state, result = loaded(path)
    monkeypatch.undo()
    assert not result.ok
    assert one_line(result, path) == "cannot read: Permission denied; using factory defaults"
    assert state.board("a") == BoardFlash(None, {})
    state.save_board("b", BoardFlash())  # what could not be read is kept, not overwritten
    assert json.loads((tmp_path / "omsd.state.corrupt").read_text())["boards"]["a"]


def test_a_directory_in_place_of_the_file(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.mkdir()
    state, result = loaded(path)
    assert not result.ok
    assert one_line(result, path) == "cannot read: Is a directory; using factory defaults"
    with pytest.raises(StateFileError, match=r'cannot save board "a": Is a directory'):
        state.save_board("a", BoardFlash())
    assert path.is_dir() and list(path.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["omsd.state"]


# -- a board section of the wrong shape ---------------------------------------------------------

BAD_SECTIONS = [
    ("x", "expected an object, got a string"),
    ({"defaults": []}, "defaults: expected an object or null, got an array"),
    ({"defaults": 5}, "defaults: expected an object or null, got a number"),
    ({"macros": []}, "macros: expected an object, got an array"),
    ({"macros": {"4": "VL1;"}}, 'macros: expected slots 5..24, got "4"'),
    ({"macros": {"25": "VL1;"}}, 'macros: expected slots 5..24, got "25"'),
    ({"macros": {"x": "VL1;"}}, 'macros: expected slots 5..24, got "x"'),
    ({"macros": {"٥": "VL1;"}}, 'macros: expected slots 5..24, got "\\u0665"'),
    ({"macros": {"5": 7}}, "macros.5: expected a string of at most 250 characters, got a number"),
    (
        {"macros": {"5": "A" * 251}},
        "macros.5: expected a string of at most 250 characters, got 251 characters",
    ),
]


@pytest.mark.parametrize(("section", "expected"), BAD_SECTIONS)
def test_a_bad_board_section_is_ignored_and_the_others_kept(
    tmp_path: Path, section: object, expected: str
) -> None:
    path = tmp_path / "omsd.state"
    good = {"defaults": {"v": 1}, "macros": {"5": "MR1;"}}
    path.write_text(json.dumps({"format": 1, "boards": {"bad": section, "good": good}}))
    state, result = loaded(path)
    assert not result.ok
    assert one_line(result, path) == f'board "bad": {expected}; that board uses factory defaults'
    assert state.board("bad") == BoardFlash(None, {})
    assert state.board("good") == BoardFlash({"v": 1}, {5: "MR1;"})


def test_several_bad_sections_make_one_line(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.write_text(json.dumps({"format": 1, "boards": {"a": 1, "b": {"macros": 2}}}))
    _, result = loaded(path)
    assert one_line(result, path) == (
        'board "a": expected an object, got a number; '
        'board "b": macros: expected an object, got a number; '
        "those boards use factory defaults"
    )


def test_missing_keys_in_a_section_are_empty(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.write_text('{"format": 1, "boards": {"a": {}, "b": {"defaults": null}}}')
    state, result = loaded(path)
    assert result == LoadResult(True, None)
    assert state.board("a") == state.board("b") == BoardFlash(None, {})


def test_a_file_without_boards_is_empty(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    path.write_text('{"format": 1}')
    state, result = loaded(path)
    assert result == LoadResult(True, None)
    state.save_board("a", BoardFlash())
    assert loaded(path)[0].board("a") == BoardFlash()


def test_a_save_writes_back_what_it_does_not_replace(tmp_path: Path) -> None:
    """Ignored sections and unknown top-level keys survive another board's save."""
    path = tmp_path / "omsd.state"
    path.write_text(json.dumps({"format": 1, "comment": "kept", "boards": {"bad": {"macros": []}}}))
    state, _ = loaded(path)
    state.save_board("a", BoardFlash({"v": 1}, {}))
    document = json.loads(path.read_text())
    assert document["comment"] == "kept"
    assert document["boards"]["bad"] == {"macros": []}
    state.save_board("bad", BoardFlash({"v": 2}, {}))  # saving that board replaces it
    assert loaded(path)[0].board("bad") == BoardFlash({"v": 2}, {})


# -- what a save refuses ------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "flash", "error"),
    [
        ("a", BoardFlash(None, {4: "x"}), ValueError),  # a temporary macro is not in flash
        ("a", BoardFlash(None, {25: "x"}), ValueError),
        ("a", BoardFlash(None, {True: "x"}), ValueError),
        ("a", BoardFlash(None, {5: "A" * 251}), ValueError),
        ("a", BoardFlash(None, {5: b"MR1;"}), ValueError),  # type: ignore[dict-item]
        ("a", BoardFlash({"x": float("nan")}, {}), ValueError),
        ("a", BoardFlash({"x": float("inf")}, {}), ValueError),
        ("a", BoardFlash({"x": {1, 2}}, {}), TypeError),
        ("a", BoardFlash(["not", "a", "dict"], {}), ValueError),  # type: ignore[arg-type]
        ("", BoardFlash(), ValueError),
    ],
)
def test_a_save_refuses_what_the_file_cannot_hold(
    tmp_path: Path, name: str, flash: BoardFlash, error: type[Exception]
) -> None:
    path = tmp_path / "omsd.state"
    state = saved_file(path)
    before = path.read_bytes()
    with pytest.raises(error):
        state.save_board(name, flash)
    assert path.read_bytes() == before
    only_the_state_file(tmp_path)


def test_reading_or_saving_before_load_is_a_mistake(tmp_path: Path) -> None:
    state = StateFile(tmp_path / "omsd.state")
    with pytest.raises(RuntimeError):
        state.board("a")
    with pytest.raises(RuntimeError):
        state.save_board("a", BoardFlash())
    assert list(tmp_path.iterdir()) == []


# -- issue 13: the file's permissions, and what a crash leaves ----------------------------------


def a_group() -> grp.struct_group:
    """A group this process may give its files to, other than its own if it can (root: any)."""
    if os.geteuid() == 0:
        candidates = [g.gr_gid for g in grp.getgrall() if g.gr_gid != os.getegid()]
    else:
        candidates = [g for g in os.getgroups() if g != os.getegid()]
    return grp.getgrgid(candidates[0] if candidates else os.getegid())


def test_with_a_group_a_new_file_is_0640_in_that_group(tmp_path: Path) -> None:
    group = a_group()
    path = tmp_path / "omsd.state"
    state = StateFile(path, group=group.gr_name)
    state.load()
    old = os.umask(0o077)  # systemd's UMask=0077: the mode is set, not left to the umask
    try:
        state.save_board("a", BoardFlash())
    finally:
        os.umask(old)
    st = path.stat()
    assert (stat.S_IMODE(st.st_mode), st.st_gid) == (0o640, group.gr_gid)
    state.save_board("a", BoardFlash({"v": 1}, {}))  # every save writes a new file: the same
    st = path.stat()
    assert (stat.S_IMODE(st.st_mode), st.st_gid) == (0o640, group.gr_gid)


def _leftover(directory: Path, name: str = "omsd.state") -> Path:
    """What a save killed between its temporary file and the rename leaves behind: the
    temporary file, named as the save names it."""
    fd, temporary = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=directory)
    os.write(fd, b'{"format": 1, "boa')
    os.close(fd)
    return Path(temporary)


def test_temporary_files_left_by_a_crash_are_removed_at_the_next_load(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    saved_file(path)
    before = path.read_bytes()
    leftovers = [_leftover(tmp_path) for _ in range(3)]
    # not the leftovers of this file: untouched
    others = [
        _leftover(tmp_path, "other.state"),
        tmp_path / ".omsd.state.notours.tmp",
        tmp_path / "omsd.state.tmp",
        tmp_path / ".omsd.state.abcdefgh.tmp.keep",
    ]
    for other in others[1:]:
        other.write_text("someone else's")
    state, result = loaded(path)
    assert result.ok
    assert one_line(result, path) == "removed 3 temporary files left by a save cut short"
    assert not any(p.exists() for p in leftovers)
    assert all(p.exists() for p in others)
    assert path.read_bytes() == before
    assert state.board("a") == BoardFlash(DEFAULTS, MACROS)
    # and the next load has nothing to say
    assert loaded(path)[1] == LoadResult(True, None)


def test_a_leftover_is_removed_whatever_else_the_load_says(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    _leftover(tmp_path)
    _, result = loaded(path)
    assert result.ok
    assert one_line(result, path) == (
        "not found; using factory defaults (the first save creates it);"
        " removed 1 temporary file left by a save cut short"
    )
    assert list(tmp_path.iterdir()) == []


def test_a_leftover_that_is_not_a_regular_file_is_left_alone(tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    odd = tmp_path / ".omsd.state.abcdefgh.tmp"
    odd.symlink_to(tmp_path / "elsewhere")
    loaded(path)
    assert odd.is_symlink()
