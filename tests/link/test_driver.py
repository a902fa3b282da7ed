"""The DOS device driver discipline (PC48 manual §7.3), on a manual clock."""

from __future__ import annotations

import pytest

from omsd.board import Board, DoneEvent, LimitEvent
from omsd.board.world import AxisWorld
from omsd.link import DriverLink, RawLink
from omsd.models import MODELS, get_model


class Host:
    """A host program talking through a link, on a manual clock."""

    def __init__(self, link: DriverLink | RawLink) -> None:
        self.link = link
        self.t = 0.0
        self.received = bytearray()
        self.events: list[object] = []

    def write(self, data: bytes) -> int:
        n = self.link.from_host(data, self.t)
        self._read()
        return n

    def _read(self) -> bytes:
        out = self.link.to_host(self.t)
        self.received += out.data
        self.events += out.events
        return out.data

    def run(self, until: float) -> bytes:
        start = len(self.received)
        while (d := self.link.next_deadline()) is not None and d <= until:
            self.t = max(self.t, d)
            self._read()
        self.t = until
        self._read()
        return bytes(self.received[start:])

    def take(self) -> bytes:
        data, self.received = bytes(self.received), bytearray()
        return data


def driver(model: str = "PC48-4", world: dict[str, AxisWorld] | None = None, **kw: int) -> Host:
    return Host(DriverLink(Board(get_model(model), 0.0, world=world), **kw))


def test_rp_through_the_driver_ends_with_the_end_of_string_character() -> None:
    """§7.3.2: "The response to an RP command when talking straight to the board is
    "<LF><CR>0<LF><CR>" ... The response from an RP command using the driver would be "0<LF>"."""
    h = driver()
    h.write(b"RP")
    assert h.take() == b"0\n"


def test_e_option_changes_the_end_of_string_character() -> None:
    """E:0D "(changes end of string char to a <CR>)"."""
    h = driver(eos=0x0D)
    h.write(b"WY RP")
    assert h.take() == b"PC48 ver 3.00-4\r0\r"


def test_status_replies_lose_their_two_carriage_returns_too() -> None:
    h = driver()
    h.write(b"AA RI AX QA")
    assert h.take() == b"PNNN,PNNN,PNNN,PNNN\nPNNN\n"


def test_command_error_is_a_hash_and_the_end_character() -> None:
    h = driver()
    h.write(b"ZZ WY")
    assert h.take() == b"#\nPC48 ver 3.00-4\n"


def test_done_is_bang_done_register_byte_end_character() -> None:
    """§7.3.3: "A DONE interrupt will place an ! into the data stream followed by the byte read
    from the done flag register of the board, followed by the end character." """
    h = driver()
    h.write(b"AA MR100,200,0,0; GO ID")
    assert h.take() == b""
    h.run(1.0)
    assert h.take() == b"!\x0f\n"
    # the driver's interrupt routine read the register: it is clear now, the flags are not
    assert h.link.board.registers.done == 0
    h.write(b"QI")
    assert h.take() == b"PDNN,PDNN,PDNN,PDNN\n"


def test_done_byte_can_be_any_value_even_the_end_character() -> None:
    """Y alone done gives register 0x02. Y and T finishing on the same sample are one interrupt:
    the register then reads 0x0A, the same byte as the LF end character; a host must take
    exactly one byte after the ``!``."""
    h = driver("PC48-8")
    h.write(b"AY ID")
    assert h.take() == b"!\x02\n"
    h.write(b"\x19AA MR,1,,1; GO AY ID AT ID")
    h.run(1.0)
    assert h.take() == b"!\n\n"


def test_a_late_run_gives_one_marker_for_the_dones_its_read_took() -> None:
    """X done at 0.1 s and Y at 0.3 s: run at each deadline, a marker each (``!\x01``,
    ``!\x02``); run once, late, after both (a service woken late, as an interrupt served
    late), the one read of the register takes both bits: ``!\x03``, and no second marker that
    "nothing" is done (``!\x00``), which a real interrupt never reads. PC48 §7.3.3: "A DONE
    interrupt will place an ! into the data stream followed by the byte read from the done
    flag register"."""
    commands = b"AX VL1000 MR100 GO ID AY VL1000 MR300 GO ID\r"
    on_time = driver("PC48-4E")
    on_time.write(commands)
    on_time.run(1.0)
    assert on_time.take() == b"!\x01\n!\x02\n"
    late = driver("PC48-4E")
    late.write(commands)
    late.t = 1.0
    late.write(b"")
    assert late.take() == b"!\x03\n"
    assert sum(type(e).__name__ == "DoneEvent" for e in late.events) == 2  # both in the log


def test_limit_and_slip_markers() -> None:
    h = driver("PC48-4E", world={"X": AxisWorld(positive_limit=500)})
    h.write(b"AX VL10000 MR1000 GO ")
    h.run(1.0)
    assert h.take() == b"@\n"
    h.write(b"AY ES5 IS ")
    h.run(1.1)
    h.link.board.inject_slip("Y", 20, h.t)
    h.run(1.2)
    assert h.take() == b"$\n"


def test_limits_on_one_sample_are_one_interrupt_and_one_at_sign() -> None:
    """§7.3.3: "A limit interrupt causes an @ character". Two axes reaching their switches on
    the same sample set the status register's OVRT bit once: one interrupt, whose service reads
    (and clears) the register, one ``@``; both limits are in the log. Limits on two samples are
    two interrupts, two ``@``."""
    world = {"X": AxisWorld(positive_limit=500), "Y": AxisWorld(positive_limit=500)}
    h = driver("PC48-4E", world=world)
    h.write(b"AA VL10000,10000 MR1000,1000 GO @ RP")
    h.run(1.0)
    said = h.take()
    assert said.startswith(b"@\n") and said.count(b"@") == 1 and said.endswith(b",0,0\n")
    assert sum(type(e).__name__ == "LimitEvent" for e in h.events) == 2
    world = {"X": AxisWorld(positive_limit=500), "Y": AxisWorld(positive_limit=600)}
    h = driver("PC48-4E", world=world)
    h.write(b"AA VL10000,10000 MR1000,1000 GO")
    h.run(1.0)
    assert h.take() == b"@\n@\n"


def test_limits_on_one_sample_of_two_sessions_each_give_their_session_an_at_sign() -> None:
    """The one ``@`` of a sample's limits is per session: each session is a host of its own, and
    §7.3.4: "the driver holds off sending characters to the board until a limit interrupt
    occurs". Session 1's X and session 2's Y reach their switches on the same sample: each
    session is told (``@``) and session 2's ``@`` wait is released (its RP runs). Before, the
    second limit of the sample was dropped whole: session 2 heard nothing and its wait held
    its input for good."""
    world = {"X": AxisWorld(positive_limit=500), "Y": AxisWorld(positive_limit=500)}
    link = DriverLink(Board(get_model("PC48-4E"), 0.0, world=world))
    got: dict[int, bytes] = {1: b"", 2: b""}

    def read(t: float) -> None:
        for session, data in link.to_host(t).pieces:
            got[session] += data

    link.from_host(b"AX VL10000 MR1000 GO\r", 0.0, 1)
    read(0.0)
    link.from_host(b"AY VL10000 MR1000 GO @ RP\r", 0.0, 2)
    read(0.0)
    t = 0.0
    while (d := link.next_deadline()) is not None and d <= 1.0:
        t = max(t, d)
        read(t)
    read(1.0)
    assert got == {1: b"@\n", 2: b"@\n501\n"}
    assert link.held() is None
    # what the link keeps of a session's limits goes with the session
    assert link._limit_marked_at.keys() == {1, 2}
    link.drop_input(1)
    assert link._limit_marked_at.keys() == {2}


def test_markers_wait_for_the_end_of_a_reply() -> None:
    """ "If the board is returning a message when an interrupt occurs, the interrupt symbol will
    be delayed until after the end of the message string." A reply is never split."""
    h = driver()
    h.write(b"ZZ RP ZZ QA")
    assert h.take() == b"#\n0\n#\nPNNN\n"


def test_bang_holds_the_host_until_done_then_control_y() -> None:
    """§7.3.4: on ``!`` the driver "stops sending characters to the board until the board
    produces a DONE interrupt ... the DONE condition is cleared with a Control-Y. Characters are
    then allowed to be passed to the board." """
    h = driver()
    h.write(b"AX VL1000 MR800 GO ID ! RP")
    assert h.link.waiting == "done"
    assert h.take() == b""  # RP is held back
    h.run(0.5)
    assert h.take() == b""
    h.run(2.0)
    # the DONE marker, then (after the Control-Y) the held RP is answered
    assert h.take() == b"!\x01\n800\n"
    assert h.link.waiting is None
    h.write(b"QA")
    assert h.take() == b"PNNN\n"  # Control-Y cleared the done flag


def test_bang_after_a_command_that_is_done_at_once() -> None:
    h = driver()
    h.write(b"AX ID ! WY")
    assert h.take() == b"!\x01\nPC48 ver 3.00-4\n"


def test_at_sign_holds_the_host_until_a_limit() -> None:
    h = driver(world={"X": AxisWorld(negative_limit=-2000)})
    h.write(b"AX JG-5000 @ RP")
    assert h.link.waiting == "limit"
    h.run(0.2)
    assert h.take() == b""
    h.run(1.0)
    reply = h.take()
    assert reply.startswith(b"@\n-200")
    assert h.link.waiting is None


def test_comment_runs_to_the_next_control_character() -> None:
    """ "All characters following the * up to the next control character (<LF>, <CR>, <TAB>, et
    cetera) are ignored by the device driver and are not passed to the controller." """
    h = driver()
    h.write(b"WY *EN RP this is not for the board\rRP *again\tQA")
    assert h.take() == b"PC48 ver 3.00-4\n0\nPNNN\n"
    assert [type(e).__name__ for e in h.events] == []


def test_comment_split_across_writes() -> None:
    h = driver()
    h.write(b"*co")
    h.write(b"mment RP")
    h.write(b"\nRP")
    assert h.take() == b"0\n"


def test_buffer_option_limits_what_the_host_can_write_at_once() -> None:
    """B:XXXX "defines the "output to board" BUFFER size. This value determines how many
    characters you can send to the device buffer at one time." """
    h = driver(buffer_size=16)
    h.write(b"AX ID !")
    assert h.link.waiting is None  # satisfied at once
    h.write(b"VL100 MR500 GO")
    assert h.write(b" ID !") == 5
    assert h.link.waiting == "done"
    taken = h.write(b"RP" * 20)
    assert taken == 16
    assert h.link.pending == 16
    h.run(10.0)  # the move ends, the driver goes on and empties its buffer
    assert h.link.pending == 0
    assert h.take().endswith(b"500\n" * 8)


def test_echo_through_the_driver() -> None:
    """EN echoes what is typed; the driver strips the LF and CR characters from it too, and
    ends the echoed text with its end character where the board's LF/CR ends it: the echo and
    the reply are two strings, not one (docs/decisions.md, "Echo (EN)")."""
    h = driver()
    h.write(b"EN\rWY\r")
    # EN cannot echo itself, nor its CR (nothing echoed yet to end); the board then sends
    # "WY<LF><CR>PC48 ver 3.00-4<LF><CR><CR>": two strings, and a CR that ends nothing
    assert h.take() == b"WY\nPC48 ver 3.00-4\n"


def test_echoed_lines_end_with_the_end_character() -> None:
    """An echoed line with no reply ends where the host's line end is echoed; a CR LF pair, or
    a line end after a reply, gives no empty string."""
    h = driver(eos=0x0D)
    h.write(b"EN\r\nAX MR10 GO\r\nRP\r\n\r\n")
    assert h.take() == b"AX MR10 GO\rRP\r0\r"


def test_markers_and_errors_with_echo_on() -> None:
    """A marker never joins echoed text: the echo before it is ended first. A command error's
    English message comes before its ``#`` ("the interrupt symbol will be delayed until after
    the end of the message string", §7.3.3)."""
    h = driver()
    h.write(b"EN XQ AX MR1000 GO ID")
    assert h.take() == b" XQ\nUnrecognized command: XQ\n#\n AX MR1000 GO ID"
    h.run(2.0)
    assert h.take() == b"\n!\x01\n"


def test_raw_link_puts_the_error_mark_after_the_message() -> None:
    """The raw link's lone ``#`` follows the English message too; the board's own framing and
    echo are otherwise untouched."""
    h = Host(RawLink(Board(get_model("PC48-4"), 0.0)))
    h.write(b"EN XQ WY\r")
    assert h.take() == (b" XQ\n\rUnrecognized command: XQ\n\r# WY\n\rPC48 ver 3.00-4\n\r\r")


def test_the_command_file_of_section_7_3_4() -> None:
    """The example command file, with its comments and waits, run through the driver: the
    limits are tripped through the simulated world, each ``!`` is satisfied by the done of the
    line before it, and the platform ends called 0,0."""
    world = {
        "X": AxisWorld(negative_limit=-2000, home_low=0, home_high=100),
        "Y": AxisWorld(negative_limit=-2000, home_low=0, home_high=100),
    }
    h = driver("PC48-2", world=world)
    command_file = (
        b"ax pl          *lift pen\r\n"
        b"ax jg-5000 @   *force x axis to go into minus limit and wait until it does\r\n"
        b"ay jg-5000 @   *force y axis to go into minus limit and wait until it does\r\n"
        b"ax vl1000 hm0 id ! *reduce the speed of the x axis and send it home\r\n"
        b"                  *wait until it gets the DONE after the home\r\n"
        b"ay vl1000 hm0 id ! *reduce the speed of the y axis and send it home\r\n"
        b"                  *wait until it gets the DONE after the home\r\n"
        b"aa vl10000,10000; ma30000,30000; go id !\r\n"
        b"                  *increase the speed and send the platform to its center\r\n"
        b"                  *wait until the move is done\r\n"
        b"ax lp0 ay lp0   *call the center 0,0\r\n"
    )
    rest = command_file
    while rest:
        taken = h.write(rest)
        rest = rest[taken:]
        if rest:
            h.run(h.t + 0.05)
        assert h.t < 60
    h.run(h.t + 10)
    h.write(b"aa rp")
    assert h.take() == b"#\n@\n@\n!\x01\n!\x02\n!\x03\n0,0\n"
    assert [type(e) for e in h.events] == [
        type(h.events[0]),
        LimitEvent,
        LimitEvent,
        DoneEvent,
        DoneEvent,
        DoneEvent,
    ]
    for letter in "XY":
        axis = h.link.board.axis_by_letter(letter)
        assert axis is not None
        assert axis.phys(h.t) == pytest.approx(30_000, abs=1)


# -- the raw link -----------------------------------------------------------------------------


def raw(model: str = "PC48-4", world: dict[str, AxisWorld] | None = None) -> Host:
    return Host(RawLink(Board(get_model(model), 0.0, world=world)))


def test_raw_link_keeps_native_framing() -> None:
    h = raw()
    h.write(b"AX QA RP")
    assert h.take() == b"\n\r\rPNNN\n\r\r\n\r0\n\r"


def test_raw_link_command_error_is_a_lone_hash() -> None:
    h = raw()
    h.write(b"AX EA")
    assert h.take() == b"#"


def test_raw_link_sends_no_done_limit_or_slip_bytes() -> None:
    h = raw("PC48-4E", world={"X": AxisWorld(positive_limit=100)})
    h.write(b"AX VL10000 MR1000 GO AY MR10 GO ID AZ ES1 IS ")
    h.run(1.0)
    h.link.board.inject_slip("Z", 5, h.t)
    h.run(2.0)
    assert h.take() == b""
    kinds = {type(e).__name__ for e in h.events}
    assert kinds == {"LimitEvent", "DoneEvent", "SlipEvent"}


def test_each_done_releases_one_wait_only() -> None:
    h = driver()
    h.write(b"AX ID ! AY VL1000 MR500 GO ID ! RP")
    assert h.link.waiting == "done"
    assert h.take() == b"!\x01\n"
    h.run(2.0)
    assert h.take() == b"!\x02\n500\n"


def test_bytes_held_by_a_wait_go_on_when_the_board_releases_it_by_itself() -> None:
    """The DONE arrives while nobody writes: the held bytes must still be passed on."""
    h = driver()
    h.write(b"AX VL10000 MR500 GO ID ! RP RP")
    assert h.link.pending == 6
    h.run(1.0)
    assert h.take() == b"!\x01\n500\n500\n"
    assert h.link.pending == 0


@pytest.mark.parametrize("name", sorted(MODELS))
def test_both_links_work_with_every_model(name: str) -> None:
    """Every personality through the driver link (framing stripped, markers) and the raw link
    (native framing; on error a lone # in the PC48 family's stream, nothing in the PCIx's)."""
    model = get_model(name)
    wy = model.who_are_you().encode()
    fields = ",".join("0" for _ in model.axes).encode()
    h = Host(DriverLink(Board(model, 0.0)))
    h.write(b"WY AA RP ZZ AX ID ")
    assert h.take() == wy + b"\n" + fields + b"\n#\n!\x01\n"
    r = Host(RawLink(Board(model, 0.0)))
    r.write(b"WY AA RP ZZ AX ID ")
    if model.framing == "trailing":  # the PCIx: text<LF><CR>, nothing before; CMD_S alone
        assert r.take() == wy + b"\n\r" + fields + b"\n\r"
    else:
        assert r.take() == b"\n\r" + wy + b"\n\r\n\r" + fields + b"\n\r#"
