"""A PCIx's flash through the real daemon: AP, RD, RF and PT across restarts, and the state file.

PCIx manual §5.4.2: "The AP command stores the current parameter set as the power-up default set
of values. This is done by writing the current parameter set to flash memory" (AC, KP, KI, KD,
KO, VL, ... "will have their values saved"); RD "restores the motion parameters using power-up
defaults"; RF "restores the current parameter set to the factory default values. This process
does not alter the parameters stored in flash via the AP command". §5.4.7: "20 are “permanent”;
i.e. stored in non-volatile flash RAM"; PT "save[s] a temporary macro permanently by copying it
to non-volatile memory"; MD: "Macros 0 through 4 are temporary and they will be erased when the
controller is reset or power is turned off".

The daemon keeps that flash in the ``[state] file`` (omsd/statefile.py): JSON, a section per
board name; "a corrupt or missing state file gives the factory defaults and one clear log line";
"the first save keeps it as ``<name>.corrupt``". A restart of the daemon is the board's power
cycle. The boards here use the raw link, so every reply is ``text<LF><CR>``.

Choices: "factory" replies are taken from a daemon that starts without any saved state rather
than written out here (the velocity default is a digest question, not this file's); a state file
that loads cleanly is expected to say nothing in the log (``LoadResult.message`` is ``None``).
"""

from __future__ import annotations

import json
import signal
from pathlib import Path
from typing import Any

from .process import Conn, Daemon, Omsd, wait_for

BOARD = "servo"
QUERIES = ("AX;?VL", "AX;?AC", "AX;?KP", "AX;?KI", "AX;?KD", "AY;?VL", "AY;?KO", "AY;?SV")
SETTINGS = "AX;VL12345;AC123456;KP25;KI0.5;KD40;AY;VL2222;KO218;SVI;"
SAVED = ["vl12345", "ac123456", "kp25.00", "ki0.50", "kd40.00", "vl2222", "ko218", "svi"]
MACRO = "AX;MR5;GO;"


def config(state: str) -> str:
    return f"""
[state]
file = "{state}"

[[board]]
name = "{BOARD}"
model = "PCIX-400"
link = "raw"
tcp = "127.0.0.1:0"
"""


def start(omsd: Omsd, state: str) -> Daemon:
    daemon = omsd(config=config(state), expect=1)
    # the state file is read before the endpoints are served; the log line comes first
    assert wait_for(lambda: "serving" in daemon.stderr), daemon.stderr
    return daemon


def replies(c: Conn, commands: str, n: int) -> list[str]:
    """Send ``commands`` (one line) and read ``n`` raw replies ``text<LF><CR>``."""
    c.send(commands.encode("ascii") + b"\n")
    out = []
    for _ in range(n):
        line = c.read_until(b"\n\r")
        out.append(line[:-2].decode("latin-1"))
    return out


def ask(c: Conn, query: str) -> str:
    (reply,) = replies(c, query, 1)
    return reply


def state_of(c: Conn) -> list[str]:
    return [ask(c, q) for q in QUERIES]


def sync(c: Conn) -> None:
    """Everything sent before has been executed by the board (the board answers in order)."""
    assert ask(c, "AX;?PM") in ("hn", "hf")


def lines_naming(daemon: Daemon, path: Path) -> list[str]:
    return [line for line in daemon.stderr.splitlines() if str(path) in line]


def stop(daemon: Daemon) -> None:
    assert daemon.stop(signal.SIGTERM) == 0, daemon.stderr[-2000:]
    assert "Traceback" not in daemon.stderr


def read_state(path: Path) -> dict[str, Any]:
    document = json.loads(path.read_text(encoding="utf-8"))
    assert isinstance(document, dict)
    return document


def saved_section(path: Path) -> dict[str, Any]:
    document = read_state(path)
    assert document["format"] == 1
    section = document["boards"][BOARD]
    assert isinstance(section, dict)
    return section


def test_ap_restart_rd_and_rf_round_trip(omsd: Omsd, tmp_path: Path) -> None:
    path = tmp_path / "omsd.state"
    first = start(omsd, "omsd.state")  # relative: to the configuration file's directory
    with first.connect() as c:
        factory = state_of(c)
        assert factory[2:5] == ["kp10.00", "ki0.04", "kd20.00"]  # E104, KI and KD pages
        assert factory[7] == "svn"
        replies(c, SETTINGS, 0)
        assert state_of(c) == SAVED
        replies(c, "AP;", 0)
        sync(c)
    stop(first)  # SIGTERM right after AP: the save is finished before the daemon exits

    section = saved_section(path)
    axes = section["defaults"]["axes"]
    assert (axes["X"]["VL"], axes["X"]["AC"], axes["Y"]["VL"]) == (12345, 123456, 2222)
    assert (axes["X"]["servo"]["kp"], axes["X"]["servo"]["ki"]) == (25, 0.5)
    assert (axes["X"]["servo"]["kd"], axes["Y"]["servo"]["ko"]) == (40, 218)
    assert axes["Y"]["servo"]["inverted"] is True
    assert axes["Z"]["VL"] == axes["T"]["VL"]  # the axes left alone are saved too
    assert section["macros"] == {}

    second = start(omsd, "omsd.state")
    assert lines_naming(second, path) == []  # a good file: nothing to say
    with second.connect() as c:
        assert state_of(c) == SAVED  # the power-up values are the archived ones
        assert ask(c, "AX;?PM") == "hf"  # the loop itself is not saved: HF at power-up
        replies(c, "AX;VL777;KP60;KI0;AY;KO-5;SVN;", 0)
        changed = state_of(c)
        assert changed[0] == "vl777" and changed[2] == "kp60.00" and changed[6] == "ko-5"
        replies(c, "RD;", 0)
        assert state_of(c) == SAVED
        before_rf = path.read_bytes()
        replies(c, "RF;", 0)
        assert state_of(c) == factory
        replies(c, "RD;", 0)
        assert state_of(c) == SAVED  # RF did not touch the flash ...
        replies(c, "RF;", 0)
        sync(c)
    stop(second)
    assert path.read_bytes() == before_rf  # ... nor the file

    third = start(omsd, "omsd.state")
    with third.connect() as c:
        assert state_of(c) == SAVED  # RF before the power cycle: the archived values again
        # "To restore the flash memory to factory default, the RF command must be issued
        # followed by the AP command"
        replies(c, "RF;AP;", 0)
        sync(c)
    stop(third)
    fourth = start(omsd, "omsd.state")
    with fourth.connect() as c:
        assert state_of(c) == factory


def test_ap_reaches_the_file_without_a_clean_stop(omsd: Omsd, tmp_path: Path) -> None:
    """AP writes flash when it is sent: the board's values survive a daemon that is killed
    (SIGKILL, no shutdown) once the file shows them."""
    path = tmp_path / "flash.json"
    first = start(omsd, str(path))
    with first.connect() as c:
        replies(c, SETTINGS + "AP;", 0)
        sync(c)

        def archived() -> bool:
            try:
                return bool(saved_section(path)["defaults"]["axes"]["X"]["VL"] == 12345)
            except (OSError, ValueError, KeyError, TypeError):
                return False

        assert wait_for(archived)
    first.kill()
    assert not first.running
    second = start(omsd, str(path))
    with second.connect() as c:
        assert state_of(c) == SAVED


def test_a_permanent_macro_survives_a_restart(omsd: Omsd, tmp_path: Path) -> None:
    """MD0 ... ^Z defines temporary macro 0; PT0,5 copies it to permanent macro 5 (flash). After
    a power cycle PM5 returns the text and MX5 runs it; the temporary macros are gone. PT does
    not archive the parameters: a VL changed before it is not a power-up value."""
    path = tmp_path / "macros.state"
    first = start(omsd, str(path))
    with first.connect() as c:
        factory_vl = ask(c, "AX;?VL")
        replies(c, f"MD0;{MACRO}^Z", 0)
        replies(c, "MD1;AY;MR9;GO;^Z", 0)
        assert ask(c, "PM0") == MACRO
        replies(c, "AX;VL4321;PT0,5;", 0)
        assert ask(c, "PM5") == MACRO
        sync(c)
    stop(first)
    section = saved_section(path)
    assert section["macros"] == {"5": MACRO}
    assert section["defaults"] is None  # never archived

    second = start(omsd, str(path))
    with second.connect() as c:
        assert ask(c, "AX;?VL") == factory_vl  # PT saved no parameters
        # an empty macro answers nothing: the next reply is the next query's
        assert replies(c, "PM0;PM1;PM5;AX;?PM", 2) == [MACRO, "hf"]
        assert ask(c, "AX;RP") == "0"
        replies(c, "MX5;", 0)
        assert wait_for(lambda: ask(c, "AX;RP") == "5")
        # AP after PT keeps the macro and adds the parameters
        replies(c, "AX;VL4321;AP;", 0)
        sync(c)
    stop(second)
    section = saved_section(path)
    assert section["macros"] == {"5": MACRO}
    assert section["defaults"]["axes"]["X"]["VL"] == 4321

    third = start(omsd, str(path))
    with third.connect() as c:
        assert replies(c, "PM5;AX;?VL", 2) == [MACRO, "vl4321"]


def test_a_corrupt_state_file_gives_factory_defaults_one_line_and_is_kept(
    omsd: Omsd, tmp_path: Path
) -> None:
    path = tmp_path / "omsd.state"
    reference = start(omsd, str(tmp_path / "fresh.state"))
    with reference.connect() as c:
        factory = state_of(c)
    stop(reference)

    garbage = b"\x00\xff\xfe{not json at all\n\x1a\x80"
    path.write_bytes(garbage)
    daemon = start(omsd, str(path))
    said = lines_naming(daemon, path)
    assert len(said) == 1, daemon.stderr
    assert "factory defaults" in said[0]
    with daemon.connect() as c:
        assert state_of(c) == factory
        assert daemon.running
        assert path.read_bytes() == garbage  # not overwritten by merely starting
        replies(c, SETTINGS + "AP;", 0)
        sync(c)

        kept = tmp_path / "omsd.state.corrupt"

        def saved() -> bool:
            try:
                return bool(saved_section(path)["defaults"]["axes"]["X"]["VL"] == 12345)
            except (OSError, ValueError, KeyError, TypeError):
                return False

        assert wait_for(saved)
        assert kept.read_bytes() == garbage
        assert state_of(c) == SAVED
    assert len(lines_naming(daemon, path)) == 1  # still the one line: the save was clean
    stop(daemon)

    again = start(omsd, str(path))
    assert lines_naming(again, path) == []
    with again.connect() as c:
        assert state_of(c) == SAVED


def test_a_missing_state_file_gives_factory_defaults_and_one_line(
    omsd: Omsd, tmp_path: Path
) -> None:
    path = tmp_path / "not" / "yet" / "omsd.state"
    daemon = start(omsd, str(path))
    said = lines_naming(daemon, path)
    assert len(said) == 1, daemon.stderr
    assert "factory defaults" in said[0]
    assert not path.exists()
    with daemon.connect() as c:
        state = state_of(c)
        assert state[2] == "kp10.00"
        assert daemon.running
        replies(c, "AX;KP33;AP;", 0)
        sync(c)
    stop(daemon)
    assert saved_section(path)["defaults"]["axes"]["X"]["servo"]["kp"] == 33
    assert not (path.parent / "omsd.state.corrupt").exists()  # nothing to keep aside
    again = start(omsd, str(path))
    assert lines_naming(again, path) == []
    with again.connect() as c:
        assert ask(c, "AX;?KP") == "kp33.00"
