"""The simulated machine around the board: switches, encoders and input lines.

A real card is wired to a stage. The stage has a carriage at some physical position, limit
switches near its ends, a home switch somewhere along it and perhaps an encoder; the card's
general-purpose inputs are wired to other equipment. This module describes that world. Physical
positions are in motor steps, in the frame the stage had at power-up; the board's position
counter is another frame that LP, HM and RM move around (PC48 §6.7, §6.11).

Switch wiring follows chapter 3 and §6.5 of the PC48 manual:

* Limits are directional (J44): an axis "will stop moving if the limit line, for the direction
  the axis is moving, is grounded". A limit switch is *active* while the carriage is at or beyond
  its position.
* The home switch is *activated* while the carriage is inside its window. A normally open switch
  grounds the line when activated, which is what the power-up HL ("active low") expects; HH
  "allows the use of a normally closed switch".
* General-purpose inputs are pulled up (2.2k), so an unconnected input reads high; "input true"
  for WS/SW means low.

Tests and the control API use :class:`AxisWorld` and :class:`WorldState` to close switches, drive
inputs and make encoders slip, as a technician would at the bench.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import Enum


class SwitchType(Enum):
    NORMALLY_OPEN = "normally_open"
    NORMALLY_CLOSED = "normally_closed"


class LimitWiring(Enum):
    """How the limit switches drive their lines. ``MATCHED`` (the default): wired to suit the
    board's limit level, whatever it is set to (a hit switch is always a limit; the PCIx's LH/LL
    and the MAX-family LT? then only report the setting). ``NORMALLY_OPEN``: the line is pulled up
    and grounded while the switch is hit, which the PCIx's LL ("TTL logic low ... the 'true'
    state", its power-up default) expects; ``NORMALLY_CLOSED``: grounded until the switch is hit,
    for LH. With an explicit wiring and the other level set, the board sees a limit everywhere
    but at the switch, as a real card would."""

    MATCHED = "matched"
    NORMALLY_OPEN = "normally_open"
    NORMALLY_CLOSED = "normally_closed"


#: The positions of an axis's world (motor steps, physical frame).
POSITIONS = ("start_position", "negative_limit", "positive_limit", "home_low", "home_high")


@dataclass(frozen=True)
class AxisWorld:
    """Configuration of one axis's stage. Defaults are chosen so that a newcomer's first
    commands behave: the carriage starts at 0, a positive ``HM`` reaches the home switch a
    thousand steps away, and the limits are far beyond every example move in the manuals."""

    start_position: float = 0.0
    negative_limit: float = -10_000_000.0
    positive_limit: float = 10_000_000.0
    home_low: float = 1_000.0
    home_high: float = 1_100.0
    home_switch: SwitchType = SwitchType.NORMALLY_OPEN
    limit_switches: LimitWiring = LimitWiring.MATCHED
    encoder_counts_per_rev: int = 4_000
    # encoder count, modulo a revolution, where the index pulse is; None: the middle of the
    # home switch's window (``index_count``), so that an encoder home (HE then HM) finds home
    encoder_index: int | None = None

    def __post_init__(self) -> None:
        # a switch is somewhere: math.inf for "no switch" would fail deep in the search for
        # crossings (a whole step beyond it), so it is refused here, as the configuration file
        # and the control API refuse it (a far position does what "none" would)
        for name in POSITIONS:
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(
                    f"AxisWorld {name}: expected a finite number of motor steps, got {value!r}"
                    " (for a switch out of reach, a far position: the default is 10,000,000)"
                )

    @property
    def index_count(self) -> int:
        """The encoder count, modulo a revolution, where the index pulse is."""
        if self.encoder_index is not None:
            return self.encoder_index
        middle = math.floor((self.home_low + self.home_high) / 2.0)
        return middle % self.encoder_counts_per_rev if self.encoder_counts_per_rev > 0 else 0

    def with_changes(self, **changes: object) -> AxisWorld:
        return replace(self, **changes)  # type: ignore[arg-type]


@dataclass(eq=False)  # state, compared by identity (omsd.engine.states)
class WorldState:
    """What the bench technician has done to the world: forced switches and driven inputs."""

    # Forced limit switch states per axis index, (negative, positive); None = follow position
    forced_limits: dict[int, list[bool | None]] = field(default_factory=dict)
    # Forced home switch (activated or not) per axis index
    forced_home: dict[int, bool] = field(default_factory=dict)
    # Levels driven onto general-purpose input lines by external equipment; absent = pulled up
    input_levels: dict[int, bool] = field(default_factory=dict)
    # Input bit -> axis index whose auxiliary output is wired to it (open-collector wired-OR)
    aux_wiring: dict[int, int] = field(default_factory=dict)

    def forced_limit(self, axis: int, direction: int) -> bool | None:
        pair = self.forced_limits.get(axis)
        if pair is None:
            return None
        return pair[1 if direction > 0 else 0]

    def limit_forced(self, axis: int) -> bool:
        """Either of the axis's limit switches is forced."""
        pair = self.forced_limits.get(axis)
        return pair is not None and (pair[0] is not None or pair[1] is not None)

    def force_limit(self, axis: int, direction: int, state: bool | None) -> None:
        pair = self.forced_limits.setdefault(axis, [None, None])
        pair[1 if direction > 0 else 0] = state
        if pair[0] is None and pair[1] is None:
            # both follow the carriage again: no switch of the axis is forced (a status then
            # reads the switches on its fast path, omsd.engine.axis_status)
            del self.forced_limits[axis]
