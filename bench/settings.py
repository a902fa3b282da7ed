"""How much of each benchmark to run: the full run (a few minutes) or ``--quick`` (seconds)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Settings:
    quick: bool
    latency_samples: int  # round trips per server per transport
    versions_samples: int  # round trips per server under Python 3.12 and 3.13 (0: not run)
    interp_commands: int  # in-process interpreter steps per command timed
    pipeline_replies: int  # pipelined RP requests in one stream
    pipeline_runs: int  # runs per server (the best is kept)
    throughput_commands: int  # commands in the mixed pipelined stream
    throughput_runs: int  # runs per server (the best is kept)
    idle_seconds: float  # CPU measurement window, idle boards
    load_seconds: float  # CPU measurement window, boards in motion
    load_settle: float  # seconds of traffic before the window opens
    load_boards: tuple[int, ...]  # board counts of the load benchmark
    watch_seconds: float  # each window of the subscription benchmark (omsd top open, or not)
    scale_boards: int  # boards in one daemon for ready time, memory and idle CPU
    scale_idle_seconds: float  # CPU measurement window of those boards, idle
    fidelity_moves: int  # moves timed on the real clock
    fidelity_longest: int  # steps of the longest of them
    startup_runs: int  # starts per server (the median is kept)
    cli_runs: int  # runs of each command (the median is kept)
    isolation_seconds: float  # seconds of each abuse
    churn_cycles: int  # connect/disconnect cycles per server and transport
    peer_samples: int  # round trips per peer (each also capped at PEER_SECONDS)
    fast: bool = False  # --fast: install uvloop if need be and measure its rows


FULL = Settings(
    quick=False,
    latency_samples=10_000,
    versions_samples=3_000,
    interp_commands=200_000,
    pipeline_replies=500_000,
    pipeline_runs=3,
    throughput_commands=100_000,
    throughput_runs=2,
    idle_seconds=10.0,
    load_seconds=10.0,
    load_settle=1.0,
    load_boards=(1, 8, 32, 128),
    watch_seconds=10.0,
    scale_boards=1000,
    scale_idle_seconds=5.0,
    fidelity_moves=20,
    fidelity_longest=50_000,
    startup_runs=11,
    cli_runs=11,
    isolation_seconds=2.0,
    churn_cycles=300,
    peer_samples=3_000,
)

QUICK = Settings(
    quick=True,
    latency_samples=100,
    versions_samples=0,
    interp_commands=5_000,
    pipeline_replies=20_000,
    pipeline_runs=1,
    throughput_commands=5_000,
    throughput_runs=1,
    idle_seconds=0.5,
    load_seconds=0.6,
    load_settle=0.2,
    load_boards=(1, 8, 128),
    watch_seconds=1.0,
    scale_boards=200,
    scale_idle_seconds=0.5,
    fidelity_moves=3,
    fidelity_longest=5_000,
    startup_runs=2,
    cli_runs=2,
    isolation_seconds=0.3,
    churn_cycles=20,
    peer_samples=100,
)
