"""EPICS ``drvOmsPC68`` traffic replayed against the real daemon's raw link, as a PC48-4.

``shared/interop/README.md`` on what this client needs: "Replies use the board's native framing:
``\\n\\r<value>\\n\\r``, and ``\\n\\r\\r<status>\\n\\r\\r`` for RA/QA/RI/QI/EA. Several replies may
follow one line (``QA RP`` gives two framed replies)." "A command error must be visible in the
stream as a lone ``#``. The client learns that an axis has no encoder (``EA``) or no servo loop
(``?KP``) from that ``#``." "It must not receive ``!``, ``@`` or ``$`` bytes on this link: its
parser counts them as header bytes and then eats the first byte of the next reply."

What the client sent (the ``RX`` side of ``epics-drvOmsPC68.trace``) is copied below, so the test
runs without ``shared/``; when the trace is there, the copy is checked against it, and the shapes
expected here against the shapes of the capture stub's ``TX`` answers. The replay keeps the
client's relative timing but shortens the long pauses of the recording.
"""

from __future__ import annotations

import ast
import re
import time
from pathlib import Path

import pytest

from .process import Conn, Omsd

TRACE = Path(__file__).resolve().parents[3] / "shared" / "interop" / "epics-drvOmsPC68.trace"

# The replies a line gets, in order: W the WY value, P4 a position per axis (AA mode), P1 one
# position, S one axis's status (QA), # a command error.
REPLY_SHAPES: dict[str, tuple[str, bytes]] = {
    "W": ("value", rb"PC48 ver [^\n\r]+"),
    "P4": ("value", rb"-?\d+,-?\d+,-?\d+,-?\d+"),
    "P1": ("value", rb"-?\d+"),
    "S": ("status", rb"[PM][DN][LN][HN]"),
    "#": ("#", b""),
}

# (seconds since the client connected, what it sent, the replies it gets)
RX: list[tuple[float, bytes, tuple[str, ...]]] = [
    (0.000, b"WY", ("W",)),
    (0.000, b"EFICAA SAAA RP", ("P4",)),
    (0.001, b"AX EA", ("#",)),
    (0.001, b"AX ?KP", ("#",)),
    (0.001, b"AY EA", ("#",)),
    (0.001, b"AY ?KP", ("#",)),
    (0.001, b"AZ EA", ("#",)),
    (0.001, b"AZ ?KP", ("#",)),
    (0.001, b"AT EA", ("#",)),
    (0.001, b"AT ?KP", ("#",)),
    (0.001, b"AA RP", ("P4",)),
    (0.001, b"AX QA RP", ("S", "P1")),
    (0.001, b"AY QA RP", ("S", "P1")),
    (0.001, b"AZ QA RP", ("S", "P1")),
    (0.001, b"AT QA RP", ("S", "P1")),
    (4.987, b"AX  VL1000 VB100 AC1800 MA600 GD ID", ()),
    (5.087, b"AX QA RP", ("S", "P1")),
    (5.187, b"AX QA RP", ("S", "P1")),
    (8.988, b"AX  VB100 AC2000 CA JG-1000;", ()),
    (9.088, b"AX QA RP", ("S", "P1")),
    (9.990, b"AX QA RP", ("S", "P1")),
    (11.992, b"AX  VL101 VB100 AC200 CA HM0 GD ID", ()),
    (12.091, b"AX QA RP", ("S", "P1")),
    (12.993, b"AX  AC1800 ST ID", ()),
    (14.994, b"AX  LP600AX QA RP", ("S", "P1")),
]

MAX_PAUSE = 0.3  # seconds: longer pauses of the recording are shortened to this
MAX_LATENCY = 0.5  # seconds to the first byte of a reply (the client wants ~3 ms; CI is slow)


def split_frames(data: bytes) -> tuple[list[tuple[str, bytes]], bytes]:
    """The whole frames at the start of ``data`` (kind and payload) and what is left over.
    Anything that cannot begin a frame is an error: no stray byte may sit between replies."""
    frames: list[tuple[str, bytes]] = []
    i = 0
    while i < len(data):
        rest = data[i:]
        if rest[:1] == b"#":
            frames.append(("#", b""))
            i += 1
        elif rest.startswith(b"\n\r\r"):
            end = rest.find(b"\n\r\r", 3)
            if end < 0:
                break
            frames.append(("status", rest[3:end]))
            i += end + 3
        elif rest.startswith(b"\n\r"):
            if len(rest) < 3:
                break  # a value or a status frame: not known yet
            end = rest.find(b"\n\r", 2)
            if end < 0:
                break
            frames.append(("value", rest[2:end]))
            i += end + 2
        elif rest == b"\n":
            break
        else:
            raise AssertionError(f"not a frame: {rest!r} (after {data[:i]!r})")
    return frames, data[i:]


def check_shape(frame: tuple[str, bytes], shape: str, line: bytes) -> None:
    kind, pattern = REPLY_SHAPES[shape]
    assert frame[0] == kind, f"{line!r}: expected a {kind} frame ({shape}), got {frame!r}"
    assert re.fullmatch(pattern, frame[1]), f"{line!r}: {frame[1]!r} is not {shape}"


def recorded_rx() -> list[tuple[float, bytes, list[bytes]]]:
    """The trace file's RX lines, with the TX answers that followed each."""
    lines = TRACE.read_text().splitlines()
    start = float(lines[0].split()[0])
    out: list[tuple[float, bytes, list[bytes]]] = []
    for line in lines:
        stamp, kind, *rest = line.split(" ", 2)
        if kind == "RX":
            out.append((float(stamp) - start, ast.literal_eval(rest[0]), []))
        elif kind == "TX":
            out[-1][2].append(ast.literal_eval(rest[0]))
    return out


@pytest.mark.skipif(
    not TRACE.exists(),
    reason=f"{TRACE} is absent: the interop traces are kept in ../shared beside the repository,"
    " not in a clone of it",
)
def test_the_copy_is_the_trace() -> None:
    recorded = recorded_rx()
    assert [data for _, data, _ in recorded] == [data for _, data, _ in RX]
    for (t, _, _), (copied, _, _) in zip(recorded, RX, strict=True):
        assert t == pytest.approx(copied, abs=0.001)
    # the replies expected here have the shape of what the client accepted in the recording
    for (_, data, answers), (_, _, shapes) in zip(recorded, RX, strict=True):
        frames, rest = split_frames(b"".join(answers))
        assert rest == b""
        assert [kind for kind, _ in frames] == [REPLY_SHAPES[s][0] for s in shapes], data
        for frame, shape in zip(frames, shapes, strict=True):
            if shape != "W":  # the stub's WY is a PC68's
                check_shape(frame, shape, data)


def test_epics_drvomspc68_trace_through_the_raw_link(omsd: Omsd) -> None:
    daemon = omsd("--board", "PC48-4", "--link", "raw", "--tcp", "127.0.0.1:0")
    (endpoint,) = daemon.endpoints
    assert (endpoint.model, endpoint.link) == ("PC48-4", "raw")
    received = bytearray()
    latencies: list[float] = []
    with daemon.connect() as c:
        start = time.monotonic()
        at = 0.0  # the replay's clock: the recording's, with long pauses shortened
        previous = 0.0
        for t, line, shapes in RX:
            at += min(t - previous, MAX_PAUSE)
            previous = t
            while (left := start + at - time.monotonic()) > 0:
                time.sleep(min(left, 0.01))
            sent = time.monotonic()
            c.send(line)
            if not shapes:
                continue
            frames, first = read_frames(c, line, len(shapes), received)
            latencies.append(first - sent)
            for frame, shape in zip(frames, shapes, strict=True):
                check_shape(frame, shape, line)
        # a move of another axis that surely ends here: its done flag shows in QA (the way
        # drvOmsPC68 learns it), never as a "!" in the stream
        c.send(b"AY VL20000 MR200 GO ID")
        deadline = time.monotonic() + 5.0
        while True:
            c.send(b"AY QA")
            (status,), _ = read_frames(c, b"AY QA", 1, received)
            check_shape(status, "S", b"AY QA")
            if status[1][1:2] == b"D" or time.monotonic() > deadline:
                break
            time.sleep(0.01)
        assert status[1][1:2] == b"D", "the Y move never reported done"
        received += c.quiet(0.1)
    assert not set(received) & set(b"!@$"), bytes(received)
    assert max(latencies) < MAX_LATENCY, latencies


def read_frames(
    c: Conn, line: bytes, count: int, received: bytearray
) -> tuple[list[tuple[str, bytes]], float]:
    """Read exactly ``count`` whole frames, and when the first byte came; a byte that does not
    belong to a frame fails at once."""
    data = bytearray()
    first = 0.0
    while True:
        frames, rest = split_frames(bytes(data))
        if len(frames) == count:
            assert rest == b"", f"{line!r}: extra bytes {bytes(data)!r}"
            return frames, first
        byte = c.read(1)
        if not data:
            first = time.monotonic()
        data += byte
        received += byte
