"""Telemetry: the traffic log of every byte in and out of the emulated boards."""

from omsd.telemetry.lines import visible
from omsd.telemetry.traffic import (
    VIEWS,
    Direction,
    Traffic,
    TrafficLog,
    TrafficLogError,
)

__all__ = ["VIEWS", "Direction", "Traffic", "TrafficLog", "TrafficLogError", "visible"]
