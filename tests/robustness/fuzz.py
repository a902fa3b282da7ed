"""The fuzzing host: a program writing random input to a board through a link, on a manual clock,
checking after every step that what reaches it is what the manuals say it should be.

``tests/board/test_bad_input.py`` feeds the bare engine (hypothesis, a few hundred examples, the
PC48 and PCIx languages). This goes through the links a client really talks to, for every
personality, at the volume the issue asks for (10^6 inputs in the long pass), with seeded
``random`` so a failure names the seed, the session and the inputs that reproduce it.

What a link must make of the board's output (the oracle, :meth:`FuzzHost.check_output`):

* the raw link (``omsd/link/raw.py``): the board's own bytes unchanged; on the PC48 family "A
  command error must be visible in the stream as a lone ``#``", on the PCIx a command error
  sends nothing (it sets CMD_S, PCIx §3.9), and the client "must not receive ``!``, ``@`` or
  ``$`` bytes on this link" (``shared/interop/README.md``, quoted in the module);
* the driver link, PC48 manual §7.3.2 and §7.3.3: a reply's "LF and CR's" stripped and the end
  character after it; "When a command error occurs it places a # symbol followed by the 'E:'
  specified end character"; "A limit interrupt causes an @ character followed by the end
  character"; slip "a $ and the end character"; "A DONE interrupt will place an ! into the data
  stream followed by the byte read from the done flag register of the board, followed by the end
  character" (any byte; completions on one sample are one interrupt, so a second ``DoneEvent`` of
  the same instant may give no marker).

Each link must also hand on every board event (the traffic log's ``[done X]``,
``[command error]`` ...) exactly once.

Where the manuals are silent, choices made here:

* **Wait characters that are never released.** The driver holds everything after a ``!`` until
  a DONE interrupt and after a ``@`` until a limit (§7.3.4); the manual gives no time-out and no
  other way out. Random input often ends inside such a wait with nothing left to release it; the
  host then does what a PC user would do, reloads the driver (a fresh :class:`DriverLink` on the
  same board, whose state is kept). :attr:`FuzzHost.reloads` counts these.
* **Control-D that cannot get in.** "Control-D ... may clear this condition if the input character
  queue is not also filled" (PC48 §6.2): with a queue full of a move that lasts days and the 124
  characters of input behind it, Control-D waits like any character. The host waits
  :data:`KILL_PATIENCE` simulated seconds, then switches the card off and on
  (:meth:`Board.power_cycle`); :attr:`FuzzHost.power_cycles` counts these.
"""

from __future__ import annotations

import random
import re
import signal
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import FrameType

from omsd.board import Board, CommandErrorEvent, DoneEvent, LimitEvent, Reply, SlipEvent
from omsd.board.events import Output
from omsd.engine.axis import Motion
from omsd.engine.registers import CMD_S
from omsd.link import DriverLink, RawLink
from omsd.link.base import message_first
from omsd.models import MODELS, Model

PATIENCE = 5.0
"""Simulated seconds a host waits for the board to take a byte of an input before it drops the
rest (a write time-out)."""

KILL_PATIENCE = 30.0
"""Simulated seconds a host waits for its Control-D to get in before it switches the board off
and on."""

MAX_SAME_INSTANT = 200
"""Deadlines a board may report for the same instant in a row before it counts as stuck (the
daemon's service would call it again and again at that instant: a busy loop)."""

WATCHDOG = 60.0
"""Wall-clock seconds one session may take before it counts as a hang (a hang detector, not a
timing assertion: a session normally takes milliseconds)."""


class Hang(Exception):
    """The board or the link did not return within :data:`WATCHDOG` seconds."""


@contextmanager
def watchdog(seconds: float, what: str) -> Iterator[None]:
    """Raise :class:`Hang` in the main thread if the block runs longer than ``seconds``."""

    def fire(signum: int, frame: FrameType | None) -> None:
        raise Hang(f"no return within {seconds} s: {what}")

    previous = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


class SpyBoard(Board):
    """A board that remembers everything it handed to its link (the oracle's input)."""

    def __init__(self, model: Model, now: float = 0.0) -> None:
        self.handed: list[Output] = []
        super().__init__(model, now=now)

    def take_output(self) -> list[Output]:
        out = super().take_output()
        self.handed.extend(out)
        return out


def wy_text(model: Model) -> str:
    """WY's text, from the manuals' examples rather than the model's own format string."""
    if model.family == "PC48":
        return f"PC48 ver 3.00-{len(model.axes)}"  # PC48 §6.13: "PC48 ver 3.00-2"
    if model.family == "PC46":
        # the datasheet: "returns the model and firmware revision", no example: the PC48's form
        # (omsd/models/pc46.py)
        return f"PC46 ver 1.00-{len(model.axes)}"
    if model.family == "VS4":
        return f"{model.name} ver 1.00 S/N 123456"  # VS4 WY: "VS4-040 ver 1.00 S/N 123456"
    # the PCIx WY page: "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems"
    assert model.family == "PCIX", model.family
    return f"{model.name} ver:1.26, s/n:000217 - Oregon Micro Systems"


def who_are_you(model: Model, kind: str, eos: bytes = b"\n") -> bytes:
    """The whole answer to WY as a host sees it on ``kind``: ``<LF><CR>text<LF><CR>`` on a PC48,
    PC46 or VS4 (PC48 §6.1: "surrounded by line feeds and carriage returns"), ``text<LF><CR>``
    on a PCIx; through the driver, the text and the end character (§7.3.2)."""
    text = wy_text(model).encode("ascii")
    if kind == "driver":
        return text + eos
    if model.framing == "trailing":
        return text + b"\n\r"
    return b"\n\r" + text + b"\n\r"


def recovery_words(model: Model) -> bytes:
    """What a host sends, after its Control-D, to bring a board back to a known state.

    Control-D ("the same functions as the KL command. It bypasses the command
    interpreter", PC48 §6.9; it also ends a PCIx macro definition). Then, on the PC48 family,
    ``AX EF AX``: echo off (EN would echo the WY; EF is not valid in AA, hence AX first); on the
    PCIx, ``DAE;`` closes a ramp table left open (DAR ... DAE, §5.8.4) and ``AX;`` selects an
    axis. These are the words ``tests/board/test_bad_input.py`` recovers with."""
    if model.dialect == "pcix":
        return b"DAE; AX;"
    return b"AX EF AX" if "EF" in model.commands else b"AX"


def bad_word(model: Model) -> bytes:
    """A word that is one command error on every board: an unknown mnemonic ("An unrecognizable
    command has been detected", CMD_S, PC48 Table 3-8 and PCIx 2.2)."""
    return b"XQ;" if model.dialect == "pcix" else b"XQ "


@dataclass
class Counters:
    inputs: int = 0
    bytes: int = 0
    dropped: int = 0
    errors: int = 0
    reloads: int = 0
    power_cycles: int = 0
    deadlines: int = 0


@dataclass
class FuzzHost:
    """A host program on a manual clock, talking to one board through one link kind."""

    model: Model
    kind: str  # "driver" or "raw"
    t: float = 0.0
    counters: Counters = field(default_factory=Counters)

    def __post_init__(self) -> None:
        self.board = SpyBoard(self.model, now=self.t)
        self.link: DriverLink | RawLink = self._new_link()
        self.received = bytearray()
        self.stuck: list[str] = []  # the board's state at each power cycle
        self._errors_since_status_read = 0

    def _new_link(self) -> DriverLink | RawLink:
        self._echoing = False  # the driver has given echoed text not yet ended by its EOS
        return DriverLink(self.board) if self.kind == "driver" else RawLink(self.board)

    @property
    def eos(self) -> bytes:
        return self.link.eos if isinstance(self.link, DriverLink) else b""

    # -- the oracle -----------------------------------------------------------------------------

    def collect(self) -> bytes:
        """Read what the link has for the host now and check it against what the board said."""
        out = self.link.to_host(self.t)
        items, self.board.handed = self.board.handed, []
        self.check_output(items, out.data, out.events)
        self.received += out.data
        return out.data

    def check_output(self, items: list[Output], data: bytes, events: Sequence[object]) -> None:
        board_events = [i for i in items if not isinstance(i, Reply)]
        assert events == board_events, f"link events {events!r} != board events {board_events!r}"
        errors = sum(isinstance(e, CommandErrorEvent) for e in board_events)
        self.counters.errors += errors
        self._errors_since_status_read += errors
        # with echo on, a command error's "#" follows its English message (both links)
        items = list(items)
        message_first(items, [0] * len(items))
        if self.kind == "raw":
            error = b"" if self.board.model.dialect == "pcix" else b"#"
            expected = b"".join(
                i.data
                if isinstance(i, Reply)
                else error
                if isinstance(i, CommandErrorEvent)
                else b""
                for i in items
            )
            assert data == expected, f"raw link gave {data!r} for {items!r}"
            return
        eos = re.escape(self.eos)
        pattern = []
        for i in items:
            if isinstance(i, Reply) and i.text is None:
                # echoed characters: LF and CR stripped, the end character where one ends text
                for b in i.data:
                    if b in b"\n\r":
                        if self._echoing:
                            pattern.append(eos)
                        self._echoing = False
                    else:
                        pattern.append(re.escape(bytes([b])))
                        self._echoing = True
                continue
            if self._echoing:  # a reply or a marker ends the echoed text
                pattern.append(eos)
                self._echoing = False
            if isinstance(i, Reply):
                pattern.append(re.escape(i.text or b"") + eos)
            elif isinstance(i, CommandErrorEvent):
                pattern.append(b"#" + eos)
            elif isinstance(i, LimitEvent):
                pattern.append(b"@" + eos)
            elif isinstance(i, SlipEvent):
                pattern.append(rb"\$" + eos)
            elif isinstance(i, DoneEvent):
                pattern.append(b"(?:!." + eos + b")?")
        assert re.fullmatch(b"".join(pattern), data, re.DOTALL), (
            f"driver link gave {data!r} for {items!r}"
        )

    def read_status(self) -> int:
        """Read the status register as a polling host does. On the raw link nobody else reads it,
        so CMD_S may be set only if a command error was reported since the last read (CMD_S
        "An unrecognizable command has been detected ..."; it resets on read, PC48 §3.4.4)."""
        status = self.board.read_status_register(self.t)
        if self.kind == "raw" and status & CMD_S:
            assert self._errors_since_status_read, (
                f"CMD_S set (status {status:#04x}) with no command error reported"
            )
        self._errors_since_status_read = 0
        return status

    # -- time -----------------------------------------------------------------------------------

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` pass, visiting every deadline as the daemon's service does, and check
        the work is bounded: time moves on and the number of wake-ups stays within a few per
        sample and axis."""
        end = self.t + seconds
        same = 0
        visits = 0
        budget = 16 + 4 * self.model.sample_rate * len(self.model.axes) * max(seconds, 1 / 64)
        while (d := self.link.next_deadline()) is not None and d <= end:
            if d <= self.t:
                same += 1
                assert same <= MAX_SAME_INSTANT, (
                    f"the board keeps asking to be woken at t={self.t} (deadline {d}): stuck"
                )
            else:
                same = 0
            self.t = max(self.t, d)
            self.collect()
            visits += 1
            assert visits <= budget, f"{visits} wake-ups in {seconds} s: unbounded work"
        self.counters.deadlines += visits
        self.t = end
        self.collect()

    # -- writing --------------------------------------------------------------------------------

    def write(self, data: bytes, patience: float = PATIENCE) -> int:
        """Write ``data`` as a host does: what the link does not take is offered again later;
        after ``patience`` simulated seconds without progress the rest is dropped (a write
        time-out). Returns the number of bytes dropped."""
        pos = 0
        step = 0.001
        waited = 0.0
        while True:
            n = self.link.from_host(data[pos:], self.t)
            pos += n
            self.collect()
            if pos >= len(data):
                return 0
            if n:
                step, waited = 0.001, 0.0
            if waited >= patience:
                self.counters.dropped += len(data) - pos
                return len(data) - pos
            self.t += step
            waited += step
            step = min(step * 2, 10.0)
            self.collect()

    def feed(self, data: bytes, gap: float) -> None:
        """One fuzz input, then ``gap`` simulated seconds of the board running by itself."""
        self.counters.inputs += 1
        self.counters.bytes += len(data)
        self.write(data)
        self.check_bounds()
        self.wait(gap)
        self.check_bounds()

    def check_bounds(self) -> None:
        board = self.board
        interp = board.interpreter
        assert len(interp.buffer) <= interp.capacity, len(interp.buffer)
        for axis in board.axes:
            assert 0 <= axis.queue.free <= self.model.queue_size, (axis.letter, axis.queue.free)
        if isinstance(self.link, DriverLink):
            assert 0 <= self.link.pending <= self.link.buffer_size

    # -- recovery -------------------------------------------------------------------------------

    def pass_on(self, data: bytes, patience: float = PATIENCE) -> bool:
        """Write ``data`` and wait until it has reached the board (through the driver: until
        the driver's buffer has passed it on). False if it did not within ``patience``
        simulated seconds, or the driver started waiting for an interrupt on the way."""
        if self.write(data, patience):
            return False
        step, waited = 0.001, 0.0
        while isinstance(self.link, DriverLink) and self.link.pending:
            if self.link.waiting is not None or waited >= patience:
                return False
            self.t += step
            waited += step
            step = min(step * 2, 10.0)
            self.collect()
        return True

    def kill(self) -> None:
        """Control-D, whatever it takes (module docstring): a driver held by a wait that
        nothing will release is reloaded; a board that has not taken the Control-D after
        :data:`KILL_PATIENCE` simulated seconds is switched off and on. Such a board must be
        busy (a deadline to come, an axis moving: a WQ behind an endless WH..WG loop or a home
        search with the limits off, LF) or wait for the outside world (a WS/SW/BW input line);
        it is never simply stuck."""
        for _ in range(3):
            if isinstance(self.link, DriverLink) and self.link.waiting is not None:
                self.counters.reloads += 1
                self.link = self._new_link()
            if self.pass_on(b"\x04", KILL_PATIENCE):
                return
            if not (isinstance(self.link, DriverLink) and self.link.waiting is not None):
                break
        self.counters.power_cycles += 1
        self.stuck.append(self.describe())
        axes = self.board.axes
        busy = self.link.next_deadline() is not None or any(
            a.motion is not Motion.IDLE for a in axes
        )
        outside = any(a.wait is not None and a.wait.kind == "input" for a in axes)
        assert busy or outside, (
            f"the board holds its input and waits for nothing: {self.describe()}"
        )
        self.board.power_cycle(self.t)
        if isinstance(self.link, DriverLink):
            self.link = self._new_link()  # the PC was restarted with its card
        self.collect()

    def describe(self) -> str:
        board = self.board
        interp = board.interpreter
        return (
            f"t={self.t:.3f} deadline={self.link.next_deadline()} mode={interp.mode_name} "
            f"buffer={bytes(interp.buffer)!r} queues={[a.queue.free for a in board.axes]} "
            f"motion={[a.motion.name for a in board.axes]} "
            f"waits={[a.wait.kind if a.wait else None for a in board.axes]}"
        )

    def recover(self) -> None:
        """Bring the board back (see the module docstring), then check it answers WY exactly
        and still reports a command error as the manual says."""
        self.read_status()
        self.kill()
        self.t += 0.001
        assert self.pass_on(recovery_words(self.model), 5.0), "board not listening"
        # an RS the fuzz sent before the Control-D raised INIT for init_time (PC48 0.1 s)
        self.wait(self.model.init_time + 0.1)
        self.read_status()
        self.received.clear()
        # the echo of "AX EF" (if echo was on) is a string the driver ends before the next one
        ended = self.eos if self._echoing else b""
        errors_before = self.counters.errors
        end = b";" if self.model.dialect == "pcix" else b""
        assert self.pass_on(bad_word(self.model) + b"WY" + end, 1.0)
        self.wait(0.1)
        expected = who_are_you(self.model, self.kind, self.eos)
        raw_error = b"" if self.model.dialect == "pcix" else b"#"  # (PCIx: CMD_S alone)
        error = ended + (b"#" + self.eos if self.kind == "driver" else raw_error)
        assert bytes(self.received) == error + expected, (
            f"after recovery: {bytes(self.received)!r}, expected {error + expected!r}"
        )
        assert self.counters.errors == errors_before + 1
        status = self.read_status()
        if self.kind == "raw":  # the driver's interrupt routine read (and cleared) it already
            assert status & CMD_S, f"status {status:#04x} after a command error"
        self.received.clear()


# -- the inputs ------------------------------------------------------------------------------------

NUMBERS = [
    "0",
    "1",
    "-1",
    "+7",
    ".5",
    "-0.25",
    "100.9",
    "2000",
    "-33554432",
    "99999999",
    "2147483647",
    "-2147483649",
    "1" * 30,
    "ff",
    "1e5",
    "00000000000000000000000000001",
]
SEPARATORS = [",", ";", " ", "\r", "\n", "\t", ",,", ";;"]
ODD = ["?", "*", "!", "@", "#", "^", "$", "\x00", "\x1a", "\x1b", "\x7f", "\x80", "\xff", "\x19"]
UNKNOWN = ["XQ", "ZZ", "QQ", "KZ", "A", "X", "?", "?ZZ", "?K"]


def command_soup(rng: random.Random, model: Model, size: int) -> bytes:
    """A stream of the model's own mnemonics (from its command table), numbers in every form
    the lexer meets (signs, fractions, overlong, beyond 32 bits, hex), separators, the driver's
    special characters and a few control characters."""
    mnemonics = sorted(model.commands)
    letters = model.axes
    pieces: list[str] = []
    for _ in range(size):
        r = rng.random()
        if r < 0.45:
            word = rng.choice(mnemonics)
            pieces.append(word)
            spec = model.commands[word]
            if spec.operand or rng.random() < 0.2:
                fields = rng.choice([1, 1, 1, 2, len(letters), len(letters) + 2])
                values = []
                for _ in range(fields):
                    v = rng.random()
                    if v < 0.5:
                        values.append(str(rng.randint(0, 5000)))
                    elif v < 0.7:
                        values.append(str(rng.randint(-10_000_000, 10_000_000)))
                    elif v < 0.8:
                        values.append("")
                    elif v < 0.9 and spec.letter_operand:
                        values.append(rng.choice(letters) + str(rng.randint(0, 9)))
                    else:
                        values.append(rng.choice(NUMBERS))
                pieces.append(",".join(values))
            pieces.append(rng.choice(SEPARATORS[:4]))
        elif r < 0.6:
            pieces.append(rng.choice(NUMBERS))
        elif r < 0.85:
            pieces.append(rng.choice(SEPARATORS))
        elif r < 0.95:
            pieces.append(rng.choice(UNKNOWN))
        else:
            pieces.append(rng.choice(ODD))
    return "".join(pieces).encode("latin-1")


def random_bytes(rng: random.Random, size: int) -> bytes:
    """Any bytes at all; one input in four is printable ASCII only (deeper into the lexer). Half
    of the inputs leave out ``!`` and ``@``: through the driver each of them holds everything
    after it until an interrupt that random input seldom causes, so with them the driver would
    mostly be waiting (the inputs with them test that)."""
    if rng.random() < 0.25:
        data = bytes(rng.choice(range(0x20, 0x7F)) for _ in range(size))
    else:
        data = rng.randbytes(size)
    if rng.random() < 0.5:
        data = data.replace(b"!", b"").replace(b"@", b"")
    return data


ALL_MODELS = sorted(MODELS)
