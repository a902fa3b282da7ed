"""A reply is in the traffic log's file before its client can have it.

The service holds the log while it handles a turn (a client's bytes, a deadline) and writes the
turn's lines (``TrafficLog.write_kept``) after it has made the replies and before it sends them.
So a daemon killed at any instant (SIGKILL: nothing runs after) has logged every byte any client
got; ``tests/robustness/test_signals.py::test_sigkill_mid_traffic`` shows it on a real daemon,
this at every single send, on random command streams, both on the clean cable's fast path and
through ``_deliver`` (the faulty cable's way with no fault on it).
"""

from __future__ import annotations

import io
import json
import pathlib
import random

import pytest
from test_io_fast_paths import (
    SEPARATORS,
    WORDS,
    Client,
    chunks,
    config,
    manual_service,
    settle,
    step,
)

from omsd.service import BoardService
from omsd.telemetry.traffic import TrafficLog

#: The fast path test's words without the driver's waits (``!`` and ``@`` wait for a done that
#: a random stream may never bring, and a wait holds the other client off the board).
SAID = [w for w in WORDS if not w.startswith((b"!", b"@")) and w not in (b"\x04", b"\x19")]


def stream(rnd: random.Random, n: int) -> bytes:
    return b"".join(rnd.choice(SAID) + rnd.choice(SEPARATORS[:4]) for _ in range(n))


def logged_out(path: pathlib.Path, label: str) -> bytes:
    """Every byte the file says went out to ``label``, in order (read as the file is now)."""
    out = bytearray()
    for line in path.read_bytes().splitlines():
        record = json.loads(line)
        if record["kind"] == "traffic" and record["endpoint"] == label and record["dir"] == "out":
            out += record["data"].encode("latin-1")
    return bytes(out)


class Checking(Client):
    """A client that, at every send, reads the log file: what it has got, this too, is there."""

    def __init__(self, service: BoardService, label: str, path: pathlib.Path) -> None:
        super().__init__(service, label)
        self.path = path
        self.sends = 0

    def send(self, data: bytes) -> None:
        super().send(data)
        self.sends += 1
        assert logged_out(self.path, self.label).startswith(bytes(self.got)), (
            f"{self.label} got {bytes(self.got)[-40:]!r} before the log had it"
        )


@pytest.mark.parametrize("straight", [False, True], ids=["clean", "deliver"])
@pytest.mark.parametrize("link", ["raw", "driver"])
@pytest.mark.parametrize("seed", range(3))
async def test_every_reply_is_in_the_file_before_it_is_sent(
    tmp_path: pathlib.Path, link: str, seed: int, straight: bool
) -> None:
    path = tmp_path / "traffic.jsonl"
    log = TrafficLog("off", file=path, stream=io.StringIO(), env={})
    service = manual_service(config(tmp_path, link), log, straight=straight)
    clients = [Checking(service, f"c{i}", path) for i in range(2)]
    rnd = random.Random(seed)
    for _ in range(40):
        who = clients[rnd.randrange(2)]
        for piece in chunks(rnd, stream(rnd, rnd.randrange(1, 6))):
            who.write(piece)
            await settle()
        step(service, rnd.choice([0.0, 0.001, 0.02, 0.3, 1.5]))  # done markers, events
        await settle()
    assert sum(c.sends for c in clients) > 20
    for client in clients:  # and nothing more was logged than was sent
        assert logged_out(path, client.label) == bytes(client.got)
    log.close()
    service.close()
