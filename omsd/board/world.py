"""The simulated world around a board, as the board's public API: :class:`AxisWorld` (one axis's
stage: limits, home switch, encoder index), :class:`SwitchType`, :class:`LimitWiring`. They are
defined in :mod:`omsd.engine.world`; this module is where configurations and tests take them
from (``from omsd.board.world import AxisWorld``, or ``from omsd.board import AxisWorld``)."""

from omsd.engine.world import AxisWorld, LimitWiring, SwitchType, WorldState

__all__ = ["AxisWorld", "LimitWiring", "SwitchType", "WorldState"]
