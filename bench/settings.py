"""How much of each benchmark to run: the full run (a minute or two) or ``--quick`` (seconds)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Settings:
    quick: bool
    latency_samples: int  # round trips per transport per server
    throughput_commands: int  # commands in the pipelined stream
    throughput_runs: int  # runs per server (the best is kept)
    idle_seconds: float  # CPU measurement window, idle boards
    load_seconds: float  # CPU measurement window, boards in motion
    load_settle: float  # seconds of traffic before the window opens
    load_boards: tuple[int, ...]  # board counts of the load benchmark
    fidelity_moves: int  # moves timed on the real clock
    fidelity_longest: int  # steps of the longest of them
    startup_runs: int  # starts per server (the median is kept)


FULL = Settings(
    quick=False,
    latency_samples=5000,
    throughput_commands=100_000,
    throughput_runs=2,
    idle_seconds=10.0,
    load_seconds=10.0,
    load_settle=1.0,
    load_boards=(1, 8, 32),
    fidelity_moves=20,
    fidelity_longest=50_000,
    startup_runs=7,
)

QUICK = Settings(
    quick=True,
    latency_samples=100,
    throughput_commands=5_000,
    throughput_runs=1,
    idle_seconds=0.5,
    load_seconds=0.6,
    load_settle=0.2,
    load_boards=(1, 8, 32),
    fidelity_moves=3,
    fidelity_longest=5_000,
    startup_runs=2,
)
