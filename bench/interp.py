"""In process, no I/O: one interpreter step for a bare query, and long motion on the manual clock.

* Interpreter step (issue 16): a board of :class:`omsd.board.harness.Harness` is given one bare
  query at a time, as the daemon gives it what a client wrote (``board.receive`` then
  ``board.take_output``, the two calls of ``Harness.send``): ``RP`` and ``QA`` to a PC48-4E,
  ``?KP`` to a PCIX-400. Nanoseconds per command, the best of :data:`REPEATS` rounds. The
  baseline is the least a Python interpreter of those queries can do: a dict from the command's
  bytes to a function that formats the reply, and a list for the output. Target: <= 1 µs. The
  boards are at rest, so they answer from the replies they keep (``Board._reports_at_rest``);
  an info row gives ``RP`` with another axis jogging, where every report is run.
* Motion on the manual clock (moved here from ``tests/board/test_motion.py``, which now counts
  deadlines instead of timing them): a ten-minute move (``VL1000 AC10000 MR600000``) and a
  ten-minute jog then ``ST``, simulated deadline by deadline (``Harness.until``). The card's
  2,048 samples a second would be 1.2 million steps; the engine visits a handful of deadlines.
  Wall time; target: <= 1 s (the bound the tests used to assert).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from bench.settings import Settings
from bench.table import Row, Target

REPEATS = 5
QUERIES = (("RP", "PC48-4E"), ("QA", "PC48-4E"), ("?KP", "PCIX-400"))


def per_command(step: Callable[[], object], n: int) -> float:
    """Seconds per call of ``step``, the best of :data:`REPEATS` rounds of ``n / REPEATS``."""
    rounds = max(1, n // REPEATS)
    best = float("inf")
    clock = time.perf_counter
    for _ in range(REPEATS):
        t0 = clock()
        for _ in range(rounds):
            step()
        best = min(best, (clock() - t0) / rounds)
    return best


def omsd_step(command: str, model: str, setup: str = "") -> Callable[[], object]:
    from omsd.board.harness import Harness  # only this benchmark needs omsd's engine

    h = Harness(model)
    if setup:
        h.send(setup)
    data = command.encode()
    first = h.send(data)
    if not first or b"#" in first:
        raise RuntimeError(f"{model}: {command} answered {first!r}")
    board = h.board
    receive, take = board.receive, board.take_output

    def step() -> object:
        receive(data, 0.0)
        return take()

    return step


def baseline_step(command: str) -> Callable[[], object]:
    position = [0]
    table: dict[bytes, Callable[[], bytes]] = {
        b"RP": lambda: b"\n\r%d\n\r" % position[0],
        b"QA": lambda: b"\n\r\rPNNN\n\r\r",
        b"?KP": lambda: b"kp%.2f\n\r" % 10.0,
    }
    out: list[bytes] = []
    data = command.encode()

    def step() -> object:
        out.append(table[data]())
        taken = out[:]
        out.clear()
        return taken

    return step


def motion() -> tuple[float, float]:
    """Wall seconds: a ten-minute move to its end; a ten-minute jog, then its stop."""
    from omsd.board.harness import Harness

    h = Harness("PC48-4")
    t0 = time.perf_counter()
    h.send("VL1000 AC10000 MR600000 GO ID")
    h.until(700.0)
    move = time.perf_counter() - t0
    if h.position() != 600_000:
        raise RuntimeError(f"the move ended at {h.position()}, not 600000")
    h = Harness("PC48-4")
    t0 = time.perf_counter()
    h.send("JG10000\r")
    h.until(600.0)
    h.send("ST")
    h.until(700.0)
    jog = time.perf_counter() - t0
    if h.position() != 6_000_000:
        raise RuntimeError(f"the jog stopped at {h.position()}, not 6000000")
    return move, jog


def run(settings: Settings, directory: Path) -> list[Row]:
    n = settings.interp_commands
    rows = []
    for command, model in QUERIES:
        ours = per_command(omsd_step(command, model), n)
        theirs = per_command(baseline_step(command), n)
        rows.append(
            Row(
                f"interpreter step in process: {command} ({model}) / dict dispatch",
                "ns",
                ours * 1e9,
                theirs * 1e9,
                Target("figure", "<=", 1000.0, "ns"),
                (
                    f"board.receive + board.take_output per command, best of {REPEATS} rounds"
                    f" of {max(1, n // REPEATS):,}"
                )
                if not rows
                else "",
            )
        )
    # the same with another axis jogging: nothing may be kept (an answer could depend on the
    # time), every report is run (the at-rest fast path all the same: the jog's next event is
    # its switch, far away)
    ours = per_command(omsd_step("RP", "PC48-4E", "AY JG2000 AX"), n)
    theirs = per_command(baseline_step("RP"), n)
    rows.append(
        Row(
            "interpreter step in process: RP (PC48-4E), another axis jogging / dict dispatch",
            "ns",
            ours * 1e9,
            theirs * 1e9,
            None,
            "no reply kept while an axis moves: the report is run each time",
        )
    )
    times = [motion() for _ in range(3)]
    move, jog = min(t[0] for t in times), min(t[1] for t in times)
    rows += [
        Row(
            "ten-minute move simulated on the manual clock (Harness)",
            "ms",
            move * 1e3,
            None,
            Target("figure", "<=", 1000.0, "ms"),
            "VL1000 AC10000 MR600000 GO ID, then Harness.until(700); best of 3",
        ),
        Row(
            "ten-minute jog and its stop simulated on the manual clock (Harness)",
            "ms",
            jog * 1e3,
            None,
            Target("figure", "<=", 1000.0, "ms"),
            "JG10000 for 600 s, ST, until 700 s; best of 3",
        ),
    ]
    return rows
