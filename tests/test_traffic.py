"""The traffic log: visible bytes, plain and journald lines, the rich view, the JSON-lines file."""

from __future__ import annotations

import datetime
import grp
import io
import json
import os
import pathlib
import re
import signal
import subprocess
import sys
import textwrap

import pytest

from omsd.telemetry import Direction, Traffic, TrafficLog, TrafficLogError, visible

ROOT = pathlib.Path(__file__).resolve().parents[1]
T0 = datetime.datetime(2024, 1, 2, 12, 0, 1, 234567).timestamp()  # 12:00:01.234 local time
EP = "tcp:127.0.0.1:7048 #1"


@pytest.fixture(autouse=True)
def _no_colour_overrides(monkeypatch: pytest.MonkeyPatch) -> None:
    """rich reads these from the process environment; keep the tests' terminals as they say."""
    for name in ("FORCE_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE", "NO_COLOR"):
        monkeypatch.delenv(name, raising=False)


def wy(direction: Direction = Direction.IN, data: bytes = b"WY\r") -> Traffic:
    return Traffic(T0, "board1", EP, direction, data)


class TTY(io.StringIO):
    def isatty(self) -> bool:
        return True


# ------------------------------------------------------------------------ visible()


def test_visible_example_of_the_issue() -> None:
    assert visible(b"WY\n\r\x04\x19") == "WY<LF><CR>^D^Y"


def test_visible_printable_ascii_is_itself() -> None:
    printable = bytes(range(0x20, 0x7F))
    assert visible(printable) == printable.decode("ascii")


def test_visible_control_characters_in_caret_notation() -> None:
    for byte in range(0x20):
        if byte in (0x0A, 0x0D):
            continue
        assert visible(bytes([byte])) == "^" + chr(byte + 0x40)
    assert visible(b"\x00\x01\x1b\x1f") == "^@^A^[^_"
    assert visible(b"\t") == "^I"


def test_visible_lf_and_cr_by_name() -> None:
    assert visible(b"\n") == "<LF>"
    assert visible(b"\r") == "<CR>"
    assert visible(b"\n\r067\n\r") == "<LF><CR>067<LF><CR>"


def test_visible_del_and_high_bytes_in_hex() -> None:
    assert visible(b"\x7f") == "<7F>"
    assert visible(b"\x80\xff") == "<80><FF>"
    assert visible(b"!\x8f\n") == "!<8F><LF>"  # a done marker for axes X, Y, Z, T and 8 more


def test_visible_every_byte_gives_one_line() -> None:
    shown = visible(bytes(range(256)))
    assert shown.isprintable() and shown.isascii()
    assert visible(b"") == ""


# ------------------------------------------------------------------------ plain view


def test_plain_line_into_the_board() -> None:
    out = io.StringIO()
    log = TrafficLog("plain", stream=out, env={})
    log.record(wy())
    assert out.getvalue() == f"12:00:01.234 board1 {EP} <- WY<CR>\n"


def test_plain_line_out_of_the_board() -> None:
    out = io.StringIO()
    log = TrafficLog("plain", stream=out, env={})
    log.record(wy(Direction.OUT, b"\n\r067\n\r"))
    assert out.getvalue() == f"12:00:01.234 board1 {EP} -> <LF><CR>067<LF><CR>\n"


def test_plain_event_and_messages() -> None:
    out = io.StringIO()
    log = TrafficLog("plain", stream=out, env={}, clock=lambda: T0)
    log.event(T0, "board1", "done X")
    log.info("board1 PC48-4E on tcp:127.0.0.1:7048")
    log.warning("board1: second client refused")
    log.error("port 7048 in use")
    assert out.getvalue().splitlines() == [
        "12:00:01.234 board1 [done X]",
        "12:00:01.234 board1 PC48-4E on tcp:127.0.0.1:7048",
        "12:00:01.234 warning: board1: second client refused",
        "12:00:01.234 error: port 7048 in use",
    ]


def test_plain_has_no_prefixes_without_journal_stream() -> None:
    out = io.StringIO()
    log = TrafficLog("auto", stream=out, env={"TERM": "xterm"})
    log.record(wy())
    log.warning("w")
    assert not log.journal
    assert "<6>" not in out.getvalue() and "<4>" not in out.getvalue()


def test_time_is_truncated_to_the_millisecond() -> None:
    out = io.StringIO()
    t = datetime.datetime(2024, 1, 2, 23, 59, 59, 999900).timestamp()
    TrafficLog("plain", stream=out, env={}).event(t, "b", "x")
    assert out.getvalue().startswith("23:59:59.999 ")


# ------------------------------------------------------------------------ journald


def test_journald_prefixes_with_journal_stream() -> None:
    out = io.StringIO()
    log = TrafficLog("auto", stream=out, env={"JOURNAL_STREAM": "8:12345"}, clock=lambda: T0)
    assert log.view == "plain" and log.journal
    log.record(wy())
    log.event(T0, "board1", "limit X+")
    log.info("started")
    log.warning("careful")
    log.error("broken\nsecond line")
    assert out.getvalue().splitlines() == [
        f"<6>12:00:01.234 board1 {EP} <- WY<CR>",
        "<6>12:00:01.234 board1 [limit X+]",
        "<6>12:00:01.234 started",
        "<4>12:00:01.234 warning: careful",
        "<3>12:00:01.234 error: broken",
        "<3>12:00:01.234 error: second line",
    ]


def test_journald_wins_over_a_terminal() -> None:
    log = TrafficLog("auto", stream=TTY(), env={"JOURNAL_STREAM": "8:12345"})
    assert (log.view, log.journal) == ("plain", True)


def test_journal_stream_compared_with_the_streams_device_and_inode(tmp_path: pathlib.Path) -> None:
    with open(tmp_path / "journal", "w") as f:
        st = os.fstat(f.fileno())
        same = TrafficLog("auto", stream=f, env={"JOURNAL_STREAM": f"{st.st_dev}:{st.st_ino}"})
        other = TrafficLog("auto", stream=f, env={"JOURNAL_STREAM": f"{st.st_dev}:{st.st_ino + 1}"})
        same.info("to the journal")
        other.info("inherited variable, not the journal")
    lines = (tmp_path / "journal").read_text().splitlines()
    assert same.journal and not other.journal
    assert lines[0].startswith("<6>") and lines[0].endswith(" to the journal")
    assert not lines[1].startswith("<")


def test_explicit_plain_also_prefixes_on_the_journal() -> None:
    out = io.StringIO()
    TrafficLog("plain", stream=out, env={"JOURNAL_STREAM": "1:2"}).warning("w")
    assert out.getvalue().startswith("<4>")


# ------------------------------------------------------------------------ rich and auto


def test_rich_view_to_a_non_tty_contains_the_visible_text() -> None:
    out = io.StringIO()
    log = TrafficLog("rich", stream=out, env={}, clock=lambda: T0)
    log.record(wy(Direction.IN, b"WY\x04\x19"))
    log.record(wy(Direction.OUT, b"\n\r067\n\r"))
    log.event(T0, "board1", "done X")
    log.warning("careful")
    lines = out.getvalue().splitlines()
    assert lines[0] == f"12:00:01.234 board1 {EP} <- WY^D^Y"
    assert lines[1] == f"12:00:01.234 board1 {EP} -> <LF><CR>067<LF><CR>"
    assert lines[2] == "12:00:01.234 board1 [done X]"
    assert lines[3] == "12:00:01.234 warning: careful"
    assert "\x1b" not in out.getvalue()  # no terminal, no colour codes


def test_rich_view_does_not_wrap_or_interpret_markup() -> None:
    out = io.StringIO()
    log = TrafficLog("rich", stream=out, env={})
    data = b"[bold]" + b"A" * 300
    log.record(wy(Direction.OUT, data))
    assert out.getvalue() == f"12:00:01.234 board1 {EP} -> {data.decode()}\n"


def test_rich_view_aligns_columns() -> None:
    out = io.StringIO()
    log = TrafficLog("rich", stream=out, env={})
    log.record(Traffic(T0, "board10", "tcp:127.0.0.1:7048 #10", Direction.IN, b"WY"))
    log.record(Traffic(T0, "b1", "pty:/x", Direction.IN, b"WY"))
    first, second = out.getvalue().splitlines()
    assert first.index("<-") == second.index("<-")


def test_auto_picks_plain_for_a_non_tty() -> None:
    out = io.StringIO()
    log = TrafficLog(stream=out, env={})
    assert log.view == "plain" and not log.journal
    log.record(wy())
    assert out.getvalue() == f"12:00:01.234 board1 {EP} <- WY<CR>\n"


def test_auto_picks_rich_for_a_terminal_with_colour(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TERM", "xterm-256color")
    out = TTY()
    log = TrafficLog(stream=out, env={})
    assert log.view == "rich"
    log.record(wy(Direction.OUT, b"0\n"))
    shown = out.getvalue()
    assert "\x1b[" in shown  # coloured
    assert re.search(r"\x1b\[[0-9;]*m<LF>", shown)  # control characters in their own colour
    assert re.search(r"\x1b\[[0-9;]*m0\x1b", shown)


def test_off_writes_nothing_but_the_file(tmp_path: pathlib.Path) -> None:
    out = io.StringIO()
    with TrafficLog("off", file=tmp_path / "t.jsonl", stream=out, env={}) as log:
        log.record(wy())
        log.error("e")
    assert out.getvalue() == ""
    assert len((tmp_path / "t.jsonl").read_text().splitlines()) == 2


def test_unknown_view_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown log view 'fancy'"):
        TrafficLog("fancy", stream=io.StringIO(), env={})


def test_default_stream_is_stderr(capsys: pytest.CaptureFixture[str]) -> None:
    log = TrafficLog("plain", env={})
    log.record(wy())
    assert capsys.readouterr().err == f"12:00:01.234 board1 {EP} <- WY<CR>\n"


def test_a_broken_stream_is_given_up_and_the_file_goes_on(tmp_path: pathlib.Path) -> None:
    class Broken(io.StringIO):
        def write(self, s: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

    log = TrafficLog("plain", file=tmp_path / "t.jsonl", stream=Broken(), env={})
    log.record(wy())
    log.record(wy())
    log.close()
    assert log.view == "off"
    assert len((tmp_path / "t.jsonl").read_text().splitlines()) == 2


# ------------------------------------------------------------------------ the JSON-lines file


def test_json_lines_round_trip_every_byte(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    items = [
        Traffic(T0, "board1", EP, Direction.IN, bytes(range(256))),
        Traffic(T0 + 0.5, "board2", "pty:/tmp/omsd/board2", Direction.OUT, b"!\x01\n"),
        Traffic(T0 + 1, "board1", EP, Direction.OUT, b""),
    ]
    log = TrafficLog("off", file=path, env={})
    for item in items:
        log.record(item)
    log.close()
    records = [json.loads(line) for line in path.read_text(encoding="ascii").splitlines()]
    assert [Traffic.from_record(r) for r in records] == items
    for record, item in zip(records, items, strict=True):
        assert record["data"].encode("latin-1") == item.data
        assert bytes.fromhex(record["hex"]) == item.data
        assert record["t"] == item.time
        assert record["dir"] == item.direction.value


def test_json_lines_example_record(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    with TrafficLog("off", file=path, env={}) as log:
        log.record(Traffic(1700000000.123456, "board1", EP, Direction.IN, b"WY\r"))
    assert json.loads(path.read_text()) == {
        "t": 1700000000.123456,
        "kind": "traffic",
        "board": "board1",
        "endpoint": EP,
        "dir": "in",
        "data": "WY\r",
        "hex": "57590d",
    }


def test_json_lines_events_and_messages(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    with TrafficLog("off", file=path, env={}, clock=lambda: 5.0) as log:
        log.event(4.0, "board1", "limit X+")
        log.info("started")
        log.warning("careful")
        log.error("broken")
    records = [json.loads(line) for line in path.read_text().splitlines()]
    assert records == [
        {"t": 4.0, "kind": "event", "board": "board1", "what": "limit X+"},
        {"t": 5.0, "kind": "info", "message": "started"},
        {"t": 5.0, "kind": "warning", "message": "careful"},
        {"t": 5.0, "kind": "error", "message": "broken"},
    ]
    with pytest.raises(ValueError, match="not a traffic record"):
        Traffic.from_record(records[0])


def test_file_is_appended_to(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    path.write_text('{"kind": "earlier"}\n')
    for n in range(2):
        with TrafficLog("off", file=path, env={}) as log:
            log.record(wy(data=str(n).encode()))
    lines = path.read_text().splitlines()
    assert lines[0] == '{"kind": "earlier"}'
    assert [json.loads(line)["data"] for line in lines[1:]] == ["0", "1"]


def test_each_record_is_in_the_file_at_once(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    log = TrafficLog("off", file=path, env={})
    log.record(wy())
    assert json.loads(path.read_text())["data"] == "WY\r"  # before close: nothing buffered
    log.close()


def test_file_that_cannot_be_opened_gives_one_clear_line(tmp_path: pathlib.Path) -> None:
    missing = tmp_path / "no" / "such" / "dir" / "t.jsonl"
    with pytest.raises(TrafficLogError) as info:
        TrafficLog("off", file=missing, env={})
    assert isinstance(info.value, OSError)
    assert str(info.value) == f"cannot open traffic log {missing}: No such file or directory"
    with pytest.raises(OSError, match=r"cannot open traffic log .*: Is a directory"):
        TrafficLog("off", file=tmp_path, env={})


def test_close_is_idempotent(tmp_path: pathlib.Path) -> None:
    out = io.StringIO()
    log = TrafficLog("plain", file=tmp_path / "t.jsonl", stream=out, env={})
    log.record(wy())
    log.close()
    log.close()
    log.record(wy())  # the stream goes on, the file does not
    assert len(out.getvalue().splitlines()) == 2
    assert len((tmp_path / "t.jsonl").read_text().splitlines()) == 1
    TrafficLog("off", env={}).close()  # no file at all


def test_a_failing_file_is_reported_once_and_closed(tmp_path: pathlib.Path) -> None:
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    out = io.StringIO()
    log = TrafficLog("plain", file=pathlib.Path("/dev/full"), stream=out, env={})
    log.record(wy())
    log.record(wy())
    errors = [line for line in out.getvalue().splitlines() if "error:" in line]
    assert len(errors) == 1 and "/dev/full" in errors[0] and "no longer written" in errors[0]
    log.close()


@pytest.mark.parametrize("journal", [False, True], ids=["stderr", "journal"])
def test_a_failing_file_is_reported_with_the_view_off_too(journal: bool) -> None:
    """With ``view = "off"`` the error of a traffic log file omsd gave up on (a full disk)
    went to the view, which is off, and to the file, which had just failed: it reached no one.
    Now an error that nothing else takes (view off, no file) is one plain line on the stream,
    with the journal's error level where the stream is the journal; nothing else is shown."""
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    out = io.StringIO()
    env = {"JOURNAL_STREAM": "1:2"} if journal else {}
    log = TrafficLog("off", file=pathlib.Path("/dev/full"), stream=out, env=env)
    log.info("serving")
    log.record(wy())
    log.record(wy())
    log.warning("a warning")
    log.close()
    lines = out.getvalue().splitlines()
    assert len(lines) == 1, lines
    prefix = "<3>" if journal else ""
    assert re.fullmatch(
        re.escape(prefix)
        + r"\d\d:\d\d:\d\d\.\d{3} error: traffic log /dev/full: No space left on device;"
        r" no longer written",
        lines[0],
    ), lines
    quiet = io.StringIO()
    with TrafficLog("off", stream=quiet, env={}) as log:
        log.error("one\ntwo")
        log.info("not shown")
    assert quiet.getvalue().endswith(" error: one two\n"), quiet.getvalue()
    assert quiet.getvalue().count("\n") == 1


CHILD = textwrap.dedent(
    """
    import pathlib, sys
    from omsd.telemetry import Direction, Traffic, TrafficLog
    log = TrafficLog("off", file=pathlib.Path(sys.argv[1]), env={})
    n = 0
    while True:
        log.record(Traffic(float(n), "board1", "pty:/x", Direction.OUT, bytes(range(256)) * 64))
        n += 1
        if n == 200:
            print("ready", flush=True)
    """
)


def test_sigkill_loses_at_most_the_line_in_progress(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, env=env, cwd=ROOT
    )
    try:
        assert child.stdout is not None
        assert child.stdout.readline() == b"ready\n"
        child.send_signal(signal.SIGKILL)
    finally:
        child.kill()
        child.wait(timeout=10)
        if child.stdout is not None:
            child.stdout.close()
    assert child.returncode == -signal.SIGKILL
    text = path.read_bytes()
    lines = text.split(b"\n")
    *complete, last = lines  # `last` is b"" or the line that was being written
    assert len(complete) >= 200  # every record logged before "ready" survived
    times = [Traffic.from_record(json.loads(line)).time for line in complete]
    assert times == [float(n) for n in range(len(complete))]
    assert all(
        Traffic.from_record(json.loads(line)).data == bytes(range(256)) * 64
        for line in complete[:3]
    )
    if last:
        with pytest.raises(json.JSONDecodeError):
            json.loads(last)


# -- issue 13: the file's permissions, and reopening it (logrotate) -----------------------------


def _mode(path: pathlib.Path) -> int:
    return path.stat().st_mode & 0o777


def a_group() -> grp.struct_group:
    """A group this process may give its files to, other than its own if it can (root: any)."""
    if os.geteuid() == 0:
        candidates = [g.gr_gid for g in grp.getgrall() if g.gr_gid != os.getegid()]
    else:
        candidates = [g for g in os.getgroups() if g != os.getegid()]
    return grp.getgrgid(candidates[0] if candidates else os.getegid())


def test_a_new_file_is_0600_whatever_the_umask(tmp_path: pathlib.Path) -> None:
    """It was created 0644: every local user could read every byte to and from the boards."""
    path = tmp_path / "traffic.jsonl"
    old = os.umask(0o022)
    try:
        TrafficLog("off", file=path, env={}).close()
    finally:
        os.umask(old)
    assert _mode(path) == 0o600


def test_with_a_group_a_new_file_is_0640_in_that_group(tmp_path: pathlib.Path) -> None:
    group = a_group()
    path = tmp_path / "traffic.jsonl"
    old = os.umask(0o077)  # systemd's UMask=0077: the mode is set, not left to the umask
    try:
        TrafficLog("off", file=path, env={}, group=group.gr_name).close()
    finally:
        os.umask(old)
    assert (_mode(path), path.stat().st_gid) == (0o640, group.gr_gid)


def test_an_existing_file_keeps_its_permissions(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    path.write_text("")
    path.chmod(0o644)  # the operator's choice: omsd changes nothing it did not create
    with TrafficLog("off", file=path, env={}, group=a_group().gr_name) as log:
        log.info("x")
    assert _mode(path) == 0o644 and path.stat().st_gid == os.getegid()


def test_a_group_that_does_not_exist_leaves_no_file(tmp_path: pathlib.Path) -> None:
    path = tmp_path / "traffic.jsonl"
    with pytest.raises(TrafficLogError) as info:
        TrafficLog("off", file=path, env={}, group="no-such-group-omsd")
    assert str(info.value) == f"cannot open traffic log {path}: no group 'no-such-group-omsd'"
    assert not path.exists()


def test_reopen_after_a_rename_writes_a_new_file(tmp_path: pathlib.Path) -> None:
    """What logrotate does without copytruncate: rename the file, then ask for a reopen."""
    path = tmp_path / "traffic.jsonl"
    rotated = tmp_path / "traffic.jsonl.1"
    with TrafficLog("off", file=path, env={}, clock=lambda: 1.0) as log:
        log.info("before")
        path.rename(rotated)
        log.info("after the rename, before the reopen")  # still the old file
        assert log.reopen() is True
        log.info("after the reopen")
    assert [json.loads(line)["message"] for line in rotated.read_text().splitlines()] == [
        "before",
        "after the rename, before the reopen",
    ]
    assert [json.loads(line)["message"] for line in path.read_text().splitlines()] == [
        "after the reopen"
    ]
    assert _mode(path) == 0o600


def test_reopen_without_a_file_or_that_fails(tmp_path: pathlib.Path) -> None:
    assert TrafficLog("off", env={}).reopen() is False
    directory = tmp_path / "logs"
    directory.mkdir()
    out = io.StringIO()
    with TrafficLog("plain", file=directory / "t.jsonl", stream=out, env={}) as log:
        (directory / "t.jsonl").rename(tmp_path / "t.jsonl.1")
        directory.rmdir()
        assert log.reopen() is False  # the directory is gone: the old file goes on
        log.info("still written")
    assert "cannot reopen: No such file or directory" in out.getvalue()
    assert "still written" in (tmp_path / "t.jsonl.1").read_text()


def test_a_full_disk_leaves_whole_lines_and_the_reopened_file_goes_on(
    tmp_path: pathlib.Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A disk that fills in the middle of a record (ENOSPC after part of it was written) left
    that part at the end of the file; the SIGHUP that reopened it once there was room again
    appended its first line to the part, and a reader lost both ("... Oregon Micro {"t": ...,
    "message": "reopened log files on SIGHUP: ..."}"). The part is now taken back: the file
    holds whole lines only, and goes on after the reopen."""
    path = tmp_path / "traffic.jsonl"
    out = io.StringIO()
    log = TrafficLog("plain", file=path, stream=out, env={}, clock=lambda: 1.0)
    log.info("before")
    real_write = os.write
    fd = log._fd

    def full(to: int, data: bytes | memoryview) -> int:
        if to != fd:
            return real_write(to, data)
        if len(data) > 10:
            return real_write(to, bytes(data[:10]))  # what fitted
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "write", full)
    log.record(wy())
    monkeypatch.setattr(os, "write", real_write)
    assert "no longer written" in out.getvalue()
    assert log.reopen() is True  # room again; SIGHUP
    log.info("after")
    log.close()
    lines = path.read_text().splitlines()
    assert [json.loads(line).get("message") for line in lines] == ["before", "after"]


def test_a_line_cut_short_by_a_crash_is_not_joined_to_the_next_one(tmp_path: pathlib.Path) -> None:
    """A daemon killed in the middle of a line loses that line (see above); the next daemon
    appending to the file must not lose its own first line too by writing it onto the cut one."""
    path = tmp_path / "traffic.jsonl"
    path.write_text('{"t": 1.0, "kind": "info", "message": "whole"}\n{"t": 2.0, "kind": "inf')
    with TrafficLog("off", file=path, env={}, clock=lambda: 3.0) as log:
        log.info("next daemon")
    lines = path.read_text().split("\n")
    assert lines[-1] == ""
    assert json.loads(lines[0])["message"] == "whole"
    assert lines[1] == '{"t": 2.0, "kind": "inf'
    assert json.loads(lines[2])["message"] == "next daemon"
