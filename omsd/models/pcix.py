"""The PCIx family (PCI bus): "USER'S MANUAL, INTELLIGENT MOTOR CONTROLLERS For PCI bus, PCIx
FAMILY", OMS Motion, 2005, document 3301-0800000 rev C (``shared/seeds/002_…``; digest
``shared/reference/pcix.md``).

The command table holds the 203 entries of the manual's ALPHABETICAL COMMAND SUMMARY (§5.3),
each with the QUEUE REQUIREMENTS table printed on its command page (§5.13). The summary's
"SQ"/"?SQ" are SO/?SO: the section tables, the command pages and the index all say SO. The PC48's
EN, EF, RS, AR, AS, AU, AV are not PCIx commands (digest §8.1) and are absent.

How the tables are read
-----------------------

* Add-ons. A ``*`` entry is the printed number plus the notes under the table: "If the axis is a
  stepper and encoder or servo axis add n" (``addons(encoder=n)``: charged on an axis with an
  encoder, which every servo axis has), "If PA (power automatic) mode is active add n"
  (``pa=n``), "If an auxiliary output bit settle time has been specified add n" (``settle=n``).
* Ramp columns. AC ("Linear ( LA or PF ) 6 … All other Parabolic Forms 15 … Custom Ramps ( SR )
  3 + (No. of ramp segments +12) … S-curve ( AJ ) 69") becomes ``qr(6, 15, 15, 15, 69) +
  addons(segments=1)``. A table without a cosine row takes the parabolic number; the "Short
  Parabolic ( PN0; or PR0; )" rows are never used: PN/PR take 3..10 steps and "A parameter out of
  this range or no parameter supplied defaults to 70% or 3 steps" (PN), so a short-form ramp
  cannot be selected and the "All other Parabolic" number is the parabolic column everywhere.
* VL: "2*" with "All other PN and PR ramp selections add 9", "CN and SC ramp selections add 9",
  "SR (custom) ramp selections add (number of steps in ramp -1)"; nothing is said for S-curves,
  which therefore cost the base 2.
* MA, MR, ML, MT: "If the axis is using the cosine acceleration ramp, and velocity needs to be
  adjusted so the profile is not truncated, add 11" (S-curve: 44). Whether the velocity must be
  reduced depends on the distance and on the AC/VL in force when the move runs, which may still
  be waiting in the queue when the command is parsed, so the 11/44 are charged on every move made
  with those ramps (the manual: "The queue requirements shown in the tables are typical").
* ML/MT's rows for an axis that is not the master ("If this is not the master axis, then the
  acceleration and velocity values will be modified, and the following queue requirements will
  be added": ML linear 6, parabolic 20, cosine 20, custom "6 + (2 x number of ramp segments)",
  S-curve 113; MT 6, 26, 26, the same, 113) are ``CommandSpec.follower``, charged when the
  command is read on every axis of the move but the master, as the registers and positions then
  foretell it (the master is the axis with the longest move time; an axis left where it is is
  not modified).
  The master's own row ("If this is the master axis for this move and its acceleration and
  velocity values need to be reset ... because a previous move altered them") prints no numbers
  of its own, and omsd gives the values back as each linear move starts: not charged.
* Not charged: the "Ramp add-ons" that MA, MR and JG need only "because the last move just prior
  to this move was either a MT or ML move": they depend on the previous move; the manual calls
  its numbers "typical" and "Depending on the circumstances … the actual queue requirement may
  vary slightly", so the table keeps the unconditional part.
* CX and CG: their "ADDITIONAL QUEUE REQUIREMENTS" by ramp type ("Add the following queue
  requirements for the ramp types listed") are unconditional and are charged: CG "Linear ( PF,
  LA ) 8", CX has no linear row (0). Custom "6 + (2 x number of ramp segments)".
* Stops that flush. ST ("flushes the queue for the current axis"), SA, SD, SI (= ST in single-axis
  mode, "can be used in place of SA"), KL ("flush the command queues"), KS ("flush only the
  selected axes' command queues") and FP ("will flush the command queue") are ``flush(n)``: the
  queue is emptied on receipt, then the printed units are queued (digest §8.2 39: "perform the
  stop/kill/flush at receipt and account the listed queue units").
* CD inside a contour definition: "AA/CD N/A" = not valid (a definition cannot be nested).

What a cell cannot hold (the handler must add it)
--------------------------------------------------

* HN: "Values in table are for a stepper with encoder axis. For a servo axis the command queue
  requires 2." A cell tells encoder axes from open-loop ones, not servos from steppers with
  encoders; the table holds the stepper-with-encoder 1.
* SR: "7 + (2* number of segments in ramp definition)" counts the segments of the table being
  selected, not of the axis's current ramp (which is what ``Cell.cost`` is given); the table
  holds the 7.

Where the manual contradicts itself (digest §8.2)
-------------------------------------------------

* BC: the BC command page prints "BC; AX – AT Immediate", the §5.12.3 backlash example's table
  "BC#; AX – AT 1". The command's own page wins, as for the PC48's BH/BL: immediate.
* RQ: immediate in every mode, contour definition included ("RQ AA/CD Immediate"); unlike the
  PC48 manual the PCIx prints one consistent table.
* IN: "This command is valid in all modes" but its table says "AA/CD Not Valid": the table wins.
* DZ: the summary marks it "Q" (a query) and its page says "used in the open-loop mode with Hold
  Off ( HE )": it is a command taking an operand (``DZ250;``) with two queue units, for servo
  axes (the HF open loop, HE being the home-encoder command).
* KD: the summary leaves its Q/C column blank; it is a command like KP. Its factory default
  (KD page "20.00" vs §2.8 "160.0") is a value, not part of this table.
* WS/WD: the WS page prints the syntax as "WD#[,state];"; WS takes the operand(s) (``WS1;``) and
  WD, the loop end, none ("WD;").
* KR: its table prints "KR#;" but its page and example use ``KR;`` and call it "identical to the
  KM command except that the direction of motion is reversed": no operand.
* ET: its table names the mode "AY – AT" like TX's ("The command is invalid for the X axis"); ET
  has no such sentence (digest §8.2 30 suspects a copy slip) but the table is the only statement
  of where ET is valid, so it is taken as printed: AY, AZ, AT.
* VS: "AX mode is the only valid mode" (table: "AX 5").
* PR: the page gives "PR#;" only; it is "similar to the PN command", and PN says "no parameter
  supplied defaults to … 3 steps", so PR may also be sent bare.
* AC range: the table-independent bound "1 ≤ AC ≤ 8,000,000" (RANGE line) wins over the prose
  "less than 999,999,999"; it is inclusive (every operand range is a row of
  ``omsd/dialects/pcix/ranges/``).

Motor types (the manual's lost icons, read from the prose)
----------------------------------------------------------

§5.2: "Some commands are valid only for stepper axes, others for stepper axes with encoder
feedback, and still others for servo axes." The icons are lost in the text, so ``motor`` follows
the prose; it restricts the single-axis form only.

* "servo": §5.6 "The following commands are valid only for servo axes" — BI, KO, ?KO, ?SO, ?SV,
  SVI, SVN, UN (§5.6.1) and KA, KB, KD, KF, KI, KP, KU, KV with their queries (§5.6.2; ?PM,
  listed there too, answers on every axis: below); DZ ("zero voltage output …
  by the servo motor"). HF and HN are listed in §5.6.2 but their pages address steppers with
  encoders too, so they are "feedback".
* "stepper_encoder": HD, HG, HV ("designed to work with stepper motor applications using encoders
  and is not designed for use with servo motors"; "This command is not designed for use with
  servo motors"), ?HD ("will only work on stepper axes with encoders"), ?HG, ?HV ("works only
  with stepper with encoder axes"), ER and ?ER ("not designed for use with servo motors"), ES and
  ?ES ("STEPPER RANGE"; slip needs an encoder), IS ("intended to be used with stepper motors and
  not servo motors"; GS is the open-loop form), ET ("intended to be used with stepper motors with
  encoders and not with servo motors"), TN, TF and ?SK (slip kill, "if the motor slips beyond
  the dead band set by the ES command").
* "feedback" (servo or stepper with encoder): HN ("For servo axes … For stepper with encoder
  feedback axes"), HF ("for stepper with an encoder axis. If the current axis is a servo"), HE
  ("enables encoder index, and phase A and B signals"), RE ("current encoder position"), EA
  ("encoder status"). Not IP: its page says "within the specified step encoder dead band" but
  also "If the position hold (HN) is not enabled for an axis, the command will behave like an
  ID command for that axis", and drops the older boards' "This command is available only in
  models with the encoder option": on an open-loop axis it is ID.
* "open_loop": GS ("this command is not valid in controls with encoder feedback which includes
  servo motors").
* Everything else applies to every axis. MO in particular: the PC48 page says "This command is
  not available in models with an encoder option" and "one step pulse"; the PCIx page drops that
  sentence and says "will output one count", so MO is left open to every axis. PE and RL report
  every axis ("All encoder positions will be reported even in single axis mode"; "Open-loop
  stepper always returns “n”") and so are not tied to the current axis's motor. BC is "implemented
  for both stepper and servo axes".

Models (Appendix C)
-------------------

PCIX-SEO: S servo axes, E steppers with encoder, O open-loop steppers ("PCIX-202 | 2 | | 2").
Two-axis models have X and Y, four-axis ones X, Y, Z, T (§4 pin-out, done-flag register "bit 0
= X … bit 3 = T"); on the 202 the servo axes come first. Servo axes have encoders
("Incremental encoder feedback is provided for all servo axes"). Where the manual is silent or
contradicts itself:

* WY: the WY page's reply, "PCIX-400 ver:1.26, s/n:000217 - Oregon Micro Systems", is the format
  (§2.4's "PCIX-400 ver 1.26 S/N 000000, Oregon Micro Systems" is prose); firmware 1.26 as
  printed (the example text says 1.28), serial 000217 as printed.
* General-purpose I/O: 8 bits (J2 carries I/O-0 … I/O-7; BH/BL/SW/BW take 0..7; BS "00 ≤ Hex
  number ≤ FF"), factory S3 "sets I/O bits 0-3 as inputs and bits 4-7 as outputs" (§2.2); the
  "16 configurable … 8 inputs and 8 outputs" of §5.5.2 and "Up to 12 bits" of Appendix C are
  not taken.
* Velocity: VL "1 ≤ VL ≤ 1044000"; JG "-1,043,999 ≤ JG ≤ 1,043,999" (``max_jog_velocity``).
* Acceleration: "RANGE: 1 ≤ AC ≤ 8,000,000", the row the interpreter checks
  (``omsd/dialects/pcix/ranges/``). ``Model.max_acceleration``, described as an exclusive
  bound, is the next float above 8,000,000.
* Defaults: VL 200,000 ("The factory default is 200,000 steps per second"; §2.8's prose
  "100,000" is not taken), AC 2,000,000, CV 1000. Position range ±33,554,431 (LP and SO; the
  "±33,544,431" of IN/MV/TL and the ±33,500,000 of Appendix C are taken as misprints/roundings).
* Queues: 124-character input buffer, 800 units per axis, 7160 in the contour queue (§5.2,
  §7.2, RQ). 2048 velocity calculations a second (§7.2).
* INIT: the manual gives no time; the PC48's 0.1 s is kept.
"""

from __future__ import annotations

import math

from omsd.models.spec import (
    IMM,
    NV,
    Cell,
    CommandSpec,
    Model,
    addons,
    flush,
    per_axis,
    q,
    qr,
)


def _c(
    mnemonic: str, operand: bool, single: Cell, multi: Cell, contour: Cell = NV, **kw: object
) -> CommandSpec:
    return CommandSpec(mnemonic, operand, single, multi, contour, **kw)  # type: ignore[arg-type]


def _o(mnemonic: str, single: Cell, multi: Cell, contour: Cell = NV, **kw: object) -> CommandSpec:
    """A command whose operand may be left out (``LN;`` / ``LN,1,,1;``, ``HM;`` / ``HM100;``)."""
    return CommandSpec(
        mnemonic,
        True,
        single,
        multi,
        contour,
        optional=True,
        **kw,  # type: ignore[arg-type]
    )


def _query(mnemonic: str, operand: bool = False, **kw: object) -> CommandSpec:
    """A report of the current axis: "AX – AT Immediate, AA-AM Not Valid, AA/CD Not Valid"."""
    return _c(mnemonic, operand, IMM, NV, NV, **kw)


def _both(mnemonic: str, operand: bool = False, **kw: object) -> CommandSpec:
    """Immediate in single-axis and AA/AM modes, not valid in a contour definition."""
    return _c(mnemonic, operand, IMM, IMM, NV, **kw)


_SERVO = "servo"
_STEP_ENC = "stepper_encoder"
_FEEDBACK = "feedback"

# GO, GD, GN, GU: "If the axis is a stepper and encoder or servo axis add 3", "If PA (power
# automatic) mode is active add 2", "If an auxiliary output bit settle time has been specified
# add 3"
_GO = addons(encoder=3, pa=2, settle=3)
# HM, HR: "… encoder or servo axis add 2", "PA … add 2", "settle time … add 3"
_HOME = addons(encoder=2, pa=2, settle=3)
# ST, SA, SD, SI, KL, KS, FP: "If PA (power automatic) mode is active add 1", "… settle time …
# add 3"
_STOP = addons(pa=1, settle=3)
# KM, KR, GS: "PA … add 2", "settle time … add 3"
_KILL_HOME = addons(pa=2, settle=3)
# JG, JF, TM: "If PA (power automatic) mode is active add 1", "If the axis is a stepper (and)
# encoder or servo axis add 1"
_JOG = addons(encoder=1, pa=1)
# CX, CG: "If the axis is a stepper and encoder or servo add 1", "PA … add 2", "settle … add 3";
# custom ramps "6 + (2 x number of ramp segments)"
_CONTOUR_GO = addons(encoder=1, pa=2, settle=3, segments=2)


def _move(base: int) -> Cell:
    """MA/MR/ML/MT: ``base`` for every ramp, "If the axis is using the cosine acceleration ramp,
    and velocity needs to be adjusted so the profile is not truncated, add 11", S-curve "add 44"
    (charged on every move: see the module docstring)."""
    return qr(base, base, base + 11, base, base + 44)


PCIX_COMMANDS: dict[str, CommandSpec] = {
    c.mnemonic: c
    for c in (
        # 5.4.1 identification; WY
        _query("?AB"),
        _query("?AC"),
        _query("?AD"),
        _query("?AJ", True),  # "?AJ#;"
        _c("?AQ", False, IMM, IMM, IMM),  # "?AQ AA/CD Immediate"
        _query("?BC"),
        _query("?DA", True),  # "?DA#;"
        _query("?DB"),
        _query("?DC"),
        _query("?DE", True),  # "?DE#,#;"
        _query("?DS", True),  # "?DS#;"
        _query("?ER", motor=_STEP_ENC),
        _query("?ES", motor=_STEP_ENC),
        _query("?HD", motor=_STEP_ENC),  # "will only work on stepper axes with encoders"
        _query("?HG", motor=_STEP_ENC),  # "works only with stepper with encoder axes"
        _query("?HM"),
        _query("?HS"),
        _query("?HV", motor=_STEP_ENC),  # "works only with stepper + encoder axes"
        _query("?KA", motor=_SERVO),
        _query("?KB", motor=_SERVO),
        _query("?KD", motor=_SERVO),
        _query("?KF", motor=_SERVO),
        _query("?KI", motor=_SERVO),
        _query("?KO", motor=_SERVO),
        _query("?KP", motor=_SERVO),
        _query("?KU", motor=_SERVO),
        _query("?KV", motor=_SERVO),
        _query("?LM"),
        _query("?LS"),
        _query("?PA"),
        # "REPORT HOLD STATE": the hold state of any axis (a servo's loop, a stepper's position
        # maintenance, hf on an open-loop axis), not the servo-only list's error: omsMAXnet asks
        # every axis "A? ?PM" on firmware before 1.30 (the PCIx's WY says 1.26), each unanswered
        # query a 2 s timeout (docs/decisions.md)
        _query("?PM"),
        _query("?RT"),
        _query("?SE"),
        _query("?SK", motor=_STEP_ENC),
        _query("?SL"),
        _query("?SO", motor=_SERVO),  # "the analog output type for the current servo axis"
        _query("?SV", motor=_SERVO),  # "the current logical direction for the current servo axis"
        _query("?TL"),
        _query("?UU"),
        _query("?VB"),
        _query("?VL"),
        _both("WY"),
        # 5.4.2 power-up defaults
        _both("AP"),
        _both("RF"),
        # "RD AX – AT Immediate" although it "places entries in all axis command queues": the
        # command acts at once, its entries (no units given) set each axis when reached
        _both("RD"),
        # 5.4.3 queue selection
        _c("AA", False, q(1), q(1)),  # "places synchronization entries in all axis queues"
        _both("AM"),
        *(_both(f"A{letter}") for letter in "XYZT"),
        # 5.4.4 queue status
        _query("FL"),
        _c("RQ", False, IMM, IMM, IMM),
        # 5.4.5 user units
        _o("UF", IMM, IMM),  # "UF;" / "UFb,b,b,b;"
        _both("UU", True),
        # 5.4.6 axis status
        _both("EA", motor=_FEEDBACK),
        _query("QA"),
        _c("QI", False, NV, IMM),
        _query("RA"),
        _c("RI", False, NV, IMM),
        # 5.4.7 macros
        _both("MD", True),
        _both("MX", True),
        _both("PM", True),
        _both("PT", True),
        # 5.5.1 auxiliary control
        _query("ADH"),
        _query("ADL"),
        _o("AN", q(1), q(1), q(2)),  # "AN AX – AT 1 … AA/CD 2*"
        _o("AF", q(1), q(1), q(2)),
        # "PAb; AX – AT 1*", "* If an auxiliary output bit settle time has been specified add 3"
        _o("PA", q(1) + addons(settle=3), q(1) + addons(settle=3)),
        _o("PH", q(1), q(1)),
        _o("PL", q(1), q(1)),
        _both("SE", True),
        # 5.5.2 general purpose I/O
        _c("BH", True, q(2), q(3), q(2)),
        _c("BL", True, q(2), q(3), q(2)),
        # "The mask must be in ASCII hex format": the operand is read as hexadecimal digits
        _c("BS", True, q(2), NV, hex_operand=True),
        _both("BX"),
        _both("RB"),  # "- AX – AT Immediate", "RB AA-AM Immediate"
        # 5.5.3 home control
        _o("HE", IMM, IMM, motor=_FEEDBACK),
        _o("HH", q(1), q(1)),
        _o("HL", q(1), q(1)),
        _o("HS", IMM, IMM),
        # 5.5.4 limit control
        _o("LF", q(1), q(1)),
        _o("LH", q(1), q(1)),
        _o("LL", q(1), q(1)),
        _o("LN", q(1), q(1)),
        _o("SF", q(1), q(1)),
        _o("SL", q(1), q(1)),
        _c("TL", True, q(3), NV),
        # 5.6.1 servo voltage control
        _query("BI", motor=_SERVO),
        _c("KO", True, q(2), NV, motor=_SERVO),
        _query("SVI", motor=_SERVO),
        _query("SVN", motor=_SERVO),
        _query("UN", motor=_SERVO),
        _c("DZ", True, q(2), NV, motor=_SERVO),  # summary only (marked "Q")
        # 5.6.2 PID
        # HF: "In AA or AM mode, a null value in the argument list specifies feedback for that
        # axis is not to be disabled": it takes the b list
        _o("HF", q(2), q(2), motor=_FEEDBACK),
        # HN "1*": "Values in table are for a stepper with encoder axis. For a servo axis the
        # command queue requires 2" (the servo's extra unit is the handler's)
        _o("HN", q(1), q(1), motor=_FEEDBACK),
        *(_c(m, True, q(2), NV, motor=_SERVO) for m in ("KA", "KB", "KD", "KF", "KI", "KP", "KU")),
        _c("KV", True, q(2), NV, motor=_SERVO),
        # 5.7.1 step encoder control
        _c("ER", True, q(1), NV, motor=_STEP_ENC),
        _c("HD", True, q(2), q(2), motor=_STEP_ENC),
        _c("HG", True, q(2), q(2), motor=_STEP_ENC),
        _c("HV", True, q(2), q(2), motor=_STEP_ENC),
        # 5.7.2 step encoder slip
        _c("ES", True, q(2), NV, motor=_STEP_ENC),
        _c("IS", False, q(1), NV, motor=_STEP_ENC),
        _both("RL"),
        _c("TF", False, q(2), NV, motor=_STEP_ENC),
        _c("TN", False, q(2), NV, motor=_STEP_ENC),
        # 5.7.3 encoder slave modes: "ET; AY – AT 2", "TX; AY – AT Immediate"
        _c("ET", False, q(2), NV, single_axes="YZT", motor=_STEP_ENC),
        _o("TX", IMM, NV, single_axes="YZT"),  # "TX;" (ratio optional)
        # 5.7.4 homing
        _o("HM", q(4) + _HOME, q(4) + _HOME),
        _o("HR", q(4) + _HOME, q(4) + _HOME),
        _c("KM", False, q(2) + _KILL_HOME, NV),
        _c("KR", False, q(2) + _KILL_HOME, NV),
        # 5.7.5 position counters
        _c("LO", True, q(2), q(2)),
        # "LP#; AX – AT 2*", "* If the axis is a stepper and encoder or servo axis add 2"
        _o("LP", q(2) + addons(encoder=2), q(2) + addons(encoder=2)),
        _both("PE"),
        _both("PP"),
        _both("RE", motor=_FEEDBACK),
        _c("RM", True, q(2), NV),
        _both("RP"),
        _both("RU"),
        # 5.8.1 velocity
        _both("RV"),
        _c("VB", True, q(2), q(2)),
        # "VL 2*": "All other PN and PR ramp selections add 9", "CN and SC ramp selections add
        # 9", "SR (custom) ramp selections add (number of steps in ramp -1)"
        _c(
            "VL",
            True,
            qr(2, 11, 11, 1, 2) + addons(segments=1),
            qr(2, 11, 11, 1, 2) + addons(segments=1),
        ),
        # 5.8.2 acceleration: Linear 6, (short parabolic 8 never selected), other parabolic 15,
        # custom "3 + (No. of ramp segments +12)", S-curve 69; no cosine row
        _c(
            "AC",
            True,
            qr(6, 15, 15, 15, 69) + addons(segments=1),
            qr(6, 15, 15, 15, 69) + addons(segments=1),
        ),
        _c("DC", True, q(2), NV),
        _both("RC"),
        # 5.8.3 profile: PN/PR "All Other Parabolic … 29" (the short form's 15 never applies)
        _c("AJ", True, IMM, NV),
        _c("CN", False, q(29), q(29)),
        _o("LA", q(11), q(11)),
        _c("PF", False, q(11), q(11)),
        _o("PN", q(29), q(29)),
        _o("PR", q(29), q(29)),
        _o("SC", q(29), q(29)),
        # SR: "7 + (2* number of segments in ramp definition)" of the table selected (handler)
        _c("SR", True, q(7), NV),
        _c("SS", True, q(117), NV),
        # 5.8.4 custom profile
        _c("DAB", True, IMM, NV),
        _c("DAE", False, IMM, NV),
        _c("DAR", True, IMM, NV),
        # 5.9.1 jogging
        _c("JF", True, q(4) + _JOG, q(4) + _JOG),
        _c("JG", True, q(4) + _JOG, q(4) + _JOG),
        _c("MO", False, q(1), NV),
        _c("TM", True, q(6) + _JOG, q(6) + _JOG),
        # 5.9.2 move specification
        # MA: "If the axis is a stepper encoder or servo axis add 2 to the command"
        _c("MA", True, _move(2) + addons(encoder=2), _move(4) + addons(encoder=2)),
        _c("ML", True, NV, _move(4), follower=qr(6, 20, 20, 6, 113) + addons(segments=2)),
        # MR: "If the axis is a stepper encoder or servo axis add 1 to both the command"
        _c("MR", True, _move(2) + addons(encoder=1), _move(2) + addons(encoder=1)),
        # MT in a contour: "6 + (number of axes included in contour definition)"
        _c(
            "MT",
            True,
            NV,
            _move(4),
            per_axis(6, 1),
            follower=qr(6, 26, 26, 6, 113) + addons(segments=2),
        ),
        # 5.9.3 move execution
        _c("GD", False, q(6) + _GO, q(8) + _GO),
        _c("GN", False, q(6) + _GO, q(7) + _GO),
        _c("GO", False, q(5) + _GO, q(7) + _GO),
        _c("GS", False, q(5) + _KILL_HOME, NV, motor="open_loop"),
        _c("GU", False, q(3) + _GO, NV),
        # 5.9.4 move termination
        _c("KL", False, flush(1) + _STOP, flush(1) + _STOP),
        _o("KS", flush(1) + _STOP, flush(1) + _STOP),
        _c("SA", False, flush(1) + _STOP, flush(1) + _STOP),
        _c("SD", False, flush(2) + _STOP, flush(2) + _STOP),
        _o("SI", flush(1) + _STOP, flush(1) + _STOP),
        # SO: "… encoder or servo axis, add 1", "PA … add 1", "settling time … add 3"
        _c("SO", True, q(5) + addons(encoder=1, pa=1, settle=3), NV),
        _c("ST", False, flush(1) + _STOP, flush(1) + _STOP),
        # 5.9.5 move completion notification
        _o("CA", IMM, IMM),
        _both("IC"),
        _c("ID", False, q(1), q(1), q(1)),
        _c("II", False, NV, q(1)),
        _c("IN", True, q(3), q(3)),
        _c("IP", False, q(1), q(1)),
        # 5.9.6 velocity stair casing
        _c("FP", True, flush(3) + _STOP, NV),
        _c("MM", False, q(1), NV),
        _c("MP", False, q(1), NV),
        # MV: "If PA … add 1", "If this axis is a stepper encoder or servo axis add 2"
        _c("MV", True, q(4) + addons(encoder=2, pa=1), NV),
        _c("SP", True, q(3) + addons(encoder=1, pa=1, settle=3), NV),
        # 5.9.7 velocity streaming: "AX mode is the only valid mode"
        _c("VS", True, q(5), NV, single_axes="X"),
        # 5.9.8 contouring
        _c("CD", True, NV, per_axis(5, 1)),  # "5 + number of axes in the contour"
        _c("CE", False, NV, NV, q(2)),
        _c("CG", False, NV, q(9) + qr(8, 26, 26, 6, 113) + _CONTOUR_GO),
        _c("CK", False, NV, NV, q(2)),
        _c("CR", True, NV, NV, q(8)),
        _c("CV", True, NV, IMM),
        _c("CX", False, NV, q(8) + qr(0, 18, 18, 6, 113) + _CONTOUR_GO),
        _c("NV", True, NV, NV, IMM),
        # 5.10.1 waiting
        _c("BW", True, q(2), q(4)),
        _c("SW", True, q(2), q(2)),
        _c("WA", False, NV, q(2)),  # "* This command places entries in all axes' queues."
        _both("WQ"),
        _c("WT", True, q(3), q(3)),
        # 5.11.1 looping
        _both("CW"),
        _c("LE", False, q(2), q(2)),
        _c("LS", True, q(2), q(2)),
        _c("WD", False, q(2), q(2)),
        _c("WG", False, q(2), q(3)),
        _c("WH", False, q(3), q(3)),
        _c("WS", True, q(2), q(2)),
        # 5.12 special: backlash (BC page "Immediate" over §5.12.3's "1"), electronic gearing
        _c("BC", True, IMM, NV),
        _c("EG", True, q(2), NV, letter_operand=True),  # "EG#,#,#, AX – AT 2": EGX1,2;
        _query("EG?"),
        _query("EGF"),
        # summary only: DBI/DBN ("DBI; AX – AT 1", "DBIb,b,b,b; AA-AM 1")
        _o("DBI", q(1), q(1)),
        _o("DBN", q(1), q(1)),
    )
}


def _pcix(name: str, axes: str, servo: str, encoders: str, description: str) -> Model:
    return Model(
        name=name,
        family="PCIX",
        description=description,
        axes=axes,
        encoder_axes=encoders,
        servo_axes=servo,
        sample_rate=2048,  # "calculates the desired velocity 2048 times each second"
        input_buffer=124,  # "stored in a 124 character buffer"
        queue_size=800,  # "The current axis command queue size for PC1x is 800."
        contour_queue=7160,  # "The size of the contour queue is 7160."
        commands=PCIX_COMMANDS,
        firmware="1.26",
        serial="000217",
        wy_format="{model} ver:{firmware}, s/n:{serial} - Oregon Micro Systems",
        max_velocity=1_044_000,  # "1 ≤ VL ≤ 1044000"
        # "RANGE: 1 ≤ AC ≤ 8,000,000", inclusive; max_acceleration is an exclusive bound
        max_acceleration=math.nextafter(8_000_000.0, math.inf),
        default_velocity=200_000,
        default_acceleration=2_000_000,
        default_contour_velocity=1000,  # "The contour velocity defaults to 1000"
        load_position_limit=33_554_431,  # "-33,554,431 ≤ LP ≤ 33,554,431"
        position_limit=33_554_431,
        io_bits=8,
        factory_outputs=0xF0,  # S3: "bits 0-3 as inputs and bits 4-7 as outputs"
        io_inputs=0x0F,
        done_bits=tuple(range(len(axes))),  # "bit 0 = X … bit 3 = T"
        framing="trailing",
        dialect="pcix",
        max_queries=True,
        max_jog_velocity=1_043_999,  # "-1,043,999 ≤ JG ≤ 1,043,999"
        init_time=0.1,  # not given by the PCIx manual: the PC48's
        # VS: "time in 1 update rate second sample intervals"; the example's "assumes an update
        # rate of 1024" is the older boards' (the PCIx updates 2048 times a second)
        velocity_stream_rate=2048,
        # VB: "If the VL command is used after the VB command and the velocity value set with
        # VL is less than the previously set VB value, the initial velocity used at the start
        # of a move will be the VL value minus one."
        base_above_peak=1.0,
    )


PCIX_MODELS: tuple[Model, ...] = (
    _pcix("PCIX-002", "XY", "", "", "2 open-loop stepper axes"),
    _pcix("PCIX-020", "XY", "", "XY", "2 stepper axes with encoder feedback"),
    _pcix("PCIX-202", "XYZT", "XY", "XY", "2 servo axes (X, Y), 2 open-loop stepper axes (Z, T)"),
    _pcix("PCIX-200", "XY", "XY", "XY", "2 servo axes"),
    _pcix("PCIX-004", "XYZT", "", "", "4 open-loop stepper axes"),
    _pcix("PCIX-040", "XYZT", "", "XYZT", "4 stepper axes with encoder feedback"),
    _pcix("PCIX-400", "XYZT", "XYZT", "XYZT", "4 servo axes"),
)
