"""Display units of stored quantities: one unit per quantity in the console, the JSON and the plots
(issue 25). The history store keeps millimetres and radians with the unit in its ``unit`` column;
what a user reads shows angles in degrees and the lambda of thermal compensation in percent."""

from __future__ import annotations

import math

__all__ = ["display_unit"]

_DISPLAY = {"rad": (180.0 / math.pi, "deg"), "degC": (1.0, "°C")}


def display_unit(unit: str):
    """``(scale, display unit)`` of a stored unit: the value shown is ``scale * stored`` (rad -> deg);
    every other unit is shown as stored."""
    return _DISPLAY.get(unit, (1.0, unit))
