"""What the card said, cut into the pieces a replay compares: replies and markers.

Both sides of a replay, the card's recorded bytes and the emulator's, are one byte stream each,
cut into *units* the same way, by the framing of the link the card was spoken to through:

* **The DOS driver link** (PC48 manual §7.3): the driver "strips off the LF and CR's and allows
  the user to define a character to show the end of the string" (§7.3.2, ``E:XX``), so a reply
  is its text and the end character. Its status markers (§7.3.3) are units of their own: "a #
  symbol followed by the 'E:' specified end character" (command error), "an @ character
  followed by the end character" (limit), "a $ and the end character" (encoder slip), "an !
  into the data stream followed by the byte read from the done flag register of the board,
  followed by the end character" (done): three bytes whatever the middle one is, which may be
  the end character itself. "If the board is returning a message when an interrupt occurs, the
  interrupt symbol will be delayed until after the end of the message string": markers never
  split a reply, so a marker is recognised only where a unit begins.
* **The raw link** (the board's own stream): replies in the framing of the model's dialect
  (:class:`omsd.engine.extensions.Framing`): "surrounded by line feeds and carriage returns"
  on the PC48 family, ``<LF><CR>`` + text + ``<LF><CR>``, and "one line feed and two carriage
  returns on each end" for an axis status (PC48 §6.13, RA); text then ``<LF><CR>`` on the PCIx
  (its manual prints every reply as text and ``<LF>``). A command error is the lone ``#`` the
  raw link shows (``docs/decisions.md``); anything else (the board's echo, with ``EN``) is cut
  before the next reply or ``#``.

The done, limit and slip markers happen when the motion does, not in answer to a command: they
are *events*, compared with the card's by their time (:mod:`omsd.recording.compare`); the rest
(replies, ``#``, echo) are *answers*, which come in the order of the host's commands. The raw link
shows no events (they are the status register's, which the stream does not carry).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from omsd.engine.extensions import Framing

DONE, LIMIT, SLIP, ERROR = 0x21, 0x40, 0x24, 0x23  # ! @ $ #

#: ``(start, end, event)``: a unit is ``data[start:end]``; ``event``: a done, limit or slip marker.
Cut = tuple[int, int, bool]
Splitter = Callable[[bytes], list[Cut]]


@dataclass(frozen=True, slots=True)
class Unit:
    """One reply or marker of one side. ``time``: when it was sent (seconds of the session);
    ``command``: the index of the host chunk it follows (-1: none yet); ``speed`` and
    ``accel``: on the emulator's side, the largest speed (steps/s) and acceleration (steps/s²)
    of any axis then (:func:`omsd.recording.emulate.motion_at`), 0 at rest."""

    time: float
    data: bytes
    event: bool
    command: int
    speed: float = 0.0
    accel: float = 0.0


def driver_splitter(eos: int) -> Splitter:
    """Cuts a driver link's stream (see the module text)."""

    def split(data: bytes) -> list[Cut]:
        cuts: list[Cut] = []
        n = len(data)
        i = 0
        while i < n:
            b = data[i]
            if b == DONE and i + 2 < n and data[i + 2] == eos:
                cuts.append((i, i + 3, True))
                i += 3
                continue
            if b in (LIMIT, SLIP) and i + 1 < n and data[i + 1] == eos:
                cuts.append((i, i + 2, True))
                i += 2
                continue
            j = data.find(eos, i)
            end = n if j < 0 else j + 1
            cuts.append((i, end, False))
            i = end
        return cuts

    return split


def raw_splitter(framing: Framing) -> Splitter:
    """Cuts a raw link's stream in the framing of the model's dialect (see the module text)."""
    # the longest opening first: a status (<LF><CR><CR>) before a value (<LF><CR>)
    frames = sorted({framing.value, framing.status}, key=lambda f: -len(f[0]))
    openings = [f for f in frames if f[0]]
    trailing = [f[1] for f in frames if not f[0] and f[1]]
    line_ends = b"\n\r"

    def framed(data: bytes, i: int) -> int:
        """The end of a framed reply that begins at ``i``, or -1."""
        for before, after in openings:
            if data.startswith(before, i):
                start = i + len(before)
                j = start
                while j < len(data) and data[j] not in line_ends:
                    j += 1
                if data.startswith(after, j):
                    return j + len(after)
        return -1

    def split(data: bytes) -> list[Cut]:
        cuts: list[Cut] = []
        n = len(data)
        i = 0
        while i < n:
            if data[i] == ERROR:
                cuts.append((i, i + 1, False))
                i += 1
                continue
            end = framed(data, i) if openings else -1
            if end < 0 and trailing:
                # text then its ending: up to the first ending (or a '#': a command error)
                best = -1
                for after in trailing:
                    j = data.find(after, i)
                    if j >= 0 and (best < 0 or j + len(after) < best):
                        best = j + len(after)
                hash_at = data.find(b"#", i)
                if best >= 0 and not (0 <= hash_at < best - 1):
                    end = best
            if end < 0:
                # echo or anything else: up to where a reply or a '#' may begin
                j = i + 1
                while j < n and data[j] != ERROR and data[j] != 0x0A:
                    j += 1
                end = j
            cuts.append((i, end, False))
            i = end
        return cuts

    return split


def splitter(link: str, eos: int, framing: Framing) -> Splitter:
    """The splitter of a link: ``driver`` with its end character, ``raw`` in ``framing``."""
    return driver_splitter(eos) if link == "driver" else raw_splitter(framing)


def cut(
    pieces: list[tuple[float, bytes, int, float, float]],
    split: Splitter,
    char_time: float = 0.0,
) -> list[Unit]:
    """The units of a stream given as pieces ``(time, data, command, speed, accel)`` in order.
    A unit's time, command, speed and acceleration are those of the piece its first byte is in;
    with ``char_time`` (a serial line's seconds per character) each piece's time is when its
    last byte arrived, and a unit's time is when its first byte left the card: that much
    earlier per byte from it to the piece's end, and one character more."""
    data = b"".join(p[1] for p in pieces)
    ends: list[int] = []
    total = 0
    for piece in pieces:
        total += len(piece[1])
        ends.append(total)
    units: list[Unit] = []
    k = 0
    for start, end, event in split(data):
        while ends[k] <= start:
            k += 1
        t, _, command, speed, accel = pieces[k]
        if char_time:
            t -= (ends[k] - start) * char_time
        units.append(Unit(t, data[start:end], event, command, speed, accel))
    return units


__all__ = ["Cut", "Splitter", "Unit", "cut", "driver_splitter", "raw_splitter", "splitter"]
