"""The example command file of PC48 manual §7.3.4, written to the real daemon over TCP as the
file it is, through the driver link.

§7.3.4: "When the driver encounters the ! (WAIT FOR DONE) symbol ... it stops sending characters
to the board until the board produces a DONE interrupt. ... When the DONE interrupt occurs after
the driver processes the ! symbol, the DONE condition is cleared with a Control-Y." "The @
character acts in a similar manner except the driver holds off sending characters to the board
until a limit interrupt occurs." "All characters following the * up to the next control character
(<LF>, <CR>, <TAB>, et cetera) are ignored by the device driver and are not passed to the
controller."

The simulated world puts the minus limits and the home switches close to power-up, so the file
runs in a few seconds of real time: the limits trip through the world, each ``!`` is released by
the done of the line before it, and the platform ends up called 0,0.
"""

from __future__ import annotations

import time

from .process import Omsd

COMMAND_FILE = (
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

# Minus limits and home switches close to power-up; the rest of the time is the file's own
# 30000-step move at 10000 steps/s.
CONFIG = """
[[board]]
name = "plotter"
model = "PC48-2"
tcp = "127.0.0.1:0"

[board.axes.X]
negative_limit = -500
home_low = 0
home_high = 100

[board.axes.Y]
negative_limit = -500
home_low = 0
home_high = 100
"""

# "pl" is no PC48 command: "#"; the two jogs each end in the minus limit: "@"; the homes and
# the move each end with a DONE interrupt: "!" and the done flag register (X, Y, then both).
MARKERS = b"#\n@\n@\n!\x01\n!\x02\n!\x03\n"


def test_the_command_file_of_section_7_3_4(omsd: Omsd) -> None:
    daemon = omsd(config=CONFIG, expect=1)
    with daemon.connect() as c:
        started = time.monotonic()
        c.send(COMMAND_FILE)
        c.expect(MARKERS, timeout=20.0)
        # the centring move alone is 30000 steps at 10000 steps/s
        assert time.monotonic() - started >= 3.0
        c.send(b"aa rp")
        c.expect(b"0,0\n")
        assert c.quiet(0.05) == b""
