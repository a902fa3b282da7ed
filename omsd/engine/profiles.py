"""Motion profiles, evaluated analytically: one namespace for the pieces, the trajectory and the
ramps (``from omsd.engine import profiles as pf``).

* :mod:`omsd.engine.pieces`: the closed-form pieces (:class:`Poly`, :class:`Cosine`, ...);
* :mod:`omsd.engine.trajectory`: :class:`Trajectory`, one axis's position as a function of time;
* :mod:`omsd.engine.ramps`: the ramp shapes (:class:`RampShape`) and the moves built of them.
"""

from omsd.engine.pieces import (
    Chain,
    Cosine,
    Decay,
    Piece,
    Poly,
    Shifted,
    Sinusoid,
    Window,
    cruise,
    mirrored,
    scaled,
)
from omsd.engine.ramps import (
    LINEAR,
    RampKind,
    RampShape,
    SCurve,
    hold_correction,
    move_pieces,
    move_time,
    profile_pieces,
    ramp_up,
    stop_at,
    stop_distance,
    velocity_change,
)
from omsd.engine.trajectory import Trajectory, pieces_between, rebased, segment, tail, window

__all__ = [
    "LINEAR",
    "Chain",
    "Cosine",
    "Decay",
    "Piece",
    "Poly",
    "RampKind",
    "RampShape",
    "SCurve",
    "Shifted",
    "Sinusoid",
    "Trajectory",
    "Window",
    "cruise",
    "hold_correction",
    "mirrored",
    "move_pieces",
    "move_time",
    "pieces_between",
    "profile_pieces",
    "ramp_up",
    "rebased",
    "scaled",
    "segment",
    "stop_at",
    "stop_distance",
    "tail",
    "velocity_change",
    "window",
]
