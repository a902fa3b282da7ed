"""Two boards in step: one with the fast paths (issue 16) and one without, the reference.

:class:`Twin` stands where a :class:`~omsd.board.Board` would (a test, a link): every call that
may change a board or that reads what it says is made on both, and the two must then give the
same answer and be in the same state, down to what each axis will do next; everything else is
read from the fast board. ``Board(model, fast_paths=False)`` runs the straightforward code:
every command through the lexer and ``_command``'s checks, every receive through the input
buffer, a ``settle`` and an ``advance`` however little there is to do, every axis stepped, the
deadline found anew each time it is asked for.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from omsd.board import Board
from omsd.board.world import AxisWorld
from omsd.engine.axis import Axis
from omsd.models import Model

#: The calls that are made on both boards.
MIRRORED = frozenset(
    {
        "receive",
        "advance",
        "settle",
        "next_deadline",
        "take_output",
        "take_output_sourced",
        "take_bytes",
        "read_status_register",
        "read_done_register",
        "write_control_register",
        "write_vector_register",
        "set_limit",
        "set_home",
        "set_input",
        "wire_input_to_aux",
        "inject_slip",
        "set_stall",
        "set_encoder_input",
        "power_cycle",
        "reset",
        "load_flash",
        "snapshot",
        "status_register",
        "input_room",
        "input_busy",
        "session_busy",
        "busy_axes",
    }
)


class Diverged(AssertionError):
    """The board with the fast paths and the reference no longer agree."""


class Twin:
    def __init__(
        self,
        model: Model,
        now: float = 0.0,
        world: Mapping[str, AxisWorld] | Sequence[AxisWorld] | None = None,
    ) -> None:
        self.fast = Board(model, now=now, world=world)
        self.reference = Board(model, now=now, world=world, fast_paths=False)
        self.calls: list[str] = []  # what was done to both, for the message of a divergence
        agree(self.fast, self.reference, self.calls)

    def __getattr__(self, name: str) -> Any:
        value = getattr(self.fast, name)
        if name not in MIRRORED:
            return value

        def both(*args: Any, **kwargs: Any) -> Any:
            self.calls.append(f"{name}{args!r}")
            result, failed = _call(value, args, kwargs)
            expected, refused = _call(getattr(self.reference, name), args, kwargs)
            if result != expected or repr(failed) != repr(refused):
                raise Diverged(
                    f"{name}: {result!r} {failed!r} != {expected!r} {refused!r}\nafter {self.calls}"
                )
            agree(self.fast, self.reference, self.calls)
            if failed is not None:
                raise failed
            return result

        return both


def _call(fn: Any, args: tuple[Any, ...], kwargs: dict[str, Any]) -> tuple[Any, Exception | None]:
    try:
        return fn(*args, **kwargs), None
    except Exception as exc:  # the same refusal from both (a ValueError for a wrong axis)
        return None, exc


def agree(fast: Board, reference: Board, calls: list[str]) -> None:
    a, b = state(fast), state(reference)
    if a != b:
        diff = {k: (a[k], b[k]) for k in a if a[k] != b[k]}
        raise Diverged(f"state differs: {diff}\nafter {calls}")


def state(board: Board) -> dict[str, Any]:
    """What a board is and has said (nothing here changes it)."""
    interp = board.interpreter
    r = board.registers
    return {
        "now": board.now,
        "talker": board.talker,
        "input_source": board.input_source,
        "output": list(board._output),
        "sources": list(board._sources),
        "registers": (r.status, r.done, r.control),
        "init_until": board.init_until,
        "outputs_low": board.outputs_low,
        "directions": board.directions,
        "contour": board.contour is not None,
        "buffer": bytes(interp.buffer),
        "pending": [(repr(token), depth) for token, depth in interp.pending],
        "interpreter": (
            interp.mode,
            interp.axis_index,
            interp.echo,
            interp.wq,
            interp.depth,
            interp.lexer.between_commands,
            interp.lexer.idle,
            interp.capture is None,
            interp.only,
            interp.contour is not None,
            [[(m.kind, m.context) for m in stack] for stack in interp.loops],
            sorted(interp.while_flags),
            interp.mt_blocked,
        ),
        "axes": [_axis(a, board.now) for a in board.axes],
    }


def _axis(a: Axis, now: float) -> tuple[Any, ...]:
    q = a.queue
    w = a.wait
    traj = a.traj
    servo = a.servo
    return (
        a.motion,
        (traj.t0, traj.x0, traj.final, traj.end_time, len(traj.pieces)),
        (traj.position(now), traj.velocity(now)),
        a.event,
        a.source,
        (a.done, a.direction, a.slipped, a.hold, a.in_position, a.limit_latched, a.limit_ramp),
        (a.vl, a.ac, a.vb, a.aux, a.aux_timer, a.in_fire, a.sensor_check),
        (a.phys_offset, a.stall_phys, a.home is not None, a.pending is not None, a.hold_goal),
        a.contour_origin,
        [(op.code, _plain(op.args), op.slots, op.source, op.group is None) for op in q.program],
        (q.pc, q.used, [(f.kind, f.start, f.remaining, f.began) for f in q.loops]),
        None if w is None else (w.kind, w.until, w.bit, w.high, w.round, w.jump),
        None
        if servo is None
        else (servo.time, servo.position, servo.velocity, servo.closed, servo.tripped),
    )


def _plain(args: tuple[Any, ...]) -> tuple[Any, ...]:
    """An op's arguments, with whatever is not a plain value (a function) named by its kind."""
    return tuple(
        x if x is None or isinstance(x, int | float | str | bool | tuple) else type(x).__name__
        for x in args
    )
