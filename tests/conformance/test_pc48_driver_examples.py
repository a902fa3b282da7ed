"""Conformance: the worked examples of PC48 chapter 7 (X6–X8 in the digest), as the *board*
sees them.

Chapter 7 is about the DOS device driver. What the driver itself does (``*`` comments, the
``!``/``@`` waits, the ``E:XX`` end character, the ``B:`` buffer) belongs to the driver link and
is tested there; here the driver's part is played by the test, and the board must do its part:
run into the limits, flush, home, move, load positions.
"""

from __future__ import annotations

from omsd.board.events import CommandErrorEvent, DoneEvent, ErrorKind, Event, LimitEvent
from omsd.board.harness import Harness
from omsd.board.world import AxisWorld

# The command file of §7.3.4, comments stripped as the driver would; each line's wait
# character is the event the test waits for before sending the next line.
COMMAND_FILE = [
    ("ax pl", None),  # *lift pen -- PL is not a PC48 command (digest §8.3 item 41)
    ("ax jg-5000", "@"),  # *force x axis to go into minus limit and wait until it does
    ("ay jg-5000", "@"),  # *force y axis to go into minus limit and wait until it does
    ("ax vl1000 hm0 id", "!"),  # *reduce the speed of the x axis and send it home
    ("ay vl1000 hm0 id", "!"),  # *reduce the speed of the y axis and send it home
    ("aa vl10000,10000; ma30000,30000; go id", "!"),  # *send the platform to its center
    ("ax lp0 ay lp0", None),  # *call the center 0,0
]


# The two jogs into the minus limits, 2000 steps away, at JG 5000 with the power-up AC of
# 1,000,000: 5 ms of ramp (12.5 steps), then 1987.5 steps at 5000/s, 0.4025 s in all (824.32
# sample ticks); the pulses stop on the first sample at or past the switch (docs/decisions.md).
LIMITS = [
    # X jogs from tick 0: limit on tick 825
    LimitEvent(825 / 2048, "X", -1),
    # Y's line is sent at 0.405 s (wait_for's 5 ms steps past X's limit): it starts on tick
    # ceil(0.405 * 2048) = 830 and meets its limit on tick 830 + 824.32 -> 1655
    LimitEvent(1655 / 2048, "Y", -1),
]


def wait_for(h: Harness, kind: type, limit: float = 120.0) -> Event:
    end = h.t + limit
    while h.t < end:
        h.advance(0.005)
        for event in h.events():
            if isinstance(event, kind):
                return event
    raise AssertionError(f"no {kind.__name__} within {limit} s")


def test_x6_command_file_homes_and_centres_the_platform() -> None:
    """X6 (§7.3.4): both axes are jogged into their minus limits ("When the board receives a
    limit signal from the platform, it flushes its command queue"), homed at 1000 steps/s,
    moved to the centre of a 60,000-step platform and called 0,0.

    The platform: minus limits 2,000 steps below the power-up position, a home switch from 0 to
    100 (so the positive home pass finds its lower edge at 0), the centre 30,000 above home.
    """
    world = {
        "X": AxisWorld(negative_limit=-2000, home_low=0, home_high=100, positive_limit=60_000),
        "Y": AxisWorld(negative_limit=-2000, home_low=0, home_high=100, positive_limit=60_000),
    }
    h = Harness("PC48-2", world=world)
    limits = iter(LIMITS)
    done_registers = iter([0b01, 0b10, 0b11])  # X's ID, Y's ID, then the AA ID of both axes
    for line, wait in COMMAND_FILE:
        h.send(line + "\r")
        if line == "ax pl":
            errors = [e for e in h.events() if isinstance(e, CommandErrorEvent)]
            assert [(e.kind, e.command) for e in errors] == [(ErrorKind.UNKNOWN_COMMAND, "PL")]
        if wait == "@":
            assert wait_for(h, LimitEvent) == next(limits)
        elif wait == "!":
            done = wait_for(h, DoneEvent)
            assert isinstance(done, DoneEvent) and done.done_register == next(done_registers)
            h.send(b"\x19")  # the driver clears the DONE with a Control-Y
    # home loaded 0 at the switch edge; the platform is now 30,000 steps above it
    for letter in "XY":
        assert abs(h.axis(letter).phys(h.t) - 30_000) <= 1
    assert h.query("AA RP") == b"\n\r0,0\n\r"
    assert h.query("RI") == b"\n\r\rPNNN,PNNN\n\r\r"


def test_x6_limit_flushes_what_was_queued_behind_the_move() -> None:
    """The reason for the ``@`` wait: "any pending commands stored in the board's queue are lost"
    at a limit. (Behind a *jog* they would not even wait for the limit: "Output events waiting
    for completion of JG will begin when JG is up to its requested velocity".)"""
    h = Harness("PC48-2", world={"X": AxisWorld(negative_limit=-2000)})
    h.send("ax vl5000 mr-10000 go vl1000 hm0 id\r")
    assert wait_for(h, LimitEvent) == LIMITS[0]  # the same ramp and speed as X's jog above
    h.run()
    assert h.board.registers.done == 0
    # stopped on tick 825 (0.40283 s): 12.5 + (0.40283 - 0.005) * 5000 = 2001.66 steps on,
    # 2001 of them whole
    assert h.position("X") == -2001
    assert h.query("ax rq") == b"\n\r200\n\r"
    assert h.axis("X").vl == 5000


def test_x8_four_boards_make_32_independent_axes() -> None:
    """X8 (§7.3.6): "you could put up to FOUR boards into one computer, allowing up to 32 axes
    of interrupt driven motion control". Each board is its own device: what one is told does
    not reach another."""
    boards = [Harness("PC48-8") for _ in range(4)]
    for n, h in enumerate(boards):
        h.send(f"AA MR{n + 1}00,{n + 1}00,{n + 1}00,{n + 1}00,{n + 1}00,{n + 1}00,{n + 1}00,1; GO")
    for n, h in enumerate(boards):
        h.run()
        fields = h.query("RP")[2:-2].split(b",")
        assert len(fields) == 8
        assert [int(f) for f in fields] == [(n + 1) * 100] * 7 + [1]
