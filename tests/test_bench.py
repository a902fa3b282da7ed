"""The benchmarks in CI: ``python -m bench --quick`` measures and prints every row.

No figure is judged here (the project has no timed assertions, and CI machines are shared and
slow): the test checks that each benchmark ran against the real daemon and printed a number for
every row of the table, with a verdict, or, for the rows that need what ``--quick`` does not
install (uvloop, Python 3.12 and 3.13), the reason it could not. The pieces the figures rest
on are checked directly: the baseline servers' answers (the replaying one must move exactly
the bytes omsd moved, the counting one answer once per request), the percentile and the
targets' verdicts.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # bench/ is a package of the repository, not of the install
    sys.path.insert(0, str(ROOT))

from bench.echo import Answer, Count  # noqa: E402
from bench.fidelity import RATE, done_after  # noqa: E402
from bench.latency import median, percentile  # noqa: E402
from bench.settings import QUICK  # noqa: E402
from bench.table import Row, Target, render, skipped  # noqa: E402
from bench.watch import NAMES as WATCH  # noqa: E402
from bench.web import NAMES as WEB  # noqa: E402


def latency_rows(kind: str) -> list[str]:
    echo = "Protocol echo" if kind == "tcp" else "add_reader echo"
    buffered = "BufferedProtocol" if kind == "tcp" else "os.readv"
    return [
        f"RP {kind}, median: omsd as users run it / {echo}",
        f"RP {kind}, p99: omsd as users run it / {echo}",
        f"RP {kind}, median: omsd view off / {echo}",
        f"RP {kind}, median: driver link / raw link (view off)",
        f"RP {kind}, median: default view / view off (the view's cost)",
        f"RP {kind}, median: {echo} / the floor (blocking, no loop)",
        f"RP {kind}, median: reused buffer ({buffered}) / {echo}",
        f"RP {kind}, median, uvloop: omsd as users run it / uvloop {echo}",
        f"RP {kind}, median: omsd as users run it, uvloop / asyncio's loop",
    ]


MANY = f"{QUICK.scale_boards:,} boards in one daemon"
MOST = max(QUICK.load_boards)
ROWS = [
    *latency_rows("tcp"),
    *latency_rows("pty"),
    "RP tcp, median, Python 3.12: omsd as users run it / Protocol echo",
    "RP tcp, median, Python 3.13: omsd as users run it / Protocol echo",
    "interpreter step in process: RP (PC48-4E) / dict dispatch",
    "interpreter step in process: QA (PC48-4E) / dict dispatch",
    "interpreter step in process: ?KP (PCIX-400) / dict dispatch",
    "interpreter step in process: RP (PC48-4E), another axis jogging / dict dispatch",
    "ten-minute move simulated on the manual clock (Harness)",
    "ten-minute jog and its stop simulated on the manual clock (Harness)",
    "pipelined RP, tcp, one board: omsd as users run it / count echo",
    "pipelined RP, tcp, one board: omsd view off / count echo",
    "mixed pipelined commands, raw link: omsd view off / replay echo",
    "idle cost, 8 boards x 8 axes",
    *(f"load cost, {n} board{'s' * (n > 1)} in motion, polled" for n in QUICK.load_boards),
    f"load cost, {MOST} boards polled, at rest",
    f"load cost, {MOST} boards polled, jogs alone",
    f"load cost, {MOST} boards: one queued move, CPU in omsd / in the engine alone",
    f"load cost, {MOST} boards: the board engine alone / omsd as users run it",
    f"load growth, CPU per poll, {MOST} vs 1 board(s)",
    f"load over time, CPU 2nd / 1st half, {MOST} boards",
    *WATCH,
    *WEB,
    f"{MANY}: ready, exec to last endpoint line / echo",
    f"{MANY}: resident memory / echo",
    f"{MANY}: memory of one board / echo's per TCP port and pty",
    f"{MANY}: idle CPU / echo",
    "timing fidelity, done marker, median |error|",
    "command, exec to exit: omsd models / python -c pass",
    "command, exec to exit: omsd ctl --help / python -c pass",
    "command, exec to exit: omsd --help / python -c pass",
    "start-up, exec to first TCP accept, one board as users run it / echo",
    *(
        f"isolation, {kind} ({link}) on one board: the other's worst RP / quiet"
        for kind, link in (
            ("flood", "driver"),
            ("flood", "raw"),
            ("never-reads", "driver"),
            ("never-reads", "raw"),
            ("garbage", "driver"),
            ("churn", "driver"),
            ("pty-flood", "driver"),
            ("slow-reader", "driver"),
        )
    ),
    "churn, tcp: connect, RP, close / echo",
    "churn, pty: open, RP, close / echo",
    "replay of a 10-minute recorded session",
]

MAY_BE_SKIPPED = {
    name
    for name in ROWS
    if "uvloop" in name
    or "Python 3.1" in name
    or (name in WEB and not os.environ.get("OMSD_NEED_CHROMIUM"))
}
"""Rows that need what --quick does not install (uvloop, other interpreters) or, outside CI, the
browser .ci/run installs: they say why."""

NO_BASELINE = {name for name in ROWS if "on the manual clock" in name}

NUMBER = r"-?[\d,]+(?:\.\d+)?(?:e-?\d+)?"


def table_rows(output: str) -> dict[str, list[str]]:
    rows: dict[str, list[str]] = {}
    for line in output.splitlines():
        if line.startswith("| ") and not line.startswith("| -"):
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            rows[cells[0]] = cells[1:]
    return rows


def bench(module: str, *args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    """``python -m MODULE ARGS...`` from the repository, its output captured."""
    return subprocess.run(
        [sys.executable, "-m", module, *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
    )


def test_quick_run_measures_and_prints_every_row() -> None:
    result = bench("bench", "--quick", timeout=300)
    report = f"stdout:\n{result.stdout}\nstderr:\n{result.stderr[-3000:]}"
    assert result.returncode == 0, report
    assert "machine: " in result.stdout, report
    rows = table_rows(result.stdout)
    assert list(rows)[1:] == ROWS, report  # the header first, then every row in order
    assert "placement: " in result.stdout and "event loop: " in result.stdout, report
    for name in ROWS:
        figure, baseline, _ratio, target, verdict = rows[name]
        if verdict == "not measured":
            assert name in MAY_BE_SKIPPED, f"{name}\n{report}"
            assert f"- {name}: not measured: " in result.stdout, f"{name}: no reason\n{report}"
            continue
        assert re.fullmatch(rf"{NUMBER} .+", figure), f"{name}: figure {figure!r}\n{report}"
        if name in NO_BASELINE:
            assert baseline == "—", f"{name}: baseline {baseline!r}\n{report}"
        else:
            assert re.fullmatch(rf"{NUMBER} .+", baseline), f"{name}: {baseline!r}\n{report}"
        assert verdict in ("ok", "MISSED", "info"), f"{name}: verdict {verdict!r}\n{report}"
        if target != "—":
            assert verdict != "info", f"{name}\n{report}"


@pytest.mark.parametrize("chunks", [[2] * 50, [1] * 100, [7, 13, 80], [100], [3, 97]])
def test_the_baseline_answers_with_exactly_the_bytes_given(chunks: list[int]) -> None:
    """Every ``every`` bytes in, the whole reply out, however the bytes are split."""
    reply = b"\n\r12345\n\r"
    answer = Answer(reply, every=2)
    out = b"".join(answer(b"x" * n) for n in chunks)
    assert out == reply * 50
    whole = bytes(range(256)) * 3
    stream = Answer(whole, every=100)
    got = b"".join(stream(b"x" * n) for n in chunks)
    assert got == whole


def test_the_baseline_echoes_without_a_reply() -> None:
    answer = Answer(None, 1)
    assert answer(b"AX RP") == b"AX RP"


@pytest.mark.parametrize("chunks", [[2] * 50, [1] * 100, [7, 13, 80], [100], [3, 97]])
def test_the_counting_baseline_answers_once_per_request(chunks: list[int]) -> None:
    """Pipelined requests of 2 bytes, however they are split: one reply each."""
    count = Count(b"\n\r0\n\r", every=2)
    out = b"".join(count(b"x" * n) for n in chunks)
    assert out == b"\n\r0\n\r" * 50


def test_percentiles_and_medians() -> None:
    samples = [float(x) for x in range(1, 101)]
    assert percentile(samples, 99) == 99.0
    assert percentile(samples, 50) == 50.0
    assert percentile([5.0], 99) == 5.0
    assert median([3.0, 1.0, 2.0]) == 2.0
    assert median([4.0, 1.0, 2.0, 3.0]) == 2.5


def test_verdicts() -> None:
    fast = Row("a", "µs", 30.0, 20.0, Target("ratio", "<=", 1.5))
    slow = Row("b", "µs", 40.0, 20.0, Target("ratio", "<=", 1.5))
    rate = Row("c", "cmd/s", 10.0, 100.0, Target("ratio", ">=", 0.3))
    absolute = Row("d", "ms", 1.9, 5.0, Target("figure", "<=", 2.0, "ms"))
    unmeasured = Row("e", "ms", None, None, Target("figure", "<=", 2.0, "ms"))
    info = Row("f", "% core", 1.0, 0.0)
    assert [r.verdict for r in (fast, slow, rate, absolute, unmeasured, info)] == [
        "ok",
        "MISSED",
        "MISSED",
        "ok",
        "NOT MEASURED",
        "info",
    ]
    assert info.ratio is None  # a zero baseline gives no ratio
    absent = skipped("g", "µs", Target("ratio", "<=", 1.1), "no python3.12 here")
    assert absent.verdict == "not measured" and "no python3.12 here" in absent.note
    text = render([fast, slow, info])
    assert "| a " in text and "1.50x" in text and "| f " in text


def test_the_expected_end_of_a_move_is_on_the_sample_grid() -> None:
    """PC48 §1.2/§1.3: a triangle of 2 sqrt(d/AC) seconds for a short move, rounded up to a
    tick, plus half a tick for the start."""
    d = 50
    duration = 2 * (d / 400_000) ** 0.5
    expected = done_after(d)
    ticks = expected * RATE - 0.5
    assert ticks == int(ticks)
    assert duration <= expected - 0.5 / RATE < duration + 1 / RATE


def test_instructions_per_poll_are_counted(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """``python -m bench.instructions`` (a developer's tool, not a row): callgrind's count of one
    board of the load, a short run and a longer one, the difference per poll."""
    import shutil

    from bench import instructions

    if shutil.which("valgrind") is None:
        pytest.skip("valgrind is not installed")
    monkeypatch.chdir(ROOT)
    monkeypatch.setattr(instructions, "SHORT", 0.3)
    monkeypatch.setattr(instructions, "LONG", 0.6)
    assert instructions.main(["at rest"]) == 0
    out = capsys.readouterr().out
    found = re.fullmatch(r"at rest +([\d,]+) instructions per poll\n", out)
    assert found is not None, out
    assert int(found[1].replace(",", "")) > 1000


def test_opcodes_per_poll_are_counted(capsys: pytest.CaptureFixture[str]) -> None:
    """``python -m bench.opcodes`` (a developer's tool, not a row): the daemon in the process,
    its loop's thread traced, the bytecodes per poll by file."""
    from bench import opcodes

    assert opcodes.main(["-n", "2", "-r", "3", "--period", "0.01", "--top", "3", "--lines"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("2 boards (at rest), 6 polls: bytecodes per poll\n"), out
    own = re.search(r"^ +([\d.]+)  the daemon's own path$", out, re.MULTILINE)
    assert own is not None, out
    assert float(own[1]) > 100
    assert "omsd/service.py:" in out


def test_an_unknown_variant_of_the_instruction_count_is_refused() -> None:
    result = bench("bench.instructions", "nope", timeout=60)
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1] == (
        "python -m bench.instructions: error: no variant 'nope' (of load, at rest, jogs alone)"
    )
