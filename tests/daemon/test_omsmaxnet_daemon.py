"""EPICS ``omsMAXnet`` traffic replayed against the real daemon: a PCIX-400 served over TCP on
the raw link, as an IOC's asyn IP port would reach it.

``shared/interop/README.md``: "Each command line ends with ``\\n``; several commands per line";
"Replies are ``text\\n\\r`` with **no leading LF/CR**"; "Every query that gets no answer costs
the client a 2 s timeout". The client lines and which of their commands are queries come from
the board-level replay (``tests/conformance/test_omsmaxnet_trace.py``); here every query must be
answered through the socket, in order, framed ``text\\n\\r``, within the client's patience, and
nothing else may arrive.
"""

from __future__ import annotations

import time

from conformance.test_omsmaxnet_trace import QUERIES, RX, mnemonics

from .process import Omsd

MAX_PAUSE = 0.2  # seconds: longer pauses of the recording are shortened to this
PATIENCE = 2.0  # the client's timeout per query


def test_epics_omsmaxnet_trace_through_the_raw_link(omsd: Omsd) -> None:
    daemon = omsd("--board", "PCIX-400", "--link", "raw", "--tcp", "127.0.0.1:0")
    (endpoint,) = daemon.endpoints
    assert (endpoint.model, endpoint.link) == ("PCIX-400", "raw")
    answered = 0
    with daemon.connect() as c:
        start = time.monotonic()
        at = previous = 0.0
        for t, line in RX:
            at += min(t - previous, MAX_PAUSE)
            previous = t
            while (left := start + at - time.monotonic()) > 0:
                time.sleep(min(left, 0.01))
            c.send(line)
            for m in mnemonics(line):
                if m not in QUERIES:
                    continue
                reply = c.read_until(b"\n\r", timeout=PATIENCE)
                assert reply.endswith(b"\n\r") and reply[:1] not in (b"\n", b"\r"), (line, reply)
                assert b"\n" not in reply[:-2] and b"\r" not in reply[:-2], (line, reply)
                answered += 1
        assert c.quiet(0.2) == b"", "nothing may come that was not asked for"
    assert answered > 100
