"""The benchmarks in CI: ``python -m bench --quick`` measures and prints every row.

No figure is judged here (the project has no timed assertions, and CI machines are shared and
slow): the test checks that each benchmark ran against the real daemon and printed a number for
every row of the table, with a verdict. The pieces the figures rest on are checked directly:
the baseline server's proportional answer (it must move exactly the bytes omsd moved), the
percentile and the targets' verdicts.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # bench/ is a package of the repository, not of the install
    sys.path.insert(0, str(ROOT))

from bench.echo import Answer  # noqa: E402
from bench.fidelity import RATE, done_after  # noqa: E402
from bench.latency import median, percentile  # noqa: E402
from bench.table import Row, Target, render  # noqa: E402

ROWS = [
    "latency RP tcp, median",
    "latency RP tcp, p99",
    "latency RP pty, median",
    "latency RP pty, p99",
    "throughput, pipelined commands, raw link",
    "idle cost, 8 boards x 8 axes",
    "load cost, 1 board in motion, polled",
    "load cost, 8 boards in motion, polled",
    "load cost, 32 boards in motion, polled",
    "load growth, CPU per poll, 32 vs 1 board(s)",
    "load over time, CPU 2nd / 1st half, 32 boards",
    "timing fidelity, done marker, median |error|",
    "start-up, exec to first TCP accept",
]

NUMBER = r"-?[\d,]+(?:\.\d+)?(?:e-?\d+)?"


def table_rows(output: str) -> dict[str, list[str]]:
    rows: dict[str, list[str]] = {}
    for line in output.splitlines():
        if line.startswith("| ") and not line.startswith("| -"):
            cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
            rows[cells[0]] = cells[1:]
    return rows


def test_quick_run_measures_and_prints_every_row() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "bench", "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        stdin=subprocess.DEVNULL,
    )
    report = f"stdout:\n{result.stdout}\nstderr:\n{result.stderr[-3000:]}"
    assert result.returncode == 0, report
    assert "machine: " in result.stdout, report
    rows = table_rows(result.stdout)
    assert list(rows)[1:] == ROWS, report  # the header first, then every row in order
    for name in ROWS:
        figure, baseline, _ratio, target, verdict = rows[name]
        assert re.fullmatch(rf"{NUMBER} .+", figure), f"{name}: figure {figure!r}\n{report}"
        assert re.fullmatch(rf"{NUMBER} .+", baseline), f"{name}: baseline {baseline!r}\n{report}"
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
