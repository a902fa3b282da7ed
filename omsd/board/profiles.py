"""Deprecated: the motion profiles moved to :mod:`omsd.engine.profiles` (pieces, trajectories,
ramps). This module re-exports them and warns; import from the engine instead."""

import warnings

from omsd.engine.profiles import *  # noqa: F403
from omsd.engine.profiles import __all__ as __all__

warnings.warn(
    "omsd.board.profiles moved to omsd.engine.profiles",
    DeprecationWarning,
    stacklevel=2,
)
