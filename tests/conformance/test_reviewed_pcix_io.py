"""PCIx I/O and report commands where a review against its manual (002_5f0bea9264c6d239.txt)
found omsd wrong.

* SE is immediate in both modes ("SE#; AX – AT Immediate", "SE#,#,##; AA-AM Immediate"): a
  settling time typed while the axis is busy is in force at once, not when its queue reaches it.
* PA "selects the mode immediately but places entries in the axis command queue to set the state
  of the aux bit to the idle state": ?PA reports the mode at once; the aux line goes to its idle
  state when the axis reaches the entry.
* PH and PL take a ``b`` in single-axis mode too ("PHb; AX – AT 1", "PLb; AX – AT 1"), as PA
  does ("PAb; AX – AT 1*"): ``PH1;`` sets the current axis's aux, it is not a command error.
* WS takes its optional second parameter, the state ("WD#[,state];" on the WS page): a
  non-zero state loops while the input is high; it was a command error.
"""

from __future__ import annotations

from omsd.board.harness import Harness

from .pcix import reply


def test_se_typed_on_a_busy_axis_is_in_force_at_once() -> None:
    """SE's table: "SE#; AX – AT Immediate", "SE#,#,##; AA-AM Immediate"; §5.4.4: "immediate
    commands are executed the moment they are received". ?SE "reports the settling time setting
    ( SE ) used with power automatic mode ( PA ) for the current axis"."""
    h = Harness("PCIX-004")
    h.send("AX;VL1000;MR100000;GO;")  # X busy for 100 s
    h.send("SE250;")
    assert h.send("?SE;") == reply("se250")  # (it was se0 until the move's end)
    h.send("AY;VL1000;MR100000;GO;AA;SE,300;AY;")
    assert h.send("?SE;") == reply("se300")  # (it was se0)
    assert h.errors() == []


def test_se_typed_during_a_move_settles_that_move() -> None:
    """SE: "a settling time ... to be used before the auxiliary output is complemented when
    using PA mode". In force at once, it applies to the end of the move that is running: PA0
    raises the aux during a 1000-count move at VL1000 (1 s and the ramps) and it stays up 500
    ms after the move."""
    h = Harness("PCIX-004")
    h.send("AX;PA;VL1000;MR1000;GO;")
    h.advance(0.5)
    h.send("SE500;")
    h.advance(0.55)  # the move is over (1.0005 s)
    assert h.position("X") == 1000
    assert h.send("?AB;") == reply("an")  # (it was af: SE waited for the move to end)
    h.advance(0.5)
    assert h.send("?AB;") == reply("af")
    assert h.errors() == []


def test_pa_selects_the_mode_at_once_and_queues_the_idle_state() -> None:
    """PA: "NOTE: PA selects the mode immediately but places entries in the axis command queue
    to set the state of the aux bit to the idle state." ?PA "reports whether the current axis
    has power automatic mode enabled". X is busy: ?PA answers the mode typed at once; the aux
    line keeps its state (AN, the power-up default) until X reaches the entry, then idles low
    (PA1: "the auxiliary output is turned off (driven low) upon the execution of the GO or GD
    command and on at the end of the move", so its idle state is high; PA0's is low)."""
    h = Harness("PCIX-004")
    h.send("AX;VL1000;MR1000;GO;MR1000;GO;")  # X busy for about 2 s
    h.send("PA1;")
    assert h.send("?PA;") == reply("pa1")  # (it was paf until both moves had ended)
    h.send("PA;")
    assert h.send("?PA;") == reply("pa0")
    assert h.send("?AB;") == reply("an")  # the entries wait in X's queue
    h.advance(3.0)
    assert h.position("X") == 2000
    assert h.send("?PA;?AB;") == reply("pa0") + reply("af")  # PA0's idle state: low
    h.send("AA;VL,1000;MR,1000;GO;PA,1;AY;")
    assert h.send("?PA;") == reply("pa1")  # (it was paf)
    assert h.errors() == []


def test_ph_and_pl_take_a_b_parameter_in_single_axis_mode() -> None:
    """PH and PL's tables: "PHb; AX – AT 1", "PLb; AX – AT 1" (and "PHb,b,b,b; AA-AM 1"); §5.3:
    "Each ‘b’ position, if used, can be any numeric value". PL "will turn the currently active
    axis auxiliary port bit 'off' (low)", PH "'on' (high)"."""
    h = Harness("PCIX-004")
    h.send("AT;PL1;")
    assert h.send("?AB;") == reply("af")  # (it was an: PL1 was a command error)
    h.send("PH0;")
    assert h.send("?AB;") == reply("an")
    h.send("PA;PL;")
    assert h.send("?PA;?AB;") == reply("paf") + reply("af")
    assert h.send("AZ;?AB;") == reply("an")  # only the current axis
    assert h.errors() == []
    h.send("PH1,1;")  # a list is the multi-axis form
    assert [e.kind.name for e in h.errors()] == ["TOO_MANY_PARAMETERS"]


def _ws_passes(text: str, loop_while_high: bool) -> tuple[int, int]:
    """X's position after the loop ``text`` ran 3.5 s with input 1 in the state that keeps it
    looping, then 2 s more after input 1 changed; each pass is an MR100 (35 ms)."""
    h = Harness("PCIX-004")
    h.board.set_input(1, loop_while_high, 0.0)
    h.send(text)
    h.advance(3.5)
    h.board.set_input(1, not loop_while_high, h.t)
    looped = h.position("X")
    h.advance(2.0)
    assert h.errors() == []
    return looped, h.position("X")


def test_ws_takes_a_state_to_loop_while_the_input_is_high() -> None:
    """WS: "WD#[,state];" "If the optional second parameter, state, is entered then it
    specifies the input condition to continue the loop. If the state parameter is zero, the
    loop will continue while the input is low. If the state parameter is non-zero, the loop will
    continue while the input is high. If the state parameter is not entered, the default
    behavior is to loop while the input is low." "The test is at the bottom of the loop"."""
    for text, high in (
        ("AX;WS1,1;MR100;GO;WD;", True),  # (it was a command error: too many parameters)
        ("AX;WS1,0;MR100;GO;WD;", False),
        ("AX;WS1;MR100;GO;WD;", False),
        ("AA;WS1,5;MR100;GO;WD;", True),  # AA: "entries are made in all axes' queues"
    ):
        looped, final = _ws_passes(text, high)
        assert looped > 1000, text  # many passes while the input kept the loop going
        assert final - looped <= 100, text  # the pass under way, then out of the loop
    h = Harness("PCIX-004")  # already in the exit state: "executed only once"
    h.send("AX;WS1,1;MR100;GO;WD;")
    h.board.set_input(1, False, 0.0)
    h.advance(1.0)
    assert h.position("X") == 100
    assert h.errors() == []


def _go_slots(h: Harness) -> int:
    """The slots a ``GO;`` takes in X's queue (RQ reports every axis whatever the mode)."""
    before = int(h.send("RQ;").split(b",")[0])
    h.send("GO;")
    return before - int(h.send("RQ;").split(b",")[0])


def test_a_go_is_charged_pa_and_se_once() -> None:
    """GO's table: "GO; AX – AT 5*", "* If PA (power automatic) mode is active add 2 to the
    command queue", "* If an auxiliary output bit settle time has been specified add 3". A GO
    typed after PA takes 5 + 2, after SE as well 5 + 2 + 3, whether PA and SE were typed while X
    was busy (they are in force at once) or at rest (it took 5 + 2 + 2 and 5 + 2 + 3 + 2 + 3:
    the PC48's per-GO charge of PA and SE on top of the PCIx table's add-ons)."""
    for busy in (True, False):
        h = Harness("PCIX-004")
        h.send("AX;VL1000;")
        if not busy:
            h.send("PA;")
            h.run()
        h.send("MR100000;GO;MR100000;")  # X busy for 100 s
        if busy:
            h.send("PA;")
        assert _go_slots(h) == 5 + 2, busy
        h.send("SE100;")
        assert _go_slots(h) == 5 + 2 + 3, busy
        assert h.errors() == []
