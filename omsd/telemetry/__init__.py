"""Telemetry: the traffic log of every byte in and out of the emulated boards."""

from omsd.telemetry.traffic import (
    VIEWS,
    Direction,
    Traffic,
    TrafficLog,
    TrafficLogError,
    visible,
)

__all__ = ["VIEWS", "Direction", "Traffic", "TrafficLog", "TrafficLogError", "visible"]
