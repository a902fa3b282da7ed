"""EPICS ``omsMAXnet`` traffic replayed against a PCIX-400 with the MAX-family query extension.

``shared/interop/README.md`` on what this client needs (PCIx / MAX dialect): "Each command line
ends with ``\n``; several commands per line, separated by ``;`` or spaces." "Replies are
``text\n\r`` with **no leading LF/CR**." "``WY`` must contain ``ver:<major>.<minor>``." "It polls
``AM;RI;`` (one ``[PM][DN][LN][HN]`` field per axis, comma separated), ``AM PP;`` (positions,
one field per axis), ``AM;RV;`` (velocities; non-zero while moving), ``AM;EA;``, ``AM;QL;`` (hex
limit bits), ``AM;CL?;``, and ``#WS`` (must answer ``=0``)". "Every query that gets no answer
costs the client a 2 s timeout". "A move ends with ``ID``; the done flag must appear in ``RI``
when the move completes, or the client flags the axis as a problem after five polls."

The trace's TX side came from a capture stub; only its shapes are used (a comparison against
the copy below). What the answers must say comes from the PCIx manual (digest
``shared/reference/pcix.md``) and, for the MAX-family queries, from the client's own decoding
(EPICS motorOmsAsyn ``omsBaseController.cpp``; see :mod:`omsd.board.max_family`).

The client's RX lines are copied below (times in seconds since it connected), so the replay runs
without ``shared/``; when the trace is present the copy is checked against it.
"""

from __future__ import annotations

import ast
import dataclasses
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import pytest

from omsd.board.board import Board
from omsd.board.events import CommandErrorEvent, ErrorKind, Reply
from omsd.board.harness import Harness
from omsd.models import get_model, variant

TRACE = Path(__file__).resolve().parents[3] / "shared" / "interop" / "epics-omsMAXnet.trace"
MODEL = "PCIX-400"

RX: list[tuple[float, bytes]] = [
    (2.025, b"WY\n"),
    (2.025, b"IC;\n"),
    (2.068, b"AM SA;\n"),
    (2.526, b"AX LH PSO; AY LH PSO;\n"),
    (3.026, b"AA RP;\n"),
    (3.027, b"AX PS?\n"),
    (3.027, b"AX LT?\n"),
    (3.027, b"AY PS?\n"),
    (3.027, b"AY LT?\n"),
    (3.027, b"AZ PS?\n"),
    (3.028, b"AZ LT?\n"),
    (3.028, b"AT PS?\n"),
    (3.028, b"AT LT?\n"),
    (3.028, b"AM PP;\n"),
    (3.028, b"AM;RI;\n"),
    (3.028, b"AM PP;\n"),
    (3.029, b"AM;CL?;\n"),
    (3.029, b"AM;RV;\n"),
    (3.029, b"AM;EA;\n"),
    (3.029, b"AM;QL;\n"),
    (3.029, b"#WS\n"),
    (5.036, b"AM;RI;\n"),
    (5.036, b"AM PP;\n"),
    (5.036, b"AM;CL?;\n"),
    (5.036, b"AM;RV;\n"),
    (5.037, b"AM;EA;\n"),
    (5.037, b"AM;QL;\n"),
    (5.037, b"#WS\n"),
    (7.041, b"AM;RI;\n"),
    (7.042, b"AM PP;\n"),
    (7.042, b"AM;CL?;\n"),
    (7.042, b"AM;RV;\n"),
    (7.042, b"AM;EA;\n"),
    (7.042, b"AM;QL;\n"),
    (7.042, b"#WS\n"),
    (9.001, b"AX;AC2000;VL1000;VB0;MA777;GO;ID;\n"),
    (9.044, b"AM;RI;\n"),
    (9.045, b"AM PP;\n"),
    (9.045, b"AM;CL?;\n"),
    (9.045, b"AM;RV;\n"),
    (9.045, b"AM;EA;\n"),
    (9.046, b"AM;QL;\n"),
    (9.046, b"#WS\n"),
    (9.206, b"AM;RI;\n"),
    (9.207, b"AM PP;\n"),
    (9.207, b"AM;RV;\n"),
    (9.207, b"AM;EA;\n"),
    (9.207, b"AM;QL;\n"),
    (9.208, b"#WS\n"),
    (9.408, b"AM;RI;\n"),
    (9.409, b"AM PP;\n"),
    (9.409, b"AM;CL?;\n"),
    (9.409, b"AM;RV;\n"),
    (9.409, b"AM;EA;\n"),
    (9.409, b"AM;QL;\n"),
    (9.409, b"#WS\n"),
    (9.610, b"AM;RI;\n"),
    (9.611, b"AM PP;\n"),
    (9.611, b"AM;CL?;\n"),
    (9.611, b"AM;RV;\n"),
    (9.611, b"AM;EA;\n"),
    (9.611, b"AM;QL;\n"),
    (9.612, b"#WS\n"),
    (9.812, b"AM;RI;\n"),
    (9.813, b"AM PP;\n"),
    (9.813, b"AM;CL?;\n"),
    (9.813, b"AM;RV;\n"),
    (9.813, b"AM;EA;\n"),
    (9.813, b"AM;QL;\n"),
    (9.814, b"#WS\n"),
    (10.014, b"AM;RI;\n"),
    (10.015, b"AM PP;\n"),
    (10.015, b"AM;CL?;\n"),
    (10.015, b"AM;RV;\n"),
    (10.015, b"AM;EA;\n"),
    (10.015, b"AM;QL;\n"),
    (10.015, b"#WS\n"),
    (10.216, b"AM;RI;\n"),
    (10.217, b"AM PP;\n"),
    (10.217, b"AM;CL?;\n"),
    (10.217, b"AM;RV;\n"),
    (10.217, b"AM;EA;\n"),
    (10.217, b"AM;QL;\n"),
    (10.217, b"#WS\n"),
    (10.418, b"AM;RI;\n"),
    (10.418, b"AM PP;\n"),
    (10.419, b"AM;CL?;\n"),
    (10.419, b"AM;RV;\n"),
    (10.419, b"AM;EA;\n"),
    (10.419, b"AM;QL;\n"),
    (10.419, b"#WS\n"),
    (10.620, b"AM;RI;\n"),
    (10.621, b"AM PP;\n"),
    (10.621, b"AM;CL?;\n"),
    (10.621, b"AM;RV;\n"),
    (10.621, b"AM;EA;\n"),
    (10.621, b"AM;QL;\n"),
    (10.622, b"#WS\n"),
    (10.822, b"AM;RI;\n"),
    (10.823, b"AM PP;\n"),
    (10.823, b"AM;CL?;\n"),
    (10.823, b"AM;RV;\n"),
    (10.824, b"AM;EA;\n"),
    (10.824, b"AM;QL;\n"),
    (10.824, b"#WS\n"),
    (11.026, b"AM;RI;\n"),
    (11.026, b"AM PP;\n"),
    (11.026, b"AM;CL?;\n"),
    (11.026, b"AM;RV;\n"),
    (11.026, b"AM;EA;\n"),
    (11.027, b"AM;QL;\n"),
    (11.027, b"#WS\n"),
    (13.030, b"AM;RI;\n"),
    (13.031, b"AM PP;\n"),
    (13.031, b"AM;CL?;\n"),
    (13.031, b"AM;RV;\n"),
    (13.031, b"AM;EA;\n"),
    (13.032, b"AM;QL;\n"),
    (13.032, b"#WS\n"),
    (15.037, b"AM;RI;\n"),
    (15.037, b"AM PP;\n"),
    (15.037, b"AM;CL?;\n"),
    (15.038, b"AM;RV;\n"),
    (15.038, b"AM;EA;\n"),
    (15.038, b"AM;QL;\n"),
    (15.038, b"#WS\n"),
    (16.004, b"AX LP42;\nAM;RI;\n"),
    (16.005, b"AM PP;\n"),
    (16.005, b"AM;CL?;\n"),
    (16.005, b"AM;RV;\n"),
    (16.005, b"AM;EA;\n"),
    (16.005, b"AM;QL;\n"),
    (16.005, b"#WS\n"),
    (16.206, b"AM;RI;\n"),
    (16.207, b"AM PP;\n"),
    (16.207, b"AM;CL?;\n"),
    (16.207, b"AM;RV;\n"),
    (16.207, b"AM;EA;\n"),
    (16.207, b"AM;QL;\n"),
    (16.208, b"#WS\n"),
    (16.409, b"AM;RI;\n"),
    (16.409, b"AM PP;\n"),
    (16.409, b"AM;CL?;\n"),
    (16.409, b"AM;RV;\n"),
    (16.409, b"AM;EA;\n"),
    (16.410, b"AM;QL;\n"),
    (16.410, b"#WS\n"),
    (16.611, b"AM;RI;\n"),
    (16.611, b"AM PP;\n"),
    (16.611, b"AM;CL?;\n"),
    (16.611, b"AM;RV;\n"),
    (16.612, b"AM;EA;\n"),
    (16.612, b"AM;QL;\n"),
    (16.612, b"#WS\n"),
    (16.813, b"AM;RI;\n"),
    (16.813, b"AM PP;\n"),
    (16.813, b"AM;CL?;\n"),
    (16.813, b"AM;RV;\n"),
    (16.814, b"AM;EA;\n"),
    (16.814, b"AM;QL;\n"),
    (16.814, b"#WS\n"),
    (17.015, b"AM;RI;\n"),
    (17.015, b"AM PP;\n"),
    (17.015, b"AM;CL?;\n"),
    (17.015, b"AM;RV;\n"),
    (17.015, b"AM;EA;\n"),
    (17.015, b"AM;QL;\n"),
    (17.015, b"#WS\n"),
    (17.216, b"AM;RI;\n"),
    (17.217, b"AM PP;\n"),
    (17.217, b"AM;CL?;\n"),
    (17.217, b"AM;RV;\n"),
    (17.217, b"AM;EA;\n"),
    (17.218, b"AM;QL;\n"),
    (17.218, b"#WS\n"),
    (17.419, b"AM;RI;\n"),
    (17.419, b"AM PP;\n"),
    (17.420, b"AM;CL?;\n"),
    (17.420, b"AM;RV;\n"),
    (17.420, b"AM;EA;\n"),
    (17.420, b"AM;QL;\n"),
    (17.420, b"#WS\n"),
    (17.621, b"AM;RI;\n"),
    (17.621, b"AM PP;\n"),
    (17.622, b"AM;CL?;\n"),
    (17.622, b"AM;RV;\n"),
    (17.622, b"AM;EA;\n"),
    (17.622, b"AM;QL;\n"),
    (17.622, b"#WS\n"),
    (17.823, b"AM;RI;\n"),
    (17.824, b"AM PP;\n"),
    (17.824, b"AM;CL?;\n"),
    (17.824, b"AM;RV;\n"),
    (17.824, b"AM;EA;\n"),
    (17.824, b"AM;QL;\n"),
    (17.825, b"#WS\n"),
    (18.026, b"AM;RI;\n"),
    (18.026, b"AM PP;\n"),
    (18.026, b"AM;CL?;\n"),
    (18.026, b"AM;RV;\n"),
    (18.026, b"AM;EA;\n"),
    (18.027, b"AM;QL;\n"),
    (18.027, b"#WS\n"),
]

# What answers on a MAX board (interop README; omsBaseController.cpp), and which answers carry one
# field per axis in AA/AM mode.
QUERIES = frozenset({"WY", "RP", "PP", "RI", "RV", "EA", "PS?", "LT?", "CL?", "QL", "#WS"})
PER_AXIS = frozenset({"RP", "PP", "RI", "RV", "EA", "CL?"})

# The shape of each answer (PCIx digest §6; MAX-family ones: omsd.board.max_family).
FIELD = {
    "RP": rb"-?\d+",
    "PP": rb"-?\d+",
    "RV": rb"-?\d+",
    "RI": rb"[PM][DN][LN][HN]",  # §6.2, the README's [PM][DN][LN][HN]
    "EA": rb"[ED][ED][SN][PN][PN]",  # §6.3 (home: "P Encoder is at home condition")
    "CL?": rb"on|off",
}
SINGLE = {
    "PS?": rb"=[OEM]",
    "LT?": rb"=[lh]",
    "CL?": rb"=(on|off)",
    "QL": rb"[0-9A-Fa-f]{4}",
    "#WS": rb"=0",
}


def mnemonics(line: bytes) -> list[str]:
    """The commands of one client line, upper case (``AC2000`` is ``AC``, ``PS?`` is ``PS?``)."""
    out = []
    for word in re.split(rb"[;\s]+", line):
        m = re.match(rb"[A-Za-z?#]+", word)
        if m:
            out.append(m.group().upper().decode())
    return out


@dataclass
class Exchange:
    t: float
    sent: bytes
    queries: list[tuple[str, str]]  # mnemonic, and the axis mode it was sent in (X … T, AA, AM)
    before: bytes  # what the board wrote while the clock ran up to ``t``
    data: bytes  # what it wrote in answer to ``sent``
    errors: list[CommandErrorEvent]

    @property
    def replies(self) -> list[bytes]:
        """The reply texts: ``data`` cut after each ``<LF><CR>``."""
        return self.data.split(b"\n\r")[:-1]


def run_trace(h: Harness) -> list[Exchange]:
    """Send every RX line at its time on the board's manual clock."""
    mode = "X"
    out = []
    for t, sent in RX:
        before = h.until(t)
        queries = []
        for m in mnemonics(sent):
            if m in ("AX", "AY", "AZ", "AT"):
                mode = m[1]
            elif m in ("AA", "AM"):
                mode = m
            elif m in QUERIES:
                queries.append((m, mode))
        data = h.send(sent)
        out.append(Exchange(t, sent, queries, before, data, h.errors()))
    return out


@pytest.fixture(scope="module")
def replayed() -> tuple[Harness, list[Exchange]]:
    h = Harness(MODEL)
    return h, run_trace(h)


def answers(exchanges: list[Exchange], mnemonic: str) -> list[tuple[float, str, str]]:
    """Every answer to ``mnemonic``: (time, axis mode, text)."""
    out = []
    for ex in exchanges:
        for (m, mode), text in zip(ex.queries, ex.replies, strict=True):
            if m == mnemonic:
                out.append((ex.t, mode, text.decode("ascii")))
    return out


def reply(h: Harness, line: str) -> str:
    """Send one client line; its one framed answer, without the framing."""
    data = h.send(line)
    assert data.endswith(b"\n\r") and data.count(b"\n\r") == 1, data
    assert data[:1] not in (b"\n", b"\r"), data
    return data[:-2].decode("ascii")


def decode_limits(ql: str, levels: dict[str, str], axes: str) -> dict[str, tuple[bool, bool]]:
    """The client's reading of QL (omsBaseController::omsPoller): bit ``i`` is the low limit and
    bit ``i + 8`` the high limit of axis ``i``, each exclusive-or'ed with "LT? said =l"."""
    bits = int(ql, 16)
    out = {}
    for i, letter in enumerate(axes):
        invert = levels[letter] == "=l"
        low = bool(bits & (1 << i)) ^ invert
        high = bool(bits & (1 << (i + 8))) ^ invert
        out[letter] = (low, high)
    return out


# -- the recording --------------------------------------------------------------------------------


@pytest.mark.skipif(
    not TRACE.exists(),
    reason=f"{TRACE} is absent: the interop traces are kept in ../shared beside the repository,"
    " not in a clone of it",
)
def test_the_copy_is_the_trace() -> None:
    """RX lines and times as recorded; the capture stub answered exactly the commands counted
    here as queries, one TX each (so the classification matches what the client waited for)."""
    lines = TRACE.read_text().splitlines()
    start = float(lines[0].split()[0])
    recorded: list[tuple[float, bytes, list[bytes]]] = []
    for line in lines:
        stamp, kind, *rest = line.split(" ", 2)
        if kind == "RX":
            recorded.append((float(stamp) - start, ast.literal_eval(rest[0]), []))
        elif kind == "TX":
            recorded[-1][2].append(ast.literal_eval(rest[0]))
    assert [sent for _, sent, _ in recorded] == [sent for _, sent in RX]
    for (t, _, _), (copied, _) in zip(recorded, RX, strict=True):
        assert t == pytest.approx(copied, abs=0.001)
    for _, sent, tx in recorded:
        queries = [m for m in mnemonics(sent) if m in QUERIES]
        assert len(b"".join(tx).split(b"\n\r")) - 1 == len(queries), sent


# -- replay: framing, counts, shapes --------------------------------------------------------------


def test_every_query_gets_exactly_one_reply_framed_text_lf_cr(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    _, exchanges = replayed
    for ex in exchanges:
        assert ex.before == b"", (ex.t, ex.before)  # nothing unasked for between the lines
        if not ex.queries:
            assert ex.data == b"", (ex.sent, ex.data)
            continue
        # README: "Replies are text\n\r with no leading LF/CR"
        assert ex.data[:1] not in (b"\n", b"\r"), (ex.sent, ex.data)
        assert ex.data.endswith(b"\n\r"), (ex.sent, ex.data)
        texts = ex.replies
        assert len(texts) == len(ex.queries), (ex.sent, ex.data)
        for text in texts:
            assert text and b"\n" not in text and b"\r" not in text, (ex.sent, ex.data)


def test_no_command_error_on_any_line(replayed: tuple[Harness, list[Exchange]]) -> None:
    _, exchanges = replayed
    assert [(ex.sent, ex.errors) for ex in exchanges if ex.errors] == []


def test_reply_shapes_and_one_field_per_axis(replayed: tuple[Harness, list[Exchange]]) -> None:
    h, exchanges = replayed
    n = len(h.board.model.axes)
    for ex in exchanges:
        for (m, mode), text in zip(ex.queries, ex.replies, strict=True):
            if m == "WY":
                assert re.search(rb"ver:\d+\.\d+", text), text  # the client's "ver:%d.%d"
            elif m in PER_AXIS and mode in ("AA", "AM"):
                fields = text.split(b",")
                assert len(fields) == n, (ex.sent, text)
                for f in fields:
                    assert re.fullmatch(FIELD[m], f), (ex.sent, text)
            else:
                assert re.fullmatch(SINGLE[m], text), (ex.sent, text)


def test_wy_firmware_and_the_queries_the_client_picks_by_it(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    """omsBaseController: ``PS?``/``LT?``/``CL?`` need ``firmwareMin(1,30,0)`` (below it the
    client sends ``?PS``, ``?LS``, ``?PM``), ``#WS`` needs ``fwMinor >= 33``. The recording is of
    a client that saw 1.33; the PCIx's own WY (the manual's example) says 1.26. Both paths are
    answered: the default board parses as 1.26 and answers the pre-1.30 questions by their second
    character as the client reads them; a board configured with ``firmware = "1.33"`` gives the
    recorded client its path."""
    _, exchanges = replayed
    ((_, _, wy),) = answers(exchanges, "WY")
    m = re.search(r"ver:(\d+)\.(\d+)", wy)
    assert m, wy
    assert (int(m[1]), int(m[2])) == (1, 26), wy
    h = Harness(MODEL)
    for letter in "XYZT":
        assert reply(h, f"A{letter} ?PS\n")[1] in "OEM"
        assert reply(h, f"A{letter} ?LS\n")[1] in "lh"
        assert reply(h, f"A{letter} ?PM\n") in ("hn", "hf")
    assert h.errors() == []
    newer = Board(variant(get_model(MODEL), firmware="1.33"))
    newer.receive(b"WY\n", 0.0)
    text = b"".join(o.data for o in newer.take_output() if isinstance(o, Reply)).decode()
    m = re.search(r"ver:(\d+)\.(\d+)", text)
    assert m and (int(m[1]), int(m[2])) >= (1, 33), text


# -- replay: what the answers say -----------------------------------------------------------------


def test_ps_reports_the_servo_axes_of_a_pcix_400(replayed: tuple[Harness, list[Exchange]]) -> None:
    """Appendix C: the PCIX-400 has four servo axes; "=M" is the client's servo (omsBaseController:
    "=O", "=E", "=M"). The trace's ``PSO`` for X and Y cannot rebuild a PCIx (the PCIx "is
    configured at the factory"), so X and Y are still servos."""
    _, exchanges = replayed
    assert [(mode, text) for _, mode, text in answers(exchanges, "PS?")] == [
        ("X", "=M"),
        ("Y", "=M"),
        ("Z", "=M"),
        ("T", "=M"),
    ]


def test_lt_reports_the_lh_of_the_init_string_and_factory_ll(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    """The init line ``AX LH PSO; AY LH PSO;`` makes X and Y active high; Z and T keep the
    factory LL (PCIx LL: "Factory default")."""
    _, exchanges = replayed
    assert [(mode, text) for _, mode, text in answers(exchanges, "LT?")] == [
        ("X", "=h"),
        ("Y", "=h"),
        ("Z", "=l"),
        ("T", "=l"),
    ]


def test_ql_decodes_to_no_limit_on_any_axis(replayed: tuple[Harness, list[Exchange]]) -> None:
    """The stage's limit switches are far from every move of the trace, so the client's reading
    of every QL (with the LT? levels it learnt) shows no limit."""
    h, exchanges = replayed
    axes = h.board.model.axes
    levels = {mode: text for _, mode, text in answers(exchanges, "LT?")}
    qls = answers(exchanges, "QL")
    assert len(qls) == 27
    for _, _, text in qls:
        assert decode_limits(text, levels, axes) == {a: (False, False) for a in axes}, text


def test_cl_is_off_everywhere_servo_loops_power_up_open(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    """HF "is the default mode at power up or reset" and the trace never sends HN."""
    _, exchanges = replayed
    cls = answers(exchanges, "CL?")
    assert len(cls) == 26
    assert {text for _, _, text in cls} == {"off,off,off,off"}


def test_watchdog_counter_is_zero(replayed: tuple[Harness, list[Exchange]]) -> None:
    _, exchanges = replayed
    ws = answers(exchanges, "#WS")
    assert len(ws) == 27
    assert {text for _, _, text in ws} == {"=0"}


@dataclass
class Poll:
    t: float
    ri: list[str]
    pp: list[int] = dataclasses.field(default_factory=list)
    rv: list[int] = dataclasses.field(default_factory=list)


def polls(exchanges: list[Exchange]) -> list[Poll]:
    """The client's status polls, each begun by its ``AM;RI;``."""
    out: list[Poll] = []
    for ex in exchanges:
        for (m, _), text in zip(ex.queries, ex.replies, strict=True):
            fields = text.decode("ascii").split(",")
            if m == "RI":
                out.append(Poll(ex.t, fields))
            elif m == "PP" and out:
                out[-1].pp = [int(f) for f in fields]
            elif m == "RV" and out:
                out[-1].rv = [int(f) for f in fields]
    return out


def sent_at(fragment: bytes) -> float:
    (t,) = [t for t, sent in RX if fragment in sent]
    return t


def test_the_trace_move_runs_and_its_done_flag_shows_in_ri(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    """``AX;AC2000;VL1000;VB0;MA777;GO;ID;``: a linear move (LA is the factory ramp) of 777 counts
    at VL 1000 and AC 2000 takes 777/1000 + 1000/2000 = 1.277 s (ramp up and down 0.5 s each,
    250 counts each). RV is non-zero while it runs; PP climbs to 777; ID sets X's done flag at
    the end, the first RI after it shows ``D`` (README: "the done flag must appear in RI when the
    move completes") and clears it (PCIx RI: "done flags reset")."""
    _, exchanges = replayed
    start = sent_at(b"MA777")
    end = start + 777 / 1000 + 1000 / 2000
    load = sent_at(b"LP42")
    all_polls = polls(exchanges)
    assert len(all_polls) == 27
    for p in all_polls:
        assert len(p.pp) == 4 and len(p.rv) == 4, p
        # Y, Z, T never move and never see an ID
        assert p.pp[1:] == [0, 0, 0] and p.rv[1:] == [0, 0, 0], p
        assert [f[1] for f in p.ri[1:]] == ["N", "N", "N"], p
    before = [p for p in all_polls if p.t < start]
    running = [p for p in all_polls if start < p.t < end - 0.01]
    stopped = [p for p in all_polls if end + 0.01 < p.t < load]
    assert before and running and stopped
    for p in before:
        assert p.pp[0] == 0 and p.rv[0] == 0 and p.ri[0][1] == "N", p
    for p in running:
        assert 0 < p.pp[0] < 777 and p.rv[0] > 0 and p.ri[0][1] == "N", p
    for p in stopped:
        assert p.pp[0] == 777 and p.rv[0] == 0, p
    # done shows once, in the first RI after the move's end
    done = [p.t for p in all_polls if p.ri[0][1] == "D"]
    assert done == [stopped[0].t]
    assert stopped[0].ri[0] == "PDNN"  # moved in the positive direction, no limit, no home
    # the client's view: X read as moving while RV > 0, then done, never five stale polls
    assert all(p.ri[0][0] == "P" for p in running + stopped)


def test_lp_loads_the_position_the_polls_then_report(
    replayed: tuple[Harness, list[Exchange]],
) -> None:
    h, exchanges = replayed
    load = sent_at(b"LP42")
    after = [p for p in polls(exchanges) if p.t >= load]
    assert len(after) == 11
    assert {p.pp[0] for p in after} == {42}
    assert h.position("X") == 42


# -- the extension switched off -------------------------------------------------------------------


MAX_ONLY_LINES = [
    b"AX PS?\n",
    b"AX LT?\n",
    b"AM;CL?;\n",
    b"AM;QL;\n",
    b"#WS\n",
    b"AX PSO;\n",
]


@pytest.mark.parametrize("line", MAX_ONLY_LINES)
def test_without_max_queries_the_extension_is_unknown(line: bytes) -> None:
    """``Model.max_queries`` off: the board is a plain PCIx, and the MAX-family commands are
    command errors (the PCIx manual does not have them), answered by nothing."""
    board = Board(dataclasses.replace(get_model(MODEL), max_queries=False))
    board.receive(line, 0.0)
    out = board.take_output()
    errors = [o for o in out if isinstance(o, CommandErrorEvent)]
    assert errors, line
    assert errors[0].kind in (ErrorKind.UNKNOWN_COMMAND, ErrorKind.BAD_CHARACTER)
    assert [o for o in out if isinstance(o, Reply)] == []
    # the same line on the default model (extension on) is no error
    on = Board(get_model(MODEL))
    on.receive(line, 0.0)
    assert [o for o in on.take_output() if isinstance(o, CommandErrorEvent)] == []


def test_without_max_queries_pcix_commands_still_answer() -> None:
    """Only the extension goes: ``AM PP;`` (a PCIx command) still answers on a plain PCIx."""
    board = Board(dataclasses.replace(get_model(MODEL), max_queries=False))
    board.receive(b"AM PP;\n", 0.0)
    out = board.take_output()
    assert [o.data for o in out if isinstance(o, Reply)] == [b"0,0,0,0\n\r"]
    assert [o for o in out if isinstance(o, CommandErrorEvent)] == []


def test_max_queries_is_on_by_default() -> None:
    assert get_model(MODEL).max_queries is True


# -- the extension's answers follow the board -----------------------------------------------------


PCIX_MODELS = ["PCIX-002", "PCIX-020", "PCIX-202", "PCIX-200", "PCIX-004", "PCIX-040", "PCIX-400"]


@cache
def built(model: str) -> dict[str, str]:
    """Each axis's motor as built, from the model row (Appendix C): servo, stepper with encoder,
    open-loop stepper."""
    m = get_model(model)
    return {a: "=M" if a in m.servo_axes else "=E" if a in m.encoder_axes else "=O" for a in m.axes}


@pytest.mark.parametrize("model", PCIX_MODELS)
def test_ps_answers_each_axis_as_built(model: str) -> None:
    h = Harness(model)
    for letter, expected in built(model).items():
        assert reply(h, f"A{letter} PS?\n") == expected
    assert h.errors() == []


def test_pcix_model_rows_name_their_motors() -> None:
    """Appendix C's naming: PCIX-SEO = servo, stepper-with-encoder and open-loop axis counts."""
    for name in PCIX_MODELS:
        s, e, o = (int(c) for c in name[-3:])
        kinds = list(built(name).values())
        assert (kinds.count("=M"), kinds.count("=E"), kinds.count("=O")) == (s, e, o), name


def test_pso_pse_psm_leave_the_axis_as_built() -> None:
    h = Harness(MODEL)
    for command in ("PSO", "PSE", "PSM"):
        h.send(f"AX {command};\n")
        h.advance(0.01)
        assert reply(h, "AX PS?\n") == "=M"
    assert h.errors() == []


def test_lt_follows_lh_and_ll() -> None:
    h = Harness(MODEL)
    assert reply(h, "AX LT?\n") == "=l"
    h.send("AX LH;\n")
    h.advance(0.01)
    assert reply(h, "AX LT?\n") == "=h"
    assert reply(h, "AY LT?\n") == "=l"
    h.send("AX LL;\n")
    h.advance(0.01)
    assert reply(h, "AX LT?\n") == "=l"
    assert h.errors() == []


def test_ql_reports_the_limit_inputs_the_board_senses() -> None:
    """With X active high (LH) and the rest active low, every combination of X's and Z's switches
    reads back, through the client's decoding, as exactly the limits the board senses."""
    h = Harness(MODEL)
    h.send("AX LH;\n")
    h.advance(0.01)
    axes = h.board.model.axes
    levels = {a: reply(h, f"A{a} LT?\n") for a in axes}
    assert levels == {"X": "=h", "Y": "=l", "Z": "=l", "T": "=l"}
    words = set()
    for x_high in (False, True):
        for z_low in (False, True):
            h.board.set_limit("X", 1, x_high, h.t)
            h.board.set_limit("Z", -1, z_low, h.t)
            ql = reply(h, "AM;QL;\n")
            words.add(ql)
            sensed = {
                a: (h.axis(a).limit_active(-1, h.t), h.axis(a).limit_active(1, h.t)) for a in axes
            }
            assert decode_limits(ql, levels, axes) == sensed, ql
            # single-axis mode reports the whole board as well
            assert reply(h, "AY QL\n") == ql
    assert len(words) == 4  # each switch shows


def test_cl_follows_hn_and_hf_on_a_servo_axis() -> None:
    """HN "closes the loop and enables the PID" of a servo axis, HF opens it."""
    h = Harness(MODEL)
    h.send("AX HN;\n")
    h.advance(0.01)
    assert reply(h, "AX CL?\n") == "=on"
    assert reply(h, "AM;CL?;\n") == "on,off,off,off"
    h.send("AX HF;\n")
    h.advance(0.01)
    assert reply(h, "AX CL?\n") == "=off"
    assert reply(h, "AA CL?;\n") == "off,off,off,off"
    assert h.errors() == []


def test_cl_follows_position_maintenance_on_a_stepper_with_encoder() -> None:
    """A stepper with encoder: HN enables "end-of-move correction" (position maintenance)."""
    h = Harness("PCIX-040")
    h.send("AY HN;\n")
    h.advance(0.01)
    assert reply(h, "AM;CL?;\n") == "off,on,off,off"
    assert reply(h, "AY CL?\n") == "=on"
    assert h.errors() == []


def test_watchdog_answers_in_every_mode() -> None:
    h = Harness(MODEL)
    for line in ("AX #WS\n", "AA #WS\n", "AM #WS\n", "AZ;#WS;\n"):
        assert reply(h, line) == "=0"
    assert h.errors() == []


@pytest.mark.parametrize("query", ["PS?", "LT?"])
def test_per_axis_queries_are_not_valid_in_multi_axis_mode(query: str) -> None:
    """Like the PCIx's own per-axis queries (?LS, EG?: "AA/AM NV")."""
    h = Harness(MODEL)
    assert h.send(f"AM;{query};\n") == b""
    assert [e.kind for e in h.errors()] == [ErrorKind.NOT_VALID_IN_MODE]


def test_closed_loop_and_encoder_load_commands_the_client_sends() -> None:
    """omsBaseController::writeInt32 / writeFloat64: ``A? CL1`` / ``A? CL0`` (firmware 1.30 and
    later; HN/HF before) and ``A? LPE%d;`` (set the encoder position). CL closes and opens the
    servo loop as HN/HF do; LPE loads the encoder (on this servo, whose position is its encoder,
    the position counter too; a stepper's stays: test_reviewed_max_family.py) and must not be
    read as LP0 followed by an unknown ``E``."""
    h = Harness(MODEL)
    h.send("AX CL1\n")
    assert reply(h, "AX CL?\n") == "=on"
    assert reply(h, "AX ?PM\n") == "hn"
    h.send("AX CL0\n")
    assert reply(h, "AX CL?\n") == "=off"
    h.send("AY LPE1234;\n")
    assert reply(h, "AY RE\n") == "1234"
    assert reply(h, "AY RP\n") == "1234"
    assert h.errors() == []
    stepper = Harness("PCIX-004")
    stepper.send("AX CL1\n")  # an open-loop stepper has no loop to close
    assert stepper.errors() != []
