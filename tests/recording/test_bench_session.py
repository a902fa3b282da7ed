"""The benchmark's synthetic session (``bench/replay.py``) is a recording that replays with no
difference, as the benchmark requires (``python -m bench --only replay`` times it)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # bench/ is a package of the repository, not of the install
    sys.path.insert(0, str(ROOT))

from bench.replay import make_session, script  # noqa: E402
from omsd.recording.replay import replay_file  # noqa: E402


def test_the_benchmarks_session_replays_with_no_difference(tmp_path: Path) -> None:
    path = tmp_path / "session.jsonl"
    chunks = make_session(path, minutes=1)
    assert chunks == len(script(1)) == 602
    result = replay_file(path)
    assert result.ok, result.report()
    assert result.counts.events == 5 and result.counts.answers > 580
