"""Review of omsd's answers against the EPICS MAX-family drivers' own parsers.

The replies of the PCIx personality (with its MAX-family extension) are read here the way
EPICS ``motorOmsAsyn`` reads them, on every PCIx model, at rest, in motion, at a limit, with servo
loops closed and open. The parsers (the poll's in ``max_client.py``, shared with
``test_reviewed_max_sequences.py``) are transcriptions of ``epics-motor/motorOmsAsyn``
``omsAsynApp/src/omsBaseController.cpp`` (the omsMAXnet client's base class) and
``omsAsynApp/src/omsMAXnet.cpp``:

* ``omsMAXnet::sendReceive`` reads up to the input EOS ``"\\n\\r"`` and cuts "a leading CR, NL,
  /006": ``while ((*outString == 6)||(*outString == 13)||(*outString == 10)) ++outString;``
* ``getAxesStatus`` (``AM;RI;``): ``if (!((inputBuff[0] == 'P') || (inputBuff[0] == 'M')))`` and
  ``if (strlen(inputBuff) < (unsigned int)(numAxes * 5 -1)) status = asynError;``; the poller
  reads ``statusBuffer[i*STATUSSTRINGLEN + 1] == 'D'`` (``STATUSSTRINGLEN`` 5), ``+ 2 == 'L'``,
  ``+ 3 == 'H'`` and ``statusBuffer[i*STATUSSTRINGLEN] == 'P'``.
* ``getAxesArray`` (``AM PP;``, ``AM PE;``, ``AM;RV;``): ``strtol`` field by field; ``if (count
  != numAxes) ... return asynError;``.
* ``AM;QL;``: ``if (1 != sscanf(pollInputBuffer, "%x", &limitFlags))`` and
  ``if (((limitFlags & (1 << (i+limitOffset))) > 0) ^ (pAxis->getLimitInvert()))
  pAxis->setIntegerParam(motorStatusLowLimit_, 1);`` (``+8`` for the high limit), the
  invert flag set when ``LT?``/``?LS`` answers ``l`` in its second character
  (``if (inputBuffer[1] == 'l'){ pAxis->setLimitInvert(1);``).
* ``AM;CL?;``: ``getSubstring(i, pollInputBuffer, clBuffer, sizeof(clBuffer))`` per axis;
  ``AM;EA;``: ``getSubstring`` per axis, ``if (encBuffer[2] == 'S')``.
* ``A? PS?`` / ``A? ?PS``: ``/*we expect any of "=O","=E","=M"  */ if (inputBuffer[1] == 'O')``.
* ``getFirmwareVersion``: ``count = sscanf(p, "ver:%d.%d.%d,", &fwMajor, &fwMinor, &fwRevision);
  ... if ((p == NULL) || (count < 2))``.

None of the parsers' tests failed when this file was written: the review found no reply of
the PCIx personality these parsers misread. What it found was what a command does: LPE, which
the clients send to set the encoder position apart from the motor's, loaded the motor position
too (the last test; ``docs/decisions.md``, "MAX-family extension").
"""

from __future__ import annotations

import re

import pytest

from omsd.board.harness import Harness
from omsd.engine.world import AxisWorld

from .max_client import poll, receive

PCIX_MODELS = ["PCIX-002", "PCIX-020", "PCIX-202", "PCIX-200", "PCIX-004", "PCIX-040", "PCIX-400"]


@pytest.mark.parametrize("model", PCIX_MODELS)
def test_omsmaxnet_parsers_read_every_pcix_at_rest_in_motion_and_at_limits(model: str) -> None:
    n = len(Harness(model).board.model.axes)
    h = Harness(model, world=[AxisWorld(negative_limit=-500, positive_limit=2000)] * n)
    m = re.search(r"ver:(\d+)\.(\d+)", receive(h, "WY"))
    assert m, "getFirmwareVersion: ver:%d.%d"
    assert len(receive(h, "AA RP;").split(",")) == n  # Init counts the axes from AA RP
    invert = []
    for axis in h.board.model.axes:
        for query in ("PS?", "?PS"):
            kind = receive(h, f"A{axis} {query}")
            assert kind[1] == "OEM"[h.axis(axis).has_encoder + h.axis(axis).is_servo], kind
        lt, ls = receive(h, f"A{axis} LT?"), receive(h, f"A{axis} ?LS")
        assert lt[1] == ls[1] and lt[1] in "lh", (lt, ls)
        invert.append(lt[1] == "l")

    at_rest = poll(h)
    assert all(f == "PNNN" for f in at_rest.RI)
    assert not any(any(at_rest.limits(i, invert[i])) for i in range(n))

    h.send("AX;AC2000;VL1000;VB0;MR-300;GO;ID;\n")
    h.advance(0.3)
    moving = poll(h)
    assert moving.RI[0][:2] == "MN" and moving.RV[0] < 0
    h.advance(2.0)
    done = poll(h)
    assert done.RI[0] == "MDNN" and done.PP[0] == -300 and done.RV[0] == 0

    h.send("AX;AC2000;VL1000;VB0;MR-1000;GO;ID;\n")
    h.send("AY AC2000; JG1500;\n")
    h.advance(3.0)
    hit = poll(h)
    assert hit.RI[0] == "MNLN" and hit.PP[0] == -500
    assert hit.RI[1] == "PNLN" and hit.PP[1] == 2000
    assert hit.RV[:2] == [0, 0]
    assert hit.limits(0, invert[0]) == (True, False)
    assert hit.limits(1, invert[1]) == (False, True)


@pytest.mark.parametrize("model", ["PCIX-400", "PCIX-202", "PCIX-200", "PCIX-040", "PCIX-020"])
def test_omsmaxnet_parsers_read_closed_loops_and_encoders(model: str) -> None:
    """``A? CL1`` on the first axis (a servo, or a stepper with encoder), then a move read by
    the poller: CL? ``on`` for it, PE the encoder, EA's third character not ``S``."""
    h = Harness(model)
    h.send("AX CL1\n")
    h.advance(0.1)
    assert poll(h).CL[0] == "on"
    h.send("AX;AC20000;VL5000;VB0;MR-3000;GO;ID;\n")
    h.advance(0.4)
    moving = poll(h)
    assert moving.RV[0] < 0 and moving.RI[0][1] == "N"
    h.advance(2.0)
    done = poll(h)
    assert done.RI[0] == "MDNN" and done.PP[0] == -3000
    assert abs(done.PE[0] + 3000) <= 1 and done.EA[0][2] != "S"
    assert int(receive(h, "AX;RE;")) == done.PE[0]


@pytest.mark.parametrize(("model", "motor"), [("PCIX-040", 100), ("PCIX-400", -100)])
def test_lpe_loads_the_encoder_apart_from_the_motor_position(model: str, motor: int) -> None:
    """``epics-motor/motorOmsAsyn`` ``omsBaseController.cpp`` sets an axis's motor position with
    ``LP`` and its encoder position with ``"A? LPE%d;"``, and ``ronaldomercado/motorOms``
    ``devOmsCom.cc`` loads the two apart: ``sprintf(motor_call->message, "LO%ld LPE%ld;", ref,
    fdbk);``. On a stepper with an encoder (PCIX-040) LPE loads the encoder alone, as the
    PCIx's LO "sets the motor position independently of the encoder position" (it loaded the
    position counter too: RP read -100); on a servo (PCIX-400) the position is the encoder, and
    both read the last load, as after LO."""
    h = Harness(model)
    h.send("AX LO100 LPE-100;\n")
    h.advance(0.1)
    assert int(receive(h, "AX;RE;")) == -100
    assert int(receive(h, "AX;RP;")) == motor
    assert h.errors() == []
