"""Operand ranges, generated from the range tables (:mod:`omsd.dialects.pc48.ranges`,
:mod:`omsd.dialects.pcix.ranges`).

For every row, on a model of every family the row applies to: a value inside the range, both
edges (the first value inside an exclusive edge) and the values just outside are sent to a
board. A value inside is accepted (no "Parameter out of range" command error) and, where a query
or the board's state shows it, takes effect; a value outside sets exactly one OUT_OF_RANGE
command error and changes nothing. A row with a default (PN, PR: "A parameter out of this range
... defaults to 70% or 3 steps") takes the default instead, without an error.

The completeness tests at the end hold the tables to the command tables: every command of every
model that takes a number has a row for its family, every row has a probe here, and no row names
a command its family does not have.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from decimal import Decimal

import pytest

from omsd import dialects as dialect
from omsd.board.events import ErrorKind
from omsd.board.harness import Harness
from omsd.dialects.pc48.ranges import PC48_RANGES
from omsd.dialects.pcix.ranges import PCIX_RANGES
from omsd.models import MODELS
from omsd.protocol.ranges import OperandRange, RangeTable

D = Decimal
TABLES: dict[str, RangeTable] = {"oms": PC48_RANGES, "pcix": PCIX_RANGES}
#: the model each family's rows are tried on (encoder axes, so the encoder commands are valid)
FAMILY_MODEL = {"PC48": "PC48-4E", "PC46": "PC46-4E", "VS4": "VS4-040", "PCIX": "PCIX-040"}
SERVO_MODEL = "PCIX-400"


def frame(h: Harness, text: str) -> bytes:
    """A reply as the board frames it (``<LF><CR>text<LF><CR>`` or ``text<LF><CR>``)."""
    if h.board.model.framing == "trailing":
        return text.encode() + b"\n\r"
    return b"\n\r" + text.encode() + b"\n\r"


Expect = Callable[[Harness, Decimal, object], object]


@dataclass(frozen=True)
class Probe:
    """How to send one operand of one command and see its effect.

    ``send`` builds the command text from the operand's text; ``read`` looks at what it sets
    (a query or the board's state); ``expect(h, value, before)`` is what ``read`` shows after an
    accepted value, given what it showed before (``None``: nothing to compare for this value).
    Without ``read`` only the command errors are checked (the effect is motion or a wait that
    no query shows at once). ``query``: the command answers itself; an accepted value's reply is
    ``expect``, a refused one gives no reply.
    """

    send: Callable[[str], str]
    read: Callable[[Harness], object] | None = None
    expect: Expect | None = None
    setup: str = ""
    tolerated: frozenset[ErrorKind] = frozenset()
    query: bool = False
    servo: bool = False
    skip: Callable[[Decimal], bool] | None = None


def probe(
    template: str,
    read: Callable[[Harness], object] | None = None,
    expect: Expect | None = None,
    **kw: object,
) -> Probe:
    return Probe(lambda v: template.format(v=v), read, expect, **kw)  # type: ignore[arg-type]


def is_(fn: Callable[[Decimal], object]) -> Expect:
    """An expectation that depends on the value only."""
    return lambda h, v, before: fn(v)


def attr(name: str, letter: str = "X") -> Callable[[Harness], object]:
    return lambda h: getattr(h.axis(letter), name)


def query(text: str) -> Callable[[Harness], object]:
    return lambda h: h.query(text)


def reply(text: str) -> Expect:
    """The reply ``text`` (a format string of ``v``), framed as the board frames it."""
    return lambda h, v, before: frame(h, text.format(v=v, i=int(v)))


def gain(name: str) -> Callable[[Harness], object]:
    def read(h: Harness) -> object:
        servo = h.axis("X").servo
        assert servo is not None
        return getattr(servo.gains, name)

    return read


def contour(h: Harness) -> object:
    defn = h.board.interpreter.contour
    return None if defn is None else (defn.start, list(defn.items))


def contour_arc(x: Decimal, y: Decimal, angle: Decimal) -> object:
    from omsd.engine.contour import Arc

    return ((0.0, 0.0), [Arc((float(int(x)), float(int(y))), float(angle))])


def pending(h: Harness) -> object:
    p = h.axis("X").pending
    return None if p is None else p.value


def in_arm(h: Harness) -> object:
    arm = h.axis("X").in_arm
    return None if arm is None else arm[0]


def low_bits(h: Harness) -> object:
    return h.board.io_bits_low(h.t)


def bit(low: bool) -> Expect:
    """BL/BH: the output goes low/high (an input bit is refused with its own error)."""

    def expect(h: Harness, v: Decimal, before: object) -> object:
        n = int(v)
        if not h.board.directions >> n & 1:
            return None  # "only valid for bits which have been configured as outputs"
        assert isinstance(before, int)
        return before | (1 << n) if low else before & ~(1 << n)

    return expect


def rate_of(h: Harness) -> object:
    return h.query("AY;EG?;")


def jog_vl(h: Harness, v: Decimal, before: object) -> object:
    """JG: "This command modifies the move velocity parameter (VL)" (whole steps; JG0 stops and
    leaves VL)."""
    return abs(whole(v)) if int(v) != 0 else before


def jf_vl(h: Harness, v: Decimal, before: object) -> object:
    """JF: "The parameter may include a fractional part"."""
    return float(abs(v)) if v != 0 else before


def whole(v: Decimal) -> float:
    return float(int(v))


NOT_AN_OUTPUT = frozenset({ErrorKind.NOT_AN_OUTPUT})
AJ_DEFAULTS = ["0.00000000", "0.00000000", "1.00000000", "0.00000000", "0.00000000", "1.00000000"]


def aj_field(k: int) -> Probe:
    """AJ's operand ``k`` (2-7): profile 1 with only that parameter given; ?AJ1 shows it."""

    def read(h: Harness) -> object:
        return h.query("AX;?AJ1;").decode().strip().split(",")[k - 1]

    return Probe(lambda v: "AX;AJ1" + "," * (k - 1) + v + ";", read, is_(lambda v: f"{v:.8f}"))


def rv(letter: str, pcix: bool) -> Callable[[Harness], object]:
    """VS velocities: RV of the axis 2 ms into the stream ("without acceleration")."""

    def read(h: Harness) -> object:
        h.advance(0.002)
        return h.query(f"A{letter};RV;" if pcix else f"A{letter} RV")

    return read


CD = "AA CD0,0; "  # a two-axis contour definition for CR

PC48_PROBES: dict[tuple[str, int], Probe] = {
    ("PN", 1): probe("PN{v} ", lambda h: h.board.ramp.steps, is_(int)),
    ("AN", 1): probe("AA AN{v}; ", attr("aux"), is_(lambda v: True), setup="AX AF "),
    ("AF", 1): probe("AA AF{v}; ", attr("aux"), is_(lambda v: False)),
    ("PA", 1): probe("AX PA{v} ", attr("pa"), is_(lambda v: v == 0)),
    ("SE", 1): probe("AX SE{v} ", attr("se_ms"), is_(int)),
    ("BL", 1): probe("AX BL{v} ", low_bits, bit(True), tolerated=NOT_AN_OUTPUT),
    ("BH", 1): probe("AX BH{v} ", low_bits, bit(False), tolerated=NOT_AN_OUTPUT),
    ("AC", 1): probe("AX AC{v} ", attr("ac"), is_(whole)),
    ("VL", 1): probe("AX VL{v} ", attr("vl"), is_(whole)),
    ("VB", 1): probe("AX VB{v} ", attr("vb"), is_(whole)),
    ("LP", 1): probe("AX LP{v} ", query("AX RP"), reply("{i}")),
    ("MA", 1): probe("AX MA{v} ", pending, is_(whole)),
    ("MR", 1): probe("AX MR{v} ", pending, is_(whole)),
    ("ML", 1): probe("AA ML{v}; ", pending, is_(whole)),
    ("MT", 1): probe("AA MT{v}; ", pending, is_(whole)),
    ("RM", 1): probe(
        "AX RM{v} ",
        query("AX RP"),
        lambda h, v, before: frame(h, str(12345 % int(v))),
        setup="AX LP12345 ",
    ),
    ("JG", 1): probe("AX JG{v} ", attr("vl"), jog_vl),
    ("JF", 1): probe("AX JF{v} ", attr("vl"), jf_vl),
    ("VS", 1): probe("AX VS{v},0,0 "),
    ("VS", 2): probe("AX VS1000,{v},0 ", rv("X", False), reply("{i}")),
    ("VS", 3): probe("AX VS1000,0,{v} ", rv("Y", False), reply("{i}")),
    ("LS", 1): probe("AX LS{v} ", lambda h: len(h.board.interpreter.loops[0]), is_(lambda v: 1)),
    ("WS", 1): probe(
        "AX WS{v} ", lambda h: h.board.interpreter.ws_bits.get(0), is_(lambda v: [(int(v), False)])
    ),
    ("HM", 1): probe("AX HM{v} "),
    ("HR", 1): probe("AX HR{v} "),
    ("IN", 1): probe("AX IN{v} ", in_arm, is_(whole)),
    ("SW", 1): probe("AX SW{v} "),
    ("WT", 1): probe("AX WT{v} "),
    ("UU", 1): probe("AX UU{v} ", attr("uu"), is_(lambda v: None if v == 1 else v)),
    ("ER", 1): probe("AX ER{v},2 ", attr("ratio"), is_(lambda v: float(v) / 2)),
    ("ER", 2): probe("AX ER2,{v} ", attr("ratio"), is_(lambda v: 2 / float(v))),
    ("HV", 1): probe("AX HV{v} ", attr("hv"), is_(whole)),
    ("HG", 1): probe("AX HG{v} ", attr("hg"), is_(whole)),
    ("HD", 1): probe("AX HD{v} ", attr("hd"), is_(whole)),
    ("ES", 1): probe("AX ES{v} ", attr("es"), is_(whole)),
    ("MV", 1): probe("AX MP MV{v},1000 "),
    ("MV", 2): probe("AX MP MV1000000,{v} "),
    ("SP", 1): probe("AX SP{v} "),
    ("FP", 1): probe("AX FP{v} "),
    ("CD", 1): probe("AA CD{v},0; ", contour, is_(lambda v: ((whole(v), 0.0), []))),
    ("CR", 1): probe("CR{v},5,1; ", contour, is_(lambda v: contour_arc(v, D(5), D(1))), setup=CD),
    ("CR", 2): probe("CR5,{v},1; ", contour, is_(lambda v: contour_arc(D(5), v, D(1))), setup=CD),
    ("CR", 3): probe("CR5,5,{v}; ", contour, is_(lambda v: contour_arc(D(5), D(5), v)), setup=CD),
    ("CV", 1): probe("AA CV{v} ", lambda h: h.board.contour_velocity, is_(float)),
    ("LN", 1): probe("AA LN{v},,,; ", attr("limits_on"), is_(lambda v: True), setup="AX LF "),
    ("LF", 1): probe("AA LF{v},,,; ", attr("limits_on"), is_(lambda v: False)),
    ("SL", 1): probe("AA SL{v},,,; ", attr("soft_limit"), is_(lambda v: True)),
    ("SF", 1): probe("AA SF{v},,,; ", attr("soft_limit"), is_(lambda v: False), setup="AX SL "),
}


def flag(mnemonic: str, name: str, value: object, setup: str = "") -> Probe:
    """A PCIx b-list command in AA mode: the value only picks the axis (X here)."""
    return probe(f"AA;{mnemonic}{{v}},;", attr(name), is_(lambda v: value), setup=setup)


def tl_skip(operand: int) -> Callable[[Decimal], bool]:
    """TL upper,lower: an upper limit at the bottom of the range (a lower one at the top) leaves
    no room for the other limit, an error of its own ("lower limit above the upper one")."""
    edge = D(-33_554_431) if operand == 1 else D(33_554_431)
    return lambda v: int(v) == edge


def servo_gain(mnemonic: str, places: int | None) -> Probe:
    text = f"{mnemonic.lower()}{{i}}" if places is None else f"{mnemonic.lower()}{{v:.2f}}"
    return probe(f"AX;{mnemonic}{{v}};", query(f"AX;?{mnemonic};"), reply(text), servo=True)


def ramp_kind(h: Harness) -> object:
    return h.axis("X").ramp.kind.name


def table_points(h: Harness) -> object:
    return list(h.board.interpreter.table_points)


PCIX_PROBES: dict[tuple[str, int], Probe] = {
    ("?AJ", 1): probe(
        "AX;?AJ{v};", expect=reply("{i}.0000000," + ",".join(AJ_DEFAULTS)), query=True
    ),
    ("?DA", 1): probe(
        "AX;?DA{v};", expect=is_(lambda v: f"DAR{int(v)}\n\rDAE\n\r".encode()), query=True
    ),
    ("?DE", 1): probe("AX;?DE{v},1;", expect=is_(lambda v: b"\n\r"), query=True),
    ("?DE", 2): probe("AX;?DE1,{v};", expect=is_(lambda v: b"\n\r"), query=True),
    ("?DS", 1): probe("AX;?DS{v};", expect=reply("ds0"), query=True),
    ("AC", 1): probe("AX;AC{v};", query("AX;?AC;"), reply("ac{i}")),
    ("AF", 1): flag("AF", "aux", False),
    ("AN", 1): flag("AN", "aux", True, setup="AX;AF;"),
    ("AJ", 1): probe(
        "AX;AJ{v},0.5;",
        lambda h: sorted(h.board.scurves),
        lambda h, v, before: sorted({*before, int(v)}),  # type: ignore[misc]
    ),
    **{("AJ", k): aj_field(k) for k in range(2, 8)},
    ("BC", 1): probe("AX;BC{v};", query("AX;?BC;"), reply("bc{i}")),
    ("BH", 1): probe("AX;BH{v};", low_bits, bit(False), tolerated=NOT_AN_OUTPUT),
    ("BL", 1): probe("AX;BL{v};", low_bits, bit(True), tolerated=NOT_AN_OUTPUT),
    # outputs 4-7 take the mask; inputs 0-3 read high ("Data written to input bits has no
    # effect")
    ("BS", 1): probe(
        "AX;BS{v};", query("BX;"), lambda h, v, before: frame(h, f"{(int(v) & 0xF0) | 0x0F:02x}")
    ),
    ("BW", 1): probe("AX;BW{v};"),
    ("CA", 1): probe("AA;CA{v},;"),
    ("CD", 1): probe("AA;CD{v},0;", contour, is_(lambda v: ((whole(v), 0.0), []))),
    ("CR", 1): probe("CR{v},5,1;", contour, is_(lambda v: contour_arc(v, D(5), D(1))), setup=CD),
    ("CR", 2): probe("CR5,{v},1;", contour, is_(lambda v: contour_arc(D(5), v, D(1))), setup=CD),
    ("CR", 3): probe("CR5,5,{v};", contour, is_(lambda v: contour_arc(D(5), D(5), v)), setup=CD),
    ("CV", 1): probe("AA;CV{v};", lambda h: h.board.contour_velocity, is_(float)),
    ("DAB", 1): probe("DAR1;DAB{v},1;", table_points, is_(lambda v: [(float(v), 1.0)])),
    ("DAB", 2): probe("DAR1;DAB1,{v};", table_points, is_(lambda v: [(1.0, float(v))])),
    ("DAR", 1): probe("DAR{v};", lambda h: h.board.interpreter.table, is_(int)),
    ("DBI", 1): flag("DBI", "direction_inverted", True),
    ("DBN", 1): flag("DBN", "direction_inverted", False, setup="AX;DBI;"),
    ("DC", 1): probe("AX;DC{v};", query("AX;?DC;"), reply("dc{i}")),
    ("DZ", 1): probe("AX;DZ{v};", gain("dz"), is_(whole), servo=True),
    # the gear rate |ratio| x master VL: X's VL is 1000, so the ratio sent is the rate / 1000
    ("EG", 1): Probe(
        lambda v: f"AY;EGX{D(v) / 1000};",
        rate_of,
        lambda h, v, before: frame(h, f"=egx{v / 1000}"),
        setup="AX;VL1000;",
    ),
    ("TX", 1): Probe(
        lambda v: f"AY;TX{D(v) / 1000};",
        rate_of,
        lambda h, v, before: frame(h, f"=egx{v / 1000}"),
        setup="AX;VL1000;",
    ),
    ("ER", 1): probe("AX;ER{v},2;", attr("ratio"), is_(lambda v: float(v) / 2)),
    ("ER", 2): probe("AX;ER2,{v};", attr("ratio"), is_(lambda v: 2 / float(v))),
    ("ES", 1): probe("AX;ES{v};", query("AX;?ES;"), reply("es{i}")),
    ("FP", 1): probe("AX;FP{v};"),
    ("HD", 1): probe("AX;HD{v};", query("AX;?HD;"), reply("hd{i}")),
    ("HE", 1): flag("HE", "home_encoder", True),
    ("HF", 1): flag("HF", "hold", False, setup="AX;HN;"),
    ("HG", 1): probe("AX;HG{v};", query("AX;?HG;"), reply("hg{i}")),
    ("HH", 1): flag("HH", "home_high", True),
    ("HL", 1): flag("HL", "home_high", False, setup="AX;HH;"),
    ("HM", 1): probe("AX;HM{v};"),
    ("HN", 1): flag("HN", "hold", True),
    ("HR", 1): probe("AX;HR{v};"),
    ("HS", 1): flag("HS", "home_encoder", False, setup="AX;HE;"),
    ("HV", 1): probe("AX;HV{v};", query("AX;?HV;"), reply("hv{i}")),
    ("IN", 1): probe("AX;IN{v};", in_arm, is_(whole)),
    ("JF", 1): probe("AX;JF{v};", attr("vl"), jf_vl),
    ("JG", 1): probe("AX;JG{v};", attr("vl"), jog_vl),
    **{(m, 1): servo_gain(m, 2) for m in ("KA", "KB", "KD", "KI", "KP", "KV")},
    **{(m, 1): servo_gain(m, None) for m in ("KF", "KU", "KO")},
    ("KS", 1): probe("AA;KS{v},;"),
    ("LA", 1): probe("AA;LA{v},;", ramp_kind, is_(lambda v: "LINEAR"), setup="AX;SC;"),
    ("SC", 1): probe("AA;SC{v},;", ramp_kind, is_(lambda v: "COSINE")),
    ("LF", 1): flag("LF", "limits_on", False),
    ("LN", 1): flag("LN", "limits_on", True, setup="AX;LF;"),
    ("LH", 1): flag("LH", "limit_high", True),
    ("LL", 1): flag("LL", "limit_high", False, setup="AX;LH;"),
    ("SF", 1): flag("SF", "soft_limit", False, setup="AX;SL;"),
    ("SL", 1): flag("SL", "soft_limit", True),
    ("UF", 1): flag("UF", "uu", None, setup="AX;UU2;"),
    ("PH", 1): flag("PH", "aux", True, setup="AX;PL;"),
    ("PL", 1): flag("PL", "aux", False),
    ("SI", 1): probe("AA;SI{v},;"),
    ("LO", 1): probe("AX;LO{v};", query("AX;RP;"), reply("{i}")),
    ("LP", 1): probe("AX;LP{v};", query("AX;RP;"), reply("{i}")),
    ("LPE", 1): probe("AX;LPE{v};", query("AX;RE;"), reply("{i}")),  # (the encoder)
    ("CL", 1): probe("AX;CL{v};", attr("hold"), is_(lambda v: v != 0)),
    ("LS", 1): probe("AX;LS{v};", lambda h: len(h.board.interpreter.loops[0]), is_(lambda v: 1)),
    ("MA", 1): probe("AX;MA{v};", pending, is_(whole)),
    ("MR", 1): probe("AX;MR{v};", pending, is_(whole)),
    ("ML", 1): probe("AA;ML{v};", pending, is_(whole)),
    ("MT", 1): probe("AA;MT{v};", pending, is_(whole)),
    ("MD", 1): probe(
        "MD{v};", lambda h: getattr(h.board.interpreter.capture, "slot", None), is_(int)
    ),
    ("MX", 1): probe("MX{v};", tolerated=frozenset({ErrorKind.NO_MACRO})),
    ("PM", 1): probe("PM{v};"),
    ("PT", 1): probe("PT{v},5;", tolerated=frozenset({ErrorKind.NO_MACRO})),
    ("PT", 2): probe("PT0,{v};", tolerated=frozenset({ErrorKind.NO_MACRO})),
    ("MV", 1): probe("AX;MP;MV{v},1000;"),
    ("MV", 2): probe("AX;MP;MV1000000,{v};"),
    ("NV", 1): probe("NV{v};", setup="AA;CD0,0;"),
    ("PA", 1): probe(
        "AX;PA{v};", query("AX;?PA;"), is_(lambda v: b"pa0\n\r" if v == 0 else b"pa1\n\r")
    ),
    ("PN", 1): probe("PN{v};", query("AX;?RT;"), reply("pr{i}")),
    ("PR", 1): probe("AX;PR{v};", query("AX;?RT;"), reply("pr{i}")),
    ("RM", 1): probe(
        "AX;RM{v};",
        query("AX;RP;"),
        lambda h, v, before: frame(h, str(12345 % int(v))),
        setup="AX;LP12345;",
    ),
    ("SE", 1): probe("AX;SE{v};", query("AX;?SE;"), reply("se{i}")),
    ("SO", 1): probe("AX;SO{v},100;"),
    ("SO", 2): probe("AX;SO1000,{v};"),
    ("SP", 1): probe("AX;SP{v};"),
    ("SR", 1): probe(
        "AX;SR{v};",
        query("AX;?RT;"),
        reply("sr{i}"),
        setup="".join(f"DAR{n};DAB1,1;DAE;" for n in range(1, 5)),
    ),
    ("SS", 1): probe("AX;SS{v};", query("AX;?RT;"), reply("ss{i}"), setup="AX;AJ1;AJ2;AJ3;AJ4;"),
    ("SW", 1): probe("AX;SW{v};"),
    ("TL", 1): probe(
        "AX;TL{v},-33554431;", query("AX;?TL;"), reply("tl{i},-33554431"), skip=tl_skip(1)
    ),
    ("TL", 2): probe(
        "AX;TL33554431,{v};", query("AX;?TL;"), reply("tl33554431,{i}"), skip=tl_skip(2)
    ),
    ("TM", 1): probe("AX;TM{v};"),
    ("UU", 1): probe("AX;UU{v};", attr("uu"), is_(lambda v: None if v == 1 else v)),
    ("VB", 1): probe("AX;VB{v};", query("AX;?VB;"), reply("vb{i}")),
    ("VL", 1): probe("AX;VL{v};", query("AX;?VL;"), reply("vl{i}")),
    ("VS", 1): probe("AX;VS{v},0,0;"),
    ("VS", 2): probe("AX;VS1000,{v},0;", rv("X", True), reply("{i}")),
    ("VS", 3): probe("AX;VS1000,0,{v};", rv("Y", True), reply("{i}")),
    ("WS", 1): probe(
        "AX;WS{v};", lambda h: h.board.interpreter.ws_bits.get(0), is_(lambda v: [(int(v), False)])
    ),
    ("WT", 1): probe("AX;WT{v};"),
}

PROBES: dict[str, dict[tuple[str, int], Probe]] = {"oms": PC48_PROBES, "pcix": PCIX_PROBES}


# -- the values tried for a row -------------------------------------------------------------------


def dec(x: float) -> Decimal:
    return Decimal(repr(x)) if isinstance(x, float) else Decimal(x)


def values(row: OperandRange, axes: int) -> list[tuple[Decimal, bool]]:
    """(value, inside) pairs: a middle value, both edges (the first value inside an exclusive
    edge), the values just outside; for a whole-number row also a fraction above the top edge,
    which is truncated into the range ("MR100.9 moves 100")."""
    if row.number == "flag":
        return [(D(0), True), (D(1), True), (D(-3), True), (D(250), True)]
    step = D(1) if row.number in ("integer", "hex") else D("0.001")
    low, high = row.edges(axes)
    out: list[tuple[Decimal, bool]] = []
    lo = None if low is None else dec(low)
    hi = None if high is None else dec(high)
    if lo is not None:
        if row.low_open:
            out += [(lo + step, True), (lo, False)]
        else:
            out += [(lo, True), (lo - step, False)]
            if row.number == "decimal":
                out.append((lo - 1, False))
    if hi is not None:
        if row.high_open:
            out += [(hi - step, True), (hi, False)]
        else:
            out += [(hi, True), (hi + step, False)]
            if row.number == "decimal":
                out.append((hi + 1, False))
            if row.number == "integer" and hi >= 0 and not row.magnitude:
                out.append((hi + D("0.5"), True))
    if lo is not None and hi is not None:
        mid = (lo + hi) / 2
        out.append((mid.to_integral_value() if step == 1 else mid.quantize(D("0.001")), True))
    elif lo is not None:
        out.append((lo + 7, True))
    else:
        out += [(D("1.5"), True), (D("-2.25"), True)]
    if row.magnitude:
        out += [(-v, inside) for v, inside in out if v > 0]
    if row.number == "hex":
        out = [(v, inside) for v, inside in out if v >= 0]
    seen: dict[Decimal, bool] = {}
    for v, inside in out:
        seen.setdefault(v, inside)
    return list(seen.items())


def text(row: OperandRange, v: Decimal) -> str:
    if row.number == "hex":
        return f"{int(v):X}"
    if v == v.to_integral_value():
        return str(int(v))
    return format(v.normalize(), "f")


def model_for(row: OperandRange, family: str, probe_: Probe) -> str:
    if family == "PCIX" and (probe_.servo or row.variant == "servo"):
        return SERVO_MODEL
    return FAMILY_MODEL[family]


def _cases() -> list[object]:
    out: list[object] = []
    for dialect_name, table in TABLES.items():
        probes = PROBES[dialect_name]
        for family in table.families:
            for row in table.for_family(family):
                probe_ = probes.get((row.mnemonic, row.operand))
                if probe_ is None:
                    continue  # test_every_row_has_a_probe reports it
                model = model_for(row, family, probe_)
                axes = len(MODELS[model].axes)
                for v, inside in values(row, axes):
                    if probe_.skip is not None and probe_.skip(v):
                        continue
                    variant = f"-{row.variant}" if row.variant else ""
                    ident = f"{model}-{row.mnemonic}{variant}#{row.operand}={text(row, v)}"
                    out.append(pytest.param(model, row, probe_, v, inside, id=ident))
    return out


@pytest.mark.parametrize(("model", "row", "probe_", "value", "inside"), _cases())
def test_operand_range(
    model: str, row: OperandRange, probe_: Probe, value: Decimal, inside: bool
) -> None:
    """The row's edges as the board applies them: inside accepted and in effect, outside one
    OUT_OF_RANGE error and nothing changed (a row with a default: the default, no error)."""
    h = Harness(model)
    if probe_.setup:
        h.send(probe_.setup)
    assert h.errors() == []
    before = probe_.read(h) if probe_.read is not None else None
    out = h.send(probe_.send(text(row, value)))
    kinds = [e.kind for e in h.errors()]
    defaulted = not inside and row.default is not None
    if inside or defaulted:
        assert ErrorKind.OUT_OF_RANGE not in kinds, row.describe()
        assert set(kinds) <= probe_.tolerated, kinds
        shown = row.default if defaulted else value
        assert shown is not None
        if probe_.query:
            assert probe_.expect is not None
            assert out == probe_.expect(h, D(shown), None)
        elif probe_.read is not None and probe_.expect is not None and not kinds:
            want = probe_.expect(h, D(shown), before)
            if want is not None:
                assert probe_.read(h) == want
    else:
        assert kinds == [ErrorKind.OUT_OF_RANGE], row.describe()
        if probe_.query:
            assert out == b""
        elif probe_.read is not None:
            assert probe_.read(h) == before


# -- completeness -------------------------------------------------------------------------------


def _numeric_commands() -> list[object]:
    out = []
    for model in MODELS.values():
        for mnemonic, spec in dialect.commands(model).items():
            if spec.operand or spec.hex_operand or spec.letter_operand:
                out.append(pytest.param(model.name, mnemonic, id=f"{model.name}-{mnemonic}"))
    return out


@pytest.mark.parametrize(("model", "mnemonic"), _numeric_commands())
def test_every_numeric_command_has_a_row(model: str, mnemonic: str) -> None:
    """A command that takes a number cannot be added to a model's table without its range."""
    m = MODELS[model]
    assert dialect.ranges(m).covers(mnemonic, m.family), f"{mnemonic} has no range row"


def test_every_row_has_a_probe() -> None:
    missing = [
        (name, row.mnemonic, row.operand)
        for name, table in TABLES.items()
        for row in table.rows
        if (row.mnemonic, row.operand) not in PROBES[name]
    ]
    assert missing == []


def test_every_row_names_a_command_of_its_families() -> None:
    """No stale rows: each row's command is in the table of a model of each of its families."""
    for table in TABLES.values():
        for row in table.rows:
            for family in row.families or table.families:
                models = [m for m in MODELS.values() if m.family == family]
                assert any(row.mnemonic in dialect.commands(m) for m in models), (family, row)


def test_rows_cite_the_manual_or_record_a_choice() -> None:
    """Each row quotes its manual (a seeds file) or says what was chosen and why."""
    prefixes = ("manual silent: ", "manual contradicts itself: ", "chosen: ", "note: ")
    for table in TABLES.values():
        for row in table.rows:
            assert row.cite or row.choice.startswith(prefixes[:2]), row
            assert not row.cite or "seeds/" in row.cite, row
            assert not row.choice or row.choice.startswith(prefixes), row


def test_model_limits_agree_with_the_tables() -> None:
    """The velocity and position numbers a model row still carries (descriptive) are the
    tables' edges."""
    for model in MODELS.values():
        table = dialect.ranges(model)
        vl = table.lookup("VL", 1, model.family)
        lp = table.lookup("LP", 1, model.family)
        ma = table.lookup("MA", 1, model.family)
        jg = table.lookup("JG", 1, model.family)
        assert vl.high == model.max_velocity, model.name
        assert lp.high == model.load_position_limit, model.name
        assert ma.high == model.position_limit, model.name
        assert jg.high == model.jog_limit, model.name
        bits = table.lookup("BL", 1, model.family)
        assert bits.high == model.io_bits - 1, model.name


def test_aj_profile_up_to_the_number_of_axes() -> None:
    """AJ: "Range: 1 ≤ # ≤ number of axes on board": a two-axis board has profiles 1 and 2."""
    h = Harness("PCIX-020")
    h.send("AX;AJ2,0.5;AJ3,0.5;")
    assert [e.kind for e in h.errors()] == [ErrorKind.OUT_OF_RANGE]
    assert sorted(h.board.scurves) == [2]


def test_the_tables_are_self_contained_data() -> None:
    """The range modules import the standard library and the row type only (a later dialect
    package takes them as they are)."""
    import ast
    import importlib.util

    for name in ("omsd.protocol.ranges", "omsd.dialects.pc48.ranges", "omsd.dialects.pcix.ranges"):
        spec = importlib.util.find_spec(name)
        assert spec is not None and spec.origin is not None
        with open(spec.origin, encoding="utf-8") as f:
            tree = ast.parse(f.read())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("omsd"):
                assert node.module == "omsd.protocol.ranges", (name, node.module)
            if isinstance(node, ast.Import):
                assert not any(a.name.startswith("omsd") for a in node.names), name
