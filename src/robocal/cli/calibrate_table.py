"""The console table of ``robocal calibrate``: identified parameters with change and sigma, and
the ones not identified with the reason (from the ``result.json`` dict)."""

from __future__ import annotations

import math

__all__ = ["parameter_table"]

_DEG = 180.0 / math.pi


def _shown(value, unit):
    """(value in display units, display unit): angles in degrees."""
    if value is None:
        return float("nan"), unit
    return (value * _DEG, "deg") if unit == "rad" else (value, unit)


def _row(p) -> str:
    value, unit = _shown(p["value"], p["unit"])
    change, _ = _shown(p["change"], p["unit"])
    std, _ = _shown(p["std"], p["unit"])
    return f"  {p['name']:<16}{unit:<5}{value:>14.5f}{change:>12.5f}{std:>11.5f}"


def parameter_table(result: dict, *, include_base: bool = False) -> list:
    """Lines: one per identified variable (name, unit, value, change from the start, 1-std;
    angles in degrees), then the variables held at their initial values with the reason. Base
    frame variables are left out unless ``include_base`` (they place the instrument, not the robot)."""
    params = result.get("parameters") or []
    shown = [p for p in params if p.get("identifiable") and (include_base or p.get("block") != "base")]
    lines = [f"identified ({len(shown)} of {len(params)} variables{'' if include_base else ', base frame not shown'}):",
             f"  {'name':<16}{'unit':<5}{'value':>14}{'change':>12}{'sigma':>11}"]
    lines += [_row(p) for p in shown]
    dropped = (result.get("identifiability") or {}).get("dropped") or []
    if dropped:
        lines.append(f"not identified ({len(dropped)}, held at their initial values):")
        lines += [f"  {d['name']:<16}{d['why']}" for d in dropped]
    return lines
