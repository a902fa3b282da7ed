"""The engine's extension points: what a dialect gives the engine, and what the engine asks of
the command language in front of it.

The engine knows no command language. A dialect (:mod:`omsd.dialects`) hands a
:class:`~omsd.engine.machine.Machine` these, through the board that joins them:

* :class:`Framing`: the bytes around a value and a status reply, and the mark of a command
  error in the board's own stream;
* :class:`Options`: behaviour switches where the manuals of two families disagree about a
  general mechanism (soft limits per axis or per board, which commands end position
  maintenance and slip detection ...);
* extra executor ops and sensor hooks (:data:`omsd.engine.executor.OpFunction`,
  :data:`omsd.engine.executor.SensorHook`), for the queued commands only one dialect has.

and the machine asks its :class:`Front` (the dialect's interpreter) to read input, to report
whether there is room for more, to forget loops a flush dropped and to power up with it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from omsd.engine.states import Motion


@dataclass(frozen=True, slots=True)
class Framing:
    """The bytes before and after a reply's text: ``value`` for a value (a position, an
    identification), ``status`` for an axis status; ``error``: what a command error puts in
    the board's own byte stream (the raw link), if anything."""

    value: tuple[bytes, bytes]
    status: tuple[bytes, bytes]
    error: bytes = b""


#: No framing at all (a machine without a dialect).
BARE = Framing((b"", b""), (b"", b""))


#: PC48 HN and IS (the VS4's pages say the same): "Hold and slip detection are disabled if an LP,
#: HM, HR, SA, ST or KL command is entered or if a limit is encountered."
PC48_CANCELS = frozenset({"LP", "HM", "HR", "SA", "ST", "KL"})


@dataclass(frozen=True, slots=True)
class Options:
    """Switches of general mechanisms, set by the dialect a model row names."""

    #: the slip tolerance an axis leaves the factory with
    slip_tolerance: float = 0.0
    #: the soft-limit mode is kept per axis (else setting it on one axis sets it on every axis)
    soft_limit_per_axis: bool = False
    #: the motions that ramp down at a limit when the soft-limit mode is on
    soft_limit_motions: frozenset[Motion] = frozenset({Motion.MOVE})
    #: the commands that end position maintenance (HN) on a stepper with an encoder, and those
    #: that end slip detection (IS), as the manual names them (HF and a limit end both on every
    #: board). A command counts when it executes from the axis's queue (a contour when it
    #: starts), by its own name (a kill home as KM or KR), except that JF is looked up as JG and
    #: a stop as ``ST`` (ST, SA, SD, SI) or, if it kills, ``KL`` (KL, KS, Control-D). The
    #: defaults: :data:`PC48_CANCELS`.
    hold_cancelled_by: frozenset[str] = PC48_CANCELS
    slip_cancelled_by: frozenset[str] = PC48_CANCELS
    #: the remainder op folds the encoder position as well as the counter
    remainder_folds_encoder: bool = False
    #: linear interpolation puts the velocity and acceleration registers back after scaling
    linear_moves_restore: bool = False
    #: a home search found loads the encoder of a stepper with an encoder as well as the
    #: position counter (PCIx HR: "the position and encoder counters are loaded")
    home_loads_encoder: bool = False
    #: the motions that turn power automatic's output to its moving state as they start (PC48
    #: §6.6 PA: "upon the execution of the GO or GD", the moves)
    power_automatic_motions: frozenset[Motion] = frozenset({Motion.MOVE})


class Front(Protocol):
    """What the machine needs of the command language in front of it."""

    #: characters read are echoed, and a command error says its message
    echo: bool

    def pump(self, t: float) -> bool:
        """Read and run what waits in the input; True if anything happened."""
        ...

    def room(self) -> bool:
        """The input buffer can take a character."""
        ...

    def holds_nothing(self) -> bool:
        """Nothing waits to be read or run, and the next character is read afresh (no echo, no
        recording): what :meth:`Machine.at_rest` asks of the front too."""
        ...

    def forget_loops(self, index: int) -> None:
        """Axis ``index``'s queue was flushed: the loops open in it are gone."""
        ...

    def take_while_flag(self, index: int) -> bool:
        """Axis ``index``'s while loop was told to end (and the flag is taken)."""
        ...

    def power_up(self) -> None:
        """Power-up and reset: the language's state to its defaults."""
        ...


class Silent:
    """The front of a machine nobody talks to."""

    echo = False

    def pump(self, t: float) -> bool:
        return False

    def room(self) -> bool:
        return True

    def holds_nothing(self) -> bool:
        return True

    def forget_loops(self, index: int) -> None:
        return None

    def take_while_flag(self, index: int) -> bool:
        return False

    def power_up(self) -> None:
        return None
